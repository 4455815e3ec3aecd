// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
//
// Orienting a file larger than the memory, piece by piece: a
// Point_stream_reader is the source (it reads the file chunk by chunk, twice),
// streaming_orient_normals() sweeps it with a bounded window, and the sink,
// a lambda, hands each oriented point to a Point_stream_writer, which writes
// a temporary file renamed over OUT by commit() at the end (so OUT is
// complete or absent).  The progress callback prints the stages on the
// standard error.  streaming_orient_files() does all this in one call; the
// pieces are what to adapt for other sources and sinks.
//
// usage: stream_ply_file IN(.ply|.xyz, with normals) OUT(.ply|.xyz) [--presorted x|y|z]
//        (--presorted: IN is sorted by that coordinate; no external sort,
//        and OUT keeps the order of IN)

#include <Normal_orientation/IO/Point_stream.h>
#include <Normal_orientation/streaming_orient_normals.h>

#include <cstdio>
#include <exception>
#include <iostream>
#include <string>

namespace NO = Normal_orientation;

int main(int argc, char** argv)
{
  const std::string axis = argc == 5 ? argv[4] : "";
  const bool axis_ok = axis == "x" || axis == "y" || axis == "z";
  if ((argc != 3 && argc != 5) || (argc == 5 && (std::string(argv[3]) != "--presorted" || !axis_ok))) {
    std::cerr << "usage: stream_ply_file IN(.ply|.xyz, with normals) OUT(.ply|.xyz) [--presorted x|y|z]\n";
    return 2;
  }
  const NO::Presorted_axis presorted = axis.empty() ? NO::Presorted_axis::NONE
                                      : axis == "x"  ? NO::Presorted_axis::X
                                      : axis == "y"  ? NO::Presorted_axis::Y
                                                     : NO::Presorted_axis::Z;

  // The stages, as they start, and how far each goes, on the standard error.
  int stage = -1; // the stage shown, -1 before the first report
  auto progress = [&stage, shown = -1](const NO::Progress_info& p) mutable {
    if (int(p.stage) != stage) {
      std::cerr << (stage < 0 ? "" : "\n") << NO::stage_name(p.stage) << ":";
      stage = int(p.stage);
      shown = -1;
    }
    if (int(10 * p.stage_fraction()) > shown)
      std::cerr << " " << 10 * (shown = int(10 * p.stage_fraction())) << "%";
    return true; // false would stop the run (temporary files removed, OUT not written)
  };

  try {
    NO::IO::Point_stream_reader reader(argv[1]); // reads the header: the format, whether there are normals
    if (!reader.has_normals()) {
      std::cerr << "stream_ply_file: " << argv[1] << " has no normals (estimate them first)\n";
      return 1;
    }
    NO::IO::Point_stream_write_options write_options; // binary PLY, with normals
    NO::IO::Point_stream_writer writer(argv[2], write_options);
    auto sink = [&writer](const NO::Point_record& record) { writer.write(record); };

    const NO::Streaming_result r = NO::streaming_orient_normals(
      reader, sink,
      NO::parameters::presorted_axis(presorted).flip_criterion(NO::Hoppe_criterion()).callback(progress));
    std::cerr << (stage < 0 ? "" : "\n");
    if (r.interrupted) {
      std::cerr << "stream_ply_file: interrupted\n";
      return 1; // the writer is not committed: no OUT
    }
    if (r.number_of_points == 0) {
      std::cerr << "stream_ply_file: " << argv[1] << " holds no point\n";
      return 1; // the writer is not committed: no OUT
    }
    writer.commit();

    std::printf("%llu points, %zu segments, %zu component(s), %llu normals flipped, %llu written\n",
                (unsigned long long)r.number_of_points, r.number_of_segments, r.number_of_components,
                (unsigned long long)r.number_of_flipped, (unsigned long long)writer.count());
    std::printf("r = %.6g%s, %s, peak window %zu points, segment energy %.6g -> %.6g\n", r.neighbor_radius,
                r.radius_estimated ? " (estimated)" : "", r.presorted ? "presorted" : "sorted along the principal axis",
                r.peak_window, r.segment_energy_before, r.segment_energy_after);
    std::printf("%.3f s: scan %.3f, radius %.3f, sort %.3f, sweep %.3f, solve %.3f, sign %.3f, output %.3f\n",
                r.seconds.total, r.seconds.frame, r.seconds.radius, r.seconds.sort, r.seconds.sweep, r.seconds.solve,
                r.seconds.sign, r.seconds.output);
  } catch (const std::exception& e) { // Io_error, bad order of a presorted input, ...: one line
    std::cerr << (stage < 0 ? "" : "\n") << "stream_ply_file: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
