/* The mesher object behind include/mixoct.h: what it keeps between calls,
 * and the figures of a run (mx_summary, printed by mx_mesher_print_report,
 * src/mesher/report.c). Private to the library: the programs in src/cli
 * include only mixoct.h. */
#ifndef MX_MESHER_H
#define MX_MESHER_H

#include <stdatomic.h>

#include "mixoct.h"

#include "kernels/boundary_stage.h"
#include "kernels/feature_place.h"
#include "kernels/contacts.h"
#include "geom/distance.h"
#include "geom/quality.h"
#include "kernels/refine.h"
#include "kernels/splice.h"
#include "kernels/transition.h"
#include "io/file_identity.h"
#include "kernels/winding_boundary.h"
#include "mesher/size_source.h"
#include "soa/regions.h"
#include "soa/trisoup.h"
#include "sizing/sources.h"
#include "geom/label_fix.h"

/* The last label image added, for the report. */
typedef struct {
  char format[16];
  int64_t dims[3];
  double spacing[3];
  int oblique;
  size_t rounded;
  int nlabels;          /* labels meshed */
  int32_t labels[64];
  char names[64][64];   /* their materials' names */
  size_t voxels[64];    /* their voxels, after the fixes */
  size_t faces[64];     /* their voxel faces on an interface */
  double volume[64];    /* their volume in the mesh */
  size_t moved;         /* nodes moved onto the smoothed interfaces */
  double seconds_mesh;  /* labels, moves, world (mx_image_mesh_finish) */
  double voxel_volume;  /* |det A|: one voxel in the world */
  mx_label_fix_stats fix;
  double seconds;       /* the labels made ready (mx_mesher_add_label_array) */
} mx_image_info;

typedef struct {
  double read, grid, refine, balance, transition, boundary, verify, quality, write, total;
} mx_phases;

typedef struct {
  size_t leaves, nodes, octants, edges, located, split_requested,
      split_balance, dropped;
  uint64_t leaves_hash;
  size_t edge_bytes;
  int threads;
  int balance;
  int max_level;
  int nodes_counted;
  int mesh;                 /* a mixed mesh was built (not only leaves) */
  size_t elements, by_type[4], invalid, closures, centre_leaves;
  double jens_min;
  mx_quality_table quality;
  double memory_estimate_mb; /* from the octree's leaves once known */
  double memory_prior_mb;    /* from the surface area, before refining */
  mx_phases ph;
  double peak_rss_mb;
  int full;                 /* the boundary stage ran */
  mx_boundary_stats boundary;
  size_t repaired;          /* invalid elements found before a repair round */
  mx_contacts contacts;     /* geometric hanging nodes of the final mesh */
  size_t contacts_repaired; /* elements split for contacts in repair rounds */
  size_t contacts_local;    /* searches around a local re-mesh's core only */
  int repair_rounds;
  size_t refined_listed;    /* leaves split by the last list refinement */
  size_t remesh_splits;     /* octants split by the last re-mesh (list, balance, requests) */
  double t_restart;         /* seconds reading or writing the restart file */
  /* the last re-mesh after a refinement (remesh_patch.c) */
  size_t reoriented;        /* input triangles flipped by the input policy */
  double volume_error;      /* (mesh - enclosed) / enclosed, one closed input */
  int input_repaired;       /* the domain is the winding number's (repair_input) */
  /* sharp features of the domain's input (geom/features.h; angle 0: none) */
  double feature_angle;
  size_t feature_edges, feature_ridges, feature_corners;
  double feature_length, feature_seconds;
  mx_feature_stats feature_place; /* placed in the mesh (kernels/feature_place.h) */
  int features_kept;              /* the placement ran */
  int feature_noise;              /* found, mostly dangling: not kept */
  int feature_fallback;           /* kept, broke the mesh: meshed again without */
  int feature_file;               /* the lines read from a file */
  size_t feature_dangling;        /* ridge edges dropped (free ends, short networks) */
  int feature_measured;           /* the distances below (mx_mesh_finish) */
  double feature_ridge_dist, feature_corner_dist; /* over the input's diagonal */
  size_t feature_apart_boxes;     /* boxes refining where features come close */
  const mx_image_info *image; /* a label image's mesh (image_mesh.c), NULL otherwise */
  mx_winding_boundary_stats winding; /* its boundary (input_repaired) */
  int local;                /* 1: every re-mesh of the call was local */
  int local_attempts;       /* patches tried (more rings when one fell short) */
  size_t patch_leaves;      /* leaves meshed again (core and context) after */
  size_t core_leaves;       /* the refinement (before repair rounds); of them,
                             * those whose elements were kept */
  mx_splice_stats splice;
  int nmaterials;           /* materials: the deepest region (0: one material) */
  size_t materials_shared;  /* materials: triangles two inputs have in common (pairs) */
  size_t materials_across;  /* elements with corners in two regions */
  double materials_across_at[3]; /* the first one's centroid */
  double t_materials;       /* seconds labelling the elements */
  /* the size field's control space (issue 27), when there is one */
  int size_field, size_structure, size_split;
  size_t size_leaves;
  int size_depth, size_capped;
  double size_kb, size_seconds;
  /* its discrete sources (sizing/sources.h): how many of each kind, the
   * gradation ratio, the tree's memory and build time (sampling included) */
  size_t size_sources, size_curvature_n, size_thickness_n, size_map_n, size_graded_n;
  double size_beta, size_src_kb, size_src_seconds;
  /* --tets (kernels/tet_split.h): the mixed mesh split, its elements by
   * type, the tetrahedra made, Steiner nodes, hexahedra split into 5, the
   * seconds of the split and of the check of the tetrahedra, and the
   * volumes (tetrahedra; the mixed elements bounded by the same triangles;
   * the mixed mesh as mx_element_volume measures it) */
  int tets;
  size_t tets_from, tets_from_by_type[4], tets_made, tets_steiner, tets_five;
  double t_tets, t_tets_check, tets_volume, tets_volume_mixed, tets_volume_fan;
} mx_summary;

/* What a call records even when it only reads the mesher: the last error,
 * the figures of the run (the timers of writing and of the restart file
 * among them) and the octree stage's hexahedra, made by its first write. */
typedef struct {
  mx_message_fn fn;         /* the user's message handler (NULL: stderr) */
  void *user;
  char last_error[1024];
  mx_summary S;
  mx_mesh hex;              /* MX_STAGE_OCTREE: the leaves as hexahedra */
  int have_hex;
  /* what the writers add to the mesh (written order, boundary faces, tags,
   * bodies), made by the first write after the mesh changed; NULL until
   * then (mesher/output.c, dropped by mx_written_forget) */
  struct mx_written *written;
  /* m->bnd is the nodes of the faces used once (mx_boundary_flags_exact);
   * 0: only the outside nodes, which miss the inside nodes lying on the
   * surface (lattice nodes on flat parts of the input) */
  int bnd_exact;
} mx_mesher_record;


/* Remembers a file the mesher read (restart: 1 for the restart file). */
void mx_mesher_note_read(mx_mesher *m, const char *path, int restart);
/* MX_OK, or MX_EINPUT with a message when path is a file the mesher read
 * (restart_out: the restart file written, which may replace the one read). */
int mx_mesher_spares_inputs(const mx_mesher *m, const char *path, int restart_out);


struct mx_mesher {
  mx_params p;

  /* inputs: the domain's shells; region surfaces apart until the octree is
   * first built, then appended after the domain's triangles in soup */
  mx_trisoup domain, soup;
  int ndomain;
  char *domain_name[64];
  int nregions;
  mx_trisoup region[MX_MAX_REGIONS];
  char *region_name[MX_MAX_REGIONS];
  int region_level[MX_MAX_REGIONS];
  unsigned region_meet_only; /* bit r: refined where met only (mx_requests) */
  /* the size field (issue 27, mesher/size_field.c): its source, bounds,
   * the control space's parameters, and the control space built from them
   * over the domain's box with the octree (kept until the source changes) */
  mx_size_source size;
  /* the discrete sources (sizing/sources.h): curvature (radians, 0: none),
   * elements across parts and gaps (0: none), the gradation ratio (0: the
   * default, 2, applied to the discrete sources only; set: to the
   * function's control space too), boxes with sizes (a size map's points,
   * boxes of zero extent, or a size per element over its box: owned, 6
   * coordinates, lo and hi, and 1 size each), and the tree built with the
   * octree */
  double size_curvature, size_thickness, size_gradation;
  double *size_map_box, *size_map_h;
  size_t size_map_n;
  char *size_map_name; /* where the points came from, for messages */
  struct mx_size_sources *size_src;
  size_t size_src_curvature, size_src_thickness, size_src_map, size_src_graded;
  mx_size_field size_F;      /* the whole field, read by the requests */
  uint32_t nt_domain, region_t0[MX_MAX_REGIONS + 1];
  int assembled;            /* soup holds domain + regions */
  mx_box_region *boxes;
  size_t nboxes;
  /* the files read (surfaces, boxes, restart file): no output may replace
   * one (the restart file written may replace the one read) */
  mx_file_id read_id[64 + MX_MAX_REGIONS + 8];
  uint8_t read_restart[64 + MX_MAX_REGIONS + 8];
  int nread;

  /* the octree, its leaves in Morton order */
  int have_tree;
  mx_builder B;
  uint32_t *leaves;
  size_t nleaves;
  uint64_t *split_keys[MX_MAX_LEVEL + 1]; /* restart: split octants, */
  size_t nsplit[MX_MAX_LEVEL + 1];        /* per level, sorted */
  /* restart read, not meshed yet: element of the file's mesh -> leaf */
  uint32_t *file_leaf;
  size_t file_nelem;
  int file_by_type;         /* its element lists number the elements grouped
                             * by type (a mixoct file, mx_restart.by_type) */

  int have_index;
  mx_surface_index SI;
  /* --materials: the inputs' pieces (kernels/interfaces.h), built with the
   * index; material_src: the inputs as given when they share triangles
   * (the domain's soup has neither copy of those), material_shared: one
   * byte per triangle of it, 1 for the shared ones */
  mx_interfaces IF;
  mx_trisoup material_src;
  uint8_t *material_shared;
  /* --repair-input on an input with no well-defined inside
   * (winding_domain.c): the input's index, orientation as given, whose
   * winding number decides the sides; the soup's domain triangles are then
   * the boundary of its domain, of signed volume winding_volume (the
   * domain's when winding_whole: the winding number takes whole values) */
  int have_winding, winding_whole;
  mx_surface_index WI;
  double winding_volume;

  /* the mesh: the stage reached (-1: none) */
  int mesh_stage;
  mx_mesh M;
  uint8_t *states;          /* per node (boundary stage), or NULL */
  uint8_t *bnd;             /* per node: 1 on the boundary (rec->bnd_exact) */
  /* the contact search (mx_repair) after a local re-mesh: the last search
   * found no contact on the mesh whose elements' array was clean_conn
   * (clean_ncells elements; contacts_clean), and the splice that replaced
   * that mesh changed only what lies in changed_box (changed_valid; see
   * mx_find_contacts_in) */
  int contacts_clean, changed_valid;
  const uint32_t *clean_conn;
  size_t clean_ncells;
  double changed_box[6];
  /* What calls record: behind a pointer, so that the calls that take the
   * mesher const (writing, the arrays) record without casting const away */
  mx_mesher_record *rec;
  /* 1: free the edge infos once the transition has read them (the program:
   * one mesh, its memory to the mesh; a split rebuilds them). 0 (the
   * library's default): keep them for the refinements of a re-meshing loop
   * (about 90 B per leaf). */
  int release_edges;
  int out_fields; /* MX_FIELDS_*: the fields the mesh files carry */
  int nmaterials;           /* materials: the deepest nesting (M.material) */
  /* materials as the user numbers and names them (mx_mesher_set_material):
   * per domain input, the number (0: not given) and name of the material
   * inside it; per depth 1..nmaterials, the number and name given it (the
   * depth and no name by default), set when the elements are labelled */
  int32_t input_material[64];
  int8_t input_slevel[64], input_ilevel[64]; /* mx_mesher_set_input_level (0: none) */
  char *input_material_name[64];
  int32_t depth_material[65];
  const char *depth_material_name[65];
  /* hooks for the program's progress line (NULL: none) */
  mx_progress progress;     /* mx_mesher_set_progress */
  /* label images (mesher/image_input.c): the options (arrays owned), and
   * what the image gave */
  mx_image_params image_params;
  mx_image_info image;
  double feature_angle;     /* mx_mesher_set_feature_angle (-1: the default, 30) */
  /* the domain's features, found with the tree (mx_mesher_features), and
   * their lines, placed after the boundary stage (pipeline.c) */
  int have_features;
  int feature_level;  /* mx_mesher_set_feature_level (0: none) */
  char *feature_file; /* mx_mesher_set_feature_file (NULL: found on the surface) */
  int feature_region; /* the region of the ridges' segments (-1: none yet) */
  mx_box_region *feature_boxes; /* the user's boxes and those keeping features apart */
  size_t nfeature_boxes;        /* (mesher/feature_apart.c), with the tree */
  mx_features feat;
  mx_feature_lines feat_lines;
  /* the feature distances measured on the mesh as it is (by the check of
   * its boundary near them, mx_mesh_stages), for mx_mesh_finish to take */
  int feature_dist_fresh;
  /* a label image meshed on its voxel lattice (mesher/image_mesh.c): the
   * padded labels made ready, the transform, the voxel level, the grid */
  int image_lattice, image_R, image_rounds;
  int32_t *image_lab;
  uint8_t *image_want; /* per label: the level asked inside it (65536) */
  int64_t image_n[3];
  double image_A[12];
  mx_grid image_grid;
  /* --tets (mx_params.tets): M holds the tetrahedra, Mmix the mixed mesh
   * they were cut from (a re-mesh starts from it) */
  int have_mix;
  mx_mesh Mmix;
  uint32_t *tet_parent; /* per tetrahedron: its element in Mmix */
  atomic_int cancel; /* mx_mesher_cancel (base/cancel.h) */
};


/* The figures of the last run (counts, phases, boundary steps). */
const mx_summary *mx_mesher_summary(const mx_mesher *m);

#endif
