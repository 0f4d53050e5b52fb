/* Several materials (issue 26), first part: each element of the transition
 * stage's mesh gets the material of the region its centroid lies in, the
 * region's nesting depth in the input's shells (mesher/materials.c). */
#ifndef MX_MATERIALS_H
#define MX_MATERIALS_H

#include "mesher/mesher.h"

/* MX_OK, or MX_EINPUT with a message when params.materials asks for what
 * this version does not do yet: the full stage (interfaces on the input
 * surfaces), re-meshing (`what`: the re-meshing call's name; NULL for
 * meshing), the winding-number domain of repair_input. */
int mx_materials_allowed(const mx_mesher *m, const char *what);
/* M.material of every element (the depth of its centroid in the index
 * built outward) and m->nmaterials (the deepest). MX_ENOMEM. */
int mx_label_materials(mx_mesher *m);
/* Its two halves, for a mesh that is not m->M (a rank's part of the
 * distributed mesh, src/mpi/p4est_mesh.c), whose deepest region may need
 * the other parts' first. mx_material_depths: M->material of each element
 * its region (nesting depth and file, 1 ..), from M's geometry alone
 * (leaves: the octree leaves M->leaf indexes, nleaves of them, in m's
 * octree; states per node or NULL; stage: the stage that made M), the
 * deepest region met and the elements across an interface (where: the
 * first one's centroid when there are, or NULL).
 * mx_material_relabel: the regions 1 .. deepest (the deepest over every
 * part) numbered as the user asked (mx_material_numbers). MX_ENOMEM,
 * MX_EINPUT. */
int mx_material_depths(mx_mesher *m, mx_mesh *M, const uint32_t *leaves, size_t nleaves,
                       const uint8_t *states, int stage, int *deepest, size_t *across,
                       double where[3]);
int mx_material_relabel(mx_mesher *m, mx_mesh *M, int deepest);

/* The numbers and names of the materials by depth 1 .. deepest
 * (m->depth_material*): the user's for the inputs given one, the depth
 * otherwise. MX_EINPUT when an input's shells nest at several depths, two
 * inputs at one depth are given different numbers, or two materials end
 * with one number (src/mesher/material_names.c). */
int mx_material_numbers(mx_mesher *m, int deepest);
/* Touching inputs (src/mesher/material_inputs.c): the triangles two input
 * files have in common (the same three corners) leave the domain's soup;
 * one copy of each becomes a region surface refined where met, at the
 * surface level; the inputs as given stay in m->material_src with
 * m->material_shared flagging the common triangles, for the pieces.
 * Nothing changes when there are none. MX_ENOMEM, MX_EINPUT. */
int mx_materials_split_shared(mx_mesher *m);
/* An input with edges of three triangles or more (a surface with internal
 * faces) split into an input per region it bounds, each its region's outer
 * shell turned outward, named "FILE region k" (the first keeps the file's
 * place); to: the domain's welded vertex of each vertex
 * (src/mesher/material_complex.c). MX_ENOMEM, MX_EINPUT. */
int mx_materials_split_complex(mx_mesher *m, const uint32_t *to);
/* The volume the outermost shells of the index (built outward) enclose,
 * the domain of several materials, and their area. MX_ENOMEM. */
int mx_materials_domain_volume(const mx_mesher *m, double *volume, double *area);
/* The name of material d (its region at nesting depth d): the input file
 * whose shells bound it from outside (all of them at depth d - 1, and no
 * other file's there), without its folder and extension; "material d"
 * otherwise. */
int mx_material_name(const mx_mesher *m, int d, char *buf, size_t n);

#endif
