// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_ORIENT_NORMALS_H
#define NORMAL_ORIENTATION_STREAMING_ORIENT_NORMALS_H

/// \file streaming_orient_normals.h
/// The out-of-core entry points (paper sec. 5): orient clouds larger than
/// memory by sorting them along their principal axis (or reading them as
/// they are when they are already sorted along x, y or z), sweeping them
/// with a window of bounded size, segmenting on the fly, solving the
/// segment graph and re-streaming the points with their final signs.  They
/// take the named parameters of `orient_normals()`, and a few of their own;
/// the stages run in `streaming/Run_stages.h`.

#include <Normal_orientation/IO/Point_stream.h>
#include <Normal_orientation/IO/Point_stream_transcode.h>
#include <Normal_orientation/parameters.h>
#include <Normal_orientation/streaming/Run_stages.h>
#include <Normal_orientation/streaming/Streaming_result.h>

#include <CGAL/tags.h>

#include <filesystem>
#include <string>
#include <system_error>

namespace Normal_orientation {

/// \ingroup PkgNormalOrientationStreaming
/// Orients the points of `source` out of core and hands them to `sink`
/// (`sink(const Point_record&)`, called once per point kept, in the sweep
/// order, with the oriented normal: only its sign differs from the
/// input's; a sink callable as `sink(record, std::uint32_t segment)` or
/// `sink(record, segment, bool flipped)` is called so, with the segment of
/// the point: the segments are numbered 0 to
/// `Streaming_result::number_of_segments` - 1 in the order the sweep opened
/// them, and each holds at least one point).
///
/// `source` is a model of `PointRecordSource`, read twice: a first pass,
/// then the external sort, or, with a presorted input, the sweep itself.
/// Stages (`Stage`, reported to the callback):
///  1. `SCAN`, the first pass: the number of points, the check that their
///     coordinates are finite, the zero normals, the centroid and principal
///     axis (`Sweep_frame`; not with a presorted input, whose order is
///     checked instead) and, when r is not given, a uniform sample of at
///     most 200,000 points;
///  2. `RADIUS`, when r is not given: the rule of `estimate_neighbor_radius()`
///     over the sample, scaled to the whole cloud;
///  3. `SORT`, the external sort along the axis (bounded memory, temporary
///     files); skipped with a presorted input;
///  4. `SWEEP` (`streaming::sweep()`): each point meets its earlier
///     neighbours of the k-nearest-neighbour graph of `orient_normals()`,
///     gets its edge weights w = phi * (1 - d^2 / r^2) and is segmented
///     (`Segmenter`); points leaving the window go to a temporary record
///     file;
///  5. `SOLVE`: `solver` on the segment graph, with the segments' unary
///     terms when there are constraints or priors;
///  6. `REFINE`: rounds of re-segmentation and single-point moves (see
///     `streaming::Refinement_options`; not with unary terms);
///  7. `SIGN`: the component sign policy, fed from the record file in the
///     passes it asks for (components with unary terms keep the sign the
///     solver gave them);
///  8. `OUTPUT`: the record file re-streamed to `sink` with the final
///     signs, without the components smaller than `minimum_component_size`;
///  9. `COMPONENTS`: optionally, one file per kept component.
///
/// The neighbour graph does not depend on the sweep order: with the same
/// r, a presorted input gives the same graph as the sorted path (up to ties
/// in distance); the segmentation, made in the sweep order, may differ
/// slightly.  Memory: the sweep window, the sort budget, O(segments +
/// segment pairs + components), and 1 MiB per open component file; the
/// temporary files are removed on success, on exceptions and on
/// cancellation.
///
/// \tparam ConcurrencyTag `CGAL::Parallel_tag`, `CGAL::Sequential_tag` or
///         `CGAL::Parallel_if_available_tag` (the default); the result does
///         not depend on it
/// \tparam Source a model of `PointRecordSource`
/// \tparam Sink a model of `PointRecordSink`
/// \param source the points, read twice
/// \param sink receives every point kept, oriented, in the sweep order
/// \param np optional named parameters: those of `orient_normals()` (but
///   `point_map` and `normal_map`: the records hold both) with the same
///   meaning and defaults, `point_is_constrained_map` and
///   `orientation_prior_map` taking a `Point_record` as key (its `index` is
///   its place in the input), and the streaming driver's own (see the page
///   \ref NormalOrientationNamedParameters):
/// \cgalNamedParamsBegin
///   \cgalParamNBegin{presorted_axis}
///     \cgalParamDescription{the input is already sorted by this coordinate (non-decreasing): no principal axis
///       and no external sort; the sweep reads the source as it is, and the output keeps the input order.  The
///       first pass checks the order (`std::runtime_error` naming the first point out of order)}
///     \cgalParamType{`Presorted_axis`}
///     \cgalParamDefault{`Presorted_axis::NONE`}
///   \cgalParamNEnd
///   \cgalParamNBegin{temporary_directory}
///     \cgalParamDescription{where the sort's runs, the record file and the other temporary files go}
///     \cgalParamType{`std::string`}
///     \cgalParamDefault{empty: `$TMPDIR` if set, else /tmp}
///   \cgalParamNEnd
///   \cgalParamNBegin{sort_memory}
///     \cgalParamDescription{bytes of memory for the runs of the external sort (see
///       `streaming::External_sort_options::memory_budget`)}
///     \cgalParamType{`std::size_t`, > 0}
///     \cgalParamDefault{256 MiB}
///   \cgalParamNEnd
///   \cgalParamNBegin{refinement_rounds}
///     \cgalParamDescription{rounds of the refinement after the solve (see `streaming::Refinement_options`); it
///       never raises the energy of the point graph, and needs a temporary edge file of 8 bytes per edge}
///     \cgalParamType{unsigned int, at most 64; 0: no refinement}
///     \cgalParamDefault{3}
///   \cgalParamNEnd
///   \cgalParamNBegin{minimum_component_size}
///     \cgalParamDescription{components of fewer points are dropped: not handed to the sink, not written to the
///       component files, counted in `Streaming_result::number_of_dropped_points`}
///     \cgalParamType{`std::uint64_t`}
///     \cgalParamDefault{0: every point is kept}
///   \cgalParamNEnd
///   \cgalParamNBegin{component_files}
///     \cgalParamDescription{one file per kept connected component, `component_000000.ply`, ... (by decreasing
///       size; ties in the sweep order of their first point), each written atomically once the sink has had
///       every point; removed when the run fails or is interrupted}
///     \cgalParamType{`Component_files_options`}
///     \cgalParamDefault{no component files}
///   \cgalParamNEnd
///   \cgalParamNBegin{batch_size}
///     \cgalParamDescription{points finalised per batch of the sweep}
///     \cgalParamType{`std::size_t`, > 0}
///     \cgalParamDefault{262144}
///   \cgalParamNEnd
/// \cgalNamedParamsEnd
///
/// \return the figures of the run; `interrupted` is true when the callback
///   returned false (the sink may have had part of the points then;
///   temporary and component files are removed)
/// \throw std::invalid_argument for a named parameter out of range;
///   std::runtime_error when a presorted input is not sorted (naming the
///   point) or has non-finite coordinates, and from the source, the sort
///   and the temporary files (also std::system_error); `IO::Io_error` when
///   a component file cannot be written
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag, typename Source, typename Sink,
          typename NamedParameters = parameters::Default_named_parameters>
Streaming_result streaming_orient_normals(Source& source, Sink& sink,
                                          const NamedParameters& np = parameters::default_values())
{
  return streaming::internal::orient_stream<ConcurrencyTag>(source, sink, np, "streaming_orient_normals",
                                                            streaming::internal::Run_hooks());
}

/// \ingroup PkgNormalOrientationStreaming
/// Orients the cloud of the file `input` (.xyz/.pwn with normals, or .ply,
/// read in chunks by `IO::Point_stream_reader`) out of core with
/// `streaming_orient_normals()` and writes it to `output` (.xyz, .pwn or
/// .ply by extension; binary PLY unless `write_options.binary` is false).
/// The output holds the points in the sweep order (along the principal
/// axis; with a presorted input, the input order), with their input
/// coordinates and normals whose sign only may have changed, without the
/// components smaller than `minimum_component_size`.  It is written to a
/// temporary file renamed at the end: on any error or interruption no
/// output file exists.  With `write_options.segments` (PLY only), each
/// point also gets its segment, as the vertex property `int segment`.  With
/// `component_files`, one file per kept component is written too, by
/// default in the output's format; they are removed when the run fails.
/// \throw IO::Io_error for unreadable, malformed or unwritable files, an
///        input without normals or without any point (as `read_point_cloud()`
///        does; no output is written then); see `streaming_orient_normals()`
/// \tparam ConcurrencyTag as for `streaming_orient_normals()`
/// \param input the file to orient (.xyz/.pwn with normals, or .ply with normals)
/// \param output the file written (.xyz, .pwn or .ply)
/// \param np the named parameters of `streaming_orient_normals()`
/// \param write_options how `output` is written (binary or ascii PLY, with the
///        segments, ...)
/// \return the figures of the run
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag,
          typename NamedParameters = parameters::Default_named_parameters>
Streaming_result streaming_orient_files(const std::string& input, const std::string& output,
                                        const NamedParameters& np = parameters::default_values(),
                                        const IO::Point_stream_write_options& write_options =
                                          IO::Point_stream_write_options())
{
  const auto t = std::chrono::steady_clock::now();
  IO::Point_stream_reader reader(input);
  if (!reader.has_normals())
    throw IO::Io_error(input + ": the file has no normals (streaming needs them)");
  IO::Point_stream_writer writer(output, write_options);
  streaming::internal::Run_hooks hooks;
  hooks.adjust = [&](streaming::internal::Streaming_settings& s) {
    if (!s.component_files.directory.empty() && s.component_files.extension.empty()) {
      s.component_files.extension = std::filesystem::path(output).extension().string();
      s.component_files.write_options = write_options;
    }
  };
  auto sink = [&writer](const Point_record& r, std::uint32_t segment) {
    if (writer.has_segments())
      writer.write(r, segment);
    else
      writer.write(r);
  };
  Streaming_result result =
    streaming::internal::orient_stream<ConcurrencyTag>(reader, sink, np, "streaming_orient_files", hooks);
  if (result.interrupted)
    return result; // the writer removes its temporary file
  if (result.number_of_points == 0) // as in core: an empty cloud is an error, not an empty output
    throw IO::Io_error(input + ": the file holds no point");
  const auto t_commit = std::chrono::steady_clock::now();
  try {
    writer.commit();
  } catch (...) {
    std::error_code ec;
    for (const std::string& f : result.component_files)
      std::filesystem::remove(f, ec);
    throw;
  }
  result.seconds.output += Normal_orientation::internal::seconds_since(t_commit);
  result.seconds.total = Normal_orientation::internal::seconds_since(t);
  return result;
}

/// \ingroup PkgNormalOrientationStreaming
/// Orients the cloud of the file `input` out of core, as
/// `streaming_orient_files()` does, and writes `output` as a copy of
/// `input` in its own order and format, in which only the signs of the
/// normals differ (see `IO::transcode_with_flips()`): every other vertex
/// property, the text of every value not negated, the header's comments
/// and the type of every property are kept; the components smaller than
/// `minimum_component_size` are left out.  The stream hands the oriented
/// points to a sink that notes, by input index, which normals to negate and
/// which points to keep (2 bits per point in memory, 25 MB for 100M
/// points); then the input is copied with those changes, in one more
/// reading of the file, with fixed memory.  On any error or interruption
/// no output file exists (an existing one is left unchanged).  The copy is
/// reported to the callback as the stage `OUTPUT`, in bytes of the input.
/// \throw IO::Io_error for unreadable, malformed or unwritable files, an
///        input without normals or without any point, an `output` whose
///        format differs from `input`'s (checked before any work), normals
///        of an unsigned integer type that must be negated, an input that
///        changes while it is read; see `streaming_orient_files()`
/// \tparam ConcurrencyTag as for `streaming_orient_normals()`
/// \param input the file to orient (.xyz/.pwn with normals, or .ply with normals)
/// \param output the file written, in the format of `input` (.ply for a .ply
///        input; .xyz or .pwn for a .xyz or .pwn input)
/// \param np the named parameters of `streaming_orient_normals()`
/// \param transcode when not null, receives the figures of the copy
/// \return the figures of the run (`seconds.output` includes the copy)
template <typename ConcurrencyTag = CGAL::Parallel_if_available_tag,
          typename NamedParameters = parameters::Default_named_parameters>
Streaming_result streaming_orient_files_in_input_order(const std::string& input, const std::string& output,
                                                       const NamedParameters& np = parameters::default_values(),
                                                       IO::Transcode_report* transcode = nullptr)
{
  const auto t = std::chrono::steady_clock::now();
  IO::Point_stream_reader reader(input);
  if (!reader.has_normals())
    throw IO::Io_error(input + ": the file has no normals (streaming needs them)");
  const std::string in_ext = IO::lower_case_extension(input);
  const std::string out_ext = IO::lower_case_extension(output);
  if (out_ext != ".ply" && out_ext != ".xyz" && out_ext != ".pwn")
    throw IO::Io_error(output + ": unknown point cloud file extension '" + out_ext + "' (expected .xyz, .pwn or .ply)");
  if ((in_ext == ".ply") != (out_ext == ".ply"))
    throw IO::Io_error(output + ": the copy of '" + input + "' in its own order must be a " +
                       (in_ext == ".ply" ? std::string(".ply") : std::string(".xyz or .pwn")) + " file, as the input");
  IO::Bit_set flip, keep;
  Progress_reporter progress;
  streaming::internal::Run_hooks hooks;
  hooks.adjust = [&](streaming::internal::Streaming_settings& s) {
    if (!s.component_files.directory.empty() && s.component_files.extension.empty())
      s.component_files.extension = std::filesystem::path(output).extension().string();
    progress = streaming::internal::stage_progress(s.progress, Stage::OUTPUT);
  };
  hooks.before_output = [&](std::uint64_t n) {
    flip = IO::Bit_set(n);
    keep = IO::Bit_set(n);
  };
  auto sink = [&](const Point_record& r, std::uint32_t, bool flipped) {
    keep.set(r.index); // throws std::out_of_range on an index beyond the count
    if (flipped)
      flip.set(r.index);
  };
  Streaming_result result =
    streaming::internal::orient_stream<ConcurrencyTag>(reader, sink, np, "streaming_orient_files_in_input_order", hooks);
  if (result.interrupted)
    return result;
  try {
    if (result.number_of_points == 0) // as in core: an empty cloud is an error, not an empty output
      throw IO::Io_error(input + ": the file holds no point");
    const auto t_copy = std::chrono::steady_clock::now();
    IO::Transcode_options to;
    if (progress.enabled())
      to.callback = [&progress](std::uint64_t done, std::uint64_t size) {
        progress.report(done, size);
        return true;
      };
    const IO::Transcode_report tr =
      IO::transcode_with_flips(input, output, flip, result.number_of_dropped_points > 0 ? &keep : nullptr, to);
    if (transcode != nullptr)
      *transcode = tr;
    result.seconds.output += Normal_orientation::internal::seconds_since(t_copy);
  } catch (const Interrupted&) {
    std::error_code ec;
    for (const std::string& f : result.component_files)
      std::filesystem::remove(f, ec);
    result.component_files.clear();
    result.interrupted = true;
  } catch (...) {
    std::error_code ec;
    for (const std::string& f : result.component_files)
      std::filesystem::remove(f, ec);
    throw;
  }
  result.seconds.total = Normal_orientation::internal::seconds_since(t);
  return result;
}

} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_ORIENT_NORMALS_H
