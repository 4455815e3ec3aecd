// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_QPBO_H
#define NORMAL_ORIENTATION_INTERNAL_QPBO_H

/// \file Qpbo.h
/// Roof duality (QPBO) for binary pairwise energies with unary terms,
/// written for this package from the published method:
/// P. L. Hammer, P. Hansen, B. Simeone, "Roof duality, complementation and
/// persistency in quadratic 0-1 optimization", Math. Programming 28, 1984;
/// E. Boros, P. L. Hammer, "Pseudo-Boolean optimization", Discrete Applied
/// Math. 123, 2002; V. Kolmogorov, C. Rother, "Minimizing non-submodular
/// functions with graph cuts - a review", IEEE PAMI 29(7), 2007 (the graph
/// construction and the weak persistencies from the strongly connected
/// components of the residual graph); C. Rother et al., "Optimizing binary
/// MRFs via extended roof duality", CVPR 2007 (QPBO-I: fixing nodes and
/// re-solving incrementally).  The maximum flow is internal/Max_flow.h.
///
/// Only the standard library is used.

#include <Normal_orientation/internal/Max_flow.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <stdexcept>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace internal {

/// \ingroup PkgNormalOrientationSolvers
/// Partial minimisation of a binary pairwise energy by roof duality (QPBO).
///
/// **Energy.**  Over x in {0,1}^n,
/// E(x) = const + sum_i U_i(x_i) + sum_(i,j) P_ij(x_i, x_j), built by
/// add_unary() and add_pairwise() (terms on the same variables add up).
/// The terms may be non-submodular (P(0,0) + P(1,1) > P(0,1) + P(1,0)).
///
/// **Result.**  solve() computes a partial labelling: label(i) is 0, 1 or
/// -1 (unlabelled).  It has the persistency property of roof duality: some
/// global minimiser of E agrees with every labelled variable at once (so
/// fixing the labelled variables and minimising over the others gives the
/// global minimum).  For a submodular energy every variable is labelled and
/// the labelling is a global minimiser.  lower_bound() is the roof-dual
/// lower bound of min E.
///
/// **Construction.**  Each variable x_i has two nodes in a flow graph:
/// the node of x_i and the node of its complement x̄_i = 1 - x_i (internally
/// nodes 2i and 2i+1 of the Max_flow graph, so that nodes can be added at
/// any time; this is the graph on i and ī = i + n of the papers, renumbered).
/// Convention: x_i = 0 when node i is on the source side of the cut, 1 when
/// it is on the sink side; node ī, which stands for x̄_i, is on the source
/// side when x_i = 1.  Every term is reparametrised as
/// P(x_i, x_j) = P00 + (P10 - P00) x_i + (P11 - P10) x_j + l (1 - x_i) x_j,
/// l = P01 + P10 - P00 - P11.  A linear term d x_i becomes terminal links
/// of capacity |d|/2 on i and on ī (s->i and ī->t if d > 0, i->t and s->ī
/// if d < 0, with the constant d moved out when d < 0).  If l >= 0 (the
/// term is submodular) the arcs i->j and j̄->ī get capacity l/2 each; if
/// l < 0, l (1 - x_i) x_j = l x_j - l x_i x_j and the arcs j̄->i and ī->j
/// get capacity -l/2 each.  All capacities are non-negative and the graph
/// is symmetric under the exchange of every node with its complement and of
/// s with t (an arc p->q of capacity c has the mirror arc q̄->p̄ of the same
/// capacity).  A cut in which every i and ī are on opposite sides costs
/// E(x) - const, so the minimum cut plus the constant is a lower bound.
///
/// **Labels.**  After the maximum flow, the residual graph is symmetrised
/// (the flow is averaged with its mirror image, which is also a maximum
/// flow), so that its arcs come in mirror pairs.  Then:
/// - the *strong persistencies* (`solve(false)`): x_i = 0 if node i is
///   reachable from s in the residual graph (hence on the source side of
///   every minimum cut; by symmetry ī then reaches t), x_i = 1 if ī is
///   reachable from s, otherwise unlabelled;
/// - the *weak persistencies* (`solve()` or `solve(true)`, the default):
///   the nodes neither reachable from s nor reaching t are grouped into the
///   strongly connected components of the residual graph.  If i and ī are
///   in the same component they are on the same side of every minimum cut
///   and x_i stays unlabelled; every other variable is labelled.  The
///   components are put in a topological order (a residual arc goes from
///   an earlier to a later component) and x_i = 0 (node i on the source
///   side) when the component of i comes after that of ī, x_i = 1
///   otherwise.  As in the classical 2-SAT argument, the source side so
///   built is closed in the residual graph, hence a minimum cut, and it
///   separates i from ī for every labelled variable: the labelling is the
///   one of a minimum cut, which is persistent, and labels as many
///   variables as any minimum cut can.  The topological order is the
///   smallest one for the smallest node index in each component (Kahn's
///   algorithm with a priority queue); it depends only on the set of
///   minimum cuts, not on the maximum flow found, so an incremental
///   re-solve gives the same labels as a fresh solve (in exact arithmetic).
///
/// **Energies with the global flip symmetry** E(x) = E(1 - x) (e.g. only
/// add_signed_edge() terms, no unary term): the graph is then also
/// symmetric under the exchange of i and ī alone, so no node is reachable
/// from s and the strong labelling is empty.  The weak labelling labels a
/// variable when a minimum cut separates it from its complement: e.g. a
/// balanced (frustration-free) connected component is labelled completely
/// with one of its two optimal labellings, while the variables of a
/// frustrated odd cycle (three edges of negative weight) stay unlabelled.
///
/// **Fixing (QPBO-I).**  fix(i, x) adds a penalty to the labellings with
/// x_i != x and the next solve() re-solves incrementally (Max_flow keeps
/// its search trees and its flow).  The penalty is the terminal capacity P
/// on node i and on ī (a cost 2P on E), with P larger than the total
/// capacity C of all the other arcs of the graph (P = 2C + 1, raised by the
/// next solve() if terms are added later; C <= 3 times the sum of the
/// absolute values of all coefficients given).  Moving i to its fixed side
/// then always lowers a cut, so every minimum cut respects the fix and
/// x_i is labelled x.  The penalties are not part of energy().
///
/// Terms may be added after a solve(); the next solve() is incremental too.
/// Coefficients must be finite.  Not thread safe.
class Qpbo
{
public:
  /// creates an empty energy, reserving room for `expected_nodes` variables
  /// and `expected_terms` pairwise terms
  explicit Qpbo(std::size_t expected_nodes = 0, std::size_t expected_terms = 0)
    : m_graph(2 * expected_nodes, 2 * expected_terms)
  {
    m_unary.reserve(expected_nodes);
    m_terms.reserve(expected_terms);
  }

  /// the number of variables
  std::size_t number_of_nodes() const { return m_unary.size(); }

  /// the number of pairwise terms given (a term on a single variable counts
  /// as a unary term)
  std::size_t number_of_pairwise_terms() const { return m_terms.size(); }

  /// adds `n` variables, without terms, and returns the index of the first
  /// (the new variables are `first ... first+n-1`); possible at any time
  std::size_t add_nodes(std::size_t n)
  {
    const std::size_t first = m_unary.size();
    m_graph.add_nodes(2 * n);
    m_unary.resize(first + n, std::make_pair(0.0, 0.0));
    m_fixed.resize(first + n, -1);
    m_label.resize(first + n, -1);
    return first;
  }

  /// adds the unary term U(x_i) with U(0) = `e0` and U(1) = `e1`
  /// \throw std::out_of_range if `i` is not a variable
  /// \throw std::invalid_argument if a coefficient is not finite
  void add_unary(std::size_t i, double e0, double e1)
  {
    check_node(i);
    check_finite(e0);
    check_finite(e1);
    m_unary[i].first += e0;
    m_unary[i].second += e1;
    m_constant += e0;
    add_linear(i, e1 - e0);
  }

  /// adds the pairwise term P(x_i, x_j) with P(0,0) = `e00`, P(0,1) =
  /// `e01`, P(1,0) = `e10`, P(1,1) = `e11`.  If `i == j`, the term
  /// P(x_i, x_i) is added as the unary term (`e00`, `e11`).
  /// \throw std::out_of_range if `i` or `j` is not a variable
  /// \throw std::invalid_argument if a coefficient is not finite
  void add_pairwise(std::size_t i, std::size_t j, double e00, double e01, double e10, double e11)
  {
    check_node(i);
    check_node(j);
    check_finite(e00);
    check_finite(e01);
    check_finite(e10);
    check_finite(e11);
    if (i == j) {
      add_unary(i, e00, e11);
      return;
    }
    m_terms.push_back(Term{i, j, {e00, e01, e10, e11}});
    m_constant += e00;
    const double l = (e01 + e10) - (e00 + e11);
    const Max_flow::Index ni = node_of(i), nj = node_of(j);
    if (l >= 0.0) {
      add_linear(i, e10 - e00);
      add_linear(j, e11 - e10);
      if (l > 0.0)
        add_edge_pair(ni, nj, l / 2); // i->j and its mirror j̄->ī
    } else {
      add_linear(i, e10 - e00);
      add_linear(j, e01 - e00);
      add_edge_pair(mirror(nj), ni, -l / 2); // j̄->i and its mirror ī->j
    }
  }

  /// adds the edge term of the orientation energy (see edge_energy() in
  /// Orientation_problem.h) between variables `i` and `j` of signed weight
  /// `w`: if w >= 0, E(same labels) = 0 and E(different labels) = w; if
  /// w < 0, E(same) = -w and E(different) = 0.  Labels map to variables by
  /// L = +1 <-> x = 0 and L = -1 <-> x = 1.  A weight w > 0 gives a
  /// submodular term, w < 0 a non-submodular one.
  void add_signed_edge(std::size_t i, std::size_t j, double w)
  {
    if (w >= 0.0)
      add_pairwise(i, j, 0.0, w, w, 0.0);
    else
      add_pairwise(i, j, -w, 0.0, 0.0, -w);
  }

  /// forces x_i = `x` (0 or 1) in the following solves by a penalty on
  /// x_i != x that dominates every other term (see the class description);
  /// `x = -1` removes the constraint.  The next solve() is incremental.
  /// Returns `false` if the constraint was already so (nothing changes),
  /// `true` otherwise.
  /// \throw std::out_of_range if `i` is not a variable
  /// \throw std::invalid_argument if `x` is not -1, 0 or 1
  bool fix(std::size_t i, int x)
  {
    check_node(i);
    if (x < -1 || x > 1)
      throw std::invalid_argument("Qpbo::fix: the value must be 0, 1 or -1");
    if (m_fixed[i] == x)
      return false;
    raise_penalty();
    if (m_fixed[i] >= 0)
      add_penalty(i, m_fixed[i], -m_penalty);
    if (x >= 0)
      add_penalty(i, x, m_penalty);
    m_fixed[i] = static_cast<signed char>(x);
    return true;
  }

  /// the value `x_i` is fixed to by fix(), or -1
  int fixed_value(std::size_t i) const
  {
    check_node(i);
    return m_fixed[i];
  }

  /// computes the maximum flow (incrementally after the first call) and the
  /// labels: the weak persistencies if `weak_persistencies` (the default),
  /// else only the strong ones (see the class description).  Cost: the
  /// maximum flow plus O(V + E) for the labels (plus O(C log C) for the
  /// C strongly connected components of the weak persistencies).
  void solve(bool weak_persistencies = true)
  {
    raise_penalty();
    m_graph.max_flow();
    compute_labels(weak_persistencies);
  }

  /// after solve(): the label of variable `i`: 0, 1, or -1 if unlabelled
  /// (also -1 before the first solve)
  int label(std::size_t i) const
  {
    check_node(i);
    return m_label[i];
  }

  /// after solve(): the number of labelled variables
  std::size_t number_of_labelled_nodes() const
  {
    return std::size_t(std::count_if(m_label.begin(), m_label.end(),
                                     [](signed char l) { return l >= 0; }));
  }

  /// after solve(): the roof-dual lower bound of the minimum of E over the
  /// labellings that satisfy the fixes (the maximum flow plus the constant
  /// of the reparametrisation), up to rounding.  It equals that minimum
  /// when the labelling is complete.
  double lower_bound() const { return m_constant + m_graph.flow(); }

  /// the energy E(x) of a complete labelling `x` (values 0 or 1, one per
  /// variable), without the penalties of fix()
  /// \throw std::invalid_argument if `x` has the wrong size or a value
  ///        other than 0 and 1
  double energy(const std::vector<int>& x) const
  {
    if (x.size() != m_unary.size())
      throw std::invalid_argument("Qpbo::energy: wrong number of labels");
    double e = 0.0;
    for (std::size_t i = 0; i < x.size(); ++i) {
      if (x[i] != 0 && x[i] != 1)
        throw std::invalid_argument("Qpbo::energy: labels must be 0 or 1");
      e += x[i] ? m_unary[i].second : m_unary[i].first;
    }
    for (const Term& t : m_terms)
      e += t.e[2 * x[t.i] + x[t.j]];
    return e;
  }

private:
  typedef Max_flow::Index Index;

  struct Term
  {
    std::size_t i, j;
    double e[4]; // e00, e01, e10, e11
  };

  static Index node_of(std::size_t i) { return Index(2 * i); }
  static Index mirror(Index p) { return p ^ 1u; }

  void check_node(std::size_t i) const
  {
    if (i >= m_unary.size())
      throw std::out_of_range("Qpbo: no such variable");
  }

  static void check_finite(double v)
  {
    if (!std::isfinite(v))
      throw std::invalid_argument("Qpbo: coefficients must be finite");
  }

  // adds d * x_i (see the class description)
  void add_linear(std::size_t i, double d)
  {
    const Index p = node_of(i);
    if (d > 0.0) {
      m_graph.add_terminal_weights(p, d / 2, 0.0);
      m_graph.add_terminal_weights(mirror(p), 0.0, d / 2);
      m_capacity += d;
    } else if (d < 0.0) {
      m_constant += d;
      m_graph.add_terminal_weights(p, 0.0, -d / 2);
      m_graph.add_terminal_weights(mirror(p), -d / 2, 0.0);
      m_capacity -= d;
    }
  }

  // adds the arc p->q and its mirror q̄->p̄, both of capacity c, as two
  // consecutive edges 2k and 2k+1 (compute_labels() relies on it)
  void add_edge_pair(Index p, Index q, double c)
  {
    m_graph.add_edge(p, q, c, 0.0);
    m_graph.add_edge(mirror(q), mirror(p), c, 0.0);
    m_capacity += 2 * c;
  }

  // adds `amount` to the penalty of x_i != x, on i and on ī
  void add_penalty(std::size_t i, int x, double amount)
  {
    const Index p = node_of(i);
    if (x == 0) { // cost if x_i = 1: s->i, ī->t
      m_graph.add_terminal_weights(p, amount, 0.0);
      m_graph.add_terminal_weights(mirror(p), 0.0, amount);
    } else { // cost if x_i = 0: i->t, s->ī
      m_graph.add_terminal_weights(p, 0.0, amount);
      m_graph.add_terminal_weights(mirror(p), amount, 0.0);
    }
  }

  // keeps the penalty of the fixes above the total capacity of the terms
  void raise_penalty()
  {
    if (m_penalty > m_capacity)
      return;
    const double p = 2 * m_capacity + 1;
    for (std::size_t i = 0; i < m_fixed.size(); ++i)
      if (m_fixed[i] >= 0)
        add_penalty(i, m_fixed[i], p - m_penalty);
    m_penalty = p;
  }

  // the residual graph after the maximum flow, symmetrised (see the class
  // description): terminal residuals tau (> 0: reachable from s), then the
  // arcs of positive residual capacity, out of node p at head[start[p] ...
  // start[p + 1] - 1]
  struct Residual_graph
  {
    std::vector<double> tau;
    std::vector<Index> start, head;
  };

  // labels from the persistencies: the strong ones, then if `weak` the weak
  // ones (see the class description)
  void compute_labels(bool weak)
  {
    const std::size_t n = m_unary.size();
    const std::size_t nn = 2 * n;
    std::fill(m_label.begin(), m_label.end(), static_cast<signed char>(-1));
    if (n == 0)
      return;

    const Residual_graph r = residual_graph();
    const std::vector<char> from_s = reachable_from_source(r);
    for (std::size_t i = 0; i < n; ++i) {
      const Index p = node_of(i);
      if (from_s[p] && !from_s[mirror(p)])
        m_label[i] = 0;
      else if (from_s[mirror(p)] && !from_s[p])
        m_label[i] = 1;
    }
    if (!weak)
      return;

    // the middle part: neither reachable from s nor reaching t (p reaches t
    // iff p̄ is reachable from s, by symmetry)
    std::vector<char> middle(nn, 0);
    for (std::size_t p = 0; p < nn; ++p)
      middle[p] = !from_s[p] && !from_s[mirror(Index(p))];

    std::vector<Index> comp;
    const Index components = strongly_connected_components(r, middle, comp);
    if (components == 0)
      return;
    const std::vector<Index> rank = topological_ranks(r, middle, comp, components);

    // node i on the source side iff its component comes after that of ī
    for (std::size_t i = 0; i < n; ++i) {
      const Index p = node_of(i);
      if (!middle[p] || comp[p] == comp[mirror(p)])
        continue;
      m_label[i] = rank[comp[p]] > rank[comp[mirror(p)]] ? 0 : 1;
    }
  }

  // the symmetrised residual graph: terminal links, then arcs (CSR)
  Residual_graph residual_graph() const
  {
    const std::size_t n = m_unary.size();
    const std::size_t nn = 2 * n;
    Residual_graph r;
    r.tau.resize(nn);
    for (std::size_t i = 0; i < n; ++i) {
      const Index p = node_of(i);
      const double t = (m_graph.terminal_residual(p) - m_graph.terminal_residual(mirror(p))) / 2;
      r.tau[p] = t;
      r.tau[mirror(p)] = -t;
    }
    const std::size_t ne = m_graph.number_of_edges();
    std::vector<double> fwd(ne), rev(ne);
    r.start.assign(nn + 1, 0);
    for (std::size_t e = 0; e < ne; e += 2) {
      const Index a = Index(e), b = Index(e + 1);
      fwd[e] = fwd[e + 1] = (m_graph.edge_residual(a, false) + m_graph.edge_residual(b, false)) / 2;
      rev[e] = rev[e + 1] = (m_graph.edge_residual(a, true) + m_graph.edge_residual(b, true)) / 2;
    }
    for (std::size_t e = 0; e < ne; ++e) {
      if (fwd[e] > 0)
        ++r.start[m_graph.edge_source(Index(e)) + 1];
      if (rev[e] > 0)
        ++r.start[m_graph.edge_target(Index(e)) + 1];
    }
    for (std::size_t p = 0; p < nn; ++p)
      r.start[p + 1] += r.start[p];
    r.head.resize(r.start[nn]);
    std::vector<Index> pos(r.start.begin(), r.start.end() - 1);
    for (std::size_t e = 0; e < ne; ++e) {
      const Index u = m_graph.edge_source(Index(e)), v = m_graph.edge_target(Index(e));
      if (fwd[e] > 0)
        r.head[pos[u]++] = v;
      if (rev[e] > 0)
        r.head[pos[v]++] = u;
    }
    return r;
  }

  // 1 for the nodes reachable from s in `r`, 0 for the others
  static std::vector<char> reachable_from_source(const Residual_graph& r)
  {
    const std::size_t nn = r.tau.size();
    std::vector<char> from_s(nn, 0);
    std::vector<Index> queue;
    queue.reserve(nn);
    for (std::size_t p = 0; p < nn; ++p)
      if (r.tau[p] > 0) {
        from_s[p] = 1;
        queue.push_back(Index(p));
      }
    for (std::size_t k = 0; k < queue.size(); ++k)
      for (Index a = r.start[queue[k]]; a < r.start[queue[k] + 1]; ++a)
        if (!from_s[r.head[a]]) {
          from_s[r.head[a]] = 1;
          queue.push_back(r.head[a]);
        }
    return from_s;
  }

  // the strongly connected components of the `middle` part of `r` (Tarjan,
  // iterative): comp[p] is the component of a middle node p; returns their
  // number
  static Index strongly_connected_components(const Residual_graph& r, const std::vector<char>& middle,
                                             std::vector<Index>& comp)
  {
    const std::size_t nn = r.tau.size();
    const Index none = std::numeric_limits<Index>::max();
    std::vector<Index> order(nn, none), low(nn, 0);
    comp.assign(nn, none);
    std::vector<Index> stack;
    std::vector<std::pair<Index, Index>> calls; // node, next arc
    Index counter = 0, components = 0;
    for (std::size_t root = 0; root < nn; ++root) {
      if (!middle[root] || order[root] != none)
        continue;
      order[root] = low[root] = counter++;
      stack.push_back(Index(root));
      calls.emplace_back(Index(root), r.start[root]);
      while (!calls.empty()) {
        const Index v = calls.back().first;
        const Index a = calls.back().second;
        if (a < r.start[v + 1]) {
          ++calls.back().second;
          const Index w = r.head[a];
          if (!middle[w])
            continue;
          if (order[w] == none) {
            order[w] = low[w] = counter++;
            stack.push_back(w);
            calls.emplace_back(w, r.start[w]);
          } else if (comp[w] == none) { // on the stack
            low[v] = std::min(low[v], order[w]);
          }
          continue;
        }
        calls.pop_back();
        if (!calls.empty())
          low[calls.back().first] = std::min(low[calls.back().first], low[v]);
        if (low[v] == order[v]) {
          Index w;
          do {
            w = stack.back();
            stack.pop_back();
            comp[w] = components;
          } while (w != v);
          ++components;
        }
      }
    }
    return components;
  }

  // the rank of each of the `components` components in their canonical
  // topological order (Kahn, smallest key first, the key of a component
  // being its smallest node)
  static std::vector<Index> topological_ranks(const Residual_graph& r, const std::vector<char>& middle,
                                              const std::vector<Index>& comp, Index components)
  {
    const std::size_t nn = r.tau.size();
    const Index none = std::numeric_limits<Index>::max();
    std::vector<Index> key(components, none), in_degree(components, 0);
    std::vector<Index> comp_start(components + 1, 0);
    for (std::size_t p = 0; p < nn; ++p)
      if (middle[p]) {
        key[comp[p]] = std::min(key[comp[p]], Index(p));
        ++comp_start[comp[p] + 1];
        for (Index a = r.start[p]; a < r.start[p + 1]; ++a)
          if (middle[r.head[a]] && comp[r.head[a]] != comp[p])
            ++in_degree[comp[r.head[a]]];
      }
    for (Index c = 0; c < components; ++c)
      comp_start[c + 1] += comp_start[c];
    std::vector<Index> members(comp_start[components]);
    {
      std::vector<Index> pos(comp_start.begin(), comp_start.end() - 1);
      for (std::size_t p = 0; p < nn; ++p)
        if (middle[p])
          members[pos[comp[p]]++] = Index(p);
    }
    typedef std::pair<Index, Index> Entry; // key, component
    std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> ready;
    for (Index c = 0; c < components; ++c)
      if (in_degree[c] == 0)
        ready.push(Entry(key[c], c));
    std::vector<Index> rank(components, none);
    Index next = 0;
    while (!ready.empty()) {
      const Index c = ready.top().second;
      ready.pop();
      rank[c] = next++;
      for (Index m = comp_start[c]; m < comp_start[c + 1]; ++m) {
        const Index p = members[m];
        for (Index a = r.start[p]; a < r.start[p + 1]; ++a) {
          const Index q = r.head[a];
          if (middle[q] && comp[q] != c && --in_degree[comp[q]] == 0)
            ready.push(Entry(key[comp[q]], comp[q]));
        }
      }
    }
    return rank;
  }

  Max_flow m_graph;
  std::vector<std::pair<double, double>> m_unary; // U_i(0), U_i(1) as given
  std::vector<Term> m_terms;
  std::vector<signed char> m_fixed; // -1, 0 or 1
  std::vector<signed char> m_label; // -1, 0 or 1
  double m_constant = 0.0; // constant of the reparametrised energy
  double m_capacity = 0.0; // total capacity of the arcs of the terms
  double m_penalty = 0.0;  // terminal capacity of a fix, on i and on ī
};

} // namespace internal
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_QPBO_H
