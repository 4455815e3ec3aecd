// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_REFINEMENT_H
#define NORMAL_ORIENTATION_STREAMING_REFINEMENT_H

/// \file Refinement.h
/// The refinement of a streamed orientation, after the segment graph of the
/// sweep is solved: passes over the points in the sweep order, each with a
/// window of bounded size, that move single points (iterated conditional
/// modes, Gauss-Seidel in the sweep order) and segment the points again
/// around the current labelling, with a limit on the size of the segments,
/// so that the solver of the new, finer segment graph can move patches that
/// the rigid segments of the sweep had locked in.  No step raises the
/// energy of the point graph.

#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/internal/Qpbo.h>
#include <Normal_orientation/streaming/Record_file.h>
#include <Normal_orientation/Segmenter.h>

#include <CGAL/property_map.h>

#include <boost/graph/compressed_sparse_row_graph.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <future>
#include <stdexcept>
#include <string>
#include <vector>

namespace Normal_orientation {
namespace streaming {

/// \ingroup PkgNormalOrientationStreaming
/// An edge of the neighbour graph as the sweep keeps it for the
/// refinement, with its later end: how many points earlier, in the sweep
/// order, its other end is, and its signed weight w_ij in the frame of the
/// input normals (single precision, as in the in-core graph).
struct Earlier_edge
{
  /// the sequence number of the later end minus that of the earlier one (>= 1)
  std::uint32_t offset;
  /// the signed weight of the edge, input normals
  float weight;
};

/// \ingroup PkgNormalOrientationStreaming
/// The parameters of the refinement of `streaming_orient_normals()` (see
/// the named parameter `refinement_rounds`).
///
/// Each round is one pass over the points in the sweep order and one solve:
/// the pass moves single points (a point flips when its edges weigh more
/// against its label than for it) and segments the points again, without
/// flips, in the frame of the labelling it has just made (the paper's
/// criteria with `thresholds`, as the in-core reduction of `Qpbo_i_solver`
/// segments around the MST labelling), with segments of at most
/// max(`smallest_segment`, n x `largest_segment` / `shrink`^t) points in
/// round t = 0, 1, ...; then the solver solves the new segment graph, whose
/// labelling all +1 is the current one, and its labelling is kept only when
/// its energy is lower.  A last pass makes single-point moves again.  So
/// patches first, then finer and finer ones, can move, not only the rigid
/// segments of the sweep.
struct Refinement_options
{
  /// the number of rounds; 0: no refinement (and no edge file: the sweep
  /// then writes only the points)
  unsigned int rounds = 3;
  /// the segmentation thresholds of the rounds (`maximum_size` is set per
  /// round)
  Segmentation_thresholds thresholds{0.5, 0.5, 0};
  /// the size limit of the segments of the first round, as a fraction of
  /// the number of points
  double largest_segment = 1.0 / 48.0;
  /// each round divides the size limit by this (> 1 makes the segments
  /// finer from round to round)
  double shrink = 4.0;
  /// the size limit is never below this
  std::size_t smallest_segment = 64;
  /// no round runs when the energy of the solved segment graph's labelling
  /// is at most this fraction of the total absolute weight of the edges:
  /// the refinement could lower it by no more (0: no round runs only when
  /// no edge contradicts the labelling)
  double negligible_energy = 1e-6;

  /// whether the rounds run, for a labelling of energy `energy` in a graph
  /// whose edges' absolute weights sum to `total_weight`: when the energy
  /// is positive and above `negligible_energy` times `total_weight`
  bool worth_running(double energy, double total_weight) const
  {
    return energy > 0.0 && energy > negligible_energy * total_weight;
  }

  /// the size limit of the segments of round `round` for `n` points
  std::size_t maximum_segment_size(std::uint64_t n, unsigned int round) const
  {
    const double limit = double(n) * largest_segment / std::pow(std::max(1.0, shrink), double(round));
    return std::max<std::size_t>(std::max<std::size_t>(1, smallest_segment),
                                 std::size_t(std::min(limit, double(n) + 1.0)));
  }
};

/// \cond SKIP_IN_MANUAL
namespace internal {

/// What one pass of `Relabelling_window` measured.
struct Relabelling_report
{
  /// the energy of the point graph with the labels the points came with
  double energy_before = 0.0;
  /// the energy with the labels they left with
  double energy_after = 0.0;
  /// the single-point moves made
  std::uint64_t moves = 0;
  /// the points
  std::uint64_t points = 0;
};

/// One refinement pass over points given in the sweep order.  Each point is
/// pushed with its current label and its earlier edges; once the `span`
/// points after it (the farthest any of its later neighbours can be) have
/// been pushed too, it is decided: it flips when
///   sum over its neighbours j of w_ij L_j
/// has the sign opposite to its label, with the new labels of its earlier
/// neighbours and the current ones of its later neighbours (one
/// Gauss-Seidel sweep of iterated conditional modes, exactly
/// `internal::improve_by_sweeps()` in the sweep order), and, when a
/// segmenter is given, it is segmented with the votes w_ij L_i L_j of its
/// earlier neighbours (the segmenter must not flip: the segment graph is
/// then that of the new labelling).  The decided points come out in order,
/// through `out(label, segment)` (segment 0 without a segmenter).
///
/// Memory: O(span) points and their earlier edges, whatever the number of
/// points.  Deterministic.
class Relabelling_window
{
public:
  /// a pass whose edges span at most `span` points; `segmenter` may be
  /// null; `energy_before`: whether to sum the energy of the labels the
  /// points come with (`Relabelling_report::energy_before`, else 0)
  Relabelling_window(std::uint64_t span, Segmenter* segmenter, bool energy_before = true)
    : m_span(span), m_segmenter(segmenter), m_energy_before(energy_before)
  {
    std::size_t capacity = 1;
    while (capacity < 2 * (span + 1))
      capacity *= 2;
    m_mask = capacity - 1;
    m_old.resize(capacity);
    m_new.resize(capacity);
    m_later.resize(capacity);
    m_segment.resize(capacity);
    m_count.resize(capacity);
    m_edges.resize(1024);
  }

  /// Pushes the next point: its label and its `count` earlier edges
  /// (`edges[t].offset` <= span); decided points go to `out`.
  /// \throw std::invalid_argument if an edge reaches farther back than the span
  template <typename Out>
  void push(Label label, const Earlier_edge* edges, std::size_t count, Out&& out)
  {
    const std::uint64_t i = m_pushed;
    const std::size_t si = slot(i);
    m_old[si] = label;
    m_later[si] = 0.0;
    m_count[si] = std::uint32_t(count);
    if (m_edge_end - m_edge_begin + count > m_edges.size())
      grow(count);
    const std::size_t edge_mask = m_edges.size() - 1;
    double energy = 0.0;
    for (std::size_t t = 0; t < count; ++t) {
      const Earlier_edge e = edges[t];
      if (e.offset == 0 || e.offset > m_span || e.offset > i)
        throw std::invalid_argument("Relabelling_window: an edge reaches outside the window");
      const std::size_t sj = slot(i - e.offset);
      const double w = double(e.weight);
      m_later[sj] += w * double(label);
      if (m_energy_before)
        energy += edge_energy(w, label, m_old[sj]);
      m_edges[std::size_t(m_edge_end++) & edge_mask] = e;
    }
    m_report.energy_before += energy;
    ++m_pushed;
    while (m_pushed - m_decided > m_span)
      decide(out);
  }

  /// Decides the points still pending, after the last push.
  template <typename Out>
  void finish(Out&& out)
  {
    while (m_decided < m_pushed)
      decide(out);
  }

  /// what the pass measured (complete after `finish()`)
  const Relabelling_report& report() const { return m_report; }

private:
  std::size_t slot(std::uint64_t sequence) const { return std::size_t(sequence) & m_mask; }

  /// makes room for `count` more edges (the ring doubles, in order)
  void grow(std::size_t count)
  {
    std::size_t size = m_edges.size();
    const std::size_t used = std::size_t(m_edge_end - m_edge_begin);
    while (size < used + count)
      size *= 2;
    std::vector<Earlier_edge> ring(size);
    for (std::size_t t = 0; t < used; ++t)
      ring[t] = m_edges[std::size_t(m_edge_begin + t) & (m_edges.size() - 1)];
    m_edges.swap(ring);
    m_edge_end -= m_edge_begin;
    m_edge_begin = 0;
  }

  template <typename Out>
  void decide(Out& out)
  {
    const std::uint64_t d = m_decided;
    const std::size_t sd = slot(d);
    const std::size_t count = m_count[sd];
    const std::size_t edge_mask = m_edges.size() - 1;
    // the votes w_ij L_j of the earlier neighbours, multiplied by L_i below
    if (m_votes.size() < count)
      m_votes.resize(count);
    double support = m_later[sd];
    for (std::size_t t = 0; t < count; ++t) {
      const Earlier_edge& e = m_edges[std::size_t(m_edge_begin + t) & edge_mask];
      const std::size_t se = slot(d - e.offset);
      const double v = double(e.weight) * double(m_new[se]);
      m_votes[t].segment = m_segment[se];
      m_votes[t].weight = v;
      support += v;
    }
    const Label old = m_old[sd];
    const Label label = support * double(old) < 0.0 ? Label(-old) : old;
    if (label != old)
      ++m_report.moves;
    m_new[sd] = label;
    double energy = 0.0;
    for (std::size_t t = 0; t < count; ++t) {
      const double v = m_votes[t].weight * double(label);
      m_votes[t].weight = v;
      energy += v < 0.0 ? -v : 0.0; // edge_energy(w, L_i, L_j)
    }
    m_report.energy_after += energy;
    if (m_segmenter != nullptr) {
      m_votes.resize(count);
      m_segment[sd] = m_segmenter->add_point(m_votes).segment;
    } else {
      m_segment[sd] = 0;
    }
    m_edge_begin += count;
    ++m_decided;
    ++m_report.points;
    out(label, m_segment[sd]);
  }

  std::uint64_t m_span;
  Segmenter* m_segmenter;
  bool m_energy_before;
  std::size_t m_mask = 0;
  std::vector<Label> m_old, m_new;
  std::vector<double> m_later;
  std::vector<std::uint32_t> m_segment, m_count;
  std::vector<Earlier_edge> m_edges; // a ring: the earlier edges of the points pushed, not yet decided
  std::uint64_t m_edge_begin = 0, m_edge_end = 0;
  std::vector<Neighbor_vote> m_votes;
  std::uint64_t m_pushed = 0, m_decided = 0;
  Relabelling_report m_report;
};

/// Reads a record file from its first record, in blocks of a fixed number
/// of records; with `prefetch`, the next block is read by a task of its own
/// while the current one is used (an error of the read is thrown by the
/// `next()` that would have returned it).  The destructor waits for the
/// task.
template <typename T>
class Record_reader
{
public:
  /// a reader of `file` (rewound), by blocks of `block` records
  Record_reader(Record_file<T>& file, std::size_t block, bool prefetch)
    : m_file(file), m_block(std::max<std::size_t>(1, block)), m_prefetch(prefetch)
  {
    m_file.rewind();
    if (m_prefetch)
      start();
  }
  Record_reader(const Record_reader&) = delete;
  Record_reader& operator=(const Record_reader&) = delete;
  ~Record_reader()
  {
    if (m_pending.valid())
      m_pending.wait();
  }

  /// the next block (empty at the end), valid until the next call
  const std::vector<T>& next()
  {
    if (!m_prefetch) {
      m_current.clear();
      m_file.read(m_current, m_block);
      return m_current;
    }
    m_pending.get(); // rethrows an error of the read
    m_current.swap(m_spare);
    if (!m_current.empty())
      start();
    return m_current;
  }

private:
  void start()
  {
    m_pending = std::async(std::launch::async, [this]() {
      m_spare.clear();
      m_file.read(m_spare, m_block);
    });
  }

  Record_file<T>& m_file;
  std::size_t m_block;
  bool m_prefetch;
  std::vector<T> m_current, m_spare;
  std::future<void> m_pending;
};

/// Reads, point after point, the edge file written by the sweep for the
/// refinement: for each point in the sweep order, a header entry whose
/// `offset` is the number n of its earlier edges (its `weight` is 0), then
/// those n edges.
class Edge_reader
{
public:
  /// a reader of `file` from its first point; see `Record_reader` for `prefetch`
  Edge_reader(Record_file<Earlier_edge>& file, bool prefetch) : m_blocks(file, std::size_t(1) << 17, prefetch), m_path(file.path()) {}

  /// The earlier edges of the next point: `edges[0] ... edges[count - 1]`,
  /// valid until the next call.
  /// \throw std::runtime_error when the file ends before the point or in
  ///        its middle (the edge file and the record file disagree)
  void next(const Earlier_edge*& edges, std::size_t& count)
  {
    if (m_next == m_buffer.size() || m_buffer[m_next].offset >= m_buffer.size() - m_next) // not all buffered
      fill();
    count = m_buffer[m_next].offset;
    edges = m_buffer.data() + m_next + 1;
    m_next += 1 + count;
  }

private:
  /// buffers the whole next point (header and edges)
  void fill()
  {
    m_buffer.erase(m_buffer.begin(), m_buffer.begin() + std::ptrdiff_t(m_next));
    m_next = 0;
    while (m_buffer.empty() || m_buffer[0].offset >= m_buffer.size()) {
      const std::vector<Earlier_edge>& block = m_blocks.next();
      if (block.empty())
        throw std::runtime_error("streaming_orient_normals: the edge file ends before the record file (" + m_path +
                                 ")");
      m_buffer.insert(m_buffer.end(), block.begin(), block.end());
    }
  }

  Record_reader<Earlier_edge> m_blocks;
  std::string m_path;
  std::vector<Earlier_edge> m_buffer;
  std::size_t m_next = 0;
};

/// The energy of the segment graph of `segmenter` with the labels `x` of
/// its segments, minus that with all +1 (in double precision, over the
/// accumulated weights of the segment pairs): the change of the energy of
/// the point graph when each segment s is flipped where x_s = -1.
inline double segment_energy_change(const Segmenter& segmenter, const std::vector<Label>& x)
{
  const Segment_pair_weights& pairs = segmenter.segment_pairs();
  double change = 0.0;
  for (std::size_t t = 0; t < pairs.size(); ++t)
    change += edge_energy(pairs.weight(t), x[pairs.first(t)], x[pairs.second(t)]) - edge_energy(pairs.weight(t), 1, 1);
  return change;
}

/// Improves the labelling all +1 of the segment graph accumulated by
/// `segmenter` (the current labelling of the points) with QPBO-I started
/// there: roof duality (weak persistencies) labels part of the segments
/// optimally, then the others are fixed to +1 in the order of their
/// numbers, in at most 64 batches with an incremental re-solve after each,
/// as `Qpbo_i_solver` does from its MST labelling.  So the result is never
/// above all +1.
inline std::vector<Label> improve_segment_labelling(const Segmenter& segmenter)
{
  const std::size_t ns = segmenter.number_of_segments();
  const Segment_pair_weights& pairs = segmenter.segment_pairs();
  std::vector<Label> x(ns, Label(1));
  Normal_orientation::internal::Qpbo qpbo(ns, pairs.size());
  qpbo.add_nodes(ns);
  bool any = false;
  for (std::size_t t = 0; t < pairs.size(); ++t)
    if (pairs.weight(t) != 0.0) {
      qpbo.add_signed_edge(pairs.first(t), pairs.second(t), pairs.weight(t));
      any = true;
    }
  if (!any)
    return x;
  qpbo.solve();
  std::vector<std::size_t> unlabelled;
  for (std::size_t i = 0; i < ns; ++i)
    if (qpbo.label(i) < 0)
      unlabelled.push_back(i);
  const std::size_t batch = std::max<std::size_t>(1, (unlabelled.size() + 63) / 64);
  std::size_t in_batch = 0;
  for (const std::size_t i : unlabelled) {
    if (qpbo.label(i) >= 0)
      continue;
    qpbo.fix(i, 0); // x = 0 is the label +1
    if (++in_batch == batch) {
      qpbo.solve();
      in_batch = 0;
    }
  }
  if (in_batch > 0)
    qpbo.solve();
  for (std::size_t i = 0; i < ns; ++i)
    x[i] = qpbo.label(i) == 1 ? Label(-1) : Label(1);
  return x;
}

/// The segment graph accumulated by `segmenter` as a `Neighbor_graph`: a
/// vertex per segment, an edge per pair of segments of nonzero summed
/// weight, with that weight (single precision, as in the point graph).
inline Neighbor_graph make_segment_graph(const Segmenter& segmenter)
{
  const Segment_pair_weights& pairs = segmenter.segment_pairs();
  std::vector<std::uint32_t> sources, targets;
  std::vector<Neighbor_edge> props;
  for (std::size_t t = 0; t < pairs.size(); ++t)
    if (pairs.weight(t) != 0.0) {
      sources.push_back(pairs.first(t));
      targets.push_back(pairs.second(t));
      props.push_back(Neighbor_edge{float(pairs.weight(t))});
    }
  return Neighbor_graph(boost::construct_inplace_from_sources_and_targets, sources, targets, props,
                        std::uint32_t(segmenter.number_of_segments()));
}

/// The labelling of the segment graph of `segmenter` of lowest energy among
/// all +1 (the current labelling), that of `improve_segment_labelling()`
/// (which finds the improvements near the current labelling) and that of
/// `solver` started from scratch (whose MST can move far from it; ties
/// keep the earlier).  `change` receives its `segment_energy_change()`,
/// < 0 unless all +1 is returned.
template <typename Solver>
std::vector<Label> solve_segment_graph(const Segmenter& segmenter, const Solver& solver, double& change)
{
  const std::size_t ns = segmenter.number_of_segments();
  std::vector<Label> best(ns, Label(1));
  change = 0.0;
  std::vector<Label> x = improve_segment_labelling(segmenter);
  double c = segment_energy_change(segmenter, x);
  if (c < change) {
    change = c;
    best.swap(x);
  }
  const Neighbor_graph g = make_segment_graph(segmenter);
  if (num_edges(g) == 0)
    return best;
  x.assign(ns, Label(1));
  solver.solve(g, get(&Neighbor_edge::weight, g), CGAL::make_property_map(x));
  c = segment_energy_change(segmenter, x);
  if (c < change) {
    change = c;
    best.swap(x);
  }
  return best;
}

} // namespace internal
/// \endcond

} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_REFINEMENT_H
