// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_PROGRESS_H
#define NORMAL_ORIENTATION_PROGRESS_H

/// \file Progress.h
/// Progress reporting and cancellation, the same for both drivers: the
/// `callback` named parameter of `orient_normals()` and
/// `streaming_orient_normals()` is either CGAL's `bool(double)` (the
/// fraction of the whole run done) or `bool(const Progress_info&)` (the
/// stage running, its units done, and that fraction).  Returning `false`
/// stops the run: both drivers then return a result whose `interrupted`
/// is true, having written nothing.

#include <algorithm>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <type_traits>
#include <utility>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationRef
/// The stages of both drivers, in the order they run (each driver runs
/// some of them: in core `INPUT`, `GRAPH`, `SOLVE`, `SIGN`, `GLOBAL`;
/// streamed `SCAN` to `COMPONENTS`).
enum class Stage
{
  INPUT,     ///< in core: copying, checking and spatially sorting the input
  GRAPH,     ///< in core: the neighbour search and the edge weights
  SCAN,      ///< streamed: the first pass (count, finiteness, frame, radius sample, order check)
  RADIUS,    ///< streamed: the neighbour distances of the radius sample (only when r is estimated)
  SORT,      ///< streamed: the external sort along the principal axis (not with a presorted input)
  SWEEP,     ///< streamed: the sweep (neighbour graph, edge weights, segmentation)
  SOLVE,     ///< the solver (streamed: on the segment graph)
  REFINE,    ///< streamed: the refinement passes
  SIGN,      ///< the sign of every connected component
  GLOBAL,    ///< the global sign stage (the winding number of the cloud)
  OUTPUT,    ///< the oriented normals written back or handed to the sink
  COMPONENTS ///< streamed: the files of the components
};

/// \ingroup PkgNormalOrientationRef
/// The lower-case name of `stage` ("input", "graph", "scan", "radius",
/// "sort", "sweep", "solve", "refine", "sign", "global", "output", "components").
/// \param stage the stage
/// \return a string literal
inline const char* stage_name(Stage stage)
{
  static const char* const names[] = {"input",  "graph", "scan",   "radius", "sort",      "sweep",
                                      "solve",  "refine", "sign", "global", "output", "components"};
  const int i = int(stage);
  return i >= 0 && i < int(sizeof(names) / sizeof(names[0])) ? names[i] : "?";
}

/// \ingroup PkgNormalOrientationRef
/// What a stage-aware progress callback is told.  Every stage is reported
/// at its start (`done` = 0) and at its end (`done` = `total`), and in
/// between as it goes.
struct Progress_info
{
  /// the stage running
  Stage stage = Stage::INPUT;
  /// the units of work of the stage done so far (points, or points times
  /// passes; in core, thousandths of the stage)
  std::uint64_t done = 0;
  /// the units of work of the stage, 0 when unknown (the scan, which
  /// counts the points)
  std::uint64_t total = 0;
  /// the fraction of the whole run done, in [0, 1], non-decreasing
  double fraction = 0.0;
  /// `done / total` in [0, 1]; 0 when the total is unknown
  double stage_fraction() const { return total > 0 ? std::min(1.0, double(done) / double(total)) : 0.0; }
};

/// \ingroup PkgNormalOrientationRef
/// Thrown inside the package when the user's callback returns `false`;
/// the drivers catch it and return a result whose `interrupted` is true.
struct Interrupted : std::runtime_error
{
  /// the exception
  Interrupted() : std::runtime_error("interrupted by the callback") {}
};

/// \ingroup PkgNormalOrientationRef
/// Forwards progress to the user's callback, from the calling thread:
/// each stage of a run is given a part [begin, end] of the whole run, and
/// reports within it.  An empty reporter costs nothing.  Throws
/// `Interrupted` when the callback returns false.
class Progress_reporter
{
public:
  /// a reporter that reports nothing
  Progress_reporter() = default;

  /// a reporter forwarding to `callback`, a callable as `bool(const
  /// Progress_info&)` or `bool(double)` (the fraction of the whole run);
  /// an empty `std::function` reports nothing
  template <typename Callback,
            typename = std::enable_if_t<!std::is_same<std::decay_t<Callback>, Progress_reporter>::value>>
  explicit Progress_reporter(Callback callback)
  {
    if constexpr (std::is_constructible<bool, const Callback&>::value) { // std::function, pointers
      if (!static_cast<bool>(callback))
        return;
    }
    if constexpr (std::is_invocable_r<bool, Callback&, const Progress_info&>::value)
      m_callback = std::move(callback);
    else {
      static_assert(std::is_invocable_r<bool, Callback&, double>::value,
                    "the callback must be callable as bool(const Progress_info&) or bool(double)");
      m_callback = [f = std::move(callback)](const Progress_info& p) mutable { return bool(f(p.fraction)); };
    }
  }

  /// the part [a, b] (fractions of this reporter's part) of the run, for `stage`
  Progress_reporter part(Stage stage, double a, double b) const
  {
    Progress_reporter r(*this);
    r.m_stage = stage;
    r.m_begin = m_begin + (m_end - m_begin) * a;
    r.m_end = m_begin + (m_end - m_begin) * b;
    return r;
  }
  /// the part [a, b] of this reporter's part, for the same stage
  Progress_reporter part(double a, double b) const { return part(m_stage, a, b); }

  /// reports `x` in [0, 1] of this part
  void report(double x) const
  {
    if (m_callback)
      call(std::uint64_t(std::clamp(x, 0.0, 1.0) * 1000.0 + 0.5), 1000, x);
  }
  /// reports `done` units of `total` (0: unknown) of this part
  void report(std::uint64_t done, std::uint64_t total) const
  {
    if (m_callback)
      call(done, total, total > 0 ? double(done) / double(total) : 0.0);
  }
  /// true when there is a callback
  bool enabled() const { return bool(m_callback); }

private:
  void call(std::uint64_t done, std::uint64_t total, double x) const
  {
    Progress_info p;
    p.stage = m_stage;
    p.done = done;
    p.total = total;
    p.fraction = m_begin + (m_end - m_begin) * std::clamp(x, 0.0, 1.0);
    if (!m_callback(p))
      throw Interrupted();
  }

  std::function<bool(const Progress_info&)> m_callback;
  Stage m_stage = Stage::INPUT;
  double m_begin = 0.0, m_end = 1.0;
};

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_PROGRESS_H
