/* The children of one split quadrant: which of the parent's triangles each
 * meets, which lie in the domain and the regions, what level they ask for.
 * The decisions are the single-process split's (kernels/refine.c,
 * classify_children), test for test, so both octrees keep, flag and locate
 * a child the same way. */
#include "mpi/p4est_octree.h"

#include "base/common.h"
#include "geom/intersect.h"

#include <string.h>

/* Side of each child in `need` (children meeting no triangle of a surface
 * their parent meets): face-adjacent such children lie on the same side, so
 * one ray-parity query per group of them. Returns the children inside. */
static uint8_t side_of_children(const mx_locator *L, uint8_t need, const double cc[8][3],
                                uint32_t *queries) {
  uint8_t inside = 0, done = 0;
  for (int c = 0; c < 8; c++) {
    if (!((need >> c) & 1) || ((done >> c) & 1)) continue;
    const int in = mx_locate(L, cc[c]);
    (*queries)++;
    uint8_t todo = (uint8_t)(1u << c), group = 0;
    while (todo) {
      const int d = __builtin_ctz(todo);
      todo &= (uint8_t)(todo - 1);
      if ((group >> d) & 1) continue;
      group |= (uint8_t)(1u << d);
      for (int a = 0; a < 3; a++) {
        const int e = d ^ (1 << a);
        if (((need >> e) & 1) && !((group >> e) & 1)) todo |= (uint8_t)(1u << e);
      }
    }
    done |= group;
    if (in) inside |= group;
  }
  return inside;
}

void mx_pq_classify(const mx_builder *B, uint64_t key, int level, const mx_pq *d,
                    const uint32_t *tris, uint8_t *mask, mx_pq_family *f) {
  memset(f, 0, sizeof *f);
  if (!mx_pq_kept(d)) {
    /* outside: so are its children (split only by the balance) */
    for (int c = 0; c < 8; c++) f->child[c].target = (uint8_t)(level + 1);
    return;
  }
  double clo[8][3], chi[8][3], cc[8][3], ch[8][3];
  for (int c = 0; c < 8; c++) {
    mx_octant_box(&B->tree.grid, mx_morton_child(key, level, c), level + 1, clo[c], chi[c]);
    for (int a = 0; a < 3; a++) {
      cc[c][a] = 0.5 * (clo[c][a] + chi[c][a]);
      ch[c][a] = 0.5 * (chi[c][a] - clo[c][a]);
    }
  }
  const double *mid = clo[7]; /* the parent's centre */
  uint8_t surf = 0, rmeet[8] = {0};
  uint32_t ntri[8] = {0};
  for (uint32_t i = 0; i < d->tri_cnt; i++) {
    const uint32_t t = tris[i];
    const double *v = B->tree.tri_xyz + 9 * (size_t)t;
    unsigned cand = 0xff; /* children the triangle's box reaches */
    for (int a = 0; a < 3; a++) {
      const double mn = mx_min(v[a], mx_min(v[3 + a], v[6 + a]));
      const double mx = mx_max(v[a], mx_max(v[3 + a], v[6 + a]));
      const unsigned upper = a == 0 ? 0xaa : a == 1 ? 0xcc : 0xf0;
      if (mn > mid[a]) cand &= upper;
      if (mx < mid[a]) cand &= ~upper;
    }
    uint8_t m = 0;
    for (unsigned s = cand; s; s &= s - 1) {
      const int c = __builtin_ctz(s);
      if (mx_tri_box_overlap(cc[c], ch[c], v)) m |= (uint8_t)(1u << c);
    }
    mask[i] = m;
    const uint8_t r = B->tri_region[t];
    for (unsigned s = m; s; s &= s - 1) {
      const int c = __builtin_ctz(s);
      ntri[c]++;
      if (r != 255) rmeet[c] |= (uint8_t)(1u << r);
    }
    if (r == 255) surf |= m;
  }
  /* the domain: meets the surface, or the parent's side, or located once
   * per group when the parent met the surface */
  const uint8_t inside = (d->flags & MX_PQ_SURFACE)
                             ? side_of_children(&B->loc_domain, (uint8_t)~surf, cc, &f->located)
                             : (uint8_t)~surf;
  const uint8_t kept = surf | inside;
  uint8_t rin[8] = {0};
  for (int r = 0; r < B->req.nregions; r++) {
    const uint8_t bit = (uint8_t)(1u << r);
    uint8_t meets = 0;
    for (int c = 0; c < 8; c++)
      if (rmeet[c] & bit) meets |= (uint8_t)(1u << c);
    const uint8_t rest = kept & (uint8_t)~meets;
    uint8_t in;
    if (B->req.meet_only & bit) /* refined where met only (a --level input) */
      in = 0;
    else if (d->rmeet & bit)
      in = side_of_children(&B->loc_region[r], rest, cc, &f->located);
    else
      in = (d->rin & bit) ? rest : 0;
    for (int c = 0; c < 8; c++)
      if ((in >> c) & 1) rin[c] |= bit;
  }
  for (int c = 0; c < 8; c++) {
    mx_pq *q = &f->child[c];
    if (!((kept >> c) & 1)) {
      q->target = (uint8_t)(level + 1); /* outside: never asked to split */
      continue;
    }
    q->flags = ((surf >> c) & 1) ? MX_PQ_SURFACE : MX_PQ_INSIDE;
    q->tri_cnt = ntri[c];
    q->rmeet = rmeet[c];
    q->rin = rin[c];
    q->target = (uint8_t)mx_target_level(&B->req, clo[c], chi[c], (surf >> c) & 1,
                                         (unsigned)(rmeet[c] | rin[c]));
  }
}

uint64_t mx_pq_family_tris(const mx_pq_family *f) {
  uint64_t s = 0;
  for (int c = 0; c < 8; c++) s += f->child[c].tri_cnt;
  return s;
}

void mx_pq_fill(mx_pq_family *f, const uint32_t *tris, uint32_t ntris, const uint8_t *mask,
                uint32_t *out, uint64_t base) {
  uint64_t w = 0;
  for (int c = 0; c < 8; c++) {
    mx_pq *q = &f->child[c];
    q->tri_off = base + w;
    if (!q->tri_cnt) continue;
    for (uint32_t k = 0; k < ntris; k++)
      if ((mask[k] >> c) & 1) out[w++] = tris[k];
  }
}
