/* Each rank meshes its part of the distributed octree (issue 14, item 3).
 *
 * The mesh of a leaf depends on the leaves around it: its transition
 * pattern on its neighbours' nodes (one ring), the boundary steps (node
 * states, projection, surface patterns, shrink, untangling, staircase) on
 * the elements a few rings out. So each rank meshes a patch, as the local
 * re-mesh does (src/mesher/remesh_patch.c): its own leaves (the core) and
 * `rings` layers of ghost leaves around them (p8est_ghost_expand), with the
 * single-process pipeline (mx_transition, mx_boundary_stage) on an octree of
 * our own made straight from the patch's leaves and the data they carry
 * (p4est_tree.h: no second refinement); it keeps the core's elements.
 *
 * Agreement on the partition boundary. A node that elements of two ranks
 * use was computed by both (each has the other's elements next to its core
 * in its patch). Every rank sends each neighbour rank the nodes it shares
 * with it (lattice key, position, state), sorted by key, and compares what
 * it receives with its own list: the same keys, bit-identical positions and
 * states. Any difference anywhere (the boundary steps reached further than
 * the rings) and every rank meshes again with twice the rings; after the
 * last attempt the run fails, naming the first node. So no rank moves a
 * node another rank owns differently: the shared nodes are computed alike
 * on both sides, and checked to be.
 *
 * Materials. With several materials the patch is cleaved along the
 * interfaces as the single-process mesh is (kernels/cleave.c: the cut
 * nodes between two lattice nodes carry a key made from theirs, so the
 * ranks match them as lattice nodes, and its choices do not depend on the
 * node numbering, which differs between a patch and the whole mesh); each
 * core element is labelled from the geometry alone (mesher/materials.h).
 *
 * Numbering. A shared node is owned by the lowest rank using it; each rank
 * numbers its owned nodes in its order (elements grouped by leaf in Morton
 * order, nodes by first use), offset by an exclusive scan of the owned
 * counts; owners send the global numbers of shared nodes to the others.
 *
 * Everything here is collective over P->comm. */
#ifndef MX_P4EST_MESH_H
#define MX_P4EST_MESH_H

#include "mesher/mesher.h"
#include "mpi/p4est_octree.h"

typedef struct {
  /* this rank's part: its leaves' elements, nodes in first-use order */
  mx_mesh M;
  uint8_t *states;        /* per node, kernels/boundary.h */
  uint64_t *gid;          /* per node: global number, 0-based */
  uint8_t *owned;         /* per node: 1 when this rank owns it */
  uint64_t first_owned, nowned;
  /* global */
  uint64_t nodes, cells, by_type[4], invalid, contact_cells, leaves;
  double jens_min, volume;
  uint64_t hash_sum;      /* sum of the elements' hash terms (io/mesh_hash.h) */
  /* several materials (m->p.materials): M.material per element, labelled
   * on each rank's core elements as the single-process mesher labels its
   * own (mx_material_depths, then the numbers once the deepest region is
   * known over every rank); per region 1 .. nmaterials its elements and
   * volume, the elements across an interface (global) */
  int nmaterials;
  uint64_t material_cells[65], across;
  double material_volume[65];
  int32_t material_id[65];       /* per region: its number and name */
  char material_name[65][128];   /* (mx_material_name) */
  /* this rank */
  int rings;              /* halo rings of the accepted attempt */
  int attempts;
  int repair_rounds;      /* rounds of the repair (global) */
  long long repaired;     /* leaves split by them (global) */
  uint64_t *defect_key;   /* this rank's leaves with defects, sorted */
  size_t ndefect;
  float worst_jens;       /* this rank's lowest J_ENS, and the key of its leaf */
  uint64_t worst_key;     /* (the smallest key among equal J_ENS) */
  uint64_t differ_first;   /* shared-node differences of the first attempt (global) */
  size_t core_leaves, patch_leaves, tree_leaves;
  double estimate_mb;     /* the memory estimated for the patch (check_memory) */
  size_t shared_nodes;    /* nodes another rank's elements use too */
  long long sent_bytes;   /* node records sent to other ranks, every attempt */
  long long largest_message; /* bytes, to one rank in one exchange */
  double t_halo, t_tree, t_transition, t_boundary, t_exchange;
  /* MX_P4EST_CHECK_TREE (p4est_tree.h): patch leaves whose octree made from
   * the leaves was compared with the one refined again (this rank, then
   * summed over the ranks by the mesh's figures) */
  uint64_t tree_checked;
} mx_p4est_mesh;

/* Repair, as the single-process mesher does (mx_repair): while elements
 * with J_ENS < 1e-6 or nodes lying on elements they are not a node of
 * remain, their leaves are split once (mx_p4est_refine_listed), the forest
 * balanced and partitioned again, and everything meshed again, up to
 * m->p.repair_rounds rounds, stopping when the defects grow twice in a row
 * (counted in elements here). For the tests, MX_P4EST_TEST_REPAIR=1 in the
 * environment makes the leaf of the element with the lowest J_ENS (the
 * smallest key among equal ones) a defect in the first round: the repair
 * path runs on any input.
 *
 * m: the rank's mesher with the inputs and requests the forest was built
 * from (its requests are cleared here: the octree of m becomes the patch's).
 * P: built by mx_p4est_build. D: zeroed by the caller. MX_OK, or an error
 * with a message (the same status on every rank). */
int mx_p4est_mesh_build(mx_p4est_octree *P, mx_mesher *m, mx_p4est_mesh *D);
/* Exit 0 is only for a non-empty mesh with no element left with J_ENS <
 * 1e-6, no node lying on an element it is not a node of, holding the
 * volume the input encloses (mx_volume_verdict); else the status, with
 * the message, on every rank. */
int mx_p4est_mesh_verdict(const mx_p4est_octree *P, mx_mesher *m, const mx_p4est_mesh *D);
/* The hash `mixoct check` computes from a file (io/pvtu.h), over every
 * rank's elements (p4est_output.c). */
uint64_t mx_p4est_mesh_hash(const mx_p4est_octree *P, const mx_p4est_mesh *D);
/* What a path is written as: 1 .pvtu (a piece per rank with GlobalNodeId,
 * rank 0 the master; all of them or nothing), 2 .msh (one binary Gmsh file,
 * MPI-IO: write_msh_mpi.h), 0 neither (not collective). */
int mx_p4est_output_kind(const char *path);
int mx_p4est_mesh_write(const mx_p4est_octree *P, const mx_p4est_mesh *D, const char *path);
void mx_p4est_mesh_free(mx_p4est_mesh *D);

#endif
