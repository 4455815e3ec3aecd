// SPDX-License-Identifier: GPL-3.0-or-later
// make_cloud MESH.off N OUT_PREFIX [--noise F] [--seed S] [--pca-k K]
//
// Samples N points on a closed, outward-oriented mesh and writes OUT_PREFIX.xyz (positions
// and PCA normals with random signs) and OUT_PREFIX.gt.xyz (positions and true normals).
#include "Mesh_sampler.h"

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

namespace {

/// Prints the usage message to `out`.
void print_usage(std::FILE* out)
{
  std::fprintf(out,
               "usage: make_cloud MESH.off N OUT_PREFIX [--noise F] [--seed S] [--pca-k K]\n"
               "  Samples N points area-uniformly on MESH (closed, outward-oriented), adds Gaussian\n"
               "  noise of standard deviation F * bbox diagonal per coordinate (default 0), estimates\n"
               "  unoriented normals with CGAL::pca_estimate_normals (K neighbours, default 18) and\n"
               "  gives them random signs (seed S, default 1). Writes OUT_PREFIX.xyz (x y z nx ny nz)\n"
               "  and OUT_PREFIX.gt.xyz (x y z gx gy gz, true outward normals), same point order.\n");
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

} // namespace

/// Entry point: see print_usage().
int main(int argc, char** argv)
{
  using namespace Normal_orientation::benchmark;

  std::string positional[3];
  int number_of_positional = 0;
  Sampling_options options;
  for(int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    std::uint64_t u = 0;
    if(arg == "-h" || arg == "--help")
    {
      print_usage(stdout);
      return EXIT_SUCCESS;
    }
    else if(arg == "--noise" && i + 1 < argc)
    {
      if(!parse_non_negative(argv[++i], options.noise))
      {
        std::fprintf(stderr, "make_cloud: invalid --noise '%s'\n", argv[i]);
        return EXIT_FAILURE;
      }
    }
    else if(arg == "--seed" && i + 1 < argc)
    {
      if(!parse_unsigned(argv[++i], options.seed))
      {
        std::fprintf(stderr, "make_cloud: invalid --seed '%s'\n", argv[i]);
        return EXIT_FAILURE;
      }
    }
    else if(arg == "--pca-k" && i + 1 < argc)
    {
      if(!parse_unsigned(argv[++i], u) || u < 2 || u > 1000)
      {
        std::fprintf(stderr, "make_cloud: invalid --pca-k '%s' (2..1000)\n", argv[i]);
        return EXIT_FAILURE;
      }
      options.pca_neighbors = static_cast<unsigned int>(u);
    }
    else if(arg.size() > 1 && arg[0] == '-')
    {
      std::fprintf(stderr, "make_cloud: unknown or incomplete option '%s'\n", arg.c_str());
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
    const Mesh_sampler sampler(positional[0]);
    const Sampled_cloud cloud = sampler.sample(options);
    write_cloud(cloud, positional[2]);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    std::fprintf(stderr,
                 "make_cloud: %zu points on %s (%zu triangles, bbox diagonal %g), noise sigma %g, seed %llu, "
                 "%.2f s\n  wrote %s.xyz and %s.gt.xyz\n",
                 cloud.points.size(), positional[0].c_str(), sampler.number_of_triangles(), cloud.bbox_diagonal,
                 cloud.noise_sigma, static_cast<unsigned long long>(options.seed), seconds,
                 positional[2].c_str(), positional[2].c_str());
  }
  catch(const std::exception& e)
  {
    std::fprintf(stderr, "make_cloud: %s\n", e.what());
    return EXIT_FAILURE;
  }
  return EXIT_SUCCESS;
}
