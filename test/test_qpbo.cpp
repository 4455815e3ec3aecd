// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// Tests of roof duality (internal/Qpbo.h) against enumeration: optimality
// on submodular energies, the persistency of the partial labellings on
// general energies, the symmetric signed energies of the orientation
// problem, fixing nodes with incremental re-solves (QPBO-I), degenerate
// cases.  Includes that header, Max_flow.h, the standard library and
// GoogleTest.

#include <Normal_orientation/internal/Max_flow.h>
#include <Normal_orientation/internal/Qpbo.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <iostream>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

namespace {

using Normal_orientation::internal::Qpbo;

struct Pair_term
{
  std::size_t i, j;
  std::array<double, 4> e; // e00, e01, e10, e11
};

// an energy kept aside, to be loaded into a Qpbo and enumerated
struct Energy
{
  std::size_t n = 0;
  std::vector<std::array<double, 2>> unary;
  std::vector<Pair_term> pairs;

  double operator()(const std::vector<int>& x) const
  {
    double e = 0.0;
    for (std::size_t i = 0; i < n; ++i)
      e += unary[i][x[i]];
    for (const Pair_term& t : pairs)
      e += t.e[2 * x[t.i] + x[t.j]];
    return e;
  }

  void load(Qpbo& q) const
  {
    q.add_nodes(n);
    for (std::size_t i = 0; i < n; ++i)
      if (unary[i][0] != 0.0 || unary[i][1] != 0.0)
        q.add_unary(i, unary[i][0], unary[i][1]);
    for (const Pair_term& t : pairs)
      q.add_pairwise(t.i, t.j, t.e[0], t.e[1], t.e[2], t.e[3]);
  }

  // the energies of the 2^n states (bit i of the state is x_i)
  std::vector<double> table() const
  {
    std::vector<double> v(std::size_t(1) << n);
    std::vector<int> x(n);
    for (std::size_t s = 0; s < v.size(); ++s) {
      for (std::size_t i = 0; i < n; ++i)
        x[i] = int((s >> i) & 1u);
      v[s] = (*this)(x);
    }
    return v;
  }
};

std::vector<int> state_labels(std::size_t s, std::size_t n)
{
  std::vector<int> x(n);
  for (std::size_t i = 0; i < n; ++i)
    x[i] = int((s >> i) & 1u);
  return x;
}

// kinds of random energies
enum class Kind { submodular, general, general_real };

Energy random_energy(std::mt19937& rng, std::size_t n, double density, Kind kind, bool with_unary = true)
{
  std::uniform_int_distribution<int> coef(-10, 10);
  std::uniform_real_distribution<double> real(-10.0, 10.0);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto draw = [&]() { return kind == Kind::general_real ? real(rng) : double(coef(rng)); };
  Energy e;
  e.n = n;
  e.unary.assign(n, {0.0, 0.0});
  if (with_unary)
    for (std::size_t i = 0; i < n; ++i)
      if (unit(rng) < 0.7)
        e.unary[i] = {draw(), draw()};
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) {
      if (i == j || unit(rng) >= density / 2)
        continue;
      std::array<double, 4> t = {draw(), draw(), draw(), draw()};
      if (kind == Kind::submodular) {
        const double l = t[1] + t[2] - t[0] - t[3];
        if (l < 0)
          t[1] -= l; // now P01 + P10 >= P00 + P11
      }
      e.pairs.push_back(Pair_term{i, j, t});
    }
  return e;
}

// signed edges of the orientation energy, as pairwise terms
Pair_term signed_term(std::size_t i, std::size_t j, double w)
{
  if (w >= 0)
    return Pair_term{i, j, {0.0, w, w, 0.0}};
  return Pair_term{i, j, {-w, 0.0, 0.0, -w}};
}

std::vector<int> labels_of(const Qpbo& q)
{
  std::vector<int> x(q.number_of_nodes());
  for (std::size_t i = 0; i < x.size(); ++i)
    x[i] = q.label(i);
  return x;
}

bool complete(const std::vector<int>& x)
{
  return std::all_of(x.begin(), x.end(), [](int l) { return l >= 0; });
}

// checks the persistency of the partial labelling `x` (-1 = unlabelled)
// against the table of energies: each labelled variable alone, and all of
// them at once, allow the global minimum
void expect_persistent(const std::vector<double>& table, const std::vector<int>& x, double tol,
                       const char* what)
{
  const std::size_t n = x.size();
  const double global = *std::min_element(table.begin(), table.end());
  std::vector<double> best(n, std::numeric_limits<double>::infinity());
  double joint = std::numeric_limits<double>::infinity();
  for (std::size_t s = 0; s < table.size(); ++s) {
    bool agrees = true;
    for (std::size_t i = 0; i < n; ++i) {
      if (x[i] < 0)
        continue;
      if (int((s >> i) & 1u) == x[i])
        best[i] = std::min(best[i], table[s]);
      else
        agrees = false;
    }
    if (agrees)
      joint = std::min(joint, table[s]);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (x[i] >= 0) {
      EXPECT_NEAR(best[i], global, tol) << what << ": variable " << i << " labelled " << x[i];
    }
  }
  EXPECT_NEAR(joint, global, tol) << what << ": joint persistency";
}

} // namespace

TEST(Qpbo, SubmodularEnergiesAreSolvedExactly)
{
  std::mt19937 rng(1);
  for (int c = 0; c < 300; ++c) {
    const std::size_t n = 1 + std::size_t(c % 12);
    const Kind kind = Kind::submodular;
    Energy e = random_energy(rng, n, 0.5, kind);
    if (c % 3 == 0) // real coefficients too
      for (Pair_term& t : e.pairs)
        for (double& v : t.e)
          v += 0.25 * std::sin(double(c + v));
    for (Pair_term& t : e.pairs) { // keep them submodular after the noise
      const double l = t.e[1] + t.e[2] - t.e[0] - t.e[3];
      if (l < 0)
        t.e[1] -= l;
    }
    const std::vector<double> table = e.table();
    const double global = *std::min_element(table.begin(), table.end());
    for (bool weak : {true, false}) {
      Qpbo q;
      e.load(q);
      q.solve(weak);
      const std::vector<int> x = labels_of(q);
      if (weak) {
        ASSERT_TRUE(complete(x)) << "case " << c;
        EXPECT_NEAR(e(x), global, 1e-9) << "case " << c;
        EXPECT_NEAR(q.energy(x), global, 1e-9) << "case " << c;
        EXPECT_NEAR(q.lower_bound(), global, 1e-9) << "case " << c;
      } else {
        expect_persistent(table, x, 1e-9, "strong, submodular");
      }
    }
  }
}

TEST(Qpbo, GeneralEnergiesArePersistent)
{
  std::mt19937 rng(2);
  std::size_t vars = 0, weak_labelled = 0, strong_labelled = 0, complete_cases = 0;
  const int cases = 600;
  for (int c = 0; c < cases; ++c) {
    const std::size_t n = 1 + std::size_t(c % 12);
    const Kind kind = (c % 4 == 3) ? Kind::general_real : Kind::general;
    const double density = (c % 3 == 0) ? 0.2 : (c % 3 == 1 ? 0.4 : 0.8);
    const Energy e = random_energy(rng, n, density, kind);
    const std::vector<double> table = e.table();
    const double global = *std::min_element(table.begin(), table.end());
    const double tol = 1e-9 * (1.0 + std::abs(global));

    Qpbo weak, strong;
    e.load(weak);
    e.load(strong);
    weak.solve();
    strong.solve(false);
    const std::vector<int> xw = labels_of(weak), xs = labels_of(strong);
    expect_persistent(table, xw, tol, "weak");
    expect_persistent(table, xs, tol, "strong");
    for (std::size_t i = 0; i < n; ++i) {
      if (xs[i] >= 0) {
        EXPECT_EQ(xw[i], xs[i]) << "case " << c << ": a strong label differs from the weak one";
      }
    }
    EXPECT_LE(weak.lower_bound(), global + tol) << "case " << c;
    EXPECT_NEAR(weak.lower_bound(), strong.lower_bound(), tol) << "case " << c;
    if (complete(xw)) {
      ++complete_cases;
      EXPECT_NEAR(e(xw), global, tol) << "case " << c;
      EXPECT_NEAR(weak.lower_bound(), global, tol) << "case " << c;
    }
    vars += n;
    weak_labelled += weak.number_of_labelled_nodes();
    strong_labelled += strong.number_of_labelled_nodes();
    EXPECT_EQ(weak.number_of_labelled_nodes(),
              std::size_t(std::count_if(xw.begin(), xw.end(), [](int l) { return l >= 0; })));
  }
  std::cout << "[ QPBO     ] general energies: " << cases << " cases, " << vars << " variables, labelled "
            << double(weak_labelled) / double(vars) << " (weak), " << double(strong_labelled) / double(vars)
            << " (strong); complete in " << complete_cases << " cases" << std::endl;
  ::testing::Test::RecordProperty("weak_fraction_labelled", std::to_string(double(weak_labelled) / double(vars)));
  ::testing::Test::RecordProperty("strong_fraction_labelled", std::to_string(double(strong_labelled) / double(vars)));
}

TEST(Qpbo, SignedSymmetricEnergies)
{
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> weight(1, 10);
  std::size_t vars = 0, labelled = 0, balanced_vars = 0, balanced_labelled = 0;
  for (int c = 0; c < 300; ++c) {
    const std::size_t n = 2 + std::size_t(c % 11);
    const bool balanced = (c % 2 == 0);
    std::vector<int> hidden(n);
    for (int& h : hidden)
      h = unit(rng) < 0.5 ? 1 : -1;
    Energy e;
    e.n = n;
    e.unary.assign(n, {0.0, 0.0});
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j)
        if (j == i + 1 || unit(rng) < 0.3) { // a path, so the graph is connected
          double w = weight(rng);
          if (balanced ? hidden[i] != hidden[j] : unit(rng) < 0.5)
            w = -w;
          e.pairs.push_back(signed_term(i, j, w));
        }
    const std::vector<double> table = e.table();
    const double global = *std::min_element(table.begin(), table.end());

    Qpbo weak, strong;
    for (Qpbo* q : {&weak, &strong}) {
      q->add_nodes(n);
      for (const Pair_term& t : e.pairs)
        q->add_signed_edge(t.i, t.j, t.e[0] > 0 ? -t.e[0] : t.e[1]);
    }
    weak.solve();
    strong.solve(false);
    // the global flip symmetry leaves no strong persistency
    EXPECT_EQ(strong.number_of_labelled_nodes(), 0u) << "case " << c;
    const std::vector<int> x = labels_of(weak);
    expect_persistent(table, x, 1e-9, "signed");
    EXPECT_LE(weak.lower_bound(), global + 1e-9);
    if (balanced) {
      // frustration free: labelled completely, with a zero-energy labelling
      ASSERT_TRUE(complete(x)) << "case " << c;
      EXPECT_EQ(e(x), 0.0);
      EXPECT_EQ(global, 0.0);
      balanced_vars += n;
      balanced_labelled += weak.number_of_labelled_nodes();
    } else {
      vars += n;
      labelled += weak.number_of_labelled_nodes();
    }
  }
  std::cout << "[ QPBO     ] signed energies without unary terms: labelled " << double(labelled) / double(vars)
            << " (weak, random signs), " << double(balanced_labelled) / double(balanced_vars)
            << " (weak, balanced), 0 (strong)" << std::endl;

  // an odd cycle of negative edges is frustrated: nothing is labelled and
  // the bound is below the minimum (1: one edge is unhappy)
  Qpbo q;
  q.add_nodes(3);
  q.add_signed_edge(0, 1, -1.0);
  q.add_signed_edge(1, 2, -1.0);
  q.add_signed_edge(2, 0, -1.0);
  q.solve();
  EXPECT_EQ(q.number_of_labelled_nodes(), 0u);
  EXPECT_LT(q.lower_bound(), 1.0 - 1e-9);
  // a unary term breaks the symmetry; QPBO-I completes it
  q.fix(0, 0);
  q.solve();
  const std::vector<int> x = labels_of(q);
  ASSERT_TRUE(complete(x));
  EXPECT_EQ(q.energy(x), 1.0);
  EXPECT_EQ(x[0], 0);
}

TEST(Qpbo, SignedEdgeConvention)
{
  // L = +1 <-> x = 0, L = -1 <-> x = 1, E as edge_energy() of Orientation_problem.h
  for (double w : {2.5, -2.5, 0.0}) {
    Qpbo q;
    q.add_nodes(2);
    q.add_signed_edge(0, 1, w);
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) {
        const bool same = (a == b);
        const double expected = w >= 0 ? (same ? 0.0 : w) : (same ? -w : 0.0);
        EXPECT_EQ(q.energy({a, b}), expected);
      }
  }
  // one positive edge: both labels equal (one of the two optima)
  Qpbo q;
  q.add_nodes(2);
  q.add_signed_edge(0, 1, 3.0);
  q.solve();
  EXPECT_EQ(q.number_of_labelled_nodes(), 2u);
  EXPECT_EQ(q.label(0), q.label(1));
  // one negative edge: different labels
  Qpbo r;
  r.add_nodes(2);
  r.add_signed_edge(0, 1, -3.0);
  r.solve();
  EXPECT_EQ(r.number_of_labelled_nodes(), 2u);
  EXPECT_NE(r.label(0), r.label(1));
}

TEST(Qpbo, FixAndIncrementalSolve)
{
  std::mt19937 rng(4);
  std::size_t fixes = 0, cases_with_fix = 0;
  for (int c = 0; c < 250; ++c) {
    const std::size_t n = 2 + std::size_t(c % 11);
    const bool signed_energy = (c % 3 == 0);
    Energy e;
    if (signed_energy) {
      std::uniform_int_distribution<int> w(-9, 9);
      std::uniform_real_distribution<double> unit(0.0, 1.0);
      e.n = n;
      e.unary.assign(n, {0.0, 0.0});
      for (std::size_t i = 0; i < n; ++i)
        for (std::size_t j = i + 1; j < n; ++j)
          if (unit(rng) < 0.5)
            e.pairs.push_back(signed_term(i, j, w(rng)));
    } else {
      e = random_energy(rng, n, 0.6, Kind::general);
    }
    const std::vector<double> table = e.table();
    const std::size_t best = std::size_t(std::min_element(table.begin(), table.end()) - table.begin());
    const std::vector<int> optimum = state_labels(best, n);

    Qpbo q;
    e.load(q);
    q.solve();
    std::vector<std::size_t> fixed;
    for (;;) {
      const std::vector<int> x = labels_of(q);
      expect_persistent(table, x, 1e-9, "after fixes"); // the optimum satisfies the fixes
      const auto it = std::find(x.begin(), x.end(), -1);
      if (it == x.end())
        break;
      const std::size_t i = std::size_t(it - x.begin());
      EXPECT_TRUE(q.fix(i, optimum[i]));
      EXPECT_FALSE(q.fix(i, optimum[i]));
      EXPECT_EQ(q.fixed_value(i), optimum[i]);
      fixed.push_back(i);
      q.solve(); // incremental
      EXPECT_EQ(q.label(i), optimum[i]);

      // the same as a fresh solve with the same fixes ...
      Qpbo fresh;
      e.load(fresh);
      for (std::size_t k : fixed)
        fresh.fix(k, optimum[k]);
      fresh.solve();
      EXPECT_EQ(labels_of(q), labels_of(fresh)) << "case " << c;
      // ... and as a fresh solve with the fixes as ordinary unary terms
      Qpbo plain;
      e.load(plain);
      for (std::size_t k : fixed)
        plain.add_unary(k, optimum[k] == 0 ? 0.0 : 1e4, optimum[k] == 0 ? 1e4 : 0.0);
      plain.solve();
      EXPECT_EQ(labels_of(q), labels_of(plain)) << "case " << c;
      EXPECT_NEAR(q.lower_bound(), fresh.lower_bound(), 1e-9) << "case " << c;
    }
    const std::vector<int> x = labels_of(q);
    ASSERT_TRUE(complete(x));
    EXPECT_EQ(e(x), table[best]) << "case " << c;
    EXPECT_NEAR(q.lower_bound(), table[best], 1e-9) << "case " << c;
    fixes += fixed.size();
    cases_with_fix += fixed.empty() ? 0 : 1;

    // removing the fixes gives back the labels of the unfixed problem
    for (std::size_t k : fixed)
      EXPECT_TRUE(q.fix(k, -1));
    q.solve();
    Qpbo unfixed;
    e.load(unfixed);
    unfixed.solve();
    EXPECT_EQ(labels_of(q), labels_of(unfixed)) << "case " << c;
  }
  std::cout << "[ QPBO     ] QPBO-I: " << fixes << " fixes in " << cases_with_fix << " of 250 cases" << std::endl;
}

TEST(Qpbo, TermsAddedAfterSolve)
{
  std::mt19937 rng(5);
  for (int c = 0; c < 150; ++c) {
    const std::size_t n = 2 + std::size_t(c % 11);
    const Energy e = random_energy(rng, n, 0.6, Kind::general);
    Qpbo q;
    q.add_nodes(n);
    const std::size_t half = e.pairs.size() / 2;
    for (std::size_t k = 0; k < half; ++k)
      q.add_pairwise(e.pairs[k].i, e.pairs[k].j, e.pairs[k].e[0], e.pairs[k].e[1], e.pairs[k].e[2],
                     e.pairs[k].e[3]);
    if (c % 2 == 0)
      q.fix(0, 1); // a fix before more terms: its penalty must be raised
    q.solve();
    for (std::size_t i = 0; i < n; ++i)
      q.add_unary(i, e.unary[i][0], e.unary[i][1]);
    for (std::size_t k = half; k < e.pairs.size(); ++k)
      q.add_pairwise(e.pairs[k].i, e.pairs[k].j, e.pairs[k].e[0], e.pairs[k].e[1], e.pairs[k].e[2],
                     e.pairs[k].e[3]);
    q.solve();
    Qpbo fresh;
    e.load(fresh);
    if (c % 2 == 0)
      fresh.fix(0, 1);
    fresh.solve();
    EXPECT_EQ(labels_of(q), labels_of(fresh)) << "case " << c;
    EXPECT_NEAR(q.lower_bound(), fresh.lower_bound(), 1e-9) << "case " << c;
    if (c % 2 == 0) {
      EXPECT_EQ(q.label(0), 1);
    }
    // variables added after a solve
    const std::size_t v = q.add_nodes(1);
    q.add_pairwise(v, 0, 5.0, 0.0, 0.0, 5.0);
    q.solve();
    EXPECT_EQ(q.number_of_nodes(), n + 1);
  }
}

TEST(Qpbo, Degenerate)
{
  { // no variables
    Qpbo q;
    q.solve();
    q.solve(false);
    EXPECT_EQ(q.number_of_nodes(), 0u);
    EXPECT_EQ(q.number_of_labelled_nodes(), 0u);
    EXPECT_EQ(q.energy({}), 0.0);
    EXPECT_EQ(q.lower_bound(), 0.0);
    EXPECT_THROW(q.label(0), std::out_of_range);
    EXPECT_THROW(q.energy({0}), std::invalid_argument);
  }
  { // unary terms only, no edges
    Qpbo q;
    EXPECT_EQ(q.add_nodes(4), 0u);
    EXPECT_EQ(q.label(0), -1); // before any solve
    q.add_unary(0, 1.0, 3.0);
    q.add_unary(1, 3.0, -1.0);
    q.add_unary(2, 2.0, 2.0); // a tie: both values are optimal
    q.solve(false);
    EXPECT_EQ(q.label(0), 0);
    EXPECT_EQ(q.label(1), 1);
    EXPECT_EQ(q.label(2), -1); // no strong persistency on a tie
    EXPECT_EQ(q.label(3), -1);
    q.solve();
    EXPECT_EQ(q.label(0), 0);
    EXPECT_EQ(q.label(1), 1);
    EXPECT_GE(q.label(2), 0); // weak: either value
    EXPECT_GE(q.label(3), 0);
    EXPECT_EQ(q.lower_bound(), 1.0 - 1.0 + 2.0);
    EXPECT_EQ(q.energy({0, 1, 0, 1}), 2.0);
    EXPECT_THROW(q.energy({0, 1, 2, 0}), std::invalid_argument);
  }
  { // a single variable, and a pairwise term on it
    Qpbo q;
    q.add_nodes(1);
    q.add_pairwise(0, 0, 4.0, 100.0, 100.0, 1.0); // P(x, x): only e00 and e11 count
    q.solve();
    EXPECT_EQ(q.label(0), 1);
    EXPECT_EQ(q.energy({1}), 1.0);
    EXPECT_EQ(q.energy({0}), 4.0);
    EXPECT_EQ(q.lower_bound(), 1.0);
    EXPECT_EQ(q.number_of_pairwise_terms(), 0u);
    EXPECT_TRUE(q.fix(0, 0));
    q.solve();
    EXPECT_EQ(q.label(0), 0);
    EXPECT_EQ(q.lower_bound(), 4.0);
    EXPECT_THROW(q.fix(0, 2), std::invalid_argument);
    EXPECT_THROW(q.fix(1, 0), std::out_of_range);
    EXPECT_THROW(q.add_unary(0, std::nan(""), 0.0), std::invalid_argument);
    EXPECT_THROW(q.add_pairwise(0, 1, 0, 0, 0, 0), std::out_of_range);
  }
  { // variables without any term
    Qpbo q;
    q.add_nodes(3);
    q.solve(false);
    EXPECT_EQ(q.number_of_labelled_nodes(), 0u);
    q.solve();
    EXPECT_EQ(q.number_of_labelled_nodes(), 3u);
  }
}

TEST(Qpbo, LargeSparseProblem)
{
  // a 60 x 60 grid of signed edges with weak unary terms, then QPBO-I:
  // fixing the unlabelled nodes one by one ends with a complete labelling
  // whose energy equals the bound of the fixed problem
  const std::size_t side = 60, n = side * side;
  std::mt19937 rng(6);
  std::uniform_int_distribution<int> w(-8, 10), u(-2, 2);
  Qpbo q(n, 2 * n);
  q.add_nodes(n);
  for (std::size_t r = 0; r < side; ++r)
    for (std::size_t c = 0; c < side; ++c) {
      const std::size_t i = r * side + c;
      q.add_unary(i, 0.0, u(rng));
      if (c + 1 < side)
        q.add_signed_edge(i, i + 1, w(rng));
      if (r + 1 < side)
        q.add_signed_edge(i, i + side, w(rng));
    }
  q.solve();
  const std::size_t first = q.number_of_labelled_nodes();
  std::size_t steps = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (q.label(i) < 0) {
      q.fix(i, 0);
      q.solve();
      ++steps;
    }
  std::vector<int> x = labels_of(q);
  ASSERT_TRUE(complete(x));
  EXPECT_NEAR(q.energy(x), q.lower_bound(), 1e-6);
  std::cout << "[ QPBO     ] grid " << side << "x" << side << ": " << double(first) / double(n)
            << " labelled, then " << steps << " QPBO-I fixes" << std::endl;
}

TEST(Qpbo, LabelsDoNotDependOnTheOrderOfTheTerms)
{
  // the weak labelling is defined by the set of minimum cuts, not by the
  // maximum flow found: shuffling the terms (hence the graph) keeps it
  std::mt19937 rng(7);
  for (int c = 0; c < 200; ++c) {
    const std::size_t n = 2 + std::size_t(c % 11);
    Energy e = random_energy(rng, n, 0.6, c % 2 ? Kind::general : Kind::submodular, c % 3 != 0);
    Qpbo a;
    e.load(a);
    a.solve();
    std::shuffle(e.pairs.begin(), e.pairs.end(), rng);
    Qpbo b;
    e.load(b);
    b.solve();
    EXPECT_EQ(labels_of(a), labels_of(b)) << "case " << c;
  }
}

TEST(Qpbo, BoundAndLabelsMatchTheHalfIntegralRelaxation)
{
  // The roof dual is the LP relaxation of the energy over the local
  // polytope, which has a half-integral optimum.  At a point x of
  // {0, 1/2, 1}^n its value is: unary terms averaged over the halves;
  // pairwise terms averaged over a half end, and for two halves
  // min((P00 + P11) / 2, (P01 + P10) / 2).  Enumerating the 3^n points
  // checks lower_bound() independently of the flow graph, and that the
  // weak labelling is integral where some optimal point is, i.e. labels as
  // many variables as any optimal half-integral point (maximality).
  std::mt19937 rng(8);
  for (int c = 0; c < 200; ++c) {
    const std::size_t n = 1 + std::size_t(c % 7);
    const Energy e = random_energy(rng, n, 0.6, Kind::general, c % 4 != 0);
    std::size_t points = 1;
    for (std::size_t i = 0; i < n; ++i)
      points *= 3;
    double best = std::numeric_limits<double>::infinity();
    std::size_t most_integral = 0;
    std::vector<int> h(n); // 0, 1, or 2 for 1/2
    std::vector<double> values(points);
    for (std::size_t s = 0; s < points; ++s) {
      std::size_t r = s;
      for (std::size_t i = 0; i < n; ++i, r /= 3)
        h[i] = int(r % 3);
      double v = 0.0;
      for (std::size_t i = 0; i < n; ++i)
        v += h[i] == 2 ? (e.unary[i][0] + e.unary[i][1]) / 2 : e.unary[i][h[i]];
      for (const Pair_term& t : e.pairs) {
        const int a = h[t.i], b = h[t.j];
        if (a != 2 && b != 2)
          v += t.e[2 * a + b];
        else if (a != 2)
          v += (t.e[2 * a] + t.e[2 * a + 1]) / 2;
        else if (b != 2)
          v += (t.e[b] + t.e[2 + b]) / 2;
        else
          v += std::min(t.e[0] + t.e[3], t.e[1] + t.e[2]) / 2;
      }
      values[s] = v;
      best = std::min(best, v);
    }
    for (std::size_t s = 0; s < points; ++s)
      if (values[s] <= best + 1e-9) {
        std::size_t integral = 0;
        for (std::size_t r = s, i = 0; i < n; ++i, r /= 3)
          integral += (r % 3 != 2);
        most_integral = std::max(most_integral, integral);
      }
    Qpbo q;
    e.load(q);
    q.solve();
    EXPECT_NEAR(q.lower_bound(), best, 1e-9) << "case " << c;
    EXPECT_EQ(q.number_of_labelled_nodes(), most_integral) << "case " << c;
    // the labelling, with 1/2 elsewhere, is an optimal point
    std::size_t s = 0;
    for (std::size_t i = n; i-- > 0;)
      s = 3 * s + std::size_t(q.label(i) < 0 ? 2 : q.label(i));
    EXPECT_NEAR(values[s], best, 1e-9) << "case " << c;
  }
}
