// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_LABELLED_RECORDS_H
#define NORMAL_ORIENTATION_STREAMING_LABELLED_RECORDS_H

/// \file Labelled_records.h
/// The swept points with their labels, as the stages after the solve read
/// them: the record file, and either the segment labels of the solve
/// (label = preliminary flip times the segment's label) or the label file
/// of the last refinement round (label times the label of its segment),
/// and the global stage's negations.

#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/streaming/Record_file.h>
#include <Normal_orientation/streaming/Segmenting_sweep.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// The final labels of the points: the segment labels of the solve, or the
/// label file of the refinement and the labels of its last segments.
struct Point_labels
{
  std::vector<Label> segment_labels;                    ///< of the sweep's segments
  std::unique_ptr<Record_file<std::uint32_t>> label_file; ///< (segment << 1) | flipped, per point; or null
  std::vector<Label> label_file_segment_labels;         ///< of the segments of `label_file`
  /// when set, the points for which it returns true (given the point, its
  /// final segment and its label) are negated too: the global stage's decision
  std::function<bool(const Swept_record&, std::uint32_t, Label)> point_flip;
  /// when set, the patch unit of every point (`Patch_units`), and per unit
  /// whether its points are negated (the global stage's decision, before
  /// `point_flip`)
  std::unique_ptr<Record_file<std::uint32_t>> unit_file;
  std::vector<char> unit_flip; ///< per unit
};

/// Reads the record file and the labels, in the sweep order, block by block.
class Labelled_reader
{
public:
  /// a reader of `records` with `labels`
  Labelled_reader(Record_file<Swept_record>& records, Point_labels& labels) : m_records(records), m_labels(labels) {}

  /// goes back to the first point
  void rewind()
  {
    m_records.rewind();
    if (m_labels.label_file)
      m_labels.label_file->rewind();
    if (m_labels.unit_file)
      m_labels.unit_file->rewind();
  }

  /// reads the next points into `points()` and their labels (before the
  /// sign of their component) into `labels()`; returns how many, 0 at the end
  std::size_t read()
  {
    m_buffer.clear();
    const std::size_t got = m_records.read(m_buffer, 1 << 15);
    m_point_labels.resize(got);
    m_segments.resize(got);
    if (m_labels.label_file) {
      m_words.clear();
      if (got > 0 && m_labels.label_file->read(m_words, got) != got)
        throw std::runtime_error("streaming_orient_normals: the label file is shorter than the record file");
      for (std::size_t q = 0; q < got; ++q) {
        m_segments[q] = m_words[q] >> 1;
        m_point_labels[q] =
          Label(((m_words[q] & 1u) != 0 ? -1 : 1) * m_labels.label_file_segment_labels[m_words[q] >> 1]);
      }
    } else {
      for (std::size_t q = 0; q < got; ++q) {
        m_segments[q] = m_buffer[q].segment;
        m_point_labels[q] = Label(m_buffer[q].flip * m_labels.segment_labels[m_buffer[q].segment]);
      }
    }
    if (m_labels.unit_file) {
      m_words.clear();
      if (got > 0 && m_labels.unit_file->read(m_words, got) != got)
        throw std::runtime_error("streaming_orient_normals: the unit file is shorter than the record file");
      for (std::size_t q = 0; q < got; ++q)
        if (m_labels.unit_flip.at(m_words[q]))
          m_point_labels[q] = Label(-m_point_labels[q]);
    }
    if (m_labels.point_flip)
      for (std::size_t q = 0; q < got; ++q)
        if (m_labels.point_flip(m_buffer[q], m_segments[q], m_point_labels[q]))
          m_point_labels[q] = Label(-m_point_labels[q]);
    return got;
  }
  /// the points of the last `read()`
  const std::vector<Swept_record>& points() const { return m_buffer; }
  /// their labels
  const std::vector<Label>& labels() const { return m_point_labels; }
  /// their final segments (those of the label file when there is one)
  const std::vector<std::uint32_t>& segments() const { return m_segments; }

private:
  Record_file<Swept_record>& m_records;
  Point_labels& m_labels;
  std::vector<Swept_record> m_buffer;
  std::vector<Label> m_point_labels;
  std::vector<std::uint32_t> m_words;
  std::vector<std::uint32_t> m_segments;
};

/// The output record of swept point `s` of label `label` (before the sign
/// of its component) in a component that flips when `flip_component`;
/// returns true when the normal was turned (a zero normal never is).
inline bool oriented_record(const Swept_record& s, Label label, bool flip_component, Point_record& out)
{
  out = s.record;
  const int l = int(label) * (flip_component ? -1 : 1);
  if (l >= 0)
    return false;
  for (double& v : out.normal)
    v = -v;
  return out.normal[0] != 0.0 || out.normal[1] != 0.0 || out.normal[2] != 0.0;
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_LABELLED_RECORDS_H
