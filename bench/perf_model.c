/* mixoct-perfmodel: where each phase of the mesher stands against the
 * machine's memory bandwidth (issue 12, item 1).
 *
 *   mixoct-perfmodel [--mixoct PATH] [--stream PATH] [--input FILE]
 *                    [--level L] [--threads T] [--repeat N] [--stream-mb MB]
 *                    [--tmpdir DIR] [--no-probe] [--no-disk] [--no-latency]
 *                    [--json-only] [--model]
 *
 * 1. The limit: mixoct-stream (default: next to this program) once, with
 *    OMP_NUM_THREADS=T: the triad bandwidth at T threads (and at 1).
 *    A pointer chase over 256 MB (one dependent cache miss per step, one
 *    thread, 2 MB pages like mx_alloc's) gives the latency of a random
 *    access; a sequential write + fsync of the output's size, next to it,
 *    the storage's speed (for the write phase).
 * 2. The times: `mixoct -i FILE -s L --threads T --json -o TMP.vtu`, N times
 *    (default 3); the median of each phase and boundary step.
 * 3. The counts: the JSON's (leaves, nodes, elements, splits, boundary
 *    counts, file bytes), and, from one run of the same mesh in this process
 *    through libmixoct ("the probe"), the counts the JSON does not give:
 *    triangle ids per split octant, edge entries registered, points of the
 *    transition's node hash, close-to-boundary candidates, shrink pairs, the
 *    elements the verification files. The probe reads the library's own
 *    structures (mx_mesher, mx_builder, mx_mesh), not their copies;
 *    with --no-probe those counts are 0 (the model is then a lower bound).
 * 4. The model: per phase, bytes read + bytes written = sum over the arrays
 *    the phase streams of count x bytes per item, plus one cache line (64 B)
 *    per access to a hash or edge table (MODEL below; every constant there,
 *    sizes by sizeof on the project's types where they are visible, so the
 *    model follows when a type shrinks). MB moved / seconds is the phase's
 *    achieved bandwidth; its fraction of the triad at T threads says how
 *    close it runs to the hardware. Where the fraction is low a note gives
 *    what the counts say bounds it instead: the random lines at the measured
 *    latency, or the computation (queries, tests) and its implied cost.
 *
 * What the model counts: the compulsory traffic of the arrays that scale
 * with the mesh (octants, leaves, nodes, elements), each array counted once
 * per pass that streams it, a gather through conn counted once per node and
 * pass (nodes are numbered in leaf order: neighbours' data are near). Not
 * counted: the input surface's data (triangle coordinates, the BVH, the
 * locator; 6300 triangles for the cortex, under 1 MB, cache-resident), the
 * pattern tables, scratch below 64 KB, allocator page faults, the re-hash
 * of a grown edge table. Hash and edge accesses count a full line each even
 * where the block hashing makes neighbours share windows, an upper bound.
 * Printed: one table, then one JSON line. --model prints the model's table
 * (the per-item constants with what they count) and exits.
 *
 * The constants were read from the code of commit e755045 (8-bit levels,
 * float J_ENS, sort by leaf by merging the tail), the transition, close,
 * patterns and untangling rows again from the passes of issue 31 (Morton
 * ranges and families; moves at the decision; patterns in place; sparse
 * incidence); a change to a phase's passes needs its rows here changed too
 * (sizes follow by themselves). */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bench_util.h"
#include "mixoct.h"
#include "kernels/boundary.h"
#include "kernels/contacts.h"
#include "geom/distance.h"
#include "kernels/surface_patterns.h"
#include "kernels/transition.h"
#include "mesher/mesher.h"
#include "patterns/lookup.h"
#include "soa/edges.h"
#include "soa/mesh.h"
#include "soa/octree.h"
#include "io/write_mesh.h"

/* ---- sizes: sizeof on the project's types ------------------------------- */

#define FSZ(T, f) ((double)sizeof(((T *)0)->f[0]))
/* the octree (src/soa/octree.h), one octant across its arrays */
#define O_KEY FSZ(mx_octree, key)
#define O_LEVEL FSZ(mx_octree, level)
#define O_FLAGS FSZ(mx_octree, flags)
#define O_TARGET FSZ(mx_octree, target)
#define O_KEPT FSZ(mx_octree, kept)
#define O_RMEET FSZ(mx_octree, rmeet)
#define O_RIN FSZ(mx_octree, rin)
#define O_PARENT FSZ(mx_octree, parent)
#define O_CHILD0 FSZ(mx_octree, child0)
#define O_TRIOFF FSZ(mx_octree, tri_off)
#define O_TRICNT FSZ(mx_octree, tri_cnt)
#define O_TRIPOOL FSZ(mx_octree, tri_pool)
#define OCT_ROW                                                                            \
  (O_KEY + O_LEVEL + O_FLAGS + O_TARGET + O_KEPT + O_RMEET + O_RIN + O_PARENT + O_CHILD0 + \
   O_TRIOFF + O_TRICNT)
/* the mesh (src/kernels/transition.h: mx_mesh), one element / node */
#define M_TYPE FSZ(mx_mesh, type)
#define M_CONN (8.0 * FSZ(mx_mesh, conn)) /* a row of 8 node ids */
#define M_LEVEL FSZ(mx_mesh, level)
#define M_LEAF FSZ(mx_mesh, leaf)
#define M_JENS FSZ(mx_mesh, jens)
#define M_XYZ (3.0 * FSZ(mx_mesh, xyz))
#define M_NKEY FSZ(mx_mesh, nkey)
#define CELL_ROW (M_TYPE + M_CONN + M_LEVEL + M_LEAF + M_JENS)
/* the optional elements of the surface patterns (kernels/surface_patterns.h) */
#define OPT_ROW                                                                    \
  (FSZ(mx_optional, type) + 8.0 * FSZ(mx_optional, conn) + FSZ(mx_optional, leaf) + \
   FSZ(mx_optional, level))
#define STATE FSZ(mx_mesher, states)        /* per node state (mesher.h) */
#define PATREF ((double)sizeof(mx_pattern_ref)) /* class + rotation per leaf */
#define EDGE_ENTRY ((double)sizeof(mx_edge)) /* one edge info (soa/edges.h) */
/* Private to their .c files (not visible by sizeof): */
#define NODE_ENTRY 16.0 /* transition.c node_entry: kw 8 + owner 4 + id 4 */
#define SPLIT_INFO 64.0 /* refine.c split_info: 2 + 8 + 8 + 8 + 32 + 4 = 62, padded */
#define U64 8.0         /* offsets, counts, prefix sums (uint64_t) */
#define IDX 4.0         /* uint32 lists (octant, leaf, element, node ids) */
#define I32 4.0         /* int32 fields of the writers (type, level, body, tags) */
#define F64 8.0         /* double fields of the writers (jens) */
#define SCAN_R (2 * U64) /* mx_scan_u64: a read pass, then a read + write pass */
#define SCAN_W U64
#define LINE 64.0       /* one cache line: a random access */
/* Verification grid (check.c ggrid): each surface element is filed in the
 * cells its box meets at a level whose cell is >= 4x the box: at most 2
 * per axis, (1 + 1/4)^3 ~ 2 on average. */
#define GRID_ENTRIES 2.0
#define RADIX_PASSES 4.0 /* mx_sort_u64 of the grid keys: ~4 varying bytes */

/* ---- the counts ---------------------------------------------------------- */

enum {
  K_TRI,        /* input triangles */
  K_ROOT,       /* root octants */
  K_SPLIT_R,    /* octants split by a request (JSON split_requested) */
  K_SPLIT_B,    /* octants split for balance (JSON split_balance) */
  K_CHILD_R,    /* children created by requested splits */
  K_CHILD_B,    /* children created by balance splits */
  K_TRIP_R,     /* triangle ids of the octants split by request */
  K_TRIP_B,     /* triangle ids of the octants split for balance */
  K_TRIC_R,     /* triangle ids written for their children */
  K_TRIC_B,
  K_EDGE_R,     /* edge entries found or claimed registering the children */
  K_EDGE_B,
  K_EDGE_BYTES, /* edge tables (JSON edge_mb) */
  K_RAY,        /* ray-parity queries (JSON located) */
  K_RUNS,       /* sibling runs the balance examines */
  K_LEAF,       /* leaves (JSON) */
  K_LEAF_E,     /* leaves at levels with edge infos (their masks look them up) */
  K_POINT,      /* (leaf, node) points of the transition (node hash accesses / 4) */
  K_NODE_T,     /* nodes of the transition mesh */
  K_ELEM_T,     /* elements of the transition mesh */
  K_ELEM_TI,    /* of which in leaves meeting no triangle (all nodes inside) */
  K_LOCATE_B,   /* nodes located with the surface index (JSON boundary.located) */
  K_CAND,       /* close-to-boundary candidates */
  K_CAND_Q,     /* closest-point queries (every candidate) */
  K_MOVED_C,    /* nodes moved close (JSON boundary.moved_close) */
  K_PATTERNED,  /* elements replaced by a surface pattern (JSON) */
  K_SUB,        /* elements after the patterns (JSON boundary.sub_elements) */
  K_OPT,        /* optional sub-elements (JSON boundary.optional) */
  K_CENTRE,     /* element centres added (JSON boundary.centres) */
  K_SHR_PAIR,   /* (leaf, outside node) pairs of the shrink */
  K_SHR_TEST,   /* point-triangle distances per shrink pass */
  K_SHRUNK,     /* outside nodes moved (JSON boundary.shrunk) */
  K_SMOOTHED,   /* node moves of the smoothing (JSON boundary.smoothed) */
  K_RESTORED,   /* optional elements put back (JSON boundary.restored) */
  K_NODE,       /* nodes of the mesh (JSON) */
  K_ELEM,       /* elements of the mesh (JSON) */
  K_SURF_ELEM,  /* elements with a face of surface nodes (verification list) */
  K_SURF_NODE,  /* surface nodes queried by the verification */
  K_SURF_PROBE, /* their grid cell probes (one per occupied level) */
  K_NEAR_FACE,  /* element faces whose nodes are all near the surface (write) */
  K_FILE,       /* bytes of the output file (JSON outputs[0].bytes) */
  K_COUNT
};

static const char *const count_name[K_COUNT] = {
    "triangles", "roots", "split_requested", "split_balance", "children_requested",
    "children_balance", "tri_ids_requested", "tri_ids_balance", "child_tri_ids_requested",
    "child_tri_ids_balance", "edge_inserts_requested", "edge_inserts_balance", "edge_bytes",
    "ray_queries", "balance_runs", "leaves", "leaves_with_edges", "points", "nodes_transition",
    "elements_transition", "elements_inside_leaves", "located_nodes", "close_candidates",
    "close_queries", "moved_close", "patterned", "sub_elements", "optional", "centres", "shrink_pairs",
    "shrink_tests", "shrunk", "smoothed", "restored", "nodes", "elements",
    "surface_elements", "surface_nodes", "surface_probes", "near_faces", "file_bytes"};

/* ---- the model: every per-item constant --------------------------------- */

typedef struct {
  const char *phase; /* a row of the table (boundary steps: "b.<step>") */
  int count;         /* K_* the constants are multiplied by */
  double r, w;       /* bytes read, bytes written per item */
  double lines;      /* random cache lines per item (hash / edge tables) */
  const char *what;  /* the arrays counted */
} term;

/* One octant split (mx_split_octants, kernels/refine.c), the same for the
 * requested splits (refine) and the balance splits (balance). */
#define SPLIT_TERMS(PH, KS, KTP, KCH, KTC, KE)                                                 \
  {PH, KS, IDX + O_TRICNT + SCAN_R, U64 + SCAN_W, 0,                                          \
   "split: list + tri_cnt read, moff written; its prefix sum"},                               \
  {PH, KS, IDX + O_KEY + O_LEVEL + O_TRIOFF + O_TRICNT + O_FLAGS + O_RMEET + O_RIN + U64,     \
   SPLIT_INFO, 0,                                                                              \
   "classify: list, key, level, tri_off, tri_cnt, flags, rmeet, rin, moff read; split_info "  \
   "written (64)"},                                                                            \
  {PH, KS, SPLIT_INFO + 2 * SCAN_R, 2 * U64 + 2 * SCAN_W, 0,                                   \
   "count: split_info read, coff + toff written; their prefix sums"},                         \
  {PH, KS, IDX + SPLIT_INFO + O_TRIOFF + O_TRICNT + 3 * U64 + O_KEY + O_FLAGS,                 \
   O_CHILD0 + O_KEPT + O_FLAGS, 0,                                                             \
   "fill: list, split_info, tri_off, tri_cnt, moff, coff, toff, key, flags read; child0, "    \
   "kept, flags written"},                                                                     \
  {PH, KTP, 2 * O_TRIPOOL + 1, 1, 0,                                                           \
   "per triangle id of the split octant: tri_pool read twice, child mask written (1) and "    \
   "read (1); its coordinates (tri_xyz) are the input's, cache-resident"},                    \
  {PH, KCH, 0, OCT_ROW, 0,                                                                     \
   "per child: every octant array written (key, level, flags, target, kept, rmeet, rin, "     \
   "parent, child0, tri_off, tri_cnt)"},                                                       \
  {PH, KTC, 0, O_TRIPOOL, 0, "per child triangle id: tri_pool written"},                       \
  {PH, KE, 0, 0, 1,                                                                            \
   "per edge of the children (mx_edges_register_children): one edge entry found or claimed "  \
   "by CAS, slots written: 1 line"}

static const term MODEL[] = {
    /* grid: mx_builder_init + mx_build_roots (kernels/refine.c) */
    {"grid", K_TRI, 3 * IDX + 2 * 72.0, 72.0 + 1, 0,
     "per input triangle: soup tri ids read, tri_xyz (9 doubles) written, read by the 2 "
     "root passes; tri_region written"},
    {"grid", K_ROOT, 0, OCT_ROW, 12,
     "per root: every octant array written; its 12 edges registered (1 line each)"},

    /* refine: the requested splits (mx_split_octants) and next_candidates */
    SPLIT_TERMS("refine", K_SPLIT_R, K_TRIP_R, K_CHILD_R, K_TRIC_R, K_EDGE_R),
    {"refine", K_SPLIT_R, 2 * (IDX + O_KEPT + O_CHILD0) + SCAN_R, U64 + SCAN_W + IDX, 0,
     "next candidates: cand, kept, child0 read (2 passes), off written, its prefix sum, next "
     "list written"},
    {"refine", K_CHILD_R, 2 * (O_TARGET + O_LEVEL), 0, 0,
     "next candidates: each child's target and level read (2 passes)"},
    {"refine", K_EDGE_BYTES, 0, 1, 0,
     "edge tables initialised (kw 0, slots MX_NONE) once at their final size"},

    /* balance: mx_balance_drain (kernels/balance.c), then its splits */
    {"balance", K_RUNS, 3 * IDX + O_PARENT + O_KEY + O_LEVEL, 0, 12 + 18,
     "per run of siblings: cur + parent ids read; the parent's 12 edge entries (1 line "
     "each) and the flags of its up to 18 face/edge neighbours (1 line each)"},
    {"balance", K_SPLIT_B, IDX, 2 * IDX, 0,
     "per octant queued: pushed to a thread buffer, copied into the wave list"},
    SPLIT_TERMS("balance", K_SPLIT_B, K_TRIP_B, K_CHILD_B, K_TRIC_B, K_EDGE_B),

    /* transition: mx_transition_masks + mx_transition_build (kernels/transition.c) */
    {"transition", K_LEAF, IDX + O_LEVEL + O_KEY, 2 * IDX, 0,
     "masks: leaves, level, key read; mask + closure bits written"},
    {"transition", K_LEAF_E, 18 * (O_FLAGS + O_KEPT), 0, 12,
     "masks of leaves with edge infos: 12 edge entries (1 line each); flags + kept of the "
     "18 face/edge neighbours"},
    {"transition", K_LEAF, IDX, IDX, 0,
     "classes (pass 0): mask read, the body-centre bit written back (counts per Morton "
     "range of leaves only)"},
    {"transition", K_LEAF, 6 * IDX + 3 * (O_KEY + O_LEVEL), 2 * IDX, 0,
     "passes 1-3 by family (insert, numbering, gather): leaves, key, level read by each; "
     "mask read by insert and gather; own written by insert, read and written by numbering"},
    {"transition", K_LEAF, 3 * IDX + O_KEY + O_LEVEL, 0, 0,
     "elements (pass 4): leaves, key, level, mask, own read"},
    {"transition", K_POINT, IDX, IDX + NODE_ENTRY / 3, 3,
     "per point: the node entry (16 B) touched by the insert, the gather and, for its "
     "owner, the numbering (1 line each: an upper bound); its id written into the leaf's "
     "rows by the gather, read by pass 4; the hash zeroed (16 B per 3 points)"},
    {"transition", K_NODE_T, 0, M_NKEY + M_XYZ, 0, "per node: nkey + xyz written"},
    {"transition", K_ELEM_T, M_TYPE, CELL_ROW, 0,
     "per element: type + conn[8] + level + leaf + jens written; type read (by-type count)"},

    /* boundary stage (kernels/boundary_stage.c), step by step */
    {"b.states", K_NODE_T, STATE, 2 * STATE, 0,
     "mx_node_states per node: states initialised, scattered (inside), read by the "
     "locate pass"},
    {"b.states", K_ELEM_T, M_LEAF + M_TYPE + IDX + O_FLAGS, 0, 0,
     "per element: leaf, type, leaves + the leaf's flags read"},
    {"b.states", K_ELEM_TI, M_CONN, 0, 0,
     "per element of a leaf meeting no triangle: conn read (its nodes inside)"},
    {"b.states", K_LOCATE_B, M_XYZ, STATE, 0,
     "per located node: xyz read, state written (a signed-distance query)"},

    {"b.close", K_NODE_T, STATE + 2 + 2 * M_XYZ + U64, 2 + U64, 0,
     "mx_move_close_nodes per node: cand + len zeroed; states gathered by the candidates "
     "pass, cand + xyz by the edge-length pass; bounding box reads xyz; the decision reads "
     "cand + len, writes cand"},
    {"b.close", K_ELEM_T, 2 * (M_TYPE + M_CONN), 0, 0,
     "per element: type + conn read (candidates pass, edge-length pass)"},
    {"b.close", K_CAND, 2 * U64, U64, 0,
     "per candidate: count + length (one word) added atomically once per element; read at "
     "the decision"},
    {"b.close", K_CAND_Q, M_XYZ, 0, 0,
     "per candidate (each a closest-point query): xyz read"},
    {"b.close", K_MOVED_C, 0, M_XYZ + STATE, 0,
     "per node moved (at its decision): xyz + state written"},

    {"b.patterns", K_ELEM_T, 2 * (M_TYPE + M_CONN) + M_LEVEL + M_LEAF + M_JENS, 0, 0,
     "mx_surface_patterns per element in: type + conn read by the count and the fill "
     "pass (counts per block of 2048 only); level, leaf, jens read"},
    {"b.patterns", K_NODE_T, 2 * STATE + 1 + M_XYZ, 0, 0,
     "per node: states (2 passes) + moved gathered, xyz gathered for the J_ENS"},
    {"b.patterns", K_SUB, 2 * (M_TYPE + M_CONN) + M_TYPE + M_JENS, CELL_ROW + M_CONN, 0,
     "per element out: type + conn[8] + level + leaf + jens written (in place from the "
     "end; the mesh's start, a few %, through new arrays); drop-unused-nodes "
     "reads type + conn twice, writes conn; summary reads type + jens"},
    {"b.patterns", K_OPT, OPT_ROW, 2 * OPT_ROW, 0,
     "per optional element: type, conn, leaf, level written, then compacted (serial)"},
    {"b.patterns", K_NODE, U64 + SCAN_R + 2 * IDX + M_XYZ + STATE + M_NKEY,
     2 * U64 + SCAN_W + 2 * IDX + M_XYZ + STATE + M_NKEY, 0,
     "drop unused nodes per node: id zeroed + marked, read, prefix sum; newid written and "
     "read; xyz, state, nkey copied"},
    {"b.patterns", K_CENTRE, 0, M_XYZ + STATE + M_NKEY, 0,
     "per centre: xyz, state, nkey written"},

    {"b.shrink", K_SUB, 2 * M_LEAF + (M_TYPE + M_CONN) + M_TYPE + M_CONN + M_JENS, M_JENS, 0,
     "mx_shrink_to_boundary per element: leaf read (run count + fill), type + conn read by "
     "the pass over leaves and the J_ENS pass; jens read + written"},
    {"b.shrink", K_LEAF, U64 + IDX + O_TRICNT, U64, 0,
     "per leaf: run start written, read once; leaves + tri_cnt read"},
    {"b.shrink", K_NODE, 2 * STATE + IDX + M_XYZ, U64 + IDX + 1, 0,
     "per node: best + btri + lock initialised; states gathered x2; btri read; xyz "
     "gathered"},
    {"b.shrink", K_SHR_PAIR, M_XYZ + U64 + IDX + 1, U64 + IDX + 1, 0,
     "per (leaf, outside node) pair: xyz read; under the node's lock best + btri read "
     "and written"},
    {"b.shrink", K_SHRUNK, M_XYZ, M_XYZ, 0, "per node moved: xyz read + written"},

    {"b.smooth", K_ELEM, M_JENS + (M_TYPE + M_CONN) + M_TYPE + M_JENS, 0, 0,
     "mx_untangle per element: jens read (work set), type + conn read once (a bit per "
     "element with a marked node; the incidence then walks those only), summary reads "
     "type + jens"},
    {"b.smooth", K_NODE, 1 + SCAN_R + U64 + 2 * 1, 1 + U64 + SCAN_W + U64 + IDX, 0,
     "per node: mark + off zeroed, mark gathered once, prefix sum, off moved up one place, "
     "mark read by the work list's count + fill; widx initialised"},

    {"b.staircase", K_OPT, FSZ(mx_optional, type) + 8 * FSZ(mx_optional, conn) + 2 + 8, 1 + 8,
     0, "mx_staircase per optional element: type + conn read, ok + q written and read"},
    {"b.staircase", K_RESTORED, OPT_ROW + 8, CELL_ROW, 0,
     "per element put back: appended to every mesh array"},
    {"b.staircase", K_ELEM, M_TYPE + M_JENS, 0, 0, "summary: type + jens read"},

    /* the rest of the boundary phase: mx_mesh_sort_by_leaf + renumbering */
    {"b.rest", K_ELEM, 2 * M_LEAF + CELL_ROW, CELL_ROW, 0,
     "sort by leaf: leaf read (order check); the restored tail merged from the back: "
     "every element after the first insertion moved (all counted), leaf compared"},
    {"b.rest", K_ELEM, 3 * (M_TYPE + M_CONN) + SCAN_R + U64 + M_TYPE + M_CONN,
     U64 + SCAN_W + M_CONN, 0,
     "renumber by first use: type + conn read by 3 passes, cnt written + prefix sum; conn "
     "rewritten"},
    {"b.rest", K_NODE, 3 * U64 + M_XYZ + STATE + M_NKEY + IDX,
     U64 + 2 * IDX + M_XYZ + STATE + M_NKEY, 0,
     "per node: first + newid initialised, first CAS / read x3, newid written; xyz, state, "
     "nkey copied"},

    /* verify: mx_find_contacts (kernels/contacts.c, check.c) */
    {"verify", K_ELEM, 2 * (M_TYPE + M_CONN), 1, 0,
     "per element: flag zeroed; type + conn read by 2 passes (surface faces)"},
    {"verify", K_NODE, 2 * STATE + STATE + 1 + 3 * M_XYZ, 3, 0,
     "per node: sel + hit zeroed; states gathered x2; sel from states; bounding box reads "
     "xyz 3 times (one pass per axis)"},
    {"verify", K_SURF_ELEM, 2 * IDX + 48 + 1 + U64 + SCAN_R, IDX + 48 + 1 + U64 + SCAN_W, 0,
     "per listed element: list written + read; padded box (48), level, entry count "
     "written and read, prefix sum"},
    {"verify", K_SURF_ELEM,
     GRID_ENTRIES * (RADIX_PASSES * (U64 + IDX + U64) + IDX + 24 + IDX + U64),
     GRID_ENTRIES * (U64 + IDX + IDX + 24 + RADIX_PASSES * (U64 + IDX) + 24 + IDX),
     GRID_ENTRIES * 1,
     "per grid entry (2 per element): key, idx, element, float box written; radix sort "
     "(4 passes, key + idx, histogram); box + element gathered into cell order; the cell "
     "hash (1 line)"},
    {"verify", K_SURF_NODE, 1 + M_XYZ, 0, 0, "per surface node: sel + xyz read"},
    {"verify", K_SURF_PROBE, 0, 0, 1, "per grid probe: the cell's hash slot (1 line)"},

    /* quality: mx_quality_tabulate (geom/quality.c) */
    {"quality", K_ELEM, M_TYPE + M_JENS, 0, 0, "per element: type + jens read"},

    /* write: mx_write_mixed (mesher/output.c) = prepare + mx_write_vtu */
    {"write", K_ELEM, M_TYPE + M_LEVEL + M_JENS + M_LEAF + IDX + O_TRICNT + M_TYPE + M_CONN,
     2 * I32 + F64, 0,
     "prepare: type, level, jens copied to the writers' int32/double fields; near-node "
     "pass reads leaf, leaves, tri_cnt, type, conn"},
    {"write", K_ELEM, M_TYPE + M_CONN + 2 * (M_TYPE + IDX), I32, 0,
     "bodies (union-find): type + conn read, then conn[0] twice; cell_body written"},
    {"write", K_ELEM, 2 * (M_TYPE + I32), IDX, 0,
     "written order: type + body read x2, order written"},
    {"write", K_ELEM, 2 * (M_TYPE + M_CONN) + 2 * (M_TYPE + 6), 6, 0,
     "boundary faces: type + conn read x2 (file faces), multiplicity (6 slots) written, "
     "type + multiplicity read x2 (gather)"},
    {"write", K_ELEM, 2 * M_TYPE + M_CONN, 0, 0,
     "view check (type + conn read), connectivity length (type read)"},
    {"write", K_ELEM,
     3 * I32 + 4 * IDX + I32 + I32 + F64 + I32 + IDX + LINE + 3 * (IDX + M_TYPE),
     0, 0,
     "vtu: u8 checks of type, level, body; type, level, jens, body gathered through order; "
     "conn rows gathered (a line each); offsets, block starts, types read type via order"},
    {"write", K_NODE, STATE + 4 * I32 + SCAN_R + U64 + 2 * I32 + M_XYZ,
     I32 + 4 * I32 + U64 + SCAN_W + 1 + I32, 0,
     "per node: boundary flag copied to int32; union-find roots + body numbers; faces CSR "
     "offsets; near flags; surface_tag; point fields checked + written; xyz read"},
    {"write", K_NEAR_FACE, U64 + IDX + 16, U64 + IDX + 16 + 1, 1,
     "per face filed: CSR count + fill, list read, sorted key built, multiplicity written; "
     "its element's row gathered (1 line)"},
    {"write", K_FILE, 2, 2, 0,
     "per file byte: written into the chunk buffer, copied into the page cache by write(2) "
     "(read + write), read by the device at fsync"},
};
#define NMODEL (sizeof MODEL / sizeof *MODEL)

/* ---- the rows of the table ------------------------------------------------ */

typedef struct {
  const char *name;   /* as in MODEL; "boundary" sums the b.* rows */
  const char *json;   /* key of the seconds (phases.* or boundary.seconds.*) */
  int sub;            /* 1: a boundary step */
  int item;           /* K_* shown as the items */
  const char *item_name;
  int cpu;            /* K_* of the computation that may bound it, -1 none */
  const char *cpu_name;
  int serial;         /* 1: its main loop runs on one thread */
} row_def;

static const row_def ROWS[] = {
    {"grid", "grid", 0, K_TRI, "triangles", K_TRI, "input triangles (root tests, locator)", 0},
    {"refine", "refine", 0, K_SPLIT_R, "splits", K_TRIP_R, "tri ids classified", 0},
    {"balance", "balance", 0, K_SPLIT_B, "splits", K_TRIP_B, "tri ids classified", 0},
    {"transition", "transition", 0, K_LEAF, "leaves", -1, NULL, 0},
    {"b.states", "states", 1, K_NODE_T, "nodes", K_LOCATE_B, "signed-distance queries", 0},
    {"b.close", "close", 1, K_NODE_T, "nodes", K_CAND_Q, "closest-point queries", 0},
    {"b.patterns", "patterns", 1, K_ELEM_T, "elements", K_PATTERNED, "tessellations", 0},
    {"b.shrink", "shrink", 1, K_NODE, "nodes", K_SHR_TEST, "pt-tri distances", 0},
    {"b.smooth", "smooth", 1, K_ELEM, "elements", K_SMOOTHED, "node moves", 0},
    {"b.staircase", "staircase", 1, K_OPT, "optional", K_OPT, "J_ENS evaluations", 0},
    {"b.rest", NULL, 1, K_ELEM, "elements", -1, NULL, 0},
    {"boundary", "boundary", 0, K_ELEM, "elements", -1, NULL, 0},
    {"verify", "verify", 0, K_ELEM, "elements", K_SURF_NODE, "node queries", 0},
    {"quality", "quality", 0, K_ELEM, "elements", -1, NULL, 0},
    {"write", "write", 0, K_ELEM, "elements", -1, NULL, 0},
};
#define NROWS (sizeof ROWS / sizeof *ROWS)
#define LOW_FRACTION 0.3 /* below this fraction of the triad a row gets a note */

/* ---- JSON lookups ------------------------------------------------------- */

static const char *jfind(const char *s, const char *key) {
  if (!s) return NULL;
  char pat[96];
  snprintf(pat, sizeof pat, "\"%s\": ", key);
  const char *p = strstr(s, pat);
  return p ? p + strlen(pat) : NULL;
}

static double jnum(const char *s, const char *key) {
  const char *p = jfind(s, key);
  return p ? strtod(p, NULL) : NAN;
}

/* Object "key": {...} (the text from its brace): the first occurrence of
 * the key whose value is an object ("boundary" is also a phase's seconds). */
static const char *jobj(const char *s, const char *key) {
  for (const char *p = jfind(s, key); p; p = jfind(p, key))
    if (*p == '{') return p;
  return NULL;
}

/* The two numbers of "key": [a, b]. */
static int jpair(const char *s, const char *key, double v[2]) {
  const char *p = jfind(s, key);
  if (!p || *p != '[') return 0;
  char *e;
  v[0] = strtod(p + 1, &e);
  if (*e != ',') return 0;
  v[1] = strtod(e + 1, NULL);
  return 1;
}

/* The last line of a command's stdout that holds a '{' (malloc'd). */
static char *run_json(const char *cmd, int *status) {
  FILE *p = popen(cmd, "r");
  if (!p) return NULL;
  char *line = NULL, *last = NULL;
  size_t cap = 0;
  while (getline(&line, &cap, p) > 0)
    if (strchr(line, '{')) {
      free(last);
      last = strdup(line);
    }
  free(line);
  *status = pclose(p);
  return last;
}

/* The 1-minute load average (other work on the machine skews the times). */
static double loadavg(void) {
  double l = NAN;
  FILE *f = fopen("/proc/loadavg", "r");
  if (f) {
    if (fscanf(f, "%lf", &l) != 1) l = NAN;
    fclose(f);
  }
  return l;
}

/* ---- machine figures ------------------------------------------------------ */

/* ns per dependent random access: a pointer chase over a random cycle of
 * cache lines (Sattolo) in `mb` MB on 2 MB pages where the kernel allows
 * (as mx_alloc gives the big arrays), one thread. */
static double chase_latency_ns(size_t mb) {
  const size_t n = mb * 1048576 / 64;
  uint64_t *a = NULL;
  if (posix_memalign((void **)&a, 2u << 20, n * 64)) return NAN;
#ifdef MADV_HUGEPAGE
  madvise(a, n * 64, MADV_HUGEPAGE); /* as mx_alloc does for big arrays */
#endif
  size_t *perm = malloc(n * sizeof *perm);
  if (!perm) {
    free(a);
    return NAN;
  }
  for (size_t i = 0; i < n; i++) perm[i] = i;
  uint64_t x = 0x9E3779B97F4A7C15ull;
  for (size_t i = n - 1; i > 0; i--) { /* Sattolo: one cycle through all */
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    const size_t j = (size_t)(x % i);
    const size_t t = perm[i];
    perm[i] = perm[j];
    perm[j] = t;
  }
  for (size_t i = 0; i < n; i++) a[8 * perm[i]] = 8 * perm[(i + 1) % n];
  free(perm);
  const size_t steps = 4000000;
  size_t p = 0;
  for (size_t i = 0; i < 100000; i++) p = a[p]; /* warm the TLB walk caches */
  const double t0 = omp_get_wtime();
  for (size_t i = 0; i < steps; i++) p = a[p];
  const double t = omp_get_wtime() - t0;
  volatile size_t sink = p;
  (void)sink;
  free(a);
  return t / (double)steps * 1e9;
}

/* GB/s of a sequential write of `bytes` to a new file in dir, fsync included
 * (what the writer does at the end). */
static double seq_write_gbs(const char *dir, double bytes) {
  char path[4400];
  snprintf(path, sizeof path, "%s/perfmodel-seq.bin", dir);
  const size_t chunk = 8u << 20;
  char *buf = malloc(chunk);
  if (!buf) return NAN;
  for (size_t i = 0; i < chunk; i++) buf[i] = (char)(i * 131 + 7);
  const int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
  if (fd < 0) {
    free(buf);
    return NAN;
  }
  const double t0 = omp_get_wtime();
  double left = bytes;
  int ok = 1;
  while (left > 0 && ok) {
    const size_t n = left < (double)chunk ? (size_t)left : chunk;
    ok = write(fd, buf, n) == (ssize_t)n;
    left -= (double)n;
  }
  ok = ok && fsync(fd) == 0;
  const double t = omp_get_wtime() - t0;
  close(fd);
  unlink(path);
  free(buf);
  return ok && t > 0 ? bytes / t / 1e9 : NAN;
}

/* ---- the probe: counts from the library's own structures ------------------ */

static void silent(void *user, int level, const char *text) {
  (void)user;
  if (level == MX_MSG_ERROR) fprintf(stderr, "mixoct-perfmodel: probe: %s\n", text);
}

/* Edge entries mx_edges_register_children looks up for a split octant with
 * these kept children: the 54 edges of the children's level inside and on
 * the octant that one of the kept children has. */
static int edge_inserts(uint8_t kept) {
  int n = 0;
  for (int a = 0; a < 3; a++) {
    const int b = (a + 1) % 3, d = (a + 2) % 3;
    for (int s = 0; s < 2; s++)
      for (int jb = 0; jb < 3; jb++)
        for (int jd = 0; jd < 3; jd++) {
          int any = 0;
          for (int cb = jb - 1; cb <= jb; cb++)
            for (int cd = jd - 1; cd <= jd; cd++) {
              if (cb < 0 || cb > 1 || cd < 0 || cd > 1) continue;
              any |= (kept >> ((s << a) | (cb << b) | (cd << d))) & 1;
            }
          n += any;
        }
  }
  return n;
}

/* Appends v to out[0..k) unless it is there (at most cap); the new k. */
static int add_distinct(uint32_t *out, int k, int cap, uint32_t v) {
  for (int j = 0; j < k; j++)
    if (out[j] == v) return k;
  if (k < cap) out[k++] = v;
  return k;
}

static int probe(const char *input, int level, int threads, double *K, double final[3]) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = level;
  p.threads = threads;
  mx_mesher *m = mx_mesher_new(&p);
  if (!m) return 1;
  mx_mesher_set_message_handler(m, silent, NULL);
  int st = mx_mesher_add_surface(m, input);
  if (!st) st = mx_mesher_build_octree(m);
  if (st) {
    mx_mesher_free(m);
    return 1;
  }
  /* the octree: splits, children, triangle ids, edges, balance runs */
  const mx_builder *B = &m->B;
  const mx_octree *T = &B->tree.oct;
  K[K_TRI] = (double)B->soup->nt;
  int ins[256];
  for (int k = 0; k < 256; k++) ins[k] = edge_inserts((uint8_t)k);
  uint8_t *parent_mark = calloc(T->n + 1, 1);
  if (!parent_mark) {
    mx_mesher_free(m);
    return 1;
  }
  for (size_t o = 0; o < T->n; o++) {
    if (T->level[o] == 0) K[K_ROOT] += 1;
    if (!(T->flags[o] & MX_OCT_SPLIT)) continue;
    const int bal = (T->flags[o] & MX_OCT_BALANCE) != 0;
    K[bal ? K_TRIP_B : K_TRIP_R] += T->tri_cnt[o];
    const int nk = __builtin_popcount(T->kept[o]);
    K[bal ? K_CHILD_B : K_CHILD_R] += nk;
    for (int k = 0; k < nk; k++) K[bal ? K_TRIC_B : K_TRIC_R] += T->tri_cnt[T->child0[o] + (uint32_t)k];
    if (B->tree.use_edges && T->level[o] + 1 <= B->tree.edge_levels)
      K[bal ? K_EDGE_B : K_EDGE_R] += ins[T->kept[o]];
    if (T->parent[o] != MX_NONE) parent_mark[T->parent[o]] = 1;
  }
  for (size_t o = 0; o < T->n; o++) K[K_RUNS] += parent_mark[o];
  free(parent_mark);
  const int etop = mx_edge_top(&B->tree);
  for (size_t i = 0; i < m->nleaves; i++) K[K_LEAF_E] += T->level[m->leaves[i]] <= etop;

  /* the transition mesh: points per leaf, inside-leaf elements, states */
  st = mx_mesher_transition(m);
  if (st) {
    mx_mesher_free(m);
    return 1;
  }
  {
    const mx_mesh *M = &m->M;
    K[K_NODE_T] = (double)M->nnodes;
    K[K_ELEM_T] = (double)M->ncells;
    for (size_t c = 0; c < M->ncells;) {
      size_t e = c;
      uint32_t pts[64];
      int np = 0;
      while (e < M->ncells && M->leaf[e] == M->leaf[c]) {
        for (int k = 0; k < mx_cell_nodes[M->type[e]]; k++)
          np = add_distinct(pts, np, 64, M->conn[8 * e + k]);
        e++;
      }
      K[K_POINT] += np;
      if (!(T->flags[m->leaves[M->leaf[c]]] & MX_OCT_SURFACE)) K[K_ELEM_TI] += (double)(e - c);
      c = e;
    }
    /* the node states (mx_node_states' rule: the nodes of leaves meeting no
     * triangle are inside, the others located), then the candidates of the
     * close-to-boundary step: inside nodes of elements with both kinds, each
     * queried (few were located: most are corners of inside leaves too) */
    mx_surface_index SI;
    uint8_t *states = malloc(M->nnodes + 1);
    uint8_t *cand = calloc(M->nnodes + 1, 1);
    uint8_t *set = calloc(M->nnodes + 1, 1);
    st = !states || !cand || !set;
    if (!st) st = mx_surface_index_build(&SI, &m->soup, 0, m->nt_domain);
    if (!st) {
      for (size_t c = 0; c < M->ncells; c++)
        if (!(T->flags[m->leaves[M->leaf[c]]] & MX_OCT_SURFACE))
          for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++) set[M->conn[8 * c + k]] = 1;
#pragma omp parallel for schedule(dynamic, 4096)
      for (size_t v = 0; v < M->nnodes; v++)
        states[v] = set[v] || mx_inside(&SI, M->xyz + 3 * v) ? MX_NODE_INSIDE : MX_NODE_OUTSIDE;
      mx_surface_index_free(&SI);
      for (size_t c = 0; c < M->ncells; c++) {
        const int nv = mx_cell_nodes[M->type[c]];
        int in = 0;
        for (int k = 0; k < nv; k++) in += states[M->conn[8 * c + k]] == MX_NODE_INSIDE;
        if (in == 0 || in == nv) continue;
        for (int k = 0; k < nv; k++)
          if (states[M->conn[8 * c + k]] == MX_NODE_INSIDE) cand[M->conn[8 * c + k]] = 1;
      }
      for (size_t v = 0; v < M->nnodes; v++) {
        final[2] += !set[v];
        K[K_CAND] += cand[v];
        K[K_CAND_Q] += cand[v] != 0;
      }
    }
    free(set);
    free(states);
    free(cand);
    if (st) {
      mx_mesher_free(m);
      return 1;
    }
  }

  /* the final mesh: shrink pairs (approximately: the mesh after the
   * staircase), the verification's list, the writer's near faces */
  st = mx_mesher_boundary(m);
  if ((st && st != MX_EINVALID) || !m->states) {
    mx_mesher_free(m);
    return 1;
  }
  {
    const mx_mesh *M = &m->M;
    const uint8_t *S = m->states;
    final[0] = (double)M->nnodes;
    final[1] = (double)M->ncells;
    for (size_t c = 0; c < M->ncells;) {
      size_t e = c;
      while (e < M->ncells && M->leaf[e] == M->leaf[c]) e++;
      const uint32_t o = m->leaves[M->leaf[c]];
      if (T->tri_cnt[o]) {
        uint32_t vs[64];
        int k = 0;
        for (size_t d = c; d < e; d++)
          for (int j = 0; j < mx_cell_nodes[M->type[d]]; j++)
            if (S[M->conn[8 * d + j]] == MX_NODE_OUTSIDE) k = add_distinct(vs, k, 64, M->conn[8 * d + j]);
        size_t dom = 0;
        for (uint32_t j = 0; j < T->tri_cnt[o]; j++) dom += T->tri_pool[T->tri_off[o] + j] < B->tree.nt_domain;
        K[K_SHR_PAIR] += k;
        K[K_SHR_TEST] += (double)k * (double)dom;
      }
      c = e;
    }
    uint32_t levels = 0;
    for (size_t c = 0; c < M->ncells; c++)
      if (mx_surface_face(M, S, c)) {
        K[K_SURF_ELEM] += 1;
        levels |= 1u << (M->level[c] & 31);
      }
    for (size_t v = 0; v < M->nnodes; v++) K[K_SURF_NODE] += S[v] == MX_NODE_OUTSIDE;
    K[K_SURF_PROBE] = K[K_SURF_NODE] * __builtin_popcount(levels);
    uint8_t *near = calloc(M->nnodes + 1, 1);
    if (near) {
      for (size_t c = 0; c < M->ncells; c++) {
        const int meets = T->tri_cnt[m->leaves[M->leaf[c]]] > 0;
        for (int k = 0; k < mx_cell_nodes[M->type[c]]; k++)
          if (meets || S[M->conn[8 * c + k]] == MX_NODE_OUTSIDE) near[M->conn[8 * c + k]] = 1;
      }
      for (size_t c = 0; c < M->ncells; c++) {
        const int t = M->type[c];
        for (int f = 0; f < mx_cell_nfaces[t]; f++) {
          int all = 1;
          for (int k = 0; k < 4 && mx_cell_faces[t][f][k] >= 0; k++)
            all &= near[M->conn[8 * c + (size_t)mx_cell_faces[t][f][k]]];
          K[K_NEAR_FACE] += all;
        }
      }
      free(near);
    }
  }
  mx_mesher_free(m);
  return 0;
}

/* ---- main ----------------------------------------------------------------- */

typedef struct {
  double r, w, lines;   /* modelled bytes read, written; random lines */
  double smb, mb;       /* MB streamed (r + w); with 64 B per line */
  double sec, sgbs, gbs, sfrac, frac; /* GB/s and fraction of the triad, both ways */
  char note[320];
} row_out;

static void model_of(const char *phase, const double *K, double *r, double *w, double *lines) {
  for (size_t i = 0; i < NMODEL; i++) {
    const term *t = &MODEL[i];
    const int match = !strcmp(phase, "boundary") ? !strncmp(t->phase, "b.", 2) : !strcmp(phase, t->phase);
    if (!match) continue;
    *r += K[t->count] * t->r;
    *w += K[t->count] * t->w;
    *lines += K[t->count] * t->lines;
  }
}

static void print_model(void) {
  printf("mixoct performance model: bytes per item (sizes of this build)\n");
  printf("%-11s %-24s %7s %7s %5s  %s\n", "phase", "per", "read", "write", "lines", "what");
  for (size_t i = 0; i < NMODEL; i++) {
    const term *t = &MODEL[i];
    printf("%-11s %-24s %7.1f %7.1f %5.1f  %s\n", t->phase, count_name[t->count], t->r, t->w,
           t->lines, t->what);
  }
  printf("(a line is %.0f B; boundary = the b.* rows; b.rest = sort by leaf + renumbering)\n",
         LINE);
}

/* Default paths next to this program (build/bench/): mixoct one up. */
static void self_dir(char *out, size_t n) {
  char exe[4096];
  const ssize_t k = readlink("/proc/self/exe", exe, sizeof exe - 1);
  if (k <= 0) {
    snprintf(out, n, ".");
    return;
  }
  exe[k] = 0;
  char *slash = strrchr(exe, '/');
  if (slash) *slash = 0;
  snprintf(out, n, "%s", exe);
}

static void fmt_count(char *s, size_t n, double v) {
  if (v >= 1e6)
    snprintf(s, n, "%.2fM", v / 1e6);
  else if (v >= 1e4)
    snprintf(s, n, "%.0fk", v / 1e3);
  else
    snprintf(s, n, "%.0f", v);
}

int main(int argc, char **argv) {
  char dir[4096], def_mixoct[4200], def_stream[4200];
  self_dir(dir, sizeof dir);
  snprintf(def_mixoct, sizeof def_mixoct, "%s/../mixoct", dir);
  snprintf(def_stream, sizeof def_stream, "%s/mixoct-stream", dir);
  const char *mixoct = def_mixoct, *stream = def_stream;
  const char *input = "../shared/data/surfaces/cortex.off";
  const char *tmpbase = getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
  int level = 9, threads = omp_get_max_threads(), repeat = 3, stream_mb = 256;
  int use_probe = 1, use_disk = 1, use_latency = 1, json_only = 0;
  for (int i = 1; i < argc; i++) {
    const int more = i + 1 < argc;
    if (!strcmp(argv[i], "--mixoct") && more) mixoct = argv[++i];
    else if (!strcmp(argv[i], "--stream") && more) stream = argv[++i];
    else if (!strcmp(argv[i], "--input") && more) input = argv[++i];
    else if (!strcmp(argv[i], "--level") && more) level = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--threads") && more) threads = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--repeat") && more) repeat = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--stream-mb") && more) stream_mb = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--tmpdir") && more) tmpbase = argv[++i];
    else if (!strcmp(argv[i], "--no-probe")) use_probe = 0;
    else if (!strcmp(argv[i], "--no-disk")) use_disk = 0;
    else if (!strcmp(argv[i], "--no-latency")) use_latency = 0;
    else if (!strcmp(argv[i], "--json-only")) json_only = 1;
    else if (!strcmp(argv[i], "--model")) {
      print_model();
      return 0;
    } else {
      fprintf(stderr,
              "usage: mixoct-perfmodel [--mixoct PATH] [--stream PATH] [--input FILE] "
              "[--level L] [--threads T] [--repeat N] [--stream-mb MB] [--tmpdir DIR] "
              "[--no-probe] [--no-disk] [--no-latency] [--json-only] [--model]\n");
      return 2;
    }
  }
  if (level < 1 || level > 12 || threads < 1 || repeat < 1 || stream_mb < 1) {
    fprintf(stderr, "mixoct-perfmodel: bad --level, --threads, --repeat or --stream-mb\n");
    return 2;
  }
  if (access(input, R_OK) != 0) {
    fprintf(stderr, "mixoct-perfmodel: cannot read %s (--input)\n", input);
    return 2;
  }

  /* 1. the machine */
  const double load0 = loadavg();
  char cmd[12288];
  int status = 0;
  snprintf(cmd, sizeof cmd, "OMP_NUM_THREADS=%d '%s' %d", threads, stream, stream_mb);
  char *sj = run_json(cmd, &status);
  double triad[2], copy[2], sth[2];
  if (!sj || status != 0 || !jpair(sj, "triad_gbs", triad) || !jpair(sj, "copy_gbs", copy) ||
      !jpair(sj, "threads", sth)) {
    fprintf(stderr, "mixoct-perfmodel: %s failed (--stream)\n", stream);
    free(sj);
    return 3;
  }
  free(sj);
  const int k_stream = threads > 1 ? 1 : 0;
  if ((int)sth[k_stream] != threads)
    fprintf(stderr, "mixoct-perfmodel: warning: mixoct-stream ran %d threads, not %d\n",
            (int)sth[k_stream], threads);
  const double triad_t = triad[k_stream], copy_t = copy[k_stream];
  const double lat_ns = use_latency ? chase_latency_ns(256) : NAN;

  /* 2. the runs */
  char tmpl[4200];
  snprintf(tmpl, sizeof tmpl, "%s/mixoct-perfmodel-XXXXXX", tmpbase);
  if (!mkdtemp(tmpl)) {
    fprintf(stderr, "mixoct-perfmodel: cannot create a directory in %s: %s\n", tmpbase,
            strerror(errno));
    return 3;
  }
  char outpath[4300];
  snprintf(outpath, sizeof outpath, "%s/mesh.vtu", tmpl);
  double sec[NROWS][64], tot_runs[64];
  char *last = NULL;
  if (repeat > 64) repeat = 64;
  for (int r = 0; r < repeat; r++) {
    snprintf(cmd, sizeof cmd, "'%s' -i '%s' -s %d --threads %d --json --quiet -o '%s'",
             mixoct, input, level, threads, outpath);
    char *js = run_json(cmd, &status);
    if (!js || status != 0 || !jobj(js, "phases")) {
      fprintf(stderr, "mixoct-perfmodel: run failed: %s\n", cmd);
      free(js);
      rmdir(tmpl);
      return 4;
    }
    const char *ph = jobj(js, "phases");
    const char *bs = jobj(jobj(js, "boundary"), "seconds");
    double subsum = 0.0;
    for (size_t k = 0; k < NROWS; k++) {
      if (!ROWS[k].json) continue;
      sec[k][r] = jnum(ROWS[k].sub ? bs : ph, ROWS[k].json);
      if (ROWS[k].sub) subsum += sec[k][r];
    }
    for (size_t k = 0; k < NROWS; k++)
      if (!ROWS[k].json) sec[k][r] = jnum(ph, "boundary") - subsum; /* b.rest */
    tot_runs[r] = jnum(js, "total_s");
    free(last);
    last = js;
  }
  unlink(outpath);

  /* the counts: JSON first, the probe for the rest */
  double K[K_COUNT];
  memset(K, 0, sizeof K);
  const char *bj = jobj(last, "boundary");
  K[K_SPLIT_R] = jnum(last, "split_requested");
  K[K_SPLIT_B] = jnum(last, "split_balance");
  K[K_EDGE_BYTES] = jnum(last, "edge_mb") * 1048576.0;
  K[K_RAY] = jnum(last, "located");
  K[K_LEAF] = jnum(last, "leaves");
  K[K_NODE] = jnum(last, "nodes");
  K[K_ELEM] = jnum(last, "elements");
  K[K_LOCATE_B] = jnum(bj, "located");
  K[K_MOVED_C] = jnum(bj, "moved_close");
  K[K_PATTERNED] = jnum(bj, "patterned");
  K[K_SUB] = jnum(bj, "sub_elements");
  K[K_OPT] = jnum(bj, "optional");
  K[K_CENTRE] = jnum(bj, "centres");
  K[K_SHRUNK] = jnum(bj, "shrunk");
  K[K_SMOOTHED] = jnum(bj, "smoothed");
  K[K_RESTORED] = jnum(bj, "restored");
  K[K_FILE] = jnum(jfind(last, "outputs"), "bytes");
  for (int k = 0; k < K_COUNT; k++)
    if (!isfinite(K[k])) K[k] = 0.0;
  if (jnum(last, "repair_rounds") > 0)
    fprintf(stderr, "mixoct-perfmodel: warning: %.0f repair round(s): the phase times include "
            "the re-meshing and further verifications, the model counts one pass\n",
            jnum(last, "repair_rounds"));
  const double disk_gbs = use_disk && K[K_FILE] > 0 ? seq_write_gbs(tmpl, K[K_FILE]) : NAN;
  rmdir(tmpl);
  int probed = 0;
  if (use_probe) {
    double P[K_COUNT], fin[3] = {0, 0, 0};
    memset(P, 0, sizeof P);
    if (probe(input, level, threads, P, fin) == 0) {
      probed = 1;
      if (fin[0] != K[K_NODE] || fin[1] != K[K_ELEM])
        fprintf(stderr, "mixoct-perfmodel: warning: the probe's mesh (%.0f nodes, %.0f "
                "elements) is not the program's (%.0f, %.0f)\n", fin[0], fin[1], K[K_NODE],
                K[K_ELEM]);
      if (fin[2] != K[K_LOCATE_B])
        fprintf(stderr, "mixoct-perfmodel: warning: the probe located %.0f nodes, the "
                "program %.0f\n", fin[2], K[K_LOCATE_B]);
      static const int from_probe[] = {
          K_TRI, K_ROOT, K_CHILD_R, K_CHILD_B, K_TRIP_R, K_TRIP_B, K_TRIC_R, K_TRIC_B, K_EDGE_R,
          K_EDGE_B, K_RUNS, K_LEAF_E, K_POINT, K_NODE_T, K_ELEM_T, K_ELEM_TI, K_CAND, K_CAND_Q,
          K_SHR_PAIR, K_SHR_TEST, K_SURF_ELEM, K_SURF_NODE, K_SURF_PROBE, K_NEAR_FACE};
      for (size_t i = 0; i < sizeof from_probe / sizeof *from_probe; i++)
        K[from_probe[i]] = P[from_probe[i]];
    } else {
      fprintf(stderr, "mixoct-perfmodel: warning: the probe failed; its counts are 0\n");
    }
  }

  const double load1 = loadavg();

  /* 3. the rows */
  row_out R[NROWS];
  row_out tot;
  memset(&tot, 0, sizeof tot);
  for (size_t k = 0; k < NROWS; k++) {
    row_out *o = &R[k];
    memset(o, 0, sizeof *o);
    o->sec = bench_median(sec[k], repeat);
    model_of(ROWS[k].name, K, &o->r, &o->w, &o->lines);
    if (!ROWS[k].sub) { /* the phases: "boundary" holds its steps */
      tot.r += o->r;
      tot.w += o->w;
      tot.lines += o->lines;
      tot.sec += o->sec;
    }
  }
  for (size_t k = 0; k <= NROWS; k++) {
    row_out *o = k < NROWS ? &R[k] : &tot;
    o->smb = (o->r + o->w) / 1e6;
    o->mb = o->smb + o->lines * LINE / 1e6;
    o->sgbs = o->sec > 0 ? o->smb / 1e3 / o->sec : NAN;
    o->gbs = o->sec > 0 ? o->mb / 1e3 / o->sec : NAN;
    o->sfrac = o->sgbs / triad_t;
    o->frac = o->gbs / triad_t;
    /* what bounds it instead, from the counts */
    if (k == NROWS || !(o->frac < LOW_FRACTION) || !(o->sec > 0)) continue;
    size_t at = 0;
#define NOTE(...) at += (size_t)snprintf(o->note + at, sizeof o->note - at, __VA_ARGS__)
    if (isfinite(lat_ns) && o->lines * lat_ns * 1e-9 / threads > 0.05 * o->sec)
      NOTE("%s%.2fM lines x %.0f ns / %d thr = %.3f s", at ? "; " : "", o->lines / 1e6, lat_ns,
           threads, o->lines * lat_ns * 1e-9 / threads);
    const int c = ROWS[k].cpu;
    if (c >= 0 && K[c] > 0) {
      const int thr = ROWS[k].serial ? 1 : threads;
      NOTE("%s%.3gM %s, %.3g %sus each", at ? "; " : "", K[c] / 1e6, ROWS[k].cpu_name,
           o->sec * thr / K[c] * 1e6, thr > 1 ? "thread-" : "");
      if (!strcmp(ROWS[k].name, "refine") && K[K_RAY] > 0) /* the ray-parity queries too */
        NOTE(" (with %.3gM ray-parity queries)", K[K_RAY] / 1e6);
    }
    if (!strcmp(ROWS[k].name, "write") && isfinite(disk_gbs))
      NOTE("%sstorage: %.0f MB + fsync at %.2f GB/s (sequential) = %.3f s", at ? "; " : "",
           K[K_FILE] / 1e6, disk_gbs, K[K_FILE] / 1e9 / disk_gbs);
    if (!strcmp(ROWS[k].name, "b.rest"))
      NOTE("%sserial: the merge of the sort by leaf (%.2fM elements); surface index build",
           at ? "; " : "", K[K_ELEM] / 1e6);
    if (!strcmp(ROWS[k].name, "boundary")) NOTE("%ssee the b.* rows", at ? "; " : "");
#undef NOTE
  }

  /* 4. the table */
  const double total_s = bench_median(tot_runs, repeat);
  if (!json_only) {
    printf("mixoct performance model: %s -s %d, %d thread%s, median of %d run%s%s; load "
           "average %.2f before, %.2f after\n",
           input, level, threads, threads > 1 ? "s" : "", repeat, repeat > 1 ? "s" : "",
           probed ? "" : " (no probe: its counts are 0)", load0, load1);
    printf("machine: triad %.2f GB/s, copy %.2f GB/s at %d thread%s (1 thread: triad %.2f); "
           "random access %.0f ns; sequential write+fsync %.2f GB/s\n",
           triad_t, copy_t, threads, threads > 1 ? "s" : "", triad[0], lat_ns, disk_gbs);
    printf("%-11s %8s %16s %8s %7s %6s %6s %6s  %s\n", "phase", "seconds", "items", "r+w MB",
           "lines", "GB/s", "triad", "+lines", "bound instead (when +lines < 30%)");
    for (size_t k = 0; k <= NROWS; k++) {
      const row_out *o = k < NROWS ? &R[k] : &tot;
      char items[64] = "", lines[32], num[32];
      if (k < NROWS) {
        fmt_count(num, sizeof num, K[ROWS[k].item]);
        snprintf(items, sizeof items, "%s %s", num, ROWS[k].item_name);
      }
      fmt_count(lines, sizeof lines, o->lines);
      char note[400];
      if (k < NROWS)
        snprintf(note, sizeof note, "%s", o->note);
      else
        snprintf(note, sizeof note, "(the top-level phases; mixoct total_s %.3f)", total_s);
      printf("%-11s %8.3f %16s %8.1f %7s %6.2f %5.1f%% %5.1f%%  %s\n",
             k < NROWS ? ROWS[k].name : "sum", o->sec, items, o->smb, lines, o->sgbs,
             100 * o->sfrac, 100 * o->frac, note);
    }
    printf("r+w MB: bytes the model streams (read + written); lines: random accesses to hash "
           "and edge tables, +lines: the fraction with 64 B each (an upper bound); constants: "
           "mixoct-perfmodel --model\n");
  }

  /* 5. the JSON line */
  printf("{\"input\": \"%s\", \"level\": %d, \"threads\": %d, \"repeat\": %d, \"probe\": %s, "
         "\"triad_gbs\": %.3f, \"copy_gbs\": %.3f, \"triad_gbs_1\": %.3f, \"latency_ns\": %.1f, "
         "\"disk_gbs\": %.3f, \"total_s\": %.4f, \"loadavg\": [%.2f, %.2f], \"phases\": {",
         input, level, threads, repeat, probed ? "true" : "false", triad_t, copy_t, triad[0],
         isfinite(lat_ns) ? lat_ns : -1.0, isfinite(disk_gbs) ? disk_gbs : -1.0, total_s,
         isfinite(load0) ? load0 : -1.0, isfinite(load1) ? load1 : -1.0);
  for (size_t k = 0; k <= NROWS; k++) {
    const row_out *o = k < NROWS ? &R[k] : &tot;
    if (k == NROWS) printf("}, \"sum\": ");
    else printf("%s\"%s\": ", k ? ", " : "", ROWS[k].name);
    printf("{\"seconds\": %.4f, ", o->sec);
    if (k < NROWS)
      printf("\"items\": %.0f, \"item\": \"%s\", ", K[ROWS[k].item], ROWS[k].item_name);
    printf("\"read_mb\": %.2f, \"write_mb\": %.2f, \"lines\": %.0f, \"mb_stream\": %.2f, "
           "\"mb\": %.2f, \"gbs_stream\": %.3f, \"gbs\": %.3f, \"fraction_stream\": %.4f, "
           "\"fraction\": %.4f",
           o->r / 1e6, o->w / 1e6, o->lines, o->smb, o->mb, isfinite(o->sgbs) ? o->sgbs : 0.0,
           isfinite(o->gbs) ? o->gbs : 0.0, isfinite(o->sfrac) ? o->sfrac : 0.0,
           isfinite(o->frac) ? o->frac : 0.0);
    if (k < NROWS) printf(", \"note\": \"%s\"", o->note);
    printf("}");
  }
  printf(", \"counts\": {");
  for (int k = 0; k < K_COUNT; k++) printf("%s\"%s\": %.0f", k ? ", " : "", count_name[k], K[k]);
  printf("}}\n");
  free(last);
  return 0;
}
