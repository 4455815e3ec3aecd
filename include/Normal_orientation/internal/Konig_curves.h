// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_KONIG_CURVES_H
#define NORMAL_ORIENTATION_INTERNAL_KONIG_CURVES_H

/// \file Konig_curves.h
/// König and Gumhold's flip criterion (VMV 2009), computed from the total
/// turning of cubic Hermite curves.
///
/// For an edge (p_i, n_i)-(p_j, n_j) the two points are joined by planar cubic
/// Hermite curves whose end tangents are perpendicular to the normals.  If the
/// normals are consistently oriented, a simple curve joins the points; if one
/// of them is flipped, the joining curve has to turn more.  The criterion
/// compares the total turning c_keep of the best "keep" curve with that of the
/// best "flip" curve, c_flip.
///
/// Construction for one edge (see `konig_edge_complexities()`):
///  1. Reference plane.  It contains the edge direction u = e / |e|,
///     e = p_j - p_i, and is the plane through u that best contains the lines
///     of n_i and n_j in the least-squares sense: with a and b the components of
///     the unit normals orthogonal to u, its in-plane direction w orthogonal to
///     u is the principal eigenvector of a a^T + b b^T, i.e. w maximises
///     <a, w>^2 + <b, w>^2 (computed in closed form from the 2x2 Gram matrix of
///     a and b, no trigonometry).  If e, n_i and n_j span a plane, this is that
///     plane (a and b are parallel); if they are collinear (a = b = 0), every
///     plane through u gives the same curves.  If a and b are orthogonal and of
///     equal length, every plane through u is equally good and the one through
///     n_a is taken (n_a: the normal of the lexicographically smaller point).
///     König blends n_i x n_j with the average normal crossed with e; the
///     average normal n_i + n_j depends on the orientations being tested, which
///     would break the exact antisymmetry phi(n_i, -n_j) = -phi(n_i, n_j) that
///     the MRF relies on, whereas the least-squares plane depends only on the
///     lines of the normals, not on their signs.
///  2. The points and normals are expressed in the plane's frame (u, w); the
///     problem is scale invariant, so p_i -> (0, 0), p_j -> (1, 0).  The frame
///     is mirrored if needed so that the first projected normal lies in the
///     first quadrant (mirroring and negating both normals change no
///     complexity); this makes the arithmetic, not just the mathematics,
///     identical for the configurations related by the symmetries below.
///  3. The tangents t_i, t_j are the unit projected normals rotated by
///     +90 degrees, scaled to 2 |e| (to 2 in the normalised frame).
///  4. Four Hermite curves from p_i to p_j with end derivatives
///     (s_i t_i, s_j t_j): (+,+) and (-,-) "keep", (+,-) and (-,+) "flip".
///  5. Complexity of a curve = its total absolute turning angle
///     (`hermite_total_turning()`: closed form, no adaptive integration).
///  6. c_keep = min over the two keep curves, c_flip = min over the flip ones.
///
/// Mapping to phi (see `konig_phi()`):
///   phi = sign(c_flip - c_keep) * (1 - min(c_keep, c_flip) / max(c_keep, c_flip)) * l_i * l_j,
/// where l_i, l_j in [0, 1] are the lengths of the unit normals projected into
/// the reference plane.  For planar configurations l_i = l_j = 1 and this is
/// exactly the mapping of the specification; the factor fades phi out, keeping
/// it continuous, when a normal becomes perpendicular to the reference plane,
/// where its projected direction (and so the whole 2-D construction) is
/// undefined.  min / max is König's uncertainty (his MST weight).

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace Normal_orientation {
namespace internal {

/// \cond SKIP_IN_MANUAL
/// implementation details of the König criterion; not part of the API
namespace konig_detail {

/// pi
constexpr double pi = 3.14159265358979323846;

/// atan2(y, x) in [-pi, pi] to about 1e-15 absolute, faster than std::atan2:
/// octant reduction, then atan(z) = pi/4 + atan((z - 1) / (z + 1)) for
/// z > tan(pi/8), then a degree-21 odd near-minimax polynomial on
/// |z| <= tan(pi/8) (Chebyshev fit of atan(sqrt(x)) / sqrt(x), error 1e-15).
/// Returns 0 for (0, 0) (including signed zeros) and for NaN input.
inline double fast_atan2(double y, double x)
{
  const double ax = std::abs(x), ay = std::abs(y);
  const double mx = std::max(ax, ay), mn = std::min(ax, ay);
  if (!(mx > 0.0))
    return 0.0;
  // z = mn / mx in [0, 1], or (z - 1) / (z + 1) if z > tan(pi/8): one division
  const bool upper = mn > 0.41421356237309504880 * mx;
  const double z = upper ? (mn - mx) / (mn + mx) : mn / mx;
  const double base = upper ? 0.25 * pi : 0.0;
  // p(v) = sum c_k v^k, v = z^2, evaluated with Estrin's scheme (short
  // dependency chains; Horner's would be ten dependent multiply-adds)
  const double v = z * z, v2 = v * v, v4 = v2 * v2, v8 = v4 * v4;
  const double q0 = 9.999999999999990408e-1 - 3.333333333322143405e-1 * v;
  const double q1 = 1.999999997839266206e-1 - 1.428571266168479384e-1 * v;
  const double q2 = 1.111104885375129568e-1 - 9.089529956562307358e-2 * v;
  const double q3 = 7.673535428183286018e-2 - 6.505982967170839916e-2 * v;
  const double q4 = 5.024762118940128032e-2 - 2.531647957377647565e-2 * v;
  const double p = (q0 + q1 * v2) + (q2 + q3 * v2) * v4 + q4 * v8;
  double a = base + z * p;
  a = ay > ax ? 0.5 * pi - a : a;
  a = x < 0.0 ? pi - a : a;
  return y < 0.0 ? -a : a;
}

/// appends to `out` (starting at index `n`) the roots of a t^2 + b t + c that
/// lie in (margin, 1 - margin), margin = 1e-6; returns the new count.
/// Near-degenerate leading coefficients (relative to the largest one) are
/// treated as zero.  The margin keeps a root that lies at an end, t = 0 or
/// t = 1, out even when rounding (up to ~1e-8 for a double root) moves it
/// inside: it would bound a negligible piece, and a cusp there is left to the
/// handling of the ends.
inline int roots_in_unit_interval(double a, double b, double c, double* out, int n)
{
  constexpr double margin = 1e-6;
  const double s = std::max(std::abs(a), std::max(std::abs(b), std::abs(c)));
  if (!(s > 0.0))
    return n;
  const double tiny = 1e-14 * s;
  auto push = [&](double r) {
    if (r > margin && r < 1.0 - margin) // false for NaN
      out[n++] = r;
  };
  if (std::abs(a) <= tiny) {
    if (std::abs(b) > tiny)
      push(-c / b);
    return n;
  }
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0)
    return n; // no real root (a touching double root does not change a sign)
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  push(q / a);
  if (q != 0.0)
    push(c / q);
  return n;
}

/// total turning of the cubic with hodograph h(t) = A t^2 + B t + C on
/// [0, 1]; inputs are expected to be of moderate magnitude (no overflow in
/// products).  See `hermite_total_turning()` for the method.
inline double hodograph_total_turning(double Ax, double Ay, double Bx, double By, double Cx,
                                      double Cy)
{
  const double s = std::max(std::max(std::max(std::abs(Ax), std::abs(Ay)),
                                      std::max(std::abs(Bx), std::abs(By))),
                             std::max(std::abs(Cx), std::abs(Cy)));
  if (!(s > 0.0))
    return 0.0; // the curve is a single point
  // det(h, h') = det(B, A) t^2 + 2 det(C, A) t + det(C, B): its sign is the
  // sense of turning, its roots the inflections
  const double d2 = Bx * Ay - By * Ax, d1 = 2.0 * (Cx * Ay - Cy * Ax), d0 = Cx * By - Cy * Bx;
  const double dmax = std::max(std::abs(d2), std::max(std::abs(d1), std::abs(d0)));
  if (dmax <= 1e-12 * s * s) {
    // h(t) stays on a line through the origin (a straight curve, possibly
    // running back and forth): the direction only reverses, by pi, where the
    // component along that line changes sign
    double Lx = Ax, Ly = Ay;
    const double la = std::max(std::abs(Ax), std::abs(Ay)), lb = std::max(std::abs(Bx), std::abs(By)),
                 lc = std::max(std::abs(Cx), std::abs(Cy));
    if (lb >= la && lb >= lc) { Lx = Bx; Ly = By; }
    else if (lc >= la)        { Lx = Cx; Ly = Cy; }
    double r[2];
    const int n = roots_in_unit_interval(Ax * Lx + Ay * Ly, Bx * Lx + By * Ly, Cx * Lx + Cy * Ly, r, 0);
    if (n == 2 && std::abs(r[0] - r[1]) <= 1e-9)
      return 0.0; // a double root: the curve stops for an instant, no reversal
    return n * pi;
  }

  // split [0, 1] into monotone runs at the inflections
  double t[4];
  int n = 0;
  t[n++] = 0.0;
  n = roots_in_unit_interval(d2, d1, d0, t, n);
  if (n == 3) {
    if (t[2] < t[1])
      std::swap(t[1], t[2]);
    if (t[2] - t[1] <= 1e-6)
      n = 1; // a (numerically) double root: det does not change sign there
  }
  t[n++] = 1.0;

  // |h| below this is a cusp (h passes through the origin): the direction
  // reverses, which is a turn of pi
  const double zero = 1e-9 * s;
  auto is_zero = [zero](double x, double y) { return std::abs(x) <= zero && std::abs(y) <= zero; };

  // direction leaving the last split point
  double cx = Cx, cy = Cy;
  if (is_zero(cx, cy)) { // h(0) = 0: leave along h'(0) (or A if that vanishes too)
    cx = Bx;
    cy = By;
    if (is_zero(cx, cy)) {
      cx = Ax;
      cy = Ay;
    }
  }
  double total = 0.0;
  bool prev_zero = false;
  double t_prev = 0.0;
  for (int k = 1; k < n; ++k) {
    const double tk = t[k];
    const double hx = (Ax * tk + Bx) * tk + Cx, hy = (Ay * tk + By) * tk + Cy;
    // arrival direction at tk (left limit) and leaving direction (right limit)
    double arr_x = hx, arr_y = hy, lea_x = hx, lea_y = hy;
    const bool cusp_here = is_zero(hx, hy);
    bool reverses = false;
    if (cusp_here) {
      lea_x = 2.0 * Ax * tk + Bx;
      lea_y = 2.0 * Ay * tk + By;
      reverses = true;
      if (is_zero(lea_x, lea_y)) { // h ~ A (t - tk)^2: touches 0 without reversing
        lea_x = Ax;
        lea_y = Ay;
        reverses = false;
      }
      arr_x = reverses ? -lea_x : lea_x;
      arr_y = reverses ? -lea_y : lea_y;
    }
    if (!(cusp_here && prev_zero && tk - t_prev < 1e-6)) { // else: same cusp as before
      // on a monotone run the direction turns by less than 2 pi in the sense
      // sign(det); the turning is the angle from (cx, cy) to the arrival
      // direction measured in that sense
      // sense: det where it is largest of three inner points of the run; if
      // it is at rounding level, the run is (nearly) straight and any
      // directed angle is noise
      double sense = 0.0;
      for (double f : {0.25, 0.5, 0.75}) {
        const double tm = t_prev + f * (tk - t_prev);
        const double dm = (d2 * tm + d1) * tm + d0;
        if (std::abs(dm) > std::abs(sense))
          sense = dm;
      }
      if (std::abs(sense) <= 1e-12 * dmax)
        sense = 0.0;
      const double raw = fast_atan2(cx * arr_y - cy * arr_x, cx * arr_x + cy * arr_y);
      double sweep = std::abs(raw);
      if (sweep < 1e-6) {
        // nearly 0 or nearly a full turn: the sign of a tiny raw angle is
        // unreliable, so ask instead whether h points backwards, against
        // the start direction, somewhere in the run (min of a quadratic)
        const double qa = Ax * cx + Ay * cy, qb = Bx * cx + By * cy, qc = Cx * cx + Cy * cy;
        auto q = [&](double tt) { return (qa * tt + qb) * tt + qc; };
        double qmin = std::min(q(t_prev), q(tk));
        if (qa > 0.0) {
          const double tv = -qb / (2.0 * qa);
          if (tv > t_prev && tv < tk)
            qmin = std::min(qmin, q(tv));
        }
        if (qmin < -1e-9 * s * (std::abs(cx) + std::abs(cy)))
          sweep = 2.0 * pi - sweep;
      } else {
        const bool wrong_side = (sense > 0.0 && raw < 0.0) || (sense < 0.0 && raw > 0.0);
        sweep = wrong_side ? 2.0 * pi - sweep : sweep;
      }
      total += sweep;
      if (reverses && k + 1 < n)
        total += pi;
    }
    cx = lea_x;
    cy = lea_y;
    prev_zero = cusp_here;
    t_prev = tk;
  }
  return total;
}

/// largest absolute component of a 3-vector
inline double max_abs3(const double v[3])
{
  return std::max(std::abs(v[0]), std::max(std::abs(v[1]), std::abs(v[2])));
}

/// unit vector of `v` into `out`; robust to huge and tiny finite lengths.
/// Returns false (out = 0) when max |v_k| <= `min_norm` or v is not finite.
inline bool unit3(const double v[3], double out[3], double min_norm)
{
  const double m = max_abs3(v);
  if (!(m > min_norm) || !std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) {
    out[0] = out[1] = out[2] = 0.0;
    return false;
  }
  double x = v[0], y = v[1], z = v[2];
  if (!(m > 1e-150 && m < 1e150)) { // rescale: the squares would under/overflow
    const double inv_m = 1.0 / m;
    x *= inv_m;
    y *= inv_m;
    z *= inv_m;
  }
  const double inv = 1.0 / std::sqrt(x * x + y * y + z * z);
  out[0] = x * inv;
  out[1] = y * inv;
  out[2] = z * inv;
  return true;
}

/// dot product of 3-vectors
inline double dot3(const double a[3], const double b[3])
{
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/// true when `a` precedes `b` lexicographically
inline bool lex_less3(const double a[3], const double b[3])
{
  if (a[0] != b[0])
    return a[0] < b[0];
  if (a[1] != b[1])
    return a[1] < b[1];
  return a[2] < b[2];
}

} // namespace konig_detail
/// \endcond

/// A normal whose largest absolute component is at most this value is
/// treated as zero ("nothing can be said": phi = 0).
constexpr double konig_zero_normal_threshold = 1e-20;

/// Two points whose difference is, in every coordinate, at most this value
/// times their largest absolute coordinate are treated as coincident (the
/// edge direction would be rounding noise).  It is 64 machine epsilons.
constexpr double konig_coincidence_tolerance = 64.0 * std::numeric_limits<double>::epsilon();

/// Total absolute turning angle, in radians, of the planar cubic Hermite curve
///   c(t) = h00(t) p0 + h10(t) m0 + h01(t) p1 + h11(t) m1,   t in [0, 1],
/// from `p0` to `p1` with end derivatives `m0` and `m1`, i.e. the integral of
/// |d theta| where theta is the direction angle of c'(t).
///
/// c'(t) = A t^2 + B t + C is quadratic (its hodograph is a parabola), with
/// A = 6 (p0 - p1) + 3 (m0 + m1), B = 6 (p1 - p0) - 4 m0 - 2 m1, C = m0.
/// Closed form, no adaptive integration, no allocation:
///  - the sense of turning is the sign of det(c', c'') = det(B, A) t^2 +
///    2 det(C, A) t + det(C, B); its roots in (0, 1), the inflections, split
///    [0, 1] into at most three monotone runs;
///  - on a monotone run the direction of a parabolic hodograph turns by less
///    than 2 pi, so the run's turning is the angle from its start direction
///    to its end direction measured in its sense, in [0, 2 pi) (one
///    arctangent).  When that angle is within 1e-6 of 0 mod 2 pi its sign is
///    rounding noise; the run then turned fully around iff c' points against
///    its start direction somewhere in the run (the minimum of a quadratic);
///  - a cusp (c' = 0: the direction reverses) counts as a turn of pi;
///  - if det(c', c'') vanishes identically, c' stays on a line through the
///    origin and the turning is pi times the number of sign changes of c'
///    along that line (a straight segment, possibly run back and forth).
///
/// An end derivative (or c' at an inner point) shorter than 1e-9 times the
/// largest coefficient of c' counts as zero: its direction is then taken as
/// the limit direction of c' (along c'', or A if c'' vanishes too), not as the
/// arbitrary direction of the tiny vector.  (König's tangents have length
/// 2 |e|, so this never happens inside `konig_phi()`.)
///
/// The result is invariant under similarity transformations and under
/// reversal of the curve, is always finite and lies in [0, 8 pi).
/// Returns 0 for a curve that is a single point or for non-finite input.
inline double hermite_total_turning(const double p0[2], const double m0[2], const double p1[2],
                                    const double m1[2])
{
  // scale to unit magnitude first: the turning is scale invariant and this
  // rules out overflow in the determinants
  double s = 0.0;
  for (int k = 0; k < 2; ++k) {
    if (!std::isfinite(p0[k]) || !std::isfinite(p1[k]) || !std::isfinite(m0[k]) || !std::isfinite(m1[k]))
      return 0.0;
    s = std::max(s, std::max(std::max(std::abs(p0[k]), std::abs(p1[k])),
                             std::max(std::abs(m0[k]), std::abs(m1[k]))));
  }
  if (!(s > 0.0))
    return 0.0;
  const double inv = 1.0 / s;
  // p1 - p0 computed on scaled values cannot overflow
  const double dx = p1[0] * inv - p0[0] * inv, dy = p1[1] * inv - p0[1] * inv;
  const double ax = m0[0] * inv, ay = m0[1] * inv, bx = m1[0] * inv, by = m1[1] * inv;
  return konig_detail::hodograph_total_turning(-6.0 * dx + 3.0 * (ax + bx), -6.0 * dy + 3.0 * (ay + by),
                                               6.0 * dx - 4.0 * ax - 2.0 * bx, 6.0 * dy - 4.0 * ay - 2.0 * by,
                                               ax, ay);
}

/// Outcome of the per-edge construction of `konig_edge_complexities()`.
enum class Konig_edge_status
{
  VALID,            ///< the curves were built; `keep` and `flip` are meaningful
  ZERO_NORMAL,      ///< a normal is zero, near zero or not finite
  INVALID_POINT,    ///< a point coordinate is not finite
  COINCIDENT_POINTS ///< the points coincide: no edge direction, no curve
};

/// The complexities of the best "keep" and "flip" curves of one edge.
struct Konig_edge_complexities
{
  /// c_keep: total turning (radians) of the simpler of the two curves with
  /// the normals as given, tangents (+t_i, +t_j) and (-t_i, -t_j)
  double keep = 0.0;
  /// c_flip: total turning (radians) of the simpler of the two curves with one
  /// normal flipped, tangents (+t_i, -t_j) and (-t_i, +t_j)
  double flip = 0.0;
  /// product l_i * l_j in [0, 1] of the lengths of the unit normals projected
  /// into the reference plane (1 when e, n_i and n_j are coplanar); 0 when
  /// a projected normal vanishes, in which case `keep` = `flip` = 0
  double in_plane_weight = 0.0;
  /// whether the construction was possible
  Konig_edge_status status = Konig_edge_status::ZERO_NORMAL;
};

/// Builds König's four Hermite curves for the edge (p_i, n_i)-(p_j, n_j) and
/// returns their complexities (see the file documentation for the
/// construction).  Normals may have any nonzero length.  The computation is
/// done with the two endpoints in a canonical (lexicographic) order, so the
/// result is bitwise identical for (i, j) and (j, i); it is also bitwise
/// invariant when both normals are negated, and negating one normal exactly
/// swaps `keep` and `flip` (the reference plane depends only on the lines of
/// the normals).  Everything is finite for finite input.
inline Konig_edge_complexities konig_edge_complexities(const double p_i[3], const double n_i[3],
                                                       const double p_j[3], const double n_j[3])
{
  using namespace konig_detail;
  Konig_edge_complexities r;
  for (int k = 0; k < 3; ++k)
    if (!std::isfinite(p_i[k]) || !std::isfinite(p_j[k])) {
      r.status = Konig_edge_status::INVALID_POINT;
      return r;
    }
  // canonical order: the same floating-point operations for (i, j) and (j, i)
  const bool swap = lex_less3(p_j, p_i);
  const double* pa = swap ? p_j : p_i;
  const double* pb = swap ? p_i : p_j;
  const double* na_in = swap ? n_j : n_i;
  const double* nb_in = swap ? n_i : n_j;
  double na[3], nb[3];
  if (!unit3(na_in, na, konig_zero_normal_threshold) || !unit3(nb_in, nb, konig_zero_normal_threshold)) {
    r.status = Konig_edge_status::ZERO_NORMAL;
    return r;
  }
  double e[3] = {pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2]};
  if (!std::isfinite(max_abs3(e))) // only for coordinates near the overflow limit
    for (int k = 0; k < 3; ++k)
      e[k] = 0.5 * pb[k] - 0.5 * pa[k];
  const double emax = max_abs3(e);
  if (emax <= konig_coincidence_tolerance * std::max(max_abs3(pa), max_abs3(pb))) {
    r.status = Konig_edge_status::COINCIDENT_POINTS;
    return r;
  }
  double u[3];
  unit3(e, u, 0.0);

  // components a, b of the normals orthogonal to u, and their Gram matrix G
  const double nax = dot3(na, u), nbx = dot3(nb, u);
  const double av[3] = {na[0] - nax * u[0], na[1] - nax * u[1], na[2] - nax * u[2]};
  const double bv[3] = {nb[0] - nbx * u[0], nb[1] - nbx * u[1], nb[2] - nbx * u[2]};
  const double gaa = dot3(av, av), gbb = dot3(bv, bv), gab = dot3(av, bv);
  // In-plane direction w = g_a a + g_b b: the principal eigenvector of
  // a a^T + b b^T lies in span(a, b) and its coefficients g form the principal
  // eigenvector of G.  Only the components of the normals along w are needed:
  // <n_a, w> = <a, w> = (G g)_a / |w|, <n_b, w> = (G g)_b / |w|, |w|^2 = g^T G g.
  const double dd = 0.5 * (gaa - gbb);
  const double rr = std::sqrt(dd * dd + gab * gab);
  double ga = 1.0, gb = 0.0; // tie (every plane through u is as good): w = a
  if (rr > 1e-12 * (gaa + gbb)) {
    if (dd >= 0.0) { ga = dd + rr; gb = gab; }
    else           { ga = gab;     gb = rr - dd; }
  }
  const double ga_w = gaa * ga + gab * gb, gb_w = gab * ga + gbb * gb; // G g
  const double w2 = ga * ga_w + gb * gb_w;
  // W (nax, nay) = (W nax, ga_w), W = |w|, and likewise for b: the projected
  // normals scaled by W, which saves a division on the critical path
  double wl = 1.0, ya = 0.0, yb = 0.0; // w2 = 0: a = b = 0, both normals along u
  if (w2 > 1e-300) {
    wl = std::sqrt(w2);
    ya = ga_w;
    yb = gb_w;
  }
  // Projected normals in the frame (u, w).  The sign of w is arbitrary (a
  // mirror image) and negating both normals does not change keep / flip
  // either; fix both so that the first normal lies in the first quadrant:
  // the computation below is then bitwise identical for (n_a, n_b),
  // (-n_a, -n_b) and mirrored frames.  (copysign(1, x) is -1 for x = -0.0
  // too; multiplying by +-1 is exact.)
  const double sx = std::copysign(1.0, nax), sy = std::copysign(1.0, ya);
  const double ax2 = sx * nax * wl, bx2 = sx * nbx * wl, ay2 = sy * ya, by2 = sy * yb;
  const double la2 = ax2 * ax2 + ay2 * ay2, lb2 = bx2 * bx2 + by2 * by2; // W^2 |projection|^2
  r.status = Konig_edge_status::VALID;
  const double min_l2 = 1e-24 * wl * wl;
  if (!(la2 > min_l2) || !(lb2 > min_l2))
    return r; // a normal is perpendicular to the plane: in_plane_weight = 0
  const double inv_la = 1.0 / std::sqrt(la2), inv_lb = 1.0 / std::sqrt(lb2);
  r.in_plane_weight = std::min(1.0, la2 * inv_la * lb2 * inv_lb / (wl * wl));
  // tangents: unit projected normals rotated by +90 degrees, length 2 |e| = 2
  const double ta_x = -2.0 * ay2 * inv_la, ta_y = 2.0 * ax2 * inv_la;
  const double tb_x = -2.0 * by2 * inv_lb, tb_y = 2.0 * bx2 * inv_lb;
  // p_a = (0, 0), p_b = (1, 0): h(t) = A t^2 + B t + C with
  // A = (-6, 0) + 3 (m0 + m1), B = (6, 0) - 4 m0 - 2 m1, C = m0
  auto turning = [](double m0x, double m0y, double m1x, double m1y) {
    return hodograph_total_turning(-6.0 + 3.0 * (m0x + m1x), 3.0 * (m0y + m1y),
                                   6.0 - 4.0 * m0x - 2.0 * m1x, -4.0 * m0y - 2.0 * m1y, m0x, m0y);
  };
  const double c_pp = turning(ta_x, ta_y, tb_x, tb_y);
  const double c_mm = turning(-ta_x, -ta_y, -tb_x, -tb_y);
  const double c_pm = turning(ta_x, ta_y, -tb_x, -tb_y);
  const double c_mp = turning(-ta_x, -ta_y, tb_x, tb_y);
  r.keep = std::min(c_pp, c_mm);
  r.flip = std::min(c_pm, c_mp);
  return r;
}

/// König's flip criterion as a signed certainty for the edge (i, j).
///
/// Returns phi in [-1, 1]: > 0 when the normals are consistently oriented,
/// < 0 when one of them should flip, |phi| the certainty, 0 where nothing can
/// be said.  With c_keep, c_flip and l_i l_j from `konig_edge_complexities()`:
///
///   phi = sign(c_flip - c_keep) * (1 - min(c_keep, c_flip) / max(c_keep, c_flip)) * l_i l_j.
///
/// 1 - min/max is one minus König's uncertainty: 1 when the simpler curve is
/// straight, 0 when both are equally complex.  l_i l_j = 1 for coplanar e,
/// n_i, n_j (the plain mapping of the specification) and fades phi to 0 as a
/// normal turns perpendicular to the reference plane (see the file
/// documentation).
///
/// Degenerate input:
///  - a zero, near-zero (max |n_k| <= `konig_zero_normal_threshold`) or
///    non-finite normal, or a non-finite point: phi = 0;
///  - coincident points (`konig_coincidence_tolerance`): there is no edge
///    direction, hence no curve; phi falls back to Hoppe's <n_i, n_j> of the
///    unit normals, as `Xie_criterion` does: exact duplicates (common in
///    merged scans) share their surface, and the fallback keeps all the
///    symmetries below.
///
/// Properties (for finite input): phi is finite; phi(i, j) == phi(j, i)
/// bitwise; phi is bitwise unchanged when both normals are negated; negating
/// one normal gives exactly -phi.  phi depends only on the directions of the
/// normals and of the edge, not on the distance between the points.
///
/// Cost: four closed-form turning computations (one quadratic and at most
/// three arctangents each), no allocation, no library trigonometry.
inline double konig_phi(const double p_i[3], const double n_i[3], const double p_j[3],
                        const double n_j[3])
{
  const Konig_edge_complexities c = konig_edge_complexities(p_i, n_i, p_j, n_j);
  double phi = 0.0;
  if (c.status == Konig_edge_status::COINCIDENT_POINTS) {
    double a[3], b[3];
    konig_detail::unit3(n_i, a, konig_zero_normal_threshold);
    konig_detail::unit3(n_j, b, konig_zero_normal_threshold);
    phi = konig_detail::dot3(a, b);
  } else if (c.status == Konig_edge_status::VALID) {
    const double mx = std::max(c.keep, c.flip), mn = std::min(c.keep, c.flip);
    if (mx > 0.0 && c.keep != c.flip)
      phi = (c.flip > c.keep ? 1.0 : -1.0) * (1.0 - mn / mx) * c.in_plane_weight;
  }
  if (!(phi >= -1.0)) // also NaN (cannot happen for finite input; belt and braces)
    phi = phi < -1.0 ? -1.0 : 0.0;
  return phi > 1.0 ? 1.0 : phi;
}

} // namespace internal
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_KONIG_CURVES_H
