// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// The main use case: a point cloud (normals estimated when it has none,
// any signs) -> orient_normals -> CGAL's Poisson surface reconstruction ->
// a closed mesh.  Without consistent, outward normals Poisson's implicit
// function has the wrong sign in places and the mesh comes out with holes,
// bubbles or inside out; with them it is closed and outward.
//
// usage: reconstruct_surface IN(.xyz|.pwn|.ply) OUT.off [--reference MESH.off]
//   --reference: also measure the result against a closed reference mesh
//   (mean and largest vertex distance in % of its bounding-box diagonal,
//   volume ratio), as the benchmark does.

#include <Normal_orientation/IO/Point_cloud_io.h>
#include <Normal_orientation/orient_normals.h>

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/compute_average_spacing.h>
#include <CGAL/jet_estimate_normals.h>
#include <CGAL/poisson_surface_reconstruction.h>
#include <CGAL/property_map.h>

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point;
typedef Kernel::Vector_3 Vector;
typedef std::pair<Point, Vector> Point_with_normal;
typedef CGAL::First_of_pair_property_map<Point_with_normal> Point_map;
typedef CGAL::Second_of_pair_property_map<Point_with_normal> Normal_map;
typedef CGAL::Surface_mesh<Point> Mesh;
namespace NO = Normal_orientation;
namespace PMP = CGAL::Polygon_mesh_processing;

namespace {

// the mean and largest distance of the vertices of `mesh` to `reference`
std::pair<double, double> vertex_distances(const Mesh& mesh, const Mesh& reference)
{
  typedef CGAL::AABB_face_graph_triangle_primitive<Mesh> Primitive;
  typedef CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>> Tree;
  Tree tree(faces(reference).first, faces(reference).second, reference);
  tree.accelerate_distance_queries();
  double sum = 0.0, largest = 0.0;
  for (Mesh::Vertex_index v : vertices(mesh)) {
    const double d = std::sqrt(tree.squared_distance(mesh.point(v)));
    sum += d;
    largest = std::max(largest, d);
  }
  return {mesh.number_of_vertices() > 0 ? sum / double(mesh.number_of_vertices()) : 0.0, largest};
}

double diagonal(const Mesh& mesh)
{
  const CGAL::Bbox_3 b = PMP::bbox(mesh);
  return std::sqrt(CGAL::square(b.xmax() - b.xmin()) + CGAL::square(b.ymax() - b.ymin()) +
                   CGAL::square(b.zmax() - b.zmin()));
}

} // namespace

int main(int argc, char** argv)
{
  std::string input, output, reference_file;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--reference" && i + 1 < argc)
      reference_file = argv[++i];
    else if (input.empty() && a.rfind("--", 0) != 0)
      input = a;
    else if (output.empty() && a.rfind("--", 0) != 0)
      output = a;
    else {
      std::cerr << "usage: reconstruct_surface IN(.xyz|.pwn|.ply) OUT.off [--reference MESH.off]\n";
      return 2;
    }
  }
  if (input.empty() || output.empty()) {
    std::cerr << "usage: reconstruct_surface IN(.xyz|.pwn|.ply) OUT.off [--reference MESH.off]\n";
    return 2;
  }
  const std::string temporary = output + ".tmp";
  try {
    // 1. The points, and unoriented normals when the file has none.
    const NO::IO::Point_cloud cloud = NO::IO::read_point_cloud(input);
    if (cloud.size() < 10)
      throw std::runtime_error(input + ": too few points to reconstruct a surface");
    std::vector<Point_with_normal> points;
    points.reserve(cloud.size());
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const auto& p = cloud.points[i];
      const Vector n = cloud.has_normals() ? Vector(cloud.normals[i][0], cloud.normals[i][1], cloud.normals[i][2])
                                           : CGAL::NULL_VECTOR;
      points.emplace_back(Point(p[0], p[1], p[2]), n);
    }
    if (!cloud.has_normals())
      CGAL::jet_estimate_normals<CGAL::Parallel_if_available_tag>(
        points, 18, CGAL::parameters::point_map(Point_map()).normal_map(Normal_map()));

    // 2. Consistent, outward normals.
    const NO::Orientation_result r =
      NO::orient_normals(points, NO::parameters::point_map(Point_map()).normal_map(Normal_map()));

    // 3. Poisson surface reconstruction (CGAL's defaults; the spacing of
    //    the cloud sets the mesh's resolution).
    const double spacing = CGAL::compute_average_spacing<CGAL::Parallel_if_available_tag>(
      points, 6, CGAL::parameters::point_map(Point_map()));
    Mesh mesh;
    if (!CGAL::poisson_surface_reconstruction_delaunay(points.begin(), points.end(), Point_map(), Normal_map(), mesh,
                                                       spacing))
      throw std::runtime_error("Poisson reconstruction failed");

    const bool closed = CGAL::is_closed(mesh);
    const bool outward = closed && PMP::is_outward_oriented(mesh);
    const double volume = closed ? PMP::volume(mesh) : 0.0;
    std::printf("%zu points (%s normals), %zu component(s), %zu wrong sign(s) flipped -> mesh of %zu vertices, "
                "%zu faces, %s, %s, volume %.6g\n",
                points.size(), cloud.has_normals() ? "given" : "estimated", r.number_of_components,
                r.number_of_flipped, std::size_t(mesh.number_of_vertices()), std::size_t(mesh.number_of_faces()),
                closed ? "closed" : "NOT closed", outward ? "outward" : "NOT outward", volume);

    // 4. The mesh, written atomically (no partial OUT on failure).
    {
      std::ofstream out(temporary);
      out.precision(17);
      if (!out || !CGAL::IO::write_OFF(out, mesh) || !out.flush())
        throw std::runtime_error("cannot write " + output);
    }
    std::filesystem::rename(temporary, output);

    // 5. Optionally, against the true surface.
    if (!reference_file.empty()) {
      Mesh reference;
      if (!CGAL::IO::read_polygon_mesh(reference_file, reference) || reference.is_empty() ||
          !CGAL::is_triangle_mesh(reference))
        throw std::runtime_error("cannot read the reference triangle mesh " + reference_file);
      const double diag = diagonal(reference);
      const auto d = vertex_distances(mesh, reference);
      const double true_volume = CGAL::is_closed(reference) ? PMP::volume(reference) : 0.0;
      std::printf("against %s: mean distance %.4f%%, largest %.4f%% of the diagonal, volume %.6g / %.6g = %.4f\n",
                  reference_file.c_str(), 100.0 * d.first / diag, 100.0 * d.second / diag, volume, true_volume,
                  true_volume != 0.0 ? volume / true_volume : 0.0);
    }
  } catch (const std::exception& e) {
    std::error_code ec;
    std::filesystem::remove(temporary, ec);
    std::cerr << "reconstruct_surface: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
