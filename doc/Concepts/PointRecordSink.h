// SPDX-License-Identifier: GPL-3.0-or-later
// Documentation only: the concept PointRecordSink (not compiled, not installed).

/*!
\ingroup PkgNormalOrientationConcepts
\cgalConcept
\headerfile Point_record.h <Normal_orientation/Point_record.h>

Where `Normal_orientation::streaming_orient_normals()` hands the oriented points: a
function object called once per point kept, in the sweep order, from the calling thread,
with the record of the point whose normal has its final sign (only the sign differs from
the input's).  `record.index` is the point's index in the input, so a sink can write the
normal back into the user's own container (`Normal_orientation::streaming::Normal_writer`)
or append the record to a file (`Normal_orientation::streaming_orient_files()` uses a
`Normal_orientation::IO::Point_stream_writer`).

A sink that can also be called with a second argument, `std::uint32_t segment`, is called
so: it then gets the segment of the point too (the segments of the streaming segmentation,
numbered from 0 to `Normal_orientation::Streaming_result::number_of_segments` - 1), which is
how `Normal_orientation::streaming_orient_files()` writes them with
`Normal_orientation::IO::Point_stream_write_options::segments`.  A sink that can be called
with a third argument, `bool flipped`, is called so: it then also learns whether the normal of
the point was negated, which is how `Normal_orientation::streaming_orient_files_in_input_order()`
notes the flips by input index without keeping the points.

\cgalHasModelsBegin
\cgalHasModels{Normal_orientation::streaming::Normal_writer}
\cgalHasModels{any function object such as a lambda, e.g. one calling Normal_orientation::IO::Point_stream_writer::write()}
\cgalHasModelsEnd

\sa `PointRecordSource`
*/
class PointRecordSink
{
public:
  /// receives one oriented point
  void operator()(const Normal_orientation::Point_record& record);
  /// optional: receives one oriented point and its segment (called instead of the
  /// operator above when the sink has it)
  void operator()(const Normal_orientation::Point_record& record, std::uint32_t segment);
  /// optional: receives one oriented point, its segment and whether its normal was negated
  /// (called instead of the operators above when the sink has it)
  void operator()(const Normal_orientation::Point_record& record, std::uint32_t segment, bool flipped);
};
