// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_TWO_LAYER_FIT_H
#define NORMAL_ORIENTATION_INTERNAL_TWO_LAYER_FIT_H

/// \file Two_layer_fit.h
/// Whether a point's neighbourhood is two parallel layers closer than the
/// neighbour distance (both sides of a thin part, or two objects in
/// contact): the fit of the manual's *Layer cues*, per point, from the
/// positions of the point and its neighbours and the point's normal line.

#include <Normal_orientation/internal/Symmetric_eigen_3.h>
#include <Normal_orientation/internal/Unit_vector.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// The result of `fit_two_layers()`.
struct Two_layer_fit
{
  bool two_layers = false;            ///< whether the neighbourhood is two layers
  std::array<double, 3> to_other{};   ///< from the point to the other layer's mean, along the fitted line
  double gap = 0.0;                   ///< the distance between the layers' means along that line
};

/// The fit's thresholds.
struct Two_layer_thresholds
{
  /// the layers' distance must exceed this times the larger spread about
  /// their own means
  double separation = 20.0;
  /// the layers' distance must exceed this times the smallest distance,
  /// across the fitted line, between two points on different layers (one
  /// surface that bends climbs less between neighbouring points)
  double min_step = 0.2;
  /// the fitted line must be within acos(this) of the point's normal line
  double min_alignment = 0.7;
  /// refits of the line to both layers, each about its own mean
  unsigned int refits = 4;
  /// the fewest points on each side of the split
  std::size_t min_side = 3;
  /// the fewest points in all (fewer, as with a small k, split by chance)
  std::size_t min_points = 10;
  /// before any refit, the split along the point's own normal line is
  /// rejected when the layers' distance is under this times the larger
  /// spread (a single layer: most points stop here)
  double early_separation = 4.0;
  /// before any refit, the split is also rejected when the layers' distance
  /// is under this times the root-mean-square distance of the neighbours
  /// from the point (the offsets of one curved layer are far smaller)
  double early_gap = 0.07;
  /// before any refit, the split is also rejected when its sides lie side
  /// by side (`side_by_side()`): one surface seen along a tilted line
  bool early_side_by_side = true;
  /// before any sort, the neighbourhood is also rejected when its offsets,
  /// less the plane that fits them best over the tangential position
  /// (`detilted_range()`), range over no more than `early_gap` times that
  /// root-mean-square distance: one layer seen along a tilted normal line
  bool early_detilt = true;
};

/// The range of the offsets of q[0..m) along the unit line `n`, from q[0],
/// less the least-squares affine function of their position across n.
inline double detilted_range(const std::vector<std::array<double, 3>>& q, const std::array<double, 3>& n)
{
  double e1[3], e2[3]; // a basis of the plane normal to n
  tangent_basis(n.data(), e1, e2);
  const std::size_t m = q.size();
  double sx = 0.0, sy = 0.0, so = 0.0, sxx = 0.0, sxy = 0.0, syy = 0.0, sxo = 0.0, syo = 0.0;
  auto coordinates = [&](std::size_t k, double& x, double& y, double& o) {
    const double v[3] = {q[k][0] - q[0][0], q[k][1] - q[0][1], q[k][2] - q[0][2]};
    x = v[0] * e1[0] + v[1] * e1[1] + v[2] * e1[2];
    y = v[0] * e2[0] + v[1] * e2[1] + v[2] * e2[2];
    o = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
  };
  for (std::size_t k = 0; k < m; ++k) {
    double x, y, o;
    coordinates(k, x, y, o);
    sx += x; sy += y; so += o;
    sxx += x * x; sxy += x * y; syy += y * y; sxo += x * o; syo += y * o;
  }
  const double w = 1.0 / double(m);
  sxx -= sx * sx * w; sxy -= sx * sy * w; syy -= sy * sy * w; sxo -= sx * so * w; syo -= sy * so * w;
  const double det = sxx * syy - sxy * sxy;
  double a = 0.0, b = 0.0;
  if (det > 1e-12 * (sxx * syy) && det > 0.0) {
    a = (sxo * syy - syo * sxy) / det;
    b = (syo * sxx - sxo * sxy) / det;
  }
  double lo = HUGE_VAL, hi = -HUGE_VAL;
  for (std::size_t k = 0; k < m; ++k) {
    double x, y, o;
    coordinates(k, x, y, o);
    const double r = o - a * x - b * y;
    lo = std::min(lo, r);
    hi = std::max(hi, r);
  }
  return hi - lo;
}

/// Whether the sides of a split lie side by side rather than over each
/// other: projected on the plane normal to `n`, no point of the lower side
/// (`scratch[0, split)`) lies beyond the nearest point of the upper side
/// along the direction between their centroids.  Two faces meeting at a
/// slight crease split so (exact planes leave each side no spread along
/// the fitted line); two layers overlap.
inline bool side_by_side(const std::vector<std::array<double, 3>>& q,
                         const std::vector<std::pair<double, std::uint32_t>>& scratch, std::size_t split,
                         const std::array<double, 3>& n)
{
  const std::size_t m = scratch.size();
  auto tangential = [&](std::size_t s) {
    const auto& p = q[scratch[s].second];
    const double v[3] = {p[0] - q[0][0], p[1] - q[0][1], p[2] - q[0][2]};
    const double o = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
    return std::array<double, 3>{{v[0] - o * n[0], v[1] - o * n[1], v[2] - o * n[2]}};
  };
  std::array<double, 3> d = {{0.0, 0.0, 0.0}}; // from the lower side's centroid to the upper's
  for (std::size_t s = 0; s < m; ++s) {
    const std::array<double, 3> v = tangential(s);
    const double w = s < split ? -1.0 / double(split) : 1.0 / double(m - split);
    for (int c = 0; c < 3; ++c)
      d[c] += w * v[c];
  }
  double lower = -HUGE_VAL, upper = HUGE_VAL;
  for (std::size_t s = 0; s < m; ++s) {
    const std::array<double, 3> v = tangential(s);
    const double x = v[0] * d[0] + v[1] * d[1] + v[2] * d[2];
    if (s < split)
      lower = std::max(lower, x);
    else
      upper = std::min(upper, x);
  }
  return lower < upper;
}

/// The smallest distance, across the line `n`, between a point of the lower
/// side of a split (`scratch[0, split)`) and one of the upper side.
inline double closest_across(const std::vector<std::array<double, 3>>& q,
                             const std::vector<std::pair<double, std::uint32_t>>& scratch, std::size_t split,
                             const std::array<double, 3>& n)
{
  double best = HUGE_VAL;
  for (std::size_t a = 0; a < split; ++a)
    for (std::size_t b = split; b < scratch.size(); ++b) {
      const auto& p = q[scratch[a].second];
      const auto& r = q[scratch[b].second];
      const double v[3] = {r[0] - p[0], r[1] - p[1], r[2] - p[2]};
      const double o = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
      best = std::min(best, v[0] * v[0] + v[1] * v[1] + v[2] * v[2] - o * o);
    }
  return std::sqrt(std::max(best, 0.0));
}

/// Whether the point `q[0]` and its neighbours `q[1..m-1]` (m >= 2 min_side, m >= min_points)
/// lie on two parallel layers.  Their offsets along the normal line `normal`
/// (unit) are split at their largest gap with at least `min_side` on each
/// side; the line is refitted to both sides, each about its own mean (the
/// smallest eigenvector of the sum of their scatter matrices), `refits`
/// times, and split again.  Two layers when the distance between the sides'
/// means along the line exceeds `separation` times the larger of their
/// standard deviations about them, the line is within acos(`min_alignment`)
/// of `normal`, the sides are not side by side (`side_by_side()`), and the
/// distance exceeds `min_step` times the closest distance across the line
/// between points of different sides (`closest_across()`).
/// Deterministic; `scratch` is reused between calls.
inline Two_layer_fit fit_two_layers(const std::vector<std::array<double, 3>>& q, const std::array<double, 3>& normal,
                                    std::vector<std::pair<double, std::uint32_t>>& scratch,
                                    const Two_layer_thresholds& t = Two_layer_thresholds())
{
  Two_layer_fit out;
  const std::size_t m = q.size();
  if (m < std::max(2 * t.min_side, t.min_points) || t.min_side < 1)
    return out;
  std::array<double, 3> n = normal;
  std::size_t split = 0; // the first `split` of `scratch` (sorted) are the lower side
  auto offsets = [&]() {
    scratch.resize(m);
    for (std::size_t k = 0; k < m; ++k) {
      const double o = (q[k][0] - q[0][0]) * n[0] + (q[k][1] - q[0][1]) * n[1] + (q[k][2] - q[0][2]) * n[2];
      scratch[k] = {o, std::uint32_t(k)};
    }
  };
  auto split_offsets = [&]() {
    std::sort(scratch.begin(), scratch.end());
    double best = -1.0;
    for (std::size_t s = t.min_side; s + t.min_side <= m; ++s) {
      const double g = scratch[s].first - scratch[s - 1].first;
      if (g > best) {
        best = g;
        split = s;
      }
    }
  };
  auto side_mean = [&](std::size_t b, std::size_t e, std::array<double, 3>& c) {
    c = {0.0, 0.0, 0.0};
    for (std::size_t s = b; s < e; ++s)
      for (int d = 0; d < 3; ++d)
        c[d] += q[scratch[s].second][d];
    for (int d = 0; d < 3; ++d)
      c[d] /= double(e - b);
  };
  auto stats = [&](std::size_t b, std::size_t e, double& mean, double& sd) {
    mean = 0.0;
    for (std::size_t s = b; s < e; ++s)
      mean += scratch[s].first;
    mean /= double(e - b);
    double v = 0.0;
    for (std::size_t s = b; s < e; ++s)
      v += (scratch[s].first - mean) * (scratch[s].first - mean);
    sd = std::sqrt(v / double(e - b));
  };
  double mean_a, sd_a, mean_b, sd_b;
  for (unsigned int r = 0;; ++r) {
    offsets();
    if (r == 0) { // (the layers' distance is at most the offsets' range)
      double ss = 0.0, lo = 0.0, hi = 0.0;
      for (std::size_t k = 1; k < m; ++k) {
        for (int d = 0; d < 3; ++d)
          ss += (q[k][d] - q[0][d]) * (q[k][d] - q[0][d]);
        lo = std::min(lo, scratch[k].first);
        hi = std::max(hi, scratch[k].first);
      }
      const double min_gap = t.early_gap * std::sqrt(ss / double(m - 1));
      if (!(hi - lo > min_gap) || (t.early_detilt && !(detilted_range(q, n) > min_gap)))
        return out;
      split_offsets();
      stats(0, split, mean_a, sd_a);
      stats(split, m, mean_b, sd_b);
      if (!(mean_b - mean_a > std::max(min_gap, t.early_separation * std::max(sd_a, sd_b))))
        return out;
      if (t.early_side_by_side && side_by_side(q, scratch, split, n))
        return out;
    } else {
      split_offsets();
    }
    if (r == t.refits)
      break;
    double scatter[3][3] = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    for (int side = 0; side < 2; ++side) {
      const std::size_t b = side == 0 ? 0 : split, e = side == 0 ? split : m;
      std::array<double, 3> c;
      side_mean(b, e, c);
      for (std::size_t s = b; s < e; ++s) {
        const auto& p = q[scratch[s].second];
        const double v[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
        for (int a = 0; a < 3; ++a)
          for (int d = 0; d < 3; ++d)
            scatter[a][d] += v[a] * v[d];
      }
    }
    double values[3], vectors[3][3];
    symmetric_eigen_3(scatter, values, vectors);
    const int k = int(std::min_element(values, values + 3) - values);
    std::array<double, 3> f = {vectors[0][k], vectors[1][k], vectors[2][k]};
    if (f[0] * n[0] + f[1] * n[1] + f[2] * n[2] < 0.0)
      f = {-f[0], -f[1], -f[2]};
    n = f;
  }
  stats(0, split, mean_a, sd_a);
  stats(split, m, mean_b, sd_b);
  const double gap = mean_b - mean_a;
  const double alignment = std::abs(n[0] * normal[0] + n[1] * normal[1] + n[2] * normal[2]);
  if (!(gap > t.separation * std::max(sd_a, sd_b)) || alignment < t.min_alignment)
    return out;
  if (side_by_side(q, scratch, split, n) || !(gap > t.min_step * closest_across(q, scratch, split, n)))
    return out;
  bool own_in_a = false; // (the point's own offset is 0)
  for (std::size_t s = 0; s < split; ++s)
    own_in_a = own_in_a || scratch[s].second == 0;
  const double other = own_in_a ? mean_b : mean_a;
  out.two_layers = true;
  out.to_other = {n[0] * other, n[1] * other, n[2] * other};
  out.gap = gap;
  return out;
}

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_TWO_LAYER_FIT_H
