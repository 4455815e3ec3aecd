// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_EXTERIOR_VISIBILITY_H
#define NORMAL_ORIENTATION_EXTERIOR_VISIBILITY_H

/// \file Exterior_visibility.h
/// The side from which an open surface was seen: orthographic views of the
/// samples, drawn as splats, from many directions around the cloud
/// (`exterior_visibility()`), and the signs of open components that follow
/// from them (`visibility_flips()`).

#include <Normal_orientation/internal/Parallel.h>
#include <Normal_orientation/internal/Unit_vector.h>

#include <CGAL/Kernel_traits.h>
#include <CGAL/tags.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationGlobal
/// The parameters of `exterior_visibility()`.
struct Exterior_visibility_options
{
  /// views, spread evenly over the sphere of directions (a Fibonacci sphere)
  unsigned int number_of_directions = 32;
  /// the up direction of the scene (need not be unit; zero: none, every
  /// view weighs 1)
  std::array<double, 3> up = {{0.0, 0.0, 1.0}};
  /// the weight of the views from below the horizon (from directions d with
  /// d . up < 0): scenes are seen from above far more often than from below,
  /// and a terrain, as visible from both sides, faces up only so
  double below_horizon_weight = 0.1;
  /// the radius of a sample's splat, in units of sqrt(area / pi)
  double splat_factor = 1.5;
  /// the largest side of a view's depth image, in pixels
  unsigned int maximum_resolution = 1024;
};

/// \cond SKIP_IN_MANUAL
namespace internal {

/// the unit direction `i` of `count` on a Fibonacci sphere
inline std::array<double, 3> fibonacci_direction(unsigned int i, unsigned int count)
{
  const double z = 1.0 - (2.0 * i + 1.0) / count, r = std::sqrt(std::max(0.0, 1.0 - z * z));
  const double phi = 2.399963229728653 * i; // the golden angle
  return {{r * std::cos(phi), r * std::sin(phi), z}};
}

/// Adds to `vote` the view from direction `d` (towards the viewer): for
/// every sample that no splat hides, weight (n . d) (nothing when `weight`
/// is 0); and n . d to `*even` unless it is null.  `radius` holds the
/// splats' radii, `cell` the smallest pixel side.
template <typename Point, typename Vector>
void add_view(const std::vector<Point>& points, const std::vector<Vector>& normals, const std::vector<double>& radius,
              const std::array<double, 3>& d, double weight, double cell, unsigned int maximum_resolution,
              std::vector<double>& vote, std::vector<double>* even = nullptr)
{
  // an orthonormal frame (u, v, d)
  const std::array<double, 3> a = std::abs(d[0]) < 0.9 ? std::array<double, 3>{{1, 0, 0}} : std::array<double, 3>{{0, 1, 0}};
  std::array<double, 3> u = {{a[1] * d[2] - a[2] * d[1], a[2] * d[0] - a[0] * d[2], a[0] * d[1] - a[1] * d[0]}};
  const double lu = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  for (double& c : u)
    c /= lu;
  const std::array<double, 3> v = {{d[1] * u[2] - d[2] * u[1], d[2] * u[0] - d[0] * u[2], d[0] * u[1] - d[1] * u[0]}};
  const std::size_t n = points.size();
  std::vector<double> x(n), y(n), t(n);
  double x0 = std::numeric_limits<double>::max(), y0 = x0, x1 = -x0, y1 = -x0;
  for (std::size_t j = 0; j < n; ++j) {
    const Point& p = points[j];
    x[j] = p.x() * u[0] + p.y() * u[1] + p.z() * u[2];
    y[j] = p.x() * v[0] + p.y() * v[1] + p.z() * v[2];
    t[j] = p.x() * d[0] + p.y() * d[1] + p.z() * d[2];
    x0 = std::min(x0, x[j] - radius[j]);
    x1 = std::max(x1, x[j] + radius[j]);
    y0 = std::min(y0, y[j] - radius[j]);
    y1 = std::max(y1, y[j] + radius[j]);
  }
  const double side = std::max({cell, (x1 - x0) / maximum_resolution, (y1 - y0) / maximum_resolution});
  const long w = std::max(1L, long(std::ceil((x1 - x0) / side))), h = std::max(1L, long(std::ceil((y1 - y0) / side)));
  std::vector<float> depth(std::size_t(w * h), -std::numeric_limits<float>::infinity());
  auto pixel = [&](double c, double origin, long size) {
    return std::min(size - 1, std::max(0L, long((c - origin) / side)));
  };
  for (std::size_t j = 0; j < n; ++j) {
    const long ia = pixel(x[j] - radius[j], x0, w), ib = pixel(x[j] + radius[j], x0, w);
    const long ja = pixel(y[j] - radius[j], y0, h), jb = pixel(y[j] + radius[j], y0, h);
    const double r2 = radius[j] * radius[j];
    for (long jy = ja; jy <= jb; ++jy)
      for (long ix = ia; ix <= ib; ++ix) {
        const double dx = std::max(0.0, std::abs(x0 + (ix + 0.5) * side - x[j]) - 0.5 * side);
        const double dy = std::max(0.0, std::abs(y0 + (jy + 0.5) * side - y[j]) - 0.5 * side);
        float& z = depth[std::size_t(jy * w + ix)];
        if (dx * dx + dy * dy <= r2 && float(t[j]) > z)
          z = float(t[j]);
      }
  }
  for (std::size_t j = 0; j < n; ++j) {
    const float front = depth[std::size_t(pixel(y[j], y0, h) * w + pixel(x[j], x0, w))];
    const Vector& m = normals[j];
    const double length = std::sqrt(m.x() * m.x() + m.y() * m.y() + m.z() * m.z());
    if (length == 0.0)
      continue;
    const double c = (m.x() * d[0] + m.y() * d[1] + m.z() * d[2]) / length;
    // the splats of a plane through the sample reach r tan(angle) nearer
    const double slope = std::min(4.0, std::sqrt(std::max(0.0, 1.0 - c * c)) / std::max(std::abs(c), 1e-3));
    if (t[j] >= double(front) - (0.5 + slope) * radius[j]) {
      if (weight > 0.0)
        vote[j] += weight * c;
      if (even)
        (*even)[j] += c;
    }
  }
}

/// The splats' radii of `exterior_visibility()`, after checking its input;
/// `caller` names the function in the exceptions.
template <typename Point, typename Vector>
std::vector<double> splat_radii(const std::vector<Point>& points, const std::vector<Vector>& normals,
                                const std::vector<double>& areas, const Exterior_visibility_options& options,
                                const char* caller)
{
  const std::size_t n = points.size();
  auto fail = [caller](const char* what) { throw std::invalid_argument(std::string(caller) + ": " + what); };
  if (normals.size() != n || areas.size() != n)
    fail("points, normals and areas differ in size");
  if (options.number_of_directions == 0 || options.maximum_resolution == 0 || !(options.splat_factor > 0.0) ||
      !(options.below_horizon_weight >= 0.0) || !std::isfinite(options.splat_factor) ||
      !std::isfinite(options.below_horizon_weight) || !std::isfinite(options.up[0]) ||
      !std::isfinite(options.up[1]) || !std::isfinite(options.up[2]))
    fail("an option is out of range");
  std::vector<double> radius(n);
  for (std::size_t j = 0; j < n; ++j) {
    if (!std::isfinite(points[j].x()) || !std::isfinite(points[j].y()) || !std::isfinite(points[j].z()))
      fail("a position is not finite");
    if (!(areas[j] >= 0.0) || !std::isfinite(areas[j]))
      fail("an area is negative or not finite");
    radius[j] = options.splat_factor * std::sqrt(areas[j] / 3.141592653589793);
  }
  return radius;
}

/// Checks the per-sample input of the group rules: `areas` and `group` have
/// `n` entries and every group id is below `number_of_groups`; `caller`
/// names the function in the exceptions.
inline void check_groups(std::size_t n, const std::vector<double>& areas, const std::vector<std::uint32_t>& group,
                         std::size_t number_of_groups, const char* caller)
{
  if (areas.size() != n || group.size() != n)
    throw std::invalid_argument(std::string(caller) + ": per-sample values, areas and groups differ in size");
  for (std::uint32_t g : group)
    if (g >= number_of_groups)
      throw std::invalid_argument(std::string(caller) + ": a group id is out of range");
}

/// Whether a sample of the top surface (`facing` from `top_view_facing()`)
/// lies within 30 degrees of horizontal: |`facing`| >= cos 30 degrees.
inline bool near_horizontal_top(double facing) { return std::abs(facing) >= 0.8660254037844386; }

/// The share of a group's near-horizontal top that must face down for
/// `downward_top_flips()` to negate it.
constexpr double top_down_share = 0.75;

/// The median of `radius` (not empty), at least the smallest positive double:
/// the pixel side of the views.
inline double median_radius(std::vector<double> radius)
{
  std::nth_element(radius.begin(), radius.begin() + std::ptrdiff_t(radius.size() / 2), radius.end());
  return std::max(radius[radius.size() / 2], std::numeric_limits<double>::min());
}

/// `exterior_visibility()`; with `even` not null, also the votes of the same
/// views, each of weight 1 (those of `options` without an up direction),
/// in `*even`: the views are drawn once.
template <typename ConcurrencyTag, typename Point, typename Vector>
std::vector<double> visibility_votes(const std::vector<Point>& points, const std::vector<Vector>& normals,
                                     const std::vector<double>& areas, const Exterior_visibility_options& options,
                                     std::vector<double>* even)
{
  const std::size_t n = points.size();
  const std::vector<double> radius = splat_radii(points, normals, areas, options, "exterior_visibility");
  std::vector<double> vote(n, 0.0);
  if (even)
    even->assign(n, 0.0);
  if (n == 0)
    return vote;
  const double cell = median_radius(radius);
  // Fixed blocks of directions, summed in order: the same votes for any
  // thread count.
  const unsigned int count = options.number_of_directions, blocks = std::min(8u, count);
  std::vector<std::vector<double>> partial(blocks, std::vector<double>(n, 0.0));
  std::vector<std::vector<double>> even_partial(even ? blocks : 0u, std::vector<double>(n, 0.0));
  auto view_weight = [&](const std::array<double, 3>& d) {
    return d[0] * options.up[0] + d[1] * options.up[1] + d[2] * options.up[2] < 0.0 ? options.below_horizon_weight
                                                                                    : 1.0;
  };
  double total_weight = 0.0;
  for (unsigned int i = 0; i < count; ++i)
    total_weight += view_weight(fibonacci_direction(i, count));
  parallel_chunks<ConcurrencyTag>(
    blocks,
    [&](std::size_t b, std::size_t e) {
      for (std::size_t k = b; k < e; ++k)
        for (unsigned int i = unsigned(k); i < count; i += blocks) {
          const std::array<double, 3> d = fibonacci_direction(i, count);
          const double weight = view_weight(d);
          if (weight > 0.0 || even)
            add_view(points, normals, radius, d, weight, cell, options.maximum_resolution, partial[k],
                     even ? &even_partial[k] : nullptr);
        }
    },
    1);
  // (the blocks' sums in block order, over the total weight)
  auto fold = [&](const std::vector<std::vector<double>>& blocks_sums, double total, std::vector<double>& out) {
    for (const std::vector<double>& block_sums : blocks_sums)
      for (std::size_t j = 0; j < n; ++j)
        out[j] += block_sums[j];
    for (double& x : out)
      x /= total;
  };
  fold(partial, total_weight, vote);
  if (even)
    fold(even_partial, double(count), *even);
  return vote;
}

} // namespace internal
/// \endcond

/// \ingroup PkgNormalOrientationGlobal
/// For every sample, how much its oriented normal faces the side from which
/// it is seen: the weighted mean over `options.number_of_directions`
/// orthographic views from directions d spread over the sphere, each of
/// weight 1, or `below_horizon_weight` when d . up < 0, of n . d (n the
/// unit normal) where no nearer splat hides the sample, 0 where one does.
/// Splats are discs of radius r = `splat_factor * sqrt(a / pi)` across the
/// view, at the sample's depth; a sample is hidden when a splat over it is
/// nearer by more than r (1/2 + tan theta), theta the angle between n and d
/// (capped at tan theta = 4), which the splats of a plane through the
/// sample do not reach.  Votes are in [-1, 1]: about +0.3 on a flat sheet
/// oriented up, and outside a closed surface, where it faces up (a tenth
/// of that where it faces down: only the lighter views from below see it);
/// their negatives when inverted; 0 for a zero normal or a sample no view
/// sees.
///
/// Deterministic for any thread count. Time O(m r^2 D) for m samples, D
/// directions and r the splats' radii in pixels; memory O(m + threads
/// * maximum_resolution^2).
///
/// \tparam ConcurrencyTag `CGAL::Sequential_tag` or `CGAL::Parallel_tag`
/// \throws std::invalid_argument when the sizes differ, a position or an
/// area is not finite, an area is negative, or an option is out of range
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename Point, typename Vector>
std::vector<double> exterior_visibility(const std::vector<Point>& points, const std::vector<Vector>& normals,
                                        const std::vector<double>& areas,
                                        const Exterior_visibility_options& options = {})
{
  return internal::visibility_votes<ConcurrencyTag>(points, normals, areas, options, nullptr);
}

/// \ingroup PkgNormalOrientationGlobal
/// For every sample, how much its oriented normal faces up where it is on
/// the top surface of the scene: n . u (n and u = `options.up` made unit)
/// where no splat hides the sample in the orthographic view from straight
/// above (the splats and the hiding rule of `exterior_visibility()`), 0
/// where one does, and 0 for every sample when `options.up` is zero.
/// Outside a closed surface, the top surface faces up everywhere; so does
/// the ground of a scene seen from above or from the ground.
///
/// \tparam ConcurrencyTag `CGAL::Sequential_tag` or `CGAL::Parallel_tag`
/// \throws std::invalid_argument as `exterior_visibility()`
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename Point, typename Vector>
std::vector<double> top_view_facing(const std::vector<Point>& points, const std::vector<Vector>& normals,
                                    const std::vector<double>& areas, const Exterior_visibility_options& options = {})
{
  const std::vector<double> radius = internal::splat_radii(points, normals, areas, options, "top_view_facing");
  std::vector<double> facing(points.size(), 0.0);
  const std::array<double, 3> u = internal::unit_vector(options.up[0], options.up[1], options.up[2]);
  if (points.empty() || (u[0] == 0.0 && u[1] == 0.0 && u[2] == 0.0))
    return facing;
  internal::add_view(points, normals, radius, u, 1.0, internal::median_radius(radius), options.maximum_resolution,
                     facing);
  return facing;
}

/// \ingroup PkgNormalOrientationGlobal
/// The groups of samples (components) whose top surface faces down: those
/// with a flag in `eligible` (per group id) where the samples of the top
/// surface that lie within 30 degrees of horizontal (|`facing`| >= cos 30
/// degrees, `facing` from `top_view_facing()`) hold at least
/// `minimum_fraction` of the group's area and face down on more than
/// three quarters of that area.  `group` is the group id of each sample;
/// the result has a flag per group id.
/// \throws std::invalid_argument when the sizes differ or an id is out of range
inline std::vector<char> downward_top_flips(const std::vector<double>& facing, const std::vector<double>& areas,
                                            const std::vector<std::uint32_t>& group,
                                            const std::vector<char>& eligible, double minimum_fraction = 0.05)
{
  internal::check_groups(facing.size(), areas, group, eligible.size(), "downward_top_flips");
  std::vector<double> area(eligible.size(), 0.0), top(eligible.size(), 0.0), down(eligible.size(), 0.0);
  for (std::size_t j = 0; j < facing.size(); ++j) {
    area[group[j]] += areas[j];
    if (internal::near_horizontal_top(facing[j])) {
      top[group[j]] += areas[j];
      if (facing[j] < 0.0)
        down[group[j]] += areas[j];
    }
  }
  std::vector<char> flip(eligible.size(), 0);
  for (std::size_t g = 0; g < eligible.size(); ++g)
    flip[g] = eligible[g] && area[g] > 0.0 && top[g] >= minimum_fraction * area[g] &&
              down[g] > internal::top_down_share * top[g];
  return flip;
}

/// \ingroup PkgNormalOrientationGlobal
/// The groups of samples (components, patches) that face away from the
/// side they were seen from: those with a flag in `eligible` (per group
/// id) whose area-weighted mean vote of `exterior_visibility()` is below
/// `-margin`.  `group` is the group id of each sample; the result has a
/// flag per group id.
/// \throws std::invalid_argument when the sizes differ or an id is out of range
inline std::vector<char> visibility_flips(const std::vector<double>& vote, const std::vector<double>& areas,
                                          const std::vector<std::uint32_t>& group,
                                          const std::vector<char>& eligible, double margin = 0.02)
{
  internal::check_groups(vote.size(), areas, group, eligible.size(), "visibility_flips");
  std::vector<double> sum(eligible.size(), 0.0), area(eligible.size(), 0.0);
  for (std::size_t j = 0; j < vote.size(); ++j) {
    sum[group[j]] += areas[j] * vote[j];
    area[group[j]] += areas[j];
  }
  std::vector<char> flip(eligible.size(), 0);
  for (std::size_t g = 0; g < eligible.size(); ++g)
    flip[g] = eligible[g] && area[g] > 0.0 && sum[g] < -margin * area[g];
  return flip;
}

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_EXTERIOR_VISIBILITY_H
