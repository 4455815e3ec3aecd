// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// The streaming pipeline over the user's own points: a CGAL::Point_set_3
// read from a file is sorted along x, handed to streaming_orient_normals()
// through the range adaptor (make_point_range_source, which checks the
// order as it reads), and the oriented normals are written back in place
// (make_normal_writer).  The same code streams any forward range of points
// with property maps; only the sweep window is held by the orientation.
//
// usage: stream_point_range IN(.ply|.xyz, with normals) OUT.ply

#include <Normal_orientation/streaming/Point_range.h>
#include <Normal_orientation/streaming_orient_normals.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>

#include <algorithm>
#include <exception>
#include <iostream>

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef CGAL::Point_set_3<Kernel::Point_3, Kernel::Vector_3> Point_set;
namespace NO = Normal_orientation;

int main(int argc, char** argv)
{
  if (argc != 3) {
    std::cerr << "usage: stream_point_range IN(.ply|.xyz, with normals) OUT.ply\n";
    return 2;
  }
  try {
    Point_set points;
    if (!CGAL::IO::read_point_set(argv[1], points) || !points.has_normal_map() || points.empty()) {
      std::cerr << "stream_point_range: cannot read points with normals from " << argv[1] << "\n";
      return 1;
    }
    // Sort the indices by x: the range is then presorted along x and the
    // pipeline skips its external sort.
    std::sort(points.begin(), points.end(), [&](Point_set::Index a, Point_set::Index b) {
      return points.point(a).x() < points.point(b).x();
    });

    auto source = NO::streaming::make_point_range_source(points, points.parameters(), 0 /* check x order */);
    auto sink = NO::streaming::make_normal_writer(points, points.parameters());
    const NO::Streaming_result result =
      NO::streaming_orient_normals(source, sink, NO::parameters::presorted_axis(NO::Presorted_axis::X));

    std::cout << result.number_of_points << " points, " << result.number_of_segments << " segments, "
              << result.number_of_components << " component(s), peak window " << result.peak_window
              << " points, " << result.seconds.total << " s\n";
    if (!CGAL::IO::write_point_set(argv[2], points, CGAL::parameters::stream_precision(17))) {
      std::cerr << "stream_point_range: cannot write " << argv[2] << "\n";
      return 1;
    }
  } catch (const std::exception& e) {
    std::cerr << "stream_point_range: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
