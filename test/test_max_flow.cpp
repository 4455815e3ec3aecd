// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// Tests of the max-flow / min-cut core (internal/Max_flow.h): flow values
// against Boost's boykov_kolmogorov_max_flow, validity of the minimum cut,
// incremental re-solves against fresh solves, a grid and degenerate graphs.
// Includes that header, Boost.Graph, the standard library and GoogleTest.

#include <Normal_orientation/internal/Max_flow.h>

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized" // inside Boost
#endif
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/boykov_kolmogorov_max_flow.hpp>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

namespace {

using Normal_orientation::internal::Max_flow;

struct Edge
{
  std::uint32_t i, j;
  double cap, rev_cap;
};

// a graph given by its total capacities
struct Problem
{
  std::size_t n = 0;
  std::vector<double> source_cap, sink_cap; // s->v, v->t
  std::vector<Edge> edges;
};

Max_flow build(const Problem& p)
{
  Max_flow mf(p.n, p.edges.size());
  mf.add_nodes(p.n);
  for (std::uint32_t v = 0; v < p.n; ++v)
    if (p.source_cap[v] != 0 || p.sink_cap[v] != 0)
      mf.add_terminal_weights(v, p.source_cap[v], p.sink_cap[v]);
  for (const Edge& e : p.edges)
    mf.add_edge(e.i, e.j, e.cap, e.rev_cap);
  return mf;
}

double boost_max_flow(const Problem& p)
{
  using namespace boost;
  typedef adjacency_list_traits<vecS, vecS, directedS> Traits;
  typedef adjacency_list<vecS, vecS, directedS, no_property,
                         property<edge_capacity_t, double,
                                  property<edge_residual_capacity_t, double,
                                           property<edge_reverse_t, Traits::edge_descriptor>>>>
    Graph;
  Graph g(p.n + 2);
  const std::size_t s = p.n, t = p.n + 1;
  auto capacity = get(edge_capacity, g);
  auto reverse = get(edge_reverse, g);
  auto arc_pair = [&](std::size_t u, std::size_t v, double c, double rc) {
    auto e1 = add_edge(u, v, g).first;
    auto e2 = add_edge(v, u, g).first;
    capacity[e1] = c;
    capacity[e2] = rc;
    reverse[e1] = e2;
    reverse[e2] = e1;
  };
  for (std::size_t v = 0; v < p.n; ++v) {
    if (p.source_cap[v] != 0)
      arc_pair(s, v, p.source_cap[v], 0.0);
    if (p.sink_cap[v] != 0)
      arc_pair(v, t, p.sink_cap[v], 0.0);
  }
  for (const Edge& e : p.edges)
    arc_pair(e.i, e.j, e.cap, e.rev_cap);

  std::vector<default_color_type> color(num_vertices(g));
  std::vector<double> distance(num_vertices(g));
  std::vector<Traits::edge_descriptor> pred(num_vertices(g));
  auto index = get(vertex_index, g);
  return boykov_kolmogorov_max_flow(g, capacity, get(edge_residual_capacity, g), reverse,
                                    make_iterator_property_map(pred.begin(), index),
                                    make_iterator_property_map(color.begin(), index),
                                    make_iterator_property_map(distance.begin(), index),
                                    index, s, t);
}

// the capacity of the cut (source side = mf.is_source_side)
double cut_value(const Problem& p, const Max_flow& mf)
{
  double cut = 0;
  for (std::uint32_t v = 0; v < p.n; ++v)
    cut += mf.is_source_side(v) ? p.sink_cap[v] : p.source_cap[v];
  for (const Edge& e : p.edges) {
    const bool si = mf.is_source_side(e.i), sj = mf.is_source_side(e.j);
    if (si && !sj)
      cut += e.cap;
    if (sj && !si)
      cut += e.rev_cap;
  }
  return cut;
}

// true if the source side of `mf` is exactly the set of the nodes reachable
// from s in the residual graph (read through the accessors)
::testing::AssertionResult source_side_is_residual_reachable(const Max_flow& mf)
{
  const std::size_t n = mf.number_of_nodes();
  std::vector<std::vector<std::uint32_t>> out(n);
  for (std::uint32_t e = 0; e < mf.number_of_edges(); ++e) {
    const std::uint32_t i = mf.edge_source(e), j = mf.edge_target(e);
    if (mf.edge_residual(e) > 0)
      out[i].push_back(j);
    if (mf.edge_residual(e, true) > 0)
      out[j].push_back(i);
  }
  std::vector<char> seen(n, 0);
  std::vector<std::uint32_t> stack;
  for (std::uint32_t v = 0; v < n; ++v)
    if (mf.terminal_residual(v) > 0) {
      seen[v] = 1;
      stack.push_back(v);
    }
  while (!stack.empty()) {
    const std::uint32_t v = stack.back();
    stack.pop_back();
    if (mf.terminal_residual(v) < 0)
      return ::testing::AssertionFailure() << "augmenting path left through node " << v;
    for (std::uint32_t w : out[v])
      if (!seen[w]) {
        seen[w] = 1;
        stack.push_back(w);
      }
  }
  for (std::uint32_t v = 0; v < n; ++v)
    if (bool(seen[v]) != mf.is_source_side(v))
      return ::testing::AssertionFailure() << "node " << v << ": reachable " << int(seen[v])
                                           << ", source side " << mf.is_source_side(v);
  return ::testing::AssertionSuccess();
}

::testing::AssertionResult near(double a, double b)
{
  if (std::abs(a - b) <= 1e-9 * std::max({1.0, std::abs(a), std::abs(b)}))
    return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << a << " != " << b << " (difference " << a - b << ")";
}

// random capacity: often zero, sometimes an integer, otherwise real
double random_cap(std::mt19937& rng, double zero_probability = 0.2)
{
  std::uniform_real_distribution<double> u(0, 1);
  const double r = u(rng);
  if (r < zero_probability)
    return 0.0;
  if (r < zero_probability + 0.3)
    return double(std::uniform_int_distribution<int>(1, 10)(rng));
  return 10 * u(rng);
}

Problem random_problem(std::mt19937& rng, std::size_t n, double mean_degree, double terminal_density)
{
  Problem p;
  p.n = n;
  p.source_cap.assign(n, 0.0);
  p.sink_cap.assign(n, 0.0);
  std::uniform_real_distribution<double> u(0, 1);
  for (std::size_t v = 0; v < n; ++v) {
    if (u(rng) < terminal_density)
      p.source_cap[v] = random_cap(rng);
    if (u(rng) < terminal_density)
      p.sink_cap[v] = random_cap(rng);
  }
  if (n >= 2) {
    const std::size_t m = std::size_t(mean_degree * double(n) / 2);
    std::uniform_int_distribution<std::uint32_t> node(0, std::uint32_t(n - 1));
    for (std::size_t k = 0; k < m; ++k) {
      const std::uint32_t i = node(rng), j = node(rng);
      if (i == j)
        continue;
      const double c = random_cap(rng), rc = u(rng) < 0.3 ? 0.0 : random_cap(rng);
      p.edges.push_back(Edge{i, j, c, rc}); // parallel edges allowed
    }
  }
  return p;
}

Problem grid_problem(std::mt19937& rng, std::size_t w, std::size_t h)
{
  Problem p;
  p.n = w * h;
  p.source_cap.assign(p.n, 0.0);
  p.sink_cap.assign(p.n, 0.0);
  std::uniform_real_distribution<double> u(0, 1);
  for (std::size_t v = 0; v < p.n; ++v) {
    // data term of a noisy binary image
    const double d = 10 * u(rng) - 5;
    (d > 0 ? p.source_cap[v] : p.sink_cap[v]) = std::abs(d);
  }
  for (std::size_t y = 0; y < h; ++y)
    for (std::size_t x = 0; x < w; ++x) {
      const std::uint32_t v = std::uint32_t(y * w + x);
      if (x + 1 < w) {
        const double c = 3 * u(rng);
        p.edges.push_back(Edge{v, v + 1, c, c});
      }
      if (y + 1 < h) {
        const double c = 3 * u(rng);
        p.edges.push_back(Edge{v, std::uint32_t(v + w), c, c});
      }
    }
  return p;
}

void check_fresh(const Problem& p)
{
  Max_flow mf = build(p);
  const double f = mf.max_flow();
  EXPECT_TRUE(near(f, boost_max_flow(p)));
  EXPECT_TRUE(near(f, cut_value(p, mf)));
  EXPECT_TRUE(source_side_is_residual_reachable(mf));
}

TEST(Max_flow, RandomGraphsAgainstBoost)
{
  std::mt19937 rng(12345);
  for (int k = 0; k < 400; ++k) {
    const std::size_t n = std::uniform_int_distribution<std::size_t>(2, 300)(rng);
    const double degree = std::uniform_real_distribution<double>(0.5, 8)(rng);
    const double terminals = std::uniform_real_distribution<double>(0.05, 0.8)(rng);
    SCOPED_TRACE(k);
    check_fresh(random_problem(rng, n, degree, terminals));
    if (HasFailure())
      return;
  }
}

TEST(Max_flow, IntegerGraphsAgainstBoost)
{
  std::mt19937 rng(777);
  for (int k = 0; k < 200; ++k) {
    Problem p = random_problem(rng, std::uniform_int_distribution<std::size_t>(2, 60)(rng), 4, 0.3);
    for (double& c : p.source_cap)
      c = std::round(c);
    for (double& c : p.sink_cap)
      c = std::round(c);
    for (Edge& e : p.edges) {
      e.cap = std::round(e.cap);
      e.rev_cap = std::round(e.rev_cap);
    }
    Max_flow mf = build(p);
    const double f = mf.max_flow();
    EXPECT_EQ(f, boost_max_flow(p)) << k;
    EXPECT_EQ(f, cut_value(p, mf)) << k;
  }
}

TEST(Max_flow, Grid100x100)
{
  std::mt19937 rng(4);
  check_fresh(grid_problem(rng, 100, 100));
}

TEST(Max_flow, RepeatedMaxFlowWithoutChange)
{
  std::mt19937 rng(5);
  Problem p = random_problem(rng, 200, 4, 0.3);
  Max_flow mf = build(p);
  const double f = mf.max_flow();
  EXPECT_EQ(mf.max_flow(), f);
  EXPECT_EQ(mf.max_flow(), f);
  EXPECT_TRUE(near(f, cut_value(p, mf)));
  EXPECT_TRUE(source_side_is_residual_reachable(mf));
}

// Changes the terminal capacities of `count` random nodes in `p` and `mf`
// alike, up and down (totals stay non-negative).
void change_terminals(std::mt19937& rng, Problem& p, Max_flow& mf, std::size_t count, double big = 0)
{
  std::uniform_int_distribution<std::uint32_t> node(0, std::uint32_t(p.n - 1));
  std::uniform_real_distribution<double> u(0, 1);
  for (std::size_t k = 0; k < count; ++k) {
    const std::uint32_t v = node(rng);
    double ds = 0, dt = 0;
    const double r = u(rng);
    if (big > 0 && r < 0.1) {
      (u(rng) < 0.5 ? ds : dt) = big; // fix the node, as QPBO-I does
    } else if (r < 0.4) {
      ds = -p.source_cap[v] * u(rng); // decreases
      dt = -p.sink_cap[v] * u(rng);
    } else if (r < 0.5) {
      ds = -p.source_cap[v]; // remove the links
      dt = -p.sink_cap[v];
    } else if (r < 0.8) {
      ds = random_cap(rng, 0.3); // increases
      dt = random_cap(rng, 0.3);
    } else if (r < 0.9) {
      ds = random_cap(rng, 0); // source up, sink down
      dt = -p.sink_cap[v] * u(rng);
    } else {
      ds = -p.source_cap[v] * u(rng); // source down, sink up
      dt = random_cap(rng, 0);
    }
    ds = std::max(ds, -p.source_cap[v]);
    dt = std::max(dt, -p.sink_cap[v]);
    p.source_cap[v] += ds;
    p.sink_cap[v] += dt;
    if (p.source_cap[v] < 0)
      p.source_cap[v] = 0; // rounding: not reached with exact arithmetic
    if (p.sink_cap[v] < 0)
      p.sink_cap[v] = 0;
    mf.add_terminal_weights(v, ds, dt);
  }
}

TEST(Max_flow, IncrementalTerminalChanges)
{
  std::mt19937 rng(2024);
  for (int k = 0; k < 150; ++k) {
    const std::size_t n = std::uniform_int_distribution<std::size_t>(2, 300)(rng);
    Problem p = random_problem(rng, n, std::uniform_real_distribution<double>(0.5, 6)(rng),
                               std::uniform_real_distribution<double>(0.05, 0.6)(rng));
    Max_flow mf = build(p);
    mf.max_flow();
    for (int round = 0; round < 20; ++round) {
      SCOPED_TRACE(::testing::Message() << "graph " << k << " round " << round);
      const std::size_t count = std::uniform_int_distribution<std::size_t>(1, std::max<std::size_t>(1, n / 5))(rng);
      change_terminals(rng, p, mf, count);
      const double f = mf.max_flow();
      Max_flow fresh = build(p);
      EXPECT_TRUE(near(f, fresh.max_flow()));
      EXPECT_TRUE(near(f, cut_value(p, mf)));
      EXPECT_TRUE(source_side_is_residual_reachable(mf));
      if (round % 5 == 4) {
        EXPECT_TRUE(near(f, boost_max_flow(p)));
      }
      if (HasFailure())
        return;
    }
  }
}

TEST(Max_flow, IncrementalFixingNodesLikeQpbo)
{
  // a large unary fixes a node at a time, then the graph is re-solved
  std::mt19937 rng(99);
  for (int k = 0; k < 30; ++k) {
    Problem p = random_problem(rng, 200, 4, 0.3);
    Max_flow mf = build(p);
    mf.max_flow();
    for (int round = 0; round < 30; ++round) {
      SCOPED_TRACE(::testing::Message() << "graph " << k << " round " << round);
      change_terminals(rng, p, mf, 1 + round % 3, 1e6);
      const double f = mf.max_flow();
      Max_flow fresh = build(p);
      EXPECT_TRUE(near(f, fresh.max_flow()));
      EXPECT_TRUE(near(f, cut_value(p, mf)));
      EXPECT_TRUE(source_side_is_residual_reachable(mf));
      if (HasFailure())
        return;
    }
  }
}

TEST(Max_flow, IncrementalAddedEdges)
{
  std::mt19937 rng(31);
  for (int k = 0; k < 50; ++k) {
    Problem p = random_problem(rng, 100, 2, 0.3);
    Max_flow mf = build(p);
    mf.max_flow();
    std::uniform_int_distribution<std::uint32_t> node(0, std::uint32_t(p.n - 1));
    for (int round = 0; round < 10; ++round) {
      SCOPED_TRACE(::testing::Message() << "graph " << k << " round " << round);
      for (int e = 0; e < 5; ++e) {
        const std::uint32_t i = node(rng), j = node(rng);
        if (i == j)
          continue;
        const Edge edge{i, j, random_cap(rng), random_cap(rng)};
        p.edges.push_back(edge);
        mf.add_edge(edge.i, edge.j, edge.cap, edge.rev_cap);
      }
      change_terminals(rng, p, mf, 3);
      const double f = mf.max_flow();
      EXPECT_TRUE(near(f, boost_max_flow(p)));
      EXPECT_TRUE(near(f, cut_value(p, mf)));
      EXPECT_TRUE(source_side_is_residual_reachable(mf));
      if (HasFailure())
        return;
    }
  }
}

TEST(Max_flow, IncrementalGrid)
{
  std::mt19937 rng(8);
  Problem p = grid_problem(rng, 100, 100);
  Max_flow mf = build(p);
  mf.max_flow();
  for (int round = 0; round < 10; ++round) {
    SCOPED_TRACE(round);
    change_terminals(rng, p, mf, 200, 1e3);
    const double f = mf.max_flow();
    EXPECT_TRUE(near(f, boost_max_flow(p)));
    EXPECT_TRUE(near(f, cut_value(p, mf)));
    EXPECT_TRUE(source_side_is_residual_reachable(mf));
  }
}

TEST(Max_flow, DegenerateGraphs)
{
  { // no node
    Max_flow mf;
    EXPECT_EQ(mf.max_flow(), 0.0);
    EXPECT_EQ(mf.number_of_nodes(), 0u);
  }
  { // a single node
    Max_flow mf;
    EXPECT_EQ(mf.add_nodes(1), 0u);
    mf.add_terminal_weights(0, 3, 5);
    EXPECT_EQ(mf.max_flow(), 3.0);
    EXPECT_TRUE(mf.is_source_side(0) == false);
    mf.add_terminal_weights(0, 4, 0); // now 7 against 5
    EXPECT_EQ(mf.max_flow(), 5.0);
    EXPECT_TRUE(mf.is_source_side(0));
    mf.add_terminal_weights(0, -7, 0); // now 0 against 5
    EXPECT_EQ(mf.max_flow(), 0.0);
    EXPECT_FALSE(mf.is_source_side(0));
  }
  { // nodes without edges
    Max_flow mf;
    mf.add_nodes(3);
    EXPECT_EQ(mf.add_nodes(2), 3u);
    mf.add_terminal_weights(0, 1, 2);
    mf.add_terminal_weights(1, 2, 1);
    mf.add_terminal_weights(4, 0, 6);
    EXPECT_EQ(mf.max_flow(), 2.0);
    EXPECT_FALSE(mf.is_source_side(0));
    EXPECT_TRUE(mf.is_source_side(1));
    EXPECT_FALSE(mf.is_source_side(2)); // isolated nodes are on the sink side
    EXPECT_FALSE(mf.is_source_side(4));
  }
  { // zero capacities everywhere
    Max_flow mf;
    mf.add_nodes(4);
    mf.add_edge(0, 1, 0, 0);
    mf.add_edge(1, 2, 0, 0);
    mf.add_terminal_weights(0, 0, 0);
    EXPECT_EQ(mf.max_flow(), 0.0);
    for (std::uint32_t v = 0; v < 4; ++v)
      EXPECT_FALSE(mf.is_source_side(v));
  }
  { // a path s -> 0 -> 1 -> 2 -> t, with isolated node 3
    Max_flow mf;
    mf.add_nodes(4);
    mf.add_terminal_weights(0, 5, 0);
    EXPECT_EQ(mf.add_edge(0, 1, 4, 0), 0u);
    EXPECT_EQ(mf.add_edge(1, 2, 3, 1), 1u);
    mf.add_terminal_weights(2, 0, 6);
    EXPECT_EQ(mf.max_flow(), 3.0);
    EXPECT_TRUE(mf.is_source_side(0));
    EXPECT_TRUE(mf.is_source_side(1));
    EXPECT_FALSE(mf.is_source_side(2));
    EXPECT_EQ(mf.edge_residual(1), 0.0);
    EXPECT_EQ(mf.edge_residual(1, true), 4.0);
    EXPECT_EQ(mf.edge_source(1), 1u);
    EXPECT_EQ(mf.edge_target(1), 2u);
    EXPECT_EQ(mf.terminal_residual(0), 2.0);
    EXPECT_EQ(mf.terminal_residual(2), -3.0);
  }
}

} // namespace
