// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_SOLVERS_QPBO_I_SOLVER_H
#define NORMAL_ORIENTATION_SOLVERS_QPBO_I_SOLVER_H

/// \file Qpbo_i_solver.h
/// MST + QPBO-I (paper sec. 4.2.1; Rother, Kolmogorov, Lempitsky and
/// Szummer, CVPR 2007).

#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/internal/Qpbo.h>
#include <Normal_orientation/solvers/Mst_solver.h>
#include <Normal_orientation/solvers/Solver_report.h>

#include <boost/graph/graph_traits.hpp>
#include <boost/property_map/property_map.hpp>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <random>
#include <tuple>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationSolvers
/// The paper's MST+QPBO-I solver.  It starts from the labelling y of
/// `initial` (an `Mst_solver`), builds the QPBO (roof duality) problem of
/// the whole energy and solves it; then it visits the nodes QPBO left
/// unlabelled in a random order and, for each one still unlabelled, fixes
/// it to its label in y and re-solves incrementally (the max-flow search
/// trees are reused), until every node is labelled.  This is repeated for
/// `orders` random orders (seeded by `seed`, so the result is
/// deterministic), and the labelling of lowest energy, y included, is
/// returned: the energy never ends above the MST's.  Unlike the MST, every
/// edge takes part in the decision.
///
/// The reference code runs a single order; the paper says several orders
/// are tried and the best kept, which is what this class does.  On 300
/// random signed graphs of 4-19 vertices (test_solvers), the exact optimum
/// was reached by 1 order on 206, 3 orders on 232, 8 orders on 257 and 16
/// orders on 266 of them; the MST alone on 93.
///
/// Cost: each re-solve updates the max-flow incrementally, then recomputes
/// the persistent labels in O(V + E); with `maximum_solves` re-solves per
/// order, an order costs O(maximum_solves * (V + E)) plus the flow
/// augmentations.  Solving only the frustrated regions of large clouds is
/// work in progress.
/// \cgalModels `OrientationSolver`
class Qpbo_i_solver
{
public:
  /// the name used on the command line and in reports
  static const char* name() { return "qpbo-i"; }

  /// the number of random orders tried
  unsigned int orders = 3;
  /// the seed of the random orders
  unsigned long seed = 0;
  /// the solver that gives the starting labelling
  Mst_solver initial;
  /// At most this many re-solves per order: the unlabelled nodes are fixed
  /// in batches of ceil(unlabelled / maximum_solves) between two re-solves,
  /// one at a time when there are at most `maximum_solves` of them (the
  /// classical QPBO-I).  Fixing to the starting labelling keeps it feasible,
  /// so batches keep the guarantee; they trade some of the propagation
  /// between fixes for a bounded cost of maximum_solves * O(V + E) per order.
  unsigned int maximum_solves = 64;

  /// the solver with `orders` random orders seeded by `seed`
  explicit Qpbo_i_solver(unsigned int number_of_orders = 3, unsigned long random_seed = 0)
    : orders(number_of_orders), seed(random_seed)
  {}

  /// Solves the orientation problem on `g` with the signed edge weights
  /// `weight` and writes +1/-1 to `labels` for every vertex.
  /// `Solver_report::iterations` counts the fixes made over all orders.
  /// \tparam Graph a model of `VertexListGraph` and `EdgeListGraph` with an
  ///         internal `vertex_index` map (vertex indices 0 ... n-1)
  /// \tparam WeightMap a readable edge property map with a floating value
  /// \tparam LabelMap a writable vertex property map accepting `Label`
  template <typename Graph, typename WeightMap, typename LabelMap>
  Solver_report solve(const Graph& g, WeightMap weight, LabelMap labels) const
  {
    const auto start = std::chrono::steady_clock::now();
    const std::size_t n = std::size_t(num_vertices(g));
    auto index = get(boost::vertex_index, g);

    // 1. Starting labelling.
    std::vector<Label> y(n, Label(1));
    initial.solve(g, weight, boost::make_iterator_property_map(y.begin(), index));

    // 2. The QPBO problem of the whole energy (x = 0 for label +1).
    internal::Qpbo qpbo(n, std::size_t(num_edges(g)));
    qpbo.add_nodes(n);
    typename boost::graph_traits<Graph>::edge_iterator it, end;
    for (boost::tie(it, end) = edges(g); it != end; ++it) {
      const double w = double(get(weight, *it));
      const std::size_t u = std::size_t(get(index, source(*it, g))), v = std::size_t(get(index, target(*it, g)));
      if (w != 0.0 && u != v)
        qpbo.add_signed_edge(u, v, w);
    }
    qpbo.solve();
    std::vector<std::size_t> unlabelled;
    for (std::size_t i = 0; i < n; ++i)
      if (qpbo.label(i) < 0)
        unlabelled.push_back(i);

    auto labelling_energy = [&](const std::vector<Label>& l) {
      return energy(g, weight, boost::make_iterator_property_map(l.cbegin(), index));
    };
    std::vector<Label> best = y;
    double best_energy = labelling_energy(y);
    Solver_report report;

    // 3. QPBO-I: fix the unlabelled nodes to y in random orders.
    std::vector<std::size_t> fixed;
    for (unsigned int o = 0; o < orders; ++o) {
      for (std::size_t i : fixed)
        qpbo.fix(i, -1);
      if (!fixed.empty())
        qpbo.solve();
      fixed.clear();
      std::vector<std::size_t> order = unlabelled;
      std::mt19937_64 rng(seed * 0x9e3779b97f4a7c15ULL + o);
      for (std::size_t k = order.size(); k > 1; --k) // Fisher-Yates, independent of the library
        std::swap(order[k - 1], order[std::size_t(rng() % k)]);
      // Nodes are fixed in batches of ceil(unlabelled / maximum_solves)
      // between two re-solves (one node at a time on small problems).
      const std::size_t batch =
        std::max<std::size_t>(1, (order.size() + maximum_solves - 1) / std::max(1u, maximum_solves));
      std::size_t in_batch = 0;
      for (std::size_t i : order) {
        if (qpbo.label(i) >= 0)
          continue;
        qpbo.fix(i, y[i] > 0 ? 0 : 1);
        fixed.push_back(i);
        if (++in_batch == batch) {
          qpbo.solve();
          in_batch = 0;
        }
      }
      if (in_batch > 0)
        qpbo.solve();
      report.iterations += fixed.size();
      std::vector<Label> x(n);
      for (std::size_t i = 0; i < n; ++i) {
        const int xi = qpbo.label(i);
        x[i] = xi < 0 ? y[i] : Label(xi == 0 ? 1 : -1);
      }
      const double e = labelling_energy(x);
      if (e < best_energy) {
        best_energy = e;
        best.swap(x);
      }
    }

    std::tie(report.energy, report.frustrated_edges) = internal::write_labels(g, weight, best, labels);
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
  }
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_SOLVERS_QPBO_I_SOLVER_H
