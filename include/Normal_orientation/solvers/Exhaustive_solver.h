// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_SOLVERS_EXHAUSTIVE_SOLVER_H
#define NORMAL_ORIENTATION_SOLVERS_EXHAUSTIVE_SOLVER_H

/// \file Exhaustive_solver.h
/// The exact solver by enumeration, for small problems: the oracle the
/// other solvers are tested against.

#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/solvers/Orientation_solver_base.h>
#include <Normal_orientation/solvers/Solver_report.h>

#include <boost/graph/graph_traits.hpp>
#include <boost/graph/properties.hpp>
#include <boost/property_map/property_map.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationSolvers
/// The exact minimum of the orientation energy by enumeration of the
/// labellings, for small problems: the test oracle of the other solvers.
///
/// The energy is separable over the connected components of the edges of
/// non-zero weight (numbered as by `connected_components()`), so each
/// component is enumerated on its own: ten components of ten vertices cost
/// 10 * 2^9 states, not 2^99.  Without unary terms, E(L) = E(-L), so the
/// first (smallest-index) vertex of every component is fixed to +1 and the
/// other k - 1 vertices of a component of k vertices are enumerated:
/// 2^(k-1) states; a vertex without informative edges gets +1.  With unary
/// terms the symmetry is lost and the k vertices are enumerated: 2^k states.
///
/// <b>Enumeration order and ties.</b>  The states of a component are visited
/// in binary reflected Gray code order, so that one label flips per step and
/// the energy is updated in O(degree) on an internal incidence structure.
/// Let v_0 < v_1 < ... < v_(k-1) be the vertices of the component: the
/// enumeration starts from all labels +1, and step t = 1, 2, ... flips the
/// vertex of bit b = (number of trailing zeros of t), where bit b stands for
/// v_(b+1) for b < k - 1 and, with unary terms only, bit k - 1 stands for
/// v_0.  Among the optimal labellings of a component, the first one visited
/// is returned; the result is deterministic.  With unary terms, the first
/// 2^(k-1) states are exactly the states enumerated without them, so zero
/// unary terms give the same labels as no unary terms.
///
/// <b>Arithmetic.</b>  To make comparisons (hence ties) exact and free of
/// drift over up to 2^29 incremental updates, the energy is accumulated in
/// 64-bit fixed point: in a component, every weight and unary cost is
/// rounded to a multiple of 2^-s, with s the largest integer such that the
/// sum T of their absolute values is below 2^61 * 2^-s.  The rounding is
/// exact for every term of magnitude at least 2^-8 T (and for smaller ones
/// with short mantissas); otherwise it moves a term by at most 2^-61 T, so
/// the labelling returned is optimal up to (number of terms) * 2^-60 T.
/// The energy in the report is recomputed in double precision with
/// `energy()`.  Edges of weight zero and self-loops (whose term does not
/// depend on the labels) are ignored by the enumeration, not by the report.
///
/// <b>Contract of `solve()`</b> (both calls, see `Orientation_solver_base`).
/// The minimum is exact.  `Solver_report::iterations` is the number of
/// states visited, summed over the components: 2^(k-1) for a component of k
/// vertices (1 for a vertex without informative edges), 2^k with unary
/// terms.  Unary costs may be negative.  Throws `std::length_error` if a
/// connected component of the edges of non-zero weight has more than
/// `maximum_vertices` vertices, `std::invalid_argument` if a weight or a
/// unary cost is not finite.
///
/// Cost: O(sum over the components of 2^(k-1) * average degree), plus
/// O(V + E).  Components larger than `maximum_vertices` are refused.
/// \cgalModels `OrientationSolver`
class Exhaustive_solver : public Orientation_solver_base<Exhaustive_solver>
{
public:
  /// the name used on the command line and in reports
  static const char* name() { return "exhaustive"; }

  /// the largest component, in vertices, the solver accepts (the
  /// enumeration of a component of k vertices visits 2^(k-1) states, 2^k
  /// with unary terms: 26 vertices take about 0.1 to 1 second, 30 vertices
  /// 3 to 20 seconds); values above 62 act as 62
  unsigned int maximum_vertices = 30;

  /// the solver accepting components of at most `maximum` vertices
  explicit Exhaustive_solver(unsigned int maximum = 30) : maximum_vertices(maximum) {}

private:
  /// \cond SKIP_IN_MANUAL
  friend class Orientation_solver_base<Exhaustive_solver>; // calls solve_impl()
  /// \endcond

  /// the hard limit on the size of a component (states fit in 64 bits)
  static constexpr unsigned int hard_maximum_vertices = 62;

  /// a neighbour in the incidence lists, with the weight of the edge
  struct Incidence
  {
    std::uint32_t other;
    double weight;
  };

  /// the number of trailing zero bits of `t` > 0
  static unsigned int trailing_zeros(std::uint64_t t)
  {
#if defined(__GNUC__) || defined(__clang__)
    return unsigned(__builtin_ctzll(t));
#else
    unsigned int b = 0;
    while ((t & 1u) == 0) {
      t >>= 1;
      ++b;
    }
    return b;
#endif
  }

  /// `x` rounded to a multiple of 2^-shift, in units of 2^-shift
  static std::int64_t fixed(double x, int shift) { return std::int64_t(std::llround(std::ldexp(x, shift))); }

  template <typename Graph, typename WeightMap, typename UnaryMap, typename LabelMap>
  Solver_report solve_impl(const Graph& g, WeightMap weight, UnaryMap unary, LabelMap labels) const
  {
    constexpr bool with_unary = !std::is_same<UnaryMap, internal::No_unary>::value;
    const auto start = std::chrono::steady_clock::now();
    const std::size_t n = num_vertices(g);
    auto index = get(boost::vertex_index, g);
    if (n >= std::size_t(~std::uint32_t(0)))
      throw std::length_error("Exhaustive_solver: more than 2^32 - 2 vertices");

    // 1. The informative edges (non-zero weight, not self-loops).
    struct Edge
    {
      std::uint32_t u, v;
      double w;
    };
    std::vector<Edge> informative;
    typename boost::graph_traits<Graph>::edge_iterator eit, eend;
    for (boost::tie(eit, eend) = edges(g); eit != eend; ++eit) {
      const double w = double(get(weight, *eit));
      if (!std::isfinite(w))
        throw std::invalid_argument("Exhaustive_solver: an edge weight is not finite");
      const std::size_t u = std::size_t(get(index, source(*eit, g)));
      const std::size_t v = std::size_t(get(index, target(*eit, g)));
      if (w != 0.0 && u != v)
        informative.push_back({std::uint32_t(u), std::uint32_t(v), w});
    }

    // 2. Unary costs by vertex index: [+1 cost, -1 cost].
    std::vector<std::pair<double, double>> costs;
    typename boost::graph_traits<Graph>::vertex_iterator vit, vend;
    if constexpr (with_unary) {
      costs.assign(n, std::pair<double, double>(0.0, 0.0));
      for (boost::tie(vit, vend) = vertices(g); vit != vend; ++vit) {
        const auto& c = get(unary, *vit);
        const double plus = double(c.first), minus = double(c.second);
        if (!std::isfinite(plus) || !std::isfinite(minus))
          throw std::invalid_argument("Exhaustive_solver: a unary cost is not finite");
        costs[std::size_t(get(index, *vit))] = {plus, minus};
      }
    }

    // 3. Components (numbered by smallest vertex), their vertices in
    //    increasing index order, and the size check before any work.
    std::vector<std::uint32_t> component;
    const std::size_t count = connected_components(g, weight, component);
    std::vector<std::size_t> first(count + 1, 0);
    for (std::size_t i = 0; i < n; ++i)
      ++first[component[i] + 1];
    for (std::size_t c = 0; c < count; ++c) {
      const std::size_t size = first[c + 1];
      if (size > maximum_vertices || size > hard_maximum_vertices)
        throw std::length_error("Exhaustive_solver: a connected component has " + std::to_string(size) +
                                " vertices, more than maximum_vertices = " +
                                std::to_string(std::min(maximum_vertices, hard_maximum_vertices)) +
                                " (its enumeration would visit 2^" + std::to_string(with_unary ? size : size - 1) +
                                " labellings)");
      first[c + 1] += first[c];
    }
    std::vector<std::uint32_t> members(n);
    {
      std::vector<std::size_t> next(first.begin(), first.end() - 1);
      for (std::size_t i = 0; i < n; ++i)
        members[next[component[i]]++] = std::uint32_t(i);
    }

    // 4. Incidence lists of the informative edges, both directions.
    std::vector<std::size_t> first_incidence(n + 1, 0);
    for (const Edge& e : informative) {
      ++first_incidence[e.u + 1];
      ++first_incidence[e.v + 1];
    }
    for (std::size_t i = 0; i < n; ++i)
      first_incidence[i + 1] += first_incidence[i];
    std::vector<Incidence> incidence(first_incidence[n]);
    {
      std::vector<std::size_t> next(first_incidence.begin(), first_incidence.end() - 1);
      for (const Edge& e : informative) {
        incidence[next[e.u]++] = {e.v, e.w};
        incidence[next[e.v]++] = {e.u, e.w};
      }
    }

    // 5. Enumerate each component.
    std::vector<Label> label(n, Label(1));
    std::vector<std::uint32_t> local(n, 0);
    Component_state state;
    Solver_report report;
    for (std::size_t c = 0; c < count; ++c) {
      const std::uint32_t* vs = members.data() + first[c];
      const std::size_t k = first[c + 1] - first[c];
      if (k == 1 && !with_unary) {
        ++report.iterations; // the single state: +1
        continue;
      }
      for (std::size_t a = 0; a < k; ++a)
        local[vs[a]] = std::uint32_t(a);
      // the scale: the sum of the magnitudes of the terms below 2^61
      double total = 0.0;
      for (std::size_t a = 0; a < k; ++a) {
        for (std::size_t t = first_incidence[vs[a]]; t < first_incidence[vs[a] + 1]; ++t)
          total += 0.5 * std::abs(incidence[t].weight); // every edge is seen twice
        if constexpr (with_unary)
          total += std::abs(costs[vs[a]].first) + std::abs(costs[vs[a]].second);
      }
      if (!std::isfinite(total))
        throw std::invalid_argument("Exhaustive_solver: the terms of a component overflow a double");
      int exponent = 0;
      if (total > 0.0)
        std::frexp(total, &exponent); // total < 2^exponent
      const int shift = 61 - exponent;
      // the local incidence structure, in the bit order of the enumeration:
      // bit b is vertex vs[b + 1] for b < k - 1 and vs[0] for b = k - 1
      const std::size_t bits = with_unary ? k : k - 1;
      state.start.assign(k + 1, 0);
      state.other.clear();
      state.weight.clear();
      state.unary_delta.assign(k, 0);
      for (std::size_t b = 0; b < k; ++b) {
        const std::uint32_t v = vs[(b + 1) % k];
        for (std::size_t t = first_incidence[v]; t < first_incidence[v + 1]; ++t) {
          const std::uint32_t a = local[incidence[t].other];
          state.other.push_back(a == 0 ? std::uint32_t(k - 1) : a - 1);
          state.weight.push_back(fixed(incidence[t].weight, shift));
        }
        state.start[b + 1] = state.other.size();
        if constexpr (with_unary)
          // change of the unary term when the vertex goes from +1 to -1
          state.unary_delta[b] = fixed(costs[v].second, shift) - fixed(costs[v].first, shift);
      }
      const std::uint64_t best = enumerate<with_unary>(state, bits);
      report.iterations += std::size_t(1) << bits;
      const std::uint64_t gray = best ^ (best >> 1);
      for (std::size_t b = 0; b < bits; ++b)
        label[vs[(b + 1) % k]] = (gray >> b) & 1u ? Label(-1) : Label(1);
    }

    // 6. Labels, then the report in double precision.
    for (boost::tie(vit, vend) = vertices(g); vit != vend; ++vit)
      put(labels, *vit, label[std::size_t(get(index, *vit))]);
    for (const Edge& e : informative)
      if ((label[e.u] == label[e.v]) != (e.w > 0.0))
        ++report.frustrated_edges;
    return internal::complete_report(report, g, weight, unary, labels, start);
  }

  /// the incidence structure of one component in fixed point, by bit
  struct Component_state
  {
    std::vector<std::size_t> start;
    std::vector<std::uint32_t> other;
    std::vector<std::int64_t> weight;
    std::vector<std::int64_t> unary_delta;
    std::vector<std::int64_t> label;
  };

  /// Visits the 2^bits states of a component in Gray code order, from all
  /// labels +1; returns the step t of the first state of minimum energy.
  template <bool with_unary>
  static std::uint64_t enumerate(Component_state& s, std::size_t bits)
  {
    const std::size_t k = s.start.size() - 1;
    s.label.assign(k, 1);
    std::int64_t* const label = s.label.data();
    const std::size_t* const start = s.start.data();
    const std::uint32_t* const other = s.other.data();
    const std::int64_t* const weight = s.weight.data();
    const std::int64_t* const unary_delta = s.unary_delta.data();
    (void)unary_delta; // unused without unary terms
    // the energy relative to the all +1 state
    std::int64_t energy = 0, best = 0;
    std::uint64_t best_step = 0;
    const std::uint64_t states = std::uint64_t(1) << bits;
    for (std::uint64_t t = 1; t < states; ++t) {
      const unsigned int b = trailing_zeros(t);
      // flipping L_b changes every edge term at b by w L_b L_j
      std::int64_t support = 0;
      for (std::size_t i = start[b]; i < start[b + 1]; ++i)
        support += weight[i] * label[other[i]];
      std::int64_t delta = support * label[b];
      if constexpr (with_unary)
        delta += label[b] * unary_delta[b];
      label[b] = -label[b];
      energy += delta;
      if (energy < best) {
        best = energy;
        best_step = t;
      }
    }
    return best_step;
  }
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_SOLVERS_EXHAUSTIVE_SOLVER_H
