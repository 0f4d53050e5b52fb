#include "kernels/contacts.h"

#include <string.h>

#include "base/common.h"
#include "io/read_mesh.h"
#include "kernels/boundary.h"
#include "verify/check.h"
#include "soa/mesh.h"
#include "base/scan.h"

enum { CHUNK = 16384 };

/* 1 when a face of element c has surface nodes only: a face that can be on
 * the boundary (one with an inside node is not: the inside nodes off the
 * surface are interior, and those the lattice puts exactly on a flat part
 * of the surface were never moved, so the transition patterns' conformity
 * holds for them). */
int mx_surface_face(const mx_mesh_out *M, const uint8_t *states, size_t c) {
  const int t = M->type[c];
  const uint32_t *row = M->conn + 8 * c;
  uint32_t out = 0;
  for (int j = 0; j < mx_cell_nodes[t]; j++) out |= (uint32_t)(states[row[j]] == MX_NODE_OUTSIDE) << j;
  if (__builtin_popcount(out) < 3) return 0;
  for (int f = 0; f < mx_cell_nfaces[t]; f++) {
    const int8_t *fv = mx_cell_faces[t][f];
    uint32_t need = 0;
    for (int k = 0; k < 4 && fv[k] >= 0; k++) need |= 1u << fv[k];
    if ((out & need) == need) return 1;
  }
  return 0;
}

int mx_find_contacts(const mx_mesh_out *M, const uint8_t *states, uint8_t *elem_flag,
                     mx_contacts *out) {
  memset(out, 0, sizeof *out);
  out->first_node = UINT32_MAX;
  const size_t nc = M->ncells, nn = M->nnodes;
  if (elem_flag) memset(elem_flag, 0, nc);
  if (!nc || !nn || !states) return MX_OK;
  /* the elements with a surface node, in id order (chunked count + fill) */
  const size_t nchunks = (nc + CHUNK - 1) / CHUNK;
  uint64_t *cnt = mx_calloc((nchunks + 1) * sizeof *cnt);
  uint8_t *sel = mx_calloc(nn + 1), *hit = mx_calloc(nn + 1);
  if (!cnt || !sel || !hit) {
    mx_free(cnt);
    mx_free(sel);
    mx_free(hit);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t end = (k + 1) * CHUNK < nc ? (k + 1) * CHUNK : nc;
    uint64_t n = 0;
    for (size_t c = k * CHUNK; c < end; c++) {
      n += (uint64_t)mx_surface_face(M, states, c);
    }
    cnt[k] = n;
  }
  const uint64_t nl = mx_scan_u64(cnt, nchunks + 1);
  uint32_t *list = mx_alloc((nl + 1) * sizeof *list);
  if (!list) {
    mx_free(cnt);
    mx_free(sel);
    mx_free(hit);
    return MX_EINPUT;
  }
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < nchunks; k++) {
    const size_t end = (k + 1) * CHUNK < nc ? (k + 1) * CHUNK : nc;
    uint64_t at = cnt[k];
    for (size_t c = k * CHUNK; c < end; c++) {
      if (mx_surface_face(M, states, c)) list[at++] = (uint32_t)c;
    }
  }
  mx_free(cnt);
  /* the surface nodes are the ones looked for */
#pragma omp parallel for schedule(static)
  for (size_t v = 0; v < nn; v++) sel[v] = states[v] == MX_NODE_OUTSIDE;
  mx_check_options o;
  mx_check_defaults(&o);
  const mx_mesh_data md = {.nnodes = nn, .ncells = nc, .xyz = M->xyz, .type = M->type,
                           .conn = M->conn};
  uint8_t *ehit = elem_flag ? elem_flag : mx_calloc(nc + 1);
  size_t found = 0;
  int st = ehit ? mx_check_contacts(&md, list, (size_t)nl, sel, o.hang_tol, hit, ehit, &found)
                : MX_EINPUT;
  mx_free(list);
  mx_free(sel);
  if (st == MX_OK && found) {
    out->nodes = found;
    for (size_t v = 0; v < nn; v++)
      if (hit[v]) {
        out->first_node = (uint32_t)v;
        memcpy(out->first, M->xyz + 3 * v, sizeof out->first);
        break;
      }
    size_t ne = 0;
#pragma omp parallel for schedule(static) reduction(+ : ne)
    for (size_t c = 0; c < nc; c++) {
      int s = ehit[c] != 0;
      for (int j = 0; j < mx_cell_nodes[M->type[c]]; j++) s |= hit[M->conn[8 * c + j]];
      ehit[c] = (uint8_t)s;
      ne += (size_t)s;
    }
    out->elements = ne;
  }
  if (ehit != elem_flag) mx_free(ehit);
  mx_free(hit);
  return st;
}
