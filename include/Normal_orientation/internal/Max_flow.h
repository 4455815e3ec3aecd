// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_MAX_FLOW_H
#define NORMAL_ORIENTATION_INTERNAL_MAX_FLOW_H

/// \file Max_flow.h
/// A maximum-flow / minimum-cut solver for the sparse graphs met in binary
/// MRF minimisation: the augmenting-path algorithm of Y. Boykov and
/// V. Kolmogorov ("An experimental comparison of min-cut/max-flow algorithms
/// for energy minimization in vision", IEEE PAMI 26(9), 2004), written for
/// this package from the published description, with the reuse of the search
/// trees between solves of P. Kohli and P. H. S. Torr ("Dynamic graph cuts
/// for efficient inference in Markov random fields", IEEE PAMI 29(12), 2007).
///
/// Only the standard library is used.

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

namespace Normal_orientation {
namespace internal {

/// \ingroup PkgNormalOrientationSolvers
/// Maximum flow and minimum cut between two terminals, the source s and the
/// sink t, by the Boykov–Kolmogorov algorithm.
///
/// The graph has nodes 0 ... number_of_nodes()-1 (created by add_nodes()),
/// terminal links s->v and v->t (add_terminal_weights()) and pairs of
/// opposite arcs between nodes (add_edge()).  Capacities are `double`s.
///
/// The algorithm grows two search trees, S from the source and T from the
/// sink, over the residual graph.  When they touch, the flow is augmented
/// along the path found; the arcs saturated on the path cut some nodes off
/// their tree (the orphans), which then look for a new parent in the same
/// tree or become free.  The algorithm stops when neither tree can grow;
/// the minimum cut separates the nodes of S from all the others.
///
/// **Incremental re-solve.**  After max_flow(), terminal capacities may be
/// changed (add_terminal_weights(), including negative amounts) and edges
/// added; the next max_flow() then keeps the trees and the flow of the
/// previous solve and re-examines only the nodes touched since (they are
/// recorded in a list of changed nodes, see mark_node()).  A decrease of a
/// terminal capacity below the flow it carries is absorbed by
/// reparametrisation (adding the same amount to both terminal links of the
/// node, which shifts every cut by that amount), as in Kohli & Torr.  The
/// result equals that of a fresh solve on the modified graph.
///
/// Capacities must be finite and non-negative (the sums given for each
/// terminal link included); use a large finite value rather than infinity.
///
/// Storage: flat vectors, 32-bit indices, 16 bytes per arc (two per edge)
/// and 32 bytes per node; no allocation per node.  Not thread safe.
class Max_flow
{
public:
  /// node and edge indices
  typedef std::uint32_t Index;

  /// creates an empty graph, reserving room for `expected_nodes` nodes and
  /// `expected_edges` edges
  explicit Max_flow(std::size_t expected_nodes = 0, std::size_t expected_edges = 0)
  {
    m_nodes.reserve(expected_nodes);
    m_arcs.reserve(2 * expected_edges);
  }

  /// the number of nodes
  std::size_t number_of_nodes() const { return m_nodes.size(); }

  /// the number of edges (pairs of opposite arcs)
  std::size_t number_of_edges() const { return m_arcs.size() / 2; }

  /// adds `n` nodes without terminal links and returns the index of the
  /// first one (the new nodes are `first ... first+n-1`)
  Index add_nodes(std::size_t n)
  {
    const std::size_t first = m_nodes.size();
    if (n >= std::size_t(max_index) - first)
      throw std::length_error("Max_flow: too many nodes for 32-bit indices");
    m_nodes.resize(first + n);
    return Index(first);
  }

  /// adds `cap_source` to the capacity of the link s->`node` and `cap_sink`
  /// to that of `node`->t.  Only the difference of the two capacities
  /// matters for the cut: their common part is pushed at once as flow
  /// s->`node`->t.  Negative amounts are allowed as long as the total
  /// capacities (the sums of all amounts given for the node) stay
  /// non-negative; after a max_flow() they are absorbed by
  /// reparametrisation.  Marks the node as changed (see mark_node()).
  void add_terminal_weights(Index node, double cap_source, double cap_sink)
  {
    check_node(node);
    Node& v = m_nodes[node];
    // residual capacities of s->v and v->t; at most one of them is non-zero
    const double to_node = (v.terminal > 0 ? v.terminal : 0.0) + cap_source;
    const double to_sink = (v.terminal < 0 ? -v.terminal : 0.0) + cap_sink;
    // push min(to_node, to_sink) along s->v->t; if it is negative, the flow
    // already on a link exceeds its new capacity and adding -min to both
    // links (every cut grows by -min) makes it feasible again
    m_flow += std::min(to_node, to_sink);
    v.terminal = to_node - to_sink;
    mark_node(node);
  }

  /// adds an edge between nodes `i` and `j` made of the arc i->j, of
  /// capacity `cap`, and of the arc j->i, of capacity `rev_cap`, and returns
  /// its index (edges are numbered 0, 1, ... in the order of creation).
  /// Both capacities must be non-negative; parallel edges are allowed,
  /// loops are not.  After a max_flow(), marks both nodes as changed.
  Index add_edge(Index i, Index j, double cap, double rev_cap)
  {
    check_node(i);
    check_node(j);
    if (i == j)
      throw std::invalid_argument("Max_flow::add_edge: loop");
    const std::size_t a = m_arcs.size();
    if (a + 2 >= std::size_t(max_index))
      throw std::length_error("Max_flow: too many edges for 32-bit indices");
    m_arcs.push_back(Arc{j, m_nodes[i].first_arc, cap});
    m_arcs.push_back(Arc{i, m_nodes[j].first_arc, rev_cap});
    m_nodes[i].first_arc = Index(a);
    m_nodes[j].first_arc = Index(a + 1);
    if (m_solved) {
      mark_node(i);
      mark_node(j);
    }
    return Index(a / 2);
  }

  /// records `node` as changed: the next max_flow() re-examines it.
  /// add_terminal_weights() and add_edge() call it; call it yourself only
  /// if you change the graph otherwise (nothing else changes it now).
  void mark_node(Index node)
  {
    check_node(node);
    Node& v = m_nodes[node];
    if (!(v.flags & changed_flag)) {
      v.flags |= changed_flag;
      m_changed.push_back(node);
    }
  }

  /// computes the maximum flow from s to t and returns its value.  The
  /// first call starts from the empty trees; later calls resume from the
  /// trees and the flow of the previous call, re-examining only the changed
  /// nodes (see the class description), and return the maximum flow of the
  /// modified graph.
  double max_flow()
  {
    if (m_solved)
      restart_from_changes();
    else
      init_trees();
    for (Index v : m_changed)
      m_nodes[v].flags &= ~changed_flag;
    m_changed.clear();
    m_solved = true;
    grow_and_augment();
    return m_flow;
  }

  /// the value of the flow found by the last max_flow(), counting the flow
  /// pushed since by add_terminal_weights()
  double flow() const { return m_flow; }

  /// after max_flow(): `true` if `node` is on the source side of the minimum
  /// cut (it is reachable from s in the residual graph), `false` if it is on
  /// the sink side
  bool is_source_side(Index node) const
  {
    check_node(node);
    const Node& v = m_nodes[node];
    return v.parent != free_node && !(v.flags & sink_flag);
  }

  /// the residual capacity of the link s->`node` if positive, minus that of
  /// `node`->t if negative (at most one of them is non-zero)
  double terminal_residual(Index node) const
  {
    check_node(node);
    return m_nodes[node].terminal;
  }

  /// the first node (tail of the arc i->j) of edge `e`
  Index edge_source(Index e) const { return m_arcs[2 * std::size_t(e) + 1].head; }

  /// the second node (head of the arc i->j) of edge `e`
  Index edge_target(Index e) const { return m_arcs[2 * std::size_t(e)].head; }

  /// the residual capacity of the arc i->j of edge `e` (`reverse == false`)
  /// or of the arc j->i (`reverse == true`)
  double edge_residual(Index e, bool reverse = false) const
  {
    return m_arcs[2 * std::size_t(e) + (reverse ? 1 : 0)].residual;
  }

private:
  static constexpr Index max_index = std::numeric_limits<Index>::max();
  // values of Node::parent that are not arcs
  static constexpr Index free_node = max_index;        // in no tree
  static constexpr Index terminal_parent = max_index - 1; // root of its tree
  static constexpr Index orphan_parent = max_index - 2;   // lost its parent
  static constexpr Index no_arc = max_index;

  static constexpr std::uint8_t sink_flag = 1;    // in T (else in S, if in a tree)
  static constexpr std::uint8_t active_flag = 2;  // in the active queue (or being scanned)
  static constexpr std::uint8_t changed_flag = 4; // in m_changed

  struct Node
  {
    Index first_arc = no_arc; // list of the arcs leaving the node
    Index parent = free_node; // arc from the node to its parent, or a marker above
    Index stamp = 0;          // time when `distance` was known exact
    Index distance = 0;       // number of arcs to the terminal (heuristic)
    double terminal = 0.0;    // residual s->v if > 0, minus residual v->t if < 0
    std::uint8_t flags = 0;
  };

  struct Arc
  {
    Index head;      // node the arc enters
    Index next;      // next arc leaving the same tail
    double residual; // residual capacity
  };

  static Index sister(Index a) { return a ^ 1u; }

  void check_node(Index node) const
  {
    if (std::size_t(node) >= m_nodes.size())
      throw std::out_of_range("Max_flow: no such node");
  }

  bool in_tree(const Node& v) const { return v.parent != free_node; }
  static bool in_sink_tree(const Node& v) { return (v.flags & sink_flag) != 0; }
  static bool has_arc_parent(const Node& v) { return v.parent < orphan_parent; }

  void next_time()
  {
    if (++m_time == 0) { // wrapped around: forget every stamp
      for (Node& v : m_nodes)
        v.stamp = 0;
      m_time = 1;
    }
  }

  void activate(Index node)
  {
    Node& v = m_nodes[node];
    if (!(v.flags & active_flag)) {
      v.flags |= active_flag;
      m_active.push_back(node);
    }
  }

  // next node of the active queue, or free_node if none is left
  Index pop_active()
  {
    while (m_active_head < m_active.size()) {
      const Index node = m_active[m_active_head++];
      if (in_tree(m_nodes[node]))
        return node; // keeps its active flag while it is scanned
      m_nodes[node].flags &= ~active_flag;
    }
    m_active.clear();
    m_active_head = 0;
    return free_node;
  }

  void make_root(Index node, bool sink)
  {
    Node& v = m_nodes[node];
    v.parent = terminal_parent;
    v.flags = std::uint8_t(sink ? (v.flags | sink_flag) : (v.flags & ~sink_flag));
    v.stamp = m_time;
    v.distance = 1;
    activate(node);
  }

  void make_orphan(Index node)
  {
    m_nodes[node].parent = orphan_parent;
    m_orphans.push_back(node);
  }

  // first solve: the roots of S and T are the nodes with a terminal residual
  void init_trees()
  {
    m_active.clear();
    m_active_head = 0;
    m_time = 1;
    for (Index i = 0; i < Index(m_nodes.size()); ++i) {
      Node& v = m_nodes[i];
      v.parent = free_node;
      v.flags &= changed_flag;
      v.stamp = 0;
      if (v.terminal > 0)
        make_root(i, false);
      else if (v.terminal < 0)
        make_root(i, true);
    }
  }

  // Re-solve.  Invariants left by the previous solve: every node with a
  // positive (negative) terminal residual is a root of S (of T); the trees
  // are valid; every node of S has been scanned since its last growth, so
  // the residual arcs leaving S all enter S.  Only the changed nodes can
  // break them; repair those and resume.
  void restart_from_changes()
  {
    next_time();
    for (Index i : m_changed) {
      Node& v = m_nodes[i];
      const int want = v.terminal > 0 ? 1 : (v.terminal < 0 ? -1 : 0); // S, T, none
      if (!in_tree(v)) {
        if (want != 0)
          make_root(i, want < 0);
        else
          activate(i); // harmless; a free node is skipped
        continue;
      }
      const int tree = in_sink_tree(v) ? -1 : 1;
      if (want == tree) {
        // connected to its own terminal: become a root (the subtree stays valid)
        v.parent = terminal_parent;
        v.stamp = m_time;
        v.distance = 1;
        activate(i);
      } else if (want == 0) {
        if (v.parent == terminal_parent)
          make_orphan(i); // lost its terminal link: look for another parent
        activate(i);
      } else {
        // connected to the other terminal: leave the tree, then root the other one
        detach(i);
        make_root(i, want < 0);
      }
    }
    adopt_orphans();
  }

  // `node` leaves its tree: its children become orphans and its neighbours
  // of the same tree that could grow into it become active
  void detach(Index node)
  {
    const bool sink = in_sink_tree(m_nodes[node]);
    for (Index a = m_nodes[node].first_arc; a != no_arc; a = m_arcs[a].next) {
      const Index q = m_arcs[a].head;
      Node& w = m_nodes[q];
      if (!in_tree(w) || in_sink_tree(w) != sink)
        continue;
      // residual arc from the neighbour's tree towards `node`
      if ((sink ? m_arcs[a].residual : m_arcs[sister(a)].residual) > 0)
        activate(q);
      if (has_arc_parent(w) && m_arcs[w.parent].head == node)
        make_orphan(q);
    }
    m_nodes[node].parent = free_node;
  }

  // Distance to the terminal of the tree of `node` along parent arcs, or 0
  // if the path ends at an orphan.  Stamps the nodes of a valid path.
  Index origin_distance(Index node)
  {
    Index d = 0;
    Index x = node;
    for (;;) {
      Node& v = m_nodes[x];
      if (v.stamp == m_time) {
        d += v.distance;
        break;
      }
      if (v.parent == terminal_parent) {
        v.stamp = m_time;
        v.distance = 1;
        d += 1;
        break;
      }
      if (!has_arc_parent(v))
        return 0; // orphan (or free)
      ++d;
      x = m_arcs[v.parent].head;
    }
    Index dd = d;
    for (x = node; m_nodes[x].stamp != m_time; x = m_arcs[m_nodes[x].parent].head) {
      m_nodes[x].stamp = m_time;
      m_nodes[x].distance = dd--;
    }
    return d;
  }

  void adopt_orphans()
  {
    for (std::size_t k = 0; k < m_orphans.size(); ++k) {
      const Index p = m_orphans[k];
      Node& v = m_nodes[p];
      if (v.parent != orphan_parent)
        continue; // re-rooted meanwhile
      const bool sink = in_sink_tree(v);
      if (sink ? v.terminal < 0 : v.terminal > 0) {
        v.parent = terminal_parent;
        v.stamp = m_time;
        v.distance = 1;
        continue;
      }
      // the valid parent closest to the terminal
      Index best_arc = no_arc;
      Index best_distance = max_index;
      for (Index a = v.first_arc; a != no_arc; a = m_arcs[a].next) {
        const Index q = m_arcs[a].head;
        const Node& w = m_nodes[q];
        if (!in_tree(w) || in_sink_tree(w) != sink)
          continue;
        if ((sink ? m_arcs[a].residual : m_arcs[sister(a)].residual) <= 0)
          continue;
        const Index d = origin_distance(q);
        if (d != 0 && d < best_distance) {
          best_distance = d;
          best_arc = a;
        }
      }
      if (best_arc != no_arc) {
        v.parent = best_arc;
        v.stamp = m_time;
        v.distance = best_distance + 1;
      } else {
        detach(p);
      }
    }
    m_orphans.clear();
  }

  // augments along s -> ... -> tail(a) -> head(a) -> ... -> t, where
  // tail(a) is in S and head(a) in T, and collects the orphans
  void augment(Index middle)
  {
    double bottleneck = m_arcs[middle].residual;
    Index x = m_arcs[sister(middle)].head;
    for (;;) { // S side, up to the source
      const Node& v = m_nodes[x];
      if (v.parent == terminal_parent) {
        bottleneck = std::min(bottleneck, v.terminal);
        break;
      }
      bottleneck = std::min(bottleneck, m_arcs[sister(v.parent)].residual);
      x = m_arcs[v.parent].head;
    }
    x = m_arcs[middle].head;
    for (;;) { // T side, down to the sink
      const Node& v = m_nodes[x];
      if (v.parent == terminal_parent) {
        bottleneck = std::min(bottleneck, -v.terminal);
        break;
      }
      bottleneck = std::min(bottleneck, m_arcs[v.parent].residual);
      x = m_arcs[v.parent].head;
    }

    m_arcs[middle].residual -= bottleneck;
    m_arcs[sister(middle)].residual += bottleneck;
    x = m_arcs[sister(middle)].head;
    for (;;) {
      Node& v = m_nodes[x];
      if (v.parent == terminal_parent) {
        v.terminal -= bottleneck;
        if (v.terminal <= 0) {
          v.terminal = 0;
          make_orphan(x);
        }
        break;
      }
      const Index a = v.parent;
      m_arcs[a].residual += bottleneck;
      m_arcs[sister(a)].residual -= bottleneck;
      x = m_arcs[a].head;
      if (m_arcs[sister(a)].residual <= 0)
        make_orphan(m_arcs[sister(a)].head);
    }
    x = m_arcs[middle].head;
    for (;;) {
      Node& v = m_nodes[x];
      if (v.parent == terminal_parent) {
        v.terminal += bottleneck;
        if (v.terminal >= 0) {
          v.terminal = 0;
          make_orphan(x);
        }
        break;
      }
      const Index a = v.parent;
      m_arcs[a].residual -= bottleneck;
      m_arcs[sister(a)].residual += bottleneck;
      x = m_arcs[a].head;
      if (m_arcs[a].residual <= 0)
        make_orphan(m_arcs[sister(a)].head);
    }
    m_flow += bottleneck;
  }

  // scans the arcs of the active node `p`; returns the arc from S to T
  // found, or no_arc once every neighbour reachable from `p` is in its tree
  Index grow(Index p)
  {
    const Node& v = m_nodes[p];
    const bool sink = in_sink_tree(v);
    for (Index a = v.first_arc; a != no_arc; a = m_arcs[a].next) {
      // residual arc in the direction of the tree's growth
      if ((sink ? m_arcs[sister(a)].residual : m_arcs[a].residual) <= 0)
        continue;
      const Index q = m_arcs[a].head;
      Node& w = m_nodes[q];
      if (!in_tree(w)) {
        w.parent = sister(a);
        w.flags = std::uint8_t(sink ? (w.flags | sink_flag) : (w.flags & ~sink_flag));
        w.stamp = v.stamp;
        w.distance = v.distance + 1;
        activate(q);
      } else if (in_sink_tree(w) != sink) {
        return sink ? sister(a) : a;
      }
    }
    return no_arc;
  }

  void grow_and_augment()
  {
    Index p = free_node;
    for (;;) {
      if (p == free_node || !in_tree(m_nodes[p])) {
        if (p != free_node)
          m_nodes[p].flags &= ~active_flag;
        p = pop_active();
        if (p == free_node)
          break;
      }
      const Index a = grow(p);
      if (a == no_arc) {
        m_nodes[p].flags &= ~active_flag; // passive: fully scanned
        p = free_node;
        continue;
      }
      next_time();
      augment(a);
      adopt_orphans();
      // keep scanning p (if it is still in a tree)
    }
  }

  std::vector<Node> m_nodes;
  std::vector<Arc> m_arcs;
  std::vector<Index> m_active;
  std::size_t m_active_head = 0;
  std::vector<Index> m_orphans;
  std::vector<Index> m_changed;
  Index m_time = 0;
  double m_flow = 0.0;
  bool m_solved = false;
};

} // namespace internal
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_MAX_FLOW_H
