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
#include "geom/affine.h"
#include "geom/label_fix.h"
#include "io/read_image.h"
#include "base/morton.h"
#include "kernels/estimate.h"
#include "mesher/mesher_impl.h"

void mx_image_params_default(mx_image_params *ip) {
  memset(ip, 0, sizeof *ip);
  ip->smooth_rounds = -1;
}

void mx_image_params_release(mx_image_params *ip) {
  mx_free((void *)ip->skip);
  mx_free((void *)ip->merge);
  mx_free((void *)ip->label_names);
  mx_free((void *)ip->label_size);
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
    c.label_size = NULL;
    if (ip->nskip < 0 || ip->nmerge < 0 || ip->nlabel_size < 0 || (ip->nskip && !ip->skip) ||
        (ip->nmerge && !ip->merge) || (ip->nlabel_size && !ip->label_size)) {
      mx_error(NULL, 0, "image options: bad label lists");
      return MX_EINPUT;
    }
    int32_t *sk = ip->nskip ? mx_alloc((size_t)ip->nskip * sizeof *sk) : NULL;
    int32_t *mg = ip->nmerge ? mx_alloc((size_t)ip->nmerge * 2 * sizeof *mg) : NULL;
    char *names = ip->label_names ? mx_strdup(ip->label_names) : NULL;
    int32_t *ls = ip->nlabel_size ? mx_alloc((size_t)ip->nlabel_size * 2 * sizeof *ls) : NULL;
    if ((ip->nskip && !sk) || (ip->nmerge && !mg) || (ip->label_names && !names) ||
        (ip->nlabel_size && !ls)) {
      mx_free(sk);
      mx_free(mg);
      mx_free(names);
      mx_free(ls);
      return MX_ENOMEM;
    }
    if (ls) memcpy(ls, ip->label_size, (size_t)ip->nlabel_size * 2 * sizeof *ls);
    c.label_size = ls;
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

/* The names of labels L[0 .. nl) (names[k], "label L" by default) from a
 * lookup-table file read once: lines "L NAME ...", '#' comments; a line
 * that does not start with a label is an error while a label is still
 * unnamed. MX_EINPUT. */
static int label_names(const char *path, const int32_t *L, int nl, char (*names)[64]) {
  for (int k = 0; k < nl; k++) snprintf(names[k], 64, "label %d", (int)L[k]);
  if (!path) return MX_OK;
  FILE *f = fopen(path, "r");
  if (!f) {
    mx_error(path, 0, "cannot open the label names");
    return MX_EINPUT;
  }
  char line[1024];
  long no = 0;
  int st = MX_OK, left = nl;
  uint8_t named[64] = {0};
  while (left && fgets(line, sizeof line, f)) {
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
    int k = 0;
    while (k < nl && (L[k] != v || named[k])) k++;
    if (k == nl) continue;
    named[k] = 1;
    left--;
    s = end;
    while (isspace((unsigned char)*s)) s++;
    size_t len = 0;
    while (s[len] && !isspace((unsigned char)s[len])) len++;
    if (len) snprintf(names[k], 64, "%.*s", (int)len, s);
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

/* hist[L]: voxels of label L, hist[65536 + L]: its voxel faces on an
 * interface; per-thread histograms summed (the same whatever the threads).
 * MX_ENOMEM. */
static int label_histogram(const int32_t *lab, double total, const int64_t n[3],
                           uint64_t *hist) {
  memset(hist, 0, 2 * 65536 * sizeof *hist);
  int oom = 0;
#pragma omp parallel
  {
    uint64_t *h = mx_calloc(2 * 65536 * sizeof *h);
    if (!h) {
#pragma omp atomic write
      oom = 1;
    }
    const int64_t st3[3] = {1, n[0], n[0] * n[1]};
#pragma omp for schedule(static)
    for (int64_t v = 0; v < (int64_t)total; v++) {
      if (!h) continue;
      const int32_t a = lab[v];
      h[a]++;
      for (int x = 0; x < 3; x++) {
        const int64_t w = v + st3[x];
        if (w < (int64_t)total && lab[w] != a) {
          h[65536 + a]++;
          h[65536 + lab[w]]++;
        }
      }
    }
    if (h) {
#pragma omp critical
      for (int k = 0; k < 2 * 65536; k++) hist[k] += h[k];
    }
    mx_free(h);
  }
  return oom ? MX_ENOMEM : MX_OK;
}

/* The octree of the image's lattice: grid (roots of 2^R voxels from the
 * image's first corner, in voxel units: x = i - 0.5 at the voxel's low
 * face), and the leaves whose ancestors must be split: blocks of one
 * label, found by halving (a pyramid of "one label or -1" per level, from
 * the voxels up). MX_ENOMEM. */
/* A block of one label is split further while it is coarser than its
 * label asks (want) or, with a size field F, wider in the world than the
 * least size the field takes over its world box (A: voxels to the world),
 * down to the voxels. */
static int finer(const mx_size_field *F, const double A[12], int R, int l, const int64_t b[3]) {
  if (!F) return 0;
  const double side = (double)((int64_t)1 << (R - l));
  double wide = 0.0, ulo[3], uhi[3], lo[3], hi[3];
  for (int a = 0; a < 3; a++) {
    wide = fmax(wide, side * mx_affine_column(A, a));
    ulo[a] = (double)b[a] * side - 0.5;
    uhi[a] = ulo[a] + side;
  }
  mx_affine_box(A, ulo, uhi, lo, hi);
  return wide > mx_size_field_min_box(F, lo, hi);
}

static int lattice_leaves(const int32_t *lab, const int64_t n[3], int R, const int dims[3],
                          const uint8_t *want, const mx_size_field *F, const double A[12],
                          uint64_t **key_out, uint8_t **level_out, size_t *nleaves) {
  int64_t D[16][3];
  int32_t *pyr[16] = {NULL};
  int st = MX_OK;
  for (int l = 0; l <= R; l++)
    for (int a = 0; a < 3; a++) D[l][a] = (int64_t)dims[a] << l;
  /* level R: the voxels (outside the image: background) */
  for (int l = R; l >= 0 && !st; l--) {
    const size_t sz = (size_t)(D[l][0] * D[l][1] * D[l][2]);
    pyr[l] = mx_alloc((sz + 1) * sizeof *pyr[l]);
    if (!pyr[l]) {
      st = MX_ENOMEM;
      break;
    }
    int32_t *P = pyr[l];
#pragma omp parallel for schedule(static)
    for (int64_t k = 0; k < D[l][2]; k++)
      for (int64_t j = 0; j < D[l][1]; j++)
        for (int64_t i = 0; i < D[l][0]; i++) {
          int32_t v;
          if (l == R) {
            const int in = i < n[0] - 2 && j < n[1] - 2 && k < n[2] - 2;
            v = in ? lab[(i + 1) + n[0] * ((j + 1) + n[1] * (k + 1))] : 0;
          } else {
            const int32_t *C = pyr[l + 1];
            v = C[(2 * i) + D[l + 1][0] * ((2 * j) + D[l + 1][1] * (2 * k))];
            for (int c = 1; c < 8 && v >= 0; c++) {
              const int64_t x = 2 * i + (c & 1), y = 2 * j + ((c >> 1) & 1), z = 2 * k + (c >> 2);
              if (C[x + D[l + 1][0] * (y + D[l + 1][1] * z)] != v) v = -1;
            }
          }
          P[i + D[l][0] * (j + D[l][1] * k)] = v;
        }
  }
  /* the leaves, depth first from each root */
  size_t cap = 4096, nl = 0;
  uint64_t *key = st ? NULL : mx_alloc(cap * sizeof *key);
  uint8_t *lev = st ? NULL : mx_alloc(cap);
  if (!st && (!key || !lev)) st = MX_ENOMEM;
  typedef struct {
    int64_t b[3];
    int l;
  } blk;
  blk stack[16 * 8];
  for (int64_t r = 0; !st && r < (int64_t)dims[0] * dims[1] * dims[2]; r++) {
    int sp = 0;
    stack[sp++] = (blk){{r % dims[0], (r / dims[0]) % dims[1], r / ((int64_t)dims[0] * dims[1])}, 0};
    while (sp && !st) {
      const blk q = stack[--sp];
      const int32_t v = pyr[q.l][q.b[0] + D[q.l][0] * (q.b[1] + D[q.l][1] * q.b[2])];
      if ((v >= 0 && q.l >= want[v] && !finer(F, A, R, q.l, q.b)) || q.l == R) {
        if (q.l == 0) continue; /* a root of one label: nothing to split */
        if (nl == cap) {
          uint64_t *k2 = mx_realloc(key, 2 * cap * sizeof *key);
          uint8_t *l2 = k2 ? mx_realloc(lev, 2 * cap) : NULL;
          if (k2) key = k2;
          if (l2) lev = l2;
          if (!k2 || !l2) {
            st = MX_ENOMEM;
            break;
          }
          cap *= 2;
        }
        const int sh = MX_MAX_LEVEL - q.l;
        key[nl] = mx_morton_encode((uint32_t)(q.b[0] << sh), (uint32_t)(q.b[1] << sh),
                                   (uint32_t)(q.b[2] << sh));
        lev[nl++] = (uint8_t)q.l;
        continue;
      }
      for (int c = 7; c >= 0; c--)
        stack[sp++] = (blk){{2 * q.b[0] + (c & 1), 2 * q.b[1] + ((c >> 1) & 1), 2 * q.b[2] + (c >> 2)},
                            q.l + 1};
    }
  }
  for (int l = 0; l <= R; l++) mx_free(pyr[l]);
  if (st) {
    mx_free(key);
    mx_free(lev);
    return st;
  }
  *key_out = key;
  *level_out = lev;
  *nleaves = nl;
  return MX_OK;
}

/* The memory budget (--max-memory, or what the machine has): MX_ENOMEM
 * with a message when need bytes do not fit. */
static int image_budget(const mx_mesher *m, const char *name, double need, const char *what) {
  const double avail = mx_available_bytes() + mx_peak_rss_mb() * 1048576.0;
  const double limit = m->p.max_memory_mb > 0 ? m->p.max_memory_mb * 1048576.0 : avail;
  if (limit > 0.0 && need > limit) {
    mx_error(name, 0, "this image needs about %.0f MB (%s) but %s %.0f MB: crop it, merge "
                      "labels, or raise --max-memory", need / 1048576.0, what,
             m->p.max_memory_mb > 0 ? "--max-memory allows" : "the machine has",
             limit / 1048576.0);
    return MX_ENOMEM;
  }
  return MX_OK;
}

/* The image's box, [-0.5, d - 0.5] in voxel units, as the domain surface
 * the octree is built in (outward triangles). */
static int add_box(mx_mesher *m, const char *name, const int64_t d[3]) {
  mx_trisoup s;
  memset(&s, 0, sizeof s);
  int st = mx_trisoup_reserve(&s, 8, 12);
  for (int c = 0; c < 8 && !st; c++) {
    const double p[3] = {(c & 1) ? (double)d[0] - 0.5 : -0.5, (c & 2) ? (double)d[1] - 0.5 : -0.5,
                         (c & 4) ? (double)d[2] - 0.5 : -0.5};
    st = mx_trisoup_set_vertex(&s, (size_t)c, p);
  }
  static const uint32_t q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                   {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (int f = 0; f < 6 && !st; f++) {
    st = mx_trisoup_add_triangle(&s, q[f][0], q[f][1], q[f][2]);
    if (!st) st = mx_trisoup_add_triangle(&s, q[f][0], q[f][2], q[f][3]);
  }
  if (!st) st = mx_mesher_add_domain(m, &s, name);
  mx_trisoup_free(&s);
  return st;
}

static int add_label_array(mx_mesher *m, const char *name, const int32_t *labels,
                           const int64_t dims[3], const double A[12],
                           const mx_image_params *ip) {
  const double t0 = mx_wtime();
  if (!ip) ip = &m->image_params;
  if (!name) name = "(label array)";
  if (!labels || !dims || !A) {
    mx_error(name, 0, "label image: no voxels or no transform given");
    return MX_EINPUT;
  }
  if (m->p.surface_level >= 0 || m->p.all_level >= 0) {
    mx_error(name, 0, "a label image is refined to its voxels at the interfaces and as coarse "
                      "as balance allows inside: no surface or all level (-s, -a) with it");
    return MX_EINPUT;
  }
  if (m->ndomain > 0 || m->image_lattice) {
    mx_error(name, 0, "a label image is meshed alone: no other image or surface with it");
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
  const double det = mx_affine_det(A);
  double sp[3];
  for (int a = 0; a < 3; a++) sp[a] = mx_affine_column(A, a);
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
  /* the labels (4 bytes a voxel), the pyramid (about 4.6), the smoothing's
   * corner map (4) */
  MX_CHECK(image_budget(m, name, 13.0 * total, "its voxels"));
  int32_t *lab = mx_calloc((size_t)total * sizeof *lab);
  if (!lab) return MX_ENOMEM;
  mx_image_info *info = &m->image;
  memset(&info->fix, 0, sizeof info->fix);
  int st = map_labels(name, labels, dims, ip, lab, n);
  if (!st && ip->min_island > 1)
    st = mx_labels_drop_islands(lab, n, (size_t)ip->min_island, &info->fix);
  /* more than 64 labels refused before the contacts' repair, which ranks
   * them by their voxels */
  uint64_t *h = st ? NULL : mx_alloc(2 * 65536 * sizeof *h);
  if (!st) st = h ? label_histogram(lab, total, n, h) : MX_ENOMEM;
  int present = 0;
  for (int32_t a = 1; !st && a < 65536; a++) present += h[a] != 0;
  if (!st && present > 64) {
    mx_error(name, 0, "label image: %d labels, at most 64; merge or skip some (is this a "
                      "segmentation? an intensity image has thousands of values)", present);
    st = MX_EINPUT;
  }
  if (!st) st = mx_labels_fix_contacts(lab, n, h, name, &info->fix);
  mx_free(h);
  /* the labels left, their voxels and their voxel faces on an interface
   * (the volume's tolerance); at most 64 (checked before the contacts'
   * repair too, which ranks the labels) */
  int nl = 0;
  int32_t L[64];
  size_t cnt[64];
  uint64_t *hist = st ? NULL : mx_alloc(2 * 65536 * sizeof *hist);
  if (!st && !hist) st = MX_ENOMEM;
  if (!st) st = label_histogram(lab, total, n, hist);
  for (int32_t a = 1; !st && a < 65536; a++) {
    if (!hist[a]) continue;
    if (nl == 64) {
      mx_error(name, 0, "label image: more than 64 labels; merge or skip some");
      st = MX_EINPUT;
      break;
    }
    L[nl] = a;
    info->faces[nl] = hist[65536 + a];
    cnt[nl++] = hist[a];
  }
  mx_free(hist);
  if (!st && nl == 0) {
    mx_error(name, 0, "label image: no voxel of any label (all background)");
    st = MX_EINPUT;
  }
  /* the lattice: roots of 2^R voxels, at most 4 along the longest axis */
  int64_t dmax = dims[0] > dims[1] ? dims[0] : dims[1];
  dmax = dmax > dims[2] ? dmax : dims[2];
  int R = 0;
  while (((int64_t)4 << R) < dmax) R++;
  if (!st && R > MX_MAX_LEVEL - 2) {
    mx_error(name, 0, "label image: too many voxels along an axis for the octree");
    st = MX_EINPUT;
  }
  mx_grid g;
  memset(&g, 0, sizeof g);
  g.side = (double)((int64_t)1 << R);
  g.unit = g.side / (double)(1u << MX_MAX_LEVEL);
  for (int a = 0; a < 3; a++) {
    g.origin[a] = -0.5;
    g.dims[a] = (int)((dims[a] + ((int64_t)1 << R) - 1) >> R);
  }
  /* the level each label asks inside it (--label-size: 2^(R - level) voxels) */
  uint8_t *want = st ? NULL : mx_calloc(65536);
  if (!st && !want) st = MX_ENOMEM;
  for (int t = 0; !st && t < ip->nlabel_size; t++) {
    const int32_t Lb = ip->label_size[2 * t], S = ip->label_size[2 * t + 1];
    if (Lb < 1 || Lb > 65535 || S < 1) {
      mx_error(name, 0, "label size %d:%d: a label 1 .. 65535 and a size of 1 voxel or more",
               (int)Lb, (int)S);
      st = MX_EINPUT;
      break;
    }
    int l = R;
    while (l > 0 && ((int64_t)1 << (R - l + 1)) <= S) l--;
    want[Lb] = (uint8_t)l;
  }
  if (!st) st = add_box(m, name, dims);
  if (st) {
    mx_free(want);
    mx_free(lab);
    return st;
  }
  mx_free(m->image_want);
  m->image_want = want;
  /* materials: label k + 1 .. as the user's numbers and names */
  st = label_names(ip->label_names, L, nl, info->names);
  for (int k = 0; k < nl && !st; k++) {
    m->depth_material[k + 1] = L[k];
    m->depth_material_name[k + 1] = info->names[k];
  }
  if (st) {
    mx_free(lab);
    return st;
  }
  m->image_lattice = 1;
  m->image_lab = lab;
  for (int a = 0; a < 3; a++) m->image_n[a] = n[a];
  memcpy(m->image_A, A, sizeof m->image_A);
  m->image_R = R;
  m->image_grid = g;
  m->image_rounds = ip->voxel ? 0 : ip->smooth_rounds < 0 ? 10 : ip->smooth_rounds;
  m->p.materials = 0;      /* labels, not the surfaces' regions */
  m->nmaterials = nl;
  info->nlabels = nl;
  for (int k = 0; k < nl; k++) {
    info->labels[k] = L[k];
    info->voxels[k] = cnt[k];
  }
  for (int a = 0; a < 3; a++) {
    info->dims[a] = dims[a];
    info->spacing[a] = sp[a];
  }
  info->seconds = mx_wtime() - t0;
  const mx_label_fix_stats *f = &info->fix;
  if (f->contact_voxels)
    mx_warning(name, 0, "%zu voxel(s) relabelled where labels met only along an edge or at "
                        "a point (the first at voxel (%lld, %lld, %lld))",
               f->contact_voxels, (long long)f->contact_at[0], (long long)f->contact_at[1],
               (long long)f->contact_at[2]);
  if (f->islands)
    mx_warning(name, 0, "%zu island(s) of fewer than %lld voxels (%zu voxels) given the label "
                        "around them", f->islands, ip->min_island, f->island_voxels);
  return MX_OK;
}

void mx_image_world_box(const mx_mesher *m, double lo[3], double hi[3]) {
  double ulo[3], uhi[3];
  for (int a = 0; a < 3; a++) {
    ulo[a] = -0.5;
    uhi[a] = (double)(m->image_n[a] - 2) - 0.5;
  }
  mx_affine_box(m->image_A, ulo, uhi, lo, hi);
}

int mx_image_split_keys(mx_mesher *m) {
  const char *name = m->domain_name[0];
  if (m->size_curvature > 0.0 || m->size_thickness > 0.0) {
    mx_error(name, 0, "a label image has no input surface: --curvature and --thickness do "
                      "not apply (a size field --size does)");
    return MX_EINPUT;
  }
  const mx_size_field *F = (m->size_F.cs || m->size_F.src) ? &m->size_F : NULL;
  uint64_t *key = NULL;
  uint8_t *lev = NULL;
  size_t nleaves = 0;
  int st = lattice_leaves(m->image_lab, m->image_n, m->image_R, m->image_grid.dims,
                          m->image_want, F, m->image_A, &key, &lev, &nleaves);
  /* the mesh from the leaves (balance adds about a sixth), the labels kept,
   * with a fifth more (the brain of 256^3: 703 MB against 707 estimated) */
  const double total = (double)m->image_n[0] * (double)m->image_n[1] * (double)m->image_n[2];
  if (!st)
    st = image_budget(m, name,
                      1.2 * (mx_estimate_bytes_leaves((size_t)(1.2 * (double)nleaves), 12,
                                                      MX_STAGE_FULL) + 8.0 * total),
                      "its octree's leaves and voxels");
  if (!st && nleaves) st = mx_mesher_set_split_keys(m, key, lev, nleaves);
  mx_free(key);
  mx_free(lev);
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

int mx_mesher_add_label_array(mx_mesher *m, const char *name, const int32_t *labels,
                              const int64_t dims[3], const double A[12],
                              const mx_image_params *ip) {
  mx_call c; /* messages to the mesher's handler, not to stderr */
  mx_call_begin(m, &c);
  return mx_call_end(m, &c, add_label_array(m, name, labels, dims, A, ip));
}
