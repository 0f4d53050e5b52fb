/* The kd-trees K_L and K_V of the control space (Jurczyk & Glut 2016,
 * sections 2.3 and 2.4; layout in src/sizing/cspace.h), built level by
 * level: the nodes of a level judged in parallel (their error on the N_s^3
 * samples, eq. 1, and where to split: s_L, s_G or s_S, section 2.2), then
 * split in order, then the new values computed in parallel. */
#include "sizing/cspace.h"

#include <math.h>
#include <string.h>

#include "base/common.h"

enum { MAX_NS = 16 };

typedef struct {
  size_t n, cap;
  uint32_t *node;   /* the frontier's nodes */
  double *box;      /* 6 a node: lo, hi */
} frontier;

static int frontier_push(frontier *F, uint32_t node, const double lo[3], const double hi[3]) {
  if (F->n == F->cap) {
    const size_t cap = F->cap ? 2 * F->cap : 256;
    uint32_t *n = mx_realloc(F->node, cap * sizeof *n);
    if (n) F->node = n;
    double *b = mx_realloc(F->box, 6 * cap * sizeof *b);
    if (b) F->box = b;
    if (!n || !b) return MX_ENOMEM;
    F->cap = cap;
  }
  F->node[F->n] = node;
  memcpy(F->box + 6 * F->n, lo, 3 * sizeof *lo);
  memcpy(F->box + 6 * F->n + 3, hi, 3 * sizeof *hi);
  F->n++;
  return MX_OK;
}

static void frontier_free(frontier *F) {
  mx_free(F->node);
  mx_free(F->box);
  memset(F, 0, sizeof *F);
}

/* Room for n more nodes and m more values. */
static int reserve(mx_cspace *c, size_t *ncap, size_t *vcap, size_t n, size_t m, int vertex) {
  if (c->nnodes + n > *ncap) {
    size_t cap = *ncap ? *ncap : 1024;
    while (cap < c->nnodes + n) cap *= 2;
    if (cap > UINT32_MAX) {
      mx_error(NULL, 0, "size field: more than 2^32 nodes");
      return MX_ENOMEM;
    }
    uint8_t *a = mx_realloc(c->axis, cap);
    if (a) c->axis = a;
    double *co = mx_realloc(c->coord, cap * sizeof *co);
    if (co) c->coord = co;
    uint32_t *ch = mx_realloc(c->child, cap * sizeof *ch);
    if (ch) c->child = ch;
    uint32_t *v = mx_realloc(c->val, cap * sizeof *v);
    if (v) c->val = v;
    uint32_t *vi = vertex ? mx_realloc(c->vid, 8 * cap * sizeof *vi) : NULL;
    if (vi) c->vid = vi;
    if (!a || !co || !ch || !v || (vertex && !vi)) return MX_ENOMEM;
    *ncap = cap;
  }
  if (c->nvalues + m > *vcap) {
    size_t cap = *vcap ? *vcap : 1024;
    while (cap < c->nvalues + m) cap *= 2;
    double *h = mx_realloc(c->h, 3 * cap * sizeof *h);
    if (!h) return MX_ENOMEM;
    c->h = h;
    *vcap = cap;
  }
  return MX_OK;
}

/* The value of node i's leaf approximation at p (box lo, hi). */
static void approx(const mx_cspace *c, uint32_t i, const double lo[3], const double hi[3],
                   const double p[3], double out[3]) {
  if (c->structure == MX_CS_KD_LEAF) {
    memcpy(out, c->h + 3 * (size_t)c->val[i], 3 * sizeof *out);
    return;
  }
  const uint32_t *v = c->vid + 8 * (size_t)c->val[i];
  double t[3];
  for (int a = 0; a < 3; a++) {
    t[a] = (p[a] - lo[a]) / (hi[a] - lo[a]);
    t[a] = t[a] < 0.0 ? 0.0 : t[a] > 1.0 ? 1.0 : t[a];
  }
  out[0] = out[1] = out[2] = 0.0;
  for (int k = 0; k < 8; k++) {
    const double w = (k & 1 ? t[0] : 1.0 - t[0]) * (k & 2 ? t[1] : 1.0 - t[1]) *
                     (k & 4 ? t[2] : 1.0 - t[2]);
    const double *h = c->h + 3 * (size_t)v[k];
    for (int a = 0; a < 3; a++) out[a] += w * h[a];
  }
}

/* Scratch of one thread. */
typedef struct {
  double xyz[3 * MAX_NS * MAX_NS * MAX_NS], h[3 * MAX_NS * MAX_NS * MAX_NS];
  double gx[3 * 3 * (MAX_NS + 1) * MAX_NS * MAX_NS], gh[3 * 3 * (MAX_NS + 1) * MAX_NS * MAX_NS];
} scratch;

/* Where node (lo, hi) splits by rule s_G or s_S: *axis and *at; 0 when the
 * gradients are all zero. */
static int gradient_split(const mx_cspace *c, mx_size_fn f, void *user, scratch *S,
                          const double lo[3], const double hi[3], int *axis, double *at,
                          int *bad) {
  const int ns = c->ns;
  const size_t per = (size_t)(ns + 1) * ns * ns;
  /* the face centres of the sub-boxes along each axis d: plane t, then the
   * sub-box indices u, v of the two other axes */
  size_t w = 0;
  for (int d = 0; d < 3; d++) {
    const int e1 = (d + 1) % 3, e2 = (d + 2) % 3;
    for (int t = 0; t <= ns; t++)
      for (int u = 0; u < ns; u++)
        for (int v = 0; v < ns; v++) {
          double *p = S->gx + 3 * w++;
          p[d] = lo[d] + (hi[d] - lo[d]) * (double)t / ns;
          p[e1] = lo[e1] + (hi[e1] - lo[e1]) * ((double)u + 0.5) / ns;
          p[e2] = lo[e2] + (hi[e2] - lo[e2]) * ((double)v + 0.5) / ns;
        }
  }
  f(user, 3 * per, S->gx, S->gh);
  if (!mx_cs_sizes_ok(S->gh, 3 * per)) {
    *bad = 1;
    return 0;
  }
  double best = 0.0, sum[3] = {0.0, 0.0, 0.0}, slab[3][MAX_NS];
  int bd = -1, bi = 0;
  for (int d = 0; d < 3; d++)
    for (int i = 0; i < ns; i++) {
      slab[d][i] = 0.0;
      for (int uv = 0; uv < ns * ns; uv++) {
        const double *a = S->gh + 3 * ((size_t)d * per + (size_t)(i + 1) * ns * ns + uv);
        const double *b = S->gh + 3 * ((size_t)d * per + (size_t)i * ns * ns + uv);
        const double g = mx_metric_nonconformity(a, b);
        slab[d][i] += g;
        if (g > best) {
          best = g;
          bd = d;
          bi = i;
        }
      }
      sum[d] += slab[d][i];
    }
  if (bd < 0) return 0;
  if (c->split == MX_SPLIT_SUM) {
    bd = 0;
    for (int d = 1; d < 3; d++)
      if (sum[d] > sum[bd]) bd = d;
    double run = 0.0;
    bi = ns - 1;
    for (int i = 0; i < ns; i++) {
      run += slab[bd][i];
      if (run > 0.5 * sum[bd]) {
        bi = i;
        break;
      }
    }
  }
  *axis = bd;
  *at = lo[bd] + (hi[bd] - lo[bd]) * ((double)bi + 0.5) / ns;
  return 1;
}

/* Whether the gradients between the sub-boxes' faces missed the error the
 * node's samples h (the ns^3 grid, x fastest) found: the largest
 * non-conformity between two neighbouring samples along the axis they
 * chose is MISSED times below the largest along another axis (the
 * non-conformity is about the square of the log of the sizes' ratio: the
 * sizes vary about 8 times less along it). That is a narrow feature of the
 * field lying between the face planes, seen by the samples only (a dip of
 * min(h, s + distance to a curve)): splitting the chosen axis again and
 * again would cut slivers that all keep the error, twice as many each
 * level, down to the depth cap (844 thousand leaves at depth 26, four
 * times more every two levels, where 1630 do). Such a node is split as by
 * s_L. F1, F3, F4 and F5 of bench/cspace_bench.c give the same trees as
 * without this rule, for every structure and tolerance; F2, capped at
 * depth 24, trees a few per cent larger. */
#define MISSED 64.0
static int gradients_missed(const double *h, int ns, int axis) {
  double var[3] = {0.0, 0.0, 0.0};
  const size_t step[3] = {1, (size_t)ns, (size_t)ns * ns};
  for (int k = 0; k < ns; k++)
    for (int j = 0; j < ns; j++)
      for (int i = 0; i < ns; i++) {
        const int at[3] = {i, j, k};
        const size_t s = (size_t)i + step[1] * j + step[2] * k;
        for (int d = 0; d < 3; d++)
          if (at[d] + 1 < ns)
            var[d] = fmax(var[d], mx_metric_nonconformity(h + 3 * s, h + 3 * (s + step[d])));
      }
  return MISSED * var[axis] < fmax(var[0], fmax(var[1], var[2]));
}

/* Node i's error and, over delta, where it splits (axis -1: it stays a
 * leaf). bad: a size not finite and positive was met. */
static void judge(const mx_cspace *c, mx_size_fn f, void *user, scratch *S, uint32_t i,
                  const double lo[3], const double hi[3], int deep_enough, int *axis,
                  double *at, int *capped, int *bad) {
  /* K_V's interpolation is exact at the corners and farthest between
   * them: twice as many samples a side (the grid's midpoints) */
  const int ns = c->structure == MX_CS_KD_VERTEX ? (2 * c->ns - 1 < MAX_NS ? 2 * c->ns - 1 : MAX_NS)
                                                 : c->ns;
  const size_t n = (size_t)ns * ns * ns;
  *axis = -1;
  mx_cs_samples(lo, hi, ns, S->xyz);
  f(user, n, S->xyz, S->h);
  if (!mx_cs_sizes_ok(S->h, n)) {
    *bad = 1;
    return;
  }
  double err = 0.0;
  for (size_t s = 0; s < n && err <= c->delta; s++) {
    double k[3];
    approx(c, i, lo, hi, S->xyz + 3 * s, k);
    err = fmax(err, mx_metric_nonconformity(S->h + 3 * s, k));
  }
  if (err <= c->delta) return;
  if (deep_enough) {
    *capped = 1;
    return;
  }
  if (c->split != MX_SPLIT_LONGEST && gradient_split(c, f, user, S, lo, hi, axis, at, bad) &&
      !gradients_missed(S->h, ns, *axis))
    return;
  if (*bad) return;
  int a = 0;
  for (int d = 1; d < 3; d++)
    if (hi[d] - lo[d] > hi[a] - lo[a]) a = d;
  *axis = a;
  *at = 0.5 * (lo[a] + hi[a]);
}

int mx_cs_build_kd(mx_cspace *c, mx_size_fn f, void *user) {
  const int vertex = c->structure == MX_CS_KD_VERTEX;
  size_t ncap = 0, vcap = 0;
  frontier F = {0, 0, NULL, NULL}, G = {0, 0, NULL, NULL};
  int *split_axis = NULL;
  double *split_at = NULL, *pts = NULL;
  int st = reserve(c, &ncap, &vcap, 1, vertex ? 8 : 1, vertex);
  /* the root and its value(s) */
  if (!st) {
    c->nnodes = 1;
    c->axis[0] = MX_KD_LEAF;
    c->coord[0] = 0.0;
    c->child[0] = 0;
    c->val[0] = 0;
    double p[24];
    const int nv = vertex ? 8 : 1;
    for (int k = 0; k < nv; k++)
      for (int a = 0; a < 3; a++)
        p[3 * k + a] = vertex ? ((k >> a) & 1 ? c->hi[a] : c->lo[a]) : 0.5 * (c->lo[a] + c->hi[a]);
    st = mx_cs_eval(f, user, (size_t)nv, p, c->h);
    c->nvalues = (size_t)nv;
    if (vertex)
      for (int k = 0; k < 8; k++) c->vid[k] = (uint32_t)k;
  }
  if (!st) st = frontier_push(&F, 0, c->lo, c->hi);
  int depth = 0, capped = 0;
  while (!st && F.n) {
    mx_free(split_axis);
    mx_free(split_at);
    split_axis = mx_alloc(F.n * sizeof *split_axis);
    split_at = mx_alloc(F.n * sizeof *split_at);
    if (!split_axis || !split_at) {
      st = MX_ENOMEM;
      break;
    }
    int bad = 0, cap = 0, nomem = 0;
    const int deep = depth >= c->max_depth;
#pragma omp parallel reduction(| : bad, cap, nomem)
    {
      scratch *S = mx_alloc(sizeof *S);
      if (!S) nomem = 1;
#pragma omp for schedule(dynamic, 16)
      for (size_t k = 0; k < F.n; k++) {
        split_axis[k] = -1;
        if (!S) continue;
        int b = 0, cp = 0;
        judge(c, f, user, S, F.node[k], F.box + 6 * k, F.box + 6 * k + 3, deep, &split_axis[k],
              &split_at[k], &cp, &b);
        bad |= b;
        cap |= cp;
      }
      mx_free(S);
    }
    if (nomem) {
      st = MX_ENOMEM;
      break;
    }
    if (bad) {
      st = mx_cs_bad_sizes(c);
      break;
    }
    capped |= cap;
    size_t nsplit = 0;
    for (size_t k = 0; k < F.n; k++) nsplit += split_axis[k] >= 0;
    if (!nsplit) break;
    const size_t per = vertex ? 4 : 2; /* new values per split */
    st = reserve(c, &ncap, &vcap, 2 * nsplit, per * nsplit, vertex);
    mx_free(pts);
    pts = mx_alloc(3 * per * nsplit * sizeof *pts);
    if (st || !pts) {
      st = st ? st : MX_ENOMEM;
      break;
    }
    /* the splits, in order: children, their boxes and the points of their
     * new values */
    G.n = 0;
    size_t np = 0;
    for (size_t k = 0; k < F.n && !st; k++) {
      const int a = split_axis[k];
      if (a < 0) continue;
      const uint32_t i = F.node[k], ch = (uint32_t)c->nnodes;
      const double *lo = F.box + 6 * k, *hi = lo + 3, at = split_at[k];
      c->axis[i] = (uint8_t)a;
      c->coord[i] = at;
      c->child[i] = ch;
      double lo1[3], hi0[3];
      memcpy(lo1, lo, sizeof lo1);
      memcpy(hi0, hi, sizeof hi0);
      hi0[a] = at;
      lo1[a] = at;
      for (int s = 0; s < 2; s++) {
        c->axis[ch + s] = MX_KD_LEAF;
        c->coord[ch + s] = 0.0; /* (a leaf's: unused, but defined) */
        c->child[ch + s] = 0;
        c->val[ch + s] = vertex ? ch + s : (uint32_t)(c->nvalues + np / 3 + s);
      }
      if (!vertex) {
        for (int s = 0; s < 2; s++)
          for (int d = 0; d < 3; d++)
            pts[np + 3 * s + d] = 0.5 * ((s ? lo1 : lo)[d] + (s ? hi : hi0)[d]);
        np += 6;
      } else {
        /* the 4 corners on the split plane, shared by both children */
        const uint32_t *pc = c->vid + 8 * (size_t)c->val[i];
        uint32_t *c0 = c->vid + 8 * (size_t)ch, *c1 = c0 + 8;
        uint32_t fresh[8];
        for (int k2 = 0; k2 < 8; k2++) {
          if ((k2 >> a) & 1) continue;
          fresh[k2] = (uint32_t)(c->nvalues + np / 3);
          for (int d = 0; d < 3; d++)
            pts[np + d] = d == a ? at : ((k2 >> d) & 1 ? hi[d] : lo[d]);
          np += 3;
        }
        for (int k2 = 0; k2 < 8; k2++) {
          const int up = (k2 >> a) & 1, mate = k2 ^ (1 << a);
          c0[k2] = up ? fresh[mate] : pc[k2];
          c1[k2] = up ? pc[k2] : fresh[k2];
        }
      }
      c->nnodes += 2;
      st = frontier_push(&G, ch, lo, hi0);
      if (!st) st = frontier_push(&G, ch + 1, lo1, hi);
    }
    if (st) break;
    const size_t nnew = np / 3;
    st = mx_cs_eval(f, user, nnew, pts, c->h + 3 * c->nvalues);
    if (st) break;
    c->nvalues += nnew;
    frontier T = F;
    F = G;
    G = T;
    depth++;
  }
  c->depth = depth;
  c->capped = capped;
  frontier_free(&F);
  frontier_free(&G);
  mx_free(split_axis);
  mx_free(split_at);
  mx_free(pts);
  if (st) return st;
  /* keep the leaves' values only (K_L) and the leaves' corner lists (K_V) */
  size_t nl = 0;
  for (size_t i = 0; i < c->nnodes; i++) nl += c->axis[i] == MX_KD_LEAF;
  c->nleaves = nl;
  if (!vertex) {
    double *h = mx_alloc((3 * nl + 3) * sizeof *h);
    if (!h) return MX_ENOMEM;
    size_t w = 0;
    for (size_t i = 0; i < c->nnodes; i++) {
      if (c->axis[i] != MX_KD_LEAF) continue;
      memcpy(h + 3 * w, c->h + 3 * (size_t)c->val[i], 3 * sizeof *h);
      c->val[i] = (uint32_t)w++;
    }
    mx_free(c->h);
    c->h = h;
    c->nvalues = nl;
  } else {
    uint32_t *v = mx_alloc((8 * nl + 8) * sizeof *v);
    if (!v) return MX_ENOMEM;
    size_t w = 0;
    for (size_t i = 0; i < c->nnodes; i++) {
      if (c->axis[i] != MX_KD_LEAF) continue;
      memcpy(v + 8 * w, c->vid + 8 * (size_t)c->val[i], 8 * sizeof *v);
      c->val[i] = (uint32_t)w++;
    }
    mx_free(c->vid);
    c->vid = v;
  }
  return MX_OK;
}

static void clamp_point(const mx_cspace *c, const double p[3], double q[3]) {
  for (int a = 0; a < 3; a++) q[a] = p[a] < c->lo[a] ? c->lo[a] : p[a] > c->hi[a] ? c->hi[a] : p[a];
}

void mx_cs_query_kd(const mx_cspace *c, const double p[3], double h[3]) {
  double q[3], lo[3], hi[3];
  clamp_point(c, p, q);
  memcpy(lo, c->lo, sizeof lo);
  memcpy(hi, c->hi, sizeof hi);
  uint32_t i = 0;
  if (c->structure == MX_CS_KD_LEAF) {
    while (c->axis[i] != MX_KD_LEAF) i = c->child[i] + (q[c->axis[i]] >= c->coord[i]);
    memcpy(h, c->h + 3 * (size_t)c->val[i], 3 * sizeof *h);
    return;
  }
  while (c->axis[i] != MX_KD_LEAF) {
    const int a = c->axis[i];
    if (q[a] < c->coord[i]) {
      hi[a] = c->coord[i];
      i = c->child[i];
    } else {
      lo[a] = c->coord[i];
      i = c->child[i] + 1;
    }
  }
  approx(c, i, lo, hi, q, h);
}

double mx_cs_min_box_kd(const mx_cspace *c, const double lo[3], const double hi[3]) {
  uint32_t stack[128];
  int top = 0;
  double best = INFINITY;
  stack[top++] = 0;
  while (top) {
    const uint32_t i = stack[--top];
    if (c->axis[i] == MX_KD_LEAF) {
      const int nv = c->structure == MX_CS_KD_LEAF ? 1 : 8;
      for (int k = 0; k < nv; k++) {
        const uint32_t v = nv == 1 ? c->val[i] : c->vid[8 * (size_t)c->val[i] + k];
        for (int a = 0; a < 3; a++) best = fmin(best, c->h[3 * (size_t)v + a]);
      }
      continue;
    }
    const int a = c->axis[i];
    if (hi[a] >= c->coord[i] && top < 128) stack[top++] = c->child[i] + 1;
    if (lo[a] < c->coord[i] && top < 128) stack[top++] = c->child[i];
  }
  return best;
}

size_t mx_cs_leaves_kd(const mx_cspace *c, double *box, double *h) {
  struct { uint32_t i; double lo[3], hi[3]; } stack[128];
  int top = 0;
  size_t n = 0;
  stack[0].i = 0;
  memcpy(stack[0].lo, c->lo, sizeof c->lo);
  memcpy(stack[0].hi, c->hi, sizeof c->hi);
  top = 1;
  while (top) {
    const int s = --top;
    const uint32_t i = stack[s].i;
    double lo[3], hi[3];
    memcpy(lo, stack[s].lo, sizeof lo);
    memcpy(hi, stack[s].hi, sizeof hi);
    if (c->axis[i] == MX_KD_LEAF) {
      if (box) {
        memcpy(box + 6 * n, lo, sizeof lo);
        memcpy(box + 6 * n + 3, hi, sizeof hi);
        const int nv = c->structure == MX_CS_KD_LEAF ? 1 : 8;
        double m = INFINITY;
        for (int k = 0; k < nv; k++) {
          const uint32_t v = nv == 1 ? c->val[i] : c->vid[8 * (size_t)c->val[i] + k];
          for (int a = 0; a < 3; a++) m = fmin(m, c->h[3 * (size_t)v + a]);
        }
        h[n] = m;
      }
      n++;
      continue;
    }
    if (top + 2 > 128) continue;
    const int a = c->axis[i];
    stack[top].i = c->child[i] + 1;
    memcpy(stack[top].lo, lo, sizeof lo);
    memcpy(stack[top].hi, hi, sizeof hi);
    stack[top].lo[a] = c->coord[i];
    top++;
    stack[top].i = c->child[i];
    memcpy(stack[top].lo, lo, sizeof lo);
    memcpy(stack[top].hi, hi, sizeof hi);
    stack[top].hi[a] = c->coord[i];
    top++;
  }
  return n;
}
