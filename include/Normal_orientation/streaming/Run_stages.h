// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_RUN_STAGES_H
#define NORMAL_ORIENTATION_STREAMING_RUN_STAGES_H

/// \file Run_stages.h
/// The stages of the streaming driver in their order (`run_stages()`),
/// and `orient_stream()`, which reads the named parameters and runs them:
/// what `streaming_orient_normals()` and the file entry points call.

#include <Normal_orientation/Component_sign.h>
#include <Normal_orientation/Flip_criteria.h>
#include <Normal_orientation/IO/Point_stream.h>
#include <Normal_orientation/IO/Point_stream_transcode.h>
#include <Normal_orientation/Point_record.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/orient_normals.h>
#include <Normal_orientation/Segmenter.h>
#include <Normal_orientation/internal/Settings.h>
#include <Normal_orientation/parameters.h>
#include <Normal_orientation/solvers/Qpbo_i_solver.h>
#include <Normal_orientation/internal/Core_coarse_scale.h>
#include <Normal_orientation/streaming/Coarse_stage.h>
#include <Normal_orientation/streaming/Component_files.h>
#include <Normal_orientation/streaming/Labelled_records.h>
#include <Normal_orientation/streaming/Output_stage.h>
#include <Normal_orientation/streaming/Record_file.h>
#include <Normal_orientation/streaming/Refine_stage.h>
#include <Normal_orientation/streaming/Refinement.h>
#include <Normal_orientation/streaming/Scan.h>
#include <Normal_orientation/streaming/Segment_solve.h>
#include <Normal_orientation/streaming/Segmenting_sweep.h>
#include <Normal_orientation/streaming/Global_stage.h>
#include <Normal_orientation/streaming/Sign_stage.h>
#include <Normal_orientation/streaming/Streaming_result.h>
#include <Normal_orientation/streaming/Streaming_settings.h>
#include <Normal_orientation/streaming/Sweep.h>
#include <Normal_orientation/streaming/external_sort.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Named_function_parameters.h>
#include <CGAL/tags.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>
#include <type_traits>
#include <vector>

namespace Normal_orientation {

/// \cond SKIP_IN_MANUAL
namespace streaming {
namespace internal {

/// The unary term of a record: `hard` for a constrained point, else its
/// prior (see `orient_normals()`).
template <typename ConstrainedMap, typename PriorMap, bool HasConstraints, bool HasPrior>
struct Record_unary
{
  static constexpr bool enabled = HasConstraints || HasPrior;
  ConstrainedMap constrained;
  PriorMap prior;
  double hard = 1.0;
  double operator()(const Point_record& r) const
  {
    if constexpr (HasConstraints)
      if (get(constrained, r))
        return hard;
    if constexpr (HasPrior) {
      const double a = double(get(prior, r));
      if (!std::isfinite(a))
        throw std::invalid_argument("streaming_orient_normals: the point of input index " + std::to_string(r.index) +
                                    " has a non-finite orientation prior");
      return a;
    }
    return 0.0;
  }
  bool is_constrained(const Point_record& r) const
  {
    if constexpr (HasConstraints)
      return bool(get(constrained, r));
    else
      return (void)r, false;
  }
};

/// What the file-level entry points add to a run: a change of the settings
/// read from the named parameters, and a call with the number of points
/// before the output stage.
struct Run_hooks
{
  std::function<void(Streaming_settings&)> adjust;
  std::function<void(std::uint64_t)> before_output;
};

/// the parts of the whole run that the stages report in
inline Progress_reporter stage_progress(const Progress_reporter& p, Stage stage)
{
  static const double begin[] = {0.0, 0.0, 0.0, 0.08, 0.1, 0.25, 0.7, 0.72, 0.85, 0.88, 0.9, 0.98};
  static const double end[] = {0.0, 0.0, 0.08, 0.1, 0.25, 0.7, 0.72, 0.85, 0.88, 0.9, 0.98, 1.0};
  return p.part(stage, begin[int(stage)], end[int(stage)]);
}

/// The first stages: the scan (count, zero normals, frame or order) and,
/// when r is not given, its estimate; then the rule of clean positions
/// (internal/Clean_positions.h) on `criterion`, which the sweep is to use;
/// returns the number of points.  `box` gets their bounding box.
template <typename ConcurrencyTag, typename Kernel, typename Source, typename FlipCriterion>
std::uint64_t scan_and_radius_stages(Source& source, const Streaming_settings& settings, int axis, Sweep_frame& frame,
                                     Normal_orientation::internal::Morton_code& box, FlipCriterion& criterion,
                                     Streaming_result& result)
{
  using Normal_orientation::internal::seconds_since;
  auto t = std::chrono::steady_clock::now();
  const bool estimate_radius = settings.neighbor_radius == 0.0;
  Scan_result<typename Kernel::Point_3> scanned =
    scan<typename Kernel::Point_3>(source, axis, estimate_radius, stage_progress(settings.progress, Stage::SCAN),
                                   std::is_same<FlipCriterion, Hoppe_konig_criterion>::value);
  const std::uint64_t n = scanned.number_of_points;
  frame = scanned.frame;
  box = scanned.box;
  result.number_of_zero_normals = scanned.number_of_zero_normals;
  result.seconds.frame = seconds_since(t);
  if (n == 0)
    return 0;
  t = std::chrono::steady_clock::now();
  // A small cloud kept for the rule of clean positions is also the whole
  // radius sample: one search serves both.
  const Small_cloud_neighbors<Kernel> small =
    small_cloud_neighbors<ConcurrencyTag, Kernel>(scanned.small_cloud, settings.number_of_neighbors);
  result.neighbor_radius = settings.neighbor_radius;
  if (estimate_radius) {
    const Progress_reporter progress = stage_progress(settings.progress, Stage::RADIUS);
    progress.report(0, 1);
    result.neighbor_radius = small.k > 0 ? radius_of_neighbors(small.d2, small.k, 1.0)
                                         : sample_radius<ConcurrencyTag, Kernel>(scanned.sample,
                                                                                  settings.number_of_neighbors, n);
    result.radius_estimated = true;
    progress.report(1, 1);
  }
  const Normal_orientation::internal::Clean_positions clean =
    Normal_orientation::internal::apply_clean_positions(criterion, std::size_t(n), [&]() {
      return small.k > 0 ? Normal_orientation::internal::konig_disagreement<ConcurrencyTag>(small.points, small.normals,
                                                                                            small.nb, small.k)
                         : std::numeric_limits<double>::quiet_NaN();
    });
  result.konig_disagreement = clean.konig_disagreement;
  result.konig_everywhere = clean.konig_everywhere;
  result.seconds.radius = seconds_since(t);
  return n;
}

/// The last stages: the output, without the components smaller than
/// `settings.minimum_component_size`, then one file per kept component when
/// asked; `segment_size` is per sweep segment.
template <typename Sink>
void output_stages(Labelled_reader& points, const Segment_solution& solution, const std::vector<char>& flip_component,
                   const std::vector<std::uint64_t>& segment_size, const Streaming_settings& settings, Sink& sink,
                   Component_file_set& component_files, std::uint64_t n, Streaming_result& result)
{
  using Normal_orientation::internal::seconds_since;
  std::vector<std::uint64_t> size(solution.number_of_components, 0);
  for (std::size_t s = 0; s < segment_size.size(); ++s)
    size[solution.component[s]] += segment_size[s];
  const Component_ranking ranking(size, settings.minimum_component_size);
  result.number_of_dropped_components = ranking.dropped_components;
  result.number_of_dropped_points = ranking.dropped_points;
  const Final_signs signs{solution.component, flip_component, ranking};
  auto t = std::chrono::steady_clock::now();
  result.number_of_flipped = output_stage(points, signs, sink, n, stage_progress(settings.progress, Stage::OUTPUT));
  result.seconds.output = seconds_since(t);
  if (component_files.enabled() && ranking.kept > 0) {
    t = std::chrono::steady_clock::now();
    component_files_stage(points, signs, settings.component_files, settings.temporary_directory, component_files, n,
                          stage_progress(settings.progress, Stage::COMPONENTS));
    result.seconds.components = seconds_since(t);
  }
  result.component_files = component_files.files();
}

/// Stages 3-4: the external sort (unless `settings` says presorted, when
/// `source` is swept as it is and rewound), then the sweep, which segments
/// the points into `segmenter`, writes them to `records` and, when `edges`
/// is not null, each point's earlier edges for the refinement; both files
/// are rewound.  Fills the sweep's figures of `result`.
template <typename ConcurrencyTag, typename Kernel, typename Source, typename FlipCriterion, typename Unary>
Sweep_stage_result sort_and_sweep_stages(Source& source, const Streaming_settings& settings, int axis,
                                         const Sweep_frame& frame, const Normal_orientation::internal::Morton_code& box,
                                         const FlipCriterion& criterion, const Unary& unary,
                                         std::uint64_t n, Segmenter& segmenter, Record_file<Swept_record>& records,
                                         Record_file<Earlier_edge>* edges, Streaming_result& result)
{
  using Normal_orientation::internal::seconds_since;
  const bool presorted = settings.presorted_axis != Presorted_axis::NONE;
  auto t = std::chrono::steady_clock::now();
  Sorted_run_reader sorted;
  if (!presorted) {
    const Progress_reporter progress = stage_progress(settings.progress, Stage::SORT);
    progress.report(0, n);
    Reporting_source<Source> counted(source, progress, n);
    sorted = external_sort(counted, frame, settings.sort);
    progress.report(n, n);
    result.seconds.sort = seconds_since(t);
  }

  t = std::chrono::steady_clock::now();
  const Progress_reporter progress = stage_progress(settings.progress, Stage::SWEEP);
  progress.report(0, n);
  Sweep_stage_result swept;
  swept.grid_origin = Normal_orientation::internal::Morton_first(box);
  Segmenting_visitor<ConcurrencyTag, Kernel, FlipCriterion, Unary> visitor(
    criterion, unary, segmenter, records, edges, result.neighbor_radius, progress, n, swept, settings.layer_edges);
  Sweep_window<Sweep_payload> window;
  Sweep_options so;
  so.number_of_neighbors = settings.number_of_neighbors;
  so.radius = result.neighbor_radius;
  so.batch_size = settings.batch_size;
  const Sweep_report sr =
    presorted ? sweep<ConcurrencyTag, Kernel>(
                  source, [axis](const Point_record& r) { return r.position[axis]; }, so, visitor, window)
              : sweep<ConcurrencyTag, Kernel>(
                  sorted, [&frame](const Point_record& r) { return frame.key(r); }, so, visitor, window);
  sorted = Sorted_run_reader(); // removes the sort's files
  if (presorted)
    source.rewind();
  records.rewind();
  if (edges)
    edges->rewind();
  result.number_of_points = sr.number_of_points;
  result.number_of_edges = sr.number_of_edges;
  result.peak_window = sr.peak_window;
  result.edge_span = swept.edge_span;
  result.energy_before = swept.energy_before;
  result.number_of_unary_terms = swept.unary_terms;
  progress.report(n, n);
  result.seconds.sweep = seconds_since(t);
  return swept;
}

/// The refinement of `labels` (`refine_stage()`; no round when the energy
/// is negligible against `total_weight`, the edges' absolute weights), with
/// its figures in `result`.
template <typename ConcurrencyTag, typename Solver>
void refinement_stage(Record_file<Swept_record>& records, Record_file<Earlier_edge>& edges, std::uint64_t n,
                      const Streaming_settings& settings, double total_weight, const Solver& solver,
                      Point_labels& labels, Streaming_result& result)
{
  const auto t = std::chrono::steady_clock::now();
  const unsigned int rounds =
    settings.refinement.worth_running(result.energy_before_refinement, total_weight) ? settings.refinement.rounds : 0;
  const Refine_stage_result rr = refine_stage<ConcurrencyTag>(
    records, edges, n, result.edge_span, settings.refinement, rounds, settings.temporary_directory, solver,
    result.energy_before_refinement, labels, stage_progress(settings.progress, Stage::REFINE));
  result.energy_after_refinement = rr.energy_after;
  result.refinement_rounds_accepted = rr.rounds_accepted;
  result.refinement_moves = rr.moves;
  result.seconds.refine = Normal_orientation::internal::seconds_since(t);
}

/// The stages, run one after the other (see `streaming_orient_normals()`).
template <typename ConcurrencyTag, typename Kernel, typename Source, typename Sink, typename FlipCriterion,
          typename Solver, typename SignPolicy, typename Unary>
void run_stages(Source& source, Sink& sink, const Streaming_settings& settings, const FlipCriterion& criterion,
                const Solver& solver, const SignPolicy& sign_policy,
                const Normal_orientation::internal::Global_settings& global, Unary unary,
                const Run_hooks& hooks, Streaming_result& result)
{
  using Normal_orientation::internal::seconds_since;
  typedef std::chrono::steady_clock Clock;
  const auto stage = [&](Stage s) { return stage_progress(settings.progress, s); };
  const bool presorted = settings.presorted_axis != Presorted_axis::NONE;
  const int axis = settings.presorted_axis == Presorted_axis::Y ? 1 : settings.presorted_axis == Presorted_axis::Z ? 2
                   : presorted                                  ? 0
                                                                : -1;
  const unsigned int k = settings.number_of_neighbors;
  result.presorted = presorted;
  result.number_of_neighbors = k;
  Component_file_set component_files(settings.component_files); // checks and creates the directory

  // 1-2. Scan and radius.
  Sweep_frame frame;
  Normal_orientation::internal::Morton_code box;
  FlipCriterion phi = criterion; // the sweep's (the coarse cloud starts again from `criterion`)
  const std::uint64_t n =
    scan_and_radius_stages<ConcurrencyTag, Kernel>(source, settings, axis, frame, box, phi, result);
  if (n == 0) {
    component_files.keep();
    return;
  }
  const double radius = result.neighbor_radius;
  unary.hard = 1.0 + double(k) * double(n); // outweighs all the edges together

  // 3-4. Sort (unless presorted), sweep and segment.
  Record_file<Swept_record> records(settings.temporary_directory);
  const bool refine = settings.refinement.rounds > 0 && !Unary::enabled;
  std::unique_ptr<Record_file<Earlier_edge>> edges; // for the refinement: each point's earlier edges
  if (refine)
    edges = std::make_unique<Record_file<Earlier_edge>>(settings.temporary_directory, 1 << 16);
  Segmenter segmenter(settings.thresholds);
  const Sweep_stage_result swept =
    sort_and_sweep_stages<ConcurrencyTag, Kernel>(source, settings, axis, frame, box, phi, unary, n, segmenter,
                                                  records, edges.get(), result);
  auto t = Clock::now();

  // 5-8. The segment graph and its solution, the refinement (skipped when
  // the labelling's energy, known from the segment graph, is negligible:
  // `Refinement_options::negligible_energy`), the sign of every component,
  // then the global stage (exterior visibility and the winding number of a
  // subsample).
  Segment_solution solution;
  Point_labels labels;
  std::vector<char> flip_component;
  std::vector<char> open_scene; // (per component, for the canopy rule)
  std::shared_ptr<const Normal_orientation::internal::Canopy_cells> canopy;
  Labelled_reader points(records, labels);
  // Layer cues (Stream_layer_cues.h): not with the user's unary terms; a
  // second solve with them as unary terms of the sweep's segments when they
  // negate enough samples.
  constexpr bool cues_possible = !Unary::enabled && solves_segments_with_unary<Solver>();
  const bool want_cues = cues_possible && settings.layer_edges && global.orientation != Global_orientation::NONE;
  Stream_layer_cues cues;
  bool cue_round = false;
  std::vector<char> cue_has_unary; // (per sweep segment, in the cue round: the user's or the cues' fixed components)
  auto fine = [&](const auto& the_solver, bool with_refinement, bool dense) {
    t = Clock::now();
    stage(Stage::SOLVE).report(0, 1);
    solution = solve_segment_graph_stage(segmenter, the_solver, Unary::enabled, cue_round ? &cues.preference : nullptr);
    result.number_of_segments = segmenter.number_of_segments();
    result.number_of_segment_edges = solution.number_of_segment_edges;
    result.segment_energy_before = solution.energy_before;
    result.segment_energy_after = solution.energy_after;
    result.number_of_components = solution.number_of_components;
    stage(Stage::SOLVE).report(1, 1);
    result.seconds.solve += seconds_since(t);

    labels = Point_labels(); // (a second call starts afresh)
    labels.segment_labels = solution.labels;
    result.energy_before_refinement = segmenter.point_energy(solution.labels);
    result.energy_after_refinement = result.energy_before_refinement;
    if (refine && with_refinement && !cue_round)
      refinement_stage<ConcurrencyTag>(records, *edges, n, settings, swept.total_weight, the_solver, labels, result);
    result.energy_after = result.energy_after_refinement;

    t = Clock::now();
    const std::vector<char>& has_unary = cue_round ? cue_has_unary : swept.segment_has_unary;
    flip_component = sign_stage(
      sign_policy, [&unary](const Point_record& r) { return unary.is_constrained(r); }, points, solution.component,
      solution.number_of_components, swept.segment_size, has_unary, radius, n, stage(Stage::SIGN));
    result.seconds.sign += seconds_since(t);

    if (global.orientation != Global_orientation::NONE) {
      t = Clock::now();
      Normal_orientation::internal::Global_settings g = global;
      g.dense_samples = dense;
      result.global = global_stage<ConcurrencyTag>(points, labels, solution.component, flip_component, has_unary,
                                                   radius, n, swept.layer_gap_points, g, stage(Stage::GLOBAL),
                                                   Unit_inputs{edges.get(), result.edge_span,
                                                               settings.temporary_directory},
                                                   want_cues && dense && !cue_round ? &cues : nullptr, double(k),
                                                   cue_round, &open_scene);
      result.seconds.global += seconds_since(t);
    }
  };
  // Noise wider than the spacing: the signs of a coarser scale (Coarse_scale.h).
  if (!Unary::enabled && global.orientation != Global_orientation::NONE) {
    auto orient_coarse = [&](auto& cloud) {
      return orient_normals<ConcurrencyTag>(
               cloud, Normal_orientation::internal::coarse_cloud_parameters<Kernel>(criterion, solver, settings, global))
        .global.closedness;
    };
    canopy = coarse_stage<Kernel>(records, radius, swept.grid_origin.position(), n, solver, fine, orient_coarse, labels,
                                  solution.component, flip_component, result.global, result.seconds.global);
  } else {
    fine(solver, true, true);
  }
  // The layer cues' round, as in core (`layer_cue_round_share`).
  if (want_cues) {
    const bool round = cues.ask_for_a_round();
    if (round) { // (`cues` stays: the round does not ask for cues)
      cue_has_unary = cues.segments_with_unary(swept.segment_has_unary, solution.component);
      cue_round = true;
      const Global_sign_summary first = result.global;
      fine(solver, false, true);
      Normal_orientation::internal::keep_coarse_report(first, result.global);
    }
    result.global.layer_cues = cues.sure;
    result.global.layer_cues_against = cues.against;
    result.global.layer_cue_round = round;
  }
  result.global.layer_pairs = swept.two_layer_points;
  // The canopy rule, last (Canopy_rule.h), unless the coarse signs were
  // taken (their own stage decided).
  if (canopy && Normal_orientation::internal::any_open_scene(open_scene) && !result.global.coarse_used) {
    result.global.canopy_cells = canopy->size();
    install_canopy_rule(canopy, open_scene, Normal_orientation::internal::canopy_up(global), solution.component,
                        flip_component, labels);
  }
  edges.reset(); // removes the edge file
  if (global.orientation != Global_orientation::NONE && labels.point_flip)
    result.energy_after = std::numeric_limits<double>::quiet_NaN(); // (point by point: not measured)

  // 9-10. Output, without the small components, and the component files.
  if (hooks.before_output)
    hooks.before_output(n);
  output_stages(points, solution, flip_component, swept.segment_size, settings, sink, component_files, n, result);
  component_files.keep();
}

/// Reads the named parameters `np` and runs the stages; an interruption by
/// the callback returns a result whose `interrupted` is true.
template <typename ConcurrencyTag, typename Source, typename Sink, typename NamedParameters>
Streaming_result orient_stream(Source& source, Sink& sink, const NamedParameters& np, const char* caller,
                               const Run_hooks& hooks)
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  namespace inp = Normal_orientation::internal_np;
  typedef std::decay_t<decltype(choose_parameter(get_parameter(np, CGAL::internal_np::geom_traits),
                                                 CGAL::Exact_predicates_inexact_constructions_kernel()))>
    Kernel;
  const auto t_start = std::chrono::steady_clock::now();
  Streaming_settings settings = read_streaming_settings(np, caller);
  if (hooks.adjust)
    hooks.adjust(settings);
  const auto policies = Normal_orientation::internal::read_policies(np, settings.random_seed);
  constexpr bool has_constraints = Normal_orientation::internal::Unary_parameters<NamedParameters>::has_constraints;
  constexpr bool has_prior = Normal_orientation::internal::Unary_parameters<NamedParameters>::has_prior;
  const auto constrained = choose_parameter(get_parameter(np, CGAL::internal_np::point_is_constrained), false);
  const auto prior = choose_parameter(get_parameter(np, inp::orientation_prior_map), false);
  Record_unary<std::decay_t<decltype(constrained)>, std::decay_t<decltype(prior)>, has_constraints, has_prior> unary{
    constrained, prior, 1.0};

  Streaming_result result;
  policies.name(result);
  try {
    Normal_orientation::internal::run_with_threads(settings.number_of_threads, [&]() {
      run_stages<ConcurrencyTag, Kernel>(source, sink, settings, policies.criterion, policies.solver,
                                         policies.sign_policy, policies.global, unary, hooks, result);
    });
  } catch (const Interrupted&) {
    result.interrupted = true;
  }
  result.seconds.total = Normal_orientation::internal::seconds_since(t_start);
  return result;
}

} // namespace internal
} // namespace streaming
/// \endcond
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_RUN_STAGES_H
