// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_TEMPORARY_FILES_H
#define NORMAL_ORIENTATION_INTERNAL_TEMPORARY_FILES_H

/// \file Temporary_files.h
/// The process-wide registry of temporary files, which a signal handler can
/// empty (`remove_temporary_files()`): an interrupted run leaves nothing
/// behind.

#include <atomic>
#include <cstddef>
#include <cstring>
#include <string>

#include <unistd.h>

namespace Normal_orientation {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// the number of temporary files that `remove_temporary_files()` can reach at once
constexpr std::size_t temporary_file_slot_count = 512;
/// the longest path (with its final NUL) that `remove_temporary_files()` can reach
constexpr std::size_t temporary_file_path_capacity = 512;

static_assert(std::atomic<int>::is_always_lock_free, "signal handlers need lock-free atomics");

/// One entry of the process-wide registry of temporary files; `state` is
/// 0 (free), 1 (being filled or released), 2 (active), 3 (removed by
/// `remove_temporary_files()`).
struct Temporary_file_slot
{
  /// the state of the slot (see above)
  std::atomic<int> state;
  /// the path, NUL-terminated
  char path[temporary_file_path_capacity];
};

/// The registry: a fixed array in static storage (zero-initialized, no dynamic
/// initialization), so that a signal handler can walk it.
inline Temporary_file_slot temporary_file_slots[temporary_file_slot_count];

/// registers `path`; returns its slot, or -1 if the registry is full or the path too long
inline int register_temporary_file(const std::string& path) noexcept
{
  if (path.size() >= temporary_file_path_capacity)
    return -1;
  for (std::size_t i = 0; i < temporary_file_slot_count; ++i) {
    int expected = 0;
    if (temporary_file_slots[i].state.compare_exchange_strong(expected, 1, std::memory_order_acq_rel)) {
      std::memcpy(temporary_file_slots[i].path, path.c_str(), path.size() + 1);
      temporary_file_slots[i].state.store(2, std::memory_order_release);
      return int(i);
    }
  }
  return -1;
}

/// frees `slot` (from `register_temporary_file()`, or -1)
inline void unregister_temporary_file(int slot) noexcept
{
  if (slot >= 0)
    temporary_file_slots[slot].state.store(0, std::memory_order_release);
}

} // namespace internal
/// \endcond

/// \ingroup PkgNormalOrientationStreaming
/// Removes every registered temporary file of the process (the runs of the
/// external sort, the record files of the streaming pipeline, the temporary
/// output files of the writers) and returns how many names were unlinked.
///
/// **Async-signal-safe**: it only walks a fixed array of C strings in static
/// storage with lock-free atomics and calls `unlink()`, so a handler of
/// SIGINT/SIGTERM may call it before `_exit()`.  The owners are not told;
/// after it, their data is lost (open descriptors still work, but do not
/// rely on it: call it only when the process is about to end).  Files created
/// while the registry (512 entries) is full, or with a path of 512 bytes or
/// more, are not reachable from here (they are still removed by their owner).
inline std::size_t remove_temporary_files() noexcept
{
  std::size_t removed = 0;
  for (std::size_t i = 0; i < internal::temporary_file_slot_count; ++i) {
    internal::Temporary_file_slot& slot = internal::temporary_file_slots[i];
    int expected = 2;
    if (slot.state.compare_exchange_strong(expected, 3, std::memory_order_acq_rel))
      if (::unlink(slot.path) == 0)
        ++removed;
  }
  return removed;
}

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_TEMPORARY_FILES_H
