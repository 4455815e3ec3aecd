// SPDX-License-Identifier: GPL-3.0-or-later
// Synthetic clouds with ground-truth outward normals, for the tests.
#ifndef NORMAL_ORIENTATION_TEST_SYNTHETIC_SHAPES_H
#define NORMAL_ORIENTATION_TEST_SYNTHETIC_SHAPES_H

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/pca_estimate_normals.h>
#include <CGAL/property_map.h>

#include <cmath>
#include <random>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace test {

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point;
typedef Kernel::Vector_3 Vector;

/// a sample: position and true outward unit normal
struct Sample
{
  Point p;
  Vector n;
};

inline Vector unit(const Vector& v) { return v / std::sqrt(v.squared_length()); }

/// n points uniform on the sphere of centre c and radius r
inline std::vector<Sample> sphere(std::size_t n, std::mt19937_64& rng, Point c = Point(0, 0, 0), double r = 1.0)
{
  std::normal_distribution<double> g;
  std::vector<Sample> s;
  for (std::size_t i = 0; i < n; ++i) {
    // (the order of the draws made explicit: that of g++, which evaluates
    // arguments right to left, so that every compiler gives the same clouds)
    const double z = g(rng), y = g(rng), x = g(rng);
    const Vector d = unit(Vector(x, y, z));
    s.push_back({c + r * d, d});
  }
  return s;
}

/// n points area-uniform on the torus of radii R (axis z) and r
inline std::vector<Sample> torus(std::size_t n, std::mt19937_64& rng, double R = 1.0, double r = 0.3)
{
  std::uniform_real_distribution<double> u(0.0, 2.0 * M_PI), w(0.0, 1.0);
  std::vector<Sample> s;
  while (s.size() < n) {
    const double a = u(rng), b = u(rng);
    if (w(rng) > (R + r * std::cos(b)) / (R + r))
      continue; // area weighting
    const Vector radial(std::cos(a), std::sin(a), 0.0);
    const Vector nrm = std::cos(b) * radial + Vector(0, 0, std::sin(b));
    s.push_back({Point(0, 0, 0) + R * radial + r * nrm, nrm});
  }
  return s;
}

/// n points area-uniform on the surface of the box [0,a]x[0,b]x[0,c]
inline std::vector<Sample> box(std::size_t n, std::mt19937_64& rng, double a, double b, double c)
{
  const double area[3] = {b * c, a * c, a * b}; // faces orthogonal to x, y, z
  const double total = 2.0 * (area[0] + area[1] + area[2]);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double size[3] = {a, b, c};
  std::vector<Sample> s;
  for (std::size_t i = 0; i < n; ++i) {
    double pick = u(rng) * total;
    int axis = 0;
    while (axis < 2 && pick >= 2.0 * area[axis]) {
      pick -= 2.0 * area[axis];
      ++axis;
    }
    const bool high = pick >= area[axis];
    double q[3];
    for (int d = 0; d < 3; ++d)
      q[d] = u(rng) * size[d];
    q[axis] = high ? size[axis] : 0.0;
    double nv[3] = {0, 0, 0};
    nv[axis] = high ? 1.0 : -1.0;
    s.push_back({Point(q[0], q[1], q[2]), Vector(nv[0], nv[1], nv[2])});
  }
  return s;
}

/// unoriented input: every true normal with a random sign and, optionally,
/// a small angular perturbation of standard deviation `angle_noise`
inline std::vector<std::pair<Point, Vector>> unoriented(const std::vector<Sample>& s, std::mt19937_64& rng,
                                                         double angle_noise = 0.0)
{
  std::normal_distribution<double> g(0.0, angle_noise > 0.0 ? angle_noise : 1.0);
  std::bernoulli_distribution coin(0.5);
  std::vector<std::pair<Point, Vector>> out;
  for (const Sample& x : s) {
    Vector n = x.n;
    if (angle_noise > 0.0) {
      const double gz = g(rng), gy = g(rng), gx = g(rng); // (g++'s order, see sphere())
      n = unit(n + Vector(gx, gy, gz));
    }
    out.push_back({x.p, coin(rng) ? n : -n});
  }
  return out;
}

/// the number of normals that do not point outward (dot <= 0)
inline std::size_t count_wrong(const std::vector<Sample>& truth, const std::vector<std::pair<Point, Vector>>& cloud)
{
  std::size_t wrong = 0;
  for (std::size_t i = 0; i < truth.size(); ++i)
    wrong += (truth[i].n * cloud[i].second <= 0.0) ? 1 : 0;
  return wrong;
}

/// `truth` with Gaussian position noise of deviation `sigma`, PCA normals
/// over 18 neighbours and random signs
inline std::vector<std::pair<Point, Vector>> noisy_cloud(const std::vector<Sample>& truth, double sigma, unsigned seed)
{
  typedef std::pair<Point, Vector> Point_with_normal;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Point_with_normal> cloud;
  for (const Sample& s : truth) {
    const double dz = g(rng), dy = g(rng), dx = g(rng); // (g++'s order, see sphere())
    cloud.emplace_back(Point(s.p.x() + sigma * dx, s.p.y() + sigma * dy, s.p.z() + sigma * dz), Vector(0, 0, 1));
  }
  CGAL::pca_estimate_normals<CGAL::Sequential_tag>(
    cloud, 18,
    CGAL::parameters::point_map(CGAL::First_of_pair_property_map<Point_with_normal>())
      .normal_map(CGAL::Second_of_pair_property_map<Point_with_normal>()));
  for (Point_with_normal& p : cloud)
    if (rng() & 1)
      p.second = -p.second;
  return cloud;
}

} // namespace test
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_TEST_SYNTHETIC_SHAPES_H
