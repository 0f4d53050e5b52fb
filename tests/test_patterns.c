/* Transition patterns: every legal configuration, rotated into place, fills
 * the unit cube exactly; face patterns agree between the two octants of a
 * face; the table's counts and quality meet the targets. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "base/common.h"
#include "geom/quality.h"
#include "patterns/lattice.h"
#include "patterns/lookup.h"
#include "soa/mesh.h"

typedef struct {
  int n;
  int v[4]; /* global point ids, cyclic order */
} poly;

static uint32_t poly_key(const poly *p) {
  int s[4] = {p->v[0], p->v[1], p->v[2], p->n == 4 ? p->v[3] : 99};
  for (int i = 0; i < 4; i++)
    for (int j = i + 1; j < 4; j++)
      if (s[j] < s[i]) {
        int t = s[i];
        s[i] = s[j];
        s[j] = t;
      }
  return (uint32_t)(s[0] | s[1] << 7 | s[2] << 14 | s[3] << 21);
}

/* Same cycle (1) or reversed cycle (-1) or neither (0). */
static int same_cycle(const poly *a, const poly *b) {
  if (a->n != b->n) return 0;
  int k0 = -1;
  for (int k = 0; k < b->n; k++)
    if (b->v[k] == a->v[0]) k0 = k;
  if (k0 < 0) return 0;
  int fwd = 1, rev = 1;
  for (int k = 0; k < a->n; k++) {
    fwd &= a->v[k] == b->v[(k0 + k) % a->n];
    rev &= a->v[k] == b->v[(k0 - k + a->n) % a->n];
  }
  return fwd ? 1 : rev ? -1 : 0;
}

/* Check one configuration; returns the number of defects. */
static int check_config(uint32_t config) {
  const mx_pattern_ref r = mx_pattern_lookup(config);
  if (r.cls == 0xffff) return 1;
  const mx_pattern_class *pc = &mx_pattern_classes[r.cls];
  uint32_t mask = 0xffu | (config << 8);
  if (mx_pattern_has_centre(r.cls)) mask |= 1u << MX_LAT_CENTRE;
  /* the class's canonical mask rotated is this mask */
  if (mx_rotate_mask(r.rot, pc->mask) != mask) return 100;
  int defects = 0;
  double vol = 0.0;
  uint32_t used = 0;
  poly faces[400];
  int nf = 0;
  for (int k = 0; k < pc->count; k++) {
    const mx_pattern_elem *e = &mx_pattern_elems[pc->first + k];
    const int nv = mx_cell_nodes[e->type];
    int v[8];
    double x[8][3];
    for (int j = 0; j < nv; j++) {
      v[j] = mx_rot_perm[r.rot][e->v[j]];
      if (!((mask >> v[j]) & 1)) defects++; /* a vertex that is not a node */
      used |= 1u << v[j];
      for (int a = 0; a < 3; a++) x[j][a] = 0.5 * mx_lat_xyz[v[j]][a];
    }
    const double ev = mx_element_volume(e->type, x);
    if (!(ev > 0.0)) defects++;
    if (!(mx_jens(e->type, x) > 0.0)) defects++;
    vol += ev;
    for (int f = 0; f < mx_cell_nfaces[e->type]; f++) {
      poly p;
      p.n = mx_cell_faces[e->type][f][3] < 0 ? 3 : 4;
      for (int j = 0; j < p.n; j++) p.v[j] = v[mx_cell_faces[e->type][f][j]];
      faces[nf++] = p;
    }
  }
  if (used != mask) defects++; /* every node is used */
  if (fabs(vol - 1.0) > 1e-12) defects++;
  /* Interior faces: exactly two, opposite; the others form the boundary. */
  int boundary[400], nb = 0;
  for (int i = 0; i < nf; i++) {
    int twins = 0, j_twin = -1;
    for (int j = 0; j < nf; j++)
      if (j != i && poly_key(&faces[j]) == poly_key(&faces[i])) {
        twins++;
        j_twin = j;
      }
    if (twins == 0) boundary[nb++] = i;
    else if (twins > 1 || same_cycle(&faces[i], &faces[j_twin]) != -1) defects++;
  }
  /* Boundary faces equal the face patterns, same orientation (outward). */
  int npat = 0;
  for (int f = 0; f < 6; f++) {
    uint8_t pp[8][4];
    const int np = mx_face_pattern(f, mask, pp);
    for (int k = 0; k < np; k++) {
      poly p;
      p.n = pp[k][3] == 255 ? 3 : 4;
      for (int j = 0; j < p.n; j++) p.v[j] = pp[k][j];
      npat++;
      int found = 0;
      for (int b = 0; b < nb; b++) found += same_cycle(&faces[boundary[b]], &p) == 1;
      if (found != 1) defects++;
    }
  }
  if (npat != nb) defects++;
  return defects;
}

/* The two octants of a face see the same subdivision: octant A at x in [0,2],
 * octant B at x in [2,4] (likewise along y and z), for every configuration of
 * the shared face. Points are compared by global coordinates. */
static int check_face_agreement(void) {
  int defects = 0;
  for (int a = 0; a < 3; a++)
    for (int cfg = 0; cfg < 32; cfg++) {
      const int split = cfg & 15, centre = cfg >> 4;
      if (centre && split != 15) continue;
      /* the +a face of A is face 2a+1; of B, face 2a (the -a face) */
      uint32_t ma = 0xff, mb = 0xff;
      const int u = (a + 1) % 3, w = (a + 2) % 3;
      /* the face's edges: along u at w in {0,2}, along w at u in {0,2} */
      int k = 0;
      for (int ax = 0; ax < 2; ax++)
        for (int s = 0; s <= 2; s += 2, k++) {
          if (!((split >> k) & 1)) continue;
          int pa[3], pb[3];
          const int along = ax ? w : u, other = ax ? u : w;
          pa[a] = 2; pb[a] = 0;
          pa[along] = pb[along] = 1;
          pa[other] = pb[other] = s;
          ma |= 1u << mx_lat_index(pa[0], pa[1], pa[2]);
          mb |= 1u << mx_lat_index(pb[0], pb[1], pb[2]);
        }
      if (centre) {
        ma |= 1u << (20 + 2 * a + 1);
        mb |= 1u << (20 + 2 * a);
      }
      uint8_t pa[8][4], pb[8][4];
      const int na = mx_face_pattern(2 * a + 1, ma, pa);
      const int nb = mx_face_pattern(2 * a, mb, pb);
      if (na != nb) {
        defects++;
        continue;
      }
      for (int i = 0; i < na; i++) {
        poly P, Q;
        P.n = pa[i][3] == 255 ? 3 : 4;
        for (int j = 0; j < P.n; j++) {
          const uint8_t *c = mx_lat_xyz[pa[i][j]];
          P.v[j] = c[0] + 5 * c[1] + 25 * c[2]; /* A's frame is global */
        }
        int found = 0;
        for (int i2 = 0; i2 < nb; i2++) {
          Q.n = pb[i2][3] == 255 ? 3 : 4;
          for (int j = 0; j < Q.n; j++) {
            int c[3] = {mx_lat_xyz[pb[i2][j]][0], mx_lat_xyz[pb[i2][j]][1],
                        mx_lat_xyz[pb[i2][j]][2]};
            c[a] += 2; /* B is shifted by one octant along a */
            Q.v[j] = c[0] + 5 * c[1] + 25 * c[2];
          }
          found += same_cycle(&P, &Q) == -1; /* same face, opposite sides */
        }
        if (found != 1) defects++;
      }
    }
  return defects;
}

int main(void) {
  CHECK(mx_patterns_init() == MX_OK);
  mx_lattice_init();
  /* The rotations: 24 distinct permutations fixing the centre. */
  for (int r = 0; r < 24; r++) {
    CHECK(mx_rot_perm[r][MX_LAT_CENTRE] == MX_LAT_CENTRE);
    for (int q = 0; q < r; q++) CHECK(memcmp(mx_rot_perm[r], mx_rot_perm[q], 27) != 0);
    for (int i = 0; i < 27; i++) CHECK(mx_rot_perm[mx_rot_inv[r]][mx_rot_perm[r][i]] == i);
  }
  int configs = 0, bad = 0;
  for (uint32_t c = 0; c < (1u << MX_CONFIG_BITS); c++) {
    if (!mx_config_valid(c)) {
      CHECK(mx_pattern_lookup(c).cls == 0xffff);
      continue;
    }
    configs++;
    int d = check_config(c);
    if (d && bad < 5) fprintf(stderr, "configuration %05x: %d defects\n", c, d);
    bad += d != 0;
  }
  printf("%d configurations, %d with defects\n", configs, bad);
  CHECK(configs == 6210);
  CHECK(bad == 0);
  CHECK(mx_pattern_nclasses == 326);
  CHECK(check_face_agreement() == 0);
  /* Targets: body centre in at most 65 classes, worst J_ENS >= 0.172. */
  int centre = 0;
  double worst = INFINITY;
  for (int k = 0; k < mx_pattern_nclasses; k++) {
    centre += mx_pattern_has_centre(k);
    for (int e = 0; e < mx_pattern_classes[k].count; e++)
      if (mx_pattern_elem_jens[mx_pattern_classes[k].first + e] < worst)
        worst = mx_pattern_elem_jens[mx_pattern_classes[k].first + e];
  }
  printf("centre classes %d, worst J_ENS %.4f\n", centre, worst);
  CHECK(centre <= 65);
  CHECK(worst >= 0.172);
  return TEST_DONE();
}
