// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_LAYER_CUES_H
#define NORMAL_ORIENTATION_INTERNAL_LAYER_CUES_H

/// \file Layer_cues.h
/// Layer cues (the manual's *Layer cues*): where a point's neighbourhood is
/// two layers (`fit_two_layers()`), the far field of the oriented cloud in
/// the middle of the gap says whether the gap is outside (a contact: the
/// point's normal faces the other layer) or inside (a wall: it faces away).
/// The far field leaves out everything within a few spacings, so the cue
/// does not depend on the local signs that it is to correct.

#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Winding_number_field.h>
#include <Normal_orientation/internal/Two_layer_fit.h>

#include <CGAL/number_utils.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// The points whose neighbourhoods are two layers (`fit_two_layers()`).
struct Layer_pairs
{
  std::vector<std::uint32_t> point;               ///< the points, increasing
  std::vector<std::array<double, 3>> to_other;    ///< per point, `Two_layer_fit::to_other`
  std::vector<double> gap;                        ///< per point, `Two_layer_fit::gap`
  std::vector<double> strength;                   ///< per point, the weight of its cue (set by the driver)
  std::size_t size() const { return point.size(); }
};

/// The share of the points whose signs the sure cues must negate for the
/// drivers to solve again with the cues as unary terms: a few cues at the
/// contacts of a clean cloud are not worth a second solve, and may be wrong.
constexpr double layer_cue_round_share = 0.001;

/// The share of a component's points that must have a sure cue for the
/// cues to fix its sign (`cue_components()`).
constexpr double layer_cue_component_share = 0.01;

/// After a solve with the cues `cue` as unary terms (per point: > 0 asks for
/// label +1, < 0 for -1, 0 none): negates, in `labels`, the components (ids
/// `component`, below `number_of_components`) where the cues' total strength
/// disagrees more than it agrees (the solver leaves the sign of a component
/// with few unary terms to chance), and returns, per point, whether its
/// component has a sure cue at `layer_cue_component_share` of its points or
/// more: those components keep the sign the cues gave them; elsewhere a
/// few cues do not outweigh the component rules (the outward vote,
/// visibility).
inline std::vector<char> cue_components(const std::vector<double>& cue, const std::vector<std::uint32_t>& component,
                                        std::size_t number_of_components, std::vector<Label>& labels)
{
  std::vector<double> vote(number_of_components, 0.0);
  std::vector<std::size_t> size(number_of_components, 0), cued(number_of_components, 0);
  for (std::size_t i = 0; i < component.size(); ++i) {
    ++size[component[i]];
    if (cue[i] != 0.0) {
      vote[component[i]] += cue[i] * double(labels[i]);
      ++cued[component[i]];
    }
  }
  std::vector<char> fixed(component.size(), 0);
  for (std::size_t i = 0; i < component.size(); ++i) {
    const std::uint32_t c = component[i];
    if (vote[c] < 0.0)
      labels[i] = Label(-labels[i]);
    fixed[i] = char(double(cued[c]) >= layer_cue_component_share * double(size[c]));
  }
  return fixed;
}

/// The settings of `layer_cues()`.
struct Layer_cue_options
{
  /// the far field leaves out the samples within max(this times the
  /// samples' spacing, `gap_radii` times the gap) of the middle of the gap
  double spacing_radii = 4.0;
  /// see `spacing_radii`
  double gap_radii = 3.0;
  /// a cue is sure when its far field is at least this far from 1/2
  double margin = 0.15;
};

/// The cues of `pairs`: per pair, the label (against the input normal of its
/// point) that the cue asks for, +1 or -1, or 0 when it is not sure.  `field`
/// holds samples of the cloud oriented by the current labels, `spacing` their
/// spacing.  The normal faces the other layer when the far field in the middle
/// of the gap is above 1/2 (the gap is outside), else away from it.
template <typename ConcurrencyTag, typename Kernel>
std::vector<Label> layer_cues(const std::vector<typename Kernel::Vector_3>& normals, const Layer_pairs& pairs,
                              const std::vector<typename Kernel::Point_3>& points,
                              const Winding_number_field<Kernel>& field, double spacing,
                              const Layer_cue_options& options = Layer_cue_options())
{
  const std::size_t m = pairs.size();
  std::vector<typename Kernel::Point_3> middle(m);
  std::vector<double> radius(m);
  for (std::size_t t = 0; t < m; ++t) {
    const auto& p = points[pairs.point[t]];
    const auto& d = pairs.to_other[t];
    middle[t] = typename Kernel::Point_3(CGAL::to_double(p.x()) + 0.5 * d[0], CGAL::to_double(p.y()) + 0.5 * d[1],
                                         CGAL::to_double(p.z()) + 0.5 * d[2]);
    radius[t] = std::max(options.spacing_radii * spacing, options.gap_radii * pairs.gap[t]);
  }
  std::vector<double> w;
  field.template evaluate_far<ConcurrencyTag>(middle, radius, w);
  std::vector<Label> cue(m, Label(0));
  for (std::size_t t = 0; t < m; ++t) {
    if (!(std::abs(w[t] - 0.5) > options.margin))
      continue;
    const auto& nv = normals[pairs.point[t]];
    const auto& d = pairs.to_other[t];
    const double toward = CGAL::to_double(nv.x()) * d[0] + CGAL::to_double(nv.y()) * d[1] + CGAL::to_double(nv.z()) * d[2];
    if (toward == 0.0)
      continue;
    const bool face_other = w[t] > 0.5;
    cue[t] = Label((toward > 0.0) == face_other ? 1 : -1);
  }
  return cue;
}

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_LAYER_CUES_H
