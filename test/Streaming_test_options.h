// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Streaming_test_options.h
/// \brief The streaming tests' options as one plain struct, turned into the
/// named parameters of streaming_orient_normals() by `params()`.
#ifndef NORMAL_ORIENTATION_TEST_STREAMING_TEST_OPTIONS_H
#define NORMAL_ORIENTATION_TEST_STREAMING_TEST_OPTIONS_H

#include <Normal_orientation/streaming_orient_normals.h>

#include <cstdint>
#include <functional>
#include <string>

namespace Normal_orientation {
namespace test {

/// \brief The settings a streaming test varies (defaults: the library's).
struct Stream_options
{
  unsigned int number_of_neighbors = default_number_of_neighbors;
  double radius = 0.0;
  std::size_t batch_size = std::size_t(1) << 18;
  std::size_t sort_memory = std::size_t(256) << 20;
  std::string temporary_directory;
  Presorted_axis presorted_axis = Presorted_axis::NONE;
  unsigned int refinement_rounds = 3;
  std::uint64_t minimum_component_size = 0;
  Component_files_options component_files;
  std::function<bool(const Progress_info&)> callback;
  Global_orientation global = Global_orientation::WINDING;
};

/// \brief `o` as named parameters
inline auto params(const Stream_options& o)
{
  return parameters::number_of_neighbors(o.number_of_neighbors)
    .neighbor_radius(o.radius)
    .batch_size(o.batch_size)
    .sort_memory(o.sort_memory)
    .temporary_directory(o.temporary_directory)
    .presorted_axis(o.presorted_axis)
    .refinement_rounds(o.refinement_rounds)
    .minimum_component_size(o.minimum_component_size)
    .component_files(o.component_files)
    .callback(o.callback)
    .global_orientation(o.global);
}

} // namespace test
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_TEST_STREAMING_TEST_OPTIONS_H
