// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_GLOBAL_STAGE_H
#define NORMAL_ORIENTATION_STREAMING_GLOBAL_STAGE_H

/// \file Global_stage.h
/// The global sign stage of the streaming driver: the winding number of a
/// bounded subsample of the labelled records decides the signs of the final
/// segments (`decide_patch_signs()`, as in core), and the segments without
/// a sample follow the samples near their points.

#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/Winding_number_field.h>
#include <Normal_orientation/streaming/Labelled_records.h>
#include <Normal_orientation/streaming/Segmenting_sweep.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <unordered_map>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// The subsample of the global stage: every `stride`-th record with a
/// normal, its orientation after the component signs, and its segment.
template <typename Kernel>
struct Global_samples
{
  std::vector<typename Kernel::Point_3> points;
  std::vector<typename Kernel::Vector_3> normals; ///< unit, oriented
  std::vector<std::uint32_t> segment;             ///< final segment
  std::vector<std::uint32_t> component;           ///< component
};

/// One pass: the samples.
template <typename Kernel>
Global_samples<Kernel> collect_global_samples(Labelled_reader& points, const std::vector<std::uint32_t>& component,
                                              const std::vector<char>& flip_component, std::uint64_t stride)
{
  Global_samples<Kernel> out;
  points.rewind();
  std::uint64_t at = 0;
  while (points.read() > 0) {
    const std::vector<Swept_record>& buffer = points.points();
    for (std::size_t q = 0; q < buffer.size(); ++q, ++at) {
      if (at % stride != 0)
        continue;
      const Swept_record& s = buffer[q];
      const std::array<double, 3> u = unit_normal(s.record);
      if (u[0] == 0.0 && u[1] == 0.0 && u[2] == 0.0)
        continue;
      const std::uint32_t c = component[s.segment];
      const double sign = double(points.labels()[q]) * (flip_component[c] ? -1.0 : 1.0);
      out.points.emplace_back(s.record.position[0], s.record.position[1], s.record.position[2]);
      out.normals.emplace_back(sign * u[0], sign * u[1], sign * u[2]);
      out.segment.push_back(points.segments()[q]);
      out.component.push_back(c);
    }
  }
  return out;
}

/// A hash grid over the samples: the samples of the cell of a position.
class Sample_grid
{
public:
  template <typename Point>
  Sample_grid(const std::vector<Point>& points, double cell) : m_cell(cell)
  {
    for (std::size_t j = 0; j < points.size(); ++j)
      m_cells[key(points[j][0], points[j][1], points[j][2])].push_back(std::uint32_t(j));
  }
  /// the samples in the cell of (x, y, z), or null
  const std::vector<std::uint32_t>* find(double x, double y, double z) const
  {
    const auto it = m_cells.find(key(x, y, z));
    return it == m_cells.end() ? nullptr : &it->second;
  }

private:
  std::uint64_t key(double x, double y, double z) const
  {
    std::uint64_t k = 0;
    for (double v : {x, y, z})
      k = (k << 21) | (std::uint64_t(std::int64_t(std::floor(v / m_cell))) & 0x1FFFFF);
    return k;
  }
  double m_cell;
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> m_cells;
};

/// The global stage on the labelled records: negates, in `labels`, the
/// final segments whose patch the field negates.  `component` and
/// `segment_has_unary` are per sweep segment; `flip_component` is the sign
/// stage's decision.  Memory: the subsample, and O(segments).
template <typename ConcurrencyTag>
Global_sign_summary global_stage(Labelled_reader& points, Point_labels& labels,
                                 const std::vector<std::uint32_t>& component, const std::vector<char>& flip_component,
                                 const std::vector<char>& segment_has_unary, std::uint64_t n,
                                 const Progress_reporter& progress)
{
  typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
  const auto t0 = std::chrono::steady_clock::now();
  progress.report(0, 3);
  const std::uint64_t m = std::max<std::uint64_t>(1, global_samples(n));
  const std::uint64_t stride = std::max<std::uint64_t>(1, (n + m - 1) / m);
  Global_samples<Kernel> samples = collect_global_samples<Kernel>(points, component, flip_component, stride);
  progress.report(1, 3);
  Global_sign_summary report;
  if (samples.points.empty()) {
    progress.report(3, 3);
    return report;
  }

  // Patches: the final segments that hold a sample, numbered densely.
  std::unordered_map<std::uint32_t, std::uint32_t> patch_of_segment;
  std::vector<std::uint32_t> patch(samples.points.size()), patch_component, patch_segment;
  for (std::size_t j = 0; j < samples.points.size(); ++j) {
    const auto ins = patch_of_segment.emplace(samples.segment[j], std::uint32_t(patch_component.size()));
    if (ins.second) {
      patch_component.push_back(samples.component[j]);
      patch_segment.push_back(samples.segment[j]);
    }
    patch[j] = ins.first->second;
  }
  std::vector<char> fixed;
  if (!labels.label_file) { // (with unary terms there is no refinement: the final segments are the sweep's)
    fixed.assign(patch_segment.size(), 0);
    for (std::size_t P = 0; P < patch_segment.size(); ++P)
      fixed[P] = segment_has_unary[patch_segment[P]];
  }
  std::vector<double> areas = estimate_point_areas<ConcurrencyTag>(samples.points, samples.normals);
  Normal_orientation::internal::cap_areas(areas);
  std::vector<char> flip;
  report = decide_patch_signs<ConcurrencyTag>(samples.points, samples.normals, areas, patch, patch_component, fixed,
                                              flip, Global_sign_options());
  progress.report(2, 3);

  // The segments without a sample follow the samples in the cells of their
  // points whose oriented normal agrees with theirs, by majority.
  std::vector<char> segment_flip(labels.number_of_segments(), 0);
  for (std::size_t P = 0; P < flip.size(); ++P)
    segment_flip[patch_segment[P]] = flip[P];
  if (report.patches_flipped > 0) {
    const double area = std::accumulate(areas.begin(), areas.end(), 0.0);
    const Sample_grid grid(samples.points, 2.0 * std::sqrt(area / double(samples.points.size())));
    std::unordered_map<std::uint32_t, std::int64_t> votes;   // segment -> (flip votes - keep votes)
    std::unordered_map<std::uint32_t, std::uint64_t> sizes; // points of the segments that may flip
    points.rewind();
    while (points.read() > 0) {
      const std::vector<Swept_record>& buffer = points.points();
      for (std::size_t q = 0; q < buffer.size(); ++q) {
        const std::uint32_t seg = points.segments()[q];
        const auto sampled = patch_of_segment.find(seg);
        if (sampled != patch_of_segment.end()) {
          if (flip[sampled->second])
            ++sizes[seg];
          continue;
        }
        ++sizes[seg];
        const Swept_record& s = buffer[q];
        const auto* cell = grid.find(s.record.position[0], s.record.position[1], s.record.position[2]);
        if (cell == nullptr)
          continue;
        const std::array<double, 3> u = unit_normal(s.record);
        const double sign = double(points.labels()[q]) * (flip_component[component[s.segment]] ? -1.0 : 1.0);
        for (std::uint32_t j : *cell) {
          const auto& m = samples.normals[j];
          if (sign * (u[0] * m.x() + u[1] * m.y() + u[2] * m.z()) > 0.5) {
            votes[seg] += flip[patch[j]] ? 1 : -1;
            break;
          }
        }
      }
    }
    for (const auto& v : votes)
      if (v.second > 0)
        segment_flip[v.first] = 1;
    for (const auto& z : sizes)
      if (segment_flip[z.first])
        report.points_flipped += z.second;
  }
  for (std::size_t s = 0; s < segment_flip.size(); ++s)
    if (segment_flip[s])
      labels.negate_segment(s);
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.report(3, 3);
  return report;
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_GLOBAL_STAGE_H
