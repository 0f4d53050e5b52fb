/* The C calls added for bindings (issue 30, item 1), through the public
 * header only:
 *   - mx_mesher_cancel from a progress hook: the call returns MX_ECANCELED
 *     at once ("cancelled" is its name), leaves no mesh, and the next
 *     mx_mesher_mesh gives the mesh a fresh mesher gives (same leaves hash
 *     and counts); a cancel asked for between two calls stops neither; the
 *     2D mesher's cancel between calls likewise;
 *   - mx_mesher_boundary_arrays: every boundary face is a face of the
 *     element it names (its nodes among the element's), used by no other
 *     element (counted here by brute force over the elements' node sets),
 *     and as many faces as the --boundary file's cells; bodies 1..nbodies;
 *   - mx_mesher_detach_mesh_buffers: the old pointers are those
 *     mx_mesher_mesh_arrays gave, their values unchanged after a re-mesh
 *     (the mesher works on the copies), and mx_mesh_arrays now gives other
 *     pointers. */
#include "check.h"
#include "mixoct.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void quiet(void *user, int level, const char *text) {
  (void)user, (void)level, (void)text;
}

typedef struct {
  mx_mesher *m;
  const char *at;
  int stages;
} stopper;

static void on_stage(void *user, const char *name) {
  stopper *s = user;
  s->stages++;
  if (s->at && !strcmp(name, s->at)) mx_mesher_cancel(s->m);
}

static mx_mesher *demo(int level) {
  mx_params p;
  mx_params_default(&p);
  p.surface_level = level;
  mx_mesher *m = mx_mesher_new(&p);
  mx_mesher_set_message_handler(m, quiet, NULL);
  CHECK(mx_mesher_add_demo_surface(m) == MX_OK);
  return m;
}

/* nodes of face k are all nodes of element e: the count of element e's
 * nodes among them */
static int face_in(const mx_mesh_arrays *a, const uint32_t *f, int nf, size_t e) {
  int in = 0;
  for (int i = 0; i < nf; i++)
    for (int j = 0; j < 8; j++)
      if (a->conn[8 * e + j] == f[i]) {
        in++;
        break;
      }
  return in;
}

int main(void) {
  /* the reference */
  mx_mesher *ref = demo(4);
  CHECK(mx_mesher_mesh(ref) == MX_OK);
  mx_stats rs;
  mx_mesher_stats(ref, &rs);

  /* cancelled at the boundary stage, then meshed again */
  for (int k = 0; k < 3; k++) {
    static const char *at[3] = {"refine", "transition", "boundary"};
    mx_mesher *m = demo(4);
    stopper s = {m, at[k], 0};
    mx_progress hooks = {on_stage, NULL, NULL, &s};
    mx_mesher_set_progress(m, &hooks);
    CHECK(mx_mesher_mesh(m) == MX_ECANCELED);
    CHECK(!strcmp(mx_status_string(MX_ECANCELED), "cancelled"));
    CHECK(strstr(mx_mesher_last_error(m), "cancelled") != NULL);
    mx_mesh_arrays a;
    CHECK(mx_mesher_mesh_arrays(m, &a) == MX_EINPUT);
    s.at = NULL;
    mx_mesher_cancel(m); /* between two calls: stops nothing */
    CHECK(mx_mesher_mesh(m) == MX_OK);
    mx_stats st;
    mx_mesher_stats(m, &st);
    CHECK(st.leaves_hash == rs.leaves_hash && st.elements == rs.elements && st.nodes == rs.nodes);
    mx_mesher_free(m);
  }

  /* the boundary faces as arrays */
  mx_mesh_arrays a;
  CHECK(mx_mesher_mesh_arrays(ref, &a) == MX_OK);
  mx_boundary_arrays b;
  CHECK(mx_mesher_boundary_arrays(ref, &b) == MX_OK);
  CHECK(b.nfaces == b.ntri + b.nquad && b.nfaces > 0 && b.nelements == a.nelements);
  CHECK(b.nbodies == 1 && b.ntags == 1 && b.material == NULL);
  size_t bad = 0, shared = 0;
  for (size_t k = 0; k < b.nfaces; k++) {
    const uint32_t *f = b.nodes + 4 * k;
    const int nf = f[3] == UINT32_MAX ? 3 : 4;
    CHECK((k < b.ntri) == (nf == 3));
    if (face_in(&a, f, nf, b.element[k]) != nf) bad++;
    if (b.tag[k] != 1) bad++;
    for (size_t e = 0; e < a.nelements; e++) /* no other element has the face */
      if (e != b.element[k] && face_in(&a, f, nf, e) == nf) shared++;
  }
  CHECK(bad == 0);
  CHECK(shared == 0);
  for (size_t e = 0; e < b.nelements; e++) CHECK(b.body[e] == 1);
  mx_boundary_arrays_free(&b);
  CHECK(b.nodes == NULL && b.nfaces == 0);

  /* the old buffers handed over */
  const size_t n = a.nnodes, ne = a.nelements;
  double *xyz = malloc(3 * n * sizeof *xyz);
  uint32_t *conn = malloc(8 * ne * sizeof *conn);
  memcpy(xyz, a.xyz, 3 * n * sizeof *xyz);
  memcpy(conn, a.conn, 8 * ne * sizeof *conn);
  void *old[MX_DETACH_MAX];
  CHECK(mx_mesher_detach_mesh_buffers(ref, old) == MX_OK);
  int found_xyz = 0, found_conn = 0;
  for (int i = 0; i < MX_DETACH_MAX; i++) {
    found_xyz |= old[i] == (const void *)a.xyz;
    found_conn |= old[i] == (const void *)a.conn;
  }
  CHECK(found_xyz && found_conn);
  uint64_t list[2] = {0, 5};
  CHECK(mx_mesher_refine_elements(ref, list, 2) == MX_OK);
  mx_mesh_arrays a2;
  CHECK(mx_mesher_mesh_arrays(ref, &a2) == MX_OK);
  CHECK(a2.xyz != a.xyz && a2.conn != a.conn && a2.nelements > ne);
  CHECK(!memcmp(xyz, a.xyz, 3 * n * sizeof *xyz));
  CHECK(!memcmp(conn, a.conn, 8 * ne * sizeof *conn));
  for (int i = 0; i < MX_DETACH_MAX; i++) mx_free_array(old[i]);
  free(xyz);
  free(conn);
  mx_mesher_free(ref);

  /* 2D: a cancel between calls stops nothing; the status is the same */
  mx_params2d p2;
  mx_params2d_default(&p2);
  p2.surface_level = 4;
  mx_mesher2d *q = mx_mesher2d_new(&p2);
  mx_mesher2d_set_message_handler(q, quiet, NULL);
  double xy[8] = {0, 0, 1, 0, 1, 1, 0, 1};
  uint32_t seg[8] = {0, 1, 1, 2, 2, 3, 3, 0};
  CHECK(mx_mesher2d_set_domain_arrays(q, "square", 4, xy, 4, seg) == MX_OK);
  mx_mesher2d_cancel(q);
  CHECK(mx_mesher2d_mesh(q) == MX_OK);
  void *old2[MX_DETACH_MAX];
  CHECK(mx_mesher2d_detach_mesh_buffers(q, old2) == MX_OK);
  for (int i = 0; i < MX_DETACH_MAX; i++) mx_free_array(old2[i]);
  mx_mesh2d_arrays a3;
  CHECK(mx_mesher2d_mesh_arrays(q, &a3) == MX_OK && a3.ncells > 0);
  mx_mesher2d_free(q);

  if (mx_test_failures) {
    fprintf(stderr, "%d failure(s)\n", mx_test_failures);
    return 1;
  }
  printf("binding API: cancel, boundary arrays, detached buffers ok\n");
  return 0;
}
