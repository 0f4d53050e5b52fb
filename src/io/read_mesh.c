/* mixoct: reading a volume mesh file (see read_mesh.h): the file is mapped
 * (or loaded) whole, its format recognised from its first bytes (or, for the
 * published mesher's text files, its extension), and the reader of that
 * format called: legacy VTK (read_vtk.c), VTU (read_vtu.c; a .pvtu master:
 * read_pvtu.c), Gmsh MSH 4.1 and 2.2 (read_msh.c, read_msh22.c), Medit .mesh / .meshb
 * (read_medit.c), M3D and MVM (read_m3d.c), GetFEM (read_getfem.c); and a
 * mesh that is 2D or 3D by its content (mx_read_mesh_dim; an OFF file as a
 * 2D mesh: read_off_plane.c). */
#include "io/read_mesh.h"

#include <fcntl.h>
#include <string.h>
#include <strings.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/common.h"
#include "io/mesh_reader.h"
#include "io/text_scan.h"

/* Whether the first token at p (after blank lines, and '%' comment lines
 * when percent is set) is word. */
static int first_word_is(const rd *r, const char *p, int percent,
                         const char *word) {
  const char *t = percent ? mx_rd_skip_percent_lines(r, p) : skip_ws(p, r->end);
  return tok_eq(t, tok_len(t, r->end), word);
}

/* Whether the last path component ends with ext. */
static int has_extension(const char *path, const char *ext) {
  const size_t n = strlen(path), e = strlen(ext);
  return n > e && strcasecmp(path + n - e, ext) == 0;
}

/* The reader of the M3D, MVM and GetFEM files: chosen by content, else
 * by the extension (for a message in that format's terms). NULL if none. */
typedef int (*text_reader)(rd *, const char *, mx_mesh_data *);
static text_reader published_reader(const rd *r, const char *p) {
  if (first_word_is(r, p, 0, "[Nodes,")) return mx_rd_m3d;
  if (first_word_is(r, p, 0, "MIXED")) return mx_rd_mvm;
  if ((p < r->end && *p == '%') || first_word_is(r, p, 1, "BEGIN"))
    return mx_rd_getfem;
  if (has_extension(r->path, ".m3d")) return mx_rd_m3d;
  if (has_extension(r->path, ".mvm")) return mx_rd_mvm;
  if (has_extension(r->path, ".getfem")) return mx_rd_getfem;
  return NULL;
}

/* A regular file whose size is not a multiple of the page size is mapped:
 * no copy, and the rest of its last page reads as zeros, so the text is
 * NUL-terminated like a loaded one. Anything else is loaded. *mapped
 * receives the mapping's length, or 0. */
static int load(const char *path, char **buf, size_t *len, size_t *mapped) {
  *mapped = 0;
  const long page = sysconf(_SC_PAGESIZE);
  int fd = open(path, O_RDONLY | O_CLOEXEC);
  if (fd >= 0) {
    struct stat st;
    if (fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0 &&
        page > 0 && st.st_size % page != 0) {
      void *p = mmap(NULL, (size_t)st.st_size, PROT_READ,
                     MAP_PRIVATE | MAP_POPULATE, fd, 0);
      if (p != MAP_FAILED) {
        close(fd);
        *buf = p;
        *len = (size_t)st.st_size;
        *mapped = *len;
        return MX_OK;
      }
    }
    close(fd);
  }
  return mx_io_load(path, buf, len); /* and its messages */
}

/* A mesh file; with piece set, a piece of a .pvtu: a VTU file only, its
 * GlobalNodeId and array signatures in *piece (piece->gid freed on
 * failure). */
int mx_rd_file(const char *path, int planar, piece_info *piece, mx_mesh_data *out) {
  memset(out, 0, sizeof *out);
  if (piece) memset(piece, 0, sizeof *piece);
  char *buf;
  size_t len, mapped;
  MX_CHECK(load(path, &buf, &len, &mapped));
  rd r;
  memset(&r, 0, sizeof r);
  r.path = path;
  r.buf = buf;
  r.end = buf + len;
  r.planar = planar;
  r.piece = piece;
  const char *p = r.buf;
  if (len >= 3 && memcmp(p, "\xEF\xBB\xBF", 3) == 0) p += 3; /* UTF-8 BOM */
  p = skip_ws(p, r.end);
  static const char magic[] = "# vtk DataFile", msh_magic[] = "$MeshFormat";
  int st, vtk = 0;
  if (piece && !(p < r.end && *p == '<')) {
    st = mx_rd_fail(&r, p, "a piece of a .pvtu must be a VTU file (VTK XML UnstructuredGrid)");
  } else if ((size_t)(r.end - p) >= sizeof magic - 1 &&
      strncasecmp(p, magic, sizeof magic - 1) == 0) {
    st = mx_rd_vtk_legacy(&r, out);
    vtk = 1;
  } else if (mx_rd_is_meshb(&r)) {
    st = mx_rd_meshb(&r, out);
  } else if (p < r.end && *p == '<') {
    st = mx_rd_vtu(&r, out);
    vtk = 1;
  } else if ((size_t)(r.end - p) >= sizeof msh_magic - 1 &&
             memcmp(p, msh_magic, sizeof msh_magic - 1) == 0) {
    st = mx_rd_msh(&r, p, out);
  } else if (mx_rd_is_medit_ascii(&r, p)) {
    st = mx_rd_medit_ascii(&r, p, out);
  } else if (published_reader(&r, p)) {
    st = published_reader(&r, p)(&r, p, out);
  } else {
    st = mx_rd_fail(&r, p,
                    "unknown mesh format: expected legacy VTK ('# vtk DataFile "
                    "Version'), VTK XML (.vtu), Gmsh MSH 4.1 or 2.2 ('$MeshFormat'), "
                    "Medit ('MeshVersionFormatted', or a binary .meshb), M3D "
                    "('[Nodes,'), MVM ('MIXED') or GetFEM ('BEGIN POINTS LIST')");
  }
  if (st == MX_OK && vtk && !r.merged) /* VTK wedges to our prism order (mesh.h) */
    for (size_t c = 0; c < out->ncells; c++)
      if (out->type[c] == MX_PRISM) {
        uint32_t row[8];
        memcpy(row, out->conn + 8 * c, sizeof row);
        for (int j = 0; j < 6; j++) out->conn[8 * c + j] = row[mx_vtk_order[MX_PRISM][j]];
      }
  for (int i = 0; i < r.ntmp; i++) mx_free(r.tmp[i]);
  if (mapped)
    munmap(buf, mapped);
  else
    mx_free(buf);
  if (st != MX_OK) {
    mx_mesh_data_free(out);
    if (piece) {
      mx_free(piece->gid);
      piece->gid = NULL;
    }
  }
  return st;
}

int mx_read_mesh(const char *path, mx_mesh_data *out) {
  return mx_rd_file(path, 0, NULL, out);
}

int mx_read_mesh_planar(const char *path, mx_mesh_data *out) {
  return mx_rd_file(path, 1, NULL, out);
}

/* Whether m is a 2D mesh: faces, no volume cell, every z = 0. */
static int planar_faces(const mx_mesh_data *m) {
  if (m->ncells || !m->nfaces) return 0;
  size_t off = 0;
#pragma omp parallel for schedule(static) reduction(+ : off) if (m->nnodes > 65536)
  for (size_t i = 0; i < m->nnodes; i++) off += m->xyz[3 * i + 2] != 0.0;
  return off == 0;
}

int mx_read_mesh_dim(const char *path, mx_mesh_data *out, int *dim) {
  memset(out, 0, sizeof *out);
  *dim = 3;
  if (mx_rd_is_off(path)) {
    MX_CHECK(mx_rd_off_plane(path, out));
    *dim = 2;
    return MX_OK;
  }
  MX_CHECK(mx_read_mesh_planar(path, out));
  if (planar_faces(out)) *dim = 2;
  return MX_OK;
}
