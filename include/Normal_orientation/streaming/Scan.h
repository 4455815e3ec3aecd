// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_SCAN_H
#define NORMAL_ORIENTATION_STREAMING_SCAN_H

/// \file Scan.h
/// The first two stages of the streaming driver: the scan (one pass over
/// the source: count, finiteness, zero normals, the sweep frame or the
/// order of a presorted input, a uniform sample for the radius) and the
/// radius, estimated from that sample by the rule of the in-core graph.

#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/Point_record.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/internal/Clean_positions.h>
#include <Normal_orientation/internal/Parallel.h>
#include <Normal_orientation/streaming/external_sort.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// What the scan found.
template <typename Point>
struct Scan_result
{
  std::uint64_t number_of_points = 0;
  std::uint64_t number_of_zero_normals = 0;
  Sweep_frame frame;         ///< the principal frame (not for a presorted input)
  /// the bounding box of the points, for their Morton codes
  Normal_orientation::internal::Morton_code box;
  std::vector<Point> sample; ///< a uniform sample (when the radius is to be estimated)
  /// every record, when asked and there are at most
  /// `clean_positions_maximum_points` (else empty)
  std::vector<Point_record> small_cloud;
};

/// The points of the radius sample
constexpr std::size_t radius_sample_size = 200000;
static_assert(radius_sample_size == Normal_orientation::internal::clean_positions_maximum_points,
              "a small cloud kept for the rule of clean positions is its own radius sample");

/// Reads `source` once, from its start, and rewinds it.  `axis` is the
/// presorted coordinate (0, 1, 2), or -1 for an input in any order, whose
/// principal frame is then computed.  A deterministic reservoir sample of
/// at most `radius_sample_size` points is kept when `sample` is true, and
/// a copy of a cloud of at most `clean_positions_maximum_points` points when
/// `keep_small` is true.
/// \throw std::runtime_error for non-finite coordinates, or for a presorted
///        input out of order (naming the point)
template <typename Point, typename Source>
Scan_result<Point> scan(Source& source, int axis, bool sample, const Progress_reporter& progress,
                        bool keep_small = false)
{
  Scan_result<Point> result;
  Moment_accumulator moments;
  std::mt19937_64 rng(0x5eed);
  std::vector<Point_record> chunk;
  chunk.reserve(65536);
  double last = -HUGE_VAL;
  std::uint64_t n = 0, non_finite = 0;
  progress.report(0, 0);
  source.rewind();
  while (true) {
    chunk.clear();
    if (source.read(chunk, 65536) == 0)
      break;
    for (const Point_record& r : chunk) {
      const bool finite = std::isfinite(r.position[0]) && std::isfinite(r.position[1]) && std::isfinite(r.position[2]);
      if (!finite)
        ++non_finite;
      else
        result.box.add(r.position);
      if (r.normal[0] == 0.0 && r.normal[1] == 0.0 && r.normal[2] == 0.0)
        ++result.number_of_zero_normals;
      if (axis >= 0) {
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
      if (keep_small && n < Normal_orientation::internal::clean_positions_maximum_points)
        result.small_cloud.push_back(r);
      if (sample) {
        const Point p(r.position[0], r.position[1], r.position[2]);
        if (result.sample.size() < radius_sample_size)
          result.sample.push_back(p);
        else {
          const std::uint64_t j = rng() % (n + 1);
          if (j < radius_sample_size)
            result.sample[std::size_t(j)] = p;
        }
      }
      ++n;
    }
    progress.report(n, 0);
  }
  source.rewind();
  if (axis < 0)
    result.frame = moments.frame();
  result.number_of_points = n;
  result.box.close();
  if (n > Normal_orientation::internal::clean_positions_maximum_points)
    std::vector<Point_record>().swap(result.small_cloud);
  progress.report(n, n);
  if (non_finite > 0)
    throw std::runtime_error("streaming_orient_normals: the input has points with non-finite coordinates");
  return result;
}

/// The rule of `estimate_neighbor_radius()` over the k-th neighbour
/// distances of the kNN distances `d2` (k per point, k > 0), times `factor`.
inline double radius_of_neighbors(const std::vector<float>& d2, unsigned int k, double factor)
{
  std::vector<float> kth(d2.size() / k);
  for (std::size_t i = 0; i < kth.size(); ++i)
    kth[i] = d2[i * k + (k - 1)];
  return estimate_neighbor_radius(kth, factor);
}

/// r for a cloud of `n` points of which `sample` is a uniform sample: the
/// rule of `estimate_neighbor_radius()` over the sample's k-th neighbour
/// distances, scaled by sqrt(sample / n) (the spacing of a surface sample).
template <typename ConcurrencyTag, typename Kernel>
double sample_radius(const std::vector<typename Kernel::Point_3>& sample, unsigned int k, std::uint64_t n)
{
  const unsigned int ks = unsigned(std::min<std::size_t>(k, sample.size() > 1 ? sample.size() - 1 : 0));
  if (ks == 0)
    return 1.0;
  std::vector<std::uint32_t> nb;
  std::vector<float> d2; // (the quantile does not depend on the order of the rows)
  Normal_orientation::internal::morton_k_nearest_neighbors<ConcurrencyTag, Kernel>(sample, ks, nb, d2);
  return radius_of_neighbors(d2, ks, std::sqrt(double(sample.size()) / double(n)));
}

/// A small cloud (`Scan_result::small_cloud`) in Morton order, with the kNN
/// of each point (k lowered to the points - 1): what the rule of clean
/// positions measures, and, the cloud being its own radius sample, what the
/// radius is estimated from.
template <typename Kernel>
struct Small_cloud_neighbors
{
  std::vector<typename Kernel::Point_3> points;
  std::vector<typename Kernel::Vector_3> normals;
  std::vector<std::uint32_t> nb;
  std::vector<float> d2;
  unsigned int k = 0; ///< 0: fewer than 2 points, nothing searched
};

/// the kNN of `cloud` (see `Small_cloud_neighbors`)
template <typename ConcurrencyTag, typename Kernel>
Small_cloud_neighbors<Kernel> small_cloud_neighbors(const std::vector<Point_record>& cloud, unsigned int k)
{
  Small_cloud_neighbors<Kernel> out;
  if (cloud.size() < 2)
    return out;
  std::vector<typename Kernel::Point_3> points;
  for (const Point_record& r : cloud)
    points.emplace_back(r.position[0], r.position[1], r.position[2]);
  for (std::uint32_t i : Normal_orientation::internal::morton_order<ConcurrencyTag>(points)) {
    out.points.push_back(points[i]);
    out.normals.emplace_back(cloud[i].normal[0], cloud[i].normal[1], cloud[i].normal[2]);
  }
  out.k = unsigned(std::min<std::size_t>(k, cloud.size() - 1));
  Normal_orientation::internal::k_nearest_neighbors<ConcurrencyTag, Kernel>(out.points, out.k, out.nb, out.d2,
                                                                             Progress_reporter(), 0, 1);
  return out;
}

/// A source that reports, after every read, the number of records read so
/// far (for the progress of the external sort).
template <typename Source>
class Reporting_source
{
public:
  /// reports to `progress` the records read of `total`
  Reporting_source(Source& source, const Progress_reporter& progress, std::uint64_t total)
    : m_source(source), m_progress(progress), m_total(total)
  {}
  /// reads as `Source::read()` does, then reports
  std::size_t read(std::vector<Point_record>& chunk, std::size_t maximum)
  {
    const std::size_t got = m_source.read(chunk, maximum);
    m_count += got;
    m_progress.report(std::min(m_count, m_total), m_total);
    return got;
  }
  /// rewinds the source
  void rewind()
  {
    m_source.rewind();
    m_count = 0;
  }

private:
  Source& m_source;
  const Progress_reporter& m_progress;
  std::uint64_t m_total;
  std::uint64_t m_count = 0;
};

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_SCAN_H
