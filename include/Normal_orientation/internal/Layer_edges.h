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
#include <cmath>
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

/// How a point's layer offset was found (`fit_layer_offsets()`).
enum Layer_fit_state : unsigned char
{
  ONE_LAYER = 0,   ///< not two layers (or not known yet)
  FIRST_PASS = 1,  ///< two layers in the first pass
  SECOND_PASS = 2, ///< two layers in the second pass
  FILLED = 3       ///< from a two-layer neighbour (the fill)
};

/// `for_each_nearest`'s index of a neighbour that is not among the points
/// of the call
constexpr std::size_t no_local = ~std::size_t(0);

/// The offset that point `p` takes from its two-layer neighbour at `q`, of
/// offset `t`: to the other layer of q when p lies on q's layer, back to
/// q's layer when it lies beyond the middle of the gap.
inline Layer_offset filled_offset(const double p[3], const double q[3], const Layer_offset& t)
{
  const double g = std::sqrt(double(t[0]) * t[0] + double(t[1]) * t[1] + double(t[2]) * t[2]);
  const double u[3] = {t[0] / g, t[1] / g, t[2] / g};
  const double s = (p[0] - q[0]) * u[0] + (p[1] - q[1]) * u[1] + (p[2] - q[2]) * u[2];
  const double a = s < 0.5 * g ? g - s : -s;
  return Layer_offset{{float(a * u[0]), float(a * u[1]), float(a * u[2])}};
}

/// Fits the layer offsets of `count` points into `out`, and their states
/// into `state` (both resized), in parallel; the same for any number of
/// threads.  `point_at(q, p, u)` writes the position and normal (any length;
/// zero: no fit) of point q to the arrays p[3] and u[3];
/// `for_each_nearest(q, f)` calls f(x, local, state, offset) for each of its
/// k nearest neighbours closer than r: x its position (double[3]), local its
/// index when it is one of the call's points, else `no_local`, with then its
/// state and offset as far as the caller knows them (`ONE_LAYER` when not
/// yet).  Coincident positions count once.
/// 1. First pass: every point, with the early rejections of
///    `Two_layer_thresholds`.
/// 2. Second pass: without them, the points with a neighbour two layers in
///    the first pass (a layer's edge, or a curved layer whose normal line is
///    a few degrees off).
/// 3. The fill: a point still on one layer, a quarter or more of whose
///    neighbours are two layers after the passes, takes its offset from the
///    nearest of them (`filled_offset()`; ties by position): where a layer
///    has fewer than 3 of a point's neighbours, the fit misses it.
template <typename ConcurrencyTag, typename PointAt, typename ForEachNearest>
void fit_layer_offsets(std::size_t count, const PointAt& point_at, const ForEachNearest& for_each_nearest,
                       std::vector<Layer_offset>& out, std::vector<unsigned char>& state)
{
  out.assign(count, Layer_offset{{0.f, 0.f, 0.f}});
  state.assign(count, ONE_LAYER);
  // again[i]: 1 when a neighbour of i is two layers in the first pass, 2
  // when one is two layers in any way (set in the first pass for the
  // neighbours that are not the call's points, whose states are known)
  std::vector<char> again(count, 0);
  Two_layer_thresholds late;
  late.early_separation = 0.0;
  late.early_gap = 0.0;
  late.early_side_by_side = false;
  late.early_detilt = false;
  auto fit = [&](bool second) {
    parallel_chunks<ConcurrencyTag>(
      count,
      [&](std::size_t b, std::size_t e) {
        std::vector<std::array<double, 3>> q;
        std::vector<std::pair<double, std::uint32_t>> scratch;
        for (std::size_t i = b; i < e; ++i) {
          if (second && (again[i] != 1 || state[i] != ONE_LAYER))
            continue;
          double p[3], n[3];
          point_at(i, p, n);
          const std::array<double, 3> u = unit_vector(n[0], n[1], n[2]);
          q.clear();
          q.push_back({{p[0], p[1], p[2]}});
          for_each_nearest(i, [&](const double* x, std::size_t local, unsigned char s, const Layer_offset&) {
            if (!second && local == no_local && s != ONE_LAYER)
              again[i] = std::max(again[i], char(s == FIRST_PASS ? 1 : s == SECOND_PASS ? 2 : 0));
            q.push_back({{x[0], x[1], x[2]}});
          });
          // coincident positions once (after the gather, whose loads overlap)
          std::size_t kept = 1;
          for (std::size_t j = 1; j < q.size(); ++j)
            if (std::find(q.begin(), q.begin() + kept, q[j]) == q.begin() + kept)
              q[kept++] = q[j];
          q.resize(kept);
          if (u == std::array<double, 3>{{0.0, 0.0, 0.0}})
            continue;
          const Two_layer_fit f = fit_two_layers(q, u, scratch, second ? late : Two_layer_thresholds());
          if (f.two_layers) {
            out[i] = Layer_offset{{float(f.to_other[0]), float(f.to_other[1]), float(f.to_other[2])}};
            state[i] = second ? SECOND_PASS : FIRST_PASS;
          }
        }
      },
      256);
  };
  auto state_of = [&](std::size_t local, unsigned char external) { return local != no_local ? state[local] : external; };
  fit(false);
  const bool first_pass_fits = std::find(state.begin(), state.end(), FIRST_PASS) != state.end();
  if (first_pass_fits)
    parallel_chunks<ConcurrencyTag>(
      count,
      [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i)
          if (state[i] == ONE_LAYER && again[i] != 1)
            for_each_nearest(i, [&](const double*, std::size_t local, unsigned char, const Layer_offset&) {
              if (local != no_local && state[local] == FIRST_PASS)
                again[i] = 1;
            });
      },
      256);
  if (std::find(again.begin(), again.end(), char(1)) != again.end())
    fit(true);
  // the fill, where a neighbour is two layers
  if (std::find_if(state.begin(), state.end(), [](unsigned char c) { return c != ONE_LAYER; }) == state.end() &&
      std::find_if(again.begin(), again.end(), [](char a) { return a != 0; }) == again.end())
    return;
  std::vector<Layer_offset> fill(count, Layer_offset{{0.f, 0.f, 0.f}});
  parallel_chunks<ConcurrencyTag>(
    count,
    [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        if (state[i] != ONE_LAYER)
          continue;
        double p[3], n[3];
        point_at(i, p, n);
        std::size_t all = 0, layered = 0;
        double best = HUGE_VAL;
        std::array<double, 3> from{};
        Layer_offset t{};
        for_each_nearest(i, [&](const double* x, std::size_t local, unsigned char s, const Layer_offset& o) {
          ++all;
          const unsigned char st = state_of(local, s);
          if (st != FIRST_PASS && st != SECOND_PASS)
            return;
          ++layered;
          const double d = (x[0] - p[0]) * (x[0] - p[0]) + (x[1] - p[1]) * (x[1] - p[1]) + (x[2] - p[2]) * (x[2] - p[2]);
          const std::array<double, 3> a = {{x[0], x[1], x[2]}};
          if (d < best || (d == best && a < from)) {
            best = d;
            from = a;
            t = local != no_local ? out[local] : o;
          }
        });
        if (layered > 0 && 4 * layered >= all)
          fill[i] = filled_offset(p, from.data(), t);
      }
    },
    256);
  for (std::size_t i = 0; i < count; ++i)
    if (is_two_layers(fill[i])) {
      out[i] = fill[i];
      state[i] = FILLED;
    }
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

/// The smallest |cos| between the normal lines of an edge's ends for the
/// edge to cross two layers: the layers are parallel, and the false fits at
/// a sharp crease see the other face, at right angles.
constexpr double layer_edge_min_alignment = 0.5;

/// Whether the edge {p, q}, of normals np and nq (any length), crosses a
/// gap between two layers, seen from either end, between nearly parallel
/// normal lines: its weight is then negated.
inline bool edge_across_layers(const double p[3], const Layer_offset& tp, const double np[3], const double q[3],
                               const Layer_offset& tq, const double nq[3])
{
  if (!across_layers(p, q, tp) && !across_layers(q, p, tq))
    return false;
  const double c = np[0] * nq[0] + np[1] * nq[1] + np[2] * nq[2];
  const double a = np[0] * np[0] + np[1] * np[1] + np[2] * np[2], b = nq[0] * nq[0] + nq[1] * nq[1] + nq[2] * nq[2];
  return c * c >= layer_edge_min_alignment * layer_edge_min_alignment * a * b && a > 0.0 && b > 0.0;
}

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_LAYER_EDGES_H
