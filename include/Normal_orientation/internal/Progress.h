// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_PROGRESS_H
#define NORMAL_ORIENTATION_INTERNAL_PROGRESS_H

/// \file Progress.h
/// Progress reporting and interruption through the `callback` named
/// parameter (`std::function<bool(double)>`, as in CGAL).

#include <functional>
#include <stdexcept>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationRef
/// Thrown inside the package when the user's callback returns `false`;
/// `orient_normals()` catches it and reports an interrupted run.
struct Interrupted : std::runtime_error
{
  /// the exception
  Interrupted() : std::runtime_error("interrupted by the callback") {}
};

namespace internal {

/// Maps the progress of one stage, in [0, 1], into a sub-range of the whole
/// run and forwards it to the user's callback, always from the calling
/// thread.  An empty callback costs nothing.
class Progress
{
public:
  /// a progress that reports nothing
  Progress() = default;
  /// a progress forwarding [0, 1] to `callback` as [begin, end]
  explicit Progress(std::function<bool(double)> callback, double begin = 0.0, double end = 1.0)
    : m_callback(std::move(callback)), m_begin(begin), m_end(end)
  {}
  /// the part [a, b] of this progress, as a progress of its own
  Progress stage(double a, double b) const
  {
    return Progress(m_callback, m_begin + (m_end - m_begin) * a, m_begin + (m_end - m_begin) * b);
  }
  /// reports `x` in [0, 1]; throws `Interrupted` when the callback says stop
  void report(double x) const
  {
    if (m_callback && !m_callback(m_begin + (m_end - m_begin) * x))
      throw Interrupted();
  }

private:
  std::function<bool(double)> m_callback;
  double m_begin = 0.0, m_end = 1.0;
};

} // namespace internal
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_INTERNAL_PROGRESS_H
