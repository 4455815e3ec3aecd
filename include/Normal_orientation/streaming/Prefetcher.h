// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_PREFETCHER_H
#define NORMAL_ORIENTATION_STREAMING_PREFETCHER_H

/// \file Prefetcher.h
/// A streaming source read ahead on a thread of its own (the sweep's input).

#include <Normal_orientation/Point_record.h>

#include <algorithm>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <mutex>
#include <thread>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace streaming {
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

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_PREFETCHER_H
