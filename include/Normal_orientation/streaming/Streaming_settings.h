// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_STREAMING_SETTINGS_H
#define NORMAL_ORIENTATION_STREAMING_STREAMING_SETTINGS_H

/// \file Streaming_settings.h
/// The named parameters of the streaming driver that the in-core driver
/// does not have, their types, and the one place that reads and checks
/// them (the shared ones are read by `internal::read_settings()`).

#include <Normal_orientation/IO/Point_stream.h>
#include <Normal_orientation/internal/Settings.h>
#include <Normal_orientation/parameters.h>
#include <Normal_orientation/streaming/Refinement.h>
#include <Normal_orientation/streaming/external_sort.h>

#include <CGAL/Named_function_parameters.h>

#include <cstdint>
#include <stdexcept>
#include <string>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationStreaming
/// The coordinate along which a streamed input is already sorted (the
/// named parameter `presorted_axis` of `streaming_orient_normals()`).
enum class Presorted_axis
{
  NONE, ///< not sorted: the pipeline sorts it along its principal axis
  X,    ///< sorted by non-decreasing x
  Y,    ///< sorted by non-decreasing y
  Z     ///< sorted by non-decreasing z
};

/// \ingroup PkgNormalOrientationStreaming
/// Where and how `streaming_orient_normals()` writes one file per connected
/// component (the named parameter `component_files`).
struct Component_files_options
{
  /// the directory of the files, created (with its parents) when missing;
  /// empty: no component files
  std::string directory;
  /// the format of the files: ".ply", ".xyz" or ".pwn"; empty: ".ply" in
  /// `streaming_orient_normals()`, the output's format (extension and write
  /// options) in `streaming_orient_files()`
  std::string extension;
  /// how the files are written (binary or ascii PLY, normals; `segments` is
  /// ignored: the component files hold no segments)
  IO::Point_stream_write_options write_options;
  /// the most component files open at once (at least 1; each buffers
  /// 1 MiB).  With more components than that, one pass over the record
  /// file first splits it into one temporary file per group of that many
  /// components, then each group is written from its file: the points are
  /// read twice (and written once more) for up to `maximum_open_files`
  /// squared components, with one more pass over the record file per
  /// further `maximum_open_files` squared (the group files of one pass are
  /// open together)
  std::size_t maximum_open_files = 32;
};

/// \ingroup PkgNormalOrientationStreaming
/// the most rounds of refinement that `refinement_rounds` accepts
constexpr unsigned int maximum_refinement_rounds = 64;

/// \ingroup PkgNormalOrientationStreaming
/// the points finalised per batch of the sweep when `batch_size` is not given
constexpr std::size_t default_batch_size = std::size_t(1) << 18;

/// \cond SKIP_IN_MANUAL
namespace streaming {
namespace internal {

/// The settings of a streamed run: the shared ones and the streaming ones.
struct Streaming_settings : Normal_orientation::internal::Settings
{
  Presorted_axis presorted_axis = Presorted_axis::NONE;
  std::string temporary_directory;
  External_sort_options sort;
  Refinement_options refinement;
  Segmentation_thresholds thresholds;
  std::uint64_t minimum_component_size = 0;
  Component_files_options component_files;
  std::size_t batch_size = default_batch_size;
};

/// Reads and checks the named parameters of `streaming_orient_normals()`
/// (`std::invalid_argument` naming `caller` for a value out of range).
template <typename NamedParameters>
Streaming_settings read_streaming_settings(const NamedParameters& np, const char* caller)
{
  using CGAL::parameters::choose_parameter;
  using CGAL::parameters::get_parameter;
  namespace inp = Normal_orientation::internal_np;
  Streaming_settings s;
  static_cast<Normal_orientation::internal::Settings&>(s) = Normal_orientation::internal::read_settings(np, caller);
  s.presorted_axis = choose_parameter(get_parameter(np, inp::presorted_axis), Presorted_axis::NONE);
  s.temporary_directory = std::string(choose_parameter(get_parameter(np, inp::temporary_directory), std::string()));
  s.sort.temporary_directory = s.temporary_directory;
  s.sort.memory_budget = std::size_t(choose_parameter(get_parameter(np, inp::sort_memory), s.sort.memory_budget));
  const long long rounds =
    (long long)(choose_parameter(get_parameter(np, inp::refinement_rounds), s.refinement.rounds));
  s.minimum_component_size =
    std::uint64_t(choose_parameter(get_parameter(np, inp::minimum_component_size), std::uint64_t(0)));
  s.component_files = choose_parameter(get_parameter(np, inp::component_files), Component_files_options());
  const long long batch = (long long)(choose_parameter(get_parameter(np, inp::batch_size), s.batch_size));
  if (rounds < 0 || rounds > (long long)(maximum_refinement_rounds))
    throw std::invalid_argument(std::string(caller) + ": refinement_rounds must be between 0 and " +
                                std::to_string(maximum_refinement_rounds));
  s.refinement.rounds = unsigned(rounds);
  if (batch < 1)
    throw std::invalid_argument(std::string(caller) + ": batch_size must be at least 1");
  s.batch_size = std::size_t(batch);
  if (s.sort.memory_budget < 1)
    throw std::invalid_argument(std::string(caller) + ": sort_memory must be at least 1 byte");
  if (s.component_files.maximum_open_files < 1)
    throw std::invalid_argument(std::string(caller) + ": component_files.maximum_open_files must be at least 1");
  return s;
}

} // namespace internal
} // namespace streaming
/// \endcond

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_STREAMING_SETTINGS_H
