/* libmixoct: the mixed-element octree mesher as a library.
 *
 * From closed triangulated surfaces and refinement requests to a conforming
 * mesh of hexahedra, prisms, pyramids and tetrahedra (Jaillet & Lobos 2021;
 * Lobos & Gonzalez 2015), and re-meshing of that mesh without starting over.
 *
 * A mesher object keeps, between calls, the input surfaces, the requests,
 * the balanced octree with its edge infos, the current mesh and the map from
 * each element to the octree leaf it came from:
 *
 *   mx_params p;  mx_params_default(&p);  p.surface_level = 5;
 *   mx_mesher *m = mx_mesher_new(&p);
 *   mx_mesher_add_surface(m, "cortex.off");
 *   mx_mesher_mesh(m);                        // octree, transition, boundary
 *   mx_mesh_arrays a;  mx_mesher_mesh_arrays(m, &a);   // no copy
 *   mx_mesher_write(m, "cortex.vtu", 0);
 *   mx_mesher_save_restart(m, "cortex.oct");
 *   uint64_t bad[] = {12, 40};                // elements with a large error
 *   mx_mesher_refine_elements(m, bad, 2);     // Algorithm 3, then re-mesh
 *   mx_mesher_free(m);
 *
 * Every function returning int returns a status (mx_status): MX_OK or the
 * class of the failure; the message that explains it (naming the file and
 * line for bad input) goes to the mesher's message handler (stderr, prefixed
 * "mixoct: ", unless replaced) and is kept as mx_mesher_last_error. A failed
 * call leaves the mesher as it was before the call, or, for a failure inside
 * meshing, without a mesh (mx_mesher_mesh can be called again).
 *
 * Threads: every pass is parallel (OpenMP); mx_params.threads sets how many
 * (0: OMP_NUM_THREADS, else one per processor). The result does not depend
 * on the thread count. With threads 0, when the environment chose no OpenMP
 * wait policy (neither OMP_WAIT_POLICY nor GOMP_SPINCOUNT was set when the
 * library was loaded), a call runs with at most as many threads as there
 * are processors left free by the running threads of other processes (at
 * least one), read from /proc at the start of the call and between its
 * stages (tens of microseconds): libgomp's default policy makes a waiting
 * thread spin, and when another job holds a core the spinning thread takes
 * the time slice of the thread it waits for (2 threads then run several
 * times slower than 1). mx_params.threads > 0, or a wait policy set before
 * the process starts (OMP_WAIT_POLICY=passive suits a shared machine),
 * turns this off; mx_last_call_threads tells the count a call ran with.
 * One mesher must not be used by two threads at once; two meshers may be
 * used at once from two threads: each call's messages go to its own
 * mesher's handler, and its thread count is its own. Mesh arrays are the mesher's own memory: they stay
 * valid until the next call that changes the mesh (refine, mesh, load,
 * free), and nothing tells a holder that they went stale. */
#ifndef MIXOCT_H
#define MIXOCT_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Status codes; the programs exit with the same numbers. */
typedef enum {
  MX_OK = 0,
  MX_EINTERNAL = 1, /* a bug or an unexpected system failure */
  MX_EINPUT = 2,    /* bad input file, bad argument, bad usage */
  MX_ENOMEM = 3,    /* out of memory, or over the memory budget */
  MX_EIO = 4,       /* an output could not be written (permission, disk) */
  MX_EINVALID = 5,  /* the mesh breaks the validity contract (J_ENS < 1e-6) */
  MX_ECANCELED = 6, /* cancelled (mx_mesher_cancel): no mesh is left */
} mx_status;

/* Element types, and their node counts: 4, 5, 6, 8. Node order: VTK's for
 * tetrahedra, pyramids and hexahedra; Gmsh's for prisms (the triangle 0 1 2
 * turns, by the right hand, towards 3 4 5). */
enum { MX_TET = 0, MX_PYRAMID = 1, MX_PRISM = 2, MX_HEX = 3 };

/* How far mx_mesher_mesh goes. */
enum {
  MX_STAGE_OCTREE = 0,     /* the balanced leaves only */
  MX_STAGE_TRANSITION = 1, /* the conforming mesh of the whole octree */
  MX_STAGE_FULL = 2,       /* the domain's mesh: boundary stage, repair */
};
enum { MX_BALANCE_EDGES = 0, MX_BALANCE_RECURSIVE = 1 };

/* The heap as the mixoct program sets it (call once, before meshing; the
 * library does not call it): arrays of 1 MB and more mapped on their own and
 * given back when freed, so the peak is what is alive. The environment
 * variable MX_HEAP=heap keeps every freed array in the heap instead,
 * MX_HEAP=default leaves the C library's settings. */
void mx_heap_setup(void);

/* The OpenMP thread count the calling thread's last mesher call (3D or 2D)
 * ran with, after the load limit (see "Threads" above): the fewest of its
 * stages when the limit changed it between them; 0 before any call. */
int mx_last_call_threads(void);

/* Message levels given to the handler. */
enum { MX_MSG_ERROR = 0, MX_MSG_WARNING = 1 };
typedef void (*mx_message_fn)(void *user, int level, const char *text);

typedef struct {
  int surface_level;   /* -s: octants meeting the domain surface; -1 none */
  int all_level;       /* -a: every octant of the domain; -1 none */
  int stage;           /* MX_STAGE_*, default MX_STAGE_FULL */
  int balance;         /* MX_BALANCE_*, default MX_BALANCE_EDGES */
  int threads;         /* 0: the OpenMP default */
  double max_memory_mb; /* refuse runs estimated above; 0: memory available */
  double close_ratio;   /* remove-close distance, 0: 0.5 (see boundary) */
  double staircase_quality; /* 0: 0.2 (the papers) */
  int repair_rounds;   /* list refinements of the leaves of invalid elements and contacts, 10 */
  int repair_input;    /* 1: an input with no well-defined inside (open,
                        * non-manifold, self-intersecting, crossing) is meshed
                        * where its generalized winding number is above 1/2;
                        * 0 (default): such an input is refused (MX_EINPUT) */
  int remesh_full;     /* 1: after a refinement, mesh the whole octree again;
                        * 0 (default): only the leaves around what was split
                        * (the rest of the mesh is kept as it was) when that
                        * is expected to cost less than the whole octree;
                        * -1: the leaves around what was split, whatever the
                        * cost (benchmarks, tests) */
  int materials;       /* 1: several materials (--materials): the shells
                        * nested in the outermost are not holes; each
                        * element gets the material of the region it is in,
                        * numbered by nesting depth (1: inside one shell, 2:
                        * inside two, ...; 0: outside every shell). This
                        * version labels the transition stage's elements by
                        * their centroid (MX_STAGE_TRANSITION; the full stage
                        * and re-meshing refuse it, MX_EINPUT); 0 (default):
                        * a nested shell is a hole */
  int smooth_rounds;   /* rounds of the smoothing after the untangling
                        * (--smooth N): nodes move only where that raises
                        * the worst J_ENS around them, and never lower any
                        * node's worst; 0: off (the default, MX_SMOOTH_ROUNDS:
                        * on the cortex it costs more time than the worst
                        * element gains, bench/smooth_bench.sh) */
  int tets;            /* 1: the final mesh split into tetrahedra (--tets,
                        * kernels/tet_split.h): each quadrilateral face cut
                        * by the diagonal through its node of the smallest
                        * index, pyramids into 2, prisms 3, hexahedra 5 or
                        * 6 (a distorted element: the cone from a new node
                        * inside it, appended after the nodes; an element
                        * nothing splits validly has its leaf refined by
                        * the repair rounds); per tetrahedron its element's
                        * leaf, level and material, so the element lists of
                        * a refinement name tetrahedra; checked again (valid,
                        * conforming, the same volume); 0 (default): mixed */
} mx_params;
/* The smoothing's default rounds (mx_params_default), measured on the
 * cortex: bench/smooth_bench.sh. */
#define MX_SMOOTH_ROUNDS 0

void mx_params_default(mx_params *p);

typedef struct mx_mesher mx_mesher;

/* NULL when out of memory. The parameters are copied. */
mx_mesher *mx_mesher_new(const mx_params *p);
void mx_mesher_free(mx_mesher *m);
/* Replace the message handler (NULL: stderr, the default). */
void mx_mesher_set_message_handler(mx_mesher *m, mx_message_fn fn, void *user);
/* Progress hooks, each may be NULL, all called from the calling thread
 * (never from a parallel region) with `user`: on_stage before each step
 * ("grid", "refine", "balance", "transition", "index", "boundary",
 * "verify", "quality", ...), on_level before each octree level is refined
 * (1..max_level), on_round before each repair round (1, 2, ...). */
typedef struct {
  void (*on_stage)(void *user, const char *name);
  void (*on_level)(void *user, int level, int max_level);
  void (*on_round)(void *user, int round);
  void *user;
} mx_progress;
void mx_mesher_set_progress(mx_mesher *m, const mx_progress *hooks);
/* Cancel the call running on m (any thread, any time; a progress hook may
 * call it): the call checks the flag between its stages, between octree
 * levels, between the boundary stage's steps and repair rounds, and returns
 * MX_ECANCELED within about a second; a cancelled mesh leaves no mesh (the
 * octree is dropped too unless it came from a restart file; a cancelled
 * re-mesh keeps the octree with the levels it completed), and the next
 * call works as usual (the flag is cleared when a call starts, so a cancel
 * asked for between two calls stops neither). */
void mx_mesher_cancel(mx_mesher *m);
/* early != 0: the edge infos are freed once the transition has read them
 * (their memory goes to the mesh: a single run's peak is lower); the next
 * refinement or re-mesh rebuilds them (time). 0, the default, keeps them. */
void mx_mesher_release_edges_early(mx_mesher *m, int early);
/* The last error message of this mesher ("" when none). */
const char *mx_mesher_last_error(const mx_mesher *m);
/* The status code's name, e.g. "bad input". */
const char *mx_status_string(int status);

/* ---- Inputs and requests (before the first mx_mesher_mesh) ----------- */

/* A closed surface bounding the domain: OFF, MDL, STL, OBJ by extension.
 * Several form one domain; a shell inside another is a hole. */
int mx_mesher_add_surface(mx_mesher *m, const char *path);
/* The same from arrays: nv points (3 doubles each), nt triangles (3 0-based
 * indices each, outward by the right hand); name is used in messages. */
int mx_mesher_add_surface_arrays(mx_mesher *m, const char *name, size_t nv,
                                 const double *xyz, size_t nt,
                                 const uint32_t *tri);
/* The built-in demo surface (a brain-like closed surface). */
int mx_mesher_add_demo_surface(mx_mesher *m);
/* -r: octants meeting or inside a region surface go to `level`. */
int mx_mesher_add_region_surface(mx_mesher *m, const char *path, int level);
/* With params.materials: the number (1 .. 65535) and name (NULL: the
 * input file's) of the material inside domain input `input` (0 for the
 * first surface added, in order): the region its shells bound from
 * outside, which must all nest at one depth. Written as the Gmsh physical
 * group, the Medit reference and the VTK/VTU field material, and given by
 * mx_mesh_arrays.material. MX_EINPUT for a bad input index or number;
 * two materials given one number, or an input whose shells nest at
 * several depths, are refused when meshing. */
int mx_mesher_set_material(mx_mesher *m, int input, int number, const char *name);
/* A level of one domain input (0 for the first surface added): octants
 * meeting its triangles go to surface_level, octants meeting or inside it
 * to inside_level (0: none; the largest request wins, as for -s and -a).
 * With params.materials, inside_level is a level everywhere in the
 * material(s) it holds. Each level given takes a region surface's place
 * (MX_MAX_REGIONS in all). MX_EINPUT for a bad index or level. */
int mx_mesher_set_input_level(mx_mesher *m, int input, int surface_level, int inside_level);
/* A surface file and its own options, as `-i FILE` with `--material`,
 * `--level`, `--inside-level` after it (the program and its --p4est front
 * share it): mx_mesher_add_surface, then mx_mesher_set_material when
 * material is not 0 and mx_mesher_set_input_level when a level is not 0,
 * on the input just added. */
int mx_mesher_add_input(mx_mesher *m, const char *path, int material, const char *material_name,
                        int surface_level, int inside_level);
/* ---- Label images (issue 28) ------------------------------------------
 * A segmented 3D image (0 background, 1, 2, ... the materials): NIfTI-1/2
 * (.nii, .nii.gz), MetaImage (.mha, .mhd), INRIA (.inr, .inr.gz). Each
 * label becomes a material of that number (params.materials is turned on),
 * bounded by the interfaces found in the image: the voxel faces between two
 * labels, smoothed (Taubin, each corner within 0.35 voxel of its place)
 * unless `voxel` is set. Without a surface level (-s) the interfaces are
 * refined to the image's resolution (octants of about one voxel). */
typedef struct {
  int voxel;             /* 1: the voxel faces as they are (a staircase) */
  int smooth_rounds;     /* Taubin rounds; -1: the default (10) */
  long long min_island;  /* parts of a label of fewer voxels take the label
                          * around them; 0: all kept */
  const int32_t *skip;   /* labels meshed as background (nskip of them) */
  int nskip;
  const int32_t *merge;  /* pairs (from, to): label `from` meshed as `to` */
  int nmerge;
  const char *label_names; /* a file of "LABEL NAME ..." lines (FreeSurfer's
                            * lookup tables read as they are); NULL: "label L" */
  const int32_t *label_size; /* pairs (label, voxels): inside that label no
                              * element wider than that many voxels (a power
                              * of two: rounded down; 1 = the voxels'
                              * level), nlabel_size of them */
  int nlabel_size;
} mx_image_params;
void mx_image_params_default(mx_image_params *ip);
/* 1 when path names a label image by its extension. */
int mx_is_label_image_path(const char *path);
/* The options mx_mesher_add_surface uses for a label image (copied, the
 * arrays too; NULL: the defaults). */
int mx_mesher_set_image_params(mx_mesher *m, const mx_image_params *ip);
/* A label image file (ip NULL: the mesher's image params). MX_EINPUT with
 * a message naming the file for a bad image. */
int mx_mesher_add_label_image(mx_mesher *m, const char *path, const mx_image_params *ip);
/* The same from memory: labels[i + dims[0] (j + dims[1] k)], A the world
 * of voxel (i, j, k)'s centre (x = A[0] i + A[1] j + A[2] k + A[3], y from
 * A[4..7], z from A[8..11]); name is used in messages. */
int mx_mesher_add_label_array(mx_mesher *m, const char *name, const int32_t *labels,
                              const int64_t dims[3], const double A[12],
                              const mx_image_params *ip);

/* -b: a box [lo, hi] whose octants go to `level` (also after meshing: see
 * mx_mesher_refine). */
int mx_mesher_add_box(mx_mesher *m, const double lo[3], const double hi[3],
                      int level);
/* The boxes of a .reg file. */
int mx_mesher_read_boxes(mx_mesher *m, const char *path);
/* Change the -s / -a levels (-1: none); after meshing, mx_mesher_refine
 * applies them to the existing octree. */
int mx_mesher_set_levels(mx_mesher *m, int surface_level, int all_level);

/* ---- Meshing ----------------------------------------------------------- */

/* Every stage up to params.stage. With MX_STAGE_FULL, elements left with
 * J_ENS < 1e-6 after the boundary stage, and elements a node lies on
 * without being one of their nodes (two parts of the boundary meeting: a
 * non-conforming contact), are repaired by list refinement of their leaves
 * (up to params.repair_rounds); if some remain the call returns MX_EINVALID
 * (the mesh is still there to inspect or write). */
int mx_mesher_mesh(mx_mesher *m);
/* The stages one at a time, in this order. */
int mx_mesher_build_octree(mx_mesher *m); /* grid, refine and balance */
int mx_mesher_transition(mx_mesher *m);   /* transition patterns */
int mx_mesher_boundary(mx_mesher *m);     /* boundary stage, with repair */

/* ---- Re-meshing (Algorithm 3 of the 2021 paper) ------------------------ */

/* Split once the leaves that own the listed elements of the current mesh (a
 * leaf listed through several elements is split once), restore balance
 * through the edge infos, apply the requests (boxes, levels, regions) to the
 * refined octree, and mesh again up to params.stage. Element indices refer
 * to the current mesh; an index out of range is MX_EINPUT (nothing done).
 * When the current mesh is a full-stage one, only the leaves around what
 * was split are meshed again (the rest of the mesh is kept) and the result
 * is the mesh a full re-mesh gives; params.remesh_full turns this off.
 * A patch too large to pay (scattered marks) is not meshed alone: the whole
 * octree is (mx_stats.remesh_local 0), with the same mesh. */
int mx_mesher_refine_elements(mx_mesher *m, const uint64_t *elements,
                              size_t n);
/* The same with leaf indices (0 .. nleaves-1, Morton order of the leaves). */
int mx_mesher_refine_leaves(mx_mesher *m, const uint64_t *leaves, size_t n);
/* Apply the current requests (after mx_mesher_add_box, set_levels, ...) to
 * the existing octree and mesh again. */
int mx_mesher_refine(mx_mesher *m);

/* ---- The restart file (Appendix A of the 2021 paper) ------------------- */

/* Write the restart file of the current octree and mesh: the published text
 * format, or, when the name ends in ".octb", the binary variant (version,
 * sizes, checksum), which also holds a full-stage mesh. */
int mx_mesher_save_restart(const mx_mesher *m, const char *path);
/* Rebuild the balanced octree and the element -> leaf map from a restart
 * file (ours or the published program's). A binary file's mesh becomes the
 * current mesh (a re-mesh from it is then local); otherwise there is no
 * mesh until the next call that meshes: call
 * mx_mesher_refine_elements (with the list, possibly empty), mx_mesher_refine
 * or mx_mesher_mesh next. The domain surfaces must have been added (the same
 * ones: a file whose octants do not lie on their grid is MX_EINPUT). Until
 * the next mesh, element indices refer to the mesh that was written with the
 * restart file, of which there are mx_mesher_restart_elements (0 when the
 * file has no counts): in the files' order (mx_mesher_written_order) for a
 * file mixoct wrote (marked so; its mesh is made again first when the file
 * does not hold it), octant by octant for the published program's. */
int mx_mesher_load_restart(mx_mesher *m, const char *path);
size_t mx_mesher_restart_elements(const mx_mesher *m);
/* Read a list of element indices (the published format: one index per
 * line; blanks, commas and line ends separate indices, '#' starts a comment
 * to the end of the line). Each word must be a whole number >= 0 and
 * < limit, written as an integer or as a real with a whole value ("12",
 * "12.0", "1.2e+01", numpy.savetxt's "1.200000000000000000e+01"); any
 * other word (not a number, a fraction, negative, NaN, too large) is
 * MX_EINPUT with a message naming the file, the line and the word. An
 * empty list is read with a warning. *out is allocated (free with
 * mx_free_array). Messages go to the current handler (stderr outside a
 * mesher call). */
int mx_read_element_list(const char *path, uint64_t limit, uint64_t **out,
                         size_t *n);
void mx_free_array(void *p);

/* ---- The mesh, as arrays, without copying ------------------------------ */

typedef struct {
  size_t nnodes, nelements, nleaves;
  const double *xyz;      /* 3 * nnodes, interleaved x y z */
  const uint8_t *type;    /* nelements, MX_TET .. MX_HEX */
  const uint32_t *conn;   /* 8 * nelements, rows padded with UINT32_MAX */
  const float *jens;      /* J_ENS of each element (computed in double,
                           * kept in float) */
  const uint32_t *leaf;   /* the leaf (0 .. nleaves-1) each element is in */
  const uint8_t *level;   /* that leaf's level */
  const uint8_t *boundary;/* per node: 1 on the domain boundary */
  size_t by_type[4];
  double jens_min;
  size_t invalid;         /* elements with J_ENS < 1e-6 */
  const uint16_t *material; /* params.materials: each element's material
                           * (its nesting depth, 0 outside every shell);
                           * NULL: one material */
} mx_mesh_arrays;

/* Valid until the next call that changes the mesh. MX_EINPUT without a
 * mixed mesh (none yet, or params.stage == MX_STAGE_OCTREE, whose leaves
 * only mx_mesher_write writes, as hexahedra). */
int mx_mesher_mesh_arrays(const mx_mesher *m, mx_mesh_arrays *a);
/* For bindings whose views of the mesh arrays may outlive the mesh: the
 * mesher takes copies of the current mesh's arrays (those of
 * mx_mesh_arrays) and hands the originals, which the last mx_mesh_arrays
 * pointed to, to the caller: old[] receives up to MX_DETACH_MAX pointers
 * (NULL-padded), each to free with mx_free_array once nothing reads it.
 * The next calls change the copies only. MX_ENOMEM (nothing changed). The
 * same for the 2D mesher (mx_mesh2d_arrays). */
#define MX_DETACH_MAX 8
int mx_mesher_detach_mesh_buffers(mx_mesher *m, void *old[MX_DETACH_MAX]);

/* The boundary faces of a full-stage mesh as a surface file of their own
 * (`--boundary FILE`), by extension: .vtu, triangles and quadrilaterals
 * with the cell fields surface_tag (the input file each lies on, 1 for the
 * first -i) and body, and the point field node (the index in the volume
 * mesh); .ply (binary) the same as vertex and face properties; .off the
 * faces alone; .stl (binary, single precision) triangles only, each
 * quadrilateral cut along the diagonal through its vertex of the smallest
 * node index. Only the nodes the faces use are written. */
int mx_mesher_write_boundary(const mx_mesher *m, const char *path);

/* The same boundary faces (and the bodies) as arrays, copied into memory
 * the caller owns (free with mx_boundary_arrays_free): the faces of the
 * `--boundary` file in its order, triangles first; each face's nodes
 * (4 a face, a triangle's 4th UINT32_MAX; outward of its element), its
 * surface tag (the file's surface_tag: the input it lies on, 1 for the
 * first; with materials 1 the outer boundary, 2.. the interfaces, whose
 * names the .msh files give), the element it bounds (an index of the mesh
 * arrays) and that face's local index (mx_cell_faces: VTK's face order);
 * per element its body (1..nbodies: the parts connected through nodes, in
 * the order of their smallest node) and, with materials, its material
 * number (else NULL). MX_EINPUT without a full-stage mesh, MX_ENOMEM. */
typedef struct {
  size_t nfaces, ntri, nquad;
  uint32_t *nodes;      /* 4 * nfaces */
  int32_t *tag;         /* nfaces */
  uint32_t *element;    /* nfaces */
  uint8_t *local_face;  /* nfaces */
  size_t nelements;
  int32_t *body;        /* nelements */
  int32_t *material;    /* nelements, or NULL */
  int nbodies, ntags;
} mx_boundary_arrays;
int mx_mesher_boundary_arrays(const mx_mesher *m, mx_boundary_arrays *b);
void mx_boundary_arrays_free(mx_boundary_arrays *b);

/* The order the mesh files list the elements in: grouped by body (the
 * parts of the mesh connected through nodes, in the order of their first
 * node), then by type (tetrahedra, pyramids, prisms, hexahedra), the
 * mesher's order within a group, so readers see at most four blocks a
 * body. order (nelements entries of
 * mx_mesh_arrays) receives, for each position k of the files, the index of
 * that element in the arrays. Element lists read with a restart file refer
 * to the files' order; mx_mesher_refine_elements takes the arrays'. */
int mx_mesher_written_order(const mx_mesher *m, uint32_t *order);

/* The element and node data the mesh files carry (`--fields`):
 * MX_FIELDS_ALL (the default): type, level, jens, the boundary flag, a size
 * field's target_size and the tags; MX_FIELDS_QUALITY: jens and the tags;
 * MX_FIELDS_NONE: the tags alone. The tags (surface_tag, body, material)
 * are written as fields only where the format has no place of its own for
 * them: .vtu and .vtk keep them, .msh carries them as physical groups and
 * then writes no $ElementData for them, .mesh as references. MX_EINPUT for
 * another value. */
enum { MX_FIELDS_ALL = 0, MX_FIELDS_QUALITY = 1, MX_FIELDS_NONE = 2 };
int mx_mesher_set_output_fields(mx_mesher *m, int which);

/* Write the current mesh; format by extension: .vtk .vtu .msh .mesh .meshb
 * .getfem .m3d .mvm; ascii: the ASCII variant of .vtk / .msh. Written under a
 * temporary name and renamed. */
int mx_mesher_write(const mx_mesher *m, const char *path, int ascii);

/* Figures of the last run. */
typedef struct {
  size_t leaves, octants, nodes, elements, invalid;
  size_t refined_listed;   /* leaves split by the last list refinement */
  size_t split_balance;    /* of which ... octants split for balance */
  size_t repaired;         /* invalid elements repaired by refinement */
  int repair_rounds;
  double jens_min;
  uint64_t leaves_hash;    /* order-independent hash of the leaves */
  double t_read, t_grid, t_refine, t_balance, t_transition, t_boundary,
      t_quality, t_write, t_restart; /* seconds, last run */
  /* the last refinement call: 1 when each re-mesh (after the refinement
   * and in the repair rounds) was local, meshing again only the leaves
   * around what was split: remesh_patch_leaves of them after the
   * refinement */
  int remesh_local;
  size_t remesh_patch_leaves;
} mx_stats;
void mx_mesher_stats(const mx_mesher *m, mx_stats *s);

/* The sharp features of the last run (issue 29): found (ridges as lines
 * from corner to corner or loops, corners, total length), kept (the
 * placement ran: not when there are none, when they are a scanned
 * surface's noise, or when keeping them broke the mesh: fallback), placed
 * (corners on nodes, lines followed by mesh edges, quadrilaterals split
 * along a line) and the distances from them to the mesh over the input's
 * diagonal (NAN when not measured: no mesh, or no features kept). */
typedef struct {
  double angle;            /* degrees; 0: no features */
  size_t ridges, corners;
  double length;
  int kept, noise, fallback;
  size_t corners_placed, lines_followed, lines_missed, quads_split;
  double ridge_distance, corner_distance;
} mx_feature_figures;
void mx_mesher_feature_figures(const mx_mesher *m, mx_feature_figures *f);


/* ---- Size fields: the control space (issue 27) ------------------------- */

/* A size field h(x) = (h1, h2, h3), the element lengths along x, y, z (the
 * metric diag(h1^-2, h2^-2, h3^-2) of Jurczyk & Glut 2016, eq. 8; an
 * isotropic field has h1 = h2 = h3), stored adaptively in one of the
 * paper's tree structures (src/sizing/). A source is a function of a block
 * of points: f(user, n, xyz, h) writes h[3i..3i+2] for the point
 * xyz[3i..3i+2], i < n; it is called from several threads at once. */
typedef void (*mx_size_fn)(void *user, size_t n, const double *xyz, double *h);

/* The structures: kd-trees with values in the leaves (K_L) or in the
 * vertices with trilinear interpolation (K_V), and octrees with values in
 * the leaves, unbalanced (K_oL) or 2:1 balanced across faces (K_oLB). */
enum { MX_CS_KD_LEAF = 0, MX_CS_KD_VERTEX = 1, MX_CS_OCT_LEAF = 2, MX_CS_OCT_BALANCED = 3 };
/* The kd-trees' split rules (section 2.2): the longest axis in its middle
 * (s_L), the largest gradient between sub-box faces (s_G), the largest sum
 * of gradients, split where it reaches half (s_S). */
enum { MX_SPLIT_LONGEST = 0, MX_SPLIT_GRADIENT = 1, MX_SPLIT_SUM = 2 };

typedef struct {
  int structure;     /* MX_CS_* */
  int split;         /* MX_SPLIT_* (kd-trees) */
  double lo[3], hi[3]; /* the box the field covers (a query outside is clamped) */
  double delta;      /* the tolerance on the metric non-conformity (eq. 1) */
  int samples;       /* N_s: the N_s^3 sample grid of a node's error; 5 */
  int max_depth;     /* splits from the root (a kd-tree needs 3 for an octree's
                      * 1); 0: 40 / 8 (256 cells a side) */
} mx_cspace_params;

typedef struct {
  size_t nodes, leaves, values; /* tree nodes (internal and leaves), stored sizes */
  size_t bytes;      /* the structure's memory */
  int depth;         /* the deepest leaf */
  int capped;        /* leaves left above delta at max_depth */
  double seconds;    /* building */
} mx_cspace_info;

typedef struct mx_cspace_s mx_cspace;

void mx_cspace_params_default(mx_cspace_params *p);
/* Builds the structure for f to tolerance p->delta: a node is split while
 * the largest non-conformity between f and the structure over its N_s^3
 * sample points exceeds delta (level by level, the nodes of a level in
 * parallel; the same tree for any thread count). MX_EINPUT for bad
 * parameters or a size that is not finite and positive (a message names
 * the point), MX_ENOMEM. */
int mx_cspace_build(const mx_cspace_params *p, mx_size_fn f, void *user, mx_cspace **out);
/* The field at p (clamped into the box): no allocation, any thread. */
void mx_cspace_query(const mx_cspace *c, const double p[3], double h[3]);
/* The smallest size the structure holds anywhere in the box [lo, hi] (the
 * least component of every leaf value, or vertex value, meeting it): what
 * an octant of that box must not exceed. */
double mx_cspace_min_box(const mx_cspace *c, const double lo[3], const double hi[3]);
void mx_cspace_info_get(const mx_cspace *c, mx_cspace_info *info);
void mx_cspace_free(mx_cspace *c);
/* The metric non-conformity of two diagonal metrics of lengths a and b:
 * || Ma^-1 Mb + Mb^-1 Ma - 2 I ||_F = sqrt(sum_i (a_i/b_i - b_i/a_i)^4)
 * (0 for equal sizes; 4.0 about a factor 2.4 apart on one axis). */
double mx_metric_nonconformity(const double a[3], const double b[3]);
/* The paper's test functions F1..F5 (section 3.1) by name ("F1".."F5"),
 * with their domains: the function, or NULL for another name. */
mx_size_fn mx_size_builtin(const char *name, double lo[3], double hi[3]);

/* A size field for the octree: an octant is split while its side exceeds
 * the least size the field takes over it (the smallest of h1, h2, h3 of
 * the control space's leaves meeting the octant), with the other requests
 * (the largest level wins; levels up to MX_MAX_LEVEL - 1). f is sampled
 * into a control space over the domain's box when the octree is built;
 * p: its structure and tolerance (NULL: K_L kd-tree, split s_S, delta 0.5,
 * the default: mx_cspace_params_default and the bench's figures). f NULL
 * removes the field. MX_EINPUT after the octree is built. */
int mx_mesher_set_size_function(mx_mesher *m, mx_size_fn f, void *user,
                                const mx_cspace_params *p);
/* The same from text (the program's --size): one of the paper's test
 * functions by name ("F1".."F5") or an expression of x, y, z (numbers,
 * + - * / ^, exp log sqrt abs sin cos min max, pi, e: src/sizing/expr.h),
 * the size the same along every axis. MX_EINPUT with a message giving the
 * column of a bad expression. */
int mx_mesher_set_size_expr(mx_mesher *m, const char *text);
/* Bounds on the field's sizes (--size-min, --size-max): each size is
 * raised to hmin and lowered to hmax before the control space is built (0:
 * no bound). With no field, hmax alone is a field of that size. MX_EINPUT
 * for a negative, non-finite or crossed pair. */
int mx_mesher_set_size_limits(mx_mesher *m, double hmin, double hmax);
/* Discrete sources, combined with the function's field by the minimum
 * (src/sizing/sources.h): each gives sizes at points, and the field grows
 * from them by at most the gradation ratio beta between neighbouring sizes
 * (h(x) = min_i h_i + (beta - 1) |x - x_i|).
 * Curvature (--curvature DEG): an element spans at most `degrees` of the
 * input surface's curvature (the angle between neighbouring triangles'
 * normals over the distance between their centroids); 0: none. */
int mx_mesher_set_size_curvature(mx_mesher *m, double degrees);
/* Thickness (--thickness N): at least `elements` (1 to 64; 0: none)
 * elements across every part of the domain and every gap between its
 * sides, measured by rays from the surface along its normals. */
int mx_mesher_set_size_thickness(mx_mesher *m, double elements);
/* The gradation ratio (--gradation BETA, above 1; 0: the default, 2 for
 * the discrete sources and none for the function). Given, it applies to the
 * function's control space too: its leaves become sources. */
int mx_mesher_set_size_gradation(mx_mesher *m, double beta);
/* Sharp features (issue 29): ridges where the input's normals part by more
 * than angle_deg (default 30; 0: none, --no-features), corners where
 * ridges end, meet or turn by more; kept in the mesh (corners on nodes,
 * ridges along element edges) where that leaves every element valid and
 * at J_ENS 0.1 or more (or what it had). MX_EINPUT outside [0, 180). */
int mx_mesher_set_feature_angle(mx_mesher *m, double angle_deg);
/* The level of the octants meeting a ridge or a corner (--feature-level;
 * 0, the default: the surface level, nothing more). MX_EINPUT outside
 * [0, MX_MAX_LEVEL]. */
int mx_mesher_set_feature_level(mx_mesher *m, int level);
/* The features given as polylines (--features FILE: one a line, "n x1 y1
 * z1 ... xn yn zn", CGAL's .polylines.txt; corners at their ends, where
 * three meet and where they turn by more than the feature angle) instead
 * of found on the surface; NULL: found. Read when the octree is built
 * (errors then, with the file and line). MX_OK, MX_ENOMEM. */
int mx_mesher_set_feature_file(mx_mesher *m, const char *path);
/* A size map: n points (xyz, 3 each) with sizes h (finite, positive),
 * copied; they must lie in the domain's box (grown by 5% of its diagonal)
 * when the octree is built. name: where they came from, for messages (or
 * NULL). n = 0 removes the map. */
int mx_mesher_set_size_points(mx_mesher *m, const double *xyz, const double *h, size_t n,
                              const char *name);
/* A size map read from a file (--size FILE): a point field (or a cell field
 * at the cells' centroids) of a .vtu, .vtp or legacy .vtk file, named
 * `field` or (NULL) found by its name (size, h, target_size, sizes) or as
 * the only one; a Gmsh .pos view (scalar elements: each node's value); or
 * text lines "x y z h". MX_EINPUT with a message naming the file and the
 * line (or the byte) of what is wrong. */
int mx_mesher_set_size_map(mx_mesher *m, const char *path, const char *field);
/* A size per element of the current mesh (a solver's estimate: n, the
 * mesh's element count, in the order of mx_mesher_mesh_arrays): a size map
 * at the elements' centroids. Then mx_mesher_refine_elements(m, NULL, 0)
 * refines the octree to it (or the next mesh from a restart file). */
int mx_mesher_set_size_elements(mx_mesher *m, const double *h, size_t n);

/* ---- 2D: the mixed quadtree mesher (the `mesher2d` program) ------------
 *
 * Closed polylines (.poly, .off, 2D .mdl) in; counter-clockwise triangles
 * and quadrilaterals out (Jaillet & Lobos 2021, sections 3, 4 and 6):
 *
 *   mx_params2d p;  mx_params2d_default(&p);  p.surface_level = 8;
 *   mx_mesher2d *m = mx_mesher2d_new(&p);
 *   mx_mesher2d_set_domain(m, "a.poly");
 *   mx_mesher2d_mesh(m);         // refine + balance, transition, boundary, check
 *   mx_mesher2d_write(m, "a.vtu", 0);
 *   mx_mesher2d_save_restart(m, "a.oct");
 *   uint64_t bad[] = {7};
 *   mx_mesher2d_refine_elements(m, bad, 1);   // Algorithm 3, then re-mesh
 *   mx_mesher2d_free(m);
 *
 * The same conventions as the 3D mesher: status codes, messages through the
 * handler (stderr "mesher2d: ..." by default), mx_mesher2d_last_error.
 * Every mesh is checked by an independent routine (conformity, orientation,
 * boundary on the polylines, features as vertices, area, topology): a mesh
 * that fails it makes the call return MX_EINVALID (the mesh is kept, and
 * mx_mesher2d_write still writes it when asked). */
typedef struct {
  int surface_level;   /* -s: quadrants meeting the polylines; -1 none */
  int all_level;       /* -a: every quadrant of the domain; -1 none */
  int balance;         /* MX_BALANCE_EDGES (default) or MX_BALANCE_RECURSIVE */
  int threads;         /* 0: the OpenMP default */
  double close_ratio;  /* projection of close inside nodes, 0: 0.3 */
  double max_memory_mb; /* refuse runs estimated above; 0: memory available */
  int feature_levels;  /* 1 (default): quadrants holding a feature are refined
                        * until features keep apart (each feature's quadrant
                        * at most half its distance to the nearest other);
                        * 0: not (two features may then claim one
                        * node: the mesh is refused, naming both) */
  int materials;       /* 1: several materials (--materials): a loop nested
                        * in an outer one is not a hole but the interface
                        * between two materials; each cell gets the
                        * material of the region it lies in, numbered by
                        * nesting depth (1: inside an outer loop only, 2:
                        * inside one more, ...; mx_mesher2d_set_material),
                        * and no cell lies across an interface (the cells
                        * are cut along it, its sharp vertices are nodes);
                        * 0 (default): a nested loop is a hole */
} mx_params2d;

void mx_params2d_default(mx_params2d *p);

typedef struct mx_mesher2d mx_mesher2d;
mx_mesher2d *mx_mesher2d_new(const mx_params2d *p);
void mx_mesher2d_free(mx_mesher2d *m);
void mx_mesher2d_set_message_handler(mx_mesher2d *m, mx_message_fn fn, void *user);
const char *mx_mesher2d_last_error(const mx_mesher2d *m);

/* The domain (once): a file, or arrays (xy: 2 per vertex; seg: 2 vertex
 * indices per segment). Checked: closed, not self-intersecting; loops are
 * oriented by nesting (outer counter-clockwise, holes clockwise). */
int mx_mesher2d_set_domain(mx_mesher2d *m, const char *path);
int mx_mesher2d_set_domain_arrays(mx_mesher2d *m, const char *name, size_t nv,
                                  const double *xy, size_t ns, const uint32_t *seg);
/* Requests (a quadrant takes the highest level asked; levels 0 to 27;
 * -1: none, as in 3D). */
int mx_mesher2d_set_levels(mx_mesher2d *m, int surface_level, int all_level);
int mx_mesher2d_add_box(mx_mesher2d *m, const double lo[2], const double hi[2], int level);
int mx_mesher2d_read_boxes(mx_mesher2d *m, const char *path);
int mx_mesher2d_add_region(mx_mesher2d *m, const char *path, int level);
int mx_mesher2d_add_drawing(mx_mesher2d *m, const char *path, int level);
/* name: "circle" (cx cy r), "line" (px py nx ny) or "sine" (amp freq phase
 * y0: y = y0 + amp sin(freq x + phase)); nargs must match. */
int mx_mesher2d_add_function(mx_mesher2d *m, const char *name, const double *args,
                             size_t nargs, int level);
/* With params.materials: the number (1 .. 65535) and name (NULL: "material
 * NUMBER") of the material at nesting depth `depth` (1: the region inside
 * the outer loops only, 2: inside the loops nested in them, ...; default
 * number: the depth). Written as the Gmsh physical group and the VTK/VTU
 * cell field material, and given by mx_mesh2d_arrays.material. MX_EINPUT
 * for a depth out of 1 .. 64 or a number out of range; two materials
 * given one number are refused when meshing. */
int mx_mesher2d_set_material(mx_mesher2d *m, int depth, int number, const char *name);
/* A size field (issue 27), as mx_mesher_set_size_function, _expr and
 * _limits with the same checks and messages: a quadrant is split while its
 * side exceeds the least size the field takes over it, with the other
 * requests (the finest wins, levels up to 27) and the balance rule. The
 * source is sampled at z = 0 (an expression of x and y) into a control
 * space over the domain's box (the z axis a thin slab) when meshing. With
 * a field, each -f curve of level RL is a source of it too: the side of
 * level RL on the curve, growing by the distance to it (slope 1), the
 * field the least of all its sources before the bounds; the quadrants
 * the curve crosses still get level RL. The written meshes carry the cell
 * field target_size (the field at each cell's centroid). A field that asks
 * for more quadrants than memory allows is refused when meshing
 * (MX_ENOMEM, naming its least size and where). */
int mx_mesher2d_set_size_function(mx_mesher2d *m, mx_size_fn f, void *user,
                                  const mx_cspace_params *p);
int mx_mesher2d_set_size_expr(mx_mesher2d *m, const char *text);
int mx_mesher2d_set_size_limits(mx_mesher2d *m, double hmin, double hmax);

/* Mesh from the requests (and the quadtree of a loaded restart file). */
int mx_mesher2d_mesh(mx_mesher2d *m);
/* Cancel the call running on m, as mx_mesher_cancel: checked between the
 * stages (refine, transition, boundary, materials, check); MX_ECANCELED. */
void mx_mesher2d_cancel(mx_mesher2d *m);
/* Re-meshing (section 4.2, Algorithm 3): each quadrant holding one of the
 * listed elements is split once (a quadrant listed twice, once), balance is
 * restored through the edge infos, and the mesh is made again. Indices
 * refer to the current mesh, or, before the first mesh after
 * mx_mesher2d_load_restart, to the mesh written with that restart file. */
int mx_mesher2d_refine_elements(mx_mesher2d *m, const uint64_t *elements, size_t n);
/* Keep the current quadtree and apply the current requests (after
 * set_levels, add_box, ...), then mesh again. */
int mx_mesher2d_refine(mx_mesher2d *m);
/* The restart file, Appendix A in its quadtree form (text): nodes "x y",
 * edges "a b mid", quadrants "4 n0 n1 n2 n3 level" and their segments, the
 * elements of each quadrant. Loading needs the domain set first (the file's
 * quadrants must lie on that domain's quadtree). */
int mx_mesher2d_save_restart(const mx_mesher2d *m, const char *path);
int mx_mesher2d_load_restart(mx_mesher2d *m, const char *path);
size_t mx_mesher2d_restart_elements(const mx_mesher2d *m);

/* Format by extension: .vtu .vtk .msh .off .getfem .m3d (ascii: the ASCII
 * .vtk / .msh). Written under a temporary name and renamed. */
int mx_mesher2d_write(const mx_mesher2d *m, const char *path, int ascii);

typedef struct {
  size_t nnodes, ncells, nleaves;
  const double *xy;       /* 2 * nnodes */
  const uint8_t *type;    /* 0 triangle, 1 quadrilateral */
  const uint32_t *conn;   /* 4 * ncells, a triangle's 4th is UINT32_MAX */
  const uint32_t *leaf;   /* the quadrant (0 .. nleaves-1) of each cell */
  const uint8_t *level;   /* its level */
  const uint16_t *material; /* params.materials: each cell's material's
                           * number; NULL: one material */
} mx_mesh2d_arrays;
int mx_mesher2d_mesh_arrays(const mx_mesher2d *m, mx_mesh2d_arrays *a);
int mx_mesher2d_detach_mesh_buffers(mx_mesher2d *m, void *old[MX_DETACH_MAX]);

typedef struct {
  size_t leaves, quadrants, nodes, cells, tris, quads, invalid;
  size_t refined_listed;  /* quadrants split by the last list refinement */
  size_t split_balance;   /* quadrants split for balance (last build) */
  int valid;              /* the last mesh passed the independent check */
  double sj_min, min_angle;
  double t_read, t_refine, t_balance, t_transition, t_boundary, t_quality,
      t_check, t_restart; /* seconds, last run */
  int materials;          /* params.materials: the materials (regions) meshed; 0 without */
} mx_stats2d;
void mx_mesher2d_stats(const mx_mesher2d *m, mx_stats2d *s);

/* ---- For programs built on the library ----------------------------------
 * What the mixoct, mesher2d and mesher_roi programs (src/cli/) need besides
 * the mesher calls; they include only this header. */

#define MX_MAX_LEVEL 16  /* the deepest octree level */

/* Returns from the calling function the status of expr when it is not
 * MX_OK (statuses travel up from where a failure happens). */
#define MX_CHECK(expr)                                                        \
  do {                                                                        \
    int mx_status_ = (expr);                                                  \
    if (mx_status_ != MX_OK) return mx_status_;                               \
  } while (0)

#define MX_MAX_REGIONS 8 /* region surfaces per mesher */

/* Wall-clock seconds, and the peak resident set size of this process. */
double mx_wtime(void);
double mx_peak_rss_mb(void);

/* A message of the program, through the calling thread's handler (stderr,
 * "mixoct: FILE:LINE: text", by default; file NULL or line 0 leave them
 * out). Warnings are dropped while the thread is quiet. */
#if defined(__GNUC__)
#define MX_PRINTF_(a, b) __attribute__((format(printf, a, b)))
#else
#define MX_PRINTF_(a, b)
#endif
void mx_error(const char *file, long line, const char *fmt, ...) MX_PRINTF_(3, 4);
void mx_warning(const char *file, long line, const char *fmt, ...) MX_PRINTF_(3, 4);
/* The calling thread's handler for messages outside a mesher's calls (a
 * mesher's calls use its own, mx_mesher_set_message_handler), and whether
 * its warnings are dropped. */
void mx_set_thread_message_handler(mx_message_fn fn, void *user);
void mx_set_thread_quiet(int quiet);

/* The library's allocator: NULL after saying "out of memory" (the size
 * asked); mx_calloc clears; mx_free(NULL) does nothing. */
void *mx_alloc(size_t bytes);
void *mx_calloc(size_t bytes);
char *mx_strdup(const char *s);
void mx_free(void *p);

/* Removes the temporary files of the outputs being written (they are
 * renamed to their names only once complete). Async-signal-safe: for a
 * program's SIGINT / SIGTERM handler. */
void mx_remove_temporaries(void);

/* The files of a run, checked before anything is read or written: no
 * output may be an input or another output (the same file, whatever the
 * spelling: device and inode, or the directory's for a file to be
 * written); the restart file written may replace the one read. */
enum { MX_FILE_INPUT, MX_FILE_OUTPUT, MX_FILE_RESTART_IN, MX_FILE_RESTART_OUT };
typedef struct {
  const char *path; /* NULL: not used by this run (skipped) */
  const char *what; /* for the message: "the mesh output" */
  int use;          /* MX_FILE_* */
} mx_file_use;
/* MX_OK, or MX_EINPUT with a message naming both paths. */
int mx_check_file_uses(const mx_file_use *u, int n);

/* 1 when the extension of path names a 3D mesh format mx_mesher_write
 * writes (mx_mesh_format_known) or a 2D one mx_mesher2d_write writes
 * (mx_plane_format_known); else 0. */
int mx_mesh_format_known(const char *path);
int mx_plane_format_known(const char *path);
/* 1 when the extension of path names a format mx_mesher_write_boundary
 * writes (.vtu, .stl, .off, .ply); else 0. */
int mx_boundary_format_known(const char *path);
/* The file of piece `piece` of a parallel VTU "DIR/BASE.pvtu":
 * "DIR/BASE_<piece>.vtu" in buf (at most n bytes; empty when it does not
 * fit). */
void mx_pvtu_piece_path(const char *pvtu_path, int piece, char *buf, size_t n);

/* ---- The run's report (the mixoct program's summary and --json) --------- */

/* What a run of the program did besides meshing, for its report: the
 * outcome, the files written, the warnings, and the machine. */
#define MX_RUN_FILES 18    /* meshes, the boundary, the restart file */
#define MX_RUN_WARNINGS 64 /* warnings kept; the rest counted */
typedef struct {
  int status;                      /* the exit code */
  int valid;                       /* exit 0's promise: a valid mesh */
  int stage;                       /* MX_STAGE_*: full unless --stage */
  int noutputs;
  const char *outputs[MX_RUN_FILES]; /* written, in order */
  long long bytes[MX_RUN_FILES];   /* their sizes (-1: unknown) */
  int dry_run;                     /* nothing was asked to be written */
  int nwarnings;
  size_t warnings_dropped;         /* beyond MX_RUN_WARNINGS */
  char *warnings[MX_RUN_WARNINGS]; /* the caller's strings */
  char error[1024];                /* the first error, "" if none */
  double total_s;                  /* seconds since the run started */
  const char *wait_policy;         /* the OpenMP wait policy, as said */
  const char *topology;            /* one line on the machine (or NULL) */
} mx_run_info;

/* Prints the report of the run on stdout: the summary (json 0: what was
 * built, the J_ENS table of the 2015 paper's Tables IV and V, the boundary
 * steps, seconds per stage, peak memory, the files written, the outcome)
 * or one line of JSON (json 1; always valid JSON, non-finite numbers null).
 * m may be NULL for a run that stopped before meshing: then only the
 * JSON's outcome members are printed (json 1), nothing otherwise. */
void mx_mesher_print_report(const mx_mesher *m, const mx_run_info *ri, int json);

/* ---- Checking a mesh file (mixoct check) -------------------------------- */

/* The independent checker on a mesh file, as `mixoct check` runs it
 * (src/mesher/check_file.c): the mesh read -- a 3D one (legacy VTK, VTU,
 * Gmsh MSH 4.1, Medit .mesh/.meshb, GetFEM, M3D, MVM) or a 2D one
 * (triangles and quadrilaterals at z = 0 in VTK, VTU, MSH or OFF) --,
 * checked (3D: against the closed surface it should fill, when given; 2D:
 * against its domain's polylines, when given) and the report printed to
 * stdout: readable, or one JSON object on one line; messages through the
 * calling thread's handler (mx_set_thread_message_handler). */
typedef struct {
  const char *mesh;    /* the mesh file */
  const char *surface; /* 3D: the surface (.off .stl .obj .mdl .ply); 2D:
                        * the domain as poly; NULL: none */
  const char *poly;    /* 2D: the domain's closed polylines (.poly, or a 2D
                        * .off or .mdl); NULL: none; not with surface */
  double volume_tol;   /* largest relative |volume error| (2D: area error)
                        * accepted; 0 (default): from the mesh */
  double dist_tol;     /* largest distance of a boundary node to the
                        * surface (2D: the polylines), relative to its
                        * bounding box diagonal (2D: diameter); 1e-6 */
  int threads;         /* OpenMP threads for the call; 0 (default): as set */
  int json;            /* 1: the JSON object instead of the report */
  int quiet;           /* 1: no report (the JSON object still with json),
                        * no warnings */
  /* 3D: the surface as several files (nsurfaces > 0; surface NULL then),
   * one per input as the mesher was given them (-i A -i B ...: touching or
   * nested inputs meshed with --materials): the regions are those of each
   * file's closed shells (verify/check.h), the volume their union's, the
   * triangles two files share interfaces, not boundary. One file here is
   * the same as surface. */
  const char *const *surfaces;
  int nsurfaces;
  /* 3D: sharp features (issue 29), the distance from them to the mesh's
   * boundary edges (ridges) and nodes (corners), reported: found on the
   * surface at feature_angle degrees (0: none; 30 by default), or read from
   * the polylines file features (n x1 y1 z1 ... xn yn zn a line; its
   * corners at feature_angle, 0: every turn) instead. feature_tol > 0: a
   * distance above feature_tol times the diagonal (the surface's bounding
   * box, else the mesh boundary's) is a defect; 0 (default): reported
   * only. */
  double feature_angle;
  const char *features;
  double feature_tol;
} mx_check_params;

/* The defaults above, no file. */
void mx_check_params_default(mx_check_params *p);
/* Returns the exit status of `mixoct check`: 0 no defect, 3 defects found,
 * 2 bad input or usage (a message names the file), 1 internal failure
 * (out of memory included). Nothing to free. */
int mx_check_file(const mx_check_params *p);

/* ---- The mixoct program's other commands (patterns, 2D report) ---------- */

/* The deepest level of the 2D mesher's quadtree (levels 0 to 27; the
 * octree's is MX_MAX_LEVEL). */
#define MX_MAX_LEVEL2D 27

/* How many numbers the 2D refinement function `name` takes ("circle" 3,
 * "line" 4, "sine" 4: see mx_mesher2d_add_function); -1 when no function
 * has that name (or name is NULL). */
int mx_mesher2d_function_args(const char *name);

/* What a 2D run did besides meshing, for its report (the mesher2d program
 * fills it). The pointers are the caller's; the report only reads them. */
typedef struct {
  const char *domain;       /* the domain file, as given */
  int status;               /* the run's status, its exit code */
  const char *error;        /* the run's first error message; NULL or "": none */
  int nwarnings;
  int noutputs;             /* mesh files asked for; 0: a dry run */
  int nwritten;             /* of which written: outputs[0 .. nwritten-1] */
  const char *const *outputs;
  const long long *bytes;   /* the size of each written (-1: unknown) */
  const char *restart;      /* the restart file written; NULL: none */
  size_t listed;            /* elements listed for re-meshing (-l) */
  double total;             /* seconds, the whole run */
} mx_run2d_info;

/* The report of a 2D run on stdout. json != 0: one JSON line (numbers that
 * are not finite are null): the outcome, the files written, the mesh's
 * figures when there is a mesh, the check's when it ran, the phases'
 * seconds, peak memory and threads. json == 0: the text summary, printed
 * only for a run that succeeded or made a mesh (nothing otherwise: the
 * error message said it). m may be NULL (the run stopped before making the
 * mesher): the run's figures only. */
void mx_mesher2d_print_report(const mx_mesher2d *m, const mx_run2d_info *ri, int json);

/* `mixoct patterns`: the statistics of the compiled transition-pattern
 * table (configurations, classes, elements by type and their J_ENS, the
 * rows of Table II of the 2015 paper) on stdout, as text or (json != 0) one
 * JSON line. MX_OK, or MX_EINTERNAL (nothing printed) when the table does
 * not cover every legal configuration. */
int mx_patterns_print(int json);

/* ---- The distributed path (mixoct --p4est; MPI builds) ------------------ */

/* The octree, and unless stopped there the mesh, built by p4est over the
 * ranks of MPI_COMM_WORLD (src/mpi/): every rank reads the same inputs,
 * refines and balances its part of the forest, meshes its leaves; rank 0
 * reports. Only in the mixoct program of a build that found MPI and p4est
 * (MX_HAVE_MPI; compiled with src/mpi/, not part of libmixoct). Every call
 * is collective: every rank of MPI_COMM_WORLD makes it, with the same
 * arguments.
 *
 *   mx_p4est_init(&argc, &argv);   // before anything may print
 *   ... the program's options into an mx_p4est_run_params ...
 *   int st = mx_p4est_run(&p);
 *   mx_p4est_finalize();
 */
#ifdef MX_HAVE_MPI
typedef struct {
  const char *const *surfaces; /* -i: the domain's surfaces */
  int nsurfaces;
  /* per surface, parallel to surfaces (NULL: none given; 0 / NULL entries:
   * not given): --material ID[:NAME], --level L, --inside-level L after -i
   * (mx_mesher_add_input) */
  const int *material_ids;
  const char *const *material_names;
  const int *surface_levels, *inside_levels;
  int materials;               /* --materials: nested shells and touching
                                * inputs are materials (mx_params.materials) */
  int demo;                    /* --demo: the built-in surface, added first */
  const char *const *region_surfaces; /* -r SURF LEVEL */
  const int *region_levels;
  int nregions;
  const char *boxes_file;      /* -b: box regions; NULL none */
  int surface_level, all_level; /* -s, -a: -1 none */
  int stage;                   /* MX_STAGE_OCTREE, else the full mesh */
  int threads;                 /* per rank; 0: the OpenMP default */
  double max_memory_mb;        /* 0: the memory available */
  int repair_input;            /* refused (MX_EINPUT): p4est needs closed inputs */
  const char *const *outputs;  /* .pvtu (a piece per rank) or .msh (binary) */
  int noutputs;
  int ascii;                   /* refused with a .msh output (MX_EINPUT) */
  int json, quiet;             /* rank 0's report: one JSON line, or no text */
  int compare;                 /* --p4est-compare: rank 0 also builds the
                                * single-process octree and compares leaves */
} mx_p4est_run_params;

/* MPI (MPI_THREAD_FUNNELED; argc and argv are MPI_Init_thread's), sc and
 * p4est set up, and the calling thread's messages printed by rank 0 only
 * ("mixoct: error: ...", warnings unless quiet). MPI's errors abort. */
void mx_p4est_init(int *argc, char ***argv);
/* Checks the outputs, sets the thread count and quiet flag, adds the inputs
 * (demo, surfaces, region surfaces, boxes), builds and reports: on stdout
 * by rank 0, the text lines unless quiet, or with json one line (on a
 * failure after the outputs' check, {"p4est": true, "exit_code", "error"}).
 * Returns MX_OK or the status of the failure, the same on every rank (the
 * message printed). The strings of p are the caller's, read during the
 * call. */
int mx_p4est_run(const mx_p4est_run_params *p);
/* p4est's and MPI's end (MPI_Finalize): call once, after the last run. */
void mx_p4est_finalize(void);
#endif

#ifdef __cplusplus
}
#endif

#endif
