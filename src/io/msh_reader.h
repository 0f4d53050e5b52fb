/* The state of the Gmsh MSH reader, shared by its 4.1 part
 * (src/io/read_msh.c, which also reads the sections both versions have and
 * puts the cells in order) and its 2.2 part (src/io/read_msh22.c). */
#ifndef MX_MSH_READER_H
#define MX_MSH_READER_H

#include "io/mesh_reader.h"
#include "io/text_cursor.h"

enum { MSH_TYPES = 32 };
/* nodes per Gmsh element type (0: unknown) */
static const int8_t msh_type_nodes[MSH_TYPES] = {
    0, 2, 3, 4, 4, 8, 6, 5, 3, 6, 9, 10, 27, 18, 14, 1,
    8, 20, 15, 13, 9, 10, 12, 15, 15, 21, 4, 5, 6, 20, 35, 56};

static inline int mx_msh_volume_type(int64_t t) {
  switch (t) {
    case 4: return MX_TET;
    case 5: return MX_HEX;
    case 6: return MX_PRISM;
    case 7: return MX_PYRAMID;
    default: return -1;
  }
}

typedef struct {
  cur c;
  int binary, dsize;
  int v2; /* MSH 2.2 (read_msh22.c) */
  int have_nodes;
  size_t nnodes;
  uint64_t *ntag;   /* nnodes: tag of each node */
  uint64_t tmin, tmax;
  uint32_t *dense;  /* tag - tmin -> index + 1 (0: none), or NULL */
  uint64_t *sorted; /* or: tags sorted, with */
  uint32_t *sidx;   /* their indices */
  uint64_t *etag;   /* per volume element */
  int32_t *cent;    /* per volume element, its entity's tag */
  int have_entities;
  size_t nsurf, nvol;
  int64_t *surf;    /* $Entities: per surface, its tag and its face tag */
  int64_t *vol;     /* per volume, its tag and its label (cell_tag) */
  size_t fcap, ncap; /* capacities of out's faces and names */
  mx_mesh_data *out;
} msh;

/* The index of node tag t, or -1. */
static inline int64_t mx_msh_node(const msh *M, uint64_t t) {
  if (t < M->tmin || t > M->tmax || M->nnodes == 0) return -1;
  if (M->dense) return (int64_t)M->dense[t - M->tmin] - 1;
  size_t lo = 0, hi = M->nnodes;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (M->sorted[mid] < t)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < M->nnodes && M->sorted[lo] == t ? (int64_t)M->sidx[lo] : -1;
}

/* The line "$End<name>" after a section. */
int mx_msh_end(msh *M, const char *name);
/* The map from node tags to indices (M->ntag, tmin, tmax set), checking
 * that no tag appears twice. */
int mx_msh_tag_map(msh *M);
/* MSH 2.2's $Nodes and $Elements (src/io/read_msh22.c), after the section's
 * name (and, binary, its end of line). */
int mx_msh22_nodes(msh *M);
int mx_msh22_elements(msh *M);

#endif
