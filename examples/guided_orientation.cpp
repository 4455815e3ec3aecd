// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// Guiding the orientation with what is known.  A dome scanned from inside
// (a room, a cave) is an open surface: the default policy makes its normals
// point out of the dome, away from the scanner, as for the boundary of a
// solid.  Three ways to say what is right, on the same input:
// the viewpoint component sign policy (Viewpoint_component_sign), a soft
// prior per point (orientation_prior_map: lambda cos(n_i, v - p_i)), and
// hard constraints on a few points whose normals are known
// (point_is_constrained_map; those normals are never changed).
//
// usage: guided_orientation [IN(.xyz|.ply, with normals) X Y Z]
//        (without arguments: 5000 points on a dome of radius 1, scanned
//        from (0, 0, 0.2); with them, the file and the scanner position X Y Z)

#include <Normal_orientation/orient_normals.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iostream>
#include <random>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point_3;
typedef Kernel::Vector_3 Vector_3;
typedef CGAL::Point_set_3<Point_3, Vector_3> Point_set;
namespace NO = Normal_orientation;
namespace NP = Normal_orientation::parameters;

int main(int argc, char** argv)
{
  if (argc != 1 && argc != 5) {
    std::cerr << "usage: guided_orientation [IN(.xyz|.ply, with normals) X Y Z]\n";
    return 2;
  }
  try {
    Point_set points;
    Point_3 scanner(0, 0, 0.2);
    if (argc == 5) {
      double v[3];
      for (int d = 0; d < 3; ++d) {
        char* end = nullptr;
        v[d] = std::strtod(argv[2 + d], &end);
        if (end == argv[2 + d] || *end != '\0' || !std::isfinite(v[d])) {
          std::cerr << "guided_orientation: the scanner position X Y Z must be three numbers\n";
          return 2;
        }
      }
      scanner = Point_3(v[0], v[1], v[2]);
      if (!CGAL::IO::read_point_set(argv[1], points) || !points.has_normal_map() || points.size() < 3) {
        std::cerr << "guided_orientation: cannot read points with normals from " << argv[1] << "\n";
        return 1;
      }
    } else { // a dome z >= 0, normals of random signs, slightly noisy
      points.add_normal_map();
      std::mt19937 random(1);
      std::uniform_real_distribution<double> uniform(0.0, 1.0);
      for (int i = 0; i < 5000; ++i) {
        const double z = uniform(random), a = 2 * M_PI * uniform(random), s = std::sqrt(1 - z * z);
        const Vector_3 noise{uniform(random) - 0.5, uniform(random) - 0.5, uniform(random) - 0.5}; // in order
        const Vector_3 n = Vector_3(s * std::cos(a), s * std::sin(a), z) + 0.3 * noise;
        points.insert(Point_3(s * std::cos(a), s * std::sin(a), z), uniform(random) < 0.5 ? n : -n);
      }
    }
    const std::vector<Vector_3> input(points.normal_map().begin(), points.normal_map().end());
    const auto faces_scanner = [&](Point_set::Index i) { return points.normal(i) * (scanner - points.point(i)) > 0; };
    const auto report = [&](const char* what, const NO::Orientation_result& r) {
      const auto facing = std::count_if(points.begin(), points.end(), faces_scanner);
      std::printf("%-26s: %6.2f%% of the normals face the scanner (%zu unary terms)\n", what,
                  100.0 * double(facing) / double(points.size()), r.number_of_unary_terms);
      std::copy(input.begin(), input.end(), points.normal_map().begin()); // the input again, for the next run
    };
    std::printf("%zu points, scanner at (%g, %g, %g)\n", points.size(), scanner.x(), scanner.y(), scanner.z());

    // 1. The default: outward, as if the dome were the boundary of a solid.
    report("default (outward)", NO::orient_normals(points, points.parameters()));

    // 2. Every component faces the scanner.
    const NO::Viewpoint_component_sign viewpoint(scanner.x(), scanner.y(), scanner.z());
    report("viewpoint sign policy",
           NO::orient_normals(points, NP::extend(points.parameters()).component_sign(viewpoint)));

    // 3. A soft prior per point, weighed against the edges (which weigh at
    //    most 1): a_i = lambda cos(n_i, v - p_i) favours facing the scanner.
    auto prior = points.add_property_map<double>("prior", 0.0).first;
    for (Point_set::Index i : points) {
      const Vector_3 v = scanner - points.point(i), n = points.normal(i);
      const double l = std::sqrt(v.squared_length() * n.squared_length());
      prior[i] = l > 0 ? 0.1 * (n * v) / l : 0.0;
    }
    report("viewpoint prior (0.1 cos)",
           NO::orient_normals(points, NP::extend(points.parameters()).orientation_prior_map(prior)));

    // 4. Hard constraints: the 3 points nearest the scanner, whose normals are
    //    known (they face it).  Every solver keeps them, their component
    //    follows them (Constrained_component_sign, the default then).
    auto constrained = points.add_property_map<bool>("constrained", false).first;
    std::vector<Point_set::Index> nearest(points.begin(), points.end());
    std::partial_sort(nearest.begin(), nearest.begin() + 3, nearest.end(), [&](auto a, auto b) {
      return CGAL::squared_distance(points.point(a), scanner) < CGAL::squared_distance(points.point(b), scanner);
    });
    std::vector<Vector_3> known;
    for (int c = 0; c < 3; ++c) {
      constrained[nearest[c]] = true;
      points.normal(nearest[c]) = faces_scanner(nearest[c]) ? points.normal(nearest[c]) : -points.normal(nearest[c]);
      known.push_back(points.normal(nearest[c]));
    }
    const NO::Orientation_result r =
      NO::orient_normals(points, NP::extend(points.parameters()).point_is_constrained_map(constrained));
    bool kept = true;
    for (int c = 0; c < 3; ++c)
      kept = kept && points.normal(nearest[c]) == known[c];
    report("3 constrained points", r);
    std::printf("the constrained normals were %s\n", kept ? "kept" : "CHANGED");
  } catch (const std::exception& e) { // a non-finite coordinate or normal in IN
    std::cerr << "guided_orientation: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
