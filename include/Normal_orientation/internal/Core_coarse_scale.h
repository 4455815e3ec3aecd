// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_CORE_COARSE_SCALE_H
#define NORMAL_ORIENTATION_INTERNAL_CORE_COARSE_SCALE_H

/// \file Core_coarse_scale.h
/// The coarse-to-fine pass (`Coarse_scale.h`) as the pipeline runs it: the
/// coarse cloud in the pipeline's own point type, what both drivers' passes
/// share (`Coarse_pass`: the accumulator, the coarse cloud oriented once by
/// the caller), and the in-core pass, which feeds the accumulator from the
/// vectors of the in-core pipeline and gives every point the coarse sign.

#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Orientation_result.h>
#include <Normal_orientation/internal/Canopy_rule.h>
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
#include <type_traits>
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

/// Whether `Point` is `Coarse_cloud_point`: the coarse cloud stands for
/// input normals that disagree at their own spacing, and its global stage
/// keeps the sparse samples (`global_samples()`).
template <typename Point>
struct Is_coarse_cloud_point : std::false_type
{};
/// \copydoc Is_coarse_cloud_point
template <typename Kernel>
struct Is_coarse_cloud_point<Coarse_cloud_point<Kernel>> : std::true_type
{};

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
/// run's flip criterion, solver, seed, threads, layer edges and global stage
/// (its mode and up direction).
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
    .layer_edges(settings.layer_edges)
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

/// What the coarse-to-fine passes of both drivers share: the accumulator,
/// which the driver feeds (`accumulator()`) before `finish()` decides
/// whether the pass runs (the grid is released when it does not), and
/// `take_coarse()`, which orients the coarse cloud once, whatever the number
/// of calls, and decides against the closedness of a fine orientation.
template <typename Kernel>
class Coarse_pass
{
public:
  /// whether the input normals disagree enough for the pass to be tried
  bool runs() const { return m_runs; }

  /// the cells of the canopy rule (`Canopy_rule.h`), from the same grid
  const std::shared_ptr<const Canopy_cells>& canopy() const { return m_canopy; }

  /// what the pass measured and did, with the seconds of all its calls
  Coarse_scale_report report() const
  {
    Coarse_scale_report r = m_report;
    r.seconds = m_seconds;
    return r;
  }

  /// Adds what the pass measured and did to the global stage's summary
  /// `global` (`before`: the coarse signs were taken before the solver), and
  /// its seconds to `global.seconds` and to `seconds`.
  void add_report(bool before, Global_sign_summary& global, double& seconds) const
  {
    global.coarse_before_solver = before;
    global.coherence = m_report.coherence;
    global.coarse_points = m_report.coarse_points;
    global.coarse_used = m_report.used;
    global.seconds += m_seconds;
    seconds += m_seconds;
  }

protected:
  explicit Coarse_pass(double radius) : m_coarse(std::make_shared<Coarse_scale>(radius)) {}

  Coarse_scale& accumulator() { return *m_coarse; }

  /// decides whether the pass runs, for a cloud of `n` points
  void finish(std::size_t n)
  {
    m_runs = m_coarse->decide(n);
    m_report = m_coarse->report();
    m_canopy = std::make_shared<const Canopy_cells>(*m_coarse);
    if (!m_runs)
      m_coarse.reset(); // its grid is not needed any more
  }

  /// Whether the points are to take the coarse signs against a fine
  /// orientation of closedness `fine_closedness`;
  /// `orient(std::vector<Coarse_cloud_point<Kernel>>&)` orients the coarse
  /// cloud in place with the pipeline and returns the closedness of the
  /// result (called once).  `runs()` must be true.
  template <typename Orient>
  bool take_coarse(double fine_closedness, const Orient& orient)
  {
    if (!m_oriented) {
      std::vector<Coarse_cloud_point<Kernel>> cloud = make_coarse_cloud<Kernel>(*m_coarse);
      m_coarse_closedness = orient(cloud);
      m_coarse_normals = coarse_cloud_normals(cloud);
      m_oriented = true;
    }
    const bool used = m_coarse->use_coarse_orientation(m_coarse_normals, m_coarse_closedness, fine_closedness);
    m_report = m_coarse->report();
    return used;
  }

  std::shared_ptr<Coarse_scale> m_coarse; ///< (released when the pass does not run)
  Coarse_scale_report m_report;
  double m_seconds = 0.0; ///< of all the calls

private:
  std::shared_ptr<const Canopy_cells> m_canopy;
  bool m_runs = false, m_oriented = false;
  double m_coarse_closedness = 0.0;
  std::vector<std::array<double, 3>> m_coarse_normals;
};

/// The coarse-to-fine pass on the in-core cloud `points` / unit `normals`
/// (zero allowed): the constructor measures whether the input normals agree
/// (`runs()`: they do not, and the pass is to be tried); `apply()`, when the
/// coarse cloud is more closed than the fine labelling, gives every label the
/// sign that makes its normal agree with the nearest coarse normal (unchanged
/// where there is none).
template <typename ConcurrencyTag, typename Kernel>
class Core_coarse_pass : public Coarse_pass<Kernel>
{
  typedef Coarse_pass<Kernel> Base;

public:
  Core_coarse_pass(const std::vector<typename Kernel::Point_3>& points,
                   const std::vector<typename Kernel::Vector_3>& normals, double radius)
    : Base(radius), m_points(points), m_normals(normals)
  {
    const auto t = std::chrono::steady_clock::now();
    if (!points.empty())
      this->accumulator().set_origin(position(0)); // (the points are in Morton order; streamed: the same point)
    for (std::size_t i = 0; i < points.size(); ++i)
      this->accumulator().add(position(i), direction(i));
    this->finish(points.size());
    this->m_seconds += seconds_since(t);
  }

  /// The pass against the fine `labels`, whose closedness is
  /// `fine_closedness` (`orient` as for `Coarse_pass::take_coarse()`).
  /// Returns whether the coarse signs were taken.
  template <typename Orient>
  bool apply(std::vector<Label>& labels, double fine_closedness, const Orient& orient)
  {
    if (!this->runs())
      return false;
    const auto t = std::chrono::steady_clock::now();
    const bool used = this->take_coarse(fine_closedness, orient);
    if (used) {
      const std::size_t n = m_points.size();
      const Coarse_scale& coarse = *this->m_coarse;
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
      this->m_report.points_flipped = 0;
      for (std::size_t i = 0; i < n; ++i)
        this->m_report.points_flipped += std::uint64_t(flipped[i]);
    }
    this->m_seconds += seconds_since(t);
    return used;
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
};

/// The coarse-to-fine pass around the solve of the in-core driver
/// (`solve_around_coarse_pass()`), as `streaming::internal::coarse_stage()`
/// is for the stream: `fine(solver, improve, dense)` solves and runs what
/// follows up to the global stage, which leaves its summary in `global`;
/// then `Core_coarse_pass` is tried against that labelling of `labels`
/// (`orient` as for `Coarse_pass::take_coarse()`), and `taken()` is called
/// when the coarse signs are taken.  Adds the pass's figures to `global` and
/// its seconds to `seconds`.  Returns the cells of the canopy rule, read
/// from the pass's grid.
template <typename ConcurrencyTag, typename Kernel, typename Solver, typename Fine, typename Orient, typename Taken>
std::shared_ptr<const Canopy_cells>
core_coarse_stage(const std::vector<typename Kernel::Point_3>& points,
                  const std::vector<typename Kernel::Vector_3>& normals, double radius, const Solver& solver,
                  const Fine& fine, const Orient& orient, std::vector<Label>& labels, Global_sign_summary& global,
                  double& seconds, const Taken& taken)
{
  Core_coarse_pass<ConcurrencyTag, Kernel> pass(points, normals, radius);
  const bool before = solve_around_coarse_pass(pass.runs(), solver, fine, [&]() {
    const bool used = pass.apply(labels, global.closedness, orient);
    if (used)
      taken();
    return used;
  });
  pass.add_report(before, global, seconds);
  return pass.canopy();
}

/// After the layer cues' round, whose stage replaced the global summary:
/// `later` (the round's) takes the coarse pass's figures from `earlier` (the
/// first round's, with `Coarse_pass::add_report()`), and the seconds of both
/// stages.  Both drivers call it.
inline void keep_coarse_report(const Global_sign_summary& earlier, Global_sign_summary& later)
{
  later.coherence = earlier.coherence;
  later.coarse_points = earlier.coarse_points;
  later.coarse_used = earlier.coarse_used;
  later.coarse_before_solver = earlier.coarse_before_solver;
  later.seconds += earlier.seconds;
}

} // namespace internal
/// \endcond
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_CORE_COARSE_SCALE_H
