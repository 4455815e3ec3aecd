// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// Orienting a CGAL::Point_set_3: the point set is read with CGAL's reader,
// gets normals from CGAL's jet fitting when the file has none, is oriented
// in place by orient_normals() through the point set's own property maps
// (point_set.parameters(), extended with the package's named parameters:
// number_of_neighbors, solver, and CGAL's callback for the progress), and
// is written back with CGAL's writer.
//
// usage: orient_point_set IN(.ply|.xyz|.off|...) OUT(.ply|.xyz) [--k N] [--solver qpbo-i|mst|lsa-tr]

#include <Normal_orientation/orient_normals.h>
#include <Normal_orientation/solvers/Lsa_tr_solver.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Point_set_3.h>
#include <CGAL/Point_set_3/IO.h>
#include <CGAL/jet_estimate_normals.h>

#include <cstdio>
#include <cstdlib>
#include <exception>
#include <functional>
#include <iostream>
#include <string>

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef CGAL::Point_set_3<Kernel::Point_3, Kernel::Vector_3> Point_set;
namespace NO = Normal_orientation;
namespace NP = Normal_orientation::parameters;

int main(int argc, char** argv)
{
  const char* usage =
    "usage: orient_point_set IN(.ply|.xyz|.off) OUT(.ply|.xyz) [--k N] [--solver qpbo-i|mst|lsa-tr]\n";
  std::string input, output, solver = "qpbo-i";
  unsigned int k = NO::default_number_of_neighbors;
  for (int a = 1; a < argc; ++a) {
    const std::string arg = argv[a];
    if (arg == "--k" && a + 1 < argc) {
      char* end = nullptr;
      const long v = std::strtol(argv[++a], &end, 10);
      if (*end != '\0' || v < 1 || v > 100000) {
        std::cerr << "orient_point_set: --k needs an integer from 1 to 100000\n" << usage;
        return 2;
      }
      k = (unsigned int)v;
    } else if (arg == "--solver" && a + 1 < argc) {
      solver = argv[++a];
      if (solver != "qpbo-i" && solver != "mst" && solver != "lsa-tr") {
        std::cerr << "orient_point_set: unknown solver '" << solver << "'\n" << usage;
        return 2;
      }
    } else if (arg.size() > 1 && arg[0] == '-') {
      std::cerr << "orient_point_set: unknown option '" << arg << "'\n" << usage;
      return 2;
    } else if (input.empty()) {
      input = arg;
    } else if (output.empty()) {
      output = arg;
    } else {
      std::cerr << usage;
      return 2;
    }
  }
  if (output.empty()) {
    std::cerr << usage;
    return 2;
  }

  try {
    Point_set points;
    if (!CGAL::IO::read_point_set(input, points) || points.empty()) {
      std::cerr << "orient_point_set: cannot read any point from " << input << "\n";
      return 1;
    }
    // Unoriented normals first, when the file has none.
    const bool estimated = !points.has_normal_map();
    if (estimated) {
      points.add_normal_map();
      CGAL::jet_estimate_normals<CGAL::Parallel_if_available_tag>(points, 18, points.parameters());
    }

    // The progress, in [0, 1], on the standard error; returning false would
    // stop the run and leave every normal as it was.
    int shown = -1;
    const std::function<bool(double)> progress = [&shown](double p) {
      if (int(p * 10) > shown)
        std::cerr << "\rorienting: " << (shown = int(p * 10)) * 10 << "%" << (p >= 1.0 ? "\n" : "") << std::flush;
      return true;
    };
    // The point set's own maps (points.parameters()), extended with the
    // package's names; the solver is a type, so each choice is a call.
    const auto orient = [&](const auto& chosen_solver) {
      return NO::orient_normals(points, NP::extend(points.parameters())
                                          .number_of_neighbors(k)
                                          .solver(chosen_solver)
                                          .callback(progress));
    };
    const NO::Orientation_result r = solver == "mst"      ? orient(NO::Mst_solver())
                                     : solver == "lsa-tr" ? orient(NO::Lsa_tr_solver())
                                                          : orient(NO::Qpbo_i_solver());

    std::printf("%zu points (%s normals), k = %u, r = %.6g%s, %zu edges\n", r.number_of_points,
                estimated ? "estimated" : "given", r.number_of_neighbors, r.neighbor_radius,
                r.radius_estimated ? " (estimated)" : "", r.number_of_edges);
    std::printf("solver %s: energy %.6g -> %.6g, %zu frustrated edges, %zu segments\n", r.solver.c_str(),
                r.energy_before, r.energy_after, r.frustrated_edges, r.number_of_segments);
    std::printf("%zu component(s) (sign: %s), %zu normals flipped, %zu zero normals, %.3f s\n",
                r.number_of_components, r.component_sign.c_str(), r.number_of_flipped, r.number_of_zero_normals,
                r.seconds.total);

    if (!CGAL::IO::write_point_set(output, points, CGAL::parameters::stream_precision(17))) {
      std::cerr << "orient_point_set: cannot write " << output << "\n";
      return 1;
    }
  } catch (const std::exception& e) {
    std::cerr << "orient_point_set: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
