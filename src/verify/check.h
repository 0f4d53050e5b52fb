/* An independent mesh checker: it looks only at a plain mesh (nodes, cells
 * in VTK order) and, optionally, at the input surface -- never at the
 * octree that produced the mesh.
 *
 * Definitions (the counters marked * are defects):
 *  empty*              1 when the mesh has no element or no node, else 0;
 *  invalid*            elements whose J_ENS (geom/quality.h) is <= 0 or
 *                      not a number (inverted, or exactly flat);
 *  degenerate*         elements with 0 < J_ENS < degenerate_below (1e-6 by
 *                      default: nodes (nearly) collinear or coplanar); an
 *                      element is counted in one of invalid / degenerate;
 *  jens_min/mean       over all elements (NAN without elements);
 *  faces are matched by their sorted node ids, triangles and quads apart:
 *  faces_interior      faces used by exactly two elements;
 *  faces_boundary      faces used by exactly one element;
 *  faces_overshared*   faces used by three or more elements (counted once);
 *  faces_misoriented*  interior faces whose two elements do not see them
 *                      with opposite cyclic orders (same orientation, or a
 *                      different cycle through the same nodes);
 *  quad_vs_triangles*  boundary quads a-b-c-d such that both triangles of one
 *                      diagonal (a-b-c + a-c-d, or a-b-d + b-c-d) are also
 *                      boundary faces;
 *  nonmanifold_edges   distinct edges used by 4, 6... boundary faces: two
 *                      parts of the domain touching along an edge (closed
 *                      and conforming, reported, not a defect);
 *  open_boundary_edges* distinct edges of boundary faces that are used an odd
 *                      number of times (the boundary is not closed there);
 *  hanging_nodes*      used nodes lying exactly (bit-equal coordinates) at
 *                      the midpoint 0.5*(a+b) of an edge of an element they
 *                      are not a vertex of, or at the midpoint of a diagonal
 *                      of a quad face they are not a vertex of (its centre
 *                      when the quad is a parallelogram); each node counted
 *                      once;
 *  geometric_hanging_nodes* the other nodes that lie, within hang_tol
 *                      (1e-9) times the element's size (the largest extent
 *                      of its bounding box), on a face (quads: the four
 *                      triangles from its edges to its centroid, as in
 *                      mx_element_volume), on an edge or at a vertex of an
 *                      element they are not a node of; nodes at exactly the
 *                      same point as a vertex are duplicates (below), not
 *                      this. Compared: the nodes of faces used by one
 *                      element, with the elements that have such a face --
 *                      a node all of whose faces are matched is surrounded
 *                      by its own elements, and an element whose faces are
 *                      all matched is surrounded by its neighbours, so a
 *                      node lying on it elsewhere would mean overlapping
 *                      elements, which this checker does not look for.
 *                      Found through a multi-level grid of the elements'
 *                      bounding boxes (each element in the cells of the
 *                      level whose cells are at least its size: O(n)
 *                      lookups);
 *  unused_nodes*       nodes no element refers to;
 *  duplicate_nodes*    nodes whose coordinates equal those of another node
 *                      (k equal nodes count k - 1);
 *  volume              sum of the signed mx_element_volume;
 *  surface_volume      |enclosed volume| of the surface (divergence theorem,
 *                      signed tetrahedra from the centre of its bounding box,
 *                      which for a closed surface equals the sum from the
 *                      origin but loses less to cancellation), NAN without;
 *  surface_open_edges  edges of the surface not used by exactly two of its
 *                      triangles (0: closed);
 *  volume_error        (volume - surface_volume) / surface_volume, or NAN;
 *  volume_off*         with a closed surface: 1 when |volume_error| >
 *                      volume_tol (see mx_check_options) or is not a number;
 *  boundary_max_dist   the largest distance from a node of a boundary face
 *                      to the nearest surface triangle, over the diagonal of
 *                      the surface's bounding box; NAN without surface;
 *  boundary_off_surface* with a closed surface: the boundary nodes whose
 *                      distance is more than boundary_tol (1e-6) times the
 *                      diagonal. With an open surface (a hole) both
 *                      measures are reported but count as no defect.
 *  with a closed surface, the distance between the mesh's skin (its faces
 *  used by one element, and with cell labels its interface faces; quads as
 *  the triangles a-b-c and a-c-d) and the surface (every triangle), both
 *  ways, sampled (verify/check_distance.c): each triangle of one side on a
 *  sub-grid of k = ceil(longest edge / spacing) steps, 2 <= k <= kmax: the
 *  points (i P1 + j P2 + (k-i-j) P0) / k (its vertices; its edge midpoints
 *  when k is even) and the centroids of its k^2 small triangles (its own
 *  centroid one of the two kinds), each sample's distance to the nearest
 *  triangle of the other side. On the mesh side the spacing is the
 *  surface's diagonal / 1000 (mesh_sample_spacing), kmax 8 (109 samples a
 *  triangle at most); on the surface side the median of the skin faces'
 *  longest sides (surface_sample_spacing), kmax 50 (3826 samples):
 *  mesh_to_surface_max    the largest sample's distance (the mesh's nodes
 *                      among the samples: at least boundary_max_dist times
 *                      the diagonal);
 *  mesh_to_surface_mean   the mean over the skin's area: each small
 *                      triangle's mean taken as 1/12 of each of its
 *                      vertices' distances plus 3/4 of its centroid's
 *                      (exact for a distance linear, even quadratic, on it);
 *  surface_to_mesh_max, surface_to_mesh_mean  the same from the surface's
 *                      triangles to the skin;
 *  surface_diagonal    the diagonal of the surface's bounding box;
 *  mesh_to_surface_samples, surface_to_mesh_samples  the samples (a point
 *                      shared by triangles counted for each);
 *  all absolute (over surface_diagonal: relative), NAN without a closed
 *  surface; indicative, no defect (the max of the two maxima is the
 *  Hausdorff distance between the sampled skin and surface);
 Cell labels (several materials: mx_mesh_data.cell_tag), when the mesh has
 * them (check_labels.c, check_regions.c):
 *  interface_faces     faces used by two elements of different labels;
 *  labels_open*        labels whose boundary (their faces used once, or
 *                      shared with another label) has an edge used an odd
 *                      number of times;
 * and with a closed surface (its shells nested: region d = inside d of
 * them, the nesting depth, from an index with every shell turned outward):
 *  labels_off*         labels whose volume is off their region's beyond
 *                      volume_tol (a label's region: the one most of its
 *                      elements lie in);
 *  interface_max_dist  the largest distance from a node of an interface face
 *                      to the nearest surface triangle, over the diagonal
 *                      (as boundary_max_dist); NAN without interface;
 *  interface_off_surface* the interface nodes farther than boundary_tol
 *                      times the diagonal;
 *  across_interface*   elements whose centroid and corners off the shells
 *                      (farther than boundary_tol times the diagonal from
 *                      every triangle) are not all in one region (each
 *                      point's region counted independently of the mesher:
 *                      geom/distance.h, mx_region_depth or mx_inside);
 *  off_label_region*   the other elements whose region is not their label's
 *                      (the labels are then no function of the regions).
 * A surface of several files (the inputs of a mesher's run, each a file,
 * touching or nested: surface->shell[t] is the file of triangle t, as
 * mx_trisoup_append numbers them; one file: today's definitions above):
 *  surface_files       the files (1 + the largest shell; 0 without surface);
 *  surface_open_edges  each file's edges apart;
 *  the regions         those of the pieces, each closed shell of each file
 *                      (its triangles connected through the file's manifold
 *                      edges): a point's region is the innermost piece
 *                      around it, keyed by (the piece's nesting depth, its
 *                      file), the first file at depth d numbered d + 1, the
 *                      others after (verify/check_pieces.c); each region
 *                      holds its pieces' volumes less their children's;
 *  surface_pieces      the pieces;
 *  surface_volume      with cell labels, the union of the pieces: the
 *                      outermost ones' volumes summed (touching pieces
 *                      share faces, no volume); without, the points of odd
 *                      nesting depth (the pieces' volumes, those at odd
 *                      depths subtracted: nested pieces are holes, as
 *                      without --materials);
 *  shared_triangles    the triangles whose three points are those of a
 *                      triangle of another file (interfaces between inputs,
 *                      not the domain's boundary: left out of the area that
 *                      sets the default volume_tol); the boundary and the
 *                      interface nodes are measured against every triangle.
 * Boundary tags (io/read_mesh.h: the tagged faces of MSH, Medit and GetFEM
 * files, the point field surface_tag of VTK files), when the mesh has them:
 *  tagged_faces        faces in the mesh's list of tagged faces;
 *  tagged_not_boundary* tagged faces that are not boundary faces (not used
 *                      by exactly one element: interior, overshared, or no
 *                      face of any element);
 *  boundary_untagged*  boundary faces that no tagged face names; counted
 *                      only when the mesh has tagged faces at all;
 *  per tag (mx_check_tags, from mx_check_mesh_tags): its name when the file
 *  gives one, its triangles and quadrilaterals, its open edges (edges used
 *  an odd number of times by the tag's faces: 0 when they close up; not a
 *  defect, an input with a hole has an open boundary) and its faces that
 *  are not boundary faces; for node tags, the nodes with each value but 0.
 *  defects = the sum of every counter marked *.
 * For each kind of defect the report lists the first MX_CHECK_LIST element
 * ids (0-based, ascending) involved -- elements with the bad J_ENS, the
 * elements using an overshared or misoriented face, the quad's element, the
 * elements of the faces along an open edge, the elements on which a
 * hanging node lies, the elements with an untagged boundary face -- and the
 * first node ids of the node defects, the first tagged faces (their index
 * in the mesh's list) that are not boundary faces; and the first
 * MX_CHECK_SHOWN geometric hanging nodes with where they lie.
 * Sums are formed in fixed chunks and lists are the smallest ids, so every
 * number is the same whatever the thread count. */
#ifndef MX_CHECK_MESH_H
#define MX_CHECK_MESH_H

#include <stddef.h>
#include <stdint.h>

#include "geom/feature_walk.h"
#include "soa/mesh_data.h"
#include "soa/trisoup.h"

enum { MX_CHECK_LIST = 20, MX_CHECK_SHOWN = 5, MX_CHECK_LABELS = 64 };

/* One label of the cells (a material): its elements and their volume. */
typedef struct {
  int32_t label;
  size_t cells;
  double volume;
  /* with a surface: the region of the surface most of the label's element
   * centroids lie in (its nesting depth, -1 unknown), what that region
   * holds, and the relative difference */
  int region;
  double region_volume, volume_error;
  /* the label's boundary (its faces used once, or shared with another
   * label): edges used an odd number of times (open: a defect) and more
   * than twice (where the label touches itself along an edge) */
  size_t open_edges, nonmanifold_edges;
  /* with a surface: its elements lying in another region than its own
   * (elements across an interface not counted) */
  size_t off_region;
} mx_check_label;


/* Kinds of defective elements (bit k of the per-element flags). */
enum {
  MX_CK_INVALID,
  MX_CK_DEGENERATE,
  MX_CK_OVERSHARED,
  MX_CK_MISORIENTED,
  MX_CK_QUAD_TRI,
  MX_CK_OPEN_EDGE,
  MX_CK_HANGING,
  MX_CK_GEOM_HANGING,
  MX_CK_ELEM_KINDS
};
/* Kinds of defective nodes. */
enum {
  MX_CK_N_UNUSED,
  MX_CK_N_DUPLICATE,
  MX_CK_N_HANGING,
  MX_CK_N_GEOM_HANGING,
  MX_CK_N_OFF_SURFACE,
  MX_CK_NODE_KINDS
};
/* Their names as in the report's counters ("invalid", "unused_nodes"...). */
extern const char *const mx_check_elem_kind_name[MX_CK_ELEM_KINDS];
extern const char *const mx_check_node_kind_name[MX_CK_NODE_KINDS];

typedef struct {
  uint32_t n;                   /* ids listed (<= MX_CHECK_LIST) */
  uint32_t id[MX_CHECK_LIST];   /* ascending */
} mx_check_ids;

/* Elements of one kind of label defect: how many, the first ids and the
 * first one's centroid. */
typedef struct {
  size_t n;
  mx_check_ids ids;
  double at[3]; /* the first element's centroid (NAN: none) */
  int region[2]; /* across: two regions met in the first element; off:
                  * its region and its label's */
} mx_check_elems_at;

/* Where a geometric hanging node lies. */
enum { MX_CK_ON_VERTEX = 1, MX_CK_ON_EDGE = 2, MX_CK_ON_FACE = 3 };
typedef struct {
  uint32_t node;
  uint32_t element; /* the smallest element it lies on */
  int on;           /* MX_CK_ON_* */
  int local;        /* vertex: local node; edge: 8 * a + b (local nodes);
                       face: local face (soa/mesh.h mx_cell_faces) */
  int nverts;       /* the vertex, edge or face: its nodes */
  uint32_t verts[4];
  double xyz[3];
} mx_check_hang;

typedef struct {
  double degenerate_below; /* J_ENS under this (and > 0): degenerate; 1e-6 */
  double hang_tol;         /* geometric hanging nodes, relative; 1e-9 */
  double volume_tol;       /* |volume_error| above: a defect; 0 (default):
                            * chosen from the mesh, max(0.05, half a layer of
                            * elements along the surface: 0.5 A h / V, with A
                            * the surface's area, h = (V / elements)^(1/3)) */
  int volume_tol_auto;     /* set by the check when it chose volume_tol */
  double boundary_tol;     /* boundary_max_dist above: a defect; 1e-6 */
} mx_check_options;

typedef struct {
  size_t nodes, elements, by_type[4]; /* by_type indexed MX_TET .. MX_HEX */
  size_t invalid;
  double jens_min, jens_mean;
  size_t faces_interior, faces_boundary, faces_overshared, faces_misoriented,
      quad_vs_triangles, open_boundary_edges, nonmanifold_edges, hanging_nodes,
      unused_nodes,
      duplicate_nodes;
  double volume;
  double surface_volume;
  double volume_error;
  double boundary_max_dist;
  size_t defects;
  /* since the geometric checks */
  size_t empty, degenerate, geometric_hanging_nodes, volume_off,
      boundary_off_surface, surface_open_edges;
  int has_surface;
  mx_check_options opt; /* the tolerances used */
  mx_check_ids elem_ids[MX_CK_ELEM_KINDS];
  mx_check_ids node_ids[MX_CK_NODE_KINDS];
  size_t nshown; /* entries of hang_at */
  mx_check_hang hang_at[MX_CHECK_SHOWN];
  /* boundary tags */
  int has_tagged_faces, has_node_tags;
  size_t tagged_faces, tagged_not_boundary, boundary_untagged;
  /* the point field boundary of the file (mixoct's VTU), one material: the
   * nodes whose flag differs from lying on a boundary face (a defect), the
   * first of them */
  int has_boundary_flags;
  size_t boundary_flags_off;
  mx_check_ids boundary_flag_ids;
  size_t tagged_interface; /* tagged faces between cells of two labels */
  /* cell labels (several materials), when the file gives them */
  size_t nlabels, labels_dropped; /* beyond MX_CHECK_LABELS */
  mx_check_label labels[MX_CHECK_LABELS];
  size_t interface_faces;  /* faces between cells of two labels */
  size_t labels_open;      /* labels whose boundary is not closed (a defect) */
  size_t labels_off;       /* labels whose volume is off their region's
                            * beyond volume_tol (a defect) */
  /* with a closed surface: interface nodes (nodes of interface faces) and
   * the elements' regions (check.h's definitions above) */
  double interface_max_dist;
  size_t interface_nodes, interface_off_surface;
  mx_check_ids interface_off_ids; /* first interface nodes off the surface */
  int has_regions;                /* the regions were looked at */
  mx_check_elems_at across_interface, off_label_region;
  /* a surface of several files (check.h's definitions above) */
  size_t surface_files, surface_pieces, shared_triangles;
  mx_check_ids untagged_ids;     /* elements with an untagged boundary face */
  mx_check_ids not_boundary_ids; /* tagged faces that are not boundary faces */
  /* with a closed surface: the skin and the surface, both ways (check.h's
   * definitions above; absolute) */
  double surface_diagonal;
  double mesh_to_surface_max, mesh_to_surface_mean;
  double surface_to_mesh_max, surface_to_mesh_mean;
  double mesh_sample_spacing, surface_sample_spacing; /* the spacings used */
  size_t mesh_to_surface_samples, surface_to_mesh_samples;
} mx_check_report;

/* One boundary tag of the mesh (check.h's definitions above). */
typedef struct {
  int32_t tag;
  const char *name; /* NULL when the file names none; in mx_check_tags */
  size_t triangles, quads, open_edges, not_boundary; /* tagged faces */
  size_t nodes;                                      /* node tags */
} mx_check_tag;

/* The tags of the tagged faces and of the node tags, each ascending. */
typedef struct {
  size_t nface_tags, nnode_tags;
  mx_check_tag *face_tags, *node_tags;
  char *names; /* where the names are kept */
} mx_check_tags;

/* The defaults above. */
void mx_check_defaults(mx_check_options *o);

/* Fills *r. Returns MX_OK, MX_EINPUT (message printed) for a mesh that
 * cannot be checked at all: a type out of range, a node index >= nnodes, a
 * coordinate that is not finite, or more than 2^32 - 2 nodes or 715 million
 * cells; MX_ENOMEM when out of memory. opt NULL: the defaults. */
int mx_check_mesh_opt(const mx_mesh_data *m, const mx_trisoup *surface,
                      const mx_check_options *opt, mx_check_report *r);
/* The same with the default options. */
int mx_check_mesh(const mx_mesh_data *m, const mx_trisoup *surface,
                  mx_check_report *r);
/* mx_check_mesh_opt, and the boundary tags one by one into *tags (zeroed
 * first; tags NULL: not collected). Free with mx_check_tags_free (also
 * after a failure). */
int mx_check_mesh_tags(const mx_mesh_data *m, const mx_trisoup *surface,
                       const mx_check_options *opt, mx_check_report *r,
                       mx_check_tags *tags);
void mx_check_tags_free(mx_check_tags *tags);

/* The geometric hanging-node search of the check alone: the nodes v with
 * node_sel[v] != 0 against the n elements of `list` (ascending ids), with
 * the same definition and tolerance as geometric_hanging_nodes above.
 * node_hit[v] (when not NULL) is set to 1 for each node found, elem_hit[c]
 * (when not NULL) becomes non-zero for each element a node lies on; *found:
 * the nodes found. Deterministic. MX_ENOMEM when out of memory. The mesher
 * does not call it: it finds its contacts with its own search
 * (kernels/contacts.h), and tests/test_contacts.c compares the two on the
 * same nodes and elements. */
int mx_check_contacts(const mx_mesh_data *m, const uint32_t *list, size_t n,
                      const uint8_t *node_sel, double tol, uint8_t *node_hit,
                      uint8_t *elem_hit, size_t *found);

/* ---- Feature distances (check_features.c; issue 29, item 5) ---------------
 *
 * How far the mesh is from given feature lines (geom/features.h: ridges as
 * polylines corner to corner, loops, corners as points; found on a surface
 * or read from a polylines file), measured against the mesh's boundary
 * edges (the distinct edges of its faces used by one element) alone:
 *  ridge_dist   the largest distance from a sample point of a line to the
 *               nearest boundary edge (point to segment). The samples of a
 *               segment p-q of a line (a loop's closing segment too): p, q
 *               and the k - 1 points p + (q - p) j / k between, k =
 *               ceil(4 |q - p| / h) with h the shorter of the boundary
 *               edges nearest to p and to q (4 samples a mesh edge), at
 *               least 4, at most 65536; NAN without lines;
 *  corner_dist  the largest distance from a corner to the nearest node of
 *               a boundary edge; NAN without corners;
 * both INFINITY when there are lines (corners) but no boundary edge. Where:
 * the sample and its line, the corner, its index and its nearest node.
 * The edges go into a BVH (geom/bvh.h, an edge a-b as the triangle a-b-b),
 * so the work is O((samples + edges) log edges), in parallel over the
 * segments; the same numbers for any thread count (the largest distance
 * kept at its first sample in line order). Not a defect here: the caller
 * decides (mixoct check --feature-tol). */
typedef struct {
  size_t lines, loops, corners; /* of the feature lines */
  double length;                /* of all lines (a loop's closing segment too) */
  size_t edges;                 /* boundary edges measured against */
  double diagonal;              /* of the box of their nodes */
  size_t samples;               /* ridge sample points (a line's points once) */
  double ridge_dist;
  double ridge_at[3];
  size_t ridge_line;
  double corner_dist;
  double corner_at[3];
  size_t corner;
  uint32_t corner_node; /* UINT32_MAX: none */
} mx_check_feature_dist;

/* Against the boundary edges edge[2 e], edge[2 e + 1] (nodes < nnodes of
 * the interleaved xyz). MX_OK, MX_ENOMEM, MX_EINPUT (message) for an edge
 * end out of range, a coordinate of an edge's node that is not finite, or
 * 2^32 - 1 edges or more. */
int mx_check_features(const mx_feature_lines *L, const double *xyz, size_t nnodes,
                      const uint32_t *edge, size_t nedges, mx_check_feature_dist *d);
/* The distinct edges of the faces of m used by exactly one element (faces
 * matched as check.h defines them: check_faces.c), each as its two nodes,
 * the smaller first, ascending; *edge allocated (mx_free). MX_OK,
 * MX_ENOMEM, MX_EINPUT (message) for a cell of a bad type or a node out of
 * range, or a mesh larger than the checker takes. */
int mx_check_boundary_edges(const mx_mesh_data *m, uint32_t **edge, size_t *nedges);
/* Both: the feature distances of mesh m. */
int mx_check_features_mesh(const mx_mesh_data *m, const mx_feature_lines *L,
                           mx_check_feature_dist *d);

#endif
