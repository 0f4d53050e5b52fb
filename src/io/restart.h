/* mixoct: restart files (Appendix A of Jaillet & Lobos 2021), text and
 * binary, as a neutral in-memory struct independent of the octree.
 *
 * ---- The text format (what the published program writes and reads) ----
 *
 *   20506 81363 10123              header: nodes edges octants
 *   (blank)
 *   +2.85692000E-01  +2.21920000E-02  +1.91885460E+01
 *   ...                            nv node lines, "%+1.8E" two blanks apart
 *   (blank)
 *   0 1 21                         ne edge lines: a b mid (0: not split)
 *   ...
 *   (blank)
 *   8 4979 4975 4967 4976 4978 4970 1316 4971 5
 *   2 4739 4854                    no octants of two lines: "8", 8 corner
 *   ...                            nodes, level; the count of intersected
 *                                  input faces, their indices ("0": none)
 *   (blank)
 *   Geometric Transform
 *   0.000000 0.000000 0.000000     two lines of three numbers ("%f")
 *   0.000000 0.000000 0.000000
 *   (blank)
 *   1 4 1 1 ...                    octant sub-elements: no counts on one
 *                                  line, each followed by a blank
 *
 * Corner order of an octant [x0,x1] x [y0,y1] x [z0,z1] (the published
 * program's; the reader does not depend on it):
 *   0 (x0,y0,z0)  1 (x0,y0,z1)  2 (x1,y0,z1)  3 (x1,y0,z0)
 *   4 (x0,y1,z0)  5 (x0,y1,z1)  6 (x1,y1,z1)  7 (x1,y1,z0)
 * i.e. the face y = y0 as 0 1 2 3, and 4..7 the same corners at y = y1.
 *
 * The writer reproduces that layout byte for byte (the published file
 * c5.oct reads and writes back identically). Coordinates keep 9 significant
 * digits and the transform 6 decimals, as in the published program; the
 * binary variant keeps every bit.
 *
 * Reading is tolerant of layout: blanks, tabs, CR, blank lines and '#'
 * comments (to the end of the line) anywhere; one item per line (a node, an
 * edge, each of the two lines of an octant, each transform line); the
 * "Geometric Transform" title line may be missing, and so may the transform
 * and the sub-element sections. Without the title, what follows the octants
 * is told apart by its count of numbers: 6 + no (transform, then
 * sub-elements), 6 (transform; when no == 6 and the six are all plain
 * integers, sub-elements), no (sub-elements), 0 (neither). The sub-element
 * counts may span lines. It is strict on content: the counts of the header
 * (truncated or extra data is refused), 8 corners an octant (4, a quadtree
 * file, is refused), node indices < nv, levels 0..MX_RESTART_MAX_LEVEL,
 * finite coordinates, no negative or overflowing numbers, exactly no
 * sub-element counts, nothing after the last section, no >= 1 and
 * nv <= UINT32_MAX.
 *
 * ---- The quadtree form (2D, dim = 2; Appendix A: "combination of quadrants
 * and octants is not allowed in a same file") ----
 *   nodes "x y" (2 numbers), cells "4 n0 n1 n2 n3 level" with the corners
 *   counter-clockwise from the lowest: (x0,y0) (x1,y0) (x1,y1) (x0,y1); the
 *   intersected faces are the domain's segments; the same edge, transform
 *   (3 numbers a line) and sub-element sections. Text only.
 *
 * ---- The binary variant (ours, ".octb"), little-endian ----
 *
 *   bytes 0..7    magic 0x89 'M' 'X' 'O' 'C' 'T' '\r' '\n'
 *   u32 version (1), u32 flags (bit 0: transform, bit 1: nsub)
 *   u64 nv, ne, no, ntri (ntri: total length of oct_tri)
 *   then the sections, each zero-padded to a multiple of 8 bytes:
 *   xyz f64[3 nv], edge u32[3 ne], oct_node u32[8 no], oct_level u8[no],
 *   per-octant face counts u32[no], oct_tri u32[ntri],
 *   transform f64[6] (flag bit 0), nsub u32[no] (flag bit 1), the mesh
 *   (flag bit 2, see below), flag bit 3: by_type, flag bit 4: materials,
 *   and last a u64 checksum of every byte before it (4-lane multiply-xorshift
 *   over 8-byte words: any change confined to one word is always detected).
 * The reader checks the magic, version and flags, then the file size
 * against the sizes (before allocating anything), the checksum, and the
 * same semantic checks as for text.
 *
 * Every function returns MX_OK, MX_EINPUT (bad or unreadable file) after one
 * message naming the file (and the line, for text), or MX_ENOMEM; the
 * writers return what the atomic-file helpers return on a write failure and
 * MX_EINTERNAL for an inconsistent struct. On failure *r is left empty. */
#ifndef MX_RESTART_H
#define MX_RESTART_H

#include <stddef.h>
#include <stdint.h>

enum { MX_RESTART_MAX_LEVEL = 16, MX_RESTART_MAX_LEVEL2D = 27 };
#define MX_RESTART_BY_TYPE "# mixoct: element indices grouped by type"
#define MX_RESTART_MATERIALS "# mixoct: several materials (--materials)"

typedef struct mx_restart {
  int dim;               /* 3 (0 also means 3): octants of 8 corners, nodes
                          * "x y z"; 2: the quadtree form, quadrants of 4
                          * corners "4 n0 n1 n2 n3 level", nodes "x y"
                          * (xyz keeps 3 per node, z = 0), text only */
  size_t nv, ne, no;     /* header: nodes, edges, octants */
  double *xyz;           /* 3*nv */
  uint32_t *edge;        /* 3*ne: node a, node b, mid node (0: not split) */
  uint32_t *oct_node;    /* 8*no: corner nodes in the order above */
  uint8_t *oct_level;    /* no */
  uint64_t *oct_tri_off; /* no+1, CSR offsets into oct_tri */
  uint32_t *oct_tri;     /* input faces (triangles) each octant intersects */
  int has_transform;     /* the "Geometric Transform" section is present */
  double transform[6];   /* its two lines */
  uint32_t *nsub;        /* no: mesh elements per octant; NULL if absent */
  int by_type;           /* the mesh written with this file numbers its
                          * elements grouped by type (mixoct's written order,
                          * io/cell_order.c), so element lists refer to that
                          * order; 0: octant by octant (the published
                          * program's). Text: the last line is the comment
                          * MX_RESTART_BY_TYPE; binary: flag bit 3. */
  int materials;         /* written by a mesher with several materials (a
                          * shell inside another is a material, not a
                          * hole): text, the comment MX_RESTART_MATERIALS
                          * after the last section; binary: flag bit 4 */
  /* Text writing only, optional: rows made while the file is written
   * instead of stored, block by block by the writer's threads (a mesher's
   * restart file: the lookups that give the edges' ends and mid-nodes and
   * the octants' corners then overlap the disk's writing, and the arrays
   * are never allocated). When a generator is set, its array (xyz, edge,
   * oct_node) may be NULL; rows must be valid (finite coordinates, node
   * indices below nv). */
  void (*node_rows)(const void *gen, size_t begin, size_t end, double *xyz); /* 3 a node */
  void (*edge_rows)(const void *gen, size_t begin, size_t end, uint32_t *rows); /* 3 a row */
  void (*oct_rows)(const void *gen, size_t begin, size_t end, uint32_t *rows);  /* 8 a row */
  const void *gen;
  /* Binary variant only, optional: the mesh written with the file (the
   * full stage: element -> octant, node lattice keys and states), so that
   * a re-mesh from the file is local (mesher/remesh_patch.c). Elements are
   * grouped by octant, nsub[i] of them for octant i. */
  int has_mesh;
  size_t mesh_nn, mesh_nc;
  double *mesh_xyz;      /* 3*mesh_nn */
  uint64_t *mesh_nkey;   /* mesh_nn: lattice key, UINT64_MAX off the lattice */
  uint8_t *mesh_state;   /* mesh_nn: 0 on the boundary, 1 inside */
  uint8_t *mesh_type;    /* mesh_nc: MX_TET .. MX_HEX */
  uint32_t *mesh_conn;   /* 8*mesh_nc, rows padded with UINT32_MAX */
  uint32_t *mesh_leaf;   /* mesh_nc: octant index, non-decreasing */
  double *mesh_jens;     /* mesh_nc */
} mx_restart;

/* Reads a restart file, text or binary (told by the binary magic). */
int mx_restart_read(const char *path, mx_restart *r);
/* The same for a dimension: 3 as mx_restart_read, 2 the quadtree form (text;
 * an octree file is refused, as a quadtree file is by mx_restart_read). */
int mx_restart_read_dim(const char *path, int dim, mx_restart *r);
int mx_restart_parse_dim(const char *name, const uint8_t *buf, size_t len, int dim,
                         mx_restart *r);
/* The same from memory; name is used in messages. */
int mx_restart_parse(const char *name, const uint8_t *buf, size_t len,
                     mx_restart *r);
/* Writers, through the atomic-file helpers (temporary name, renamed when
 * complete). The text file has the transform section only when
 * has_transform is set (the published program always writes one: set it,
 * with zeros, for files that program must read) and the sub-element line
 * only when nsub is not NULL. */
int mx_restart_write_text(const char *path, const mx_restart *r);
int mx_restart_write_binary(const char *path, const mx_restart *r);
/* Frees the arrays (mx_free) and zeroes *r. */
void mx_restart_free(mx_restart *r);

#endif
