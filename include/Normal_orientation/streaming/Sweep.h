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
  friend Sweep_report sweep(S&, F, const Sweep_options&, V&, Sweep_window<P>&);

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
/// Reads a streaming source on a thread of its own, a few chunks ahead of
/// the consumer, so that the reading (parsing, merging sorted runs) runs
/// while the sweep computes.  The chunks arrive in the source's order; an
/// exception thrown by the source is rethrown by `read()`; the destructor
/// stops and joins the thread.
template <typename Source>
class Prefetcher
{
public:
  Prefetcher(Source& source, std::size_t chunk_size, std::size_t depth = 3)
    : m_source(source), m_chunk_size(chunk_size), m_depth(std::max<std::size_t>(1, depth))
  {
    m_thread = std::thread([this] { run(); });
  }
  Prefetcher(const Prefetcher&) = delete;
  Prefetcher& operator=(const Prefetcher&) = delete;
  ~Prefetcher()
  {
    {
      std::lock_guard<std::mutex> lock(m_mutex);
      m_stop = true;
    }
    m_changed.notify_all();
    m_thread.join();
  }
  /// appends the next chunk to `chunk`; returns its size, 0 at the end
  std::size_t read(std::vector<Point_record>& chunk)
  {
    std::unique_lock<std::mutex> lock(m_mutex);
    m_changed.wait(lock, [this] { return !m_ready.empty() || m_done; });
    if (m_ready.empty()) {
      if (m_error)
        std::rethrow_exception(m_error);
      return 0;
    }
    std::vector<Point_record> next = std::move(m_ready.front());
    m_ready.pop_front();
    lock.unlock();
    m_changed.notify_all();
    const std::size_t got = next.size();
    if (chunk.empty())
      chunk.swap(next);
    else
      chunk.insert(chunk.end(), next.begin(), next.end());
    return got;
  }

private:
  void run()
  {
    try {
      while (true) {
        std::vector<Point_record> chunk;
        chunk.reserve(m_chunk_size);
        const std::size_t got = m_source.read(chunk, m_chunk_size);
        std::unique_lock<std::mutex> lock(m_mutex);
        if (got == 0 || m_stop)
          break;
        m_ready.push_back(std::move(chunk));
        m_changed.notify_all();
        m_changed.wait(lock, [this] { return m_ready.size() < m_depth || m_stop; });
        if (m_stop)
          break;
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(m_mutex);
      m_error = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lock(m_mutex);
      m_done = true;
    }
    m_changed.notify_all();
  }

  Source& m_source;
  std::size_t m_chunk_size, m_depth;
  std::mutex m_mutex;
  std::condition_variable m_changed;
  std::deque<std::vector<Point_record>> m_ready;
  bool m_done = false, m_stop = false;
  std::exception_ptr m_error;
  std::thread m_thread;
};

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
} // namespace internal
/// \endcond

/// \ingroup PkgNormalOrientationStreaming
/// Sweeps the points of `source` (a model of the streaming source concept:
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
/// work that can run in parallel, such as edge weights.  A point is
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
Sweep_report sweep(Source& source, KeyFunction key, const Sweep_options& options, Visitor& visitor,
                   Sweep_window<Payload>& window)
{
  typedef Normal_orientation::internal::Knn_tree_types<Kernel> Types;
  typedef typename Types::Point Point;
  typedef typename Types::Point_pmap Point_pmap;
  typedef typename Types::Distance Distance;
  typedef typename Types::Tree Tree;

  const double r = options.radius;
  const unsigned int k = options.number_of_neighbors;
  if (!(r > 0.0) || !std::isfinite(r))
    throw std::invalid_argument("sweep: the radius must be a finite number > 0");
  if (k < 1)
    throw std::invalid_argument("sweep: the number of neighbors must be at least 1");
  const double r2 = r * r;
  const std::size_t batch = std::max<std::size_t>(1, options.batch_size);
  const std::size_t read_size = std::max<std::size_t>(64, std::min<std::size_t>(batch, 65536));

  Sweep_report report;
  internal::Prefetcher<Source> prefetcher(source, read_size);
  auto& slots = window.m_slots;
  std::uint64_t finalized = window.m_base + slots.size(); // the next point to finalise
  std::uint64_t queried = finalized;                      // the next point to query
  std::uint64_t read_count = 0;
  double last_key = -std::numeric_limits<double>::infinity();
  bool at_end = false;
  std::vector<Point_record> chunk;

  // A batch whose neighbours are being, or have been, searched: points
  // [first, first + count); knn holds sequence numbers - base.
  struct Job
  {
    std::uint64_t first = 0, base = 0;
    std::size_t count = 0;
    std::vector<std::uint32_t> knn;
    std::vector<float> knn_d2;
  };
  Job jobs[2];
  int current = 0;
  bool pending = false; // jobs[1 - current] is searched, not yet finalised

  // A reverse edge: an edge found by the earlier end's query, handed to its
  // later end (`target`), whose source is `target - back`.
  struct Reverse
  {
    std::uint64_t target;
    std::uint32_t back;
    float squared_distance;
  };
  const std::size_t block = 1024; // points per block of the parallel steps (fixed: determinism)
  std::vector<Reverse> carry, next_carry; // reverse edges to points after the batch being finalised
  std::vector<std::vector<Reverse>> block_reverse; // per block of a batch: its reverse edges
  std::vector<Reverse> bucketed; // the reverse edges to the batch's points, by target
  std::vector<std::size_t> batch_first;
  std::vector<Sweep_neighbor> batch_neighbors;
  std::vector<std::vector<Sweep_neighbor>> block_lists; // per block of a batch
  std::vector<std::size_t> bucket_begin;
  std::vector<Point> points;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed; // (Morton code, slot), sorted
  std::vector<std::uint32_t> queries;                          // tree positions of the batch
  std::vector<double> part_box;
  std::vector<Sweep_neighbor> earlier;

  // The neighbours of the points [first, first + count) over a copy of the
  // window (points in Morton order, slots from `base`): the tree is built
  // over the window's points in Morton order and the batch is queried in
  // that order, so that consecutive queries visit the same leaves (several
  // times faster than in the sweep order, whose consecutive points lie far
  // apart across the slab).  Runs while the previous batch is finalised.
  auto search = [&](Job& job) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::size_t w = points.size();
    const Point_pmap pmap = CGAL::make_property_map(static_cast<const std::vector<Point>&>(points));
    Tree tree(boost::counting_iterator<std::uint32_t>(0), boost::counting_iterator<std::uint32_t>(std::uint32_t(w)),
              typename Types::Splitter(), typename Types::Traits(pmap));
    tree.template build<ConcurrencyTag>();
    const Distance distance(pmap);
    const std::size_t first_slot = std::size_t(job.first - job.base);
    job.knn.assign(job.count * k, ~std::uint32_t(0));
    job.knn_d2.assign(job.count * k, 0.f);
    Normal_orientation::internal::parallel_chunks<ConcurrencyTag>(queries.size(), [&](std::size_t b, std::size_t e) {
      std::vector<std::uint32_t> nb(k);
      for (std::size_t q = b; q < e; ++q) {
        const std::uint32_t i = queries[q];
        const std::size_t row = std::size_t(keyed[i].second - first_slot) * k;
        const unsigned int found =
          Types::nearest(tree, distance, points[i], i, k, nb.data(), &job.knn_d2[row], false); // order: not needed
        for (unsigned int t = 0; t < found; ++t)
          job.knn[row + t] = keyed[nb[t]].second; // tree position -> slot
      }
    }, 256);
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };

  // The window's points, in Morton order, for the search of `job`.
  auto snapshot = [&](const Job& job) {
    const std::size_t first_slot = std::size_t(job.first - job.base);
    // Only the points within r of the batch along the axis can be its
    // neighbours (a margin covers the rounding of the squared distances):
    // the points of the previous batch, not yet released, mostly are not.
    const double from = slots[first_slot].key - r * (1.0 + 1e-6);
    std::size_t s0 = first_slot;
    {
      std::size_t lo = 0, hi = first_slot; // the first slot with key > from
      while (lo < hi) {
        const std::size_t mid = lo + (hi - lo) / 2;
        if (slots[mid].key > from)
          hi = mid;
        else
          lo = mid + 1;
      }
      s0 = lo;
    }
    const std::size_t w = slots.size() - s0;
    // the bounding box, in a fixed number of parts (deterministic)
    const std::size_t parts = 64;
    part_box.assign(parts * 6, 0.0);
    Normal_orientation::internal::parallel_chunks<ConcurrencyTag>(parts, [&](std::size_t pb, std::size_t pe) {
      for (std::size_t part = pb; part < pe; ++part) {
        double* box = &part_box[part * 6];
        for (int d = 0; d < 3; ++d) {
          box[d] = HUGE_VAL;
          box[3 + d] = -HUGE_VAL;
        }
        for (std::size_t s = s0 + w * part / parts; s < s0 + w * (part + 1) / parts; ++s)
          for (int d = 0; d < 3; ++d) {
            box[d] = std::min(box[d], slots[s].record.position[d]);
            box[3 + d] = std::max(box[3 + d], slots[s].record.position[d]);
          }
      }
    }, 1);
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (std::size_t part = 0; part < parts; ++part)
      for (int d = 0; d < 3; ++d) {
        lo[d] = std::min(lo[d], part_box[part * 6 + d]);
        hi[d] = std::max(hi[d], part_box[part * 6 + 3 + d]);
      }
    const double extent = std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    const double scale = extent > 0.0 ? double((1u << 21) - 1) / extent : 0.0;
    keyed.resize(w);
    Normal_orientation::internal::parallel_chunks<ConcurrencyTag>(w, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const double* p = slots[s0 + i].record.position;
        std::uint64_t code = 0;
        for (int d = 0; d < 3; ++d)
          code |= Normal_orientation::internal::spread_bits_3(std::uint64_t((p[d] - lo[d]) * scale)) << d;
        keyed[i] = {code, std::uint32_t(s0 + i)};
      }
    });
    Normal_orientation::internal::parallel_sort<ConcurrencyTag>(keyed, std::less<std::pair<std::uint64_t, std::uint32_t>>());
    points.resize(w);
    Normal_orientation::internal::parallel_chunks<ConcurrencyTag>(w, [&](std::size_t b, std::size_t e) {
      for (std::size_t i = b; i < e; ++i) {
        const double* p = slots[keyed[i].second].record.position;
        points[i] = Point(p[0], p[1], p[2]);
      }
    });
    queries.clear();
    for (std::size_t i = 0; i < w; ++i)
      if (keyed[i].second >= first_slot && keyed[i].second - first_slot < job.count)
        queries.push_back(std::uint32_t(i));
  };

  // Finalises the searched batch `job` (its points are still in the window,
  // whose front may have moved since the search) and releases what no
  // later point can need.
  auto finish = [&](Job& job) {
    const std::size_t count = job.count, blocks = (count + block - 1) / block;
    if (block_reverse.size() < blocks) {
      block_reverse.resize(blocks);
      block_lists.resize(blocks);
    }
    // body(blk, b, e) for the points [b, e) of every block, in parallel
    // (fixed blocks: the result does not depend on the threads)
    auto for_each_block = [&](const auto& body) {
      Normal_orientation::internal::parallel_chunks<ConcurrencyTag>(blocks, [&](std::size_t bb, std::size_t be) {
        for (std::size_t blk = bb; blk < be; ++blk)
          body(blk, blk * block, std::min(count, (blk + 1) * block));
      }, 1);
    };
    // f(sj, d2) for the neighbours sj of point first + q found by its query
    // and closer than r
    auto for_each_found = [&](std::size_t q, const auto& f) {
      for (unsigned int t = 0; t < k; ++t) {
        const std::uint32_t j = job.knn[q * k + t];
        if (j != ~std::uint32_t(0) && double(job.knn_d2[q * k + t]) < r2)
          f(job.base + j, job.knn_d2[q * k + t]);
      }
    };
    // 1. The reverse edges of the batch (to later points), per block.
    for_each_block([&](std::size_t blk, std::size_t b, std::size_t e) {
      std::vector<Reverse>& out = block_reverse[blk];
      out.clear();
      for (std::size_t q = b; q < e; ++q) {
        const std::uint64_t sp = job.first + q;
        for_each_found(q, [&](std::uint64_t sj, float d2) {
          if (sj > sp)
            out.push_back(Reverse{sj, std::uint32_t(sj - sp), d2});
        });
      }
    });
    // Bucket those to the batch's points by target (a counting sort: the
    // edges carried from earlier batches, then the blocks in order; the
    // order within a target does not matter, the lists are sorted per point
    // below); the others are carried to the next batches.
    const std::uint64_t end = job.first + count;
    bucket_begin.assign(count + 1, 0);
    next_carry.clear();
    auto count_edge = [&](const Reverse& e) {
      if (e.target < end)
        ++bucket_begin[std::size_t(e.target - job.first) + 1];
      else
        next_carry.push_back(e);
    };
    for (const Reverse& e : carry)
      count_edge(e);
    for (std::size_t blk = 0; blk < blocks; ++blk)
      for (const Reverse& e : block_reverse[blk])
        count_edge(e);
    for (std::size_t q = 0; q < count; ++q)
      bucket_begin[q + 1] += bucket_begin[q];
    bucketed.resize(bucket_begin[count]);
    {
      std::vector<std::size_t>& next = batch_first; // the next free place of each bucket (reused buffer)
      next.assign(bucket_begin.begin(), bucket_begin.begin() + std::ptrdiff_t(count));
      auto place = [&](const Reverse& e) {
        if (e.target < end)
          bucketed[next[std::size_t(e.target - job.first)]++] = e;
      };
      for (const Reverse& e : carry)
        place(e);
      for (std::size_t blk = 0; blk < blocks; ++blk)
        for (const Reverse& e : block_reverse[blk])
          place(e);
    }
    carry.swap(next_carry);

    // 2. The earlier neighbours of every point of the batch (sorted by
    //    sequence number): its own earlier kNN, then its reverse edges,
    //    without duplicates; built in parallel, in blocks of fixed size
    //    (the result does not depend on the threads), each block's lists
    //    written to a buffer of its own, then copied to their place once the
    //    counts are known.  Then the visitor: `prepare` on the whole batch
    //    when it has one (it may work in parallel), then `finalize` in order.
    batch_first.resize(count + 1);
    batch_first[0] = 0;
    for_each_block([&](std::size_t blk, std::size_t b, std::size_t e) {
      std::vector<Sweep_neighbor>& out = block_lists[blk];
      out.clear();
      for (std::size_t q = b; q < e; ++q) {
        const std::uint64_t sp = job.first + q;
        const std::size_t from = out.size();
        for_each_found(q, [&](std::uint64_t sj, float d2) {
          if (sj < sp)
            out.push_back(Sweep_neighbor{sj, d2});
        });
        for (std::size_t v = bucket_begin[q]; v < bucket_begin[q + 1]; ++v)
          out.push_back(Sweep_neighbor{sp - bucketed[v].back, bucketed[v].squared_distance});
        const auto list = out.begin() + std::ptrdiff_t(from);
        std::sort(list, out.end(),
                  [](const Sweep_neighbor& x, const Sweep_neighbor& y) { return x.sequence < y.sequence; });
        out.erase(std::unique(list, out.end(),
                              [](const Sweep_neighbor& x, const Sweep_neighbor& y) { return x.sequence == y.sequence; }),
                  out.end());
        batch_first[q + 1] = out.size() - from; // the count, for now
      }
    });
    for (std::size_t q = 0; q < count; ++q)
      batch_first[q + 1] += batch_first[q];
    batch_neighbors.resize(batch_first[count]);
    for_each_block([&](std::size_t blk, std::size_t b, std::size_t) {
      std::copy(block_lists[blk].begin(), block_lists[blk].end(),
                batch_neighbors.begin() + std::ptrdiff_t(batch_first[b]));
    });
    report.number_of_edges += batch_neighbors.size();
    if constexpr (internal::Has_prepare<Visitor, Sweep_window<Payload>>::value)
      visitor.prepare(window, job.first, batch_first, batch_neighbors);
    for (std::size_t q = 0; q < count; ++q) {
      earlier.assign(batch_neighbors.begin() + std::ptrdiff_t(batch_first[q]),
                     batch_neighbors.begin() + std::ptrdiff_t(batch_first[q + 1]));
      visitor.finalize(window, job.first + q, earlier);
    }
    finalized = job.first + count;
    report.number_of_points += count;

    // 3. Release the points that no point still to finalise can need: the
    //    first unfinalised point, or the next one to be read, has a key at
    //    least `limit` (the batch being searched keeps its own copy of the
    //    points, and its neighbours are all within r of its first point).
    const bool all_done = finalized == window.m_base + slots.size();
    const double limit = !all_done ? slots[std::size_t(finalized - window.m_base)].key
                                   : at_end ? std::numeric_limits<double>::infinity() : last_key;
    while (!slots.empty() && window.m_base < finalized && slots.front().key + r <= limit) {
      visitor.release(window, window.m_base);
      slots.pop_front();
      ++window.m_base;
    }
  };

  while (true) {
    // 1. Read until a batch can be searched (or the input ends): point p can
    //    once every point with a key below key(p) + r has been read.
    auto searchable = [&]() -> std::uint64_t { // one past the last point that may be searched
      if (at_end)
        return window.m_base + slots.size();
      std::uint64_t e = queried;
      while (e < window.m_base + slots.size() && slots[std::size_t(e - window.m_base)].key + r <= last_key)
        ++e;
      return e;
    };
    std::uint64_t ready = searchable();
    while (!at_end && ready - queried < batch) {
      chunk.clear();
      const std::size_t got = prefetcher.read(chunk);
      if (got == 0) {
        at_end = true;
        break;
      }
      for (const Point_record& p : chunk) {
        const double kp = double(key(p));
        if (!std::isfinite(kp) || kp < last_key) {
          std::ostringstream msg;
          msg << "sweep: the input is not sorted along the sweep axis at point " << read_count << " (input index "
              << p.index << ")";
          throw std::runtime_error(msg.str());
        }
        last_key = kp;
        slots.push_back(typename Sweep_window<Payload>::Slot{p, kp, Payload()});
        ++read_count;
      }
      report.peak_window = std::max(report.peak_window, slots.size());
      ready = searchable();
    }
    ready = searchable();
    if (ready == queried) {
      if (!at_end)
        continue;
      if (pending) // the last batch; then every point is released
        finish(jobs[1 - current]);
      break;
    }

    // 2. Search batch [queried, ready) on a thread of its own while the
    //    previous batch is finalised on this one.
    Job& job = jobs[current];
    job.first = queried;
    job.base = window.m_base;
    job.count = std::size_t(ready - queried);
    snapshot(job);
    if (!std::is_convertible<ConcurrencyTag, CGAL::Parallel_tag>::value) {
      report.seconds_neighbors += search(job); // one thread: one after the other
      if (pending)
        finish(jobs[1 - current]);
    } else {
      std::future<double> searching = std::async(std::launch::async, [&]() { return search(job); });
      const Normal_orientation::internal::Future_waiter<double> wait{searching}; // on exceptions too: `search` uses this frame
      if (pending)
        finish(jobs[1 - current]);
      report.seconds_neighbors += searching.get();
    }
    ++report.number_of_batches;
    queried = ready;
    pending = true;
    current = 1 - current;
  }
  return report;
}

} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_SWEEP_H
