/* The 27 lattice points of an octant and the 24 rotations of the cube.
 *
 * Coordinates are in half sides, each of x, y, z in {0, 1, 2}. Numbering:
 *   0..7    corners: (x/2) + 2 (y/2) + 4 (z/2)  (the Morton child order)
 *   8..19   edge midpoints: 8 + 4a + j for the edge along axis a (0 x, 1 y,
 *           2 z), j = (p_b / 2) + 2 (p_c / 2) with b = a+1, c = a+2 (mod 3)
 *   20..25  face centres: 20 + 2a + s, s = 0 on the face p_a = 0, 1 on p_a = 2
 *   26      body centre
 * An octant's node mask has bit i set when lattice point i is a node of the
 * mesh; corners always are. The 18 bits 8..25 ("the configuration") say which
 * edges are split and which faces have a centre (a face centre only where
 * all four edges of that face are split); bit 26, the body centre, is added
 * by the octant itself when its pattern needs it.
 *
 * Rotations are the 24 proper rotations about the body centre, as
 * permutations of the 27 points: point i goes to mx_rot_perm[r][i]. They keep
 * orientation, so rotated elements stay positive.
 *
 * Face patterns (one subdivision of a square face per configuration of its
 * four edges and centre, the same whichever octant looks at it):
 *
 *   none split      one split        two adjacent      two opposite
 *   3-------2       3-------2        3-------2         3---m2---2
 *   |       |       |\     /|        |\   _-/|         |   |    |
 *   |       |       | \   / |        | \ /  m1         |   |    |
 *   |       |       |  \ /  |        |  /\_  |         |   |    |
 *   0-------1       0---m0--1        0-m0---1          0---m0---1
 *   1 quad          3 triangles      4 triangles       2 quads
 *                   fanned from m0   (c0 m0 c3)(m0 c1 m1)(m0 m1 c3)(m1 c2 c3)
 *
 *   three split     four, no centre  four with centre
 *   3---m2---2      3---m2---2       3---m2---2
 *   |   / \  |      |  / \   |       |   |    |
 *  m3--/---\m1     m3 <   > m1      m3---f---m1
 *   |        |      |  \ /   |       |   |    |
 *   0--------1      0---m0---1       0---m0---1
 *   quad (0 1 m1 m3)  diamond         4 quads
 *   + 3 triangles    (m0 m1 m2 m3)
 *   (m1 2 m2)        + 4 corner
 *   (m2 3 m3)        triangles
 *   (m1 m2 m3)
 * Each is invariant under the symmetries of its configuration, so the two
 * octants sharing a face, whatever their orientation, produce the same face. */
#ifndef MX_LATTICE_H
#define MX_LATTICE_H

#include <stdint.h>

#define MX_LAT_CENTRE 26
#define MX_CONFIG_BITS 18

extern const uint8_t mx_lat_xyz[27][3];
extern uint8_t mx_rot_perm[24][27];
extern uint8_t mx_rot_inv[24];

/* Build the rotation tables (idempotent, thread-safe after the first call
 * returns; call it once at start-up). */
void mx_lattice_init(void);

/* Lattice index of the point (x, y, z) in half sides. */
int mx_lat_index(int x, int y, int z);

/* Rotate a 27-bit mask. */
uint32_t mx_rotate_mask(int r, uint32_t mask);

/* 1 when the 18-bit configuration is legal (a face centre only with all four
 * of its edges split). */
int mx_config_valid(uint32_t config);

/* The face pattern of face f (0..5, = 20+f's centre) for the node mask:
 * writes up to 8 polygons of 3 or 4 lattice indices (poly[k][3] = 255 for a
 * triangle), oriented with their normal out of the octant. Returns the
 * polygon count. */
int mx_face_pattern(int f, uint32_t mask, uint8_t poly[8][4]);

#endif
