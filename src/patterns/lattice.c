#include "patterns/lattice.h"

#include <string.h>

const uint8_t mx_lat_xyz[27][3] = {
    /* corners */
    {0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {2, 2, 0},
    {0, 0, 2}, {2, 0, 2}, {0, 2, 2}, {2, 2, 2},
    /* x edges: j = y/2 + 2 z/2 */
    {1, 0, 0}, {1, 2, 0}, {1, 0, 2}, {1, 2, 2},
    /* y edges: j = z/2 + 2 x/2 */
    {0, 1, 0}, {0, 1, 2}, {2, 1, 0}, {2, 1, 2},
    /* z edges: j = x/2 + 2 y/2 */
    {0, 0, 1}, {2, 0, 1}, {0, 2, 1}, {2, 2, 1},
    /* faces -x +x -y +y -z +z */
    {0, 1, 1}, {2, 1, 1}, {1, 0, 1}, {1, 2, 1}, {1, 1, 0}, {1, 1, 2},
    /* centre */
    {1, 1, 1}};

uint8_t mx_rot_perm[24][27];
uint8_t mx_rot_inv[24];
static uint8_t index_of[27];
static volatile int ready = 0;

int mx_lat_index(int x, int y, int z) { return index_of[x + 3 * y + 9 * z]; }

void mx_lattice_init(void) {
  if (ready) return;
  uint8_t idx[27];
  for (int i = 0; i < 27; i++)
    idx[mx_lat_xyz[i][0] + 3 * mx_lat_xyz[i][1] + 9 * mx_lat_xyz[i][2]] = (uint8_t)i;
  memcpy(index_of, idx, sizeof idx);
  /* Signed permutation matrices with determinant +1. */
  static const int perms[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1},
                                  {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
  int r = 0;
  uint8_t perm[24][27];
  for (int p = 0; p < 6; p++)
    for (int s = 0; s < 8; s++) {
      const int even = p < 3;
      const int nneg = __builtin_popcount((unsigned)s);
      if ((even ? 0 : 1) != (nneg & 1)) continue; /* det = sign(p) * (-1)^nneg */
      for (int i = 0; i < 27; i++) {
        int q[3];
        for (int a = 0; a < 3; a++) {
          int v = mx_lat_xyz[i][perms[p][a]] - 1;
          if ((s >> a) & 1) v = -v;
          q[a] = v + 1;
        }
        perm[r][i] = idx[q[0] + 3 * q[1] + 9 * q[2]];
      }
      r++;
    }
  /* Put the identity first. */
  for (int k = 0; k < 24; k++) {
    int id = 1;
    for (int i = 0; i < 27; i++) id &= perm[k][i] == i;
    if (id && k) {
      uint8_t t[27];
      memcpy(t, perm[0], 27);
      memcpy(perm[0], perm[k], 27);
      memcpy(perm[k], t, 27);
    }
  }
  memcpy(mx_rot_perm, perm, sizeof perm);
  for (int a = 0; a < 24; a++)
    for (int b = 0; b < 24; b++) {
      int id = 1;
      for (int i = 0; i < 27; i++) id &= perm[b][perm[a][i]] == i;
      if (id) mx_rot_inv[a] = (uint8_t)b;
    }
  __atomic_store_n(&ready, 1, __ATOMIC_RELEASE);
}

uint32_t mx_rotate_mask(int r, uint32_t mask) {
  uint32_t out = 0;
  for (uint32_t m = mask; m; m &= m - 1) out |= 1u << mx_rot_perm[r][__builtin_ctz(m)];
  return out;
}

/* Edges (as lattice indices 8..19) of face 20+f, and its corners, in the
 * face's counter-clockwise order seen from outside. */
static void face_frame(int f, uint8_t c[4], uint8_t m[4]) {
  const int a = f / 2, s = f % 2;
  const int u = (a + 1) % 3, v = (a + 2) % 3;
  /* counter-clockwise in (u, v) is outward for the high face */
  static const int cu[4] = {0, 2, 2, 0}, cv[4] = {0, 0, 2, 2};
  int p[3];
  uint8_t cc[4], mm[4];
  for (int k = 0; k < 4; k++) {
    p[a] = 2 * s;
    p[u] = cu[k];
    p[v] = cv[k];
    cc[k] = (uint8_t)mx_lat_index(p[0], p[1], p[2]);
    p[u] = (cu[k] + cu[(k + 1) % 4]) / 2;
    p[v] = (cv[k] + cv[(k + 1) % 4]) / 2;
    mm[k] = (uint8_t)mx_lat_index(p[0], p[1], p[2]);
  }
  if (s == 1) {
    memcpy(c, cc, 4);
    memcpy(m, mm, 4);
  } else { /* reverse: corners c0 c3 c2 c1, edge k between c_k and c_k+1 */
    for (int k = 0; k < 4; k++) {
      c[k] = cc[(4 - k) % 4];
      m[k] = mm[(3 - k + 4) % 4];
    }
  }
}

int mx_config_valid(uint32_t config) {
  const uint32_t mask = config << 8;
  for (int f = 0; f < 6; f++) {
    if (!((mask >> (20 + f)) & 1)) continue;
    uint8_t c[4], m[4];
    face_frame(f, c, m);
    for (int k = 0; k < 4; k++)
      if (!((mask >> m[k]) & 1)) return 0;
  }
  return 1;
}

static void put(uint8_t poly[8][4], int *n, int a, int b, int c, int d) {
  poly[*n][0] = (uint8_t)a;
  poly[*n][1] = (uint8_t)b;
  poly[*n][2] = (uint8_t)c;
  poly[*n][3] = (uint8_t)d;
  (*n)++;
}

int mx_face_pattern(int f, uint32_t mask, uint8_t poly[8][4]) {
  uint8_t c[4], m[4];
  face_frame(f, c, m);
  int split = 0;
  for (int k = 0; k < 4; k++) split |= ((mask >> m[k]) & 1) << k;
  const int centre = (mask >> (20 + f)) & 1;
  const int ns = __builtin_popcount((unsigned)split);
  int n = 0;
#define C(k) c[(k) & 3]
#define M(k) m[(k) & 3]
  if (ns == 0) {
    put(poly, &n, c[0], c[1], c[2], c[3]);
  } else if (ns == 1) {
    const int i = __builtin_ctz((unsigned)split);
    put(poly, &n, M(i), C(i + 1), C(i + 2), 255);
    put(poly, &n, M(i), C(i + 2), C(i + 3), 255);
    put(poly, &n, M(i), C(i + 3), C(i), 255);
  } else if (ns == 2 && (split == 5 || split == 10)) {
    const int i = split == 5 ? 0 : 1;
    put(poly, &n, C(i), M(i), M(i + 2), C(i + 3));
    put(poly, &n, M(i), C(i + 1), C(i + 2), M(i + 2));
  } else if (ns == 2) {
    int i = 0; /* split edges i and i+1 */
    while (!(((split >> i) & 1) && ((split >> ((i + 1) & 3)) & 1))) i++;
    put(poly, &n, C(i), M(i), C(i + 3), 255);
    put(poly, &n, M(i), C(i + 1), M(i + 1), 255);
    put(poly, &n, M(i), M(i + 1), C(i + 3), 255);
    put(poly, &n, M(i + 1), C(i + 2), C(i + 3), 255);
  } else if (ns == 3) {
    const int j = __builtin_ctz((unsigned)(~split & 15)); /* the unsplit edge */
    put(poly, &n, C(j), C(j + 1), M(j + 1), M(j + 3));
    put(poly, &n, M(j + 1), C(j + 2), M(j + 2), 255);
    put(poly, &n, M(j + 2), C(j + 3), M(j + 3), 255);
    put(poly, &n, M(j + 1), M(j + 2), M(j + 3), 255);
  } else if (!centre) {
    put(poly, &n, m[0], m[1], m[2], m[3]);
    for (int k = 0; k < 4; k++) put(poly, &n, C(k), M(k), M(k + 3), 255);
  } else {
    const int fc = 20 + f;
    for (int k = 0; k < 4; k++) put(poly, &n, C(k), M(k), fc, M(k + 3));
  }
#undef C
#undef M
  return n;
}
