// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// The orient_normals program's setting of the C library's allocator: the
// memory that the process frees is kept for reuse (doc/cli.md, "Memory and
// speed").

#ifndef NORMAL_ORIENTATION_EXAMPLES_CLI_ALLOCATOR_SETTINGS_H
#define NORMAL_ORIENTATION_EXAMPLES_CLI_ALLOCATOR_SETTINGS_H

#include <cstdlib> // defines __GLIBC__ with the GNU C library

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace Cli {

/// \brief Asks glibc's `malloc` to keep in the process the memory that it
/// frees: blocks of up to 1 GiB come from the heap instead of mappings of
/// their own, and the heap is not trimmed below 1 GiB of free memory.
///
/// The stages allocate and free arrays of one entry per point or per edge,
/// one after the other. With this setting a new array reuses pages already
/// mapped, instead of mapping fresh ones whose first touch costs a page fault
/// each. Outputs are unchanged; the peak resident memory can grow, since the
/// heap keeps what it freed and can fragment. Call it once, at the start of
/// `main()`, before any allocation of size. Returns whether both settings
/// were accepted (false, doing nothing, without glibc).
inline bool keep_freed_memory()
{
#if defined(__GLIBC__) && defined(M_MMAP_THRESHOLD) && defined(M_TRIM_THRESHOLD)
  const int one_gib = 1 << 30;
  const bool mapped = mallopt(M_MMAP_THRESHOLD, one_gib) == 1;
  const bool trimmed = mallopt(M_TRIM_THRESHOLD, one_gib) == 1;
  return mapped && trimmed;
#else
  return false;
#endif
}

} // namespace Cli

#endif // NORMAL_ORIENTATION_EXAMPLES_CLI_ALLOCATOR_SETTINGS_H
