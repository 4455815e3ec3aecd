// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_WINDING_NUMBER_FIELD_H
#define NORMAL_ORIENTATION_WINDING_NUMBER_FIELD_H

/// \file Winding_number_field.h
/// The generalised winding number of an oriented point cloud (Barill et al.
/// 2018), evaluated by a Barnes-Hut treecode, and the point areas it needs.

#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/internal/Unit_vector.h>
#include <Normal_orientation/internal/Winding_number_tree.h>

#include <CGAL/Kernel_traits.h>
#include <CGAL/tags.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationGlobal
/// The default number of neighbours of `estimate_point_areas()`.
constexpr unsigned int default_area_neighbors = 16;

/// \ingroup PkgNormalOrientationGlobal
/// The default opening ratio beta of `Winding_number_field`: a node of radius r
/// whose centre is farther than beta r from the query is summed as a whole.
constexpr double default_opening_ratio = 2.0;

/// \ingroup PkgNormalOrientationGlobal
/// The default smoothing factor of `Winding_number_field`: the kernel of point i
/// is smoothed over the width eps_i = factor * sqrt(a_i), about one point spacing.
constexpr double default_smoothing_factor = 1.0;

/// \ingroup PkgNormalOrientationGlobal
/// The default number of points per leaf of the tree of `Winding_number_field`.
constexpr unsigned int default_winding_leaf_size = 16;

/// \cond SKIP_IN_MANUAL
namespace internal {

/// The area of the Voronoi cell of the origin among the points (x[t], y[t]),
/// t < m, of a plane, clipped to the regular octagon of inradius h.
inline double clipped_voronoi_area(const double* x, const double* y, unsigned int m, double h)
{
  // Sutherland-Hodgman clipping of a convex polygon by half-planes.
  std::array<double, 2 * (8 + 64) + 2> buffer_a, buffer_b;
  double* poly = buffer_a.data();
  double* next = buffer_b.data();
  unsigned int size = 8;
  const double pi = 3.14159265358979323846;
  const double R = h / std::cos(pi / 8.0); // circumradius of the octagon
  for (unsigned int v = 0; v < 8; ++v) {
    poly[2 * v] = R * std::cos(pi / 8.0 + v * pi / 4.0);
    poly[2 * v + 1] = R * std::sin(pi / 8.0 + v * pi / 4.0);
  }
  for (unsigned int t = 0; t < m && size > 0; ++t) {
    // keep {z : z . u <= |u|^2 / 2}, u = (x[t], y[t])
    const double ux = x[t], uy = y[t], c = 0.5 * (ux * ux + uy * uy);
    if (!(c > 0.0))
      continue;
    unsigned int out = 0;
    for (unsigned int v = 0; v < size; ++v) {
      const double* a = poly + 2 * v;
      const double* b = poly + 2 * ((v + 1) % size);
      const double fa = a[0] * ux + a[1] * uy - c, fb = b[0] * ux + b[1] * uy - c;
      if (fa <= 0.0) {
        next[2 * out] = a[0];
        next[2 * out + 1] = a[1];
        ++out;
      }
      if ((fa < 0.0 && fb > 0.0) || (fa > 0.0 && fb < 0.0)) {
        const double s = fa / (fa - fb);
        next[2 * out] = a[0] + s * (b[0] - a[0]);
        next[2 * out + 1] = a[1] + s * (b[1] - a[1]);
        ++out;
      }
    }
    std::swap(poly, next);
    size = out;
  }
  double twice = 0.0;
  for (unsigned int v = 0; v < size; ++v) {
    const unsigned int w = (v + 1) % size;
    twice += poly[2 * v] * poly[2 * w + 1] - poly[2 * w] * poly[2 * v + 1];
  }
  return 0.5 * std::abs(twice);
}

} // namespace internal
/// \endcond

/// \ingroup PkgNormalOrientationGlobal
/// Estimates the area a_i of the surface that each point stands for: the area
/// of its Voronoi cell in its tangent plane, among its `k` nearest neighbours
/// projected onto that plane (Barill et al. 2018, sec. 4.1).
///
/// - The tangent plane of point i passes through p_i orthogonally to n_i
///   (the sign of n_i does not matter).
/// - The cell is clipped to the regular octagon whose inradius is half the
///   distance d_k from p_i to its k-th neighbour, so that a point on the
///   border of an open surface, whose cell is unbounded, gets a finite area
///   (about 1.5 d_k^2 / 2 there, instead of about the spacing squared).
/// - Points at the same position share one cell: each gets the cell's area
///   divided by their number (when they are among each other's k nearest).
/// - A point with a zero or non-finite normal gets pi d_k^2 / (k + 1), the
///   area per point of a disc of radius d_k that holds it and its k
///   neighbours.  A cloud of a single point gets area 0.
///
/// On a uniform sampling of a smooth closed surface the areas sum to close
/// to the surface's area, and the sum approaches it as the spacing shrinks.
/// Where the surface bends or has edges within the neighbourhood, the
/// neighbours project onto the plane short of where the surface takes them,
/// and the sum falls short (measured in doc/global_orientation.md, *The
/// cheese at 4k points: its areas*).
///
/// \tparam ConcurrencyTag `CGAL::Parallel_tag` (kd-tree and cells in parallel
///         with TBB) or `CGAL::Sequential_tag`; the areas are the same either way
/// \tparam Point a \cgal `Point_3`
/// \tparam Vector the `Vector_3` of the same kernel
/// \param points the positions (finite)
/// \param normals the normals, same size (any length and sign)
/// \param k the number of neighbours, 1 to 64 (lowered to n - 1 for small clouds)
/// \return a_i for every point, in the order of `points`
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename Point, typename Vector>
std::vector<double> estimate_point_areas(const std::vector<Point>& points, const std::vector<Vector>& normals,
                                         unsigned int k = default_area_neighbors)
{
  typedef typename CGAL::Kernel_traits<Point>::Kernel Kernel;
  if (points.size() != normals.size())
    throw std::invalid_argument("estimate_point_areas: points and normals differ in size");
  if (points.size() >= std::size_t(std::numeric_limits<std::uint32_t>::max()))
    throw std::length_error("estimate_point_areas: more than 2^32 - 2 points");
  if (k < 1 || k > 64)
    throw std::invalid_argument("estimate_point_areas: the number of neighbors must be in [1, 64]");
  const std::size_t n = points.size();
  std::vector<double> areas(n, 0.0);
  k = unsigned(std::min<std::size_t>(k, n > 0 ? n - 1 : 0));
  if (k == 0)
    return areas;
  std::vector<std::uint32_t> nb;
  std::vector<float> d2;
  const std::vector<std::uint32_t> order =
    internal::morton_k_nearest_neighbors<ConcurrencyTag, Kernel>(points, k, nb, d2);
  std::vector<float>().swap(d2);
  const double pi = 3.14159265358979323846;
  internal::parallel_chunks<ConcurrencyTag>(n, [&](std::size_t sb, std::size_t se) {
    double x[64], y[64];
    for (std::size_t s = sb; s < se; ++s) {
      const std::size_t i = order[s]; // nb[s * k + t]: the neighbours of point i
      const Point& p = points[i];
      const double dk2 = [&] { // the exact squared distance to the k-th neighbour
        const Point& q = points[nb[s * k + k - 1]];
        double s = 0.0;
        for (int c = 0; c < 3; ++c)
          s += (CGAL::to_double(q[c]) - CGAL::to_double(p[c])) * (CGAL::to_double(q[c]) - CGAL::to_double(p[c]));
        return s;
      }();
      double nv[3];
      double len2 = 0.0;
      for (int c = 0; c < 3; ++c) {
        nv[c] = CGAL::to_double(normals[i][c]);
        len2 += nv[c] * nv[c];
      }
      if (!(len2 > 0.0) || !std::isfinite(len2)) {
        areas[i] = pi * dk2 / double(k + 1);
        continue;
      }
      const double inv = 1.0 / std::sqrt(len2);
      for (double& c : nv)
        c *= inv;
      double u[3], v[3]; // an orthonormal basis of the tangent plane
      internal::tangent_basis(nv, u, v);
      unsigned int m = 0, same = 0;
      for (unsigned int t = 0; t < k; ++t) {
        const Point& q = points[nb[s * k + t]];
        const double dx[3] = {CGAL::to_double(q[0]) - CGAL::to_double(p[0]),
                              CGAL::to_double(q[1]) - CGAL::to_double(p[1]),
                              CGAL::to_double(q[2]) - CGAL::to_double(p[2])};
        if (dx[0] == 0.0 && dx[1] == 0.0 && dx[2] == 0.0) {
          ++same;
          continue;
        }
        x[m] = dx[0] * u[0] + dx[1] * u[1] + dx[2] * u[2];
        y[m] = dx[0] * v[0] + dx[1] * v[1] + dx[2] * v[2];
        ++m;
      }
      areas[i] = internal::clipped_voronoi_area(x, y, m, 0.5 * std::sqrt(dk2)) / double(same + 1);
    }
  }, 256);
  return areas;
}

/// \ingroup PkgNormalOrientationGlobal
/// The generalised winding number of an oriented point cloud (Barill, Dickson,
/// Schmidt, Levin, Jacobson, "Fast Winding Numbers for Soups and Clouds",
/// SIGGRAPH 2018), smoothed near the samples, and its gradient:
///
///   w(q) = 1/(4 pi) sum_i a_i (p_i - q) . n_i / (|p_i - q|^2 + eps_i^2)^(3/2)
///
/// with p_i the points, n_i their unit normals (times a sign that `negate()`
/// flips), a_i their areas (see `estimate_point_areas()`) and eps_i =
/// `smoothing_factor()` * sqrt(a_i) the smoothing width (sqrt(a_i) or a
/// smaller cap per point given to `build()`, times the factor).  For a closed surface
/// sampled densely with outward normals, w is about 1 inside, 0 outside and
/// 1/2 on the surface; with eps_i > 0 it is finite and smooth everywhere,
/// on the samples too.  The field is linear in the normals: the field of a
/// union of point sets is the sum of their fields, and negating the normals
/// of a patch P changes w by -2 w_P.
///
/// **Treecode.** The points are stored in a kd-tree (median splits along the
/// longest side, leaves of at most `leaf_size` points).  Each node keeps its
/// area-weighted centre c, its radius r (the largest |p_i - c|), its dipole
/// N = sum a_i n_i and its moments sum a_i (p_i - c) n_i^T (second order) and
/// sum a_i (p_i - c) (p_i - c) n_i^T (third order, Barill's "order 2").  A
/// query q sums a node as a whole, by the Taylor expansion of the kernel
/// about c to second order in p_i - c (with the smoothing width of the
/// node's mean area), when |q - c| > beta r; it opens the node otherwise,
/// and sums the points of the leaves it reaches exactly.  beta is the
/// opening ratio (`opening_ratio()`): larger is more accurate and slower,
/// and the error of a node falls as (r / |q - c|)^3.  Measured against the
/// direct sum on 50k-point spheres and tori (2000 queries, half in the
/// bounding box, half 1.2 spacings off the surface or on samples), the
/// largest |error| of w is about 0.03 at beta = 1.5, 0.01 at beta = 2 and
/// 0.002 at beta = 3, the mean |error| 0.006, 0.0017 and 0.0003.
///
/// **Smoothing.** Across a plane sampled evenly, the smoothed w is about
/// 1/2 + z / (2 sqrt(z^2 + eps^2)) at signed distance z: within 0.05 of 0 or
/// 1 from z = 3 eps on, so probes meant to be clearly inside or outside sit
/// a few widths away from the samples.
///
/// **Use.**
/// - Build with `build()`; evaluate many queries with `evaluate()` (in
///   parallel, the same values bit for bit for any number of threads), one
///   with `value()` and `gradient()`, and the exact O(n) sums with the
///   `direct_` functions.
/// - The sign of patches: `negate()` flips the normals of any set of
///   points and updates the moments of the nodes above them in O(n /
///   leaf_size) time, without touching the geometry; the field is then the
///   same, bit for bit, as one built with those normals negated.  A patch's
///   own contribution w_P is the field built over the patch's points alone.
/// - Probes just inside and outside the samples: query p_i -/+ d n_i with d
///   a few times `smoothing_width(i)`.
/// - A field over a bounded subsample (for streaming): keep a subset of the
///   points and give each kept point the summed area, and the area-weighted
///   mean normal, of the points it stands for.
///
/// Thread safety: the const functions may be called concurrently;
/// `build()`, `negate()` and the setters may not run with anything else.
///
/// \tparam Kernel a \cgal kernel
template <typename Kernel>
class Winding_number_field
{
public:
  /// the point type
  typedef typename Kernel::Point_3 Point_3;
  /// the vector type
  typedef typename Kernel::Vector_3 Vector_3;

  /// an empty field (w = 0 everywhere)
  Winding_number_field() = default;

  /// Builds the field over points with normals and areas (copied; the
  /// normals are normalised, zero or non-finite ones contribute nothing, and
  /// no sign is negated).
  /// \tparam ConcurrencyTag `CGAL::Parallel_tag` (the tree built in parallel
  ///         with TBB) or `CGAL::Sequential_tag`; the field is the same either way
  /// \param points the positions, finite
  /// \param normals the normals, same size (any length)
  /// \param areas the areas a_i >= 0, same size (see `estimate_point_areas()`)
  /// \param leaf_size the largest number of points of a leaf, >= 1
  template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag>
  void build(const std::vector<Point_3>& points, const std::vector<Vector_3>& normals,
             const std::vector<double>& areas, unsigned int leaf_size = default_winding_leaf_size)
  {
    build<ConcurrencyTag>(points, normals, areas, std::vector<double>(), leaf_size);
  }

  /// Builds the field as `build()` above, with the smoothing width of every
  /// point i capped: eps_i = f min(sqrt(a_i), `width_caps`[i]); a node
  /// summed as a whole takes the area-weighted mean of its points' squared
  /// widths.  Narrow widths keep the field of one surface sharp at another
  /// surface closer than the spacing (the manual's *Sharp field at contacts*).
  /// \param points the positions, finite
  /// \param normals the normals, same size (any length)
  /// \param areas the areas a_i >= 0, same size
  /// \param width_caps per point, a cap >= 0 (+inf: none); empty: no caps
  /// \param leaf_size the largest number of points of a leaf, >= 1
  /// \throw std::invalid_argument when `width_caps` is neither empty nor of
  ///        the points' size, or holds a negative or NaN cap
  template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag>
  void build(const std::vector<Point_3>& points, const std::vector<Vector_3>& normals,
             const std::vector<double>& areas, const std::vector<double>& width_caps,
             unsigned int leaf_size = default_winding_leaf_size)
  {
    if (points.size() != normals.size() || points.size() != areas.size())
      throw std::invalid_argument("Winding_number_field: points, normals and areas differ in size");
    if (!width_caps.empty() && width_caps.size() != points.size())
      throw std::invalid_argument("Winding_number_field: the width caps and the points differ in size");
    for (double c : width_caps)
      if (!(c >= 0.0))
        throw std::invalid_argument("Winding_number_field: a width cap is negative or NaN");
    if (points.size() >= std::size_t(std::numeric_limits<std::uint32_t>::max()))
      throw std::length_error("Winding_number_field: more than 2^32 - 2 points");
    if (leaf_size < 1)
      throw std::invalid_argument("Winding_number_field: the leaf size must be at least 1");
    const std::size_t n = points.size();
    for (std::size_t i = 0; i < n; ++i) {
      const double c = CGAL::to_double(points[i].x()) + CGAL::to_double(points[i].y()) + CGAL::to_double(points[i].z());
      if (!std::isfinite(c) || !(areas[i] >= 0.0) || !std::isfinite(areas[i]))
        throw std::invalid_argument("Winding_number_field: a point is not finite or an area is not finite and >= 0");
    }
    std::vector<internal::Winding_sample> samples(n);
    internal::parallel_chunks<ConcurrencyTag>(n, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        internal::Winding_sample& s = samples[i];
        double len2 = 0.0;
        for (int c = 0; c < 3; ++c) {
          s.p[c] = CGAL::to_double(points[i][c]);
          s.an[c] = CGAL::to_double(normals[i][c]);
          len2 += s.an[c] * s.an[c];
        }
        s.area = areas[i];
        s.width2 = width_caps.empty() ? s.area : std::min(s.area, width_caps[i] * width_caps[i]);
        s.index = std::uint32_t(i);
        const double scale = (len2 > 0.0 && std::isfinite(len2)) ? s.area / std::sqrt(len2) : 0.0;
        for (double& c : s.an)
          c *= scale;
      }
    });
    tree_.template build<ConcurrencyTag>(std::move(samples), leaf_size);
    negated_.assign(n, false);
  }

  /// the number of points
  std::size_t size() const { return tree_.size(); }

  /// Sets the opening ratio beta > 0 (default `default_opening_ratio`).
  void set_opening_ratio(double beta)
  {
    if (!(beta > 0.0) || !std::isfinite(beta))
      throw std::invalid_argument("Winding_number_field: the opening ratio must be finite and > 0");
    beta_ = beta;
  }
  /// the opening ratio beta
  double opening_ratio() const { return beta_; }

  /// Sets the smoothing factor f >= 0 (default `default_smoothing_factor`):
  /// eps_i = f sqrt(a_i).  0 gives the unsmoothed kernel, infinite on the
  /// samples' surface (each sample's own term is taken as 0).  No rebuild is needed.
  void set_smoothing_factor(double factor)
  {
    if (!(factor >= 0.0) || !std::isfinite(factor))
      throw std::invalid_argument("Winding_number_field: the smoothing factor must be finite and >= 0");
    factor_ = factor;
  }
  /// the smoothing factor f
  double smoothing_factor() const { return factor_; }
  /// the smoothing width eps_i = f min(sqrt(a_i), its cap) of point i (an index of the build input)
  double smoothing_width(std::size_t i) const { return factor_ * std::sqrt(sample(i).width2); }
  /// the cap of the smoothing width of point i given to `build()`, where it
  /// is below sqrt(a_i); +inf elsewhere
  double width_cap(std::size_t i) const
  {
    const internal::Winding_sample& s = sample(i);
    return s.width2 < s.area ? std::sqrt(s.width2) : HUGE_VAL;
  }

  /// Negates the normals of the points whose indices (in the build input)
  /// `indices` lists, each at most once, and updates the tree's moments.
  /// \tparam IndexRange a range of integer indices < `size()`
  template <typename IndexRange>
  void negate(const IndexRange& indices)
  {
    std::vector<std::uint32_t> list;
    for (const auto& i : indices) {
      if (std::size_t(i) >= size())
        throw std::out_of_range("Winding_number_field::negate: index out of range");
      list.push_back(std::uint32_t(i));
      negated_[std::size_t(i)] = !negated_[std::size_t(i)];
    }
    tree_.negate(list.begin(), list.end());
  }
  /// true when the normal of point i has been negated an odd number of times
  bool is_negated(std::size_t i) const { return negated_.at(i); }

  /// w(q) by the treecode
  double value(const Point_3& q) const
  {
    double w, qd[3];
    to_array(q, qd);
    tree_.template evaluate<false>(qd, beta_ * beta_, factor_ * factor_, w, nullptr);
    return w * inv_4pi();
  }
  /// grad w(q) by the treecode
  Vector_3 gradient(const Point_3& q) const
  {
    double w, g[3], qd[3];
    to_array(q, qd);
    tree_.template evaluate<true>(qd, beta_ * beta_, factor_ * factor_, w, g);
    return Vector_3(g[0] * inv_4pi(), g[1] * inv_4pi(), g[2] * inv_4pi());
  }
  /// w(q) by the direct sum over all points (O(n))
  double direct_value(const Point_3& q) const
  {
    double w, qd[3];
    to_array(q, qd);
    tree_.template evaluate_direct<false>(qd, factor_ * factor_, w, nullptr);
    return w * inv_4pi();
  }
  /// grad w(q) by the direct sum over all points (O(n))
  Vector_3 direct_gradient(const Point_3& q) const
  {
    double w, g[3], qd[3];
    to_array(q, qd);
    tree_.template evaluate_direct<true>(qd, factor_ * factor_, w, g);
    return Vector_3(g[0] * inv_4pi(), g[1] * inv_4pi(), g[2] * inv_4pi());
  }

  /// Evaluates w at every query by the treecode, in parallel: `values[t]` =
  /// w(`queries[t]`), the same bit for bit for any number of threads.
  /// \tparam ConcurrencyTag `CGAL::Parallel_tag` or `CGAL::Sequential_tag`
  /// \tparam PointRange a random-access range of `Point_3`
  template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange>
  void evaluate(const PointRange& queries, std::vector<double>& values) const
  {
    run<ConcurrencyTag, false, false>(queries, values, nullptr);
  }
  /// Evaluates w and grad w at every query by the treecode, in parallel.
  /// \tparam ConcurrencyTag `CGAL::Parallel_tag` or `CGAL::Sequential_tag`
  /// \tparam PointRange a random-access range of `Point_3`
  template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange>
  void evaluate(const PointRange& queries, std::vector<double>& values, std::vector<Vector_3>& gradients) const
  {
    run<ConcurrencyTag, true, false>(queries, values, &gradients);
  }
  /// Evaluates w at every query by the direct sum (O(n) per query), in parallel.
  /// \tparam ConcurrencyTag `CGAL::Parallel_tag` or `CGAL::Sequential_tag`
  /// \tparam PointRange a random-access range of `Point_3`
  template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange>
  void evaluate_direct(const PointRange& queries, std::vector<double>& values) const
  {
    run<ConcurrencyTag, false, true>(queries, values, nullptr);
  }
  /// Evaluates w and grad w at every query by the direct sum, in parallel.
  /// \tparam ConcurrencyTag `CGAL::Parallel_tag` or `CGAL::Sequential_tag`
  /// \tparam PointRange a random-access range of `Point_3`
  template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange>
  void evaluate_direct(const PointRange& queries, std::vector<double>& values,
                       std::vector<Vector_3>& gradients) const
  {
    run<ConcurrencyTag, true, true>(queries, values, &gradients);
  }

  /// The far field of q: w(q) summed over the points at distance at least
  /// `exclusion` from q only, by the treecode.  Whatever the signs of the
  /// points nearer than that, it is the same; across a thin gap between two
  /// layers of a closed surface it is near 1 when the gap is outside (a
  /// contact) and near 0 when it is inside (a wall), once the left-out
  /// layers are wide against the gap (see the manual).  With `exclusion` = 0
  /// it is `value(q)`, up to the treecode's error.
  /// \throw std::invalid_argument when `exclusion` is not finite and >= 0
  double far_value(const Point_3& q, double exclusion) const
  {
    check_exclusion(exclusion);
    return far<false>(q, exclusion);
  }
  /// `far_value()` by the direct sum (O(n))
  double direct_far_value(const Point_3& q, double exclusion) const
  {
    check_exclusion(exclusion);
    return far<true>(q, exclusion);
  }
  /// Evaluates the far field at every query by the treecode, in parallel:
  /// `values[t]` = `far_value(queries[t], exclusions[t])`, the same bit for
  /// bit for any number of threads.
  /// \tparam ConcurrencyTag `CGAL::Parallel_tag` or `CGAL::Sequential_tag`
  /// \tparam PointRange a random-access range of `Point_3`
  /// \throw std::invalid_argument when `exclusions` is not one finite value
  ///        >= 0 per query
  template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename PointRange>
  void evaluate_far(const PointRange& queries, const std::vector<double>& exclusions,
                    std::vector<double>& values) const
  {
    if (exclusions.size() != std::size_t(queries.size()))
      throw std::invalid_argument("Winding_number_field::evaluate_far: one exclusion radius per query");
    for (double x : exclusions)
      check_exclusion(x);
    run<ConcurrencyTag, false, false>(queries, values, nullptr, &exclusions);
  }

  /// The moment a_i s_i n_i of point i (area times signed unit normal).
  Vector_3 moment(std::size_t i) const
  {
    const internal::Winding_sample& s = sample(i);
    return Vector_3(s.an[0], s.an[1], s.an[2]);
  }

  /// The adjoint of the field at the points: given a weight c_j per point
  /// (in the order of `build()`), sets `derivatives[i]` to the derivative
  /// of J = sum_j c_j w(p_j) with respect to the moment a_i n_i of point i,
  ///
  ///   v_i = 1/(4 pi) sum_j c_j (p_i - p_j) / (|p_i - p_j|^2 + eps_i^2)^(3/2),
  ///
  /// by a treecode over the same tree (charge sums and their first
  /// moments, opened with the field's `opening_ratio()`, or with
  /// `opening_ratio` when given: a smaller one is cheaper and coarser).
  /// So the part of J due to a set of points P is sum_{i in P}
  /// `moment(i)` . v_i, and negating P changes J by -2 times that: one pass
  /// gives the effect on J of negating every patch.  Deterministic for any
  /// number of threads.
  /// \tparam ConcurrencyTag `CGAL::Parallel_tag` or `CGAL::Sequential_tag`
  /// \throw std::invalid_argument when the weights are not one finite value
  ///        per point or `opening_ratio` is not finite and > 0
  template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag>
  void moment_derivatives(const std::vector<double>& weights, std::vector<Vector_3>& derivatives)
  {
    moment_derivatives<ConcurrencyTag>(weights, derivatives, beta_);
  }

  /// `moment_derivatives()` with the opening ratio `opening_ratio`
  template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag>
  void moment_derivatives(const std::vector<double>& weights, std::vector<Vector_3>& derivatives,
                          double opening_ratio)
  {
    const std::size_t n = size();
    if (weights.size() != n)
      throw std::invalid_argument("Winding_number_field::moment_derivatives: one weight per point is needed");
    for (double c : weights)
      if (!std::isfinite(c))
        throw std::invalid_argument("Winding_number_field::moment_derivatives: a weight is not finite");
    if (!(opening_ratio > 0.0) || !std::isfinite(opening_ratio))
      throw std::invalid_argument("Winding_number_field::moment_derivatives: the opening ratio must be finite and > 0");
    tree_.set_charges(weights);
    derivatives.assign(n, Vector_3(0, 0, 0));
    const double beta2 = opening_ratio * opening_ratio, f2 = factor_ * factor_, s = inv_4pi();
    const auto& samples = tree_.samples();
    internal::parallel_chunks<ConcurrencyTag>(n, [&](std::size_t b, std::size_t e) {
      for (std::size_t t = b; t < e; ++t) { // in tree order: coherent
        double F[3];
        tree_.charge_field(samples[t].p, beta2, f2 * samples[t].width2, F);
        derivatives[samples[t].index] = Vector_3(F[0] * s, F[1] * s, F[2] * s);
      }
    }, 64);
  }

private:
  static double inv_4pi() { return 0.25 / 3.14159265358979323846; }

  static void to_array(const Point_3& q, double* out)
  {
    for (int c = 0; c < 3; ++c)
      out[c] = CGAL::to_double(q[c]);
  }

  const internal::Winding_sample& sample(std::size_t i) const
  {
    if (i >= size())
      throw std::out_of_range("Winding_number_field: index out of range");
    return tree_.samples()[tree_.position(i)];
  }

  /// the values (and gradients) at the queries; with `exclusions`, the far
  /// fields (no gradient)
  template <typename ConcurrencyTag, bool Gradient, bool Direct, typename PointRange>
  void run(const PointRange& queries, std::vector<double>& values, std::vector<Vector_3>* gradients,
           const std::vector<double>* exclusions = nullptr) const
  {
    const std::size_t m = std::size_t(queries.size());
    if (m >= std::size_t(std::numeric_limits<std::uint32_t>::max()))
      throw std::length_error("Winding_number_field::evaluate: more than 2^32 - 2 queries");
    values.assign(m, 0.0);
    if (Gradient)
      gradients->assign(m, Vector_3(0, 0, 0));
    const double beta2 = beta_ * beta_, f2 = factor_ * factor_, s = inv_4pi();
    // queries in Morton order (coherent in the tree); each value depends on its query only
    std::vector<std::array<double, 3>> q(m);
    for (std::size_t t = 0; t < m; ++t)
      to_array(queries[t], q[t].data());
    const std::vector<std::uint32_t> order = internal::morton_order<ConcurrencyTag>(q);
    internal::parallel_chunks<ConcurrencyTag>(m, [&](std::size_t b, std::size_t e) {
      for (std::size_t o = b; o < e; ++o) {
        const std::size_t t = order[o];
        const double* qd = q[t].data();
        double w, g[3] = {0.0, 0.0, 0.0};
        if (exclusions)
          w = tree_.template evaluate_far<Direct>(qd, beta2, f2, (*exclusions)[t]);
        else if (Direct)
          tree_.template evaluate_direct<Gradient>(qd, f2, w, g);
        else
          tree_.template evaluate<Gradient>(qd, beta2, f2, w, g);
        values[t] = w * s;
        if (Gradient)
          (*gradients)[t] = Vector_3(g[0] * s, g[1] * s, g[2] * s);
      }
    }, Direct ? 4 : 64);
  }

  static void check_exclusion(double x)
  {
    if (!(x >= 0.0) || !std::isfinite(x))
      throw std::invalid_argument("Winding_number_field: the exclusion radius must be finite and >= 0");
  }

  template <bool Direct>
  double far(const Point_3& q, double exclusion) const
  {
    double qd[3];
    to_array(q, qd);
    return tree_.template evaluate_far<Direct>(qd, beta_ * beta_, factor_ * factor_, exclusion) * inv_4pi();
  }

  internal::Winding_tree tree_;
  std::vector<bool> negated_;
  double beta_ = default_opening_ratio;
  double factor_ = default_smoothing_factor;
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_WINDING_NUMBER_FIELD_H
