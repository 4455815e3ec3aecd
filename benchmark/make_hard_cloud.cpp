// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// make_hard_cloud SHAPE N OUT_PREFIX [--noise F] [--seed S] [--pca-k K] [--true-normals]
// make_hard_cloud --list
//
// Samples N points on one of the synthetic shapes of test/Hard_shapes.h (the failure classes
// of issue 15) and writes OUT_PREFIX.xyz (positions and unoriented normals with random signs)
// and OUT_PREFIX.gt.xyz (positions and true normals), in the format of make_cloud.
#include "Mesh_sampler.h"

#include "Hard_shapes.h"

#include <CGAL/pca_estimate_normals.h>
#include <CGAL/property_map.h>
#include <CGAL/tags.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace {

using namespace Normal_orientation::benchmark;

/// Prints the usage message to `out`.
void print_usage(std::FILE* out)
{
  std::fprintf(out,
               "usage: make_hard_cloud SHAPE N OUT_PREFIX [--noise F] [--seed S] [--pca-k K] [--true-normals]\n"
               "       make_hard_cloud --list\n"
               "  Samples N points area-uniformly on SHAPE (see --list and test/Hard_shapes.h), adds\n"
               "  Gaussian noise of standard deviation F * bbox diagonal per coordinate (default 0),\n"
               "  estimates unoriented normals with CGAL::pca_estimate_normals (K neighbours, default 18),\n"
               "  or takes the true normals with --true-normals, and gives them random signs (seed S,\n"
               "  default 1). Writes OUT_PREFIX.xyz (x y z nx ny nz) and OUT_PREFIX.gt.xyz (x y z gx gy gz,\n"
               "  true normals: outward, or towards the sensor's side on open scans), same point order.\n");
}

/// Parses a non-negative integer; returns false if `text` is not one.
bool parse_unsigned(const char* text, std::uint64_t& value)
{
  char* end = nullptr;
  if(text[0] == '-')
    return false;
  value = std::strtoull(text, &end, 10);
  return end != text && *end == '\0';
}

/// Parses a finite non-negative double; returns false if `text` is not one.
bool parse_non_negative(const char* text, double& value)
{
  char* end = nullptr;
  value = std::strtod(text, &end);
  return end != text && *end == '\0' && value >= 0.0 && value < 1e300;
}

/// Returns the bounding-box diagonal of `points`.
double bbox_diagonal(const std::vector<Point_3>& points)
{
  double lo[3], hi[3];
  for(int d = 0; d < 3; ++d)
  {
    lo[d] = std::numeric_limits<double>::max();
    hi[d] = -std::numeric_limits<double>::max();
  }
  for(const Point_3& p : points)
    for(int d = 0; d < 3; ++d)
    {
      lo[d] = (std::min)(lo[d], p[d]);
      hi[d] = (std::max)(hi[d], p[d]);
    }
  return std::sqrt(CGAL::square(hi[0] - lo[0]) + CGAL::square(hi[1] - lo[1]) + CGAL::square(hi[2] - lo[2]));
}

/**
 * \brief Generates the cloud of `shape`, as Mesh_sampler::sample() does on a mesh: samples,
 * Gaussian noise, unoriented normals (PCA, or the truth when `true_normals`), random signs.
 *
 * The sampling, noise and sign streams are seeded independently from `options.seed`.
 * \throws std::invalid_argument on an unknown shape.
 */
Sampled_cloud make_hard_cloud(const std::string& shape, const Sampling_options& options, bool true_normals)
{
  const std::size_t n = options.number_of_points;
  std::mt19937_64 sampling_rng(mix_seed(options.seed));
  const std::vector<Normal_orientation::hard_shapes::Sample> samples =
    Normal_orientation::hard_shapes::hard_shape(shape, n, sampling_rng);

  Sampled_cloud cloud;
  cloud.points.reserve(n);
  cloud.true_normals.reserve(n);
  for(const auto& s : samples)
  {
    cloud.points.push_back(s.p);
    cloud.true_normals.push_back(s.n);
  }
  cloud.bbox_diagonal = bbox_diagonal(cloud.points);
  cloud.noise_sigma = options.noise * cloud.bbox_diagonal;

  if(cloud.noise_sigma > 0.0)
  {
    std::mt19937_64 noise_rng(mix_seed(options.seed ^ 0x6E6F697365ull)); // "noise", as make_cloud
    Gaussian_generator gaussian(noise_rng);
    for(Point_3& p : cloud.points)
    {
      const double dx = gaussian(), dy = gaussian(), dz = gaussian();
      p = Point_3(p.x() + cloud.noise_sigma * dx, p.y() + cloud.noise_sigma * dy, p.z() + cloud.noise_sigma * dz);
    }
  }

  using Point_with_normal = std::pair<Point_3, Vector_3>;
  std::vector<Point_with_normal> with_normals;
  with_normals.reserve(n);
  for(std::size_t i = 0; i < n; ++i)
    with_normals.emplace_back(cloud.points[i], cloud.true_normals[i]);
  if(!true_normals && n > options.pca_neighbors) // else (too few points for PCA): the truth
    CGAL::pca_estimate_normals<CGAL::Parallel_if_available_tag>(
      with_normals, options.pca_neighbors,
      CGAL::parameters::point_map(CGAL::First_of_pair_property_map<Point_with_normal>())
        .normal_map(CGAL::Second_of_pair_property_map<Point_with_normal>()));

  std::mt19937_64 sign_rng(mix_seed(options.seed ^ 0x7369676E73ull)); // "signs", as make_cloud
  cloud.normals.reserve(n);
  for(std::size_t i = 0; i < n; ++i)
  {
    const Vector_3& v = with_normals[i].second;
    cloud.normals.push_back((sign_rng() >> 63) != 0 ? -v : v);
  }
  return cloud;
}

} // namespace

/// Entry point: see print_usage().
int main(int argc, char** argv)
{
  std::string positional[3];
  int number_of_positional = 0;
  Sampling_options options;
  bool true_normals = false;
  for(int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    std::uint64_t u = 0;
    if(arg == "-h" || arg == "--help")
    {
      print_usage(stdout);
      return EXIT_SUCCESS;
    }
    else if(arg == "--list")
    {
      for(const std::string& name : Normal_orientation::hard_shapes::hard_shape_names())
        std::printf("%s\n", name.c_str());
      return EXIT_SUCCESS;
    }
    else if(arg == "--true-normals")
      true_normals = true;
    else if(arg == "--noise" && i + 1 < argc)
    {
      if(!parse_non_negative(argv[++i], options.noise))
      {
        std::fprintf(stderr, "make_hard_cloud: invalid --noise '%s'\n", argv[i]);
        return EXIT_FAILURE;
      }
    }
    else if(arg == "--seed" && i + 1 < argc)
    {
      if(!parse_unsigned(argv[++i], options.seed))
      {
        std::fprintf(stderr, "make_hard_cloud: invalid --seed '%s'\n", argv[i]);
        return EXIT_FAILURE;
      }
    }
    else if(arg == "--pca-k" && i + 1 < argc)
    {
      if(!parse_unsigned(argv[++i], u) || u < 2 || u > 1000)
      {
        std::fprintf(stderr, "make_hard_cloud: invalid --pca-k '%s' (2..1000)\n", argv[i]);
        return EXIT_FAILURE;
      }
      options.pca_neighbors = static_cast<unsigned int>(u);
    }
    else if(arg.size() > 1 && arg[0] == '-')
    {
      std::fprintf(stderr, "make_hard_cloud: unknown or incomplete option '%s'\n", arg.c_str());
      print_usage(stderr);
      return EXIT_FAILURE;
    }
    else if(number_of_positional < 3)
      positional[number_of_positional++] = arg;
    else
    {
      print_usage(stderr);
      return EXIT_FAILURE;
    }
  }
  std::uint64_t n = 0;
  if(number_of_positional != 3 || !parse_unsigned(positional[1].c_str(), n) || n == 0)
  {
    print_usage(stderr);
    return EXIT_FAILURE;
  }
  options.number_of_points = static_cast<std::size_t>(n);

  try
  {
    const auto start = std::chrono::steady_clock::now();
    const Sampled_cloud cloud = make_hard_cloud(positional[0], options, true_normals);
    write_cloud(cloud, positional[2]);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::fprintf(stderr,
                 "make_hard_cloud: %zu points on %s (bbox diagonal %g), noise sigma %g, %s normals, seed %llu, "
                 "%.2f s\n  wrote %s.xyz and %s.gt.xyz\n",
                 cloud.points.size(), positional[0].c_str(), cloud.bbox_diagonal, cloud.noise_sigma,
                 true_normals ? "true" : "PCA", static_cast<unsigned long long>(options.seed), seconds,
                 positional[2].c_str(), positional[2].c_str());
  }
  catch(const std::exception& e)
  {
    std::fprintf(stderr, "make_hard_cloud: %s\n", e.what());
    return EXIT_FAILURE;
  }
  return EXIT_SUCCESS;
}
