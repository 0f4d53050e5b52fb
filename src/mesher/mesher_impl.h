/* Shared by the files of src/mesher: one public call's set-up and tear-down
 * (the mesher's message handler installed, then restored), and the
 * steps the calls share. */
#ifndef MX_MESHER_IMPL_H
#define MX_MESHER_IMPL_H

#include "base/common.h"
#include "mesher/call.h"
#include "mesher/mesher.h"
#include "soa/mesh_data.h"

void mx_call_begin(const mx_mesher *m, mx_call *c);
/* Restores what mx_call_begin changed. Returns the status to give the
 * caller. */
int mx_call_end(const mx_mesher *m, mx_call *c, int status);

void mx_mesh_clear(mx_mesher *m);   /* drop the mesh */
void mx_tree_clear(mx_mesher *m);   /* drop the octree and the mesh */
int mx_update_leaves(mx_mesher *m); /* leaves of the octree, Morton order */
int mx_mesh_stages(mx_mesher *m);   /* the stages up to params.stage */
int mx_mesh_full(mx_mesher *m);     /* transition + boundary, whole octree */
int mx_repair(mx_mesher *m);        /* repair rounds on the full-stage mesh */
/* Whether the repair goes on after round `round` left `defects`: none left,
 * the rounds spent, or two rounds since the best one that did not lower the
 * count of the round before stop it (p: the caller's, zeroed at first). */
typedef struct {
  uint64_t best, last; /* the least count so far; the round before's */
  int worse;           /* rounds since the best that did not lower the count */
} mx_repair_progress;
int mx_repair_go_on(int round, uint64_t defects, int max_rounds, mx_repair_progress *p);
/* The input file a message about the whole mesh names, or "the inputs a,
 * b" (in buf) when there are several; NULL without an input. Every exit-5
 * message (MX_EINVALID) names it. */
enum { MX_INPUTS_LABEL = 512 };
const char *mx_inputs_label(const mx_mesher *m, char *buf, size_t n);
int mx_mesh_finish(mx_mesher *m);   /* flags, counts; MX_EINVALID if invalid */
/* --tets (mesher/tets.c): the mesh split into tetrahedra and checked
 * again, the mixed mesh kept (nothing without params.tets, or done);
 * MX_EINVALID when an element cannot be split or the check fails. */
int mx_mesher_tets(mx_mesher *m);
/* The mixed mesh back in place of the tetrahedra (a re-mesh edits it). */
void mx_mesher_untets(mx_mesher *m);
/* The sum of the elements' signed volumes; the domain volume check on a
 * mesh of that volume and ncells elements (MX_EINVALID, message given,
 * when it holds much more or less than the input encloses). */
double mx_mesh_volume(const mx_mesh *M);
int mx_volume_verdict(mx_mesher *m, double vm, size_t ncells);
/* After a refinement of the octree (old_leaves: the leaves before it, in
 * Morton order): the transition and boundary stages again, only on the
 * leaves around what was split when the current mesh allows it
 * (remesh_patch.c), else on the whole octree. Does not repair. */
int mx_remesh_changed(mx_mesher *m, const uint32_t *old_leaves, size_t nold);
/* The leaves of the refined octree, then mx_remesh_changed from the leaves
 * the mesher held. */
int mx_remesh_after_refine(mx_mesher *m);
/* The choice of mx_remesh_changed (params.remesh_full 0): 1 when a local
 * re-mesh of a patch of np leaves of the nl leaves, whose core has nborder
 * leaves on its border, is expected to cost less than meshing all nl again,
 * a refused splice's cost counted (the cost model in remesh_patch.c).
 * Increasing in np and nborder. */
int mx_remesh_local_pays(size_t np, size_t nborder, size_t nl);
/* A label image's mesh after the transition stage (image_mesh.c): each
 * element the label of its leaf, the background's dropped, the nodes on
 * an interface moved onto the smoothed interface (as far as the elements
 * stay valid), the world by the image's transform, the volume judged
 * against the voxels'. MX_ENOMEM, MX_EINVALID. */
int mx_image_mesh_finish(mx_mesher *m);
/* A label image's octree (image_input.c): the split keys of its blocks of
 * one label, each split further while coarser than its label asks or
 * wider in the world than the size field (m->size_F, built) over it;
 * MX_EINPUT for curvature or thickness sources (no surface), MX_ENOMEM
 * over the budget. The world box of the image (the size field's). */
int mx_image_split_keys(mx_mesher *m);
void mx_image_world_box(const mx_mesher *m, double lo[3], double hi[3]);
/* The domain input's sharp features counted for the report (mesher.c). */
int mx_mesher_features(mx_mesher *m);
/* The boxes that keep the features apart (mesher/feature_apart.c), after
 * the user's, in m->feature_boxes; root_side: the octree's. */
int mx_feature_apart_boxes(mx_mesher *m, double root_side);
/* The arrays and file name an mx_image_params holds (image_input.c). */
void mx_image_params_release(mx_image_params *ip);
/* One domain input appended to m->domain under name (copied; s is left
 * as it was): MX_EINPUT past 64 inputs or after the octree was built. */
int mx_mesher_add_domain(mx_mesher *m, mx_trisoup *s, const char *name);
/* The inputs assembled into m->soup once (inputs.c): the input policy,
 * the domain's triangles, then each region's. */
int mx_mesher_assemble_inputs(mx_mesher *m);
/* The volume a closed surface encloses (signed: negative inside out), and
 * in *area (may be NULL) its area (inputs.c). */
double mx_enclosed_volume(const mx_trisoup *d, double *area);
int mx_build_tree(mx_mesher *m);    /* grid, refine, balance, leaves */
/* The side of the domain the builder B (over m's soup) locates octants
 * by: the ray parity, or with repair_input the winding number and with
 * materials (shells nested) the index built outward (the outermost shells'
 * insides whole, nested shells not holes). mx_build_tree and the
 * distributed forest (src/mpi/p4est_inputs.c) both set it here. */
int mx_mesher_domain_side(mx_mesher *m, mx_builder *B);
/* --repair-input on an input with no well-defined inside (winding_domain.c):
 * m->WI, and in *boundary (empty on entry) the boundary of the winding
 * number's domain, which replaces the input in the soup; MX_EINPUT when the
 * domain is empty. */
int mx_winding_domain(mx_mesher *m, mx_trisoup *boundary);
/* The volume of that domain (the volume rule's reference). */
double mx_winding_domain_volume(const mx_mesher *m);
/* The split set (m->split_keys, replaced) of an octree with the leaves
 * (key[i], level[i]), i < n, in any order: every ancestor of a leaf is
 * split; mx_build_tree then refines from the roots through it
 * (restart_octree.c). MX_OK or MX_ENOMEM. */
int mx_mesher_set_split_keys(mx_mesher *m, const uint64_t *key, const uint8_t *level, size_t n);
mx_requests mx_mesher_requests(const mx_mesher *m);
/* The size field's control space over the domain's box, built once per
 * source (mesher/size_field.c); and freeing it with the source. */
int mx_mesher_size_space(mx_mesher *m);
void mx_mesher_size_free(mx_mesher *m);
/* Whether any source of a size field is set. */
int mx_mesher_has_size(const mx_mesher *m);
/* Write the mixed mesh (src/mesher/output.c): written order, boundary tags
 * and bodies, fields. */
int mx_write_mixed(const mx_mesher *m, const char *path, int ascii);
/* near[v] = 1 for the nodes a boundary face of the full-stage mesh can have
 * (src/mesher/output.c): those of leaves meeting the input and the outside
 * ones. */
int mx_boundary_candidates(const mx_mesher *m, uint8_t *near);
/* m->bnd made exact (the nodes of the faces used once) when it is not:
 * the writers' tags do it on the way (src/mesher/output.c). */
int mx_boundary_flags_exact(const mx_mesher *m);
/* The order the mesh files list the cells in (src/mesher/output.c). */
int mx_written_order(const mx_mesher *m, uint32_t *order);
/* The octree's figures (leaves, hash, octants, edges, splits) into m->rec->S. */
void mx_fill_tree_stats(mx_mesher *m);

/* The view of the mesh the writers get (mesher/output.c: bodies, boundary
 * faces and their tags, materials), handed to fn for the time of the call
 * (mesher/boundary_arrays.c reads it). */
int mx_with_written_view(const mx_mesher *m, int (*fn)(void *ctx, const mx_mesh_view *v),
                         void *ctx);
/* Drops what the writers keep of the mesh (written order, boundary faces
 * and tags, made once per mesh by the first write: mesher/output.c). Every
 * call that changes the mesh (or may) calls it first. */
typedef struct mx_written mx_written;
void mx_written_forget(mx_mesher *m);
/* The same for the memory's sake (the mesh is as it was: the next write
 * makes them again). */
void mx_written_release(const mx_mesher *m);

/* The checker's view (verify/check.h) of a mesh: nodes and elements, no
 * fields (mesher.c). */
mx_mesh_data mx_mesh_data_of(const mx_mesh *M);

#endif
