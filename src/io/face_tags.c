/* The tagged faces of a mesh being read (declared in io/face_tags.h). */
#include "io/face_tags.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"

/* Room for n more tagged faces in out (capacity *cap, at least doubled; n
 * already checked against the file size). */
int mx_rd_face_room(rd *r, mx_mesh_data *out, size_t *cap, size_t n) {
  if (n <= *cap - out->nfaces) return MX_OK;
  const size_t most = UINT32_MAX / 6;
  if (n > most - out->nfaces)
    return mx_rd_fail(r, NULL, "more than %zu boundary faces", most);
  size_t nc = *cap ? 2 * *cap : 1024;
  if (nc < out->nfaces + n) nc = out->nfaces + n;
  if (nc > most) nc = most;
  uint8_t *nn = mx_realloc(out->face_nn, nc);
  if (!nn) return MX_ENOMEM;
  out->face_nn = nn;
  uint32_t *cn = mx_realloc(out->face_conn, 4 * nc * sizeof *cn);
  if (!cn) return MX_ENOMEM;
  out->face_conn = cn;
  int32_t *tg = mx_realloc(out->face_tag, nc * sizeof *tg);
  if (!tg) return MX_ENOMEM;
  out->face_tag = tg;
  *cap = nc;
  return MX_OK;
}

/* Appends a face (room made by mx_rd_face_room). */
void mx_rd_add_face(mx_mesh_data *out, int nn, const uint32_t v[4],
                    int32_t tag) {
  const size_t f = out->nfaces++;
  out->face_nn[f] = (uint8_t)nn;
  for (int j = 0; j < 4; j++) out->face_conn[4 * f + (size_t)j] = j < nn ? v[j] : 0;
  out->face_tag[f] = tag;
}

/* A tag read as a 64-bit integer must fit an int32. */
int mx_rd_tag_range(rd *r, const char *at, int64_t v, const char *what) {
  if (v < INT32_MIN || v > INT32_MAX)
    return mx_rd_fail(r, at, "%s %lld is out of range (32-bit integers)", what,
                      (long long)v);
  return MX_OK;
}
