// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_CANOPY_RULE_H
#define NORMAL_ORIENTATION_INTERNAL_CANOPY_RULE_H

/// \file Canopy_rule.h
/// The canopy rule, last of the global stage in both drivers: in a scene
/// seen from above, the points of scatter that fills a volume (a tree's
/// crown) face up.  Their normals are those of no surface, and the side
/// from which an airborne scan saw them is up.
/// - Where: the cells of twice the side of the coarse pass's grid
///   (`Coarse_scale`, which both drivers feed with every point) whose
///   3 x 3 x 3 block of such cells holds at least `canopy_minimum_points`
///   points that fill a volume (the smallest eigenvalue of their covariance
///   is more than `canopy_volume_share` of its trace: 0 on a plane, 1/3 in
///   an isotropic blob) and whose normals disagree (their coherence is below
///   `coarse_coherence_threshold`).  A noisy surface looks like that at a
///   few spacings, not at the block's size (about 12 spacings).
/// - Which components: those that the stage read as scenes seen from above
///   (`open_scene_components()`): open in the field after the stage, or
///   negated by the top surface's rule.  A closed surface is left alone.
/// - Which points: those whose normal lies within 60 degrees of the up
///   direction's line (`canopy_vertical_cos`) and faces down.  Only signs
///   change.

#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Orientation_result.h>
#include <Normal_orientation/internal/Coarse_scale.h>
#include <Normal_orientation/internal/Seen_side_rules.h>

#include <CGAL/number_utils.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace Normal_orientation {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// The share of the trace of a block's covariance above which its smallest
/// eigenvalue makes it a volume.
constexpr double canopy_volume_share = 0.12;
/// The fewest points of a block that the canopy rule reads.
constexpr double canopy_minimum_points = 6.0;
/// The canopy rule turns the normals within 60 degrees of the up line.
constexpr double canopy_vertical_cos = 0.5;

/// The cells of the canopy rule (see the file comment), built from the
/// cells of a `Coarse_scale` after its `decide()`; empty without a grid.
class Canopy_cells
{
public:
  Canopy_cells() = default;

  /// the canopy cells of the grid of `coarse`
  explicit Canopy_cells(const Coarse_scale& coarse) : m_origin(coarse.origin()), m_cell(2.0 * coarse.cell_size())
  {
    const std::vector<Coarse_cell> merged = merge_into_doubled_cells(coarse.cells());
    for (const Coarse_cell& c : merged) {
      Coarse_cell block;
      for_coarse_block(merged, c.key, [&](std::size_t j) { block.add(merged[j]); });
      if (block.count >= canopy_minimum_points && is_volume(block) && block.normals >= 3.0 &&
          normal_coherence(block) < coarse_coherence_threshold)
        m_keys.push_back(c.key);
    }
  }

  /// the number of canopy cells
  std::size_t size() const { return m_keys.size(); }

  /// whether the point `p` lies in a canopy cell
  bool contains(const std::array<double, 3>& p) const
  {
    if (m_keys.empty())
      return false;
    const double q[3] = {p[0] - m_origin[0], p[1] - m_origin[1], p[2] - m_origin[2]};
    return std::binary_search(m_keys.begin(), m_keys.end(), coarse_point_key(q, m_cell));
  }

  /// Whether the point `p`, whose unit (or zero) normal `n` is oriented by
  /// `sign` (+1 or -1), is to be negated: it lies in a canopy cell, and
  /// `sign` n lies within 60 degrees of the unit `up`, facing down.
  bool faces_down(const std::array<double, 3>& p, const std::array<double, 3>& n, int sign,
                  const std::array<double, 3>& up) const
  {
    const double dot = double(sign) * (n[0] * up[0] + n[1] * up[1] + n[2] * up[2]);
    return dot <= -canopy_vertical_cos && contains(p);
  }

private:
  /// whether the points of `b` fill a volume
  static bool is_volume(const Coarse_cell& b)
  {
    double v[3];
    std::array<double, 3> axis;
    coarse_eigen(cell_covariance(b), v, 0, axis);
    const double trace = v[0] + v[1] + v[2];
    return trace > 0.0 && v[0] > canopy_volume_share * trace;
  }

  std::array<double, 3> m_origin{{0.0, 0.0, 0.0}};
  double m_cell = 1.0;
  std::vector<std::uint64_t> m_keys; ///< sorted
};

/// The unit up direction of `settings` when the canopy rule runs (exterior
/// visibility with an up direction), else zero.
inline std::array<double, 3> canopy_up(const Global_settings& settings)
{
  const std::array<double, 3>& u = settings.up;
  const double l = std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  if (settings.orientation != Global_orientation::VISIBILITY_AND_WINDING || !(l > 0.0) || !std::isfinite(l))
    return {{0.0, 0.0, 0.0}};
  return {{u[0] / l, u[1] / l, u[2] / l}};
}

/// Per component (ids below `number_of_components`), whether the stage read
/// it as a scene seen from above, where the canopy rule applies: it has
/// samples, is not in `fixed` (per component, or empty), and either reads
/// open in the field `w` at the samples after the stage
/// (`groups_read_closed()` with the default options) or the top surface's
/// rule negated it (`top`, per component).  All false unless `settings`
/// asks for the rule (`canopy_up()`).
inline std::vector<char> open_scene_components(const std::vector<double>& w, const std::vector<double>& areas,
                                               const std::vector<std::uint32_t>& sample_component,
                                               std::size_t number_of_components, const std::vector<char>& top,
                                               const std::vector<char>& fixed, const Global_settings& settings)
{
  std::vector<char> open(number_of_components, 0);
  const std::array<double, 3> up = canopy_up(settings);
  if (up[0] == 0.0 && up[1] == 0.0 && up[2] == 0.0)
    return open;
  const std::vector<char> closed =
    groups_read_closed(w, areas, sample_component, number_of_components, Global_sign_options());
  std::vector<double> area(number_of_components, 0.0);
  for (std::size_t j = 0; j < areas.size(); ++j)
    area[sample_component[j]] += areas[j];
  for (std::size_t c = 0; c < number_of_components; ++c)
    open[c] = char(area[c] > 0.0 && (!closed[c] || top[c]) && !(c < fixed.size() && fixed[c]));
  return open;
}

/// whether the canopy rule applies to a component of `open`
/// (`open_scene_components()`)
inline bool any_open_scene(const std::vector<char>& open)
{
  return std::find(open.begin(), open.end(), char(1)) != open.end();
}

/// The canopy rule on the in-core arrays: negates in `labels` the points of
/// the components of `open` (per component; `component` per point) that
/// `cells` turns up (`Canopy_cells::faces_down()`, `normals` unit or zero,
/// `up` from `canopy_up()`).  Returns how many.
template <typename Point, typename Vector, typename LabelType>
std::uint64_t negate_canopy_down(const Canopy_cells& cells, const std::vector<Point>& points,
                                 const std::vector<Vector>& normals, const std::vector<std::uint32_t>& component,
                                 const std::vector<char>& open, const std::array<double, 3>& up,
                                 std::vector<LabelType>& labels)
{
  std::uint64_t negated = 0;
  if (cells.size() == 0 || !any_open_scene(open))
    return negated;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!open[component[i]])
      continue;
    const std::array<double, 3> p{{CGAL::to_double(points[i].x()), CGAL::to_double(points[i].y()),
                                   CGAL::to_double(points[i].z())}};
    const std::array<double, 3> n{{CGAL::to_double(normals[i].x()), CGAL::to_double(normals[i].y()),
                                   CGAL::to_double(normals[i].z())}};
    if (cells.faces_down(p, n, int(labels[i]), up)) {
      labels[i] = LabelType(-labels[i]);
      ++negated;
    }
  }
  return negated;
}

/// The canopy rule of the in-core driver, after every other decision:
/// `negate_canopy_down()` with `cells` (null: none), unless `global` says
/// that the coarse signs were taken (their own stage decided) or no
/// component of `open` is a scene seen from above.  Sets the rule's figures
/// in `global` and adds its time to `global.seconds` and to `seconds`.
template <typename Point, typename Vector, typename LabelType>
void core_canopy_rule(const Canopy_cells* cells, const std::vector<Point>& points, const std::vector<Vector>& normals,
                      const std::vector<std::uint32_t>& component, const std::vector<char>& open,
                      const Global_settings& settings, std::vector<LabelType>& labels, Global_sign_summary& global,
                      double& seconds)
{
  if (cells == nullptr || !any_open_scene(open) || global.coarse_used)
    return;
  const auto t = std::chrono::steady_clock::now();
  global.canopy_cells = cells->size();
  global.canopy_points_flipped =
    negate_canopy_down(*cells, points, normals, component, open, canopy_up(settings), labels);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  global.seconds += s;
  seconds += s;
}

} // namespace internal
/// \endcond
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_CANOPY_RULE_H
