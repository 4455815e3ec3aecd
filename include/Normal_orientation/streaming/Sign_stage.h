// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_SIGN_STAGE_H
#define NORMAL_ORIENTATION_STREAMING_SIGN_STAGE_H

/// \file Sign_stage.h
/// The sign stage of the streaming driver: the component sign policy's
/// accumulator fed from the record file, in as many passes as it asks for
/// (the in-core driver feeds the same accumulator from its vectors).

#include <Normal_orientation/Component_sign.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/streaming/Labelled_records.h>

#include <array>
#include <cstdint>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// For each component, whether to flip it: `policy` decides the components
/// without unary terms (`segment_has_unary`), whose sign the solver chose.
/// `constrained(record)` tells the constrained points.
template <typename ComponentSignPolicy, typename Constrained>
std::vector<char> sign_stage(const ComponentSignPolicy& policy, const Constrained& constrained,
                             Labelled_reader& points, const std::vector<std::uint32_t>& component,
                             std::size_t number_of_components, const std::vector<std::uint64_t>& segment_size,
                             const std::vector<char>& segment_has_unary, double radius, std::uint64_t n,
                             const Progress_reporter& progress)
{
  Component_sign_setup setup;
  setup.number_of_components = number_of_components;
  setup.radius = radius;
  setup.component_size.assign(number_of_components, 0);
  for (std::size_t s = 0; s < segment_size.size(); ++s)
    setup.component_size[component[s]] += segment_size[s];
  auto accumulator = policy.begin(setup);
  const unsigned int passes = accumulator.number_of_passes();
  progress.report(0, std::uint64_t(passes) * n);
  Component_sign_point p;
  for (unsigned int pass = 0; pass < passes; ++pass) {
    points.rewind();
    std::uint64_t read = 0;
    while (points.read() > 0) {
      const std::vector<Swept_record>& buffer = points.points();
      read += buffer.size();
      for (std::size_t q = 0; q < buffer.size(); ++q) {
        const Swept_record& s = buffer[q];
        const std::array<double, 3> u = unit_normal(s.record);
        p.component = component[s.segment];
        p.label = points.labels()[q];
        p.constrained = constrained(s.record);
        for (int d = 0; d < 3; ++d) {
          p.position[d] = s.record.position[d];
          p.normal[d] = double(p.label) * u[d];
        }
        accumulator.add(pass, p);
      }
      progress.report(std::uint64_t(pass) * n + read, std::uint64_t(passes) * n);
    }
  }
  std::vector<char> flip = accumulator.decide();
  for (std::size_t s = 0; s < segment_has_unary.size(); ++s) // the solver gave these their sign
    if (segment_has_unary[s])
      flip[component[s]] = 0;
  return flip;
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_SIGN_STAGE_H
