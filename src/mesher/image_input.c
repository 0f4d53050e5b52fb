/* Label images as inputs (issue 28; mixoct.h, "Label images"): the image
 * read (io/read_image.h), padded, its labels mapped (skip, merge), small
 * islands dropped, enclosed background filled and the contacts a surface
 * cannot bound removed (geom/label_fix.h); its interfaces as one smoothed
 * surface (geom/label_surface.h); then one domain input per label: the
 * outer shells of its parts, which touch the other labels' on their common
 * triangles, so the materials' path (touching inputs, nested shells) meshes
 * them with the label as the material's number. */
#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "geom/label_fix.h"
#include "geom/label_surface.h"
#include "io/read_image.h"
#include "kernels/grid.h"
#include "mesher/mesher_impl.h"

void mx_image_params_default(mx_image_params *ip) {
  memset(ip, 0, sizeof *ip);
  ip->smooth_rounds = -1;
}

void mx_image_params_release(mx_image_params *ip) {
  mx_free((void *)ip->skip);
  mx_free((void *)ip->merge);
  mx_free((void *)ip->label_names);
  mx_image_params_default(ip);
}

static int ends_with(const char *s, const char *suffix) {
  const size_t a = strlen(s), b = strlen(suffix);
  return a >= b && strcasecmp(s + a - b, suffix) == 0;
}

int mx_is_label_image_path(const char *path) {
  if (!path) return 0;
  static const char *const ext[] = {".nii", ".nii.gz", ".mha", ".mhd", ".inr", ".inr.gz"};
  for (size_t k = 0; k < sizeof ext / sizeof ext[0]; k++)
    if (ends_with(path, ext[k])) return 1;
  return 0;
}

int mx_mesher_set_image_params(mx_mesher *m, const mx_image_params *ip) {
  mx_image_params c;
  mx_image_params_default(&c);
  if (ip) {
    c = *ip;
    c.skip = NULL;
    c.merge = NULL;
    c.label_names = NULL;
    if (ip->nskip < 0 || ip->nmerge < 0 || (ip->nskip && !ip->skip) ||
        (ip->nmerge && !ip->merge)) {
      mx_error(NULL, 0, "image options: bad label lists");
      return MX_EINPUT;
    }
    int32_t *sk = ip->nskip ? mx_alloc((size_t)ip->nskip * sizeof *sk) : NULL;
    int32_t *mg = ip->nmerge ? mx_alloc((size_t)ip->nmerge * 2 * sizeof *mg) : NULL;
    char *names = ip->label_names ? mx_strdup(ip->label_names) : NULL;
    if ((ip->nskip && !sk) || (ip->nmerge && !mg) || (ip->label_names && !names)) {
      mx_free(sk);
      mx_free(mg);
      mx_free(names);
      return MX_ENOMEM;
    }
    if (sk) memcpy(sk, ip->skip, (size_t)ip->nskip * sizeof *sk);
    if (mg) memcpy(mg, ip->merge, (size_t)ip->nmerge * 2 * sizeof *mg);
    c.skip = sk;
    c.merge = mg;
    c.label_names = names;
  }
  mx_image_params_release(&m->image_params);
  m->image_params = c;
  return MX_OK;
}

/* The name of label L from a lookup-table file: lines "L NAME ...", '#'
 * comments. MX_EINPUT for a line that does not start with a label. */
static int label_name(const char *path, int32_t L, char *buf, size_t n) {
  snprintf(buf, n, "label %d", (int)L);
  if (!path) return MX_OK;
  FILE *f = fopen(path, "r");
  if (!f) {
    mx_error(path, 0, "cannot open the label names");
    return MX_EINPUT;
  }
  char line[1024];
  long no = 0;
  int st = MX_OK;
  while (fgets(line, sizeof line, f)) {
    no++;
    char *s = line;
    while (isspace((unsigned char)*s)) s++;
    if (!*s || *s == '#') continue;
    char *end = NULL;
    const long v = strtol(s, &end, 10);
    if (end == s || !isspace((unsigned char)*end)) {
      mx_error(path, no, "expected a label number and its name, e.g. \"2 grey_matter\"");
      st = MX_EINPUT;
      break;
    }
    if (v != L) continue;
    s = end;
    while (isspace((unsigned char)*s)) s++;
    size_t len = 0;
    while (s[len] && !isspace((unsigned char)s[len])) len++;
    if (len) snprintf(buf, n, "%.*s", (int)len, s);
    break;
  }
  fclose(f);
  return st;
}

/* The labels as meshed: skip -> 0, merge from -> to; padded copy. */
static int map_labels(const char *name, const int32_t *in, const int64_t d[3],
                      const mx_image_params *ip, int32_t *lab, const int64_t n[3]) {
  int st = MX_OK;
  int64_t bad = INT64_MAX;
#pragma omp parallel for schedule(static) reduction(min : bad)
  for (int64_t k = 0; k < d[2]; k++)
    for (int64_t j = 0; j < d[1]; j++)
      for (int64_t i = 0; i < d[0]; i++) {
        const int64_t v = i + d[0] * (j + d[1] * k);
        int32_t L = in[v];
        for (int t = 0; t < ip->nmerge; t++)
          if (L == ip->merge[2 * t]) {
            L = ip->merge[2 * t + 1];
            break;
          }
        for (int t = 0; t < ip->nskip; t++)
          if (L == ip->skip[t]) L = 0;
        if ((L < 0 || L > 65535) && v < bad) bad = v;
        lab[(i + 1) + n[0] * ((j + 1) + n[1] * (k + 1))] = L;
      }
  if (bad != INT64_MAX) {
    mx_error(name, 0, "voxel (%lld, %lld, %lld): label %d is not a material number (0 .. 65535); "
                      "map it with merge or skip",
             (long long)(bad % d[0]), (long long)((bad / d[0]) % d[1]),
             (long long)(bad / (d[0] * d[1])), (int)in[bad]);
    st = MX_EINPUT;
  }
  return st;
}

/* One input per label: its kept sides, vertices renumbered. */
static int add_label_inputs(mx_mesher *m, const char *name, const mx_label_surface *S,
                            const mx_image_params *ip, const int32_t *labels, int nl) {
  uint32_t *map = mx_alloc((S->nv + 1) * sizeof *map);
  if (!map) return MX_ENOMEM;
  int st = MX_OK;
  for (int l = 0; l < nl && !st; l++) {
    const int32_t L = labels[l];
    for (size_t v = 0; v < S->nv; v++) map[v] = UINT32_MAX;
    mx_trisoup s;
    memset(&s, 0, sizeof s);
    size_t nv = 0, nt = 0;
    for (size_t t = 0; t < S->nt; t++)
      for (int side = 0; side < 2; side++)
        if ((S->keep[t] >> side & 1) && S->label[2 * t + side] == L) {
          nt++;
          for (int c = 0; c < 3; c++)
            if (map[S->tri[3 * t + c]] == UINT32_MAX) map[S->tri[3 * t + c]] = (uint32_t)nv++;
        }
    st = mx_trisoup_reserve(&s, nv, nt);
    for (size_t v = 0; !st && v < S->nv; v++)
      if (map[v] != UINT32_MAX) st = mx_trisoup_set_vertex(&s, map[v], S->xyz + 3 * v);
    for (size_t t = 0; !st && t < S->nt; t++)
      for (int side = 0; side < 2 && !st; side++)
        if ((S->keep[t] >> side & 1) && S->label[2 * t + side] == L) {
          const uint32_t *c = S->tri + 3 * t;
          st = side == 0 ? mx_trisoup_add_triangle(&s, map[c[0]], map[c[1]], map[c[2]])
                         : mx_trisoup_add_triangle(&s, map[c[0]], map[c[2]], map[c[1]]);
        }
    char nm[256], input[4096 + 300];
    if (!st) st = label_name(ip->label_names, L, nm, sizeof nm);
    snprintf(input, sizeof input, "%s label %d", name, (int)L);
    if (!st) st = mx_mesher_add_domain(m, &s, input);
    if (!st) st = mx_mesher_set_material(m, m->ndomain - 1, L, nm);
    mx_trisoup_free(&s);
  }
  mx_free(map);
  return st;
}

int mx_mesher_add_label_array(mx_mesher *m, const char *name, const int32_t *labels,
                              const int64_t dims[3], const double A[12],
                              const mx_image_params *ip) {
  const double t0 = mx_wtime();
  if (!ip) ip = &m->image_params;
  if (!name) name = "(label array)";
  if (!labels || !dims || !A) {
    mx_error(name, 0, "label image: no voxels or no transform given");
    return MX_EINPUT;
  }
  for (int a = 0; a < 3; a++)
    if (dims[a] < 1 || dims[a] > (1 << 20)) {
      mx_error(name, 0, "label image: %lld voxels along axis %d (1 .. 1048576)",
               (long long)dims[a], a);
      return MX_EINPUT;
    }
  for (int k = 0; k < 12; k++)
    if (!isfinite(A[k])) {
      mx_error(name, 0, "label image: the voxel-to-world transform is not finite");
      return MX_EINPUT;
    }
  const double det = A[0] * (A[5] * A[10] - A[6] * A[9]) - A[1] * (A[4] * A[10] - A[6] * A[8]) +
                     A[2] * (A[4] * A[9] - A[5] * A[8]);
  double sp[3];
  for (int a = 0; a < 3; a++) sp[a] = sqrt(A[a] * A[a] + A[4 + a] * A[4 + a] + A[8 + a] * A[8 + a]);
  if (!(fabs(det) > 1e-12 * sp[0] * sp[1] * sp[2]) || !(sp[0] > 0 && sp[1] > 0 && sp[2] > 0)) {
    mx_error(name, 0, "label image: the voxel-to-world transform is singular (spacing %g %g %g)",
             sp[0], sp[1], sp[2]);
    return MX_EINPUT;
  }
  const int64_t n[3] = {dims[0] + 2, dims[1] + 2, dims[2] + 2};
  const double total = (double)n[0] * (double)n[1] * (double)n[2];
  if (total >= 4294967295.0) {
    mx_error(name, 0, "label image: %lld x %lld x %lld voxels: at most 2^32 with the padding",
             (long long)dims[0], (long long)dims[1], (long long)dims[2]);
    return MX_EINPUT;
  }
  int32_t *lab = mx_calloc((size_t)total * sizeof *lab);
  if (!lab) return MX_ENOMEM;
  mx_image_info *info = &m->image;
  memset(&info->fix, 0, sizeof info->fix);
  int st = map_labels(name, labels, dims, ip, lab, n);
  if (!st && ip->min_island > 1)
    st = mx_labels_drop_islands(lab, n, (size_t)ip->min_island, &info->fix);
  if (!st) st = mx_labels_fill_cavities(lab, n, &info->fix);
  if (!st) st = mx_labels_fix_contacts(lab, n, name, &info->fix);
  /* the labels left and their voxels */
  int nl = 0;
  int32_t L[64];
  size_t cnt[64];
  for (size_t v = 0; !st && v < (size_t)total; v++) {
    if (!lab[v]) continue;
    int k = 0;
    while (k < nl && L[k] != lab[v]) k++;
    if (k == nl) {
      if (nl == 64) {
        mx_error(name, 0, "label image: more than 64 labels; merge or skip some");
        st = MX_EINPUT;
        break;
      }
      L[nl] = lab[v];
      cnt[nl++] = 0;
    }
    cnt[k]++;
  }
  if (!st && nl == 0) {
    mx_error(name, 0, "label image: no voxel of any label (all background)");
    st = MX_EINPUT;
  }
  for (int x = 1; x < nl; x++) /* ascending labels */
    for (int y = x; y > 0 && L[y] < L[y - 1]; y--) {
      const int32_t t = L[y];
      L[y] = L[y - 1];
      L[y - 1] = t;
      const size_t c = cnt[y];
      cnt[y] = cnt[y - 1];
      cnt[y - 1] = c;
    }
  if (!st && m->ndomain + nl > 64) {
    mx_error(name, 0, "label image: %d labels and %d inputs before: at most 64 inputs", nl,
             m->ndomain);
    st = MX_EINPUT;
  }
  mx_label_surface S;
  memset(&S, 0, sizeof S);
  if (!st) {
    const int rounds = ip->voxel ? 0 : ip->smooth_rounds < 0 ? 10 : ip->smooth_rounds;
    st = mx_label_surface_build(lab, n, A, rounds, ip->voxel ? 0.0 : 0.35, &S);
  }
  mx_free(lab);
  if (!st) st = add_label_inputs(m, name, &S, ip, L, nl);
  if (!st) {
    /* the level of about one voxel: the root cube is 1.01 the box's shortest side */
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (size_t v = 0; v < S.nv; v++)
      for (int a = 0; a < 3; a++) {
        const double x = S.xyz[3 * v + a];
        lo[a] = x < lo[a] ? x : lo[a];
        hi[a] = x > hi[a] ? x : hi[a];
      }
    double side = hi[0] - lo[0];
    for (int a = 1; a < 3; a++) side = hi[a] - lo[a] < side ? hi[a] - lo[a] : side;
    const double voxel = fmin(sp[0], fmin(sp[1], sp[2]));
    int level = (int)lround(log2(1.01 * side / voxel));
    level = level < 1 ? 1 : level > 12 ? 12 : level;
    if (level > m->image_level) m->image_level = level;
    if (m->p.surface_level < 0 && m->p.all_level < 0) m->p.surface_level = m->image_level;
    m->p.materials = 1;
    m->image_inputs += nl;
    info->nlabels = nl;
    for (int k = 0; k < nl; k++) {
      info->labels[k] = L[k];
      info->voxels[k] = cnt[k];
    }
    for (int a = 0; a < 3; a++) {
      info->dims[a] = dims[a];
      info->spacing[a] = sp[a];
    }
    info->triangles = S.nt;
    info->max_move = S.max_move;
    info->seconds = mx_wtime() - t0;
    const mx_label_fix_stats *f = &info->fix;
    if (f->cavities)
      mx_warning(name, 0, "%zu enclosed background region(s) (%zu voxels) meshed as the label "
                          "around them (several materials have no holes)",
                 f->cavities, f->cavity_voxels);
    if (f->contact_voxels)
      mx_warning(name, 0, "%zu voxel(s) relabelled where labels met only along an edge or at "
                          "a point (the first at voxel (%lld, %lld, %lld))",
                 f->contact_voxels, (long long)f->contact_at[0], (long long)f->contact_at[1],
                 (long long)f->contact_at[2]);
  }
  mx_label_surface_free(&S);
  return st;
}

int mx_mesher_add_label_image(mx_mesher *m, const char *path, const mx_image_params *ip) {
  mx_label_image img;
  memset(&img, 0, sizeof img);
  int st = mx_read_label_image(path, &img);
  if (!st) {
    mx_image_info *info = &m->image;
    snprintf(info->format, sizeof info->format, "%s", img.format);
    info->oblique = img.oblique;
    info->rounded = img.rounded;
    if (img.oblique)
      mx_warning(path, 0, "the voxel-to-world transform is oblique: the mesh is rotated with it");
    const int64_t dims[3] = {img.nx, img.ny, img.nz};
    st = mx_mesher_add_label_array(m, path, img.label, dims, img.A, ip);
    if (!st) mx_mesher_note_read(m, path, 0);
  }
  mx_label_image_free(&img);
  return st;
}
