// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_GLOBAL_STAGE_H
#define NORMAL_ORIENTATION_STREAMING_GLOBAL_STAGE_H

/// \file Global_stage.h
/// The global sign stage of the streaming driver: the winding number of a
/// bounded subsample of the labelled records decides the signs of patches
/// (the final segments, cut by cells, as the in-core patches are), and every
/// point follows the samples near it.

#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/Winding_number_field.h>
#include <Normal_orientation/internal/Core_global_sign.h>
#include <Normal_orientation/streaming/Labelled_records.h>
#include <Normal_orientation/streaming/Segmenting_sweep.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
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

/// The decision of the global stage for every point of the stream: a
/// point takes the decision of a sample of its grid cell in its component
/// whose oriented normal agrees with its own (within 60 degrees), else the
/// majority of the samples of its final segment.
struct Global_point_flips
{
  std::shared_ptr<const Sample_grid> grid;
  std::vector<std::array<double, 3>> normal;           ///< the samples' oriented normals
  std::vector<std::uint32_t> component;                ///< the samples' components
  std::vector<char> flip;                              ///< per sample
  std::unordered_map<std::uint32_t, char> segment_flip; ///< per final segment with samples: the majority
  const std::vector<std::uint32_t>* segment_component = nullptr; ///< per sweep segment
  std::vector<char> flip_component; ///< the sign stage's, before the global stage's

  bool operator()(const Swept_record& s, std::uint32_t segment, Label label) const
  {
    const std::uint32_t c = (*segment_component)[s.segment];
    const std::array<double, 3> u = unit_normal(s.record);
    const double sign = double(label) * (flip_component[c] ? -1.0 : 1.0);
    if (const auto* cell = grid->find(s.record.position[0], s.record.position[1], s.record.position[2]))
      for (std::uint32_t j : *cell)
        if (component[j] == c && sign * (u[0] * normal[j][0] + u[1] * normal[j][1] + u[2] * normal[j][2]) > 0.5)
          return flip[j] != 0;
    const auto it = segment_flip.find(segment);
    return it != segment_flip.end() && it->second != 0;
  }
};

/// The patches of one level: the final segment of each sample, cut by
/// cells of side `cell` (0: not cut), numbered densely in sample order.
template <typename Point>
std::vector<std::uint32_t> segment_patches(const std::vector<Point>& points, const std::vector<std::uint32_t>& segment,
                                           double cell, std::vector<std::uint32_t>& first_sample)
{
  std::unordered_map<std::uint64_t, std::uint32_t> id;
  std::vector<std::uint32_t> patch(points.size());
  first_sample.clear();
  for (std::size_t j = 0; j < points.size(); ++j) {
    std::uint64_t key = segment[j];
    if (cell > 0.0)
      for (int d = 0; d < 3; ++d)
        key = (key << 10) ^ (std::uint64_t(std::int64_t(std::floor(points[j][d] / cell))) & 0x3FF);
    const auto ins = id.emplace(key, std::uint32_t(first_sample.size()));
    if (ins.second)
      first_sample.push_back(std::uint32_t(j));
    patch[j] = ins.first->second;
  }
  return patch;
}

/// The global stage on the labelled records, as in core on a subsample:
/// exterior visibility (`seen_side_flips()`) over the components and the
/// final segments, then the winding number (`Winding_patch_signs`) over
/// three levels of patches (the final segments, then the segments cut by
/// cells of 4 and 1.5 radii).  Whole components negate in
/// `flip_component` (the sign stage's decision, per component); the points
/// follow the samples for the rest (`Global_point_flips`, installed in
/// `labels`).  `component` and `segment_has_unary` are per sweep segment.
/// Memory: the subsample, and O(segments).
template <typename ConcurrencyTag>
Global_sign_summary global_stage(Labelled_reader& points, Point_labels& labels,
                                 const std::vector<std::uint32_t>& component, std::vector<char>& flip_component,
                                 const std::vector<char>& segment_has_unary, double radius, std::uint64_t n,
                                 const Normal_orientation::internal::Global_settings& settings,
                                 const Progress_reporter& progress)
{
  typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
  const auto t0 = std::chrono::steady_clock::now();
  progress.report(0, 4);
  const std::uint64_t m = std::max<std::uint64_t>(1, global_samples(n, settings.dense_samples));
  const std::uint64_t stride = std::max<std::uint64_t>(1, (n + m - 1) / m);
  Global_samples<Kernel> samples = collect_global_samples<Kernel>(points, component, flip_component, stride);
  progress.report(1, 4);
  Global_sign_summary report;
  const std::size_t ns = samples.points.size();
  if (ns == 0) {
    progress.report(4, 4);
    return report;
  }
  std::vector<double> areas = estimate_point_areas<ConcurrencyTag>(samples.points, samples.normals);
  Normal_orientation::internal::cap_areas(areas);
  // Exterior visibility first: whole components negate in flip_component,
  // segments through the samples.
  const std::size_t nc = flip_component.size();
  std::vector<char> component_fixed(nc, 0);
  if (!labels.label_file)
    for (std::size_t j = 0; j < ns; ++j)
      component_fixed[samples.component[j]] |= segment_has_unary[samples.segment[j]];
  std::vector<std::uint32_t> sheet_first;
  const std::vector<std::uint32_t> sheet = segment_patches(samples.points, samples.segment, 0.0, sheet_first);
  const Normal_orientation::internal::Seen_side_flips seen = Normal_orientation::internal::seen_side_flips<ConcurrencyTag>(
    samples.points, samples.normals, areas, samples.component, sheet, nc, sheet_first.size(), component_fixed,
    settings);
  std::vector<char> sample_flip(ns, 0);
  std::vector<Kernel::Vector_3> oriented(samples.normals);
  for (std::size_t j = 0; j < ns; ++j) {
    sample_flip[j] = seen.patch[sheet[j]];
    if (seen.component[samples.component[j]] != sample_flip[j])
      oriented[j] = -oriented[j];
  }
  Winding_patch_signs<Kernel> search;
  search.template build<ConcurrencyTag>(samples.points, oriented, areas);
  for (double cell_radii : Normal_orientation::internal::patch_cell_radii) {
    std::vector<std::uint32_t> cut_first; // (the first level is the sheets: segments do not change)
    const std::vector<std::uint32_t> patch =
      cell_radii == 0.0 ? sheet : segment_patches(samples.points, samples.segment, cell_radii * radius, cut_first);
    const std::vector<std::uint32_t>& first = cell_radii == 0.0 ? sheet_first : cut_first;
    std::vector<std::uint32_t> patch_component(first.size());
    std::vector<char> fixed(first.size(), 0);
    for (std::size_t P = 0; P < first.size(); ++P)
      patch_component[P] = samples.component[first[P]];
    if (!labels.label_file) // (with unary terms there is no refinement: the final segments are the sweep's)
      for (std::size_t j = 0; j < ns; ++j)
        fixed[patch[j]] |= segment_has_unary[samples.segment[j]];
    std::vector<char> flip;
    const Global_sign_summary level = search.template decide<ConcurrencyTag>(
      patch, patch_component, fixed, flip, Normal_orientation::internal::winding_level_options(false));
    for (std::size_t j = 0; j < ns; ++j)
      sample_flip[j] ^= flip[patch[j]];
    Normal_orientation::internal::add_level(report, level);
  }
  // The winding number's flips against both the solver and visibility, in
  // the segments they turn away from where they were seen, are undone.
  std::vector<char> by_visibility(ns), by_winding(ns);
  for (std::size_t j = 0; j < ns; ++j) {
    by_visibility[j] = seen.component[samples.component[j]] != seen.patch[sheet[j]];
    by_winding[j] = sample_flip[j] != seen.patch[sheet[j]];
  }
  const std::vector<char> veto = Normal_orientation::internal::seen_side_vetoes(
    seen.vote, areas, sheet, by_visibility, by_winding, sheet_first.size());
  for (std::size_t j = 0; j < ns; ++j)
    if (veto[sheet[j]] && Normal_orientation::internal::negated_against_both(by_visibility[j], by_winding[j]))
      sample_flip[j] = seen.patch[sheet[j]];
  for (char v : veto)
    report.seen_vetoes += v ? 1 : 0;
  // Components whose top surface faces down are negated.
  for (std::size_t j = 0; j < ns; ++j)
    oriented[j] = seen.component[samples.component[j]] != sample_flip[j] ? -samples.normals[j] : samples.normals[j];
  const std::vector<char> top = Normal_orientation::internal::top_side_flips<ConcurrencyTag>(
    samples.points, oriented, areas, samples.component, nc, component_fixed, settings);
  for (char f : top)
    report.top_components_flipped += f ? 1 : 0;
  progress.report(3, 4);
  report.points_flipped = 0; // (counted in core only)
  if (std::find(sample_flip.begin(), sample_flip.end(), 1) != sample_flip.end()) {
    auto flips = std::make_shared<Global_point_flips>();
    const double area = std::accumulate(areas.begin(), areas.end(), 0.0);
    flips->grid = std::make_shared<const Sample_grid>(samples.points, 2.0 * std::sqrt(area / double(ns)));
    std::unordered_map<std::uint32_t, std::int64_t> votes;
    for (std::size_t j = 0; j < ns; ++j) {
      const auto& v = samples.normals[j];
      flips->normal.push_back({{v.x(), v.y(), v.z()}});
      votes[samples.segment[j]] += sample_flip[j] ? 1 : -1;
    }
    for (const auto& v : votes)
      flips->segment_flip.emplace(v.first, char(v.second > 0));
    flips->component = std::move(samples.component);
    flips->flip = std::move(sample_flip);
    flips->segment_component = &component;
    flips->flip_component = flip_component;
    labels.point_flip = [flips](const Swept_record& s, std::uint32_t segment, Label label) {
      return (*flips)(s, segment, label);
    };
  }
  for (std::size_t c = 0; c < nc; ++c)
    flip_component[c] ^= char(seen.component[c] != top[c]);
  report.visibility = settings.orientation == Normal_orientation::Global_orientation::VISIBILITY_AND_WINDING;
  report.seen_components_flipped = seen.components_flipped;
  report.seen_patches_flipped = seen.patches_flipped;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.report(4, 4);
  return report;
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_GLOBAL_STAGE_H
