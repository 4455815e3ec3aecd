// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// Writing your own policies: a flip criterion (a model of FlipCriterion)
// and a solver (a model of OrientationSolver), plugged into orient_normals()
// with the named parameters flip_criterion and solver.  The energies of the
// custom solver are compared with the default solver's on the same edge
// weights, and the orientations with the package's defaults.
//
// usage: custom_policies IN(.xyz|.ply, with normals)

#include <Normal_orientation/orient_normals.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/read_points.h>
#include <CGAL/property_map.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <iostream>
#include <queue>
#include <tuple>
#include <utility>
#include <vector>

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef std::pair<Kernel::Point_3, Kernel::Vector_3> Point_with_normal;
typedef CGAL::First_of_pair_property_map<Point_with_normal> Point_map;
typedef CGAL::Second_of_pair_property_map<Point_with_normal> Normal_map;
namespace NO = Normal_orientation;
namespace NP = Normal_orientation::parameters;

// Hoppe's criterion whose confidence fades faster with the angle between
// the normals: phi = c |c|, c the cosine.  Symmetric, unchanged when both
// normals flip, odd when one does, 0 for a zero normal: a FlipCriterion.
struct Squared_cosine_criterion
{
  template <typename Point_3, typename Vector_3>
  double operator()(const Point_3&, const Vector_3& n_i, const Point_3&, const Vector_3& n_j) const
  {
    const double l2 = CGAL::to_double(n_i.squared_length()) * CGAL::to_double(n_j.squared_length());
    if (!(l2 > 0.0))
      return 0.0;
    const double c = std::clamp(CGAL::to_double(n_i * n_j) / std::sqrt(l2), -1.0, 1.0);
    return c * std::abs(c);
  }
  static const char* name() { return "squared-cosine"; } // reported in Orientation_result::criterion
};

// Hoppe et al.'s (1992) propagation: from the first vertex of each
// component, always cross the strongest edge (largest |w|) leaving the
// labelled vertices (Prim's maximum spanning tree), then a few sweeps of
// greedy single-vertex flips.  An OrientationSolver without the overload
// for unary terms: it cannot be used with constraints or priors.
struct Best_first_solver
{
  unsigned int sweeps = 2;
  static const char* name() { return "best-first"; }

  template <typename Graph, typename WeightMap, typename LabelMap>
  NO::Solver_report solve(const Graph& g, WeightMap weight, LabelMap labels) const
  {
    const auto index = get(boost::vertex_index, g);
    const std::size_t n = num_vertices(g);
    std::vector<std::vector<std::pair<std::size_t, double>>> adjacent(n); // (neighbour, w)
    for (auto e : CGAL::make_range(edges(g))) {
      const std::size_t i = get(index, source(e, g)), j = get(index, target(e, g));
      adjacent[i].emplace_back(j, double(get(weight, e)));
      adjacent[j].emplace_back(i, double(get(weight, e)));
    }
    std::vector<NO::Label> label(n, 0); // 0: not reached yet
    std::priority_queue<std::tuple<double, std::size_t, int>> queue; // (|w|, vertex, its label)
    for (std::size_t seed = 0; seed < n; ++seed) {
      for (queue.emplace(0.0, seed, 1); !queue.empty();) {
        const auto [strength, v, l] = queue.top();
        queue.pop();
        if (label[v] != 0)
          continue;
        label[v] = NO::Label(l);
        for (const auto& [u, w] : adjacent[v])
          if (label[u] == 0 && w != 0.0)
            queue.emplace(std::abs(w), u, w > 0.0 ? l : -l); // the label that meets the edge's wish
      }
    }
    NO::Solver_report report;
    for (unsigned int s = 0; s < sweeps; ++s) // flip a vertex when its edges weigh more against its label
      for (std::size_t v = 0; v < n; ++v) {
        double support = 0.0;
        for (const auto& [u, w] : adjacent[v])
          support += w * label[v] * label[u];
        if (support < 0.0) {
          label[v] = NO::Label(-label[v]);
          ++report.iterations;
        }
      }
    for (auto v : CGAL::make_range(vertices(g)))
      put(labels, v, label[get(index, v)]);
    const auto label_map = boost::make_iterator_property_map(label.begin(), index);
    report.energy = NO::energy(g, weight, label_map);
    for (auto e : CGAL::make_range(edges(g)))
      report.frustrated_edges += NO::edge_energy(get(weight, e), get(label_map, source(e, g)),
                                                 get(label_map, target(e, g))) > 0.0;
    return report;
  }
};

int main(int argc, char** argv)
{
  if (argc != 2) {
    std::cerr << "usage: custom_policies IN(.xyz|.ply, with normals)\n";
    return 2;
  }
  std::vector<Point_with_normal> input;
  const auto maps = NP::point_map(Point_map()).normal_map(Normal_map());
  if (!CGAL::IO::read_points(argv[1], std::back_inserter(input), maps) || input.empty() ||
      std::all_of(input.begin(), input.end(), [](const auto& p) { return p.second == CGAL::NULL_VECTOR; })) {
    std::cerr << "custom_policies: cannot read points with normals from " << argv[1] << "\n";
    return 1;
  }
  // Three runs on copies of the input: the defaults; both custom policies;
  // the custom criterion with the default solver (same weights as the 2nd).
  std::vector<Point_with_normal> defaults = input, custom = input, mixed = input;
  const auto print = [](const NO::Orientation_result& r) {
    std::printf("%-14s + %-10s: energy %10.4f -> %8.4f, %6zu frustrated edges, %.3f s\n", r.criterion.c_str(),
                r.solver.c_str(), r.energy_before, r.energy_after, r.frustrated_edges, r.seconds.total);
    return r.energy_after;
  };
  double e_custom = 0.0, e_default = 0.0;
  try {
    print(NO::orient_normals(defaults, maps));
    e_custom =
      print(NO::orient_normals(custom, maps.flip_criterion(Squared_cosine_criterion()).solver(Best_first_solver())));
    e_default = print(NO::orient_normals(mixed, maps.flip_criterion(Squared_cosine_criterion())));
  } catch (const std::exception& e) { // a non-finite coordinate or normal in IN
    std::cerr << "custom_policies: " << e.what() << "\n";
    return 1;
  }
  std::printf("best-first energy / default solver energy: %.3f\n", e_default > 0 ? e_custom / e_default : 1.0);

  std::size_t agree = 0;
  for (std::size_t i = 0; i < input.size(); ++i)
    agree += custom[i].second * defaults[i].second > 0 || custom[i].second == CGAL::NULL_VECTOR;
  std::printf("custom policies and defaults agree on %.2f%% of the normals\n", 100.0 * agree / input.size());
  return 0;
}
