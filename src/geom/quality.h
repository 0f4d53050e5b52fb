/* Element quality: J_ENS, the element normalized scaled Jacobian of Lobos &
 * Gonzalez (2015), section 3, one small pure function per element type.
 *
 * At a node with three neighbours a, b, c in the element, J_S is the triple
 * product (d_a x d_b) . d_c of the unit vectors from the node to them, the
 * neighbours taken in the order that makes it +1 at a right-angled corner of
 * a positively oriented element. J_ENS maps J_S with the type's constant k
 * (the J_S of the equilateral element: tet and pyramid sqrt(2)/2, prism
 * sqrt(3)/2, hex 1):  J_S > k: (1 + k) - J_S;  |J_S| <= k: J_S / k;
 * J_S < -k: -(1 + k) - J_S. The pyramid's apex takes the least positive J_S
 * of its four tetrahedra with consecutive base nodes (the largest negative
 * if none is positive). The element's quality is the least J_ENS over its
 * nodes when all are positive, else the largest negative one.
 *
 * Nodes are in VTK order; the first face's right-hand normal points into the
 * element (tet 0-1-2 towards 3, pyramid base 0-1-2-3 towards 4, prism 0-1-2
 * towards 3-4-5, hexahedron 0-1-2-3 towards 4-5-6-7). */
#ifndef MX_QUALITY_H
#define MX_QUALITY_H

#include <stddef.h>
#include <stdint.h>

/* The contract of a valid mesh (exit 0): every element's J_ENS at least
 * this. Below it an element is inverted or degenerate (nodes collinear or
 * coplanar): "invalid" everywhere in mixoct. */
#define MX_JENS_VALID 1e-6
static inline int mx_jens_invalid(double q) { return !(q >= MX_JENS_VALID); }

double mx_jens_tet(const double p[4][3]);
double mx_jens_pyramid(const double p[5][3]);
double mx_jens_prism(const double p[6][3]);
double mx_jens_hex(const double p[8][3]);
/* Dispatch on MX_TET .. MX_HEX (soa/mesh.h); p holds the element's nodes. */
double mx_jens(int type, const double (*p)[3]);

/* Signed volume of a linear element, its faces split into triangles around
 * each face's centroid (so two elements sharing a face agree exactly). */
double mx_element_volume(int type, const double (*p)[3]);

/* The quality table printed after each run: the J_ENS histogram with the
 * bins of Table IV of the 2015 paper and min / max / mean per element type
 * (Table V). Sums are formed in fixed chunks, so the table is the same for
 * any thread count. */
#define MX_QBINS 6
static const double mx_qbin_upper[MX_QBINS] = {0.03, 0.2, 0.4, 0.6, 0.8, 1.0};
typedef struct {
  size_t count[4];
  double min[4], max[4], mean[4];
  size_t bins[MX_QBINS]; /* < 0.03 (including <= 0), < 0.2, < 0.4, < 0.6, < 0.8, <= 1 */
  size_t invalid;        /* J_ENS < 1e-6 */
  size_t below_02;       /* J_ENS < 0.2 */
  double min_all;
} mx_quality_table;

void mx_quality_tabulate(const uint8_t *type, const float *jens, size_t n,
                         mx_quality_table *q);

#endif
