/* What the mesh readers share (one reader per file: read_vtk.c, read_vtu.c,
 * read_pvtu.c, read_msh.c, read_medit.c, read_m3d.c, read_getfem.c; the
 * dispatcher in read_mesh.c): the state of one file being read (rd), its
 * messages and temporaries, raw value arrays (binary in place, or parsed
 * from ASCII), blank-separated text tokens, and each reader's entry point.
 * Defined in src/io/mesh_reader.c; the small helpers are inline here. */
#ifndef MX_MESH_READER_H
#define MX_MESH_READER_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <strings.h>

#include "io/read_mesh.h"

#define HOST_LE (__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__)

typedef enum {
  T_I8, T_U8, T_I16, T_U16, T_I32, T_U32, T_I64, T_U64, T_F32, T_F64, T_NONE
} vtype;
static const int vsize[T_NONE + 1] = {1, 1, 2, 2, 4, 4, 8, 8, 4, 8, 0};

/* n values of type t, stored from data on (byte-swapped when swap). */
typedef struct {
  const unsigned char *data;
  size_t n;
  vtype t;
  int swap;
  const char *text; /* parsed from ASCII starting here (for messages) */
} rawarr;

enum { MAX_TMP = 32, MSG = 512 };

/* What a piece of a .pvtu gives besides its mesh (see mx_rd_pvtu). */
typedef struct {
  uint64_t *gid;               /* its GlobalNodeId (nnodes values), or NULL */
  uint64_t point_sig, cell_sig; /* its point and cell arrays (names, types) */
} piece_info;

typedef struct {
  const char *path, *buf, *end; /* the file, NUL-terminated at end */
  const char *bin_from;         /* binary data starts here (or NULL) */
  void *tmp[MAX_TMP];
  int ntmp;
  int planar; /* VTK triangles and quadrilaterals accepted (mx_read_mesh_planar) */
  piece_info *piece; /* reading a piece of a .pvtu: a VTU file only */
  int merged;        /* a .pvtu was read: its pieces' wedges are ours already */
  /* A VTK file with volume cells and faces (io/vtk_cells.c): the file's
   * cell of each volume cell and each face, and its number of cells; NULL
   * when every cell of the file is a volume cell. */
  const uint32_t *cell_from, *face_from;
  size_t file_cells;
} rd;

/* Prints the message with the line of `at` in a text part, its byte offset
 * in a binary part, nothing when at is NULL; returns MX_EINPUT. */
int mx_rd_fail(const rd *r, const char *at, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* ---- raw values ---------------------------------------------------------- */

static inline uint64_t load_bits(const unsigned char *p, int size, int swap) {
  switch (size) {
    case 1:
      return p[0];
    case 2: {
      uint16_t v;
      memcpy(&v, p, 2);
      return swap ? __builtin_bswap16(v) : v;
    }
    case 4: {
      uint32_t v;
      memcpy(&v, p, 4);
      return swap ? __builtin_bswap32(v) : v;
    }
    default: {
      uint64_t v;
      memcpy(&v, p, 8);
      return swap ? __builtin_bswap64(v) : v;
    }
  }
}

/* Element i of an integer array; -1 for values beyond INT64_MAX. */
static inline int64_t raw_int(const rawarr *a, size_t i) {
  uint64_t b = load_bits(a->data + i * (size_t)vsize[a->t], vsize[a->t],
                         a->swap);
  switch (a->t) {
    case T_I8: return (int8_t)b;
    case T_I16: return (int16_t)b;
    case T_I32: return (int32_t)b;
    case T_I64: return (int64_t)b;
    case T_U64: return b > (uint64_t)INT64_MAX ? -1 : (int64_t)b;
    default: return (int64_t)b; /* U8, U16, U32 */
  }
}

static inline double raw_double(const rawarr *a, size_t i) {
  if (a->t == T_F32) {
    uint32_t b = (uint32_t)load_bits(a->data + 4 * i, 4, a->swap);
    float f;
    memcpy(&f, &b, 4);
    return f;
  }
  uint64_t b = load_bits(a->data + 8 * i, 8, a->swap);
  double d;
  memcpy(&d, &b, 8);
  return d;
}

static inline int is_float(vtype t) { return t == T_F32 || t == T_F64; }

/* ---- text ---------------------------------------------------------------- */

static inline int is_ws(char c) {
  return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' ||
         c == '\v';
}

static inline const char *skip_ws(const char *p, const char *end) {
  while (p < end && is_ws(*p)) p++;
  return p;
}

static inline size_t tok_len(const char *p, const char *end) {
  const char *q = p;
  while (q < end && *q && !is_ws(*q)) q++;
  return (size_t)(q - p);
}

static inline int tok_eq(const char *t, size_t n, const char *kw) {
  return strlen(kw) == n && strncasecmp(t, kw, n) == 0;
}

static inline int shown(size_t n) { return n > 40 ? 40 : (int)n; }

/* A temporary freed when the file is done (at most MAX_TMP per file):
 * MX_OK, MX_ENOMEM, or MX_EINTERNAL (too many). */
int mx_rd_alloc(rd *r, size_t bytes, void **out);

/* Where element i of a lies in the file, for messages: in place, or found
 * again by counting the tokens of the ASCII text it was parsed from. */
const char *mx_rd_arr_at(const rd *r, const rawarr *a, size_t i);

/* Parses n values (integers, or finite doubles when floats) from *pp into a
 * temporary, stopping at end, at a NUL or at `stop`, and describes them as
 * a host-order array. */
int mx_rd_ascii_array(rd *r, const char **pp, char stop, size_t n, int floats,
                      rawarr *out, const char *what);

/* Past blank lines and '%' comment lines. */
const char *mx_rd_skip_percent_lines(const rd *r, const char *p);

/* ---- the readers, one file each ------------------------------------------ */

/* A mesh file (src/io/read_mesh.c); with piece set, a piece of a .pvtu: a
 * VTU file only, its GlobalNodeId and array signatures in *piece
 * (piece->gid freed on failure). */
int mx_rd_file(const char *path, int planar, piece_info *piece, mx_mesh_data *out);
/* Legacy VTK (src/io/read_vtk.c). */
int mx_rd_vtk_legacy(rd *r, mx_mesh_data *out);
/* VTK XML UnstructuredGrid (src/io/read_vtu.c). */
int mx_rd_vtu(rd *r, mx_mesh_data *out);
/* A .pvtu master and its pieces, from its <VTKFile> at p (src/io/read_pvtu.c). */
int mx_rd_pvtu(rd *r, const char *p, mx_mesh_data *out);
/* Gmsh MSH 4.1 from its $MeshFormat at p (src/io/read_msh.c). */
int mx_rd_msh(rd *r, const char *p, mx_mesh_data *out);
/* Medit .mesh from p and .meshb, and the tests that recognise them
 * (src/io/read_medit.c). */
int mx_rd_medit_ascii(rd *r, const char *p, mx_mesh_data *out);
int mx_rd_meshb(rd *r, mx_mesh_data *out);
int mx_rd_is_medit_ascii(rd *r, const char *p);
int mx_rd_is_meshb(const rd *r);
/* The published mesher's M3D and MVM files (src/io/read_m3d.c) and GetFEM
 * files (src/io/read_getfem.c), from p. */
int mx_rd_m3d(rd *r, const char *p, mx_mesh_data *out);
int mx_rd_mvm(rd *r, const char *p, mx_mesh_data *out);
int mx_rd_getfem(rd *r, const char *p, mx_mesh_data *out);
/* An OFF file as a 2D mesh (src/io/read_off_plane.c), and whether the
 * first content token of the file at path (after blanks and '#' comment
 * lines, in its first bytes) is an OFF keyword. */
int mx_rd_off_plane(const char *path, mx_mesh_data *out);
int mx_rd_is_off(const char *path);

#endif
