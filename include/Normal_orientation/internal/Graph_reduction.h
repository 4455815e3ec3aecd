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
#include <Normal_orientation/Segmenter.h>

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

  /// no vertices (an object to assign lists to)
  Incidence() : first(1, 0) {}

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

/// the thresholds of the segmentation
typedef Segmentation_thresholds Segmentation_thresholds;

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

/// Segments the problem of `inc` around the labelling `start` in vertex
/// order, with the paper's segmentation (`Segmenter`) in the
/// frame where `start` is all +1 (vote(i, j) = w_ij * L_i * L_j), and
/// without flips (`may_flip = false`): vertex i joins the segment of its
/// earlier neighbours whose vote is largest among the valid ones, or opens
/// a new segment.  So `start` is a labelling of the reduced problem (all
/// +1) and a solver started there never ends above it.  A reduced
/// labelling X maps back to L_i = start_i * X_segment(i), with the same
/// energy up to the constant of the edges inside the segments.
/// `preference` is empty or holds the unary preference of every vertex (see
/// `Array_problem`).  Cost: O(V + E) expected.
inline Segment_reduction reduce_to_segments(const Incidence& inc, const std::vector<double>& preference,
                                            const std::vector<Label>& start,
                                            const Segmentation_thresholds& theta = Segmentation_thresholds())
{
  const std::size_t n = inc.number_of_vertices();
  Segment_reduction r;
  r.segment.assign(n, 0);
  Segmenter segmenter(theta, false);
  std::vector<Neighbor_vote> votes;
  for (std::size_t i = 0; i < n; ++i) {
    votes.clear();
    for (std::uint32_t t = inc.first[i]; t < inc.first[i + 1]; ++t) {
      const std::uint32_t j = inc.other[t];
      if (j < i)
        votes.push_back({r.segment[j], double(inc.weight[t]) * double(start[i]) * double(start[j])});
    }
    r.segment[i] = segmenter.add_point(votes, preference.empty() ? 0.0 : preference[i] * double(start[i])).segment;
  }

  const Segment_pair_weights& between = segmenter.segment_pairs();
  Array_problem& q = r.reduced;
  q.number_of_vertices = segmenter.number_of_segments();
  q.tail.reserve(between.size());
  q.head.reserve(between.size());
  q.weight.reserve(between.size());
  for (std::size_t s = 0; s < between.size(); ++s)
    if (between.weight(s) != 0.0) {
      q.tail.push_back(between.first(s));
      q.head.push_back(between.second(s));
      q.weight.push_back(between.weight(s));
    }
  if (!preference.empty())
    q.preference = segmenter.segment_preferences();
  return r;
}

/// The segments of the labelling `labels` on the graph of incidence lists
/// `inc` (`reduce_to_segments()`: the paper's segmentation with its default
/// thresholds, in vertex order, in the frame where `labels` is all +1):
/// regions that the labelling made consistent, as the streamed driver's
/// final segments are.  Writes the segment of every vertex to `segment`;
/// returns their number.
inline std::size_t labelling_segments(const Incidence& inc, const std::vector<Label>& labels,
                                      std::vector<std::uint32_t>& segment)
{
  Segment_reduction r = reduce_to_segments(inc, std::vector<double>(), labels);
  segment = std::move(r.segment);
  return r.reduced.number_of_vertices;
}

} // namespace internal
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_GRAPH_REDUCTION_H
