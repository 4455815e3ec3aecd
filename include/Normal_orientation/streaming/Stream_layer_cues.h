// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_STREAM_LAYER_CUES_H
#define NORMAL_ORIENTATION_STREAMING_STREAM_LAYER_CUES_H

/// \file Stream_layer_cues.h
/// The layer cues (`Layer_cues.h`) in the streaming driver, at the end of
/// the global stage: the pairs are the stage's two-layer samples, whose
/// records carry their offsets (`layer_code()`), the far field is that of
/// the samples with their final signs, and the cues become unary terms of
/// the sweep's segments for one more solve.

#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Winding_number_field.h>
#include <Normal_orientation/internal/Layer_cues.h>
#include <Normal_orientation/streaming/Segmenting_sweep.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// What the streamed layer cues saw, and their unary terms.
struct Stream_layer_cues
{
  std::size_t samples = 0; ///< the samples of the global stage
  std::size_t sure = 0;    ///< two-layer samples with a sure cue
  std::size_t against = 0; ///< of them, those whose final sign the cue negates
  /// per sweep segment, the cues' preference for its preliminary
  /// orientation (as `Segmenter::segment_preferences()`); empty: no cue
  std::vector<double> preference;
  /// per component, whether a sure cue is at `layer_cue_component_share` of
  /// its samples or more (its sign is then the cues')
  std::vector<char> fixed_component;

  /// whether the solver runs again with the cues: when they negate more
  /// than `layer_cue_round_share` of the samples, as in core
  bool ask_for_a_round() const
  {
    return !preference.empty() &&
           double(against) > Normal_orientation::internal::layer_cue_round_share * double(samples);
  }

  /// per sweep segment (of component `component`), whether it has a unary
  /// term in that round: the user's (`segment_has_unary`) or a fixed
  /// component's
  std::vector<char> segments_with_unary(const std::vector<char>& segment_has_unary,
                                        const std::vector<std::uint32_t>& component) const
  {
    std::vector<char> out(component.size(), 0);
    for (std::size_t s = 0; s < out.size(); ++s)
      out[s] = char(segment_has_unary[s] || fixed_component[component[s]]);
    return out;
  }
};

/// The cues of the two-layer samples of `samples` (`Global_samples`, with
/// the final negations `final_flip` per sample and their `areas`): each
/// sure cue adds `strength` times its label, in its segment's frame, to the
/// preference of its sweep segment.  `radius` is the neighbour radius of
/// the layer codes; there are `number_of_segments` sweep segments and
/// `number_of_components` components.
template <typename ConcurrencyTag, typename Kernel, typename Samples>
Stream_layer_cues stream_layer_cues(const Samples& samples, const std::vector<char>& final_flip,
                                    const std::vector<double>& areas, double radius, std::size_t number_of_segments,
                                    std::size_t number_of_components, double strength)
{
  typedef typename Kernel::Vector_3 Vector;
  const std::size_t ns = samples.points.size();
  Stream_layer_cues out;
  out.samples = ns;
  Normal_orientation::internal::Layer_pairs pairs;
  std::vector<Vector> input(ns), oriented(ns);
  for (std::size_t j = 0; j < ns; ++j) {
    input[j] = samples.normals[j] * double(samples.sign[j]);
    oriented[j] = final_flip[j] ? -samples.normals[j] : samples.normals[j];
    if (samples.layer[j] == 0)
      continue;
    const std::array<double, 3> u = {{input[j].x(), input[j].y(), input[j].z()}};
    const std::array<double, 3> t = layer_code_offset(samples.layer[j], u, radius);
    pairs.point.push_back(std::uint32_t(j));
    pairs.to_other.push_back(t);
    pairs.gap.push_back(std::sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]));
  }
  if (pairs.size() == 0)
    return out;
  Winding_number_field<Kernel> field;
  field.template build<ConcurrencyTag>(samples.points, oriented, areas);
  const double spacing = std::sqrt(Normal_orientation::internal::median(areas));
  const std::vector<Label> cue =
    Normal_orientation::internal::layer_cues<ConcurrencyTag, Kernel>(input, pairs, samples.points, field, spacing);
  std::vector<std::size_t> cued(number_of_components, 0), size(number_of_components, 0);
  for (std::size_t j = 0; j < ns; ++j)
    ++size[samples.component[j]];
  for (std::size_t t = 0; t < pairs.size(); ++t) {
    if (cue[t] == 0)
      continue;
    const std::size_t j = pairs.point[t];
    if (out.preference.empty())
      out.preference.assign(number_of_segments, 0.0);
    ++out.sure;
    const Label now = Label(samples.sign[j] * (final_flip[j] ? -1 : 1));
    if (cue[t] != now)
      ++out.against;
    out.preference[samples.sweep_segment[j]] += double(cue[t]) * double(samples.sweep_flip[j]) * strength;
    ++cued[samples.component[j]];
  }
  out.fixed_component.assign(number_of_components, 0);
  for (std::size_t c = 0; c < number_of_components; ++c)
    out.fixed_component[c] =
      char(cued[c] > 0 &&
           double(cued[c]) >= Normal_orientation::internal::layer_cue_component_share * double(size[c]));
  return out;
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_STREAM_LAYER_CUES_H
