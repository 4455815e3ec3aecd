// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_EXTERNAL_SORT_H
#define NORMAL_ORIENTATION_STREAMING_EXTERNAL_SORT_H

/// \file external_sort.h
/// Sorting a streamed point cloud along its sweep axis with bounded memory.
///
/// The streaming (out-of-core) pipeline sweeps the cloud along the principal
/// axis of largest variance, given by a `Sweep_frame` (`Sweep_frame.h`).  This
/// header provides `External_sorter` (and the shortcut `external_sort()`): it
/// sorts all records of a source by (key along the axis, index) with bounded
/// memory: sorted runs written to temporary files, merged lazily by a
/// `Sorted_run_reader`, which is itself a source.  The temporary files are
/// reached by `remove_temporary_files()`, an async-signal-safe clean-up for
/// signal handlers.
///
/// **The Source concept.**  A source of `Point_record`s is any object `s` with
/// - `std::size_t s.read(std::vector<Point_record>& chunk, std::size_t maximum)`:
///   appends up to `maximum` records to `chunk` and returns how many (0 at the end);
/// - `void s.rewind()`: starts again from the first record.
///
/// The records are never transformed: positions and normals come out of the sort
/// bit-identical, in the input coordinate frame.
///
/// POSIX only (`mkstemp`, `pread`, `unlink`).

#include <Normal_orientation/Point_record.h>
#include <Normal_orientation/internal/Future_waiter.h>
#include <Normal_orientation/internal/Temporary_files.h>
#include <Normal_orientation/remove_temporary_files.h>
#include <Normal_orientation/streaming/Sweep_frame.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <future>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace streaming {
namespace internal {

/// A run of the external sort on disk: a temporary file of `Point_record`s in
/// the temporary directory (see `Normal_orientation::internal::Temporary_file`),
/// appended, then read at any position (`pread()`: no shared offset).
class Run_file
{
public:
  /// creates an empty file `directory`/normal_orientation_sort_XXXXXX; if
  /// `unlink_now`, removes its name at once (the data lives while the file is open)
  Run_file(const std::string& directory, bool unlink_now) : m_file(directory, "normal_orientation_sort_", unlink_now) {}

  /// appends `n` records stored as bytes at `records` (n * 56 bytes)
  void append(const void* records, std::size_t n)
  {
    m_file.append(records, n * sizeof(Point_record));
    m_size += n;
  }

  /// reads up to `n` records from record `first` on; returns how many
  std::size_t read(Point_record* records, std::size_t n, std::uint64_t first) const
  {
    if (first >= m_size)
      return 0;
    n = std::size_t(std::min<std::uint64_t>(n, m_size - first));
    m_file.read(records, n * sizeof(Point_record), first * sizeof(Point_record));
    return n;
  }

  /// the number of records written
  std::uint64_t size() const { return m_size; }
  /// the path of the file
  const std::string& path() const { return m_file.path(); }

private:
  Normal_orientation::internal::Temporary_file m_file;
  std::uint64_t m_size = 0;
};

/// the sort order: by key (NaN keys last, all equal), then by index.  A strict
/// weak order even with NaN keys.
inline bool key_index_less(double key_a, std::uint64_t index_a, double key_b, std::uint64_t index_b)
{
  const bool nan_a = std::isnan(key_a), nan_b = std::isnan(key_b);
  if (nan_a != nan_b)
    return nan_b;
  if (!nan_a) {
    if (key_a < key_b)
      return true;
    if (key_b < key_a)
      return false;
  }
  return index_a < index_b;
}

/// A run of the external sort in memory: the records as read, and one
/// (key, position) tag per record, which is what is sorted (16 bytes moved
/// instead of 56); the records are then written, or permuted, in the tags'
/// order.
struct Sort_run
{
  /// a record's sweep key and its position in `records`
  struct Tag
  {
    double key;
    std::uint32_t position;
  };
  std::vector<Point_record> records;
  std::vector<Tag> tags;

  void reserve(std::size_t n)
  {
    if (records.capacity() < n) {
      records.reserve(n);
      tags.reserve(n);
    }
  }
  void append(const std::vector<Point_record>& chunk, const Sweep_frame& frame)
  {
    for (const Point_record& r : chunk) {
      tags.push_back(Tag{frame.key(r), std::uint32_t(records.size())});
      records.push_back(r);
    }
  }
  /// sorts the tags by (key, index) (`key_index_less`)
  void sort()
  {
    const Point_record* r = records.data();
    std::sort(tags.begin(), tags.end(), [r](const Tag& a, const Tag& b) {
      if (a.key < b.key)
        return true;
      if (b.key < a.key)
        return false;
      // equal keys, or a NaN: the full order (NaN last, then by index)
      return key_index_less(a.key, r[a.position].index, b.key, r[b.position].index);
    });
  }
  /// writes the records in the order of the sorted tags
  void write(Run_file& file) const
  {
    const std::size_t block = 8192;
    std::vector<Point_record> buffer(std::min(block, tags.size()));
    for (std::size_t b = 0; b < tags.size(); b += block) {
      const std::size_t e = std::min(tags.size(), b + block);
      for (std::size_t i = b; i < e; ++i)
        buffer[i - b] = records[tags[i].position];
      file.append(buffer.data(), e - b);
    }
  }
  /// puts the records in the order of the sorted tags, in place (one cycle
  /// of the permutation at a time; the tags are used up)
  void permute()
  {
    const std::uint32_t done = ~std::uint32_t(0);
    for (std::size_t i = 0; i < tags.size(); ++i) {
      if (tags[i].position == done || tags[i].position == i) {
        tags[i].position = done;
        continue;
      }
      const Point_record first = records[i];
      std::size_t j = i;
      for (;;) { // slot j receives the record of tags[j].position
        const std::size_t from = tags[j].position;
        tags[j].position = done;
        if (from == i) {
          records[j] = first;
          break;
        }
        records[j] = records[from];
        j = from;
      }
    }
    tags.clear();
  }
  void clear()
  {
    records.clear();
    tags.clear();
  }
  /// frees the memory
  void release()
  {
    records = std::vector<Point_record>();
    tags = std::vector<Tag>();
  }
};

/// Lazy k-way merge of sorted run files (a binary heap of the run heads): a
/// source of the merged sequence.  Ties on (key, index) are broken by run order.
class Run_merger
{
public:
  /// merges `runs` (not owned; they must outlive the merger), buffering up to
  /// `buffer_records` records of each run
  Run_merger(std::vector<const Run_file*> runs, const Sweep_frame& frame, std::size_t buffer_records)
    : m_frame(frame), m_buffer_records(std::max<std::size_t>(buffer_records, 1))
  {
    m_cursors.resize(runs.size());
    for (std::size_t i = 0; i < runs.size(); ++i)
      m_cursors[i].file = runs[i];
    rewind();
  }

  /// starts again from the first record
  void rewind()
  {
    m_heap.clear();
    for (std::size_t i = 0; i < m_cursors.size(); ++i) {
      Cursor& c = m_cursors[i];
      c.next_record = 0;
      if (refill(c))
        m_heap.push_back(head(i));
    }
    std::make_heap(m_heap.begin(), m_heap.end(), Head_greater());
  }

  /// appends up to `maximum` merged records to `chunk`; returns how many
  std::size_t read(std::vector<Point_record>& chunk, std::size_t maximum)
  {
    std::size_t produced = 0;
    while (produced < maximum && !m_heap.empty()) {
      std::pop_heap(m_heap.begin(), m_heap.end(), Head_greater());
      const std::size_t run = m_heap.back().run;
      m_heap.pop_back();
      Cursor& c = m_cursors[run];
      chunk.push_back(c.buffer[c.position]);
      ++c.position;
      ++produced;
      if (c.position == c.buffer.size() && !refill(c))
        continue;
      m_heap.push_back(head(run));
      std::push_heap(m_heap.begin(), m_heap.end(), Head_greater());
    }
    return produced;
  }

private:
  /// a run being read: its file, a buffer of its next records and where they come from
  struct Cursor
  {
    const Run_file* file = nullptr;
    std::vector<Point_record> buffer;
    std::size_t position = 0;
    std::uint64_t next_record = 0;
  };
  /// the first unread record of a run, as ordered in the heap
  struct Head
  {
    double key;
    std::uint64_t index;
    std::size_t run;
  };
  /// the heap order (a min-heap on (key, index, run))
  struct Head_greater
  {
    bool operator()(const Head& a, const Head& b) const
    {
      if (key_index_less(b.key, b.index, a.key, a.index))
        return true;
      if (key_index_less(a.key, a.index, b.key, b.index))
        return false;
      return a.run > b.run;
    }
  };

  bool refill(Cursor& c)
  {
    const std::uint64_t left = c.file->size() - c.next_record;
    const std::size_t n = std::size_t(std::min<std::uint64_t>(left, m_buffer_records));
    c.buffer.resize(n);
    c.position = 0;
    if (n == 0) {
      c.buffer.shrink_to_fit();
      return false;
    }
    c.file->read(c.buffer.data(), n, c.next_record);
    c.next_record += n;
    return true;
  }

  Head head(std::size_t run) const
  {
    const Point_record& r = m_cursors[run].buffer[m_cursors[run].position];
    return Head{m_frame.key(r), r.index, run};
  }

  Sweep_frame m_frame;
  std::size_t m_buffer_records;
  std::vector<Cursor> m_cursors;
  std::vector<Head> m_heap;
};

/// the temporary directory: `requested` if not empty, else `$TMPDIR` if set and
} // namespace internal

/// \ingroup PkgNormalOrientationStreaming
/// See `Normal_orientation::remove_temporary_files()` (in
/// `remove_temporary_files.h`): also reaches the sort's files.
using Normal_orientation::remove_temporary_files;

// ---------------------------------------------------------------------------
// External sort
// ---------------------------------------------------------------------------

/// \ingroup PkgNormalOrientationStreaming
/// Options of `External_sorter`.
struct External_sort_options
{
  /// bytes of memory for the runs: a run holds `memory_budget /
  /// bytes_per_record` records (at least 16), read from the source while
  /// the previous run is sorted and written.  The merge buffers of the
  /// reader share this budget too (at least 64 records per run).  Peak
  /// memory of the sort: about 1.25 times this (intermediate merges use a
  /// quarter of the budget while the runs are kept) plus 0.6 MiB.
  std::size_t memory_budget = std::size_t(256) << 20;
  /// the bytes of `memory_budget` a record of a run takes: 56 for the
  /// record and 16 for its sort key and position, twice (the run being read
  /// and the run being sorted and written)
  static constexpr std::size_t bytes_per_record = 2 * (sizeof(Point_record) + 16);
  /// where temporary files go; empty: `$TMPDIR` if set, else /tmp
  std::string temporary_directory;
  /// the most runs merged at once (at least 2); more runs are merged in
  /// intermediate passes, which bounds the number of open files
  std::size_t max_merge_fan_in = 64;
  /// when everything fits in one run, keep it in memory (no file at all)
  bool keep_single_run_in_memory = true;
  /// remove the name of every temporary file right after creating it: nothing
  /// can be left behind, even after SIGKILL, but the files are then invisible
  /// (and `remove_temporary_files()` has nothing to do)
  bool unlink_on_creation = false;
};

/// \ingroup PkgNormalOrientationStreaming
/// Figures of one external sort.
struct External_sort_report
{
  /// the number of records sorted
  std::uint64_t points = 0;
  /// the number of sorted runs produced from the source (1 when it fits in memory)
  std::size_t runs = 0;
  /// the number of intermediate merge passes (each merges `max_merge_fan_in` runs)
  std::size_t intermediate_merges = 0;
  /// the number of runs merged by the reader (0 when the single run is kept in memory)
  std::size_t merged_runs = 0;
  /// bytes written to temporary files (runs and intermediate merges)
  std::uint64_t bytes_written = 0;
  /// wall-clock seconds of the sort (reading the source, sorting runs, writing
  /// them, intermediate merges; not the final merge, which happens as the
  /// reader is read)
  double seconds = 0.;
  /// the directory of the temporary files
  std::string temporary_directory;
};

class External_sorter;

/// \ingroup PkgNormalOrientationStreaming
/// The sorted records, read sequentially: a source (`read()`, `rewind()`)
/// whose records come by increasing (`frame().key()`, index), NaN keys last.
/// It owns the temporary files of the sort and removes them when destroyed.
/// Move-only.  Made by `External_sorter::sort()` (or `external_sort()`).
class Sorted_run_reader
{
public:
  /// an empty reader
  Sorted_run_reader() = default;
  /// moves
  Sorted_run_reader(Sorted_run_reader&&) = default;
  /// moves (the temporary files of `*this` are removed)
  Sorted_run_reader& operator=(Sorted_run_reader&&) = default;

  /// appends up to `maximum` records to `chunk`, in sorted order; returns how many (0 at the end)
  std::size_t read(std::vector<Point_record>& chunk, std::size_t maximum)
  {
    if (m_merger)
      return m_merger->read(chunk, maximum);
    const std::size_t n = std::min(maximum, m_memory.size() - m_memory_position);
    chunk.insert(chunk.end(), m_memory.begin() + std::ptrdiff_t(m_memory_position),
                 m_memory.begin() + std::ptrdiff_t(m_memory_position + n));
    m_memory_position += n;
    return n;
  }

  /// starts again from the first record
  void rewind()
  {
    if (m_merger)
      m_merger->rewind();
    m_memory_position = 0;
  }

  /// the number of records
  std::uint64_t size() const { return m_report.points; }
  /// the frame whose keys order the records
  const Sweep_frame& frame() const { return m_frame; }
  /// the figures of the sort
  const External_sort_report& report() const { return m_report; }
  /// the number of temporary files held (0 when the records are in memory)
  std::size_t number_of_temporary_files() const { return m_runs.size(); }

private:
  friend class External_sorter;

  Sweep_frame m_frame;
  External_sort_report m_report;
  std::vector<Point_record> m_memory; // the single run, sorted, when it fits in memory
  std::size_t m_memory_position = 0;
  std::vector<std::unique_ptr<internal::Run_file>> m_runs;
  std::unique_ptr<internal::Run_merger> m_merger; // after m_runs: destroyed first
};

/// \ingroup PkgNormalOrientationStreaming
/// Sorts all records of a source by (sweep key, index) with bounded memory.
///
/// The source is read in runs of at most `memory_budget / bytes_per_record`
/// records; each run is sorted in memory (`std::sort` of (key, position)
/// tags) and written to a temporary file (`mkstemp()` in the temporary
/// directory) on a thread of its own while the next run is read.  Whenever
/// `max_merge_fan_in` runs of the same level exist they are merged into one
/// (intermediate passes, like a log-structured merge), so at most about
/// `max_merge_fan_in * levels` files exist at once.  The final k-way merge is
/// not written: the returned `Sorted_run_reader` performs it as it is read.
/// When everything fits in one run, it stays in memory and no file is written
/// (unless `keep_single_run_in_memory` is false).
///
/// Temporary files are owned by RAII objects: they are removed when the reader
/// is destroyed, and at once if the sort fails (the source throws, a write
/// fails: the exception propagates).  `remove_temporary_files()` removes them
/// from a signal handler.  The output is deterministic.
class External_sorter
{
public:
  /// a sorter with `options`
  explicit External_sorter(External_sort_options options = External_sort_options())
    : m_options(std::move(options))
  {}

  /// the options
  const External_sort_options& options() const { return m_options; }

  /// sorts the records of `source` (rewound first) by (`frame.key()`, index)
  template <class Source>
  Sorted_run_reader sort(Source& source, const Sweep_frame& frame) const
  {
    const auto start = std::chrono::steady_clock::now();
    Sorted_run_reader result;
    result.m_frame = frame;
    External_sort_report& report = result.m_report;
    report.temporary_directory = Normal_orientation::internal::temporary_directory(m_options.temporary_directory);

    const std::size_t run_capacity = std::min<std::size_t>(
      std::max<std::size_t>(m_options.memory_budget / External_sort_options::bytes_per_record, 16),
      std::numeric_limits<std::uint32_t>::max()); // positions in a run are 32-bit
    const std::size_t staging_capacity = std::min<std::size_t>(run_capacity, 8192);
    const std::size_t fan_in = std::max<std::size_t>(m_options.max_merge_fan_in, 2);

    // Two runs: one filled here from the source while the other is sorted
    // and written on a thread of its own (`flush`), so that reading and
    // parsing overlap with sorting and writing.
    internal::Sort_run runs_in_memory[2];
    internal::Sort_run* filling = &runs_in_memory[0];
    internal::Sort_run* flushed = &runs_in_memory[1];
    std::vector<Level_run> runs; // the files; touched by one flush at a time
    auto flush = [&](internal::Sort_run& run) {
      run.sort();
      auto file = std::make_unique<internal::Run_file>(report.temporary_directory,
                                                             m_options.unlink_on_creation);
      run.write(*file);
      report.bytes_written += file->size() * sizeof(Point_record);
      ++report.runs;
      runs.push_back(Level_run{std::move(file), 0});
      run.clear();
      collapse(runs, fan_in, fan_in, frame, report, m_options.memory_budget / 4);
    };
    std::future<void> flushing;
    const Normal_orientation::internal::Future_waiter<void> wait{flushing}; // on exceptions too: `flush` uses this frame

    std::vector<Point_record> staging;
    staging.reserve(staging_capacity);
    source.rewind();
    for (;;) {
      const std::size_t size = filling->records.size();
      const std::size_t want = size < run_capacity ? std::min(staging_capacity, run_capacity - size) : staging_capacity;
      staging.clear();
      const std::size_t n = source.read(staging, want);
      if (n == 0)
        break;
      if (n != staging.size() || n > want)
        throw std::logic_error("External_sorter: the source's read() returned a wrong count");
      report.points += n;
      if (size == run_capacity) { // more records than one run: this one goes to a file
        if (flushing.valid())
          flushing.get(); // rethrows a failed write
        std::swap(filling, flushed);
        flushing = std::async(std::launch::async, [&flush, flushed]() { flush(*flushed); });
      }
      filling->reserve(run_capacity); // once: never more than the budget
      filling->append(staging, frame);
    }
    if (flushing.valid())
      flushing.get();
    staging = std::vector<Point_record>();
    flushed->release();

    if (runs.empty() && m_options.keep_single_run_in_memory) {
      filling->sort();
      filling->permute();
      report.runs = filling->records.empty() ? 0 : 1;
      result.m_memory = std::move(filling->records);
    }
    else {
      if (!filling->records.empty())
        flush(*filling);
      filling->release();
      collapse(runs, fan_in, 1, frame, report, m_options.memory_budget); // at most fan_in runs for the reader
      std::vector<const internal::Run_file*> files;
      for (Level_run& r : runs) {
        files.push_back(r.file.get());
        result.m_runs.push_back(std::move(r.file));
      }
      report.merged_runs = files.size();
      result.m_merger = std::make_unique<internal::Run_merger>(
        std::move(files), frame, merge_buffer_records(report.merged_runs, m_options.memory_budget));
    }
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
  }

private:
  /// a run file and its merge level (0: written from memory)
  struct Level_run
  {
    std::unique_ptr<internal::Run_file> file;
    std::size_t level;
  };

  /// the records buffered per run when `runs` runs share `budget` bytes
  static std::size_t merge_buffer_records(std::size_t runs, std::size_t budget)
  {
    const std::size_t records = budget / (std::max<std::size_t>(runs, 1) * sizeof(Point_record));
    return std::min<std::size_t>(std::max<std::size_t>(records, 64), 65536);
  }

  /// merges the last `fan_in` runs while the last `same_level` (or more) runs
  /// have the same level (same_level == fan_in), or while there are more than
  /// `fan_in` runs (same_level == 1); the merge buffers share `budget` bytes
  void collapse(std::vector<Level_run>& runs, std::size_t fan_in, std::size_t same_level,
                const Sweep_frame& frame, External_sort_report& report, std::size_t budget) const
  {
    std::vector<Point_record> buffer;
    for (;;) {
      if (same_level > 1) {
        if (runs.size() < fan_in)
          return;
        const std::size_t level = runs.back().level;
        std::size_t count = 0;
        while (count < runs.size() && runs[runs.size() - 1 - count].level == level)
          ++count;
        if (count < fan_in)
          return;
      }
      else if (runs.size() <= fan_in)
        return;
      const std::size_t first = runs.size() - fan_in;
      std::vector<const internal::Run_file*> files;
      std::size_t level = 0;
      for (std::size_t i = first; i < runs.size(); ++i) {
        files.push_back(runs[i].file.get());
        level = std::max(level, runs[i].level);
      }
      auto merged = std::make_unique<internal::Run_file>(report.temporary_directory,
                                                               m_options.unlink_on_creation);
      {
        const std::size_t chunk = merge_buffer_records(fan_in + 1, budget);
        internal::Run_merger merger(std::move(files), frame, chunk);
        buffer.reserve(chunk);
        for (;;) {
          buffer.clear();
          const std::size_t n = merger.read(buffer, chunk);
          if (n == 0)
            break;
          merged->append(buffer.data(), n);
        }
      }
      report.bytes_written += merged->size() * sizeof(Point_record);
      ++report.intermediate_merges;
      runs.erase(runs.begin() + std::ptrdiff_t(first), runs.end()); // removes the merged files
      runs.push_back(Level_run{std::move(merged), level + 1});
    }
  }

  External_sort_options m_options;
};

/// \ingroup PkgNormalOrientationStreaming
/// Shortcut for `External_sorter(options).sort(source, frame)`.
template <class Source>
Sorted_run_reader external_sort(Source& source, const Sweep_frame& frame,
                                const External_sort_options& options = External_sort_options())
{
  return External_sorter(options).sort(source, frame);
}

} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_EXTERNAL_SORT_H
