// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmark-local ground truth of the normals of a cloud sampled on a mesh: the outward unit
// normal of the mesh triangle closest to a point (CGAL::AABB_tree). A normal is wrong when its
// dot product with that truth is <= 0 (zero and NaN normals included). Used by
// count_wrong_normals and render_cloud, so that both count the same wrong normals.
#ifndef NORMAL_ORIENTATION_BENCHMARK_REFERENCE_MESH_H
#define NORMAL_ORIENTATION_BENCHMARK_REFERENCE_MESH_H

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>

#include <cmath>
#include <cstddef>
#include <filesystem>
#include <iterator>
#include <limits>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace benchmark {

/// Kernel of the mesh and of the queries (the same as `Mesh_sampler.h`'s).
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
/// Point type.
using Point_3 = Kernel::Point_3;
/// Vector type.
using Vector_3 = Kernel::Vector_3;
/// Triangle type.
using Triangle_3 = Kernel::Triangle_3;
/// Iterator over the mesh triangles: the primitive id of the AABB tree.
using Mesh_triangle_iterator = std::vector<Triangle_3>::const_iterator;
/// Primitive of the AABB tree.
using Mesh_primitive = CGAL::AABB_triangle_primitive<Kernel, Mesh_triangle_iterator>;
/// AABB tree over the mesh triangles.
using Mesh_tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Mesh_primitive>>;

/// The mesh: non-degenerate triangles (fan-triangulated faces) and their outward unit normals.
struct Reference_mesh
{
  /// Triangles with positive area, vertices in the order of the file.
  std::vector<Triangle_3> triangles;
  /// Unit normal of each triangle (right-hand rule: outward for an outward-oriented mesh).
  std::vector<Vector_3> normals;
  /// Bounding-box diagonal of the mesh vertices.
  double bbox_diagonal = 0.0;
};

/**
 * \brief Reads `path` as a polygon soup, fan-triangulates its faces and drops the triangles
 * of zero area.
 * \throws std::runtime_error if the file cannot be read or has no usable triangle.
 */
inline Reference_mesh read_reference_mesh(const std::string& path)
{
  std::vector<Point_3> points;
  std::vector<std::vector<std::size_t>> polygons;
  std::error_code ec;
  if(!std::filesystem::is_regular_file(path, ec))
    throw std::runtime_error("cannot read mesh '" + path + "': no such file");
  if(!CGAL::IO::read_polygon_soup(path, points, polygons) || points.empty())
    throw std::runtime_error("cannot read mesh '" + path + "'");
  Reference_mesh mesh;
  const CGAL::Bbox_3 box = CGAL::bbox_3(points.begin(), points.end());
  mesh.bbox_diagonal = std::sqrt(CGAL::square(box.xmax() - box.xmin()) + CGAL::square(box.ymax() - box.ymin()) +
                                 CGAL::square(box.zmax() - box.zmin()));
  for(const std::vector<std::size_t>& polygon : polygons)
  {
    for(std::size_t i : polygon)
      if(i >= points.size())
        throw std::runtime_error("mesh '" + path + "': vertex index out of range");
    for(std::size_t j = 1; j + 1 < polygon.size(); ++j)
    {
      const Triangle_3 t(points[polygon[0]], points[polygon[j]], points[polygon[j + 1]]);
      const Vector_3 c = CGAL::cross_product(t[1] - t[0], t[2] - t[0]);
      const double twice_area = std::sqrt(c.squared_length());
      if(!(twice_area > 0.0) || !std::isfinite(twice_area))
        continue;
      mesh.triangles.push_back(t);
      mesh.normals.push_back(c / twice_area);
    }
  }
  if(mesh.triangles.empty())
    throw std::runtime_error("mesh '" + path + "' has no triangle of positive area");
  return mesh;
}

/**
 * \brief Returns a closest triangle of the mesh to `p` and its squared distance to `p`.
 *
 * Fast path for points on the surface: the triangles meeting the box of half-size `h` around
 * `p` (`all_intersected_primitives`, exact box-triangle test) are the candidates; if the
 * closest of them is within `h`, it is the closest triangle of the mesh (any closer triangle
 * would meet the ball of radius `h`, hence the box). Otherwise, and when no triangle meets the
 * box, `closest_point_and_primitive` answers. Both give a closest triangle; between
 * equidistant triangles (a point on an edge) the choice may differ. `candidates` is scratch
 * space (one per thread).
 */
inline std::pair<Mesh_triangle_iterator, double> closest_triangle(const Mesh_tree& tree, const Point_3& p, double h,
                                                                  std::vector<Mesh_triangle_iterator>& candidates)
{
  candidates.clear();
  const CGAL::Bbox_3 box(p.x() - h, p.y() - h, p.z() - h, p.x() + h, p.y() + h, p.z() + h);
  tree.all_intersected_primitives(box, std::back_inserter(candidates));
  double best = std::numeric_limits<double>::infinity();
  Mesh_triangle_iterator best_triangle{};
  for(const Mesh_triangle_iterator& t : candidates)
  {
    const double d2 = CGAL::squared_distance(p, *t);
    if(d2 < best)
    {
      best = d2;
      best_triangle = t;
    }
  }
  if(!candidates.empty() && best <= h * h)
    return {best_triangle, best};
  const Mesh_tree::Point_and_primitive_id hit = tree.closest_point_and_primitive(p);
  return {hit.second, CGAL::squared_distance(p, hit.first)};
}

/**
 * \brief The truth of the normals: a reference mesh and its AABB tree, ready for distance
 * queries (const member functions may be called from several threads).
 *
 * Not copyable nor movable: the tree refers to the triangles it holds.
 */
class Reference_normals
{
public:
  /// \brief Reads the mesh `path` (see `read_reference_mesh()`) and builds its tree.
  /// \throws std::runtime_error as `read_reference_mesh()`.
  explicit Reference_normals(const std::string& path)
    : mesh_(read_reference_mesh(path)), tree_(mesh_.triangles.begin(), mesh_.triangles.end())
  {
    tree_.build();
    tree_.accelerate_distance_queries();
    (void)tree_.closest_point_and_primitive(mesh_.triangles.front()[0]); // builds the search tree now
  }
  Reference_normals(const Reference_normals&) = delete;
  Reference_normals& operator=(const Reference_normals&) = delete;

  /// The mesh.
  const Reference_mesh& mesh() const { return mesh_; }
  /// Half-size of the fast-path box of `closest_triangle()`: 1e-6 x bbox diagonal.
  double fast_path_half_size() const { return 1e-6 * mesh_.bbox_diagonal; }

  /// \brief Returns the outward unit normal of a closest triangle to `p` and the squared
  /// distance of `p` to the mesh. `candidates` is scratch space (one per thread).
  std::pair<Vector_3, double> truth(const Point_3& p, std::vector<Mesh_triangle_iterator>& candidates) const
  {
    const std::pair<Mesh_triangle_iterator, double> hit =
      closest_triangle(tree_, p, fast_path_half_size(), candidates);
    return {mesh_.normals[static_cast<std::size_t>(hit.first - mesh_.triangles.begin())], hit.second};
  }

  /// \brief Returns `true` if `normal` is wrong at `p`: its dot product with the truth is <= 0
  /// (zero and NaN normals are wrong).
  static bool is_wrong(const Vector_3& truth, const double normal[3])
  {
    const double dot = truth.x() * normal[0] + truth.y() * normal[1] + truth.z() * normal[2];
    return !(dot > 0.0);
  }

private:
  Reference_mesh mesh_;
  Mesh_tree tree_;
};

} // namespace benchmark
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_BENCHMARK_REFERENCE_MESH_H
