// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_CORE_LAYER_CUES_H
#define NORMAL_ORIENTATION_INTERNAL_CORE_LAYER_CUES_H

/// \file Core_layer_cues.h
/// The layer cues (`Layer_cues.h`) on the in-core arrays, at the end of the
/// global stage: the pairs from the layer offsets of the graph, the
/// far field from the stage's samples with their final signs, and the cues
/// as unary terms for one more solve.

#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Winding_number_field.h>
#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/internal/Layer_edges.h>
#include <Normal_orientation/internal/Layer_cues.h>

#include <boost/range/iterator_range.hpp>

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
  std::size_t sure = 0;      ///< of them, with a sure cue
  std::size_t against = 0;   ///< of them, whose label the cue negates
  /// per point, the cue's label times the total weight of the point's edges
  /// (a cue outweighs its point's edges), 0 without a sure cue; empty when
  /// no point has one
  std::vector<double> unary;
};

/// The points of the in-core cloud whose neighbourhoods are two layers,
/// from their layer offsets (per point, `build_neighbor_graph()`), each with
/// the total absolute weight of its edges in `graph` as its strength (a cue
/// outweighs its point's edges).
template <typename WeightMap>
Layer_pairs core_layer_pairs(const std::vector<Layer_offset>& offsets, const Neighbor_graph& graph,
                             const WeightMap& weight)
{
  Layer_pairs pairs;
  std::vector<std::uint32_t> at(offsets.size(), ~std::uint32_t(0)); // point -> its pair
  for (std::size_t i = 0; i < offsets.size(); ++i)
    if (is_two_layers(offsets[i])) {
      const Layer_offset& t = offsets[i];
      at[i] = std::uint32_t(pairs.point.size());
      pairs.point.push_back(std::uint32_t(i));
      pairs.to_other.push_back({{double(t[0]), double(t[1]), double(t[2])}});
      pairs.gap.push_back(std::sqrt(double(t[0]) * t[0] + double(t[1]) * t[1] + double(t[2]) * t[2]));
    }
  pairs.strength.assign(pairs.size(), 0.0);
  if (pairs.size() > 0)
    for (const auto e : boost::make_iterator_range(edges(graph))) {
      const double w = std::abs(double(get(weight, e)));
      for (const std::uint32_t v : {std::uint32_t(source(e, graph)), std::uint32_t(target(e, graph))})
        if (at[v] != ~std::uint32_t(0))
          pairs.strength[at[v]] += w;
    }
  for (double& s : pairs.strength)
    s = std::max(s, 1e-3);
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
