// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_REMOVE_TEMPORARY_FILES_H
#define NORMAL_ORIENTATION_REMOVE_TEMPORARY_FILES_H

/// \file remove_temporary_files.h
/// `remove_temporary_files()`: the clean-up a signal handler calls, so that an
/// interrupted run leaves no temporary file behind.

#include <Normal_orientation/internal/Temporary_files.h>

#include <atomic>
#include <cstddef>

#include <unistd.h>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationStreaming
/// Removes every registered temporary file of the process (the runs of the
/// external sort, the record files of the streaming pipeline, the temporary
/// output files of the writers of `Normal_orientation::IO`) and returns how many
/// names were unlinked.
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

#endif // NORMAL_ORIENTATION_REMOVE_TEMPORARY_FILES_H
