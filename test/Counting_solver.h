// SPDX-License-Identifier: GPL-3.0-or-later
// A solver for the tests that records the size of every graph it solves.
#ifndef NORMAL_ORIENTATION_TEST_COUNTING_SOLVER_H
#define NORMAL_ORIENTATION_TEST_COUNTING_SOLVER_H

#include <Normal_orientation/solvers/Mst_solver.h>
#include <Normal_orientation/solvers/Qpbo_i_solver.h>

#include <cstddef>
#include <memory>
#include <vector>

namespace Normal_orientation {
namespace test {

/// `Qpbo_i_solver` that appends the number of vertices of every graph it is
/// given to `sizes` (shared by its copies); like it, it starts from its
/// member `initial`.
struct Counting_solver
{
  Mst_solver initial;
  std::shared_ptr<std::vector<std::size_t>> sizes = std::make_shared<std::vector<std::size_t>>();
  static const char* name() { return "counting qpbo-i"; }

  template <typename Graph, typename WeightMap, typename LabelMap>
  Solver_report solve(const Graph& g, WeightMap weight, LabelMap labels) const
  {
    sizes->push_back(std::size_t(num_vertices(g)));
    return Qpbo_i_solver().solve(g, weight, labels);
  }
};

} // namespace test
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_TEST_COUNTING_SOLVER_H
