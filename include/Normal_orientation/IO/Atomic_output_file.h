// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Atomic_output_file.h
/// \brief Atomic output: a file written to a temporary file beside its target, through
/// a buffer, and renamed over the target only when complete, so that an output file is
/// either complete or absent, and an existing target is left untouched on failure.

#ifndef NORMAL_ORIENTATION_IO_ATOMIC_OUTPUT_FILE_H
#define NORMAL_ORIENTATION_IO_ATOMIC_OUTPUT_FILE_H

#include <Normal_orientation/IO/Io_error.h>
#include <Normal_orientation/IO/Number_text.h>
#include <Normal_orientation/internal/Temporary_files.h>
#include <Normal_orientation/remove_temporary_files.h>

#include <atomic>
#include <cerrno>
#include <charconv>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

#include <sys/types.h>
#include <unistd.h>

namespace Normal_orientation {
namespace IO {
namespace internal {

/// \brief Output file written through a temporary file renamed over the target by
/// `commit()`; if `commit()` is not reached, the destructor removes the temporary file.
///
/// The temporary file `<target>.tmp.<pid>.<counter>` is registered for
/// `Normal_orientation::remove_temporary_files()`. Every error throws `Io_error`
/// naming the target.
class Atomic_output_file
{
public:
  /// Creates `<target>.tmp.<pid>.<counter>` for writing.
  explicit Atomic_output_file(const std::string& target)
    : target_(target), buffer_(new char[capacity])
  {
    static std::atomic<unsigned long> counter{0};
    std::string temporary = target + ".tmp." + std::to_string(static_cast<long>(::getpid())) + "." +
                            std::to_string(counter.fetch_add(1));
    try {
      file_.emplace(Normal_orientation::internal::Temporary_file::Exact_name{temporary});
    } catch(const std::system_error& error) {
      fail(target_, "cannot create temporary file '" + temporary + "': " + error_text(error.code().value()));
    }
  }

  Atomic_output_file(const Atomic_output_file&) = delete;
  Atomic_output_file& operator=(const Atomic_output_file&) = delete;

  /// Name of the target file.
  const std::string& target() const { return target_; }

  /// Makes room for `size` (at most `capacity`) bytes and returns where to put them;
  /// `advance()` must then be called with the number of bytes put.
  char* room(std::size_t size)
  {
    if(used_ + size > capacity) flush_buffer();
    return buffer_.get() + used_;
  }

  /// Accounts for `size` bytes put at `room()`.
  void advance(std::size_t size) { used_ += size; }

  /// Appends one character.
  void put(char c)
  {
    *room(1) = c;
    ++used_;
  }

  /// Appends `text`.
  void put(std::string_view text)
  {
    if(text.size() > capacity) {
      flush_buffer();
      write_through(text.data(), text.size());
      return;
    }
    std::memcpy(room(text.size()), text.data(), text.size());
    used_ += text.size();
  }

  /// Appends the shortest text that reads back as `value` (a `double`, `float` or integer).
  template <class T>
  void put_shortest(T value)
  {
    char* first = room(max_number_length);
    const std::to_chars_result result = std::to_chars(first, first + max_number_length, value);
    used_ += static_cast<std::size_t>(result.ptr - first);
  }

  /// Appends `value` with `precision` significant digits (`%g` style); shortest exact
  /// text if `precision <= 0`.
  void put_real(double value, int precision)
  {
    char* first = room(max_number_length);
    used_ += static_cast<std::size_t>(format_real(first, value, precision) - first);
  }

  /// Replaces the `data.size()` bytes at byte `offset` of the data put so far (for
  /// instance a count in a header, written with a fixed width); appending resumes at
  /// the end of the data.
  void overwrite(std::uint64_t offset, std::string_view data)
  {
    flush_buffer();
    seek(static_cast<off_t>(offset), SEEK_SET);
    write_through(data.data(), data.size());
    seek(0, SEEK_END);
  }

  /// Writes the remaining data, closes the temporary file and renames it over the target.
  void commit()
  {
    flush_buffer();
    if(const int error = file_->close()) fail(target_, "cannot close file: " + error_text(error));
    if(std::rename(file_->path().c_str(), target_.c_str()) != 0) {
      const int error_number = errno;
      fail(target_, "cannot rename '" + file_->path() + "' to the target: " + error_text(error_number));
    }
    file_->keep();
  }

  /// Size of the write buffer.
  static constexpr std::size_t capacity = std::size_t(1) << 20;
  /// Room reserved for one number.
  static constexpr std::size_t max_number_length = 64;

private:
  void write_through(const char* data, std::size_t size)
  {
    if(const int error = Normal_orientation::internal::write_fully(file_->descriptor(), data, size))
      fail(target_, "cannot write file: " + error_text(error));
  }

  void flush_buffer()
  {
    write_through(buffer_.get(), used_);
    used_ = 0;
  }

  void seek(off_t offset, int whence)
  {
    if(::lseek(file_->descriptor(), offset, whence) < 0) fail(target_, "cannot seek in file: " + error_text(errno));
  }

  std::string target_;
  std::optional<Normal_orientation::internal::Temporary_file> file_;
  std::unique_ptr<char[]> buffer_;
  std::size_t used_ = 0;
};

} // namespace internal
} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_ATOMIC_OUTPUT_FILE_H
