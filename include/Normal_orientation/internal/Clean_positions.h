// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_CLEAN_POSITIONS_H
#define NORMAL_ORIENTATION_INTERNAL_CLEAN_POSITIONS_H

/// \file Clean_positions.h
/// Whether the default criterion, `Hoppe_konig_criterion`, takes König's
/// curves on every edge: on clouds of at most
/// `clean_positions_maximum_points` points whose positions are clean for
/// their spacing.  The rule, for both drivers:
/// - over the pairs (i, j), j one of the k nearest neighbours of i, whose
///   normals are nearly parallel (|phi_Hoppe| >= `clean_positions_parallel`),
///   the share of those where König's criterion has the other sign;
/// - König's curves everywhere when that share is below
///   `clean_positions_threshold`.
/// Between nearly parallel normals, the two criteria disagree where the
/// points lie off each other's tangent planes, which position noise of the
/// order of the spacing does, and the curves of a clean surface do not.  The
/// in-core driver measures it on the kNN of its graph, the streamed one on
/// its scan's copy of a small cloud; larger clouds are not measured (a
/// subsample has a wider spacing, so it would read cleaner than the cloud).

#include <Normal_orientation/Flip_criteria.h>
#include <Normal_orientation/internal/Parallel.h>

#include <CGAL/number_utils.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <type_traits>
#include <vector>

namespace Normal_orientation {
namespace internal {

/// The largest cloud that is measured.
constexpr std::size_t clean_positions_maximum_points = 200000;
/// The least |phi_Hoppe| of the pairs counted.
constexpr double clean_positions_parallel = 0.8;
/// Below this share of disagreeing pairs, König's curves are taken everywhere.
constexpr double clean_positions_threshold = 0.05;

/// The points measured: about this many, whatever the cloud's size.
constexpr std::size_t clean_positions_measured_points = 32768;

/// Whether point `p` of a cloud of `n` points is among those measured: a
/// hash of its coordinates, so that the choice does not depend on the order
/// of the points (the drivers hold them in different orders).
template <typename Point>
bool measured_point(const Point& p, std::size_t n)
{
  const std::uint64_t stride = std::max<std::uint64_t>(1, n / clean_positions_measured_points);
  if (stride == 1)
    return true;
  const double c[3] = {CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())};
  std::uint64_t h = 0x9e3779b97f4a7c15ull;
  for (double x : c) {
    std::uint64_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    h ^= bits + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
    h ^= h >> 31;
    h *= 0xbf58476d1ce4e5b9ull;
    h ^= h >> 29;
  }
  return h % stride == 0;
}

/// The share of disagreeing pairs (see the file comment) over the kNN lists
/// `nb` (k per point, as `k_nearest_neighbors()` returns them) of the
/// measured points (`measured_point()`); NaN when no pair counts.  The
/// counts are integers, so the result does not depend on the threads.
template <typename ConcurrencyTag, typename Point, typename Vector>
double konig_disagreement(const std::vector<Point>& points, const std::vector<Vector>& normals,
                          const std::vector<std::uint32_t>& nb, unsigned int k)
{
  const std::size_t n = points.size();
  std::vector<std::uint32_t> parallel(n, 0), disagree(n, 0);
  const Hoppe_criterion hoppe;
  const Konig_criterion konig;
  parallel_chunks<ConcurrencyTag>(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      if (!measured_point(points[i], n))
        continue;
      for (unsigned int t = 0; t < k; ++t) {
        const std::uint32_t j = nb[i * k + t];
        if (j >= n || j == i)
          continue;
        const double h = hoppe(points[i], normals[i], points[j], normals[j]);
        if (!(std::abs(h) >= clean_positions_parallel))
          continue;
        ++parallel[i];
        if (h * konig(points[i], normals[i], points[j], normals[j]) < 0.0)
          ++disagree[i];
      }
    }
  });
  std::uint64_t p = 0, d = 0;
  for (std::size_t i = 0; i < n; ++i) {
    p += parallel[i];
    d += disagree[i];
  }
  return p > 0 ? double(d) / double(p) : std::numeric_limits<double>::quiet_NaN();
}

/// What the rule found: the share (NaN when not measured) and the decision.
struct Clean_positions
{
  double konig_disagreement = std::numeric_limits<double>::quiet_NaN();
  bool konig_everywhere = false;
};

/// Applies the rule to `criterion` (a copy of the caller's) for a cloud of
/// `n` points; `measure()` returns the share.  Criteria other than the
/// default are left as they are, and nothing is measured.
template <typename FlipCriterion, typename Measure>
Clean_positions apply_clean_positions(FlipCriterion& criterion, std::size_t n, const Measure& measure)
{
  Clean_positions c;
  if constexpr (std::is_same<FlipCriterion, Hoppe_konig_criterion>::value) {
    if (n > clean_positions_maximum_points)
      return c;
    c.konig_disagreement = measure();
    c.konig_everywhere = c.konig_disagreement < clean_positions_threshold;
    criterion.konig_everywhere = c.konig_everywhere;
  }
  (void)criterion;
  (void)n;
  (void)measure;
  return c;
}

} // namespace internal
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_CLEAN_POSITIONS_H
