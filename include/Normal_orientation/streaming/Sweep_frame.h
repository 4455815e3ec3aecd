// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_SWEEP_FRAME_H
#define NORMAL_ORIENTATION_STREAMING_SWEEP_FRAME_H

/// \file Sweep_frame.h
/// The frame of the sweep of the streaming (out-of-core) pipeline: `Sweep_frame`, the
/// centroid and a right-handed orthonormal basis (axis, u, v) of the cloud, the axis
/// being the principal direction of largest variance, and `compute_sweep_frame()`,
/// which computes it in one streaming pass over a source (see the Source concept in
/// `external_sort.h`).

#include <Normal_orientation/Point_record.h>
#include <Normal_orientation/internal/Symmetric_eigen_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <vector>

namespace Normal_orientation {
namespace streaming {

/// \ingroup PkgNormalOrientationStreaming
/// The frame of a sweep: the centroid `c` of the cloud and a right-handed
/// orthonormal basis (`axis`, `u`, `v`), `axis` being the principal direction of
/// largest variance and `u` the second one.  The sweep visits the points by
/// increasing `key(p) = dot(p - c, axis)`; `uv(p)` gives their coordinates in the
/// plane orthogonal to the axis (for a 2-D grid).  The frame only *reads*
/// positions: the records themselves are never moved to this frame.
///
/// For degenerate clouds (empty, one point, identical, collinear or planar
/// points) the frame is still orthonormal, right-handed and deterministic; for
/// an empty cloud it is the canonical frame at the origin.
struct Sweep_frame
{
  /// the centroid of the (finite) points
  std::array<double, 3> centroid{{0., 0., 0.}};
  /// the sweep axis: the unit principal direction of largest variance, its
  /// largest absolute component positive (ties: the first one)
  std::array<double, 3> axis{{1., 0., 0.}};
  /// the unit principal direction of second largest variance, orthogonal to
  /// `axis`, its largest absolute component positive (ties: the first one)
  std::array<double, 3> u{{0., 1., 0.}};
  /// `axis` x `u`, so that (axis, u, v) is right-handed
  std::array<double, 3> v{{0., 0., 1.}};
  /// the variances along `axis`, `u` and `v` (eigenvalues of the population
  /// covariance, in decreasing order)
  std::array<double, 3> variances{{0., 0., 0.}};
  /// the number of records read
  std::uint64_t size = 0;
  /// the number of records ignored because a coordinate is not finite (their
  /// key is NaN; the sort puts them last)
  std::uint64_t non_finite = 0;

  /// the sweep key of `r`: dot(position - centroid, axis)
  double key(const Point_record& r) const
  {
    const double dx = r.position[0] - centroid[0];
    const double dy = r.position[1] - centroid[1];
    const double dz = r.position[2] - centroid[2];
    const double kx = dx * axis[0];
    const double ky = dy * axis[1];
    const double kz = dz * axis[2];
    return (kx + ky) + kz;
  }

  /// the coordinate of `r` along `u`: dot(position - centroid, u)
  double u_coordinate(const Point_record& r) const { return project(r, u); }

  /// the coordinate of `r` along `v`: dot(position - centroid, v)
  double v_coordinate(const Point_record& r) const { return project(r, v); }

  /// the coordinates (u, v) of `r` in the plane orthogonal to the axis
  std::array<double, 2> uv(const Point_record& r) const
  {
    return {{u_coordinate(r), v_coordinate(r)}};
  }

private:
  double project(const Point_record& r, const std::array<double, 3>& d) const
  {
    const double dx = r.position[0] - centroid[0];
    const double dy = r.position[1] - centroid[1];
    const double dz = r.position[2] - centroid[2];
    return (dx * d[0] + dy * d[1]) + dz * d[2];
  }
};

namespace internal {

// the eigen solver, under the name the streaming code has always used
using Normal_orientation::internal::symmetric_eigen_3;

/// normalizes `d`; returns false if its length is zero or not finite
inline bool normalize(std::array<double, 3>& d)
{
  const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  if (!(length > 0.) || !std::isfinite(length))
    return false;
  for (double& x : d)
    x /= length;
  return true;
}

/// flips `d` so that its largest absolute component (the first one on ties) is positive
inline void make_sign_canonical(std::array<double, 3>& d)
{
  int largest = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(d[k]) > std::abs(d[largest]))
      largest = k;
  if (d[largest] < 0.)
    for (double& x : d)
      x = -x;
}

/// the cross product a x b
inline std::array<double, 3> cross(const std::array<double, 3>& a, const std::array<double, 3>& b)
{
  return {{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}};
}

/// Streaming accumulator of the count, the centroid and the covariance of
/// positions (Welford's update, numerically stable for far-from-origin clouds).
/// Records with a non-finite coordinate are counted but otherwise ignored.
class Moment_accumulator
{
public:
  /// adds one record
  void add(const Point_record& r)
  {
    ++m_size;
    const double* p = r.position;
    if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]))) {
      ++m_non_finite;
      return;
    }
    ++m_count;
    const double n = double(m_count);
    double delta[3], delta_after[3];
    for (int i = 0; i < 3; ++i) {
      delta[i] = p[i] - m_mean[i];
      m_mean[i] += delta[i] / n;
      delta_after[i] = p[i] - m_mean[i];
    }
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j)
        m_m2[i][j] += delta[i] * delta_after[j];
  }

  /// the frame of the records added so far
  Sweep_frame frame() const
  {
    Sweep_frame f;
    f.size = m_size;
    f.non_finite = m_non_finite;
    if (m_count == 0)
      return f;
    for (int i = 0; i < 3; ++i)
      f.centroid[i] = m_mean[i];
    double covariance[3][3];
    bool finite = true;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        covariance[i][j] = (i <= j ? m_m2[i][j] : m_m2[j][i]) / double(m_count);
        finite = finite && std::isfinite(covariance[i][j]);
      }
    if (!finite) // overflow (coordinates beyond ~1e150): keep the canonical basis
      return f;
    double values[3], vectors[3][3];
    symmetric_eigen_3(covariance, values, vectors);
    int order[3] = {0, 1, 2};
    std::stable_sort(order, order + 3, [&](int a, int b) { return values[a] > values[b]; });
    std::array<double, 3> axis{{vectors[0][order[0]], vectors[1][order[0]], vectors[2][order[0]]}};
    std::array<double, 3> u{{vectors[0][order[1]], vectors[1][order[1]], vectors[2][order[1]]}};
    if (!normalize(axis))
      return f;
    make_sign_canonical(axis);
    // re-orthogonalize u against the axis (Jacobi's vectors are orthogonal up to rounding)
    const double along = u[0] * axis[0] + u[1] * axis[1] + u[2] * axis[2];
    for (int i = 0; i < 3; ++i)
      u[i] -= along * axis[i];
    if (!normalize(u)) { // cannot happen with an orthogonal Jacobi output; be safe anyway
      int smallest = 0;
      for (int k = 1; k < 3; ++k)
        if (std::abs(axis[k]) < std::abs(axis[smallest]))
          smallest = k;
      std::array<double, 3> e{{0., 0., 0.}};
      e[smallest] = 1.;
      u = cross(axis, e);
      normalize(u);
    }
    make_sign_canonical(u);
    f.axis = axis;
    f.u = u;
    f.v = cross(axis, u);
    normalize(f.v);
    for (int k = 0; k < 3; ++k)
      f.variances[k] = std::max(0., values[order[k]]);
    return f;
  }

private:
  std::uint64_t m_size = 0;
  std::uint64_t m_non_finite = 0;
  std::uint64_t m_count = 0;
  double m_mean[3] = {0., 0., 0.};
  double m_m2[3][3] = {{0., 0., 0.}, {0., 0., 0.}, {0., 0., 0.}};
};

} // namespace internal

/// \ingroup PkgNormalOrientationStreaming
/// Computes the sweep frame of all records of `source` in one streaming pass,
/// reading chunks of at most `chunk_records` records.  Rewinds the source
/// before and after the pass.  Memory: one chunk.
template <class Source>
Sweep_frame compute_sweep_frame(Source& source, std::size_t chunk_records = 65536)
{
  chunk_records = std::max<std::size_t>(chunk_records, 1);
  source.rewind();
  internal::Moment_accumulator accumulator;
  std::vector<Point_record> chunk;
  chunk.reserve(chunk_records);
  for (;;) {
    chunk.clear();
    const std::size_t n = source.read(chunk, chunk_records);
    if (n == 0)
      break;
    if (n != chunk.size())
      throw std::logic_error("compute_sweep_frame: the source's read() returned a wrong count");
    for (const Point_record& r : chunk)
      accumulator.add(r);
  }
  source.rewind();
  return accumulator.frame();
}

} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_SWEEP_FRAME_H
