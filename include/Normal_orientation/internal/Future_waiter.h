// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_FUTURE_WAITER_H
#define NORMAL_ORIENTATION_INTERNAL_FUTURE_WAITER_H

/// \file Future_waiter.h
/// A guard that waits for an asynchronous task before the frame it uses ends.

#include <future>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// Waits for `future` (when it is valid) on destruction.  A task launched
/// with `std::async` that refers to variables of the launching function must
/// end before they do, also when an exception leaves the function; declared
/// after those variables, this guard sees to it.  Its exception, if any, is
/// left in the future.
template <typename T>
struct Future_waiter
{
  /// the future waited for
  std::future<T>& future;
  ~Future_waiter()
  {
    if (future.valid())
      future.wait();
  }
};

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_FUTURE_WAITER_H
