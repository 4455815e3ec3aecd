// SPDX-License-Identifier: GPL-3.0-or-later
// The README's API example, compiled: orient a std::vector of
// (point, normal) pairs read from an .xyz file, then write it back.
//
//   orient_pairs IN.xyz OUT.xyz

#include <Normal_orientation/orient_normals.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/read_points.h>
#include <CGAL/IO/write_points.h>
#include <CGAL/property_map.h>

#include <iostream>
#include <utility>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point_3;
typedef Kernel::Vector_3 Vector_3;
typedef std::pair<Point_3, Vector_3> Point_with_normal;
typedef CGAL::First_of_pair_property_map<Point_with_normal> Point_map;
typedef CGAL::Second_of_pair_property_map<Point_with_normal> Normal_map;

int main(int argc, char** argv)
{
  if (argc != 3) {
    std::cerr << "usage: orient_pairs IN.xyz OUT.xyz\n";
    return 2;
  }
  std::vector<Point_with_normal> points;
  if (!CGAL::IO::read_points(argv[1], std::back_inserter(points),
                             CGAL::parameters::point_map(Point_map()).normal_map(Normal_map()))) {
    std::cerr << "cannot read " << argv[1] << "\n";
    return 1;
  }

  namespace NP = Normal_orientation::parameters;
  const Normal_orientation::Orientation_result result = Normal_orientation::orient_normals(
    points, NP::point_map(Point_map())
              .normal_map(Normal_map())
              .number_of_neighbors(18)                                // optional, like every name below
              .flip_criterion(Normal_orientation::Hoppe_criterion())); // Xie_criterion() for clean creases

  std::cout << result.number_of_points << " points, " << result.number_of_components << " component(s), energy "
            << result.energy_before << " -> " << result.energy_after << ", " << result.number_of_flipped
            << " normals flipped in " << result.seconds.total << " s\n";
  if (!CGAL::IO::write_points(argv[2], points, CGAL::parameters::point_map(Point_map()).normal_map(Normal_map()).stream_precision(17))) {
    std::cerr << "cannot write " << argv[2] << "\n";
    return 1;
  }
  return 0;
}
