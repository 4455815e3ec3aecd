// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_PATCH_UNITS_H
#define NORMAL_ORIENTATION_STREAMING_PATCH_UNITS_H

/// \file Patch_units.h
/// The units of the streamed global stage's patches, and the graph between
/// them, built in one pass over the labelled points and the sweep's edge
/// file: the patches of every level are unions of units, as the in-core
/// patches are unions of points (`build_patches()`).

#include <Normal_orientation/Signed_union_find.h>
#include <Normal_orientation/internal/Core_global_sign.h>
#include <Normal_orientation/streaming/Refinement.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <unordered_map>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// The slots of the last `span` points of a pass in the sweep order, whose
/// earlier edges reach at most `span` points back: the slot of point `at`,
/// and the point `back` places before it.
template <typename T>
class Span_ring
{
public:
  explicit Span_ring(std::uint64_t span) : m_span(span)
  {
    std::size_t size = 1; // (a power of two: no division per edge)
    while (size < std::size_t(span) + 1)
      size *= 2;
    m_slots.resize(size);
  }

  /// the slot of point `at`
  T& slot(std::uint64_t at) { return m_slots[std::size_t(at & (m_slots.size() - 1))]; }

  /// the point `back` places before point `at`
  /// \throw std::runtime_error when it is before the first point or farther
  ///        back than the span
  const T& earlier(std::uint64_t at, std::uint64_t back) const
  {
    if (back == 0 || back > at || back > m_span)
      throw std::runtime_error("streaming_orient_normals: an edge of the edge file reaches beyond its span");
    return m_slots[std::size_t((at - back) & (m_slots.size() - 1))];
  }

  /// the span
  std::uint64_t span() const { return m_span; }

private:
  std::uint64_t m_span;
  std::vector<T> m_slots;
};

/// A point's measures that `Patch_units` reads (`Unit_measure`): whether
/// it has a normal, and its cell.
struct Measured_point
{
  std::array<std::int32_t, 3> cell{{0, 0, 0}};
  std::uint64_t packed_cell = 0;
  bool has_normal = false;
};

/// The measures of an earlier edge (`Unit_measure`): its slope
/// (`Normal_orientation::internal::edge_slope()`; 2 when the earlier end
/// has no normal) and the scalar product of its ends' oriented normals (0
/// then).  Neither is measured when the later end has no normal.
struct Measured_edge
{
  double slope = 2.0;
  double dot = 0.0;
};

/// The geometry of the points pushed in the sweep order, apart from the
/// units' sequential state, so that a pass can measure the next points
/// while `Patch_units` takes the last ones: a ring of the last `span`
/// positions and oriented normals.  Deterministic.
class Unit_measure
{
public:
  typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;

  /// for edges reaching at most `span` points back, cells of side `cell` (> 0)
  Unit_measure(std::uint64_t span, double cell) : m_cell(cell), m_ring(span) {}

  /// Measures the next point: its position `p`, its oriented normal `m`
  /// (zero: none) and its earlier edges `edges[0 .. count - 1]`, whose
  /// measures go to `out[0 .. count - 1]` (unless it has no normal).
  /// \throw std::runtime_error when an edge reaches before the first point or
  ///        farther back than the span
  Measured_point measure(const Kernel::Point_3& p, const Kernel::Vector_3& m, const Earlier_edge* edges,
                         std::size_t count, Measured_edge* out)
  {
    Measured_point r;
    r.has_normal = m != CGAL::NULL_VECTOR;
    for (std::size_t e = 0; e < count && r.has_normal; ++e) {
      const Point& o = m_ring.earlier(m_at, edges[e].offset);
      out[e] = Measured_edge();
      if (!o.has_normal)
        continue;
      out[e].slope = Normal_orientation::internal::edge_slope(p, o.position, m, o.normal);
      out[e].dot = CGAL::to_double(m * o.normal);
    }
    for (int d = 0; d < 3; ++d) {
      r.cell[d] = std::int32_t(std::max(-1e9, std::min(1e9, std::floor(CGAL::to_double(p[d]) / m_cell))));
      r.packed_cell = (r.packed_cell << 21) | (std::uint64_t(std::int64_t(r.cell[d])) & 0x1FFFFF);
    }
    Point& slot = m_ring.slot(m_at);
    slot.position = p;
    slot.normal = m;
    slot.has_normal = r.has_normal;
    ++m_at;
    return r;
  }

private:
  struct Point
  {
    Kernel::Point_3 position;
    Kernel::Vector_3 normal;
    bool has_normal = false;
  };

  double m_cell;
  std::uint64_t m_at = 0;
  Span_ring<Point> m_ring;
};

/// The patch units of the points pushed in the sweep order.  A point joins
/// the provisional sheet of its earlier neighbours across the edges that
/// `same_sheet()` accepts with the median slope of the edges seen so far
/// (`patch_slope()`), or starts one; a unit is the points of one final
/// segment, one provisional sheet and one cell of side `cell`.  Two units
/// are adjacent when an edge of slope at most `sheet_slope` joins them
/// within one component with oriented normals within 60 degrees of each
/// other or of each other's opposite; each adjacency keeps the smallest
/// slope of either kind.  So a patch of the current signs (`patches()`) is
/// what `build_patches()` would make of the points, except that a unit is
/// never split.  The points come measured by a `Unit_measure`, which a pass
/// can run ahead on another thread, or are measured here.  Memory: the last
/// `span` points, the units, their adjacencies (at most `maximum_units`
/// units) and the provisional sheets.  Deterministic.
class Patch_units
{
public:
  typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
  /// the side of a coarse cell (level 1 of `patches()`), in cells
  static constexpr int coarse_factor = 3;

  /// for edges reaching at most `span` points back, cells of side `cell`
  /// (> 0) and at most `maximum_units` units (beyond, `overflowed()`)
  Patch_units(std::uint64_t span, double cell, std::size_t maximum_units = std::size_t(1) << 18)
    : m_ring(span), m_cell(cell), m_maximum_units(maximum_units)
  {}

  /// whether the points needed more than the maximum number of units: then
  /// the units and their adjacencies stop growing, and are not to be used
  bool overflowed() const { return m_overflowed; }

  /// The next point in the sweep order: its position, its oriented normal
  /// (zero: none), its final segment and component, its earlier edges
  /// `edges[0 .. count - 1]` and `sign`, +1 or -1, its oriented normal over
  /// its input normal (the frame of the edges' weights); returns its unit.
  /// \throw std::runtime_error when an edge reaches before the first point or
  ///        farther back than the span
  std::uint32_t push(const Kernel::Point_3& p, const Kernel::Vector_3& m, std::uint32_t segment,
                     std::uint32_t component, const Earlier_edge* edges, std::size_t count, int sign = 1)
  {
    if (!m_measure)
      m_measure = std::make_unique<Unit_measure>(m_ring.span(), m_cell);
    m_measured.resize(std::max<std::size_t>(m_measured.size(), count));
    const Measured_point point = m_measure->measure(p, m, edges, count, m_measured.data());
    return push(point, m_measured.data(), segment, component, edges, count, sign);
  }

  /// The next point as `push()` above, measured by a `Unit_measure` of the
  /// same span and cell side that measured every earlier point: `point`,
  /// and `measured[0 .. count - 1]` the measures of `edges`.
  std::uint32_t push(const Measured_point& point, const Measured_edge* measured, std::uint32_t segment,
                     std::uint32_t component, const Earlier_edge* edges, std::size_t count, int sign = 1)
  {
    const bool has_normal = point.has_normal;
    std::uint32_t sheet = no_sheet;
    for (std::size_t e = 0; e < count && has_normal; ++e) {
      const Point& o = earlier(edges[e].offset);
      if (!o.has_normal || o.component != component ||
          !Normal_orientation::internal::same_sheet(measured[e].dot, float(measured[e].slope), m_split_slope))
        continue;
      if (sheet == no_sheet)
        sheet = find(o.sheet);
      else
        sheet = unite(sheet, o.sheet);
    }
    if (sheet == no_sheet) {
      sheet = std::uint32_t(m_sheet_parent.size());
      m_sheet_parent.push_back(sheet);
    }
    const std::uint32_t unit = unit_of(point, segment, sheet, component);
    std::uint64_t last_pair = ~std::uint64_t(0);
    Pair* pair = nullptr;
    for (std::size_t e = 0; e < count && has_normal && !m_overflowed; ++e) {
      const Point& o = earlier(edges[e].offset);
      if (!o.has_normal)
        continue;
      const double s = measured[e].slope;
      ++m_histogram[std::min<std::size_t>(m_histogram.size() - 1, std::size_t(s * double(m_histogram.size())))];
      if (o.unit == unit)
        continue;
      const std::uint32_t a = std::min(unit, o.unit), b = std::max(unit, o.unit);
      const std::uint64_t key = (std::uint64_t(a) << 32) | b;
      if (key != last_pair) { // (the elements of the map stay where they are)
        pair = &m_pairs[key];
        last_pair = key;
      }
      const float w = edges[e].weight * float(sign * o.sign);
      pair->coupling += w;
      pair->magnitude += std::abs(w);
      if (o.component != component || s > Normal_orientation::internal::sheet_slope)
        continue;
      const double dot = measured[e].dot;
      if (dot > -0.5 && dot < 0.5)
        continue;
      float& least = pair->least[dot >= 0.5 ? 0 : 1];
      least = std::min(least, float(s));
    }
    if (!m_overflowed)
      ++m_unit_size[unit];
    Point& slot = m_ring.slot(m_at);
    slot.unit = unit;
    slot.sheet = sheet;
    slot.component = component;
    slot.has_normal = has_normal;
    slot.sign = sign < 0 ? -1 : 1;
    if (++m_at % 4096 == 0)
      m_split_slope = patch_slope();
    return unit;
  }

  /// the span of the edges
  std::uint64_t span() const { return m_ring.span(); }
  /// the side of the cells
  double cell_side() const { return m_cell; }
  /// the number of units
  std::size_t number_of_units() const { return m_unit_segment.size(); }
  /// the final segment of every unit
  const std::vector<std::uint32_t>& unit_segment() const { return m_unit_segment; }
  /// the component of every unit
  const std::vector<std::uint32_t>& unit_component() const { return m_unit_component; }
  /// the points of every unit
  const std::vector<std::uint32_t>& unit_size() const { return m_unit_size; }

  /// Calls `f(a, b, coupling, magnitude)` for every pair of units a < b
  /// joined by edges: the sum of their weights in the frame of the pushed
  /// orientations, and the sum of their absolute values.  In an order that
  /// depends only on the points pushed.
  template <typename F>
  void visit_couplings(F f) const
  {
    for (const auto& pair : m_pairs)
      f(std::uint32_t(pair.first >> 32), std::uint32_t(pair.first & 0xFFFFFFFFu), double(pair.second.coupling),
        double(pair.second.magnitude));
  }

  /// The patches of the units with the negations `flip` (per unit, relative
  /// to the orientation pushed): the units united across their adjacencies
  /// whose oriented normals agree after the negations with a slope of at
  /// most `max_slope`, within one cell of `level` (0: anywhere, 1: a coarse
  /// cell, 2: a cell), numbered 0, 1, ... by their first unit.
  std::vector<std::uint32_t> patches(const std::vector<char>& flip, double max_slope, int level) const
  {
    // (the sets do not depend on the order of the unions; their numbers,
    // by first unit, do not depend on the roots)
    Signed_union_find sets(flip.size());
    for (const auto& pair : m_pairs) {
      const std::uint32_t a = std::uint32_t(pair.first >> 32), b = std::uint32_t(pair.first & 0xFFFFFFFFu);
      if (double(pair.second.least[flip[a] != flip[b] ? 1 : 0]) > max_slope)
        continue;
      if (level != 0 && !same_cell(a, b, level == 1 ? coarse_factor : 1))
        continue;
      sets.unite(a, b);
    }
    const std::uint32_t unset = ~std::uint32_t(0);
    std::vector<std::uint32_t> id(flip.size(), unset), patch(flip.size());
    std::uint32_t next = 0;
    for (std::size_t u = 0; u < patch.size(); ++u) {
      const std::uint32_t r = sets.find(Signed_union_find::Index(u));
      if (id[r] == unset)
        id[r] = next++;
      patch[u] = id[r];
    }
    return patch;
  }

  /// the median slope of the edges pushed, within [`patch_slope_floor`,
  /// `sheet_slope`], as `patch_slope()` of the in-core graph
  double patch_slope() const
  {
    std::uint64_t total = 0, below = 0;
    for (std::uint64_t c : m_histogram)
      total += c;
    if (total == 0)
      return Normal_orientation::internal::sheet_slope;
    std::size_t b = 0;
    for (; b + 1 < m_histogram.size(); ++b) {
      below += m_histogram[b];
      if (2 * below > total)
        break;
    }
    const double median = (double(b) + 0.5) / double(m_histogram.size());
    return Normal_orientation::internal::clamp_patch_slope(median);
  }

private:
  static constexpr std::uint32_t no_sheet = ~std::uint32_t(0);

  struct Point
  {
    std::uint32_t unit = 0, sheet = 0, component = 0;
    bool has_normal = false;
    signed char sign = 1;
  };
  /// the units joined by edges: the least slope of an edge between
  /// oriented normals that agree [0] or are opposite [1] (2: none, or not
  /// adjacent), the sum of the edges' weights and of their absolute values
  struct Pair
  {
    std::array<float, 2> least{{2.0f, 2.0f}};
    float coupling = 0.0f, magnitude = 0.0f;
  };
  typedef std::pair<std::uint64_t, std::uint64_t> Key;
  struct Key_hash
  {
    std::size_t operator()(const Key& k) const
    {
      return std::size_t((k.first * 0x9E3779B97F4A7C15ull) ^ (k.second * 0xC2B2AE3D27D4EB4Full));
    }
  };

  const Point& earlier(std::uint64_t back) const { return m_ring.earlier(m_at, back); }

  std::uint32_t find(std::uint32_t s)
  {
    while (m_sheet_parent[s] != s)
      s = m_sheet_parent[s] = m_sheet_parent[m_sheet_parent[s]];
    return s;
  }
  std::uint32_t unite(std::uint32_t a, std::uint32_t b)
  {
    a = find(a);
    b = find(b);
    m_sheet_parent[std::max(a, b)] = std::min(a, b);
    return std::min(a, b);
  }

  std::uint32_t unit_of(const Measured_point& point, std::uint32_t segment, std::uint32_t sheet,
                        std::uint32_t component)
  {
    const std::array<std::int32_t, 3>& c = point.cell;
    const Key key((std::uint64_t(sheet) << 32) | segment, point.packed_cell);
    if (m_at > 0 && key == m_last_key)
      return m_last_unit;
    if (m_overflowed)
      return 0;
    if (m_unit_segment.size() >= m_maximum_units && m_units.find(key) == m_units.end()) {
      m_overflowed = true;
      m_units.clear();
      m_pairs.clear();
      return 0;
    }
    const auto ins = m_units.emplace(key, std::uint32_t(m_unit_segment.size()));
    if (ins.second) {
      m_unit_cell.push_back(c);
      m_unit_segment.push_back(segment);
      m_unit_component.push_back(component);
      m_unit_size.push_back(0);
    }
    m_last_key = key;
    m_last_unit = ins.first->second;
    return m_last_unit;
  }

  bool same_cell(std::uint32_t a, std::uint32_t b, int factor) const
  {
    auto coarse = [factor](std::int32_t c) { return c >= 0 ? c / factor : -((-c + factor - 1) / factor); };
    for (int d = 0; d < 3; ++d)
      if (coarse(m_unit_cell[a][d]) != coarse(m_unit_cell[b][d]))
        return false;
    return true;
  }

  Span_ring<Point> m_ring;
  double m_cell;
  std::unique_ptr<Unit_measure> m_measure; // (for the first `push()`)
  std::vector<Measured_edge> m_measured;
  std::size_t m_maximum_units;
  bool m_overflowed = false;
  std::uint64_t m_at = 0;
  double m_split_slope = Normal_orientation::internal::sheet_slope;
  std::array<std::uint64_t, 1024> m_histogram{};
  std::vector<std::uint32_t> m_sheet_parent;
  std::unordered_map<Key, std::uint32_t, Key_hash> m_units;
  Key m_last_key;
  std::uint32_t m_last_unit = 0;
  std::vector<std::array<std::int32_t, 3>> m_unit_cell;
  std::vector<std::uint32_t> m_unit_segment, m_unit_component, m_unit_size;
  std::unordered_map<std::uint64_t, Pair> m_pairs;
};

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_PATCH_UNITS_H
