// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_SOLVERS_MST_SOLVER_H
#define NORMAL_ORIENTATION_SOLVERS_MST_SOLVER_H

/// \file Mst_solver.h
/// The maximum-spanning-tree solver on the signed union-find (supplement,
/// Algorithm 1).

#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Signed_union_find.h>
#include <Normal_orientation/internal/Graph_reduction.h>
#include <Normal_orientation/solvers/Orientation_solver_base.h>
#include <Normal_orientation/solvers/Solver_report.h>

#include <boost/graph/graph_traits.hpp>
#include <boost/property_map/property_map.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <tuple>
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
/// (iterated conditional modes, `internal::improve_by_sweeps()`): in vertex
/// order, a vertex flips when the edges at it (in single precision) weigh
/// more against its label than for it.  A move never raises the energy (up
/// to that rounding), and all the edges at a vertex vote, where the forest
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
/// of the tree's edges); the sweeps weigh c- - c+ for label +1 at every
/// vertex, with its edges.  So a vertex whose unary cost difference
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
/// the edges of `g` only.  Throws `std::invalid_argument` if an edge weight
/// or a unary cost is not finite.
///
/// Cost: O(E) for the sort (radix), then O(E alpha(V)), then O(E) per sweep.
/// Memory: about 24 bytes per edge during the sort, 12 per edge and 7 per
/// vertex during the forest, then 16 per edge and 5 per vertex during the
/// sweeps; with unary terms, plus 8 bytes per vertex (24 while the costs
/// are read), and the edges to the ground count as edges.
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
  friend class Qpbo_i_solver;                       // keeps the incidence lists (solve_forest())
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

  /// The solve, without unary terms when `UnaryMap` is `internal::No_unary`.
  template <typename Graph, typename WeightMap, typename UnaryMap, typename LabelMap>
  Solver_report solve_impl(const Graph& g, WeightMap weight, UnaryMap unary, LabelMap labels) const
  {
    return solve_forest(g, weight, unary, labels, nullptr);
  }

  /// The informative edges of `g` (and, with unary terms, the edges to the
  /// ground vertex n of weight `preference[i]`), sorted by decreasing |w|
  /// rounded to single precision, ties in the order of `edges(g)`.
  template <typename Graph, typename WeightMap>
  static std::vector<Sorted_edge> sorted_edges(const Graph& g, WeightMap weight,
                                               const std::vector<double>& preference)
  {
    // 1. A 32-bit sort key per edge: the complement of |w| as float bits, so
    //    that larger |w| comes first.  The sign of w is kept in the top bit
    //    of the head.  The ends travel with the key, so the Kruskal loop
    //    reads the edges sequentially.
    const std::size_t n = num_vertices(g);
    auto index = get(boost::vertex_index, g);
    std::vector<Sorted_edge> sorted;
    sorted.reserve(std::size_t(num_edges(g)) + preference.size());
    typename boost::graph_traits<Graph>::edge_iterator it, end;
    for (boost::tie(it, end) = edges(g); it != end; ++it) {
      const double w = double(get(weight, *it));
      if (!std::isfinite(w))
        throw std::invalid_argument("Mst_solver: an edge weight is not finite");
      const std::size_t u = std::size_t(get(index, source(*it, g)));
      const std::size_t v = std::size_t(get(index, target(*it, g)));
      if (w != 0.0 && u != v) // zero weights carry no information
        sorted.push_back(make_sorted_edge(w, std::uint32_t(u), std::uint32_t(v)));
    }
    for (std::size_t i = 0; i < preference.size(); ++i)
      if (preference[i] != 0.0)
        sorted.push_back(make_sorted_edge(preference[i], std::uint32_t(i), std::uint32_t(n)));
    // 2. A stable least-significant-digit radix sort on the key, two 16-bit
    //    digits: the order is fully determined, whatever the number of
    //    threads.
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
    return sorted;
  }

  /// The solve; with `incidence` not null, the incidence lists of (`g`,
  /// `weight`) that the sweeps ran on are left in `*incidence` (built even
  /// without sweeps), for a caller that sweeps again.
  template <typename Graph, typename WeightMap, typename UnaryMap, typename LabelMap>
  Solver_report solve_forest(const Graph& g, WeightMap weight, UnaryMap unary, LabelMap labels,
                             internal::Incidence* incidence) const
  {
    constexpr bool with_unary = !std::is_same<UnaryMap, internal::No_unary>::value;
    const auto start = std::chrono::steady_clock::now();
    const std::size_t n = num_vertices(g);
    if (n + (with_unary ? 1 : 0) >= std::size_t(negative_bit))
      throw std::length_error(with_unary ? "Mst_solver: more than 2^31 - 2 vertices with unary terms"
                                         : "Mst_solver: more than 2^31 - 1 vertices");
    // With unary terms, the costs (c+, c-) of vertex i are the constant
    // min(c+, c-) plus edge_energy(c- - c+, L_i, L_n) with the ground vertex
    // n labelled +1: an edge of signed weight c- - c+ from i to n.
    const std::vector<double> preference = internal::unary_preferences(g, unary, "Mst_solver");
    std::vector<Sorted_edge> sorted = sorted_edges(g, weight, preference);
    const std::size_t vertex_count = n + (with_unary ? 1 : 0);
    const std::uint32_t ground = std::uint32_t(n);

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
      report.tree_edges += (!with_unary || v != ground) ? 1 : 0;
    }
    report.iterations = sorted.size();
    std::vector<Sorted_edge>().swap(sorted);

    // 4. Labels.  With unary terms the ground must be +1: its tree is
    //    flipped if needed (the energy of a tree does not change when all
    //    its labels flip).
    std::vector<Label> label(vertex_count);
    for (std::size_t i = 0; i < vertex_count; ++i)
      label[i] = Label(uf.sign(std::uint32_t(i)) ? -1 : 1);
    if (with_unary && label[ground] < 0) {
      const auto ground_root = uf.find(ground);
      for (std::size_t i = 0; i < vertex_count; ++i)
        if (uf.find(std::uint32_t(i)) == ground_root)
          label[i] = Label(-label[i]);
    }
    label.resize(n);

    // 5. Sweeps of single-vertex moves, the unary terms as preferences.
    if (local_sweeps > 0 || incidence) {
      internal::Incidence own;
      internal::Incidence& inc = incidence ? *incidence : own;
      inc = internal::Incidence(g, weight, "Mst_solver");
      if (local_sweeps > 0)
        report.iterations += internal::improve_by_sweeps(inc, preference, label, local_sweeps);
    }
    std::tie(report.energy, report.frustrated_edges) = internal::write_labels(g, weight, unary, label, labels);
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
  }
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_SOLVERS_MST_SOLVER_H
