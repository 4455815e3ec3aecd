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
#include <Normal_orientation/internal/Canopy_rule.h>
#include <Normal_orientation/internal/Coarse_scale.h>
#include <Normal_orientation/internal/Core_coarse_scale.h>
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
/// into the accumulator, whose grid starts at `origin` (the first point in
/// Morton order, as in core: `Sweep_stage_result::grid_origin`), and
/// measures whether their input normals agree (`runs()`: they do not, and
/// the pass is to be tried).  `apply()`, when the coarse cloud is more
/// closed than the fine orientation (`fine_closedness`; `orient` as for
/// `Normal_orientation::internal::Coarse_pass::take_coarse()`), installs the
/// coarse signs in `labels` before the global stage's decision, which is kept
/// for the points without a coarse opinion.  `component` is per sweep
/// segment, `flip_component` the sign stage's decision; both must outlive the
/// output passes.
template <typename Kernel>
class Stream_coarse_pass : public Normal_orientation::internal::Coarse_pass<Kernel>
{
  typedef Normal_orientation::internal::Coarse_pass<Kernel> Base;
  typedef Normal_orientation::internal::Coarse_scale Coarse_scale;

public:
  Stream_coarse_pass(Record_file<Swept_record>& records, double radius, const std::array<double, 3>& origin,
                     std::uint64_t n)
    : Base(radius)
  {
    const auto t = std::chrono::steady_clock::now();
    this->accumulator().set_origin(origin);
    records.rewind();
    std::vector<Swept_record> chunk;
    while (true) {
      chunk.clear();
      if (records.read(chunk, std::size_t(1) << 15) == 0)
        break;
      for (const Swept_record& s : chunk) {
        const Point_record& r = s.record;
        this->accumulator().add({{r.position[0], r.position[1], r.position[2]}}, unit_normal(r));
      }
    }
    records.rewind();
    this->finish(std::size_t(n));
    this->m_seconds += Normal_orientation::internal::seconds_since(t);
  }

  /// the pass against the fine orientation in `labels`; returns whether the
  /// coarse signs were installed
  template <typename Orient>
  bool apply(Point_labels& labels, const std::vector<std::uint32_t>& component,
             const std::vector<char>& flip_component, double fine_closedness, const Orient& orient)
  {
    if (!this->runs())
      return false;
    const auto t = std::chrono::steady_clock::now();
    const bool used = this->take_coarse(fine_closedness, orient);
    if (used) {
      auto previous = std::move(labels.point_flip);
      const std::shared_ptr<Coarse_scale> coarse = this->m_coarse;
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
    this->m_seconds += Normal_orientation::internal::seconds_since(t);
    return used;
  }
};

/// The coarse-to-fine pass around the solve (`solve_around_coarse_pass()`):
/// `fine(solver, improve, dense)` solves, refines when `improve`, signs and
/// runs the global stage (on the dense samples when `dense`), leaving its
/// summary in `global`; then the pass is tried
/// (`Stream_coarse_pass`, `orient` as for `Stream_coarse_pass::apply()`).
/// Adds the pass's figures to `global` and its seconds to `seconds`.
/// Returns the cells of the canopy rule, read from the pass's grid, which
/// starts at `origin`.
template <typename Kernel, typename Solver, typename Fine, typename Orient>
std::shared_ptr<const Normal_orientation::internal::Canopy_cells>
coarse_stage(Record_file<Swept_record>& records, double radius, const std::array<double, 3>& origin,
             std::uint64_t n, const Solver& solver,
             const Fine& fine, const Orient& orient, Point_labels& labels, const std::vector<std::uint32_t>& component,
             const std::vector<char>& flip_component, Global_sign_summary& global, double& seconds)
{
  Stream_coarse_pass<Kernel> pass(records, radius, origin, n);
  const bool before = Normal_orientation::internal::solve_around_coarse_pass(pass.runs(), solver, fine, [&]() {
    return pass.apply(labels, component, flip_component, global.closedness, orient);
  });
  pass.add_report(before, global, seconds);
  return pass.canopy();
}

/// Installs the canopy rule (`Canopy_rule.h`) in `labels`, after every
/// other decision of the stages: the points of the components of `open`
/// that `cells` turns up are negated.  `component` is per sweep segment and
/// `flip_component` the final sign of each component; both, and `cells`,
/// must outlive the output passes.
inline void install_canopy_rule(std::shared_ptr<const Normal_orientation::internal::Canopy_cells> cells,
                                const std::vector<char>& open, const std::array<double, 3>& up,
                                const std::vector<std::uint32_t>& component, const std::vector<char>& flip_component,
                                Point_labels& labels)
{
  if (!cells || cells->size() == 0 || !Normal_orientation::internal::any_open_scene(open))
    return;
  auto previous = std::move(labels.point_flip);
  const std::vector<std::uint32_t>* segment_component = &component;
  const std::vector<char>* flips = &flip_component;
  labels.point_flip = [cells, open, up, previous, segment_component, flips](const Swept_record& s,
                                                                            std::uint32_t segment, Label label) {
    const bool flipped = previous ? previous(s, segment, label) : false;
    const std::uint32_t c = (*segment_component)[s.segment];
    if (!open[c])
      return flipped;
    const Point_record& r = s.record;
    const int sign = int(label) * (flipped ? -1 : 1) * ((*flips)[c] ? -1 : 1);
    return flipped != cells->faces_down({{r.position[0], r.position[1], r.position[2]}}, unit_normal(r), sign, up);
  };
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_COARSE_STAGE_H
