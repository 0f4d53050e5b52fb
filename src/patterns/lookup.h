/* O(1) pattern lookup: a table over the 2^18 configurations (edge and face
 * bits of the node mask, lattice.h) giving the rotation class and the
 * rotation that carries the class's canonical frame onto the octant's. Built
 * once at start-up from the generated table (src/patterns/table.c). */
#ifndef MX_PATTERN_LOOKUP_H
#define MX_PATTERN_LOOKUP_H

#include <stdint.h>

#include "patterns/table.h"

typedef struct {
  uint16_t cls;  /* class index, 0xffff for an illegal configuration */
  uint8_t rot;   /* rotation: canonical lattice index v -> mx_rot_perm[rot][v] */
} mx_pattern_ref;

/* Build the lookup table (thread-safe, idempotent). MX_OK or MX_EINTERNAL if
 * the compiled table does not cover every legal configuration. */
int mx_patterns_init(void);
/* The class and rotation of a configuration (bits 8..25 of the mask >> 8). */
mx_pattern_ref mx_pattern_lookup(uint32_t config);
/* J_ENS of each pattern element on the unit cube (rotations and uniform
 * scaling keep J_ENS, so it is the element's J_ENS in any octant). */
extern double *mx_pattern_elem_jens;

/* 1 when the class's pattern uses the body centre. */
static inline int mx_pattern_has_centre(int cls) {
  return (mx_pattern_classes[cls].mask >> 26) & 1;
}

#endif
