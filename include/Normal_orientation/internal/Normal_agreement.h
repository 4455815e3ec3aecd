// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_NORMAL_AGREEMENT_H
#define NORMAL_ORIENTATION_INTERNAL_NORMAL_AGREEMENT_H

/// \file Normal_agreement.h
/// Which samples have a normal that agrees with those of their neighbours:
/// the samples of a surface, as opposed to scatter (vegetation, noise wider
/// than the spacing), whose normal lines say little about the side a
/// surface faces.  The measure and its threshold are those of the
/// coarse-to-fine pass (`Coarse_scale.h`), over a sample and its nearest
/// samples instead of a grid cell.

#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/internal/Coarse_scale.h>
#include <Normal_orientation/internal/Parallel.h>

#include <CGAL/Kernel_traits.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// The nearest samples whose normals `normals_agree()` reads, besides the
/// sample's own.
constexpr unsigned int agreement_neighbors = 8;

/// Per sample, whether its normal agrees with those of its
/// `agreement_neighbors` nearest samples: the largest eigenvalue of the mean
/// n n^T of their unit normals and its own (1 when they are parallel, 1/3
/// when they are isotropic) is at least `coarse_coherence_threshold`.  Signs
/// do not matter; zero normals are left out of the mean, and a sample whose
/// own normal is zero does not agree.  With fewer than two samples, every
/// sample with a normal agrees.  Deterministic for any thread count.
template <typename ConcurrencyTag, typename Point, typename Vector>
std::vector<char> normals_agree(const std::vector<Point>& points, const std::vector<Vector>& normals)
{
  typedef typename CGAL::Kernel_traits<Point>::Kernel Kernel;
  const std::size_t n = points.size();
  auto unit = [&](std::size_t i, double (&u)[3]) {
    const Vector& v = normals[i];
    const double x = CGAL::to_double(v.x()), y = CGAL::to_double(v.y()), z = CGAL::to_double(v.z());
    const double length = std::sqrt(x * x + y * y + z * z);
    if (!(length > 0.0) || !std::isfinite(length))
      return false;
    u[0] = x / length;
    u[1] = y / length;
    u[2] = z / length;
    return true;
  };
  std::vector<char> agree(n, 0);
  const unsigned int k = unsigned(std::min<std::size_t>(agreement_neighbors, n > 0 ? n - 1 : 0));
  if (k == 0) {
    double u[3];
    for (std::size_t i = 0; i < n; ++i)
      agree[i] = char(unit(i, u));
    return agree;
  }
  // kNN in Morton order (coherent queries); sorted[s] = points[order[s]]
  const std::vector<std::uint32_t> order = morton_order<ConcurrencyTag>(points);
  std::vector<Point> sorted(n);
  for (std::size_t s = 0; s < n; ++s)
    sorted[s] = points[order[s]];
  std::vector<std::uint32_t> nb;
  std::vector<float> d2;
  k_nearest_neighbors<ConcurrencyTag, Kernel>(sorted, k, nb, d2, Progress_reporter(), 0.0, 1.0);
  parallel_chunks<ConcurrencyTag>(n, [&](std::size_t sb, std::size_t se) {
    for (std::size_t s = sb; s < se; ++s) {
      const std::size_t i = order[s];
      double u[3];
      if (!unit(i, u))
        continue;
      std::array<double, 6> m{{0.0, 0.0, 0.0, 0.0, 0.0, 0.0}}; // (xx xy xz yy yz zz)
      double count = 0.0;
      auto add = [&](const double (&a)[3]) {
        m[0] += a[0] * a[0];
        m[1] += a[0] * a[1];
        m[2] += a[0] * a[2];
        m[3] += a[1] * a[1];
        m[4] += a[1] * a[2];
        m[5] += a[2] * a[2];
        count += 1.0;
      };
      add(u);
      for (unsigned int t = 0; t < k; ++t) {
        double v[3];
        if (unit(order[nb[s * k + t]], v))
          add(v);
      }
      for (double& x : m)
        x /= count;
      double values[3];
      std::array<double, 3> axis;
      coarse_eigen(m, values, 2, axis);
      agree[i] = char(values[2] >= coarse_coherence_threshold);
    }
  }, 256);
  return agree;
}

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_NORMAL_AGREEMENT_H
