// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_SOLVERS_MST_SOLVER_H
#define NORMAL_ORIENTATION_SOLVERS_MST_SOLVER_H

/// \file Mst_solver.h
/// The maximum-spanning-tree solver on the signed union-find (supplement,
/// Algorithm 1).

#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Signed_union_find.h>
#include <Normal_orientation/solvers/Solver_report.h>

#include <boost/graph/graph_traits.hpp>
#include <boost/property_map/property_map.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationSolvers
/// Kruskal's maximum spanning forest with respect to |w|, propagating the
/// orientation while the forest grows (supplement, Algorithm 1): edges are
/// taken in decreasing |w|; an edge that joins two components first flips
/// one of them, in constant time on the signed union-find, if the edge's
/// wish is not met, then merges them.  Edges inside a component are
/// ignored, which is why the result can be far from optimal when strong
/// edges contradict many weaker ones (paper, Figure 2).  It is exact when
/// the problem is balanced (some labelling meets every edge).
///
/// Edges of weight zero carry no information and are skipped, so each
/// component of the result is a component of the non-zero edges.  Edges are
/// ranked by |w| rounded to single precision; equal ranks are taken in the
/// order of `edges(g)`, so the result is deterministic, whatever the number
/// of threads.  The global sign of every component is left as it comes
/// (see `Component_sign.h`); vertices without edges get +1.
///
/// Cost: O(E) for the sort (radix), then O(E alpha(V)).
/// Memory: about 24 bytes per edge and 7 bytes per vertex during the solve.
/// \cgalModels `OrientationSolver`
class Mst_solver
{
public:
  /// the name used on the command line and in reports
  static const char* name() { return "mst"; }

  /// Solves the orientation problem on `g` with the signed edge weights
  /// `weight` and writes +1/-1 to `labels` for every vertex.
  /// \tparam Graph a model of `VertexListGraph` and `EdgeListGraph` with an
  ///         internal `vertex_index` map (vertex indices 0 ... n-1)
  /// \tparam WeightMap a readable edge property map with a floating value
  /// \tparam LabelMap a writable vertex property map accepting `Label`
  template <typename Graph, typename WeightMap, typename LabelMap>
  Solver_report solve(const Graph& g, WeightMap weight, LabelMap labels) const
  {
    const auto start = std::chrono::steady_clock::now();
    typedef typename boost::graph_traits<Graph>::edge_iterator edge_iterator;
    const std::size_t n = num_vertices(g);
    auto index = get(boost::vertex_index, g);

    // 1. Gather the informative edges with a 32-bit sort key: the
    //    complement of |w| as float bits, so that larger |w| comes first.
    //    The sign of w is kept in the top bit of the head.  The ends travel
    //    with the key, so the Kruskal loop below reads the edges
    //    sequentially.
    const std::uint32_t negative_bit = 0x80000000u;
    if (n >= std::size_t(negative_bit))
      throw std::length_error("Mst_solver: more than 2^31 - 1 vertices");
    struct Sorted_edge
    {
      std::uint32_t key, tail, head;
    };
    std::vector<Sorted_edge> sorted;
    sorted.reserve(std::size_t(num_edges(g)));
    edge_iterator it, end;
    for (boost::tie(it, end) = edges(g); it != end; ++it) {
      const double w = double(get(weight, *it));
      if (!(w != 0.0))
        continue; // zero (or NaN) weights carry no information
      const std::size_t u = std::size_t(get(index, source(*it, g)));
      const std::size_t v = std::size_t(get(index, target(*it, g)));
      if (u == v)
        continue;
      float a = float(std::abs(w));
      std::uint32_t bits;
      std::memcpy(&bits, &a, sizeof bits);
      sorted.push_back({~bits, std::uint32_t(u), std::uint32_t(v) | (w < 0.0 ? negative_bit : 0u)});
    }

    // 2. Sort by decreasing |w|, ties in the order of edges(g): a stable
    //    least-significant-digit radix sort on the key, two 16-bit digits.
    //    The order is fully determined, whatever the number of threads.
    {
      std::vector<Sorted_edge> buffer(sorted.size());
      std::vector<std::size_t> start(std::size_t(1) << 16);
      for (int shift = 0; shift < 32; shift += 16) {
        std::fill(start.begin(), start.end(), std::size_t(0));
        for (const Sorted_edge& e : sorted)
          ++start[(e.key >> shift) & 0xffffu];
        std::size_t sum = 0;
        for (std::size_t& c : start) {
          const std::size_t count = c;
          c = sum;
          sum += count;
        }
        for (const Sorted_edge& e : sorted)
          buffer[start[(e.key >> shift) & 0xffffu]++] = e;
        sorted.swap(buffer);
      }
    }

    // 3. Kruskal with orientation propagation on the signed union-find.
    Signed_union_find uf(n);
    Solver_report report;
    for (const Sorted_edge& e : sorted) {
      const std::uint32_t u = e.tail, v = e.head & ~negative_bit;
      bool su, sv;
      const auto ru = uf.find(u, su), rv = uf.find(v, sv);
      if (ru == rv)
        continue;
      if ((su != sv) != ((e.head & negative_bit) != 0))
        uf.flip_root(rv);
      uf.unite_roots(ru, rv);
      ++report.tree_edges;
    }
    report.iterations = sorted.size();

    // 4. Labels, then energy and frustrated edges in one pass.
    std::vector<Label> label(n);
    for (std::size_t i = 0; i < n; ++i)
      label[i] = Label(uf.sign(std::uint32_t(i)) ? -1 : 1);
    typename boost::graph_traits<Graph>::vertex_iterator vit, vend;
    for (boost::tie(vit, vend) = vertices(g); vit != vend; ++vit)
      put(labels, *vit, label[std::size_t(get(index, *vit))]);
    for (const Sorted_edge& e : sorted) {
      const bool negative = (e.head & negative_bit) != 0;
      if ((label[e.tail] == label[e.head & ~negative_bit]) == negative)
        ++report.frustrated_edges;
    }
    report.energy = energy(g, weight, labels);
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
  }
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_SOLVERS_MST_SOLVER_H
