// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_BENCHMARK_NORMAL_SCORE_H
#define NORMAL_ORIENTATION_BENCHMARK_NORMAL_SCORE_H

/// \file Normal_score.h
/// The scoring rule of `score_normals` and `sign_floor`: a normal is wrong
/// when its dot product with the true normal is <= 0, and clear when its
/// line is within 60 degrees of the truth's (|cos| >= 0.5); zero and
/// non-finite normals are invalid, and count as wrong and clear.

#include <cmath>
#include <cstddef>

namespace Normal_orientation {
namespace benchmark {

/// The counts of one scoring.
struct Normal_score
{
  std::size_t points = 0;      ///< normals scored
  std::size_t wrong = 0;       ///< dot with the truth <= 0, or invalid
  std::size_t clear = 0;       ///< |cos| >= 0.5, or invalid
  std::size_t clear_wrong = 0; ///< wrong among the clear ones
  std::size_t invalid = 0;     ///< zero or non-finite normals

  /// Scores the normal `n` against the true normal `g` (3 coordinates each).
  void add(const double* n, const double* g)
  {
    ++points;
    const double dot = n[0] * g[0] + n[1] * g[1] + n[2] * g[2];
    const double lengths =
      std::sqrt((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) * (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]));
    if(!(std::isfinite(dot) && std::isfinite(lengths) && lengths > 0.0))
    {
      ++invalid;
      ++wrong;
      ++clear;
      ++clear_wrong;
      return;
    }
    const bool is_wrong = !(dot > 0.0);
    const bool is_clear = std::fabs(dot) >= 0.5 * lengths;
    wrong += is_wrong ? 1 : 0;
    clear += is_clear ? 1 : 0;
    clear_wrong += (is_clear && is_wrong) ? 1 : 0;
  }
};

/// Returns `100 * part / whole`, or 0 when `whole` is 0.
inline double percent(std::size_t part, std::size_t whole)
{
  return whole == 0 ? 0.0 : 100.0 * double(part) / double(whole);
}

} // namespace benchmark
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_BENCHMARK_NORMAL_SCORE_H
