// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_SEGMENTER_H
#define NORMAL_ORIENTATION_SEGMENTER_H

/// \file Segmenter.h
/// The segmentation of the paper (sec. 5.1, supplement sec. 3), one point at
/// a time: each point joins a segment of its earlier neighbours or opens a
/// new one, with a preliminary flip, and the segment graph is accumulated on
/// the fly.  The streaming pipeline feeds it in sweep order; the in-core
/// reduction of the global solvers (`internal/Graph_reduction.h`) in vertex
/// order.

#include <Normal_orientation/Orientation_problem.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationStreaming
/// The thresholds of the segmentation (paper sec. 5.1, supplement eq. 5-7).
struct Segmentation_thresholds
{
  /// theta_S: the tolerated sum of contradicting votes, inside a segment
  /// and across segment borders
  double contradiction = 0.0;
  /// theta_acc: the smallest |vote| of a segment that a point may join
  double acceptance = 0.5;
  /// the most points a segment may hold (0: no limit)
  std::size_t maximum_size = 0;
};

/// \ingroup PkgNormalOrientationStreaming
/// The vote of one earlier neighbour j for the current point i: the segment
/// of j and the edge weight w_ij computed with j's normal as it stands
/// after j's preliminary flip (and i's normal as read).
struct Neighbor_vote
{
  /// the segment of the neighbour
  std::uint32_t segment;
  /// the signed weight of the edge, in the neighbour's current frame
  double weight;
};

/// \ingroup PkgNormalOrientationStreaming
/// What `Segmenter::add_point()` decided for a point.
struct Segment_assignment
{
  /// the segment the point joined or opened
  std::uint32_t segment;
  /// the preliminary flip: -1 if the point's normal is to be flipped
  Label flip;
  /// true when the point opened a new segment
  bool opened;
};

/// \ingroup PkgNormalOrientationStreaming
/// The edges of a segment graph as `Segmenter` accumulates them: an
/// open-addressing hash map from a pair of segment numbers (a < b) to the
/// sum of the weights between them and the sum of their absolute values,
/// in insertion order (pair t: `first(t)`, `second(t)`, `weight(t)`).
class Segment_pair_weights
{
public:
  Segment_pair_weights() : m_slot(1024, empty) {}

  /// the accumulated weight between `a` and `b` (0 when none)
  double get(std::uint32_t a, std::uint32_t b) const
  {
    const std::uint64_t key = make_key(a, b);
    for (std::size_t h = hash(key) & (m_slot.size() - 1);; h = (h + 1) & (m_slot.size() - 1)) {
      const std::uint32_t s = m_slot[h];
      if (s == empty)
        return 0.0;
      if (m_key[s] == key)
        return m_weight[s];
    }
  }

  /// adds `w` to the weight between `a` and `b`, and `absolute` (the sum of
  /// the absolute values of the weights `w` sums) to their absolute weight
  void add(std::uint32_t a, std::uint32_t b, double w, double absolute)
  {
    const std::uint64_t key = make_key(a, b);
    for (std::size_t h = hash(key) & (m_slot.size() - 1);; h = (h + 1) & (m_slot.size() - 1)) {
      const std::uint32_t s = m_slot[h];
      if (s == empty) {
        m_slot[h] = std::uint32_t(m_key.size());
        m_key.push_back(key);
        m_weight.push_back(w);
        m_absolute.push_back(absolute);
        if (2 * m_key.size() > m_slot.size())
          grow();
        return;
      }
      if (m_key[s] == key) {
        m_weight[s] += w;
        m_absolute[s] += absolute;
        return;
      }
    }
  }

  /// the number of pairs
  std::size_t size() const { return m_key.size(); }
  /// the smaller segment of the `i`-th pair inserted
  std::uint32_t first(std::size_t i) const { return std::uint32_t(m_key[i] >> 32); }
  /// the larger segment of the `i`-th pair inserted
  std::uint32_t second(std::size_t i) const { return std::uint32_t(m_key[i]); }
  /// the weight of the `i`-th pair inserted
  double weight(std::size_t i) const { return m_weight[i]; }
  /// the sum of the absolute values of the edge weights of the `i`-th pair
  /// inserted (equal to |weight(i)| when they all have the same sign)
  double absolute_weight(std::size_t i) const { return m_absolute[i]; }

private:
  static constexpr std::uint32_t empty = ~std::uint32_t(0);

  static std::uint64_t make_key(std::uint32_t a, std::uint32_t b)
  {
    return a < b ? (std::uint64_t(a) << 32) | b : (std::uint64_t(b) << 32) | a;
  }
  static std::size_t hash(std::uint64_t key)
  {
    key ^= key >> 33;
    key *= 0xff51afd7ed558ccdULL;
    key ^= key >> 33;
    return std::size_t(key);
  }
  void grow()
  {
    std::vector<std::uint32_t> slot(2 * m_slot.size(), empty);
    for (std::size_t s = 0; s < m_key.size(); ++s) {
      std::size_t h = hash(m_key[s]) & (slot.size() - 1);
      while (slot[h] != empty)
        h = (h + 1) & (slot.size() - 1);
      slot[h] = std::uint32_t(s);
    }
    m_slot.swap(slot);
  }

  std::vector<std::uint32_t> m_slot;
  std::vector<std::uint64_t> m_key;
  std::vector<double> m_weight, m_absolute;
};

/// \ingroup PkgNormalOrientationStreaming
/// The paper's segmentation, one point at a time (sec. 5.1; supplement
/// eq. 5-7).  For a point i and the votes of its earlier neighbours, summed
/// per segment into positive and negative parts, a segment s is valid when
///  - its vote v = vote(i, s) has |v| >= theta_acc, and the votes against
///    the flip f = sign(v) sum to at most theta_S (intra-segment criterion);
///  - for every other neighbouring segment t, the weight accumulated so far
///    between s and t is zero or has the sign of f * vote(i, t), unless
///    |vote(i, t)| <= theta_S (inter-segment criterion).
/// The valid segment of largest |v| is chosen (the first one on ties, in
/// the order of the votes), and the point's normal is flipped when f < 0;
/// without a valid segment the point opens a new one, unflipped.  The
/// weights between segments (and the points' unary preferences, if any)
/// are accumulated: they form the segment graph, whose labelling all +1 is
/// the preliminary orientation and whose energy equals that of the point
/// graph for every labelling that keeps segments rigid, up to the constant
/// of the edges inside the segments.
///
/// Unlike the reference code, ties and orders are deterministic, and the
/// inter-segment criterion follows the paper's rule ("< theta_S" tolerates;
/// the reference code tests "<=").  With `may_flip = false` a point only
/// joins segments that vote for its current orientation: the in-core
/// reduction uses this to segment around a given labelling.
///
/// Memory: O(segments + segment pairs); nothing is kept per point.
class Segmenter
{
public:
  /// a segmenter with thresholds `theta`; see the class description for
  /// `may_flip`
  explicit Segmenter(const Segmentation_thresholds& theta = Segmentation_thresholds(), bool may_flip = true)
    : m_theta(theta), m_may_flip(may_flip)
  {}

  /// Assigns the next point, given the votes of its earlier neighbours (any
  /// order, several per segment allowed) and its unary preference (see
  /// `internal::Array_problem`; 0 for none).
  Segment_assignment add_point(const std::vector<Neighbor_vote>& votes, double preference = 0.0)
  {
    m_sums.clear();
    bool one_segment = !votes.empty();
    for (const Neighbor_vote& v : votes)
      if (v.segment != votes.front().segment) {
        one_segment = false;
        break;
      }
    if (one_segment) { // the common case, summed in registers (the same sums)
      double positive = 0.0, negative = 0.0;
      for (const Neighbor_vote& v : votes)
        (v.weight > 0.0 ? positive : negative) += v.weight;
      m_sums.push_back(Sum{votes.front().segment, positive, negative});
    } else {
      for (const Neighbor_vote& v : votes) {
        auto it = std::find_if(m_sums.begin(), m_sums.end(), [&](const Sum& x) { return x.segment == v.segment; });
        if (it == m_sums.end())
          it = m_sums.insert(m_sums.end(), Sum{v.segment, 0.0, 0.0});
        (v.weight > 0.0 ? it->positive : it->negative) += v.weight;
      }
    }
    std::size_t best = m_sums.size();
    double best_vote = m_theta.acceptance;
    Label best_flip = 1;
    for (std::size_t c = 0; c < m_sums.size(); ++c) {
      const Sum& s = m_sums[c];
      const double vote = s.positive + s.negative;
      const Label f = (vote < 0.0 && m_may_flip) ? Label(-1) : Label(1);
      const double strength = f * vote;
      const double against = f > 0 ? -s.negative : s.positive;
      if (strength < best_vote || against > m_theta.contradiction || (best != m_sums.size() && strength == best_vote))
        continue;
      if (m_theta.maximum_size != 0 && m_size[s.segment] >= m_theta.maximum_size)
        continue;
      bool valid = true;
      for (const Sum& t : m_sums) {
        if (t.segment == s.segment)
          continue;
        const double a = f * (t.positive + t.negative);
        const double w = m_between.get(s.segment, t.segment);
        if (w != 0.0 && a != 0.0 && ((w > 0.0) != (a > 0.0)) && std::abs(a) > m_theta.contradiction) {
          valid = false;
          break;
        }
      }
      if (valid) {
        best = c;
        best_vote = strength;
        best_flip = f;
      }
    }
    Segment_assignment result;
    if (best == m_sums.size()) {
      result = Segment_assignment{std::uint32_t(m_preference.size()), Label(1), true};
      m_preference.push_back(0.0);
      m_size.push_back(0);
    } else {
      result = Segment_assignment{m_sums[best].segment, best_flip, false};
    }
    for (const Sum& t : m_sums)
      if (t.segment != result.segment)
        m_between.add(result.segment, t.segment, result.flip * (t.positive + t.negative), t.positive - t.negative);
      else // the edges inside the segment that contradict the flip
        m_inside += result.flip > 0 ? -t.negative : t.positive;
    m_preference[result.segment] += result.flip * preference;
    ++m_size[result.segment];
    ++m_points;
    return result;
  }

  /// the number of segments opened so far
  std::size_t number_of_segments() const { return m_preference.size(); }
  /// the number of points assigned so far
  std::size_t number_of_points() const { return m_points; }
  /// the accumulated weights between segments (the segment graph's edges,
  /// in the order their pairs first met; a weight may be zero)
  const Segment_pair_weights& segment_pairs() const { return m_between; }
  /// the summed unary preference of each segment, in the frame of its
  /// preliminary orientation
  const std::vector<double>& segment_preferences() const { return m_preference; }
  /// The energy of the edges seen so far (the votes; `edge_energy()`
  /// summed over them) for the labelling that gives the points of each
  /// segment s their preliminary orientation times `x[s]`: the energy
  /// inside the segments plus, per segment pair (a, b) of weight W and
  /// absolute weight A, (A - W x_a x_b) / 2.  It is exactly 0 when no
  /// edge contradicts that labelling.
  /// \pre `x` has a label per segment
  double point_energy(const std::vector<Label>& x) const
  {
    double e = m_inside;
    for (std::size_t i = 0; i < m_between.size(); ++i)
      e += 0.5 * (m_between.absolute_weight(i) - m_between.weight(i) * x[m_between.first(i)] * x[m_between.second(i)]);
    return e;
  }

private:
  struct Sum
  {
    std::uint32_t segment;
    double positive, negative;
  };

  Segmentation_thresholds m_theta;
  bool m_may_flip;
  Segment_pair_weights m_between;
  std::vector<double> m_preference;
  std::vector<std::size_t> m_size;
  std::vector<Sum> m_sums;
  std::size_t m_points = 0;
  double m_inside = 0.0;
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_SEGMENTER_H
