// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// The reports of the orient_normals program: the summary on stderr and the
// JSON object of --json on stdout, in core and with --stream.

#ifndef NORMAL_ORIENTATION_EXAMPLES_CLI_CLI_REPORT_H
#define NORMAL_ORIENTATION_EXAMPLES_CLI_CLI_REPORT_H

#include "Cli_options.h"
#include "Json_writer.h"

#include <Normal_orientation/orient_normals.h>
#include <Normal_orientation/streaming_orient_normals.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>

namespace Cli {

/// \brief What the program did in core around `orient_normals()`.
struct In_core_run
{
  /// why the normals were estimated; empty when they were read
  std::string normals_estimated_because;
  double read_seconds = 0.0;     ///< reading IN
  double estimate_seconds = 0.0; ///< estimating the normals
  double write_seconds = 0.0;    ///< writing OUT
  double total_seconds = 0.0;    ///< the whole run
  /// \brief true when the normals were estimated
  bool normals_estimated() const { return !normals_estimated_because.empty(); }
};

/// \brief What the program did with --stream.
struct Streamed_run
{
  Normal_orientation::Streaming_result result; ///< the library's report
  unsigned int refinement_rounds = 0;          ///< the rounds of refinement asked for
  double total_seconds = 0.0;                  ///< the whole run
};

/// \cond SKIP_IN_MANUAL
namespace internal {

/// "wrote PATH" (absolute when it can be made so), or with a `prefix`
inline void print_wrote(const std::string& path, const char* prefix = "wrote ")
{
  std::error_code ec;
  const std::string where = std::filesystem::absolute(path, ec).string();
  std::fprintf(stderr, "%s%s\n", prefix, ec ? path.c_str() : where.c_str());
}

inline const char* plural(std::size_t n) { return n == 1 ? "" : "s"; }

/// one line on what the global sign stage saw and did, when it ran
inline void print_global(const Normal_orientation::Global_sign_summary& g)
{
  if (g.ran)
    std::fprintf(stderr,
                 "global stage (%s): %zu patch%s, %zu flipped; closedness %.3f, %zu closed and %zu open "
                 "component%s; seen side: %zu component%s and %zu sheet%s flipped, %zu veto%s; top side: %zu "
                 "component%s flipped; %.3f s\n",
                 g.visibility ? "visibility, winding" : "winding", g.number_of_patches,
                 g.number_of_patches == 1 ? "" : "es", g.patches_flipped, g.closedness, g.closed_components,
                 g.open_components, plural(g.open_components), g.seen_components_flipped,
                 plural(g.seen_components_flipped), g.seen_patches_flipped, plural(g.seen_patches_flipped),
                 g.seen_vetoes, g.seen_vetoes == 1 ? "" : "es", g.top_components_flipped,
                 plural(g.top_components_flipped), g.seconds);
  if (g.ran && g.layer_pairs > 0)
    std::fprintf(stderr, "layer cues: %zu point%s on two layers, %zu sure cue%s, %zu against the stage%s\n",
                 g.layer_pairs, plural(g.layer_pairs), g.layer_cues, plural(g.layer_cues), g.layer_cues_against,
                 g.layer_cue_round ? "; solved again with them" : "");
  if (g.ran && g.canopy_cells > 0) { // (points are counted in core only)
    std::fprintf(stderr, "canopy: %zu cell%s of volume scatter in scenes seen from above", g.canopy_cells,
                 plural(g.canopy_cells));
    if (g.canopy_points_flipped > 0)
      std::fprintf(stderr, ", %llu point%s turned up", (unsigned long long)g.canopy_points_flipped,
                   plural(std::size_t(g.canopy_points_flipped)));
    std::fprintf(stderr, "\n");
  }
}

/// "global": what the global sign stage saw and did (null when it did not run)
inline void json_global(Json_writer& j, const Normal_orientation::Global_sign_summary& g)
{
  j.key("global");
  if (!g.ran) {
    j.null();
    return;
  }
  j.begin_object();
  j.key("stage").string(g.visibility ? "visibility" : "winding").key("closedness").number(g.closedness);
  j.key("samples").integer(g.number_of_samples).key("patches").integer(g.number_of_patches);
  j.key("patches_flipped").integer(g.patches_flipped).key("points_flipped").integer(g.points_flipped);
  j.key("closed_components").integer(g.closed_components).key("open_components").integer(g.open_components);
  j.key("rounds").integer(g.rounds);
  j.key("seen_components_flipped").integer(g.seen_components_flipped);
  j.key("seen_patches_flipped").integer(g.seen_patches_flipped).key("seen_vetoes").integer(g.seen_vetoes);
  j.key("top_components_flipped").integer(g.top_components_flipped);
  j.key("canopy_cells").integer(g.canopy_cells).key("canopy_points_flipped").integer(g.canopy_points_flipped);
  j.key("layer_pairs").integer(g.layer_pairs).key("layer_cues").integer(g.layer_cues);
  j.key("layer_cues_against").integer(g.layer_cues_against).key("layer_cue_round").boolean(g.layer_cue_round);
  j.key("sharp_samples").integer(g.sharp_samples).key("islands_flipped").integer(g.islands_flipped);
  j.key("moves_completed").integer(g.moves_completed);
  j.key("moves_rejected").integer(g.moves_rejected);
  j.key("energy_before").number(g.energy_before).key("energy_after").number(g.energy_after);
  j.key("coherence").number(g.coherence).key("coarse_points").integer(g.coarse_points);
  j.key("coarse_used").boolean(g.coarse_used);
  j.key("coarse_before_solver").boolean(g.coarse_before_solver);
  j.key("seconds").fixed(g.seconds);
  j.end_object();
}

} // namespace internal
/// \endcond

/// \brief Prints the summary of an in-core run on stderr.
inline void print_summary(const Normal_orientation::Orientation_result& r, const In_core_run& run,
                          const Options& o)
{
  std::fprintf(stderr,
               "oriented %zu points%s: %zu edges (k = %u, r = %.6g), %zu component%s, energy %.6g -> %.6g, "
               "%zu normals flipped, %.3f s\n",
               r.number_of_points, run.normals_estimated() ? " (normals estimated)" : "", r.number_of_edges,
               r.number_of_neighbors, r.neighbor_radius, r.number_of_components,
               internal::plural(r.number_of_components), r.energy_before, r.energy_after, r.number_of_flipped,
               run.total_seconds);
  internal::print_global(r.global);
  if (r.number_of_zero_normals > 0)
    std::fprintf(stderr, "%llu of %llu points have a zero normal: left as they were\n",
                 (unsigned long long)r.number_of_zero_normals, (unsigned long long)r.number_of_points);
  internal::print_wrote(o.output);
}

/// \brief The JSON report of an in-core run (one line, no newline).
inline std::string json_report(const Normal_orientation::Orientation_result& r, const In_core_run& run,
                               const Options& o)
{
  Json_writer j;
  j.begin_object();
  j.key("input").string(o.input).key("output").string(o.output);
  j.key("points").integer(r.number_of_points).key("edges").integer(r.number_of_edges);
  j.key("components").integer(r.number_of_components);
  j.key("k").integer(r.number_of_neighbors).key("radius").number(r.neighbor_radius);
  j.key("radius_estimated").boolean(r.radius_estimated);
  j.key("criterion").string(r.criterion).key("solver").string(r.solver);
  j.key("konig_disagreement").number(r.konig_disagreement).key("konig_everywhere").boolean(r.konig_everywhere);
  j.key("component_sign").string(r.component_sign);
  j.key("seed").integer(o.seed).key("threads").integer(o.threads);
  j.key("normals_estimated").boolean(run.normals_estimated());
  if (run.normals_estimated())
    j.key("normals_estimated_because").string(run.normals_estimated_because);
  j.key("energy_before").number(r.energy_before).key("energy_after").number(r.energy_after);
  j.key("frustrated_edges").integer(r.frustrated_edges).key("segments").integer(r.number_of_segments);
  j.key("unary_terms").integer(r.number_of_unary_terms).key("flipped").integer(r.number_of_flipped);
  j.key("zero_normals").integer(r.number_of_zero_normals);
  internal::json_global(j, r.global);
  j.key("seconds").begin_object();
  j.key("read").fixed(run.read_seconds).key("estimate_normals").fixed(run.estimate_seconds);
  j.key("neighbors").fixed(r.seconds.neighbors).key("graph").fixed(r.seconds.graph);
  j.key("solve").fixed(r.seconds.solve).key("sign").fixed(r.seconds.sign).key("global").fixed(r.seconds.global);
  j.key("orient_total").fixed(r.seconds.total).key("write").fixed(run.write_seconds);
  j.key("total").fixed(run.total_seconds);
  j.end_object();
  j.end_object();
  return j.str();
}

/// \brief Prints the summary of a streamed run on stderr.
inline void print_summary(const Streamed_run& run, const Options& o)
{
  const Normal_orientation::Streaming_result& r = run.result;
  std::fprintf(stderr,
               "oriented %llu points out of core%s: %llu edges (k = %u, r = %.6g), %zu segments, %zu component%s, "
               "peak window %zu points, %llu normals flipped, %.3f s\n",
               (unsigned long long)r.number_of_points, r.presorted ? " (presorted input)" : "",
               (unsigned long long)r.number_of_edges, o.k, r.neighbor_radius, r.number_of_segments,
               r.number_of_components, internal::plural(r.number_of_components), r.peak_window,
               (unsigned long long)r.number_of_flipped, run.total_seconds);
  internal::print_global(r.global);
  if (r.number_of_dropped_components > 0)
    std::fprintf(stderr, "dropped %zu component%s of fewer than %llu points (%llu points)\n",
                 r.number_of_dropped_components, internal::plural(r.number_of_dropped_components),
                 o.min_component_size, (unsigned long long)r.number_of_dropped_points);
  if (r.number_of_zero_normals > 0)
    std::fprintf(stderr, "%llu of %llu points have a zero normal: left as they were\n",
                 (unsigned long long)r.number_of_zero_normals, (unsigned long long)r.number_of_points);
  internal::print_wrote(o.output);
  if (!o.components_dir.empty()) {
    const std::string prefix = "wrote " + std::to_string(r.component_files.size()) + " component file" +
                               internal::plural(r.component_files.size()) + " in ";
    internal::print_wrote(o.components_dir, prefix.c_str());
  }
}

/// \brief The JSON report of a streamed run (one line, no newline).
inline std::string json_report(const Streamed_run& run, const Options& o)
{
  const Normal_orientation::Streaming_result& r = run.result;
  Json_writer j;
  j.begin_object();
  j.key("input").string(o.input).key("output").string(o.output).key("mode").string("stream");
  j.key("points").integer(r.number_of_points).key("edges").integer(r.number_of_edges);
  j.key("segments").integer(r.number_of_segments).key("segment_edges").integer(r.number_of_segment_edges);
  j.key("components").integer(r.number_of_components);
  j.key("dropped_components").integer(r.number_of_dropped_components);
  j.key("dropped_points").integer(r.number_of_dropped_points);
  j.key("min_component_size").integer(o.min_component_size);
  j.key("component_files").integer(r.component_files.size());
  j.key("components_dir").string_or_null(o.components_dir);
  j.key("presorted").string_or_null(o.presorted).key("keep_order").boolean(o.keep_order);
  j.key("peak_window").integer(r.peak_window).key("k").integer(o.k);
  j.key("radius").number(r.neighbor_radius).key("radius_estimated").boolean(r.radius_estimated);
  j.key("criterion").string(o.criterion).key("solver").string(o.solver).key("threads").integer(o.threads);
  j.key("konig_disagreement").number(r.konig_disagreement).key("konig_everywhere").boolean(r.konig_everywhere);
  j.key("segment_energy_before").number(r.segment_energy_before);
  j.key("segment_energy_after").number(r.segment_energy_after);
  j.key("refinement_rounds").integer(run.refinement_rounds);
  j.key("refinement_rounds_accepted").integer(r.refinement_rounds_accepted);
  j.key("refinement_moves").integer(r.refinement_moves);
  j.key("energy_before_refinement").number(r.energy_before_refinement);
  j.key("energy_after_refinement").number(r.energy_after_refinement);
  j.key("edge_span").integer(r.edge_span).key("flipped").integer(r.number_of_flipped);
  j.key("component_sign").string(r.component_sign).key("unary_terms").integer(r.number_of_unary_terms);
  j.key("zero_normals").integer(r.number_of_zero_normals);
  j.key("energy_before").number(r.energy_before).key("energy_after").number(r.energy_after);
  internal::json_global(j, r.global);
  j.key("seconds").begin_object();
  j.key("frame").fixed(r.seconds.frame).key("radius").fixed(r.seconds.radius);
  j.key("sort").fixed(r.seconds.sort).key("sweep").fixed(r.seconds.sweep);
  j.key("solve").fixed(r.seconds.solve).key("refine").fixed(r.seconds.refine);
  j.key("sign").fixed(r.seconds.sign).key("global").fixed(r.seconds.global).key("output").fixed(r.seconds.output);
  j.key("components").fixed(r.seconds.components).key("total").fixed(run.total_seconds);
  j.end_object();
  j.end_object();
  return j.str();
}

} // namespace Cli

#endif // NORMAL_ORIENTATION_EXAMPLES_CLI_CLI_REPORT_H
