// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_COARSE_SCALE_H
#define NORMAL_ORIENTATION_INTERNAL_COARSE_SCALE_H

/// \file Coarse_scale.h
/// The coarse-to-fine pass of the global stage (issue 15, item 4).  Where the
/// position noise is wider than the point spacing, the input normals of
/// neighbouring points do not agree, and the edges of the graph say little.
/// The cloud is then oriented at a coarser scale: one point per grid cell,
/// whose normal is fitted to the points of its 3 x 3 x 3 block of cells.
/// Every input normal then takes the sign that agrees with the nearest coarse
/// normal.  Only signs change.
///
/// The rule is written once, for both drivers: an accumulator is fed every
/// point once, in a fixed order, and then decides from its grid of moments.
/// - Whether the input normals agree: the coherence of a cell is the largest
///   eigenvalue of the mean n n^T of its input normals (1 when they are
///   parallel, 1/3 when they are isotropic).  The coarse pass runs when the
///   median over the points is below `coarse_coherence_threshold`.
/// - The scale: the base cell is a quarter of the neighbour radius (about two
///   spacings), so a block spans about 6 spacings.  The coarse cloud is
///   oriented by the whole pipeline, this pass included: if its normals still
///   do not agree, it goes one scale coarser in turn, until they do.
/// - Whether to trust it: the coarse signs are taken only when the coarse
///   orientation is clearly more closed (see `Global_sign_summary::closedness`)
///   than the fine one, by `coarse_closedness_margin`.

#include <Normal_orientation/internal/Symmetric_eigen_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <type_traits>
#include <unordered_map>
#include <utility>
#include <vector>

namespace Normal_orientation {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// Below this median coherence of the input normals the coarse pass runs.
/// Measured: clean clouds 0.96-1; 30k points with noise 0.5% of the diagonal
/// 0.85-0.93; 200k points with noise 0.5%, 0.65-0.70 (0.84 on the cheese).
constexpr double coarse_coherence_threshold = 0.9;
/// The coarse signs are taken when the closedness of the coarse orientation
/// exceeds that of the fine one by this much (the manual, "Noise Wider than
/// the Spacing", gives the closedness of both where either wins).
constexpr double coarse_closedness_margin = 0.02;
/// The fewest points a coarse cloud may have.
constexpr std::size_t coarse_minimum_points = 1000;
/// The most cells the accumulator holds (about 40 MB); beyond, the cells
/// double in size, so that memory stays bounded on any stream.
constexpr std::size_t coarse_maximum_cells = std::size_t(1) << 18;

/// What the coarse pass saw and did.
struct Coarse_scale_report
{
  double coherence = 1.0;         ///< the median coherence of the input normals
  double cell = 0.0;              ///< the cell size
  std::size_t coarse_points = 0;  ///< points of the coarse cloud (0: the pass did not run)
  double fine_closedness = std::numeric_limits<double>::quiet_NaN();   ///< of the fine orientation
  double coarse_closedness = std::numeric_limits<double>::quiet_NaN(); ///< of the coarse orientation
  bool used = false;              ///< the points took the coarse signs
  std::uint64_t points_flipped = 0; ///< labels changed (in core; 0 streamed)
  double seconds = 0.0;
};

/// The moments of the points and normals of one grid cell.
struct Coarse_cell
{
  std::uint64_t key = 0;
  double count = 0.0;   ///< points
  double normals = 0.0; ///< non-zero normals
  std::array<double, 3> s{{0.0, 0.0, 0.0}};                 ///< sum of p (relative to the origin)
  std::array<double, 6> ss{{0.0, 0.0, 0.0, 0.0, 0.0, 0.0}}; ///< sum of p p^T: xx xy xz yy yz zz
  std::array<double, 6> nn{{0.0, 0.0, 0.0, 0.0, 0.0, 0.0}}; ///< sum of n n^T over the unit normals

  void add(const Coarse_cell& o)
  {
    count += o.count;
    normals += o.normals;
    for (int d = 0; d < 3; ++d)
      s[d] += o.s[d];
    for (int d = 0; d < 6; ++d) {
      ss[d] += o.ss[d];
      nn[d] += o.nn[d];
    }
  }
};

/// Cell coordinates are signed, relative to the origin, 21 bits each.
constexpr std::int64_t coarse_coordinate_offset = std::int64_t(1) << 20;

/// The key of the cell of coordinates `c` (clamped to the grid).
inline std::uint64_t coarse_key(const std::array<std::int64_t, 3>& c)
{
  std::uint64_t k = 0;
  for (int d = 0; d < 3; ++d)
    k = (k << 21) | std::uint64_t(std::min(std::max(c[d] + coarse_coordinate_offset, std::int64_t(0)),
                                           2 * coarse_coordinate_offset - 1));
  return k;
}

/// The coordinates of the cell of `key`.
inline std::array<std::int64_t, 3> coarse_coordinates(std::uint64_t key)
{
  const std::uint64_t m = (std::uint64_t(1) << 21) - 1;
  return {{std::int64_t(key >> 42) - coarse_coordinate_offset,
           std::int64_t((key >> 21) & m) - coarse_coordinate_offset, std::int64_t(key & m) - coarse_coordinate_offset}};
}

/// Adds (x, y, z)(x, y, z)^T to the packed symmetric matrix `m` (xx xy xz
/// yy yz zz), the form that `coarse_eigen()` reads.
inline void add_outer(std::array<double, 6>& m, double x, double y, double z)
{
  m[0] += x * x;
  m[1] += x * y;
  m[2] += x * z;
  m[3] += y * y;
  m[4] += y * z;
  m[5] += z * z;
}

/// The eigenvalues of the packed symmetric matrix `a` (xx xy xz yy yz zz),
/// ascending, and in `axis` the unit eigenvector of `values[which]`.
inline void coarse_eigen(const std::array<double, 6>& a, double (&values)[3], int which, std::array<double, 3>& axis)
{
  const double m[3][3] = {{a[0], a[1], a[2]}, {a[1], a[3], a[4]}, {a[2], a[4], a[5]}};
  double v[3], e[3][3];
  symmetric_eigen_3(m, v, e);
  int o[3] = {0, 1, 2};
  std::sort(o, o + 3, [&](int i, int j) { return v[i] < v[j] || (v[i] == v[j] && i < j); });
  for (int k = 0; k < 3; ++k)
    values[k] = v[o[k]];
  for (int d = 0; d < 3; ++d)
    axis[d] = e[d][o[which]];
}

/// The key of the cell of side `cell` holding the point `q` (relative to
/// the grid's origin; clamped to the grid).
inline std::uint64_t coarse_point_key(const double (&q)[3], double cell)
{
  std::array<std::int64_t, 3> c;
  const double limit = double(coarse_coordinate_offset);
  for (int d = 0; d < 3; ++d)
    c[d] = std::int64_t(std::min(limit, std::max(-limit, std::floor(q[d] / cell))));
  return coarse_key(c);
}

/// `cells` merged into cells twice as wide (the coordinates halved, rounded
/// down), sorted by key; the moments of a merged cell add in the order of
/// `cells`.
inline std::vector<Coarse_cell> merge_into_doubled_cells(std::vector<Coarse_cell> cells)
{
  for (Coarse_cell& c : cells) {
    std::array<std::int64_t, 3> x = coarse_coordinates(c.key);
    for (int d = 0; d < 3; ++d)
      x[d] = x[d] >= 0 ? x[d] / 2 : -((1 - x[d]) / 2); // floor(x / 2)
    c.key = coarse_key(x);
  }
  std::stable_sort(cells.begin(), cells.end(), [](const Coarse_cell& a, const Coarse_cell& b) { return a.key < b.key; });
  std::vector<Coarse_cell> merged;
  for (const Coarse_cell& c : cells)
    if (!merged.empty() && merged.back().key == c.key)
      merged.back().add(c);
    else
      merged.push_back(c);
  return merged;
}

/// Calls f(index) for the cells of `cells` (sorted by key) in the 3 x 3 x 3
/// block around `key`.
template <typename F>
void for_coarse_block(const std::vector<Coarse_cell>& cells, std::uint64_t key, const F& f)
{
  const std::array<std::int64_t, 3> c = coarse_coordinates(key);
  for (std::int64_t dx = -1; dx <= 1; ++dx)
    for (std::int64_t dy = -1; dy <= 1; ++dy)
      for (std::int64_t dz = -1; dz <= 1; ++dz) {
        const std::array<std::int64_t, 3> x{{c[0] + dx, c[1] + dy, c[2] + dz}};
        const std::uint64_t k = coarse_key(x);
        if (coarse_coordinates(k) != x) // clamped: outside the grid
          continue;
        const auto it = std::lower_bound(cells.begin(), cells.end(), k,
                                         [](const Coarse_cell& a, std::uint64_t b) { return a.key < b; });
        if (it != cells.end() && it->key == k)
          f(std::size_t(it - cells.begin()));
      }
}

/// The covariance of the points of `b` (at least one) about their centroid,
/// packed as `coarse_eigen()` reads it.
inline std::array<double, 6> cell_covariance(const Coarse_cell& b)
{
  const double m = b.count;
  const double g[3] = {b.s[0] / m, b.s[1] / m, b.s[2] / m};
  return {{b.ss[0] / m - g[0] * g[0], b.ss[1] / m - g[0] * g[1], b.ss[2] / m - g[0] * g[2],
           b.ss[3] / m - g[1] * g[1], b.ss[4] / m - g[1] * g[2], b.ss[5] / m - g[2] * g[2]}};
}

/// The coherence of the normals of `b` (at least one): the largest
/// eigenvalue of their mean n n^T.
inline double normal_coherence(const Coarse_cell& b)
{
  std::array<double, 6> m;
  for (int d = 0; d < 6; ++d)
    m[d] = b.nn[d] / b.normals;
  double v[3];
  std::array<double, 3> axis;
  coarse_eigen(m, v, 2, axis);
  return v[2];
}

/// The coarse-to-fine accumulator (see the file comment).  Feed every point
/// with `add()` in a fixed order; when `decide()` returns true, orient
/// `coarse_points()` / `coarse_normals()` and, if the result is to be used,
/// pass it to `use_coarse_orientation()`; then `sign()` gives every point its
/// label.  The same order of `add()` gives the same result.
class Coarse_scale
{
public:
  /// `radius`: the neighbour radius of the fine graph; the base cell is a
  /// quarter of it.
  explicit Coarse_scale(double radius) : m_cell(radius > 0.0 && std::isfinite(radius) ? 0.25 * radius : 1.0) {}

  /// Starts the grid at `p`.  Both drivers start it at the first point in
  /// Morton order (`morton_order()`; ties by input index), so that they read
  /// the same cells whatever order they add the points in; without it, the
  /// grid starts at the first point added.
  /// \throw std::logic_error after an `add()`
  void set_origin(const std::array<double, 3>& p)
  {
    if (!m_cells.empty())
      throw std::logic_error("Coarse_scale::set_origin: points were added already");
    m_origin = p;
    m_has_origin = true;
  }

  /// adds a point and its unit (or zero) normal
  void add(const std::array<double, 3>& p, const std::array<double, 3>& n)
  {
    if (!m_has_origin) {
      m_origin = p;
      m_has_origin = true;
    }
    const double q[3] = {p[0] - m_origin[0], p[1] - m_origin[1], p[2] - m_origin[2]};
    const std::uint64_t key = key_of(q);
    if (m_last == std::size_t(-1) || m_last_key != key) {
      auto it = m_index.find(key);
      if (it == m_index.end()) {
        if (m_cells.size() >= coarse_maximum_cells) {
          coarsen();
          add(p, n);
          return;
        }
        it = m_index.emplace(key, m_cells.size()).first;
        m_cells.emplace_back();
        m_cells.back().key = key;
      }
      m_last = it->second;
      m_last_key = key;
    }
    Coarse_cell& cell = m_cells[m_last];
    cell.count += 1.0;
    for (int d = 0; d < 3; ++d)
      cell.s[d] += q[d];
    add_outer(cell.ss, q[0], q[1], q[2]);
    if (n[0] != 0.0 || n[1] != 0.0 || n[2] != 0.0) {
      cell.normals += 1.0;
      add_outer(cell.nn, n[0], n[1], n[2]);
    }
  }

  /// Measures the coherence of the input normals and, when it is low,
  /// builds the coarse cloud; returns whether there is one to orient (at
  /// least `coarse_minimum_points` and at most half of `fine_points`, so
  /// that repeating the pass on it ends).
  bool decide(std::size_t fine_points)
  {
    m_index.clear();
    m_last = std::size_t(-1);
    std::sort(m_cells.begin(), m_cells.end(), [](const Coarse_cell& a, const Coarse_cell& b) { return a.key < b.key; });
    m_report.cell = m_cell;
    m_report.coherence = coherence();
    if (!(m_report.coherence < coarse_coherence_threshold))
      return false;
    build_coarse_cloud();
    m_report.coarse_points = m_points.size();
    return m_points.size() >= coarse_minimum_points && 2 * m_points.size() <= fine_points;
  }

  /// the coarse points
  const std::vector<std::array<double, 3>>& coarse_points() const { return m_points; }
  /// their unit normals, unoriented
  const std::vector<std::array<double, 3>>& coarse_normals() const { return m_normals; }

  /// The coarse normals once oriented (in the order of `coarse_points()`),
  /// with the closedness of the coarse and of the fine orientation; returns
  /// whether the points are to take the coarse signs.
  bool use_coarse_orientation(const std::vector<std::array<double, 3>>& oriented, double coarse_closedness,
                              double fine_closedness)
  {
    m_report.coarse_closedness = coarse_closedness;
    m_report.fine_closedness = fine_closedness;
    m_report.used = coarse_closedness > fine_closedness + coarse_closedness_margin;
    if (m_report.used)
      m_normals = oriented;
    return m_report.used;
  }

  /// The label of a point with input normal `n`: +1 or -1, the sign of
  /// n . (the nearest coarse normal in its block), or 0 without an opinion
  /// (the coarse signs are not used, no coarse point nearby, or n is zero or
  /// perpendicular to it).  Thread-safe.
  signed char sign(const std::array<double, 3>& p, const std::array<double, 3>& n) const
  {
    if (!m_report.used)
      return 0;
    const double q[3] = {p[0] - m_origin[0], p[1] - m_origin[1], p[2] - m_origin[2]};
    double best = std::numeric_limits<double>::infinity();
    std::uint32_t nearest = std::uint32_t(-1);
    for_block(key_of(q), [&](std::size_t cell) {
      const std::uint32_t j = m_point_of_cell[cell];
      if (j == std::uint32_t(-1))
        return;
      double d2 = 0.0;
      for (int d = 0; d < 3; ++d)
        d2 += (m_points[j][d] - p[d]) * (m_points[j][d] - p[d]);
      if (d2 < best) {
        best = d2;
        nearest = j;
      }
    });
    if (nearest == std::uint32_t(-1))
      return 0;
    const auto& c = m_normals[nearest];
    const double dot = n[0] * c[0] + n[1] * c[1] + n[2] * c[2];
    return dot > 0.0 ? 1 : (dot < 0.0 ? -1 : 0);
  }

  /// what the pass saw and did
  Coarse_scale_report& report() { return m_report; }

  /// the cells, sorted by key after `decide()`
  const std::vector<Coarse_cell>& cells() const { return m_cells; }
  /// the side of a cell
  double cell_size() const { return m_cell; }
  /// the origin of the grid (`set_origin()`, else the first point added)
  const std::array<double, 3>& origin() const { return m_origin; }

private:
  std::uint64_t key_of(const double (&q)[3]) const { return coarse_point_key(q, m_cell); }

  /// doubles the cells, merging their moments (in the order of the keys)
  void coarsen()
  {
    m_cell *= 2.0;
    m_cells = merge_into_doubled_cells(std::move(m_cells));
    m_index.clear();
    for (std::size_t i = 0; i < m_cells.size(); ++i)
      m_index.emplace(m_cells[i].key, i);
    m_last = std::size_t(-1);
  }

  /// calls f(index) for the occupied cells of the 3 x 3 x 3 block around `key`
  template <typename F>
  void for_block(std::uint64_t key, const F& f) const
  {
    for_coarse_block(m_cells, key, f);
  }

  /// the point-weighted median coherence of the normals of the cells with
  /// at least 3 of them (1 when there are none)
  double coherence() const
  {
    std::vector<std::pair<double, double>> values; // (coherence, normals)
    double weight = 0.0;
    for (const Coarse_cell& c : m_cells) {
      if (c.normals < 3.0)
        continue;
      values.emplace_back(normal_coherence(c), c.normals);
      weight += c.normals;
    }
    if (values.empty())
      return 1.0;
    std::sort(values.begin(), values.end());
    double below = 0.0;
    for (const auto& v : values) {
      below += v.second;
      if (below >= 0.5 * weight)
        return v.first;
    }
    return values.back().first;
  }

  /// one coarse point per cell whose block has at least 6 points: the
  /// centroid of the cell, and the normal of the block (the least
  /// eigenvector of its covariance)
  void build_coarse_cloud()
  {
    m_point_of_cell.assign(m_cells.size(), std::uint32_t(-1));
    for (std::size_t i = 0; i < m_cells.size(); ++i) {
      const Coarse_cell& c = m_cells[i];
      Coarse_cell b;
      for_block(c.key, [&](std::size_t j) { b.add(m_cells[j]); });
      if (b.count < 6.0)
        continue;
      double v[3];
      std::array<double, 3> axis;
      coarse_eigen(cell_covariance(b), v, 0, axis);
      if (!(v[1] > 0.0) || !std::isfinite(axis[0] + axis[1] + axis[2]))
        continue;
      m_point_of_cell[i] = std::uint32_t(m_points.size());
      m_points.push_back({{m_origin[0] + c.s[0] / c.count, m_origin[1] + c.s[1] / c.count,
                           m_origin[2] + c.s[2] / c.count}});
      m_normals.push_back(axis);
    }
  }

  double m_cell;
  std::array<double, 3> m_origin{{0.0, 0.0, 0.0}};
  bool m_has_origin = false;
  std::vector<Coarse_cell> m_cells; ///< sorted by key after `decide()`
  std::unordered_map<std::uint64_t, std::size_t> m_index;
  std::size_t m_last = std::size_t(-1);
  std::uint64_t m_last_key = 0;
  std::vector<std::uint32_t> m_point_of_cell;
  std::vector<std::array<double, 3>> m_points, m_normals;
  Coarse_scale_report m_report;
};

/// Whether `Solver` improves the labelling of a solver of its own, its
/// public member `initial` (`Qpbo_i_solver`, `Lsa_tr_solver`).
template <typename Solver, typename = void>
struct Has_starting_solver : std::false_type
{};
template <typename Solver>
struct Has_starting_solver<Solver, std::void_t<decltype(std::declval<const Solver&>().initial)>> : std::true_type
{};

/// The order of the solve and of the coarse-to-fine pass, in both drivers.
/// `fine(solver, improve, dense)` labels the cloud with `solver` and runs
/// what follows it up to the global stage (`improve`: with the streamed
/// refinement; `dense`: the field on the dense samples of
/// `global_samples()`, where the pass does not run); `apply()` tries the
/// pass against that labelling and returns whether the coarse signs were
/// taken.  Where the pass runs (`pass_runs`)
/// and `solver` starts from another, the pass is first tried against the
/// labelling of that start, unimproved: when it is taken, `solver` never
/// runs on the cloud.  Returns whether that happened.
template <typename Solver, typename Fine, typename Apply>
bool solve_around_coarse_pass(bool pass_runs, const Solver& solver, const Fine& fine, const Apply& apply)
{
  if constexpr (Has_starting_solver<Solver>::value) {
    if (pass_runs) {
      fine(solver.initial, false, false);
      if (apply())
        return true;
    }
  }
  fine(solver, true, !pass_runs);
  if (pass_runs)
    apply();
  return false;
}

} // namespace internal
/// \endcond
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_COARSE_SCALE_H
