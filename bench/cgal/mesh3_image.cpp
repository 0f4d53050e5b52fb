// mixoct bench (issue 28): the reference side of bench/image_bench.sh.
// Meshes a segmented 3D label image (0 background, 1.. materials) into
// tetrahedra with CGAL's Mesh_3 over a labelled image domain and writes a
// Medit .mesh whose tetrahedra carry the label as reference.
//
//   mesh3_image IN.inr OUT.mesh --facet-size S [--facet-distance D]
//               [--cell-size C] [--facet-angle A] [--cell-ratio R]
//               [--error-bound E] [--no-perturb] [--no-exude] [--seed N]
//
// The image is read by CGAL::Image_3 (CGAL's own ImageIO, compiled from
// the headers: .inr, .inr.gz only if CGAL was told about zlib, and the
// other formats ImageIO knows). The domain is
// Labeled_mesh_domain_3::create_labeled_image_mesh_domain: the label of a
// point is the image's value by CGAL's "labellized" trilinear interpolation
// (the label with the largest interpolated weight), voxel (i, j, k) at
// (i vx + tx, j vy + ty, k vz + tz): the voxel's centre is its position, as
// mixoct's readers put it with an axis-aligned affine of no offset. The
// sub-domain of a cell is the label there; label 0 (and the outside of the
// image) is out of the mesh. CGAL 5.5 has no feature detection for images
// (that came in 5.6), so the lines where three labels meet are not
// protected: some of their facets may be missing or coarse.
//
// Criteria (CGAL::Mesh_criteria_3): facet_size, facet_distance, facet_angle
// (default 30 degrees), cell_size (default: the facet size), cell
// radius-edge ratio (default 3); a value 0 leaves that criterion out. The
// domain's relative error bound on the interfaces' intersections (default
// 1e-3 of the bounding box's diagonal). make_mesh_3's default
// optimisation (perturb, exude) runs unless turned off.
//
// Output (Medit ASCII, "MeshVersionFormatted 2"): the vertices of the
// complex; the facets of the complex as Triangles, reference = 1000 * the
// smaller label on their sides + the larger (0 outside the mesh); the
// tetrahedra of the complex with det(p1-p0, p2-p0, p3-p0) > 0 and the label
// as reference. One line "V vertices, T tetrahedra, F triangles; ..." and
// one JSON object on the last line of stdout: counts, labels, the times
// (read, domain, mesh = make_mesh_3, write, total).
//
// Written for mixoct against CGAL's documented API (Mesh_3 user manual and
// reference, CGAL 5.5); build: g++ -O2 -DNDEBUG -std=c++17 ... -lgmp -lmpfr
// (CGAL 5.x is header-only, ImageIO included).

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Image_3.h>
#include <CGAL/Labeled_mesh_domain_3.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/make_mesh_3.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
typedef K::Point_3 Point;
typedef CGAL::Labeled_mesh_domain_3<K> Domain;
typedef CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type Tr;
typedef CGAL::Mesh_complex_3_in_triangulation_3<Tr> C3t3;
typedef CGAL::Mesh_criteria_3<Tr> Criteria;

typedef std::chrono::steady_clock Clock;
double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

[[noreturn]] void fail(const std::string &msg) {
  std::cerr << "mesh3_image: " << msg << "\n";
  std::exit(2);
}

struct Options {
  double facet_size = 0, facet_distance = 0, facet_angle = 30, cell_size = -1, cell_ratio = 3;
  double error_bound = 1e-3;
  bool perturb = true, exude = true;
  unsigned seed = 0;
};

struct Counts {
  std::size_t vertices = 0, tets = 0, tris = 0;
  std::map<int, std::size_t> per_label;
};

Counts write_medit(const char *path, const C3t3 &c3t3) {
  Counts n;
  std::unordered_map<const void *, std::size_t> id;
  std::vector<Tr::Vertex_handle> verts;
  auto number = [&](Tr::Vertex_handle v) {
    auto it = id.find(&*v);
    if (it != id.end()) return it->second;
    verts.push_back(v);
    return id[&*v] = verts.size();
  };
  std::vector<std::array<std::size_t, 5>> tets;
  tets.reserve(c3t3.number_of_cells_in_complex());
  for (auto c = c3t3.cells_in_complex_begin(); c != c3t3.cells_in_complex_end(); ++c) {
    std::array<std::size_t, 5> e;
    for (int k = 0; k < 4; k++) e[k] = number(c->vertex(k));
    const Point p0 = c->vertex(0)->point().point(), p1 = c->vertex(1)->point().point(),
                p2 = c->vertex(2)->point().point(), p3 = c->vertex(3)->point().point();
    if (CGAL::orientation(p0, p1, p2, p3) == CGAL::NEGATIVE) std::swap(e[2], e[3]);
    e[4] = (std::size_t)c3t3.subdomain_index(c);
    n.per_label[(int)e[4]]++;
    tets.push_back(e);
  }
  std::vector<std::array<std::size_t, 4>> tris;
  for (auto f = c3t3.facets_in_complex_begin(); f != c3t3.facets_in_complex_end(); ++f) {
    const Tr::Cell_handle c = f->first, o = c->neighbor(f->second);
    int a = c3t3.is_in_complex(c) ? (int)c3t3.subdomain_index(c) : 0;
    int b = c3t3.is_in_complex(o) ? (int)c3t3.subdomain_index(o) : 0;
    if (a > b) std::swap(a, b);
    const int i = f->second;
    tris.push_back({number(c->vertex((i + 1) & 3)), number(c->vertex((i + 2) & 3)),
                    number(c->vertex((i + 3) & 3)), (std::size_t)(1000 * a + b)});
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
  n.vertices = verts.size();
  n.tets = tets.size();
  n.tris = tris.size();
  return n;
}

void usage() {
  std::cerr << "usage: mesh3_image IN.inr OUT.mesh --facet-size S [--facet-distance D]\n"
               "         [--cell-size C] [--facet-angle A] [--cell-ratio R] [--error-bound E]\n"
               "         [--no-perturb] [--no-exude] [--seed N]\n";
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
    else if (a == "--error-bound") o.error_bound = value();
    else if (a == "--seed") o.seed = (unsigned)value();
    else if (a == "--no-perturb") o.perturb = false;
    else if (a == "--no-exude") o.exude = false;
    else usage();
  }
  if (!(o.facet_size > 0) && !(o.facet_distance > 0))
    fail("give --facet-size or --facet-distance (the surfaces would not be refined)");
  if (o.cell_size < 0) o.cell_size = o.facet_size;

  const auto t0 = Clock::now();
  CGAL::Image_3 image;
  if (!image.read(in_path)) fail(std::string("cannot read the image ") + in_path);
  const double t_read = since(t0);
  std::printf("image %zu x %zu x %zu, voxel %g x %g x %g, origin (%g, %g, %g)\n",
              image.xdim(), image.ydim(), image.zdim(), image.vx(), image.vy(), image.vz(),
              image.tx(), image.ty(), image.tz());

  const auto t1 = Clock::now();
  CGAL::Random rng(o.seed);
  namespace P = CGAL::parameters;
  Domain domain = Domain::create_labeled_image_mesh_domain(
      image, P::relative_error_bound = o.error_bound, P::p_rng = &rng);
  const double t_domain = since(t1);

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
  const Counts n = write_medit(out_path, c3t3);
  const double t_write = since(t3);

  std::ostringstream labels;
  bool first = true;
  for (const auto &kv : n.per_label) {
    labels << (first ? "" : ", ") << "\"" << kv.first << "\": " << kv.second;
    first = false;
  }
  std::printf("%zu vertices, %zu tetrahedra, %zu triangles; make_mesh_3 %.3f s\n", n.vertices,
              n.tets, n.tris, t_mesh);
  std::printf(
      "{\"tool\": \"cgal_mesh_3_image\", \"cgal_version\": \"%s\", \"dims\": [%zu, %zu, %zu], "
      "\"facet_size\": %g, \"facet_distance\": %g, \"facet_angle\": %g, \"cell_size\": %g, "
      "\"cell_ratio\": %g, \"error_bound\": %g, \"perturb\": %s, \"exude\": %s, "
      "\"nodes\": %zu, \"elements\": %zu, \"triangles\": %zu, \"tets_per_label\": {%s}, "
      "\"seconds\": {\"read\": %.6f, \"domain\": %.6f, \"mesh\": %.6f, \"write\": %.6f, "
      "\"total\": %.6f}}\n",
      CGAL_VERSION_STR, image.xdim(), image.ydim(), image.zdim(), o.facet_size,
      o.facet_distance, o.facet_angle, o.cell_size, o.cell_ratio, o.error_bound,
      o.perturb ? "true" : "false", o.exude ? "true" : "false", n.vertices, n.tets, n.tris,
      labels.str().c_str(), t_read, t_domain, t_mesh, t_write, since(t0));
  return 0;
}
