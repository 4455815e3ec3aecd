// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// Solving your own orientation problem: no points, no neighbour search, a
// graph of the user's.  A CGAL::Surface_mesh is a Boost graph, so its
// vertices and edges are the problem as they are: each vertex gets its
// normal with a random sign, each edge a signed weight from a flip
// criterion, and a solver (MST, then QPBO-I) labels the vertices; the
// library's connected_components() and Outward_component_sign then choose
// the global sign, as orient_normals() does.  The program reports how many
// vertex normals agree with the mesh's own outward normals.
//
// usage: orient_mesh_graph [--xie] [MESH.off]
//        (without a mesh: a bumpy sphere, an icosahedron subdivided 4 times;
//        --xie: Xie's criterion instead of Hoppe's, for meshes with sharp
//        creases, such as CGAL's cheese.off, where Hoppe's fails)

#include <Normal_orientation/Component_sign.h>
#include <Normal_orientation/Flip_criteria.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/solvers/Qpbo_i_solver.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>
#include <CGAL/Polygon_mesh_processing/compute_normal.h>
#include <CGAL/Subdivision_method_3/subdivision_methods_3.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/boost/graph/generators.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <iostream>
#include <random>
#include <string>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point_3;
typedef Kernel::Vector_3 Vector_3;
typedef CGAL::Surface_mesh<Point_3> Mesh;
typedef Mesh::Vertex_index Vertex_index;
typedef Mesh::Edge_index Edge_index;
namespace NO = Normal_orientation;
namespace PMP = CGAL::Polygon_mesh_processing;

int main(int argc, char** argv)
{
  const bool xie = argc > 1 && std::string(argv[1]) == "--xie";
  const int first = xie ? 2 : 1;
  if (argc > first + 1 || (argc == first + 1 && argv[first][0] == '-')) {
    std::cerr << "usage: orient_mesh_graph [--xie] [MESH.off]\n";
    return 2;
  }
  Mesh mesh;
  if (argc == first + 1) {
    if (!CGAL::IO::read_polygon_mesh(argv[first], mesh) || mesh.is_empty() || mesh.has_garbage()) {
      std::cerr << "orient_mesh_graph: cannot read a polygon mesh from " << argv[first] << "\n";
      return 1;
    }
  } else { // a sphere with bumps, so that neighbouring normals differ
    CGAL::make_icosahedron(mesh, Point_3(0, 0, 0), 1.0);
    CGAL::Subdivision_method_3::Loop_subdivision(mesh, CGAL::parameters::number_of_iterations(4));
    for (Vertex_index v : mesh.vertices()) {
      const Vector_3 u = (mesh.point(v) - CGAL::ORIGIN) / std::sqrt((mesh.point(v) - CGAL::ORIGIN).squared_length());
      mesh.point(v) = CGAL::ORIGIN + u * (1.0 + 0.3 * std::sin(5 * u.x()) * std::sin(5 * u.y()) * std::sin(5 * u.z()));
    }
  }

  // The truth (the mesh's outward vertex normals), then the input: the same
  // normals with random signs (fixed seed).
  auto truth = mesh.add_property_map<Vertex_index, Vector_3>("v:true_normal", CGAL::NULL_VECTOR).first;
  PMP::compute_vertex_normals(mesh, truth);
  auto normal = mesh.add_property_map<Vertex_index, Vector_3>("v:normal", CGAL::NULL_VECTOR).first;
  std::mt19937 random(1);
  for (Vertex_index v : mesh.vertices())
    normal[v] = (random() & 1) ? -truth[v] : truth[v];

  // The signed edge weights: phi in [-1, 1] from a flip criterion (the
  // neighbour graph of the package also multiplies it by a weight that
  // fades with the distance; the edges of a mesh are all close neighbours).
  auto weight = mesh.add_property_map<Edge_index, double>("e:weight", 0.0).first;
  for (Edge_index e : mesh.edges()) {
    const Vertex_index i = source(e, mesh), j = target(e, mesh);
    weight[e] = xie ? NO::Xie_criterion()(mesh.point(i), normal[i], mesh.point(j), normal[j])
                    : NO::Hoppe_criterion()(mesh.point(i), normal[i], mesh.point(j), normal[j]);
  }

  // Solve: one label (+1 keep, -1 flip) per vertex, by vertex index.
  std::vector<NO::Label> labels(num_vertices(mesh), NO::Label(1));
  const auto label_map = boost::make_iterator_property_map(labels.begin(), get(boost::vertex_index, mesh));
  const NO::Solver_report report = NO::Qpbo_i_solver().solve(mesh, weight, label_map); // or NO::Mst_solver()

  // The energy leaves the sign of each connected component free: choose it
  // as orient_normals() does, with a component sign policy.
  std::vector<std::uint32_t> component;
  const std::size_t number_of_components = NO::connected_components(mesh, weight, component);
  std::vector<Point_3> points;
  std::vector<Vector_3> unit_normals;
  for (Vertex_index v : mesh.vertices()) { // in vertex-index order, as the labels
    points.push_back(mesh.point(v));
    const double l = std::sqrt(normal[v].squared_length());
    unit_normals.push_back(l > 0 ? normal[v] / l : CGAL::NULL_VECTOR);
  }
  const NO::Component_sign_input<Kernel> input{points, unit_normals, labels, component, number_of_components,
                                               0.0, nullptr};
  const std::vector<char> flip = NO::component_signs(NO::Outward_component_sign(), input);

  // Apply the labels, and compare with the truth.
  std::size_t agree = 0, zero = 0;
  for (Vertex_index v : mesh.vertices()) {
    const std::size_t i = std::size_t(v);
    if (labels[i] * (flip[component[i]] ? -1 : 1) < 0)
      normal[v] = -normal[v];
    if (truth[v] == CGAL::NULL_VECTOR)
      ++zero; // an isolated or degenerate vertex: no normal to orient
    else if (normal[v] * truth[v] > 0)
      ++agree;
  }
  const std::size_t n = mesh.number_of_vertices() - zero;
  std::printf("%zu vertices, %zu edges, %zu component(s): energy %.6g, %zu frustrated edges, %zu segments\n",
              std::size_t(mesh.number_of_vertices()), std::size_t(mesh.number_of_edges()), number_of_components,
              report.energy, report.frustrated_edges, report.segments);
  std::printf("%zu of %zu vertex normals (%.2f%%) agree with the mesh's outward normals\n", agree, n,
              n > 0 ? 100.0 * double(agree) / double(n) : 100.0);
  return 0;
}
