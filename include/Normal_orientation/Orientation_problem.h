// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_ORIENTATION_PROBLEM_H
#define NORMAL_ORIENTATION_ORIENTATION_PROBLEM_H

/// \file Orientation_problem.h
/// The orientation energy (paper eq. 2-3) and the connected components of
/// an orientation problem, for any Boost graph with a signed edge weight map.
///
/// Conventions shared by every function and solver of the package:
/// - every edge `e` of the graph is one pairwise term of the energy between
///   `source(e, g)` and `target(e, g)`; its direction, if the graph is
///   directed, is ignored, so store each neighbour pair once;
/// - the weight w_e = phi * omega is signed: w > 0 asks for equal labels,
///   w < 0 for different labels, |w| is the penalty when the wish is not met;
/// - labels are +1 (keep the normal) or -1 (flip it).

#include <Normal_orientation/Signed_union_find.h>

#include <boost/graph/graph_traits.hpp>
#include <boost/graph/properties.hpp>
#include <boost/property_map/property_map.hpp>

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationProblem
/// The type of a label: +1 keeps a normal, -1 flips it.
typedef signed char Label;

/// \ingroup PkgNormalOrientationProblem
/// The penalty of one edge of weight `w` whose end labels are `l_i`, `l_j`
/// (paper eq. 2): |w| when (w >= 0) xor (l_i == l_j), else 0.
/// \param w the signed weight of the edge
/// \param l_i the label (+1 or -1) of one end
/// \param l_j the label (+1 or -1) of the other end
/// \return the penalty, >= 0
inline double edge_energy(double w, int l_i, int l_j)
{
  const bool same = (l_i == l_j);
  if (w >= 0.0)
    return same ? 0.0 : w;
  return same ? -w : 0.0;
}

/// \ingroup PkgNormalOrientationProblem
/// Returns the energy E(L) of eq. 3 of the labelling `labels` (a readable
/// vertex property map with values +1/-1) on `g` with the signed edge
/// weights `weight` (a readable edge property map).
/// \tparam Graph a model of `EdgeListGraph`
/// \param g the graph: one pairwise term per edge
/// \param weight the signed edge weights
/// \param labels the label (+1 or -1) of every vertex
/// \return the sum of `edge_energy()` over the edges
template <typename Graph, typename WeightMap, typename LabelMap>
double energy(const Graph& g, WeightMap weight, LabelMap labels)
{
  double e = 0.0;
  typename boost::graph_traits<Graph>::edge_iterator it, end;
  for (boost::tie(it, end) = edges(g); it != end; ++it)
    e += edge_energy(double(get(weight, *it)),
                     int(get(labels, source(*it, g))),
                     int(get(labels, target(*it, g))));
  return e;
}

/// \ingroup PkgNormalOrientationProblem
/// Returns the energy of the labelling `labels` with unary terms:
/// E(L) = sum over the edges e = (i, j) of `edge_energy(w_e, L_i, L_j)`
/// (the energy of `energy(g, weight, labels)`) plus, for every vertex i,
/// `get(unary, i).first` if L_i = +1 and `get(unary, i).second` if L_i = -1.
/// \tparam Graph a model of `VertexListGraph` and `EdgeListGraph`
/// \tparam WeightMap a readable edge property map with a floating value
/// \tparam UnaryMap a readable vertex property map whose value has members
///         `first` (the cost of label +1) and `second` (the cost of label
///         -1) convertible to `double`, such as `std::pair<double, double>`
/// \tparam LabelMap a readable vertex property map with values +1/-1
/// \param g the graph: one pairwise term per edge
/// \param weight the signed edge weights
/// \param unary the unary costs of every vertex
/// \param labels the label (+1 or -1) of every vertex
/// \return the energy, edges and unary terms together
template <typename Graph, typename WeightMap, typename UnaryMap, typename LabelMap>
double energy(const Graph& g, WeightMap weight, UnaryMap unary, LabelMap labels)
{
  double e = energy(g, weight, labels);
  typename boost::graph_traits<Graph>::vertex_iterator it, end;
  for (boost::tie(it, end) = vertices(g); it != end; ++it) {
    const auto& costs = get(unary, *it);
    e += int(get(labels, *it)) > 0 ? double(costs.first) : double(costs.second);
  }
  return e;
}

/// \ingroup PkgNormalOrientationProblem
/// Numbers the connected components of the graph formed by the edges of
/// non-zero weight (an edge of weight zero carries no information, so it
/// does not join its ends).  Components are numbered 0, 1, ... in the order
/// of their smallest vertex index; `component[i]` receives the number of
/// vertex `i`.  Returns the number of components.
/// \tparam Graph a model of `VertexListGraph` and `EdgeListGraph` with an
///         internal `vertex_index` map
/// \tparam WeightMap a readable edge property map with a floating value
/// \param g the graph
/// \param weight the signed edge weights (only whether they are zero matters)
/// \param component receives the component of every vertex, by vertex index
/// \return the number of components
template <typename Graph, typename WeightMap>
std::size_t connected_components(const Graph& g, WeightMap weight, std::vector<std::uint32_t>& component)
{
  const std::size_t n = num_vertices(g);
  auto index = get(boost::vertex_index, g);
  Signed_union_find uf(n);
  typename boost::graph_traits<Graph>::edge_iterator it, end;
  for (boost::tie(it, end) = edges(g); it != end; ++it)
    if (double(get(weight, *it)) != 0.0)
      uf.unite(Signed_union_find::Index(get(index, source(*it, g))),
               Signed_union_find::Index(get(index, target(*it, g))));
  const std::uint32_t unset = ~std::uint32_t(0);
  std::vector<std::uint32_t> root_id(n, unset);
  component.assign(n, 0);
  std::size_t count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto r = uf.find(Signed_union_find::Index(i));
    if (root_id[r] == unset)
      root_id[r] = std::uint32_t(count++);
    component[i] = root_id[r];
  }
  return count;
}

/// \cond SKIP_IN_MANUAL
namespace internal {

/// The tag that stands for "no unary terms" in the solvers' implementations.
struct No_unary
{};

/// The energy of `best` (one label per vertex index) on `g`, with the unary
/// terms `unary` unless `UnaryMap` is `No_unary` (the value of `energy()`,
/// summed in the same order), and the number of edges whose wish it does
/// not meet.
template <typename Graph, typename WeightMap, typename UnaryMap>
std::pair<double, std::size_t> labelling_energy(const Graph& g, WeightMap weight, const UnaryMap& unary,
                                                const std::vector<Label>& best)
{
  auto index = get(boost::vertex_index, g);
  double e = 0.0;
  std::size_t frustrated = 0;
  typename boost::graph_traits<Graph>::edge_iterator it, end;
  for (boost::tie(it, end) = edges(g); it != end; ++it) {
    const double term = edge_energy(double(get(weight, *it)), best[std::size_t(get(index, source(*it, g)))],
                                    best[std::size_t(get(index, target(*it, g)))]);
    e += term;
    frustrated += term > 0.0 ? 1 : 0;
  }
  if constexpr (!std::is_same<UnaryMap, No_unary>::value) {
    typename boost::graph_traits<Graph>::vertex_iterator vit, vend;
    for (boost::tie(vit, vend) = vertices(g); vit != vend; ++vit) {
      const auto& costs = get(unary, *vit);
      e += best[std::size_t(get(index, *vit))] > 0 ? double(costs.first) : double(costs.second);
    }
  } else
    (void)unary;
  return {e, frustrated};
}

/// Writes `best` (one label per vertex index) to `labels`.
template <typename Graph, typename LabelMap>
void put_labels(const Graph& g, const std::vector<Label>& best, LabelMap labels)
{
  auto index = get(boost::vertex_index, g);
  typename boost::graph_traits<Graph>::vertex_iterator vit, vend;
  for (boost::tie(vit, vend) = vertices(g); vit != vend; ++vit)
    put(labels, *vit, best[std::size_t(get(index, *vit))]);
}

/// Writes `best` (one label per vertex index) to `labels`; returns
/// `labelling_energy(g, weight, unary, best)`.
template <typename Graph, typename WeightMap, typename UnaryMap, typename LabelMap>
std::pair<double, std::size_t> write_labels(const Graph& g, WeightMap weight, const UnaryMap& unary,
                                            const std::vector<Label>& best, LabelMap labels)
{
  put_labels(g, best, labels);
  return labelling_energy(g, weight, unary, best);
}

/// Returns the unary costs of `unary` by vertex index: `first` the cost of
/// label +1, `second` the cost of label -1.
/// \throw std::invalid_argument (naming `solver`) if a cost is not finite
template <typename Graph, typename UnaryMap>
std::vector<std::pair<double, double>> unary_costs(const Graph& g, UnaryMap unary, const char* solver)
{
  std::vector<std::pair<double, double>> costs(std::size_t(num_vertices(g)), std::pair<double, double>(0.0, 0.0));
  auto index = get(boost::vertex_index, g);
  typename boost::graph_traits<Graph>::vertex_iterator vit, vend;
  for (boost::tie(vit, vend) = vertices(g); vit != vend; ++vit) {
    const auto& c = get(unary, *vit);
    const double plus = double(c.first), minus = double(c.second);
    if (!std::isfinite(plus) || !std::isfinite(minus))
      throw std::invalid_argument(std::string(solver) + ": a unary cost is not finite");
    costs[std::size_t(get(index, *vit))] = {plus, minus};
  }
  return costs;
}

} // namespace internal
/// \endcond

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_ORIENTATION_PROBLEM_H
