// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_NEIGHBOR_GRAPH_H
#define NORMAL_ORIENTATION_NEIGHBOR_GRAPH_H

/// \file Neighbor_graph.h
/// The symmetric, radius-truncated k-nearest-neighbour graph of the paper
/// (sec. 3), with the edge weights w_ij = phi(i, j) * omega(p_i, p_j).

#include <Normal_orientation/Progress.h>
#include <Normal_orientation/internal/Clean_positions.h>
#include <Normal_orientation/internal/Layer_edges.h>
#include <Normal_orientation/internal/Layer_gap.h>
#include <Normal_orientation/internal/Parallel.h>

#include <CGAL/Kd_tree.h>
#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/Splitters.h>
#include <CGAL/property_map.h>
#include <CGAL/tags.h>

#include <boost/graph/compressed_sparse_row_graph.hpp>
#include <boost/iterator/counting_iterator.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <type_traits>
#include <utility>
#include <vector>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationGraph
/// The bundled property of an edge of the neighbour graph.
struct Neighbor_edge
{
  /// the signed weight w_ij = phi(i, j) * omega(p_i, p_j)
  float weight = 0.f;
};

/// \ingroup PkgNormalOrientationGraph
/// The neighbour graph: a Boost compressed-sparse-row graph with 32-bit
/// vertex and edge indices.  Each undirected neighbour pair {i, j} is stored
/// once, as one arc whose direction means nothing (see
/// `Orientation_problem.h`).  Read the weights with
/// `get(&Neighbor_edge::weight, graph)`.
typedef boost::compressed_sparse_row_graph<boost::directedS, boost::no_property, Neighbor_edge,
                                           boost::no_property, std::uint32_t, std::uint32_t>
  Neighbor_graph;

/// \ingroup PkgNormalOrientationGraph
/// What the graph construction measured and decided.
struct Neighbor_graph_report
{
  /// the number of neighbours k actually used (k is lowered to n - 1 for
  /// clouds of at most k points)
  unsigned int number_of_neighbors = 0;
  /// the radius r actually used (given or estimated)
  double radius = 0.0;
  /// true when r was estimated from the data
  bool radius_estimated = false;
  /// the number of (undirected) edges
  std::size_t number_of_edges = 0;
  /// seconds spent in the kd-tree and the kNN queries
  double seconds_neighbors = 0.0;
  /// seconds spent in the weights and the graph assembly
  double seconds_graph = 0.0;
  /// with `Hoppe_konig_criterion`, on clouds of at most 200,000 points: the
  /// share of nearly parallel neighbours where König's criterion disagrees
  /// (NaN: not measured), and whether König's criterion was then taken on
  /// every edge
  double konig_disagreement = std::numeric_limits<double>::quiet_NaN();
  bool konig_everywhere = false; ///< see `konig_disagreement`
  /// the points whose k nearest neighbours lie on two layers, whose edges
  /// across the gap are negated (see `build_neighbor_graph()`)
  std::size_t number_of_two_layer_points = 0;
};

/// \ingroup PkgNormalOrientationGraph
/// The default number of neighbours k.  Chosen on 48 benchmark clouds (8
/// meshes, noise 0 and 0.5% of the diagonal, 3 seeds; see the README): k =
/// 12 gave the fewest wrong normals with the MST solver; k = 18 joined
/// close sheets of noisy thin parts more often, k = 10 left noisy regions
/// badly connected.
constexpr unsigned int default_number_of_neighbors = 12;
/// \ingroup PkgNormalOrientationGraph
/// the largest k that the drivers accept
constexpr unsigned int maximum_number_of_neighbors = 100000;

/// \ingroup PkgNormalOrientationGraph
/// The rule used when no radius is given: r = `default_radius_factor` times
/// the 90th percentile, over all points, of the distance from a point to its
/// k-th nearest neighbour.  A percentile of the k-th neighbour distance
/// follows the sampling density, so the rule works at any scale; a high
/// percentile and a generous factor keep sparsely sampled regions connected
/// on clouds of uneven density.  The factor also sets how strongly
/// omega = 1 - d^2 / r^2 favours the closest neighbours: on the benchmark
/// clouds a factor of 2 (omega between about 0.75 and 1) made the MST
/// solver prefer close but noisy neighbours and left up to 3 times more
/// wrong normals on noisy clouds than 4, while no distance weighting at
/// all (r infinite) joined close sheets more often.  Outliers farther than
/// r from everything become isolated points.
constexpr double default_radius_factor = 4.0;
/// the percentile of the k-th neighbour distance used by the radius rule
constexpr double default_radius_percentile = 0.9;

/// \ingroup PkgNormalOrientationGraph
/// The radius rule of both drivers: `default_radius_factor` times the
/// `default_radius_percentile` quantile of the k-th neighbour distances,
/// times `density_scale` (1 when the distances are those of every point;
/// sqrt(sample size / n) for a uniform sample of a surface of n points,
/// whose spacing is that much larger).  1 when that is not a finite number
/// > 0 (every point with k coincident neighbours, or no distance at all).
/// \param kth_squared_distances the squared k-th neighbour distances,
///        reordered by the call
/// \param density_scale the factor above
/// \return r
inline double estimate_neighbor_radius(std::vector<float>& kth_squared_distances, double density_scale)
{
  std::vector<float>& kth = kth_squared_distances;
  if (kth.empty())
    return 1.0;
  const auto q =
    kth.begin() + std::ptrdiff_t(std::min(kth.size() - 1, std::size_t(default_radius_percentile * double(kth.size()))));
  std::nth_element(kth.begin(), q, kth.end());
  const double radius = default_radius_factor * std::sqrt(double(*q)) * density_scale;
  return radius > 0.0 && std::isfinite(radius) ? radius : 1.0;
}

/// \cond SKIP_IN_MANUAL
namespace internal {


/// The CGAL kd-tree over point indices (with the points cache) and its
/// k-nearest-neighbour search, as used by the graph and the sweep.
template <typename Kernel>
struct Knn_tree_types
{
  typedef typename Kernel::Point_3 Point;
  typedef CGAL::Search_traits_3<Kernel> Base_traits;
  typedef typename CGAL::Pointer_property_map<Point>::const_type Point_pmap;
  typedef CGAL::Search_traits_adapter<std::uint32_t, Point_pmap, Base_traits> Traits;
  typedef CGAL::Sliding_midpoint<Traits> Splitter;
  typedef CGAL::Distance_adapter<std::uint32_t, Point_pmap, CGAL::Euclidean_distance<Base_traits>> Distance;
  typedef CGAL::Kd_tree<Traits, Splitter, CGAL::Tag_true, CGAL::Tag_true> Tree;
  typedef CGAL::Orthogonal_k_neighbor_search<Traits, Distance, Splitter, Tree> Search;

  /// Writes to `out` / `out_d2` the k nearest neighbours of point `self`
  /// of the tree (itself excluded; fewer when the tree has fewer points)
  /// and their squared distances in single precision; returns how many.
  /// When `sorted`, by increasing distance; otherwise in the search's own
  /// order (the same set, up to ties at the k-th distance when `self` is not
  /// among the k + 1 nearest, i.e. with more than k coincident points),
  /// which saves sorting each result.
  static unsigned int nearest(const Tree& tree, const Distance& distance, const Point& query, std::uint32_t self,
                              unsigned int k, std::uint32_t* out, float* out_d2, bool sorted = true)
  {
    double exact[64]; // unsorted: the distances compared, in double precision
    if (k > 64)
      sorted = true;
    Search search(tree, query, k + 1, 0, true, distance, sorted);
    unsigned int t = 0;
    bool self_skipped = false;
    for (auto it = search.begin(); it != search.end(); ++it) {
      if (!self_skipped && it->first == self) {
        self_skipped = true;
        continue;
      }
      const double d2 = CGAL::to_double(it->second);
      if (t < k) {
        out[t] = it->first;
        out_d2[t] = float(d2);
        if (!sorted)
          exact[t] = d2;
        ++t;
      } else if (sorted) {
        break;
      } else { // k + 1 others: keep the k nearest (the first of equals stays)
        unsigned int far = 0;
        for (unsigned int s = 1; s < k; ++s)
          if (exact[s] > exact[far])
            far = s;
        if (d2 < exact[far]) {
          out[far] = it->first;
          out_d2[far] = float(d2);
          exact[far] = d2;
        }
      }
    }
    return t;
  }
};

/// The k nearest neighbours of every point (itself excluded), as flat
/// arrays: neighbors[i*k + t] and squared distances sq_dist[i*k + t],
/// t = 0..k-1, sorted by distance.  Computed with CGAL's kd-tree and
/// `Orthogonal_k_neighbor_search`, queries in parallel, in index order (so
/// points in a spatially coherent order, see `morton_order()`, query fast).
template <typename ConcurrencyTag, typename Kernel>
void k_nearest_neighbors(const std::vector<typename Kernel::Point_3>& points, unsigned int k,
                         std::vector<std::uint32_t>& neighbors, std::vector<float>& sq_dist,
                         const Progress_reporter& progress, double progress_begin, double progress_end)
{
  typedef Knn_tree_types<Kernel> Types;
  typedef typename Types::Point_pmap Point_pmap;
  typedef typename Types::Traits Traits;
  typedef typename Types::Splitter Splitter;
  typedef typename Types::Distance Distance;
  typedef typename Types::Tree Tree;

  const std::size_t n = points.size();
  neighbors.assign(n * k, 0);
  sq_dist.assign(n * k, 0.f);
  if (n == 0 || k == 0)
    return;
  const Point_pmap pmap = CGAL::make_property_map(points);
  Tree tree(boost::counting_iterator<std::uint32_t>(0), boost::counting_iterator<std::uint32_t>(std::uint32_t(n)),
            Splitter(), Traits(pmap));
  tree.template build<ConcurrencyTag>();
  const Distance distance(pmap);

  // Queries in blocks so that progress is reported (and interruption
  // checked) on the calling thread between blocks.
  const std::size_t block = std::size_t(1) << 16;
  for (std::size_t b0 = 0; b0 < n; b0 += block) {
    const std::size_t b1 = std::min(n, b0 + block);
    parallel_chunks<ConcurrencyTag>(b1 - b0, [&](std::size_t cb, std::size_t ce) {
      for (std::size_t q = b0 + cb; q < b0 + ce; ++q) {
        const std::uint32_t i = std::uint32_t(q);
        // with fewer than k + 1 points nothing is missing: k <= n - 1
        Types::nearest(tree, distance, points[i], i, k, &neighbors[std::size_t(i) * k], &sq_dist[std::size_t(i) * k]);
      }
    }, 256);
    progress.report(progress_begin + (progress_end - progress_begin) * double(b1) / double(n));
  }
}

/// `k_nearest_neighbors()` of points in any order, queried in Morton order
/// (`morton_order()`, several times faster than an incoherent order) without
/// a progress report.  Returns that order; row s of `neighbors` and
/// `sq_dist` (k entries each) belongs to points[order[s]], and its
/// neighbours are indices into `points`.  k must be at most the points - 1.
template <typename ConcurrencyTag, typename Kernel>
std::vector<std::uint32_t> morton_k_nearest_neighbors(const std::vector<typename Kernel::Point_3>& points,
                                                      unsigned int k, std::vector<std::uint32_t>& neighbors,
                                                      std::vector<float>& sq_dist)
{
  const std::vector<std::uint32_t> order = morton_order<ConcurrencyTag>(points);
  {
    std::vector<typename Kernel::Point_3> sorted(points.size());
    for (std::size_t s = 0; s < points.size(); ++s)
      sorted[s] = points[order[s]];
    k_nearest_neighbors<ConcurrencyTag, Kernel>(sorted, k, neighbors, sq_dist, Progress_reporter(), 0.0, 1.0);
  }
  for (std::uint32_t& j : neighbors)
    j = order[j];
  return order;
}

/// The layer gap of every point (`layer_gap_code()` of the least
/// `layer_gap_to()` over its own k nearest neighbours closer than `radius`;
/// `nb` and `d2` as `k_nearest_neighbors()` gives them), as the sweep's.
template <typename ConcurrencyTag, typename Point, typename Vector>
std::vector<std::uint8_t> layer_gap_codes(const std::vector<Point>& points, const std::vector<Vector>& normals,
                                          const std::vector<std::uint32_t>& nb, const std::vector<float>& d2,
                                          unsigned int k, double radius)
{
  const std::size_t n = points.size();
  const double r2 = radius * radius;
  std::vector<std::uint8_t> codes(n, 0);
  parallel_chunks<ConcurrencyTag>(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      double p[3], u[3], x[3], m[3], gap = HUGE_VAL;
      to_array(points[i], p);
      to_array(normals[i], u);
      for (unsigned t = 0; t < k; ++t) {
        const std::uint32_t j = nb[i * k + t];
        if (!(double(d2[i * k + t]) < r2) || j == i)
          continue;
        to_array(points[j], x);
        to_array(normals[j], m);
        gap = std::min(gap, layer_gap_to(p, u, x, m));
      }
      codes[i] = layer_gap_code(gap, radius);
    }
  });
  return codes;
}

} // namespace internal
/// \endcond

/// \ingroup PkgNormalOrientationGraph
/// Builds the neighbour graph of the paper (sec. 3): i and j are joined iff
/// one is among the other's `k` nearest neighbours and |p_i - p_j| < r; the
/// edge weight is w_ij = phi(i, j) * (1 - |p_i - p_j|^2 / r^2), negated
/// where the edge crosses the gap between two layers (the manual's *Layer
/// edges*; unless `negate_across_layers` is false): where the k nearest
/// neighbours of i (or j) closer than r lie on two parallel layers, both
/// sides of a part thinner than the neighbour distance or two objects in
/// contact, whose outward normals are opposite.
///
/// \tparam ConcurrencyTag `CGAL::Parallel_tag` (kd-tree build, queries and
///         weights in parallel with TBB) or `CGAL::Sequential_tag`; the
///         graph is identical either way.
/// \tparam Kernel a \cgal kernel, whose `Point_3` and `Vector_3` the points and
///         normals are
/// \tparam FlipCriterion a model of `FlipCriterion`
///
/// Queries run in the order of `points`: points in a spatially coherent
/// order (a scan order, or the Morton order that `orient_normals()`
/// applies) make the construction several times faster than points in
/// random order.
///
/// \param points the positions
/// \param normals the normals, same size (any length; zero allowed)
/// \param k the number of neighbours, >= 1 (lowered to n - 1 when n <= k)
/// \param radius r > 0, or 0 to estimate it (see `default_radius_factor`)
/// \param criterion a model of `FlipCriterion`
/// \param graph receives the graph
/// \param progress receives progress in [0, 1] and may interrupt the run
///        (`Progress_reporter()` reports nothing; a reporter whose callback
///        returns `false` throws `Interrupted`)
/// \param negate_across_layers whether the weights of the edges across two
///        layers are negated
/// \param layer_offsets if not null, receives per point the vector from it
///        to the other layer's mean along the fitted normal line, zero where
///        the point's neighbourhood is one layer (or with
///        `negate_across_layers` false)
/// \param layer_gaps if not null, receives per point the distance to the
///        nearest of its neighbours on another layer, coded in 8 bits
///        (`internal::layer_gap_code()`; 0: none)
/// \pre points and normals are finite (checked by `orient_normals()`)
/// \return what was measured and decided: the k and r used, the number of edges, the times
template <typename ConcurrencyTag, typename Kernel, typename FlipCriterion>
Neighbor_graph_report build_neighbor_graph(const std::vector<typename Kernel::Point_3>& points,
                                           const std::vector<typename Kernel::Vector_3>& normals,
                                           unsigned int k, double radius, const FlipCriterion& criterion,
                                           Neighbor_graph& graph,
                                           const Progress_reporter& progress = Progress_reporter(),
                                           bool negate_across_layers = true,
                                           std::vector<std::array<float, 3>>* layer_offsets = nullptr,
                                           std::vector<std::uint8_t>* layer_gaps = nullptr)
{
  if (points.size() != normals.size())
    throw std::invalid_argument("build_neighbor_graph: points and normals differ in size");
  if (k < 1)
    throw std::invalid_argument("build_neighbor_graph: the number of neighbors must be at least 1");
  if (!(radius >= 0.0) || !std::isfinite(radius))
    throw std::invalid_argument("build_neighbor_graph: the radius must be a finite number > 0");
  if (points.size() >= std::size_t(std::numeric_limits<std::uint32_t>::max()))
    throw std::length_error("build_neighbor_graph: more than 2^32 - 1 points");

  Neighbor_graph_report report;
  const std::size_t n = points.size();
  k = unsigned(std::min<std::size_t>(k, n > 0 ? n - 1 : 0));
  report.number_of_neighbors = k;
  auto t0 = std::chrono::steady_clock::now();

  std::vector<std::uint32_t> nb;
  std::vector<float> d2;
  internal::k_nearest_neighbors<ConcurrencyTag, Kernel>(points, k, nb, d2, progress, 0.0, 0.8);
  auto t1 = std::chrono::steady_clock::now();
  report.seconds_neighbors = std::chrono::duration<double>(t1 - t0).count();

  // Radius.
  if (k > 0) {
    std::vector<float> kth(n);
    for (std::size_t i = 0; i < n; ++i)
      kth[i] = d2[i * k + (k - 1)];
    if (radius == 0.0) {
      radius = estimate_neighbor_radius(kth, 1.0);
      report.radius_estimated = true;
    }
  } else if (radius == 0.0) {
    radius = 1.0;
    report.radius_estimated = true;
  }
  report.radius = radius;
  const double r2 = radius * radius;

  // The default criterion on small clean clouds (internal/Clean_positions.h).
  FlipCriterion phi = criterion;
  const internal::Clean_positions clean = internal::apply_clean_positions(
    phi, n, [&]() { return internal::konig_disagreement<ConcurrencyTag>(points, normals, nb, k); });
  report.konig_disagreement = clean.konig_disagreement;
  report.konig_everywhere = clean.konig_everywhere;

  // Each undirected edge {i, j} is emitted once: by i if j is one of i's
  // neighbours and (i < j or i is not one of j's neighbours).
  auto keeps = [&](std::size_t i, unsigned t) -> bool {
    if (!(double(d2[i * k + t]) < r2))
      return false;
    const std::uint32_t j = nb[i * k + t];
    if (j == i)
      return false;
    if (i < j)
      return true;
    const std::uint32_t* nj = &nb[std::size_t(j) * k];
    for (unsigned s = 0; s < k; ++s)
      if (nj[s] == i && double(d2[std::size_t(j) * k + s]) < r2)
        return false;
    return true;
  };
  // The layer offsets of every point, from its own k nearest neighbours.
  std::vector<internal::Layer_offset> layer;
  std::vector<unsigned char> layer_state;
  if (negate_across_layers && k > 0)
    internal::fit_layer_offsets<ConcurrencyTag>(
      n,
      [&](std::size_t i, double* p, double* u) {
        internal::to_array(points[i], p);
        internal::to_array(normals[i], u);
      },
      [&](std::size_t i, auto&& f) {
        const internal::Layer_offset none{};
        for (unsigned t = 0; t < k; ++t) {
          const std::uint32_t j = nb[i * k + t];
          if (double(d2[i * k + t]) < r2 && j != i) {
            double x[3];
            internal::to_array(points[j], x);
            f(x, std::size_t(j), internal::ONE_LAYER, none);
          }
        }
      },
      layer, layer_state);
  for (const internal::Layer_offset& t : layer)
    report.number_of_two_layer_points += internal::is_two_layers(t) ? 1 : 0;
  if (layer_gaps != nullptr)
    *layer_gaps = internal::layer_gap_codes<ConcurrencyTag>(points, normals, nb, d2, k, radius);

  std::vector<std::uint32_t> count(n + 1, 0);
  std::vector<unsigned char> kept(n * k);
  internal::parallel_chunks<ConcurrencyTag>(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      std::uint32_t c = 0;
      for (unsigned t = 0; t < k; ++t) {
        const bool keep = keeps(i, t);
        kept[i * k + t] = keep ? 1 : 0;
        c += keep ? 1 : 0;
      }
      count[i + 1] = c;
    }
  });
  for (std::size_t i = 0; i < n; ++i)
    count[i + 1] += count[i];
  const std::size_t m = count[n];
  std::vector<std::uint32_t> sources(m), targets(m);
  std::vector<Neighbor_edge> props(m);
  internal::parallel_chunks<ConcurrencyTag>(n, [&](std::size_t b, std::size_t e) {
    for (std::size_t i = b; i < e; ++i) {
      std::size_t pos = count[i];
      for (unsigned t = 0; t < k; ++t) {
        if (!kept[i * k + t])
          continue;
        const std::uint32_t j = nb[i * k + t];
        const double omega = 1.0 - double(d2[i * k + t]) / r2;
        sources[pos] = std::uint32_t(i);
        targets[pos] = j;
        double w = phi(points[i], normals[i], points[j], normals[j]) * omega;
        if (!layer.empty() && (internal::is_two_layers(layer[i]) || internal::is_two_layers(layer[j]))) {
          double p[3], q[3], np[3], nq[3];
          internal::to_array(points[i], p);
          internal::to_array(points[j], q);
          internal::to_array(normals[i], np);
          internal::to_array(normals[j], nq);
          if (internal::edge_across_layers(p, layer[i], np, q, layer[j], nq))
            w = -w;
        }
        props[pos].weight = float(w);
        ++pos;
      }
    }
  });
  progress.report(0.9);
  { std::vector<std::uint32_t>().swap(nb); std::vector<float>().swap(d2); std::vector<unsigned char>().swap(kept); }
  Neighbor_graph g(boost::construct_inplace_from_sources_and_targets, sources, targets, props,
                   std::uint32_t(n));
  std::swap(graph, g);
  report.number_of_edges = m;
  if (layer_offsets != nullptr)
    layer_offsets->swap(layer);
  report.seconds_graph = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
  progress.report(1.0);
  return report;
}

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_NEIGHBOR_GRAPH_H
