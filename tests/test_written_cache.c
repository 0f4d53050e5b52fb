/* What the writers add to the mesh (written order, boundary faces, tags,
 * bodies) is made once per mesh and kept by the mesher (issue 31 item 4,
 * mesher/output.c). Through the public API, on the demo surface at level 4
 * (no shared data needed, about a second):
 * - cache correctness: one mesher writing .vtu, .msh, .mesh and the
 *   boundary (.off) one after the other, then .vtu again, gives the bytes
 *   of fresh meshers writing each file alone;
 * - cache invalidation: after a re-mesh (refine_elements of elements on
 *   the boundary) the boundary faces given (the .off file, the boundary
 *   arrays) are the new mesh's, compared with the faces found here
 *   independently (each element's faces from VTK's tables, a face on the
 *   boundary when one element has it), and the .msh is the bytes of a
 *   fresh mesher that made the same re-mesh without writing before it;
 * - the .msh boxes of the surface entities, made from the tagged faces
 *   (io/write_msh.c, per thread then merged): two nested cubes at level 7
 *   (faces enough for two threads), each tag's box the box of its cube,
 *   the same bytes for 1 and 2 threads (about a second each). */
#include "check.h"
#include "file_util.h"
#include "mixoct.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define DIR "written_cache_out"

/* VTK's faces of each type as node sets (orientation plays no part): tet
 * 0-3, pyramid base 0-3 and apex 4, wedge 0,1,2 / 3,4,5, hexahedron 0-3 /
 * 4-7; -1 ends a triangle. */
static const int faces_of[4][6][4] = {
    {{0, 1, 2, -1}, {0, 1, 3, -1}, {1, 2, 3, -1}, {0, 2, 3, -1}},
    {{0, 1, 2, 3}, {0, 1, 4, -1}, {1, 2, 4, -1}, {2, 3, 4, -1}, {3, 0, 4, -1}},
    {{0, 1, 2, -1}, {3, 4, 5, -1}, {0, 1, 4, 3}, {1, 2, 5, 4}, {2, 0, 3, 5}},
    {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}}};
static const int nfaces_of[4] = {4, 5, 5, 6};

typedef struct {
  uint32_t v[4]; /* sorted; a triangle's 4th UINT32_MAX */
  uint32_t elem;
} face_key;

static int cmp_key(const void *a, const void *b) {
  return memcmp(((const face_key *)a)->v, ((const face_key *)b)->v, sizeof(uint32_t) * 4);
}

static void sort4(uint32_t *v) {
  for (int i = 1; i < 4; i++)
    for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
      const uint32_t t = v[j];
      v[j] = v[j - 1];
      v[j - 1] = t;
    }
}

/* The boundary faces of the mesh arrays (sorted keys, in *out; the count
 * returned): faces that one element alone has. */
static size_t boundary_faces(const mx_mesh_arrays *a, face_key **out) {
  face_key *k = malloc((6 * a->nelements + 1) * sizeof *k);
  size_t n = 0;
  for (size_t e = 0; e < a->nelements; e++) {
    const int t = a->type[e];
    for (int f = 0; f < nfaces_of[t]; f++) {
      for (int j = 0; j < 4; j++) {
        const int l = faces_of[t][f][j];
        k[n].v[j] = l < 0 ? UINT32_MAX : a->conn[8 * e + l];
      }
      sort4(k[n].v);
      k[n++].elem = (uint32_t)e;
    }
  }
  qsort(k, n, sizeof *k, cmp_key);
  size_t nb = 0;
  for (size_t i = 0; i < n;) {
    size_t j = i + 1;
    while (j < n && !cmp_key(&k[i], &k[j])) j++;
    if (j == i + 1) k[nb++] = k[i];
    i = j;
  }
  *out = k;
  return nb;
}

/* The faces of the boundary arrays as sorted keys: equal to the ones found
 * here, face for face. */
static int same_faces(const mx_boundary_arrays *b, const face_key *ref, size_t nref) {
  if (b->nfaces != nref) return 0;
  face_key *k = malloc((b->nfaces + 1) * sizeof *k);
  for (size_t i = 0; i < b->nfaces; i++) {
    memcpy(k[i].v, b->nodes + 4 * i, sizeof k[i].v);
    sort4(k[i].v);
  }
  qsort(k, b->nfaces, sizeof *k, cmp_key);
  int same = 1;
  for (size_t i = 0; i < nref && same; i++) same = !cmp_key(&k[i], &ref[i]);
  free(k);
  return same;
}

/* The face count of an .off file ("OFF", then "nv nf ne"). */
static long off_faces(const char *path) {
  FILE *f = fopen(path, "r");
  long nv = -1, nf = -1, ne = -1;
  if (f && fscanf(f, "OFF %ld %ld %ld", &nv, &nf, &ne) != 3) nf = -1;
  if (f) fclose(f);
  return nf;
}

static mx_mesher *demo_mesher(void) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 4;
  mx_mesher *m = mx_mesher_new(&p);
  CHECK(m != NULL);
  if (!m) exit(1);
  CHECK(mx_mesher_add_demo_surface(m) == MX_OK);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  return m;
}

/* A fresh mesher writes one file alone (boundary: the boundary file). */
static void write_alone(const char *path, int boundary) {
  mx_mesher *m = demo_mesher();
  CHECK((boundary ? mx_mesher_write_boundary(m, path) : mx_mesher_write(m, path, 0)) == MX_OK);
  mx_mesher_free(m);
}

/* An axis-aligned cube [lo, hi]^3 as an OFF file, faces outward. */
static void write_cube(const char *path, double lo, double hi) {
  static const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                              {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  FILE *f = fopen(path, "w");
  CHECK(f != NULL);
  if (!f) return;
  fprintf(f, "OFF\n8 12 0\n");
  for (int i = 0; i < 8; i++)
    fprintf(f, "%g %g %g\n", i & 1 ? hi : lo, i & 2 ? hi : lo, i & 4 ? hi : lo);
  for (int k = 0; k < 6; k++)
    fprintf(f, "3 %d %d %d\n3 %d %d %d\n", q[k][0], q[k][1], q[k][2], q[k][0], q[k][2], q[k][3]);
  fclose(f);
}

/* The two cubes meshed with `threads` threads, written as ASCII .msh. */
static void write_cubes(const char *path, int threads) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = 7;
  p.threads = threads;
  mx_mesher *m = mx_mesher_new(&p);
  CHECK(m != NULL);
  if (!m) return;
  CHECK(mx_mesher_add_surface(m, DIR "/outer.off") == MX_OK);
  CHECK(mx_mesher_add_surface(m, DIR "/inner.off") == MX_OK);
  CHECK(mx_mesher_mesh(m) == MX_OK);
  CHECK(mx_mesher_write(m, path, 1) == MX_OK);
  mx_mesher_free(m);
}

/* The surface entities' boxes: tag t's in box[t] (t 1, 2); 1 when the
 * $Entities section has the two surfaces and one volume. */
static int surface_boxes(const char *path, double box[3][6]) {
  size_t len = 0;
  char *text = slurp(path, &len);
  const char *e = text ? strstr(text, "$Entities\n") : NULL;
  int ok = 0;
  long np, nc, ns, nv;
  if (e && sscanf(e, "$Entities %ld %ld %ld %ld", &np, &nc, &ns, &nv) == 4 && np == 0 &&
      nc == 0 && ns == 2 && nv == 1) {
    const char *line = strchr(strchr(e, '\n') + 1, '\n') + 1;
    ok = 1;
    for (int k = 0; k < 2 && ok; k++) {
      int tag;
      double b[6];
      ok = sscanf(line, "%d %lf %lf %lf %lf %lf %lf", &tag, b, b + 1, b + 2, b + 3, b + 4,
                  b + 5) == 7 && tag == k + 1;
      if (ok) memcpy(box[tag], b, sizeof b);
      line = strchr(line, '\n') + 1;
    }
  }
  free(text);
  return ok;
}

int main(void) {
  mkdir(DIR, 0755);
  /* one mesher, every file in turn: made once, read four times */
  mx_mesher *m = demo_mesher();
  CHECK(mx_mesher_write(m, DIR "/all.vtu", 0) == MX_OK);
  CHECK(mx_mesher_write(m, DIR "/all.msh", 0) == MX_OK);
  CHECK(mx_mesher_write(m, DIR "/all.mesh", 0) == MX_OK);
  CHECK(mx_mesher_write_boundary(m, DIR "/all_b.off") == MX_OK);
  CHECK(mx_mesher_write(m, DIR "/again.vtu", 0) == MX_OK);
  write_alone(DIR "/one.vtu", 0);
  write_alone(DIR "/one.msh", 0);
  write_alone(DIR "/one.mesh", 0);
  write_alone(DIR "/one_b.off", 1);
  CHECK(files_equal(DIR "/all.vtu", DIR "/one.vtu"));
  CHECK(files_equal(DIR "/all.msh", DIR "/one.msh"));
  CHECK(files_equal(DIR "/all.mesh", DIR "/one.mesh"));
  CHECK(files_equal(DIR "/all_b.off", DIR "/one_b.off"));
  CHECK(files_equal(DIR "/again.vtu", DIR "/one.vtu"));

  /* the faces before: the cache's against ours */
  mx_mesh_arrays a;
  CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
  face_key *before = NULL;
  const size_t nbefore = boundary_faces(&a, &before);
  mx_boundary_arrays ba;
  CHECK(mx_mesher_boundary_arrays(m, &ba) == MX_OK);
  CHECK(same_faces(&ba, before, nbefore));
  CHECK(off_faces(DIR "/all_b.off") == (long)nbefore);
  mx_boundary_arrays_free(&ba);
  /* elements on the boundary, refined: the boundary changes */
  uint64_t pick[8];
  size_t npick = 0;
  for (size_t i = 0; i < nbefore && npick < 8; i += nbefore / 8 + 1) pick[npick++] = before[i].elem;
  free(before);
  CHECK(npick >= 4);
  CHECK(mx_mesher_refine_elements(m, pick, npick) == MX_OK);
  CHECK(mx_mesher_write_boundary(m, DIR "/after_b.off") == MX_OK);
  CHECK(mx_mesher_write(m, DIR "/after.msh", 0) == MX_OK);
  CHECK(mx_mesher_mesh_arrays(m, &a) == MX_OK);
  face_key *after = NULL;
  const size_t nafter = boundary_faces(&a, &after);
  CHECK(nafter != nbefore); /* else the test proves nothing */
  CHECK(off_faces(DIR "/after_b.off") == (long)nafter);
  CHECK(mx_mesher_boundary_arrays(m, &ba) == MX_OK);
  CHECK(same_faces(&ba, after, nafter));
  CHECK(ba.nelements == a.nelements);
  mx_boundary_arrays_free(&ba);
  free(after);
  mx_mesher_free(m);
  /* the same re-mesh with nothing written before it */
  m = demo_mesher();
  CHECK(mx_mesher_refine_elements(m, pick, npick) == MX_OK);
  CHECK(mx_mesher_write(m, DIR "/fresh.msh", 0) == MX_OK);
  mx_mesher_free(m);
  CHECK(files_equal(DIR "/after.msh", DIR "/fresh.msh"));
  CHECK(!files_equal(DIR "/after.msh", DIR "/all.msh"));

  /* two inputs: each tag's box is its cube's (the faces lie on it and
   * reach its corners), whatever the threads */
  write_cube(DIR "/outer.off", 0.0, 1.0);
  write_cube(DIR "/inner.off", 0.3, 0.7);
  write_cubes(DIR "/cubes1.msh", 1);
  write_cubes(DIR "/cubes2.msh", 2);
  CHECK(files_equal(DIR "/cubes1.msh", DIR "/cubes2.msh"));
  double box[3][6];
  CHECK(surface_boxes(DIR "/cubes2.msh", box));
  for (int a = 0; a < 3; a++) {
    CHECK(fabs(box[1][a]) < 1e-12 && fabs(box[1][3 + a] - 1.0) < 1e-12);
    CHECK(fabs(box[2][a] - 0.3) < 1e-12 && fabs(box[2][3 + a] - 0.7) < 1e-12);
  }
  return TEST_DONE();
}
