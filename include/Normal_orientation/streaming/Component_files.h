// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_COMPONENT_FILES_H
#define NORMAL_ORIENTATION_STREAMING_COMPONENT_FILES_H

/// \file Component_files.h
/// The component-files stage of the streaming driver: one file per kept
/// connected component, at most `maximum_open_files` open at once, through
/// temporary group files when there are more components than that.

#include <Normal_orientation/IO/Point_cloud_io.h>
#include <Normal_orientation/IO/Point_stream.h>
#include <Normal_orientation/Point_record.h>
#include <Normal_orientation/Progress.h>
#include <Normal_orientation/streaming/Output_stage.h>
#include <Normal_orientation/streaming/Record_file.h>
#include <Normal_orientation/streaming/Streaming_settings.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <system_error>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// a point with its final sign and the rank of its component, as kept in
/// the temporary group files of the component output
struct Ranked_record
{
  Point_record record;
  std::uint64_t rank;
};

/// The component files of one run: creates their directory, names them,
/// and removes those written (and the directory, if it created it and it is
/// empty) unless `keep()` was called.
class Component_file_set
{
public:
  /// checks the options and creates the directory when files are wanted
  explicit Component_file_set(const Component_files_options& options)
    : m_directory(options.directory), m_extension(options.extension.empty() ? std::string(".ply") : options.extension)
  {
    if (m_directory.empty())
      return;
    const std::string e = IO::lower_case_extension("f" + m_extension);
    if (e != ".ply" && e != ".xyz" && e != ".pwn")
      throw std::invalid_argument("streaming_orient_normals: unknown component file extension '" + m_extension +
                                  "' (expected .ply, .xyz or .pwn)");
    std::error_code ec;
    if (std::filesystem::is_directory(m_directory, ec))
      return;
    if (std::filesystem::exists(m_directory, ec))
      throw IO::Io_error(m_directory + ": cannot write the component files: not a directory");
    m_created = std::filesystem::create_directories(m_directory, ec);
    if (ec)
      throw IO::Io_error(m_directory + ": cannot create the directory of the component files: " + ec.message());
  }
  Component_file_set(const Component_file_set&) = delete;
  Component_file_set& operator=(const Component_file_set&) = delete;
  ~Component_file_set()
  {
    if (m_kept)
      return;
    std::error_code ec;
    for (const std::string& f : m_written)
      std::filesystem::remove(f, ec);
    if (m_created)
      std::filesystem::remove(m_directory, ec); // only if empty
  }
  /// true when component files are wanted
  bool enabled() const { return !m_directory.empty(); }
  /// the name of the file of the component of rank `rank`
  std::string path(std::size_t rank) const
  {
    char name[48];
    std::snprintf(name, sizeof name, "component_%06zu", rank);
    return (std::filesystem::path(m_directory) / (name + m_extension)).string();
  }
  /// records that the file `path` was written (committed)
  void written(const std::string& path) { m_written.push_back(path); }
  /// the files written, in order
  const std::vector<std::string>& files() const { return m_written; }
  /// the run succeeded: keep the files
  void keep() { m_kept = true; }

private:
  std::string m_directory, m_extension;
  std::vector<std::string> m_written;
  bool m_created = false, m_kept = false;
};

/// Writes one file per kept component of `signs.ranking` (`n` points in
/// all), at most `options.maximum_open_files` open at once.
inline void component_files_stage(Labelled_reader& points, const Final_signs& signs,
                                  const Component_files_options& options, const std::string& temporary_directory,
                                  Component_file_set& files, std::uint64_t n, const Progress_reporter& progress)
{
  const std::size_t kept = signs.ranking.kept;
  const std::size_t G = std::max<std::size_t>(1, options.maximum_open_files);
  const std::size_t groups = (kept + G - 1) / G;
  const std::size_t rounds = (groups + G - 1) / G;
  const std::uint64_t total = groups == 1 ? n : std::uint64_t(rounds) * n + signs.ranking.kept_points;
  std::uint64_t done = 0;
  progress.report(0, total);
  auto count = [&](std::size_t c) {
    done += c;
    progress.report(done, total);
  };
  std::vector<IO::Point_stream_writer> writers;
  IO::Point_stream_write_options write_options = options.write_options;
  write_options.segments = false;
  auto open_writers = [&](std::size_t first, std::size_t last) {
    writers.clear();
    writers.reserve(last - first);
    for (std::size_t r = first; r < last; ++r)
      writers.emplace_back(files.path(r), write_options);
  };
  auto commit_writers = [&]() {
    for (IO::Point_stream_writer& w : writers) {
      w.commit();
      files.written(w.filename());
    }
    writers.clear();
  };
  if (groups == 1) {
    open_writers(0, kept);
    for_each_kept_point(
      points, signs,
      [&](const Point_record& out, std::uint32_t, bool, std::uint64_t r) { writers[std::size_t(r)].write(out); },
      count);
    commit_writers();
  } else {
    std::vector<Ranked_record> ranked;
    for (std::size_t round = 0; round < rounds; ++round) {
      // split the records of the groups of this round into one file per group
      const std::size_t first_group = round * G, last_group = std::min(groups, first_group + G);
      const std::uint64_t first_rank = std::uint64_t(first_group) * G,
                          last_rank = std::min<std::uint64_t>(kept, std::uint64_t(last_group) * G);
      std::vector<std::unique_ptr<Record_file<Ranked_record>>> group_files;
      for (std::size_t g = first_group; g < last_group; ++g)
        group_files.push_back(std::make_unique<Record_file<Ranked_record>>(temporary_directory, 4096));
      for_each_kept_point(
        points, signs,
        [&](const Point_record& out, std::uint32_t, bool, std::uint64_t r) {
          if (r >= first_rank && r < last_rank)
            group_files[std::size_t(r / G) - first_group]->append(Ranked_record{out, r});
        },
        count);
      // then write each group, one file per component
      for (std::size_t g = first_group; g < last_group; ++g) {
        Record_file<Ranked_record>& file = *group_files[g - first_group];
        open_writers(g * G, std::min(kept, (g + 1) * G));
        file.rewind();
        while (true) {
          ranked.clear();
          if (file.read(ranked, 1 << 14) == 0)
            break;
          for (const Ranked_record& rr : ranked)
            writers[std::size_t(rr.rank - std::uint64_t(g) * G)].write(rr.record);
          count(ranked.size());
        }
        commit_writers();
        group_files[g - first_group].reset(); // removes the group file
      }
    }
  }
  progress.report(total, total);
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_COMPONENT_FILES_H
