// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Text_threads.h
/// \brief Text files parsed and formatted by several threads: how many threads for a
/// text of a given size, running tasks concurrently with the first error in task order,
/// and splitting a text at line boundaries.

#ifndef NORMAL_ORIENTATION_IO_TEXT_THREADS_H
#define NORMAL_ORIENTATION_IO_TEXT_THREADS_H

#include <Normal_orientation/IO/Text_lines.h>

#include <algorithm>
#include <cstddef>
#include <exception>
#include <thread>
#include <vector>

namespace Normal_orientation {
namespace IO {
namespace internal {

/// \brief Text size above which `.xyz`/`.pwn` files are parsed and formatted by several
/// threads when the number of threads is chosen automatically.
constexpr std::size_t parallel_text_size = std::size_t(4) << 20;

/// \brief Largest number of threads parsing or formatting a text file.
constexpr unsigned int max_text_threads = 8;

/// \brief Number of threads for a text of about `size` bytes: `requested` if positive,
/// otherwise 1 up to `parallel_text_size` bytes and the number of hardware threads
/// above; at most `max_text_threads` in all cases.
inline unsigned int text_thread_count(unsigned int requested, std::size_t size)
{
  if(requested > 0) return std::min(requested, max_text_threads);
  if(size <= parallel_text_size) return 1;
  const unsigned int hardware = std::thread::hardware_concurrency(); // 0 if unknown
  return std::max(1u, std::min(hardware, max_text_threads));
}

/// \brief Calls `task(i)` for every `i` in `[0, count)`, concurrently: `task(0)` in the
/// calling thread, the others in new threads (in the calling thread, after `task(0)`,
/// if no more threads can be started). Returns when all calls have returned; then
/// rethrows the exception of the call with the smallest `i` that threw, if any.
template <class Task>
inline void run_concurrently(std::size_t count, const Task& task)
{
  if(count == 0) return;
  std::vector<std::exception_ptr> errors(count);
  auto run = [&task, &errors](std::size_t i) {
    try {
      task(i);
    } catch(...) {
      errors[i] = std::current_exception();
    }
  };
  std::vector<std::thread> threads;
  threads.reserve(count - 1); // emplace_back below does not reallocate
  std::size_t started = 1;
  try {
    for(; started < count; ++started) threads.emplace_back(run, started);
  } catch(...) {
    // No more threads: the remaining calls are made by the calling thread.
  }
  run(0);
  for(std::size_t i = started; i < count; ++i) run(i);
  for(std::thread& thread : threads) thread.join();
  for(const std::exception_ptr& error : errors)
    if(error) std::rethrow_exception(error);
}

/// \brief Splits `[begin, end)` into `parts` consecutive chunks of about the same size,
/// each made of whole lines (a chunk ends just after a `'\n'`, or at `end`; some chunks
/// may be empty). Returns the `parts + 1` chunk bounds.
inline std::vector<const char*> split_at_lines(const char* begin, const char* end, unsigned int parts)
{
  std::vector<const char*> bounds(1, begin);
  const std::size_t step = static_cast<std::size_t>(end - begin) / std::max(parts, 1u);
  for(unsigned int i = 1; i < parts; ++i) {
    const char* target = std::max(begin + step * i, bounds.back());
    const char* eol = end_of_line(target, end);
    bounds.push_back(eol < end ? eol + 1 : end);
  }
  bounds.push_back(end);
  return bounds;
}

} // namespace internal
} // namespace IO
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_IO_TEXT_THREADS_H
