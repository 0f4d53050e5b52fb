/* Two searches for one thing: the mesher's contacts (kernels/contacts.c:
 * elements filed in cells of the octree's lattice, closest points of
 * geom/distance.h) and the checker's geometric hanging nodes (verify/,
 * mx_check_contacts: a multi-level grid over the nodes' box, its own
 * point-triangle distance). Neither calls the other; they must find the
 * same contacts: the same surface nodes on the same elements with a
 * surface face. Compared: the number of nodes found, the first of them and
 * the elements involved (those the nodes lie on and those using them).
 *
 * Meshes: hand-made ones (nodes on an edge and inside a face of a
 * hexahedron, a node just within and just beyond the tolerance of a face,
 * a conforming split: none), and the meshes the repair loop looks at -- the
 * triple torus of CGAL's data (data/meshes/3torus.off, Debian's
 * libcgal-demo, extracted here) at -s 6 after 0, 1, 2, 3 and 4 repair
 * rounds (its first mesh has contacts), two unit cubes touching along a
 * face with --repair-input, and the cortex at -s 5. Without the archive
 * or the shared data those parts are skipped (a failure when CI is set).
 * Then the search within a region (mx_find_contacts_in, the one after a
 * local re-mesh) against the search everywhere, on contacts made by moving
 * a node of the cortex's mesh onto a face. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "check.h"
#include "base/common.h"
#include "kernels/boundary.h"
#include "kernels/contacts.h"
#include "mesher/mesher.h"
#include "mixoct.h"
#include "soa/mesh.h"
#include "verify/check.h"

static int compared, with_contacts;

static void quiet(void *user, int level, const char *text) {
  (void)user;
  (void)level;
  (void)text;
}


/* Both searches on M (its surface nodes: states MX_NODE_OUTSIDE); 1 when
 * they agree. */
static int compare(const char *name, const mx_mesh *M, const mx_grid *G,
                   const uint8_t *states) {
  const size_t nc = M->ncells, nn = M->nnodes;
  /* the mesher's */
  uint8_t *mflag = calloc(nc + 1, 1);
  mx_contacts k;
  CHECK(mflag && mx_find_contacts(M, G, states, mflag, &k) == MX_OK);
  /* the checker's, on the same nodes and elements */
  uint32_t *list = malloc((nc + 1) * sizeof *list);
  uint8_t *sel = calloc(nn + 1, 1), *hit = calloc(nn + 1, 1), *cflag = calloc(nc + 1, 1);
  CHECK(list && sel && hit && cflag);
  size_t nl = 0;
  for (size_t c = 0; c < nc; c++)
    if (mx_surface_face(M, states, c)) list[nl++] = (uint32_t)c;
  for (size_t v = 0; v < nn; v++) sel[v] = states[v] == MX_NODE_OUTSIDE;
  const mx_mesh_data md = {.nnodes = nn, .ncells = nc, .xyz = M->xyz, .type = M->type,
                           .conn = M->conn};
  mx_check_options o;
  mx_check_defaults(&o);
  size_t found = 0;
  CHECK(mx_check_contacts(&md, list, nl, sel, o.hang_tol, hit, cflag, &found) == MX_OK);
  uint32_t first = UINT32_MAX;
  for (size_t v = 0; v < nn && first == UINT32_MAX; v++)
    if (hit[v]) first = (uint32_t)v;
  size_t ne = 0, differ = 0;
  for (size_t c = 0; c < nc; c++) {
    int s = cflag[c] != 0;
    for (int j = 0; j < mx_cell_nodes[M->type[c]]; j++) s |= hit[M->conn[8 * c + (size_t)j]];
    ne += (size_t)s;
    differ += (size_t)s != (size_t)mflag[c];
  }
  const int same = k.nodes == found && k.first_node == first && k.elements == ne && differ == 0;
  printf("%-34s %9zu elements, %6zu listed: mesher %zu nodes %zu elements, "
         "checker %zu nodes %zu elements%s\n",
         name, nc, nl, k.nodes, k.elements, found, ne, same ? "" : "  DIFFER");
  compared++;
  with_contacts += found > 0;
  free(mflag);
  free(list);
  free(sel);
  free(hit);
  free(cflag);
  return same;
}

/* ---- hand-made meshes -------------------------------------------------------- */

typedef struct {
  size_t nn, nc;
  double xyz[3 * 64];
  uint8_t type[16];
  uint32_t conn[8 * 16];
} small_mesh;

static uint32_t node_at(small_mesh *t, double x, double y, double z) {
  for (size_t v = 0; v < t->nn; v++)
    if (t->xyz[3 * v] == x && t->xyz[3 * v + 1] == y && t->xyz[3 * v + 2] == z)
      return (uint32_t)v;
  t->xyz[3 * t->nn] = x;
  t->xyz[3 * t->nn + 1] = y;
  t->xyz[3 * t->nn + 2] = z;
  return (uint32_t)t->nn++;
}

/* The box [lo, hi] as a hexahedron (VTK order). */
static void box(small_mesh *t, const double lo[3], const double hi[3]) {
  static const int corner[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                   {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};
  for (int j = 0; j < 8; j++)
    t->conn[8 * t->nc + (size_t)j] =
        node_at(t, corner[j][0] ? hi[0] : lo[0], corner[j][1] ? hi[1] : lo[1],
                corner[j][2] ? hi[2] : lo[2]);
  t->type[t->nc++] = MX_HEX;
}

/* One root cube around the nodes, as the mesher's grid would be. */
static void grid_around(const small_mesh *t, mx_grid *G) {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t v = 0; v < t->nn; v++)
    for (int a = 0; a < 3; a++) {
      lo[a] = fmin(lo[a], t->xyz[3 * v + (size_t)a]);
      hi[a] = fmax(hi[a], t->xyz[3 * v + (size_t)a]);
    }
  double side = 0.0;
  for (int a = 0; a < 3; a++) side = fmax(side, hi[a] - lo[a]);
  side *= 1.01;
  for (int a = 0; a < 3; a++) {
    G->origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * side;
    G->dims[a] = 1;
  }
  G->side = side;
  G->unit = ldexp(side, -MX_MAX_LEVEL);
}

static void compare_small(const char *name, small_mesh *t, size_t expect_nodes) {
  mx_mesh M;
  memset(&M, 0, sizeof M);
  M.nnodes = t->nn;
  M.ncells = t->nc;
  M.xyz = t->xyz;
  M.type = t->type;
  M.conn = t->conn;
  mx_grid G;
  grid_around(t, &G);
  uint8_t st[64];
  memset(st, MX_NODE_OUTSIDE, sizeof st);
  CHECK(compare(name, &M, &G, st));
  mx_contacts k;
  CHECK(mx_find_contacts(&M, &G, st, NULL, &k) == MX_OK);
  if (k.nodes != expect_nodes) fprintf(stderr, "%s: %zu nodes, %zu expected\n", name, k.nodes, expect_nodes);
  CHECK(k.nodes == expect_nodes);
}

static void test_small(void) {
  small_mesh t;
  /* the hexahedron against two boxes cut at z = 1/3: two nodes on its
   * edges */
  memset(&t, 0, sizeof t);
  box(&t, (double[]){0, 0, 0}, (double[]){1, 1, 1});
  box(&t, (double[]){1, 0, 0}, (double[]){2, 1, 1.0 / 3.0});
  box(&t, (double[]){1, 0, 1.0 / 3.0}, (double[]){2, 1, 1});
  compare_small("edges", &t, 2);
  /* four boxes against it, cut at y = 0.3 and z = 0.6: one node inside its
   * face x = 1, four on the edges of that face */
  memset(&t, 0, sizeof t);
  box(&t, (double[]){0, 0, 0}, (double[]){1, 1, 1});
  box(&t, (double[]){1, 0, 0}, (double[]){2, 0.3, 0.6});
  box(&t, (double[]){1, 0.3, 0}, (double[]){2, 1, 0.6});
  box(&t, (double[]){1, 0, 0.6}, (double[]){2, 0.3, 1});
  box(&t, (double[]){1, 0.3, 0.6}, (double[]){2, 1, 1});
  compare_small("face", &t, 5);
  /* a box whose corner is 1e-10 (within the tolerance: 1e-9 times half the
   * side) and 1e-8 (beyond it) off the hexahedron's face */
  const double off[2] = {1e-10, 1e-8};
  const size_t expect[2] = {1, 0};
  for (int i = 0; i < 2; i++) {
    memset(&t, 0, sizeof t);
    box(&t, (double[]){0, 0, 0}, (double[]){1, 1, 1});
    box(&t, (double[]){1 + off[i], 0.25, 0.25}, (double[]){2, 0.75, 0.75});
    /* only the corner (1 + off, 0.25, 0.25) is a surface node: the others
     * would lie on it too */
    uint8_t st[64];
    memset(st, MX_NODE_INSIDE, sizeof st);
    st[node_at(&t, 1 + off[i], 0.25, 0.25)] = MX_NODE_OUTSIDE;
    for (size_t v = 0; v < 8; v++) st[v] = MX_NODE_OUTSIDE; /* the hexahedron's */
    mx_mesh M;
    memset(&M, 0, sizeof M);
    M.nnodes = t.nn;
    M.ncells = t.nc;
    M.xyz = t.xyz;
    M.type = t.type;
    M.conn = t.conn;
    mx_grid G;
    grid_around(&t, &G);
    CHECK(compare(i ? "beyond the tolerance" : "within the tolerance", &M, &G, st));
    mx_contacts k;
    CHECK(mx_find_contacts(&M, &G, st, NULL, &k) == MX_OK && k.nodes == expect[i]);
  }
  /* conforming: both sides split at the same height */
  memset(&t, 0, sizeof t);
  box(&t, (double[]){0, 0, 0}, (double[]){1, 1, 0.5});
  box(&t, (double[]){0, 0, 0.5}, (double[]){1, 1, 1});
  box(&t, (double[]){1, 0, 0}, (double[]){2, 1, 0.5});
  box(&t, (double[]){1, 0, 0.5}, (double[]){2, 1, 1});
  compare_small("conforming", &t, 0);
}

/* ---- meshes of the mesher ------------------------------------------------------ */

/* Meshes `paths` (n of them) at -s level after `rounds` repair rounds and
 * compares the two searches on the result. */
static void compare_mesher(const char *name, const char *const *paths, int n, int level,
                           int rounds, int repair_input) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = level;
  p.repair_rounds = rounds;
  p.repair_input = repair_input;
  mx_mesher *m = mx_mesher_new(&p);
  CHECK(m != NULL);
  if (!m) return;
  mx_mesher_set_message_handler(m, quiet, NULL);
  for (int i = 0; i < n; i++) CHECK(mx_mesher_add_surface(m, paths[i]) == MX_OK);
  const int st = mx_mesher_mesh(m); /* MX_EINVALID: contacts left, the point */
  CHECK(st == MX_OK || st == MX_EINVALID);
  CHECK(m->states != NULL && m->M.ncells > 0);
  if (m->states && m->M.ncells) {
    char label[96];
    snprintf(label, sizeof label, "%s, %d round(s)", name, rounds);
    CHECK(compare(label, &m->M, &m->B.tree.grid, m->states));
  }
  mx_mesher_free(m);
}

static const char *find_data(void) { return test_data_dir("surfaces/cortex.off"); }

static void test_mesher(void) {
  char tmp[] = "/tmp/mx_contacts_XXXXXX";
  CHECK(mkdtemp(tmp) != NULL);
  /* the triple torus: contacts in its first mesh, repaired in 4 rounds */
  const char *cgal = getenv("CGAL_DATA") ? getenv("CGAL_DATA") : "/usr/share/doc/libcgal-dev/data.tar.gz";
  char cmd[1400], torus[700];
  snprintf(torus, sizeof torus, "%s/data/meshes/3torus.off", tmp);
  snprintf(cmd, sizeof cmd, "tar -xzf '%s' -C '%s' data/meshes/3torus.off 2>/dev/null", cgal, tmp);
  if (access(cgal, R_OK) == 0 && system(cmd) == 0) {
    const char *in[1] = {torus};
    for (int r = 0; r <= 4; r++) compare_mesher("3torus.off -s 6", in, 1, 6, r, 0);
  } else {
    TEST_DATA_MISSING("%s (the triple torus; Debian: libcgal-demo)", cgal);
  }
  /* two unit cubes touching along a face, one file, --repair-input */
  char cubes[700];
  snprintf(cubes, sizeof cubes, "%s/AB.off", tmp);
  FILE *f = fopen(cubes, "w");
  CHECK(f != NULL);
  if (f) {
    static const int F[12][3] = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                                 {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
    fprintf(f, "OFF\n16 24 0\n");
    for (int b = 0; b < 2; b++)
      for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++)
          for (int k = 0; k < 2; k++) fprintf(f, "%d %d %d\n", b + i, j, k);
    for (int b = 0; b < 2; b++)
      for (int t = 0; t < 12; t++)
        fprintf(f, "3 %d %d %d\n", F[t][0] + 8 * b, F[t][1] + 8 * b, F[t][2] + 8 * b);
    fclose(f);
    const char *in[1] = {cubes};
    compare_mesher("two touching cubes -s 4", in, 1, 4, 0, 1);
  }
  const char *data = find_data();
  if (data) {
    char cortex[700];
    snprintf(cortex, sizeof cortex, "%s/surfaces/cortex.off", data);
    const char *in[1] = {cortex};
    compare_mesher("cortex.off -s 5", in, 1, 5, 0, 0);
  } else {
    TEST_DATA_MISSING("the shared data (surfaces/cortex.off)");
  }
  snprintf(cmd, sizeof cmd, "rm -rf '%s'", tmp);
  CHECK(system(cmd) == 0);
}

/* ---- the search around a changed region -------------------------------------- */

/* Both searches (everywhere, and in region) agree on M: 1 when they do. */
static int same_in_region(const mx_mesh *M, const mx_grid *G, const uint8_t *states,
                          const double *region, size_t *nodes) {
  const size_t nc = M->ncells;
  uint8_t *a = calloc(nc + 1, 1), *b = calloc(nc + 1, 1);
  mx_contacts ka, kb;
  CHECK(a && b);
  CHECK(mx_find_contacts(M, G, states, a, &ka) == MX_OK);
  CHECK(mx_find_contacts_in(M, G, states, region, b, &kb) == MX_OK);
  int same = ka.nodes == kb.nodes && ka.elements == kb.elements &&
             ka.first_node == kb.first_node && memcmp(a, b, nc) == 0;
  *nodes = ka.nodes;
  free(a);
  free(b);
  return same;
}

/* The cortex at -s 5 (no contact), then a surface node moved onto the
 * centre of a surface face of an element it is not a node of, near it: a
 * contact, which the search in the region of the changed elements (the
 * moved node's: mx_contact_box) finds as the search everywhere does, for
 * 20 such moves, each on the mesh as meshed; a region beside it (the same
 * size, moved by three of its sides) does not. */
static void test_region(void) {
  const char *data = find_data();
  if (!data) {
    TEST_DATA_MISSING("the shared data (surfaces/cortex.off)");
    return;
  }
  char cortex[700];
  snprintf(cortex, sizeof cortex, "%s/surfaces/cortex.off", data);
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 5;
  p.remesh_full = -1; /* re-meshes local (the end of the test) */
  mx_mesher *m = mx_mesher_new(&p);
  CHECK(m && mx_mesher_add_surface(m, cortex) == MX_OK && mx_mesher_mesh(m) == MX_OK);
  if (!m || !m->states) return;
  mx_mesh *M = &m->M;
  const mx_grid *G = &m->B.tree.grid;
  size_t n0 = 1;
  CHECK(same_in_region(M, G, m->states, NULL, &n0) && n0 == 0);
  int moves = 0, found = 0, missed_beside = 0;
  for (size_t e = 0; e < M->ncells && moves < 20; e += M->ncells / 499 + 1) {
    if (!mx_surface_face(M, m->states, e)) continue;
    /* a face of e with outside nodes only, its centre */
    const int t = M->type[e];
    const uint32_t *row = M->conn + 8 * e;
    int face = -1;
    for (int f = 0; f < mx_cell_nfaces[t] && face < 0; f++) {
      int all = 1;
      for (int k = 0; k < 4 && mx_cell_faces[t][f][k] >= 0; k++)
        all &= m->states[row[mx_cell_faces[t][f][k]]] == MX_NODE_OUTSIDE;
      if (all) face = f;
    }
    if (face < 0) continue;
    double c[3] = {0, 0, 0}, ext = 0;
    int nf = 0;
    for (int k = 0; k < 4 && mx_cell_faces[t][face][k] >= 0; k++, nf++)
      for (int a = 0; a < 3; a++) c[a] += M->xyz[3 * (size_t)row[mx_cell_faces[t][face][k]] + a];
    for (int a = 0; a < 3; a++) c[a] /= nf;
    for (int a = 0; a < 3; a++)
      ext = fmax(ext, fabs(M->xyz[3 * (size_t)row[0] + a] - M->xyz[3 * (size_t)row[1] + a]));
    /* the nearest outside node not of e, within a few sides of it */
    uint32_t v = UINT32_MAX;
    double best = 9.0 * ext * ext;
    for (size_t w = 0; w < M->nnodes; w++) {
      if (m->states[w] != MX_NODE_OUTSIDE) continue;
      int mine = 0;
      for (int k = 0; k < mx_cell_nodes[t]; k++) mine |= row[k] == w;
      double d2 = 0;
      for (int a = 0; a < 3; a++) d2 += (M->xyz[3 * w + a] - c[a]) * (M->xyz[3 * w + a] - c[a]);
      if (!mine && d2 > 0 && d2 < best) best = d2, v = (uint32_t)w;
    }
    if (v == UINT32_MAX) continue;
    double keep[3];
    memcpy(keep, M->xyz + 3 * (size_t)v, sizeof keep);
    memcpy(M->xyz + 3 * (size_t)v, c, sizeof c);
    /* the region: the padded boxes of v's elements */
    double R[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (size_t q = 0; q < M->ncells; q++)
      for (int k = 0; k < mx_cell_nodes[M->type[q]]; k++)
        if (M->conn[8 * q + k] == v) {
          double b[6];
          mx_contact_box(M, q, b);
          for (int a = 0; a < 3; a++) R[a] = fmin(R[a], b[a]), R[3 + a] = fmax(R[3 + a], b[3 + a]);
        }
    size_t n = 0;
    CHECK(same_in_region(M, G, m->states, R, &n));
    found += n > 0;
    /* beside it: the contact is not found */
    double S[6];
    for (int a = 0; a < 3; a++) {
      const double w = 3.0 * (R[3 + a] - R[a]) + 1e-9;
      S[a] = R[a] + w;
      S[3 + a] = R[3 + a] + w;
    }
    mx_contacts k;
    CHECK(mx_find_contacts_in(M, G, m->states, S, NULL, &k) == MX_OK);
    missed_beside += n > 0 && k.nodes < n;
    memcpy(M->xyz + 3 * (size_t)v, keep, sizeof keep);
    moves++;
  }
  printf("region: %d moves, %d made contacts, the region beside missed %d\n", moves, found,
         missed_beside);
  CHECK(moves == 20 && found >= 15 && missed_beside == found);
  /* a local re-mesh of 40 elements in a row (the mesh as meshed: no
   * contact): its search is the region's, and finds what the search
   * everywhere finds on the result */
  uint64_t list[40];
  for (int i = 0; i < 40; i++) list[i] = M->ncells / 3 + (uint64_t)i;
  CHECK(mx_mesher_refine_elements(m, list, 40) == MX_OK);
  CHECK(m->rec->S.local && m->rec->S.contacts_local >= 1);
  mx_contacts all;
  CHECK(mx_find_contacts(&m->M, G, m->states, NULL, &all) == MX_OK);
  CHECK(all.nodes == m->rec->S.contacts.nodes && all.elements == m->rec->S.contacts.elements);
  printf("re-mesh of 40 elements: local %d, %zu region search(es), %zu contact node(s)\n",
         m->rec->S.local, m->rec->S.contacts_local, all.nodes);
  mx_mesher_free(m);
}

int main(void) {
  test_small();
  test_mesher();
  test_region();
  printf("%d meshes compared, %d of them with contacts\n", compared, with_contacts);
  CHECK(with_contacts > 2);
  return TEST_DONE();
}
