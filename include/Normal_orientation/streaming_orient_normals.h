// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_ORIENT_NORMALS_H
#define NORMAL_ORIENTATION_STREAMING_ORIENT_NORMALS_H

/// \file streaming_orient_normals.h
/// The out-of-core entry point (paper sec. 5): orients clouds larger than
/// memory by sorting them along their principal axis (or reading them as
/// they are when they are already sorted along x, y or z), sweeping them
/// with a window of bounded size, segmenting on the fly, solving the
/// segment graph and re-streaming the points with their final signs, to one
/// output and, optionally, to one file per connected component.

#include <Normal_orientation/Component_sign.h>
#include <Normal_orientation/Flip_criteria.h>
#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/IO/Point_stream.h>
#include <Normal_orientation/IO/Point_stream_transcode.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/internal/Progress.h>
#include <Normal_orientation/solvers/Qpbo_i_solver.h>
#include <Normal_orientation/Point_record.h>
#include <Normal_orientation/streaming/Record_file.h>
#include <Normal_orientation/streaming/Refinement.h>
#include <Normal_orientation/Segmenter.h>
#include <Normal_orientation/streaming/Sweep.h>
#include <Normal_orientation/streaming/external_sort.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/tags.h>

#include <boost/graph/compressed_sparse_row_graph.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <numeric>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>
#include <type_traits>
#include <utility>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationStreaming
/// The coordinate along which a streamed input is already sorted (see
/// `Streaming_options::presorted_axis`).
enum class Presorted_axis
{
  NONE, ///< not sorted: the pipeline sorts it along its principal axis
  X,    ///< sorted by non-decreasing x
  Y,    ///< sorted by non-decreasing y
  Z     ///< sorted by non-decreasing z
};

/// \ingroup PkgNormalOrientationStreaming
/// The stages of `streaming_orient_normals()`, in the order they run, as
/// reported to `Streaming_options::callback`.
enum class Streaming_stage
{
  SCAN,      ///< the first pass over the input: count, finiteness, frame, radius sample, order check
  RADIUS,    ///< the k-nearest-neighbour distances of the radius sample (only when r is estimated)
  SORT,      ///< the external sort along the principal axis (not with a presorted input)
  SWEEP,     ///< the sweep: neighbour graph, edge weights, segmentation
  SOLVE,     ///< the solver on the segment graph
  REFINE,    ///< the refinement passes (only with `Streaming_options::refinement`.rounds > 0)
  SIGN,      ///< the outward sign of every component (passes over the record file)
  OUTPUT,    ///< the oriented points handed to the sink
  COMPONENTS ///< the files of the components (only with `Streaming_options::component_files`)
};

/// \ingroup PkgNormalOrientationStreaming
/// The lower-case name of `stage` ("scan", "radius", "sort", "sweep",
/// "solve", "refine", "sign", "output", "components").
/// \param stage the stage
/// \return a string literal
inline const char* streaming_stage_name(Streaming_stage stage)
{
  switch (stage) {
  case Streaming_stage::SCAN:
    return "scan";
  case Streaming_stage::RADIUS:
    return "radius";
  case Streaming_stage::SORT:
    return "sort";
  case Streaming_stage::SWEEP:
    return "sweep";
  case Streaming_stage::SOLVE:
    return "solve";
  case Streaming_stage::REFINE:
    return "refine";
  case Streaming_stage::SIGN:
    return "sign";
  case Streaming_stage::OUTPUT:
    return "output";
  case Streaming_stage::COMPONENTS:
    return "components";
  }
  return "?";
}

/// \ingroup PkgNormalOrientationStreaming
/// What `Streaming_options::callback` is told: the stage running and how far
/// it is.  Every stage is reported at its start (`done` = 0) and at its end
/// (`done` = `total`), and in between as it goes (per chunk read, per batch
/// of the sweep).
struct Streaming_progress
{
  /// the stage running
  Streaming_stage stage = Streaming_stage::SCAN;
  /// the units of work of the stage done so far (points, or points times
  /// passes, as in `SIGN` and `REFINE`; for `SOLVE`, 0 then 1)
  std::uint64_t done = 0;
  /// the units of work of the stage, 0 when unknown (the scan, which counts
  /// the points)
  std::uint64_t total = 0;
  /// `done / total` in [0, 1]; 0 when the total is unknown
  double fraction() const { return total > 0 ? std::min(1.0, double(done) / double(total)) : 0.0; }
};

/// \ingroup PkgNormalOrientationStreaming
/// Where and how `streaming_orient_normals()` writes one file per connected
/// component (see `Streaming_options::component_files`).
struct Component_files_options
{
  /// the directory of the files, created (with its parents) when missing;
  /// empty: no component files
  std::string directory;
  /// the format of the files: ".ply", ".xyz" or ".pwn"; empty: ".ply" in
  /// `streaming_orient_normals()`, the output's format (extension and write
  /// options) in `streaming_orient_files()`
  std::string extension;
  /// how the files are written (binary or ascii PLY, normals; `segments` is
  /// ignored: the component files hold no segments)
  IO::Point_stream_write_options write_options;
  /// the most component files open at once (at least 1; each buffers
  /// 1 MiB).  With more components than that, one pass over the record
  /// file first splits it into one temporary file per group of that many
  /// components, then each group is written from its file: the points are
  /// read twice (and written once more) for up to `maximum_open_files`
  /// squared components, with one more pass over the record file per
  /// further `maximum_open_files` squared (the group files of one pass are
  /// open together)
  std::size_t maximum_open_files = 32;
};

/// \ingroup PkgNormalOrientationStreaming
/// The parameters of `streaming_orient_normals()`.
struct Streaming_options
{
  /// k of the neighbour graph
  unsigned int number_of_neighbors = default_number_of_neighbors;
  /// r; 0 to estimate it from a uniform sample of the cloud (see
  /// `streaming_orient_normals()`)
  double radius = 0.0;
  /// the segmentation thresholds of the sweep (the paper's defaults:
  /// theta_S = 0, theta_acc = 0.5)
  Segmentation_thresholds thresholds;
  /// The refinement after the segment graph is solved (see
  /// `streaming::Refinement_options`): rounds of re-segmentation around the
  /// current labelling, with finer and finer segments, each solved again,
  /// and single-point moves, in passes over the points in the sweep order
  /// with a window of bounded size.  It never raises the energy of the
  /// point graph.  It needs the edges of the graph: the sweep writes them
  /// to a temporary file of 8 bytes per edge (about 56 bytes per point with
  /// k = 12, next to the 64 of the record file).  `rounds = 0` turns it off.
  streaming::Refinement_options refinement;
  /// points finalised per batch of the sweep
  std::size_t batch_size = std::size_t(1) << 18;
  /// the external sort (memory budget, temporary directory)
  streaming::External_sort_options sort;
  /// where the record file goes (empty: TMPDIR, else /tmp)
  std::string temporary_directory;
  /// The input is already sorted by this coordinate (non-decreasing): the
  /// principal axis and the external sort are skipped, the sweep reads the
  /// source as it is, along that axis, and the output keeps the input
  /// order.  The first pass still counts the points, checks that they are
  /// finite and checks the order (`std::runtime_error` naming the first
  /// point out of order, before any other work).  `Presorted_axis::NONE`
  /// (the default): the input may be in any order.
  Presorted_axis presorted_axis = Presorted_axis::NONE;
  /// Components of fewer points are dropped: not handed to the sink, not
  /// written to the component files, and counted in
  /// `Streaming_result::number_of_dropped_points` and
  /// `number_of_dropped_components`.  0 or 1: every point is kept.
  std::uint64_t minimum_component_size = 0;
  /// One file per kept connected component, written after the sink has
  /// had every point: `component_000000.ply`, `component_000001.ply`, ...
  /// (six digits or more, the extension of `Component_files_options`),
  /// numbered by decreasing size (ties: in the sweep order of their first
  /// point), each holding the points of its component in the sweep order,
  /// with the same coordinates and normals as the sink gets.  Each file is
  /// written to a temporary file and renamed when complete; files of the
  /// same names are replaced, other files of the directory are left alone.
  /// When the run fails or is cancelled, the component files it has
  /// written are removed.  Not written when `directory` is empty.
  Component_files_options component_files;
  /// Progress and cancellation: called from the calling thread at the start
  /// and the end of every stage and as it goes (per chunk read, per batch of
  /// the sweep); returning `false` stops the run with `Interrupted`
  /// (temporary files removed, nothing more handed to the sink, the
  /// component files written so far removed).  Empty: no reports.
  std::function<bool(const Streaming_progress&)> callback;
};

/// \ingroup PkgNormalOrientationStreaming
/// What `streaming_orient_normals()` did.
struct Streaming_result
{
  std::uint64_t number_of_points = 0;   ///< points oriented (the dropped ones included)
  std::uint64_t number_of_edges = 0;    ///< edges of the (implicit) neighbour graph
  std::size_t number_of_segments = 0;   ///< segments, the vertices of the segment graph
  std::size_t number_of_segment_edges = 0; ///< edges of the segment graph
  std::size_t number_of_components = 0; ///< connected components (the dropped ones included)
  std::size_t number_of_dropped_components = 0; ///< components below `Streaming_options::minimum_component_size`
  std::uint64_t number_of_dropped_points = 0;   ///< their points, not handed to the sink
  std::size_t peak_window = 0;          ///< most points held by the sweep at once
  double neighbor_radius = 0.0;         ///< r used
  bool radius_estimated = false;        ///< r was estimated from a sample
  bool presorted = false;               ///< the input was read as presorted (no principal axis, no sort)
  double segment_energy_before = 0.0;   ///< energy of the segment graph, preliminary orientation
  double segment_energy_after = 0.0;    ///< energy of the segment graph after the solver
  /// energy of the point graph (every edge, as in core) with the labelling
  /// of the segment graph's solution, before the refinement
  double energy_before_refinement = 0.0;
  /// energy of the point graph after the refinement (the final labelling,
  /// up to the free sign of each component); never above
  /// `energy_before_refinement`, equal to it without refinement
  double energy_after_refinement = 0.0;
  /// the rounds of the refinement whose new segment graph lowered the energy
  unsigned int refinement_rounds_accepted = 0;
  /// the single-point moves of the refinement, over all its passes
  std::uint64_t refinement_moves = 0;
  /// the most points back, in the sweep order, that an edge reaches: the
  /// refinement holds twice as many points at once
  std::uint64_t edge_span = 0;
  std::uint64_t number_of_flipped = 0;  ///< normals handed to the sink whose sign changed
  /// the component files written, by rank (largest component first)
  std::vector<std::string> component_files;
  /// seconds per stage (`frame`: the first pass over the input, whatever it
  /// computes; `components`: the component files)
  struct Seconds
  {
    /// @{
    /// wall-clock seconds of the stage of that name (see `Streaming_stage`;
    /// `total`: the whole call)
    double frame = 0, radius = 0, sort = 0, sweep = 0, solve = 0, refine = 0, sign = 0, output = 0, components = 0,
           total = 0;
    /// @}
  } seconds; ///< seconds per stage
};

/// \cond SKIP_IN_MANUAL
namespace internal {

/// a point after the sweep: the record, its segment and its preliminary flip
struct Swept_record
{
  Point_record record;
  std::uint32_t segment;
  std::int32_t flip;
};

/// a point with its final sign and the rank of its component, as kept in
/// the temporary group files of the component output
struct Ranked_record
{
  Point_record record;
  std::uint64_t rank;
};

/// what the sweep keeps per point in its window
struct Sweep_payload
{
  std::uint32_t segment = 0;
  Label flip = 1;
};

/// unit normal of a record (zero when the normal is zero)
inline std::array<double, 3> unit_normal(const Point_record& r)
{
  const double l2 = r.normal[0] * r.normal[0] + r.normal[1] * r.normal[1] + r.normal[2] * r.normal[2];
  if (!(l2 > 0.0))
    return {0.0, 0.0, 0.0};
  const double inv = 1.0 / std::sqrt(l2);
  return {r.normal[0] * inv, r.normal[1] * inv, r.normal[2] * inv};
}

/// Hands `record` to `sink`, with the segment of the point and whether its
/// normal was negated when the sink takes them (see `PointRecordSink`).
template <typename Sink>
void hand_to_sink(Sink& sink, const Point_record& record, std::uint32_t segment, bool flipped)
{
  if constexpr (std::is_invocable_v<Sink&, const Point_record&, std::uint32_t, bool>)
    sink(record, segment, flipped);
  else if constexpr (std::is_invocable_v<Sink&, const Point_record&, std::uint32_t>)
    sink(record, segment);
  else
    sink(record);
}

/// Calls the user's progress callback, if any; throws `Interrupted` when it
/// returns false.
class Streaming_reporter
{
public:
  explicit Streaming_reporter(const std::function<bool(const Streaming_progress&)>& callback)
    : m_callback(callback)
  {}
  void operator()(Streaming_stage stage, std::uint64_t done, std::uint64_t total) const
  {
    if (!m_callback)
      return;
    Streaming_progress p;
    p.stage = stage;
    p.done = done;
    p.total = total;
    if (!m_callback(p))
      throw Interrupted();
  }

private:
  const std::function<bool(const Streaming_progress&)>& m_callback;
};

/// A source that reports, after every read, the number of records read so
/// far (for the progress of the external sort).
template <typename Source>
class Reporting_source
{
public:
  Reporting_source(Source& source, const Streaming_reporter& report, Streaming_stage stage, std::uint64_t total)
    : m_source(source), m_report(report), m_stage(stage), m_total(total)
  {}
  std::size_t read(std::vector<Point_record>& chunk, std::size_t maximum)
  {
    const std::size_t got = m_source.read(chunk, maximum);
    m_count += got;
    m_report(m_stage, std::min(m_count, m_total), m_total);
    return got;
  }
  void rewind()
  {
    m_source.rewind();
    m_count = 0;
  }

private:
  Source& m_source;
  const Streaming_reporter& m_report;
  Streaming_stage m_stage;
  std::uint64_t m_total;
  std::uint64_t m_count = 0;
};

/// The component files of one run: creates their directory, names them,
/// and removes those written (and the directory, if it created it and it is
/// empty) unless `keep()` was called.
class Component_file_set
{
public:
  explicit Component_file_set(const Component_files_options& options)
    : m_directory(options.directory), m_extension(options.extension.empty() ? std::string(".ply") : options.extension)
  {
    if (m_directory.empty())
      return;
    const std::string e = IO::lower_case_extension("f" + m_extension);
    if (e != ".ply" && e != ".xyz" && e != ".pwn")
      throw std::invalid_argument("streaming_orient_normals: unknown component file extension '" + m_extension +
                                  "' (expected .ply, .xyz or .pwn)");
    std::error_code ec;
    if (std::filesystem::is_directory(m_directory, ec))
      return;
    if (std::filesystem::exists(m_directory, ec))
      IO::internal::fail(m_directory, "cannot write the component files: not a directory");
    m_created = std::filesystem::create_directories(m_directory, ec);
    if (ec)
      IO::internal::fail(m_directory, "cannot create the directory of the component files: " + ec.message());
  }
  Component_file_set(const Component_file_set&) = delete;
  Component_file_set& operator=(const Component_file_set&) = delete;
  ~Component_file_set()
  {
    if (m_kept)
      return;
    std::error_code ec;
    for (const std::string& f : m_written)
      std::filesystem::remove(f, ec);
    if (m_created)
      std::filesystem::remove(m_directory, ec); // only if empty
  }
  /// true when component files are wanted
  bool enabled() const { return !m_directory.empty(); }
  /// the name of the file of the component of rank `rank`
  std::string path(std::size_t rank) const
  {
    char name[48];
    std::snprintf(name, sizeof name, "component_%06zu", rank);
    return (std::filesystem::path(m_directory) / (name + m_extension)).string();
  }
  /// records that the file `path` was written (committed)
  void written(const std::string& path) { m_written.push_back(path); }
  /// the files written, in order
  const std::vector<std::string>& files() const { return m_written; }
  /// the run succeeded: keep the files
  void keep() { m_kept = true; }

private:
  std::string m_directory, m_extension;
  std::vector<std::string> m_written;
  bool m_created = false, m_kept = false;
};

} // namespace internal
/// \endcond

/// \ingroup PkgNormalOrientationStreaming
/// Orients the points of `source` out of core and hands them to `sink`
/// (`sink(const Point_record&)`, called once per point kept, in
/// the sweep order, with the oriented normal: only its sign differs from the
/// input's; a sink callable as `sink(record, std::uint32_t segment)` is
/// called so, with the segment of the point: the segments are numbered 0 to
/// `Streaming_result::number_of_segments` - 1 in the order the sweep opened
/// them, and each holds at least one point).
///
/// `source` is a streaming source (`read(chunk, maximum)`, `rewind()`; see
/// `external_sort.h`), read twice: a first pass, then the external sort, or,
/// with `Streaming_options::presorted_axis`, the sweep itself.  Stages:
///  1. the first pass (`Streaming_stage::SCAN`): the number of points, the
///     check that their coordinates are finite, the centroid and principal
///     axis (`Sweep_frame`, as `compute_sweep_frame()` gives it; not with a
///     presorted input, whose order is checked instead) and, when r is not
///     given, a uniform sample of at most 200,000 points;
///  2. r, when not given: 4 x the 90th percentile of the k-th neighbour
///     distance of the sample, scaled by sqrt(sample / n) (the spacing of a
///     surface sample);
///  3. the external sort along the axis (bounded memory, temporary files);
///     skipped with a presorted input;
///  4. the sweep (`streaming::sweep()`), along the axis or the presorted
///     coordinate: each point meets its earlier
///     neighbours of the k-nearest-neighbour graph, gets its edge weights
///     w = phi * (1 - d^2 / r^2) (in parallel per batch, with the input
///     normals; the neighbours' preliminary flips multiply them, as labels
///     do in core) and is
///     segmented (`Segmenter`); points leaving the window
///     go to a temporary record file (the sort's files are removed then);
///  5. `solver` on the segment graph (a BGL graph);
///  6. the outward sign of every connected component, from two passes over
///     the record file (the rule of `Outward_component_sign`);
///  7. the record file is re-streamed to `sink` with the final signs,
///     without the components smaller than
///     `Streaming_options::minimum_component_size`;
///  8. optionally, one file per kept component
///     (`Streaming_options::component_files`).
///
/// The neighbour graph does not depend on the sweep order: with the same
/// r, a presorted input gives the same graph as the sorted path (up to ties
/// in distance; r estimated from more than 200,000 points depends on the
/// input order through the sample); the segmentation, made in the sweep
/// order, may differ slightly.
/// Memory: the sweep window, the sort budget, O(segments + segment pairs +
/// components), and 1 MiB per open component file; the temporary files are
/// removed on success, on exceptions and on cancellation.
///
/// \warning With `presorted_axis`, the input must be sorted by
///          non-decreasing coordinate; the first pass checks it.
/// \throw std::invalid_argument for bad options; std::runtime_error when a
///        presorted input is not sorted (naming the point), and from the
///        source, the sort and the temporary files (also std::system_error);
///        `IO::Io_error` when a component file cannot be written;
///        `Interrupted` when the callback returns false
///
/// \tparam ConcurrencyTag `CGAL::Parallel_tag`, `CGAL::Sequential_tag` or
///         `CGAL::Parallel_if_available_tag` (the default); the result does
///         not depend on it
/// \tparam Kernel the \cgal kernel of the computations (the records hold doubles)
/// \tparam Source a model of `PointRecordSource`
/// \tparam Sink a model of `PointRecordSink`
/// \tparam FlipCriterion a model of `FlipCriterion`
/// \tparam Solver a model of `OrientationSolver`, run without unary terms on
///         the segment graph
/// \param source the points, read twice
/// \param sink receives every point kept, oriented, in the sweep order
/// \param options k, r, the segmentation, the sort, the presorted axis, the
///        component files, the progress callback
/// \param criterion the flip criterion
/// \param solver the solver of the segment graph
/// \return the figures of the run
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag,
          typename Kernel = CGAL::Exact_predicates_inexact_constructions_kernel, typename Source, typename Sink,
          typename FlipCriterion = Hoppe_criterion, typename Solver = Qpbo_i_solver>
Streaming_result streaming_orient_normals(Source& source, Sink& sink, const Streaming_options& options = Streaming_options(),
                                          const FlipCriterion& criterion = FlipCriterion(),
                                          const Solver& solver = Solver())
{
  typedef typename Kernel::Point_3 Point;
  typedef typename Kernel::Vector_3 Vector;
  using Clock = std::chrono::steady_clock;
  auto since = [](Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); };
  const auto t_start = Clock::now();
  Streaming_result result;
  if (options.number_of_neighbors < 1)
    throw std::invalid_argument("streaming_orient_normals: the number of neighbors must be at least 1");
  if (options.radius != 0.0 && !(options.radius > 0.0 && std::isfinite(options.radius)))
    throw std::invalid_argument("streaming_orient_normals: the radius must be a finite number > 0");
  const unsigned int k = options.number_of_neighbors;
  const bool presorted = options.presorted_axis != Presorted_axis::NONE;
  const int axis = options.presorted_axis == Presorted_axis::Y ? 1 : options.presorted_axis == Presorted_axis::Z ? 2 : 0;
  result.presorted = presorted;
  const internal::Streaming_reporter report(options.callback);
  internal::Component_file_set component_files(options.component_files); // checks and creates the directory

  // 1. The first pass: count, finiteness, frame (or order), radius sample.
  auto t = Clock::now();
  report(Streaming_stage::SCAN, 0, 0);
  const bool estimate_radius = options.radius == 0.0;
  std::vector<Point> sample;
  std::uint64_t n = 0, non_finite = 0;
  streaming::Sweep_frame frame;
  {
    streaming::internal::Moment_accumulator moments;
    const std::size_t m = 200000;
    std::mt19937_64 rng(0x5eed);
    std::vector<Point_record> chunk;
    chunk.reserve(65536);
    double last = -HUGE_VAL;
    source.rewind();
    while (true) { // reservoir sampling, deterministic
      chunk.clear();
      if (source.read(chunk, 65536) == 0)
        break;
      for (const Point_record& r : chunk) {
        const bool finite = std::isfinite(r.position[0]) && std::isfinite(r.position[1]) && std::isfinite(r.position[2]);
        if (!finite)
          ++non_finite;
        if (presorted) {
          if (finite) {
            const double v = r.position[axis];
            if (v < last) {
              std::ostringstream msg;
              msg.precision(17);
              msg << "streaming_orient_normals: the input is not sorted by increasing " << char('x' + axis)
                  << " (presorted_axis): point " << n << " (input index " << r.index << ") has " << char('x' + axis)
                  << " = " << v << ", below the previous point's " << last;
              throw std::runtime_error(msg.str());
            }
            last = v;
          }
        } else
          moments.add(r);
        if (estimate_radius) {
          const Point p(r.position[0], r.position[1], r.position[2]);
          if (sample.size() < m)
            sample.push_back(p);
          else {
            const std::uint64_t j = rng() % (n + 1);
            if (j < m)
              sample[std::size_t(j)] = p;
          }
        }
        ++n;
      }
      report(Streaming_stage::SCAN, n, 0);
    }
    source.rewind();
    if (!presorted)
      frame = moments.frame();
  }
  report(Streaming_stage::SCAN, n, n);
  result.seconds.frame = since(t);
  if (non_finite > 0)
    throw std::runtime_error("streaming_orient_normals: the input has points with non-finite coordinates");
  if (n == 0) {
    component_files.keep();
    result.seconds.total = since(t_start);
    return result;
  }

  // 2. Radius.
  t = Clock::now();
  double radius = options.radius;
  if (estimate_radius) {
    report(Streaming_stage::RADIUS, 0, 1);
    const unsigned int ks = unsigned(std::min<std::size_t>(k, sample.size() > 1 ? sample.size() - 1 : 0));
    if (ks > 0) {
      { // queries in Morton order are several times faster (the quantile does not depend on the order)
        const std::vector<std::uint32_t> order = internal::morton_order<ConcurrencyTag>(sample);
        std::vector<Point> sorted(sample.size());
        for (std::size_t i = 0; i < order.size(); ++i)
          sorted[i] = sample[order[i]];
        sample.swap(sorted);
      }
      std::vector<std::uint32_t> nb;
      std::vector<float> d2;
      internal::k_nearest_neighbors<ConcurrencyTag, Kernel>(sample, ks, nb, d2,
                                                            internal::Progress(std::function<bool(double)>()), 0, 1);
      std::vector<float> kth(sample.size());
      for (std::size_t i = 0; i < sample.size(); ++i)
        kth[i] = d2[i * ks + (ks - 1)];
      auto q = kth.begin() + std::ptrdiff_t(std::min(kth.size() - 1, std::size_t(default_radius_percentile * double(kth.size()))));
      std::nth_element(kth.begin(), q, kth.end());
      radius = default_radius_factor * std::sqrt(double(*q)) * std::sqrt(double(sample.size()) / double(n));
    }
    if (!(radius > 0.0) || !std::isfinite(radius))
      radius = 1.0;
    result.radius_estimated = true;
    std::vector<Point>().swap(sample);
    report(Streaming_stage::RADIUS, 1, 1);
  }
  result.neighbor_radius = radius;
  result.seconds.radius = since(t);

  // 3. Sort (unless presorted).
  t = Clock::now();
  streaming::Sorted_run_reader sorted;
  if (!presorted) {
    report(Streaming_stage::SORT, 0, n);
    internal::Reporting_source<Source> counted(source, report, Streaming_stage::SORT, n);
    sorted = streaming::external_sort(counted, frame, options.sort);
    report(Streaming_stage::SORT, n, n);
    result.seconds.sort = since(t);
  }

  // 4. Sweep and segmentation.
  t = Clock::now();
  report(Streaming_stage::SWEEP, 0, n);
  streaming::Record_file<internal::Swept_record> records(options.temporary_directory);
  const bool refine = options.refinement.rounds > 0;
  // for the refinement, the earlier edges of every point in the sweep order,
  // each point's after a header entry whose offset is their number
  std::unique_ptr<streaming::Record_file<streaming::Earlier_edge>> edges;
  if (refine)
    edges = std::make_unique<streaming::Record_file<streaming::Earlier_edge>>(options.temporary_directory, 1 << 16);
  Segmenter segmenter(options.thresholds);
  std::vector<std::uint64_t> segment_size;
  const double r2 = radius * radius;
  struct Visitor
  {
    const FlipCriterion& criterion;
    Segmenter& segmenter;
    streaming::Record_file<internal::Swept_record>& records;
    streaming::Record_file<streaming::Earlier_edge>* edges;
    std::vector<std::uint64_t>& segment_size;
    double r2;
    const internal::Streaming_reporter& report;
    std::uint64_t n;
    std::vector<Neighbor_vote> votes;
    std::uint64_t span = 0; // the farthest back an edge reaches

    // The edge weights of a whole batch, in parallel, with the input
    // normals (as in the in-core graph, in single precision); the
    // neighbours' preliminary flips are applied in `finalize`.
    std::vector<float> weights;
    std::size_t cursor = 0;
    void prepare(streaming::Sweep_window<internal::Sweep_payload>& w, std::uint64_t first,
                 const std::vector<std::size_t>& offsets, const std::vector<streaming::Sweep_neighbor>& neighbors)
    {
      report(Streaming_stage::SWEEP, first, n); // `first` points are finalised
      weights.resize(neighbors.size());
      cursor = 0;
      internal::parallel_chunks<ConcurrencyTag>(offsets.size() - 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t q = b; q < e; ++q) {
          const Point_record& p = w.record(first + q);
          const std::array<double, 3> np = internal::unit_normal(p);
          const Point pp(p.position[0], p.position[1], p.position[2]);
          const Vector vp(np[0], np[1], np[2]);
          for (std::size_t t = offsets[q]; t < offsets[q + 1]; ++t) {
            const Point_record& o = w.record(neighbors[t].sequence);
            const std::array<double, 3> no = internal::unit_normal(o);
            const double omega = 1.0 - double(neighbors[t].squared_distance) / r2;
            weights[t] = float(criterion(pp, vp, Point(o.position[0], o.position[1], o.position[2]),
                                         Vector(no[0], no[1], no[2])) *
                               omega);
          }
        }
      }, 256);
    }
    void finalize(streaming::Sweep_window<internal::Sweep_payload>& w, std::uint64_t s,
                  const std::vector<streaming::Sweep_neighbor>& earlier)
    {
      votes.clear();
      if (edges != nullptr) { // a header (the number of edges), then the edges
        const std::uint64_t farthest = earlier.empty() ? 0 : s - earlier.front().sequence; // sorted
        if (farthest > std::uint64_t(std::numeric_limits<std::uint32_t>::max()) ||
            earlier.size() > std::size_t(std::numeric_limits<std::uint32_t>::max()))
          throw std::length_error("streaming_orient_normals: the sweep window is too large for the refinement");
        span = std::max(span, farthest);
        edges->append(streaming::Earlier_edge{std::uint32_t(earlier.size()), 0.0f});
      }
      for (const streaming::Sweep_neighbor& nb : earlier) {
        const internal::Sweep_payload& pq = w.payload(nb.sequence);
        const float weight = weights[cursor++];
        votes.push_back({pq.segment, double(weight) * double(pq.flip)});
        if (edges != nullptr)
          edges->append(streaming::Earlier_edge{std::uint32_t(s - nb.sequence), weight});
      }
      const Segment_assignment a = segmenter.add_point(votes);
      w.payload(s) = internal::Sweep_payload{a.segment, a.flip};
      if (a.segment >= segment_size.size())
        segment_size.resize(a.segment + 1, 0);
      ++segment_size[a.segment];
    }
    void release(streaming::Sweep_window<internal::Sweep_payload>& w, std::uint64_t s)
    {
      records.append(internal::Swept_record{w.record(s), w.payload(s).segment, std::int32_t(w.payload(s).flip)});
    }
  } visitor{criterion, segmenter, records, edges.get(), segment_size, r2, report, n, {}, 0, {}, 0};
  streaming::Sweep_window<internal::Sweep_payload> window;
  streaming::Sweep_options so;
  so.number_of_neighbors = k;
  so.radius = radius;
  so.batch_size = options.batch_size;
  const streaming::Sweep_report sr =
    presorted ? streaming::sweep<ConcurrencyTag, Kernel>(
                  source, [axis](const Point_record& r) { return r.position[axis]; }, so, visitor, window)
              : streaming::sweep<ConcurrencyTag, Kernel>(
                  sorted, [&frame](const Point_record& r) { return frame.key(r); }, so, visitor, window);
  sorted = streaming::Sorted_run_reader(); // removes the sort's files
  if (presorted)
    source.rewind();
  records.rewind();
  if (edges)
    edges->rewind();
  result.number_of_points = sr.number_of_points;
  result.number_of_edges = sr.number_of_edges;
  result.peak_window = sr.peak_window;
  result.edge_span = visitor.span;
  report(Streaming_stage::SWEEP, n, n);
  result.seconds.sweep = since(t);

  // 5. The segment graph and its solution.
  t = Clock::now();
  report(Streaming_stage::SOLVE, 0, 1);
  const std::size_t ns = segmenter.number_of_segments();
  result.number_of_segments = ns;
  const Neighbor_graph sg = streaming::internal::make_segment_graph(segmenter);
  result.number_of_segment_edges = num_edges(sg);
  const auto weight = get(&Neighbor_edge::weight, sg);
  std::vector<Label> x(ns, Label(1));
  result.segment_energy_before = energy(sg, weight, CGAL::make_property_map(x));
  solver.solve(sg, weight, CGAL::make_property_map(x));
  result.segment_energy_after = energy(sg, weight, CGAL::make_property_map(x));
  std::vector<std::uint32_t> component;
  const std::size_t nc = connected_components(sg, weight, component);
  result.number_of_components = nc;
  report(Streaming_stage::SOLVE, 1, 1);
  result.seconds.solve = since(t);

  // 5b. The refinement: rounds of one pass over the points (single-point
  //     moves, then segmentation around the new labelling) and one solve of
  //     the new segment graph.  The labels of a pass come from the record
  //     file (preliminary flip times the segment's label) in the first
  //     round, then from the label file of the previous round (label times
  //     the label of its new segment); so do the final labels.
  //     It is skipped when no edge contradicts the labelling (its energy,
  //     known from the segment graph, is 0): nothing could improve it.
  std::unique_ptr<streaming::Record_file<std::uint32_t>> final_labels;
  std::vector<Label> final_segment_label; // the labels of the segments of `final_labels`
  result.energy_before_refinement = segmenter.point_energy(x);
  result.energy_after_refinement = result.energy_before_refinement;
  if (refine) {
    t = Clock::now();
    const unsigned int rounds = result.energy_before_refinement > 0.0 ? options.refinement.rounds : 0;
    const std::uint64_t total = std::uint64_t(options.refinement.rounds) * n;
    const bool prefetch = std::is_convertible<ConcurrencyTag, CGAL::Parallel_tag>::value;
    report(Streaming_stage::REFINE, 0, total);
    std::vector<Label> segment_label; // the labels of the segments of the label file read
    std::unique_ptr<streaming::Record_file<std::uint32_t>> in, out;
    std::uint64_t done = 0;
    for (unsigned int round = 0; round < rounds; ++round) {
      Segmentation_thresholds theta = options.refinement.thresholds;
      theta.maximum_size = options.refinement.maximum_segment_size(n, round);
      Segmenter resegmenter(theta, false);
      out = std::make_unique<streaming::Record_file<std::uint32_t>>(options.temporary_directory, 1 << 16);
      streaming::internal::Relabelling_window pass(result.edge_span, &resegmenter, false);
      auto write = [&out](Label label, std::uint32_t segment) {
        if (segment > (std::numeric_limits<std::uint32_t>::max() >> 1))
          throw std::length_error("streaming_orient_normals: too many segments in the refinement");
        out->append((segment << 1) | (label < 0 ? 1u : 0u));
      };
      streaming::internal::Edge_reader edge_reader(*edges, prefetch);
      const streaming::Earlier_edge* point_edges = nullptr;
      std::size_t count = 0;
      if (round == 0) {
        streaming::internal::Record_reader<internal::Swept_record> reader(records, std::size_t(1) << 15, prefetch);
        while (true) {
          const std::vector<internal::Swept_record>& chunk = reader.next();
          if (chunk.empty())
            break;
          for (const internal::Swept_record& s : chunk) {
            edge_reader.next(point_edges, count);
            pass.push(Label(s.flip * x[s.segment]), point_edges, count, write);
          }
          done += chunk.size();
          report(Streaming_stage::REFINE, done, total);
        }
      } else {
        streaming::internal::Record_reader<std::uint32_t> reader(*in, std::size_t(1) << 16, prefetch);
        while (true) {
          const std::vector<std::uint32_t>& chunk = reader.next();
          if (chunk.empty())
            break;
          for (const std::uint32_t word : chunk) {
            edge_reader.next(point_edges, count);
            pass.push(Label(((word & 1u) != 0 ? -1 : 1) * segment_label[word >> 1]), point_edges, count, write);
          }
          done += chunk.size();
          report(Streaming_stage::REFINE, done, total);
        }
      }
      pass.finish(write);
      out->flush();
      const streaming::internal::Relabelling_report& pr = pass.report();
      if (pr.points != n)
        throw std::runtime_error("streaming_orient_normals: the edge file and the record file disagree");
      result.refinement_moves += pr.moves;
      double change = 0.0;
      segment_label = streaming::internal::solve_segment_graph(resegmenter, solver, change);
      if (change < 0.0)
        ++result.refinement_rounds_accepted;
      result.energy_after_refinement = resegmenter.point_energy(segment_label);
      in = std::move(out);
    }
    final_labels = std::move(in);
    final_segment_label = std::move(segment_label);
    report(Streaming_stage::REFINE, total, total);
    result.seconds.refine = since(t);
  }
  edges.reset(); // removes the edge file

  // 6. Outward sign per component (the rule of Outward_component_sign, in
  //    two passes over the record file: extents, then votes).
  t = Clock::now();
  const Outward_component_sign rule;
  std::vector<std::uint64_t> size(nc, 0);
  for (std::size_t s = 0; s < ns; ++s)
    size[component[s]] += segment_size[s];
  const unsigned D = std::max(1u, rule.number_of_directions);
  std::vector<std::array<double, 3>> dir(D);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (unsigned d = 0; d < D; ++d) {
    const double z = 1.0 - (2.0 * d + 1.0) / double(D);
    const double sz = std::sqrt(std::max(0.0, 1.0 - z * z));
    dir[d] = {sz * std::cos(golden * d), sz * std::sin(golden * d), z};
  }
  std::vector<std::uint64_t> stride(nc, 1), seen(nc, 0);
  for (std::size_t c = 0; c < nc; ++c)
    stride[c] = std::max<std::uint64_t>(1, (size[c] + rule.maximum_voters - 1) / std::max<std::size_t>(1, rule.maximum_voters));
  const bool any_large = std::any_of(size.begin(), size.end(),
                                     [&](std::uint64_t s) { return s >= rule.minimum_size_for_directions; });
  std::vector<double> hi(any_large ? nc * D : 0, -HUGE_VAL), lo(any_large ? nc * D : 0, HUGE_VAL),
    num(any_large ? nc * D : 0, 0.0), den(any_large ? nc * D : 0, 0.0);
  std::vector<std::array<double, 3>> sum_p(nc, {0, 0, 0}), sum_n(nc, {0, 0, 0});
  std::vector<double> sum_pn(nc, 0.0);
  std::vector<internal::Swept_record> buffer;
  std::vector<Label> labels; // the label of every point of `buffer`, before the sign of its component
  std::vector<std::uint32_t> label_words;
  auto rewind_points = [&]() {
    records.rewind();
    if (final_labels)
      final_labels->rewind();
  };
  // reads the next points into `buffer` and their labels into `labels`;
  // returns how many (0 at the end)
  auto read_points = [&]() -> std::size_t {
    buffer.clear();
    const std::size_t got = records.read(buffer, 1 << 15);
    labels.resize(got);
    if (final_labels) {
      label_words.clear();
      if (got > 0 && final_labels->read(label_words, got) != got)
        throw std::runtime_error("streaming_orient_normals: the label file is shorter than the record file");
      for (std::size_t q = 0; q < got; ++q)
        labels[q] = Label(((label_words[q] & 1u) != 0 ? -1 : 1) * final_segment_label[label_words[q] >> 1]);
    } else {
      for (std::size_t q = 0; q < got; ++q)
        labels[q] = Label(buffer[q].flip * x[buffer[q].segment]);
    }
    return got;
  };
  auto oriented = [&](const internal::Swept_record& s, Label label) {
    std::array<double, 3> u = internal::unit_normal(s.record);
    const double f = double(label);
    return std::array<double, 3>{f * u[0], f * u[1], f * u[2]};
  };
  const int sign_passes = any_large ? 2 : 1;
  report(Streaming_stage::SIGN, 0, std::uint64_t(sign_passes) * n);
  for (int pass = 0; pass < sign_passes; ++pass) {
    std::fill(seen.begin(), seen.end(), 0);
    rewind_points();
    std::uint64_t read = 0;
    while (read_points() > 0) {
      read += buffer.size();
      for (std::size_t q = 0; q < buffer.size(); ++q) {
        const internal::Swept_record& s = buffer[q];
        const std::uint32_t c = component[s.segment];
        const double* p = s.record.position;
        if (size[c] < rule.minimum_size_for_directions) {
          if (pass == 0) {
            const std::array<double, 3> on = oriented(s, labels[q]);
            for (int d = 0; d < 3; ++d) {
              sum_p[c][d] += p[d];
              sum_n[c][d] += on[d];
            }
            sum_pn[c] += p[0] * on[0] + p[1] * on[1] + p[2] * on[2];
          }
          continue;
        }
        if (seen[c]++ % stride[c] != 0)
          continue;
        const std::array<double, 3> on = oriented(s, labels[q]);
        for (unsigned d = 0; d < D; ++d) {
          const double proj = p[0] * dir[d][0] + p[1] * dir[d][1] + p[2] * dir[d][2];
          const std::size_t slot = std::size_t(c) * D + d;
          if (pass == 0) {
            hi[slot] = std::max(hi[slot], proj);
            lo[slot] = std::min(lo[slot], proj);
          } else {
            const double depth = rule.band * (hi[slot] - lo[slot]);
            const double w = depth > 0.0 ? 1.0 - (hi[slot] - proj) / depth : (proj >= hi[slot] ? 1.0 : 0.0);
            if (w > 0.0) {
              num[slot] += w * (on[0] * dir[d][0] + on[1] * dir[d][1] + on[2] * dir[d][2]);
              den[slot] += w;
            }
          }
        }
      }
      report(Streaming_stage::SIGN, std::uint64_t(pass) * n + read, std::uint64_t(sign_passes) * n);
    }
  }
  std::vector<char> flip_component(nc, 0);
  for (std::size_t c = 0; c < nc; ++c) {
    double vote = 0.0;
    if (size[c] >= rule.minimum_size_for_directions) {
      for (unsigned d = 0; d < D; ++d) {
        const std::size_t slot = c * D + d;
        if (den[slot] > 0.0)
          vote += num[slot] / den[slot];
      }
    } else if (size[c] > 0) {
      // sum over points of (p - centroid) . n = sum p.n - centroid . sum n
      const double m = double(size[c]);
      vote = sum_pn[c] - (sum_p[c][0] * sum_n[c][0] + sum_p[c][1] * sum_n[c][1] + sum_p[c][2] * sum_n[c][2]) / m;
    }
    flip_component[c] = vote < 0.0 ? 1 : 0;
  }
  result.seconds.sign = since(t);

  // The components kept, ranked by decreasing size (ties: by component
  // number, the sweep order of their first segment).
  const std::uint64_t minimum = options.minimum_component_size;
  constexpr std::uint64_t dropped = ~std::uint64_t(0);
  std::vector<std::uint64_t> rank(nc, dropped);
  std::size_t kept = 0;
  std::uint64_t kept_points = 0;
  {
    std::vector<std::uint32_t> order;
    for (std::size_t c = 0; c < nc; ++c)
      if (size[c] > 0 && size[c] >= minimum)
        order.push_back(std::uint32_t(c));
      else if (size[c] > 0) {
        ++result.number_of_dropped_components;
        result.number_of_dropped_points += size[c];
      }
    std::stable_sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return size[a] > size[b]; });
    for (std::size_t i = 0; i < order.size(); ++i) {
      rank[order[i]] = i;
      kept_points += size[order[i]];
    }
    kept = order.size();
  }
  // the final record of a swept point; true when its normal was turned
  auto finish = [&](const internal::Swept_record& s, Label point_label, Point_record& out) {
    out = s.record;
    const int label = int(point_label) * (flip_component[component[s.segment]] ? -1 : 1);
    if (label >= 0)
      return false;
    for (double& v : out.normal)
      v = -v;
    return out.normal[0] != 0.0 || out.normal[1] != 0.0 || out.normal[2] != 0.0;
  };

  // 7. Output.
  t = Clock::now();
  report(Streaming_stage::OUTPUT, 0, n);
  rewind_points();
  {
    std::uint64_t read = 0;
    Point_record out;
    while (read_points() > 0) {
      read += buffer.size();
      for (std::size_t q = 0; q < buffer.size(); ++q) {
        const internal::Swept_record& s = buffer[q];
        if (rank[component[s.segment]] == dropped)
          continue;
        const bool flipped = finish(s, labels[q], out);
        if (flipped)
          ++result.number_of_flipped;
        internal::hand_to_sink(sink, out, s.segment, flipped);
      }
      report(Streaming_stage::OUTPUT, read, n);
    }
  }
  result.seconds.output = since(t);

  // 8. One file per kept component, at most G open at once.
  if (component_files.enabled() && kept > 0) {
    t = Clock::now();
    const std::size_t G = std::max<std::size_t>(1, options.component_files.maximum_open_files);
    const std::size_t groups = (kept + G - 1) / G;
    const std::size_t rounds = (groups + G - 1) / G;
    const std::uint64_t total = groups == 1 ? n : std::uint64_t(rounds) * n + kept_points;
    std::uint64_t done = 0;
    report(Streaming_stage::COMPONENTS, 0, total);
    std::vector<IO::Point_stream_writer> writers;
    IO::Point_stream_write_options component_write_options = options.component_files.write_options;
    component_write_options.segments = false;
    auto open_writers = [&](std::size_t first, std::size_t last) {
      writers.clear();
      writers.reserve(last - first);
      for (std::size_t r = first; r < last; ++r)
        writers.emplace_back(component_files.path(r), component_write_options);
    };
    auto commit_writers = [&]() {
      for (IO::Point_stream_writer& w : writers) {
        w.commit();
        component_files.written(w.filename());
      }
      writers.clear();
    };
    Point_record out;
    if (groups == 1) {
      open_writers(0, kept);
      rewind_points();
      while (read_points() > 0) {
        done += buffer.size();
        for (std::size_t q = 0; q < buffer.size(); ++q) {
          const internal::Swept_record& s = buffer[q];
          const std::uint64_t r = rank[component[s.segment]];
          if (r == dropped)
            continue;
          finish(s, labels[q], out);
          writers[std::size_t(r)].write(out);
        }
        report(Streaming_stage::COMPONENTS, done, total);
      }
      commit_writers();
    } else {
      std::vector<internal::Ranked_record> ranked;
      for (std::size_t round = 0; round < rounds; ++round) {
        // split the records of the groups of this round into one file per group
        const std::size_t first_group = round * G, last_group = std::min(groups, first_group + G);
        const std::uint64_t first_rank = std::uint64_t(first_group) * G,
                            last_rank = std::min<std::uint64_t>(kept, std::uint64_t(last_group) * G);
        std::vector<std::unique_ptr<streaming::Record_file<internal::Ranked_record>>> group_files;
        for (std::size_t g = first_group; g < last_group; ++g)
          group_files.push_back(
            std::make_unique<streaming::Record_file<internal::Ranked_record>>(options.temporary_directory, 4096));
        rewind_points();
        while (read_points() > 0) {
          done += buffer.size();
          for (std::size_t q = 0; q < buffer.size(); ++q) {
            const internal::Swept_record& s = buffer[q];
            const std::uint64_t r = rank[component[s.segment]];
            if (r == dropped || r < first_rank || r >= last_rank)
              continue;
            finish(s, labels[q], out);
            group_files[std::size_t(r / G) - first_group]->append(internal::Ranked_record{out, r});
          }
          report(Streaming_stage::COMPONENTS, done, total);
        }
        // then write each group, one file per component
        for (std::size_t g = first_group; g < last_group; ++g) {
          streaming::Record_file<internal::Ranked_record>& file = *group_files[g - first_group];
          open_writers(g * G, std::min(kept, (g + 1) * G));
          file.rewind();
          while (true) {
            ranked.clear();
            if (file.read(ranked, 1 << 14) == 0)
              break;
            done += ranked.size();
            for (const internal::Ranked_record& rr : ranked)
              writers[std::size_t(rr.rank - std::uint64_t(g) * G)].write(rr.record);
            report(Streaming_stage::COMPONENTS, done, total);
          }
          commit_writers();
          group_files[g - first_group].reset(); // removes the group file
        }
      }
    }
    report(Streaming_stage::COMPONENTS, total, total);
    result.seconds.components = since(t);
  }
  result.component_files = component_files.files();
  component_files.keep();
  result.seconds.total = since(t_start);
  return result;
}

/// \ingroup PkgNormalOrientationStreaming
/// Orients the cloud of the file `input` (.xyz/.pwn with normals, or .ply,
/// read in chunks by `IO::Point_stream_reader`) out of core with
/// `streaming_orient_normals()` and writes it to `output` (.xyz, .pwn or
/// .ply by extension; binary PLY unless `write_options.binary` is false).
/// The output holds the points in the sweep order (along the principal
/// axis; with `Streaming_options::presorted_axis`, the input order), with
/// their input coordinates and normals whose sign only may have changed,
/// without the components smaller than
/// `Streaming_options::minimum_component_size`.  It is written to a
/// temporary file renamed at the end: on any error no output file exists.
/// With `write_options.segments` (PLY only), each point of `output` also
/// gets its segment, as the vertex property `int segment` (the segments of
/// `streaming_orient_normals()`: as many distinct values as
/// `Streaming_result::number_of_segments` when no component is dropped).
/// With `Streaming_options::component_files` (a directory), one file per
/// kept component is written there too, by default in the output's format
/// (see `Component_files_options::extension`); they are removed when the
/// run fails, the output's last step included.
/// \throw IO::Io_error for unreadable, malformed or unwritable files, an
///        input without normals or without any point (as `read_point_cloud()`
///        does; no output is written then); see `streaming_orient_normals()`
/// \tparam ConcurrencyTag, Kernel, FlipCriterion, Solver as for `streaming_orient_normals()`
/// \param input the file to orient (.xyz/.pwn with normals, or .ply with normals)
/// \param output the file written (.xyz, .pwn or .ply)
/// \param options, criterion, solver as for `streaming_orient_normals()`
/// \param write_options how `output` is written (binary or ascii PLY, with the
///        segments, ...)
/// \return the figures of the run
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag,
          typename Kernel = CGAL::Exact_predicates_inexact_constructions_kernel,
          typename FlipCriterion = Hoppe_criterion, typename Solver = Qpbo_i_solver>
Streaming_result streaming_orient_files(const std::string& input, const std::string& output,
                                        const Streaming_options& options = Streaming_options(),
                                        const FlipCriterion& criterion = FlipCriterion(),
                                        const Solver& solver = Solver(),
                                        const IO::Point_stream_write_options& write_options =
                                          IO::Point_stream_write_options())
{
  IO::Point_stream_reader reader(input);
  if (!reader.has_normals())
    throw IO::Io_error(input + ": the file has no normals (streaming needs them)");
  IO::Point_stream_writer writer(output, write_options);
  Streaming_options o = options;
  if (!o.component_files.directory.empty() && o.component_files.extension.empty()) {
    o.component_files.extension = std::filesystem::path(output).extension().string();
    o.component_files.write_options = write_options;
  }
  auto sink = [&writer](const Point_record& r, std::uint32_t segment) {
    if (writer.has_segments())
      writer.write(r, segment);
    else
      writer.write(r);
  };
  Streaming_result result =
    streaming_orient_normals<ConcurrencyTag, Kernel>(reader, sink, o, criterion, solver);
  const auto t = std::chrono::steady_clock::now();
  if (result.number_of_points == 0) // as in core: an empty cloud is an error, not an empty output
    throw IO::Io_error(input + ": the file holds no point");
  try {
    writer.commit();
  } catch (...) {
    std::error_code ec;
    for (const std::string& f : result.component_files)
      std::filesystem::remove(f, ec);
    throw;
  }
  result.seconds.output += std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  return result;
}

/// \ingroup PkgNormalOrientationStreaming
/// Orients the cloud of the file `input` out of core, as
/// `streaming_orient_files()` does, and writes `output` as a copy of
/// `input` in its own order and format, in which only the signs of the
/// normals differ (see `IO::transcode_with_flips()`): every other vertex
/// property, the text of every value not negated, the header's comments
/// and the type of every property are kept; the components smaller than
/// `Streaming_options::minimum_component_size` are left out (their points
/// removed, the vertex count of a PLY header updated); as with
/// `IO::write_point_cloud()`, the PLY elements other than `vertex` are left
/// out.  The stream hands the oriented points to a sink that notes, by
/// input index, which normals to negate and which points to keep (2 bits
/// per point in memory, 25 MB for 100M points); then the input is copied
/// with those changes, in one more reading of the file, with fixed memory.
/// The output is written to a temporary file renamed at the end: on any
/// error or interruption no output file exists (an existing one is left
/// unchanged).  `Streaming_options::component_files` works as in
/// `streaming_orient_files()` (files in the sweep order, in the format of
/// `output`).  The copy is reported to `Streaming_options::callback` as the
/// stage `OUTPUT`, in bytes of the input.
/// \throw IO::Io_error for unreadable, malformed or unwritable files, an
///        input without normals or without any point, an `output` whose
///        format differs from `input`'s (checked before any work), normals
///        of an unsigned integer type that must be negated, an input that
///        changes while it is read; see `streaming_orient_files()`
/// \tparam ConcurrencyTag, Kernel, FlipCriterion, Solver as for `streaming_orient_normals()`
/// \param input the file to orient (.xyz/.pwn with normals, or .ply with normals)
/// \param output the file written, in the format of `input` (.ply for a .ply
///        input; .xyz or .pwn for a .xyz or .pwn input)
/// \param options, criterion, solver as for `streaming_orient_normals()`
/// \param transcode when not null, receives the figures of the copy
/// \return the figures of the run (`seconds.output` includes the copy)
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag,
          typename Kernel = CGAL::Exact_predicates_inexact_constructions_kernel,
          typename FlipCriterion = Hoppe_criterion, typename Solver = Qpbo_i_solver>
Streaming_result streaming_orient_files_in_input_order(const std::string& input, const std::string& output,
                                                       const Streaming_options& options = Streaming_options(),
                                                       const FlipCriterion& criterion = FlipCriterion(),
                                                       const Solver& solver = Solver(),
                                                       IO::Transcode_report* transcode = nullptr)
{
  IO::Point_stream_reader reader(input);
  if (!reader.has_normals())
    throw IO::Io_error(input + ": the file has no normals (streaming needs them)");
  const std::string in_ext = IO::lower_case_extension(input);
  const std::string out_ext = IO::lower_case_extension(output);
  if (out_ext != ".ply" && out_ext != ".xyz" && out_ext != ".pwn")
    throw IO::Io_error(output + ": unknown point cloud file extension '" + out_ext + "' (expected .xyz, .pwn or .ply)");
  if ((in_ext == ".ply") != (out_ext == ".ply"))
    throw IO::Io_error(output + ": the copy of '" + input + "' in its own order must be a " +
                       (in_ext == ".ply" ? std::string(".ply") : std::string(".xyz or .pwn")) + " file, as the input");
  Streaming_options o = options;
  if (!o.component_files.directory.empty() && o.component_files.extension.empty())
    o.component_files.extension = std::filesystem::path(output).extension().string();
  IO::Bit_set flip, keep;
  // the number of points is known (from the first pass) when the output stage starts
  o.callback = [&](const Streaming_progress& p) {
    if (p.stage == Streaming_stage::OUTPUT && p.done == 0 && keep.size() != p.total) {
      flip = IO::Bit_set(p.total);
      keep = IO::Bit_set(p.total);
    }
    return options.callback ? options.callback(p) : true;
  };
  auto sink = [&](const Point_record& r, std::uint32_t, bool flipped) {
    keep.set(r.index); // throws std::out_of_range on an index beyond the count
    if (flipped)
      flip.set(r.index);
  };
  Streaming_result result = streaming_orient_normals<ConcurrencyTag, Kernel>(reader, sink, o, criterion, solver);
  try {
    if (result.number_of_points == 0) // as in core: an empty cloud is an error, not an empty output
      throw IO::Io_error(input + ": the file holds no point");
    const auto t = std::chrono::steady_clock::now();
    IO::Transcode_options to;
    if (options.callback)
      to.callback = [&options](std::uint64_t done, std::uint64_t size) {
        Streaming_progress p;
        p.stage = Streaming_stage::OUTPUT;
        p.done = done;
        p.total = size;
        return options.callback(p);
      };
    const IO::Transcode_report tr =
      IO::transcode_with_flips(input, output, flip, result.number_of_dropped_points > 0 ? &keep : nullptr, to);
    if (transcode != nullptr)
      *transcode = tr;
    const double copy = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
    result.seconds.output += copy;
    result.seconds.total += copy;
  } catch (...) {
    std::error_code ec;
    for (const std::string& f : result.component_files)
      std::filesystem::remove(f, ec);
    throw;
  }
  return result;
}

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_ORIENT_NORMALS_H
