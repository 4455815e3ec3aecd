// SPDX-License-Identifier: GPL-3.0-or-later
// solver_quality: energy, wrong normals and solve time of three solvers on the same graphs,
// in the form of Table 1 of the paper (Schertler et al. 2017).
//
// For each mesh and each noise level, generates a cloud in process (Mesh_sampler.h) and
// orients copies of it with (a) Mst_solver(0), the paper's MST (Algorithm 1), (b) Mst_solver(),
// MST + 3 local sweeps, (c) Qpbo_i_solver(orders, seed), MST + QPBO-I on the segment graph, and
// (d) Lsa_tr_solver(), LSA-TR from the MST.  Every other parameter is at its default, so the
// four runs build the same graph.  Subtotals per noise level and a check of the quality
// criteria follow the table.
// Prints a Markdown table. See README.md.
#include "Benchmark_options.h"
#include "Mesh_sampler.h"

#include <Normal_orientation/orient_normals.h>
#include <Normal_orientation/parameters.h>
#include <Normal_orientation/solvers/Mst_solver.h>
#include <Normal_orientation/solvers/Lsa_tr_solver.h>
#include <Normal_orientation/solvers/Qpbo_i_solver.h>

#include <CGAL/property_map.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#ifndef NORMAL_ORIENTATION_BENCHMARK_MESH_DIR
#define NORMAL_ORIENTATION_BENCHMARK_MESH_DIR "/work/shared/data/meshes"
#endif

namespace {

namespace fs = std::filesystem;
using namespace Normal_orientation::benchmark;

/// Number of compared solvers.
constexpr std::size_t number_of_solvers = 4;

/// Column labels of the compared solvers, in table order.
const std::array<const char*, number_of_solvers> solver_labels = {"MST", "MST+sweeps", "QPBO-I", "LSA-TR"};

/// Command-line options of solver_quality (the seed also seeds the QPBO-I orders).
struct Options : Cloud_options
{
  Options() { noises = {0.0, 0.001, 0.005}; }
  /// Random orders tried by QPBO-I.
  unsigned int orders = 3;
  /// Maximum number of threads of orient_normals (0: all).
  int threads = 0;
};

/// What one solver gave on one cloud.
struct Solver_row
{
  /// Energy (eq. 3) of the output orientation.
  double energy = 0.0;
  /// Normals with dot(n, n_true) <= 0.
  std::size_t wrong = 0;
  /// Seconds of the solver stage (Orientation_result::seconds.solve).
  double solve_seconds = 0.0;
  /// Seconds of the neighbour graph (kd-tree, queries and weights).
  double graph_seconds = 0.0;
};

/// One line of the table: a cloud and the result of each solver.
struct Table_row
{
  /// File name of the mesh (without directory).
  std::string mesh;
  /// Noise level.
  double noise = 0.0;
  /// Number of points.
  std::size_t points = 0;
  /// Results, in the order of `solver_labels`.
  std::array<Solver_row, number_of_solvers> solvers;
};

/// Prints the usage message to `out`.
void print_usage(std::FILE* out)
{
  std::fprintf(
    out,
    "usage: solver_quality [options]\n"
    "  --meshes DIR_OR_FILES...  meshes (.off files, or directories whose *.off are used);\n"
    "                            default: " NORMAL_ORIENTATION_BENCHMARK_MESH_DIR "/*.off\n"
    "  --points N                points per cloud (default 30000)\n"
    "  --noise a,b,...           noise levels, x bbox diagonal (default 0,0.001,0.005)\n"
    "  --seed S                  seed of the clouds and of QPBO-I (default 1)\n"
    "  --orders N                random orders of QPBO-I (default 3)\n"
    "  --threads T               maximum threads of orient_normals (default 0: all)\n"
    "Orients copies of each cloud with Mst_solver(0) (paper MST), Mst_solver() (MST + 3 sweeps),\n"
    "Qpbo_i_solver(orders, seed) and Lsa_tr_solver() on the same graph and prints a Markdown\n"
    "table, subtotals per noise level and a check of the quality criteria of issue 3.\n"
    "Exit status: 0 on success, 1 on a runtime error, 2 on usage errors.\n");
}



/// Parses the command line into `options`; returns false (after printing why) on an error.
bool parse_options(int argc, char** argv, Options& options, bool& help)
{
  help = false;
  for(int i = 1; i < argc; ++i)
  {
    const std::string arg = argv[i];
    const bool has_value = i + 1 < argc;
    unsigned long long value = 0;
    if(arg == "-h" || arg == "--help")
    {
      help = true;
      return true;
    }
    else if(const int parsed = parse_cloud_option(argc, argv, i, options, "solver_quality"))
    {
      if(parsed < 0)
        return false;
    }
    else if(arg == "--orders" && has_value)
    {
      if(!parse_unsigned(argv[++i], 1, 100000, value))
      {
        std::fprintf(stderr, "solver_quality: invalid --orders '%s' (1..100000)\n", argv[i]);
        return false;
      }
      options.orders = static_cast<unsigned int>(value);
    }
    else if(arg == "--threads" && has_value)
    {
      if(!parse_unsigned(argv[++i], 0, 4096, value))
      {
        std::fprintf(stderr, "solver_quality: invalid --threads '%s' (0..4096, 0 = all)\n", argv[i]);
        return false;
      }
      options.threads = static_cast<int>(value);
    }
    else
    {
      std::fprintf(stderr, "solver_quality: unknown or incomplete option '%s'\n", arg.c_str());
      return false;
    }
  }
  return true;
}


/// A point with its (to be oriented) normal.
using Point_with_normal = std::pair<Point_3, Vector_3>;

/**
 * \brief Orients a copy of the normals of `cloud` with `solver` and scores the result.
 *
 * The energy and the solve time are those reported by `orient_normals()`; a normal is wrong
 * when its dot product with the true normal is not strictly positive.
 * \param number_of_edges receives the number of edges of the graph (to check that every
 *   solver saw the same graph).
 * \throws std::runtime_error if the run was interrupted or changed the number of points.
 */
template <typename Solver>
Solver_row run_solver(const Sampled_cloud& cloud, const Solver& solver, int threads, std::size_t& number_of_edges)
{
  std::vector<Point_with_normal> points;
  points.reserve(cloud.points.size());
  for(std::size_t i = 0; i < cloud.points.size(); ++i)
    points.emplace_back(cloud.points[i], cloud.normals[i]);

  namespace NP = Normal_orientation::parameters;
  const Normal_orientation::Orientation_result result = Normal_orientation::orient_normals(
    points, NP::point_map(CGAL::First_of_pair_property_map<Point_with_normal>())
              .normal_map(CGAL::Second_of_pair_property_map<Point_with_normal>())
              .solver(solver)
              .number_of_threads(threads));
  if(result.interrupted || result.number_of_points != cloud.points.size())
    throw std::runtime_error("orient_normals did not complete");

  Solver_row row;
  row.energy = result.energy_after;
  row.solve_seconds = result.seconds.solve;
  row.graph_seconds = result.seconds.neighbors + result.seconds.graph;
  for(std::size_t i = 0; i < points.size(); ++i)
    if(!(points[i].second * cloud.true_normals[i] > 0.0))
      ++row.wrong;
  number_of_edges = result.number_of_edges;
  return row;
}

/// Returns the energy reduction of `energy` relative to `reference`, in percent (0 when the reference is 0).
double reduction_percent(double reference, double energy)
{
  return reference > 0.0 ? 100.0 * (reference - energy) / reference : 0.0;
}

/// Prints the header of the Markdown table.
void print_header()
{
  std::printf("| mesh | noise | points |");
  for(const char* label : solver_labels)
    std::printf(" E %s |", label);
  for(std::size_t s = 1; s < number_of_solvers; ++s)
    std::printf(" red. %s |", solver_labels[s]);
  for(const char* label : solver_labels)
    std::printf(" wrong %s |", label);
  std::printf(" graph s |");
  for(const char* label : solver_labels)
    std::printf(" solve s %s |", label);
  std::printf("\n|---|---:|---:|");
  for(std::size_t c = 0; c < 4 * number_of_solvers; ++c)
    std::printf("---:|");
  std::printf("\n");
}

/// Prints one line of the table; `mesh` and `noise` are already formatted.
void print_line(const std::string& mesh, const std::string& noise, std::size_t points,
                const std::array<Solver_row, number_of_solvers>& solvers)
{
  std::printf("| %s | %s | %zu |", mesh.c_str(), noise.c_str(), points);
  for(const Solver_row& s : solvers)
    std::printf(" %.2f |", s.energy);
  for(std::size_t s = 1; s < number_of_solvers; ++s)
    std::printf(" %.2f%% |", reduction_percent(solvers[0].energy, solvers[s].energy));
  for(const Solver_row& s : solvers)
    std::printf(" %zu (%.2f%%) |", s.wrong, points > 0 ? 100.0 * double(s.wrong) / double(points) : 0.0);
  std::printf(" %.3f |", solvers[0].graph_seconds);
  for(const Solver_row& s : solvers)
    std::printf(" %.3f |", s.solve_seconds);
  std::printf("\n");
  std::fflush(stdout);
}

} // namespace

/// Entry point: parses the options, runs every cloud and prints the table.
int main(int argc, char** argv)
{
  Options options;
  bool help = false;
  if(!parse_options(argc, argv, options, help))
  {
    print_usage(stderr);
    return 2;
  }
  if(help)
  {
    print_usage(stdout);
    return 0;
  }

  try
  {
    const std::vector<std::string> meshes = collect_meshes(options.mesh_arguments);
    std::printf("solver_quality: %zu mesh(es), %zu points, seed %llu, QPBO-I orders %u, threads %d "
                "(same graph, default k and radius, for every solver)\n\n",
                meshes.size(), options.points, static_cast<unsigned long long>(options.seed), options.orders,
                options.threads);
    print_header();

    const Normal_orientation::Mst_solver paper_mst(0);
    const Normal_orientation::Mst_solver default_mst;
    const Normal_orientation::Qpbo_i_solver qpbo_i(options.orders, static_cast<unsigned long>(options.seed));
    const Normal_orientation::Lsa_tr_solver lsa_tr;

    std::array<Solver_row, number_of_solvers> totals;
    std::vector<std::array<Solver_row, number_of_solvers>> noise_totals(options.noises.size());
    std::vector<std::size_t> noise_points(options.noises.size(), 0);
    std::size_t total_points = 0, clouds = 0, qpbo_above_mst = 0, lsa_above_mst = 0;
    auto add = [](std::array<Solver_row, number_of_solvers>& sum, const std::array<Solver_row, number_of_solvers>& r) {
      for(std::size_t s = 0; s < number_of_solvers; ++s)
      {
        sum[s].energy += r[s].energy;
        sum[s].wrong += r[s].wrong;
        sum[s].solve_seconds += r[s].solve_seconds;
        sum[s].graph_seconds += r[s].graph_seconds;
      }
    };
    for(const std::string& mesh : meshes)
    {
      const Mesh_sampler sampler(mesh);
      for(std::size_t level = 0; level < options.noises.size(); ++level)
      {
        const double noise = options.noises[level];
        Sampling_options sampling;
        sampling.number_of_points = options.points;
        sampling.noise = noise;
        sampling.seed = options.seed;
        const Sampled_cloud cloud = sampler.sample(sampling);

        Table_row row;
        row.mesh = fs::path(mesh).filename().string();
        row.noise = noise;
        row.points = cloud.points.size();
        std::array<std::size_t, number_of_solvers> edges{};
        row.solvers[0] = run_solver(cloud, paper_mst, options.threads, edges[0]);
        row.solvers[1] = run_solver(cloud, default_mst, options.threads, edges[1]);
        row.solvers[2] = run_solver(cloud, qpbo_i, options.threads, edges[2]);
        row.solvers[3] = run_solver(cloud, lsa_tr, options.threads, edges[3]);
        for(std::size_t s = 1; s < number_of_solvers; ++s)
          if(edges[s] != edges[0])
            throw std::runtime_error("the solvers did not see the same graph on '" + row.mesh + "'");

        char noise_text[32];
        std::snprintf(noise_text, sizeof(noise_text), "%g", noise);
        print_line(row.mesh, noise_text, row.points, row.solvers);
        add(totals, row.solvers);
        add(noise_totals[level], row.solvers);
        noise_points[level] += row.points;
        total_points += row.points;
        ++clouds;
        // QPBO-I and LSA-TR start from the paper's MST labelling or better
        const double slack = 1e-9 * (1.0 + row.solvers[0].energy);
        qpbo_above_mst += row.solvers[2].energy > row.solvers[0].energy + slack;
        lsa_above_mst += row.solvers[3].energy > row.solvers[0].energy + slack;
      }
    }
    for(std::size_t level = 0; level < options.noises.size(); ++level)
    {
      char label[48];
      std::snprintf(label, sizeof(label), "*noise %g*", options.noises[level]);
      print_line(label, "", noise_points[level], noise_totals[level]);
    }
    print_line("**total**", "", total_points, totals);

    // The quality criteria of issue 3, on these clouds.
    std::array<Solver_row, number_of_solvers> noisy;
    for(std::size_t level = 0; level < options.noises.size(); ++level)
      if(options.noises[level] > 0.0)
        add(noisy, noise_totals[level]);
    std::printf("\nclouds where the energy ends above the paper MST's: QPBO-I %zu of %zu, LSA-TR %zu of %zu\n",
                qpbo_above_mst, clouds, lsa_above_mst, clouds);
    std::printf("noisy clouds, total energy against the paper MST: QPBO-I %.1f%% lower, LSA-TR %.1f%% lower\n",
                reduction_percent(noisy[0].energy, noisy[2].energy),
                reduction_percent(noisy[0].energy, noisy[3].energy));
    std::printf("noisy clouds, total energy against MST+sweeps: QPBO-I %.1f%% lower, LSA-TR %.1f%% lower\n",
                reduction_percent(noisy[1].energy, noisy[2].energy),
                reduction_percent(noisy[1].energy, noisy[3].energy));
    std::printf("wrong normals over all clouds: MST %zu, MST+sweeps %zu, QPBO-I %zu, LSA-TR %zu\n",
                totals[0].wrong, totals[1].wrong, totals[2].wrong, totals[3].wrong);
  }
  catch(const std::exception& e)
  {
    std::fprintf(stderr, "solver_quality: %s\n", e.what());
    return 1;
  }
  return 0;
}
