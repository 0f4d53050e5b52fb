/* The mesher's own conformity check after the boundary stage: a node of the
 * mesh lying on a face, an edge or at a vertex of an element it is not a node
 * of (a geometric hanging node). The lattice of the transition patterns is
 * conforming by construction; such contacts appear only where the boundary
 * stage moved nodes: two sheets of the surface projected onto the same
 * place (a thin part, two features meeting, parts of the input touching).
 * Searched among the elements with a surface face and the surface nodes,
 * with the mesher's own code (contacts.c: the elements filed in cells of the
 * octree's lattice, named by lattice keys). The definition is the one of
 * `mixoct check`'s geometric hanging nodes (the checker, src/verify): a
 * node within 1e-9 times half the element's largest extent of a face of the
 * element (a quad: the four triangles from its edges to its centroid); a
 * node at exactly the point of one of the element's nodes is a duplicate,
 * not a contact. The checker finds the same contacts with its own search
 * (tests/test_contacts.c compares the two). */
#ifndef MX_CONTACTS_H
#define MX_CONTACTS_H

#include <stddef.h>
#include <stdint.h>

#include "soa/grid.h"
#include "soa/mesh.h"

typedef struct {
  size_t nodes;     /* nodes lying on an element they are not a node of */
  size_t elements;  /* elements involved: those the nodes lie on, and the
                     * elements using such a node */
  double first[3];  /* the position of the lowest such node */
  uint32_t first_node;
} mx_contacts;

/* states: per node (kernels/boundary.h), MX_NODE_OUTSIDE on the surface;
 * G: the octree's grid (its lattice names the cells of the search; M->level,
 * when not NULL, gives each element's leaf level).
 * elem_flag (M->ncells bytes, or NULL): set to 1 for the elements involved,
 * 0 elsewhere. Deterministic, parallel, O(elements near the surface).
 * MX_OK, or MX_ENOMEM. */
int mx_find_contacts(const mx_mesh *M, const mx_grid *G, const uint8_t *states,
                     uint8_t *elem_flag, mx_contacts *out);
/* The same, searched within the box region (lo x, y, z, then hi; NULL:
 * everywhere): the surface nodes in it against the elements with a surface
 * face whose padded box (mx_contact_box) meets it. Every contact of the
 * mesh is found when every contact has its node or its element changed
 * since a mesh without contacts, and region holds the changed nodes and the
 * padded boxes of the changed elements (a local re-mesh: mx_contact_box of
 * the core's elements). */
int mx_find_contacts_in(const mx_mesh *M, const mx_grid *G, const uint8_t *states,
                        const double *region, uint8_t *elem_flag, mx_contacts *out);
/* Element c's box padded as the search files it (lo, then hi): every point
 * lying on the element in the sense above is inside. */
void mx_contact_box(const mx_mesh *M, size_t c, double box[6]);
/* 1 when a face of element c has surface (outside) nodes only: the
 * elements the search looks at. */
int mx_surface_face(const mx_mesh *M, const uint8_t *states, size_t c);

#endif
