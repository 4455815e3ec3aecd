// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_CORE_LAYER_CUES_H
#define NORMAL_ORIENTATION_INTERNAL_CORE_LAYER_CUES_H

/// \file Core_layer_cues.h
/// The layer cues (`Layer_cues.h`) on the in-core arrays, at the end of the
/// global stage: the pairs from the neighbour graph's incidence lists, the
/// far field from the stage's samples with their final signs, and the cues
/// as unary terms for one more solve.

#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Winding_number_field.h>
#include <Normal_orientation/internal/Graph_reduction.h>
#include <Normal_orientation/internal/Layer_cues.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// What the layer cues saw, and their unary terms.
struct Layer_cue_report
{
  std::size_t pairs = 0;     ///< points whose neighbourhood is two layers
  std::size_t sure = 0;      ///< of them, with a sure cue
  std::size_t against = 0;   ///< of them, whose label the cue negates
  /// per point, the cue's label times the total weight of the point's edges
  /// (a cue outweighs its point's edges), 0 without a sure cue; empty when
  /// no point has one
  std::vector<double> unary;
};

/// The points of the in-core cloud whose neighbourhoods (over the incidence
/// lists `inc` of the neighbour graph) are two layers, each with the total
/// weight of its edges as its strength (a cue outweighs its point's edges).
template <typename ConcurrencyTag, typename Point, typename Vector>
Layer_pairs core_layer_pairs(const Incidence& inc, const std::vector<Point>& points,
                             const std::vector<Vector>& normals)
{
  Layer_pairs pairs = find_layer_pairs<ConcurrencyTag>(points, normals, [&](std::size_t i, auto&& f) {
    for (std::uint32_t t = inc.first[i]; t < inc.first[i + 1]; ++t)
      f(std::size_t(inc.other[t]));
  });
  pairs.strength.assign(pairs.size(), 0.0);
  for (std::size_t t = 0; t < pairs.size(); ++t) {
    const std::size_t i = pairs.point[t];
    for (std::uint32_t e = inc.first[i]; e < inc.first[i + 1]; ++e)
      pairs.strength[t] += std::abs(double(inc.weight[e]));
    pairs.strength[t] = std::max(pairs.strength[t], 1e-3);
  }
  return pairs;
}

/// The layer cues of `pairs` (`core_layer_pairs()`) in the labelled in-core
/// cloud, with the far field over `samples` (with `points`, `oriented` and
/// `areas` members: a subsample oriented by `labels`).
template <typename ConcurrencyTag, typename Kernel, typename Samples>
Layer_cue_report core_layer_cues(const Layer_pairs& pairs, const std::vector<typename Kernel::Point_3>& points,
                                 const std::vector<typename Kernel::Vector_3>& normals,
                                 const std::vector<Label>& labels, const Samples& samples)
{
  Layer_cue_report report;
  report.pairs = pairs.size();
  if (pairs.size() > 0 && !samples.points.empty()) {
    Winding_number_field<Kernel> field;
    field.template build<ConcurrencyTag>(samples.points, samples.oriented, samples.areas);
    const double spacing = std::sqrt(median(samples.areas));
    const std::vector<Label> cue = layer_cues<ConcurrencyTag, Kernel>(normals, pairs, points, field, spacing);
    for (std::size_t t = 0; t < pairs.size(); ++t) {
      if (cue[t] == 0)
        continue;
      const std::size_t i = pairs.point[t];
      if (report.unary.empty())
        report.unary.assign(points.size(), 0.0);
      report.unary[i] = double(cue[t]) * pairs.strength[t];
      ++report.sure;
      if (cue[t] != labels[i])
        ++report.against;
    }
  }
  return report;
}

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_CORE_LAYER_CUES_H
