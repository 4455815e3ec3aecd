// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_SOLVERS_MST_SOLVER_H
#define NORMAL_ORIENTATION_SOLVERS_MST_SOLVER_H

/// \file Mst_solver.h
/// The maximum-spanning-tree solver on the signed union-find (supplement,
/// Algorithm 1).

#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Signed_union_find.h>
#include <Normal_orientation/solvers/Orientation_solver_base.h>
#include <Normal_orientation/solvers/Solver_report.h>

#include <boost/graph/graph_traits.hpp>
#include <boost/property_map/property_map.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationSolvers
/// Kruskal's maximum spanning forest with respect to |w|, propagating the
/// orientation while the forest grows (supplement, Algorithm 1): edges are
/// taken in decreasing |w|; an edge that joins two components first flips
/// one of them, in constant time on the signed union-find, if the edge's
/// wish is not met, then merges them.  Edges inside a component are
/// ignored, which is why the result can be far from optimal when strong
/// edges contradict many weaker ones (paper, Figure 2).  It is exact when
/// the problem is balanced (some labelling meets every edge).
///
/// Edges of weight zero carry no information and are skipped, so each
/// component of the result is a component of the non-zero edges.  Edges are
/// ranked by |w| rounded to single precision; equal ranks are taken in the
/// order of `edges(g)`, so the result is deterministic, whatever the number
/// of threads.  The global sign of every component is left as it comes
/// (see `Component_sign.h`); vertices without edges get +1.
///
/// After the forest, `local_sweeps` sweeps of single-vertex moves follow
/// (iterated conditional modes): in vertex order, a vertex flips when the
/// edges at it weigh more against its label than for it.  A move never
/// raises the energy (up to the single-precision rounding of the weights
/// used for ranking), and all the edges at a vertex vote, where the forest
/// listened to one; on the benchmark clouds this removes about 5% of the
/// wrong normals left by the forest, and it finds the optimum of the
/// paper's Figure 2 example.  With `local_sweeps = 0` the solver is
/// exactly the paper's Algorithm 1.
///
/// <b>Unary terms.</b>  `solve()` also accepts unary terms (user
/// constraints).  They are reduced exactly to edges to one extra "ground"
/// vertex n whose label is +1: the costs (c+, c-) of vertex i are the
/// constant min(c+, c-) plus `edge_energy(c- - c+, L_i, +1)`, an edge of
/// signed weight c- - c+ between i and n (none when c+ = c-).  These edges
/// are ranked with the others (after the edges of `g` of the same rank) and
/// the same algorithm runs on the n + 1 vertices; then, if the ground came
/// out -1, every vertex of its tree flips (which does not change the energy
/// of the tree's edges), and the sweeps never move the ground but count its
/// edges at every other vertex.  So a vertex whose unary cost difference
/// exceeds the sum of the |w| of its edges ends with its cheaper label (up
/// to the single-precision rounding of the ranks and sweeps);
/// conflicting constraints are decided by the forest, strongest first.
/// With zero unary terms the labels are those of the solve without them.
///
/// <b>Contract of `solve()`</b> (both calls, see `Orientation_solver_base`).
/// The minimum is heuristic.  Unary costs may be negative; a vertex whose
/// two costs are equal is unconstrained.  With unary terms,
/// `Solver_report::energy` includes the unary costs,
/// `Solver_report::iterations` counts the ground edges too, and
/// `Solver_report::tree_edges` and `Solver_report::frustrated_edges` count
/// the edges of `g` only.  Throws `std::invalid_argument` if a unary cost is
/// not finite.
///
/// Cost: O(E) for the sort (radix), then O(E alpha(V)), then O(E) per sweep.
/// Memory: about 24 bytes per edge and 7 bytes per vertex during the solve
/// (with unary terms: plus about 40 bytes per vertex whose two costs
/// differ, and 16 bytes per vertex while the costs are read).
/// \cgalModels `OrientationSolver`
class Mst_solver : public Orientation_solver_base<Mst_solver>
{
public:
  /// the name used on the command line and in reports
  static const char* name() { return "mst"; }

  /// the number of sweeps of single-vertex moves after the spanning forest
  /// (0: the paper's Algorithm 1 alone); sweeps stop early when nothing moves
  unsigned int local_sweeps = 3;

  /// the solver with `sweeps` sweeps of single-vertex moves
  explicit Mst_solver(unsigned int sweeps = 3) : local_sweeps(sweeps) {}

private:
  /// \cond SKIP_IN_MANUAL
  friend class Orientation_solver_base<Mst_solver>; // calls solve_impl()
  /// \endcond

  /// the top bit of `Sorted_edge::head`: the weight is negative
  static constexpr std::uint32_t negative_bit = 0x80000000u;

  /// an informative edge: complement of the float bits of |w| (so that
  /// larger |w| sorts first), ends, and the sign of w in the head's top bit
  struct Sorted_edge
  {
    std::uint32_t key, tail, head;
  };

  /// the edge of signed weight `w` != 0 between `u` and `v`, with its key
  static Sorted_edge make_sorted_edge(double w, std::uint32_t u, std::uint32_t v)
  {
    float a = float(std::abs(w));
    std::uint32_t bits;
    std::memcpy(&bits, &a, sizeof bits);
    return {~bits, u, v | (w < 0.0 ? negative_bit : 0u)};
  }

  /// The solve, without unary terms when `UnaryMap` is `internal::No_unary`
  /// (then vertex n, the ground, does not exist).
  template <typename Graph, typename WeightMap, typename UnaryMap, typename LabelMap>
  Solver_report solve_impl(const Graph& g, WeightMap weight, UnaryMap unary, LabelMap labels) const
  {
    constexpr bool with_unary = !std::is_same<UnaryMap, internal::No_unary>::value;
    const auto start = std::chrono::steady_clock::now();
    typedef typename boost::graph_traits<Graph>::edge_iterator edge_iterator;
    const std::size_t n = num_vertices(g);
    auto index = get(boost::vertex_index, g);

    // 1. Gather the informative edges with a 32-bit sort key: the
    //    complement of |w| as float bits, so that larger |w| comes first.
    //    The sign of w is kept in the top bit of the head.  The ends travel
    //    with the key, so the Kruskal loop below reads the edges
    //    sequentially.
    if (n + (with_unary ? 1 : 0) >= std::size_t(negative_bit))
      throw std::length_error(with_unary ? "Mst_solver: more than 2^31 - 2 vertices with unary terms"
                                         : "Mst_solver: more than 2^31 - 1 vertices");
    std::vector<Sorted_edge> sorted;
    sorted.reserve(std::size_t(num_edges(g)) + (with_unary ? n : 0));
    edge_iterator it, end;
    for (boost::tie(it, end) = edges(g); it != end; ++it) {
      const double w = double(get(weight, *it));
      if (!(w != 0.0))
        continue; // zero (or NaN) weights carry no information
      const std::size_t u = std::size_t(get(index, source(*it, g)));
      const std::size_t v = std::size_t(get(index, target(*it, g)));
      if (u == v)
        continue;
      sorted.push_back(make_sorted_edge(w, std::uint32_t(u), std::uint32_t(v)));
    }
    // With unary terms, the costs (c+, c-) of vertex i are the constant
    // min(c+, c-) plus edge_energy(c- - c+, L_i, L_n) with the ground vertex
    // n labelled +1: an edge of signed weight c- - c+ from i to n.
    const std::uint32_t ground = std::uint32_t(n);
    if constexpr (with_unary) {
      const std::vector<std::pair<double, double>> costs = internal::unary_costs(g, unary, "Mst_solver");
      for (std::size_t i = 0; i < n; ++i) {
        const double w = costs[i].second - costs[i].first;
        if (w != 0.0)
          sorted.push_back(make_sorted_edge(w, std::uint32_t(i), ground));
      }
    } else
      (void)unary;
    const std::size_t vertex_count = n + (with_unary ? 1 : 0);

    // 2. Sort by decreasing |w|, ties in the order of edges(g): a stable
    //    least-significant-digit radix sort on the key, two 16-bit digits.
    //    The order is fully determined, whatever the number of threads.
    {
      std::vector<Sorted_edge> buffer(sorted.size());
      std::vector<std::size_t> bucket_start(std::size_t(1) << 16);
      for (int shift = 0; shift < 32; shift += 16) {
        std::fill(bucket_start.begin(), bucket_start.end(), std::size_t(0));
        for (const Sorted_edge& e : sorted)
          ++bucket_start[(e.key >> shift) & 0xffffu];
        std::size_t sum = 0;
        for (std::size_t& c : bucket_start) {
          const std::size_t count = c;
          c = sum;
          sum += count;
        }
        for (const Sorted_edge& e : sorted)
          buffer[bucket_start[(e.key >> shift) & 0xffffu]++] = e;
        sorted.swap(buffer);
      }
    }

    // 3. Kruskal with orientation propagation on the signed union-find.
    Signed_union_find uf(vertex_count);
    Solver_report report;
    for (const Sorted_edge& e : sorted) {
      const std::uint32_t u = e.tail, v = e.head & ~negative_bit;
      bool su, sv;
      const auto ru = uf.find(u, su), rv = uf.find(v, sv);
      if (ru == rv)
        continue;
      if ((su != sv) != ((e.head & negative_bit) != 0))
        uf.flip_root(rv);
      uf.unite_roots(ru, rv);
      if constexpr (with_unary)
        report.tree_edges += (v != ground);
      else
        ++report.tree_edges;
    }
    report.iterations = sorted.size();

    // 4. Labels, then energy and frustrated edges in one pass.  With unary
    //    terms the ground must be +1: its tree is flipped if needed (the
    //    energy of a tree does not change when all its labels flip).
    std::vector<Label> label(vertex_count);
    for (std::size_t i = 0; i < vertex_count; ++i)
      label[i] = Label(uf.sign(std::uint32_t(i)) ? -1 : 1);
    if constexpr (with_unary) {
      if (label[ground] < 0) {
        const auto ground_root = uf.find(ground);
        for (std::size_t i = 0; i < vertex_count; ++i)
          if (uf.find(std::uint32_t(i)) == ground_root)
            label[i] = Label(-label[i]);
      }
    }
    // the sweeps never move the ground (vertex n), but see its edges
    if (local_sweeps > 0)
      report.iterations += improve_vertices(vertex_count, n, sorted, label);
    typename boost::graph_traits<Graph>::vertex_iterator vit, vend;
    for (boost::tie(vit, vend) = vertices(g); vit != vend; ++vit)
      put(labels, *vit, label[std::size_t(get(index, *vit))]);
    for (const Sorted_edge& e : sorted) {
      const bool negative = (e.head & negative_bit) != 0;
      const std::uint32_t v = e.head & ~negative_bit;
      if constexpr (with_unary)
        if (v == ground)
          continue;
      if ((label[e.tail] == label[v]) == negative)
        ++report.frustrated_edges;
    }
    return internal::complete_report(report, g, weight, unary, labels, start);
  }

  /// the signed weight of `e`, as ranked (single precision)
  static float signed_weight(const Sorted_edge& e)
  {
    const std::uint32_t bits = ~e.key;
    float a;
    std::memcpy(&a, &bits, sizeof a);
    return (e.head & negative_bit) ? -a : a;
  }

  /// Runs up to `local_sweeps` sweeps of single-vertex moves in vertex
  /// order on the `n` vertices of `edges`, of which only the first
  /// `movable` may move; returns the number of moves.
  std::size_t improve_vertices(std::size_t n, std::size_t movable, const std::vector<Sorted_edge>& edges,
                               std::vector<Label>& label) const
  {
    // Incidence lists of the informative edges (both directions).
    std::vector<std::uint32_t> first(n + 1, 0);
    for (const Sorted_edge& e : edges) {
      ++first[e.tail + 1];
      ++first[(e.head & ~negative_bit) + 1];
    }
    for (std::size_t i = 0; i < n; ++i)
      first[i + 1] += first[i];
    std::vector<std::pair<std::uint32_t, float>> incident(first[n]);
    {
      std::vector<std::uint32_t> next(first.begin(), first.end() - 1);
      for (const Sorted_edge& e : edges) {
        const std::uint32_t v = e.head & ~negative_bit;
        const float w = signed_weight(e);
        incident[next[e.tail]++] = {v, w};
        incident[next[v]++] = {e.tail, w};
      }
    }
    // Flipping i changes the energy by sum_j w_ij L_i L_j: flip when < 0.
    std::size_t moves = 0;
    for (unsigned int sweep = 0; sweep < local_sweeps; ++sweep) {
      std::size_t moved = 0;
      for (std::size_t i = 0; i < movable; ++i) {
        double support = 0.0;
        for (std::uint32_t t = first[i]; t < first[i + 1]; ++t)
          support += double(incident[t].second) * double(label[incident[t].first]);
        if (support * double(label[i]) < 0.0) {
          label[i] = Label(-label[i]);
          ++moved;
        }
      }
      moves += moved;
      if (moved == 0)
        break;
    }
    return moves;
  }
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_SOLVERS_MST_SOLVER_H
