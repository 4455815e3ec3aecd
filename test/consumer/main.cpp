// SPDX-License-Identifier: GPL-3.0-or-later
// Consumer of the installed package (see ../consumer_test.sh): orients a
// sphere whose radial normals have random signs, with the default
// parameters, and checks that every normal points outward.

#include <Normal_orientation/orient_normals.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/property_map.h>

#include <cmath>
#include <cstddef>
#include <iostream>
#include <random>
#include <utility>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point_3;
typedef Kernel::Vector_3 Vector_3;
typedef std::pair<Point_3, Vector_3> Point_with_normal;

int main()
{
  const std::size_t n = 4000;
  const Point_3 centre(1.0, -2.0, 0.5);
  const double radius = 2.0;
  const double pi = std::acos(-1.0);

  // Fibonacci sphere: evenly spread points, radial normals of random sign.
  std::mt19937 random(5);
  std::vector<Point_with_normal> points;
  points.reserve(n);
  std::size_t inward_before = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * double(i) + 1.0) / double(n);
    const double r = std::sqrt(1.0 - z * z);
    const double a = pi * (3.0 - std::sqrt(5.0)) * double(i);
    const Vector_3 u(r * std::cos(a), r * std::sin(a), z);
    const bool inward = (random() & 1u) != 0;
    inward_before += inward ? 1 : 0;
    points.emplace_back(centre + radius * u, inward ? -u : u);
  }

  namespace NP = Normal_orientation::parameters;
  const Normal_orientation::Orientation_result result = Normal_orientation::orient_normals(
    points, NP::point_map(CGAL::First_of_pair_property_map<Point_with_normal>())
              .normal_map(CGAL::Second_of_pair_property_map<Point_with_normal>()));

  std::size_t outward = 0;
  for (const Point_with_normal& p : points)
    if (p.second * (p.first - centre) > 0)
      ++outward;

#ifdef CGAL_LINKED_WITH_TBB
  const char* tbb = "on";
#else
  const char* tbb = "off";
#endif
  const bool ok = result.number_of_points == n && outward == n;
  std::cout << "consumer: " << (ok ? "OK" : "FAILED") << ", " << outward << "/" << n
            << " normals outward (" << inward_before << " inward before, " << result.number_of_flipped
            << " flipped), " << result.number_of_components << " component(s), TBB " << tbb << "\n";
  return ok ? 0 : 1;
}
