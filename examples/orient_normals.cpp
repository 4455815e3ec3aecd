// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// orient_normals: the command-line program of Normal_orientation.
//
//   orient_normals [options] [IN [OUT]]
//
// Reads a point cloud (.xyz/.pwn or .ply), estimates normals when it has
// none (or when all of them are zero), orients them consistently and
// outward, in core or streamed (--stream), and writes the result (.xyz or
// .ply, by extension) through a temporary file and a rename, so an output
// file is either complete or absent.
//
// The program is in five parts: cli/Cli_options.h (the command line),
// cli/Allocator_settings.h (freed memory kept for reuse),
// cli/Progress_bar.h, cli/Json_writer.h and cli/Cli_report.h (the summary
// and the JSON report), and this file: the choice of the policies, written
// once for both drivers, the in-core run and the streamed run.

#include "cli/Allocator_settings.h"
#include "cli/Cli_options.h"
#include "cli/Cli_report.h"
#include "cli/Cli_sign_policy.h"
#include "cli/Progress_bar.h"

#include <Normal_orientation/IO/Point_cloud_io.h>
#include <Normal_orientation/IO/Point_stream.h>
#include <Normal_orientation/orient_normals.h>
#include <Normal_orientation/solvers/Lsa_tr_solver.h>
#include <Normal_orientation/solvers/Qpbo_i_solver.h>
#include <Normal_orientation/streaming_orient_normals.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/jet_estimate_normals.h>
#include <CGAL/pca_estimate_normals.h>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/global_control.h>
#endif

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <string>
#include <vector>

namespace NO = Normal_orientation;
typedef CGAL::Exact_predicates_inexact_constructions_kernel Kernel;
typedef Kernel::Point_3 Point;
typedef Kernel::Vector_3 Vector;

namespace {

typedef std::chrono::steady_clock Clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

/// Reads the positions of a `Point_cloud` by index.
struct Cloud_point_map
{
  typedef std::size_t key_type;
  typedef Point value_type;
  typedef Point reference;
  typedef boost::readable_property_map_tag category;
  const NO::IO::Point_cloud* cloud;
  friend Point get(const Cloud_point_map& m, std::size_t i)
  {
    const auto& p = m.cloud->points[i];
    return Point(p[0], p[1], p[2]);
  }
};

/// Reads and writes the normals of a `Point_cloud` by index.
struct Cloud_normal_map
{
  typedef std::size_t key_type;
  typedef Vector value_type;
  typedef Vector reference;
  typedef boost::read_write_property_map_tag category;
  NO::IO::Point_cloud* cloud;
  friend Vector get(const Cloud_normal_map& m, std::size_t i)
  {
    const auto& n = m.cloud->normals[i];
    return Vector(n[0], n[1], n[2]);
  }
  friend void put(const Cloud_normal_map& m, std::size_t i, const Vector& v)
  {
    m.cloud->normals[i] = {v.x(), v.y(), v.z()};
  }
};

/// true when `n` is a zero normal as the library counts them (its squared
/// length is 0; a non-finite normal is not zero: it is bad input)
bool is_zero_normal(const double* n) { return n[0] * n[0] + n[1] * n[1] + n[2] * n[2] == 0.0; }

// ---------------------------------------------------------------------------
// The policies: one dispatch for both drivers
// ---------------------------------------------------------------------------

/// Calls `f(criterion, solver)` with the flip criterion and the solver named
/// by --criterion and --solver, and returns what it returns.
template <typename F>
auto with_criterion_and_solver(const Cli::Options& o, const F& f)
{
  auto with_solver = [&](const auto& criterion) {
    if (o.solver == "mst")
      return f(criterion, NO::Mst_solver());
    if (o.solver == "lsa-tr")
      return f(criterion, NO::Lsa_tr_solver());
    return f(criterion, NO::Qpbo_i_solver(o.orders, o.seed));
  };
  if (o.criterion == "xie")
    return with_solver(NO::Xie_criterion());
  if (o.criterion == "konig")
    return with_solver(NO::Konig_criterion());
  if (o.criterion == "hoppe")
    return with_solver(NO::Hoppe_criterion());
  return with_solver(NO::Hoppe_konig_criterion());
}

// ---------------------------------------------------------------------------
// In core
// ---------------------------------------------------------------------------

/// Why the normals of `cloud` must be estimated; empty when they are usable.
std::string reason_to_estimate_normals(const NO::IO::Point_cloud& cloud)
{
  if (!cloud.has_normals())
    return "the input has no normals";
  for (const auto& n : cloud.normals)
    if (!is_zero_normal(n.data()))
      return "";
  return "all input normals are zero";
}

/// Estimates the normals of `cloud` (--normals, --normal-k) when it has none
/// or when they are all zero (placeholders); fills the estimation fields of `run`.
template <typename Range>
void estimate_normals_if_needed(NO::IO::Point_cloud& cloud, Range& range, const Cli::Options& o, Cli::In_core_run& run)
{
  run.normals_estimated_because = reason_to_estimate_normals(cloud);
  if (!run.normals_estimated())
    return;
  const auto t = Clock::now();
  if (cloud.size() < 4)
    throw std::runtime_error(o.input + (cloud.has_normals() ? ": all normals are zero, and too few points to estimate them"
                                                            : ": too few points to estimate normals"));
  if (cloud.has_normals() && !o.quiet)
    std::fprintf(stderr, "%s: all %zu normals are zero: estimating them (%s), as for a file without normals\n",
                 o.input.c_str(), cloud.size(), o.normals.c_str());
  cloud.normals.assign(cloud.size(), {0.0, 0.0, 0.0});
  cloud.normal_digits = 0; // computed values: written with as many digits as they need
  const unsigned nk = unsigned(std::min<std::size_t>(o.normal_k, cloud.size() - 1));
  auto np = CGAL::parameters::point_map(Cloud_point_map{&cloud}).normal_map(Cloud_normal_map{&cloud});
  if (o.normals == "pca")
    CGAL::pca_estimate_normals<CGAL::Parallel_if_available_tag>(range, nk, np);
  else
    CGAL::jet_estimate_normals<CGAL::Parallel_if_available_tag>(range, nk, np);
  run.estimate_seconds = seconds_since(t);
}

/// The viewpoint prior of --prior-weight W (see `Cli::viewpoint_prior()`);
/// empty without --prior-weight.
std::vector<double> viewpoint_prior(const NO::IO::Point_cloud& cloud, const Cli::Options& o)
{
  std::vector<double> prior;
  if (!(o.prior_weight > 0.0))
    return prior;
  prior.resize(cloud.size(), 0.0);
  const std::array<double, 3> viewpoint{{o.viewpoint[0], o.viewpoint[1], o.viewpoint[2]}};
  for (std::size_t i = 0; i < cloud.size(); ++i)
    prior[i] = Cli::viewpoint_prior(viewpoint, o.prior_weight, cloud.points[i].data(), cloud.normals[i].data());
  return prior;
}

/// `orient_normals()` with the criterion, the solver and the component sign
/// policy of the options (and the viewpoint prior when `prior` is not empty).
template <typename Range, typename Np>
NO::Orientation_result orient_in_core(Range& range, const Np& np, const Cli::Options& o, std::vector<double>& prior)
{
  return with_criterion_and_solver(o, [&](const auto& criterion, const auto& solver) {
    const auto policies = np.flip_criterion(criterion)
                            .solver(solver)
                            .component_sign(Cli::Component_sign(o))
                            .global_orientation(Cli::global_orientation(o))
                            .up_direction(o.up)
                            .layer_edges(o.layer_edges);
    if (!prior.empty())
      return NO::orient_normals(range, policies.orientation_prior_map(CGAL::make_property_map(prior)));
    return NO::orient_normals(range, policies);
  });
}

/// In core: read, estimate the normals if needed, orient, write, report.
int run_in_core(const Cli::Options& o, Clock::time_point t0)
{
  Cli::In_core_run run;
  // --threads bounds every stage: reading, orienting and writing.
  NO::IO::Read_options ro;
  ro.number_of_threads = unsigned(o.threads); // 0: automatic
  NO::IO::Point_cloud cloud = NO::IO::read_point_cloud(o.input, ro);
  run.read_seconds = seconds_since(t0);
  if (cloud.size() == 0)
    throw std::runtime_error(o.input + ": the file holds no point");

  // The program's own structure, seen through index-based property maps.
  std::vector<std::size_t> range(cloud.size());
  std::iota(range.begin(), range.end(), std::size_t(0));
  estimate_normals_if_needed(cloud, range, o, run);

  Cli::Progress_bar bar(!o.quiet);
  std::function<bool(double)> callback = [&bar](double x) { return bar(x); };
  auto np = NO::parameters::point_map(Cloud_point_map{&cloud})
              .normal_map(Cloud_normal_map{&cloud})
              .number_of_neighbors(o.k)
              .neighbor_radius(o.radius)
              .number_of_threads(o.threads)
              .random_seed(o.seed)
              .callback(callback);
  std::vector<double> prior = viewpoint_prior(cloud, o);
  const NO::Orientation_result r = orient_in_core(range, np, o, prior);
  bar.finish();

  const auto tw = Clock::now();
  NO::IO::Write_options wo;
  wo.binary = !o.ascii;
  wo.number_of_threads = ro.number_of_threads;
  // The digits the input text had (or the shortest exact text): values read
  // back from the output equal, bit for bit, those read from the input.
  wo.precision = NO::IO::Write_options::PRECISION_AS_READ;
  NO::IO::write_point_cloud(o.output, cloud, wo);
  run.write_seconds = seconds_since(tw);
  run.total_seconds = seconds_since(t0);

  if (!o.quiet)
    Cli::print_summary(r, run, o);
  if (o.json)
    std::printf("%s\n", Cli::json_report(r, run, o).c_str());
  return 0;
}

// ---------------------------------------------------------------------------
// Streamed (--stream)
// ---------------------------------------------------------------------------

/// Fails when every normal of `input` is zero: a file of placeholders,
/// whose normals only the in-core run estimates.  Cheap: it stops at the
/// first non-zero normal, in the first records of any usable file; it reads
/// the whole file only when it is to fail.  Errors of the file are left to
/// the streaming run, which reports them as it always has.
void refuse_all_zero_normals(const std::string& input)
{
  bool all_zero = false;
  try {
    NO::IO::Point_stream_reader reader(input, NO::IO::Point_stream_reader::minimum_buffer_size);
    if (!reader.has_normals())
      return;
    std::vector<NO::Point_record> chunk;
    std::uint64_t count = 0;
    while (reader.read(chunk, 1024) > 0) {
      for (const NO::Point_record& p : chunk)
        if (!is_zero_normal(p.normal))
          return;
      count += chunk.size();
      chunk.clear();
    }
    all_zero = count > 0;
  } catch (const std::exception&) {
    return;
  }
  if (all_zero)
    throw std::runtime_error(input + ": every normal is zero (placeholders, not normals): run without --stream "
                                     "to estimate the normals");
}

/// --stream, file to file: the one place where the program calls the
/// streaming library, with the same criterion, solver, sign policy and
/// viewpoint prior as in core.
Cli::Streamed_run orient_streamed(const Cli::Options& o, Cli::Progress_bar& bar)
{
  refuse_all_zero_normals(o.input);
  NO::Component_files_options component_files;
  component_files.directory = o.components_dir; // in OUT's format
  Cli::Streamed_run run;
  run.refinement_rounds =
    o.refine_rounds >= 0 ? unsigned(o.refine_rounds) : NO::streaming::Refinement_options().rounds;
  auto callback = [&bar](const NO::Progress_info& p) {
    return bar.update(NO::stage_name(p.stage), p.total > 0 ? p.stage_fraction() : -1.0, p.done);
  };
  const auto np = NO::parameters::number_of_neighbors(o.k)
                    .neighbor_radius(o.radius)
                    .presorted_axis(o.presorted == "x"   ? NO::Presorted_axis::X
                                    : o.presorted == "y" ? NO::Presorted_axis::Y
                                    : o.presorted == "z" ? NO::Presorted_axis::Z
                                                         : NO::Presorted_axis::NONE)
                    .minimum_component_size(std::uint64_t(o.min_component_size))
                    .refinement_rounds(run.refinement_rounds)
                    .component_files(component_files)
                    .batch_size(o.batch_size != 0 ? std::size_t(o.batch_size) : NO::default_batch_size)
                    .number_of_threads(o.threads)
                    .callback(std::function<bool(const NO::Progress_info&)>(callback));
  NO::IO::Point_stream_write_options wo;
  wo.binary = !o.ascii;
  wo.segments = o.write_segments;
  auto orient = [&](const auto& policies) {
    if (o.keep_order)
      return NO::streaming_orient_files_in_input_order(o.input, o.output, policies);
    return NO::streaming_orient_files(o.input, o.output, policies, wo);
  };
  run.result = with_criterion_and_solver(o, [&](const auto& criterion, const auto& solver) {
    const auto policies = np.flip_criterion(criterion)
                            .solver(solver)
                            .component_sign(Cli::Component_sign(o))
                            .global_orientation(Cli::global_orientation(o))
                            .up_direction(o.up)
                            .layer_edges(o.layer_edges);
    if (o.prior_weight > 0.0)
      return orient(policies.orientation_prior_map(
        Cli::Record_viewpoint_prior{{{o.viewpoint[0], o.viewpoint[1], o.viewpoint[2]}}, o.prior_weight}));
    return orient(policies);
  });
  return run;
}

/// Streamed: orient file to file, report.
int run_streamed(const Cli::Options& o, Clock::time_point t0)
{
  Cli::Progress_bar bar(!o.quiet);
  Cli::Streamed_run run = orient_streamed(o, bar);
  bar.finish();
  run.total_seconds = seconds_since(t0);
  if (!o.quiet)
    Cli::print_summary(run, o);
  if (o.json)
    std::printf("%s\n", Cli::json_report(run, o).c_str());
  return 0;
}

int main_impl(int argc, char** argv)
{
  const auto t0 = Clock::now();
  const Cli::Options o = Cli::parse_options(argc, argv, NORMAL_ORIENTATION_SAMPLE_CLOUD);
  // In core, freed memory is kept for reuse unless --return-memory; the
  // streamed run reuses its own buffers (doc/cli.md, "Memory and speed")
  if (!o.stream && !o.return_memory)
    Cli::keep_freed_memory();
#ifdef CGAL_LINKED_WITH_TBB
  // --threads N: at most N threads in every parallel stage of the process,
  // normal estimation included (the library's own stages also run in an
  // arena of N threads, see number_of_threads)
  std::unique_ptr<tbb::global_control> thread_limit;
  if (o.threads > 0)
    thread_limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                         std::size_t(o.threads));
#endif
  return o.stream ? run_streamed(o, t0) : run_in_core(o, t0);
}

} // namespace

/// SIGINT/SIGTERM: remove every temporary file (sort runs, record files, the
/// output being written), then die of the signal as usual.
extern "C" void on_terminating_signal(int sig)
{
  NO::remove_temporary_files();
  std::signal(sig, SIG_DFL);
  std::raise(sig);
}

int main(int argc, char** argv)
{
  std::signal(SIGINT, on_terminating_signal);
  std::signal(SIGTERM, on_terminating_signal);
  try {
    return main_impl(argc, argv);
  } catch (const Cli::Usage_error& e) {
    std::fprintf(stderr, "orient_normals: %s (see --help)\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "orient_normals: error: %s\n", e.what());
    return 1;
  }
}
