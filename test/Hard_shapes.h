// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// Synthetic clouds of the failure classes of issue 15: shapes on which the local energy's
// minimum is a wrong orientation (touching objects, nested shells, thin parts, flat ends on
// a thick part, sparse tubes) and open scans that must face the side their sensor saw.
// Every function returns exactly n samples, area-uniform on the surface, with the true unit
// normal: outward on closed objects, towards the sensor's side on open scans.
//
// Scales are stated as fractions of the spacing s = sqrt(area / 30000), the side of the square
// each point stands for at 30k points (the mean nearest-neighbour distance is about s / 2).
// The geometry does not depend on n: the same object is sampled more or less densely.
// All randomness is drawn from the caller's std::mt19937_64 through uniform_01() below (no
// std::*_distribution), so a seed gives the same cloud with every standard library.
#ifndef NORMAL_ORIENTATION_TEST_HARD_SHAPES_H
#define NORMAL_ORIENTATION_TEST_HARD_SHAPES_H

#include "Synthetic_shapes.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace hard_shapes {

/// a sample: position and true unit normal (that of test/Synthetic_shapes.h)
using Sample = test::Sample;
/// the point type of the samples
using Point = test::Point;
/// the vector type of the samples
using Vector = test::Vector;

namespace internal {

/// pi, spelt out (M_PI is not standard C++)
constexpr double pi = 3.14159265358979323846;

/// a uniform double in [0, 1) from the top 53 bits of one draw (portable)
inline double uniform_01(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0); }

/// a uniform double in [lo, hi)
inline double uniform(std::mt19937_64& rng, double lo, double hi) { return lo + (hi - lo) * uniform_01(rng); }

/// `v` scaled to unit length (`v` must not be zero)
inline Vector unit(const Vector& v) { return v / std::sqrt(v.squared_length()); }

/// A piece of surface sampled by rejection. `envelope` bounds its area from above; `draw`
/// proposes one sample and returns false to reject it, so that accepted samples are
/// area-uniform and the acceptance rate is area / envelope.
struct Part
{
  double envelope;
  std::function<bool(std::mt19937_64&, Sample&)> draw;
};

/// Exactly n samples area-uniform on the union of `parts`, among those `keep` accepts (all
/// when `keep` is empty; it must accept a part of positive area, or this never returns).
/// A part is chosen by its envelope and a rejected proposal restarts the whole draw, which
/// makes the density uniform over the union.
inline std::vector<Sample> sample_parts(const std::vector<Part>& parts, std::size_t n, std::mt19937_64& rng,
                                        const std::function<bool(const Sample&)>& keep = {})
{
  std::vector<double> cumulative;
  double total = 0.0;
  for (const Part& part : parts)
    cumulative.push_back(total += part.envelope);
  std::vector<Sample> samples;
  samples.reserve(n);
  Sample s{Point(0, 0, 0), Vector(0, 0, 0)};
  while (samples.size() < n) {
    const double pick = uniform_01(rng) * total;
    std::size_t i = static_cast<std::size_t>(std::upper_bound(cumulative.begin(), cumulative.end(), pick) -
                                              cumulative.begin());
    i = (std::min)(i, parts.size() - 1);
    if (parts[i].draw(rng, s) && (!keep || keep(s)))
      samples.push_back(s);
  }
  return samples;
}

/// The ellipsoid of centre c and semi-axes a, b, c_z along x, y, z. Normals outward, or
/// inward (towards the centre) when `inward`. A uniform point on the unit sphere is mapped
/// onto the ellipsoid and kept with probability (local area stretch) / (largest stretch).
inline Part ellipsoid(const Point& c, double a, double b, double c_z, bool inward = false)
{
  const double stretch_max = (std::max)({b * c_z, a * c_z, a * b});
  return {4.0 * pi * stretch_max, [=](std::mt19937_64& rng, Sample& s) {
            const double z = uniform(rng, -1.0, 1.0), phi = uniform(rng, 0.0, 2.0 * pi);
            const double rho = std::sqrt((std::max)(0.0, 1.0 - z * z));
            const double x = rho * std::cos(phi), y = rho * std::sin(phi);
            const double stretch = std::sqrt(CGAL::square(b * c_z * x) + CGAL::square(a * c_z * y) +
                                             CGAL::square(a * b * z));
            if (uniform_01(rng) * stretch_max >= stretch)
              return false;
            const Vector n = unit(Vector(x / a, y / b, z / c_z));
            s = {c + Vector(a * x, b * y, c_z * z), inward ? -n : n};
            return true;
          }};
}

/// The parallelogram origin + u e1 + v e2 (u, v in [0, 1)) with the unit normal `normal`,
/// which the caller orients.
inline Part parallelogram(const Point& origin, const Vector& e1, const Vector& e2, const Vector& normal)
{
  return {std::sqrt(CGAL::cross_product(e1, e2).squared_length()), [=](std::mt19937_64& rng, Sample& s) {
            const double u = uniform_01(rng), v = uniform_01(rng);
            s = {origin + u * e1 + v * e2, normal};
            return true;
          }};
}

/// The faces of the axis-aligned box [lo, hi], normals outward, in the order -x, +x, -y, +y,
/// +z, -z; without the last (the floor) when `with_floor` is false.
inline std::vector<Part> box_faces(const Point& lo, const Point& hi, bool with_floor = true)
{
  const Vector dx(hi.x() - lo.x(), 0, 0), dy(0, hi.y() - lo.y(), 0), dz(0, 0, hi.z() - lo.z());
  std::vector<Part> faces = {parallelogram(lo, dy, dz, Vector(-1, 0, 0)), parallelogram(lo + dx, dy, dz, Vector(1, 0, 0)),
                             parallelogram(lo, dx, dz, Vector(0, -1, 0)), parallelogram(lo + dy, dx, dz, Vector(0, 1, 0)),
                             parallelogram(lo + dz, dx, dy, Vector(0, 0, 1))};
  if (with_floor)
    faces.push_back(parallelogram(lo, dx, dy, Vector(0, 0, -1)));
  return faces;
}

/// The wall of the cylinder of axis z, radius r, between heights z0 < z1; normals away from
/// the axis, or towards it when `inward`.
inline Part cylinder_wall(double r, double z0, double z1, bool inward)
{
  return {2.0 * pi * r * (z1 - z0), [=](std::mt19937_64& rng, Sample& s) {
            const double phi = uniform(rng, 0.0, 2.0 * pi), z = uniform(rng, z0, z1);
            const Vector radial(std::cos(phi), std::sin(phi), 0.0);
            s = {Point(r * radial.x(), r * radial.y(), z), inward ? -radial : radial};
            return true;
          }};
}

/// The annulus r_in <= |(x, y)| <= r_out in the plane z = height, with normal (0, 0, nz).
inline Part annulus(double r_in, double r_out, double height, double nz)
{
  return {pi * (r_out * r_out - r_in * r_in), [=](std::mt19937_64& rng, Sample& s) {
            const double phi = uniform(rng, 0.0, 2.0 * pi);
            const double rho = std::sqrt(r_in * r_in + uniform_01(rng) * (r_out * r_out - r_in * r_in));
            s = {Point(rho * std::cos(phi), rho * std::sin(phi), height), Vector(0, 0, nz)};
            return true;
          }};
}

/// The closed surface of a cylinder of axis z with a coaxial bore, z in [0, height]: the outer
/// wall of radius r_out (normals away from the axis), the bore of radius r_in < r_out (normals
/// towards the axis), and the annular ends (normals -z at z = 0, +z at z = height).
inline std::vector<Part> bored_cylinder_parts(double r_in, double r_out, double height)
{
  return {cylinder_wall(r_out, 0.0, height, false), cylinder_wall(r_in, 0.0, height, true),
          annulus(r_in, r_out, 0.0, -1.0), annulus(r_in, r_out, height, 1.0)};
}

/// The torus of axis z, centred at the origin, with radii R > r; normals outward. The two
/// angles are uniform and a proposal is kept with probability (R + r cos b) / (R + r).
inline Part torus(double R, double r)
{
  return {4.0 * pi * pi * r * (R + r), [=](std::mt19937_64& rng, Sample& s) {
            const double a = uniform(rng, 0.0, 2.0 * pi), b = uniform(rng, 0.0, 2.0 * pi);
            if (uniform_01(rng) * (R + r) >= R + r * std::cos(b))
              return false;
            const Vector radial(std::cos(a), std::sin(a), 0.0);
            const Vector n = std::cos(b) * radial + Vector(0, 0, std::sin(b));
            s = {Point(0, 0, 0) + R * radial + r * n, n};
            return true;
          }};
}

/// The zone of the sphere of centre 0 and radius r between polar angles 0 and `theta` (from
/// +z); normals away from the centre, or towards it when `inward`. Uniform on the sphere by
/// z = cos(polar angle), uniform in [cos theta, 1].
inline Part spherical_cap(double r, double theta, bool inward)
{
  const double z0 = std::cos(theta);
  return {2.0 * pi * r * r * (1.0 - z0), [=](std::mt19937_64& rng, Sample& s) {
            const double z = uniform(rng, z0, 1.0), phi = uniform(rng, 0.0, 2.0 * pi);
            const double rho = std::sqrt((std::max)(0.0, 1.0 - z * z));
            const Vector n(rho * std::cos(phi), rho * std::sin(phi), z);
            s = {Point(r * n.x(), r * n.y(), r * n.z()), inward ? -n : n};
            return true;
          }};
}

/// The band of the cone of apex 0 and half-angle `theta` about +z between the distances
/// r_in < r_out from the apex; normals away from the axis and down the cone's side (the rim of
/// `thin_dome()`).
inline Part cone_band(double r_in, double r_out, double theta)
{
  return {pi * std::sin(theta) * (r_out * r_out - r_in * r_in), [=](std::mt19937_64& rng, Sample& s) {
            const double phi = uniform(rng, 0.0, 2.0 * pi);
            const double t = std::sqrt(r_in * r_in + uniform_01(rng) * (r_out * r_out - r_in * r_in));
            const Vector radial(std::cos(phi), std::sin(phi), 0.0);
            const Vector along = std::sin(theta) * radial + Vector(0, 0, std::cos(theta));
            const Vector n = std::cos(theta) * radial - Vector(0, 0, std::sin(theta));
            s = {Point(t * along.x(), t * along.y(), t * along.z()), n};
            return true;
          }};
}

/// The ground of terrain_with_buildings(): z = h(x, y), a sum of two gentle waves.
struct Terrain
{
  /// the height at (x, y); |h| <= amplitude()
  static double height(double x, double y)
  {
    return 0.06 * std::sin(1.3 * x + 0.4) * std::cos(1.1 * y) + 0.04 * std::sin(0.7 * x + 1.9 * y);
  }
  /// the gradient of height() at (x, y)
  static Vector gradient(double x, double y)
  {
    const double w = std::cos(0.7 * x + 1.9 * y);
    return Vector(0.078 * std::cos(1.3 * x + 0.4) * std::cos(1.1 * y) + 0.028 * w,
                  -0.066 * std::sin(1.3 * x + 0.4) * std::sin(1.1 * y) + 0.076 * w, 0.0);
  }
  /// a bound on |height()|
  static double amplitude() { return 0.1; }
  /// a bound on the area stretch sqrt(1 + |gradient|^2) (|h_x| <= 0.106, |h_y| <= 0.142)
  static double stretch_max() { return std::sqrt(1.0 + 0.106 * 0.106 + 0.142 * 0.142); }
};

/// an axis-aligned building footprint [x0, x1] x [y0, y1] with a flat roof at height `top`
struct Building
{
  double x0, x1, y0, y1, top;
};

/// The vertical wall from (x0, y0) to (x1, y1) of a building standing on the terrain, from
/// the ground up to `top`, with the horizontal outward normal `normal`. Heights are drawn
/// from [-amplitude, top] and those under the ground rejected.
inline Part terrain_wall(double x0, double y0, double x1, double y1, double top, const Vector& normal)
{
  const double length = std::sqrt(CGAL::square(x1 - x0) + CGAL::square(y1 - y0));
  return {length * (top + Terrain::amplitude()), [=](std::mt19937_64& rng, Sample& s) {
            const double u = uniform_01(rng), z = uniform(rng, -Terrain::amplitude(), top);
            const double x = x0 + u * (x1 - x0), y = y0 + u * (y1 - y0);
            if (z < Terrain::height(x, y))
              return false;
            s = {Point(x, y, z), normal};
            return true;
          }};
}

/// The terrain over [-half, half]^2, normals up, without the ground under the buildings.
inline Part terrain_ground(double half, const std::vector<Building>& buildings)
{
  return {4.0 * half * half * Terrain::stretch_max(), [=](std::mt19937_64& rng, Sample& s) {
            const double x = uniform(rng, -half, half), y = uniform(rng, -half, half);
            for (const Building& b : buildings)
              if (x >= b.x0 && x <= b.x1 && y >= b.y0 && y <= b.y1)
                return false;
            const Vector g = Terrain::gradient(x, y);
            const double stretch = std::sqrt(1.0 + g.squared_length());
            if (uniform_01(rng) * Terrain::stretch_max() >= stretch)
              return false;
            s = {Point(x, y, Terrain::height(x, y)), Vector(-g.x(), -g.y(), 1.0) / stretch};
            return true;
          }};
}

/// the signed distance to the torus of axis z, centred at the origin, with radii R > r
inline double torus_distance(const Point& p, double R, double r)
{
  const double ring = std::sqrt(p.x() * p.x() + p.y() * p.y()) - R;
  return std::sqrt(ring * ring + p.z() * p.z()) - r;
}

/// Whether the torus (R, r) leaves the segment from the surface sample `s` to `eye` free.
/// The ray is marched with steps of max(distance, r / 64): a grazing crossing thinner than
/// that step may be missed, and a grazing ray that dips in at once counts as occluded.
inline bool torus_sees(const Sample& s, const Point& eye, double R, double r)
{
  const Vector to_eye = eye - s.p;
  const double length = std::sqrt(to_eye.squared_length());
  const Vector d = to_eye / length;
  const double step_min = r / 64.0;
  for (double t = step_min; t < length;) {
    const double distance = torus_distance(s.p + t * d, R, r);
    if (distance < 0.0)
      return false;
    t += (std::max)(distance, step_min);
  }
  return true;
}

} // namespace internal

/**
 * A foot-like cluster of 6 closed ellipsoids ("bones"), normals outward. Area 4.16, s = 0.0118.
 * - heel: centre (-1.2, 0, 0), semi-axes (0.45, 0.26, 0.24);
 * - talus on the heel: centre (-1.2, 0, 0.4 + g), semi-axes (0.3, 0.2, 0.16), tip to tip in z;
 * - midfoot: centre (-0.57 + g, 0, 0), semi-axes (0.18, 0.33, 0.2), tip to tip with the heel in x;
 * - three metatarsals side by side: semi-axes (0.55, 0.1, 0.1), centres (0.16 + 2g, y, 0) with
 *   y = -(0.2 + g), 0, 0.2 + g; the middle one tip to tip with the midfoot, each touching its
 *   neighbours along their whole length; the outer ones are 0.037 (3 s) from the midfoot.
 * The gaps g = 0.003 (0.25 s) are the shortest distances between touching bones.
 */
inline std::vector<Sample> touching_ellipsoids(std::size_t n, std::mt19937_64& rng)
{
  using internal::ellipsoid;
  const double g = 0.003;
  std::vector<internal::Part> bones = {ellipsoid(Point(-1.2, 0, 0), 0.45, 0.26, 0.24),
                                       ellipsoid(Point(-1.2, 0, 0.4 + g), 0.3, 0.2, 0.16),
                                       ellipsoid(Point(-0.57 + g, 0, 0), 0.18, 0.33, 0.2)};
  for (double y : {-(0.2 + g), 0.0, 0.2 + g})
    bones.push_back(ellipsoid(Point(0.16 + 2.0 * g, y, 0), 0.55, 0.1, 0.1));
  return internal::sample_parts(bones, n, rng);
}

/**
 * Four closed axis-aligned boxes that touch face to face across gaps g = 0.005 (0.2 s),
 * normals outward. Area 16.8, s = 0.0236.
 * - base [0, 2] x [0, 1.2] x [0, 0.5];
 * - on the base: [0.3, 1.3] x [0.2, 1.0] x [0.5 + g, 1.1 + g];
 * - on that one: [0.5, 1.1] x [0.35, 0.85] x [1.1 + 2g, 1.5 + 2g];
 * - beside the base: [2 + g, 2.8 + g] x [0.1, 0.9] x [0, 0.7].
 * Each contact is a partial overlap of two parallel faces with opposite normals.
 */
inline std::vector<Sample> touching_boxes(std::size_t n, std::mt19937_64& rng)
{
  const double g = 0.005;
  const Point corners[4][2] = {{Point(0, 0, 0), Point(2, 1.2, 0.5)},
                               {Point(0.3, 0.2, 0.5 + g), Point(1.3, 1.0, 1.1 + g)},
                               {Point(0.5, 0.35, 1.1 + 2 * g), Point(1.1, 0.85, 1.5 + 2 * g)},
                               {Point(2 + g, 0.1, 0), Point(2.8 + g, 0.9, 0.7)}};
  std::vector<internal::Part> faces;
  for (const auto& c : corners)
    for (internal::Part& f : internal::box_faces(c[0], c[1]))
      faces.push_back(std::move(f));
  return internal::sample_parts(faces, n, rng);
}

/**
 * A hollow ball: the sphere of radius 1 with outward normals around a cavity bounded by the
 * concentric sphere of radius 0.8, whose normals point towards the centre (into the cavity).
 * Area 20.6, s = 0.026; the walls are 0.2 (7.6 s) apart, so no edge joins them: only a global
 * rule can tell that the inner wall faces the cavity. 39% of the points are on the inner wall.
 */
inline std::vector<Sample> hollow_ball(std::size_t n, std::mt19937_64& rng)
{
  return internal::sample_parts({internal::ellipsoid(Point(0, 0, 0), 1, 1, 1),
                                 internal::ellipsoid(Point(0, 0, 0), 0.8, 0.8, 0.8, true)},
                                n, rng);
}

/**
 * A closed plate [0, 1] x [0, 1] x [0, t], all six faces sampled, normals outward, with
 * t = 0.0025 (0.3 s, s = 0.0082 for the area 2.01): every neighbourhood holds points of both
 * large faces, whose true normals are opposite. The rims hold 0.5% of the points.
 */
inline std::vector<Sample> thin_plate(std::size_t n, std::mt19937_64& rng)
{
  return internal::sample_parts(internal::box_faces(Point(0, 0, 0), Point(1, 1, 0.0025)), n, rng);
}

/**
 * A thin-walled pipe of axis z, closed: outer wall radius 1 (normals away from the axis), inner
 * wall radius 0.994 (normals towards the axis), height 1.5, and flat annular ends. Area 18.8,
 * s = 0.025 at 30k points: the wall is 0.006 (0.24 s) thick, curved, and every neighbourhood
 * holds points of both walls, whose true normals are opposite.
 */
inline std::vector<Sample> thin_pipe(std::size_t n, std::mt19937_64& rng)
{
  return internal::sample_parts(internal::bored_cylinder_parts(0.994, 1.0, 1.5), n, rng);
}

/**
 * A thin dome, closed: the cap of the unit sphere about +z up to the polar angle 1 (57
 * degrees), normals outward, over the cap of the sphere of radius 0.996, normals towards the
 * centre, joined by a conical rim band. Area 5.8, s = 0.014 at 30k points: the shell is 0.004
 * (0.29 s) thick and curved both ways.
 */
inline std::vector<Sample> thin_dome(std::size_t n, std::mt19937_64& rng)
{
  using namespace internal;
  return sample_parts({spherical_cap(1.0, 1.0, false), spherical_cap(0.996, 1.0, true), cone_band(0.996, 1.0, 1.0)},
                      n, rng);
}

/**
 * A thick cylinder of axis z with a coaxial bore: outer wall radius 1 (normals away from the
 * axis), bore radius 0.5 (normals towards the axis), height 1.5 (z in [0, 1.5]), and flat
 * annular ends with normals -z at z = 0 and +z at z = 1.5. Area 18.8, s = 0.025; the flat ends
 * meet both walls at sharp right-angled edges.
 */
inline std::vector<Sample> bored_cylinder(std::size_t n, std::mt19937_64& rng)
{
  return internal::sample_parts(internal::bored_cylinder_parts(0.5, 1.0, 1.5), n, rng);
}

/**
 * A long thin torus of axis z, radii R = 1 and r = 0.015, normals outward: the tube is 67
 * times longer than its circumference. Area 0.59; at 4000 points the spacing is 0.012, about
 * 8 points per circumference, and every neighbourhood of 12 reaches round the tube.
 */
inline std::vector<Sample> sparse_tube(std::size_t n, std::mt19937_64& rng)
{
  return internal::sample_parts({internal::torus(1.0, 0.015)}, n, rng);
}

/**
 * A building scanned from the outside: the walls of the box [0, 2] x [0, 1.2] x [0, 0.8] and
 * its flat roof, which overhangs the walls by 0.25 on every side (eaves): the rectangle
 * [-0.25, 2.25] x [-0.25, 1.45] at z = 0.8, which the walls meet from below along a line 0.25
 * inside its edge. No floor, and neither the eaves' underside nor their edge is sampled (as
 * when the roof is seen from the air and the walls from the street). Normals outward, as
 * seen from outside: the walls' away from the building, the roof's up. Area 9.37, s = 0.0177.
 */
inline std::vector<Sample> open_box(std::size_t n, std::mt19937_64& rng)
{
  std::vector<internal::Part> parts = internal::box_faces(Point(0, 0, 0), Point(2, 1.2, 0.8), false);
  parts.pop_back(); // the box's own roof: replaced by the wider one
  parts.push_back(internal::parallelogram(Point(-0.25, -0.25, 0.8), Vector(2.5, 0, 0), Vector(0, 1.7, 0), Vector(0, 0, 1)));
  return internal::sample_parts(parts, n, rng);
}

/**
 * An airborne-like tile: the terrain z = 0.06 sin(1.3 x + 0.4) cos(1.1 y) + 0.04 sin(0.7 x + 1.9 y)
 * over [-2, 2]^2 (|z| <= 0.1, slopes under 0.18), normals up, and four box buildings standing
 * on it: walls from the ground to the flat roof, normals outward, roofs with normals up, no
 * floor, no ground under them. Footprints and roof heights:
 * [-1.5, -0.7] x [-1.4, -0.6] at 0.5; [0.2, 1.4] x [-1.2, -0.5] at 0.8;
 * [-1.2, -0.4] x [0.5, 1.5] at 0.35; [0.6, 1.3] x [0.4, 1.3] at 1.1. Area about 25, s = 0.029.
 */
inline std::vector<Sample> terrain_with_buildings(std::size_t n, std::mt19937_64& rng)
{
  using namespace internal;
  const std::vector<Building> buildings = {
    {-1.5, -0.7, -1.4, -0.6, 0.5}, {0.2, 1.4, -1.2, -0.5, 0.8}, {-1.2, -0.4, 0.5, 1.5, 0.35}, {0.6, 1.3, 0.4, 1.3, 1.1}};
  std::vector<Part> parts = {terrain_ground(2.0, buildings)};
  for (const Building& b : buildings) {
    parts.push_back(terrain_wall(b.x0, b.y0, b.x1, b.y0, b.top, Vector(0, -1, 0)));
    parts.push_back(terrain_wall(b.x1, b.y0, b.x1, b.y1, b.top, Vector(1, 0, 0)));
    parts.push_back(terrain_wall(b.x1, b.y1, b.x0, b.y1, b.top, Vector(0, 1, 0)));
    parts.push_back(terrain_wall(b.x0, b.y1, b.x0, b.y0, b.top, Vector(-1, 0, 0)));
    parts.push_back(parallelogram(Point(b.x0, b.y0, b.top), Vector(b.x1 - b.x0, 0, 0), Vector(0, b.y1 - b.y0, 0),
                                  Vector(0, 0, 1)));
  }
  return sample_parts(parts, n, rng);
}

/**
 * An urban tile seen from the air: the flat ground z = 0 over [-3.2, 3.2] x [-2.4, 2.4],
 * normals up, with twelve box buildings in a 4 x 3 grid, 0.6 to 1.1 wide, 0.3 to 2.0 high,
 * along alleys about 0.4 wide: walls outward, roofs up, no floors, no ground under them.
 * Walls along narrow alleys are seen from few directions.  Area about 45, s = 0.039 at
 * 30k points.
 */
inline std::vector<Sample> city_block(std::size_t n, std::mt19937_64& rng)
{
  using namespace internal;
  // x0, y0, width, depth, height (a fixed table: the same city for every seed)
  const double table[12][5] = {{-2.9, -2.2, 0.8, 0.7, 0.9},  {-1.35, -2.1, 1.0, 0.9, 2.0}, {0.2, -2.25, 0.7, 1.1, 0.5},
                               {1.6, -2.0, 1.1, 0.8, 1.4},   {-2.8, -0.6, 1.0, 1.0, 0.3},  {-1.4, -0.75, 0.9, 0.6, 1.2},
                               {0.1, -0.7, 1.1, 1.0, 1.7},   {1.75, -0.55, 0.7, 0.9, 0.8}, {-2.95, 0.8, 0.9, 1.1, 1.5},
                               {-1.3, 0.9, 0.6, 0.8, 0.6},   {0.25, 0.85, 1.0, 0.7, 1.0},  {1.6, 0.75, 0.9, 1.0, 1.9}};
  std::vector<Building> buildings;
  for (const auto& t : table)
    buildings.push_back({t[0], t[0] + t[2], t[1], t[1] + t[3], t[4]});
  std::vector<Part> parts;
  const double hx = 3.2, hy = 2.4;
  parts.push_back({4.0 * hx * hy, [=](std::mt19937_64& g, Sample& s) {
                     const double x = uniform(g, -hx, hx), y = uniform(g, -hy, hy);
                     for (const Building& b : buildings)
                       if (x >= b.x0 && x <= b.x1 && y >= b.y0 && y <= b.y1)
                         return false;
                     s = {Point(x, y, 0.0), Vector(0, 0, 1)};
                     return true;
                   }});
  for (const Building& b : buildings) {
    std::vector<Part> faces = box_faces(Point(b.x0, b.y0, 0.0), Point(b.x1, b.y1, b.top), false);
    parts.insert(parts.end(), faces.begin(), faces.end());
  }
  return sample_parts(parts, n, rng);
}

/**
 * A street between two facades, seen from the street: the ground z = 0 over [0, 8] x [-1, 1],
 * normals up, and the walls y = -1 and y = 1, 1.5 high, normals towards the street; nothing
 * behind the facades.  Exterior views see the facades from the back as much as from the
 * street: a limit of exterior visibility.  Area 40, s = 0.037 at 30k points.
 */
inline std::vector<Sample> street_canyon(std::size_t n, std::mt19937_64& rng)
{
  using namespace internal;
  return sample_parts({parallelogram(Point(0, -1, 0), Vector(8, 0, 0), Vector(0, 2, 0), Vector(0, 0, 1)),
                       parallelogram(Point(0, -1, 0), Vector(8, 0, 0), Vector(0, 0, 1.5), Vector(0, 1, 0)),
                       parallelogram(Point(0, 1, 0), Vector(8, 0, 0), Vector(0, 0, 1.5), Vector(0, -1, 0))},
                      n, rng);
}

/**
 * A single-view scan of the torus of axis z, radii R = 1 and r = 0.35, from the viewpoint
 * (0, -3.5, 2.5) (35 degrees above the torus' plane): the points of the area-uniform
 * sampling that face the viewpoint and that the torus does not hide from it, normals outward,
 * i.e. towards the viewer's side. Part of the inner wall of the far side is seen through the
 * hole. The visible area is about 44% of the torus' 13.8, s = 0.014 at 30k points.
 */
inline std::vector<Sample> single_view_scan(std::size_t n, std::mt19937_64& rng)
{
  const double R = 1.0, r = 0.35;
  const Point eye(0, -3.5, 2.5);
  return internal::sample_parts({internal::torus(R, r)}, n, rng, [&](const Sample& s) {
    return s.n * (eye - s.p) > 0.0 && internal::torus_sees(s, eye, R, r);
  });
}

namespace internal {

/// a shape generator of this header
typedef std::vector<Sample> (*Generator)(std::size_t, std::mt19937_64&);

/// the shapes of this header by name, in a fixed order
inline const std::vector<std::pair<std::string, Generator>>& generators()
{
  static const std::vector<std::pair<std::string, Generator>> table = {
    {"touching_ellipsoids", touching_ellipsoids}, {"touching_boxes", touching_boxes},
    {"hollow_ball", hollow_ball},                 {"thin_plate", thin_plate},
    {"thin_pipe", thin_pipe},                     {"thin_dome", thin_dome},
    {"bored_cylinder", bored_cylinder},           {"sparse_tube", sparse_tube},
    {"open_box", open_box},                       {"terrain_with_buildings", terrain_with_buildings},
    {"single_view_scan", single_view_scan},       {"city_block", city_block},
    {"street_canyon", street_canyon}};
  return table;
}

} // namespace internal

/// the names of the shapes of this header, in a fixed order
inline std::vector<std::string> hard_shape_names()
{
  std::vector<std::string> names;
  for (const auto& entry : internal::generators())
    names.push_back(entry.first);
  return names;
}

/// the shape called `name` (one of hard_shape_names()) with n samples;
/// throws std::invalid_argument on an unknown name
inline std::vector<Sample> hard_shape(const std::string& name, std::size_t n, std::mt19937_64& rng)
{
  for (const auto& entry : internal::generators())
    if (name == entry.first)
      return entry.second(n, rng);
  throw std::invalid_argument("unknown hard shape '" + name + "'");
}

} // namespace hard_shapes
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_TEST_HARD_SHAPES_H
