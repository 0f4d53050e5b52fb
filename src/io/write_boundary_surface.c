/* mixoct: the boundary faces as a plain surface file for the next tool
 * (issue 30, `--boundary FILE.stl | .off | .ply`), beside the tagged VTU of
 * write_boundary.c:
 *
 *   .stl  binary STL: triangles only, single precision (the format's); a
 *         quadrilateral is cut along the diagonal through its vertex of the
 *         smallest node index (the --tets rule), facet normals from the
 *         vertices, attribute bytes 0. Vertices repeat per facet.
 *   .off  ASCII OFF: the nodes the faces use (doubles, shortest round-trip
 *         text) and the faces as polygons of 3 or 4 vertices; no tags.
 *   .ply  binary little-endian PLY 1.0: vertices x y z (double) and node
 *         (int: the index in the volume mesh), faces as lists of 3 or 4
 *         vertex indices with surface_tag and body (int).
 *
 * Every face is outward (mx_boundary_faces), so the OFF and PLY files are
 * closed, consistently oriented surfaces the mesher reads back. The bytes
 * are formatted in parallel by mx_afile_emit and do not depend on the
 * thread count. */
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "io/atomic_file.h"
#include "io/boundary_faces.h"
#include "io/bytes.h"
#include "io/mesh_view_check.h"
#include "io/text_num.h"
#include "io/write_mesh.h"
#include "soa/mesh.h"

typedef struct {
  const mx_mesh_view *m;
  const mx_boundary_nodes *N;
  int what;
} sctx;

enum { S_STL, S_OFF_POINTS, S_OFF_FACES, S_PLY_POINTS, S_PLY_FACES };

/* Face i of the triangles then quadrilaterals: its k (3 or 4) nodes, in a
 * quadrilateral's case rotated so that the smallest node index comes first
 * (its split diagonal is v[0]-v[2]). */
static int face_nodes(const mx_boundary_faces *bf, size_t i, uint32_t v[4], int rotate) {
  if (i < bf->ntri) {
    memcpy(v, bf->tri + 3 * i, 3 * sizeof *v);
    return 3;
  }
  const uint32_t *q = bf->quad + 4 * (i - bf->ntri);
  int s = 0;
  if (rotate)
    for (int j = 1; j < 4; j++)
      if (q[j] < q[s]) s = j;
  for (int j = 0; j < 4; j++) v[j] = q[(s + j) & 3];
  return 4;
}

static size_t put_f32(unsigned char *out, double x) {
  const float f = (float)x;
  uint32_t u;
  memcpy(&u, &f, sizeof u);
  mx_store_le(out, u, 4);
  return 4;
}

static size_t put_f64(unsigned char *out, double x) {
  uint64_t u;
  memcpy(&u, &x, sizeof u);
  mx_store_le(out, u, 8);
  return 8;
}

/* One STL facet (50 bytes) of the triangle a b c. */
static size_t stl_facet(unsigned char *out, const double *xyz, uint32_t a, uint32_t b,
                        uint32_t c) {
  const double *p = xyz + 3 * (size_t)a, *q = xyz + 3 * (size_t)b, *r = xyz + 3 * (size_t)c;
  const double u[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const double w[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
  double n[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
  const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  for (int k = 0; k < 3; k++) n[k] = len > 0.0 ? n[k] / len : 0.0;
  size_t o = 0;
  for (int k = 0; k < 3; k++) o += put_f32(out + o, n[k]);
  const double *v[3] = {p, q, r};
  for (int j = 0; j < 3; j++)
    for (int k = 0; k < 3; k++) o += put_f32(out + o, v[j][k]);
  out[o++] = 0; /* the attribute byte count */
  out[o++] = 0;
  return o;
}

static size_t fill(const void *vctx, size_t b, size_t e, char *cout) {
  const sctx *c = vctx;
  const mx_boundary_faces *bf = c->m->bfaces;
  const uint32_t *id = c->N->newid;
  unsigned char *out = (unsigned char *)cout;
  size_t n = 0;
  for (size_t i = b; i < e; i++) {
    if (c->what == S_OFF_POINTS) {
      n += mx_put_xyz_lines(cout + n, c->m->xyz + 3 * (size_t)c->N->used[i], 0, 1);
      continue;
    }
    if (c->what == S_PLY_POINTS) {
      const double *p = c->m->xyz + 3 * (size_t)c->N->used[i];
      for (int k = 0; k < 3; k++) n += put_f64(out + n, p[k]);
      mx_store_le(out + n, c->N->used[i], 4);
      n += 4;
      continue;
    }
    uint32_t v[4];
    const int k = face_nodes(bf, i, v, c->what == S_STL);
    if (c->what == S_STL) {
      n += stl_facet(out + n, c->m->xyz, v[0], v[1], v[2]);
      if (k == 4) n += stl_facet(out + n, c->m->xyz, v[0], v[2], v[3]);
    } else if (c->what == S_OFF_FACES) {
      cout[n++] = (char)('0' + k);
      for (int j = 0; j < k; j++) {
        cout[n++] = ' ';
        n += mx_put_u64(cout + n, id[v[j]]);
      }
      cout[n++] = '\n';
    } else { /* S_PLY_FACES */
      out[n++] = (unsigned char)k;
      for (int j = 0; j < k; j++, n += 4) mx_store_le(out + n, id[v[j]], 4);
      const size_t q = i < bf->ntri ? i : i - bf->ntri;
      const int32_t *tags = i < bf->ntri ? bf->tri_tag : bf->quad_tag;
      const uint64_t src = i < bf->ntri ? bf->tri_src[q] : bf->quad_src[q];
      const int32_t tag = tags ? tags[q] : 1;
      const int32_t body = c->m->cell_body ? c->m->cell_body[src >> 3] : 1;
      mx_store_le(out + n, (uint32_t)tag, 4);
      mx_store_le(out + n + 4, (uint32_t)body, 4);
      n += 8;
    }
  }
  return n;
}

static int emit(mx_afile *f, sctx *c, int what, size_t count, size_t item_max) {
  c->what = what;
  return mx_afile_emit(f, count, item_max, fill, c);
}

static int stl(mx_afile *f, sctx *c) {
  const mx_boundary_faces *bf = c->m->bfaces;
  const uint64_t ntri = bf->ntri + 2 * (uint64_t)bf->nquad;
  if (ntri > UINT32_MAX) {
    mx_error(NULL, 0, "the boundary has %llu triangles: more than binary STL can count",
             (unsigned long long)ntri);
    return MX_EINPUT;
  }
  unsigned char head[84];
  memset(head, 0, sizeof head);
  const char *title = "mixoct boundary faces";
  memcpy(head, title, strlen(title));
  mx_store_le(head + 80, ntri, 4);
  MX_CHECK(mx_afile_write(f, head, sizeof head));
  return emit(f, c, S_STL, bf->ntri + bf->nquad, 100);
}

static int off(mx_afile *f, sctx *c) {
  const mx_boundary_faces *bf = c->m->bfaces;
  MX_CHECK(mx_afile_printf(f, "OFF\n%zu %zu 0\n", c->N->nused, bf->ntri + bf->nquad));
  MX_CHECK(emit(f, c, S_OFF_POINTS, c->N->nused, MX_XYZ_LINE_MAX));
  return emit(f, c, S_OFF_FACES, bf->ntri + bf->nquad, 2 + 4 * (MX_U64_CHARS + 1));
}

static int ply(mx_afile *f, sctx *c) {
  const mx_boundary_faces *bf = c->m->bfaces;
  MX_CHECK(mx_afile_printf(f,
                           "ply\nformat binary_little_endian 1.0\n"
                           "comment mixoct boundary faces: node is the index in the volume "
                           "mesh, surface_tag the input surface, body the part\n"
                           "element vertex %zu\nproperty double x\nproperty double y\n"
                           "property double z\nproperty int node\n"
                           "element face %zu\nproperty list uchar int vertex_indices\n"
                           "property int surface_tag\nproperty int body\nend_header\n",
                           c->N->nused, bf->ntri + bf->nquad));
  MX_CHECK(emit(f, c, S_PLY_POINTS, c->N->nused, 28));
  return emit(f, c, S_PLY_FACES, bf->ntri + bf->nquad, 1 + 16 + 8);
}

int mx_write_boundary_surface(const char *path, const mx_mesh_view *m) {
  MX_CHECK(mx_mesh_view_check(path, m));
  const char *dot = path ? strrchr(path, '.') : NULL;
  int (*body)(mx_afile *, sctx *) = NULL;
  if (dot && !strcasecmp(dot, ".stl")) body = stl;
  else if (dot && !strcasecmp(dot, ".off")) body = off;
  else if (dot && !strcasecmp(dot, ".ply")) body = ply;
  if (!m->bfaces || !body) {
    mx_error(path, 0, "internal error: no boundary faces or no surface format");
    return MX_EINTERNAL;
  }
  mx_boundary_nodes N;
  MX_CHECK(mx_boundary_nodes_number(m->bfaces, m->nnodes, &N));
  sctx c = {m, &N, 0};
  mx_afile f;
  int st = mx_afile_open(&f, path);
  if (!st) st = mx_afile_finish(&f, body(&f, &c));
  mx_boundary_nodes_free(&N);
  return st;
}
