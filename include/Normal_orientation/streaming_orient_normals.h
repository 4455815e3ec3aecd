// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_ORIENT_NORMALS_H
#define NORMAL_ORIENTATION_STREAMING_ORIENT_NORMALS_H

/// \file streaming_orient_normals.h
/// The out-of-core entry point (paper sec. 5): orients clouds larger than
/// memory by sorting them along their principal axis, sweeping them with a
/// window of bounded size, segmenting on the fly, solving the segment graph
/// and re-streaming the points with their final signs.

#include <Normal_orientation/Component_sign.h>
#include <Normal_orientation/Flip_criteria.h>
#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/IO/Point_stream.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/solvers/Qpbo_i_solver.h>
#include <Normal_orientation/streaming/Point_record.h>
#include <Normal_orientation/streaming/Record_file.h>
#include <Normal_orientation/streaming/Segmenter.h>
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
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationStreaming
/// The parameters of `streaming_orient_normals()`.
struct Streaming_options
{
  /// k of the neighbour graph
  unsigned int number_of_neighbors = default_number_of_neighbors;
  /// r; 0 to estimate it from a uniform sample of the cloud (see
  /// `streaming_orient_normals()`)
  double radius = 0.0;
  /// the segmentation thresholds (the paper's defaults: theta_S = 0,
  /// theta_acc = 0.5)
  streaming::Segmentation_thresholds thresholds;
  /// points finalised per batch of the sweep
  std::size_t batch_size = std::size_t(1) << 18;
  /// the external sort (memory budget, temporary directory)
  streaming::External_sort_options sort;
  /// where the record file goes (empty: TMPDIR, else /tmp)
  std::string temporary_directory;
};

/// \ingroup PkgNormalOrientationStreaming
/// What `streaming_orient_normals()` did.
struct Streaming_result
{
  std::uint64_t number_of_points = 0;   ///< points oriented
  std::uint64_t number_of_edges = 0;    ///< edges of the (implicit) neighbour graph
  std::size_t number_of_segments = 0;   ///< segments, the vertices of the segment graph
  std::size_t number_of_segment_edges = 0; ///< edges of the segment graph
  std::size_t number_of_components = 0; ///< connected components
  std::size_t peak_window = 0;          ///< most points held by the sweep at once
  double neighbor_radius = 0.0;         ///< r used
  bool radius_estimated = false;        ///< r was estimated from a sample
  double segment_energy_before = 0.0;   ///< energy of the segment graph, preliminary orientation
  double segment_energy_after = 0.0;    ///< energy of the segment graph after the solver
  std::uint64_t number_of_flipped = 0;  ///< normals whose sign changed
  /// seconds per stage
  struct Seconds
  {
    double frame = 0, radius = 0, sort = 0, sweep = 0, solve = 0, sign = 0, output = 0, total = 0;
  } seconds;
};

/// \cond SKIP_IN_MANUAL
namespace internal {

/// a point after the sweep: the record, its segment and its preliminary flip
struct Swept_record
{
  streaming::Point_record record;
  std::uint32_t segment;
  std::int32_t flip;
};

/// what the sweep keeps per point in its window
struct Sweep_payload
{
  std::uint32_t segment = 0;
  Label flip = 1;
};

/// unit normal of a record (zero when the normal is zero)
inline std::array<double, 3> unit_normal(const streaming::Point_record& r)
{
  const double l2 = r.normal[0] * r.normal[0] + r.normal[1] * r.normal[1] + r.normal[2] * r.normal[2];
  if (!(l2 > 0.0))
    return {0.0, 0.0, 0.0};
  const double inv = 1.0 / std::sqrt(l2);
  return {r.normal[0] * inv, r.normal[1] * inv, r.normal[2] * inv};
}

} // namespace internal
/// \endcond

/// \ingroup PkgNormalOrientationStreaming
/// Orients the points of `source` out of core and hands them to `sink`
/// (`sink(const streaming::Point_record&)`, called once per point, in the
/// sweep order, with the oriented normal: only its sign differs from the
/// input's).
///
/// `source` is a streaming source (`read(chunk, maximum)`, `rewind()`; see
/// `external_sort.h`), read four times: the sweep frame, the radius sample,
/// the external sort, then the sorted stream.  Stages:
///  1. the centroid and principal axis (`compute_sweep_frame()`);
///  2. r, when not given: 4 x the 90th percentile of the k-th neighbour
///     distance of a uniform sample of at most 200,000 points, scaled by
///     sqrt(sample / n) (the spacing of a surface sample);
///  3. the external sort along the axis (bounded memory, temporary files);
///  4. the sweep (`streaming::sweep()`): each point meets its earlier
///     neighbours of the k-nearest-neighbour graph, gets its edge weights
///     w = phi * (1 - d^2 / r^2) (in parallel per batch, with the input
///     normals; the neighbours' preliminary flips multiply them, as labels
///     do in core) and is
///     segmented (`streaming::Segmenter`); points leaving the window
///     go to a temporary record file;
///  5. `solver` on the segment graph (a BGL graph);
///  6. the outward sign of every connected component, from two passes over
///     the record file (the rule of `Outward_component_sign`);
///  7. the record file is re-streamed to `sink` with the final signs.
/// Memory: the sweep window, the sort budget, and O(segments + segment
/// pairs); the temporary files are removed on success and on exceptions.
///
/// \throw std::invalid_argument for bad options; std::runtime_error and
///        std::system_error from the source, the sort and the temporary files
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

  // 1. Frame.
  auto t = Clock::now();
  const streaming::Sweep_frame frame = streaming::compute_sweep_frame(source);
  result.seconds.frame = since(t);
  const std::uint64_t n = frame.size;
  if (frame.non_finite > 0)
    throw std::runtime_error("streaming_orient_normals: the input has points with non-finite coordinates");
  if (n == 0) {
    result.seconds.total = since(t_start);
    return result;
  }

  // 2. Radius.
  t = Clock::now();
  double radius = options.radius;
  if (radius == 0.0) {
    const std::size_t m = std::size_t(std::min<std::uint64_t>(n, 200000));
    std::vector<Point> sample;
    sample.reserve(m);
    std::mt19937_64 rng(0x5eed);
    std::vector<streaming::Point_record> chunk;
    std::uint64_t seen = 0;
    source.rewind();
    while (true) { // reservoir sampling, deterministic
      chunk.clear();
      if (source.read(chunk, 65536) == 0)
        break;
      for (const auto& r : chunk) {
        const Point p(r.position[0], r.position[1], r.position[2]);
        if (sample.size() < m)
          sample.push_back(p);
        else {
          const std::uint64_t j = rng() % (seen + 1);
          if (j < m)
            sample[std::size_t(j)] = p;
        }
        ++seen;
      }
    }
    source.rewind();
    const unsigned int ks = unsigned(std::min<std::size_t>(k, sample.size() > 1 ? sample.size() - 1 : 0));
    if (ks > 0) {
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
  }
  result.neighbor_radius = radius;
  result.seconds.radius = since(t);

  // 3. Sort.
  t = Clock::now();
  streaming::Sorted_run_reader sorted = streaming::external_sort(source, frame, options.sort);
  result.seconds.sort = since(t);

  // 4. Sweep and segmentation.
  t = Clock::now();
  streaming::Record_file<internal::Swept_record> records(options.temporary_directory);
  streaming::Segmenter segmenter(options.thresholds);
  std::vector<std::uint64_t> segment_size;
  const double r2 = radius * radius;
  struct Visitor
  {
    const FlipCriterion& criterion;
    streaming::Segmenter& segmenter;
    streaming::Record_file<internal::Swept_record>& records;
    std::vector<std::uint64_t>& segment_size;
    double r2;
    std::vector<streaming::Neighbor_vote> votes;

    // The edge weights of a whole batch, in parallel, with the input
    // normals (as in the in-core graph, in single precision); the
    // neighbours' preliminary flips are applied in `finalize`.
    std::vector<float> weights;
    std::size_t cursor = 0;
    void prepare(streaming::Sweep_window<internal::Sweep_payload>& w, std::uint64_t first,
                 const std::vector<std::size_t>& offsets, const std::vector<streaming::Sweep_neighbor>& neighbors)
    {
      weights.resize(neighbors.size());
      cursor = 0;
      internal::parallel_chunks<ConcurrencyTag>(offsets.size() - 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t q = b; q < e; ++q) {
          const streaming::Point_record& p = w.record(first + q);
          const std::array<double, 3> np = internal::unit_normal(p);
          const Point pp(p.position[0], p.position[1], p.position[2]);
          const Vector vp(np[0], np[1], np[2]);
          for (std::size_t t = offsets[q]; t < offsets[q + 1]; ++t) {
            const streaming::Point_record& o = w.record(neighbors[t].sequence);
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
      for (const streaming::Sweep_neighbor& nb : earlier) {
        const internal::Sweep_payload& pq = w.payload(nb.sequence);
        votes.push_back({pq.segment, double(weights[cursor++]) * double(pq.flip)});
      }
      const streaming::Segment_assignment a = segmenter.add_point(votes);
      w.payload(s) = internal::Sweep_payload{a.segment, a.flip};
      if (a.segment >= segment_size.size())
        segment_size.resize(a.segment + 1, 0);
      ++segment_size[a.segment];
    }
    void release(streaming::Sweep_window<internal::Sweep_payload>& w, std::uint64_t s)
    {
      records.append(internal::Swept_record{w.record(s), w.payload(s).segment, std::int32_t(w.payload(s).flip)});
    }
  } visitor{criterion, segmenter, records, segment_size, r2, {}, {}, 0};
  streaming::Sweep_window<internal::Sweep_payload> window;
  streaming::Sweep_options so;
  so.number_of_neighbors = k;
  so.radius = radius;
  so.batch_size = options.batch_size;
  const streaming::Sweep_report sr = streaming::sweep<ConcurrencyTag, Kernel>(
    sorted, [&frame](const streaming::Point_record& r) { return frame.key(r); }, so, visitor, window);
  records.rewind();
  result.number_of_points = sr.number_of_points;
  result.number_of_edges = sr.number_of_edges;
  result.peak_window = sr.peak_window;
  result.seconds.sweep = since(t);

  // 5. The segment graph and its solution.
  t = Clock::now();
  const std::size_t ns = segmenter.number_of_segments();
  result.number_of_segments = ns;
  const auto& pairs = segmenter.segment_pairs();
  std::vector<std::uint32_t> sources, targets;
  std::vector<Neighbor_edge> props;
  for (std::size_t e = 0; e < pairs.size(); ++e)
    if (pairs.weight(e) != 0.0) {
      sources.push_back(pairs.first(e));
      targets.push_back(pairs.second(e));
      props.push_back(Neighbor_edge{float(pairs.weight(e))});
    }
  result.number_of_segment_edges = sources.size();
  Neighbor_graph sg(boost::construct_inplace_from_sources_and_targets, sources, targets, props, std::uint32_t(ns));
  const auto weight = get(&Neighbor_edge::weight, sg);
  std::vector<Label> x(ns, Label(1));
  result.segment_energy_before = energy(sg, weight, CGAL::make_property_map(x));
  solver.solve(sg, weight, CGAL::make_property_map(x));
  result.segment_energy_after = energy(sg, weight, CGAL::make_property_map(x));
  std::vector<std::uint32_t> component;
  const std::size_t nc = connected_components(sg, weight, component);
  result.number_of_components = nc;
  result.seconds.solve = since(t);

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
  auto oriented = [&](const internal::Swept_record& s) {
    std::array<double, 3> u = internal::unit_normal(s.record);
    const double f = double(s.flip) * double(x[s.segment]);
    return std::array<double, 3>{f * u[0], f * u[1], f * u[2]};
  };
  for (int pass = 0; pass < (any_large ? 2 : 1); ++pass) {
    std::fill(seen.begin(), seen.end(), 0);
    records.rewind();
    while (true) {
      buffer.clear();
      if (records.read(buffer, 1 << 15) == 0)
        break;
      for (const internal::Swept_record& s : buffer) {
        const std::uint32_t c = component[s.segment];
        const double* p = s.record.position;
        if (size[c] < rule.minimum_size_for_directions) {
          if (pass == 0) {
            const std::array<double, 3> on = oriented(s);
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
        const std::array<double, 3> on = oriented(s);
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

  // 7. Output.
  t = Clock::now();
  records.rewind();
  while (true) {
    buffer.clear();
    if (records.read(buffer, 1 << 15) == 0)
      break;
    for (internal::Swept_record& s : buffer) {
      const int label = s.flip * int(x[s.segment]) * (flip_component[component[s.segment]] ? -1 : 1);
      if (label < 0) {
        for (double& v : s.record.normal)
          v = -v;
        if (s.record.normal[0] != 0.0 || s.record.normal[1] != 0.0 || s.record.normal[2] != 0.0)
          ++result.number_of_flipped;
      }
      sink(s.record);
    }
  }
  result.seconds.output = since(t);
  result.seconds.total = since(t_start);
  return result;
}

/// \ingroup PkgNormalOrientationStreaming
/// Orients the cloud of the file `input` (.xyz/.pwn with normals, or .ply,
/// read in chunks by `IO::Point_stream_reader`) out of core with
/// `streaming_orient_normals()` and writes it to `output` (.xyz, .pwn or
/// .ply by extension; binary PLY unless `write_options.binary` is false).
/// The output holds the points in the sweep order (along the principal
/// axis), with their input coordinates and normals whose sign only may
/// have changed.  It is written to a temporary file renamed at the end: on
/// any error no output file exists.
/// \throw IO::Io_error for unreadable, malformed or unwritable files, or an
///        input without normals; see `streaming_orient_normals()`
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
  auto sink = [&writer](const streaming::Point_record& r) { writer.write(r); };
  Streaming_result result =
    streaming_orient_normals<ConcurrencyTag, Kernel>(reader, sink, options, criterion, solver);
  const auto t = std::chrono::steady_clock::now();
  writer.commit();
  result.seconds.output += std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  return result;
}

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_ORIENT_NORMALS_H
