// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_STREAMING_RESULT_H
#define NORMAL_ORIENTATION_STREAMING_STREAMING_RESULT_H

/// \file Streaming_result.h
/// What `streaming_orient_normals()` reports: the fields it shares with
/// `orient_normals()` (`Orientation_summary`), and its own.

#include <Normal_orientation/Orientation_result.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationStreaming
/// Wall-clock seconds of each stage of `streaming_orient_normals()` (see
/// `Stage`; `frame` is the first pass over the input, whatever it computes).
struct Streaming_seconds
{
  /// @{
  /// the seconds of the stage of that name (`total`: the whole call)
  double frame = 0, radius = 0, sort = 0, sweep = 0, solve = 0, refine = 0, sign = 0, global = 0, output = 0,
         components = 0, total = 0;
  /// @}
};

/// \ingroup PkgNormalOrientationStreaming
/// What `streaming_orient_normals()` did.  `energy_before` and
/// `energy_after` are those of the whole point graph, as in core (summed in
/// the sweep order).
struct Streaming_result : Orientation_summary
{
  std::size_t number_of_segment_edges = 0;      ///< edges of the segment graph
  std::size_t number_of_dropped_components = 0; ///< components below `minimum_component_size`
  std::uint64_t number_of_dropped_points = 0;   ///< their points, not handed to the sink
  std::size_t peak_window = 0;                  ///< most points held by the sweep at once
  bool presorted = false; ///< the input was read as presorted (no principal axis, no sort)
  double segment_energy_before = 0.0; ///< energy of the segment graph, preliminary orientation
  double segment_energy_after = 0.0;  ///< energy of the segment graph after the solver
  /// energy of the point graph with the labelling of the segment graph's
  /// solution, before the refinement
  double energy_before_refinement = 0.0;
  /// energy of the point graph after the refinement; never above
  /// `energy_before_refinement`, equal to it without refinement (and equal
  /// to `energy_after`)
  double energy_after_refinement = 0.0;
  /// the rounds of the refinement whose new segment graph lowered the energy
  unsigned int refinement_rounds_accepted = 0;
  /// the single-point moves of the refinement, over all its passes
  std::uint64_t refinement_moves = 0;
  /// the most points back, in the sweep order, that an edge reaches: the
  /// refinement holds twice as many points at once
  std::uint64_t edge_span = 0;
  /// the component files written, by rank (largest component first)
  std::vector<std::string> component_files;
  /// seconds per stage
  Streaming_seconds seconds;
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_STREAMING_RESULT_H
