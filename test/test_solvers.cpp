// SPDX-License-Identifier: GPL-3.0-or-later
// Solvers against the exact oracle: MST+QPBO-I never ends above the MST and
// reaches the exhaustive optimum on most small random signed graphs.

#include <Normal_orientation/solvers/Exhaustive_solver.h>
#include <Normal_orientation/solvers/Mst_solver.h>
#include <Normal_orientation/solvers/Qpbo_i_solver.h>

#include <CGAL/property_map.h>

#include <boost/graph/adjacency_list.hpp>

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace NO = Normal_orientation;

namespace {

typedef boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS, boost::no_property,
                              boost::property<boost::edge_weight_t, double>>
  Ugraph;

Ugraph random_graph(std::mt19937_64& rng, int n, int m, double negative_fraction)
{
  Ugraph g(n);
  std::uniform_int_distribution<int> pick(0, n - 1);
  std::uniform_real_distribution<double> mag(0.05, 1.0), u(0.0, 1.0);
  for (int e = 0; e < m; ++e) {
    const int a = pick(rng), b = pick(rng);
    if (a != b)
      boost::add_edge(a, b, (u(rng) < negative_fraction ? -1.0 : 1.0) * mag(rng), g);
  }
  return g;
}

template <typename Solver>
double solve(const Solver& s, const Ugraph& g, std::vector<NO::Label>& l)
{
  l.assign(boost::num_vertices(g), 0);
  return s.solve(g, get(boost::edge_weight, g), CGAL::make_property_map(l)).energy;
}

} // namespace

TEST(Qpbo_i_solver, NeverAboveMstAndUsuallyOptimal)
{
  std::mt19937_64 rng(21);
  int trials = 0, optimal = 0, mst_optimal = 0, strictly_better = 0;
  for (int t = 0; t < 300; ++t) {
    const int n = 4 + int(rng() % 16);
    const Ugraph g = random_graph(rng, n, 2 * n + int(rng() % (2 * n)), 0.35);
    std::vector<NO::Label> a, b, c;
    const double mst = solve(NO::Mst_solver(0), g, a);
    const double qpbo_i = solve(NO::Qpbo_i_solver(3, 7), g, b);
    const double exact = solve(NO::Exhaustive_solver(), g, c);
    ASSERT_LE(qpbo_i, mst + 1e-9) << "trial " << t;
    ASSERT_GE(qpbo_i, exact - 1e-9) << "trial " << t;
    ASSERT_NEAR(NO::energy(g, get(boost::edge_weight, g), CGAL::make_property_map(b)), qpbo_i, 1e-9);
    ++trials;
    optimal += qpbo_i <= exact + 1e-9;
    mst_optimal += mst <= exact + 1e-9;
    strictly_better += qpbo_i < mst - 1e-9;
  }
  std::cout << "[ info ] optimum reached: QPBO-I " << optimal << "/" << trials << ", MST " << mst_optimal << "/"
            << trials << "; QPBO-I strictly below MST on " << strictly_better << "\n";
  // measured: QPBO-I (3 orders) 232/300 optimal, MST 93/300; 1 order 206,
  // 8 orders 257, 16 orders 266
  EXPECT_GE(optimal, 2 * mst_optimal);
  EXPECT_GE(optimal, trials * 7 / 10);
}

TEST(Qpbo_i_solver, FindsTheFigure2OptimumAndIsDeterministic)
{
  Ugraph g(4);
  for (auto [a, b, w] : {std::tuple{0, 1, -1.0}, {0, 2, 0.7}, {2, 1, 0.7}, {0, 3, 0.7}, {3, 1, 0.7}})
    boost::add_edge(a, b, w, g);
  NO::Qpbo_i_solver s(2, 3);
  s.initial = NO::Mst_solver(0); // start from the paper's MST, which pays 1.4
  std::vector<NO::Label> a, b;
  EXPECT_NEAR(solve(s, g, a), 1.0, 1e-9);
  solve(s, g, b);
  EXPECT_EQ(a, b);
}

TEST(Qpbo_i_solver, SameResultForSameSeed)
{
  std::mt19937_64 rng(5);
  for (int t = 0; t < 30; ++t) {
    const Ugraph g = random_graph(rng, 40, 160, 0.4);
    std::vector<NO::Label> a, b;
    solve(NO::Qpbo_i_solver(4, 11), g, a);
    solve(NO::Qpbo_i_solver(4, 11), g, b);
    ASSERT_EQ(a, b);
  }
}
