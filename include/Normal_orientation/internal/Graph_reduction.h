// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_GRAPH_REDUCTION_H
#define NORMAL_ORIENTATION_INTERNAL_GRAPH_REDUCTION_H

/// \file Graph_reduction.h
/// The orientation problem in flat arrays, and its reduction to a segment
/// graph around a starting labelling (the in-core form of the paper's
/// segmentation, sec. 5.1 and supplement sec. 3): the global solvers run on
/// the reduced problem, whose labellings are exactly the labellings of the
/// full problem that keep every segment rigid.

#include <Normal_orientation/Orientation_problem.h>

#include <boost/graph/graph_traits.hpp>
#include <boost/graph/properties.hpp>
#include <boost/property_map/property_map.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace internal {

/// A binary orientation problem in flat arrays: informative edges (non-zero
/// weight, no self-loops) with their signed weights, and optionally one
/// unary preference per vertex.  A unary term with costs (c+, c-) of the
/// labels +1 and -1 equals the constant min(c+, c-) plus the energy of an
/// edge of weight a = c- - c+ to a vertex fixed to +1: `preference[i]` is
/// that a (> 0 favours +1, < 0 favours -1).
struct Array_problem
{
  /// the number of vertices
  std::size_t number_of_vertices = 0;
  /// the ends and signed weights of the edges
  std::vector<std::uint32_t> tail, head;
  /// the signed weights of the edges
  std::vector<double> weight;
  /// per vertex, a = c- - c+ of its unary term; empty without unary terms
  std::vector<double> preference;

  /// the energy of `labels` up to the constant of the unary terms
  double energy(const std::vector<Label>& labels) const
  {
    double e = 0.0;
    for (std::size_t t = 0; t < weight.size(); ++t)
      e += edge_energy(weight[t], labels[tail[t]], labels[head[t]]);
    for (std::size_t i = 0; i < preference.size(); ++i)
      e += edge_energy(preference[i], labels[i], 1);
    return e;
  }
};

/// The unary preferences of the vertices of `g` (see `Array_problem`); empty
/// when `UnaryMap` is `No_unary`.
/// \throw std::invalid_argument (naming `solver`) if a unary cost is not finite
template <typename Graph, typename UnaryMap>
std::vector<double> unary_preferences(const Graph& g, const UnaryMap& unary, const char* solver)
{
  std::vector<double> preference;
  if constexpr (!std::is_same<UnaryMap, No_unary>::value) {
    const std::vector<std::pair<double, double>> costs = unary_costs(g, unary, solver);
    preference.resize(costs.size());
    for (std::size_t i = 0; i < costs.size(); ++i)
      preference[i] = costs[i].second - costs[i].first;
  }
  return preference;
}

/// Copies the informative edges of `g` (and the unary terms, unless
/// `UnaryMap` is `No_unary`) into an `Array_problem`.
/// \throw std::invalid_argument if a weight or a unary cost is not finite
/// \throw std::length_error if `g` has 2^32 - 1 vertices or more
template <typename Graph, typename WeightMap, typename UnaryMap>
Array_problem make_array_problem(const Graph& g, WeightMap weight, const UnaryMap& unary, const char* solver)
{
  Array_problem p;
  p.number_of_vertices = std::size_t(num_vertices(g));
  if (p.number_of_vertices >= std::size_t(std::numeric_limits<std::uint32_t>::max()))
    throw std::length_error(std::string(solver) + ": too many vertices");
  auto index = get(boost::vertex_index, g);
  p.tail.reserve(std::size_t(num_edges(g)));
  p.head.reserve(std::size_t(num_edges(g)));
  p.weight.reserve(std::size_t(num_edges(g)));
  typename boost::graph_traits<Graph>::edge_iterator it, end;
  for (boost::tie(it, end) = edges(g); it != end; ++it) {
    const double w = double(get(weight, *it));
    if (!std::isfinite(w))
      throw std::invalid_argument(std::string(solver) + ": an edge weight is not finite");
    const std::size_t u = std::size_t(get(index, source(*it, g))), v = std::size_t(get(index, target(*it, g)));
    if (w == 0.0 || u == v)
      continue;
    p.tail.push_back(std::uint32_t(u));
    p.head.push_back(std::uint32_t(v));
    p.weight.push_back(w);
  }
  p.preference = unary_preferences(g, unary, solver);
  return p;
}

/// The incidence lists of a problem, both directions, with single-precision
/// weights (the compact form of large problems): the neighbours of vertex i
/// are `other[first[i]] ... other[first[i+1]-1]`, with the weights
/// `weight[...]`, in the order of the edges.  Edges of weight zero and
/// self-loops are left out.
struct Incidence
{
  /// the start of each vertex's list (size n + 1)
  std::vector<std::uint32_t> first;
  /// the other end of each incident edge
  std::vector<std::uint32_t> other;
  /// the signed weight of each incident edge
  std::vector<float> weight;

  /// the incidence lists of `p`
  explicit Incidence(const Array_problem& p)
  {
    build(p.number_of_vertices, [&](auto&& visit) {
      for (std::size_t t = 0; t < p.tail.size(); ++t)
        visit(p.tail[t], p.head[t], p.weight[t]);
    });
  }

  /// the incidence lists of the graph `g` with the edge weights `weight`
  /// \throw std::invalid_argument (naming `solver`) if a weight is not finite
  /// \throw std::length_error if `g` has 2^32 - 1 vertices or more
  template <typename Graph, typename WeightMap>
  Incidence(const Graph& g, WeightMap weight, const char* solver)
  {
    const std::size_t n = std::size_t(num_vertices(g));
    if (n >= std::size_t(std::numeric_limits<std::uint32_t>::max()))
      throw std::length_error(std::string(solver) + ": too many vertices");
    auto index = get(boost::vertex_index, g);
    build(n, [&](auto&& visit) {
      typename boost::graph_traits<Graph>::edge_iterator it, end;
      for (boost::tie(it, end) = edges(g); it != end; ++it) {
        const double w = double(get(weight, *it));
        if (!std::isfinite(w))
          throw std::invalid_argument(std::string(solver) + ": an edge weight is not finite");
        visit(std::uint32_t(get(index, source(*it, g))), std::uint32_t(get(index, target(*it, g))), w);
      }
    });
  }

  /// the number of vertices
  std::size_t number_of_vertices() const { return first.size() - 1; }

private:
  /// Two passes over the edges given by `for_each_edge(visit)`, which calls
  /// visit(u, v, w) for each edge: count, then fill.
  template <typename ForEachEdge>
  void build(std::size_t n, const ForEachEdge& for_each_edge)
  {
    first.assign(n + 1, 0);
    for_each_edge([&](std::uint32_t u, std::uint32_t v, double w) {
      if (u != v && float(w) != 0.0f) {
        ++first[u + 1];
        ++first[v + 1];
      }
    });
    for (std::size_t i = 0; i < n; ++i)
      first[i + 1] += first[i];
    other.resize(first[n]);
    weight.resize(first[n]);
    std::vector<std::uint32_t> next(first.begin(), first.end() - 1);
    for_each_edge([&](std::uint32_t u, std::uint32_t v, double w) {
      if (u != v && float(w) != 0.0f) {
        other[next[u]] = v;
        weight[next[u]++] = float(w);
        other[next[v]] = u;
        weight[next[v]++] = float(w);
      }
    });
  }
};

/// Runs at most `sweeps` sweeps of single-vertex moves (iterated
/// conditional modes) in vertex order on `labels`: a vertex flips when its
/// edges and its unary preference weigh more against its label than for it.
/// No move raises the energy.  Returns the number of moves.
/// `preference` is empty or holds the unary preference of every vertex (see
/// `Array_problem`).
inline std::size_t improve_by_sweeps(const Incidence& inc, const std::vector<double>& preference,
                                     std::vector<Label>& labels, unsigned int sweeps)
{
  std::size_t moves = 0;
  const bool with_unary = !preference.empty();
  const std::size_t n = inc.number_of_vertices();
  for (unsigned int s = 0; s < sweeps; ++s) {
    std::size_t moved = 0;
    for (std::size_t i = 0; i < n; ++i) {
      double support = with_unary ? preference[i] : 0.0;
      for (std::uint32_t t = inc.first[i]; t < inc.first[i + 1]; ++t)
        support += double(inc.weight[t]) * double(labels[inc.other[t]]);
      if (support * double(labels[i]) < 0.0) {
        labels[i] = Label(-labels[i]);
        ++moved;
      }
    }
    moves += moved;
    if (moved == 0)
      break;
  }
  return moves;
}

/// An open-addressing hash map from a pair of segment numbers (a < b) to
/// the sum of the weights between them, in insertion order.
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

  /// adds `w` to the weight between `a` and `b`
  void add(std::uint32_t a, std::uint32_t b, double w)
  {
    const std::uint64_t key = make_key(a, b);
    for (std::size_t h = hash(key) & (m_slot.size() - 1);; h = (h + 1) & (m_slot.size() - 1)) {
      const std::uint32_t s = m_slot[h];
      if (s == empty) {
        m_slot[h] = std::uint32_t(m_key.size());
        m_key.push_back(key);
        m_weight.push_back(w);
        if (2 * m_key.size() > m_slot.size())
          grow();
        return;
      }
      if (m_key[s] == key) {
        m_weight[s] += w;
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
  std::vector<double> m_weight;
};

/// The thresholds of the segmentation (paper sec. 5.1, supplement eq. 5-7).
struct Segmentation_thresholds
{
  /// theta_S: the tolerated sum of contradicting votes, inside a segment
  /// and across segment borders
  double contradiction = 0.0;
  /// theta_acc: the smallest vote of a segment that a vertex may join
  double acceptance = 0.5;
};

/// A segmentation of a problem and the problem it reduces to.
struct Segment_reduction
{
  /// the segment of every vertex
  std::vector<std::uint32_t> segment;
  /// the reduced problem: one vertex per segment, edges summed over the
  /// segment pairs, unary preferences summed over the segments; its
  /// labelling all +1 is the starting labelling
  Array_problem reduced;
};

/// Segments `p` around the labelling `start` in vertex order, as the
/// paper's segmentation (sec. 5.1) with the preliminary orientation given by
/// `start`: in the frame where `start` is all +1 (vote(i, j) = w_ij * L_i *
/// L_j), vertex i joins the segment of its earlier neighbours whose vote is
/// largest among those that (intra-segment criterion) vote at least
/// theta_acc, with contradicting votes summing to at most theta_S, and
/// (inter-segment criterion) whose accumulated weight to every other
/// neighbouring segment t does not contradict i's vote for t by more than
/// theta_S; otherwise it opens a new segment.  Vertex i may not flip against
/// `start`, so `start` is a labelling of the reduced problem (all +1) and a
/// solver started there never ends above it.  A reduced labelling X maps
/// back to L_i = start_i * X_segment(i), with the same energy up to the
/// constant of the edges inside the segments.  Cost: O(V + E) expected.
/// `preference` is empty or holds the unary preference of every vertex (see
/// `Array_problem`).
inline Segment_reduction reduce_to_segments(const Incidence& inc, const std::vector<double>& preference,
                                            const std::vector<Label>& start,
                                            const Segmentation_thresholds& theta = Segmentation_thresholds())
{
  const std::size_t n = inc.number_of_vertices();
  const std::uint32_t unset = ~std::uint32_t(0);
  Segment_reduction r;
  r.segment.assign(n, unset);
  Segment_pair_weights between;
  struct Vote
  {
    std::uint32_t segment;
    double positive, negative;
  };
  std::vector<Vote> votes;
  std::uint32_t count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    votes.clear();
    for (std::uint32_t t = inc.first[i]; t < inc.first[i + 1]; ++t) {
      const std::uint32_t j = inc.other[t];
      if (r.segment[j] == unset)
        continue;
      const double v = double(inc.weight[t]) * double(start[i]) * double(start[j]);
      auto it = std::find_if(votes.begin(), votes.end(),
                             [&](const Vote& x) { return x.segment == r.segment[j]; });
      if (it == votes.end())
        it = votes.insert(votes.end(), Vote{r.segment[j], 0.0, 0.0});
      (v > 0.0 ? it->positive : it->negative) += v;
    }
    std::uint32_t best = unset;
    double best_vote = theta.acceptance;
    for (const Vote& s : votes) {
      const double vote = s.positive + s.negative;
      if (vote < best_vote || -s.negative > theta.contradiction || (best != unset && vote == best_vote))
        continue;
      bool valid = true;
      for (const Vote& t : votes) {
        if (t.segment == s.segment)
          continue;
        const double a = t.positive + t.negative;
        const double w = between.get(s.segment, t.segment);
        if (w != 0.0 && a != 0.0 && ((w > 0.0) != (a > 0.0)) && std::abs(a) > theta.contradiction) {
          valid = false;
          break;
        }
      }
      if (valid) {
        best = s.segment;
        best_vote = vote;
      }
    }
    if (best == unset)
      best = count++;
    r.segment[i] = best;
    for (const Vote& t : votes)
      if (t.segment != best)
        between.add(best, t.segment, t.positive + t.negative);
  }

  Array_problem& q = r.reduced;
  q.number_of_vertices = count;
  q.tail.reserve(between.size());
  q.head.reserve(between.size());
  q.weight.reserve(between.size());
  for (std::size_t s = 0; s < between.size(); ++s)
    if (between.weight(s) != 0.0) {
      q.tail.push_back(between.first(s));
      q.head.push_back(between.second(s));
      q.weight.push_back(between.weight(s));
    }
  if (!preference.empty()) {
    q.preference.assign(count, 0.0);
    for (std::size_t i = 0; i < n; ++i)
      q.preference[r.segment[i]] += preference[i] * double(start[i]);
  }
  return r;
}

} // namespace internal
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_GRAPH_REDUCTION_H
