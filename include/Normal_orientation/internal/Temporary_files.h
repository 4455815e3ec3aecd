// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_TEMPORARY_FILES_H
#define NORMAL_ORIENTATION_INTERNAL_TEMPORARY_FILES_H

/// \file Temporary_files.h
/// Temporary files, in one place: where they go (`temporary_directory()`), how they
/// are made (`Temporary_file`: `mkstemp()`, or a given name beside an output file),
/// the process-wide registry that a signal handler empties
/// (`Normal_orientation::remove_temporary_files()`, so that an interrupted run leaves
/// nothing behind), and the reads and writes that resume after a signal (`EINTR`).
///
/// POSIX only (`mkstemp`, `open`, `pread`, `unlink`).

#if !defined(__unix__) && !defined(__APPLE__)
#error "Normal_orientation/internal/Temporary_files.h needs POSIX (mkstemp, pread, unlink)"
#endif

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

namespace Normal_orientation {
/// \cond SKIP_IN_MANUAL
namespace internal {

// ------------------------------------------------------------------------ registry

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

/// returns true if `remove_temporary_files()` unlinked the file of `slot` (or -1)
inline bool removed_by_handler(int slot) noexcept
{
  return slot >= 0 && temporary_file_slots[slot].state.load(std::memory_order_acquire) == 3;
}

// ------------------------------------------------------------------ reads, writes

/// writes the `bytes` bytes at `data` to `fd`, resuming after `EINTR` and short
/// writes; returns 0, or the `errno` value of the failure (`ENOSPC` when `write()`
/// writes nothing)
inline int write_fully(int fd, const void* data, std::size_t bytes) noexcept
{
  const char* p = static_cast<const char*>(data);
  while (bytes > 0) {
    const ::ssize_t n = ::write(fd, p, std::min<std::size_t>(bytes, std::size_t(1) << 30));
    if (n < 0) {
      if (errno == EINTR)
        continue;
      return errno;
    }
    if (n == 0)
      return ENOSPC;
    p += n;
    bytes -= std::size_t(n);
  }
  return 0;
}

/// writes `bytes` bytes to `fd`, throwing `std::system_error` ("cannot write the
/// temporary file `path`") on failure
inline void write_all(int fd, const void* data, std::size_t bytes, const std::string& path)
{
  if (const int error = write_fully(fd, data, bytes))
    throw std::system_error(error, std::generic_category(), "cannot write the temporary file " + path);
}

/// reads `bytes` bytes at byte `offset` of `fd` into `data` (`pread()`, resuming after
/// `EINTR` and short reads); throws `std::system_error` ("cannot read the temporary
/// file `path`") on failure, `std::runtime_error` if the file ends first
inline void read_all(int fd, void* data, std::size_t bytes, std::uint64_t offset, const std::string& path)
{
  char* p = static_cast<char*>(data);
  while (bytes > 0) {
    const ::ssize_t got = ::pread(fd, p, bytes, ::off_t(offset));
    if (got < 0) {
      if (errno == EINTR)
        continue;
      throw std::system_error(errno, std::generic_category(), "cannot read the temporary file " + path);
    }
    if (got == 0)
      throw std::runtime_error("cannot read the temporary file " + path + ": it is shorter than written");
    p += got;
    bytes -= std::size_t(got);
    offset += std::uint64_t(got);
  }
}

// ----------------------------------------------------------------------- files

/// the temporary directory: `requested` if not empty, else `$TMPDIR` if set and
/// not empty, else /tmp
inline std::string temporary_directory(const std::string& requested = std::string())
{
  if (!requested.empty())
    return requested;
  const char* tmpdir = std::getenv("TMPDIR");
  if (tmpdir != nullptr && tmpdir[0] != '\0')
    return tmpdir;
  return "/tmp";
}

/// A temporary file, open for reading and writing, registered for
/// `remove_temporary_files()` and removed by the destructor (also when an exception
/// unwinds) unless `keep()` was called.  Move-only.
class Temporary_file
{
public:
  /// Asks for a file of the given name (see the constructor).
  struct Exact_name
  {
    /// the path of the file
    std::string path;
  };

  /// creates an empty file `<directory>/<prefix>XXXXXX` with `mkstemp()` (mode 0600) in
  /// `temporary_directory(directory)`; if `unlink_now`, removes its name at once (the
  /// data lives while the file is open; nothing is registered)
  /// \throw std::system_error ("cannot create a temporary file ...") on failure
  Temporary_file(const std::string& directory, const std::string& prefix, bool unlink_now = false)
  {
    std::string name = temporary_directory(directory);
    if (name.back() != '/')
      name += '/';
    name += prefix + "XXXXXX";
    m_path = name; // allocated before the file exists: nothing can leak after mkstemp()
    m_fd = ::mkstemp(&m_path[0]);
    if (m_fd < 0)
      throw std::system_error(errno, std::generic_category(), "cannot create a temporary file " + name);
    if (unlink_now) {
      ::unlink(m_path.c_str());
      m_unlinked = true;
    }
    else
      m_slot = register_temporary_file(m_path);
  }

  /// creates (or truncates) the file `name.path` for writing, as `fopen(..., "wb")`
  /// does (mode 0666 less the umask): an output written under a temporary name, to be
  /// renamed to its target once complete
  /// \throw std::system_error (the `errno` value, the message "cannot create `path`") on failure
  explicit Temporary_file(Exact_name name) : m_path(std::move(name.path))
  {
    do
      m_fd = ::open(m_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0666);
    while (m_fd < 0 && errno == EINTR);
    if (m_fd < 0)
      throw std::system_error(errno, std::generic_category(), "cannot create " + m_path);
    m_slot = register_temporary_file(m_path);
  }

  /// takes the file of `other`, which then owns none
  Temporary_file(Temporary_file&& other) noexcept { swap(other); }
  /// removes the file of `*this` and takes the one of `other`
  Temporary_file& operator=(Temporary_file&& other) noexcept
  {
    Temporary_file(std::move(other)).swap(*this);
    return *this;
  }
  Temporary_file(const Temporary_file&) = delete;
  Temporary_file& operator=(const Temporary_file&) = delete;

  /// closes and removes the file (unless kept, or already removed by the handler)
  ~Temporary_file()
  {
    if (!m_unlinked && !m_path.empty()) {
      if (!removed_by_handler(m_slot)) // a handler removed it: leave the name alone
        ::unlink(m_path.c_str());
      unregister_temporary_file(m_slot);
    }
    if (m_fd >= 0)
      ::close(m_fd);
  }

  /// the file descriptor (-1 after `close()`)
  int descriptor() const { return m_fd; }
  /// the path of the file
  const std::string& path() const { return m_path; }

  /// appends `bytes` bytes (see `write_all()`)
  void append(const void* data, std::size_t bytes) { write_all(m_fd, data, bytes, m_path); }
  /// reads `bytes` bytes at byte `offset` (see `read_all()`)
  void read(void* data, std::size_t bytes, std::uint64_t offset) const { read_all(m_fd, data, bytes, offset, m_path); }

  /// closes the descriptor (the file stays); returns 0 or the `errno` value of `close()`
  int close() noexcept
  {
    const int fd = m_fd;
    m_fd = -1;
    return fd >= 0 && ::close(fd) != 0 ? errno : 0;
  }

  /// the file is no longer temporary (it was renamed, say): unregisters it; the
  /// destructor will not remove it
  void keep() noexcept
  {
    unregister_temporary_file(m_slot);
    m_slot = -1;
    m_unlinked = true;
  }

private:
  void swap(Temporary_file& other) noexcept
  {
    std::swap(m_fd, other.m_fd);
    std::swap(m_slot, other.m_slot);
    std::swap(m_unlinked, other.m_unlinked);
    std::swap(m_path, other.m_path);
  }

  int m_fd = -1;
  int m_slot = -1;
  bool m_unlinked = false; // the name is gone, or not ours to remove
  std::string m_path;
};

} // namespace internal
/// \endcond
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_TEMPORARY_FILES_H
