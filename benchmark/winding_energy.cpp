// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// winding_energy ORIENTED.xyz TRUTH.gt.xyz [--stride S] [--mesh MESH.off] [--json]
//
// Tells whether the global stage's winding energy or its search is wrong on a cloud: the
// energy E = sum_j a_j (w(p_j) - 1/2)^2 of `decide_patch_signs()` on a subsample (every S-th
// point of the file), per unit of area, once with the signs of the oriented cloud and once with
// the signs of the truth (the oriented normals' directions either way). Where the truth's
// energy is the lower one, a better search would find it; where it is the higher one, the
// energy itself prefers the wrong signs at that sampling. The default S is that of the
// drivers' dense samples (`global_samples(n, true)`); the subsample is the file's order, not
// the drivers' spatial order, so the figures are close to, not equal to, the stage's. With the
// mesh the cloud was sampled from, it also prints how much of the mesh's area the samples'
// estimated areas (`estimate_point_areas()`, capped as in the stage) add up to: where they fall
// short, w at the samples falls short of 1/2 whatever the signs.
#include "Mesh_sampler.h"
#include "Xyz_io.h"

#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Winding_number_field.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
using Normal_orientation::benchmark::Xyz_row;

/// Prints the usage message to `out`.
void print_usage(std::FILE* out)
{
  std::fprintf(out,
               "usage: winding_energy ORIENTED.xyz TRUTH.gt.xyz [--stride S] [--mesh MESH.off] [--json]\n"
               "  Both files: x y z nx ny nz per line, the same points in the same order (the\n"
               "  truth as make_cloud writes it). On every S-th point (default: the drivers'\n"
               "  dense samples, ceil(n / global_samples(n, true))), prints the winding energy\n"
               "  of the global stage per unit of area with the oriented signs and with the\n"
               "  true signs, and the samples whose sign is wrong. --mesh: also the samples'\n"
               "  estimated areas as a share of the mesh's area. --json: one JSON line.\n"
               "  Exit status: 0 done, 1 unreadable or mismatched files, 2 bad usage.\n");
}

/// E / A of the samples with `normals` (areas `areas`, summing to `total`).
double energy_per_area(const std::vector<Kernel::Point_3>& points, const std::vector<Kernel::Vector_3>& normals,
                       const std::vector<double>& areas, double total)
{
  Normal_orientation::Winding_patch_signs<Kernel> field;
  field.build(points, normals, areas);
  return total > 0.0 ? field.energy() / total : 0.0;
}

} // namespace

/// Entry point: see print_usage().
int main(int argc, char** argv)
{
  long long stride = 0;
  std::string mesh_path;
  auto option = [&](const std::string& arg, int& i) {
    if(arg == "--mesh" && i + 1 < argc)
    {
      mesh_path = argv[++i];
      return true;
    }
    if(arg != "--stride" || i + 1 >= argc)
      return false;
    char* end = nullptr;
    stride = std::strtoll(argv[++i], &end, 10);
    if(end == argv[i] || *end != '\0' || stride < 1)
    {
      std::fprintf(stderr, "winding_energy: --stride needs a whole number >= 1, not '%s'\n", argv[i]);
      std::exit(2);
    }
    return true;
  };
  std::vector<Xyz_row> oriented, truth;
  const bool json = Normal_orientation::benchmark::read_oriented_and_truth_command(
                      argc, argv, "winding_energy", print_usage, option, oriented, truth)
                      .json;

  const std::size_t n = truth.size();
  if(stride == 0)
  {
    const std::size_t m = std::size_t(Normal_orientation::global_samples(n, true));
    stride = (long long)((n + m - 1) / m);
  }
  std::vector<Kernel::Point_3> points;
  std::vector<Kernel::Vector_3> ours, true_signs;
  std::size_t wrong = 0;
  for(std::size_t i = 0; i < n; i += std::size_t(stride))
  {
    const Kernel::Vector_3 v(oriented[i][3], oriented[i][4], oriented[i][5]);
    const double dot = v.x() * truth[i][3] + v.y() * truth[i][4] + v.z() * truth[i][5];
    if(!std::isfinite(dot) || v == CGAL::NULL_VECTOR)
    {
      std::fprintf(stderr, "winding_energy: point %zu (counted from 0) has a zero or non-finite normal\n", i);
      return EXIT_FAILURE;
    }
    points.emplace_back(oriented[i][0], oriented[i][1], oriented[i][2]);
    ours.push_back(v);
    true_signs.push_back(dot > 0.0 ? v : -v);
    wrong += dot > 0.0 ? 0 : 1;
  }
  std::vector<double> areas = Normal_orientation::estimate_point_areas(points, ours);
  Normal_orientation::internal::cap_areas(areas);
  double total = 0.0;
  for(double a : areas)
    total += a;
  double area_share = -1.0; // (no mesh)
  if(!mesh_path.empty())
  {
    try
    {
      area_share = total / Normal_orientation::benchmark::Mesh_sampler(mesh_path).area();
    }
    catch(const std::exception& e)
    {
      std::fprintf(stderr, "winding_energy: %s\n", e.what());
      return EXIT_FAILURE;
    }
  }
  const double e_ours = energy_per_area(points, ours, areas, total);
  const double e_truth = energy_per_area(points, true_signs, areas, total);
  if(json)
  {
    std::printf("{\"samples\":%zu,\"stride\":%lld,\"wrong_samples\":%zu,\"energy_oriented\":%.9g,"
                "\"energy_truth\":%.9g",
                points.size(), stride, wrong, e_ours, e_truth);
    if(area_share >= 0.0)
      std::printf(",\"area_share\":%.6g", area_share);
    std::printf("}\n");
    return EXIT_SUCCESS;
  }
  if(area_share >= 0.0)
    std::printf("areas: %.4f of the mesh's\n", area_share);
    std::printf("samples %zu (stride %lld), wrong %zu; E/A with the oriented signs %.6f, with the true "
                "signs %.6f: %s\n",
                points.size(), stride, wrong, e_ours, e_truth,
                e_truth < e_ours ? "the truth is lower (the search misses it)"
                                 : "the truth is not lower (the energy prefers these signs)");
  return EXIT_SUCCESS;
}
