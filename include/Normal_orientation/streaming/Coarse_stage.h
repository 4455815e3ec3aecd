// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_COARSE_STAGE_H
#define NORMAL_ORIENTATION_STREAMING_COARSE_STAGE_H

/// \file Coarse_stage.h
/// The streaming driver of the coarse-to-fine pass (`internal/Coarse_scale.h`),
/// after the global stage: one more pass over the labelled records feeds the
/// accumulator, whose grid holds at most `coarse_maximum_cells` cells; the
/// coarse cloud is oriented in core by the caller, and the points take its
/// signs in the output passes (through `Point_labels::point_flip`).

#include <Normal_orientation/internal/Coarse_scale.h>
#include <Normal_orientation/internal/Settings.h>
#include <Normal_orientation/streaming/Labelled_records.h>
#include <Normal_orientation/streaming/Segmenting_sweep.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// Runs the coarse-to-fine pass over `points`, whose orientation has the
/// closedness `fine_closedness`.  `orient(const Coarse_scale&)` must orient
/// its coarse cloud with the in-core pipeline and return the oriented normals
/// and the closedness of the result, as a pair.  When the coarse signs are
/// used, they are installed in `labels` before the global stage's decision,
/// which is kept for the points without a coarse opinion.  `component` is
/// per sweep segment, `flip_component` the sign stage's decision; both must
/// outlive the output passes.
template <typename Orient>
Normal_orientation::internal::Coarse_scale_report
coarse_stage(Labelled_reader& points, Point_labels& labels, const std::vector<std::uint32_t>& component,
             const std::vector<char>& flip_component, double radius, std::uint64_t n, double fine_closedness,
             const Orient& orient)
{
  using Normal_orientation::internal::Coarse_scale;
  const auto t = std::chrono::steady_clock::now();
  auto coarse = std::make_shared<Coarse_scale>(radius);
  points.rewind();
  for (std::size_t got = points.read(); got > 0; got = points.read())
    for (const Swept_record& s : points.points()) {
      const Point_record& r = s.record;
      coarse->add({{r.position[0], r.position[1], r.position[2]}}, unit_normal(r));
    }
  points.rewind();
  if (coarse->decide(std::size_t(n))) {
    const std::pair<std::vector<std::array<double, 3>>, double> oriented = orient(*coarse);
    if (coarse->use_coarse_orientation(oriented.first, oriented.second, fine_closedness)) {
      auto previous = std::move(labels.point_flip);
      const std::vector<std::uint32_t>* segment_component = &component;
      const std::vector<char>* flips = &flip_component;
      labels.point_flip = [coarse, previous, segment_component, flips](const Swept_record& s, std::uint32_t segment,
                                                                       Label label) {
        const Point_record& r = s.record;
        const signed char c = coarse->sign({{r.position[0], r.position[1], r.position[2]}}, unit_normal(r));
        if (c == 0)
          return previous ? previous(s, segment, label) : false;
        const int sign = (*flips)[(*segment_component)[s.segment]] ? -1 : 1;
        return int(label) * sign != int(c); // the output label is label * sign, negated when true
      };
    }
  }
  coarse->report().seconds = Normal_orientation::internal::seconds_since(t);
  return coarse->report();
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_COARSE_STAGE_H
