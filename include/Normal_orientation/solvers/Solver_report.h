// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_SOLVERS_SOLVER_REPORT_H
#define NORMAL_ORIENTATION_SOLVERS_SOLVER_REPORT_H

/// \file Solver_report.h
/// What an `OrientationSolver` returns.

#include <Normal_orientation/Orientation_problem.h>

#include <cstddef>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationSolvers
/// The report of one solve.
struct Solver_report
{
  /// the energy of the labelling written by the solver
  double energy = 0.0;
  /// solver-specific count: edges processed plus single-vertex moves (MST),
  /// re-solves (QPBO-I), ...
  std::size_t iterations = 0;
  /// edges that joined two different components (MST: the spanning forest)
  std::size_t tree_edges = 0;
  /// edges whose wish the labelling does not meet
  std::size_t frustrated_edges = 0;
  /// the number of vertices of the reduced (segment) graph the solver
  /// worked on, 0 if it worked on the whole graph
  std::size_t segments = 0;
  /// wall-clock seconds of the solve
  double seconds = 0.0;
  /// the labelling the solver started from and improved, per vertex index
  /// (QPBO-I and LSA-TR: their `initial` MST's), empty when it had none.
  /// The drivers' global stage never joins, in one patch, a vertex that
  /// the solver negated against it with one that it did not.
  std::vector<Label> starting_labels;
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_SOLVERS_SOLVER_REPORT_H
