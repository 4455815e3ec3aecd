// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// Winding_number_field at scale: N oriented points (a unit sphere, or samples of a closed,
// outward-oriented mesh with their true normals), N queries (half uniform in the bounding
// box, half just inside or outside random samples).  Prints, as JSON: the area estimation
// and build times, the evaluation times (w, and w with its gradient) for each opening ratio,
// the error against the direct sum on a random subset of the queries, and the time to
// negate the normals of half the points.
//
// usage: winding_number_benchmark [--points N] [--queries M] [--check K] [--beta B1,B2,...]
//                                 [--smoothing F] [--seed S] [--mesh FILE.off]

#include "Mesh_sampler.h"

#include <Normal_orientation/Winding_number_field.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace NO = Normal_orientation;
using NO::benchmark::Kernel;
using NO::benchmark::Point_3;
using NO::benchmark::Vector_3;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0)
{
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

[[noreturn]] void usage(const char* message)
{
  std::fprintf(stderr,
               "winding_number_benchmark: %s\nusage: winding_number_benchmark [--points N] [--queries M] "
               "[--check K] [--beta B1,B2,...] [--smoothing F] [--seed S] [--mesh FILE.off]\n",
               message);
  std::exit(2);
}

/// the command line
struct Options
{
  std::size_t n = 1000000, m = 0, check = 300;
  std::vector<double> betas = {1.5, 2.0, 3.0};
  double smoothing = NO::default_smoothing_factor;
  unsigned long long seed = 1;
  std::string mesh;
};

Options parse(int argc, char** argv)
{
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc)
      usage(("missing value after " + a).c_str());
    const char* v = argv[++i];
    char* end = nullptr;
    if (a == "--points")
      o.n = std::strtoull(v, &end, 10);
    else if (a == "--queries")
      o.m = std::strtoull(v, &end, 10);
    else if (a == "--check")
      o.check = std::strtoull(v, &end, 10);
    else if (a == "--smoothing")
      o.smoothing = std::strtod(v, &end);
    else if (a == "--seed")
      o.seed = std::strtoull(v, &end, 10);
    else if (a == "--mesh") {
      o.mesh = v;
      continue;
    } else if (a == "--beta") {
      o.betas.clear();
      const char* s = v;
      while (*s) {
        o.betas.push_back(std::strtod(s, &end));
        if (end == s || !(o.betas.back() > 0.0))
          usage("bad --beta list");
        s = *end == ',' ? end + 1 : end;
      }
      continue;
    } else
      usage(("unknown option " + a).c_str());
    if (end == v || *end != '\0')
      usage(("bad value of " + a).c_str());
  }
  if (o.n < 2)
    usage("--points must be at least 2");
  if (o.m == 0)
    o.m = o.n;
  o.check = std::min(o.check, o.m);
  return o;
}

} // namespace

int main(int argc, char** argv)
{
  const Options o = parse(argc, argv);
  const std::size_t n = o.n, m = o.m, check = o.check;
  const std::vector<double>& betas = o.betas;
  const double smoothing = o.smoothing;
  const unsigned long long seed = o.seed;
  const std::string& mesh = o.mesh;
  // The cloud: positions and true outward normals.
  std::vector<Point_3> points;
  std::vector<Vector_3> normals;
  auto t0 = std::chrono::steady_clock::now();
  if (mesh.empty()) {
    std::mt19937_64 rng(NO::benchmark::mix_seed(seed));
    NO::benchmark::Gaussian_generator g(rng);
    for (std::size_t i = 0; i < n; ++i) {
      const double x = g(), y = g(), z = g();
      const double l = std::sqrt(x * x + y * y + z * z);
      points.emplace_back(x / l, y / l, z / l);
      normals.emplace_back(x / l, y / l, z / l);
    }
  } else {
    NO::benchmark::Sampling_options options;
    options.number_of_points = n;
    options.seed = seed;
    const NO::benchmark::Sampled_cloud cloud = NO::benchmark::Mesh_sampler(mesh).sample(options);
    points = cloud.points;
    normals = cloud.true_normals;
  }
  const double seconds_cloud = seconds_since(t0);

  t0 = std::chrono::steady_clock::now();
  const std::vector<double> areas = NO::estimate_point_areas<CGAL::Parallel_if_available_tag>(points, normals);
  const double seconds_areas = seconds_since(t0);
  double total_area = 0.0;
  for (double a : areas)
    total_area += a;

  NO::Winding_number_field<Kernel> field;
  field.set_smoothing_factor(smoothing);
  t0 = std::chrono::steady_clock::now();
  field.build<CGAL::Parallel_if_available_tag>(points, normals, areas);
  const double seconds_build = seconds_since(t0);

  // Queries: even ones uniform in the bounding box grown by 10%, odd ones at one
  // smoothing width (at least 1e-3 of the box) inside or outside a random sample.
  double lo[3], hi[3];
  for (int c = 0; c < 3; ++c) {
    lo[c] = hi[c] = points[0][c];
    for (const Point_3& p : points) {
      lo[c] = std::min(lo[c], p[c]);
      hi[c] = std::max(hi[c], p[c]);
    }
  }
  const double diagonal = std::sqrt(CGAL::square(hi[0] - lo[0]) + CGAL::square(hi[1] - lo[1]) + CGAL::square(hi[2] - lo[2]));
  std::mt19937_64 rng(NO::benchmark::mix_seed(seed ^ 0x717565ull));
  std::vector<Point_3> queries;
  queries.reserve(m);
  for (std::size_t t = 0; t < m; ++t) {
    if (t % 2 == 0) {
      double q[3];
      for (int c = 0; c < 3; ++c) {
        const double grow = 0.1 * (hi[c] - lo[c]);
        q[c] = lo[c] - grow + NO::benchmark::uniform_01(rng) * (hi[c] - lo[c] + 2.0 * grow);
      }
      queries.emplace_back(q[0], q[1], q[2]);
    } else {
      const std::size_t i = std::size_t(rng() % n);
      const double d = std::max(field.smoothing_width(i), 1e-3 * diagonal) * ((rng() >> 63) ? 1.0 : -1.0);
      queries.push_back(points[i] + d * normals[i] / std::sqrt(normals[i].squared_length()));
    }
  }
  // The checked subset: every (m / check)-th query.
  std::vector<Point_3> subset;
  for (std::size_t t = 0; t < check; ++t)
    subset.push_back(queries[t * (m / check)]);
  t0 = std::chrono::steady_clock::now();
  std::vector<double> exact;
  std::vector<Vector_3> exact_gradients;
  field.evaluate_direct<CGAL::Parallel_if_available_tag>(subset, exact, exact_gradients);
  const double seconds_direct = seconds_since(t0);

  std::printf("{\n  \"points\": %zu,\n  \"queries\": %zu,\n  \"shape\": \"%s\",\n  \"hardware_threads\": %u,\n", n, m,
              mesh.empty() ? "unit sphere" : mesh.c_str(), std::thread::hardware_concurrency());
  std::printf("  \"smoothing_factor\": %g,\n  \"seconds_cloud\": %.3f,\n  \"seconds_areas\": %.3f,\n", smoothing,
              seconds_cloud, seconds_areas);
  std::printf("  \"total_area\": %.6g,\n  \"seconds_build\": %.3f,\n", total_area, seconds_build);
  std::printf("  \"direct_sum\": {\"queries\": %zu, \"seconds\": %.3f, \"seconds_per_query\": %.3g},\n", check,
              seconds_direct, check > 0 ? seconds_direct / double(check) : 0.0);
  std::printf("  \"treecode\": [\n");
  for (std::size_t b = 0; b < betas.size(); ++b) {
    field.set_opening_ratio(betas[b]);
    std::vector<double> values, approx;
    std::vector<Vector_3> gradients, approx_gradients;
    t0 = std::chrono::steady_clock::now();
    field.evaluate<CGAL::Parallel_if_available_tag>(queries, values);
    const double seconds_value = seconds_since(t0);
    t0 = std::chrono::steady_clock::now();
    field.evaluate<CGAL::Parallel_if_available_tag>(queries, values, gradients);
    const double seconds_gradient = seconds_since(t0);
    double max_error = 0.0, mean_error = 0.0, max_gradient_error = 0.0;
    for (std::size_t t = 0; t < check; ++t) {
      const std::size_t s = t * (m / check);
      const double e = std::abs(values[s] - exact[t]);
      max_error = std::max(max_error, e);
      mean_error += e / double(check);
      const double scale = std::max(1.0, std::sqrt(exact_gradients[t].squared_length()));
      max_gradient_error =
        std::max(max_gradient_error, std::sqrt((gradients[s] - exact_gradients[t]).squared_length()) / scale);
    }
    std::printf("    {\"opening_ratio\": %g, \"seconds_value\": %.3f, \"seconds_value_and_gradient\": %.3f, "
                "\"max_error\": %.3g, \"mean_error\": %.3g, \"max_relative_gradient_error\": %.3g}%s\n",
                betas[b], seconds_value, seconds_gradient, max_error, mean_error, max_gradient_error,
                b + 1 < betas.size() ? "," : "");
  }
  std::printf("  ],\n");
  // Negating the normals of half the points (the sign stage's patch flips).
  std::vector<std::size_t> half;
  for (std::size_t i = 0; i < n; ++i)
    if (points[i].z() > 0.5 * (lo[2] + hi[2]))
      half.push_back(i);
  t0 = std::chrono::steady_clock::now();
  field.negate(half);
  const double seconds_negate = seconds_since(t0);
  std::printf("  \"negate\": {\"points\": %zu, \"seconds\": %.4f}\n}\n", half.size(), seconds_negate);
  return 0;
}
