/* One field of a VTK file read instead of its mesh: the legacy and XML
 * readers' second mode (mx_rd_vtk_legacy_fields in src/io/read_vtk.c,
 * mx_rd_vtu_fields in src/io/read_vtu.c), for the size maps of
 * src/io/read_sizemap.c.
 *
 * The reader lists the file's arrays of point and cell data (arr), calls
 * pick to choose one, checks that one has a value per point or per cell,
 * and gives its values with the points and, for a cell array, the cells'
 * node lists. It assembles no mesh: cells of any type and node count are
 * accepted, and PolyData too (XML .vtp, legacy DATASET POLYDATA), whose
 * cells come in VTK's order: vertices, lines, polygons, strips (one block
 * each). The rawarrs point into the file or into the rd's temporaries:
 * valid until the caller frees them. Counts are checked against the file
 * as the mesh readers check them; the values themselves (finite, node
 * indices in range) are the caller's to check. */
#ifndef MX_VTK_FIELDS_H
#define MX_VTK_FIELDS_H

#include "io/mesh_reader.h"

enum { RD_MAX_ARRAYS = 256, RD_MAX_BLOCKS = 4 };

/* An array of point or cell data as listed. */
typedef struct {
  const char *name; /* nlen bytes of the file (not NUL-terminated) */
  size_t nlen;
  int point;        /* point data, else cell data */
  uint64_t ncomp;   /* components (XML: 0 when NumberOfComponents is not a count) */
  const char *at;   /* its header (XML: its <DataArray> tag), for messages */
  /* legacy only: the type, the tuples its section announced, and where its
   * values start (after its header's last word) */
  vtype t;
  size_t count;
  const char *data;
} rd_array;

/* A block of cells: a count-prefixed list (legacy CELLS before version 5),
 * or offsets + connectivity: vtu_offsets, ncells end offsets (XML); else
 * ncells + 1 offsets from the first cell's start (legacy 5.x). */
typedef struct {
  size_t ncells;
  int list_form, vtu_offsets;
  rawarr list;    /* list form: for each cell its node count, then its nodes */
  rawarr off, cn; /* offsets form */
  const char *at; /* its section, for messages (NULL: the block is absent) */
} rd_cells;

typedef struct rd_fields {
  /* in: chooses an array of arr (its index in *which), or returns
   * MX_EINPUT after a message; user is its own (a field name) */
  int (*pick)(const rd *r, const struct rd_fields *f, size_t *which);
  const void *user;
  /* out */
  rd_array arr[RD_MAX_ARRAYS];
  size_t narr;
  const char *stopped; /* legacy: the unknown keyword that ended the attributes */
  size_t which;        /* the array picked */
  size_t npts;
  rawarr pts;          /* 3 * npts coordinates */
  rawarr values;       /* the picked array's values, one a point or a cell */
  rd_cells cells[RD_MAX_BLOCKS];
  size_t ncells;       /* in all blocks */
} rd_fields;

/* f->pick and f->user set, the rest zero; r as mx_rd_vtk_legacy and
 * mx_rd_vtu take it (r->piece NULL). */
int mx_rd_vtk_legacy_fields(rd *r, rd_fields *f);
int mx_rd_vtu_fields(rd *r, rd_fields *f);

#endif
