/* Where the soup's triangles come from: the lines of their faces, kept in
 * runs of evenly spaced lines (see mx_line_run in trisoup.h), and the names
 * messages give a triangle ("face 12 (triangle 2 of 4, line 57)"). */
#include <stdio.h>
#include <string.h>

#include "base/common.h"
#include "soa/trisoup.h"

static int push_run(mx_trisoup *s, mx_line_run r) {
  if (s->nrun == s->cap_run) {
    const size_t cap = s->cap_run ? 2 * s->cap_run : 4;
    mx_line_run *p = mx_realloc(s->run, cap * sizeof *p);
    if (!p) return MX_ENOMEM;
    s->run = p;
    s->cap_run = cap;
  }
  s->run[s->nrun++] = r;
  return MX_OK;
}

/* Whether run r gives face f line l (setting its step from its second
 * face). */
static int extends(mx_line_run *r, uint32_t f, uint32_t l) {
  if (r->line0 == 0 || f < r->face0 || l < r->line0) return 0;
  const uint64_t df = f - r->face0, dl = l - r->line0;
  if (df == 0) return dl == 0;
  if (r->step == 0) {
    if (dl == 0 || dl % df != 0 || dl / df > UINT32_MAX) return 0;
    r->step = (uint32_t)(dl / df);
    return 1;
  }
  return dl == df * r->step;
}

int mx_trisoup_note_line(mx_trisoup *s, size_t t, uint32_t face, long line) {
  mx_line_run *last = s->nrun ? &s->run[s->nrun - 1] : NULL;
  if (last && last->step && face >= last->face0 && line > 0 &&
      (uint64_t)line == last->line0 + (uint64_t)last->step * (face - last->face0))
    return MX_OK; /* the usual case: the next face on the next line */
  if (t > UINT32_MAX) return MX_OK; /* beyond what runs hold: lines unknown */
  const uint32_t l = line > 0 && line <= (long)UINT32_MAX ? (uint32_t)line : 0;
  if (!last && l == 0) return MX_OK;
  if (last && l != 0 && extends(last, face, l)) return MX_OK;
  if (last && l == 0 && last->line0 == 0) return MX_OK;
  const mx_line_run r = {(uint32_t)t, face, l, 0};
  if (last && last->t0 == r.t0) { /* the last run has no triangle yet */
    *last = r;
    return MX_OK;
  }
  return push_run(s, r);
}

int mx_trisoup_append_runs(mx_trisoup *dst, const mx_trisoup *src) {
  if (dst->nt > UINT32_MAX) return MX_OK;
  const uint32_t off = (uint32_t)dst->nt;
  /* dst's last run must not go on over src's triangles */
  if (dst->nrun && (src->nrun == 0 || src->run[0].t0 != 0))
    MX_CHECK(push_run(dst, (mx_line_run){off, 0, 0, 0}));
  for (size_t i = 0; i < src->nrun; i++) {
    mx_line_run r = src->run[i];
    if ((uint64_t)r.t0 + off > UINT32_MAX) break;
    r.t0 += off;
    MX_CHECK(push_run(dst, r));
  }
  mx_trisoup_drop_empty_runs(dst);
  return MX_OK;
}

void mx_trisoup_drop_empty_runs(mx_trisoup *s) {
  size_t k = 0;
  for (size_t i = 0; i < s->nrun; i++) {
    if (k > 0 && s->run[k - 1].t0 == s->run[i].t0) k--; /* the earlier one is empty */
    s->run[k++] = s->run[i];
  }
  s->nrun = k;
}

long mx_trisoup_line(const mx_trisoup *s, size_t t) {
  if (!s->run || t >= s->nt || t > UINT32_MAX) return 0;
  size_t lo = 0, hi = s->nrun; /* the last run with t0 <= t */
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (s->run[mid].t0 <= t)
      lo = mid + 1;
    else
      hi = mid;
  }
  if (lo == 0) return 0;
  const mx_line_run *r = &s->run[lo - 1];
  const uint32_t f = s->face[t];
  if (r->line0 == 0 || f < r->face0) return 0;
  const uint64_t l = r->line0 + (uint64_t)r->step * (f - r->face0);
  return l <= (uint64_t)UINT32_MAX ? (long)l : 0;
}

/* Whether the input of triangle t has a face split into several triangles
 * (triangles [b, e) of one shell around t). */
static int has_polygons(const mx_trisoup *s, size_t t, size_t *b, size_t *e) {
  size_t lo = t, hi = t + 1;
  const uint16_t sh = s->shell[t];
  while (lo > 0 && s->shell[lo - 1] == sh) lo--;
  while (hi < s->nt && s->shell[hi] == sh) hi++;
  *b = lo;
  *e = hi;
  for (size_t i = lo + 1; i < hi; i++)
    if (s->face[i] == s->face[i - 1]) return 1;
  return 0;
}

int mx_trisoup_name(const mx_trisoup *s, size_t t, char *buf, size_t n) {
  if (n == 0) return 0;
  if (!s || !s->face || t >= s->nt) {
    snprintf(buf, n, "triangle %zu", t);
    return 0;
  }
  size_t b, e;
  const int poly = has_polygons(s, t, &b, &e);
  const uint32_t f = s->face[t];
  size_t first = t, last = t + 1; /* the triangles of t's face */
  while (first > b && s->face[first - 1] == f) first--;
  while (last < e && s->face[last] == f) last++;
  const long line = mx_trisoup_line(s, t);
  char part[64] = "", at[32] = "";
  if (last - first > 1)
    snprintf(part, sizeof part, "triangle %zu of %zu", t - first + 1, last - first);
  if (line > 0) snprintf(at, sizeof at, "line %ld", line);
  const int paren = part[0] || at[0];
  snprintf(buf, n, "%s %u%s%s%s%s%s", poly ? "face" : "triangle", f, paren ? " (" : "",
           part, part[0] && at[0] ? ", " : "", at, paren ? ")" : "");
  return paren;
}
