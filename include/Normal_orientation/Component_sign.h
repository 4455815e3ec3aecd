// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_COMPONENT_SIGN_H
#define NORMAL_ORIENTATION_COMPONENT_SIGN_H

/// \file Component_sign.h
/// Component sign policies: the energy does not change when every label of
/// a connected component flips, so after the solve a policy decides the
/// sign of each component.

#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/Orientation_problem.h>

#include <CGAL/number_utils.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationSign
/// What a component sign policy sees.  `normals[i] * labels[i]` is the
/// current orientation of point i (normals are unit length, or zero).
template <typename Kernel>
struct Component_sign_input
{
  /// the positions
  const std::vector<typename Kernel::Point_3>& points;
  /// the input normals, normalised (zero where the input normal was zero)
  const std::vector<typename Kernel::Vector_3>& normals;
  /// the labels chosen by the solver (+1 / -1)
  const std::vector<Label>& labels;
  /// the component of every point, 0 ... number_of_components - 1
  const std::vector<std::uint32_t>& component;
  /// the number of components
  std::size_t number_of_components;
  /// the neighbour radius r of the graph
  double radius;
  /// when not null, `(*constrained)[i] != 0` marks a point whose input
  /// normal is known to be correctly oriented (`point_is_constrained_map`)
  const std::vector<char>* constrained;
};

/// \ingroup PkgNormalOrientationSign
/// Leaves every component as the solver left it.
/// \cgalModels `ComponentSignPolicy`
struct Keep_component_sign
{
  /// returns, for each component, whether to flip it: never
  template <typename Kernel>
  std::vector<char> operator()(const Component_sign_input<Kernel>& in) const
  {
    return std::vector<char>(in.number_of_components, 0);
  }
  /// the name used in reports
  static const char* name() { return "keep"; }
};

/// \ingroup PkgNormalOrientationSign
/// The default: every component is made to face outward, as the boundary of
/// a closed object would.  For a component of at least
/// `minimum_size_for_directions` points, each of `number_of_directions`
/// directions d spread evenly on the sphere is a witness: the points whose
/// projection on d lies within `band` times the component's extent along d
/// of the extremal one are on the convex hull side facing d, where outward
/// normals point along d; the witness's vote is the mean of d . n over
/// those points, weighted by closeness to the extremal plane, a number in
/// [-1, 1].  The component flips when the sum of the votes is negative.
/// Components larger than `maximum_voters` vote with an evenly spread
/// subsample of that size, which keeps the cost at O(n + 64 *
/// maximum_voters) per component.
/// Many witnesses, each averaging many points, keep one noisy normal at the
/// topmost point (the peers' rule) from flipping a whole object.  Smaller
/// components flip when the normals point on average towards their
/// centroid.  Open surfaces (a single flat patch, say) get a vote near zero
/// and are left as they are.  A closed component nested inside another
/// (the inner wall of a hollow object) is also made to face outward of
/// itself, which is wrong for such walls: use a viewpoint or constraints.
/// \cgalModels `ComponentSignPolicy`
struct Outward_component_sign
{
  /// witnesses per component
  unsigned int number_of_directions = 64;
  /// relative depth of the band of points that vote for each direction
  double band = 0.03;
  /// components smaller than this use the centroid rule
  std::size_t minimum_size_for_directions = 128;
  /// larger components vote with an evenly spread subsample of about this
  /// many points
  std::size_t maximum_voters = 16384;

  /// the name used in reports
  static const char* name() { return "outward"; }

  /// returns, for each component, whether to flip it
  template <typename Kernel>
  std::vector<char> operator()(const Component_sign_input<Kernel>& in) const
  {
    const std::size_t n = in.points.size(), nc = in.number_of_components;
    std::vector<std::size_t> size(nc, 0);
    for (std::size_t i = 0; i < n; ++i)
      ++size[in.component[i]];
    auto oriented = [&](std::size_t i, int d) {
      return double(in.labels[i]) * CGAL::to_double(in.normals[i][d]);
    };
    auto coord = [&](std::size_t i, int d) { return CGAL::to_double(in.points[i][d]); };

    // Large components: extremal witnesses along many directions.
    const std::uint32_t none = ~std::uint32_t(0);
    std::vector<std::uint32_t> large_id(nc, none);
    std::size_t nl = 0;
    for (std::size_t c = 0; c < nc; ++c)
      if (size[c] >= minimum_size_for_directions)
        large_id[c] = std::uint32_t(nl++);
    const unsigned D = std::max(1u, number_of_directions);
    std::vector<std::array<double, 3>> dir(D);
    const double golden = M_PI * (3.0 - std::sqrt(5.0));
    for (unsigned t = 0; t < D; ++t) { // Fibonacci sphere
      const double z = 1.0 - (2.0 * t + 1.0) / double(D);
      const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
      dir[t] = {s * std::cos(golden * t), s * std::sin(golden * t), z};
    }
    // Flat copies of the points of large components (positions and
    // current normals), so that the loops below stream through memory.
    // A component of more than `maximum_voters` points votes with every
    // s-th of its points, s = ceil(size / maximum_voters): the vote needs a
    // dense sample of the extremal bands, not every point, and points
    // arrive in a spatially coherent order (see `orient_normals()`), so the
    // subsample is spread evenly.
    std::vector<std::size_t> stride(nc, 1), seen(nc, 0);
    for (std::size_t c = 0; c < nc; ++c)
      stride[c] = std::max<std::size_t>(1, (size[c] + maximum_voters - 1) / std::max<std::size_t>(1, maximum_voters));
    std::vector<std::uint32_t> cid;
    std::vector<double> px, py, pz, nx, ny, nz;
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t c = large_id[in.component[i]];
      if (c == none)
        continue;
      if (seen[in.component[i]]++ % stride[in.component[i]] != 0)
        continue;
      cid.push_back(c);
      px.push_back(coord(i, 0)); py.push_back(coord(i, 1)); pz.push_back(coord(i, 2));
      nx.push_back(oriented(i, 0)); ny.push_back(oriented(i, 1)); nz.push_back(oriented(i, 2));
    }
    const std::size_t m = cid.size();
    std::vector<double> hi(nl * D, -HUGE_VAL), lo(nl * D, HUGE_VAL), num(nl * D, 0.0), den(nl * D, 0.0);
    if (nl > 0) {
      // Each direction is handled by one task over all points, so every
      // sum is accumulated in point order: deterministic for any thread
      // count.
      internal::parallel_chunks<CGAL::Parallel_if_available_tag>(D, [&](std::size_t b, std::size_t e) {
        std::vector<double> proj(m);
        for (std::size_t t = b; t < e; ++t) {
          const double dx = dir[t][0], dy = dir[t][1], dz = dir[t][2];
          for (std::size_t i = 0; i < m; ++i) {
            const double p = px[i] * dx + py[i] * dy + pz[i] * dz;
            proj[i] = p;
            const std::size_t s = std::size_t(cid[i]) * D + t;
            hi[s] = std::max(hi[s], p);
            lo[s] = std::min(lo[s], p);
          }
          for (std::size_t i = 0; i < m; ++i) {
            const std::size_t s = std::size_t(cid[i]) * D + t;
            const double depth = band * (hi[s] - lo[s]);
            const double w = depth > 0.0 ? 1.0 - (hi[s] - proj[i]) / depth : (proj[i] >= hi[s] ? 1.0 : 0.0);
            if (w <= 0.0)
              continue;
            num[s] += w * (nx[i] * dx + ny[i] * dy + nz[i] * dz);
            den[s] += w;
          }
        }
      }, 1);
    }
    std::vector<double> vote(nc, 0.0);
    for (std::size_t c = 0; c < nc; ++c)
      if (large_id[c] != none)
        for (unsigned t = 0; t < D; ++t) {
          const std::size_t s = std::size_t(large_id[c]) * D + t;
          if (den[s] > 0.0)
            vote[c] += num[s] / den[s];
        }

    // Small components: do normals point away from the centroid?
    std::vector<std::array<double, 3>> centroid(nc, {0.0, 0.0, 0.0});
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t c = in.component[i];
      if (large_id[c] != none)
        continue;
      for (int d = 0; d < 3; ++d)
        centroid[c][d] += coord(i, d) / double(size[c]);
    }
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t c = in.component[i];
      if (large_id[c] != none)
        continue;
      for (int d = 0; d < 3; ++d)
        vote[c] += (coord(i, d) - centroid[c][d]) * oriented(i, d);
    }

    std::vector<char> flip(nc, 0);
    for (std::size_t c = 0; c < nc; ++c)
      flip[c] = vote[c] < 0.0 ? 1 : 0;
    return flip;
  }
};

/// \ingroup PkgNormalOrientationSign
/// Every component faces a viewpoint (a scanner position, a camera): it
/// flips when its normals point, on average, away from the viewpoint.
/// \cgalModels `ComponentSignPolicy`
struct Viewpoint_component_sign
{
  /// the viewpoint
  std::array<double, 3> viewpoint{{0.0, 0.0, 0.0}};

  /// the policy for the viewpoint (x, y, z)
  Viewpoint_component_sign(double x = 0.0, double y = 0.0, double z = 0.0) : viewpoint{{x, y, z}} {}

  /// the name used in reports
  static const char* name() { return "viewpoint"; }

  /// returns, for each component, whether to flip it
  template <typename Kernel>
  std::vector<char> operator()(const Component_sign_input<Kernel>& in) const
  {
    std::vector<double> vote(in.number_of_components, 0.0);
    for (std::size_t i = 0; i < in.points.size(); ++i) {
      double v[3], l2 = 0.0, dn = 0.0;
      for (int d = 0; d < 3; ++d) {
        v[d] = viewpoint[d] - CGAL::to_double(in.points[i][d]);
        l2 += v[d] * v[d];
      }
      if (!(l2 > 0.0))
        continue;
      for (int d = 0; d < 3; ++d)
        dn += v[d] * double(in.labels[i]) * CGAL::to_double(in.normals[i][d]);
      vote[in.component[i]] += dn / std::sqrt(l2);
    }
    std::vector<char> flip(in.number_of_components, 0);
    for (std::size_t c = 0; c < flip.size(); ++c)
      flip[c] = vote[c] < 0.0 ? 1 : 0;
    return flip;
  }
};

/// \ingroup PkgNormalOrientationSign
/// User-fixed points (CGAL's `point_is_constrained_map` idea): a component
/// that holds constrained points takes the sign on which most of them agree
/// with their input orientation; components without constrained points,
/// or with a tie, are decided by `Fallback`.
/// \cgalModels `ComponentSignPolicy`
template <typename Fallback = Outward_component_sign>
struct Constrained_component_sign
{
  /// the policy for components without constrained points
  Fallback fallback;

  /// the name used in reports
  static const char* name() { return "constrained"; }

  /// returns, for each component, whether to flip it
  template <typename Kernel>
  std::vector<char> operator()(const Component_sign_input<Kernel>& in) const
  {
    std::vector<char> flip = fallback(in);
    if (in.constrained == nullptr)
      return flip;
    std::vector<long long> agree(in.number_of_components, 0);
    for (std::size_t i = 0; i < in.points.size(); ++i)
      if ((*in.constrained)[i])
        agree[in.component[i]] += in.labels[i];
    for (std::size_t c = 0; c < flip.size(); ++c)
      if (agree[c] != 0)
        flip[c] = agree[c] < 0 ? 1 : 0;
    return flip;
  }
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_COMPONENT_SIGN_H
