// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_ORIENT_NORMALS_H
#define NORMAL_ORIENTATION_ORIENT_NORMALS_H

/// \file orient_normals.h
/// The in-core entry point: `Normal_orientation::orient_normals()`.

#include <Normal_orientation/Component_sign.h>
#include <Normal_orientation/Flip_criteria.h>
#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Orientation_result.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/internal/Core_coarse_scale.h>
#include <Normal_orientation/internal/Core_global_sign.h>
#include <Normal_orientation/internal/Core_layer_cues.h>
#include <Normal_orientation/internal/Settings.h>
#include <Normal_orientation/internal/Unit_vector.h>
#include <Normal_orientation/parameters.h>
#include <Normal_orientation/solvers/Mst_solver.h>
#include <Normal_orientation/solvers/Qpbo_i_solver.h>

#include <CGAL/Kernel_traits.h>
#include <CGAL/boost/graph/named_params_helper.h>
#include <CGAL/property_map.h>
#include <CGAL/tags.h>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/task_arena.h>
#endif

#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <iterator>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace Normal_orientation {


/// \cond SKIP_IN_MANUAL
namespace internal {

/// Whether the named parameters `NamedParameters` carry constraints or priors.
template <typename NamedParameters>
struct Unary_parameters
{
  static constexpr bool has_constraints =
    !CGAL::parameters::is_default_parameter<NamedParameters, CGAL::internal_np::point_is_constrained_t>::value;
  static constexpr bool has_prior =
    !CGAL::parameters::is_default_parameter<NamedParameters, internal_np::orientation_prior_map_t>::value;
};

/// The policies of a run, as both drivers read them.
template <typename FlipCriterion, typename Solver, typename SignPolicy>
struct Policies
{
  FlipCriterion criterion;
  Solver solver;
  SignPolicy sign_policy;
  Global_settings global;
  /// writes their names into `result`
  void name(Orientation_summary& result) const
  {
    result.criterion = name_of(criterion);
    result.solver = name_of(solver);
    result.component_sign = name_of(sign_policy);
  }
};

/// The flip criterion, the solver, the component sign policy and the
/// global stage of `np`, with the defaults of both drivers:
/// `Hoppe_konig_criterion`, `Qpbo_i_solver(3, seed)`, `Outward_component_sign`
/// (or `Constrained_component_sign<>` when there are constraints), and
/// `Global_orientation::VISIBILITY_AND_WINDING` when the sign policy is the
/// default and there are no constraints or priors (which say what the user
/// wants), `Global_orientation::NONE` otherwise; the up direction +z.
template <typename NamedParameters>
auto read_policies(const NamedParameters& np, unsigned long seed)
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  typedef std::conditional_t<Unary_parameters<NamedParameters>::has_constraints, Constrained_component_sign<>,
                             Outward_component_sign>
    Default_sign;
  auto criterion = choose_parameter(get_parameter(np, internal_np::flip_criterion), Hoppe_konig_criterion());
  auto solver = choose_parameter(get_parameter(np, internal_np::solver), Qpbo_i_solver(3, seed));
  auto sign_policy = choose_parameter(get_parameter(np, internal_np::component_sign), Default_sign());
  constexpr bool user_signs = Unary_parameters<NamedParameters>::has_constraints
                              || Unary_parameters<NamedParameters>::has_prior
                              || !CGAL::parameters::is_default_parameter<NamedParameters,
                                                                         internal_np::component_sign_t>::value;
  Global_settings global;
  global.orientation = choose_parameter(get_parameter(np, internal_np::global_orientation),
                                        user_signs ? Global_orientation::NONE
                                                   : Global_orientation::VISIBILITY_AND_WINDING);
  global.up = direction_array(choose_parameter(get_parameter(np, internal_np::up_direction), global.up));
  for (double c : global.up)
    if (!std::isfinite(c))
      throw std::invalid_argument("orient_normals: up_direction is not finite");
  return Policies<decltype(criterion), decltype(solver), decltype(sign_policy)>{criterion, solver, sign_policy,
                                                                                 global};
}

/// The in-core copy of the input: positions, unit normals (zero where the
/// input normal is zero), and the constraints and priors when given.
template <typename Kernel>
struct Core_points
{
  std::vector<typename Kernel::Point_3> points;
  std::vector<typename Kernel::Vector_3> normals;
  std::vector<char> constrained; ///< empty without constraints
  std::vector<double> prior;     ///< empty without priors
};

/// Copies and checks the input (`std::invalid_argument` naming the point
/// for a non-finite coordinate, normal or prior); counts the zero normals.
template <typename Kernel, typename PointRange, typename PointMap, typename NormalMap, typename NamedParameters,
          bool HasConstraints, bool HasPrior>
void copy_input(PointRange& points, const PointMap& point_map, const NormalMap& normal_map,
                const NamedParameters& np, Core_points<Kernel>& out, Orientation_result& result)
{
  typedef typename Kernel::Point_3 Point;
  typedef typename Kernel::Vector_3 Vector;
  const std::size_t n = std::size_t(std::distance(points.begin(), points.end()));
  result.number_of_points = n;
  out.points.reserve(n);
  out.normals.reserve(n);
  std::size_t i = 0;
  for (auto it = points.begin(); it != points.end(); ++it, ++i) {
    const Point& p = get(point_map, *it);
    const Vector v = get(normal_map, *it);
    const double c[6] = {CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z()),
                         CGAL::to_double(v.x()), CGAL::to_double(v.y()), CGAL::to_double(v.z())};
    for (int d = 0; d < 6; ++d)
      if (!std::isfinite(c[d])) {
        std::ostringstream msg;
        msg << "orient_normals: point " << i << " has a non-finite " << (d < 3 ? "coordinate" : "normal");
        throw std::invalid_argument(msg.str());
      }
    out.points.push_back(p);
    const std::array<double, 3> u = unit_vector(c[3], c[4], c[5]);
    out.normals.push_back(Vector(u[0], u[1], u[2]));
    if (u[0] == 0.0 && u[1] == 0.0 && u[2] == 0.0)
      ++result.number_of_zero_normals;
  }
  if constexpr (HasConstraints) {
    const auto cmap = CGAL::parameters::get_parameter(np, CGAL::internal_np::point_is_constrained);
    out.constrained.reserve(n);
    for (auto it = points.begin(); it != points.end(); ++it)
      out.constrained.push_back(get(cmap, *it) ? 1 : 0);
  }
  if constexpr (HasPrior) {
    const auto pmap = CGAL::parameters::get_parameter(np, internal_np::orientation_prior_map);
    out.prior.reserve(n);
    std::size_t j = 0;
    for (auto it = points.begin(); it != points.end(); ++it, ++j) {
      const double a = double(get(pmap, *it));
      if (!std::isfinite(a)) {
        std::ostringstream msg;
        msg << "orient_normals: point " << j << " has a non-finite orientation prior";
        throw std::invalid_argument(msg.str());
      }
      out.prior.push_back(a);
    }
  }
  (void)np;
}

/// Renumbers the points along a Morton curve and returns the order (the
/// input index of each new position): the kNN queries, the graph, the
/// solver and the sign policy then walk memory in a spatially coherent
/// order (random input orders cost several times more).  Ties are broken
/// by input index, so this is deterministic.
template <typename ConcurrencyTag, typename Kernel>
std::vector<std::uint32_t> sort_spatially(Core_points<Kernel>& in)
{
  const std::size_t n = in.points.size();
  const std::vector<std::uint32_t> order = morton_order<ConcurrencyTag>(in.points);
  std::vector<typename Kernel::Point_3> sorted_pts(n);
  std::vector<typename Kernel::Vector_3> sorted_nrm(n);
  parallel_chunks<ConcurrencyTag>(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t q = b; q < e; ++q) {
      sorted_pts[q] = in.points[order[q]];
      sorted_nrm[q] = in.normals[order[q]];
    }
  });
  in.points.swap(sorted_pts);
  in.normals.swap(sorted_nrm);
  if (!in.constrained.empty()) {
    std::vector<char> sorted_constrained(n);
    for (std::size_t q = 0; q < n; ++q)
      sorted_constrained[q] = in.constrained[order[q]];
    in.constrained.swap(sorted_constrained);
  }
  if (!in.prior.empty()) {
    std::vector<double> sorted_prior(n);
    for (std::size_t q = 0; q < n; ++q)
      sorted_prior[q] = in.prior[order[q]];
    in.prior.swap(sorted_prior);
  }
  return order;
}

/// Whether `Solver` takes unary terms on the in-core graph.
template <typename Solver, typename WeightMap, typename LabelMap>
struct Accepts_core_unary
{
  /// the unary map of `solve_core()`
  typedef decltype(boost::make_iterator_property_map(
    std::declval<std::vector<std::pair<double, double>>&>().begin(),
    get(boost::vertex_index, std::declval<const Neighbor_graph&>()))) Unary_map;
  static constexpr bool value = Accepts_unary<Solver, Neighbor_graph, WeightMap, Unary_map, LabelMap>::value;
};

/// Runs `solver` on `graph`, with the constraints and priors of `in` as
/// unary terms when `UserUnary` (a constraint outweighs all the edges
/// together), and the layer cues `cue` (per point, or empty) added to the
/// priors when the solver accepts unary terms; `has_unary` marks the
/// vertices with a unary term.
template <bool UserUnary, typename Solver, typename Kernel, typename WeightMap, typename LabelMap>
Solver_report solve_core(const Solver& solver, const Neighbor_graph& graph, WeightMap weight, LabelMap label_map,
                         const Core_points<Kernel>& in, const std::vector<double>& cue, std::vector<char>& has_unary,
                         Orientation_result& result)
{
  if constexpr (UserUnary || Accepts_core_unary<Solver, WeightMap, LabelMap>::value) {
    if (UserUnary || !cue.empty()) {
      typedef std::pair<double, double> Costs;
      static_assert(Accepts_core_unary<Solver, WeightMap, LabelMap>::value,
                    "orient_normals: point_is_constrained_map and orientation_prior_map need a solver with "
                    "solve(graph, weight, unary, labels)");
      const std::size_t n = in.points.size();
      double hard = 1.0;
      typename boost::graph_traits<Neighbor_graph>::edge_iterator eit, eend;
      for (boost::tie(eit, eend) = edges(graph); eit != eend; ++eit)
        hard += std::abs(double(get(weight, *eit)));
      std::vector<Costs> unary(n, Costs(0.0, 0.0));
      has_unary.assign(n, 0);
      for (std::size_t i = 0; i < n; ++i) {
        double a = (in.prior.empty() ? 0.0 : in.prior[i]) + (cue.empty() ? 0.0 : cue[i]); // > 0: keep (label +1)
        if (!in.constrained.empty() && in.constrained[i])
          a = hard;
        if (a != 0.0 && in.normals[i] != CGAL::NULL_VECTOR) {
          unary[i] = a > 0.0 ? Costs(0.0, a) : Costs(-a, 0.0);
          has_unary[i] = 1;
          ++result.number_of_unary_terms;
        }
      }
      return solver.solve(graph, weight,
                          boost::make_iterator_property_map(unary.begin(), get(boost::vertex_index, graph)), label_map);
    }
  }
  (void)in;
  (void)cue;
  (void)has_unary;
  (void)result;
  return solver.solve(graph, weight, label_map);
}

/// Copies what the graph's construction reports to `result`.
inline void add_graph_report(const Neighbor_graph_report& gr, Orientation_result& result)
{
  result.number_of_edges = gr.number_of_edges;
  result.number_of_neighbors = gr.number_of_neighbors;
  result.neighbor_radius = gr.radius;
  result.radius_estimated = gr.radius_estimated;
  result.konig_disagreement = gr.konig_disagreement;
  result.konig_everywhere = gr.konig_everywhere;
  result.seconds.neighbors = gr.seconds_neighbors;
  result.seconds.graph = gr.seconds_graph;
}

/// The component signs of the labelling `labels` of `graph` (step 4):
/// writes the components to `component` and negates the components that
/// `sign_policy` negates, except those that the unary terms fix.  After a
/// solve with the layer cues `cue` (per point, or empty), `has_unary` marks
/// the cues' points: they move to `cued`, and `cue_fixed` marks the points
/// of the components that the cues fix (`cue_components()`).
template <typename Kernel, typename WeightMap, typename SignPolicy>
void core_component_signs(const Neighbor_graph& graph, WeightMap weight, const SignPolicy& sign_policy,
                          const Core_points<Kernel>& in, double radius, bool has_constraints,
                          const std::vector<double>& cue, std::vector<char>& has_unary, std::vector<char>& cued,
                          std::vector<char>& cue_fixed, std::vector<std::uint32_t>& component,
                          std::vector<Label>& labels, Orientation_result& result)
{
  result.number_of_components = connected_components(graph, weight, component);
  if (!cue.empty()) {
    cued.swap(has_unary);
    cue_fixed = cue_components(cue, component, result.number_of_components, labels);
  }
  const Component_sign_input<Kernel> input{in.points, in.normals, labels, component, result.number_of_components,
                                           radius, has_constraints ? &in.constrained : nullptr};
  std::vector<char> flip = component_signs(sign_policy, input);
  for (const std::vector<char>* fixed : {&has_unary, &cue_fixed}) // (the solver gave these components their sign)
    for (std::size_t i = 0; i < fixed->size(); ++i)
      if ((*fixed)[i])
        flip[component[i]] = 0;
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (flip[component[i]])
      labels[i] = Label(-labels[i]);
}

/// The global stage of the in-core driver: `stage(moved, restart)` runs it
/// on `labels`.  When it negated in full moves of the solver that hold at
/// least `rejected_move_share` of the points (`rejected_moves()`), `labels`
/// start again from `solved` (the solver's labels) with those moves negated,
/// `sign()` gives the components their signs, and the stage runs once more
/// with the moves that remain.  Returns the summary of its last run, with
/// the figures of both.
template <typename Stage, typename Sign>
Global_sign_summary stage_without_rejected_moves(const std::vector<char>& moved, const std::vector<Label>& solved,
                                                 std::vector<Label>& labels, const Stage& stage, const Sign& sign)
{
  Stage_restart restart;
  const Global_sign_summary first = stage(moved, &restart);
  if (restart.rejected == 0)
    return first;
  for (std::size_t i = 0; i < labels.size(); ++i)
    labels[i] = moved[i] && !restart.moved[i] ? Label(-solved[i]) : solved[i];
  sign();
  Global_sign_summary second = stage(restart.moved, nullptr);
  second.moves_rejected = restart.rejected;
  second.moves_completed += first.moves_completed;
  second.seconds += first.seconds;
  return second;
}

/// Negates the normals of `points` whose label in `labels` (in the order of
/// `points`) is -1; returns how many.  Zero normals are never negated: their
/// edges weigh 0, so every solver leaves them at +1.
template <typename PointRange, typename NormalMap>
std::size_t write_back_signs(PointRange& points, const NormalMap& normal_map, const std::vector<Label>& labels)
{
  std::size_t i = 0, flipped = 0;
  for (auto it = points.begin(); it != points.end(); ++it, ++i)
    if (labels[i] < 0) {
      put(normal_map, *it, -get(normal_map, *it));
      ++flipped;
    }
  return flipped;
}

/// The layer cues' round (step 6): where the cues of `report` negate more
/// than `layer_cue_round_share` of the `n` points, they become the unary
/// terms `cue_unary` and `again()` runs the solver and the stage once more,
/// writing its summary to `global`, whose coarse pass's figures are kept
/// from the first round.  The cues' figures go to `global`.
template <typename Again>
void core_layer_cue_round(Layer_cue_report& report, std::vector<double>& cue_unary, std::size_t n,
                          Global_sign_summary& global, const Again& again)
{
  const bool round = double(report.against) > layer_cue_round_share * double(n);
  if (round) {
    cue_unary.swap(report.unary);
    const Global_sign_summary first = global;
    again();
    keep_coarse_report(first, global);
  }
  global.layer_cues = report.sure;
  global.layer_cues_against = report.against;
  global.layer_cue_round = round;
}

} // namespace internal
/// \endcond

/// \ingroup PkgNormalOrientationRef
/// Orients the normals of `points` consistently and, by default, outward.
///
/// The pipeline of the paper (Schertler et al. 2017, sec. 3-4): the
/// symmetric, radius-truncated k-nearest-neighbour graph; edge weights
/// w_ij = phi(i, j) * (1 - d_ij^2 / r^2) from a flip criterion; a solver
/// minimising the energy of eq. 3 over the labels L_i in {+1, -1}; then a
/// component sign policy fixes the free sign of every connected component;
/// then, by default, the global sign stage lets the winding number of the
/// cloud decide the signs of patches where it is closed (touching and
/// nested objects, flat faces), and where the input normals disagree (noise
/// wider than the spacing) a coarser cloud may give the signs, in which case
/// a solver with a starting solver (`initial`) does not run (see the manual,
/// "Noise Wider than the Spacing"); finally n_i <- L_i n_i through the
/// normal map.
///
/// The input order is never changed and only the sign of normals changes
/// (their length and direction are kept exactly).  Zero normals are left
/// as they are.  When the callback interrupts the run, or an exception is
/// thrown, no normal has been modified.
///
/// \tparam ConcurrencyTag `CGAL::Parallel_tag`, `CGAL::Sequential_tag` or
///   `CGAL::Parallel_if_available_tag` (the default); results are the same
///   for any choice and any number of threads.
/// \tparam PointRange a model of `Range` whose iterator is a forward
///   iterator; its value type is the key of the point and normal maps.
///
/// \param points the input points, with unoriented normals
/// \param np optional named parameters among the following ones (described
///   on the page \ref NormalOrientationNamedParameters):
/// \cgalNamedParamsBegin
///   \cgalParamNBegin{point_map}
///     \cgalParamDescription{a property map associating points to the elements of `points`}
///     \cgalParamType{a model of `ReadablePropertyMap` with value type `geom_traits::Point_3`}
///     \cgalParamDefault{`CGAL::Identity_property_map<geom_traits::Point_3>`}
///   \cgalParamNEnd
///   \cgalParamNBegin{normal_map}
///     \cgalParamDescription{a property map associating normals to the elements of `points`}
///     \cgalParamType{a model of `ReadWritePropertyMap` with value type `geom_traits::Vector_3`}
///     \cgalParamDefault{none: this parameter is required}
///   \cgalParamNEnd
///   \cgalParamNBegin{geom_traits}
///     \cgalParamDescription{the geometric traits}
///     \cgalParamDefault{the kernel of the point type}
///   \cgalParamNEnd
///   \cgalParamNBegin{number_of_neighbors}
///     \cgalParamDescription{k of the k-nearest-neighbour graph (a `Normal_orientation::parameters` name)}
///     \cgalParamType{unsigned int, at least 1}
///     \cgalParamDefault{`default_number_of_neighbors` (12)}
///   \cgalParamNEnd
///   \cgalParamNBegin{neighbor_radius}
///     \cgalParamDescription{the radius r: no edge is longer, and omega = 1 - d^2 / r^2}
///     \cgalParamType{floating scalar value > 0}
///     \cgalParamDefault{estimated: `default_radius_factor` times a high percentile of the k-th neighbour distance}
///   \cgalParamNEnd
///   \cgalParamNBegin{flip_criterion}
///     \cgalParamDescription{a model of `FlipCriterion`}
///     \cgalParamDefault{`Hoppe_konig_criterion()`}
///   \cgalParamNEnd
///   \cgalParamNBegin{layer_edges}
///     \cgalParamDescription{whether the edges across two layers closer than the neighbour distance
///       are negated (`build_neighbor_graph()`), and the layer cues run; off, the graph is the
///       paper's}
///     \cgalParamType{`bool`}
///     \cgalParamDefault{`true`}
///   \cgalParamNEnd
///   \cgalParamNBegin{solver}
///     \cgalParamDescription{a model of `OrientationSolver`}
///     \cgalParamDefault{`Qpbo_i_solver(3, random_seed)`: MST, then QPBO-I on the segment graph; on the
///       benchmark clouds it leaves a third fewer wrong normals than the MST at 1.2-1.5 times its
///       run time (see the README); `Mst_solver()` is the fastest}
///   \cgalParamNEnd
///   \cgalParamNBegin{component_sign}
///     \cgalParamDescription{a model of `ComponentSignPolicy`}
///     \cgalParamDefault{`Outward_component_sign()`, or `Constrained_component_sign<>()` when `point_is_constrained_map` is given}
///   \cgalParamNEnd
///   \cgalParamNBegin{global_orientation}
///     \cgalParamDescription{the global sign stage after the component signs: components and sheets
///       face the side they were seen from (`exterior_visibility()`), then the winding number of the
///       whole cloud decides the signs of patches where it is closed (see `decide_patch_signs()`)}
///     \cgalParamType{`Global_orientation`}
///     \cgalParamDefault{`Global_orientation::VISIBILITY_AND_WINDING` with the default `component_sign`
///       and without constraints or priors, `Global_orientation::NONE` otherwise}
///   \cgalParamNEnd
///   \cgalParamNBegin{up_direction}
///     \cgalParamDescription{the scene's up direction for exterior visibility: views from below weigh
///       less, and a component whose top surface faces down is negated last
///       (`downward_top_flips()`); a zero vector gives no side a preference and turns that rule off}
///     \cgalParamType{`Kernel::Vector_3`}
///     \cgalParamDefault{`Kernel::Vector_3(0, 0, 1)`}
///   \cgalParamNEnd
///   \cgalParamNBegin{point_is_constrained_map}
///     \cgalParamDescription{points whose input normal is known to be correctly oriented: hard
///       constraints, given to the solver as unary terms that outweigh all the edges together, so
///       every solver keeps them; their components keep their sign}
///     \cgalParamType{a model of `ReadablePropertyMap` with value type `bool`}
///     \cgalParamDefault{no constrained point}
///   \cgalParamNEnd
///   \cgalParamNBegin{orientation_prior_map}
///     \cgalParamDescription{a soft prior per point (a `Normal_orientation::parameters` name): a value
///       a > 0 favours keeping the input normal, a < 0 favours flipping it, with the weight |a| of an
///       edge (edges weigh at most 1); 0 for no prior.  A viewpoint prior, for example, is
///       a_i = lambda * cos(angle between n_i and the direction from p_i to the viewpoint).  The
///       solver weighs priors against the edges; the components with a prior keep the sign the
///       solver gave them}
///     \cgalParamType{a model of `ReadablePropertyMap` with a floating value type}
///     \cgalParamDefault{no prior}
///   \cgalParamNEnd
///   \cgalParamNBegin{callback}
///     \cgalParamDescription{called with the progress, from the calling thread; returning `false` interrupts the
///       run (see `Progress.h`)}
///     \cgalParamType{`std::function<bool(double)>` (the fraction of the run done, in [0, 1]) or a callable as
///       `bool(const Progress_info&)` (the stage too)}
///     \cgalParamDefault{none}
///   \cgalParamNEnd
///   \cgalParamNBegin{random_seed}
///     \cgalParamDescription{the seed of randomised solvers}
///     \cgalParamType{unsigned int}
///     \cgalParamDefault{`0`}
///   \cgalParamNEnd
///   \cgalParamNBegin{number_of_threads}
///     \cgalParamDescription{the maximum number of threads (a `Normal_orientation::parameters` name)}
///     \cgalParamType{int, 0 for all}
///     \cgalParamDefault{`0`}
///   \cgalParamNEnd
/// \cgalNamedParamsEnd
///
/// \return an `Orientation_result`
/// \throw std::invalid_argument for k < 1, r <= 0, a negative thread
///   count, or a non-finite coordinate, normal or prior (the message names the point)
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange,
          typename NamedParameters = parameters::Default_named_parameters>
Orientation_result orient_normals(PointRange& points, const NamedParameters& np = parameters::default_values())
{
  typedef CGAL::Point_set_processing_3_np_helper<PointRange, NamedParameters> NP_helper;
  typedef typename NP_helper::Geom_traits Kernel;
  static_assert(NP_helper::has_normal_map(), "orient_normals: the normal_map named parameter is required");

  const auto t_start = std::chrono::steady_clock::now();
  const auto point_map = NP_helper::get_point_map(points, np);
  const auto normal_map = NP_helper::get_normal_map(points, np);
  const internal::Settings settings = internal::read_settings(np, "orient_normals");
  const auto policies = internal::read_policies(np, settings.random_seed);
  const auto& criterion = policies.criterion;
  const auto& solver = policies.solver;
  const auto& sign_policy = policies.sign_policy;
  constexpr bool has_constraints = internal::Unary_parameters<NamedParameters>::has_constraints;
  constexpr bool has_prior = internal::Unary_parameters<NamedParameters>::has_prior;

  Orientation_result result;
  policies.name(result);

  // 1. Copy and check the input; normals are normalised for the criteria.
  internal::Core_points<Kernel> in;
  internal::copy_input<Kernel, PointRange, std::decay_t<decltype(point_map)>, std::decay_t<decltype(normal_map)>,
                       NamedParameters, has_constraints, has_prior>(points, point_map, normal_map, np, in, result);
  const std::size_t n = in.points.size();
  if (n == 0) {
    result.seconds.total = result.seconds.input = internal::seconds_since(t_start);
    return result;
  }

  std::vector<Label> input_labels(n, Label(1));
  try {
    internal::run_with_threads(settings.number_of_threads, [&]() {
      const Progress_reporter& progress = settings.progress;
      progress.part(Stage::INPUT, 0.0, 0.0).report(0.0);
      // Labels are mapped back to the input order at the end.
      const std::vector<std::uint32_t> order = internal::sort_spatially<ConcurrencyTag>(in);
      result.seconds.input = internal::seconds_since(t_start);

      // 2. Graph, with the edges across two layers negated.
      Neighbor_graph graph;
      std::vector<internal::Layer_offset> layer_offsets;
      std::vector<std::uint8_t> layer_gaps; // (for the global stage's field)
      const Neighbor_graph_report gr = build_neighbor_graph<ConcurrencyTag, Kernel>(
        in.points, in.normals, settings.number_of_neighbors, settings.neighbor_radius, criterion, graph,
        progress.part(Stage::GRAPH, 0.0, 0.8), settings.layer_edges, &layer_offsets,
        policies.global.orientation != Global_orientation::NONE ? &layer_gaps : nullptr);
      internal::add_graph_report(gr, result);
      const auto weight = get(&Neighbor_edge::weight, graph);
      const internal::Layer_pairs layer_pairs = internal::core_layer_pairs(layer_offsets, graph, weight);
      std::vector<internal::Layer_offset>().swap(layer_offsets);
      std::vector<Label> labels(n, Label(1));
      const auto label_map = CGAL::make_property_map(labels);
      result.energy_before = energy(graph, weight, label_map);

      // 3-5. Solve (with unary terms when there are constraints or priors),
      // give every component its sign, then the global stage.
      // The field's samples are dense where the input normals agree (the
      // coarse pass does not run), except on the pass's own coarse cloud.
      std::vector<char> has_unary; // per vertex, with unary terms only
      std::vector<double> cue_unary; // per vertex, the layer cues' unary terms (empty: none)
      constexpr bool coarse_cloud =
        internal::Is_coarse_cloud_point<typename std::iterator_traits<decltype(points.begin())>::value_type>::value;
      // Layer cues: not with the user's unary terms, nor on the coarse pass's own cloud.
      constexpr bool cues_possible =
        !has_constraints && !has_prior && !coarse_cloud &&
        internal::Accepts_core_unary<std::decay_t<decltype(solver)>, decltype(weight), decltype(label_map)>::value;
      bool want_cues = cues_possible && policies.global.orientation != Global_orientation::NONE;
      internal::Layer_cue_report cue_report;
      std::vector<std::uint32_t> final_component; // (of the last `fine`; `open_scene` per component, for the
      std::vector<char> open_scene;               // canopy rule, with the cells of the coarse pass's grid)
      std::shared_ptr<const internal::Canopy_cells> canopy;
      auto fine = [&](const auto& the_solver, bool, bool dense) {
        internal::Global_settings global = policies.global;
        global.dense_samples = dense && !coarse_cloud;
        auto t = std::chrono::steady_clock::now();
        std::fill(labels.begin(), labels.end(), Label(1));
        const Solver_report sr = internal::solve_core<has_constraints || has_prior>(
          the_solver, graph, weight, label_map, in, cue_unary, has_unary, result);
        result.frustrated_edges = sr.frustrated_edges;
        result.number_of_segments = sr.segments;
        const std::vector<char> moved = internal::solver_moves(labels, sr.starting_labels);
        result.seconds.solve += internal::seconds_since(t);
        progress.part(Stage::SOLVE, 0.8, 0.9).report(1.0);

        std::vector<std::uint32_t> component;
        std::vector<char> cued, cue_fixed; // (the layer cues' points, and those of the components they fix)
        auto sign = [&](bool again) { // (again: the cues' points back where the solve left them)
          if (again && !cue_unary.empty())
            cued.swap(has_unary);
          t = std::chrono::steady_clock::now();
          internal::core_component_signs(graph, weight, sign_policy, in, gr.radius, has_constraints, cue_unary,
                                         has_unary, cued, cue_fixed, component, labels, result);
          result.seconds.sign += internal::seconds_since(t);
        };
        const std::vector<Label> solved = moved.empty() ? std::vector<Label>() : labels; // (for a second run)
        sign(false);
        progress.part(Stage::SIGN, 0.9, 0.92).report(1.0);

        if (policies.global.orientation != Global_orientation::NONE) {
          progress.part(Stage::GLOBAL, 0.92, 1.0).report(0.0);
          auto stage = [&](const std::vector<char>& the_moved, internal::Stage_restart* r) {
            return internal::core_global_signs<ConcurrencyTag, Kernel>(
              graph, in.points, in.normals, component, gr.radius, has_unary, cued, cue_fixed, the_moved, global,
              labels, &layer_pairs, want_cues && dense ? &cue_report : nullptr, // (none where noise hides the layers)
              &layer_gaps, &open_scene, r);
          };
          result.global = internal::stage_without_rejected_moves(moved, solved, labels, stage, [&]() { sign(true); });
          result.seconds.global += result.global.seconds;
        }
        final_component = std::move(component);
      };
      // Noise wider than the spacing: the signs of a coarser scale (Coarse_scale.h).
      constexpr bool coarse_pass = !has_constraints && !has_prior; // (no pass with unary terms)
      if (coarse_pass && policies.global.orientation != Global_orientation::NONE) {
        auto orient_coarse = [&](auto& cloud) {
          return orient_normals<ConcurrencyTag>(
                   cloud, internal::coarse_cloud_parameters<Kernel>(criterion, solver, settings, policies.global))
            .global.closedness;
        };
        canopy = internal::core_coarse_stage<ConcurrencyTag, Kernel>(
          in.points, in.normals, gr.radius, solver, fine, orient_coarse, labels, result.global, result.seconds.global,
          [&]() { cue_report.unary.clear(); }); // (the cues were of the fine labels)
      } else {
        fine(solver, true, true);
      }
      // 6. Layer cues: where two layers lie closer than the neighbour
      // distance, the far field decides their signs (Layer_cues.h); the
      // solver and the stage run once more with the cues as unary terms when
      // they negate enough points.
      if (want_cues)
        internal::core_layer_cue_round(cue_report, cue_unary, n, result.global, [&]() {
          want_cues = false;        // (the round asks for no cues)
          fine(solver, true, true); // (cues come only from the dense step: the pass did not run)
        });
      result.global.layer_pairs = layer_pairs.size();
      // 7. The canopy rule, last (Canopy_rule.h).
      internal::core_canopy_rule(canopy.get(), in.points, in.normals, final_component, open_scene, policies.global,
                                 labels, result.global, result.seconds.global);
      result.energy_after = energy(graph, weight, label_map);
      for (std::size_t q = 0; q < n; ++q)
        input_labels[order[q]] = labels[q];
      progress.part(Stage::GLOBAL, 0.92, 1.0).report(1.0);
    });
  } catch (const Interrupted&) {
    result.interrupted = true;
    result.seconds.total = internal::seconds_since(t_start);
    return result;
  }

  // 8. Write back: only the sign changes.
  const auto t_out = std::chrono::steady_clock::now();
  result.number_of_flipped = internal::write_back_signs(points, normal_map, input_labels);
  result.seconds.output = internal::seconds_since(t_out);
  result.seconds.total = internal::seconds_since(t_start);
  return result;
}

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_ORIENT_NORMALS_H
