// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_CORE_COARSE_SCALE_H
#define NORMAL_ORIENTATION_INTERNAL_CORE_COARSE_SCALE_H

/// \file Core_coarse_scale.h
/// The in-core driver of the coarse-to-fine pass (`Coarse_scale.h`): it feeds
/// the accumulator from the vectors of the in-core pipeline, has the coarse
/// cloud oriented by the caller and gives every point the coarse sign.

#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/internal/Coarse_scale.h>
#include <Normal_orientation/internal/Core_global_sign.h>
#include <Normal_orientation/internal/Parallel.h>
#include <Normal_orientation/internal/Settings.h>
#include <Normal_orientation/parameters.h>

#include <CGAL/number_utils.h>

#include <boost/property_map/property_map.hpp>

#include <array>
#include <chrono>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace Normal_orientation {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// A point of the coarse cloud as the in-core pipeline orients it.
template <typename Kernel>
struct Coarse_cloud_point
{
  typename Kernel::Point_3 point;
  typename Kernel::Vector_3 normal;
};

/// The position map of a coarse cloud.
template <typename Kernel>
struct Coarse_point_map
{
  typedef Coarse_cloud_point<Kernel> key_type;
  typedef typename Kernel::Point_3 value_type;
  typedef const value_type& reference;
  typedef boost::readable_property_map_tag category;
  friend reference get(const Coarse_point_map&, const key_type& k) { return k.point; }
};

/// The normal map of a coarse cloud.
template <typename Kernel>
struct Coarse_normal_map
{
  typedef Coarse_cloud_point<Kernel> key_type;
  typedef typename Kernel::Vector_3 value_type;
  typedef const value_type& reference;
  typedef boost::read_write_property_map_tag category;
  friend reference get(const Coarse_normal_map&, const key_type& k) { return k.normal; }
  friend void put(const Coarse_normal_map&, key_type& k, const value_type& v) { k.normal = v; }
};

/// The named parameters with which both drivers orient a coarse cloud: the
/// run's flip criterion, solver, seed, threads and global stage (its mode and
/// up direction).
template <typename Kernel, typename FlipCriterion, typename Solver>
auto coarse_cloud_parameters(const FlipCriterion& criterion, const Solver& solver, const Settings& settings,
                             const Global_settings& global)
{
  return parameters::point_map(Coarse_point_map<Kernel>())
    .normal_map(Coarse_normal_map<Kernel>())
    .geom_traits(Kernel())
    .flip_criterion(criterion)
    .solver(solver)
    .global_orientation(global.orientation)
    .up_direction(global.up)
    .random_seed((unsigned int)(settings.random_seed))
    .number_of_threads(settings.number_of_threads);
}

/// Builds the coarse cloud of `coarse` as the in-core pipeline takes it.
template <typename Kernel>
std::vector<Coarse_cloud_point<Kernel>> make_coarse_cloud(const Coarse_scale& coarse)
{
  const auto& p = coarse.coarse_points();
  const auto& v = coarse.coarse_normals();
  std::vector<Coarse_cloud_point<Kernel>> cloud(p.size());
  for (std::size_t j = 0; j < p.size(); ++j) {
    cloud[j].point = typename Kernel::Point_3(p[j][0], p[j][1], p[j][2]);
    cloud[j].normal = typename Kernel::Vector_3(v[j][0], v[j][1], v[j][2]);
  }
  return cloud;
}

/// The normals of an oriented coarse cloud.
template <typename Kernel>
std::vector<std::array<double, 3>> coarse_cloud_normals(const std::vector<Coarse_cloud_point<Kernel>>& cloud)
{
  std::vector<std::array<double, 3>> normals(cloud.size());
  for (std::size_t j = 0; j < cloud.size(); ++j)
    normals[j] = {{CGAL::to_double(cloud[j].normal.x()), CGAL::to_double(cloud[j].normal.y()),
                   CGAL::to_double(cloud[j].normal.z())}};
  return normals;
}

/// Runs the coarse-to-fine pass on the in-core cloud `points` / unit
/// `normals` (zero allowed), whose current `labels` have the closedness
/// `fine_closedness`.  `orient(std::vector<Coarse_cloud_point<Kernel>>&)`
/// must orient the coarse cloud in place with the pipeline and return the
/// closedness of the result.  When the coarse signs are used, every label
/// becomes the one that makes its normal agree with the nearest coarse
/// normal (unchanged where there is none).
template <typename ConcurrencyTag, typename Kernel, typename Orient>
Coarse_scale_report core_coarse_signs(const std::vector<typename Kernel::Point_3>& points,
                                      const std::vector<typename Kernel::Vector_3>& normals, double radius,
                                      std::vector<Label>& labels, double fine_closedness, const Orient& orient)
{
  const auto t = std::chrono::steady_clock::now();
  const std::size_t n = points.size();
  auto position = [&](std::size_t i) {
    return std::array<double, 3>{{CGAL::to_double(points[i].x()), CGAL::to_double(points[i].y()),
                                  CGAL::to_double(points[i].z())}};
  };
  auto direction = [&](std::size_t i) {
    return std::array<double, 3>{{CGAL::to_double(normals[i].x()), CGAL::to_double(normals[i].y()),
                                  CGAL::to_double(normals[i].z())}};
  };
  Coarse_scale coarse(radius);
  for (std::size_t i = 0; i < n; ++i)
    coarse.add(position(i), direction(i));
  if (coarse.decide(n)) {
    std::vector<Coarse_cloud_point<Kernel>> cloud = make_coarse_cloud<Kernel>(coarse);
    const double closedness = orient(cloud);
    if (coarse.use_coarse_orientation(coarse_cloud_normals(cloud), closedness, fine_closedness)) {
      std::vector<char> flipped(n, 0);
      parallel_chunks<ConcurrencyTag>(n, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
          const signed char s = coarse.sign(position(i), direction(i));
          if (s != 0 && s != labels[i]) {
            labels[i] = Label(s);
            flipped[i] = 1;
          }
        }
      });
      for (std::size_t i = 0; i < n; ++i)
        coarse.report().points_flipped += std::uint64_t(flipped[i]);
    }
  }
  coarse.report().seconds = seconds_since(t);
  return coarse.report();
}

} // namespace internal
/// \endcond
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_CORE_COARSE_SCALE_H
