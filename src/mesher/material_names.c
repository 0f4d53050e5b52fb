/* Several materials: their numbers and names, the user's
 * (mx_mesher_set_material) or the defaults (mesher/materials.h). */
#include <stdio.h>
#include <string.h>

#include "base/common.h"
#include "mesher/materials.h"
#include "mesher/mesher_impl.h"

int mx_material_name(const mx_mesher *m, int d, char *buf, size_t n) {
  if (d >= 1 && d <= 64 && m->depth_material_name[d]) {
    snprintf(buf, n, "%s", m->depth_material_name[d]);
    return MX_OK;
  }
  snprintf(buf, n, "material %d", d >= 1 && d <= 64 ? m->depth_material[d] : d);
  /* the input file whose pieces bound region d (one region per file and
   * depth: the pieces of region d are one file's) */
  const mx_interfaces *I = &m->IF;
  int file = -1;
  for (uint32_t q = 0; q < I->npieces && file < 0; q++)
    if (I->region[q] == d) file = I->file[q];
  if (file < 0 || file >= m->ndomain) return MX_OK;
  for (uint32_t q = 0; q < I->npieces; q++) /* that file's pieces all bound region d */
    if (I->file[q] == file && I->region[q] != d) return MX_OK;
  const char *path = m->domain_name[file];
  const char *slash = strrchr(path, '/');
  const char *base = slash ? slash + 1 : path;
  while (*base == '-') base++; /* "--demo" */
  /* the extension goes; a region of one file ("brain.off region 2",
   * material_complex.c) keeps what follows it */
  const char *space = strchr(base, ' ');
  const char *dot = base;
  for (const char *c = base; *c && (!space || c < space); c++)
    if (*c == '.') dot = c;
  const int len = dot > base ? (int)(dot - base) : space ? (int)(space - base) : (int)strlen(base);
  snprintf(buf, n, "%.*s%s", len, base, space ? space : "");
  return MX_OK;
}

int mx_mesher_set_material(mx_mesher *m, int input, int number, const char *name) {
  mx_call c;
  mx_call_begin(m, &c);
  int st = MX_OK;
  if (input < 0 || input >= m->ndomain) {
    mx_error(NULL, 0, "material: no input %d (%d surface(s) added)", input, m->ndomain);
    st = MX_EINPUT;
  } else if (number < 1 || number > 65535) {
    mx_error(NULL, 0, "material: number %d for %s out of 1 .. 65535", number,
             m->domain_name[input]);
    st = MX_EINPUT;
  }
  char *copy = NULL;
  if (!st && name && !(copy = mx_strdup(name))) st = MX_ENOMEM;
  if (!st) {
    mx_free(m->input_material_name[input]);
    m->input_material_name[input] = copy;
    m->input_material[input] = number;
  }
  return mx_call_end(m, &c, st);
}

/* The numbers and names of the materials by region index
 * (m->depth_material*): the user's for the inputs given one, the index
 * otherwise. MX_EINPUT when an input's pieces bound several regions (its
 * shells nest at several depths) or two materials end with one number. */
int mx_material_numbers(mx_mesher *m, int deepest) {
  const mx_interfaces *I = &m->IF;
  for (int d = 0; d <= 64; d++) {
    m->depth_material[d] = d;
    m->depth_material_name[d] = NULL;
  }
  for (int k = 0; k < m->ndomain && k < 64; k++) {
    if (!m->input_material[k]) continue;
    int region = -1, depth = -1;
    for (uint32_t q = 0; q < I->npieces; q++) {
      if (I->file[q] != k) continue;
      if (region >= 0 && I->region[q] != region) {
        mx_error(m->domain_name[k], 0, "material %d: the shells of this input nest at "
                                       "several depths (%d and %d): the material inside it is "
                                       "not one region", m->input_material[k], depth,
                 (int)I->depth[q]);
        return MX_EINPUT;
      }
      region = I->region[q];
      depth = I->depth[q];
    }
    if (region < 1 || region > 64) continue;
    m->depth_material[region] = m->input_material[k];
    if (m->input_material_name[k]) m->depth_material_name[region] = m->input_material_name[k];
  }
  for (int a = 1; a <= deepest && a <= 64; a++)
    for (int b = a + 1; b <= deepest && b <= 64; b++)
      if (m->depth_material[a] == m->depth_material[b]) {
        mx_error(NULL, 0, "materials: the regions %d and %d are both numbered %d; "
                          "give each its own number", a, b, m->depth_material[a]);
        return MX_EINPUT;
      }
  return MX_OK;
}
