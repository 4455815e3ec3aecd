// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_ORIENT_NORMALS_H
#define NORMAL_ORIENTATION_STREAMING_ORIENT_NORMALS_H

/// \file streaming_orient_normals.h
/// The out-of-core entry points (paper sec. 5): orient clouds larger than
/// memory by sorting them along their principal axis (or reading them as
/// they are when they are already sorted along x, y or z), sweeping them
/// with a window of bounded size, segmenting on the fly, solving the
/// segment graph and re-streaming the points with their final signs.  They
/// take the named parameters of `orient_normals()`, and a few of their own;
/// this file is a short orchestrator over the stages in `streaming/`.

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
/// returns the number of points.
template <typename ConcurrencyTag, typename Kernel, typename Source, typename FlipCriterion>
std::uint64_t scan_and_radius_stages(Source& source, const Streaming_settings& settings, int axis, Sweep_frame& frame,
                                     FlipCriterion& criterion, Streaming_result& result)
{
  using Normal_orientation::internal::seconds_since;
  auto t = std::chrono::steady_clock::now();
  const bool estimate_radius = settings.neighbor_radius == 0.0;
  Scan_result<typename Kernel::Point_3> scanned =
    scan<typename Kernel::Point_3>(source, axis, estimate_radius, stage_progress(settings.progress, Stage::SCAN),
                                   std::is_same<FlipCriterion, Hoppe_konig_criterion>::value);
  const std::uint64_t n = scanned.number_of_points;
  frame = scanned.frame;
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
  FlipCriterion phi = criterion; // the sweep's (the coarse cloud starts again from `criterion`)
  const std::uint64_t n = scan_and_radius_stages<ConcurrencyTag, Kernel>(source, settings, axis, frame, phi, result);
  if (n == 0) {
    component_files.keep();
    return;
  }
  const double radius = result.neighbor_radius;
  unary.hard = 1.0 + double(k) * double(n); // outweighs all the edges together

  // 3. Sort (unless presorted).
  auto t = Clock::now();
  Sorted_run_reader sorted;
  if (!presorted) {
    const Progress_reporter progress = stage(Stage::SORT);
    progress.report(0, n);
    Reporting_source<Source> counted(source, progress, n);
    sorted = external_sort(counted, frame, settings.sort);
    progress.report(n, n);
    result.seconds.sort = seconds_since(t);
  }

  // 4. Sweep and segmentation.
  t = Clock::now();
  const Progress_reporter sweep_progress = stage(Stage::SWEEP);
  sweep_progress.report(0, n);
  Record_file<Swept_record> records(settings.temporary_directory);
  const bool refine = settings.refinement.rounds > 0 && !Unary::enabled;
  std::unique_ptr<Record_file<Earlier_edge>> edges; // for the refinement: each point's earlier edges
  if (refine)
    edges = std::make_unique<Record_file<Earlier_edge>>(settings.temporary_directory, 1 << 16);
  Segmenter segmenter(settings.thresholds);
  Sweep_stage_result swept;
  Segmenting_visitor<ConcurrencyTag, Kernel, FlipCriterion, Unary> visitor(
    phi, unary, segmenter, records, edges.get(), radius, sweep_progress, n, swept, settings.layer_edges);
  Sweep_window<Sweep_payload> window;
  Sweep_options so;
  so.number_of_neighbors = k;
  so.radius = radius;
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
  sweep_progress.report(n, n);
  result.seconds.sweep = seconds_since(t);

  // 5-8. The segment graph and its solution, the refinement (skipped when
  // the labelling's energy, known from the segment graph, is negligible:
  // `Refinement_options::negligible_energy`), the sign of every component,
  // then the global stage (exterior visibility and the winding number of a
  // subsample).
  Segment_solution solution;
  Point_labels labels;
  std::vector<char> flip_component;
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
    if (refine && with_refinement && !cue_round) {
      t = Clock::now();
      const unsigned int rounds =
        settings.refinement.worth_running(result.energy_before_refinement, swept.total_weight)
          ? settings.refinement.rounds
          : 0;
      const Refine_stage_result rr = refine_stage<ConcurrencyTag>(
        records, *edges, n, result.edge_span, settings.refinement, rounds, settings.temporary_directory, the_solver,
        result.energy_before_refinement, labels, stage(Stage::REFINE));
      result.energy_after_refinement = rr.energy_after;
      result.refinement_rounds_accepted = rr.rounds_accepted;
      result.refinement_moves = rr.moves;
      result.seconds.refine = seconds_since(t);
    }
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
                                                   radius, n, g, stage(Stage::GLOBAL),
                                                   Unit_inputs{edges.get(), result.edge_span,
                                                               settings.temporary_directory},
                                                   want_cues && dense && !cue_round ? &cues : nullptr, double(k));
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
    coarse_stage<Kernel>(records, radius, n, solver, fine, orient_coarse, labels, solution.component, flip_component,
                         result.global, result.seconds.global);
  } else {
    fine(solver, true, true);
  }
  // The layer cues' round, as in core (`layer_cue_round_share`).
  if (want_cues) {
    const bool round = !cues.preference.empty() &&
                       double(cues.against) > Normal_orientation::internal::layer_cue_round_share * double(cues.samples);
    if (round) { // (`cues` stays: the round does not ask for cues)
      cue_has_unary.assign(solution.component.size(), 0);
      for (std::size_t s = 0; s < cue_has_unary.size(); ++s)
        cue_has_unary[s] = char(swept.segment_has_unary[s] || cues.fixed_component[solution.component[s]]);
      cue_round = true;
      fine(solver, false, true);
    }
    result.global.layer_cues = cues.sure;
    result.global.layer_cues_against = cues.against;
    result.global.layer_cue_round = round;
  }
  result.global.layer_pairs = swept.two_layer_points;
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

/// \ingroup PkgNormalOrientationStreaming
/// Orients the points of `source` out of core and hands them to `sink`
/// (`sink(const Point_record&)`, called once per point kept, in the sweep
/// order, with the oriented normal: only its sign differs from the
/// input's; a sink callable as `sink(record, std::uint32_t segment)` or
/// `sink(record, segment, bool flipped)` is called so, with the segment of
/// the point: the segments are numbered 0 to
/// `Streaming_result::number_of_segments` - 1 in the order the sweep opened
/// them, and each holds at least one point).
///
/// `source` is a model of `PointRecordSource`, read twice: a first pass,
/// then the external sort, or, with a presorted input, the sweep itself.
/// Stages (`Stage`, reported to the callback):
///  1. `SCAN`, the first pass: the number of points, the check that their
///     coordinates are finite, the zero normals, the centroid and principal
///     axis (`Sweep_frame`; not with a presorted input, whose order is
///     checked instead) and, when r is not given, a uniform sample of at
///     most 200,000 points;
///  2. `RADIUS`, when r is not given: the rule of `estimate_neighbor_radius()`
///     over the sample, scaled to the whole cloud;
///  3. `SORT`, the external sort along the axis (bounded memory, temporary
///     files); skipped with a presorted input;
///  4. `SWEEP` (`streaming::sweep()`): each point meets its earlier
///     neighbours of the k-nearest-neighbour graph of `orient_normals()`,
///     gets its edge weights w = phi * (1 - d^2 / r^2) and is segmented
///     (`Segmenter`); points leaving the window go to a temporary record
///     file;
///  5. `SOLVE`: `solver` on the segment graph, with the segments' unary
///     terms when there are constraints or priors;
///  6. `REFINE`: rounds of re-segmentation and single-point moves (see
///     `streaming::Refinement_options`; not with unary terms);
///  7. `SIGN`: the component sign policy, fed from the record file in the
///     passes it asks for (components with unary terms keep the sign the
///     solver gave them);
///  8. `OUTPUT`: the record file re-streamed to `sink` with the final
///     signs, without the components smaller than `minimum_component_size`;
///  9. `COMPONENTS`: optionally, one file per kept component.
///
/// The neighbour graph does not depend on the sweep order: with the same
/// r, a presorted input gives the same graph as the sorted path (up to ties
/// in distance); the segmentation, made in the sweep order, may differ
/// slightly.  Memory: the sweep window, the sort budget, O(segments +
/// segment pairs + components), and 1 MiB per open component file; the
/// temporary files are removed on success, on exceptions and on
/// cancellation.
///
/// \tparam ConcurrencyTag `CGAL::Parallel_tag`, `CGAL::Sequential_tag` or
///         `CGAL::Parallel_if_available_tag` (the default); the result does
///         not depend on it
/// \tparam Source a model of `PointRecordSource`
/// \tparam Sink a model of `PointRecordSink`
/// \param source the points, read twice
/// \param sink receives every point kept, oriented, in the sweep order
/// \param np optional named parameters: those of `orient_normals()` (but
///   `point_map` and `normal_map`: the records hold both) with the same
///   meaning and defaults, `point_is_constrained_map` and
///   `orientation_prior_map` taking a `Point_record` as key (its `index` is
///   its place in the input), and the streaming driver's own (see the page
///   \ref NormalOrientationNamedParameters):
/// \cgalNamedParamsBegin
///   \cgalParamNBegin{presorted_axis}
///     \cgalParamDescription{the input is already sorted by this coordinate (non-decreasing): no principal axis
///       and no external sort; the sweep reads the source as it is, and the output keeps the input order.  The
///       first pass checks the order (`std::runtime_error` naming the first point out of order)}
///     \cgalParamType{`Presorted_axis`}
///     \cgalParamDefault{`Presorted_axis::NONE`}
///   \cgalParamNEnd
///   \cgalParamNBegin{temporary_directory}
///     \cgalParamDescription{where the sort's runs, the record file and the other temporary files go}
///     \cgalParamType{`std::string`}
///     \cgalParamDefault{empty: `$TMPDIR` if set, else /tmp}
///   \cgalParamNEnd
///   \cgalParamNBegin{sort_memory}
///     \cgalParamDescription{bytes of memory for the runs of the external sort (see
///       `streaming::External_sort_options::memory_budget`)}
///     \cgalParamType{`std::size_t`, > 0}
///     \cgalParamDefault{256 MiB}
///   \cgalParamNEnd
///   \cgalParamNBegin{refinement_rounds}
///     \cgalParamDescription{rounds of the refinement after the solve (see `streaming::Refinement_options`); it
///       never raises the energy of the point graph, and needs a temporary edge file of 8 bytes per edge}
///     \cgalParamType{unsigned int, at most 64; 0: no refinement}
///     \cgalParamDefault{3}
///   \cgalParamNEnd
///   \cgalParamNBegin{minimum_component_size}
///     \cgalParamDescription{components of fewer points are dropped: not handed to the sink, not written to the
///       component files, counted in `Streaming_result::number_of_dropped_points`}
///     \cgalParamType{`std::uint64_t`}
///     \cgalParamDefault{0: every point is kept}
///   \cgalParamNEnd
///   \cgalParamNBegin{component_files}
///     \cgalParamDescription{one file per kept connected component, `component_000000.ply`, ... (by decreasing
///       size; ties in the sweep order of their first point), each written atomically once the sink has had
///       every point; removed when the run fails or is interrupted}
///     \cgalParamType{`Component_files_options`}
///     \cgalParamDefault{no component files}
///   \cgalParamNEnd
///   \cgalParamNBegin{batch_size}
///     \cgalParamDescription{points finalised per batch of the sweep}
///     \cgalParamType{`std::size_t`, > 0}
///     \cgalParamDefault{262144}
///   \cgalParamNEnd
/// \cgalNamedParamsEnd
///
/// \return the figures of the run; `interrupted` is true when the callback
///   returned false (the sink may have had part of the points then;
///   temporary and component files are removed)
/// \throw std::invalid_argument for a named parameter out of range;
///   std::runtime_error when a presorted input is not sorted (naming the
///   point) or has non-finite coordinates, and from the source, the sort
///   and the temporary files (also std::system_error); `IO::Io_error` when
///   a component file cannot be written
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename Source, typename Sink,
          typename NamedParameters = parameters::Default_named_parameters>
Streaming_result streaming_orient_normals(Source& source, Sink& sink,
                                          const NamedParameters& np = parameters::default_values())
{
  return streaming::internal::orient_stream<ConcurrencyTag>(source, sink, np, "streaming_orient_normals",
                                                            streaming::internal::Run_hooks());
}

/// \ingroup PkgNormalOrientationStreaming
/// Orients the cloud of the file `input` (.xyz/.pwn with normals, or .ply,
/// read in chunks by `IO::Point_stream_reader`) out of core with
/// `streaming_orient_normals()` and writes it to `output` (.xyz, .pwn or
/// .ply by extension; binary PLY unless `write_options.binary` is false).
/// The output holds the points in the sweep order (along the principal
/// axis; with a presorted input, the input order), with their input
/// coordinates and normals whose sign only may have changed, without the
/// components smaller than `minimum_component_size`.  It is written to a
/// temporary file renamed at the end: on any error or interruption no
/// output file exists.  With `write_options.segments` (PLY only), each
/// point also gets its segment, as the vertex property `int segment`.  With
/// `component_files`, one file per kept component is written too, by
/// default in the output's format; they are removed when the run fails.
/// \throw IO::Io_error for unreadable, malformed or unwritable files, an
///        input without normals or without any point (as `read_point_cloud()`
///        does; no output is written then); see `streaming_orient_normals()`
/// \tparam ConcurrencyTag as for `streaming_orient_normals()`
/// \param input the file to orient (.xyz/.pwn with normals, or .ply with normals)
/// \param output the file written (.xyz, .pwn or .ply)
/// \param np the named parameters of `streaming_orient_normals()`
/// \param write_options how `output` is written (binary or ascii PLY, with the
///        segments, ...)
/// \return the figures of the run
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag,
          typename NamedParameters = parameters::Default_named_parameters>
Streaming_result streaming_orient_files(const std::string& input, const std::string& output,
                                        const NamedParameters& np = parameters::default_values(),
                                        const IO::Point_stream_write_options& write_options =
                                          IO::Point_stream_write_options())
{
  const auto t = std::chrono::steady_clock::now();
  IO::Point_stream_reader reader(input);
  if (!reader.has_normals())
    throw IO::Io_error(input + ": the file has no normals (streaming needs them)");
  IO::Point_stream_writer writer(output, write_options);
  streaming::internal::Run_hooks hooks;
  hooks.adjust = [&](streaming::internal::Streaming_settings& s) {
    if (!s.component_files.directory.empty() && s.component_files.extension.empty()) {
      s.component_files.extension = std::filesystem::path(output).extension().string();
      s.component_files.write_options = write_options;
    }
  };
  auto sink = [&writer](const Point_record& r, std::uint32_t segment) {
    if (writer.has_segments())
      writer.write(r, segment);
    else
      writer.write(r);
  };
  Streaming_result result =
    streaming::internal::orient_stream<ConcurrencyTag>(reader, sink, np, "streaming_orient_files", hooks);
  if (result.interrupted)
    return result; // the writer removes its temporary file
  if (result.number_of_points == 0) // as in core: an empty cloud is an error, not an empty output
    throw IO::Io_error(input + ": the file holds no point");
  const auto t_commit = std::chrono::steady_clock::now();
  try {
    writer.commit();
  } catch (...) {
    std::error_code ec;
    for (const std::string& f : result.component_files)
      std::filesystem::remove(f, ec);
    throw;
  }
  result.seconds.output += Normal_orientation::internal::seconds_since(t_commit);
  result.seconds.total = Normal_orientation::internal::seconds_since(t);
  return result;
}

/// \ingroup PkgNormalOrientationStreaming
/// Orients the cloud of the file `input` out of core, as
/// `streaming_orient_files()` does, and writes `output` as a copy of
/// `input` in its own order and format, in which only the signs of the
/// normals differ (see `IO::transcode_with_flips()`): every other vertex
/// property, the text of every value not negated, the header's comments
/// and the type of every property are kept; the components smaller than
/// `minimum_component_size` are left out.  The stream hands the oriented
/// points to a sink that notes, by input index, which normals to negate and
/// which points to keep (2 bits per point in memory, 25 MB for 100M
/// points); then the input is copied with those changes, in one more
/// reading of the file, with fixed memory.  On any error or interruption
/// no output file exists (an existing one is left unchanged).  The copy is
/// reported to the callback as the stage `OUTPUT`, in bytes of the input.
/// \throw IO::Io_error for unreadable, malformed or unwritable files, an
///        input without normals or without any point, an `output` whose
///        format differs from `input`'s (checked before any work), normals
///        of an unsigned integer type that must be negated, an input that
///        changes while it is read; see `streaming_orient_files()`
/// \tparam ConcurrencyTag as for `streaming_orient_normals()`
/// \param input the file to orient (.xyz/.pwn with normals, or .ply with normals)
/// \param output the file written, in the format of `input` (.ply for a .ply
///        input; .xyz or .pwn for a .xyz or .pwn input)
/// \param np the named parameters of `streaming_orient_normals()`
/// \param transcode when not null, receives the figures of the copy
/// \return the figures of the run (`seconds.output` includes the copy)
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag,
          typename NamedParameters = parameters::Default_named_parameters>
Streaming_result streaming_orient_files_in_input_order(const std::string& input, const std::string& output,
                                                       const NamedParameters& np = parameters::default_values(),
                                                       IO::Transcode_report* transcode = nullptr)
{
  const auto t = std::chrono::steady_clock::now();
  IO::Point_stream_reader reader(input);
  if (!reader.has_normals())
    throw IO::Io_error(input + ": the file has no normals (streaming needs them)");
  const std::string in_ext = IO::lower_case_extension(input);
  const std::string out_ext = IO::lower_case_extension(output);
  if (out_ext != ".ply" && out_ext != ".xyz" && out_ext != ".pwn")
    throw IO::Io_error(output + ": unknown point cloud file extension '" + out_ext + "' (expected .xyz, .pwn or .ply)");
  if ((in_ext == ".ply") != (out_ext == ".ply"))
    throw IO::Io_error(output + ": the copy of '" + input + "' in its own order must be a " +
                       (in_ext == ".ply" ? std::string(".ply") : std::string(".xyz or .pwn")) + " file, as the input");
  IO::Bit_set flip, keep;
  Progress_reporter progress;
  streaming::internal::Run_hooks hooks;
  hooks.adjust = [&](streaming::internal::Streaming_settings& s) {
    if (!s.component_files.directory.empty() && s.component_files.extension.empty())
      s.component_files.extension = std::filesystem::path(output).extension().string();
    progress = streaming::internal::stage_progress(s.progress, Stage::OUTPUT);
  };
  hooks.before_output = [&](std::uint64_t n) {
    flip = IO::Bit_set(n);
    keep = IO::Bit_set(n);
  };
  auto sink = [&](const Point_record& r, std::uint32_t, bool flipped) {
    keep.set(r.index); // throws std::out_of_range on an index beyond the count
    if (flipped)
      flip.set(r.index);
  };
  Streaming_result result =
    streaming::internal::orient_stream<ConcurrencyTag>(reader, sink, np, "streaming_orient_files_in_input_order", hooks);
  if (result.interrupted)
    return result;
  try {
    if (result.number_of_points == 0) // as in core: an empty cloud is an error, not an empty output
      throw IO::Io_error(input + ": the file holds no point");
    const auto t_copy = std::chrono::steady_clock::now();
    IO::Transcode_options to;
    if (progress.enabled())
      to.callback = [&progress](std::uint64_t done, std::uint64_t size) {
        progress.report(done, size);
        return true;
      };
    const IO::Transcode_report tr =
      IO::transcode_with_flips(input, output, flip, result.number_of_dropped_points > 0 ? &keep : nullptr, to);
    if (transcode != nullptr)
      *transcode = tr;
    result.seconds.output += Normal_orientation::internal::seconds_since(t_copy);
  } catch (const Interrupted&) {
    std::error_code ec;
    for (const std::string& f : result.component_files)
      std::filesystem::remove(f, ec);
    result.component_files.clear();
    result.interrupted = true;
  } catch (...) {
    std::error_code ec;
    for (const std::string& f : result.component_files)
      std::filesystem::remove(f, ec);
    throw;
  }
  result.seconds.total = Normal_orientation::internal::seconds_since(t);
  return result;
}

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_ORIENT_NORMALS_H
