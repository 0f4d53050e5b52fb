/* The surface-pattern table (src/patterns/surface_table.c), checked case by
 * case on reference elements, independently of the generator:
 * - every sub-element is positive and they fill the element: volumes sum to
 *   the element's;
 * - interior faces are shared by exactly two sub-elements, with opposite
 *   orientations; the faces left over are exactly the element's faces cut
 *   by the Fig. 9 rule (quad kept, or the two triangles of the diagonal);
 * - a case keeps its element whole only when the rule splits no quad face;
 * - the kept sub-elements (an inside vertex, or the inside centre) exist,
 *   and the centre appears only where the case declares it.
 * Then the rule itself: both elements sharing a face split it alike (it
 * reads only the four states) and it is invariant under the face's
 * rotations and reflection. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "base/common.h"
#include "geom/quality.h"
#include "kernels/surface_patterns.h"
#include "patterns/surface_table.h"
#include "soa/mesh.h"

static const double ref_xyz[4][9][3] = {
    {{0}},
    {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5, 0.5, 1}},
    {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}},
    {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
};

typedef struct {
  int n;
  int v[4];     /* as listed (orientation) */
  uint32_t key; /* sorted vertex set */
} face;

static uint32_t set_key(int n, const int *v) {
  uint32_t k = 0;
  for (int i = 0; i < n; i++) k |= 1u << v[i];
  return k | (uint32_t)n << 16;
}

/* 1 if b is a's cycle reversed */
static int reversed(const face *a, const face *b) {
  if (a->n != b->n) return 0;
  for (int s = 0; s < a->n; s++) {
    int ok = 1;
    for (int k = 0; k < a->n && ok; k++) ok = a->v[k] == b->v[(s - k + 2 * a->n) % a->n];
    if (ok) return 1;
  }
  return 0;
}

static void check_case(int t, unsigned m) {
  const int nv = mx_cell_nodes[t];
  const mx_surface_case *sc =
      &mx_surface_cases[(t == MX_PYRAMID ? MX_SURFACE_BASE_PYRAMID
                         : t == MX_PRISM ? MX_SURFACE_BASE_PRISM : MX_SURFACE_BASE_HEX) + (int)m];
  CHECK(sc->type == t && sc->mask == m);
  /* the element's faces cut by the rule */
  face want[16];
  int nwant = 0, splits = 0;
  for (int f = 0; f < mx_cell_nfaces[t]; f++) {
    const int n = mx_cell_faces[t][f][3] < 0 ? 3 : 4;
    int v[4];
    for (int k = 0; k < n; k++) v[k] = mx_cell_faces[t][f][k];
    int d = 0;
    if (n == 4)
      d = mx_surface_diagonal((m >> v[0]) & 1, (m >> v[1]) & 1, (m >> v[2]) & 1, (m >> v[3]) & 1);
    if (d == 0) {
      want[nwant].n = n;
      memcpy(want[nwant].v, v, sizeof v);
      want[nwant].key = set_key(n, v);
      nwant++;
    } else {
      splits++;
      const int s = d - 1;
      const int t1[3] = {v[s], v[s + 1], v[s + 2]}, t2[3] = {v[s], v[s + 2], v[(s + 3) % 4]};
      for (int h = 0; h < 2; h++) {
        want[nwant].n = 3;
        memcpy(want[nwant].v, h ? t2 : t1, 3 * sizeof(int));
        want[nwant].key = set_key(3, h ? t2 : t1);
        nwant++;
      }
    }
  }
  if (m == 0 || m == (1u << nv) - 1 || sc->count == 0) {
    CHECK(sc->count == 0);
    if (m != 0 && m != (1u << nv) - 1) CHECK(splits == 0 || t == MX_HEX);
    if (sc->count == 0 && splits) {
      fprintf(stderr, "type %d mask %02x: whole element but %d faces split\n", t, m, splits);
      CHECK(0);
    }
    return;
  }
  double pts[9][3];
  memcpy(pts, ref_xyz[t], sizeof pts);
  for (int a = 0; a < 3; a++) {
    double c = 0.0;
    for (int k = 0; k < nv; k++) c += ref_xyz[t][k][a];
    pts[MX_SURFACE_CENTRE][a] = c / nv;
  }
  double vol = 0.0;
  face got[128];
  int ngot = 0, kept = 0, uses_centre = 0;
  for (int i = 0; i < sc->count; i++) {
    const mx_pattern_elem *e = &mx_surface_elems[sc->first + i];
    const int ne = mx_cell_nodes[e->type];
    double x[8][3];
    int inside = 0;
    for (int k = 0; k < ne; k++) {
      CHECK(e->v[k] < nv || e->v[k] == MX_SURFACE_CENTRE);
      memcpy(x[k], pts[e->v[k]], sizeof x[k]);
      if (e->v[k] == MX_SURFACE_CENTRE) {
        uses_centre = 1;
        inside |= sc->centre == 1;
      } else {
        inside |= (m >> e->v[k]) & 1;
      }
    }
    kept += inside;
    const double v = mx_element_volume(e->type, x);
    CHECK(v > 1e-12);
    CHECK(mx_jens(e->type, x) > 0.0);
    vol += v;
    for (int f = 0; f < mx_cell_nfaces[e->type]; f++) {
      const int n = mx_cell_faces[e->type][f][3] < 0 ? 3 : 4;
      face F;
      F.n = n;
      for (int k = 0; k < n; k++) F.v[k] = e->v[mx_cell_faces[e->type][f][k]];
      F.key = set_key(n, F.v);
      /* pair with an open face of the same set, else open it */
      int paired = 0;
      for (int j = 0; j < ngot && !paired; j++)
        if (got[j].key == F.key) {
          CHECK(reversed(&got[j], &F));
          got[j] = got[--ngot];
          paired = 1;
        }
      if (!paired && ngot < 128) got[ngot++] = F;
    }
  }
  CHECK(kept > 0);
  CHECK(uses_centre == (sc->centre != 0));
  double x[8][3];
  for (int k = 0; k < nv; k++) memcpy(x[k], ref_xyz[t][k], sizeof x[k]);
  const double v0 = mx_element_volume(t, x);
  if (fabs(vol - v0) > 1e-12) {
    fprintf(stderr, "type %d mask %02x: volume %.15g, element %.15g\n", t, m, vol, v0);
    CHECK(0);
  }
  /* the open faces are exactly the cut element faces, same orientation */
  CHECK(ngot == nwant);
  for (int i = 0; i < nwant; i++) {
    int found = 0;
    for (int j = 0; j < ngot && !found; j++)
      if (got[j].key == want[i].key) {
        face r = want[i];
        for (int k = 0; k < r.n; k++) r.v[k] = want[i].v[(r.n - k) % r.n];
        CHECK(reversed(&got[j], &r)); /* same cycle as the element's face */
        found = 1;
      }
    if (!found) {
      fprintf(stderr, "type %d mask %02x: element face piece missing\n", t, m);
      CHECK(0);
    }
  }
}

/* mx_release_range, which the fill uses to give back the elements it has
 * read: whole pages before `to` read zero after, the bytes of a page that
 * straddles `to` and everything after are kept, and so is the first partial
 * page (where the allocator keeps its header). */
static void check_release(size_t bytes, size_t to) {
  unsigned char *p = mx_alloc(bytes);
  CHECK(p != NULL);
  memset(p, 0xA5, bytes);
  mx_release_range(p, 0, to / 2);
  mx_release_range(p, to / 2, to); /* the second call from where the first stopped */
  const uintptr_t first = ((uintptr_t)p + 4095) & ~(uintptr_t)4095;
  const uintptr_t last = ((uintptr_t)p + to) & ~(uintptr_t)4095;
  size_t zeros = 0;
  for (size_t i = 0; i < bytes; i++) {
    const uintptr_t a = (uintptr_t)p + i;
    const int gone = a >= first && a < last;
    CHECK(p[i] == (gone ? 0 : 0xA5));
    zeros += gone;
  }
  CHECK(to < 3 * 4096 || zeros > 0);
  mx_free(p); /* the allocator's header survived */
}

int main(void) {
  check_release(100000, 70001);
  check_release(20u << 20, (13u << 20) + 123);
  check_release(5000, 4000);
  int cases = 0;
  for (int t = MX_PYRAMID; t <= MX_HEX; t++)
    for (unsigned m = 0; m < (1u << mx_cell_nodes[t]); m++, cases++) check_case(t, m);
  /* The rule: invariant under the 8 symmetries of the quad. */
  for (int s = 0; s < 16; s++) {
    const int f[4] = {s & 1, (s >> 1) & 1, (s >> 2) & 1, (s >> 3) & 1};
    const int d = mx_surface_diagonal(f[0], f[1], f[2], f[3]);
    for (int r = 0; r < 4; r++)
      for (int flip = 0; flip < 2; flip++) {
        int g[4];
        for (int k = 0; k < 4; k++) g[k] = f[flip ? (r - k + 4) % 4 : (r + k) % 4];
        const int e = mx_surface_diagonal(g[0], g[1], g[2], g[3]);
        /* vertex k of g is vertex (r +- k) of f: diagonal a-c of g is the
         * diagonal through f's vertex r */
        const int through_r = e == 0 ? 0 : (e == 1 ? (r % 2 == 0 ? 1 : 2) : (r % 2 == 0 ? 2 : 1));
        CHECK(through_r == d);
      }
    const int in = f[0] + f[1] + f[2] + f[3];
    if (in == 1) { /* the inside corner is cut off */
      const int a = f[0] ? 0 : f[1] ? 1 : f[2] ? 2 : 3;
      CHECK(d == (a % 2 == 0 ? 2 : 1));
    }
    if (in == 0 || in == 4) CHECK(d == 0);
  }
  int centre = 0, total = 0;
  for (int i = 0; i < 32 + 64 + 256; i++) {
    centre += mx_surface_cases[i].centre != 0;
    total += mx_surface_cases[i].count;
  }
  printf("surface patterns: %d cases checked, %d elements, %d cases with the centre\n", cases,
         total, centre);
  CHECK(total == mx_surface_nelems);
  return TEST_DONE();
}
