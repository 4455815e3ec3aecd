// SPDX-License-Identifier: GPL-3.0-or-later
// Documentation only: the concept PointRecordSource (not compiled, not installed).

/*!
\ingroup PkgNormalOrientationConcepts
\cgalConcept
\headerfile Point_record.h <Normal_orientation/Point_record.h>

A source of `Normal_orientation::Point_record`s: what the out-of-core pipeline
reads, chunk by chunk, so that the cloud is never held in memory as a whole (see
\ref NormalOrientationSecStreaming).  The records carry their index in the input (0, 1,
...), which breaks every tie.

`Normal_orientation::streaming_orient_normals()` reads its source twice (a first pass,
then the external sort or, for a presorted input, the sweep), calling `rewind()` in
between; `Normal_orientation::streaming::sweep()`,
`Normal_orientation::streaming::compute_sweep_frame()` and
`Normal_orientation::streaming::External_sorter` read sources too.

\cgalHasModelsBegin
\cgalHasModels{Normal_orientation::IO::Point_stream_reader}
\cgalHasModels{Normal_orientation::streaming::Point_range_source}
\cgalHasModels{Normal_orientation::streaming::Sorted_run_reader}
\cgalHasModels{Normal_orientation::streaming::Record_file (of Point_record)}
\cgalHasModelsEnd

\sa `PointRecordSink`
*/
class PointRecordSource
{
public:
  /// appends up to `maximum` records to `chunk` (which it does not clear) and returns how
  /// many; 0 at the end of the data
  /// \param chunk the vector the records are appended to
  /// \param maximum the largest number of records to append
  /// \return the number of records appended
  std::size_t read(std::vector<Normal_orientation::Point_record>& chunk, std::size_t maximum);

  /// starts again from the first record
  void rewind();
};
