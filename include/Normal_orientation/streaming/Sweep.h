// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_SWEEP_H
#define NORMAL_ORIENTATION_STREAMING_SWEEP_H

/// \file Sweep.h
/// The sweep of the streaming pipeline (paper sec. 5; Pajarola 2005): points
/// sorted along a sweep axis pass through a window of bounded size; each
/// point is handed over, in the sweep order, with its earlier neighbours in
/// the symmetric, radius-truncated k-nearest-neighbour graph, exactly the
/// edges `build_neighbor_graph()` would give in core.

#include <Normal_orientation/Neighbor_graph.h>
#include <Normal_orientation/internal/Future_waiter.h>
#include <Normal_orientation/Point_record.h>
#include <Normal_orientation/streaming/Prefetcher.h>

#include <CGAL/Kd_tree.h>
#include <CGAL/Orthogonal_k_neighbor_search.h>
#include <CGAL/Search_traits_3.h>
#include <CGAL/Search_traits_adapter.h>
#include <CGAL/property_map.h>

#include <boost/iterator/counting_iterator.hpp>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <future>
#include <mutex>
#include <thread>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <limits>
#include <sstream>
#include <type_traits>
#include <stdexcept>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace streaming {

/// \ingroup PkgNormalOrientationStreaming
/// The parameters of `sweep()`.
struct Sweep_options
{
  /// k of the k-nearest-neighbour graph
  unsigned int number_of_neighbors = 12;
  /// r: no edge is as long as r; must be > 0 and finite
  double radius = 0.0;
  /// points finalised per batch (one kd-tree over the window per batch)
  std::size_t batch_size = std::size_t(1) << 18;
};

/// \ingroup PkgNormalOrientationStreaming
/// An earlier neighbour of the point being finalised: its sequence number
/// (position in the sweep order) and the squared distance, in single
/// precision as in `build_neighbor_graph()`.
struct Sweep_neighbor
{
  /// the sequence number of the neighbour
  std::uint64_t sequence;
  /// the squared distance to it
  float squared_distance;
};

/// \ingroup PkgNormalOrientationStreaming
/// What `sweep()` measured.
struct Sweep_report
{
  /// points swept
  std::uint64_t number_of_points = 0;
  /// edges handed over (each undirected edge once, to its later end)
  std::uint64_t number_of_edges = 0;
  /// batches, hence kd-trees built
  std::size_t number_of_batches = 0;
  /// the largest number of points held in the window at once
  std::size_t peak_window = 0;
  /// seconds spent in the kd-trees and queries
  double seconds_neighbors = 0.0;
};

/// \ingroup PkgNormalOrientationStreaming
/// The k nearest neighbours closer than r that the queries of a batch found
/// for its points, earlier and later ones alike (the point's own k nearest,
/// as in core before the graph is made symmetric), for a visitor's
/// `prepare`.
class Sweep_batch_nearest
{
public:
  /// calls f(sequence, squared_distance) for each of the k nearest
  /// neighbours closer than r of point `first + q` of the batch
  template <typename F>
  void for_each(std::size_t q, const F& f) const
  {
    for (unsigned int t = 0; t < m_k; ++t) {
      const std::uint32_t j = m_knn[q * m_k + t];
      if (j != ~std::uint32_t(0) && double(m_d2[q * m_k + t]) < m_r2)
        f(m_base + j, m_d2[q * m_k + t]);
    }
  }

private:
  template <typename C, typename K, typename S, typename F, typename V, typename P>
  friend class Sweep;
  const std::uint32_t* m_knn = nullptr;
  const float* m_d2 = nullptr;
  std::uint64_t m_base = 0;
  unsigned int m_k = 0;
  double m_r2 = 0.0;
};

template <typename ConcurrencyTag, typename Kernel, typename Source, typename KeyFunction, typename Visitor,
          typename Payload>
class Sweep;

/// \ingroup PkgNormalOrientationStreaming
/// The window of a sweep, as the visitor sees it: the points between the
/// oldest one not yet released and the front, by sequence number, with one
/// `Payload` per point for the visitor's own state (a segment, a flip...).
template <typename Payload>
class Sweep_window
{
public:
  /// the record of point `sequence` (it must be in the window)
  const Point_record& record(std::uint64_t sequence) const { return slot(sequence).record; }
  /// the payload of point `sequence` (it must be in the window)
  Payload& payload(std::uint64_t sequence) { return m_slots[std::size_t(sequence - m_base)].payload; }
  /// the payload of point `sequence` (it must be in the window)
  const Payload& payload(std::uint64_t sequence) const { return slot(sequence).payload; }
  /// the sequence number of the oldest point in the window
  std::uint64_t first() const { return m_base; }
  /// one past the sequence number of the newest point in the window
  std::uint64_t end() const { return m_base + m_slots.size(); }
  /// the number of points held
  std::size_t size() const { return m_slots.size(); }

private:
  template <typename C, typename K, typename S, typename F, typename V, typename P>
  friend class Sweep;

  struct Slot
  {
    Point_record record;
    double key;
    Payload payload;
  };
  const Slot& slot(std::uint64_t sequence) const { return m_slots[std::size_t(sequence - m_base)]; }

  std::deque<Slot> m_slots;
  std::uint64_t m_base = 0;
};

/// \cond SKIP_IN_MANUAL
namespace internal {
/// true when `Visitor` has `prepare(window, first, offsets, neighbors)`
template <typename Visitor, typename Window, typename = void>
struct Has_prepare : std::false_type
{};
template <typename Visitor, typename Window>
struct Has_prepare<Visitor, Window,
                   std::void_t<decltype(std::declval<Visitor&>().prepare(
                     std::declval<Window&>(), std::uint64_t(0), std::declval<const std::vector<std::size_t>&>(),
                     std::declval<const std::vector<Sweep_neighbor>&>()))>> : std::true_type
{};
/// true when `Visitor` has `prepare(window, first, offsets, neighbors, nearest)`
template <typename Visitor, typename Window, typename = void>
struct Has_prepare_nearest : std::false_type
{};
template <typename Visitor, typename Window>
struct Has_prepare_nearest<Visitor, Window,
                           std::void_t<decltype(std::declval<Visitor&>().prepare(
                             std::declval<Window&>(), std::uint64_t(0), std::declval<const std::vector<std::size_t>&>(),
                             std::declval<const std::vector<Sweep_neighbor>&>(),
                             std::declval<const Sweep_batch_nearest&>()))>> : std::true_type
{};
} // namespace internal
/// \endcond

/// \ingroup PkgNormalOrientationStreaming
/// The sweep: it reads the points of `source` (a model of the streaming source concept:
/// `std::size_t read(std::vector<Point_record>& chunk, std::size_t maximum)`
/// appends up to `maximum` records and returns how many, 0 at the end),
/// which must be sorted by `key(record)` (non-decreasing; checked as they
/// are read).
///
/// Every point p is finalised once all the points with a key below
/// key(p) + r have been read, in the sweep order: `visitor.finalize(window,
/// sequence, earlier)` is called with its neighbours of smaller sequence
/// number in the graph of `build_neighbor_graph()` (j is a neighbour of p
/// iff one is among the other's k nearest and |p - j| < r; `earlier` is
/// sorted by sequence number), all of them still in `window`.  Points are
/// finalised in batches; a visitor with a member `prepare(window, first,
/// offsets, neighbors)` gets the whole batch first (point first + q has the
/// neighbours `neighbors[offsets[q]] ... neighbors[offsets[q+1]-1]`), for
/// work that can run in parallel, such as edge weights; with a member
/// `prepare(window, first, offsets, neighbors, nearest)`, it also gets the
/// points' own k nearest neighbours (`Sweep_batch_nearest`).  A point is
/// released (`visitor.release(window, sequence)`, in order) once no point
/// that may still need it remains to be finalised; then it leaves the
/// window.  The window holds at most the points of a slab of thickness 3r
/// plus two batches and one read (min(batch, 65536) points): memory does
/// not grow with the length of the cloud.
///
/// Unlike the reference code, which locks grid cells, the sweep works in
/// phases: the neighbours of a batch of points are searched with one CGAL
/// kd-tree built over a copy of the window and queried in parallel (read
/// only, no locks), on a thread of its own while the previous batch is
/// finalised (the visitor runs sequentially in the sweep order; with
/// `CGAL::Sequential_tag` the two run one after the other).  The result is the same
/// for any number of threads.  The k nearest neighbours are those of the
/// whole cloud for every neighbour closer than r (the points left out of
/// the window are all farther), so the graph is exactly the in-core graph,
/// up to ties in distance.
///
/// \tparam ConcurrencyTag `CGAL::Parallel_tag` or `CGAL::Sequential_tag`
/// \tparam Kernel a CGAL kernel (for its `Point_3` and search traits)
/// \throw std::invalid_argument if r is not > 0 and finite or k < 1
/// \throw std::runtime_error if the keys are not sorted or not finite (the
///        message names the point)
template <typename ConcurrencyTag, typename Kernel, typename Source, typename KeyFunction, typename Visitor,
          typename Payload>
class Sweep
{
  typedef Normal_orientation::internal::Knn_tree_types<Kernel> Types;
  typedef typename Types::Point Point;
  typedef typename Types::Point_pmap Point_pmap;
  typedef typename Types::Distance Distance;
  typedef typename Types::Tree Tree;
  typedef typename Sweep_window<Payload>::Slot Slot;

public:
  /// a sweep of `source` by `key`, handing the points to `visitor` through `window`
  Sweep(Source& source, KeyFunction key, const Sweep_options& options, Visitor& visitor, Sweep_window<Payload>& window)
    : m_key(key), m_r(checked_radius(options.radius)), m_k(checked_k(options.number_of_neighbors)),
      m_visitor(visitor), m_window(window), m_slots(window.m_slots),
      m_batch(std::max<std::size_t>(1, options.batch_size)),
      m_prefetcher(source, std::max<std::size_t>(64, std::min<std::size_t>(m_batch, 65536)))
  {
    m_r2 = m_r * m_r;
    m_finalized = m_queried = window.m_base + m_slots.size();
  }

  /// runs the sweep to the end of the source
  Sweep_report run()
  {
    while (true) {
      // 1. Read until a batch can be searched (or the input ends).
      std::uint64_t ready = searchable();
      while (!m_at_end && ready - m_queried < m_batch) {
        if (!read_chunk())
          break;
        ready = searchable();
      }
      ready = searchable();
      if (ready == m_queried) {
        if (!m_at_end)
          continue;
        if (m_pending) // the last batch; then every point is released
          finish(m_jobs[1 - m_current]);
        break;
      }
      // 2. Search batch [queried, ready) on a thread of its own while the
      //    previous batch is finalised on this one.
      Job& job = m_jobs[m_current];
      job.first = m_queried;
      job.base = m_window.m_base;
      job.count = std::size_t(ready - m_queried);
      snapshot(job);
      if (!std::is_convertible<ConcurrencyTag, CGAL::Parallel_tag>::value) {
        m_report.seconds_neighbors += search(job); // one thread: one after the other
        if (m_pending)
          finish(m_jobs[1 - m_current]);
      } else {
        std::future<double> searching = std::async(std::launch::async, [&]() { return search(job); });
        const Normal_orientation::internal::Future_waiter<double> wait{searching}; // `search` uses this object
        if (m_pending)
          finish(m_jobs[1 - m_current]);
        m_report.seconds_neighbors += searching.get();
      }
      ++m_report.number_of_batches;
      m_queried = ready;
      m_pending = true;
      m_current = 1 - m_current;
    }
    return m_report;
  }

private:
  // A batch whose neighbours are being, or have been, searched: points
  // [first, first + count); knn holds sequence numbers - base.
  struct Job
  {
    std::uint64_t first = 0, base = 0;
    std::size_t count = 0;
    std::vector<std::uint32_t> knn;
    std::vector<float> knn_d2;
  };
  // A reverse edge: an edge found by the earlier end's query, handed to its
  // later end (`target`), whose source is `target - back`.
  struct Reverse
  {
    std::uint64_t target;
    std::uint32_t back;
    float squared_distance;
  };
  static constexpr std::size_t block = 1024; // points per block of the parallel steps (fixed: determinism)

  static double checked_radius(double r)
  {
    if (!(r > 0.0) || !std::isfinite(r))
      throw std::invalid_argument("sweep: the radius must be a finite number > 0");
    return r;
  }
  static unsigned int checked_k(unsigned int k)
  {
    if (k < 1)
      throw std::invalid_argument("sweep: the number of neighbors must be at least 1");
    return k;
  }

  // One past the last point that may be searched: point p can once every
  // point with a key below key(p) + r has been read.
  std::uint64_t searchable() const
  {
    if (m_at_end)
      return m_window.m_base + m_slots.size();
    std::uint64_t e = m_queried;
    while (e < m_window.m_base + m_slots.size() && m_slots[std::size_t(e - m_window.m_base)].key + m_r <= m_last_key)
      ++e;
    return e;
  }

  // Reads the next chunk into the window; false at the end of the input.
  bool read_chunk()
  {
    m_chunk.clear();
    if (m_prefetcher.read(m_chunk) == 0) {
      m_at_end = true;
      return false;
    }
    for (const Point_record& p : m_chunk) {
      const double kp = double(m_key(p));
      if (!std::isfinite(kp) || kp < m_last_key) {
        std::ostringstream msg;
        msg << "sweep: the input is not sorted along the sweep axis at point " << m_read_count << " (input index "
            << p.index << ")";
        throw std::runtime_error(msg.str());
      }
      m_last_key = kp;
      m_slots.push_back(Slot{p, kp, Payload()});
      ++m_read_count;
    }
    m_report.peak_window = std::max(m_report.peak_window, m_slots.size());
    return true;
  }

  // The neighbours of the points [first, first + count) over the copy of
  // the window made by `snapshot()`: the tree is built over the window's
  // points in Morton order and the batch is queried in that order, so that
  // consecutive queries visit the same leaves.  Runs while the previous
  // batch is finalised; returns its seconds.
  double search(Job& job)
  {
    const auto t0 = std::chrono::steady_clock::now();
    const std::size_t w = m_points.size();
    const Point_pmap pmap = CGAL::make_property_map(static_cast<const std::vector<Point>&>(m_points));
    Tree tree(boost::counting_iterator<std::uint32_t>(0), boost::counting_iterator<std::uint32_t>(std::uint32_t(w)),
              typename Types::Splitter(), typename Types::Traits(pmap));
    tree.template build<ConcurrencyTag>();
    const Distance distance(pmap);
    const std::size_t first_slot = std::size_t(job.first - job.base);
    const unsigned int k = m_k;
    job.knn.assign(job.count * k, ~std::uint32_t(0));
    job.knn_d2.assign(job.count * k, 0.f);
    Normal_orientation::internal::parallel_chunks<ConcurrencyTag>(m_queries.size(), [&](std::size_t b, std::size_t e) {
      std::vector<std::uint32_t> nb(k);
      for (std::size_t q = b; q < e; ++q) {
        const std::uint32_t i = m_queries[q];
        const std::size_t row = std::size_t(m_keyed[i].second - first_slot) * k;
        const unsigned int found =
          Types::nearest(tree, distance, m_points[i], i, k, nb.data(), &job.knn_d2[row], false); // order: not needed
        for (unsigned int t = 0; t < found; ++t)
          job.knn[row + t] = m_keyed[nb[t]].second; // tree position -> slot
      }
    }, 256);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }

  // The first slot whose point may be a neighbour of the batch of `job`:
  // only the points within r of the batch along the axis can be (a margin
  // covers the rounding of the squared distances).
  std::size_t first_candidate(const Job& job) const
  {
    const std::size_t first_slot = std::size_t(job.first - job.base);
    const double from = m_slots[first_slot].key - m_r * (1.0 + 1e-6);
    std::size_t lo = 0, hi = first_slot; // the first slot with key > from
    while (lo < hi) {
      const std::size_t mid = lo + (hi - lo) / 2;
      if (m_slots[mid].key > from)
        hi = mid;
      else
        lo = mid + 1;
    }
    return lo;
  }

  // The window's candidate points, in Morton order, for the search of `job`.
  void snapshot(const Job& job)
  {
    const std::size_t first_slot = std::size_t(job.first - job.base);
    const std::size_t s0 = first_candidate(job);
    const std::size_t w = m_slots.size() - s0;
    // the bounding box, in a fixed number of parts (deterministic)
    const std::size_t parts = 64;
    m_part_box.assign(parts * 6, 0.0);
    Normal_orientation::internal::parallel_chunks<ConcurrencyTag>(parts, [&](std::size_t pb, std::size_t pe) {
      for (std::size_t part = pb; part < pe; ++part) {
        double* box = &m_part_box[part * 6];
        for (int d = 0; d < 3; ++d) {
          box[d] = HUGE_VAL;
          box[3 + d] = -HUGE_VAL;
        }
        for (std::size_t s = s0 + w * part / parts; s < s0 + w * (part + 1) / parts; ++s)
          for (int d = 0; d < 3; ++d) {
            box[d] = std::min(box[d], m_slots[s].record.position[d]);
            box[3 + d] = std::max(box[3 + d], m_slots[s].record.position[d]);
          }
      }
    }, 1);
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (std::size_t part = 0; part < parts; ++part)
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], m_part_box[part * 6 + d]);
        hi[d] = std::max(hi[d], m_part_box[part * 6 + 3 + d]);
      }
    const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    const double scale = extent > 0.0 ? double((1u << 21) - 1) / extent : 0.0;
    m_keyed.resize(w);
    Normal_orientation::internal::parallel_chunks<ConcurrencyTag>(w, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const double* p = m_slots[s0 + i].record.position;
        std::uint64_t code = 0;
        for (int d = 0; d < 3; ++d)
          code |= Normal_orientation::internal::spread_bits_3(std::uint64_t((p[d] - lo[d]) * scale)) << d;
        m_keyed[i] = {code, std::uint32_t(s0 + i)};
      }
    });
    Normal_orientation::internal::parallel_sort<ConcurrencyTag>(m_keyed,
                                                                std::less<std::pair<std::uint64_t, std::uint32_t>>());
    m_points.resize(w);
    Normal_orientation::internal::parallel_chunks<ConcurrencyTag>(w, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const double* p = m_slots[m_keyed[i].second].record.position;
        m_points[i] = Point(p[0], p[1], p[2]);
      }
    });
    m_queries.clear();
    for (std::size_t i = 0; i < w; ++i)
      if (m_keyed[i].second >= first_slot && m_keyed[i].second - first_slot < job.count)
        m_queries.push_back(std::uint32_t(i));
  }

  // body(blk, b, e) for the points [b, e) of every block of `count`, in
  // parallel (fixed blocks: the result does not depend on the threads)
  template <typename Body>
  void for_each_block(std::size_t count, const Body& body) const
  {
    const std::size_t blocks = (count + block - 1) / block;
    Normal_orientation::internal::parallel_chunks<ConcurrencyTag>(blocks, [&](std::size_t bb, std::size_t be) {
      for (std::size_t blk = bb; blk < be; ++blk)
        body(blk, blk * block, std::min(count, (blk + 1) * block));
    }, 1);
  }

  // f(sj, d2) for the neighbours sj of point first + q found by its query
  // and closer than r
  template <typename F>
  void for_each_found(const Job& job, std::size_t q, const F& f) const
  {
    for (unsigned int t = 0; t < m_k; ++t) {
      const std::uint32_t j = job.knn[q * m_k + t];
      if (j != ~std::uint32_t(0) && double(job.knn_d2[q * m_k + t]) < m_r2)
        f(job.base + j, job.knn_d2[q * m_k + t]);
    }
  }

  // The reverse edges of the batch (to later points), per block; then those
  // to the batch's points bucketed by target (a counting sort: the edges
  // carried from earlier batches, then the blocks in order; the order
  // within a target does not matter, the lists are sorted per point), the
  // others carried to the next batches.
  void bucket_reverse_edges(const Job& job)
  {
    const std::size_t count = job.count, blocks = (count + block - 1) / block;
    for_each_block(count, [&](std::size_t blk, std::size_t b, std::size_t e) {
      std::vector<Reverse>& out = m_block_reverse[blk];
      out.clear();
      for (std::size_t q = b; q < e; ++q) {
        const std::uint64_t sp = job.first + q;
        for_each_found(job, q, [&](std::uint64_t sj, float d2) {
          if (sj > sp)
            out.push_back(Reverse{sj, std::uint32_t(sj - sp), d2});
        });
      }
    });
    const std::uint64_t end = job.first + count;
    m_bucket_begin.assign(count + 1, 0);
    m_next_carry.clear();
    auto count_edge = [&](const Reverse& e) {
      if (e.target < end)
        ++m_bucket_begin[std::size_t(e.target - job.first) + 1];
      else
        m_next_carry.push_back(e);
    };
    for (const Reverse& e : m_carry)
      count_edge(e);
    for (std::size_t blk = 0; blk < blocks; ++blk)
      for (const Reverse& e : m_block_reverse[blk])
        count_edge(e);
    for (std::size_t q = 0; q < count; ++q)
      m_bucket_begin[q + 1] += m_bucket_begin[q];
    m_bucketed.resize(m_bucket_begin[count]);
    std::vector<std::size_t>& next = m_batch_first; // the next free place of each bucket (reused buffer)
    next.assign(m_bucket_begin.begin(), m_bucket_begin.begin() + std::ptrdiff_t(count));
    auto place = [&](const Reverse& e) {
      if (e.target < end)
        m_bucketed[next[std::size_t(e.target - job.first)]++] = e;
    };
    for (const Reverse& e : m_carry)
      place(e);
    for (std::size_t blk = 0; blk < blocks; ++blk)
      for (const Reverse& e : m_block_reverse[blk])
        place(e);
    m_carry.swap(m_next_carry);
  }

  // The earlier neighbours of every point of the batch (sorted by sequence
  // number): its own earlier kNN, then its reverse edges, without
  // duplicates; built in parallel in blocks of fixed size, each block's
  // lists written to a buffer of its own, then copied to their place once
  // the counts are known.
  void build_earlier_lists(const Job& job)
  {
    const std::size_t count = job.count;
    m_batch_first.resize(count + 1);
    m_batch_first[0] = 0;
    for_each_block(count, [&](std::size_t blk, std::size_t b, std::size_t e) {
      std::vector<Sweep_neighbor>& out = m_block_lists[blk];
      out.clear();
      for (std::size_t q = b; q < e; ++q) {
        const std::uint64_t sp = job.first + q;
        const std::size_t from = out.size();
        for_each_found(job, q, [&](std::uint64_t sj, float d2) {
          if (sj < sp)
            out.push_back(Sweep_neighbor{sj, d2});
        });
        for (std::size_t v = m_bucket_begin[q]; v < m_bucket_begin[q + 1]; ++v)
          out.push_back(Sweep_neighbor{sp - m_bucketed[v].back, m_bucketed[v].squared_distance});
        const auto list = out.begin() + std::ptrdiff_t(from);
        std::sort(list, out.end(),
                  [](const Sweep_neighbor& x, const Sweep_neighbor& y) { return x.sequence < y.sequence; });
        out.erase(std::unique(list, out.end(),
                              [](const Sweep_neighbor& x, const Sweep_neighbor& y) { return x.sequence == y.sequence; }),
                  out.end());
        m_batch_first[q + 1] = out.size() - from; // the count, for now
      }
    });
    for (std::size_t q = 0; q < count; ++q)
      m_batch_first[q + 1] += m_batch_first[q];
    m_batch_neighbors.resize(m_batch_first[count]);
    for_each_block(count, [&](std::size_t blk, std::size_t b, std::size_t) {
      std::copy(m_block_lists[blk].begin(), m_block_lists[blk].end(),
                m_batch_neighbors.begin() + std::ptrdiff_t(m_batch_first[b]));
    });
  }

  // Finalises the searched batch `job` (its points are still in the window,
  // whose front may have moved since the search): the visitor's `prepare`
  // on the whole batch when it has one (it may work in parallel), then
  // `finalize` in order; then releases what no later point can need.
  void finish(Job& job)
  {
    const std::size_t count = job.count, blocks = (count + block - 1) / block;
    if (m_block_reverse.size() < blocks) {
      m_block_reverse.resize(blocks);
      m_block_lists.resize(blocks);
    }
    bucket_reverse_edges(job);
    build_earlier_lists(job);
    m_report.number_of_edges += m_batch_neighbors.size();
    if constexpr (internal::Has_prepare_nearest<Visitor, Sweep_window<Payload>>::value) {
      Sweep_batch_nearest nearest;
      nearest.m_knn = job.knn.data();
      nearest.m_d2 = job.knn_d2.data();
      nearest.m_base = job.base;
      nearest.m_k = m_k;
      nearest.m_r2 = m_r2;
      m_visitor.prepare(m_window, job.first, m_batch_first, m_batch_neighbors, nearest);
    } else if constexpr (internal::Has_prepare<Visitor, Sweep_window<Payload>>::value) {
      m_visitor.prepare(m_window, job.first, m_batch_first, m_batch_neighbors);
    }
    for (std::size_t q = 0; q < count; ++q) {
      m_earlier.assign(m_batch_neighbors.begin() + std::ptrdiff_t(m_batch_first[q]),
                       m_batch_neighbors.begin() + std::ptrdiff_t(m_batch_first[q + 1]));
      m_visitor.finalize(m_window, job.first + q, m_earlier);
    }
    m_finalized = job.first + count;
    m_report.number_of_points += count;
    release();
  }

  // Releases the points that no point still to finalise can need: the
  // first unfinalised point, or the next one to be read, has a key at least
  // `limit` (the batch being searched keeps its own copy of the points, and
  // its neighbours are all within r of its first point).
  void release()
  {
    const bool all_done = m_finalized == m_window.m_base + m_slots.size();
    const double limit = !all_done ? m_slots[std::size_t(m_finalized - m_window.m_base)].key
                         : m_at_end ? std::numeric_limits<double>::infinity()
                                    : m_last_key;
    while (!m_slots.empty() && m_window.m_base < m_finalized && m_slots.front().key + m_r <= limit) {
      m_visitor.release(m_window, m_window.m_base);
      m_slots.pop_front();
      ++m_window.m_base;
    }
  }

  KeyFunction m_key;
  double m_r, m_r2 = 0.0;
  unsigned int m_k;
  Visitor& m_visitor;
  Sweep_window<Payload>& m_window;
  std::deque<Slot>& m_slots;
  std::size_t m_batch;
  internal::Prefetcher<Source> m_prefetcher;
  Sweep_report m_report;
  std::uint64_t m_finalized = 0, m_queried = 0, m_read_count = 0; // the next point to finalise, to query
  double m_last_key = -std::numeric_limits<double>::infinity();
  bool m_at_end = false, m_pending = false; // m_pending: m_jobs[1 - m_current] is searched, not yet finalised
  std::vector<Point_record> m_chunk;
  Job m_jobs[2];
  int m_current = 0;
  std::vector<Reverse> m_carry, m_next_carry;      // reverse edges to points after the batch being finalised
  std::vector<std::vector<Reverse>> m_block_reverse; // per block of a batch: its reverse edges
  std::vector<Reverse> m_bucketed;                  // the reverse edges to the batch's points, by target
  std::vector<std::size_t> m_batch_first, m_bucket_begin;
  std::vector<Sweep_neighbor> m_batch_neighbors, m_earlier;
  std::vector<std::vector<Sweep_neighbor>> m_block_lists; // per block of a batch
  std::vector<Point> m_points;                            // the search's copy of the window, in Morton order
  std::vector<std::pair<std::uint64_t, std::uint32_t>> m_keyed; // (Morton code, slot), sorted
  std::vector<std::uint32_t> m_queries;                          // tree positions of the batch
  std::vector<double> m_part_box;
};

/// \ingroup PkgNormalOrientationStreaming
/// Runs a `Sweep` of `source` by `key` to its end (see `Sweep` for the
/// contract).
/// \tparam ConcurrencyTag `CGAL::Parallel_tag` or `CGAL::Sequential_tag`
/// \tparam Kernel a CGAL kernel (for its `Point_3` and search traits)
/// \return what the sweep measured
template <typename ConcurrencyTag, typename Kernel, typename Source, typename KeyFunction, typename Visitor,
          typename Payload>
Sweep_report sweep(Source& source, KeyFunction key, const Sweep_options& options, Visitor& visitor,
                   Sweep_window<Payload>& window)
{
  return Sweep<ConcurrencyTag, Kernel, Source, KeyFunction, Visitor, Payload>(source, key, options, visitor, window)
    .run();
}

} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_SWEEP_H
