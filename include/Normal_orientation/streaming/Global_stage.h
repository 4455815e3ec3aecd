// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_GLOBAL_STAGE_H
#define NORMAL_ORIENTATION_STREAMING_GLOBAL_STAGE_H

/// \file Global_stage.h
/// The global sign stage of the streaming driver: exterior visibility and
/// the winding number of a bounded subsample of the labelled records decide
/// the signs of patches (unions of `Patch_units`, as the in-core patches are
/// unions of points), and every point follows its unit.

#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/Winding_number_field.h>
#include <Normal_orientation/internal/Canopy_rule.h>
#include <Normal_orientation/internal/Core_global_sign.h>
#include <Normal_orientation/internal/Layer_gap.h>
#include <Normal_orientation/internal/Parallel.h>
#include <Normal_orientation/streaming/Labelled_records.h>
#include <Normal_orientation/streaming/Patch_units.h>
#include <Normal_orientation/streaming/Segmenting_sweep.h>
#include <Normal_orientation/streaming/Stream_layer_cues.h>
#include <Normal_orientation/streaming/Unit_islands.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <numeric>
#include <string>
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
  std::vector<std::uint32_t> unit;                ///< patch unit (with `Patch_units`)
  std::vector<char> two_layers;                   ///< on two layers (`Swept_record::layer` not 0)
  std::vector<std::uint16_t> layer;               ///< `Swept_record::layer` (`layer_code()`)
  std::vector<std::uint8_t> gap;                  ///< `Swept_record::gap` (`layer_gap_code()`)
  std::vector<signed char> sign;                  ///< the oriented normal over the input normal, +1 or -1
  std::vector<std::uint32_t> sweep_segment;       ///< the sweep's segment (`Swept_record::segment`)
  std::vector<signed char> sweep_flip;            ///< the sweep's flip in it (`Swept_record::flip`)
};

/// What the global stage needs to build its patches from units
/// (`Patch_units`): the sweep's edge file and span, and the directory of the
/// unit file.  Without an edge file (no refinement), the patches are the
/// final segments, cut by cells.
struct Unit_inputs
{
  Record_file<Earlier_edge>* edges = nullptr;
  std::uint64_t span = 0;
  std::string temporary_directory;
};

/// One read of the labelled points (`Labelled_reader::read()`), copied, with
/// their signs and unit normals and, for the units, their earlier edges
/// measured (`Unit_measure`): the first half of the pass of
/// `collect_global_samples()`.
struct Unit_block
{
  std::vector<Swept_record> records;
  std::vector<std::uint32_t> segments;
  std::vector<double> sign;             ///< the oriented normal over the input normal
  std::vector<std::array<double, 3>> u; ///< the unit input normal
  std::vector<std::size_t> first_edge;  ///< the edges of point q: [first_edge[q], first_edge[q + 1])
  std::vector<Earlier_edge> edges;
  std::vector<Measured_edge> measured_edges;
  std::vector<Measured_point> measured;

  /// Reads the next points of `points` into this block; with `measure`,
  /// also their edges from `edge_reader`, measured.  Returns how many (0 at
  /// the end).
  std::size_t read(Labelled_reader& points, const std::vector<std::uint32_t>& component,
                   const std::vector<char>& flip_component, Edge_reader* edge_reader, Unit_measure* measure)
  {
    const std::size_t got = points.read();
    records.assign(points.points().begin(), points.points().end());
    segments.assign(points.segments().begin(), points.segments().end());
    sign.resize(got);
    u.resize(got);
    first_edge.assign(1, 0);
    edges.clear();
    measured.resize(measure ? got : 0);
    for (std::size_t q = 0; q < got; ++q) {
      sign[q] = double(points.labels()[q]) * (flip_component[component[records[q].segment]] ? -1.0 : 1.0);
      u[q] = unit_normal(records[q].record);
      if (measure) {
        const Earlier_edge* point_edges = nullptr;
        std::size_t count = 0;
        edge_reader->next(point_edges, count);
        edges.insert(edges.end(), point_edges, point_edges + count);
      }
      first_edge.push_back(edges.size());
    }
    measured_edges.resize(edges.size());
    for (std::size_t q = 0; q < got && measure; ++q) {
      const double* x = records[q].record.position;
      measured[q] = measure->measure(
        Patch_units::Kernel::Point_3(x[0], x[1], x[2]),
        Patch_units::Kernel::Vector_3(sign[q] * u[q][0], sign[q] * u[q][1], sign[q] * u[q][2]),
        edges.data() + first_edge[q], first_edge[q + 1] - first_edge[q], measured_edges.data() + first_edge[q]);
    }
    return got;
  }
};

/// One pass: the samples.  With `units`, the same pass pushes every point
/// into `units`, with its earlier edges from `edges`, and appends its unit
/// to `unit_file`.  The next block is read and measured (`Unit_block`)
/// while the units take the last one, at the same time with
/// `CGAL::Parallel_tag`: the units are those of pushing the points one by
/// one.
template <typename ConcurrencyTag, typename Kernel>
Global_samples<Kernel> collect_global_samples(Labelled_reader& points, const std::vector<std::uint32_t>& component,
                                              const std::vector<char>& flip_component, std::uint64_t stride,
                                              Patch_units* units = nullptr, Record_file<Earlier_edge>* edges = nullptr,
                                              Record_file<std::uint32_t>* unit_file = nullptr)
{
  Global_samples<Kernel> out;
  points.rewind();
  std::unique_ptr<Edge_reader> edge_reader;
  std::unique_ptr<Unit_measure> measure;
  if (units) {
    edge_reader = std::make_unique<Edge_reader>(*edges, false);
    measure = std::make_unique<Unit_measure>(units->span(), units->cell_side());
  }
  std::uint64_t at = 0;
  auto take = [&](const Unit_block& block) {
    for (std::size_t q = 0; q < block.records.size(); ++q, ++at) {
      const Swept_record& s = block.records[q];
      const std::uint32_t c = component[s.segment];
      const double sign = block.sign[q];
      const std::array<double, 3>& u = block.u[q];
      std::uint32_t unit = 0;
      if (units && !units->overflowed()) { // (after an overflow, the units and their file are dropped)
        const std::size_t e = block.first_edge[q];
        unit = units->push(block.measured[q], block.measured_edges.data() + e, block.segments[q], c,
                           block.edges.data() + e, block.first_edge[q + 1] - e, sign < 0.0 ? -1 : 1);
        unit_file->append(unit);
      }
      if (at % stride != 0 || (u[0] == 0.0 && u[1] == 0.0 && u[2] == 0.0))
        continue;
      out.points.emplace_back(s.record.position[0], s.record.position[1], s.record.position[2]);
      out.normals.emplace_back(sign * u[0], sign * u[1], sign * u[2]);
      out.segment.push_back(block.segments[q]);
      out.component.push_back(c);
      out.unit.push_back(unit);
      out.two_layers.push_back(char(s.layer != 0));
      out.layer.push_back(s.layer);
      out.gap.push_back(s.gap);
      out.sign.push_back(sign < 0.0 ? -1 : 1);
      out.sweep_segment.push_back(s.segment);
      out.sweep_flip.push_back(s.flip < 0 ? -1 : 1);
    }
  };
  Unit_block block[2];
  int current = 0;
  std::size_t got = block[0].read(points, component, flip_component, edge_reader.get(), measure.get());
  while (got > 0) {
    std::size_t next = 0;
    Normal_orientation::internal::parallel_pair<ConcurrencyTag>(
      [&]() { next = block[1 - current].read(points, component, flip_component, edge_reader.get(), measure.get()); },
      [&]() { take(block[current]); });
    current = 1 - current;
    got = next;
  }
  if (unit_file)
    unit_file->flush();
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

/// The side of the cells of `Patch_units`: 0.7 neighbour radii, times
/// sqrt(stride / 4) where the samples are sparser than one in four points,
/// so that the units stay about as many as the samples.
inline double unit_cell(double radius, std::uint64_t stride)
{
  return 0.7 * radius * std::max(1.0, std::sqrt(double(stride) / 4.0));
}

/// Installs `Global_point_flips` in `labels`: every point follows the
/// samples near it (`sample_flip`, per sample).
template <typename Kernel>
void install_sample_flips(Global_samples<Kernel>& samples, const std::vector<double>& areas,
                          std::vector<char>& sample_flip, const std::vector<std::uint32_t>& component,
                          const std::vector<char>& flip_component, Point_labels& labels)
{
  const std::size_t ns = samples.points.size();
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

/// The visibility decisions of the streamed global stage, per sample and,
/// with units, per unit: whether the point is negated after the component's
/// decision (its sheet's, then its final segment's).
struct Stream_seen_sides
{
  Normal_orientation::internal::Seen_side_flips seen; ///< components and sheets
  std::vector<std::uint32_t> sheet;                  ///< per sample
  std::size_t number_of_sheets = 0;
  std::vector<char> sample;                          ///< per sample
  std::vector<char> unit;                            ///< per unit
  std::vector<std::uint32_t> unit_sheet;             ///< per unit
};

/// Exterior visibility over the samples: components, then sheets (with
/// `units`, the unit patches of slope at most `sheet_slope`, as in core;
/// else the final segments), then, with units, the final segments that
/// still face away from where they were seen both with the views weighted
/// by the up direction and with every view weighing 1 (`segment_tier_flips()`).
template <typename ConcurrencyTag, typename Kernel>
Stream_seen_sides stream_seen_sides(const Global_samples<Kernel>& samples, const std::vector<double>& areas,
                                    const std::vector<std::uint32_t>& segment_patch, std::size_t number_of_segments,
                                    std::size_t number_of_components, const std::vector<char>& component_fixed,
                                    const Patch_units* units,
                                    const Normal_orientation::internal::Global_settings& settings)
{
  Stream_seen_sides out;
  const std::size_t ns = samples.points.size();
  if (units) {
    out.unit_sheet = units->patches(std::vector<char>(units->number_of_units(), 0),
                                    Normal_orientation::internal::sheet_slope, 0);
    for (std::uint32_t id : out.unit_sheet) // (every unit's, sampled or not)
      out.number_of_sheets = std::max<std::size_t>(out.number_of_sheets, std::size_t(id) + 1);
    for (std::size_t j = 0; j < ns; ++j)
      out.sheet.push_back(out.unit_sheet[samples.unit[j]]);
  } else {
    out.sheet = segment_patch;
    out.number_of_sheets = number_of_segments;
  }
  out.seen = Normal_orientation::internal::seen_side_flips<ConcurrencyTag>(
    samples.points, samples.normals, areas, samples.component, out.sheet, number_of_components,
    out.number_of_sheets, component_fixed, settings, {}, samples.two_layers);
  std::vector<char> segment_flip(number_of_segments, 0);
  if (units && settings.orientation == Normal_orientation::Global_orientation::VISIBILITY_AND_WINDING) {
    segment_flip = Normal_orientation::internal::segment_tier_flips(
      areas, samples.component, out.sheet, segment_patch, number_of_segments, out.seen, component_fixed, settings);
    for (char f : segment_flip)
      out.seen.patches_flipped += f ? 1 : 0;
  }
  out.sample.resize(ns);
  for (std::size_t j = 0; j < ns; ++j)
    out.sample[j] = char(out.seen.patch[out.sheet[j]] ^ segment_flip[segment_patch[j]]);
  if (units) {
    std::unordered_map<std::uint32_t, char> by_segment; // final segment -> its flip, where it has samples
    for (std::size_t j = 0; j < ns; ++j)
      by_segment[samples.segment[j]] = segment_flip[segment_patch[j]];
    out.unit.resize(units->number_of_units());
    for (std::size_t u = 0; u < out.unit.size(); ++u) {
      const auto it = by_segment.find(units->unit_segment()[u]);
      out.unit[u] = char(out.seen.patch[out.unit_sheet[u]] ^ (it != by_segment.end() ? it->second : 0));
    }
  }
  return out;
}

/// The winding number's three levels over the samples, from the negations
/// `sample_flip` (per sample, after visibility), and with units
/// `unit_flip` (per unit), which it updates: with units, the unit patches of
/// the current signs (`Patch_units::patches()`, anywhere, then within coarse
/// cells, then within cells); else the final segments, then the segments
/// cut by cells of `patch_cell_radii` radii.
template <typename ConcurrencyTag, typename Kernel>
void stream_winding_levels(const Global_samples<Kernel>& samples, Winding_patch_signs<Kernel>& search,
                           const Patch_units* units, const std::vector<std::uint32_t>& segment_patch,
                           const std::vector<std::uint32_t>& segment_first, double radius,
                           const std::vector<char>& has_unary,
                           std::vector<char>& sample_flip, std::vector<char>& unit_flip, Global_sign_summary& report)
{
  const std::size_t ns = samples.points.size();
  const double slope = units ? units->patch_slope() : 0.0;
  int level = 0;
  for (double cell_radii : Normal_orientation::internal::patch_cell_radii) {
    std::vector<std::uint32_t> first, of_unit;
    std::vector<std::uint32_t> patch;
    if (units) {
      of_unit = units->patches(unit_flip, slope, level);
      std::vector<std::uint32_t> ids(ns);
      for (std::size_t j = 0; j < ns; ++j)
        ids[j] = of_unit[samples.unit[j]];
      patch = segment_patches(samples.points, ids, 0.0, first);
    } else if (cell_radii == 0.0) {
      patch = segment_patch;
      first = segment_first;
    } else {
      patch = segment_patches(samples.points, samples.segment, cell_radii * radius, first);
    }
    std::vector<std::uint32_t> patch_component(first.size());
    std::vector<char> fixed(first.size(), 0);
    for (std::size_t P = 0; P < first.size(); ++P)
      patch_component[P] = samples.component[first[P]];
    for (std::size_t j = 0; j < ns && !has_unary.empty(); ++j)
      fixed[patch[j]] |= has_unary[samples.segment[j]];
    std::vector<char> flip;
    const Global_sign_summary decided = search.template decide<ConcurrencyTag>(
      patch, patch_component, fixed, flip, Normal_orientation::internal::winding_level_options(units && level == 0));
    for (std::size_t j = 0; j < ns; ++j)
      sample_flip[j] ^= flip[patch[j]];
    if (units) {
      const std::uint32_t unset = ~std::uint32_t(0);
      std::vector<std::uint32_t> sampled(units->number_of_units(), unset); // unit patch -> its patch, if sampled
      for (std::size_t j = 0; j < ns; ++j)
        sampled[of_unit[samples.unit[j]]] = patch[j];
      for (std::size_t u = 0; u < unit_flip.size(); ++u)
        if (sampled[of_unit[u]] != unset && flip[sampled[of_unit[u]]])
          unit_flip[u] ^= 1;
    }
    Normal_orientation::internal::add_level(report, decided);
    ++level;
  }
}

/// The global stage on the labelled records, as in core on a subsample:
/// exterior visibility (`stream_seen_sides()`), then the winding number
/// (`Winding_patch_signs`) over three levels of patches
/// (`stream_winding_levels()`), then the seen-side vetoes, the islands
/// (with units, `negate_unit_islands()`) and the top surface.  With
/// `unit_inputs.edges`, the patches are unions of units
/// (`Patch_units`), built in the pass that takes the samples, and every
/// point follows its unit (a unit file installed in `labels`); else the
/// points follow the samples (`Global_point_flips`).  Whole components
/// negate in `flip_component` (the sign stage's decision, per component).
/// `component` and `segment_has_unary` are per sweep segment.  With
/// `cues`, the layer cues of the final signs go there
/// (`stream_layer_cues()`), each as strong as `cue_strength` per point that
/// its sample stands for.  With `fixed_by_cues` (the layer cues' round), the
/// components that `segment_has_unary` fixes are the cues', which the top
/// surface's rule (`top_side_flips()`) does not leave out, as in core.
/// With `open_scenes`, the components where the canopy rule applies
/// (`open_scene_components()`) go there.
/// The field's smoothing widths are capped at the
/// samples' layer gaps (`contact_width_caps()`, with `layer_gap_points` of
/// the `n` points having one).  Memory: the subsample, the units and
/// O(segments).
template <typename ConcurrencyTag>
Global_sign_summary global_stage(Labelled_reader& points, Point_labels& labels,
                                 const std::vector<std::uint32_t>& component, std::vector<char>& flip_component,
                                 const std::vector<char>& segment_has_unary, double radius, std::uint64_t n,
                                 std::uint64_t layer_gap_points,
                                 const Normal_orientation::internal::Global_settings& settings,
                                 const Progress_reporter& progress, const Unit_inputs& unit_inputs = Unit_inputs(),
                                 Stream_layer_cues* cues = nullptr, double cue_strength = 0.0,
                                 bool fixed_by_cues = false, std::vector<char>* open_scenes = nullptr)
{
  typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
  const auto t0 = std::chrono::steady_clock::now();
  progress.report(0, 4);
  const std::uint64_t m = std::max<std::uint64_t>(1, global_samples(n, settings.dense_samples));
  const std::uint64_t stride = std::max<std::uint64_t>(1, (n + m - 1) / m);
  std::unique_ptr<Patch_units> units;
  std::unique_ptr<Record_file<std::uint32_t>> unit_file;
  if (unit_inputs.edges) {
    units = std::make_unique<Patch_units>(unit_inputs.span, unit_cell(radius, stride));
    unit_file = std::make_unique<Record_file<std::uint32_t>>(unit_inputs.temporary_directory, 1 << 16);
  }
  Global_samples<Kernel> samples = collect_global_samples<ConcurrencyTag, Kernel>(
    points, component, flip_component, stride, units.get(), unit_inputs.edges, unit_file.get());
  if (units && units->overflowed()) { // (noise: segments of a few points) as without an edge file
    units.reset();
    unit_file.reset();
  }
  progress.report(1, 4);
  Global_sign_summary report;
  const std::size_t ns = samples.points.size();
  if (ns == 0) {
    progress.report(4, 4);
    return report;
  }
  std::vector<double> areas = estimate_point_areas<ConcurrencyTag>(samples.points, samples.normals);
  Normal_orientation::internal::cap_areas(areas);
  const std::vector<double> width_caps =
    Normal_orientation::internal::contact_width_caps(samples.gap, layer_gap_points, n, radius, areas);
  // Exterior visibility first: whole components negate in flip_component,
  // sheets and segments through the samples and the units.
  const std::size_t nc = flip_component.size();
  std::vector<char> component_fixed(nc, 0);
  const std::vector<char> no_unary;
  const std::vector<char>& has_unary = labels.label_file ? no_unary : segment_has_unary; // (with unary terms there is no refinement: the final segments are the sweep's)
  for (std::size_t j = 0; j < ns && !has_unary.empty(); ++j)
    component_fixed[samples.component[j]] |= has_unary[samples.segment[j]];
  std::vector<std::uint32_t> segment_first;
  const std::vector<std::uint32_t> segment_patch = segment_patches(samples.points, samples.segment, 0.0, segment_first);
  const Stream_seen_sides seen = stream_seen_sides<ConcurrencyTag>(
    samples, areas, segment_patch, segment_first.size(), nc, component_fixed, units.get(), settings);
  std::vector<char> sample_flip(seen.sample), unit_flip(seen.unit);
  std::vector<Kernel::Vector_3> oriented(samples.normals);
  for (std::size_t j = 0; j < ns; ++j)
    if (seen.seen.component[samples.component[j]] != sample_flip[j])
      oriented[j] = -oriented[j];
  Winding_patch_signs<Kernel> search;
  search.template build<ConcurrencyTag>(samples.points, oriented, areas, width_caps);
  stream_winding_levels<ConcurrencyTag>(samples, search, units.get(), segment_patch, segment_first, radius,
                                        has_unary, sample_flip, unit_flip, report);
  // The winding number's flips against both the solver and visibility, in
  // the sheets they turn away from where they were seen, are undone.
  std::vector<char> by_visibility(ns), by_winding(ns);
  for (std::size_t j = 0; j < ns; ++j) {
    by_visibility[j] = seen.seen.component[samples.component[j]] != seen.sample[j];
    by_winding[j] = sample_flip[j] != seen.sample[j];
  }
  const std::vector<char> veto = Normal_orientation::internal::seen_side_vetoes(
    seen.seen.vote, areas, seen.sheet, by_visibility, by_winding, seen.number_of_sheets);
  std::vector<std::uint32_t> vetoed; // (samples)
  for (std::size_t j = 0; j < ns; ++j)
    if (veto[seen.sheet[j]] && Normal_orientation::internal::negated_against_both(by_visibility[j], by_winding[j])) {
      vetoed.push_back(std::uint32_t(j));
      sample_flip[j] = seen.sample[j];
    }
  for (std::size_t u = 0; u < unit_flip.size(); ++u) {
    const char visible = seen.seen.component[units->unit_component()[u]] != seen.unit[u];
    if (veto[seen.unit_sheet[u]] &&
        Normal_orientation::internal::negated_against_both(visible, char(unit_flip[u] != seen.unit[u])))
      unit_flip[u] = seen.unit[u];
  }
  for (char v : veto)
    report.seen_vetoes += v ? 1 : 0;
  // Islands left against their surroundings, where the field agrees (on
  // the units; without them, none).
  if (units) {
    if (!vetoed.empty())
      search.template negate_samples<ConcurrencyTag>(vetoed);
    std::vector<char> negated(unit_flip.size()), sample_negated(ns);
    for (std::size_t u = 0; u < negated.size(); ++u)
      negated[u] = char(seen.seen.component[units->unit_component()[u]] != unit_flip[u]);
    for (std::size_t j = 0; j < ns; ++j)
      sample_negated[j] = char(seen.seen.component[samples.component[j]] != sample_flip[j]);
    report.islands_flipped = negate_unit_islands<ConcurrencyTag, Kernel>(*units, n, samples.unit, search, negated,
                                                                         sample_negated);
    for (std::size_t u = 0; u < negated.size(); ++u)
      unit_flip[u] = char(seen.seen.component[units->unit_component()[u]] != negated[u]);
    for (std::size_t j = 0; j < ns; ++j)
      sample_flip[j] = char(seen.seen.component[samples.component[j]] != sample_negated[j]);
  }
  // Components whose top surface faces down are negated.
  for (std::size_t j = 0; j < ns; ++j)
    oriented[j] = seen.seen.component[samples.component[j]] != sample_flip[j] ? -samples.normals[j] : samples.normals[j];
  // (the user's unary terms hold against it, the layer cues' do not: as in core)
  const std::vector<char> top = Normal_orientation::internal::top_side_flips<ConcurrencyTag>(
    samples.points, oriented, areas, samples.component, nc, fixed_by_cues ? std::vector<char>() : component_fixed,
    settings);
  for (char f : top)
    report.top_components_flipped += f ? 1 : 0;
  if (open_scenes) // (for the canopy rule: Canopy_rule.h)
    *open_scenes = Normal_orientation::internal::open_scene_components(
      search.values(), areas, samples.component, nc, top, fixed_by_cues ? std::vector<char>() : component_fixed,
      settings);
  if (cues) {
    std::vector<char> final_flip(ns);
    for (std::size_t j = 0; j < ns; ++j)
      final_flip[j] = char((seen.seen.component[samples.component[j]] != sample_flip[j]) != (top[samples.component[j]] != 0));
    *cues = stream_layer_cues<ConcurrencyTag, Kernel>(samples, final_flip, areas, radius, component.size(), nc,
                                                      double(stride) * cue_strength);
  }
  progress.report(3, 4);
  report.points_flipped = 0; // (counted in core only)
  if (units) {
    labels.unit_file = std::move(unit_file);
    labels.unit_flip = std::move(unit_flip);
  } else if (std::find(sample_flip.begin(), sample_flip.end(), 1) != sample_flip.end()) {
    install_sample_flips(samples, areas, sample_flip, component, flip_component, labels);
  }
  for (std::size_t c = 0; c < nc; ++c)
    flip_component[c] ^= char(seen.seen.component[c] != top[c]);
  report.visibility = settings.orientation == Normal_orientation::Global_orientation::VISIBILITY_AND_WINDING;
  report.seen_components_flipped = seen.seen.components_flipped;
  report.seen_patches_flipped = seen.seen.patches_flipped;
  report.sharp_samples = Normal_orientation::internal::sharp_samples(width_caps);
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.report(4, 4);
  return report;
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_GLOBAL_STAGE_H
