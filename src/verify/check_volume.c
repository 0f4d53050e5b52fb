/* Pass 7 of the checker, volume, with a surface: whether the surface is
 * closed (its edges not used by exactly two of its triangles; with several
 * files, each file's edges apart), the volume it encloses (divergence
 * theorem: signed tetrahedra from the centre of its bounding box, in fixed
 * chunks; several files: their pieces' union, check_pieces.c), and the
 * mesh's volume error against it; with a closed surface, the error is a
 * defect beyond volume_tol (chosen from the mesh when 0: half a layer of
 * elements along the surface -- the triangles two files share are inside
 * the domain, not along its surface --, 5% at least). */
#include "verify/check_passes.h"

#include "base/scan.h"

/* Edges of the surface not used by exactly two of its triangles. */
static int surface_open(const mx_trisoup *s, size_t *open) {
  const size_t ne = 3 * s->nt;
  uint64_t *k = mx_alloc((ne + 1) * sizeof *k);
  if (!k) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (s->nt > 65536)
  for (size_t t = 0; t < s->nt; t++)
    for (int x = 0; x < 3; x++) {
      const uint32_t a = s->tri[3 * t + (size_t)x],
                     b = s->tri[3 * t + (size_t)(x + 1) % 3];
      k[3 * t + (size_t)x] = a < b ? (uint64_t)a << 32 | b
                                   : (uint64_t)b << 32 | a;
    }
  const int st = mx_sort_u64(k, NULL, ne);
  size_t n = 0;
  for (size_t i = 0; st == MX_OK && i < ne;) {
    size_t j = i + 1;
    while (j < ne && k[j] == k[i]) j++;
    n += j - i != 2;
    i = j;
  }
  mx_free(k);
  *open = n;
  return st;
}

int mx_ck_surface_volume(const mx_trisoup *s, mx_check_report *r) {
  MX_CHECK(surface_open(s, &r->surface_open_edges));
  double lo[3], hi[3];
  mx_trisoup_bbox(s, lo, hi);
  double ctr[3];
  for (int a = 0; a < 3; a++) ctr[a] = 0.5 * (lo[a] + hi[a]);
  /* Enclosed volume, in fixed chunks. */
  const size_t nchunks = (s->nt + CHUNK - 1) / CHUNK;
  double *part = mx_alloc((nchunks + 1) * sizeof *part);
  if (!part) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (nchunks > 1)
  for (size_t k = 0; k < nchunks; k++) {
    double v = 0.0;
    const size_t end = (k + 1) * CHUNK < s->nt ? (k + 1) * CHUNK : s->nt;
    for (size_t t = k * CHUNK; t < end; t++) {
      const uint32_t *i = s->tri + 3 * t;
      double a[3] = {s->x[i[0]] - ctr[0], s->y[i[0]] - ctr[1],
                     s->z[i[0]] - ctr[2]};
      double b[3] = {s->x[i[1]] - ctr[0], s->y[i[1]] - ctr[1],
                     s->z[i[1]] - ctr[2]};
      double c[3] = {s->x[i[2]] - ctr[0], s->y[i[2]] - ctr[1],
                     s->z[i[2]] - ctr[2]};
      v += a[0] * (b[1] * c[2] - b[2] * c[1]) -
           a[1] * (b[0] * c[2] - b[2] * c[0]) +
           a[2] * (b[0] * c[1] - b[1] * c[0]);
    }
    part[k] = v;
  }
  double vol = 0.0;
  for (size_t k = 0; k < nchunks; k++) vol += part[k];
  mx_free(part);
  r->surface_volume = fabs(vol / 6.0);
  r->volume_error = r->surface_volume > 0.0
                        ? (r->volume - r->surface_volume) / r->surface_volume
                        : NAN;
  return MX_OK;
}

void mx_ck_volume_verdict(const mx_mesh_data *m, const mx_trisoup *surface, const uint8_t *skip,
                          const mx_check_options *o, mx_check_report *r) {
  double tol = o->volume_tol;
  if (!(tol > 0.0)) {
    /* a coarse mesh loses or gains up to about a layer of elements
     * along the surface: half of one is allowed, 5% at least */
    double area = 0.0;
    for (size_t t = 0; t < surface->nt; t++) {
      if (skip && skip[t]) continue;
      const uint32_t *v = surface->tri + 3 * t;
      const double ux = surface->x[v[1]] - surface->x[v[0]],
                   uy = surface->y[v[1]] - surface->y[v[0]],
                   uz = surface->z[v[1]] - surface->z[v[0]];
      const double wx = surface->x[v[2]] - surface->x[v[0]],
                   wy = surface->y[v[2]] - surface->y[v[0]],
                   wz = surface->z[v[2]] - surface->z[v[0]];
      const double cx = uy * wz - uz * wy, cy = uz * wx - ux * wz, cz = ux * wy - uy * wx;
      area += 0.5 * sqrt(cx * cx + cy * cy + cz * cz);
    }
    const double V = fabs(r->surface_volume);
    const double h = m->ncells ? cbrt(fabs(r->volume) / (double)m->ncells) : 0.0;
    tol = V > 0.0 ? fmax(0.05, 0.5 * area * h / V) : 0.05;
    r->opt.volume_tol = tol;
    r->opt.volume_tol_auto = 1;
  }
  r->volume_off = !(fabs(r->volume_error) <= tol);
}
