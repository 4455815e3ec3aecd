// SPDX-License-Identifier: GPL-3.0-or-later
// Benchmark-local generator of point clouds with ground-truth outward normals:
// area-uniform sampling of a closed, outward-oriented triangle mesh, optional Gaussian
// noise, unoriented PCA normals (as a user would estimate them) with random signs.
#ifndef NORMAL_ORIENTATION_BENCHMARK_MESH_SAMPLER_H
#define NORMAL_ORIENTATION_BENCHMARK_MESH_SAMPLER_H

#include "Xyz_io.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/pca_estimate_normals.h>
#include <CGAL/property_map.h>
#include <CGAL/tags.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace benchmark {

/// Kernel used by the benchmark programs (the one a typical CGAL user picks).
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
/// Point type of the benchmark programs.
using Point_3 = Kernel::Point_3;
/// Vector type of the benchmark programs.
using Vector_3 = Kernel::Vector_3;

/**
 * \brief Derives a well-mixed 64-bit seed from `x` (SplitMix64 finaliser).
 *
 * Used to give the sampling, noise and sign streams independent generators from one user
 * seed, so that e.g. the same seed yields the same base samples at every noise level.
 */
inline std::uint64_t mix_seed(std::uint64_t x)
{
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/**
 * \brief Returns a uniform double in [0, 1) built from the top 53 bits of one draw.
 *
 * Written out (rather than `std::uniform_real_distribution`, whose algorithm is
 * implementation-defined) so that a seed gives the same cloud with every standard library.
 */
inline double uniform_01(std::mt19937_64& rng)
{
  return static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0);
}

/**
 * \brief Standard normal variates by the Box-Muller transform (portable, unlike
 * `std::normal_distribution`); the second variate of each pair is cached.
 */
class Gaussian_generator
{
public:
  /// Creates a generator drawing from `rng` (which must outlive this object).
  explicit Gaussian_generator(std::mt19937_64& rng) : m_rng(rng) {}

  /// Returns the next N(0, 1) variate.
  double operator()()
  {
    if(m_has_spare)
    {
      m_has_spare = false;
      return m_spare;
    }
    const double two_pi = 6.283185307179586476925286766559;
    const double u1 = 1.0 - uniform_01(m_rng); // in (0, 1]: log is finite
    const double u2 = uniform_01(m_rng);
    const double radius = std::sqrt(-2.0 * std::log(u1));
    m_spare = radius * std::sin(two_pi * u2);
    m_has_spare = true;
    return radius * std::cos(two_pi * u2);
  }

private:
  std::mt19937_64& m_rng;
  double m_spare = 0.0;
  bool m_has_spare = false;
};

/// Parameters of one generated cloud.
struct Sampling_options
{
  /// Number of sampled points.
  std::size_t number_of_points = 30000;
  /// Noise level: positions get isotropic Gaussian noise with standard deviation
  /// `noise * bounding-box diagonal` on each coordinate (0 = no noise).
  double noise = 0.0;
  /// Seed of every random choice (same seed => same cloud).
  std::uint64_t seed = 1;
  /// Number of neighbours of `CGAL::pca_estimate_normals`.
  unsigned int pca_neighbors = 18;
};

/// A generated cloud: noisy positions, unoriented estimated normals, true outward normals.
struct Sampled_cloud
{
  /// Sample positions (after noise).
  std::vector<Point_3> points;
  /// PCA normals with random signs: the input of the orientation programs.
  std::vector<Vector_3> normals;
  /// Unit normal of the triangle each sample was drawn on: the ground truth.
  std::vector<Vector_3> true_normals;
  /// Bounding-box diagonal of the mesh.
  double bbox_diagonal = 0.0;
  /// Standard deviation of the noise added to each coordinate.
  double noise_sigma = 0.0;
};

/**
 * \brief Samples point clouds on a closed, outward-oriented triangle mesh.
 *
 * The mesh is read as a polygon soup (faces are kept exactly as in the file, nothing is
 * repaired or re-oriented) and polygons with more than three vertices are fan-triangulated.
 */
class Mesh_sampler
{
public:
  /**
   * \brief Reads the mesh `path` (OFF, or any format `CGAL::IO::read_polygon_soup` knows).
   * \throws std::runtime_error if the file cannot be read or has no triangle of positive area.
   */
  explicit Mesh_sampler(const std::string& path)
  {
    std::vector<Point_3> vertices;
    std::vector<std::vector<std::size_t>> polygons;
    if(!CGAL::IO::read_polygon_soup(path, vertices, polygons) || vertices.empty())
      throw std::runtime_error("cannot read mesh '" + path + "'");

    double lo[3], hi[3];
    for(int d = 0; d < 3; ++d)
    {
      lo[d] = std::numeric_limits<double>::max();
      hi[d] = -std::numeric_limits<double>::max();
    }
    for(const Point_3& p : vertices)
      for(int d = 0; d < 3; ++d)
      {
        lo[d] = (std::min)(lo[d], p[d]);
        hi[d] = (std::max)(hi[d], p[d]);
      }
    m_bbox_diagonal = std::sqrt(CGAL::square(hi[0] - lo[0]) + CGAL::square(hi[1] - lo[1])
                                + CGAL::square(hi[2] - lo[2]));

    double total = 0.0;
    for(const std::vector<std::size_t>& polygon : polygons)
    {
      for(std::size_t i : polygon)
        if(i >= vertices.size())
          throw std::runtime_error("mesh '" + path + "': vertex index out of range");
      for(std::size_t j = 1; j + 1 < polygon.size(); ++j)
      {
        const std::array<Point_3, 3> triangle = {vertices[polygon[0]], vertices[polygon[j]],
                                                 vertices[polygon[j + 1]]};
        const Vector_3 cross = CGAL::cross_product(triangle[1] - triangle[0], triangle[2] - triangle[0]);
        const double twice_area = std::sqrt(cross.squared_length());
        if(!(twice_area > 0.0))
          continue; // degenerate: can never be sampled
        total += 0.5 * twice_area;
        m_triangles.push_back(triangle);
        m_unit_normals.push_back(cross / twice_area);
        m_cumulative_area.push_back(total);
      }
    }
    if(m_triangles.empty())
      throw std::runtime_error("mesh '" + path + "' has no triangle of positive area");
  }

  /// Returns the number of (non-degenerate) triangles.
  std::size_t number_of_triangles() const { return m_triangles.size(); }

  /// Returns the total surface area.
  double area() const { return m_cumulative_area.back(); }

  /// Returns the bounding-box diagonal of the mesh vertices.
  double bbox_diagonal() const { return m_bbox_diagonal; }

  /**
   * \brief Generates a cloud: area-uniform samples, Gaussian noise, PCA normals
   * (`CGAL::pca_estimate_normals<CGAL::Parallel_if_available_tag>`), random signs.
   *
   * The three random streams (sampling, noise, signs) are seeded independently from
   * `options.seed`, so the base samples do not depend on the noise level.
   */
  Sampled_cloud sample(const Sampling_options& options) const
  {
    const std::size_t n = options.number_of_points;
    Sampled_cloud cloud;
    cloud.bbox_diagonal = m_bbox_diagonal;
    cloud.noise_sigma = options.noise * m_bbox_diagonal;
    cloud.points.reserve(n);
    cloud.true_normals.reserve(n);

    // 1. Area-uniform sampling: triangle by inverse CDF, point by the square-root rule.
    std::mt19937_64 sampling_rng(mix_seed(options.seed));
    const double total = area();
    for(std::size_t i = 0; i < n; ++i)
    {
      const double u = uniform_01(sampling_rng) * total;
      std::size_t t = static_cast<std::size_t>(
        std::upper_bound(m_cumulative_area.begin(), m_cumulative_area.end(), u) - m_cumulative_area.begin());
      t = (std::min)(t, m_triangles.size() - 1);
      const double s = std::sqrt(uniform_01(sampling_rng));
      const double r = uniform_01(sampling_rng);
      const std::array<Point_3, 3>& tri = m_triangles[t];
      const double a = 1.0 - s, b = s * (1.0 - r), c = s * r;
      cloud.points.emplace_back(a * tri[0].x() + b * tri[1].x() + c * tri[2].x(),
                                a * tri[0].y() + b * tri[1].y() + c * tri[2].y(),
                                a * tri[0].z() + b * tri[1].z() + c * tri[2].z());
      cloud.true_normals.push_back(m_unit_normals[t]);
    }

    // 2. Isotropic Gaussian noise on positions.
    if(cloud.noise_sigma > 0.0)
    {
      std::mt19937_64 noise_rng(mix_seed(options.seed ^ 0x6E6F697365ull)); // "noise"
      Gaussian_generator gaussian(noise_rng);
      for(Point_3& p : cloud.points)
      {
        const double dx = gaussian(), dy = gaussian(), dz = gaussian();
        p = Point_3(p.x() + cloud.noise_sigma * dx, p.y() + cloud.noise_sigma * dy,
                    p.z() + cloud.noise_sigma * dz);
      }
    }

    // 3. Unoriented normals, estimated as a user would.
    using Point_with_normal = std::pair<Point_3, Vector_3>;
    std::vector<Point_with_normal> with_normals;
    with_normals.reserve(n);
    for(const Point_3& p : cloud.points)
      with_normals.emplace_back(p, CGAL::NULL_VECTOR);
    if(n > options.pca_neighbors)
      CGAL::pca_estimate_normals<CGAL::Parallel_if_available_tag>(
        with_normals, options.pca_neighbors,
        CGAL::parameters::point_map(CGAL::First_of_pair_property_map<Point_with_normal>())
          .normal_map(CGAL::Second_of_pair_property_map<Point_with_normal>()));
    else
      for(std::size_t i = 0; i < n; ++i) // too few points for PCA: fall back to the truth
        with_normals[i].second = cloud.true_normals[i];

    // 4. Random signs.
    std::mt19937_64 sign_rng(mix_seed(options.seed ^ 0x7369676E73ull)); // "signs"
    cloud.normals.reserve(n);
    for(std::size_t i = 0; i < n; ++i)
    {
      const Vector_3& v = with_normals[i].second;
      cloud.normals.push_back((sign_rng() >> 63) != 0 ? -v : v);
    }
    return cloud;
  }

private:
  std::vector<std::array<Point_3, 3>> m_triangles;
  std::vector<Vector_3> m_unit_normals;
  std::vector<double> m_cumulative_area;
  double m_bbox_diagonal = 0.0;
};

/**
 * \brief Writes `prefix + ".xyz"` (x y z nx ny nz: the input of the orientation programs)
 * and `prefix + ".gt.xyz"` (x y z gx gy gz: the ground truth), in the same point order.
 * \throws std::runtime_error on a write error.
 */
inline void write_cloud(const Sampled_cloud& cloud, const std::string& prefix)
{
  const std::string input_path = prefix + ".xyz";
  const std::string truth_path = prefix + ".gt.xyz";
  Xyz_writer input(input_path);
  Xyz_writer truth(truth_path);
  if(!input.is_open())
    throw std::runtime_error("cannot write '" + input_path + "'");
  if(!truth.is_open())
    throw std::runtime_error("cannot write '" + truth_path + "'");
  for(std::size_t i = 0; i < cloud.points.size(); ++i)
  {
    const Point_3& p = cloud.points[i];
    const Vector_3& n = cloud.normals[i];
    const Vector_3& g = cloud.true_normals[i];
    input.write_row(p.x(), p.y(), p.z(), n.x(), n.y(), n.z());
    truth.write_row(p.x(), p.y(), p.z(), g.x(), g.y(), g.z());
  }
  if(!input.close())
    throw std::runtime_error("write error on '" + input_path + "'");
  if(!truth.close())
    throw std::runtime_error("write error on '" + truth_path + "'");
}

} // namespace benchmark
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_BENCHMARK_MESH_SAMPLER_H
