// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_OUTPUT_STAGE_H
#define NORMAL_ORIENTATION_STREAMING_OUTPUT_STAGE_H

/// \file Output_stage.h
/// The output stage of the streaming driver: the components ranked by size
/// (the small ones dropped), and the points re-streamed from the record file
/// to the sink with their final signs.

#include <Normal_orientation/Point_record.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/streaming/Labelled_records.h>

#include <algorithm>
#include <cstdint>
#include <type_traits>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// The components kept, ranked by decreasing size (ties: by component
/// number, the sweep order of their first segment); the others dropped.
struct Component_ranking
{
  static constexpr std::uint64_t dropped = ~std::uint64_t(0);
  std::vector<std::uint64_t> rank; ///< per component; `dropped` for the dropped ones
  std::size_t kept = 0;
  std::uint64_t kept_points = 0;
  std::size_t dropped_components = 0;
  std::uint64_t dropped_points = 0;

  /// ranks the components of sizes `size`, dropping those below `minimum`
  Component_ranking(const std::vector<std::uint64_t>& size, std::uint64_t minimum) : rank(size.size(), dropped)
  {
    std::vector<std::uint32_t> order;
    for (std::size_t c = 0; c < size.size(); ++c)
      if (size[c] > 0 && size[c] >= minimum)
        order.push_back(std::uint32_t(c));
      else if (size[c] > 0) {
        ++dropped_components;
        dropped_points += size[c];
      }
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return size[a] > size[b]; });
    for (std::size_t i = 0; i < order.size(); ++i) {
      rank[order[i]] = i;
      kept_points += size[order[i]];
    }
    kept = order.size();
  }
};

/// The final state of every point: its component, its component's sign and rank.
struct Final_signs
{
  const std::vector<std::uint32_t>& component; ///< per segment
  const std::vector<char>& flip_component;     ///< per component
  const Component_ranking& ranking;
};

/// One pass over the points: `f(out, segment, flipped, rank)` for every
/// kept point with its output record, in the sweep order; `after(count)`
/// after each block of `count` points (kept or not).
template <typename F, typename After>
void for_each_kept_point(Labelled_reader& points, const Final_signs& signs, const F& f, const After& after)
{
  points.rewind();
  Point_record out;
  while (points.read() > 0) {
    const std::vector<Swept_record>& buffer = points.points();
    for (std::size_t q = 0; q < buffer.size(); ++q) {
      const Swept_record& s = buffer[q];
      const std::uint32_t c = signs.component[s.segment];
      const std::uint64_t r = signs.ranking.rank[c];
      if (r == Component_ranking::dropped)
        continue;
      const bool flipped = oriented_record(s, points.labels()[q], signs.flip_component[c] != 0, out);
      f(out, s.segment, flipped, r);
    }
    after(buffer.size());
  }
}

/// Hands `record` to `sink`, with the segment of the point and whether its
/// normal was negated when the sink takes them (see `PointRecordSink`).
template <typename Sink>
void hand_to_sink(Sink& sink, const Point_record& record, std::uint32_t segment, bool flipped)
{
  if constexpr (std::is_invocable_v<Sink&, const Point_record&, std::uint32_t, bool>)
    sink(record, segment, flipped);
  else if constexpr (std::is_invocable_v<Sink&, const Point_record&, std::uint32_t>)
    sink(record, segment);
  else
    sink(record);
}

/// Hands every kept point of the `n` to `sink`; returns the number of
/// normals turned.
template <typename Sink>
std::uint64_t output_stage(Labelled_reader& points, const Final_signs& signs, Sink& sink, std::uint64_t n,
                           const Progress_reporter& progress)
{
  std::uint64_t flipped_count = 0, read = 0;
  progress.report(0, n);
  for_each_kept_point(
    points, signs,
    [&](const Point_record& out, std::uint32_t segment, bool flipped, std::uint64_t) {
      if (flipped)
        ++flipped_count;
      hand_to_sink(sink, out, segment, flipped);
    },
    [&](std::size_t count) {
      read += count;
      progress.report(read, n);
    });
  return flipped_count;
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_OUTPUT_STAGE_H
