// SPDX-License-Identifier: GPL-3.0-or-later
// cgal_mst_orient IN.xyz OUT.xyz [--k K] [--quiet]
//
// The peer of the benchmark: CGAL::mst_orient_normals used the way a CGAL user would use it
// (CGAL::IO::read_XYZ, a std::vector of tuples with property maps, default parameters,
// CGAL::IO::write_XYZ). The output keeps the input point order; points CGAL leaves
// unoriented are written with their input normals.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/read_xyz_points.h>
#include <CGAL/IO/write_xyz_points.h>
#include <CGAL/mst_orient_normals.h>
#include <CGAL/property_map.h>

#include <chrono>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point_3 = Kernel::Point_3;
using Vector_3 = Kernel::Vector_3;
/// Point, normal, and index in the input file.
using Point_with_normal = std::tuple<Point_3, Vector_3, std::size_t>;
using Point_map = CGAL::Nth_of_tuple_property_map<0, Point_with_normal>;
using Normal_map = CGAL::Nth_of_tuple_property_map<1, Point_with_normal>;

/// Prints the usage message to `out`.
void print_usage(std::FILE* out)
{
  std::fprintf(out,
               "usage: cgal_mst_orient [--k K] [--quiet] IN.xyz OUT.xyz\n"
               "  Orients the normals of IN (x y z nx ny nz) with CGAL::mst_orient_normals (K\n"
               "  neighbours, default 18, other parameters at their defaults) and writes OUT in\n"
               "  the input point order; unoriented points keep their input normals.\n"
               "  Prints the time spent in mst_orient_normals and the number of unoriented\n"
               "  points to stderr (unless --quiet).\n");
}

/// Returns the seconds elapsed since `start`.
double seconds_since(std::chrono::steady_clock::time_point start)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

/// Entry point: see print_usage().
int main(int argc, char** argv)
{
  unsigned int k = 18;
  bool quiet = false;
  std::vector<std::string> positional;
  for(int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    if(arg == "-h" || arg == "--help")
    {
      print_usage(stdout);
      return EXIT_SUCCESS;
    }
    else if(arg == "--quiet")
      quiet = true;
    else if(arg == "--k" && i + 1 < argc)
    {
      char* end = nullptr;
      const unsigned long value = std::strtoul(argv[++i], &end, 10);
      if(end == argv[i] || *end != '\0' || value < 2 || value > 10000)
      {
        std::fprintf(stderr, "cgal_mst_orient: invalid --k '%s' (2..10000)\n", argv[i]);
        return EXIT_FAILURE;
      }
      k = static_cast<unsigned int>(value);
    }
    else if(arg.size() > 1 && arg[0] == '-')
    {
      std::fprintf(stderr, "cgal_mst_orient: unknown or incomplete option '%s'\n", arg.c_str());
      print_usage(stderr);
      return EXIT_FAILURE;
    }
    else
      positional.push_back(arg);
  }
  if(positional.size() != 2)
  {
    print_usage(stderr);
    return EXIT_FAILURE;
  }

  const auto np = CGAL::parameters::point_map(Point_map()).normal_map(Normal_map());

  // Read.
  const auto read_start = std::chrono::steady_clock::now();
  std::vector<Point_with_normal> points;
  if(!CGAL::IO::read_XYZ<Point_with_normal>(positional[0], std::back_inserter(points), np))
  {
    std::fprintf(stderr, "cgal_mst_orient: cannot read '%s'\n", positional[0].c_str());
    return EXIT_FAILURE;
  }
  if(points.empty())
  {
    std::fprintf(stderr, "cgal_mst_orient: '%s' holds no point\n", positional[0].c_str());
    return EXIT_FAILURE;
  }
  for(std::size_t i = 0; i < points.size(); ++i)
    std::get<2>(points[i]) = i;
  const double read_seconds = seconds_since(read_start);

  // Orient (mst_orient_normals reorders the points: oriented ones first).
  const auto orient_start = std::chrono::steady_clock::now();
  const std::vector<Point_with_normal>::iterator first_unoriented = CGAL::mst_orient_normals(points, k, np);
  const double orient_seconds = seconds_since(orient_start);
  const std::size_t unoriented = static_cast<std::size_t>(std::distance(first_unoriented, points.end()));

  // Write in the input order.
  const auto write_start = std::chrono::steady_clock::now();
  std::vector<Point_with_normal> in_input_order(points.size());
  for(Point_with_normal& p : points)
    in_input_order[std::get<2>(p)] = std::move(p);
  if(!CGAL::IO::write_XYZ(positional[1], in_input_order, np.stream_precision(9)))
  {
    std::fprintf(stderr, "cgal_mst_orient: cannot write '%s'\n", positional[1].c_str());
    return EXIT_FAILURE;
  }
  const double write_seconds = seconds_since(write_start);

  if(!quiet)
    std::fprintf(stderr,
                 "cgal_mst_orient: %zu points, k = %u\n"
                 "  mst_orient_normals: %.3f s\n"
                 "  unoriented points:  %zu\n"
                 "  (read_XYZ %.3f s, write_XYZ %.3f s)\n",
                 points.size(), k, orient_seconds, unoriented, read_seconds, write_seconds);
  return EXIT_SUCCESS;
}
