// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_CORE_GLOBAL_SIGN_H
#define NORMAL_ORIENTATION_INTERNAL_CORE_GLOBAL_SIGN_H

/// \file Core_global_sign.h
/// The global sign stage of `orient_normals()`: patches from the neighbour
/// graph and the labels, a bounded subsample with areas, and
/// `decide_patch_signs()`.

#include <Normal_orientation/Exterior_visibility.h>
#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Signed_union_find.h>
#include <Normal_orientation/Winding_number_field.h>
#include <Normal_orientation/internal/Canopy_rule.h>
#include <Normal_orientation/internal/Core_layer_cues.h>
#include <Normal_orientation/internal/Frustrated_islands.h>
#include <Normal_orientation/internal/Graph_reduction.h>
#include <Normal_orientation/internal/Layer_gap.h>
#include <Normal_orientation/internal/Parallel.h>
#include <Normal_orientation/internal/Seen_side_rules.h>
#include <Normal_orientation/internal/Undone_moves.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// The levels of patches, coarse to fine, as the side of their cells in
/// neighbour radii (0: no cells).  A patch never spans two cells, so that
/// one wrong joint ties two objects together over at most one cell; the
/// coarse levels move whole sheets at once.
constexpr double patch_cell_radii[] = {0.0, 4.0, 1.5};

/// The slope of the edge (i, j) against the normals `mi`, `mj` of its ends:
/// the larger |cos| of its angles with them (0: it lies in both tangent
/// planes), or 1 when the edge or a normal is zero.
template <typename Point, typename Vector>
double edge_slope(const Point& pi, const Point& pj, const Vector& mi, const Vector& mj)
{
  const double d[3] = {CGAL::to_double(pj.x() - pi.x()), CGAL::to_double(pj.y() - pi.y()),
                       CGAL::to_double(pj.z() - pi.z())};
  const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  const double a[3] = {CGAL::to_double(mi.x()), CGAL::to_double(mi.y()), CGAL::to_double(mi.z())};
  const double b[3] = {CGAL::to_double(mj.x()), CGAL::to_double(mj.y()), CGAL::to_double(mj.z())};
  const double la = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  const double lb = std::sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
  if (!(len > 0.0) || !(la > 0.0) || !(lb > 0.0))
    return 1.0;
  const double da = std::abs(d[0] * a[0] + d[1] * a[1] + d[2] * a[2]) / (len * la);
  const double db = std::abs(d[0] * b[0] + d[1] * b[1] + d[2] * b[2]) / (len * lb);
  return std::min(1.0, std::max(da, db));
}

/// The settings of the winding number's search on one level of patches: a
/// patch of `whole_sheets` (no cells: in core, the first level) is negated
/// from half the default `Global_sign_options::minimum_decrease` per unit of
/// its area, since its decrease is averaged over a whole sheet; patches cut
/// by cells, or by the streamed segments, can be a few samples, whose
/// changes of w noise and sampling make larger.
inline Global_sign_options winding_level_options(bool whole_sheets)
{
  Global_sign_options o;
  if (whole_sheets)
    o.minimum_decrease = 0.5 * o.minimum_decrease;
  return o;
}

/// The largest edge slope (`edge_slopes()`) of the sheets of exterior
/// visibility and of the seen-side vetoes: 30 degrees from both tangent planes.
constexpr double sheet_slope = 0.5;

/// The smallest edge slope of the winding number's patches (`patch_slope()`):
/// about 8.6 degrees from both tangent planes.
constexpr double patch_slope_floor = 0.15;

/// Calls `f(j, e)` for every out-edge (i, j) of `graph`, e its rank in the
/// order of `edges(graph)` (that of the sources' out-edges).
template <typename Function>
void for_each_out_edge(const Neighbor_graph& graph, std::size_t i, const Function& f)
{
  typename boost::graph_traits<Neighbor_graph>::out_edge_iterator it, end;
  for (boost::tie(it, end) = out_edges(std::uint32_t(i), graph); it != end; ++it)
    f(std::size_t(target(*it, graph)), std::size_t(get(boost::edge_index, graph, *it)));
}

/// Calls `f(i, j, e)` for every edge (i, j) of `graph`, e its rank in the
/// order of `edges(graph)`, in parallel over the sources: `f` may write to
/// slot e of a per-edge array.
template <typename ConcurrencyTag, typename Function>
void for_each_edge_in_parallel(const Neighbor_graph& graph, const Function& f)
{
  parallel_chunks<ConcurrencyTag>(std::size_t(num_vertices(graph)), [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i)
      for_each_out_edge(graph, i, [&](std::size_t j, std::size_t edge) { f(i, j, edge); });
  });
}

/// `edge_slope()` of every edge of `graph`, in the order of `edges(graph)`,
/// with the unoriented normals.
template <typename Kernel, typename ConcurrencyTag = CGAL::Parallel_if_available_tag>
std::vector<float> edge_slopes(const Neighbor_graph& graph, const std::vector<typename Kernel::Point_3>& points,
                               const std::vector<typename Kernel::Vector_3>& normals)
{
  std::vector<float> slope(num_edges(graph));
  for_each_edge_in_parallel<ConcurrencyTag>(graph, [&](std::size_t i, std::size_t j, std::size_t e) {
    slope[e] = float(edge_slope(points[i], points[j], normals[i], normals[j]));
  });
  return slope;
}

/// `median` within [`patch_slope_floor`, `sheet_slope`]: the largest edge
/// slope of the winding number's patches, in core (`patch_slope()`) and
/// streamed (`streaming::internal::Patch_units::patch_slope()`).
inline double clamp_patch_slope(double median)
{
  return std::min(sheet_slope, std::max(patch_slope_floor, median));
}

/// The largest edge slope of the winding number's patches: the median of
/// `slopes` (every 16th of them), within [`patch_slope_floor`,
/// `sheet_slope`].  On a clean cloud the patches end where the surface bends
/// by more than about 8.6 degrees over one edge (thin parts, contacts
/// between objects, features that the spacing under-samples); noise steepens
/// every edge, and the median keeps at least half of them.
inline double patch_slope(const std::vector<float>& slopes)
{
  std::vector<float> some;
  for (std::size_t e = 0; e < slopes.size(); e += 16)
    some.push_back(slopes[e]);
  if (some.empty())
    return sheet_slope;
  std::nth_element(some.begin(), some.begin() + std::ptrdiff_t(some.size() / 2), some.end());
  return clamp_patch_slope(double(some[some.size() / 2]));
}

/// Whether an edge joins two points of one smooth sheet that the solver
/// oriented consistently: the oriented normals of its ends agree within 60
/// degrees (`product`, their scalar product, is at least 1/2) and its slope
/// (`edge_slopes()`) is at most `max_slope`.
inline bool same_sheet(double product, float slope, double max_slope)
{
  return double(slope) <= max_slope && product >= 0.5;
}

/// Unites the ends of every edge `e` of `graph` with `joins[e]` in `uf`
/// (singletons on entry).  The points are cut into blocks of `block`
/// consecutive indices: the edges inside one block are united in parallel
/// over the blocks (each block's trees hold only its own points), then the
/// edges between blocks sequentially.  The sets are those of uniting every
/// edge in order, for any number of threads; only their roots may differ.
template <typename ConcurrencyTag>
void unite_joined_edges(const Neighbor_graph& graph, const std::vector<unsigned char>& joins,
                        Signed_union_find& uf, std::size_t block = std::size_t(1) << 16)
{
  typedef Signed_union_find::Index Index;
  const std::size_t n = std::size_t(num_vertices(graph)), blocks = (n + block - 1) / block;
  std::vector<std::vector<std::pair<Index, Index>>> across(blocks);
  parallel_chunks<ConcurrencyTag>(blocks, [&](std::size_t bb, std::size_t be) {
    for (std::size_t b = bb; b < be; ++b)
      for (std::size_t i = b * block; i < std::min(n, (b + 1) * block); ++i)
        for_each_out_edge(graph, i, [&](std::size_t j, std::size_t e) {
          if (!joins[e])
            return;
          if (j / block == b)
            uf.unite(Index(i), Index(j));
          else
            across[b].emplace_back(Index(i), Index(j));
        });
  }, 1);
  for (const auto& pairs : across)
    for (const auto& ij : pairs)
      uf.unite(ij.first, ij.second);
}

/// Patches of the labelled cloud, numbered 0, 1, ... by their first point:
/// the points joined by `same_sheet` edges (`slopes` from `edge_slopes()`,
/// at most `max_slope`) within one cell of side `cell` (0: anywhere) whose
/// ends the solver either both negated or both kept against its start
/// (`moved`, per point; empty: no start); then patches without a sample join
/// a neighbouring patch through an edge whose oriented normals agree.
/// Returns the patch of every point (zero normals get a patch of their own).
/// The tests of the edges run in parallel, the unions mostly so
/// (`unite_joined_edges()`): the patches are the same for any number of
/// threads.
template <typename Kernel, typename ConcurrencyTag = CGAL::Parallel_if_available_tag>
std::vector<std::uint32_t> build_patches(const Neighbor_graph& graph,
                                         const std::vector<typename Kernel::Point_3>& points,
                                         const std::vector<typename Kernel::Vector_3>& normals,
                                         const std::vector<Label>& labels, const std::vector<char>& moved,
                                         double cell, const std::vector<float>& slopes, double max_slope,
                                         const std::vector<char>& is_sample, std::size_t& number_of_patches)
{
  typedef Signed_union_find::Index Index;
  const std::size_t n = points.size();
  double lo[3] = {0, 0, 0};
  for (int c = 0; c < 3 && n > 0; ++c) {
    lo[c] = CGAL::to_double(points[0][c]);
    for (const auto& p : points)
      lo[c] = std::min(lo[c], CGAL::to_double(p[c]));
  }
  std::vector<std::uint64_t> cells(n, 0);
  if (cell > 0.0)
    parallel_chunks<ConcurrencyTag>(n, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i)
        for (int c = 0; c < 3; ++c)
          cells[i] = (cells[i] << 21) | (std::uint64_t((CGAL::to_double(points[i][c]) - lo[c]) / cell) & 0x1FFFFF);
    });
  // (the product of the oriented normals, exactly: negation is exact)
  auto oriented_product = [&](std::size_t i, std::size_t j) {
    const double d = CGAL::to_double(normals[i] * normals[j]);
    return labels[i] == labels[j] ? d : -d;
  };
  auto same_move = [&](std::size_t i, std::size_t j) { return moved.empty() || moved[i] == moved[j]; };
  // Per edge (in the order of edges(graph), which is that of the sources'
  // out-edges): 1 when it joins its ends into one patch (`same_sheet()`).
  std::vector<unsigned char> joins(num_edges(graph), 0);
  for_each_edge_in_parallel<ConcurrencyTag>(graph, [&](std::size_t i, std::size_t j, std::size_t e) {
    joins[e] = cells[i] == cells[j] && same_move(i, j) && same_sheet(oriented_product(i, j), slopes[e], max_slope);
  });
  Signed_union_find uf(n);
  unite_joined_edges<ConcurrencyTag>(graph, joins, uf);
  // Patches without a sample join a sampled neighbour (a few sweeps reach
  // patches two or three steps away), through the edges between two patches
  // whose oriented normals agree (no other edge can ever join two).
  std::vector<Index> root(n);
  std::vector<char> sampled(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    root[i] = uf.find(Index(i));
    if (is_sample[i])
      sampled[root[i]] = 1;
  }
  for_each_edge_in_parallel<ConcurrencyTag>(graph, [&](std::size_t i, std::size_t j, std::size_t e) {
    joins[e] = root[i] != root[j] && oriented_product(i, j) > 0.0;
  });
  std::vector<std::pair<Index, Index>> between;
  typename boost::graph_traits<Neighbor_graph>::edge_iterator it, end;
  std::size_t e = 0;
  for (boost::tie(it, end) = edges(graph); it != end; ++it, ++e)
    if (joins[e])
      between.emplace_back(Index(source(*it, graph)), Index(target(*it, graph)));
  for (int sweep = 0; sweep < 4; ++sweep) {
    bool changed = false;
    for (const auto& ij : between) {
      const Index ri = uf.find(ij.first), rj = uf.find(ij.second);
      if (ri == rj || sampled[ri] == sampled[rj])
        continue;
      uf.unite(ri, rj);
      sampled[uf.find(ri)] = 1;
      changed = true;
    }
    if (!changed)
      break;
  }
  const std::uint32_t unset = ~std::uint32_t(0);
  std::vector<std::uint32_t> id(n, unset), patch(n);
  number_of_patches = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto r = uf.find(Index(i));
    if (id[r] == unset)
      id[r] = std::uint32_t(number_of_patches++);
    patch[i] = id[r];
  }
  return patch;
}

/// Per point, whether the solver negated it against its start (`start`,
/// per point; empty when the solver had none, and so is the result).
inline std::vector<char> solver_moves(const std::vector<Label>& labels, const std::vector<Label>& start)
{
  std::vector<char> moved;
  if (start.size() == labels.size()) {
    moved.resize(labels.size());
    for (std::size_t i = 0; i < labels.size(); ++i)
      moved[i] = labels[i] != start[i];
  }
  return moved;
}

/// Adds the figures of one level of patches to `total`.
inline void add_level(Global_sign_summary& total, const Global_sign_summary& level)
{
  if (!total.ran)
    total.energy_before = level.energy_before;
  total.ran = true;
  total.number_of_samples = level.number_of_samples;
  total.number_of_patches = level.number_of_patches; // the finest level's
  total.patches_flipped += level.patches_flipped;
  total.rounds += level.rounds;
  total.closed_components = level.closed_components;
  total.open_components = level.open_components;
  total.closedness = level.closedness;
  total.energy_after = level.energy_after;
}

/// The samples of the in-core global stage: every stride-th point of the
/// Morton order with a normal (an even subsample), oriented by `labels`.
template <typename Kernel>
struct Core_samples
{
  std::vector<std::uint32_t> index;                ///< the points sampled
  std::vector<char> is_sample;                     ///< per point
  std::vector<typename Kernel::Point_3> points;    ///< their positions
  std::vector<typename Kernel::Vector_3> oriented; ///< their normals, oriented
  std::vector<double> areas;                       ///< their capped areas
  std::vector<double> width_caps;                  ///< the caps of their smoothing widths (empty: none)
  std::vector<std::uint32_t> component;            ///< their components
};

/// The samples of `points` (`global_samples()`, `dense` as there), with
/// their areas (`estimate_point_areas()`, capped by `cap_areas()`).
template <typename ConcurrencyTag, typename Kernel>
Core_samples<Kernel> core_samples(const std::vector<typename Kernel::Point_3>& points,
                                  const std::vector<typename Kernel::Vector_3>& normals,
                                  const std::vector<std::uint32_t>& component, const std::vector<Label>& labels,
                                  bool dense)
{
  Core_samples<Kernel> s;
  const std::size_t n = points.size();
  const std::size_t m = std::max<std::size_t>(1, std::size_t(global_samples(n, dense)));
  const std::size_t stride = std::max<std::size_t>(1, (n + m - 1) / m);
  s.is_sample.assign(n, 0);
  for (std::size_t i = 0; i < n; i += stride)
    if (normals[i] != CGAL::NULL_VECTOR) {
      s.is_sample[i] = 1;
      s.index.push_back(std::uint32_t(i));
      s.points.push_back(points[i]);
      s.oriented.push_back(normals[i]);
      s.component.push_back(component[i]);
    }
  s.areas = estimate_point_areas<ConcurrencyTag>(s.points, s.oriented);
  cap_areas(s.areas);
  for (std::size_t t = 0; t < s.index.size(); ++t)
    if (labels[s.index[t]] < 0)
      s.oriented[t] = -s.oriented[t];
  return s;
}

/// The winding number's levels of patches (`patch_cell_radii`, edges of
/// slope at most `patch_slope()` of `slopes`) on the in-core arrays: flips
/// `labels` and adds the figures to `report`.  `sheets` (`number_of_sheets`
/// of them, of slope at most `sheet_slope`) are the first level's patches
/// when `labels` has not changed since they were built and the slopes agree,
/// else empty; `moved` is that of `build_patches()`.  `search` is built
/// here, on `samples`, and keeps the signs chosen.
template <typename ConcurrencyTag, typename Kernel>
void core_winding_levels(const Neighbor_graph& graph, const std::vector<typename Kernel::Point_3>& points,
                         const std::vector<typename Kernel::Vector_3>& normals, const std::vector<float>& slopes,
                         const std::vector<std::uint32_t>& component, double radius,
                         const std::vector<char>& has_unary, const std::vector<char>& moved,
                         const Core_samples<Kernel>& samples,
                         const std::vector<std::uint32_t>& sheets, std::size_t number_of_sheets,
                         std::vector<Label>& labels, Global_sign_summary& report,
                         Winding_patch_signs<Kernel>& search)
{
  const std::size_t n = points.size();
  search.template build<ConcurrencyTag>(samples.points, samples.oriented, samples.areas, samples.width_caps);
  const double slope = patch_slope(slopes);
  for (double cell_radii : patch_cell_radii) {
    const bool reuse = cell_radii == 0.0 && !sheets.empty() && slope == sheet_slope;
    std::size_t np = reuse ? number_of_sheets : 0;
    const std::vector<std::uint32_t> patch =
      reuse ? sheets
            : build_patches<Kernel, ConcurrencyTag>(graph, points, normals, labels, moved, cell_radii * radius,
                                                    slopes, slope, samples.is_sample, np);
    std::vector<std::uint32_t> spatch;
    for (std::uint32_t i : samples.index)
      spatch.push_back(patch[i]);
    std::vector<std::uint32_t> patch_component(np, 0);
    std::vector<char> fixed(np, 0);
    for (std::size_t i = 0; i < n; ++i) {
      patch_component[patch[i]] = component[i];
      if (!has_unary.empty() && has_unary[i])
        fixed[patch[i]] = 1;
    }
    std::vector<char> flip;
    const Global_sign_summary level = search.template decide<ConcurrencyTag>(spatch, patch_component, fixed, flip,
                                                                             winding_level_options(cell_radii == 0.0));
    for (std::size_t i = 0; i < n; ++i)
      if (flip[patch[i]])
        labels[i] = Label(-labels[i]);
    add_level(report, level);
  }
}

/// Adds to `report` what exterior visibility did (`seen`, its vetoes
/// `veto`), the points whose labels differ between `before` and `labels`,
/// and the samples whose width is capped (`width_caps`).
inline void add_stage_figures(Global_sign_summary& report, const Seen_side_flips& seen, const std::vector<char>& veto,
                              const std::vector<Label>& before, const std::vector<Label>& labels,
                              const std::vector<double>& width_caps)
{
  report.seen_components_flipped = seen.components_flipped;
  report.seen_patches_flipped = seen.patches_flipped;
  report.seen_vetoes = std::size_t(std::count(veto.begin(), veto.end(), char(1)));
  report.points_flipped = 0;
  for (std::size_t i = 0; i < labels.size(); ++i)
    report.points_flipped += before[i] != labels[i] ? 1 : 0;
  report.sharp_samples = sharp_samples(width_caps);
}

/// What exterior visibility decided in the in-core global stage.
struct Core_seen_sides
{
  Seen_side_flips seen;                    ///< components and sheets (and the segments' count)
  std::vector<std::uint32_t> sheet;        ///< per point: its sheet
  std::size_t number_of_sheets = 0;
  std::vector<std::uint32_t> sample_sheet; ///< per sample: its sheet
};

/// Step 1 of `core_global_signs()`: exterior visibility negates the
/// components (those of `component_fixed` and `whole_fixed` left out), then
/// the sheets (patches of slope at most `sheet_slope`), then the
/// labelling's segments (`segment_tier_flips()`), that face away from the
/// side they were seen from, in `labels` and `samples.oriented`.  The
/// points of `cued` (per point, or empty) keep the signs of their sheets
/// and segments; the samples on the layers of `pairs` do not vote.
template <typename ConcurrencyTag, typename Kernel>
Core_seen_sides core_seen_sides(const Neighbor_graph& graph, const Incidence& inc,
                                const std::vector<typename Kernel::Point_3>& points,
                                const std::vector<typename Kernel::Vector_3>& normals,
                                const std::vector<float>& slopes, const std::vector<char>& moved,
                                const std::vector<std::uint32_t>& component, const std::vector<char>& cued,
                                const std::vector<char>& component_fixed, const std::vector<char>& whole_fixed,
                                std::size_t nc,
                                const Global_settings& settings, const Layer_pairs* pairs,
                                Core_samples<Kernel>& samples, std::vector<Label>& labels)
{
  Core_seen_sides out;
  const std::size_t n = points.size(), ns = samples.index.size();
  out.sheet = build_patches<Kernel, ConcurrencyTag>(graph, points, normals, labels, moved, 0.0, slopes, sheet_slope,
                                                    samples.is_sample, out.number_of_sheets);
  out.sample_sheet.resize(ns);
  for (std::size_t t = 0; t < ns; ++t)
    out.sample_sheet[t] = out.sheet[samples.index[t]];
  std::vector<char> sample_two_layers; // (per sample)
  if (pairs && pairs->size() > 0) {
    sample_two_layers.resize(ns);
    for (std::size_t t = 0; t < ns; ++t)
      sample_two_layers[t] = char(std::binary_search(pairs->point.begin(), pairs->point.end(), samples.index[t]));
  }
  Seen_side_flips& seen = out.seen;
  seen = seen_side_flips<ConcurrencyTag>(samples.points, samples.oriented, samples.areas, samples.component,
                                         out.sample_sheet, nc, out.number_of_sheets, component_fixed, settings,
                                         whole_fixed, sample_two_layers);
  std::vector<std::uint32_t> segment, sample_segment(ns);
  std::vector<char> segment_flip;
  if (settings.orientation == Global_orientation::VISIBILITY_AND_WINDING) {
    const std::size_t number_of_segments = labelling_segments(inc, labels, segment);
    for (std::size_t t = 0; t < ns; ++t)
      sample_segment[t] = segment[samples.index[t]];
    segment_flip = segment_tier_flips(samples.areas, samples.component, out.sample_sheet, sample_segment,
                                      number_of_segments, seen, component_fixed, settings);
    for (char f : segment_flip)
      seen.patches_flipped += f ? 1 : 0;
  }
  for (std::size_t i = 0; i < cued.size(); ++i)
    if (cued[i]) {
      seen.patch[out.sheet[i]] = 0;
      if (!segment_flip.empty())
        segment_flip[segment[i]] = 0;
    }
  auto seen_flip = [&](std::uint32_t c, std::uint32_t sheet_id, std::uint32_t segment_id) {
    return (seen.component[c] != seen.patch[sheet_id]) != (!segment_flip.empty() && segment_flip[segment_id]);
  };
  for (std::size_t i = 0; i < n; ++i)
    if (seen_flip(component[i], out.sheet[i], segment.empty() ? 0 : segment[i]))
      labels[i] = Label(-labels[i]);
  for (std::size_t t = 0; t < ns; ++t)
    if (seen_flip(samples.component[t], out.sample_sheet[t], sample_segment[t]))
      samples.oriented[t] = -samples.oriented[t];
  return out;
}

/// Step 3 of `core_global_signs()`: the winding number's flips against both
/// the solver and visibility (`seen_side_vetoes()`: the labels went from
/// `before` to `seen_labels` by visibility, then to `labels`) are undone in
/// `labels` in the sheets of `sides` that they turn away from where they were
/// seen.  Returns the vetoes per sheet; `vetoed` gets the samples undone
/// (indices into `sample_index`, the samples' points).
inline std::vector<char> core_seen_side_vetoes(const Core_seen_sides& sides,
                                               const std::vector<std::uint32_t>& sample_index,
                                               const std::vector<double>& areas, const std::vector<Label>& before,
                                               const std::vector<Label>& seen_labels, std::vector<Label>& labels,
                                               std::vector<std::uint32_t>& vetoed)
{
  const std::size_t ns = sample_index.size();
  auto by_visibility = [&](std::size_t i) { return char(seen_labels[i] != before[i]); };
  auto by_winding = [&](std::size_t i) { return char(labels[i] != seen_labels[i]); };
  std::vector<char> sample_by_visibility(ns), sample_by_winding(ns);
  for (std::size_t t = 0; t < ns; ++t) {
    sample_by_visibility[t] = by_visibility(sample_index[t]);
    sample_by_winding[t] = by_winding(sample_index[t]);
  }
  const std::vector<char> veto = seen_side_vetoes(sides.seen.vote, areas, sides.sample_sheet, sample_by_visibility,
                                                  sample_by_winding, sides.number_of_sheets);
  vetoed.clear();
  for (std::size_t t = 0; t < ns; ++t) {
    const std::size_t i = sample_index[t];
    if (veto[sides.sheet[i]] && negated_against_both(by_visibility(i), by_winding(i)))
      vetoed.push_back(std::uint32_t(t));
  }
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (veto[sides.sheet[i]] && negated_against_both(by_visibility(i), by_winding(i)))
      labels[i] = seen_labels[i];
  return veto;
}

/// The global stage on the in-core arrays (points in Morton order), on a
/// subsample: exterior visibility negates the components, then the sheets
/// (the patches of the first level), that face away from where they were
/// seen; the winding number then negates patches, level by level, and its
/// flips against both the solver and visibility are undone in the sheets
/// they turn away from where they were seen (`seen_side_vetoes()`); then
/// the islands left against their borders (`negate_frustrated_islands()`)
/// and the rest of the solver's moves that the stage undid for the most
/// part (`complete_undone_moves()`) are negated.
/// Components with a point of `has_unary` keep their signs.  With
/// `cues`, the layer cues of `pairs` (`core_layer_cues()`) after the
/// stage's signs go to `cues`.  The layer cues' points (`cued`, per point, or empty) keep the signs of their
/// sheets, segments and patches against their component, and the
/// components with a point of `cue_fixed` (per point, or empty) keep theirs
/// as a whole (`cue_components()`); no patch joins
/// points that the solver negated against its start with points that it
/// kept (`moved`, per point; empty: no start).  With `open_scenes`, the
/// components where the canopy rule applies (`open_scene_components()`) go
/// there.  With `restart`, the solver's moves that the stage negated in
/// full go there (`rejected_moves()`, before the top surface's rule), for
/// the caller to sign and stage the solver's labels again without them.
template <typename ConcurrencyTag, typename Kernel>
Global_sign_summary core_global_signs(const Neighbor_graph& graph, const std::vector<typename Kernel::Point_3>& points,
                                      const std::vector<typename Kernel::Vector_3>& normals,
                                      const std::vector<std::uint32_t>& component, double radius,
                                      const std::vector<char>& has_unary, const std::vector<char>& cued,
                                      const std::vector<char>& cue_fixed, const std::vector<char>& moved,
                                      const Global_settings& settings,
                                      std::vector<Label>& labels, const Layer_pairs* pairs = nullptr,
                                      Layer_cue_report* cues = nullptr,
                                      const std::vector<std::uint8_t>* layer_gaps = nullptr,
                                      std::vector<char>* open_scenes = nullptr, Stage_restart* restart = nullptr)
{
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t n = points.size();
  const std::vector<Label> labels_before = labels;
  Core_samples<Kernel> samples =
    core_samples<ConcurrencyTag, Kernel>(points, normals, component, labels, settings.dense_samples);
  const std::size_t ns = samples.index.size();
  if (layer_gaps != nullptr && layer_gaps->size() == n) {
    std::vector<std::uint8_t> codes(ns);
    for (std::size_t t = 0; t < ns; ++t)
      codes[t] = (*layer_gaps)[samples.index[t]];
    const std::size_t with_gap = n - std::size_t(std::count(layer_gaps->begin(), layer_gaps->end(), std::uint8_t(0)));
    samples.width_caps = contact_width_caps(codes, with_gap, n, radius, samples.areas);
  }
  std::size_t nc = 0;
  for (std::uint32_t c : component)
    nc = std::max<std::size_t>(nc, std::size_t(c) + 1);
  std::vector<char> component_fixed(nc, 0);
  for (std::size_t i = 0; i < has_unary.size(); ++i)
    if (has_unary[i])
      component_fixed[component[i]] = 1;
  std::vector<char> whole_fixed(nc, 0); // (components fixed as a whole: their sheets are free)
  for (std::size_t i = 0; i < cue_fixed.size(); ++i)
    if (cue_fixed[i])
      whole_fixed[component[i]] = 1;
  const std::vector<float> slopes = edge_slopes<Kernel, ConcurrencyTag>(graph, points, normals);
  // 1. Exterior visibility.
  const Incidence inc(graph, get(&Neighbor_edge::weight, graph), "the global stage"); // (segments, islands)
  const Core_seen_sides seen_sides = core_seen_sides<ConcurrencyTag, Kernel>(
    graph, inc, points, normals, slopes, moved, component, cued, component_fixed, whole_fixed, nc, settings, pairs,
    samples, labels);
  const Seen_side_flips& seen = seen_sides.seen;
  const std::vector<std::uint32_t>& sheet = seen_sides.sheet;
  const std::size_t number_of_sheets = seen_sides.number_of_sheets;
  const std::vector<Label> seen_labels = labels;
  // 2. The winding number.
  Global_sign_summary report;
  // (visibility flipped nothing: the sheets are the winding number's first level)
  const bool unchanged = seen.components_flipped == 0 && seen.patches_flipped == 0;
  std::vector<char> keep = has_unary; // (the patches that keep their signs)
  if (!cued.empty()) {
    keep.resize(n, 0);
    for (std::size_t i = 0; i < n; ++i)
      keep[i] = char(keep[i] || cued[i]);
  }
  Winding_patch_signs<Kernel> search;
  core_winding_levels<ConcurrencyTag, Kernel>(graph, points, normals, slopes, component, radius, keep,
                                              moved, samples, unchanged ? sheet : std::vector<std::uint32_t>(),
                                              number_of_sheets, labels, report, search);
  // 3. Its flips against both the solver and visibility, in the sheets they
  // turn away from where they were seen, are undone.
  std::vector<std::uint32_t> vetoed; // (samples)
  const std::vector<char> veto =
    core_seen_side_vetoes(seen_sides, samples.index, samples.areas, labels_before, seen_labels, labels, vetoed);
  // 4. Islands left against their surroundings, where the field agrees.
  if (!vetoed.empty())
    search.template negate_samples<ConcurrencyTag>(vetoed);
  report.islands_flipped = negate_frustrated_islands<ConcurrencyTag, Kernel>(inc, samples.index, keep, search, labels);
  // 5. The solver's moves that the stage undid for the most part are undone in full.
  report.moves_completed = complete_undone_moves(inc, moved, keep, labels_before, labels);
  if (restart)
    restart->rejected = rejected_moves(inc, moved, keep, labels_before, labels, restart->moved);
  // 6. Components whose top surface faces down are negated.
  for (std::size_t t = 0; t < ns; ++t)
    samples.oriented[t] = labels[samples.index[t]] < 0 ? -normals[samples.index[t]] : normals[samples.index[t]];
  // (the user's unary terms hold against it; the layer cues' do not: on a
  // closed surface the top faces up, and on an open scene the cues' far field
  // does not tell the sides apart)
  const std::vector<char> top = top_side_flips<ConcurrencyTag>(samples.points, samples.oriented, samples.areas,
                                                               samples.component, nc, component_fixed, settings);
  for (std::size_t i = 0; i < n; ++i)
    if (top[component[i]])
      labels[i] = Label(-labels[i]);
  for (char f : top)
    report.top_components_flipped += f ? 1 : 0;
  if (open_scenes) // (for the canopy rule, after the stage: Canopy_rule.h)
    *open_scenes = open_scene_components(search.values(), samples.areas, samples.component, nc, top,
                                         component_fixed, settings);
  // 7. The layer cues of the final signs.
  if (cues && pairs) {
    for (std::size_t t = 0; t < ns; ++t)
      if (top[samples.component[t]])
        samples.oriented[t] = -samples.oriented[t];
    *cues = core_layer_cues<ConcurrencyTag, Kernel>(*pairs, points, normals, labels, samples);
  }
  report.visibility = settings.orientation == Global_orientation::VISIBILITY_AND_WINDING;
  add_stage_figures(report, seen, veto, labels_before, labels, samples.width_caps);
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_CORE_GLOBAL_SIGN_H
