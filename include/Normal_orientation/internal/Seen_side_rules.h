// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_SEEN_SIDE_RULES_H
#define NORMAL_ORIENTATION_INTERNAL_SEEN_SIDE_RULES_H

/// \file Seen_side_rules.h
/// The rules of the global stage that both drivers share around exterior
/// visibility: its settings, the components, sheets and segments that face
/// away from the side they were seen from, the vetoes on the winding
/// number's flips, and the components whose top surface faces down.

#include <Normal_orientation/Exterior_visibility.h>
#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/internal/Normal_agreement.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// What the drivers' global stage does: its mode, and the up direction of
/// exterior visibility (zero: none).
struct Global_settings
{
  Global_orientation orientation = Global_orientation::NONE;
  std::array<double, 3> up = {{0.0, 0.0, 1.0}};
  /// the field's samples: `global_samples()` with `dense`, where the input
  /// normals agree at their own spacing (the drivers' fine step, when the
  /// coarse-to-fine pass does not run)
  bool dense_samples = false;
  /// the options of `exterior_visibility()`
  Exterior_visibility_options visibility() const
  {
    Exterior_visibility_options o;
    o.up = up;
    return o;
  }
};

/// `v` as an array (the `up_direction` parameter: a `std::array<double, 3>`)
inline std::array<double, 3> direction_array(const std::array<double, 3>& v) { return v; }
/// `v` as an array (the `up_direction` parameter: a vector with x(), y(), z())
template <typename Vector>
std::array<double, 3> direction_array(const Vector& v)
{
  return {{double(v.x()), double(v.y()), double(v.z())}};
}

/// The share of a sheet's area that the views must see for the sheets' tier
/// of exterior visibility to decide its sign.  A sheet that reaches into a
/// pocket that no view sees, and across a wall thinner than the spacing to
/// a part that they see from behind, may be half seen, half right and half
/// wrong: its sign is left to the segments' tier and to the winding number.
constexpr double sheet_seen_share = 2.0 / 3.0;

/// Per group id below `number_of_groups`, whether the samples of `vote`
/// (0: no view saw it) that `group` puts in it were seen over less than
/// `sheet_seen_share` of their area (`areas`); a group without area is not.
inline std::vector<char> mostly_unseen(const std::vector<double>& vote, const std::vector<double>& areas,
                                       const std::vector<std::uint32_t>& group, std::size_t number_of_groups)
{
  std::vector<double> area(number_of_groups, 0.0), seen(number_of_groups, 0.0);
  for (std::size_t j = 0; j < vote.size(); ++j) {
    area[group[j]] += areas[j];
    seen[group[j]] += vote[j] != 0.0 ? areas[j] : 0.0;
  }
  std::vector<char> unseen(number_of_groups, 0);
  for (std::size_t g = 0; g < number_of_groups; ++g)
    unseen[g] = char(seen[g] < sheet_seen_share * area[g]);
  return unseen;
}

/// The decisions of exterior visibility.
struct Seen_side_flips
{
  std::vector<char> component; ///< per component id: the whole component negates
  std::vector<char> patch;     ///< per patch id: the patch negates (after its component)
  std::vector<double> vote;    ///< per sample: `exterior_visibility()` of the input orientation
  /// per sample: the votes of the same views, each of weight 1 (empty
  /// without visibility or without an up direction, where `vote` is that)
  std::vector<double> even_vote;
  std::size_t components_flipped = 0;
  std::size_t patches_flipped = 0;
};

/// The components (ids below `number_of_components`, those of `fixed` and
/// `whole_fixed` left out) that face away from the side they were seen from
/// (`exterior_visibility()` of the samples, with their oriented normals),
/// then the patches of `sample_patch` that still do (those of the
/// components of `fixed` left out, and those that the views see in less
/// than `sheet_seen_share` of their area); nothing unless `settings` asks for
/// visibility.  The samples of `two_layers` (per sample, or empty) do not
/// vote (their votes are 0): both layers lie within a splat's depth of each
/// other, so either may be the first that a view meets; they count as
/// unseen, so the patches where they hold more than a third of the area
/// keep their signs.
template <typename ConcurrencyTag, typename Point, typename Vector>
Seen_side_flips seen_side_flips(const std::vector<Point>& points, const std::vector<Vector>& oriented,
                                const std::vector<double>& areas, const std::vector<std::uint32_t>& sample_component,
                                const std::vector<std::uint32_t>& sample_patch, std::size_t number_of_components,
                                std::size_t number_of_patches, const std::vector<char>& fixed,
                                const Global_settings& settings, const std::vector<char>& whole_fixed = {},
                                const std::vector<char>& two_layers = {})
{
  Seen_side_flips out;
  out.component.assign(number_of_components, 0);
  out.patch.assign(number_of_patches, 0);
  out.vote.assign(points.size(), 0.0);
  if (points.empty() || settings.orientation != Global_orientation::VISIBILITY_AND_WINDING)
    return out;
  std::vector<char> free_component(number_of_components, 1), free_patch(number_of_patches, 0);
  for (std::size_t c = 0; c < fixed.size() && c < number_of_components; ++c)
    free_component[c] = !fixed[c];
  const Exterior_visibility_options options = settings.visibility();
  const bool weighted = options.up != std::array<double, 3>{{0.0, 0.0, 0.0}};
  out.vote = visibility_votes<ConcurrencyTag>(points, oriented, areas, options, weighted ? &out.even_vote : nullptr);
  for (std::size_t j = 0; j < two_layers.size(); ++j)
    if (two_layers[j])
      out.vote[j] = 0.0;
  std::vector<double> vote = out.vote;
  std::vector<char> free_whole = free_component;
  for (std::size_t c = 0; c < whole_fixed.size() && c < number_of_components; ++c)
    free_whole[c] = char(free_whole[c] && !whole_fixed[c]);
  out.component = visibility_flips(vote, areas, sample_component, free_whole, 0.01);
  for (std::size_t j = 0; j < vote.size(); ++j) {
    free_patch[sample_patch[j]] = free_component[sample_component[j]];
    if (out.component[sample_component[j]])
      vote[j] = -vote[j];
  }
  // (a patch mostly unseen, or mostly on two layers, whose votes are 0, keeps its sign)
  const std::vector<char> unseen = mostly_unseen(vote, areas, sample_patch, number_of_patches);
  for (std::size_t P = 0; P < number_of_patches; ++P)
    if (unseen[P])
      free_patch[P] = 0;
  out.patch = visibility_flips(vote, areas, sample_patch, free_patch);
  for (char f : out.component)
    out.components_flipped += f ? 1 : 0;
  for (char f : out.patch)
    out.patches_flipped += f ? 1 : 0;
  return out;
}

/// The segments' tier of exterior visibility, after the components and the
/// sheets of `seen`: the segments (`sample_segment`, per sample, below
/// `number_of_segments`) that still face away from where they were seen,
/// both by the votes of `seen` (views below the horizon weigh less) and by
/// its votes of views that all weigh 1 (`Seen_side_flips::even_vote`).
/// The solvers' errors are whole segments; but the lower part of an object
/// scanned from one side faces down, and the views from above see it from
/// behind, through the open back: only they would turn it.  Nothing unless
/// `settings` asks for visibility.
inline std::vector<char> segment_tier_flips(const std::vector<double>& areas,
                                            const std::vector<std::uint32_t>& sample_component,
                                            const std::vector<std::uint32_t>& sample_sheet,
                                            const std::vector<std::uint32_t>& sample_segment,
                                            std::size_t number_of_segments, const Seen_side_flips& seen,
                                            const std::vector<char>& component_fixed, const Global_settings& settings)
{
  const std::size_t ns = sample_component.size();
  if (ns == 0 || settings.orientation != Global_orientation::VISIBILITY_AND_WINDING)
    return std::vector<char>(number_of_segments, 0);
  // (the votes as they stand after the components and sheets of `seen`)
  auto after_seen = [&](std::vector<double> v) {
    for (std::size_t j = 0; j < ns; ++j)
      if (seen.component[sample_component[j]] != seen.patch[sample_sheet[j]])
        v[j] = -v[j];
    return v;
  };
  std::vector<char> free_segment(number_of_segments, 0);
  for (std::size_t j = 0; j < ns; ++j)
    free_segment[sample_segment[j]] = !component_fixed[sample_component[j]];
  std::vector<char> flip = visibility_flips(after_seen(seen.vote), areas, sample_segment, free_segment);
  if (seen.even_vote.empty())
    return flip; // (every view already weighs 1)
  const std::vector<char> even_flip =
    visibility_flips(after_seen(seen.even_vote), areas, sample_segment, free_segment);
  for (std::size_t P = 0; P < flip.size(); ++P)
    flip[P] = char(flip[P] && even_flip[P]);
  return flip;
}

/// The share of a component's area that the samples whose normals agree
/// with their neighbours' must hold for the top rule to read only them.
constexpr double top_agreeing_share = 0.1;

/// The share of the area counted that the near-horizontal top must hold
/// for the top rule to read it (`downward_top_flips()`'s minimum_fraction).
constexpr double top_minimum_fraction = 0.05;

/// Whether the rule of `top_side_flips()` may negate a component of
/// `eligible`, whichever samples count: where it does, the downward part
/// of the top (`downward_top_flips()`) exceeds three quarters of
/// `top_minimum_fraction` of the area counted, which is at least
/// `top_agreeing_share` of the component's.  Half that bound is tested,
/// against rounding; false spares reading the samples' agreement, and the
/// rule then negates nothing.
inline bool top_flip_possible(const std::vector<double>& facing, const std::vector<double>& areas,
                              const std::vector<std::uint32_t>& sample_component, const std::vector<char>& eligible)
{
  std::vector<double> area(eligible.size(), 0.0), down(eligible.size(), 0.0);
  for (std::size_t j = 0; j < facing.size(); ++j) {
    area[sample_component[j]] += areas[j];
    if (facing[j] < 0.0 && near_horizontal_top(facing[j]))
      down[sample_component[j]] += areas[j];
  }
  for (std::size_t c = 0; c < eligible.size(); ++c)
    if (eligible[c] && down[c] > 0.5 * top_down_share * top_minimum_fraction * top_agreeing_share * area[c])
      return true;
  return false;
}

/// The components (ids below `number_of_components`, those of `fixed` left
/// out) whose top surface faces down (`downward_top_flips()` of
/// `top_view_facing()` of the samples, with their final oriented normals);
/// nothing unless `settings` asks for visibility.  A closed surface's top
/// faces up, and so does the ground of a scene seen from above or from the
/// ground: this undoes the winding number where it takes a scene open to
/// the sky (a street between facades) for part of a closed surface.  Only
/// the samples whose normals agree with their neighbours' (`normals_agree()`)
/// count, in every component where they hold at least `top_agreeing_share`
/// of the area: scatter (a forest's canopy over the ground) hides much of
/// the ground from above, and its normals do not say which way is up.
template <typename ConcurrencyTag, typename Point, typename Vector>
std::vector<char> top_side_flips(const std::vector<Point>& points, const std::vector<Vector>& oriented,
                                 const std::vector<double>& areas, const std::vector<std::uint32_t>& sample_component,
                                 std::size_t number_of_components, const std::vector<char>& fixed,
                                 const Global_settings& settings)
{
  if (points.empty() || settings.orientation != Global_orientation::VISIBILITY_AND_WINDING)
    return std::vector<char>(number_of_components, 0);
  std::vector<char> eligible(number_of_components, 1);
  for (std::size_t c = 0; c < fixed.size() && c < number_of_components; ++c)
    eligible[c] = !fixed[c];
  const std::vector<double> facing = top_view_facing<ConcurrencyTag>(points, oriented, areas, settings.visibility());
  if (!top_flip_possible(facing, areas, sample_component, eligible))
    return std::vector<char>(number_of_components, 0);
  const std::vector<char> agree = normals_agree<ConcurrencyTag>(points, oriented);
  std::vector<double> area(number_of_components, 0.0), agreeing(number_of_components, 0.0);
  for (std::size_t j = 0; j < agree.size(); ++j) {
    area[sample_component[j]] += areas[j];
    agreeing[sample_component[j]] += agree[j] ? areas[j] : 0.0;
  }
  std::vector<double> counted(areas); // (the areas that count)
  for (std::size_t j = 0; j < counted.size(); ++j) {
    const std::uint32_t c = sample_component[j];
    if (!agree[j] && agreeing[c] >= top_agreeing_share * area[c])
      counted[j] = 0.0;
  }
  return downward_top_flips(facing, counted, sample_component, eligible, top_minimum_fraction);
}

/// Whether the winding number negated a sample against both the solver and
/// exterior visibility: it negated it (`by_winding`), visibility did not
/// (`by_visibility`).
inline bool negated_against_both(char by_visibility, char by_winding) { return by_winding && !by_visibility; }

/// The sheets (groups of `sample_group`) where the winding number's flips
/// are undone: where it negated samples against both the solver and
/// exterior visibility (`negated_against_both()`; per sample, whether
/// visibility negated it, `by_visibility`, and whether the winding number
/// negated it after that, `by_winding`), and these samples, with their
/// final signs, face away from the side they were seen from (their
/// area-weighted mean `vote`, of their input orientation, is below
/// `-margin`).  Where visibility negated a sheet and the winding number
/// negates it back, the solver and the winding number outvote it.
inline std::vector<char> seen_side_vetoes(const std::vector<double>& vote, const std::vector<double>& areas,
                                          const std::vector<std::uint32_t>& sample_group,
                                          const std::vector<char>& by_visibility, const std::vector<char>& by_winding,
                                          std::size_t number_of_groups, double margin = 0.01)
{
  std::vector<char> eligible(number_of_groups, 0);
  std::vector<double> final_vote(vote.size(), 0.0), area(vote.size(), 0.0);
  for (std::size_t j = 0; j < vote.size(); ++j)
    if (negated_against_both(by_visibility[j], by_winding[j])) {
      eligible[sample_group[j]] = 1;
      final_vote[j] = (by_visibility[j] != by_winding[j] ? -1.0 : 1.0) * vote[j];
      area[j] = areas[j];
    }
  return visibility_flips(final_vote, area, sample_group, eligible, margin);
}

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_SEEN_SIDE_RULES_H
