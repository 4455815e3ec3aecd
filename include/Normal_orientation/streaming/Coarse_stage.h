// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_COARSE_STAGE_H
#define NORMAL_ORIENTATION_STREAMING_COARSE_STAGE_H

/// \file Coarse_stage.h
/// The streaming driver of the coarse-to-fine pass (`internal/Coarse_scale.h`),
/// around the solve and the global stage: one more pass over the records feeds the
/// accumulator, whose grid holds at most `coarse_maximum_cells` cells; the
/// coarse cloud is oriented in core by the caller, and the points take its
/// signs in the output passes (through `Point_labels::point_flip`).

#include <Normal_orientation/Orientation_result.h>
#include <Normal_orientation/internal/Coarse_scale.h>
#include <Normal_orientation/internal/Settings.h>
#include <Normal_orientation/streaming/Labelled_records.h>
#include <Normal_orientation/streaming/Segmenting_sweep.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// The coarse-to-fine pass on the records: the constructor reads them once
/// into the accumulator and measures whether their input normals agree
/// (`runs()`: they do not, and the pass is to be tried).  `apply()` orients
/// the coarse cloud (once, whatever the number of calls; `orient(const
/// Coarse_scale&)` must orient it with the in-core pipeline and return the
/// oriented normals and the closedness of the result, as a pair) and, when it
/// is more closed than the fine orientation (`fine_closedness`), installs the
/// coarse signs in `labels` before the global stage's decision, which is kept
/// for the points without a coarse opinion.  `component` is per sweep
/// segment, `flip_component` the sign stage's decision; both must outlive the
/// output passes.
class Stream_coarse_pass
{
  typedef Normal_orientation::internal::Coarse_scale Coarse_scale;

public:
  Stream_coarse_pass(Record_file<Swept_record>& records, double radius, std::uint64_t n)
    : m_coarse(std::make_shared<Coarse_scale>(radius))
  {
    const auto t = std::chrono::steady_clock::now();
    records.rewind();
    std::vector<Swept_record> chunk;
    while (true) {
      chunk.clear();
      if (records.read(chunk, std::size_t(1) << 15) == 0)
        break;
      for (const Swept_record& s : chunk) {
        const Point_record& r = s.record;
        m_coarse->add({{r.position[0], r.position[1], r.position[2]}}, unit_normal(r));
      }
    }
    records.rewind();
    m_runs = m_coarse->decide(std::size_t(n));
    m_report = m_coarse->report();
    if (!m_runs)
      m_coarse.reset(); // its grid is not needed any more
    m_seconds = Normal_orientation::internal::seconds_since(t);
  }

  /// whether the input normals disagree enough for the pass to be tried
  bool runs() const { return m_runs; }

  /// the pass against the fine orientation in `labels`; returns whether the
  /// coarse signs were installed
  template <typename Orient>
  bool apply(Point_labels& labels, const std::vector<std::uint32_t>& component,
             const std::vector<char>& flip_component, double fine_closedness, const Orient& orient)
  {
    if (!m_runs)
      return false;
    const auto t = std::chrono::steady_clock::now();
    if (!m_oriented) {
      m_oriented_cloud = orient(*m_coarse);
      m_oriented = true;
    }
    const bool used =
      m_coarse->use_coarse_orientation(m_oriented_cloud.first, m_oriented_cloud.second, fine_closedness);
    if (used) {
      auto previous = std::move(labels.point_flip);
      const std::shared_ptr<Coarse_scale> coarse = m_coarse;
      const std::vector<std::uint32_t>* segment_component = &component;
      const std::vector<char>* flips = &flip_component;
      labels.point_flip = [coarse, previous, segment_component, flips](const Swept_record& s, std::uint32_t segment,
                                                                       Label label) {
        const Point_record& r = s.record;
        const signed char c = coarse->sign({{r.position[0], r.position[1], r.position[2]}}, unit_normal(r));
        if (c == 0)
          return previous ? previous(s, segment, label) : false;
        const int sign = (*flips)[(*segment_component)[s.segment]] ? -1 : 1;
        return int(label) * sign != int(c); // the output label is label * sign, negated when true
      };
    }
    m_report = m_coarse->report();
    m_seconds += Normal_orientation::internal::seconds_since(t);
    return used;
  }

  /// what the pass measured and did, with the seconds of all its calls
  Normal_orientation::internal::Coarse_scale_report report() const
  {
    Normal_orientation::internal::Coarse_scale_report r = m_report;
    r.seconds = m_seconds;
    return r;
  }

private:
  std::shared_ptr<Coarse_scale> m_coarse; ///< (released when the pass does not run)
  Normal_orientation::internal::Coarse_scale_report m_report;
  bool m_runs = false, m_oriented = false;
  std::pair<std::vector<std::array<double, 3>>, double> m_oriented_cloud;
  double m_seconds = 0.0;
};

/// The coarse-to-fine pass around the solve (`solve_around_coarse_pass()`):
/// `fine(solver, improve)` solves, refines when `improve`, signs and runs
/// the global stage, leaving its summary in `global`; then the pass is tried
/// (`Stream_coarse_pass`, `orient` as for `Stream_coarse_pass::apply()`).
/// Adds the pass's figures to `global` and its seconds to `seconds`.
template <typename Solver, typename Fine, typename Orient>
void coarse_stage(Record_file<Swept_record>& records, double radius, std::uint64_t n, const Solver& solver,
                  const Fine& fine, const Orient& orient, Point_labels& labels,
                  const std::vector<std::uint32_t>& component, const std::vector<char>& flip_component,
                  Global_sign_summary& global, double& seconds)
{
  auto t = std::chrono::steady_clock::now();
  Stream_coarse_pass pass(records, radius, n);
  seconds += Normal_orientation::internal::seconds_since(t);
  const bool before = Normal_orientation::internal::solve_around_coarse_pass(pass.runs(), solver, fine, [&]() {
    t = std::chrono::steady_clock::now();
    const bool used = pass.apply(labels, component, flip_component, global.closedness, orient);
    seconds += Normal_orientation::internal::seconds_since(t);
    return used;
  });
  const Normal_orientation::internal::Coarse_scale_report coarse = pass.report();
  global.coarse_before_solver = before;
  global.coherence = coarse.coherence;
  global.coarse_points = coarse.coarse_points;
  global.coarse_used = coarse.used;
  global.seconds += coarse.seconds;
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_COARSE_STAGE_H
