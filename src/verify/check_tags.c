/* Pass 5b of the checker, boundary tags: every tagged face of the mesh
 * (its list of tagged faces, io/read_mesh.h) is looked up among the faces
 * of the elements (the buckets of check_faces.c): a tagged face that is not
 * a boundary face (unless the cells carry labels and it lies between two
 * cells of different labels: an interface between materials), a boundary
 * face that no tagged face names. When asked,
 * the tags one by one: faces sorted by tag, each tag's edges sorted and
 * counted (its open edges), and the node tags' values with their counts;
 * names from the file's list. */
#include "verify/check_passes.h"

#include "base/scan.h"

/* A sort key of tag t ordering tags as signed integers, with v below. */
static inline uint64_t tag_key(int32_t t, uint32_t v) {
  return (uint64_t)((uint32_t)t ^ 0x80000000u) << 32 | v;
}

static inline int32_t key_tag(uint64_t k) {
  return (int32_t)((uint32_t)(k >> 32) ^ 0x80000000u);
}

/* The names of m sorted by tag (keys as tag_key(tag, index)), or NULL. */
static int sorted_names(const mx_mesh_data *m, uint64_t **out) {
  *out = NULL;
  if (!m->nnames || !m->name || !m->name_tag || m->nnames >= UINT32_MAX)
    return MX_OK;
  uint64_t *k = mx_alloc(m->nnames * sizeof *k);
  if (!k) return MX_ENOMEM;
  for (size_t i = 0; i < m->nnames; i++) k[i] = tag_key(m->name_tag[i], (uint32_t)i);
  const int st = mx_sort_u64(k, NULL, m->nnames);
  if (st != MX_OK) {
    mx_free(k);
    return st;
  }
  *out = k;
  return MX_OK;
}

/* The name of tag t (its first in the file), or NULL. */
static const char *tag_name(const mx_mesh_data *m, const uint64_t *k,
                            int32_t t) {
  if (!k) return NULL;
  size_t lo = 0, hi = m->nnames;
  const uint64_t want = tag_key(t, 0);
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (k[mid] < want)
      lo = mid + 1;
    else
      hi = mid;
  }
  if (lo == m->nnames || key_tag(k[lo]) != t) return NULL;
  return m->name[(uint32_t)k[lo]];
}

/* Copies the names of the listed tags into tags->names. */
static int keep_names(mx_check_tag *list, size_t n, mx_check_tags *tags) {
  size_t total = 1;
  for (size_t i = 0; i < n; i++)
    if (list[i].name) total += strlen(list[i].name) + 1;
  char *buf = mx_alloc(total);
  if (!buf) return MX_ENOMEM;
  size_t at = 0;
  for (size_t i = 0; i < n; i++) {
    if (!list[i].name) continue;
    const size_t l = strlen(list[i].name) + 1;
    memcpy(buf + at, list[i].name, l);
    list[i].name = buf + at;
    at += l;
  }
  tags->names = buf;
  return MX_OK;
}

/* The tags of the tagged faces, with their counts: faces sorted by tag,
 * then per tag its edges sorted and counted. bad[i]: face i is not a
 * boundary face. */
static int face_tag_list(const mx_mesh_data *m, const uint8_t *bad,
                         const uint64_t *names, mx_check_tag **out,
                         size_t *nout) {
  const size_t nf = m->nfaces;
  uint64_t *k = mx_alloc((nf + 1) * sizeof *k);
  uint64_t *ek = mx_alloc((4 * nf + 1) * sizeof *ek);
  if (!k || !ek) {
    mx_free(k);
    mx_free(ek);
    return MX_ENOMEM;
  }
  for (size_t i = 0; i < nf; i++) k[i] = tag_key(m->face_tag[i], (uint32_t)i);
  int st = mx_sort_u64(k, NULL, nf);
  size_t nt = 0;
  for (size_t i = 0; st == MX_OK && i < nf; i++)
    nt += i == 0 || key_tag(k[i]) != key_tag(k[i - 1]);
  mx_check_tag *list = st == MX_OK ? mx_calloc((nt + 1) * sizeof *list) : NULL;
  if (st == MX_OK && !list) st = MX_ENOMEM;
  size_t t = 0;
  for (size_t a = 0; st == MX_OK && a < nf; t++) {
    size_t b = a + 1;
    while (b < nf && key_tag(k[b]) == key_tag(k[a])) b++;
    mx_check_tag *g = &list[t];
    g->tag = key_tag(k[a]);
    g->name = tag_name(m, names, g->tag);
    size_t ne = 0;
    for (size_t x = a; x < b; x++) {
      const size_t f = (uint32_t)k[x];
      const int n = m->face_nn[f];
      const uint32_t *v = m->face_conn + 4 * f;
      g->triangles += n == 3;
      g->quads += n == 4;
      g->not_boundary += bad[f];
      for (int j = 0; j < n; j++) {
        const uint32_t p = v[j], q = v[(j + 1) % n];
        ek[ne++] = p < q ? (uint64_t)p << 32 | q : (uint64_t)q << 32 | p;
      }
    }
    st = mx_sort_u64(ek, NULL, ne);
    for (size_t i = 0; st == MX_OK && i < ne;) {
      size_t j = i + 1;
      while (j < ne && ek[j] == ek[i]) j++;
      g->open_edges += (j - i) % 2;
      i = j;
    }
    a = b;
  }
  mx_free(k);
  mx_free(ek);
  if (st != MX_OK) {
    mx_free(list);
    return st;
  }
  *out = list;
  *nout = nt;
  return MX_OK;
}

/* The values of the node tags but 0, with their node counts. */
static int node_tag_list(const mx_mesh_data *m, const uint64_t *names,
                         mx_check_tag **out, size_t *nout) {
  const size_t nn = m->nnodes;
  uint64_t *k = mx_alloc((nn + 1) * sizeof *k);
  if (!k) return MX_ENOMEM;
#pragma omp parallel for schedule(static) if (nn > SMALL)
  for (size_t i = 0; i < nn; i++) k[i] = tag_key(m->node_tag[i], 0);
  int st = mx_sort_u64(k, NULL, nn);
  size_t nt = 0;
  for (size_t i = 0; st == MX_OK && i < nn; i++)
    nt += (i == 0 || k[i] != k[i - 1]) && key_tag(k[i]) != 0;
  mx_check_tag *list = st == MX_OK ? mx_calloc((nt + 1) * sizeof *list) : NULL;
  if (st == MX_OK && !list) st = MX_ENOMEM;
  size_t t = 0;
  for (size_t a = 0; st == MX_OK && a < nn;) {
    size_t b = a + 1;
    while (b < nn && k[b] == k[a]) b++;
    if (key_tag(k[a]) != 0) {
      list[t].tag = key_tag(k[a]);
      list[t].name = tag_name(m, names, list[t].tag);
      list[t++].nodes = b - a;
    }
    a = b;
  }
  mx_free(k);
  if (st != MX_OK) {
    mx_free(list);
    return st;
  }
  *out = list;
  *nout = nt;
  return MX_OK;
}

/* Matches every tagged face with the faces of the elements (the buckets of
 * faces_match): the tagged faces that are not boundary faces, the boundary
 * faces no tagged face names; then, when tags is not NULL, the per-tag
 * lists. */
int mx_ck_tag_pass(const mx_mesh_data *m, const faces *F,
                    mx_check_report *r, mx_check_tags *tags) {
  const size_t nf = m->nfaces, nslots = 6 * m->ncells;
  r->has_node_tags = m->node_tag != NULL;
  r->has_tagged_faces = nf > 0;
  r->tagged_faces = nf;
  if (!nf && !(tags && m->node_tag)) return MX_OK;
  uint8_t *named = mx_calloc(nslots + 1); /* boundary slot named by a face */
  uint8_t *bad = mx_alloc(nf + 1);       /* tagged face not a boundary face */
  if (!named || !bad) {
    mx_free(named);
    mx_free(bad);
    return MX_ENOMEM;
  }
  size_t nb = 0, ni = 0;
#pragma omp parallel for schedule(dynamic, 1024) reduction(+ : nb, ni) \
    if (nf > SMALL)
  for (size_t i = 0; i < nf; i++) {
    uint32_t v[4];
    const int n = m->face_nn[i];
    memcpy(v, m->face_conn + 4 * i, sizeof v);
    sort4(v, n);
    const int64_t s = mx_ck_find_slot(m, F, v, n);
    const int ok = s >= 0 && F->use[s] == 1;
    /* with cell labels (several materials), a face of two cells of
     * different labels is an interface: tagged rightly */
    int between = 0;
    if (!ok && s >= 0 && F->use[s] == 2 && m->cell_tag) {
      const int64_t s2 = mx_ck_find_second(m, F, v, n);
      between = s2 >= 0 && m->cell_tag[s / 6] != m->cell_tag[s2 / 6];
    }
    bad[i] = (uint8_t)!(ok || between);
    nb += !(ok || between);
    ni += between;
    if (ok) __atomic_store_n(&named[s], 1, __ATOMIC_RELAXED);
  }
  r->tagged_not_boundary = nb;
  r->tagged_interface = ni;
  size_t un = 0;
  if (nf) {
#pragma omp parallel for schedule(static) reduction(+ : un) \
    if (nslots > SMALL)
    for (size_t s = 0; s < nslots; s++) un += F->use[s] == 1 && !named[s];
  }
  r->boundary_untagged = un;
  mx_check_ids *l = &r->not_boundary_ids;
  for (size_t i = 0; i < nf && nb && l->n < MX_CHECK_LIST; i++)
    if (bad[i]) l->id[l->n++] = (uint32_t)i;
  l = &r->untagged_ids;
  for (size_t s = 0; s < nslots && un && l->n < MX_CHECK_LIST; s++)
    if (F->use[s] == 1 && !named[s] &&
        (l->n == 0 || l->id[l->n - 1] != (uint32_t)(s / 6)))
      l->id[l->n++] = (uint32_t)(s / 6);
  mx_free(named);
  int st = MX_OK;
  if (tags) {
    uint64_t *names = NULL;
    st = sorted_names(m, &names);
    if (st == MX_OK && nf)
      st = face_tag_list(m, bad, names, &tags->face_tags, &tags->nface_tags);
    if (st == MX_OK && m->node_tag)
      st = node_tag_list(m, names, &tags->node_tags, &tags->nnode_tags);
    mx_free(names);
    mx_check_tag *all = NULL;
    const size_t n = tags->nface_tags + tags->nnode_tags;
    if (st == MX_OK && n) { /* both lists' names in one buffer */
      all = mx_alloc(n * sizeof *all);
      if (!all) st = MX_ENOMEM;
    }
    if (all) {
      if (tags->nface_tags)
        memcpy(all, tags->face_tags, tags->nface_tags * sizeof *all);
      if (tags->nnode_tags)
        memcpy(all + tags->nface_tags, tags->node_tags,
               tags->nnode_tags * sizeof *all);
      st = keep_names(all, n, tags);
      for (size_t i = 0; st == MX_OK && i < tags->nface_tags; i++)
        tags->face_tags[i].name = all[i].name;
      for (size_t i = 0; st == MX_OK && i < tags->nnode_tags; i++)
        tags->node_tags[i].name = all[tags->nface_tags + i].name;
      mx_free(all);
    }
  }
  mx_free(bad);
  return st;
}
