// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_RECORD_FILE_H
#define NORMAL_ORIENTATION_STREAMING_RECORD_FILE_H

/// \file Record_file.h
/// A temporary file of fixed-size records, appended once and read back
/// sequentially any number of times: where the streaming pipeline keeps the
/// points that left the sweep window until the segment labels are known.

#include <Normal_orientation/streaming/external_sort.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <system_error>
#include <type_traits>
#include <vector>

#include <unistd.h>

namespace Normal_orientation {
namespace streaming {

/// \ingroup PkgNormalOrientationStreaming
/// A temporary file of records of the trivially copyable type `T`, created
/// with `mkstemp()` in `directory` (TMPDIR, else /tmp, when empty),
/// registered for `remove_temporary_files()` (so that a signal handler can
/// remove it), and removed by the destructor, also when an exception
/// unwinds.  Appends are buffered; `read()` reads sequentially from a
/// cursor that `rewind()` resets.
template <typename T>
class Record_file
{
  static_assert(std::is_trivially_copyable<T>::value, "records are written as bytes");

public:
  /// creates the empty file; `buffer_records` records are buffered
  explicit Record_file(const std::string& directory = std::string(), std::size_t buffer_records = 1 << 14)
    : m_capacity(std::max<std::size_t>(1, buffer_records))
  {
    std::string name = directory;
    if (name.empty()) {
      const char* t = std::getenv("TMPDIR");
      name = (t != nullptr && *t != '\0') ? t : "/tmp";
    }
    if (name.back() != '/')
      name += '/';
    name += "normal_orientation_records_XXXXXX";
    m_path = name;
    m_fd = ::mkstemp(&m_path[0]);
    if (m_fd < 0)
      throw std::system_error(errno, std::generic_category(), "cannot create a temporary file " + name);
    m_slot = internal::register_temporary_file(m_path);
    m_buffer.reserve(m_capacity);
  }

  Record_file(const Record_file&) = delete;
  Record_file& operator=(const Record_file&) = delete;

  /// closes and removes the file
  ~Record_file()
  {
    const bool removed_by_handler =
      m_slot >= 0 && internal::temporary_file_slots[m_slot].state.load(std::memory_order_acquire) == 3;
    if (!removed_by_handler)
      ::unlink(m_path.c_str());
    internal::unregister_temporary_file(m_slot);
    ::close(m_fd);
  }

  /// appends `record`
  void append(const T& record)
  {
    m_buffer.push_back(record);
    if (m_buffer.size() == m_capacity)
      flush();
  }

  /// writes the buffered records to the file
  /// \throw std::system_error when the write fails (disk full, say)
  void flush()
  {
    if (m_buffer.empty())
      return;
    internal::write_all(m_fd, m_buffer.data(), m_buffer.size() * sizeof(T), m_path);
    m_size += m_buffer.size();
    m_buffer.clear();
  }

  /// restarts reading from the first record (flushes first)
  void rewind()
  {
    flush();
    m_next = 0;
  }

  /// appends to `out` up to `maximum` records from the cursor on; returns
  /// how many (0 at the end).  Flush (or rewind) after the last append.
  std::size_t read(std::vector<T>& out, std::size_t maximum)
  {
    const std::size_t n = std::size_t(std::min<std::uint64_t>(maximum, m_size - m_next));
    if (n == 0)
      return 0;
    const std::size_t old = out.size();
    out.resize(old + n);
    char* p = reinterpret_cast<char*>(out.data() + old);
    std::size_t bytes = n * sizeof(T);
    std::uint64_t offset = m_next * sizeof(T);
    while (bytes > 0) {
      const ::ssize_t got = ::pread(m_fd, p, bytes, ::off_t(offset));
      if (got < 0 && errno == EINTR)
        continue;
      if (got <= 0) {
        out.resize(old);
        throw std::runtime_error("cannot read the temporary file " + m_path);
      }
      p += got;
      bytes -= std::size_t(got);
      offset += std::uint64_t(got);
    }
    m_next += n;
    return n;
  }

  /// the number of records appended
  std::uint64_t size() const { return m_size + m_buffer.size(); }
  /// the path of the file
  const std::string& path() const { return m_path; }

private:
  std::size_t m_capacity;
  std::vector<T> m_buffer;
  std::string m_path;
  int m_fd = -1;
  int m_slot = -1;
  std::uint64_t m_size = 0, m_next = 0;
};

} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_RECORD_FILE_H
