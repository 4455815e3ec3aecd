// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_SEGMENT_SOLVE_H
#define NORMAL_ORIENTATION_STREAMING_SEGMENT_SOLVE_H

/// \file Segment_solve.h
/// The solve stage of the streaming driver: the segment graph that the
/// sweep accumulated, solved by the solver policy (with the segments'
/// summed unary terms when there are any), and its connected components.

#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Segmenter.h>
#include <Normal_orientation/internal/Settings.h>
#include <Normal_orientation/streaming/Refinement.h>

#include <CGAL/property_map.h>

#include <boost/property_map/property_map.hpp>

#include <cstdint>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// The solution of the segment graph.
struct Segment_solution
{
  std::vector<Label> labels;            ///< per segment
  std::vector<std::uint32_t> component; ///< per segment
  std::size_t number_of_components = 0;
  std::size_t number_of_segment_edges = 0;
  double energy_before = 0.0, energy_after = 0.0; ///< of the segment graph (its edges)
};

/// Whether `Solver` solves the segment graph with unary terms.
template <typename Solver>
constexpr bool solves_segments_with_unary()
{
  typedef std::pair<double, double> Costs;
  typedef decltype(get(&Neighbor_edge::weight, std::declval<const Neighbor_graph&>())) Weight;
  typedef decltype(boost::make_iterator_property_map(std::declval<std::vector<Costs>&>().begin(),
                                                     get(boost::vertex_index, std::declval<const Neighbor_graph&>())))
    Unary;
  typedef decltype(CGAL::make_property_map(std::declval<std::vector<Label>&>())) Labels;
  return Normal_orientation::internal::Accepts_unary<Solver, Neighbor_graph, Weight, Unary, Labels>::value;
}

/// Solves the segment graph of `segmenter` with `solver`, with the
/// segments' unary preferences when `with_unary`, plus `extra` (per
/// segment, in the same frame) when it is not null.
template <typename Solver>
Segment_solution solve_segment_graph_stage(const Segmenter& segmenter, const Solver& solver, bool with_unary,
                                           const std::vector<double>* extra = nullptr)
{
  Segment_solution out;
  const std::size_t ns = segmenter.number_of_segments();
  const Neighbor_graph sg = make_segment_graph(segmenter);
  out.number_of_segment_edges = num_edges(sg);
  const auto weight = get(&Neighbor_edge::weight, sg);
  out.labels.assign(ns, Label(1));
  const auto labels = CGAL::make_property_map(out.labels);
  out.energy_before = energy(sg, weight, labels);
  if (with_unary || extra != nullptr) {
    typedef std::pair<double, double> Costs;
    std::vector<Costs> unary(ns, Costs(0.0, 0.0));
    const std::vector<double>& preference = segmenter.segment_preferences();
    for (std::size_t s = 0; s < ns; ++s) { // > 0: keep the preliminary orientation (label +1)
      const double p = (with_unary ? preference[s] : 0.0) + (extra != nullptr && s < extra->size() ? (*extra)[s] : 0.0);
      unary[s] = p > 0.0 ? Costs(0.0, p) : Costs(-p, 0.0);
    }
    const auto unary_map = boost::make_iterator_property_map(unary.begin(), get(boost::vertex_index, sg));
    if constexpr (solves_segments_with_unary<Solver>())
      solver.solve(sg, weight, unary_map, labels);
    else
      throw std::invalid_argument("streaming_orient_normals: point_is_constrained_map and orientation_prior_map "
                                  "need a solver with solve(graph, weight, unary, labels)");
  } else {
    solver.solve(sg, weight, labels);
  }
  out.energy_after = energy(sg, weight, labels);
  out.number_of_components = connected_components(sg, weight, out.component);
  return out;
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_SEGMENT_SOLVE_H
