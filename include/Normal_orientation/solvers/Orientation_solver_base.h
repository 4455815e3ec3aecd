// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_SOLVERS_ORIENTATION_SOLVER_BASE_H
#define NORMAL_ORIENTATION_SOLVERS_ORIENTATION_SOLVER_BASE_H

/// \file Orientation_solver_base.h
/// The two `solve()` calls of the `OrientationSolver` concept, written once
/// for the package's solvers.

#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/solvers/Solver_report.h>

#include <chrono>
#include <type_traits>

namespace Normal_orientation {

namespace internal {

/// Completes `report` once the labels are written to `labels`: its energy,
/// recomputed by `energy()` (with the unary costs unless `UnaryMap` is
/// `No_unary`), then the wall-clock seconds since `start`.
template <typename Graph, typename WeightMap, typename UnaryMap, typename LabelMap>
Solver_report& complete_report(Solver_report& report, const Graph& g, WeightMap weight, const UnaryMap& unary,
                               LabelMap labels, std::chrono::steady_clock::time_point start)
{
  if constexpr (!std::is_same<UnaryMap, No_unary>::value)
    report.energy = energy(g, weight, unary, labels);
  else
    report.energy = energy(g, weight, labels);
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

} // namespace internal

/// \ingroup PkgNormalOrientationSolvers
/// The public face shared by the package's solvers: the two `solve()` calls
/// of the `OrientationSolver` concept, with and without unary terms, both
/// handed to one private member of the solver,
/// `Solver::solve_impl(g, weight, unary, labels)`, whose `unary` is
/// `internal::No_unary` for the call without unary terms.  A solver derives
/// from `Orientation_solver_base<Solver>` (the curiously recurring template
/// pattern) and befriends it; what a solver throws and what its report's
/// counts mean are stated in the solver's own description.
///
/// Requirements on the arguments (see the `OrientationSolver` concept):
/// - `Graph` is a model of `VertexListGraph` and `EdgeListGraph` with an
///   internal `vertex_index` map (vertex indices 0 ... n-1);
/// - `WeightMap` is a readable edge property map with a floating value;
/// - `UnaryMap` is a readable vertex property map whose value has members
///   `first` (the cost of label +1) and `second` (the cost of label -1)
///   convertible to `double`, such as `std::pair<double, double>`; costs
///   may be negative;
/// - `LabelMap` is a writable vertex property map accepting `Label`.
/// \tparam Solver the solver deriving from this class, with a `const`
///         member template `solve_impl(g, weight, unary, labels)`
///         returning a `Solver_report`
template <typename Solver>
class Orientation_solver_base
{
public:
  /// Solves the orientation problem on `g` with the signed edge weights
  /// `weight`: minimises E(L) = sum over the edges of
  /// `edge_energy(w_e, L_i, L_j)`, and writes +1/-1 to `labels` for every
  /// vertex.
  /// \param g the graph: one pairwise term per edge
  /// \param weight the signed edge weights
  /// \param labels receives the label (+1 or -1) of every vertex
  /// \return the report of the solve
  template <typename Graph, typename WeightMap, typename LabelMap>
  Solver_report solve(const Graph& g, WeightMap weight, LabelMap labels) const
  {
    return static_cast<const Solver&>(*this).solve_impl(g, weight, internal::No_unary(), labels);
  }

  /// Solves the orientation problem with unary terms: minimises
  /// E(L) = sum over the edges of `edge_energy(w_e, L_i, L_j)` + sum over the
  /// vertices of the unary cost of L_i (see the `energy()` overload with a
  /// `unary` map), and writes +1/-1 to `labels` for every vertex.  With
  /// every unary cost zero, the labels are those of the solve without unary
  /// terms.
  /// \param g the graph: one pairwise term per edge
  /// \param weight the signed edge weights
  /// \param unary the costs of the labels +1 (`first`) and -1 (`second`) of every vertex
  /// \param labels receives the label (+1 or -1) of every vertex
  /// \return the report of the solve (its energy includes the unary costs)
  template <typename Graph, typename WeightMap, typename UnaryMap, typename LabelMap>
  Solver_report solve(const Graph& g, WeightMap weight, UnaryMap unary, LabelMap labels) const
  {
    return static_cast<const Solver&>(*this).solve_impl(g, weight, unary, labels);
  }
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_SOLVERS_ORIENTATION_SOLVER_BASE_H
