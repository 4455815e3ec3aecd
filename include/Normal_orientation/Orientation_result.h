// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_ORIENTATION_RESULT_H
#define NORMAL_ORIENTATION_ORIENTATION_RESULT_H

/// \file Orientation_result.h
/// What the drivers report: the fields both share (`Orientation_summary`),
/// and the in-core result.

#include <cstddef>
#include <cstdint>
#include <string>

namespace Normal_orientation {

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
  double energy_before = 0.0;              ///< energy (eq. 3) of the point graph with the input orientation
  double energy_after = 0.0;               ///< energy of the point graph with the output orientation
  std::size_t number_of_segments = 0;      ///< vertices of the segment graph the solver worked on (0: none)
  std::uint64_t number_of_unary_terms = 0; ///< points with a constraint or a non-zero prior
  std::string criterion;                   ///< the flip criterion's name
  std::string solver;                      ///< the solver's name
  std::string component_sign;              ///< the component sign policy's name
  bool interrupted = false;                ///< true when the callback stopped the run (nothing was written)
};

/// \ingroup PkgNormalOrientationRef
/// Wall-clock seconds of each stage of `orient_normals()`.
struct Stage_seconds
{
  double input = 0.0;     ///< copying, checking and spatially sorting the input
  double neighbors = 0.0; ///< kd-tree and k-nearest-neighbour queries
  double graph = 0.0;     ///< edge weights and graph assembly
  double solve = 0.0;     ///< the solver
  double sign = 0.0;      ///< components and their global signs
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
