// mixoct bench (issue 26): the reference side of bench/cgal_materials_bench.sh.
// Meshes nested closed triangulated shells (one OFF file, as mixoct
// --materials reads it: tests/make_surfaces.py's shell.off) into tetrahedra
// with CGAL's Mesh_3 and writes a Medit .mesh whose tetrahedra carry the
// sub-domain index, numbered as mixoct numbers its materials: by nesting
// depth (1 inside one shell, 2 inside two, ...).
//
//   mesh3_materials IN.off OUT.mesh --facet-size S [--facet-distance D]
//                   [--cell-size C] [--facet-angle A] [--cell-ratio R]
//                   [--no-perturb] [--no-exude] [--seed N]
//
// The domain is CGAL::Polyhedral_complex_mesh_domain_3 over the shells of
// the file (its connected components, each a closed surface), with for each
// shell the sub-domain behind its facets and the one their normals point
// to (see `sides` below for the order). A shell at depth d (inside d other
// shells) bounds region d + 1 inside and region d outside; the normals of
// an outward oriented shell (positive enclosed volume) point to the
// outside, those of an inward one (the cavity of shell.off) to the inside.
//
// Criteria (CGAL::Mesh_criteria_3): facet_size, facet_distance, facet_angle
// (default 25 degrees), cell_size (default: the facet size), cell
// radius-edge ratio (default 3); a value 0 leaves that criterion out.
// The default optimisation of make_mesh_3 (perturb, exude) runs unless
// turned off.
//
// Output (Medit ASCII, "MeshVersionFormatted 2"): the vertices of the
// complex; the facets of the complex as Triangles with the shell's number
// (1-based, in file order of the shells' first faces) as reference,
// oriented outward from the material of smaller number on their two sides
// (outward from the mesh on its boundary), as mixoct writes its interface
// faces; the tetrahedra of the complex with det(p1-p0, p2-p0, p3-p0) > 0
// (CGAL's positive orientation, Medit's convention) and the sub-domain as
// reference. One JSON object on the last line of stdout: the counts and
// the times (read, domain, mesh = make_mesh_3, write, total).
//
// Written for mixoct against CGAL's documented API (Mesh_3 user manual and
// reference, CGAL 5.5); build: g++ -O2 -DNDEBUG ... -lgmp -lmpfr.

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polyhedral_complex_mesh_domain_3.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/make_mesh_3.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;
typedef CGAL::Mesh_polyhedron_3<K>::type Polyhedron;
typedef CGAL::Polyhedral_complex_mesh_domain_3<K> Domain;
typedef CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type Tr;
typedef CGAL::Mesh_complex_3_in_triangulation_3<Tr, Domain::Corner_index, Domain::Curve_index>
    C3t3;
typedef CGAL::Mesh_criteria_3<Tr> Criteria;

typedef std::chrono::steady_clock Clock;
double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

[[noreturn]] void fail(const std::string &msg) {
  std::cerr << "mesh3_materials: " << msg << "\n";
  std::exit(2);
}

// ---- input: an OFF file of triangles ---------------------------------------

struct Soup {
  std::vector<Point> v;
  std::vector<std::array<std::size_t, 3>> f;
};

// The next whitespace-separated word of an OFF stream, '#' comments skipped.
bool next_word(std::istream &in, std::string &w) {
  while (in >> w) {
    if (w[0] != '#') return true;
    std::string rest;
    std::getline(in, rest);
  }
  return false;
}

Soup read_off(const char *path) {
  std::ifstream in(path);
  if (!in) fail(std::string("cannot open ") + path);
  std::string w;
  if (!next_word(in, w) || w != "OFF") fail(std::string(path) + ": not an OFF file");
  auto num = [&](const char *what) {
    if (!next_word(in, w)) fail(std::string(path) + ": truncated at " + what);
    char *end = nullptr;
    const double x = std::strtod(w.c_str(), &end);
    if (*end) fail(std::string(path) + ": bad number '" + w + "' at " + what);
    return x;
  };
  const long nv = (long)num("the counts"), nf = (long)num("the counts");
  num("the counts");
  if (nv < 4 || nf < 4) fail(std::string(path) + ": too few vertices or faces");
  Soup s;
  for (long i = 0; i < nv; i++) {
    const double x = num("a vertex"), y = num("a vertex"), z = num("a vertex");
    s.v.emplace_back(x, y, z);
  }
  for (long i = 0; i < nf; i++) {
    if ((long)num("a face") != 3) fail(std::string(path) + ": a face is not a triangle");
    std::array<std::size_t, 3> t;
    for (auto &k : t) {
      const double x = num("a face");
      if (x < 0 || x >= (double)nv) fail(std::string(path) + ": vertex index out of range");
      k = (std::size_t)x;
    }
    s.f.push_back(t);
  }
  return s;
}

// ---- the shells: connected components of the faces -------------------------

struct Shell {
  Soup soup;          // its own vertices, renumbered
  double volume = 0;  // signed: > 0 when oriented outward
  int depth = 0;      // number of other shells around it
};

std::vector<Shell> split_shells(const Soup &in) {
  std::vector<std::size_t> parent(in.v.size());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (const auto &t : in.f) {
    parent[find(t[0])] = find(t[1]);
    parent[find(t[1])] = find(t[2]);
  }
  std::map<std::size_t, std::size_t> shell_of_root;  // in order of first face
  std::vector<Shell> shells;
  std::vector<std::map<std::size_t, std::size_t>> renumber;
  for (const auto &t : in.f) {
    const std::size_t r = find(t[0]);
    auto it = shell_of_root.find(r);
    if (it == shell_of_root.end()) {
      it = shell_of_root.emplace(r, shells.size()).first;
      shells.emplace_back();
      renumber.emplace_back();
    }
    Shell &s = shells[it->second];
    auto &map = renumber[it->second];
    std::array<std::size_t, 3> u;
    for (int k = 0; k < 3; k++) {
      auto m = map.find(t[k]);
      if (m == map.end()) {
        m = map.emplace(t[k], s.soup.v.size()).first;
        s.soup.v.push_back(in.v[t[k]]);
      }
      u[k] = m->second;
    }
    s.soup.f.push_back(u);
  }
  for (Shell &s : shells) {
    const Point &o = s.soup.v[0];
    for (const auto &t : s.soup.f)
      s.volume += CGAL::determinant(s.soup.v[t[0]] - o, s.soup.v[t[1]] - o, s.soup.v[t[2]] - o) / 6;
  }
  return shells;
}

// ---- the mesh --------------------------------------------------------------

struct Options {
  double facet_size = 0, facet_distance = 0, facet_angle = 25, cell_size = -1, cell_ratio = 3;
  bool perturb = true, exude = true;
  unsigned seed = 0;
};

void write_medit(const char *path, const C3t3 &c3t3, std::size_t counts[3]) {
  std::map<Tr::Vertex_handle, std::size_t> id;
  std::vector<Tr::Vertex_handle> verts;
  auto number = [&](Tr::Vertex_handle v) {
    auto it = id.find(v);
    if (it != id.end()) return it->second;
    verts.push_back(v);
    return id[v] = verts.size();
  };
  std::vector<std::array<std::size_t, 5>> tets;
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    std::array<std::size_t, 5> e;
    for (int k = 0; k < 4; k++) e[k] = number(c->vertex(k));
    e[4] = (std::size_t)c3t3.subdomain_index(c);
    tets.push_back(e);
  }
  std::vector<std::array<std::size_t, 4>> tris;
  for (auto f = c3t3.facets_in_complex_begin(); f != c3t3.facets_in_complex_end(); ++f) {
    // the cell on the side the triangle must face away from: the material
    // of smaller non-zero number (the only one on the boundary)
    Tr::Cell_handle c = f->first;
    int i = f->second;
    const Tr::Cell_handle o = c->neighbor(i);
    const int a = c3t3.is_in_complex(c) ? (int)c3t3.subdomain_index(c) : 0;
    const int b = c3t3.is_in_complex(o) ? (int)c3t3.subdomain_index(o) : 0;
    if (a == 0 || (b != 0 && b < a)) {
      i = o->index(c);
      c = o;
    }
    std::array<Tr::Vertex_handle, 3> t = {c->vertex((i + 1) & 3), c->vertex((i + 2) & 3),
                                          c->vertex((i + 3) & 3)};
    // the cell's own vertex i must lie on the negative side of t
    if (CGAL::orientation(t[0]->point().point(), t[1]->point().point(),
                          t[2]->point().point(), c->vertex(i)->point().point()) ==
        CGAL::POSITIVE)
      std::swap(t[1], t[2]);
    tris.push_back({number(t[0]), number(t[1]), number(t[2]),
                    (std::size_t)c3t3.surface_patch_index(*f)});
  }
  std::FILE *out = std::fopen(path, "w");
  if (!out) fail(std::string("cannot write ") + path);
  std::fprintf(out, "MeshVersionFormatted 2\n\nDimension 3\n\nVertices\n%zu\n", verts.size());
  for (const auto &v : verts) {
    const Point p = v->point().point();
    std::fprintf(out, "%.17g %.17g %.17g 0\n", p.x(), p.y(), p.z());
  }
  std::fprintf(out, "\nTriangles\n%zu\n", tris.size());
  for (const auto &t : tris) std::fprintf(out, "%zu %zu %zu %zu\n", t[0], t[1], t[2], t[3]);
  std::fprintf(out, "\nTetrahedra\n%zu\n", tets.size());
  for (const auto &e : tets)
    std::fprintf(out, "%zu %zu %zu %zu %zu\n", e[0], e[1], e[2], e[3], e[4]);
  std::fprintf(out, "\nEnd\n");
  if (std::fclose(out) != 0) fail(std::string("error writing ") + path);
  counts[0] = verts.size();
  counts[1] = tets.size();
  counts[2] = tris.size();
}

void usage() {
  std::cerr << "usage: mesh3_materials IN.off OUT.mesh --facet-size S [--facet-distance D]\n"
               "         [--cell-size C] [--facet-angle A] [--cell-ratio R] [--no-perturb]\n"
               "         [--no-exude] [--seed N]\n";
  std::exit(2);
}

}  // namespace

int main(int argc, char **argv) {
  if (argc < 3) usage();
  const char *in_path = argv[1], *out_path = argv[2];
  Options o;
  for (int i = 3; i < argc; i++) {
    const std::string a = argv[i];
    auto value = [&]() {
      if (i + 1 >= argc) usage();
      char *end = nullptr;
      const double x = std::strtod(argv[++i], &end);
      if (*end || !(x >= 0)) fail("bad value for " + a);
      return x;
    };
    if (a == "--facet-size") o.facet_size = value();
    else if (a == "--facet-distance") o.facet_distance = value();
    else if (a == "--facet-angle") o.facet_angle = value();
    else if (a == "--cell-size") o.cell_size = value();
    else if (a == "--cell-ratio") o.cell_ratio = value();
    else if (a == "--seed") o.seed = (unsigned)value();
    else if (a == "--no-perturb") o.perturb = false;
    else if (a == "--no-exude") o.exude = false;
    else usage();
  }
  if (!(o.facet_size > 0) && !(o.facet_distance > 0))
    fail("give --facet-size or --facet-distance (the surface would not be refined)");
  if (o.cell_size < 0) o.cell_size = o.facet_size;

  const auto t0 = Clock::now();
  const Soup soup = read_off(in_path);
  std::vector<Shell> shells = split_shells(soup);
  const double t_read = since(t0);

  // each shell's depth: the other shells around one of its vertices
  const auto t1 = Clock::now();
  std::vector<Polyhedron> polys(shells.size());
  for (std::size_t s = 0; s < shells.size(); s++) {
    CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(shells[s].soup.v,
                                                                shells[s].soup.f, polys[s]);
    if (!CGAL::is_closed(polys[s]) || !CGAL::is_triangle_mesh(polys[s]))
      fail("shell " + std::to_string(s + 1) + " is not a closed triangle surface");
  }
  for (std::size_t s = 0; s < shells.size(); s++) {
    // an inward shell is inside-out for the point test: turn a copy outward
    Polyhedron outward = polys[s];
    if (shells[s].volume < 0) CGAL::Polygon_mesh_processing::reverse_face_orientations(outward);
    CGAL::Side_of_triangle_mesh<Polyhedron, K> inside(outward);
    for (std::size_t r = 0; r < shells.size(); r++)
      if (r != s && inside(shells[r].soup.v[0]) == CGAL::ON_BOUNDED_SIDE) shells[r].depth++;
  }
  // (the side the facets' normals point away from, the side they point to):
  // the order CGAL 5.5 reads the pairs in (Is_in_domain in
  // Polyhedral_complex_mesh_domain_3.h gives a point with orientation(a,
  // b, c, p) NEGATIVE the first one; the class's comment words it the other
  // way round, and the wrong order makes the outside a material)
  std::vector<std::pair<int, int>> sides;
  for (const Shell &s : shells) {
    const int out = s.depth, in = s.depth + 1;
    sides.push_back(s.volume > 0 ? std::make_pair(in, out) : std::make_pair(out, in));
  }
  CGAL::Random rng(o.seed);
  Domain domain(polys.begin(), polys.end(), sides.begin(), sides.end(), &rng);
  const double t_domain = since(t1);

  namespace P = CGAL::parameters;
  // (CGAL 5.5's Mesh_criteria_3 takes Boost.Parameter keywords)
  Criteria criteria(P::facet_angle = o.facet_angle, P::facet_size = o.facet_size,
                    P::facet_distance = o.facet_distance,
                    P::cell_radius_edge_ratio = o.cell_ratio, P::cell_size = o.cell_size);
  const auto t2 = Clock::now();
  C3t3 c3t3;
  if (o.perturb && o.exude)
    c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria);
  else if (o.perturb)
    c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, P::no_exude());
  else if (o.exude)
    c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, P::no_perturb());
  else
    c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria, P::no_perturb(), P::no_exude());
  const double t_mesh = since(t2);

  const auto t3 = Clock::now();
  std::size_t counts[3];
  write_medit(out_path, c3t3, counts);
  const double t_write = since(t3);

  std::ostringstream depth;
  for (std::size_t s = 0; s < shells.size(); s++)
    depth << (s ? ", " : "") << "[" << shells[s].depth << ", " << sides[s].first << ", "
          << sides[s].second << "]";
  std::printf("shells (depth, material behind, material in front): %s\n", depth.str().c_str());
  std::printf("%zu vertices, %zu tetrahedra, %zu triangles; make_mesh_3 %.3f s\n", counts[0],
              counts[1], counts[2], t_mesh);
  std::printf(
      "{\"tool\": \"cgal_mesh_3\", \"cgal_version\": \"%s\", \"shells\": %zu, \"facet_size\": %g, "
      "\"facet_distance\": %g, \"facet_angle\": %g, \"cell_size\": %g, \"cell_ratio\": %g, "
      "\"perturb\": %s, \"exude\": %s, \"nodes\": %zu, \"elements\": %zu, \"triangles\": %zu, "
      "\"seconds\": {\"read\": %.6f, \"domain\": %.6f, \"mesh\": %.6f, \"write\": %.6f, "
      "\"total\": %.6f}}\n",
      CGAL_VERSION_STR, shells.size(), o.facet_size, o.facet_distance, o.facet_angle,
      o.cell_size, o.cell_ratio, o.perturb ? "true" : "false", o.exude ? "true" : "false",
      counts[0], counts[1], counts[2], t_read, t_domain, t_mesh, t_write, since(t0));
  return 0;
}
