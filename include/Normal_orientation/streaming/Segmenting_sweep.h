// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_SEGMENTING_SWEEP_H
#define NORMAL_ORIENTATION_STREAMING_SEGMENTING_SWEEP_H

/// \file Segmenting_sweep.h
/// The sweep stage of the streaming driver: the sweep's visitor that
/// weighs each point's earlier edges with the flip criterion, segments the
/// point (`Segmenter`), and writes it to the record file (and its edges to
/// the edge file of the refinement) when it leaves the window.

#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Point_record.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/Segmenter.h>
#include <Normal_orientation/internal/Layer_edges.h>
#include <Normal_orientation/internal/Layer_gap.h>
#include <Normal_orientation/internal/Parallel.h>
#include <Normal_orientation/internal/Unit_vector.h>
#include <Normal_orientation/streaming/Record_file.h>
#include <Normal_orientation/streaming/Refinement.h>
#include <Normal_orientation/streaming/Sweep.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// a point after the sweep: the record, its segment, its preliminary flip
/// and, when its neighbourhood is two layers (`build_neighbor_graph()`),
/// where the other layer lies (`layer_code()`; 0: one layer)
struct Swept_record
{
  Point_record record;
  std::uint32_t segment;
  std::int8_t flip;
  std::uint8_t gap;    ///< `layer_gap_code()`: 0 without a neighbour on another layer
  std::uint16_t layer; ///< `layer_code()`: 0 on one layer
};

/// The layer offset `t` of a point of unit normal `u` (zero: one layer),
/// coded in 16 bits for `Swept_record::layer`: 0 on one layer; else bit
/// 15 set when the other layer lies along u, and bits 0-14 the gap |t| in
/// units of `radius` / 32767 (at least 1).  `layer_code_offset()` reads it
/// back along u: the fit's line is within a few degrees of the normal line.
inline std::uint16_t layer_code(const Normal_orientation::internal::Layer_offset& t, const std::array<double, 3>& u,
                                double radius)
{
  if (!Normal_orientation::internal::is_two_layers(t))
    return 0;
  const double g = std::sqrt(double(t[0]) * t[0] + double(t[1]) * t[1] + double(t[2]) * t[2]);
  const double along = double(t[0]) * u[0] + double(t[1]) * u[1] + double(t[2]) * u[2];
  const double units = std::round(std::min(1.0, g / radius) * 32767.0);
  return std::uint16_t(std::max(1.0, units)) | std::uint16_t(along > 0.0 ? 0x8000u : 0u);
}

/// The offset to the other layer that `code` (`layer_code()`, not 0) gives
/// a point of unit normal `u`.
inline std::array<double, 3> layer_code_offset(std::uint16_t code, const std::array<double, 3>& u, double radius)
{
  const double g = double(code & 0x7fffu) / 32767.0 * radius * ((code & 0x8000u) != 0 ? 1.0 : -1.0);
  return {{g * u[0], g * u[1], g * u[2]}};
}

/// what the sweep keeps per point in its window
struct Sweep_payload
{
  std::uint32_t segment = 0;
  Label flip = 1;
  unsigned char layer_state = 0; ///< how `layer` was found (`Layer_fit_state`)
  Normal_orientation::internal::Layer_offset layer{}; ///< the layer offset (`build_neighbor_graph()`)
  std::uint8_t gap = 0; ///< the layer gap's code (`build_neighbor_graph()`)
};

/// unit normal of a record (zero when the normal is zero)
inline std::array<double, 3> unit_normal(const Point_record& r)
{
  return Normal_orientation::internal::unit_vector(r.normal[0], r.normal[1], r.normal[2]);
}

/// What the sweep stage leaves: the segmentation, per segment its size and
/// whether a point of it has a unary term, and the figures of the sweep.
struct Sweep_stage_result
{
  std::vector<std::uint64_t> segment_size;
  std::vector<char> segment_has_unary;
  std::uint64_t edge_span = 0;       ///< the farthest back an edge reaches
  std::uint64_t unary_terms = 0;     ///< points with a unary term
  double energy_before = 0.0;        ///< the energy of the input orientation, summed in the sweep order
  double total_weight = 0.0;         ///< the sum of the edges' absolute weights, in the sweep order
  std::uint64_t two_layer_points = 0; ///< points on two layers (`build_neighbor_graph()`)
  std::uint64_t layer_gap_points = 0; ///< points with a layer gap (`build_neighbor_graph()`)
  /// the first point in Morton order (ties by input index), where the
  /// in-core driver, which works in that order, starts the coarse grid; set
  /// up over the points' box (`Scan_result::box`) before the sweep
  Normal_orientation::internal::Morton_first grid_origin;
};

/// The visitor of `sweep()` for the streaming driver.  `Unary` is callable
/// as `double(const Point_record&)`: the point's preference for its input
/// sign (> 0 keep, < 0 flip, 0 none; see `orient_normals()`).  Without
/// `layer_edges`, no layer offset is fitted and no edge is negated.
template <typename ConcurrencyTag, typename Kernel, typename FlipCriterion, typename Unary>
class Segmenting_visitor
{
  typedef typename Kernel::Point_3 Point;
  typedef typename Kernel::Vector_3 Vector;

public:
  Segmenting_visitor(const FlipCriterion& criterion, const Unary& unary, Segmenter& segmenter,
                     Record_file<Swept_record>& records, Record_file<Earlier_edge>* edges, double radius,
                     const Progress_reporter& progress, std::uint64_t n, Sweep_stage_result& out,
                     bool layer_edges)
    : m_criterion(criterion), m_unary(unary), m_segmenter(segmenter), m_records(records), m_edges(edges),
      m_r2(radius * radius), m_progress(progress), m_n(n), m_out(out), m_layer_edges(layer_edges)
  {}

  /// The layer offsets and the edge weights of a whole batch, in parallel,
  /// with the input normals (as in the in-core graph, in single precision,
  /// negated across two layers); the neighbours' preliminary flips are
  /// applied in `finalize`.  The second pass and the fill of the fit see
  /// the batch and the earlier points (a later batch's are not known yet).
  void prepare(Sweep_window<Sweep_payload>& w, std::uint64_t first, const std::vector<std::size_t>& offsets,
               const std::vector<Sweep_neighbor>& neighbors, const Sweep_batch_nearest& nearest)
  {
    m_progress.report(first, m_n); // `first` points are finalised
    const std::size_t count = offsets.size() - 1;
    // The layer gaps, from every point's own k nearest (as in core): in the
    // fit's first gather, whose loads they share, else in a loop of their own.
    const double radius = std::sqrt(m_r2);
    m_gaps.assign(count, 0);
    m_gap_done.assign(count, 0);
    auto gap_of = [&](const Point_record& p, double& gap, std::uint64_t j) {
      const Point_record& o = w.record(j);
      gap = std::min(gap, Normal_orientation::internal::layer_gap_to(p.position, p.normal, o.position, o.normal));
    };
    if (m_layer_edges) {
      Normal_orientation::internal::fit_layer_offsets<ConcurrencyTag>(
        count,
        [&](std::size_t q, double* p, double* u) {
          const Point_record& r = w.record(first + q);
          for (int d = 0; d < 3; ++d) {
            p[d] = r.position[d];
            u[d] = r.normal[d];
          }
        },
        [&](std::size_t q, auto&& f) {
          const bool measure = !m_gap_done[q]; // (the first pass visits every point first)
          const Point_record& p = w.record(first + q);
          double gap = HUGE_VAL;
          nearest.for_each(q, [&](std::uint64_t j, float) {
            if (measure)
              gap_of(p, gap, j);
            if (j >= first && j < first + count)
              f(w.record(j).position, std::size_t(j - first), Normal_orientation::internal::ONE_LAYER, m_none);
            else if (j < first)
              f(w.record(j).position, Normal_orientation::internal::no_local, w.payload(j).layer_state,
                w.payload(j).layer);
            else // (a later batch's: not fitted yet)
              f(w.record(j).position, Normal_orientation::internal::no_local, Normal_orientation::internal::ONE_LAYER,
                m_none);
          });
          if (measure) {
            m_gaps[q] = Normal_orientation::internal::layer_gap_code(gap, radius);
            m_gap_done[q] = 1;
          }
        },
        m_layers, m_states);
    } else {
      Normal_orientation::internal::parallel_chunks<ConcurrencyTag>(count, [&](std::size_t b, std::size_t e) {
        for (std::size_t q = b; q < e; ++q) {
          const Point_record& p = w.record(first + q);
          double gap = HUGE_VAL;
          nearest.for_each(q, [&](std::uint64_t j, float) { gap_of(p, gap, j); });
          m_gaps[q] = Normal_orientation::internal::layer_gap_code(gap, radius);
        }
      }, 256);
      m_layers.assign(count, m_none);
      m_states.assign(count, Normal_orientation::internal::ONE_LAYER);
    }
    for (std::size_t q = 0; q < count; ++q) {
      Sweep_payload& payload = w.payload(first + q);
      payload.layer = m_layers[q];
      payload.layer_state = m_states[q];
      const bool two = Normal_orientation::internal::is_two_layers(m_layers[q]);
      m_out.two_layer_points += two ? 1 : 0;
      m_window_two_layers += two ? 1 : 0;
      payload.gap = m_gaps[q];
      m_out.layer_gap_points += m_gaps[q] != 0 ? 1 : 0;
    }
    const bool any_two_layers = m_window_two_layers > 0; // (else no edge of the batch crosses layers)
    m_weights.resize(neighbors.size());
    m_cursor = 0;
    Normal_orientation::internal::parallel_chunks<ConcurrencyTag>(count, [&](std::size_t b, std::size_t e) {
      for (std::size_t q = b; q < e; ++q) {
        const Point_record& p = w.record(first + q);
        const std::array<double, 3> np = unit_normal(p);
        const Point pp(p.position[0], p.position[1], p.position[2]);
        const Vector vp(np[0], np[1], np[2]);
        for (std::size_t t = offsets[q]; t < offsets[q + 1]; ++t) {
          const Point_record& o = w.record(neighbors[t].sequence);
          const std::array<double, 3> no = unit_normal(o);
          const double omega = 1.0 - double(neighbors[t].squared_distance) / m_r2;
          double weight = m_criterion(pp, vp, Point(o.position[0], o.position[1], o.position[2]),
                                      Vector(no[0], no[1], no[2])) *
                          omega;
          if (any_two_layers &&
              Normal_orientation::internal::edge_across_layers(p.position, w.payload(first + q).layer, np.data(),
                                                               o.position, w.payload(neighbors[t].sequence).layer,
                                                               no.data()))
            weight = -weight;
          m_weights[t] = float(weight);
        }
      }
    }, 256);
  }

  /// segments point `s`, whose earlier neighbours are `earlier`
  void finalize(Sweep_window<Sweep_payload>& w, std::uint64_t s, const std::vector<Sweep_neighbor>& earlier)
  {
    m_votes.clear();
    if (m_edges != nullptr) { // a header (the number of edges), then the edges
      const std::uint64_t farthest = earlier.empty() ? 0 : s - earlier.front().sequence; // sorted
      if (farthest > std::uint64_t(std::numeric_limits<std::uint32_t>::max()) ||
          earlier.size() > std::size_t(std::numeric_limits<std::uint32_t>::max()))
        throw std::length_error("streaming_orient_normals: the sweep window is too large for the refinement");
      m_out.edge_span = std::max(m_out.edge_span, farthest);
      m_edges->append(Earlier_edge{std::uint32_t(earlier.size()), 0.0f});
    }
    for (const Sweep_neighbor& nb : earlier) {
      const Sweep_payload& pq = w.payload(nb.sequence);
      const float weight = m_weights[m_cursor++];
      m_votes.push_back({pq.segment, double(weight) * double(pq.flip)});
      m_out.energy_before += edge_energy(double(weight), Label(1), Label(1));
      m_out.total_weight += std::abs(double(weight));
      if (m_edges != nullptr)
        m_edges->append(Earlier_edge{std::uint32_t(s - nb.sequence), weight});
    }
    double preference = 0.0;
    const Point_record& record = w.record(s);
    if (Unary::enabled && (record.normal[0] != 0.0 || record.normal[1] != 0.0 || record.normal[2] != 0.0))
      preference = m_unary(record);
    const Segment_assignment a = m_segmenter.add_point(m_votes, preference);
    w.payload(s).segment = a.segment;
    w.payload(s).flip = a.flip;
    if (a.segment >= m_out.segment_size.size()) {
      m_out.segment_size.resize(a.segment + 1, 0);
      m_out.segment_has_unary.resize(a.segment + 1, 0);
    }
    ++m_out.segment_size[a.segment];
    if (preference != 0.0) {
      m_out.segment_has_unary[a.segment] = 1;
      ++m_out.unary_terms;
    }
  }

  /// writes point `s`, leaving the window, to the record file
  void release(Sweep_window<Sweep_payload>& w, std::uint64_t s)
  {
    const Sweep_payload& p = w.payload(s);
    const Point_record& r = w.record(s);
    m_out.grid_origin.add(r.position, r.index);
    m_window_two_layers -= Normal_orientation::internal::is_two_layers(p.layer) ? 1 : 0;
    m_records.append(Swept_record{r, p.segment, std::int8_t(p.flip), p.gap,
                                  layer_code(p.layer, unit_normal(r), std::sqrt(m_r2))});
  }

private:
  const FlipCriterion& m_criterion;
  const Unary& m_unary;
  Segmenter& m_segmenter;
  Record_file<Swept_record>& m_records;
  Record_file<Earlier_edge>* m_edges;
  double m_r2;
  const Progress_reporter& m_progress;
  std::uint64_t m_n;
  Sweep_stage_result& m_out;
  bool m_layer_edges;
  std::vector<Neighbor_vote> m_votes;
  std::vector<float> m_weights;
  std::vector<Normal_orientation::internal::Layer_offset> m_layers;
  std::vector<unsigned char> m_states;
  std::vector<std::uint8_t> m_gaps;   // (per point of the batch, `layer_gap_code()`)
  std::vector<char> m_gap_done;
  const Normal_orientation::internal::Layer_offset m_none{};
  std::uint64_t m_window_two_layers = 0; // two-layer points in the window
  std::size_t m_cursor = 0;
};

/// No unary term.
struct No_unary
{
  static constexpr bool enabled = false;
  double operator()(const Point_record&) const { return 0.0; }
};

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_SEGMENTING_SWEEP_H
