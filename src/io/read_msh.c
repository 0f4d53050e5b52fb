/* mixoct: reading Gmsh MSH 4.1, ASCII and binary (see read_mesh.h), in one
 * pass with the cursor of io/text_cursor.h; every count is checked against
 * the bytes left before anything is allocated for it.
 *
 * $MeshFormat "4.1 0|1 8" (binary: then the int 1 in the writer's byte
 * order, which tells a swapped file), $Nodes, $Elements, $Entities and
 * $PhysicalNames are read; every other section ($NodeData...) is skipped up
 * to its $End line. $Entities: four counts (points, curves, surfaces,
 * volumes), then per entity its tag, its coordinates (points 3, others a
 * box of 6), a count and that many physical tags, and for all but points a
 * count and that many bounding entities (binary: counts size_t, tags int,
 * coordinates double). $PhysicalNames (ASCII in both variants): a count,
 * then lines "dim tag \"name\"". Nodes come in blocks: dim tag parametric n, n tags, then n
 * coordinate lines (x y z, + dim parametric values when parametric);
 * elements in blocks: dim tag type n, then n lines "tag node-tags...".
 * Binary files use size_t (the data size of the format line, 4 or 8 bytes)
 * for counts and tags, int for dimensions, entity tags and types, doubles
 * for coordinates. Tetrahedra (type 4), hexahedra (5), prisms (6) and
 * pyramids (7) are kept, in the order of their tags (mixoct writes tag =
 * index + 1); triangles (2) and quadrangles (3) of blocks of dimension 2
 * are the tagged faces, their tag their entity's (read_mesh.h), in file
 * order; points, lines and other triangles and quadrangles are skipped;
 * any other type is refused. Node orders are Gmsh's, which are
 * mixoct's (soa/mesh.h). Node tags are mapped to indices by a direct table
 * when they are dense, else by a sorted one.
 *
 * Cell labels (cell_tag, several materials): a volume element's label is
 * the first physical tag of its volume entity in $Entities, or the entity
 * tag itself when that entity has no physical tag or is not listed (no
 * $Entities: every label is an entity tag). The labels follow the cells
 * into the order of their tags. cell_tag stays NULL when every volume
 * element has the same label (one volume entity, or one physical volume):
 * a single label tells no material from another, and a plain mesh (one
 * volume entity in one physical group, as mixoct writes it) stays
 * unlabelled, as in the other formats. A label must fit an int32. */
#include "io/mesh_reader.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "base/common.h"
#include "base/scan.h"
#include "io/face_tags.h"
#include "io/msh_reader.h"
#include "io/text_scan.h"

/* Appends the name s[0, n) of tag (capacity *cap, doubled). */
static int add_name(mx_mesh_data *out, size_t *cap, int32_t tag,
                    const char *s, size_t n) {
  if (out->nnames == *cap) {
    const size_t nc = *cap ? 2 * *cap : 16;
    int32_t *t = mx_realloc(out->name_tag, nc * sizeof *t);
    if (!t) return MX_ENOMEM;
    out->name_tag = t;
    char **nm = mx_realloc(out->name, nc * sizeof *nm);
    if (!nm) return MX_ENOMEM;
    out->name = nm;
    *cap = nc;
  }
  char *c = mx_alloc(n + 1);
  if (!c) return MX_ENOMEM;
  memcpy(c, s, n);
  c[n] = '\0';
  out->name_tag[out->nnames] = tag;
  out->name[out->nnames++] = c;
  return MX_OK;
}

/* The names sorted by tag, each tag once (the last name given to it). */
static int sort_names(mx_mesh_data *out) {
  const size_t n = out->nnames;
  if (n < 2) return MX_OK;
  uint64_t *k = mx_alloc(n * sizeof *k);
  int32_t *t = mx_alloc(n * sizeof *t);
  char **nm = mx_alloc(n * sizeof *nm);
  if (!k || !t || !nm) {
    mx_free(k);
    mx_free(t);
    mx_free(nm);
    return MX_ENOMEM;
  }
  for (size_t i = 0; i < n; i++)
    k[i] = (uint64_t)((uint32_t)out->name_tag[i] ^ 0x80000000u) << 32 | i;
  int st = mx_sort_u64(k, NULL, n);
  size_t m = 0;
  for (size_t i = 0; st == MX_OK && i < n; i++) {
    const size_t at = (size_t)(uint32_t)k[i];
    if (i + 1 < n && k[i + 1] >> 32 == k[i] >> 32) { /* named again later */
      mx_free(out->name[at]);
      out->name[at] = NULL;
      continue;
    }
    t[m] = out->name_tag[at];
    nm[m++] = out->name[at];
  }
  if (st != MX_OK) {
    mx_free(k);
    mx_free(t);
    mx_free(nm);
    return st;
  }
  mx_free(k);
  mx_free(out->name_tag);
  mx_free(out->name);
  out->name_tag = t;
  out->name = nm;
  out->nnames = m;
  return MX_OK;
}

/* Where the next value starts, for messages (text: after the blanks;
 * binary: here, blanks are data). */
static const char *msh_at(msh *M) {
  return M->binary ? M->c.p : cur_skip(&M->c);
}

static void msh_free(msh *M) {
  mx_free(M->ntag);
  mx_free(M->dense);
  mx_free(M->sorted);
  mx_free(M->sidx);
  mx_free(M->etag);
  mx_free(M->cent);
  mx_free(M->surf);
  mx_free(M->vol);
}

/* A size_t (binary) or a count (text). */
static int msh_size(msh *M, uint64_t *v, const char *what) {
  if (!M->binary) return cur_count(&M->c, v, 0, what);
  MX_CHECK(cur_need(&M->c, (uint64_t)M->dsize, what));
  *v = bin_u(&M->c, M->dsize);
  return MX_OK;
}

/* An int (binary) or an integer (text). */
static int msh_int(msh *M, int64_t *v, const char *what) {
  if (!M->binary) return cur_int(&M->c, v, what);
  MX_CHECK(cur_need(&M->c, 4, what));
  *v = (int32_t)(uint32_t)bin_u(&M->c, 4);
  return MX_OK;
}

/* The line "$End<name>" after a section (text and binary: the binary data
 * is followed by a newline). */
int mx_msh_end(msh *M, const char *name) {
  size_t n;
  const char *t = cur_tok(&M->c, &n);
  char want[64];
  snprintf(want, sizeof want, "$End%s", name);
  if (n != strlen(want) || memcmp(t, want, n) != 0)
    return mx_rd_fail(M->c.r, t, "expected %s, found '%.*s' (wrong count?)", want,
                      shown(n), t);
  return MX_OK;
}

static int msh_format(msh *M) {
  rd *r = M->c.r;
  size_t n;
  const char *t = cur_tok(&M->c, &n);
  M->v2 = tok_eq(t, n, "2.2");
  if (!M->v2 && !tok_eq(t, n, "4.1"))
    return mx_rd_fail(r, t,
                      "MSH version '%.*s' is not supported (4.1 or 2.2: gmsh "
                      "-format msh41)",
                      shown(n), t);
  int64_t ft = 0, ds = 0;
  MX_CHECK(cur_int(&M->c, &ft, "$MeshFormat file type"));
  MX_CHECK(cur_int(&M->c, &ds, "$MeshFormat data size"));
  if (ft != 0 && ft != 1)
    return mx_rd_fail(r, t, "$MeshFormat: file type %lld (0 ASCII, 1 binary)",
                      (long long)ft);
  if (ds != 4 && ds != 8 && !M->v2)
    return mx_rd_fail(r, t, "$MeshFormat: data size %lld (4 or 8)", (long long)ds);
  if (M->v2 && ds != 8)
    return mx_rd_fail(r, t, "$MeshFormat: data size %lld (MSH 2.2: 8, the size of a double)",
                      (long long)ds);
  M->binary = ft == 1;
  M->dsize = (int)ds;
  if (M->binary) {
    const char *p = M->c.p, *end = r->end;
    while (p < end && (*p == ' ' || *p == '\r' || *p == '\t')) p++;
    if (p >= end || *p != '\n')
      return mx_rd_fail(r, p, "$MeshFormat: expected the end of the line");
    M->c.p = p + 1;
    r->bin_from = M->c.p;
    MX_CHECK(cur_need(&M->c, 4, "$MeshFormat: the binary one"));
    const uint32_t one = (uint32_t)bin_u(&M->c, 4);
    if (one == 1)
      M->c.swap = 0;
    else if (one == 0x01000000u)
      M->c.swap = 1;
    else
      return mx_rd_fail(r, M->c.p - 4,
                        "$MeshFormat: the binary 1 reads as %u (not a binary MSH "
                        "file?)",
                        one);
  }
  return mx_msh_end(M, "MeshFormat");
}

static int msh_nodes(msh *M) {
  rd *r = M->c.r;
  if (M->have_nodes) return mx_rd_fail(r, M->c.p, "$Nodes given twice");
  M->have_nodes = 1;
  uint64_t nb = 0, nn = 0, tmin = 0, tmax = 0;
  const char *at = msh_at(M);
  MX_CHECK(msh_size(M, &nb, "$Nodes: number of blocks"));
  MX_CHECK(msh_size(M, &nn, "$Nodes: number of nodes"));
  MX_CHECK(msh_size(M, &tmin, "$Nodes: smallest tag"));
  MX_CHECK(msh_size(M, &tmax, "$Nodes: largest tag"));
  /* a node takes at least a tag and 3 doubles (binary), "1\n0 0 0\n" */
  const uint64_t least = M->binary ? (uint64_t)M->dsize + 24 : 8;
  if (nn >= UINT32_MAX || nn > cur_left(&M->c) / least + 1 ||
      nb > cur_left(&M->c) / 4 + 1)
    return mx_rd_fail(r, at,
                      "$Nodes: %llu nodes in %llu blocks announced but the file "
                      "is too short (truncated file or wrong count)",
                      (unsigned long long)nn, (unsigned long long)nb);
  M->nnodes = (size_t)nn;
  M->out->nnodes = (size_t)nn;
  M->out->xyz = mx_alloc((3 * (size_t)nn + 1) * sizeof(double));
  M->ntag = mx_alloc(((size_t)nn + 1) * sizeof *M->ntag);
  if (!M->out->xyz || !M->ntag) return MX_ENOMEM;
  size_t done = 0;
  for (uint64_t b = 0; b < nb; b++) {
    int64_t dim = 0, etag = 0, par = 0;
    uint64_t n = 0;
    at = msh_at(M);
    MX_CHECK(msh_int(M, &dim, "$Nodes block: entity dimension"));
    MX_CHECK(msh_int(M, &etag, "$Nodes block: entity tag"));
    MX_CHECK(msh_int(M, &par, "$Nodes block: parametric"));
    MX_CHECK(msh_size(M, &n, "$Nodes block: number of nodes"));
    if (dim < 0 || dim > 3 || (par != 0 && par != 1))
      return mx_rd_fail(r, at, "$Nodes block %llu: dimension %lld, parametric %lld",
                        (unsigned long long)b, (long long)dim, (long long)par);
    if (n > nn - done)
      return mx_rd_fail(r, at, "$Nodes block %llu: %llu nodes, more than announced",
                        (unsigned long long)b, (unsigned long long)n);
    const int ncoord = 3 + (par ? (int)dim : 0);
    if (M->binary)
      MX_CHECK(cur_need(&M->c, n * ((uint64_t)M->dsize + 8 * (uint64_t)ncoord),
                        "$Nodes block"));
    for (uint64_t i = 0; i < n; i++) {
      uint64_t tag = 0;
      if (M->binary)
        tag = bin_u(&M->c, M->dsize);
      else
        MX_CHECK(cur_count(&M->c, &tag, 1, "$Nodes: node tag"));
      if (tag < tmin || tag > tmax || tag == 0)
        return mx_rd_fail(r, M->c.p, "node tag %llu outside %llu..%llu",
                          (unsigned long long)tag, (unsigned long long)tmin,
                          (unsigned long long)tmax);
      M->ntag[done + i] = tag;
    }
    for (uint64_t i = 0; i < n; i++) {
      double *q = M->out->xyz + 3 * (done + i);
      for (int k = 0; k < ncoord; k++) {
        double v = 0.0;
        const char *vat = msh_at(M);
        if (M->binary)
          v = bin_real(&M->c, 8);
        else
          MX_CHECK(cur_real(&M->c, &v, "$Nodes: coordinate"));
        if (!isfinite(v))
          return mx_rd_fail(r, vat, "node %zu: coordinate %d is not a finite "
                            "number", done + (size_t)i, k);
        if (k < 3) q[k] = v;
      }
    }
    done += (size_t)n;
  }
  if (done != nn)
    return mx_rd_fail(r, M->c.p, "$Nodes: %zu nodes in the blocks, %llu announced",
                      done, (unsigned long long)nn);
  M->tmin = tmin;
  M->tmax = tmax;
  MX_CHECK(mx_msh_tag_map(M));
  return mx_msh_end(M, "Nodes");
}

int mx_msh_tag_map(msh *M) {
  rd *r = M->c.r;
  const uint64_t nn = M->nnodes, tmin = M->tmin, tmax = M->tmax;
  if (nn > 0 && tmax - tmin < 2 * nn + 1024) {
    const size_t span = (size_t)(tmax - tmin) + 1;
    M->dense = mx_calloc(span * sizeof *M->dense);
    if (!M->dense) return MX_ENOMEM;
    for (size_t i = 0; i < nn; i++) {
      uint32_t *d = &M->dense[M->ntag[i] - tmin];
      if (*d)
        return mx_rd_fail(r, NULL, "node tag %llu appears twice",
                          (unsigned long long)M->ntag[i]);
      *d = (uint32_t)i + 1;
    }
  } else if (nn > 0) {
    M->sorted = mx_alloc((size_t)nn * sizeof *M->sorted);
    M->sidx = mx_alloc((size_t)nn * sizeof *M->sidx);
    if (!M->sorted || !M->sidx) return MX_ENOMEM;
    for (size_t i = 0; i < nn; i++) {
      M->sorted[i] = M->ntag[i];
      M->sidx[i] = (uint32_t)i;
    }
    MX_CHECK(mx_sort_u64(M->sorted, M->sidx, (size_t)nn));
    for (size_t i = 1; i < nn; i++)
      if (M->sorted[i] == M->sorted[i - 1])
        return mx_rd_fail(r, NULL, "node tag %llu appears twice",
                          (unsigned long long)M->sorted[i]);
  }
  return MX_OK;
}

/* A double of $Entities (binary: no check of its value, it is not used). */
static int msh_real(msh *M, const char *what) {
  if (!M->binary) {
    double v;
    return cur_real(&M->c, &v, what);
  }
  MX_CHECK(cur_need(&M->c, 8, what));
  M->c.p += 8;
  return MX_OK;
}

static int surf_cmp(const void *a, const void *b) {
  const int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
  return (x > y) - (x < y);
}

static int msh_entities(msh *M) {
  rd *r = M->c.r;
  if (M->have_entities) return mx_rd_fail(r, M->c.p, "$Entities given twice");
  M->have_entities = 1;
  uint64_t n[4] = {0, 0, 0, 0};
  const char *at = msh_at(M);
  for (int d = 0; d < 4; d++)
    MX_CHECK(msh_size(M, &n[d], "$Entities: number of entities"));
  /* an entity takes at least a tag, 3 doubles and a count */
  const uint64_t least = M->binary ? 4 + 24 + (uint64_t)M->dsize : 8;
  for (int d = 0; d < 4; d++)
    if (n[d] > cur_left(&M->c) / least + 1)
      return mx_rd_fail(r, at,
                        "$Entities: %llu entities of dimension %d announced but "
                        "the file is too short (truncated file or wrong count)",
                        (unsigned long long)n[d], d);
  M->surf = mx_alloc((2 * (size_t)n[2] + 1) * sizeof *M->surf);
  M->vol = mx_alloc((2 * (size_t)n[3] + 1) * sizeof *M->vol);
  if (!M->surf || !M->vol) return MX_ENOMEM;
  for (int d = 0; d < 4; d++)
    for (uint64_t i = 0; i < n[d]; i++) {
      int64_t tag = 0, first = 0;
      uint64_t np = 0, nb = 0;
      at = msh_at(M);
      MX_CHECK(msh_int(M, &tag, "$Entities: entity tag"));
      for (int k = 0; k < (d ? 6 : 3); k++)
        MX_CHECK(msh_real(M, "$Entities: coordinate"));
      const char *pat = msh_at(M);
      MX_CHECK(msh_size(M, &np, "$Entities: number of physical tags"));
      if (np > cur_left(&M->c) / 2 + 1)
        return mx_rd_fail(r, pat, "$Entities: %llu physical tags announced but the "
                          "file is too short", (unsigned long long)np);
      for (uint64_t j = 0; j < np; j++) {
        int64_t ph = 0;
        MX_CHECK(msh_int(M, &ph, "$Entities: physical tag"));
        if (j == 0) first = ph;
      }
      if (d > 0) {
        pat = msh_at(M);
        MX_CHECK(msh_size(M, &nb, "$Entities: number of bounding entities"));
        if (nb > cur_left(&M->c) / 2 + 1)
          return mx_rd_fail(r, pat, "$Entities: %llu bounding entities announced "
                            "but the file is too short", (unsigned long long)nb);
        for (uint64_t j = 0; j < nb; j++) {
          int64_t b = 0;
          MX_CHECK(msh_int(M, &b, "$Entities: bounding entity"));
        }
      }
      if (d == 2) {
        const int64_t face_tag = np ? first : tag;
        MX_CHECK(mx_rd_tag_range(r, at, face_tag, "$Entities: surface tag"));
        M->surf[2 * i] = tag;
        M->surf[2 * i + 1] = face_tag;
      } else if (d == 3) {
        const int64_t label = np ? first : tag;
        MX_CHECK(mx_rd_tag_range(r, at, label, "$Entities: volume tag"));
        M->vol[2 * i] = tag;
        M->vol[2 * i + 1] = label;
      }
    }
  M->nsurf = (size_t)n[2];
  M->nvol = (size_t)n[3];
  qsort(M->surf, M->nsurf, 2 * sizeof *M->surf, surf_cmp);
  qsort(M->vol, M->nvol, 2 * sizeof *M->vol, surf_cmp);
  return mx_msh_end(M, "Entities");
}

/* $PhysicalNames: the names of dimension 2 (boundary tags) are kept. */
static int msh_names(msh *M) {
  rd *r = M->c.r;
  uint64_t n = 0;
  const char *at = cur_skip(&M->c);
  MX_CHECK(cur_count(&M->c, &n, 0, "$PhysicalNames: number of names"));
  if (n > cur_left(&M->c) / 8 + 1)
    return mx_rd_fail(r, at, "$PhysicalNames: %llu names announced but the file "
                      "is too short (truncated file or wrong count)",
                      (unsigned long long)n);
  for (uint64_t i = 0; i < n; i++) {
    int64_t dim = 0, tag = 0;
    at = cur_skip(&M->c);
    MX_CHECK(cur_int(&M->c, &dim, "$PhysicalNames: dimension"));
    MX_CHECK(cur_int(&M->c, &tag, "$PhysicalNames: physical tag"));
    const char *p = M->c.p, *end = r->end;
    const char *nl = memchr(p, '\n', (size_t)(end - p));
    if (!nl) nl = end;
    const char *q1 = memchr(p, '"', (size_t)(nl - p));
    const char *q2 = q1 ? memrchr(q1 + 1, '"', (size_t)(nl - q1 - 1)) : NULL;
    if (!q2)
      return mx_rd_fail(r, at, "$PhysicalNames: name %llu is not in double quotes",
                        (unsigned long long)i);
    M->c.p = nl;
    if (dim != 2) continue;
    MX_CHECK(mx_rd_tag_range(r, at, tag, "$PhysicalNames: physical tag"));
    MX_CHECK(add_name(M->out, &M->ncap, (int32_t)tag, q1 + 1,
                      (size_t)(q2 - q1 - 1)));
  }
  return mx_msh_end(M, "PhysicalNames");
}

/* The entry of tag e in the (tag, value) pairs of tab, sorted by tag, or
 * -1. */
static int64_t pair_find(const int64_t *tab, size_t n, int64_t e) {
  size_t lo = 0, hi = n;
  while (lo < hi) {
    const size_t mid = lo + (hi - lo) / 2;
    if (tab[2 * mid] < e)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < n && tab[2 * lo] == e ? (int64_t)lo : -1;
}

/* The faces' entity tags to their entities' physical tags. */
static void msh_face_tags(msh *M) {
  mx_mesh_data *out = M->out;
  for (size_t f = 0; f < out->nfaces && M->nsurf; f++) {
    const int64_t i = pair_find(M->surf, M->nsurf, out->face_tag[f]);
    if (i >= 0) out->face_tag[f] = (int32_t)M->surf[2 * i + 1];
  }
}

/* The volume elements' entity tags to their labels (see the top): the
 * cell_tag of out, unless every label is the same. */
static void msh_cell_tags(msh *M) {
  mx_mesh_data *out = M->out;
  const size_t nc = out->ncells;
  int32_t *lab = M->cent;
  int varies = 0;
  for (size_t c = 0; c < nc; c++) {
    const int64_t i = pair_find(M->vol, M->nvol, lab[c]);
    if (i >= 0) lab[c] = (int32_t)M->vol[2 * i + 1];
    varies |= lab[c] != lab[0];
  }
  if (!varies) return;
  out->cell_tag = lab;
  M->cent = NULL;
}

static int msh_elements(msh *M) {
  rd *r = M->c.r;
  if (!M->have_nodes)
    return mx_rd_fail(r, M->c.p, "$Elements before $Nodes");
  if (M->etag) return mx_rd_fail(r, M->c.p, "$Elements given twice");
  uint64_t nb = 0, ne = 0, tmin = 0, tmax = 0;
  const char *at = msh_at(M);
  MX_CHECK(msh_size(M, &nb, "$Elements: number of blocks"));
  MX_CHECK(msh_size(M, &ne, "$Elements: number of elements"));
  MX_CHECK(msh_size(M, &tmin, "$Elements: smallest tag"));
  MX_CHECK(msh_size(M, &tmax, "$Elements: largest tag"));
  const uint64_t least = M->binary ? 2 * (uint64_t)M->dsize : 4;
  if (ne > cur_left(&M->c) / least + 1 || nb > cur_left(&M->c) / 4 + 1)
    return mx_rd_fail(r, at,
                      "$Elements: %llu elements in %llu blocks announced but the "
                      "file is too short (truncated file or wrong count)",
                      (unsigned long long)ne, (unsigned long long)nb);
  M->etag = mx_alloc(sizeof *M->etag); /* grows with the cells */
  if (!M->etag) return MX_ENOMEM;
  mx_mesh_data *out = M->out;
  uint64_t done = 0;
  for (uint64_t b = 0; b < nb; b++) {
    int64_t dim = 0, etag = 0, type = 0;
    uint64_t n = 0;
    at = msh_at(M);
    MX_CHECK(msh_int(M, &dim, "$Elements block: entity dimension"));
    MX_CHECK(msh_int(M, &etag, "$Elements block: entity tag"));
    MX_CHECK(msh_int(M, &type, "$Elements block: element type"));
    MX_CHECK(msh_size(M, &n, "$Elements block: number of elements"));
    if (n > ne - done)
      return mx_rd_fail(r, at,
                        "$Elements block %llu: %llu elements, more than announced",
                        (unsigned long long)b, (unsigned long long)n);
    const int vt = mx_msh_volume_type(type);
    const int k = type > 0 && type < MSH_TYPES ? msh_type_nodes[type] : 0;
    const int skipped = type == 1 || type == 2 || type == 3 || type == 15;
    const int face = dim == 2 && (type == 2 || type == 3);
    if (k == 0 || (vt < 0 && !skipped))
      return mx_rd_fail(r, at,
                        "$Elements block %llu: element type %lld is not supported "
                        "(linear tetrahedra 4, hexahedra 5, prisms 6, pyramids 7; "
                        "points, lines, triangles and quadrangles are skipped)",
                        (unsigned long long)b, (long long)type);
    if (face || vt >= 0)
      MX_CHECK(mx_rd_tag_range(r, at, etag, "$Elements block: entity tag"));
    const uint64_t line_bytes = (uint64_t)(k + 1) * (uint64_t)M->dsize;
    if (M->binary)
      MX_CHECK(cur_need(&M->c, n * line_bytes, "$Elements block"));
    else if (n > cur_left(&M->c) / (2 * (uint64_t)(k + 1)) + 1)
      return mx_rd_fail(r, at,
                        "$Elements block %llu: %llu elements announced but the "
                        "file is too short (truncated file or wrong count)",
                        (unsigned long long)b, (unsigned long long)n);
    const size_t c0 = out->ncells;
    if (vt >= 0) {
      MX_CHECK(mx_rd_grow_cells(r, out, (size_t)n));
      uint64_t *et = mx_realloc(M->etag, ((size_t)(c0 + n) + 1) *
                                             sizeof *M->etag);
      if (!et) return MX_ENOMEM;
      M->etag = et;
      int32_t *ce = mx_realloc(M->cent, ((size_t)(c0 + n) + 1) * sizeof *M->cent);
      if (!ce) return MX_ENOMEM;
      M->cent = ce;
      for (uint64_t i = 0; i < n; i++) ce[c0 + (size_t)i] = (int32_t)etag;
    }
    if (face) MX_CHECK(mx_rd_face_room(r, out, &M->fcap, (size_t)n));
    for (uint64_t i = 0; i < n; i++) {
      uint64_t tag = 0;
      at = msh_at(M);
      if (M->binary)
        tag = bin_u(&M->c, M->dsize);
      else
        MX_CHECK(cur_count(&M->c, &tag, 1, "$Elements: element tag"));
      uint32_t fv[4] = {0, 0, 0, 0};
      uint32_t *row = vt >= 0 ? out->conn + 8 * (c0 + (size_t)i)
                      : face  ? fv
                              : NULL;
      for (int j = 0; j < k; j++) {
        uint64_t t = 0;
        const char *nat = msh_at(M);
        if (M->binary)
          t = bin_u(&M->c, M->dsize);
        else
          MX_CHECK(cur_count(&M->c, &t, 1, "$Elements: node tag"));
        if (!row) continue;
        const int64_t v = mx_msh_node(M, t);
        if (v < 0)
          return mx_rd_fail(r, nat, "element %llu: node tag %llu is not a node",
                            (unsigned long long)tag, (unsigned long long)t);
        row[j] = (uint32_t)v;
      }
      if (face) /* the entity tag for now (msh_face_tags) */
        mx_rd_add_face(out, k, fv, (int32_t)etag);
      else if (row) {
        out->type[c0 + (size_t)i] = (uint8_t)vt;
        M->etag[c0 + (size_t)i] = tag;
      }
    }
    if (vt >= 0) out->ncells = c0 + (size_t)n;
    done += n;
  }
  if (done != ne)
    return mx_rd_fail(r, M->c.p,
                      "$Elements: %llu elements in the blocks, %llu announced",
                      (unsigned long long)done, (unsigned long long)ne);
  (void)tmin;
  (void)tmax;
  return mx_msh_end(M, "Elements");
}

/* Volume elements (and their entity tags) in the order of their tags
 * (unique). */
static int msh_order(msh *M) {
  mx_mesh_data *out = M->out;
  const size_t nc = out->ncells;
  int sorted = 1;
  for (size_t c = 1; c < nc && sorted; c++) sorted = M->etag[c - 1] < M->etag[c];
  if (sorted) return MX_OK;
  uint64_t *k = mx_alloc((nc + 1) * sizeof *k);
  uint32_t *idx = mx_alloc((nc + 1) * sizeof *idx);
  uint8_t *t = mx_alloc(nc + 1);
  uint32_t *cn = mx_alloc((8 * nc + 1) * sizeof *cn);
  int32_t *ce = mx_alloc((nc + 1) * sizeof *ce);
  int st = k && idx && t && cn && ce ? MX_OK : MX_ENOMEM;
  if (st == MX_OK) {
    for (size_t c = 0; c < nc; c++) {
      k[c] = M->etag[c];
      idx[c] = (uint32_t)c;
    }
    st = mx_sort_u64(k, idx, nc);
  }
  for (size_t c = 1; st == MX_OK && c < nc; c++)
    if (k[c] == k[c - 1])
      st = mx_rd_fail(M->c.r, NULL, "element tag %llu appears twice",
                      (unsigned long long)k[c]);
  if (st == MX_OK) {
    for (size_t c = 0; c < nc; c++) {
      t[c] = out->type[idx[c]];
      memcpy(cn + 8 * c, out->conn + 8 * (size_t)idx[c], 8 * sizeof *cn);
      ce[c] = M->cent[idx[c]];
    }
    mx_free(out->type);
    mx_free(out->conn);
    mx_free(M->cent);
    out->type = t;
    out->conn = cn;
    M->cent = ce;
    t = NULL;
    cn = NULL;
    ce = NULL;
  }
  mx_free(k);
  mx_free(idx);
  mx_free(t);
  mx_free(cn);
  mx_free(ce);
  return st;
}

int mx_rd_msh(rd *r, const char *p, mx_mesh_data *out) {
  msh M;
  memset(&M, 0, sizeof M);
  M.c.r = r;
  M.c.p = p;
  M.dsize = 8;
  M.out = out;
  int st = MX_OK, have_format = 0;
  for (;;) {
    size_t n;
    const char *t = cur_tok(&M.c, &n);
    if (n == 0) {
      if (t < r->end)
        st = mx_rd_fail(r, t, "unexpected NUL byte");
      break;
    }
    if (t[0] != '$') {
      st = mx_rd_fail(r, t, "expected a section ($Name), found '%.*s'", shown(n),
                      t);
      break;
    }
    if (tok_eq(t, n, "$MeshFormat")) {
      st = msh_format(&M);
      have_format = 1;
    } else if (!have_format) {
      st = mx_rd_fail(r, t, "expected $MeshFormat first");
    } else if (tok_eq(t, n, "$PhysicalNames")) {
      st = msh_names(&M);
    } else if (tok_eq(t, n, "$Nodes") || tok_eq(t, n, "$Elements") ||
               (tok_eq(t, n, "$Entities") && !M.v2)) {
      if (M.binary && !M.v2) { /* the data starts after the end of the line */
        const char *q = M.c.p;
        while (q < r->end && (*q == ' ' || *q == '\t' || *q == '\r')) q++;
        if (q >= r->end || *q != '\n') {
          st = mx_rd_fail(r, q, "expected the end of the line after %.*s",
                          shown(n), t);
          break;
        }
        M.c.p = q + 1;
      }
      if (M.v2)
        st = tok_eq(t, n, "$Nodes") ? mx_msh22_nodes(&M) : mx_msh22_elements(&M);
      else
        st = tok_eq(t, n, "$Nodes")      ? msh_nodes(&M)
             : tok_eq(t, n, "$Elements") ? msh_elements(&M)
                                         : msh_entities(&M);
    } else { /* skipped up to $End<name> at the start of a line */
      char want[80];
      snprintf(want, sizeof want, "\n$End%.*s", (int)(n > 60 ? 60 : n - 1),
               t + 1);
      const size_t wl = strlen(want);
      const char *q = memmem(M.c.p, cur_left(&M.c), want, wl);
      if (!q) {
        st = mx_rd_fail(r, t, "no %s after %.*s", want + 1, shown(n), t);
        break;
      }
      M.c.p = q + wl;
      if (M.c.p < r->end && !is_ws(*M.c.p) && *M.c.p)
        st = mx_rd_fail(r, q + 1, "expected %s", want + 1);
    }
    if (st != MX_OK) break;
  }
  if (st == MX_OK && !have_format) st = mx_rd_fail(r, NULL, "no $MeshFormat");
  if (st == MX_OK && !M.have_nodes) st = mx_rd_fail(r, NULL, "no $Nodes section");
  if (st == MX_OK && !M.etag) st = mx_rd_fail(r, NULL, "no $Elements section");
  if (st == MX_OK) st = msh_order(&M);
  if (st == MX_OK) msh_face_tags(&M);
  if (st == MX_OK) msh_cell_tags(&M);
  if (st == MX_OK) st = sort_names(out);
  msh_free(&M);
  return st;
}
