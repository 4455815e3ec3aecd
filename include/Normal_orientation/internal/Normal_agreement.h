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
#include <Normal_orientation/internal/Coarse_scale.h>
#include <Normal_orientation/internal/Parallel.h>
#include <Normal_orientation/internal/Unit_vector.h>

#include <CGAL/Kernel_traits.h>

#include <algorithm>
#include <array>
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
  std::vector<std::array<double, 3>> unit(n); // (zero: no normal)
  std::vector<char> agree(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    unit[i] = unit_vector(CGAL::to_double(normals[i].x()), CGAL::to_double(normals[i].y()),
                          CGAL::to_double(normals[i].z()));
    agree[i] = char(unit[i] != std::array<double, 3>{{0.0, 0.0, 0.0}});
  }
  const unsigned int k = unsigned(std::min<std::size_t>(agreement_neighbors, n > 0 ? n - 1 : 0));
  if (k == 0)
    return agree;
  std::vector<std::uint32_t> nb;
  std::vector<float> d2;
  const std::vector<std::uint32_t> order = morton_k_nearest_neighbors<ConcurrencyTag, Kernel>(points, k, nb, d2);
  parallel_chunks<ConcurrencyTag>(n, [&](std::size_t sb, std::size_t se) {
    for (std::size_t s = sb; s < se; ++s) {
      const std::size_t i = order[s];
      if (!agree[i])
        continue;
      std::array<double, 6> m{{0.0, 0.0, 0.0, 0.0, 0.0, 0.0}};
      double count = 0.0;
      for (unsigned int t = 0; t <= k; ++t) { // the sample, then its neighbours
        const std::array<double, 3>& u = unit[t == 0 ? i : nb[s * k + t - 1]];
        if (u[0] != 0.0 || u[1] != 0.0 || u[2] != 0.0) {
          add_outer(m, u[0], u[1], u[2]);
          count += 1.0;
        }
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
