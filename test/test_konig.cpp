// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// Tests of König's flip criterion (internal/Konig_curves.h).  Includes only
// that header, the standard library and GoogleTest.

#include <Normal_orientation/internal/Konig_curves.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

namespace {

using Normal_orientation::internal::hermite_total_turning;
using Normal_orientation::internal::konig_edge_complexities;
using Normal_orientation::internal::konig_phi;
using Normal_orientation::internal::Konig_edge_status;

constexpr double pi = 3.14159265358979323846;
constexpr double deg = pi / 180.0;

using V3 = std::array<double, 3>;

double phi(const V3& pi_, const V3& ni, const V3& pj, const V3& nj)
{
  return konig_phi(pi_.data(), ni.data(), pj.data(), nj.data());
}

V3 neg(const V3& v) { return {-v[0], -v[1], -v[2]}; }
V3 add(const V3& a, const V3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
V3 mul(double s, const V3& v) { return {s * v[0], s * v[1], s * v[2]}; }
double dot(const V3& a, const V3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
V3 unit(const V3& v) { return mul(1.0 / std::sqrt(dot(v, v)), v); }

/// a random rotation (rows of an orthonormal, right-handed matrix)
struct Rotation
{
  V3 r0, r1, r2;
  V3 operator()(const V3& v) const { return {dot(r0, v), dot(r1, v), dot(r2, v)}; }
};

Rotation random_rotation(std::mt19937_64& g)
{
  std::normal_distribution<double> N(0.0, 1.0);
  const V3 a = unit({N(g), N(g), N(g)});
  V3 b{N(g), N(g), N(g)};
  b = unit(add(b, mul(-dot(a, b), a)));
  const V3 c{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  return Rotation{a, b, c};
}

/// reference total turning by dense sampling of the tangent c'(t)
double sampled_turning(const double p0[2], const double m0[2], const double p1[2], const double m1[2],
                       double* min_speed)
{
  const double Ax = 6 * (p0[0] - p1[0]) + 3 * (m0[0] + m1[0]), Ay = 6 * (p0[1] - p1[1]) + 3 * (m0[1] + m1[1]);
  const double Bx = 6 * (p1[0] - p0[0]) - 4 * m0[0] - 2 * m1[0], By = 6 * (p1[1] - p0[1]) - 4 * m0[1] - 2 * m1[1];
  const int n = 10007;
  double total = 0.0, px = m0[0], py = m0[1];
  *min_speed = std::hypot(px, py);
  for (int k = 1; k <= n; ++k) {
    const double t = double(k) / n;
    const double hx = (Ax * t + Bx) * t + m0[0], hy = (Ay * t + By) * t + m0[1];
    *min_speed = std::min(*min_speed, std::hypot(hx, hy));
    if (hx == 0.0 && hy == 0.0)
      continue; // an exact cusp on a sample: keep the previous direction
    total += std::abs(std::atan2(px * hy - py * hx, px * hx + py * hy));
    px = hx;
    py = hy;
  }
  return total;
}

/// Xie's criterion, for comparison only
double xie(const V3& p_i, const V3& n_i, const V3& p_j, const V3& n_j)
{
  const V3 e = unit(add(p_i, neg(p_j)));
  const V3 a = unit(n_i), b = unit(n_j);
  return dot(a, b) - 2.0 * dot(e, a) * dot(e, b);
}

} // namespace

// ---------------------------------------------------------------------------
// The turning angle of one Hermite curve

TEST(Konig_criterion, HermiteTurningSimpleCurves)
{
  const double p0[2] = {0, 0}, p1[2] = {1, 0};
  {
    // straight segment
    const double m[2] = {2, 0};
    EXPECT_NEAR(hermite_total_turning(p0, m, p1, m), 0.0, 1e-12);
  }
  {
    // starts forward, ends backward: straight, with one reversal (cusp)
    const double m0[2] = {2, 0}, m1[2] = {-2, 0};
    EXPECT_NEAR(hermite_total_turning(p0, m0, p1, m1), pi, 1e-12);
  }
  {
    // both tangents backward: straight, two reversals
    const double m[2] = {-2, 0};
    EXPECT_NEAR(hermite_total_turning(p0, m, p1, m), 2 * pi, 1e-12);
  }
  {
    // the cubic parametrisation of the segment itself (m = p1 - p0): 0
    const double m[2] = {1, 0};
    EXPECT_NEAR(hermite_total_turning(p0, m, p1, m), 0.0, 1e-12);
  }
  {
    // a convex arc whose tangent speed stays moderate turns by exactly the
    // angle between its end tangents
    const double a = 40 * deg;
    const double m0[2] = {std::cos(a), -std::sin(a)}, m1[2] = {std::cos(a), std::sin(a)};
    EXPECT_NEAR(hermite_total_turning(p0, m0, p1, m1), 2 * a, 1e-12);
  }
  {
    // semicircle-like arc with perpendicular end tangents: pi
    const double m0[2] = {0, 2}, m1[2] = {0, -2};
    EXPECT_NEAR(hermite_total_turning(p0, m0, p1, m1), pi, 1e-12);
  }
  {
    // a single point, zero tangents: 0; non-finite input: 0
    const double z[2] = {0, 0};
    EXPECT_EQ(hermite_total_turning(z, z, z, z), 0.0);
    const double m[2] = {1, 0.5};
    for (int k = 0; k < 2; ++k) {
      double bad[2] = {1, 0.5};
      bad[k] = std::numeric_limits<double>::quiet_NaN();
      EXPECT_EQ(hermite_total_turning(p0, bad, p1, m), 0.0);
      EXPECT_EQ(hermite_total_turning(p0, m, p1, bad), 0.0);
      EXPECT_EQ(hermite_total_turning(bad, m, p1, m), 0.0);
      bad[k] = std::numeric_limits<double>::infinity();
      EXPECT_EQ(hermite_total_turning(p0, m, bad, m), 0.0);
    }
  }
}

TEST(Konig_criterion, HermiteTurningMatchesDenseSampling)
{
  std::mt19937_64 g(12345);
  std::normal_distribution<double> N(0.0, 1.0);
  int compared = 0;
  for (int it = 0; it < 1500; ++it) {
    double p0[2] = {N(g), N(g)}, p1[2] = {N(g), N(g)}, m0[2] = {N(g), N(g)}, m1[2] = {N(g), N(g)};
    if (it % 3 == 0) { // longer, more curved tangents
      m0[0] *= 4;
      m1[1] *= 4;
    }
    double min_speed = 0;
    const double ref = sampled_turning(p0, m0, p1, m1, &min_speed);
    const double f = hermite_total_turning(p0, m0, p1, m1);
    ASSERT_TRUE(std::isfinite(f));
    ASSERT_GE(f, 0.0);
    ASSERT_LT(f, 8 * pi);
    if (min_speed < 1e-2) // near a cusp the sampling itself is unreliable
      continue;
    ++compared;
    EXPECT_NEAR(f, ref, 1e-6) << "case " << it;
  }
  EXPECT_GT(compared, 1400);
}

TEST(Konig_criterion, HermiteTurningNearDegenerateCurves)
{
  // special values (straight curves, cusps, double roots, closed curves)
  // plus perturbations from 1e-4 down to 1e-12: curves that nearly stop,
  // nearly double back or nearly wrap around once
  const double vals[] = {0, 1, -1, 2, -2, 3, -3, 0.5, -0.5, 6};
  std::mt19937_64 g(4);
  std::uniform_int_distribution<int> I(0, 9);
  int compared = 0;
  for (int it = 0; it < 2500; ++it) {
    double p0[2] = {0, 0}, p1[2] = {vals[I(g)], vals[I(g)]}, m0[2] = {vals[I(g)], vals[I(g)]},
           m1[2] = {vals[I(g)], vals[I(g)]};
    if (it % 2 == 1) {
      std::normal_distribution<double> N(0.0, std::pow(10.0, -4 - (it / 2) % 9));
      for (double* q : {p1, m0, m1}) {
        q[0] += N(g);
        q[1] += N(g);
      }
    }
    const double f = hermite_total_turning(p0, m0, p1, m1);
    ASSERT_TRUE(std::isfinite(f));
    ASSERT_GE(f, 0.0);
    ASSERT_LT(f, 8 * pi);
    // a (nearly) zero end derivative has an arbitrary direction, which the
    // sampled reference would count; the function starts along c'' instead
    if (std::hypot(m0[0], m0[1]) < 1e-6 || std::hypot(m1[0], m1[1]) < 1e-6)
      continue;
    double min_speed = 0;
    const double ref = sampled_turning(p0, m0, p1, m1, &min_speed);
    ++compared;
    EXPECT_NEAR(f, ref, 1e-3) << "p1 (" << p1[0] << ", " << p1[1] << ") m0 (" << m0[0] << ", " << m0[1]
                              << ") m1 (" << m1[0] << ", " << m1[1] << ")";
  }
  EXPECT_GT(compared, 2000);
}

TEST(Konig_criterion, HermiteTurningInvariances)
{
  std::mt19937_64 g(777);
  std::normal_distribution<double> N(0.0, 1.0);
  for (int it = 0; it < 2000; ++it) {
    const double p0[2] = {N(g), N(g)}, p1[2] = {N(g), N(g)}, m0[2] = {N(g), N(g)}, m1[2] = {N(g), N(g)};
    const double f = hermite_total_turning(p0, m0, p1, m1);
    // reversal: from p1 to p0 with tangents -m1, -m0
    const double r0[2] = {-m1[0], -m1[1]}, r1[2] = {-m0[0], -m0[1]};
    EXPECT_NEAR(hermite_total_turning(p1, r0, p0, r1), f, 1e-9);
    // similarity: rotation, mirror, scale, translation
    const double c = std::cos(0.3 * it), s = std::sin(0.3 * it);
    for (double scale : {1e-12, 1e-3, 1e3, 1e12}) {
      auto T = [&](const double v[2], double out[2], bool point) {
        out[0] = scale * (c * v[0] - s * v[1]) + (point ? 5.0 * scale : 0.0);
        out[1] = -scale * (s * v[0] + c * v[1]) + (point ? -2.0 * scale : 0.0); // with a mirror
      };
      double q0[2], q1[2], n0[2], n1[2];
      T(p0, q0, true);
      T(p1, q1, true);
      T(m0, n0, false);
      T(m1, n1, false);
      EXPECT_NEAR(hermite_total_turning(q0, n0, q1, n1), f, 1e-8);
    }
  }
}

// ---------------------------------------------------------------------------
// phi: basic configurations

TEST(Konig_criterion, PlaneWithEqualNormals)
{
  std::mt19937_64 g(1);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (int it = 0; it < 200; ++it) {
    const Rotation R = random_rotation(g);
    const double spacing = std::pow(10.0, 6.0 * U(g));
    const V3 p_i = R({U(g), U(g), 0.0});
    const V3 p_j = add(p_i, R({spacing * std::cos(3.0 * it), spacing * std::sin(3.0 * it), 0.0}));
    const V3 n = mul(std::pow(10.0, 3.0 * U(g)), R({0.0, 0.0, 1.0})); // any length
    EXPECT_GT(phi(p_i, n, p_j, n), 0.9);
    EXPECT_LT(phi(p_i, n, p_j, neg(n)), -0.9);
    EXPECT_LT(phi(p_i, neg(n), p_j, n), -0.9);
    EXPECT_GT(phi(p_i, neg(n), p_j, neg(n)), 0.9);
  }
  // axis-aligned: the consistent curve is the straight segment (c_keep = 0),
  // the inconsistent one has a cusp (c_flip = pi): phi = +-1 exactly
  const V3 a{0, 0, 0}, b{1, 0, 0}, n{0, 0, 1};
  const auto c = konig_edge_complexities(a.data(), n.data(), b.data(), n.data());
  EXPECT_EQ(c.status, Konig_edge_status::VALID);
  EXPECT_NEAR(c.keep, 0.0, 1e-12);
  EXPECT_NEAR(c.flip, pi, 1e-12);
  EXPECT_EQ(c.in_plane_weight, 1.0);
  EXPECT_DOUBLE_EQ(phi(a, n, b, n), 1.0);
  EXPECT_DOUBLE_EQ(phi(a, n, b, neg(n)), -1.0);
}

TEST(Konig_criterion, CircleWithRadialNormals)
{
  // consistent neighbours on a circle (radial normals, outward or inward),
  // arcs of 5..80 degrees, several radii, centres and 3-D embeddings
  std::mt19937_64 g(2);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (double radius : {1e-6, 1e-2, 1.0, 1e3, 1e6}) {
    for (double arc = 5.0; arc <= 80.0; arc += 5.0) {
      for (int rep = 0; rep < 4; ++rep) {
        const Rotation R = random_rotation(g);
        const V3 centre = mul(radius, {U(g), U(g), U(g)});
        const double t0 = pi * U(g), t1 = t0 + arc * deg;
        const V3 d0 = R({std::cos(t0), std::sin(t0), 0.0}), d1 = R({std::cos(t1), std::sin(t1), 0.0});
        const V3 p_i = add(centre, mul(radius, d0)), p_j = add(centre, mul(radius, d1));
        const double sgn = (rep % 2 == 0) ? 1.0 : -1.0; // outward / inward
        const V3 n_i = mul(sgn, d0), n_j = mul(sgn, d1);
        const double f = phi(p_i, n_i, p_j, n_j);
        EXPECT_GT(f, 0.5) << "radius " << radius << " arc " << arc;
        EXPECT_LT(phi(p_i, n_i, p_j, neg(n_j)), -0.5) << "radius " << radius << " arc " << arc;
        // the certainty decreases as the arc grows
        if (radius == 1.0 && rep == 0 && arc >= 10.0) {
          const double t2 = t0 + (arc - 5.0) * deg;
          const V3 d2 = R({std::cos(t2), std::sin(t2), 0.0});
          EXPECT_GT(phi(p_i, n_i, add(centre, mul(radius, d2)), mul(sgn, d2)), f);
        }
      }
    }
  }
}

TEST(Konig_criterion, Crease90Degrees)
{
  // cube occupying x <= 0, z <= 0 near its edge along y: top face z = 0
  // (normal +z) and side face x = 0 (normal +x).  Hoppe's dot product is 0
  // everywhere; König says "consistent" everywhere, most clearly when the two
  // points are at comparable distances from the edge and the edge e is not
  // nearly parallel to the crease line (there e, n_i, n_j approach a
  // symmetric tie of the reference plane and the in-plane weight drops to
  // 1/2).  A scan (not repeated here) over 1000:1 distance ratios and edges up
  // to 89.9 degrees from the perpendicular gave phi in (0.0004, 0.62].
  std::mt19937_64 g(3);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  int clear_cases = 0;
  for (double h : {1e-3, 0.05, 1.0, 40.0}) { // sampling scale
    for (int rep = 0; rep < 100; ++rep) {
      const Rotation R = random_rotation(g);
      const double di = h * (0.05 + U(g)), dj = h * (0.05 + U(g)), dy = h * (U(g) - 0.5);
      const V3 p_i = R({-di, 0.0, 0.0}), p_j = R({0.0, dy, -dj});
      const V3 n_i = R({0, 0, 1}), n_j = R({1, 0, 0});
      EXPECT_NEAR(dot(n_i, n_j), 0.0, 1e-12); // Hoppe says nothing
      const double f = phi(p_i, n_i, p_j, n_j);
      EXPECT_GT(f, 0.0);
      EXPECT_LT(phi(p_i, n_i, p_j, neg(n_j)), 0.0);
      EXPECT_LT(phi(p_i, neg(n_i), p_j, n_j), 0.0);
      EXPECT_GT(xie(p_i, n_i, p_j, n_j), 0.0); // Xie agrees
      const double ratio = std::max(di, dj) / std::min(di, dj);
      if (ratio <= 2.0 && std::abs(dy) <= std::hypot(di, dj)) { // e within 45 deg of the perpendicular
        EXPECT_GT(f, 0.3) << "di " << di << " dj " << dj << " dy " << dy;
        ++clear_cases;
      }
    }
  }
  EXPECT_GT(clear_cases, 50);
  // the symmetric case is the quarter circle: c_keep = 90 deg, c_flip =
  // 237.5 deg, phi = 0.621
  const V3 a{-1, 0, 0}, b{0, 0, -1}, na{0, 0, 1}, nb{1, 0, 0};
  EXPECT_NEAR(phi(a, na, b, nb), 1.0 - 90.0 / 237.508, 1e-4);
  // equal distances, oblique edge (45 deg from the perpendicular): still clear
  EXPECT_GT(phi(a, na, {0, std::sqrt(2.0), -1}, nb), 0.5);
}

TEST(Konig_criterion, ThinSlab)
{
  // A slab of thickness h: p_i on the top face (normal +z), p_j on the bottom
  // face (normal -z) with a lateral offset dx.  The criterion depends only on
  // directions, not on distances: the thickness relative to the sampling
  // spacing matters only through the direction of the edge.  Findings:
  //  - directly below (dx = 0): c_keep = 180 deg (a half-turn joins the two
  //    sheets), c_flip = 247.4 deg (an S-curve): "consistent", phi = 0.272,
  //    weaker than Xie's +1;
  //  - phi decreases with dx/h and changes sign at dx / h = 0.894 (Xie's
  //    criterion changes sign at dx / h = 1);
  //  - for dx >~ h, i.e. typical neighbours when the thickness is comparable
  //    to or smaller than the spacing, König says "flip" (the two sheets look
  //    like one sheet with a flipped normal), with growing certainty.
  const V3 n_top{0, 0, 1}, n_bottom{0, 0, -1};
  auto slab = [&](double dx, double h) {
    return phi({0.0, 0.0, 0.0}, n_top, {dx, 0.0, -h}, n_bottom);
  };
  for (double h : {1e-4, 1.0, 1e4}) {
    EXPECT_NEAR(slab(0.0, h), 1.0 - 180.0 / 247.38, 1e-3);
    EXPECT_GT(slab(0.5 * h, h), 0.0);
    EXPECT_GT(slab(0.85 * h, h), 0.0);
    EXPECT_LT(slab(0.95 * h, h), 0.0);
    EXPECT_LT(slab(2.0 * h, h), -0.25);
    EXPECT_LT(slab(4.0 * h, h), -0.5);
    // monotone in the offset
    double prev = slab(0.0, h);
    for (double r = 0.1; r <= 8.0; r += 0.1) {
      const double f = slab(r * h, h);
      EXPECT_LT(f, prev);
      prev = f;
    }
    // Xie, for comparison: consistent up to dx = h
    EXPECT_NEAR(xie({0.0, 0.0, 0.0}, n_top, {0.0, 0.0, -h}, n_bottom), 1.0, 1e-12);
    EXPECT_GT(xie({0.0, 0.0, 0.0}, n_top, {0.95 * h, 0.0, -h}, n_bottom), 0.0);
    EXPECT_LT(xie({0.0, 0.0, 0.0}, n_top, {1.05 * h, 0.0, -h}, n_bottom), 0.0);
  }
  // report the crossing (bisection)
  double lo = 0.5, hi = 1.0;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (lo + hi);
    (slab(mid, 1.0) > 0.0 ? lo : hi) = mid;
  }
  std::printf("[ thin slab ] phi(dx = 0) = %.4f, sign change at dx / h = %.4f\n", slab(0.0, 1.0), lo);
  EXPECT_NEAR(lo, 0.9, 0.05);
}

// ---------------------------------------------------------------------------
// phi: symmetries, range, robustness

TEST(Konig_criterion, RandomConfigurationsSymmetriesAndRange)
{
  // 10^5 random 3-D configurations (fixed seed) over many scales
  std::mt19937_64 g(20240601);
  std::normal_distribution<double> N(0.0, 1.0);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  int nonzero = 0;
  for (int it = 0; it < 100000; ++it) {
    const double scale = std::pow(10.0, 12.0 * U(g));
    const double spread = (it % 4 == 0) ? 1e-3 : 1.0; // close neighbours too
    const V3 p_i = mul(scale, {N(g), N(g), N(g)});
    const V3 p_j = add(p_i, mul(scale * spread, {N(g), N(g), N(g)}));
    V3 n_i{N(g), N(g), N(g)}, n_j{N(g), N(g), N(g)};
    if (it % 5 == 1) { // nearly coplanar configurations
      n_j = add(n_i, mul(0.1, n_j));
    }
    n_i = mul(std::pow(10.0, 6.0 * U(g)), n_i);
    n_j = mul(std::pow(10.0, 6.0 * U(g)), n_j);
    const double f = phi(p_i, n_i, p_j, n_j);
    ASSERT_TRUE(std::isfinite(f)) << it;
    ASSERT_GE(f, -1.0);
    ASSERT_LE(f, 1.0);
    ASSERT_EQ(phi(p_j, n_j, p_i, n_i), f) << it;                 // symmetric (bitwise)
    ASSERT_EQ(phi(p_i, neg(n_i), p_j, neg(n_j)), f) << it;       // both flipped
    ASSERT_EQ(phi(p_i, n_i, p_j, neg(n_j)), -f) << it;           // one flipped (exact,
    ASSERT_EQ(phi(p_i, neg(n_i), p_j, n_j), -f) << it;           // 1e-9 is required)
    ASSERT_EQ(phi(p_j, neg(n_j), p_i, n_i), -f) << it;
    if (f != 0.0)
      ++nonzero;
  }
  EXPECT_GT(nonzero, 99000);
}

TEST(Konig_criterion, StructuredDegenerateConfigurations)
{
  // coordinates drawn from a small set of special values hit exact
  // degeneracies: normals along the edge or perpendicular to the reference
  // plane, ties of the plane, straight and cusped curves, coincident points
  const double vals[] = {0.0, 1.0, -1.0, 2.0, -0.5, 1e-8, -1e-8, 1e-13, 3.0};
  std::mt19937_64 g(9);
  std::uniform_int_distribution<int> I(0, 8);
  for (int it = 0; it < 100000; ++it) {
    V3 v[4];
    for (V3& x : v)
      x = {vals[I(g)], vals[I(g)], vals[I(g)]};
    const double f = phi(v[0], v[1], v[2], v[3]);
    ASSERT_TRUE(std::isfinite(f)) << it;
    ASSERT_LE(std::abs(f), 1.0) << it;
    ASSERT_EQ(phi(v[2], v[3], v[0], v[1]), f) << it;
    ASSERT_EQ(phi(v[0], neg(v[1]), v[2], neg(v[3])), f) << it;
    ASSERT_EQ(phi(v[0], v[1], v[2], neg(v[3])), -f) << it;
    ASSERT_EQ(phi(v[0], neg(v[1]), v[2], v[3]), -f) << it;
  }
}

TEST(Konig_criterion, RotationScaleTranslationInvariance)
{
  std::mt19937_64 g(5);
  std::normal_distribution<double> N(0.0, 1.0);
  int worse = 0;
  double max_diff = 0.0;
  for (int it = 0; it < 5000; ++it) {
    const V3 p_i{N(g), N(g), N(g)}, p_j{N(g), N(g), N(g)}, n_i{N(g), N(g), N(g)}, n_j{N(g), N(g), N(g)};
    const double f = phi(p_i, n_i, p_j, n_j);
    const Rotation R = random_rotation(g);
    for (double s : {1e-12, 1e-5, 1.0, 1e5, 1e12}) {
      const V3 t = mul(3.0 * s, {N(g), N(g), N(g)});
      const double h = phi(add(t, mul(s, R(p_i))), R(n_i), add(t, mul(s, R(p_j))), R(n_j));
      // a near-tie of the reference plane (normals' perpendicular parts
      // orthogonal and of equal length) amplifies rounding
      if (std::abs(h - f) > 1e-7)
        ++worse;
      max_diff = std::max(max_diff, std::abs(h - f));
    }
  }
  std::printf("[ invariance ] max |phi difference| %.3g, %d of 25000 above 1e-7\n", max_diff, worse);
  EXPECT_LT(worse, 5);
  EXPECT_LT(max_diff, 1e-6);
}

TEST(Konig_criterion, PlanarConfigurationsEmbeddedIn3D)
{
  // e, n_i, n_j coplanar: the reference plane is their plane, the weight is 1
  // and phi does not depend on how the plane sits in space
  std::mt19937_64 g(6);
  std::uniform_real_distribution<double> U(-pi, pi);
  for (int it = 0; it < 2000; ++it) {
    const double ai = U(g), aj = U(g), ae = U(g);
    const V3 p_i{0, 0, 0}, p_j{std::cos(ae), std::sin(ae), 0}, n_i{std::cos(ai), std::sin(ai), 0},
        n_j{std::cos(aj), std::sin(aj), 0};
    const double f = phi(p_i, n_i, p_j, n_j);
    const auto c = konig_edge_complexities(p_i.data(), n_i.data(), p_j.data(), n_j.data());
    EXPECT_NEAR(c.in_plane_weight, 1.0, 1e-12);
    const Rotation R = random_rotation(g);
    EXPECT_NEAR(phi(R(p_i), R(n_i), R(p_j), R(n_j)), f, 1e-8);
  }
}

TEST(Konig_criterion, NormalLengthDoesNotMatter)
{
  std::mt19937_64 g(7);
  std::normal_distribution<double> N(0.0, 1.0);
  for (int it = 0; it < 2000; ++it) {
    const V3 p_i{N(g), N(g), N(g)}, p_j{N(g), N(g), N(g)}, n_i{N(g), N(g), N(g)}, n_j{N(g), N(g), N(g)};
    const double f = phi(p_i, n_i, p_j, n_j);
    for (double s : {1e-15, 1e-3, 7.0, 1e200})
      EXPECT_NEAR(phi(p_i, mul(s, n_i), p_j, n_j), f, 1e-12);
  }
}

TEST(Konig_criterion, DegenerateInputs)
{
  const V3 a{1, 2, 3}, b{1.5, 2, 3}, n{0, 0, 1}, m{0.3, -0.2, 0.9}, zero{0, 0, 0};
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  // zero, near-zero and non-finite normals: nothing can be said
  EXPECT_EQ(phi(a, zero, b, n), 0.0);
  EXPECT_EQ(phi(a, n, b, zero), 0.0);
  EXPECT_EQ(phi(a, {1e-25, 0, 0}, b, n), 0.0);
  for (int k = 0; k < 3; ++k) {
    V3 bad_nan = m, bad_inf = m;
    bad_nan[k] = nan;
    bad_inf[k] = -inf;
    EXPECT_EQ(phi(a, bad_nan, b, n), 0.0);
    EXPECT_EQ(phi(a, n, b, bad_inf), 0.0);
    EXPECT_EQ(konig_edge_complexities(a.data(), bad_nan.data(), b.data(), n.data()).status,
              Konig_edge_status::ZERO_NORMAL);
  }
  EXPECT_EQ(konig_edge_complexities(a.data(), zero.data(), b.data(), n.data()).status,
            Konig_edge_status::ZERO_NORMAL);
  // non-finite points
  EXPECT_EQ(phi({nan, 0, 0}, n, b, n), 0.0);
  EXPECT_EQ(phi(a, n, {0, inf, 0}, n), 0.0);
  EXPECT_EQ(konig_edge_complexities(a.data(), n.data(), V3{0, -inf, 0}.data(), n.data()).status,
            Konig_edge_status::INVALID_POINT);
  // coincident points: Hoppe's <n_i, n_j> of the unit normals
  EXPECT_NEAR(phi(a, n, a, m), dot(unit(n), unit(m)), 1e-15);
  EXPECT_NEAR(phi(a, n, a, neg(m)), -dot(unit(n), unit(m)), 1e-15);
  EXPECT_EQ(konig_edge_complexities(a.data(), n.data(), a.data(), m.data()).status,
            Konig_edge_status::COINCIDENT_POINTS);
  // points one ulp apart at 1e12 are coincident as well
  const V3 big{1e12, 1e12, 1e12};
  const V3 big2{std::nextafter(1e12, 2e12), 1e12, 1e12};
  EXPECT_NEAR(phi(big, n, big2, m), dot(unit(n), unit(m)), 1e-15);
  // ... but points 1e-6 apart at 1e6 are not
  EXPECT_EQ(konig_edge_complexities(V3{1e6, 0, 0}.data(), n.data(), V3{1e6 + 1e-6, 0, 0}.data(), n.data()).status,
            Konig_edge_status::VALID);
  EXPECT_GT(phi({1e6, 0, 0}, n, {1e6 + 1e-6, 0, 0}, n), 0.9);
  // a normal perpendicular to the reference plane: e = x, n_i = y, n_j = z
  // (their perpendicular parts tie; the plane through e and n_i is taken and
  // n_j projects to 0): phi = 0
  EXPECT_EQ(phi({0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {0, 0, 1}), 0.0);
  // both normals along the edge: any plane through e, a half-turn against an
  // S-curve
  const V3 o{0, 0, 0}, x{1, 0, 0};
  EXPECT_NEAR(phi(o, x, x, x), -(1.0 - 180.0 / 247.38), 1e-3); // same direction: flip
  EXPECT_NEAR(phi(o, neg(x), x, x), 1.0 - 180.0 / 247.38, 1e-3); // facing away: consistent
  // huge and tiny coordinates stay finite and in range, even near overflow
  const double big_c = 0.9 * std::numeric_limits<double>::max();
  for (const V3& q : {V3{big_c, -big_c, 0}, V3{-big_c, big_c, big_c}, V3{1e-300, 0, 0}, V3{5e-324, 0, 0}}) {
    const double f = phi(q, n, neg(q), m);
    EXPECT_TRUE(std::isfinite(f));
    EXPECT_LE(std::abs(f), 1.0);
  }
}

TEST(Konig_criterion, ComplexitiesSwapWhenOneNormalFlips)
{
  std::mt19937_64 g(8);
  std::normal_distribution<double> N(0.0, 1.0);
  for (int it = 0; it < 2000; ++it) {
    const V3 p_i{N(g), N(g), N(g)}, p_j{N(g), N(g), N(g)}, n_i{N(g), N(g), N(g)}, n_j{N(g), N(g), N(g)};
    const auto c = konig_edge_complexities(p_i.data(), n_i.data(), p_j.data(), n_j.data());
    const V3 f = neg(n_j);
    const auto d = konig_edge_complexities(p_i.data(), n_i.data(), p_j.data(), f.data());
    ASSERT_EQ(c.status, Konig_edge_status::VALID);
    EXPECT_EQ(c.keep, d.flip);
    EXPECT_EQ(c.flip, d.keep);
    EXPECT_EQ(c.in_plane_weight, d.in_plane_weight);
    EXPECT_GE(c.keep, 0.0);
    EXPECT_GE(c.flip, 0.0);
    EXPECT_GE(c.in_plane_weight, 0.0);
    EXPECT_LE(c.in_plane_weight, 1.0);
    // phi follows from the complexities
    const double mx = std::max(c.keep, c.flip), mn = std::min(c.keep, c.flip);
    const double expected = (c.flip > c.keep ? 1.0 : -1.0) * (1.0 - mn / mx) * c.in_plane_weight;
    EXPECT_NEAR(konig_phi(p_i.data(), n_i.data(), p_j.data(), n_j.data()), expected, 1e-15);
  }
}
