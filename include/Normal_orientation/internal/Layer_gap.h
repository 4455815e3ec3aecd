// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_LAYER_GAP_H
#define NORMAL_ORIENTATION_INTERNAL_LAYER_GAP_H

/// \file Layer_gap.h
/// The rule of both drivers for the manual's *Sharp field at contacts*: per
/// point, the distance to the nearest of its own k nearest neighbours that
/// lies on another layer (another object it touches, or the other side of
/// a part thinner than the spacing), coded in 8 bits; and the caps of the
/// global stage's smoothing widths that the samples' codes give.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// A neighbour is on another layer when the edge to it is steeper than
/// this (the larger |cos| of its angles with the two normals: about 27
/// degrees out of both tangent planes) ...
constexpr double layer_gap_slope = 0.45;

/// ... and the two normal lines are within acos(this), about 26 degrees.
/// On one smooth surface an edge that steep joins normals about 53 degrees
/// apart; two objects in contact, or the sides of a thin part, are parallel.
constexpr double layer_gap_parallel = 0.9;

/// The distance from p (normal `n`) to its neighbour q (normal `m`) when q
/// is on another layer, else HUGE_VAL; also HUGE_VAL for a zero or
/// non-finite normal or a neighbour at p.  The normals may have any length;
/// the tests compare squares, so that most neighbours cost no root.
inline double layer_gap_to(const double p[3], const double n[3], const double q[3], const double m[3])
{
  const double v[3] = {q[0] - p[0], q[1] - p[1], q[2] - p[2]};
  const double len2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
  const double mm = m[0] * m[0] + m[1] * m[1] + m[2] * m[2];
  if (!(len2 > 0.0) || !(nn > 0.0) || !(mm > 0.0) || !std::isfinite(nn) || !std::isfinite(mm))
    return HUGE_VAL;
  const double vn = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
  const double vm = v[0] * m[0] + v[1] * m[1] + v[2] * m[2];
  const double s2 = layer_gap_slope * layer_gap_slope;
  if (!(vn * vn > s2 * len2 * nn) && !(vm * vm > s2 * len2 * mm)) // (not steep from either tangent plane)
    return HUGE_VAL;
  const double nm = n[0] * m[0] + n[1] * m[1] + n[2] * m[2];
  return nm * nm >= layer_gap_parallel * layer_gap_parallel * nn * mm ? std::sqrt(len2) : HUGE_VAL;
}

/// The gap `gap` (HUGE_VAL: none) in 8 bits: 0 for none, else
/// round(255 min(1, gap / radius)), at least 1.
inline std::uint8_t layer_gap_code(double gap, double radius)
{
  if (!(gap < HUGE_VAL) || !(radius > 0.0))
    return 0;
  return std::uint8_t(std::max(1.0, std::round(255.0 * std::min(1.0, gap / radius))));
}

/// The gap that `code` (`layer_gap_code()`) stands for: HUGE_VAL for 0.
inline double layer_gap_value(std::uint8_t code, double radius)
{
  return code == 0 ? HUGE_VAL : radius * double(code) / 255.0;
}

/// The caps of the smoothing widths are this times the gaps.
constexpr double contact_width_factor = 0.3;

/// ... but at least this times the spacing of the points a sample stands
/// for: narrower, the field of a sparse layer is its samples' spikes.
constexpr double contact_width_floor = 0.35;

/// No caps where more than this share of the points have a gap: noise
/// wider than the spacing, not layers, steepens those edges.
constexpr double contact_gap_share = 0.35;

/// The caps of the smoothing widths of the global stage's samples, in both
/// drivers: `contact_width_factor` times the gaps of their codes
/// (`sample_codes`; +inf without one), at least `contact_width_floor` times
/// sqrt(a_j m / n) (a sample of area a_j stands for n / m points: m samples,
/// `points` n); or none (empty) when more than `contact_gap_share` of the
/// points have a gap (`points_with_gap`) or no sample has one.
inline std::vector<double> contact_width_caps(const std::vector<std::uint8_t>& sample_codes,
                                              std::uint64_t points_with_gap, std::uint64_t points, double radius,
                                              const std::vector<double>& areas)
{
  const std::size_t m = sample_codes.size();
  if (double(points_with_gap) > contact_gap_share * double(points) || areas.size() != m ||
      std::find_if(sample_codes.begin(), sample_codes.end(), [](std::uint8_t c) { return c != 0; }) ==
        sample_codes.end())
    return std::vector<double>();
  std::vector<double> caps(m);
  for (std::size_t j = 0; j < m; ++j) {
    const double spacing = std::sqrt(std::max(0.0, areas[j]) * double(m) / double(points));
    caps[j] = std::max(contact_width_factor * layer_gap_value(sample_codes[j], radius), contact_width_floor * spacing);
  }
  return caps;
}

/// the caps of `contact_width_caps()` that cap a width (finite)
inline std::size_t sharp_samples(const std::vector<double>& caps)
{
  return std::size_t(std::count_if(caps.begin(), caps.end(), [](double c) { return c < HUGE_VAL; }));
}

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_LAYER_GAP_H
