#include "kernels/estimate.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double area(const mx_trisoup *s, uint32_t t0, uint32_t t1) {
  double a = 0.0;
  for (uint32_t t = t0; t < t1; t++) {
    const uint32_t *v = s->tri + 3 * (size_t)t;
    const double u[3] = {s->x[v[1]] - s->x[v[0]], s->y[v[1]] - s->y[v[0]], s->z[v[1]] - s->z[v[0]]};
    const double w[3] = {s->x[v[2]] - s->x[v[0]], s->y[v[2]] - s->y[v[0]], s->z[v[2]] - s->z[v[0]]};
    const double c[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
    a += 0.5 * sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  }
  return a;
}

static double bbox_volume(const mx_trisoup *s, uint32_t t0, uint32_t t1) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (uint32_t t = t0; t < t1; t++)
    for (int k = 0; k < 3; k++) {
      const uint32_t v = s->tri[3 * (size_t)t + k];
      const double p[3] = {s->x[v], s->y[v], s->z[v]};
      for (int a = 0; a < 3; a++) {
        lo[a] = fmin(lo[a], p[a]);
        hi[a] = fmax(hi[a], p[a]);
      }
    }
  return t1 > t0 ? (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]) : 0.0;
}

double mx_estimate_bytes(const mx_trisoup *soup, uint32_t nt_domain,
                         const uint32_t *region_t0, const mx_requests *req,
                         const mx_grid *g, int stage) {
  const double vol = bbox_volume(soup, 0, nt_domain);
  double leaves = (double)g->dims[0] * g->dims[1] * g->dims[2];
  if (req->s_level > 0) {
    const double h = ldexp(g->side, -req->s_level);
    leaves += 3.2 * area(soup, 0, nt_domain) / (h * h);
  }
  if (req->a_level > 0) {
    const double h = ldexp(g->side, -req->a_level);
    leaves += vol / (h * h * h);
  }
  for (size_t b = 0; b < req->nboxes; b++) {
    const mx_box_region *r = &req->boxes[b];
    const double h = ldexp(g->side, -r->level);
    double v = 1.0;
    for (int a = 0; a < 3; a++) v *= fmax(0.0, r->hi[a] - r->lo[a]);
    leaves += fmin(v, vol) / (h * h * h);
  }
  for (int r = 0; r < req->nregions; r++) {
    const double h = ldexp(g->side, -req->rlevel[r]);
    if ((req->meet_only >> r) & 1) /* a surface: as the input surface's */
      leaves += 3.2 * area(soup, region_t0[r], region_t0[r + 1]) / (h * h);
    else
      leaves += fmin(bbox_volume(soup, region_t0[r], region_t0[r + 1]), vol) / (h * h * h);
  }
  /* bytes per leaf at the peak (mx_estimate_bytes_leaves), on this
   * estimate of the leaves */
  return mx_estimate_bytes_leaves((size_t)leaves, soup->nt, stage);
}

double mx_estimate_bytes_leaves(size_t leaves, size_t triangles, int stage) {
  const double l = (double)leaves;
  if (stage == 0) return 6.6e6 + 600.0 * (double)triangles + 240.0 * l;
  /* refit after the transition's hash went before its element arrays, the
   * surface patterns gave back the elements they had read and the writers
   * stopped copying fields (issue 12): cortex -s 4 to -s 10 within
   * 0.93-1.10 of the measured peak (bench/memory_sweep.sh) */
  return 5.5e6 + 600.0 * (double)triangles + 290.0 * l + 100.0 * (l < 2e5 ? l : 2e5);
}

/* The limit of the memory cgroup this process runs in (a batch job's
 * --mem), minus what it already uses; 0 when there is none. */
static double cgroup_room(void) {
  double max = 0.0, cur = 0.0;
  FILE *f = fopen("/sys/fs/cgroup/memory.max", "r"); /* cgroup v2 */
  if (f) {
    char w[64] = "";
    if (fscanf(f, "%63s", w) == 1 && strcmp(w, "max") != 0) max = atof(w);
    fclose(f);
    f = fopen("/sys/fs/cgroup/memory.current", "r");
    if (f) {
      if (fscanf(f, "%lf", &cur) != 1) cur = 0.0;
      fclose(f);
    }
  } else if ((f = fopen("/sys/fs/cgroup/memory/memory.limit_in_bytes", "r"))) { /* v1 */
    if (fscanf(f, "%lf", &max) != 1 || max > 1e18) max = 0.0;
    fclose(f);
    f = fopen("/sys/fs/cgroup/memory/memory.usage_in_bytes", "r");
    if (f) {
      if (fscanf(f, "%lf", &cur) != 1) cur = 0.0;
      fclose(f);
    }
  }
  return max > cur ? max - cur : 0.0;
}

double mx_available_bytes(void) {
  FILE *f = fopen("/proc/meminfo", "r");
  double kb = 0.0;
  if (f) {
    char line[256];
    while (fgets(line, sizeof line, f))
      if (sscanf(line, "MemAvailable: %lf kB", &kb) == 1) break;
    fclose(f);
  }
  const double avail = kb * 1024.0, room = cgroup_room();
  return room > 0.0 && (avail <= 0.0 || room < avail) ? room : avail;
}
