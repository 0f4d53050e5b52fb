// mixoct bench (issue 29): the reference side of bench/features_compare.sh.
// Meshes a closed triangulated surface (OFF) into tetrahedra with CGAL's
// Mesh_3 keeping its sharp features (the polyhedral domain with features:
// edges whose dihedral angle departs from flat by more than ANGLE are
// protected and meshed first), and writes a Medit .mesh.
//
//   mesh3_features IN.off OUT.mesh SIZE [ANGLE]
//
// Criteria: edge, facet and cell size SIZE, facet distance SIZE / 10, facet
// angle 25 degrees, radius-edge ratio 3; ANGLE default 30. The last line of
// stdout: one JSON object with the counts and the seconds of make_mesh_3.
// Written for mixoct against CGAL's documented API (CGAL 5.5, Mesh_3
// reference: Polyhedral_mesh_domain_with_features_3, detect_features,
// make_mesh_3, output_to_medit); build: g++ -O2 -DNDEBUG ... -lgmp -lmpfr.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Mesh_complex_3_in_triangulation_3.h>
#include <CGAL/Mesh_criteria_3.h>
#include <CGAL/Mesh_polyhedron_3.h>
#include <CGAL/Mesh_triangulation_3.h>
#include <CGAL/Polyhedral_mesh_domain_with_features_3.h>
#include <CGAL/make_mesh_3.h>
#include <CGAL/IO/File_medit.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Polyhedron = CGAL::Mesh_polyhedron_3<K>::type;
using Domain = CGAL::Polyhedral_mesh_domain_with_features_3<K>;
using Tr = CGAL::Mesh_triangulation_3<Domain, CGAL::Default, CGAL::Sequential_tag>::type;
using C3t3 = CGAL::Mesh_complex_3_in_triangulation_3<Tr, Domain::Corner_index, Domain::Curve_index>;
using Criteria = CGAL::Mesh_criteria_3<Tr>;

int main(int argc, char **argv) {
  if (argc < 4) {
    std::cerr << "usage: mesh3_features IN.off OUT.mesh SIZE [ANGLE]\n";
    return 2;
  }
  const double h = std::atof(argv[3]), angle = argc > 4 ? std::atof(argv[4]) : 30.0;
  Polyhedron poly;
  std::ifstream in(argv[1]);
  if (!(in >> poly) || poly.empty()) {
    std::cerr << argv[1] << ": not a closed OFF surface CGAL reads\n";
    return 2;
  }
  Domain domain(poly);
  // detect_features marks the edges whose two facets' normals part by more
  // than the angle given (measured: 150 found none of an L-bracket's 90
  // degree edges, 60 all of them): ANGLE as mixoct's --feature-angle
  domain.detect_features(angle);
  namespace p = CGAL::parameters;
  Criteria criteria(p::edge_size = h, p::facet_angle = 25, p::facet_size = h,
                    p::facet_distance = h / 10, p::cell_radius_edge_ratio = 3, p::cell_size = h);
  const auto t0 = std::chrono::steady_clock::now();
  C3t3 c3t3 = CGAL::make_mesh_3<C3t3>(domain, criteria);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ofstream out(argv[2]);
  c3t3.output_to_medit(out);
  std::printf("{\"vertices\": %zu, \"cells\": %zu, \"seconds\": %.3f}\n",
              (size_t)c3t3.triangulation().number_of_vertices(),
              (size_t)c3t3.number_of_cells_in_complex(), s);
  return 0;
}
