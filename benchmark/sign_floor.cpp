// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// sign_floor CLOUD.xyz TRUTH.gt.xyz [--k K1,K2,...] [--json]
//
// A floor under the wrong count of any method that only chooses signs: every normal of CLOUD
// takes the sign that agrees with a coarse normal at its point, the PCA normal of its K nearest
// neighbours (CGAL::pca_estimate_normals over CLOUD's positions), and that coarse normal is
// oriented by the truth, so that no region is inward. What stays wrong is what the input
// normals' directions and a coarse estimate at that scale cannot tell apart: normals nearly
// perpendicular to the surface, where the noise is wider than the spacing. The counts are those
// of score_normals (wrong: dot with the truth <= 0; clear: the line within 60 degrees of the
// truth's).
#include "Normal_score.h"
#include "Xyz_io.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/pca_estimate_normals.h>
#include <CGAL/property_map.h>
#include <CGAL/tags.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point_3;
typedef Kernel::Vector_3 Vector_3;
typedef std::pair<Point_3, Vector_3> Point_with_normal;
using Normal_orientation::benchmark::Normal_score;
using Normal_orientation::benchmark::Xyz_row;
using Normal_orientation::benchmark::percent;

/// Prints the usage message to `out`.
void print_usage(std::FILE* out)
{
  std::fprintf(out,
               "usage: sign_floor CLOUD.xyz TRUTH.gt.xyz [--k K1,K2,...] [--json]\n"
               "  Both files: x y z nx ny nz per line, the same points in the same order (CLOUD\n"
               "  as make_cloud writes it, with its normals' signs in any state). For each K\n"
               "  (default 24,48,96), every normal takes the sign of the PCA normal of its K\n"
               "  nearest neighbours oriented by the truth; prints the wrong normals that remain,\n"
               "  over all normals and over the clear ones (as score_normals counts them): a\n"
               "  floor for methods that only choose signs. --json: one JSON line per K.\n"
               "  Exit status: 0 done, 1 unreadable or mismatched files, 2 bad usage.\n");
}

/// The scores after the signs of the coarse normals of `k` neighbours.
Normal_score floor_at(const std::vector<Xyz_row>& cloud, const std::vector<Xyz_row>& truth, unsigned int k)
{
  std::vector<Point_with_normal> points(cloud.size());
  for(std::size_t i = 0; i < cloud.size(); ++i)
    points[i].first = Point_3(cloud[i][0], cloud[i][1], cloud[i][2]);
  CGAL::pca_estimate_normals<CGAL::Parallel_if_available_tag>(
    points, k,
    CGAL::parameters::point_map(CGAL::First_of_pair_property_map<Point_with_normal>())
      .normal_map(CGAL::Second_of_pair_property_map<Point_with_normal>()));
  Normal_score f;
  for(std::size_t i = 0; i < cloud.size(); ++i)
  {
    const double* n = &cloud[i][3];
    const double* g = &truth[i][3];
    const Vector_3& c = points[i].second;
    const double cg = c.x() * g[0] + c.y() * g[1] + c.z() * g[2];
    const double nc = (n[0] * c.x() + n[1] * c.y() + n[2] * c.z()) * (cg < 0.0 ? -1.0 : 1.0);
    const double s = nc < 0.0 ? -1.0 : 1.0;
    const double signed_normal[3] = {s * n[0], s * n[1], s * n[2]};
    f.add(signed_normal, g);
  }
  return f;
}

/// Parses "K1,K2,..." (each at least 3) into `ks`; false when malformed.
bool parse_ks(const std::string& text, std::vector<unsigned int>& ks)
{
  ks.clear();
  const char* s = text.c_str();
  while(*s)
  {
    char* end = nullptr;
    const unsigned long k = std::strtoul(s, &end, 10);
    if(end == s || k < 3 || k > 100000)
      return false;
    ks.push_back(static_cast<unsigned int>(k));
    if(*end == ',')
      ++end;
    else if(*end != '\0')
      return false;
    s = end;
  }
  return !ks.empty();
}

} // namespace

/// Entry point: see print_usage().
int main(int argc, char** argv)
{
  std::vector<unsigned int> ks = {24, 48, 96};
  auto option = [&](const std::string& arg, int& i) {
    if(arg != "--k")
      return false;
    if(i + 1 >= argc || !parse_ks(argv[++i], ks))
    {
      std::fprintf(stderr, "sign_floor: --k takes a list of neighbour counts of at least 3, like 24,48\n");
      std::exit(2);
    }
    return true;
  };
  std::vector<Xyz_row> cloud, truth;
  const Normal_orientation::benchmark::Oriented_and_truth_command command =
    Normal_orientation::benchmark::read_oriented_and_truth_command(argc, argv, "sign_floor", print_usage, option,
                                                                   cloud, truth);
  const bool json = command.json;
  if(cloud.size() < 3)
  {
    std::fprintf(stderr, "sign_floor: '%s' has fewer than 3 points\n", command.oriented.c_str());
    return EXIT_FAILURE;
  }
  for(unsigned int k : ks)
  {
    const unsigned int kk = static_cast<unsigned int>(std::min<std::size_t>(k, cloud.size()));
    const Normal_score f = floor_at(cloud, truth, kk);
    if(json)
      std::printf("{\"k\":%u,\"points\":%zu,\"wrong\":%zu,\"wrong_percent\":%.4f,\"clear\":%zu,\"clear_wrong\":%zu}\n",
                  kk, cloud.size(), f.wrong, percent(f.wrong, cloud.size()), f.clear, f.clear_wrong);
    else
      std::printf("k %u points %zu wrong %zu (%.2f%%) clear %zu clear_wrong %zu (%.2f%%)\n", kk, cloud.size(),
                  f.wrong, percent(f.wrong, cloud.size()), f.clear, f.clear_wrong, percent(f.clear_wrong, f.clear));
  }
  return EXIT_SUCCESS;
}
