// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_CORE_GLOBAL_SIGN_H
#define NORMAL_ORIENTATION_INTERNAL_CORE_GLOBAL_SIGN_H

/// \file Core_global_sign.h
/// The global sign stage of `orient_normals()`: patches from the neighbour
/// graph and the labels, a bounded subsample with areas, and
/// `decide_patch_signs()`.

#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Signed_union_find.h>
#include <Normal_orientation/Winding_number_field.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// The levels of patches, coarse to fine, as the side of their cells in
/// neighbour radii (0: no cells).  A patch never spans two cells, so that
/// one wrong joint ties two objects together over at most one cell; the
/// coarse levels move whole sheets at once.
constexpr double patch_cell_radii[] = {0.0, 4.0, 1.5};

/// Whether the edge (i, j) joins two points of one smooth sheet that the
/// solver oriented consistently: the oriented normals agree within 60
/// degrees and the edge lies within 60 degrees of both tangent planes.
template <typename Point, typename Vector>
bool same_sheet(const Point& pi, const Point& pj, const Vector& mi, const Vector& mj)
{
  const double d[3] = {CGAL::to_double(pj.x() - pi.x()), CGAL::to_double(pj.y() - pi.y()),
                       CGAL::to_double(pj.z() - pi.z())};
  const double len = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  const double a[3] = {CGAL::to_double(mi.x()), CGAL::to_double(mi.y()), CGAL::to_double(mi.z())};
  const double b[3] = {CGAL::to_double(mj.x()), CGAL::to_double(mj.y()), CGAL::to_double(mj.z())};
  const double ab = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  if (!(ab >= 0.5))
    return false;
  if (!(len > 0.0))
    return true;
  const double da = (d[0] * a[0] + d[1] * a[1] + d[2] * a[2]) / len;
  const double db = (d[0] * b[0] + d[1] * b[1] + d[2] * b[2]) / len;
  return std::abs(da) <= 0.5 && std::abs(db) <= 0.5;
}

/// Patches of the labelled cloud, numbered 0, 1, ... by their first point:
/// the points joined by `same_sheet` edges within one cell of side
/// `cell` (0: anywhere); then patches without a sample join a
/// neighbouring patch through an edge whose oriented normals agree.
/// Returns the patch of every point (zero normals get a patch of their own).
template <typename Kernel>
std::vector<std::uint32_t> build_patches(const Neighbor_graph& graph, const std::vector<typename Kernel::Point_3>& points,
                                         const std::vector<typename Kernel::Vector_3>& normals,
                                         const std::vector<Label>& labels, double cell,
                                         const std::vector<char>& is_sample, std::size_t& number_of_patches)
{
  const std::size_t n = points.size();
  double lo[3] = {0, 0, 0};
  for (int c = 0; c < 3 && n > 0; ++c) {
    lo[c] = CGAL::to_double(points[0][c]);
    for (const auto& p : points)
      lo[c] = std::min(lo[c], CGAL::to_double(p[c]));
  }
  std::vector<std::uint64_t> cells(n, 0);
  if (cell > 0.0)
    for (std::size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c)
        cells[i] = (cells[i] << 21) | (std::uint64_t((CGAL::to_double(points[i][c]) - lo[c]) / cell) & 0x1FFFFF);
  auto oriented = [&](std::size_t i) { return labels[i] < 0 ? -normals[i] : normals[i]; };
  Signed_union_find uf(n);
  typename boost::graph_traits<Neighbor_graph>::edge_iterator it, end;
  for (boost::tie(it, end) = edges(graph); it != end; ++it) {
    const std::size_t i = source(*it, graph), j = target(*it, graph);
    if (cells[i] == cells[j] && same_sheet(points[i], points[j], oriented(i), oriented(j)))
      uf.unite(Signed_union_find::Index(i), Signed_union_find::Index(j));
  }
  // Patches without a sample join a sampled neighbour (a few sweeps reach
  // patches two or three steps away).
  std::vector<char> sampled(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    if (is_sample[i])
      sampled[uf.find(Signed_union_find::Index(i))] = 1;
  for (int sweep = 0; sweep < 4; ++sweep) {
    bool changed = false;
    for (boost::tie(it, end) = edges(graph); it != end; ++it) {
      const std::size_t i = source(*it, graph), j = target(*it, graph);
      const auto ri = uf.find(Signed_union_find::Index(i)), rj = uf.find(Signed_union_find::Index(j));
      if (ri == rj || sampled[ri] == sampled[rj] || oriented(i) * oriented(j) <= 0.0)
        continue;
      uf.unite(ri, rj);
      sampled[uf.find(ri)] = 1;
      changed = true;
    }
    if (!changed)
      break;
  }
  const std::uint32_t unset = ~std::uint32_t(0);
  std::vector<std::uint32_t> id(n, unset), patch(n);
  number_of_patches = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto r = uf.find(Signed_union_find::Index(i));
    if (id[r] == unset)
      id[r] = std::uint32_t(number_of_patches++);
    patch[i] = id[r];
  }
  return patch;
}

/// Adds the figures of one level of patches to `total`.
inline void add_level(Global_sign_summary& total, const Global_sign_summary& level)
{
  if (!total.ran)
    total.energy_before = level.energy_before;
  total.ran = true;
  total.number_of_samples = level.number_of_samples;
  total.number_of_patches = level.number_of_patches; // the finest level's
  total.patches_flipped += level.patches_flipped;
  total.rounds += level.rounds;
  total.closed_components = level.closed_components;
  total.open_components = level.open_components;
  total.closedness = level.closedness;
  total.energy_after = level.energy_after;
}

/// The global stage on the in-core arrays (points in Morton order): flips
/// `labels` of the patches that `decide_patch_signs()` negates.  Patches
/// with a point of `has_unary` keep their sign.
template <typename ConcurrencyTag, typename Kernel>
Global_sign_summary core_global_signs(const Neighbor_graph& graph, const std::vector<typename Kernel::Point_3>& points,
                                      const std::vector<typename Kernel::Vector_3>& normals,
                                      const std::vector<std::uint32_t>& component, double radius,
                                      const std::vector<char>& has_unary, std::vector<Label>& labels)
{
  typedef typename Kernel::Point_3 Point;
  typedef typename Kernel::Vector_3 Vector;
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t n = points.size();
  // Every stride-th point of the Morton order with a normal: an even subsample.
  const std::size_t m = std::max<std::size_t>(1, std::size_t(global_samples(n)));
  const std::size_t stride = std::max<std::size_t>(1, (n + m - 1) / m);
  std::vector<char> is_sample(n, 0);
  std::vector<std::uint32_t> sample_index;
  for (std::size_t i = 0; i < n; i += stride)
    if (normals[i] != CGAL::NULL_VECTOR) {
      is_sample[i] = 1;
      sample_index.push_back(std::uint32_t(i));
    }
  const std::vector<Label> labels_before = labels;
  std::vector<Point> sp;
  std::vector<Vector> sn;
  for (std::uint32_t i : sample_index) {
    sp.push_back(points[i]);
    sn.push_back(normals[i]);
  }
  std::vector<double> areas = estimate_point_areas<ConcurrencyTag>(sp, sn);
  cap_areas(areas);
  for (std::size_t t = 0; t < sample_index.size(); ++t)
    if (labels[sample_index[t]] < 0)
      sn[t] = -sn[t];
  Winding_patch_signs<Kernel> search;
  search.template build<ConcurrencyTag>(sp, sn, areas);
  Global_sign_summary report;
  for (double cell_radii : patch_cell_radii) {
    std::size_t np = 0;
    const std::vector<std::uint32_t> patch =
      build_patches<Kernel>(graph, points, normals, labels, cell_radii * radius, is_sample, np);
    std::vector<std::uint32_t> spatch;
    for (std::uint32_t i : sample_index)
      spatch.push_back(patch[i]);
    std::vector<std::uint32_t> patch_component(np, 0);
    std::vector<char> fixed(np, 0);
    for (std::size_t i = 0; i < n; ++i) {
      patch_component[patch[i]] = component[i];
      if (!has_unary.empty() && has_unary[i])
        fixed[patch[i]] = 1;
    }
    std::vector<char> flip;
    const Global_sign_summary level =
      search.template decide<ConcurrencyTag>(spatch, patch_component, fixed, flip, Global_sign_options());
    for (std::size_t i = 0; i < n; ++i)
      if (flip[patch[i]])
        labels[i] = Label(-labels[i]);
    add_level(report, level);
  }
  report.points_flipped = 0;
  for (std::size_t i = 0; i < n; ++i)
    report.points_flipped += labels_before[i] != labels[i] ? 1 : 0;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_CORE_GLOBAL_SIGN_H
