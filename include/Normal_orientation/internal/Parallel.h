// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_PARALLEL_H
#define NORMAL_ORIENTATION_INTERNAL_PARALLEL_H

/// \file Parallel.h
/// Deterministic parallel loops and sorts (TBB when `ConcurrencyTag` is
/// `CGAL::Parallel_tag` and TBB is linked, else sequential), and the Morton
/// order both drivers walk the points in.

#include <CGAL/number_utils.h>
#include <CGAL/tags.h>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>
#endif

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace internal {

/// Runs `f(begin, end)` over [0, n) in chunks, in parallel when
/// `ConcurrencyTag` is `CGAL::Parallel_tag` and TBB is linked.
template <typename ConcurrencyTag, typename F>
void parallel_chunks(std::size_t n, const F& f, std::size_t grain = 1024)
{
#ifdef CGAL_LINKED_WITH_TBB
  if (std::is_convertible<ConcurrencyTag, CGAL::Parallel_tag>::value) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain),
                      [&](const tbb::blocked_range<std::size_t>& r) { f(r.begin(), r.end()); });
    return;
  }
#endif
  (void)grain;
  f(std::size_t(0), n);
}

/// Runs `f()` and `g()`, at the same time when `ConcurrencyTag` is
/// `CGAL::Parallel_tag` and TBB is linked, else one after the other; an
/// exception of either is rethrown.
template <typename ConcurrencyTag, typename F, typename G>
void parallel_pair(const F& f, const G& g)
{
#ifdef CGAL_LINKED_WITH_TBB
  if (std::is_convertible<ConcurrencyTag, CGAL::Parallel_tag>::value) {
    tbb::parallel_invoke(f, g);
    return;
  }
#endif
  f();
  g();
}

/// Sorts `v` with `less` (in parallel with TBB); the result is the same for
/// any thread count when `less` is a strict total order.
template <typename ConcurrencyTag, typename T, typename Less>
void parallel_sort(std::vector<T>& v, Less less)
{
#ifdef CGAL_LINKED_WITH_TBB
  if (std::is_convertible<ConcurrencyTag, CGAL::Parallel_tag>::value) {
    tbb::parallel_sort(v.begin(), v.end(), less);
    return;
  }
#endif
  std::sort(v.begin(), v.end(), less);
}

/// spreads the low 21 bits of x to every third bit
inline std::uint64_t spread_bits_3(std::uint64_t x)
{
  x &= 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

/// The Morton (Z-curve) code of a point in a bounding box: its coordinates
/// from the box's low corner, scaled so that the longest side spans 21
/// bits, interleaved.  Grow the box with `add()`, `close()` it, then read
/// `code()`.
class Morton_code
{
public:
  /// grows the box to hold `p` (finite)
  void add(const double p[3])
  {
    for (int d = 0; d < 3; ++d) {
      m_lo[d] = std::min(m_lo[d], p[d]);
      m_hi[d] = std::max(m_hi[d], p[d]);
    }
  }
  /// fixes the scale, once every point is added
  void close()
  {
    double extent = 0.0;
    for (int d = 0; d < 3; ++d)
      extent = std::max(extent, m_hi[d] - m_lo[d]);
    m_scale = extent > 0.0 ? double((1u << 21) - 1) / extent : 0.0;
  }
  /// the code of `p`, which lies in the box (after `close()`)
  std::uint64_t code(const double p[3]) const
  {
    std::uint64_t c = 0;
    for (int d = 0; d < 3; ++d)
      c |= spread_bits_3(std::uint64_t((p[d] - m_lo[d]) * m_scale)) << d;
    return c;
  }

private:
  double m_lo[3] = {std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
                    std::numeric_limits<double>::max()};
  double m_hi[3] = {-std::numeric_limits<double>::max(), -std::numeric_limits<double>::max(),
                    -std::numeric_limits<double>::max()};
  double m_scale = 0.0;
};

/// The first of some points in the order of `morton_order()` (by
/// `Morton_code` over their box, ties by the smaller index), whatever order
/// they are added in.
class Morton_first
{
public:
  /// for points in `box` (closed)
  explicit Morton_first(const Morton_code& box = Morton_code()) : m_box(box) {}
  /// takes point `p` (in the box), of index `index`
  void add(const double p[3], std::uint64_t index)
  {
    const std::uint64_t code = m_box.code(p);
    if (code < m_code || (code == m_code && index < m_index)) {
      m_position = {{p[0], p[1], p[2]}};
      m_code = code;
      m_index = index;
    }
  }
  /// the first point's position (zero before any `add()`)
  const std::array<double, 3>& position() const { return m_position; }
  /// the first point's index (the largest std::uint64_t before any `add()`)
  std::uint64_t index() const { return m_index; }

private:
  Morton_code m_box;
  std::array<double, 3> m_position{};
  std::uint64_t m_code = ~std::uint64_t(0);
  std::uint64_t m_index = ~std::uint64_t(0);
};

/// Returns the indices 0..n-1 in Morton (Z-curve) order of the points
/// (`Morton_code` over their bounding box), ties broken by index: queries
/// made in this order hit the kd-tree's caches.
template <typename ConcurrencyTag, typename Point>
std::vector<std::uint32_t> morton_order(const std::vector<Point>& points)
{
  const std::size_t n = points.size();
  auto coordinates = [&](std::size_t i, double* c) {
    for (int d = 0; d < 3; ++d)
      c[d] = CGAL::to_double(points[i][d]);
  };
  Morton_code morton;
  for (std::size_t i = 0; i < n; ++i) {
    double c[3];
    coordinates(i, c);
    morton.add(c);
  }
  morton.close();
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(n);
  parallel_chunks<ConcurrencyTag>(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      double c[3];
      coordinates(i, c);
      keyed[i] = {morton.code(c), std::uint32_t(i)};
    }
  });
  parallel_sort<ConcurrencyTag>(keyed, std::less<std::pair<std::uint64_t, std::uint32_t>>());
  std::vector<std::uint32_t> order(n);
  for (std::size_t i = 0; i < n; ++i)
    order[i] = keyed[i].second;
  return order;
}

} // namespace internal
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_PARALLEL_H
