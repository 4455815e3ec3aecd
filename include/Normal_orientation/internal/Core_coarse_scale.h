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
#include <memory>
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

/// The coarse-to-fine pass on the in-core cloud `points` / unit `normals`
/// (zero allowed): the constructor measures whether the input normals agree
/// (`runs()`: they do not, and the pass is to be tried); `apply()` orients
/// the coarse cloud (once, whatever the number of calls) and, when it is more
/// closed than the fine labelling, gives every label the sign that makes its
/// normal agree with the nearest coarse normal (unchanged where there is
/// none).
template <typename ConcurrencyTag, typename Kernel>
class Core_coarse_pass
{
public:
  Core_coarse_pass(const std::vector<typename Kernel::Point_3>& points,
                   const std::vector<typename Kernel::Vector_3>& normals, double radius)
    : m_points(points), m_normals(normals), m_coarse(std::make_unique<Coarse_scale>(radius))
  {
    const auto t = std::chrono::steady_clock::now();
    for (std::size_t i = 0; i < points.size(); ++i)
      m_coarse->add(position(i), direction(i));
    m_runs = m_coarse->decide(points.size());
    m_report = m_coarse->report();
    if (!m_runs)
      m_coarse.reset(); // its grid is not needed any more
    m_seconds = seconds_since(t);
  }

  /// whether the input normals disagree enough for the pass to be tried
  bool runs() const { return m_runs; }

  /// The pass against the fine `labels`, whose closedness is
  /// `fine_closedness`; `orient(std::vector<Coarse_cloud_point<Kernel>>&)`
  /// orients the coarse cloud in place with the pipeline and returns the
  /// closedness of the result.  Returns whether the coarse signs were taken.
  template <typename Orient>
  bool apply(std::vector<Label>& labels, double fine_closedness, const Orient& orient)
  {
    if (!m_runs)
      return false;
    const auto t = std::chrono::steady_clock::now();
    if (!m_oriented) {
      std::vector<Coarse_cloud_point<Kernel>> cloud = make_coarse_cloud<Kernel>(*m_coarse);
      m_coarse_closedness = orient(cloud);
      m_coarse_normals = coarse_cloud_normals(cloud);
      m_oriented = true;
    }
    bool used = false;
    if (m_coarse->use_coarse_orientation(m_coarse_normals, m_coarse_closedness, fine_closedness)) {
      used = true;
      const std::size_t n = m_points.size();
      std::vector<char> flipped(n, 0);
      parallel_chunks<ConcurrencyTag>(n, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
          const signed char s = m_coarse->sign(position(i), direction(i));
          if (s != 0 && s != labels[i]) {
            labels[i] = Label(s);
            flipped[i] = 1;
          }
        }
      });
      m_coarse->report().points_flipped = 0;
      for (std::size_t i = 0; i < n; ++i)
        m_coarse->report().points_flipped += std::uint64_t(flipped[i]);
    }
    m_report = m_coarse->report();
    m_seconds += seconds_since(t);
    return used;
  }

  /// what the pass measured and did, with the seconds of all its calls
  Coarse_scale_report report() const
  {
    Coarse_scale_report r = m_report;
    r.seconds = m_seconds;
    return r;
  }

private:
  std::array<double, 3> position(std::size_t i) const
  {
    return {{CGAL::to_double(m_points[i].x()), CGAL::to_double(m_points[i].y()), CGAL::to_double(m_points[i].z())}};
  }
  std::array<double, 3> direction(std::size_t i) const
  {
    return {{CGAL::to_double(m_normals[i].x()), CGAL::to_double(m_normals[i].y()), CGAL::to_double(m_normals[i].z())}};
  }

  const std::vector<typename Kernel::Point_3>& m_points;
  const std::vector<typename Kernel::Vector_3>& m_normals;
  std::unique_ptr<Coarse_scale> m_coarse; ///< (released when the pass does not run)
  Coarse_scale_report m_report;
  bool m_runs = false, m_oriented = false;
  double m_coarse_closedness = 0.0, m_seconds = 0.0;
  std::vector<std::array<double, 3>> m_coarse_normals;
};

} // namespace internal
/// \endcond
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_CORE_COARSE_SCALE_H
