// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_FLIP_CRITERIA_H
#define NORMAL_ORIENTATION_FLIP_CRITERIA_H

/// \file Flip_criteria.h
/// Flip criteria: models of the `FlipCriterion` concept.
///
/// A flip criterion maps an edge (p_i, n_i), (p_j, n_j) of the neighbour graph
/// to phi in [-1, 1]: phi > 0 when the two normals are consistently oriented,
/// phi < 0 when one of them should flip, |phi| the certainty (paper, sec. 3).
/// Every model here is symmetric in i and j, invariant when both normals
/// flip, accepts normals of any length (they are normalised internally) and
/// returns a finite value on degenerate input: phi = 0 when a normal is zero,
/// that is "nothing can be said".

#include <Normal_orientation/internal/Konig_curves.h>
#include <Normal_orientation/internal/Unit_vector.h>

#include <CGAL/number_utils.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace Normal_orientation {

/// \cond SKIP_IN_MANUAL
namespace internal {

/// a plain 3-vector of doubles, used by the criteria
struct Vec3
{
  double x, y, z;
};

template <typename P>
Vec3 to_vec3(const P& p)
{
  return Vec3{CGAL::to_double(p.x()), CGAL::to_double(p.y()), CGAL::to_double(p.z())};
}

inline double dot(const Vec3& a, const Vec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

/// normalises `v` in place; returns false (and leaves a zero vector) when
/// `v` is zero or not finite
inline bool normalize(Vec3& v)
{
  const std::array<double, 3> u = unit_vector(v.x, v.y, v.z);
  v = Vec3{u[0], u[1], u[2]};
  return u[0] != 0.0 || u[1] != 0.0 || u[2] != 0.0;
}

inline double clamp_unit(double x) { return std::min(1.0, std::max(-1.0, x)); }

} // namespace internal
/// \endcond

/// \ingroup PkgNormalOrientationCriteria
/// Hoppe's criterion (paper eq. 1): phi = <n_i, n_j> for unit normals.
/// Best on smooth, densely sampled surfaces and the most robust to noise;
/// fails at sharp creases and across thin parts, where the true normals of
/// neighbours point in different or opposite directions.
/// \cgalModels `FlipCriterion`
struct Hoppe_criterion
{
  /// returns phi in [-1, 1] for the edge (p_i, n_i)-(p_j, n_j)
  template <typename Point, typename Vector>
  double operator()(const Point&, const Vector& n_i, const Point&, const Vector& n_j) const
  {
    internal::Vec3 a = internal::to_vec3(n_i), b = internal::to_vec3(n_j);
    if (!internal::normalize(a) || !internal::normalize(b))
      return 0.0;
    return internal::clamp_unit(internal::dot(a, b));
  }
  /// the name used on the command line and in reports
  static const char* name() { return "hoppe"; }
};

/// \ingroup PkgNormalOrientationCriteria
/// Xie's criterion (supplement eq. 1): n_i is reflected on the plane
/// orthogonal to e = (p_i - p_j) / |p_i - p_j| and compared with n_j:
/// phi = <n_i - 2 e <e, n_i>, n_j> = <n_i, n_j> - 2 <e, n_i><e, n_j>.
/// It orients sharp creases and close parallel sheets (thin parts) where
/// Hoppe's criterion fails.  For coincident points e is undefined and the
/// criterion falls back to Hoppe's.
/// \cgalModels `FlipCriterion`
struct Xie_criterion
{
  /// returns phi in [-1, 1] for the edge (p_i, n_i)-(p_j, n_j)
  template <typename Point, typename Vector>
  double operator()(const Point& p_i, const Vector& n_i, const Point& p_j, const Vector& n_j) const
  {
    internal::Vec3 a = internal::to_vec3(n_i), b = internal::to_vec3(n_j);
    if (!internal::normalize(a) || !internal::normalize(b))
      return 0.0;
    const internal::Vec3 pi = internal::to_vec3(p_i), pj = internal::to_vec3(p_j);
    internal::Vec3 e{pi.x - pj.x, pi.y - pj.y, pi.z - pj.z};
    if (!internal::normalize(e))
      return internal::clamp_unit(internal::dot(a, b));
    return internal::clamp_unit(internal::dot(a, b) - 2.0 * internal::dot(e, a) * internal::dot(e, b));
  }
  /// the name used on the command line and in reports
  static const char* name() { return "xie"; }
};

/// \ingroup PkgNormalOrientationCriteria
/// König and Gumhold's criterion (VMV 2009): the two points are joined by
/// cubic Hermite curves whose end tangents are perpendicular to the normals,
/// once with the normals as given ("keep") and once with one of them flipped
/// ("flip"); the curve that turns less wins.  phi = sign(c_flip - c_keep) *
/// (1 - min(c_keep, c_flip) / max(c_keep, c_flip)) * l_i * l_j, where c is
/// the total turning angle of the best curve of each kind, computed in the
/// plane through p_i p_j that best contains the lines of both normals, and
/// l_i, l_j are the lengths of the unit normals projected into that plane
/// (1 when the edge and the normals are coplanar; the factor fades the
/// criterion out where the planar construction means little).  It assumes
/// low curvature between neighbours and handles creases better than
/// Hoppe's criterion; like Hoppe's, it says "flip" across a slab thinner
/// than the point spacing, where Xie's criterion is the one to use.
/// The construction and its guarantees are described with
/// `internal::konig_phi()`, in `internal/Konig_curves.h`.
/// \cgalModels `FlipCriterion`
struct Konig_criterion
{
  /// returns phi in [-1, 1] for the edge (p_i, n_i)-(p_j, n_j)
  template <typename Point, typename Vector>
  double operator()(const Point& p_i, const Vector& n_i, const Point& p_j, const Vector& n_j) const
  {
    const internal::Vec3 pi = internal::to_vec3(p_i), pj = internal::to_vec3(p_j);
    const internal::Vec3 ni = internal::to_vec3(n_i), nj = internal::to_vec3(n_j);
    const double a[3] = {pi.x, pi.y, pi.z}, b[3] = {pj.x, pj.y, pj.z};
    const double na[3] = {ni.x, ni.y, ni.z}, nb[3] = {nj.x, nj.y, nj.z};
    return internal::konig_phi(a, na, b, nb);
  }
  /// the name used on the command line and in reports
  static const char* name() { return "konig"; }
};

/// \ingroup PkgNormalOrientationCriteria
/// Hoppe's criterion, with König and Gumhold's where Hoppe's is unsure and
/// König's is surer (the default): phi = phi_H when |phi_H| >= `hoppe_limit`,
/// else whichever of phi_H and phi_K has the larger magnitude (phi_H when
/// they are equal).  Between normals nearly parallel, which is where noise
/// puts most edges, it is Hoppe's criterion, and König's curves, which noise
/// wider than the spacing makes unreliable, are not even computed.  At a
/// sharp crease (normals at a right angle, phi_H near 0), the curves decide.
/// On small clouds whose positions are clean, the pipelines take König's
/// criterion on every edge (`konig_everywhere`).
/// \cgalModels `FlipCriterion`
struct Hoppe_konig_criterion
{
  /// `hoppe_limit` in [0, 1]: below this |phi_H|, König's criterion is
  /// consulted (0: Hoppe's criterion; above 1: the larger of the two everywhere)
  explicit Hoppe_konig_criterion(double hoppe_limit = 0.5) : hoppe_limit(hoppe_limit) {}

  /// returns phi in [-1, 1] for the edge (p_i, n_i)-(p_j, n_j)
  template <typename Point, typename Vector>
  double operator()(const Point& p_i, const Vector& n_i, const Point& p_j, const Vector& n_j) const
  {
    if (konig_everywhere)
      return Konig_criterion()(p_i, n_i, p_j, n_j);
    const double h = Hoppe_criterion()(p_i, n_i, p_j, n_j);
    if (!(std::abs(h) < hoppe_limit))
      return h;
    const double k = Konig_criterion()(p_i, n_i, p_j, n_j);
    return std::abs(k) > std::abs(h) ? k : h;
  }
  /// the name used on the command line and in reports
  static const char* name() { return "hoppe-konig"; }

  double hoppe_limit; ///< below this |phi_H|, König's criterion is consulted
  /// König's criterion on every edge.  Both drivers set it on clouds of at
  /// most 200,000 points whose positions are clean for their spacing (see
  /// the manual, "Hoppe's and König's Criteria Together"); false by default.
  bool konig_everywhere = false;
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_FLIP_CRITERIA_H
