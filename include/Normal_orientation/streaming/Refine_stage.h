// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_REFINE_STAGE_H
#define NORMAL_ORIENTATION_STREAMING_REFINE_STAGE_H

/// \file Refine_stage.h
/// The refine stage of the streaming driver: rounds of one pass over the
/// points (single-point moves, then segmentation around the new labelling)
/// and one solve of the new segment graph (see `Refinement_options`).  The
/// labels of a pass come from the record file (preliminary flip times the
/// segment's label) in the first round, then from the label file of the
/// previous round (label times the label of its new segment); so do the
/// final labels.

#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/Segmenter.h>
#include <Normal_orientation/streaming/Labelled_records.h>
#include <Normal_orientation/streaming/Record_file.h>
#include <Normal_orientation/streaming/Refinement.h>
#include <Normal_orientation/streaming/Segmenting_sweep.h>

#include <CGAL/tags.h>

#include <cstdint>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// What the refinement did.
struct Refine_stage_result
{
  double energy_after = 0.0;
  unsigned int rounds_accepted = 0;
  std::uint64_t moves = 0;
};

/// Runs `rounds` rounds of the refinement over the `n` points of `records`
/// (with the earlier edges of `edges`, reaching at most `edge_span` points
/// back), starting from `labels.segment_labels`, whose point-graph energy is
/// `energy`; leaves the final labels in `labels` (a label file).  Reports
/// `total_rounds` times n units of progress.
template <typename ConcurrencyTag, typename Solver>
Refine_stage_result refine_stage(Record_file<Swept_record>& records, Record_file<Earlier_edge>& edges,
                                 std::uint64_t n, std::uint64_t edge_span, const Refinement_options& options,
                                 unsigned int rounds, const std::string& temporary_directory, const Solver& solver,
                                 double energy, Point_labels& labels, const Progress_reporter& progress)
{
  Refine_stage_result result;
  result.energy_after = energy;
  const std::uint64_t total = std::uint64_t(options.rounds) * n;
  const bool prefetch = std::is_convertible<ConcurrencyTag, CGAL::Parallel_tag>::value;
  progress.report(0, total);
  std::vector<Label> segment_label; // the labels of the segments of the label file read
  std::unique_ptr<Record_file<std::uint32_t>> in, out;
  std::uint64_t done = 0;
  for (unsigned int round = 0; round < rounds; ++round) {
    Segmentation_thresholds theta = options.thresholds;
    theta.maximum_size = options.maximum_segment_size(n, round);
    Segmenter resegmenter(theta, false);
    out = std::make_unique<Record_file<std::uint32_t>>(temporary_directory, 1 << 16);
    Relabelling_window pass(edge_span, &resegmenter, false);
    auto write = [&out](Label label, std::uint32_t segment) {
      if (segment > (std::numeric_limits<std::uint32_t>::max() >> 1))
        throw std::length_error("streaming_orient_normals: too many segments in the refinement");
      out->append((segment << 1) | (label < 0 ? 1u : 0u));
    };
    Edge_reader edge_reader(edges, prefetch);
    const Earlier_edge* point_edges = nullptr;
    std::size_t count = 0;
    if (round == 0) {
      Record_reader<Swept_record> reader(records, std::size_t(1) << 15, prefetch);
      while (true) {
        const std::vector<Swept_record>& chunk = reader.next();
        if (chunk.empty())
          break;
        for (const Swept_record& s : chunk) {
          edge_reader.next(point_edges, count);
          pass.push(Label(s.flip * labels.segment_labels[s.segment]), point_edges, count, write);
        }
        done += chunk.size();
        progress.report(done, total);
      }
    } else {
      Record_reader<std::uint32_t> reader(*in, std::size_t(1) << 16, prefetch);
      while (true) {
        const std::vector<std::uint32_t>& chunk = reader.next();
        if (chunk.empty())
          break;
        for (const std::uint32_t word : chunk) {
          edge_reader.next(point_edges, count);
          pass.push(Label(((word & 1u) != 0 ? -1 : 1) * segment_label[word >> 1]), point_edges, count, write);
        }
        done += chunk.size();
        progress.report(done, total);
      }
    }
    pass.finish(write);
    out->flush();
    const Relabelling_report& pr = pass.report();
    if (pr.points != n)
      throw std::runtime_error("streaming_orient_normals: the edge file and the record file disagree");
    result.moves += pr.moves;
    double change = 0.0;
    segment_label = solve_segment_graph(resegmenter, solver, change);
    if (change < 0.0)
      ++result.rounds_accepted;
    result.energy_after = resegmenter.point_energy(segment_label);
    in = std::move(out);
  }
  labels.label_file = std::move(in);
  labels.label_file_segment_labels = std::move(segment_label);
  progress.report(total, total);
  return result;
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_REFINE_STAGE_H
