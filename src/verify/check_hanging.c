/* Pass 4 of the checker, hanging nodes: the midpoint 0.5 * (a + b) of every
 * edge of every element is looked up in the coordinate hash of the nodes
 * (exact, bit-equal coordinates); a used node there that is not a node of
 * the element is hanging, and the element is flagged. (The centres of the
 * quad faces are looked up while the faces are matched, check_faces.c.)
 * Nodes lying elsewhere on an element are the geometric hanging nodes of
 * check_contacts.c. */
#include "verify/check_passes.h"

#include "soa/mesh.h"

static const int8_t edge_tab[4][12][2] = {
    {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}},
    {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {0, 4}, {1, 4}, {2, 4}, {3, 4}},
    {{0, 1}, {1, 2}, {2, 0}, {3, 4}, {4, 5}, {5, 3}, {0, 3}, {1, 4}, {2, 5}},
    {{0, 1},
     {1, 2},
     {2, 3},
     {3, 0},
     {4, 5},
     {5, 6},
     {6, 7},
     {7, 4},
     {0, 4},
     {1, 5},
     {2, 6},
     {3, 7}}};
static const int nedges[4] = {6, 8, 9, 12};

void mx_ck_edge_midpoints(const mx_mesh_data *m, const chash *H,
                           uint8_t *flags, uint8_t *ef) {
#pragma omp parallel for schedule(dynamic, 4096) if (m->ncells > SMALL)
  for (size_t c = 0; c < m->ncells; c++) {
    const int t = m->type[c], ne = nedges[t];
    const uint32_t *row = m->conn + 8 * c;
    double q[12][3];
    cprobe p[12];
    int live[12];
    for (int e = 0; e < ne; e++) {
      midpoint(m->xyz + 3 * (size_t)row[edge_tab[t][e][0]],
               m->xyz + 3 * (size_t)row[edge_tab[t][e][1]], q[e]);
      live[e] = chash_probe(H, q[e], &p[e]);
      if (live[e]) __builtin_prefetch(&H->slot[p[e].base + (p[e].h & p[e].mask)]);
    }
    int hit = 0;
    for (int e = 0; e < ne; e++)
      if (live[e])
        hit |= mark_hanging(flags, chash_lookup(H, q[e], &p[e]), row,
                            mx_cell_nodes[t]);
    if (hit) eflag(ef, c, MX_CK_HANGING);
  }
}
