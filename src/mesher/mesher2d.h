/* The 2D mesher object behind include/mixoct.h (mx_mesher2d): what it keeps
 * between calls and the figures of a run, read by the report of a run
 * (src/mesher/mesher2d_report.c) and by the checker of 2D mesh files
 * (src/mesher/check_file.c). Private to the library: programs use mixoct.h.
 *
 * The pipeline, one call each (mesher2d.c):
 *   mx_poly_check_domain -> mx_poly_index_build -> mx_qtree_build (requests,
 *   feature levels, the kept leaves of a restart or of the last mesh) ->
 *   mx_qtree_leaves -> mx_qtransition -> mx_qboundary -> mx_qquality_measure
 *   -> mx_qmesh_check. Re-meshing (restart_quadtree.c): the quadtree to and
 *   from the restart file, elements to quadrants. */
#ifndef MX_MESHER2D_H
#define MX_MESHER2D_H

#include <stdatomic.h>
#include "mixoct.h"
#include "mesher/size_source.h"
#include "quad/quad.h"

enum { M2_READ, M2_REFINE, M2_BALANCE, M2_TRANSITION, M2_BOUNDARY, M2_QUALITY, M2_CHECK,
       M2_WRITE, M2_NPH };

/* What a call records even when it only reads the mesher (saving, writing
 * take it const): the handler, the last error, the phases' seconds. Behind
 * a pointer, so those calls record without casting const away. */
typedef struct {
  mx_message_fn fn;
  void *user;
  char last_error[1024];
  double t[M2_NPH], t_restart;
} mx_mesher2d_record;

/* Several materials: at most this many (regions nested this deep). */
#define MX_MAT2D_MAX 64

/* The check of one material's cells against its own loops. */
typedef struct {
  size_t cells;
  mx_qcheck_report cr;
  double area_tol;
} mx_mat2d_report;

struct mx_mesher2d {
  mx_params2d p;
  mx_mesher2d_record *rec;
  /* inputs */
  int has_domain;
  mx_poly domain;
  mx_poly_index index;
  mx_poly *regions, *drawings;
  int *region_level, *drawing_level;
  size_t nregions, ndrawings;
  mx_qbox *boxes;
  size_t nboxes;
  mx_qfun *funs;
  size_t nfuns;
  /* the size field (issue 27, mesher2d_size.c): its source and bounds, and
   * the control space built from them and the -f curves over the domain's
   * box when meshing (kept until one of them changes); the quadrants it
   * asks for (the memory estimate), its least size and where */
  mx_size_source size;
  double size_cells, size_hmin, size_at[3];
  uint32_t *features; /* the domain's feature vertices */
  size_t nfeatures;
  /* the leaves to keep (a loaded restart file, or the last tree when
   * refining): anchor keys ascending, levels (+1 when listed) */
  uint64_t *keep_key;
  uint8_t *keep_level;
  size_t nkeep;
  /* a loaded restart file, before the first mesh: the elements of each of
   * its quadrants (file order) and the quadrant's position in keep_* */
  uint32_t *rs_nsub, *rs_pos;
  size_t rs_n;
  /* the state */
  mx_qtree T;
  mx_qstats qs;
  uint32_t *leaves;
  size_t nleaves;
  mx_qmesh M;
  mx_qboundary_stats bs;
  mx_qquality q;
  mx_qcheck_report cr;
  double area_tol;
  int meshed, checked, valid;
  size_t refined_listed, feature_boxes;
  double estimate_mb;
  /* several materials (params.materials; mesher2d_materials.c): the
   * regions of the domain's loops; with nested loops, the outer loops
   * (the domain the quadtree and the boundary step see) and the
   * interfaces; per cell its material's number; by depth the user's
   * numbers and names (0 / NULL: the defaults); the cleave's figures and
   * each material's check (1 .. nmaterials) */
  int mat_ready;
  mx_qregions nest;
  mx_poly outer, interfaces;
  mx_poly_index outer_index;
  uint16_t *material;
  int nmaterials;
  int mat_number[MX_MAT2D_MAX + 1];
  char *mat_name[MX_MAT2D_MAX + 1];
  mx_qcleave_stats cs;
  mx_mat2d_report *mat_report;
  double t_materials;
  atomic_int cancel; /* mx_mesher2d_cancel (base/cancel.h) */
};

/* restart_quadtree.c */
struct mx_restart;
/* The current quadtree as a restart file's content (dim 2): the leaves'
 * corners, their edges, the leaves with their segments, the cells of each. */
int mx_qrestart_from_mesher(const mx_mesher2d *m, struct mx_restart *r);
/* A restart file's quadrants as kept leaves of the domain's quadtree
 * (m->keep_*, m->rs_*), each checked to lie on the lattice. */
int mx_qrestart_to_keep(mx_mesher2d *m, const struct mx_restart *r);

/* mesher2d.c: the box of the domain's segments' ends, the root grid the
 * domain's quadtree has over it (mx_qgrid_build), and the whole pipeline
 * from the requests and kept leaves. */
void mx_mesher2d_box(const mx_mesher2d *m, double lo[2], double hi[2]);
int mx_mesher2d_grid(const mx_mesher2d *m, mx_qgrid *g);
int mx_mesher2d_run(mx_mesher2d *m);
/* The area tolerance of the check (mesher2d and `mixoct check`): half a
 * layer of cells of the mean size along the polylines, relative to the
 * domain's area, 5% at least, 25% at most. */
double mx_qarea_tolerance(const mx_poly *P, const mx_qcheck_report *c, size_t ncells);

/* mesher2d_size.c: the size field. The calls' work (mx_mesher2d_set_size_*
 * wrap them); the control space dropped when a source of it changes (a -f
 * curve added), or freed with the mesher. */
int mx_mesher2d_set_size_function_(mx_mesher2d *m, mx_size_fn f, void *user,
                                   const mx_cspace_params *p);
int mx_mesher2d_set_size_expr_(mx_mesher2d *m, const char *text);
int mx_mesher2d_set_size_limits_(mx_mesher2d *m, double hmin, double hmax);
void mx_mesher2d_size_reset(mx_mesher2d *m);
void mx_mesher2d_size_free(mx_mesher2d *m);
/* With a field, its control space over the domain's box (the grid g's
 * roots of side g->side give the -f curves' sizes), once per source; sets
 * m->size_cells, size_hmin, size_at. MX_OK without a field. */
int mx_mesher2d_size_space(mx_mesher2d *m, const mx_qgrid *g);
/* The cell field target_size: the field at each cell's centroid (*out
 * allocated, ncells values), *out NULL without a field. MX_ENOMEM. */
int mx_mesher2d_target_sizes(const mx_mesher2d *m, double **out);

/* mesher2d_materials.c */
/* The regions of the domain's loops, and with nested loops the outer ones
 * (indexed) and the interfaces; once per domain. MX_EINPUT beyond
 * MX_MAT2D_MAX materials. */
int mx_mesher2d_materials_prepare(mx_mesher2d *m);
void mx_mesher2d_materials_free(mx_mesher2d *m);
void mx_mesher2d_materials_names_free(mx_mesher2d *m);
/* Several materials with nested loops (prepared). */
int mx_mesher2d_nested(const mx_mesher2d *m);
/* The loops the quadtree, the boundary step and the whole mesh's check
 * see: the outer ones with nested materials, else the domain. */
const mx_poly *mx_mesher2d_outer(const mx_mesher2d *m);
/* After the boundary step: the mesh cleaved along the interfaces (nested
 * loops) and m->material, m->nmaterials set. MX_EINPUT when two materials
 * end with one number. */
int mx_mesher2d_materials_label(mx_mesher2d *m);
/* Each material's cells checked against its loops (m->mat_report);
 * MX_EINVALID naming the first that fails. */
int mx_mesher2d_materials_check(mx_mesher2d *m, double tol);
/* The number and name of the material at depth d (the user's or the
 * defaults: d, "material <number>"); the depth of a number (0: none). */
int mx_mesher2d_material_number(const mx_mesher2d *m, int d);
void mx_mesher2d_material_name(const mx_mesher2d *m, int d, char *buf, size_t n);
int mx_mesher2d_material_depth(const mx_mesher2d *m, int number);
int mx_mesher2d_set_material_(mx_mesher2d *m, int depth, int number, const char *name);
/* The mesh written with its materials (mesher/qmesh_output.h), and the
 * cell field target_size when not NULL. */
int mx_mesher2d_write_materials(const mx_mesher2d *m, const char *path, int ascii,
                                const double *target_size);

#endif
