// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_ORIENTATION_RESULT_H
#define NORMAL_ORIENTATION_ORIENTATION_RESULT_H

/// \file Orientation_result.h
/// What the drivers report: the fields both share (`Orientation_summary`),
/// and the in-core result.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationGlobal
/// What the global sign stage (`decide_patch_signs()`) saw and did.
struct Global_sign_summary
{
  bool ran = false;                    ///< false when the stage was off or had nothing to decide
  bool visibility = false;             ///< exterior visibility ran first (`Global_orientation::VISIBILITY_AND_WINDING`)
  std::size_t number_of_samples = 0;   ///< points the field was built on (a subsample of large clouds)
  std::size_t number_of_patches = 0;   ///< patches whose signs were decided
  std::size_t patches_flipped = 0;     ///< patches the stage negated
  std::uint64_t points_flipped = 0;    ///< points of those patches (in core; 0 streamed)
  std::size_t closed_components = 0;   ///< components found closed: the stage's signs were kept there
  std::size_t open_components = 0;     ///< components found open: they keep the signs they had before the winding number
  std::size_t seen_components_flipped = 0; ///< components negated to face the side they were seen from
  std::size_t seen_patches_flipped = 0;    ///< sheets (in core) or segments (streamed) negated so, after their components
  std::size_t seen_vetoes = 0;             ///< sheets (streamed: segments) where the winding number's flips against both the solver and visibility were undone
  std::size_t top_components_flipped = 0;  ///< components negated last because their top surface faced down (`top_side_flips()`)
  /// the cells of the canopy rule (scatter that fills a volume, in a scene
  /// seen from above, faces up: the manual's *The canopy faces up*), 0
  /// where the rule does not run
  std::size_t canopy_cells = 0;
  std::uint64_t canopy_points_flipped = 0; ///< points the canopy rule negated (in core; 0 streamed)
  unsigned int rounds = 0;             ///< rounds of patch flips
  /// the points whose k nearest neighbours lie on two layers closer than
  /// the neighbour distance (a thin part, or a contact), whose edges across
  /// the gap are negated (`build_neighbor_graph()`); set with or without
  /// the stage
  std::size_t layer_pairs = 0;
  std::size_t layer_cues = 0;          ///< of `layer_pairs`, those with a sure cue from the far field (streamed: of the samples)
  std::size_t layer_cues_against = 0;  ///< of `layer_cues`, those whose sign the cue negated
  bool layer_cue_round = false;        ///< the solver and the stage ran again, with the cues as unary terms
  /// the samples whose smoothing width was capped at their layer gap (the
  /// manual's *Sharp field at contacts*; `Winding_number_field::build()`)
  std::size_t sharp_samples = 0;
  /// the islands, segments of the final signs whose border weighs mostly
  /// against them, that the stage negated last where the field agreed (the
  /// manual's *Islands left by the stage*; streamed, segments of patch
  /// units, and 0 where the stage has no units)
  std::size_t islands_flipped = 0;
  /// the solver's moves (connected points that it negated against the
  /// labelling it started from) that the stage had negated for the most
  /// part and then negated in full (the manual's *Moves the stage undid*;
  /// in core only, 0 streamed)
  std::size_t moves_completed = 0;
  /// the solver's moves that the stage negated in full, after which it ran
  /// once more from the solver's labels without them, so that no decision
  /// rests on the field of a move it rejected (the manual's *Moves the
  /// stage undid*; in core only, 0 streamed)
  std::size_t moves_rejected = 0;
  /// the fraction of the sampled area where w is within the tolerance of
  /// 1/2, after the stage: near 1 on closed surfaces, low on open scans
  double closedness = std::numeric_limits<double>::quiet_NaN();
  double energy_before = std::numeric_limits<double>::quiet_NaN(); ///< sum a_j (w_j - 1/2)^2 before the stage
  double energy_after = std::numeric_limits<double>::quiet_NaN();  ///< the same after it
  double seconds = 0.0;                ///< the stage's wall-clock time
  /// the coarse-to-fine pass (noise wider than the spacing): the median
  /// coherence of the input normals in cells of about two spacings (1 when
  /// parallel, 1/3 when isotropic; NaN when not measured), the points of the
  /// coarse cloud (0 when the normals agreed), and whether the points took
  /// its signs
  double coherence = std::numeric_limits<double>::quiet_NaN();
  std::size_t coarse_points = 0;       ///< see `coherence`
  bool coarse_used = false;            ///< see `coherence`
  /// the coarse signs were taken against the labelling that the solver
  /// starts from (its `initial` MST), so that the solver itself did not run
  bool coarse_before_solver = false;
};

/// \ingroup PkgNormalOrientationRef
/// The figures that both `orient_normals()` and `streaming_orient_normals()`
/// report, under the same names.
struct Orientation_summary
{
  std::uint64_t number_of_points = 0;      ///< points in the input
  std::uint64_t number_of_edges = 0;       ///< edges of the neighbour graph
  std::size_t number_of_components = 0;    ///< connected components (each got its own global sign)
  std::uint64_t number_of_flipped = 0;     ///< normals whose sign was changed
  std::uint64_t number_of_zero_normals = 0; ///< zero normals (left as they were)
  unsigned int number_of_neighbors = 0;    ///< k used
  double neighbor_radius = 0.0;            ///< r used
  bool radius_estimated = false;           ///< true when r was estimated from the data
  /// with `Hoppe_konig_criterion`, on clouds of at most 200,000 points: the
  /// share of nearly parallel neighbours where König's criterion disagrees
  /// with Hoppe's (NaN: not measured)
  double konig_disagreement = std::numeric_limits<double>::quiet_NaN();
  bool konig_everywhere = false;           ///< König's criterion was taken on every edge (clean positions)
  double energy_before = 0.0;              ///< energy (eq. 3) of the point graph with the input orientation
  /// energy of the point graph with the output orientation (streamed: NaN,
  /// not measured, when the global stage negated points)
  double energy_after = 0.0;
  std::size_t number_of_segments = 0;      ///< vertices of the segment graph the solver worked on (0: none)
  std::uint64_t number_of_unary_terms = 0; ///< points with a constraint or a non-zero prior
  std::string criterion;                   ///< the flip criterion's name
  std::string solver;                      ///< the solver's name
  std::string component_sign;              ///< the component sign policy's name
  bool interrupted = false;                ///< true when the callback stopped the run (nothing was written)
  Global_sign_summary global;              ///< the global sign stage
};

/// \ingroup PkgNormalOrientationRef
/// Wall-clock seconds of each stage of `orient_normals()`.
struct Stage_seconds
{
  double input = 0.0;     ///< copying, checking and spatially sorting the input
  double neighbors = 0.0; ///< kd-tree and k-nearest-neighbour queries
  double graph = 0.0;     ///< edge weights and graph assembly
  double solve = 0.0;     ///< the solver
  double sign = 0.0;      ///< components and their signs
  double global = 0.0;    ///< the global sign stage
  double output = 0.0;    ///< writing the normals back
  double total = 0.0;     ///< the whole call
};

/// \ingroup PkgNormalOrientationRef
/// What `orient_normals()` did.
struct Orientation_result : Orientation_summary
{
  std::size_t frustrated_edges = 0; ///< edges whose wish the output does not meet
  Stage_seconds seconds;            ///< time per stage
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_ORIENTATION_RESULT_H
