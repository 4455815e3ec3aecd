// SPDX-License-Identifier: GPL-3.0-or-later
// Tests of the exact solver by enumeration, against a naive brute force.

#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/solvers/Exhaustive_solver.h>

#include <boost/graph/adjacency_list.hpp>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

namespace NO = Normal_orientation;

namespace {

typedef boost::adjacency_list<boost::vecS, boost::vecS, boost::undirectedS, boost::no_property,
                              boost::property<boost::edge_weight_t, double>>
  Ugraph;
typedef boost::adjacency_list<boost::vecS, boost::vecS, boost::bidirectionalS, boost::no_property,
                              boost::property<boost::edge_weight_t, double>>
  Dgraph;
typedef std::pair<double, double> Costs; // cost of +1, cost of -1

struct Signed_edge
{
  int u, v;
  double w;
};

template <typename Graph = Ugraph>
Graph make_graph(int n, const std::vector<Signed_edge>& edges)
{
  Graph g(n);
  for (const auto& e : edges)
    boost::add_edge(e.u, e.v, e.w, g);
  return g;
}

template <typename Graph, typename T>
auto vertex_map(std::vector<T>& values, const Graph& g)
{
  return boost::make_iterator_property_map(values.begin(), get(boost::vertex_index, g));
}

template <typename Graph>
NO::Solver_report solve(const Graph& g, std::vector<NO::Label>& labels, const NO::Exhaustive_solver& solver = NO::Exhaustive_solver())
{
  labels.assign(num_vertices(g), NO::Label(0));
  return solver.solve(g, get(boost::edge_weight, g), vertex_map(labels, g));
}

template <typename Graph>
NO::Solver_report solve(const Graph& g, std::vector<Costs>& unary, std::vector<NO::Label>& labels,
                        const NO::Exhaustive_solver& solver = NO::Exhaustive_solver())
{
  labels.assign(num_vertices(g), NO::Label(0));
  return solver.solve(g, get(boost::edge_weight, g), vertex_map(unary, g), vertex_map(labels, g));
}

template <typename Graph>
double energy_of(const Graph& g, std::vector<NO::Label>& labels)
{
  return NO::energy(g, get(boost::edge_weight, g), vertex_map(labels, g));
}

template <typename Graph>
double energy_of(const Graph& g, std::vector<Costs>& unary, std::vector<NO::Label>& labels)
{
  return NO::energy(g, get(boost::edge_weight, g), vertex_map(unary, g), vertex_map(labels, g));
}

// All 2^n labellings, each evaluated from scratch with energy().
template <typename Graph>
double brute_force_minimum(const Graph& g, std::vector<Costs>* unary = nullptr)
{
  const int n = int(num_vertices(g));
  double best = HUGE_VAL;
  std::vector<NO::Label> l(n);
  for (std::uint64_t mask = 0; mask < (std::uint64_t(1) << n); ++mask) {
    for (int i = 0; i < n; ++i)
      l[i] = (mask >> i) & 1 ? -1 : 1;
    best = std::min(best, unary ? energy_of(g, *unary, l) : energy_of(g, l));
  }
  return best;
}

// Random signed edges, with zero weights, self-loops and parallel edges.
std::vector<Signed_edge> random_edges(std::mt19937_64& rng, int n, int m)
{
  std::uniform_int_distribution<int> pick(0, n - 1), kind(0, 19);
  std::uniform_real_distribution<double> mag(0.01, 1.0);
  std::vector<Signed_edge> edges;
  for (int e = 0; e < m; ++e) {
    const int u = pick(rng), k = kind(rng);
    int v = pick(rng);
    if (k == 0)
      v = u; // self-loop: a constant term
    double w = (k % 2 ? 1.0 : -1.0) * mag(rng);
    if (k == 1)
      w = 0.0; // no information
    edges.push_back({u, v, w});
    if (k == 2)
      edges.push_back({v, u, -0.5 * w}); // parallel edge
  }
  return edges;
}

std::vector<Costs> random_unaries(std::mt19937_64& rng, int n)
{
  std::uniform_real_distribution<double> cost(-1.0, 1.0);
  std::uniform_int_distribution<int> kind(0, 3);
  std::vector<Costs> unary(n);
  for (auto& c : unary) {
    const int k = kind(rng);
    c = k == 0 ? Costs(0.0, 0.0) : Costs(cost(rng), k == 1 ? 0.0 : cost(rng));
  }
  return unary;
}

// The states the solver documents it visits: 2^(k-1) per component of k
// vertices (2^k with unary terms), components of the non-zero edges.
template <typename Graph>
std::size_t expected_states(const Graph& g, bool with_unary)
{
  std::vector<std::uint32_t> component;
  const std::size_t count = NO::connected_components(g, get(boost::edge_weight, g), component);
  std::vector<std::size_t> size(count, 0);
  for (auto c : component)
    ++size[c];
  std::size_t states = 0;
  for (auto k : size)
    states += std::size_t(1) << (with_unary ? k : k - 1);
  return states;
}

void expect_plus_minus_one(const std::vector<NO::Label>& labels)
{
  for (auto l : labels)
    ASSERT_TRUE(l == 1 || l == -1);
}

} // namespace

TEST(Exhaustive_solver, MatchesBruteForceWithoutUnaries)
{
  std::mt19937_64 rng(1);
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 1 + int(rng() % 14);
    const Ugraph g = make_graph(n, random_edges(rng, n, int(rng() % (3 * n + 1))));
    std::vector<NO::Label> labels;
    const auto report = solve(g, labels);
    expect_plus_minus_one(labels);
    const double best = brute_force_minimum(g);
    ASSERT_NEAR(report.energy, best, 1e-9) << "trial " << trial;
    ASSERT_NEAR(energy_of(g, labels), best, 1e-9) << "trial " << trial;
    ASSERT_EQ(report.iterations, expected_states(g, false)) << "trial " << trial;
  }
}

TEST(Exhaustive_solver, MatchesBruteForceWithUnaries)
{
  std::mt19937_64 rng(2);
  for (int trial = 0; trial < 400; ++trial) {
    const int n = 1 + int(rng() % 14);
    const Ugraph g = make_graph(n, random_edges(rng, n, int(rng() % (3 * n + 1))));
    std::vector<Costs> unary = random_unaries(rng, n);
    std::vector<NO::Label> labels;
    const auto report = solve(g, unary, labels);
    expect_plus_minus_one(labels);
    const double best = brute_force_minimum(g, &unary);
    ASSERT_NEAR(report.energy, best, 1e-9) << "trial " << trial;
    ASSERT_NEAR(energy_of(g, unary, labels), best, 1e-9) << "trial " << trial;
    ASSERT_EQ(report.iterations, expected_states(g, true)) << "trial " << trial;
  }
}

TEST(Exhaustive_solver, DirectedGraphsIgnoreTheDirection)
{
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 100; ++trial) {
    const int n = 1 + int(rng() % 12);
    const Dgraph g = make_graph<Dgraph>(n, random_edges(rng, n, int(rng() % (3 * n + 1))));
    std::vector<NO::Label> labels;
    const auto report = solve(g, labels);
    ASSERT_NEAR(report.energy, brute_force_minimum(g), 1e-9) << "trial " << trial;
  }
}

TEST(Exhaustive_solver, EnumeratesComponentsSeparately)
{
  // 10 components of 10 vertices (100 vertices: 2^99 states as a whole),
  // joined by zero-weight edges, which carry no information.
  std::mt19937_64 rng(4);
  std::vector<Signed_edge> all;
  double sum_of_minima = 0.0, sum_with_unaries = 0.0;
  std::vector<Costs> unary;
  for (int c = 0; c < 10; ++c) {
    std::vector<Signed_edge> part = random_edges(rng, 10, 25);
    for (int i = 0; i + 1 < 10; ++i)
      part.push_back({i, i + 1, rng() % 2 ? 0.3 : -0.3}); // connected
    std::vector<Costs> part_unary = random_unaries(rng, 10);
    const Ugraph piece = make_graph(10, part);
    sum_of_minima += brute_force_minimum(piece);
    sum_with_unaries += brute_force_minimum(piece, &part_unary);
    for (auto e : part)
      all.push_back({e.u + 10 * c, e.v + 10 * c, e.w});
    unary.insert(unary.end(), part_unary.begin(), part_unary.end());
    if (c > 0)
      all.push_back({10 * c, 10 * c - 1, 0.0});
  }
  const Ugraph g = make_graph(100, all);
  std::vector<NO::Label> labels;
  const auto report = solve(g, labels);
  EXPECT_NEAR(report.energy, sum_of_minima, 1e-9);
  EXPECT_EQ(report.iterations, 10u * 512u);
  for (int c = 0; c < 10; ++c)
    EXPECT_EQ(labels[10 * c], 1) << "the first vertex of a component is fixed to +1";
  const auto with_unaries = solve(g, unary, labels);
  EXPECT_NEAR(with_unaries.energy, sum_with_unaries, 1e-9);
  EXPECT_EQ(with_unaries.iterations, 10u * 1024u);
}

TEST(Exhaustive_solver, FindsTheOptimumOfTheFigure2Graph)
{
  // A strong edge asks 0 and 1 to differ; two paths of weaker edges ask
  // them to agree: the optimum violates the strong edge only.
  const Ugraph g = make_graph(4, {{0, 1, -1.0}, {0, 2, 0.7}, {2, 1, 0.7}, {0, 3, 0.7}, {3, 1, 0.7}});
  std::vector<NO::Label> labels;
  const auto report = solve(g, labels);
  EXPECT_NEAR(report.energy, 1.0, 1e-12);
  EXPECT_EQ(labels, (std::vector<NO::Label>{1, 1, 1, 1}));
  EXPECT_EQ(report.frustrated_edges, 1u);
  EXPECT_EQ(report.iterations, 8u);
}

TEST(Exhaustive_solver, TwentySixVertices)
{
  const NO::Exhaustive_solver solver;
  // A frustrated ring (odd number of negative edges): the optimum violates
  // the weakest edge only.
  {
    std::mt19937_64 rng(6);
    std::uniform_real_distribution<double> mag(0.1, 1.0);
    std::vector<Signed_edge> ring;
    double weakest = HUGE_VAL;
    for (int i = 0; i < 26; ++i) {
      const double m = mag(rng);
      weakest = std::min(weakest, m);
      ring.push_back({i, (i + 1) % 26, (i % 9 == 0 ? -1.0 : 1.0) * m}); // 3 negative edges
    }
    const Ugraph g = make_graph(26, ring);
    std::vector<NO::Label> labels;
    const auto report = solve(g, labels, solver);
    EXPECT_NEAR(report.energy, weakest, 1e-12);
    EXPECT_EQ(report.frustrated_edges, 1u);
    EXPECT_EQ(report.iterations, std::size_t(1) << 25);
  }
  // A dense random frustrated graph: timed; the result is no worse than any
  // single-vertex move and than many random labellings.
  std::mt19937_64 rng(7);
  std::vector<Signed_edge> edges = random_edges(rng, 26, 100);
  for (int i = 0; i + 1 < 26; ++i)
    edges.push_back({i, i + 1, rng() % 2 ? 0.5 : -0.5});
  const Ugraph g = make_graph(26, edges);
  std::vector<NO::Label> labels;
  const auto start = std::chrono::steady_clock::now();
  const auto report = solve(g, labels, solver);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::cout << "26 vertices, " << boost::num_edges(g) << " edges: " << report.iterations << " states in "
            << seconds << " s (report: " << report.seconds << " s)" << std::endl;
  RecordProperty("seconds_26_vertices", std::to_string(seconds));
  EXPECT_EQ(report.iterations, std::size_t(1) << 25);
  EXPECT_LT(seconds, 30.0);
  const double e = report.energy;
  EXPECT_NEAR(e, energy_of(g, labels), 1e-12);
  for (int i = 0; i < 26; ++i) {
    labels[i] = NO::Label(-labels[i]);
    EXPECT_GE(energy_of(g, labels), e - 1e-9);
    labels[i] = NO::Label(-labels[i]);
  }
  std::vector<NO::Label> random(26);
  for (int trial = 0; trial < 2000; ++trial) {
    for (auto& l : random)
      l = rng() % 2 ? 1 : -1;
    EXPECT_GE(energy_of(g, random), e - 1e-9);
  }
}

TEST(Exhaustive_solver, RefusesComponentsAboveMaximumVertices)
{
  std::vector<Signed_edge> path;
  for (int i = 0; i + 1 < 31; ++i)
    path.push_back({i, i + 1, i % 2 ? 0.5 : -0.25});
  const Ugraph g = make_graph(31, path);
  std::vector<NO::Label> labels;
  std::vector<Costs> unary(31, Costs(0.0, 0.0));
  EXPECT_EQ(NO::Exhaustive_solver().maximum_vertices, 30u);
  EXPECT_THROW(solve(g, labels), std::length_error);
  EXPECT_THROW(solve(g, unary, labels), std::length_error);
  try {
    solve(g, labels);
  } catch (const std::length_error& error) {
    EXPECT_NE(std::string(error.what()).find("31 vertices"), std::string::npos) << error.what();
  }
  // a lower limit
  const Ugraph nine = make_graph(10, {{0, 1, 1}, {1, 2, 1}, {2, 3, 1}, {3, 4, 1}, {4, 5, 1}, {5, 6, 1}, {6, 7, 1}, {7, 8, 1}});
  EXPECT_THROW(solve(nine, labels, NO::Exhaustive_solver(8)), std::length_error);
  EXPECT_NO_THROW(solve(nine, labels, NO::Exhaustive_solver(9)));
  // the limit is on components, not on the graph: 40 vertices in two paths
  std::vector<Signed_edge> two_paths;
  for (int i = 0; i + 1 < 20; ++i) {
    two_paths.push_back({i, i + 1, -0.5});
    two_paths.push_back({20 + i, 21 + i, 0.5});
  }
  const Ugraph forty = make_graph(40, two_paths);
  const auto report = solve(forty, labels);
  EXPECT_EQ(report.energy, 0.0);
  EXPECT_EQ(report.iterations, std::size_t(2) << 19); // 2 * 2^19
}

TEST(Exhaustive_solver, RefusesNonFiniteTerms)
{
  const Ugraph g = make_graph(3, {{0, 1, 0.5}, {1, 2, std::numeric_limits<double>::quiet_NaN()}});
  std::vector<NO::Label> labels;
  EXPECT_THROW(solve(g, labels), std::invalid_argument);
  const Ugraph h = make_graph(3, {{0, 1, 0.5}});
  std::vector<Costs> unary(3, Costs(0.0, 0.0));
  unary[2].second = HUGE_VAL;
  EXPECT_THROW(solve(h, unary, labels), std::invalid_argument);
}

TEST(Exhaustive_solver, IsolatedVerticesGetPlusOne)
{
  // 2, 5 and 6 have no edge; 3 and 4 are joined by a zero weight only
  const Ugraph g = make_graph(7, {{0, 1, -0.5}, {3, 4, 0.0}, {6, 6, -0.25}});
  std::vector<NO::Label> labels;
  const auto report = solve(g, labels);
  EXPECT_EQ(labels, (std::vector<NO::Label>{1, -1, 1, 1, 1, 1, 1}));
  EXPECT_EQ(report.energy, 0.25); // the self-loop's constant term
  EXPECT_EQ(report.iterations, 2u + 5u);
  // with unary terms, they take their cheaper label, +1 on a tie
  std::vector<Costs> unary = {{0, 0}, {0, 0}, {0.5, 0.25}, {0, 0}, {-1, -1}, {0.125, 0.5}, {0, 0}};
  const auto with_unaries = solve(g, unary, labels);
  EXPECT_EQ(labels, (std::vector<NO::Label>{1, -1, -1, 1, 1, 1, 1}));
  EXPECT_EQ(with_unaries.energy, 0.25 + 0.25 - 1 + 0.125);
}

TEST(Exhaustive_solver, ReturnsTheFirstOptimumInGrayCodeOrder)
{
  // Weights +-1 and integer unary costs: energies are exact, so the
  // documented order can be replayed from scratch.
  std::mt19937_64 rng(8);
  for (int trial = 0; trial < 150; ++trial) {
    const int n = 2 + int(rng() % 9);
    std::vector<Signed_edge> edges;
    for (int i = 1; i < n; ++i)
      edges.push_back({int(rng() % i), i, rng() % 2 ? 1.0 : -1.0}); // connected
    for (int e = int(rng() % (2 * n)); e > 0; --e) {
      const int u = int(rng() % n), v = int(rng() % n);
      if (u != v)
        edges.push_back({u, v, rng() % 2 ? 1.0 : -1.0});
    }
    const Ugraph g = make_graph(n, edges);
    std::vector<Costs> unary(n);
    for (auto& c : unary)
      c = Costs(double(rng() % 3), double(rng() % 3));
    for (const bool with_unary : {false, true}) {
      // bit b is vertex b + 1, and with unary terms bit n - 1 is vertex 0
      const int bits = with_unary ? n : n - 1;
      std::vector<NO::Label> l(n), first_best;
      double best = HUGE_VAL;
      for (std::uint64_t t = 0; t < (std::uint64_t(1) << bits); ++t) {
        const std::uint64_t gray = t ^ (t >> 1);
        for (int b = 0; b < n; ++b)
          l[(b + 1) % n] = b < bits && (gray >> b) & 1 ? -1 : 1;
        const double e = with_unary ? energy_of(g, unary, l) : energy_of(g, l);
        if (e < best) {
          best = e;
          first_best = l;
        }
      }
      std::vector<NO::Label> labels, again;
      const auto report = with_unary ? solve(g, unary, labels) : solve(g, labels);
      ASSERT_EQ(report.energy, best) << "trial " << trial;
      ASSERT_EQ(labels, first_best) << "trial " << trial << (with_unary ? " with" : " without") << " unaries";
      with_unary ? solve(g, unary, again) : solve(g, again);
      ASSERT_EQ(labels, again) << "deterministic";
    }
  }
}

TEST(Exhaustive_solver, ZeroUnariesGiveTheSameLabels)
{
  std::mt19937_64 rng(9);
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 1 + int(rng() % 12);
    const Ugraph g = make_graph(n, random_edges(rng, n, int(rng() % (3 * n + 1))));
    std::vector<Costs> zero(n, Costs(0.0, 0.0));
    std::vector<NO::Label> a, b;
    const double ea = solve(g, a).energy;
    const double eb = solve(g, zero, b).energy;
    ASSERT_EQ(a, b) << "trial " << trial;
    ASSERT_EQ(ea, eb);
  }
}

TEST(Exhaustive_solver, ExactOnWeightsOfVeryDifferentMagnitudes)
{
  // The fixed-point scale follows the largest terms of each component; the
  // small weights still decide between the labellings the large ones tie
  // (a frustrated triangle: any one of its edges can be violated).
  const Ugraph g = make_graph(5, {{0, 1, 1e3}, {1, 2, -1e3}, {2, 0, 1e3},
                                  {3, 0, 1e-9}, {3, 1, -2e-9}, {3, 2, 4e-9}, {4, 3, -3e-9}, {4, 0, 5e-9}});
  std::vector<NO::Label> labels;
  EXPECT_NEAR(solve(g, labels).energy, brute_force_minimum(g), 1e-12);
  std::vector<Costs> unary = {{0, 1e-9}, {0, 0}, {0, -3e-9}, {2e-9, 0}, {0, 0}};
  EXPECT_NEAR(solve(g, unary, labels).energy, brute_force_minimum(g, &unary), 1e-12);
  // components of very different scales do not interfere: each frustrated
  // triangle violates one edge
  const Ugraph h = make_graph(6, {{0, 1, 1e9}, {1, 2, -1e9}, {2, 0, 1e9}, {3, 4, 1e-9}, {4, 5, -1e-9}, {5, 3, 1e-9}});
  const auto report = solve(h, labels);
  EXPECT_EQ(report.frustrated_edges, 2u);
  EXPECT_NEAR(report.energy, 1e9, 1e-6);
}

TEST(Exhaustive_solver, EnergyWithUnaryTerms)
{
  const Ugraph g = make_graph(3, {{0, 1, 0.5}, {1, 2, -0.25}});
  std::vector<Costs> unary = {{1.0, 2.0}, {-1.0, 0.5}, {0.0, 0.125}};
  std::vector<NO::Label> labels = {1, -1, -1};
  // pairwise: 0.5 (0-1 differ) + 0.25 (1-2 agree); unary: 1 + 0.5 + 0.125
  EXPECT_EQ(energy_of(g, unary, labels), 0.75 + 1.625);
}
