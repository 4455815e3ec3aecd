// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_RECORD_FILE_H
#define NORMAL_ORIENTATION_STREAMING_RECORD_FILE_H

/// \file Record_file.h
/// A temporary file of fixed-size records, appended once and read back
/// sequentially any number of times: where the streaming pipeline keeps the
/// points that left the sweep window until the segment labels are known.

#include <Normal_orientation/internal/Temporary_files.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

namespace Normal_orientation {
namespace streaming {

/// \ingroup PkgNormalOrientationStreaming
/// A temporary file of records of the trivially copyable type `T`, created
/// with `mkstemp()` in `directory` (TMPDIR, else /tmp, when empty),
/// registered for `remove_temporary_files()` (so that a signal handler can
/// remove it), and removed by the destructor, also when an exception
/// unwinds (see `Normal_orientation::internal::Temporary_file`).  Appends are
/// buffered; `read()` reads sequentially from a cursor that `rewind()` resets.
template <typename T>
class Record_file
{
  static_assert(std::is_trivially_copyable<T>::value, "records are written as bytes");

public:
  /// creates the empty file; `buffer_records` records are buffered
  explicit Record_file(const std::string& directory = std::string(), std::size_t buffer_records = 1 << 14)
    : m_capacity(std::max<std::size_t>(1, buffer_records)), m_file(directory, "normal_orientation_records_")
  {
    m_buffer.reserve(m_capacity);
  }

  Record_file(const Record_file&) = delete;
  Record_file& operator=(const Record_file&) = delete;

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
    m_file.append(m_buffer.data(), m_buffer.size() * sizeof(T));
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
    try {
      m_file.read(out.data() + old, n * sizeof(T), m_next * sizeof(T));
    } catch (...) {
      out.resize(old);
      throw;
    }
    m_next += n;
    return n;
  }

  /// the number of records appended
  std::uint64_t size() const { return m_size + m_buffer.size(); }
  /// the path of the file
  const std::string& path() const { return m_file.path(); }

private:
  std::size_t m_capacity;
  std::vector<T> m_buffer;
  Normal_orientation::internal::Temporary_file m_file;
  std::uint64_t m_size = 0, m_next = 0;
};

} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_RECORD_FILE_H
