// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Input_file.h
/// \brief Reading a file: its whole content at once (`read_file_content()`), or
/// sequentially through a buffer of fixed size (`Buffered_input`), with the same checks
/// and messages when it cannot be opened.

#ifndef NORMAL_ORIENTATION_IO_INPUT_FILE_H
#define NORMAL_ORIENTATION_IO_INPUT_FILE_H

#include <Normal_orientation/IO/Io_error.h>

#include <algorithm>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <system_error>
#include <utility>

#include <sys/types.h>

namespace Normal_orientation {
namespace IO {
namespace internal {

/// \brief Opens `filename` for reading (binary).
/// \throws Io_error if it is a directory or cannot be opened.
inline std::FILE* open_for_reading(const std::string& filename)
{
  std::error_code error;
  if(std::filesystem::is_directory(filename, error)) fail(filename, "cannot read file: it is a directory");
  std::FILE* file = std::fopen(filename.c_str(), "rb");
  if(file == nullptr) {
    const int error_number = errno;
    fail(filename, "cannot open file for reading: " + error_text(error_number));
  }
  return file;
}

/// \brief The whole content of a file.
struct File_content
{
  std::unique_ptr<char[]> data;
  std::size_t size = 0;
  const char* begin() const { return data.get(); }
  const char* end() const { return data.get() + size; }
};

/// \brief Reads the whole file `filename` (a single `fread` for a regular file).
inline File_content read_file_content(const std::string& filename)
{
  std::FILE* file = open_for_reading(filename);
  struct Closer {
    std::FILE* file;
    ~Closer() { std::fclose(file); }
  } closer{file};

  std::error_code error;
  const std::uintmax_t size_hint = std::filesystem::file_size(filename, error);
  if(!error && size_hint >= std::numeric_limits<std::size_t>::max() / 2)
    fail(filename, "file too large");
  // One more byte than expected, so that a regular file is read by a single fread.
  std::size_t capacity = error ? std::size_t(1) << 16 : static_cast<std::size_t>(size_hint) + 1;
  File_content content;
  content.data.reset(new char[capacity]);
  for(;;) {
    const std::size_t wanted = capacity - content.size;
    const std::size_t got = std::fread(content.data.get() + content.size, 1, wanted, file);
    content.size += got;
    if(got < wanted) {
      if(std::ferror(file)) {
        const int error_number = errno;
        fail(filename, "cannot read file: " + error_text(error_number));
      }
      break; // end of file
    }
    // The file grew or its size was unknown: enlarge the buffer.
    if(capacity >= std::numeric_limits<std::size_t>::max() / 4)
      fail(filename, "file too large");
    std::unique_ptr<char[]> larger(new char[capacity * 2]);
    std::memcpy(larger.get(), content.data.get(), content.size);
    content.data = std::move(larger);
    capacity *= 2;
  }
  return content;
}

/// \brief Sequential reading of a seekable file through a buffer of fixed capacity.
///
/// `data()` and `available()` give the bytes read but not consumed yet; `fill()` reads
/// more (moving the unconsumed bytes to the front of the buffer, which invalidates the
/// pointers obtained before).
class Buffered_input
{
public:
  /// Result of `next_line()`.
  enum class Line_status
  {
    LINE,     ///< a line was found
    END,      ///< end of file, no more lines
    TOO_LONG  ///< the line does not fit in the buffer; nothing was consumed
  };

  /// Opens `filename` for reading, with a buffer of `capacity` bytes.
  Buffered_input(const std::string& filename, std::size_t capacity)
    : filename_(filename), capacity_(capacity), buffer_(new char[capacity])
  {
    file_ = open_for_reading(filename);
    if(::fseeko(file_, 0, SEEK_END) != 0) seek_failed();
    const off_t size = ::ftello(file_);
    if(size < 0) seek_failed();
    file_size_ = static_cast<std::uint64_t>(size);
    seek(0);
  }

  Buffered_input(const Buffered_input&) = delete;
  Buffered_input& operator=(const Buffered_input&) = delete;

  ~Buffered_input()
  {
    if(file_ != nullptr) std::fclose(file_);
  }

  /// Size of the buffer in bytes.
  std::size_t capacity() const { return capacity_; }
  /// Size of the file in bytes when it was opened.
  std::uint64_t file_size() const { return file_size_; }
  /// Byte offset in the file of `data()`.
  std::uint64_t position() const { return buffer_offset_ + static_cast<std::uint64_t>(begin_ - buffer_.get()); }
  /// The bytes read and not consumed yet.
  const char* data() const { return begin_; }
  /// Number of bytes at `data()`.
  std::size_t available() const { return static_cast<std::size_t>(end_ - begin_); }
  /// Consumes `size <= available()` bytes.
  void consume(std::size_t size) { begin_ += size; }

  /// Enlarges the buffer to at least `capacity` bytes, keeping its content.
  void reserve(std::size_t capacity)
  {
    if(capacity <= capacity_) return;
    std::unique_ptr<char[]> larger(new char[capacity]);
    const std::size_t size = available();
    std::memcpy(larger.get(), begin_, size);
    buffer_offset_ = position();
    buffer_ = std::move(larger);
    capacity_ = capacity;
    begin_ = buffer_.get();
    end_ = begin_ + size;
  }

  /// Restarts reading at byte `offset` of the file.
  void seek(std::uint64_t offset)
  {
    if(::fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0) seek_failed();
    buffer_offset_ = offset;
    begin_ = end_ = buffer_.get();
    at_end_ = false;
  }

  /// Reads until at least `wanted` (at most `capacity()`) bytes are available or the
  /// file ends; returns `available()`.
  std::size_t fill(std::size_t wanted)
  {
    if(available() >= wanted || at_end_) return available();
    const std::size_t size = available();
    buffer_offset_ = position();
    std::memmove(buffer_.get(), begin_, size);
    begin_ = buffer_.get();
    end_ = begin_ + size;
    const std::size_t room = capacity_ - size;
    const std::size_t got = std::fread(end_, 1, room, file_);
    end_ += got;
    if(got < room) {
      if(std::ferror(file_)) {
        const int error_number = errno;
        fail(filename_, "cannot read file: " + error_text(error_number));
      }
      at_end_ = true;
    }
    return available();
  }

  /// Skips `size` bytes; returns `false`, at the end of the file, if it has fewer.
  bool skip(std::uint64_t size)
  {
    if(size <= available()) {
      consume(static_cast<std::size_t>(size));
      return true;
    }
    const std::uint64_t target = position() + size;
    if(target > file_size_) {
      seek(file_size_);
      return false;
    }
    seek(target);
    return true;
  }

  /// Sets `[begin, eol)` to the next line (without its `'\n'`) and consumes it.
  Line_status next_line(const char*& begin, const char*& eol)
  {
    std::size_t scanned = 0; // bytes at data() known to hold no '\n'
    for(;;) {
      const void* newline = std::memchr(begin_ + scanned, '\n', available() - scanned);
      if(newline != nullptr) {
        begin = begin_;
        eol = static_cast<const char*>(newline);
        begin_ += (eol - begin_) + 1;
        return Line_status::LINE;
      }
      scanned = available();
      if(at_end_) {
        if(scanned == 0) return Line_status::END;
        begin = begin_;
        eol = end_;
        begin_ = end_;
        return Line_status::LINE;
      }
      if(scanned == capacity_) return Line_status::TOO_LONG;
      fill(scanned + 1);
    }
  }

  /// Consumes the rest of the current line, its `'\n'` included, whatever its length.
  void skip_line()
  {
    for(;;) {
      const void* newline = std::memchr(begin_, '\n', available());
      if(newline != nullptr) {
        begin_ += (static_cast<const char*>(newline) - begin_) + 1;
        return;
      }
      begin_ = end_;
      if(fill(1) == 0) return;
    }
  }

  /// Appends the next line, its `'\n'` included, to `text`, but no more than
  /// `max_size - text.size()` bytes; returns `false` at the end of the file.
  bool append_line(std::string& text, std::size_t max_size)
  {
    if(fill(1) == 0) return false;
    while(text.size() < max_size) {
      const std::size_t size = std::min(available(), max_size - text.size());
      const void* newline = std::memchr(begin_, '\n', size);
      const std::size_t taken = newline != nullptr ? static_cast<std::size_t>(static_cast<const char*>(newline) - begin_) + 1
                                                   : size;
      text.append(begin_, taken);
      begin_ += taken;
      if(newline != nullptr || fill(1) == 0) break;
    }
    return true;
  }

private:
  [[noreturn]] void seek_failed()
  {
    const int error_number = errno;
    fail(filename_, "cannot seek in file (streaming needs a regular file): " + error_text(error_number));
  }

  std::string filename_;
  std::FILE* file_ = nullptr;
  std::uint64_t file_size_ = 0;
  std::size_t capacity_;
  std::unique_ptr<char[]> buffer_;
  std::uint64_t buffer_offset_ = 0; // byte offset in the file of buffer_[0]
  char* begin_ = nullptr;           // unconsumed data: [begin_, end_)
  char* end_ = nullptr;
  bool at_end_ = false; // the file has no more bytes after end_
};

} // namespace internal
} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_INPUT_FILE_H
