// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_LAYER_EDGES_H
#define NORMAL_ORIENTATION_INTERNAL_LAYER_EDGES_H

/// \file Layer_edges.h
/// Edges across two layers (the manual's *Layer edges*), the rule of both
/// drivers' graphs: where a point's k nearest neighbours lie on two parallel
/// layers closer than the neighbour distance (`fit_two_layers()`), the
/// layers bound the slab between them, so their outward normals are
/// opposite whether the slab is inside (a thin part) or outside (a
/// contact), while the flip criterion sees two nearly parallel normal lines
/// and asks for the same sign.  The weight of every edge across the gap is
/// negated.

#include <Normal_orientation/internal/Parallel.h>
#include <Normal_orientation/internal/Two_layer_fit.h>
#include <Normal_orientation/internal/Unit_vector.h>

#include <CGAL/number_utils.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// Per point, the vector from it to the other layer's mean along the fitted
/// line (`Two_layer_fit::to_other`), in single precision; zero where the
/// neighbourhood is one layer.
typedef std::array<float, 3> Layer_offset;

/// The coordinates of a CGAL point or vector `v`, written to x[3].
template <typename PointOrVector>
void to_array(const PointOrVector& v, double* x)
{
  x[0] = CGAL::to_double(v.x());
  x[1] = CGAL::to_double(v.y());
  x[2] = CGAL::to_double(v.z());
}

/// true when the neighbourhood of the point of offset `t` is two layers
inline bool is_two_layers(const Layer_offset& t) { return t[0] != 0.f || t[1] != 0.f || t[2] != 0.f; }

/// Fits the layer offsets of `count` points into `out` (resized), in
/// parallel; the same for any number of threads.  `point_at(q, p, u)` writes
/// the position and normal (any length; zero: no fit) of point q to the
/// arrays p[3] and u[3]; `for_each_nearest(q, f)` calls f(x) with the
/// position x (double[3]) of each of its k nearest neighbours closer than r
/// (coincident positions count once).
/// First pass: every point, with the early rejections of
/// `Two_layer_thresholds`.  Second pass: without them, the points for which
/// `nearest_two_layers(q)`, called after the first pass (`out` then holds its
/// offsets), says that a nearest neighbour was two layers in the first pass
/// (a layer's edge, or a curved layer whose normal line is a few degrees
/// off).  `first_pass`, if not null, receives per point whether it was two
/// layers after the first pass.
template <typename ConcurrencyTag, typename PointAt, typename ForEachNearest, typename NearestTwoLayers>
void fit_layer_offsets(std::size_t count, const PointAt& point_at, const ForEachNearest& for_each_nearest,
                       const NearestTwoLayers& nearest_two_layers, std::vector<Layer_offset>& out,
                       std::vector<char>* first_pass = nullptr)
{
  out.assign(count, Layer_offset{{0.f, 0.f, 0.f}});
  std::vector<char> again;
  Two_layer_thresholds late;
  late.early_separation = 0.0;
  late.early_gap = 0.0;
  auto fit = [&](bool second) {
    parallel_chunks<ConcurrencyTag>(
      count,
      [&](std::size_t b, std::size_t e) {
        std::vector<std::array<double, 3>> q;
        std::vector<std::pair<double, std::uint32_t>> scratch;
        for (std::size_t i = b; i < e; ++i) {
          if (second && !again[i])
            continue;
          double p[3], n[3];
          point_at(i, p, n);
          const std::array<double, 3> u = unit_vector(n[0], n[1], n[2]);
          if (u == std::array<double, 3>{{0.0, 0.0, 0.0}})
            continue;
          q.clear();
          q.push_back({{p[0], p[1], p[2]}});
          for_each_nearest(i, [&](const double* x) { // (coincident points count once)
            const std::array<double, 3> a = {{x[0], x[1], x[2]}};
            if (std::find(q.begin(), q.end(), a) == q.end())
              q.push_back(a);
          });
          const Two_layer_fit f = fit_two_layers(q, u, scratch, second ? late : Two_layer_thresholds());
          if (f.two_layers)
            out[i] = Layer_offset{{float(f.to_other[0]), float(f.to_other[1]), float(f.to_other[2])}};
        }
      },
      256);
  };
  fit(false);
  if (first_pass != nullptr) {
    first_pass->assign(count, 0);
    for (std::size_t i = 0; i < count; ++i)
      (*first_pass)[i] = char(is_two_layers(out[i]));
  }
  again.assign(count, 0);
  bool any = false;
  for (std::size_t i = 0; i < count; ++i)
    if (!is_two_layers(out[i]) && nearest_two_layers(i)) {
      again[i] = 1;
      any = true;
    }
  if (any)
    fit(true);
}

/// Whether q lies on the other layer of the point p, whose layer offset is
/// `t`: beyond the middle of the gap.
inline bool across_layers(const double p[3], const double q[3], const Layer_offset& t)
{
  const double tt = double(t[0]) * t[0] + double(t[1]) * t[1] + double(t[2]) * t[2];
  if (tt == 0.0)
    return false;
  const double d = (q[0] - p[0]) * t[0] + (q[1] - p[1]) * t[1] + (q[2] - p[2]) * t[2];
  return d > 0.5 * tt;
}

/// Whether the edge {p, q} crosses a gap between two layers, seen from
/// either end: its weight is then negated.
inline bool edge_across_layers(const double p[3], const Layer_offset& tp, const double q[3], const Layer_offset& tq)
{
  return across_layers(p, q, tp) || across_layers(q, p, tq);
}

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_LAYER_EDGES_H
