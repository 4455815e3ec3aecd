// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file test_streaming_driver.cpp
/// \brief Tests of streaming_orient_normals.h: presorted input, component files
/// and the minimum component size, the copy in the input order, progress and
/// cancellation, the bounded window, the range adaptor, and faults (a disk that
/// fills up half way through a run).

#include "Streaming_test_support.h"

namespace {

TEST(Streaming_presorted, SameOrientationAsTheSortedPath)
{
  Temporary_directory directory;
  std::mt19937_64 rng(17);
  Test_cloud cloud;
  cloud.ellipsoid(20000, Vec{{1., -2., 0.5}}, 4., 1., 0.7, rng);
  const std::size_t n = cloud.records.size();

  // the reference: the input in random order, sorted by the pipeline
  std::vector<Point_record> shuffled = cloud.records;
  std::shuffle(shuffled.begin(), shuffled.end(), rng);
  Vector_source source(shuffled);
  Stream_options options = streaming_options_in(directory.path());
  options.batch_size = 2000;
  options.sort_memory = 5000 * ns::External_sort_options::bytes_per_record; // several runs
  std::vector<Point_record> reference;
  const NO::Streaming_result ref = stream(source, options, reference);
  ASSERT_EQ(reference.size(), n);
  EXPECT_FALSE(ref.presorted);
  EXPECT_TRUE(ref.radius_estimated);
  EXPECT_EQ(cloud.wrong(reference), 0u);
  EXPECT_EQ(source.delivered(), 2 * n); // the first pass and the sort
  std::vector<Vec> normal(n);
  for (const Point_record& r : reference)
    normal[r.index] = Vec{{r.normal[0], r.normal[1], r.normal[2]}};
  EXPECT_EQ(directory.count(), 0u);

  const NO::Presorted_axis axes[3] = {NO::Presorted_axis::X, NO::Presorted_axis::Y, NO::Presorted_axis::Z};
  for (int axis = 0; axis < 3; ++axis) {
    SCOPED_TRACE(axis);
    Vector_source presorted(sorted_by(cloud.records, axis));
    Stream_options po = options;
    po.presorted_axis = axes[axis];
    po.sort_memory = 16 * ns::External_sort_options::bytes_per_record; // would make runs: it must not sort
    std::size_t most_files = 0;
    presorted.on_read = [&](std::size_t) { most_files = std::max(most_files, directory.count()); };
    std::vector<Point_record> out;
    const NO::Streaming_result r = stream(presorted, po, out);
    EXPECT_TRUE(r.presorted);
    EXPECT_EQ(presorted.delivered(), 2 * n); // the first pass and the sweep
    EXPECT_LE(most_files, 2u); // the record file and the refinement's edge file: no sort runs
    EXPECT_EQ(r.seconds.sort, 0.0);
    // the same radius (the sample is the whole cloud), hence the same graph
    EXPECT_EQ(r.neighbor_radius, ref.neighbor_radius);
    EXPECT_EQ(r.number_of_points, ref.number_of_points);
    EXPECT_EQ(r.number_of_edges, ref.number_of_edges);
    EXPECT_EQ(r.number_of_components, ref.number_of_components);
    EXPECT_LT(r.peak_window, n);
    // the output keeps the input order, with the same sign for every input index
    ASSERT_EQ(out.size(), n);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < n; ++i) {
      EXPECT_EQ(out[i].index, presorted.records()[i].index);
      const Point_record& in = presorted.records()[i];
      EXPECT_EQ(std::memcmp(out[i].position, in.position, sizeof in.position), 0);
      const Vec& want = normal[out[i].index];
      differ += (out[i].normal[0] != want[0] || out[i].normal[1] != want[1] || out[i].normal[2] != want[2]) ? 1 : 0;
    }
    EXPECT_EQ(differ, 0u);
    EXPECT_EQ(cloud.wrong(out), 0u);
    EXPECT_EQ(directory.count(), 0u);
  }
}

TEST(Streaming_presorted, UnsortedInputFailsEarlyWithAClearError)
{
  Temporary_directory directory, files;
  std::mt19937_64 rng(18);
  Test_cloud cloud;
  cloud.ellipsoid(5000, Vec{{0., 0., 0.}}, 3., 1., 1., rng);
  std::vector<Point_record> records = sorted_by(cloud.records, 0);
  std::swap(records[1500], records[1700]);
  Stream_options options = streaming_options_in(directory.path());
  options.presorted_axis = NO::Presorted_axis::X;
  std::size_t sunk = 0;
  auto sink = [&sunk](const Point_record&) { ++sunk; };
  Vector_source source(records);
  try {
    NO::streaming_orient_normals(source, sink, params(options));
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("not sorted by increasing x"), std::string::npos) << what;
    // the first point out of order is the one at 1501, below the one moved to 1500
    EXPECT_NE(what.find("point 1501 (input index " + std::to_string(records[1501].index) + ")"), std::string::npos)
      << what;
    EXPECT_EQ(what.find('\n'), std::string::npos);
  }
  EXPECT_EQ(sunk, 0u);
  EXPECT_LE(source.delivered(), records.size()); // found by the first pass, before any sweep
  EXPECT_EQ(directory.count(), 0u);

  // from files: no output, no temporary file
  write_cloud(files.file("in.ply"), records);
  options.component_files.directory = files.file("components");
  EXPECT_THROW(NO::streaming_orient_files(files.file("in.ply"), files.file("out.ply"), params(options)), std::runtime_error);
  EXPECT_EQ(files.listing(), std::vector<std::string>{"in.ply"});
  EXPECT_EQ(directory.count(), 0u);
  // sorted along y, it is not sorted along x, but it is along y
  write_cloud(files.file("in_y.ply"), sorted_by(cloud.records, 1));
  options.component_files.directory.clear();
  EXPECT_THROW(NO::streaming_orient_files(files.file("in_y.ply"), files.file("out.ply"), params(options)), std::runtime_error);
  options.presorted_axis = NO::Presorted_axis::Y;
  const NO::Streaming_result r = NO::streaming_orient_files(files.file("in_y.ply"), files.file("out.ply"), params(options));
  EXPECT_EQ(r.number_of_points, records.size());
  EXPECT_EQ(read_cloud(files.file("out.ply")).size(), records.size());
  EXPECT_EQ(directory.count(), 0u);
}

/// two ellipsoids of 3000 and 1500 points and six isolated points
Test_cloud two_bodies_and_dust(std::mt19937_64& rng)
{
  Test_cloud cloud;
  cloud.ellipsoid(3000, Vec{{0., 0., 0.}}, 1.5, 1., 1., rng);
  cloud.ellipsoid(1500, Vec{{5., 0., 0.}}, 0.8, 0.8, 0.8, rng);
  for (int i = 0; i < 6; ++i)
    cloud.add(Vec{{20. + 3. * i, 1., -1.}}, Vec{{0., 0., 1.}}, rng);
  std::shuffle(cloud.records.begin(), cloud.records.end(), rng);
  return cloud;
}

TEST(Streaming_components, MinimumSizeDropsSmallComponentsFromEveryOutput)
{
  Temporary_directory directory, files;
  std::mt19937_64 rng(19);
  const Test_cloud cloud = two_bodies_and_dust(rng);
  const std::size_t n = cloud.records.size();
  write_cloud(files.file("in.ply"), cloud.records);
  Stream_options options = streaming_options_in(directory.path());
  options.radius = 0.3;
  options.minimum_component_size = 10;
  options.component_files.directory = files.file("parts/a"); // created, with its parent
  const NO::Streaming_result r = NO::streaming_orient_files(files.file("in.ply"), files.file("out.ply"), params(options));
  EXPECT_EQ(r.number_of_points, n);
  EXPECT_EQ(r.number_of_components, 8u);
  EXPECT_EQ(r.number_of_dropped_components, 6u);
  EXPECT_EQ(r.number_of_dropped_points, 6u);
  const std::vector<Point_record> out = read_cloud(files.file("out.ply"));
  EXPECT_EQ(out.size(), n - 6);
  for (const Point_record& p : out)
    EXPECT_LT(p.position[0], 10.); // no dust
  ASSERT_EQ(r.component_files.size(), 2u);
  EXPECT_EQ(r.component_files[0], files.file("parts/a/component_000000.ply"));
  EXPECT_EQ(r.component_files[1], files.file("parts/a/component_000001.ply"));
  const std::vector<Point_record> big = read_cloud(r.component_files[0]), small = read_cloud(r.component_files[1]);
  EXPECT_EQ(big.size(), 3000u); // the largest first
  EXPECT_EQ(small.size(), 1500u);
  for (const Point_record& p : big)
    EXPECT_LT(p.position[0], 2.);
  for (const Point_record& p : small)
    EXPECT_GT(p.position[0], 3.);
  // together, exactly the output (same coordinates and normals)
  std::vector<Point_record> both = big;
  both.insert(both.end(), small.begin(), small.end());
  EXPECT_EQ(sorted_points(both), sorted_points(out));
  std::vector<std::string> listing;
  for (const auto& e : fs::directory_iterator(files.file("parts/a")))
    listing.push_back(e.path().filename().string());
  std::sort(listing.begin(), listing.end());
  EXPECT_EQ(listing, (std::vector<std::string>{"component_000000.ply", "component_000001.ply"}));
  EXPECT_EQ(directory.count(), 0u);

  // one open file at a time (groups of one component, written in rounds):
  // the same bytes; and xyz files like the output
  const std::string first = file_bytes(r.component_files[0]), second = file_bytes(r.component_files[1]);
  options.component_files.maximum_open_files = 1;
  options.component_files.directory = files.file("parts/b");
  const NO::Streaming_result r1 = NO::streaming_orient_files(files.file("in.ply"), files.file("out1.ply"), params(options));
  ASSERT_EQ(r1.component_files.size(), 2u);
  // the total covers every stage, the output's commit included
  const NO::Streaming_seconds& sec = r1.seconds;
  EXPECT_GE(sec.total, sec.frame + sec.radius + sec.sort + sec.sweep + sec.solve + sec.refine + sec.sign + sec.output +
                         sec.components);
  EXPECT_EQ(file_bytes(r1.component_files[0]), first);
  EXPECT_EQ(file_bytes(r1.component_files[1]), second);
  EXPECT_EQ(file_bytes(files.file("out1.ply")), file_bytes(files.file("out.ply")));
  options.component_files.directory = files.file("parts/c");
  const NO::Streaming_result rx = NO::streaming_orient_files(files.file("in.ply"), files.file("out.xyz"), params(options));
  ASSERT_EQ(rx.component_files.size(), 2u);
  EXPECT_EQ(rx.component_files[1], files.file("parts/c/component_000001.xyz"));
  EXPECT_EQ(read_cloud(rx.component_files[1]).size(), 1500u);
  EXPECT_EQ(directory.count(), 0u);

  // without a minimum, every component is kept: the dust too, one point per file
  options.minimum_component_size = 0;
  options.component_files.maximum_open_files = 3;
  options.component_files.directory = files.file("parts/d");
  const NO::Streaming_result r0 = NO::streaming_orient_files(files.file("in.ply"), files.file("out0.ply"), params(options));
  EXPECT_EQ(r0.number_of_dropped_components, 0u);
  EXPECT_EQ(r0.number_of_dropped_points, 0u);
  EXPECT_EQ(read_cloud(files.file("out0.ply")).size(), n);
  ASSERT_EQ(r0.component_files.size(), 8u);
  EXPECT_EQ(file_bytes(r0.component_files[0]), first);
  EXPECT_EQ(file_bytes(r0.component_files[1]), second);
  for (std::size_t c = 2; c < 8; ++c)
    EXPECT_EQ(read_cloud(r0.component_files[c]).size(), 1u);
  EXPECT_EQ(directory.count(), 0u);
  // a bad extension is refused before any work
  options.component_files.extension = ".obj";
  Vector_source source(cloud.records);
  std::vector<Point_record> sunk;
  EXPECT_THROW(stream(source, options, sunk), std::invalid_argument);
  EXPECT_EQ(source.delivered(), 0u);
}

// streaming_orient_files_in_input_order: OUT is IN in its own order and
// format, every other property kept, only the signs of the normals changed
// (those of streaming_orient_files, point for point), the dropped components
// left out; a format other than IN's is refused before any work; nothing is
// left behind.
TEST(Streaming_components, InputOrderCopyKeepsEveryPropertyAndTheOrder)
{
  Temporary_directory directory, files;
  std::mt19937_64 rng(23);
  const Test_cloud cloud = two_bodies_and_dust(rng);
  const std::size_t n = cloud.records.size();
  // an ascii PLY with float normals between the coordinates and a colour after them
  {
    std::ofstream out(files.file("in.ply"), std::ios::binary);
    out << "ply\nformat ascii 1.0\ncomment kept as it is\nelement vertex " << n
        << "\nproperty float nx\nproperty double x\nproperty double y\nproperty double z\nproperty float ny\n"
           "property float nz\nproperty uchar red\nend_header\n";
    out.precision(17);
    for (const Point_record& r : cloud.records)
      out << float(r.normal[0]) << ' ' << r.position[0] << ' ' << r.position[1] << ' ' << r.position[2] << ' '
          << float(r.normal[1]) << ' ' << float(r.normal[2]) << ' ' << (r.index * 7) % 256 << '\n';
  }
  write_cloud(files.file("in.xyz"), read_cloud(files.file("in.ply")));
  Stream_options options = streaming_options_in(directory.path());
  options.radius = 0.3;
  options.minimum_component_size = 10;
  const NO::Streaming_result reference =
    NO::streaming_orient_files(files.file("in.ply"), files.file("sweep.ply"), params(options));
  const std::vector<Point_record> swept = read_cloud(files.file("sweep.ply"));
  ASSERT_EQ(swept.size(), n - 6);

  NO::IO::Transcode_report report;
  const NO::Streaming_result r = NO::streaming_orient_files_in_input_order<CGAL::Parallel_if_available_tag>(
    files.file("in.ply"), files.file("out.ply"), params(options), &report);
  EXPECT_EQ(r.number_of_points, n);
  EXPECT_EQ(r.number_of_dropped_points, 6u);
  EXPECT_EQ(r.number_of_flipped, reference.number_of_flipped);
  EXPECT_EQ(report.number_of_points, n);
  EXPECT_EQ(report.number_of_written_points, n - 6);
  EXPECT_EQ(report.number_of_flipped, r.number_of_flipped);
  EXPECT_GT(r.number_of_flipped, 0u);
  // the input's order, without the dust (the 6 points beyond x = 19)
  const std::vector<Point_record> input = read_cloud(files.file("in.ply")), out = read_cloud(files.file("out.ply"));
  std::vector<Point_record> kept;
  for (const Point_record& p : input)
    if (p.position[0] < 19.)
      kept.push_back(p); // with its index in the input
  ASSERT_EQ(out.size(), kept.size());
  for (std::size_t i = 0; i < out.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      ASSERT_EQ(out[i].position[c], kept[i].position[c]) << i;
      ASSERT_EQ(std::abs(out[i].normal[c]), std::abs(kept[i].normal[c])) << i;
    }
  // the same normals as the sweep-order output, point for point
  EXPECT_EQ(sorted_points(out), sorted_points(swept));
  std::vector<Point_record> indexed = out; // with the indices of `cloud` (shuffled in the file)
  for (std::size_t i = 0; i < out.size(); ++i)
    indexed[i].index = cloud.records[std::size_t(kept[i].index)].index;
  EXPECT_EQ(cloud.wrong(indexed), 0u);
  // the header (comment, property order and types) and the colours as they were
  std::ifstream in_text(files.file("in.ply")), out_text(files.file("out.ply"));
  std::string a, b;
  std::size_t line = 0, data = 0;
  while (std::getline(out_text, b)) {
    do
      std::getline(in_text, a);
    while (line >= 12 && std::stod(a.substr(a.find(' ') + 1)) >= 19.); // a dropped point
    if (line == 3)
      EXPECT_EQ(b, "element vertex " + std::to_string(n - 6));
    else if (line < 12) // the header: 7 properties
      EXPECT_EQ(b, a);
    else {
      EXPECT_EQ(b.substr(b.rfind(' ')), a.substr(a.rfind(' '))) << line; // red
      ++data;
    }
    ++line;
  }
  EXPECT_EQ(data, n - 6);

  // an .xyz input: an .xyz copy, with the same signs
  const NO::Streaming_result rx =
    NO::streaming_orient_files_in_input_order(files.file("in.xyz"), files.file("out.xyz"), params(options));
  EXPECT_EQ(rx.number_of_flipped, r.number_of_flipped);
  EXPECT_EQ(sorted_points(read_cloud(files.file("out.xyz"))), sorted_points(out));
  // another format than the input's: refused before any work, nothing written
  EXPECT_THROW(NO::streaming_orient_files_in_input_order(files.file("in.ply"), files.file("out2.xyz"), params(options)),
               NO::IO::Io_error);
  EXPECT_THROW(NO::streaming_orient_files_in_input_order(files.file("in.xyz"), files.file("out2.ply"), params(options)),
               NO::IO::Io_error);
  EXPECT_FALSE(fs::exists(files.file("out2.xyz")));
  EXPECT_FALSE(fs::exists(files.file("out2.ply")));
  // a cancellation during the copy: no output, nothing left
  Stream_options cancel = options;
  cancel.callback = [n](const NO::Progress_info& p) { // the copy counts bytes, not points
    return !(p.stage == NO::Stage::OUTPUT && p.total != n && p.done > 0);
  };
  EXPECT_TRUE(
    NO::streaming_orient_files_in_input_order(files.file("in.ply"), files.file("out3.ply"), params(cancel)).interrupted);
  EXPECT_FALSE(fs::exists(files.file("out3.ply")));
  EXPECT_EQ(directory.count(), 0u);
  std::size_t in_files = 0;
  for (const auto& e : fs::directory_iterator(files.path()))
    in_files += e.path().filename().string().find(".tmp.") != std::string::npos ? 1 : 0;
  EXPECT_EQ(in_files, 0u);
}

TEST(Streaming_components, ManyComponentsWithFewOpenFiles)
{
  Temporary_directory directory, parts;
  std::mt19937_64 rng(20);
  Test_cloud cloud;
  const int clusters = 40;
  for (int c = 0; c < clusters; ++c) // 40 small spheres of 30 to 69 points, 3 apart along x
    cloud.ellipsoid(30 + std::size_t(c), Vec{{3. * c, 0., 0.}}, 0.2, 0.2, 0.2, rng);
  std::shuffle(cloud.records.begin(), cloud.records.end(), rng);
  const std::size_t n = cloud.records.size();
  Vector_source source(cloud.records);
  Stream_options options = streaming_options_in(directory.path());
  options.radius = 0.3;
  options.batch_size = 100;
  options.component_files.directory = parts.path();
  options.component_files.maximum_open_files = 3; // 14 groups of 3, in 5 rounds
  std::size_t most_open = 0, most_temporary = 0;
  options.callback = [&](const NO::Progress_info& p) {
    if (p.stage == NO::Stage::COMPONENTS) {
      std::size_t open = 0;
      for (const std::string& f : parts.listing())
        open += f.find(".tmp.") != std::string::npos ? 1 : 0;
      most_open = std::max(most_open, open);
      most_temporary = std::max(most_temporary, directory.count());
    }
    return true;
  };
  std::vector<Point_record> out;
  const NO::Streaming_result r = stream(source, options, out);
  EXPECT_EQ(r.number_of_components, std::size_t(clusters));
  ASSERT_EQ(r.component_files.size(), std::size_t(clusters));
  EXPECT_GT(most_open, 0u);
  EXPECT_LE(most_open, 3u);
  // the record file, the refinement's last label file, the global stage's
  // unit file and the group files of a round
  EXPECT_LE(most_temporary, 3u + 3u);
  EXPECT_EQ(parts.count(), std::size_t(clusters));
  EXPECT_EQ(directory.count(), 0u);
  std::size_t total = 0, previous = n;
  std::vector<int> file_of(clusters, -1);
  for (std::size_t f = 0; f < r.component_files.size(); ++f) {
    char name[48];
    std::snprintf(name, sizeof name, "component_%06zu.ply", f);
    EXPECT_EQ(r.component_files[f], parts.file(name));
    const std::vector<Point_record> part = read_cloud(r.component_files[f]);
    ASSERT_FALSE(part.empty());
    EXPECT_LE(part.size(), previous); // by decreasing size
    previous = part.size();
    total += part.size();
    const int c = int(std::lround(part[0].position[0] / 3.));
    for (const Point_record& p : part)
      EXPECT_EQ(int(std::lround(p.position[0] / 3.)), c); // one cluster per file
    ASSERT_GE(c, 0);
    ASSERT_LT(c, clusters);
    EXPECT_EQ(file_of[std::size_t(c)], -1);
    file_of[std::size_t(c)] = int(f);
    EXPECT_EQ(part.size(), 30u + std::size_t(c));
  }
  EXPECT_EQ(total, n);
  EXPECT_EQ(out.size(), n);
}

TEST(Streaming_progress, ReportsEveryStageInOrderAndCancels)
{
  Temporary_directory directory, files;
  std::mt19937_64 rng(21);
  Test_cloud cloud = two_bodies_and_dust(rng);
  const std::size_t n = cloud.records.size();
  Stream_options options = streaming_options_in(directory.path());
  options.batch_size = 300;
  options.sort_memory = 1000 * ns::External_sort_options::bytes_per_record;
  std::vector<NO::Progress_info> log;
  options.callback = [&log](const NO::Progress_info& p) {
    log.push_back(p);
    return true;
  };
  std::vector<Point_record> out;
  {
    Vector_source source(cloud.records);
    stream(source, options, out);
  }
  const NO::Stage order[] = {NO::Stage::SCAN,   NO::Stage::RADIUS,
                                       NO::Stage::SORT,   NO::Stage::SWEEP,
                                       NO::Stage::SOLVE,  NO::Stage::REFINE,
                                       NO::Stage::SIGN,   NO::Stage::GLOBAL, NO::Stage::OUTPUT};
  auto check_log = [&](const std::vector<NO::Stage>& expected) {
    std::vector<NO::Stage> stages;
    for (std::size_t i = 0; i < log.size(); ++i) {
      const NO::Progress_info& p = log[i];
      EXPECT_GE(p.stage_fraction(), 0.0);
      EXPECT_LE(p.stage_fraction(), 1.0);
      if (stages.empty() || stages.back() != p.stage) {
        stages.push_back(p.stage);
        EXPECT_EQ(p.done, 0u) << NO::stage_name(p.stage); // reported at its start
      } else {
        EXPECT_GE(p.done, log[i - 1].done) << NO::stage_name(p.stage);
      }
      if (i + 1 == log.size() || log[i + 1].stage != p.stage) { // and at its end
        EXPECT_EQ(p.done, p.total) << NO::stage_name(p.stage);
        EXPECT_EQ(p.stage_fraction(), 1.0) << NO::stage_name(p.stage);
      }
    }
    EXPECT_EQ(stages, expected);
  };
  check_log(std::vector<NO::Stage>(std::begin(order), std::end(order)));
  std::size_t sweep_reports = 0;
  for (const NO::Progress_info& p : log)
    if (p.stage == NO::Stage::SWEEP) {
      ++sweep_reports;
      EXPECT_EQ(p.total, n);
    }
  EXPECT_GT(sweep_reports, 10u); // per batch
  EXPECT_STREQ(NO::stage_name(NO::Stage::SWEEP), "sweep");
  EXPECT_STREQ(NO::stage_name(NO::Stage::REFINE), "refine");
  EXPECT_STREQ(NO::stage_name(NO::Stage::COMPONENTS), "components");

  // presorted, with a radius and component files: no sort, no radius stage
  log.clear();
  {
    Stream_options po = options;
    po.presorted_axis = NO::Presorted_axis::X;
    po.radius = 0.3;
    po.component_files.directory = files.file("parts");
    Vector_source source(sorted_by(cloud.records, 0));
    stream(source, po, out);
  }
  check_log({NO::Stage::SCAN, NO::Stage::SWEEP, NO::Stage::SOLVE,
             NO::Stage::REFINE, NO::Stage::SIGN, NO::Stage::GLOBAL, NO::Stage::OUTPUT,
             NO::Stage::COMPONENTS});

  // cancelled half way through the sweep: interrupted, nothing sunk, nothing left
  {
    Stream_options co = options;
    co.callback = [](const NO::Progress_info& p) {
      return !(p.stage == NO::Stage::SWEEP && p.stage_fraction() >= 0.5);
    };
    Vector_source source(cloud.records);
    EXPECT_TRUE(stream(source, co, out).interrupted);
    EXPECT_TRUE(out.empty());
    EXPECT_EQ(directory.count(), 0u);
  }
  // cancelled during the sort
  {
    Stream_options co = options;
    co.callback = [](const NO::Progress_info& p) {
      return !(p.stage == NO::Stage::SORT && p.stage_fraction() >= 0.5);
    };
    Vector_source source(cloud.records);
    EXPECT_TRUE(stream(source, co, out).interrupted);
    EXPECT_EQ(directory.count(), 0u);
  }
  // cancelled once a component file is written: no output, no component
  // file, not even the directory the run created, no temporary file
  {
    write_cloud(files.file("in.ply"), cloud.records);
    Stream_options co = options;
    co.radius = 0.3;
    co.component_files.directory = files.file("cancelled");
    co.component_files.maximum_open_files = 1;
    bool seen_file = false;
    co.callback = [&](const NO::Progress_info& p) {
      seen_file = seen_file || fs::exists(files.file("cancelled/component_000000.ply"));
      return !(p.stage == NO::Stage::COMPONENTS && seen_file);
    };
    EXPECT_TRUE(NO::streaming_orient_files(files.file("in.ply"), files.file("out.ply"), params(co)).interrupted);
    EXPECT_TRUE(seen_file);
    EXPECT_EQ(files.listing(), (std::vector<std::string>{"in.ply", "parts"}));
    EXPECT_EQ(directory.count(), 0u);
  }
}

/// n points on a cylinder of radius 0.5 and length `length` along x, at a
/// fixed density when n / length is fixed, in random order
Test_cloud cylinder(std::size_t n, double length, std::mt19937_64& rng)
{
  std::uniform_real_distribution<double> along(0.0, length), angle(0.0, 2.0 * M_PI);
  Test_cloud cloud;
  for (std::size_t i = 0; i < n; ++i) {
    const double a = angle(rng);
    cloud.add(Vec{{along(rng), 0.5 * std::cos(a), 0.5 * std::sin(a)}}, Vec{{0., std::cos(a), std::sin(a)}}, rng);
  }
  return cloud;
}

TEST(Streaming_window, PeakDoesNotGrowWithTheLength)
{
  Temporary_directory directory;
  std::mt19937_64 rng(22);
  const Test_cloud short_cloud = cylinder(20000, 25.0, rng), long_cloud = cylinder(80000, 100.0, rng);
  for (const bool presorted : {true, false}) {
    SCOPED_TRACE(presorted ? "presorted" : "sorted");
    std::size_t peak[2] = {0, 0};
    std::uint64_t span[2] = {0, 0};
    double radius[2] = {0, 0};
    for (int which = 0; which < 2; ++which) {
      const Test_cloud& cloud = which == 0 ? short_cloud : long_cloud;
      Vector_source source(presorted ? sorted_by(cloud.records, 0) : cloud.records);
      Stream_options options = streaming_options_in(directory.path());
      options.batch_size = 1000; // the window is a slab of about 3r, plus a batch and a read
      options.sort_memory = 20000 * ns::External_sort_options::bytes_per_record;
      if (presorted)
        options.presorted_axis = NO::Presorted_axis::X;
      std::vector<Point_record> out;
      const NO::Streaming_result r = stream(source, options, out);
      EXPECT_EQ(out.size(), cloud.records.size());
      peak[which] = r.peak_window;
      span[which] = r.edge_span;
      radius[which] = r.neighbor_radius;
      std::cout << "[ info ] cylinder of " << cloud.records.size() << " points (" << (presorted ? "presorted" : "sorted")
                << "): r = " << r.neighbor_radius << ", peak window " << r.peak_window << "\n";
    }
    EXPECT_NEAR(radius[1] / radius[0], 1.0, 0.1); // the same density
    EXPECT_LE(double(peak[1]), 1.2 * double(peak[0]));
    EXPECT_LT(peak[1], long_cloud.records.size() / 10);
    EXPECT_LT(peak[0], short_cloud.records.size() / 2);
    // the window of the refinement (twice the edge span) neither
    EXPECT_GT(span[0], 0u);
    EXPECT_LE(double(span[1]), 1.2 * double(span[0]));
    EXPECT_LT(span[1], long_cloud.records.size() / 20);
  }
  EXPECT_EQ(directory.count(), 0u);
}

} // namespace

namespace {

typedef CGAL::Exact_predicates_inexact_constructions_kernel Range_kernel;
typedef std::pair<Range_kernel::Point_3, Range_kernel::Vector_3> Point_with_normal;

} // namespace

// The range adaptor: a user's vector of (point, normal) pairs, presorted
// along x, streamed through make_point_range_source and written back in
// place by make_normal_writer, gives the orientation of the file path, and
// the adaptor's order check names the first point out of order.
TEST(Streaming_point_range, OrientsAUserRangeInPlaceAndChecksItsOrder)
{
  namespace NP = Normal_orientation::parameters;
  Temporary_directory directory;
  std::mt19937_64 rng(29);
  Test_cloud cloud;
  cloud.ellipsoid(15000, Vec{{0.5, 1., -1.}}, 3., 1.2, 0.8, rng);
  std::vector<Point_record> sorted = sorted_by(cloud.records, 0);
  std::vector<Point_with_normal> points;
  std::vector<Vec> truth;
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    const Point_record& r = sorted[i];
    points.emplace_back(Range_kernel::Point_3(r.position[0], r.position[1], r.position[2]),
                        Range_kernel::Vector_3(r.normal[0], r.normal[1], r.normal[2]));
    truth.push_back(cloud.truth[r.index]);
    sorted[i].index = i; // as the adaptor numbers them
  }
  const auto np = NP::point_map(CGAL::First_of_pair_property_map<Point_with_normal>())
                    .normal_map(CGAL::Second_of_pair_property_map<Point_with_normal>());
  std::vector<Point_with_normal> original = points;

  // the reference: the same records through a plain vector source
  Vector_source reference_source(sorted);
  Stream_options options = streaming_options_in(directory.path());
  options.presorted_axis = NO::Presorted_axis::X;
  std::vector<Point_record> reference;
  const NO::Streaming_result rr = stream(reference_source, options, reference);
  ASSERT_EQ(reference.size(), points.size());

  auto source = ns::make_point_range_source(points, np, 0);
  EXPECT_EQ(source.size(), points.size());
  auto sink = ns::make_normal_writer(points, np);
  const NO::Streaming_result result = NO::streaming_orient_normals(source, sink, params(options));
  EXPECT_EQ(result.number_of_points, points.size());
  EXPECT_EQ(result.number_of_edges, rr.number_of_edges);
  std::size_t wrong = 0, differ = 0, moved = 0;
  for (const Point_record& r : reference) { // the reference's index is the position in `points`
    const Range_kernel::Vector_3& n = points[r.index].second;
    wrong += dot(Vec{{n.x(), n.y(), n.z()}}, truth[r.index]) <= 0.0 ? 1 : 0;
    differ += (n.x() != r.normal[0] || n.y() != r.normal[1] || n.z() != r.normal[2]) ? 1 : 0;
    moved += points[r.index].first != original[r.index].first ? 1 : 0;
    // only the sign of a normal may change
    const Range_kernel::Vector_3& m = original[r.index].second;
    EXPECT_TRUE(n == m || n == -m);
  }
  EXPECT_EQ(differ, 0u) << "the in-place result differs from the vector source's";
  EXPECT_EQ(moved, 0u);
  EXPECT_LE(wrong, points.size() / 200) << wrong << " wrong normals";

  // the order check of the adaptor: swap two points far apart along x
  std::swap(points[100], points[9000]);
  auto bad = ns::make_point_range_source(points, np, 0);
  std::vector<Point_record> chunk;
  try {
    while (bad.read(chunk, 4096) > 0) {
    }
    ADD_FAILURE() << "the order check did not fire";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not sorted by increasing x at point 101"), std::string::npos) << e.what();
  }
  // rewind starts again; without a checked axis nothing is checked
  auto unchecked = ns::make_point_range_source(points, np);
  chunk.clear();
  while (unchecked.read(chunk, 4096) > 0) {
  }
  EXPECT_EQ(chunk.size(), points.size());
  EXPECT_EQ(chunk[100].index, 100u);
  unchecked.rewind();
  chunk.clear();
  EXPECT_EQ(unchecked.read(chunk, 10), 10u);
  EXPECT_EQ(chunk[0].index, 0u);
  EXPECT_THROW(ns::make_point_range_source(points, np, 3), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// (g) fault injection: the disk becomes full half way through a run
// ---------------------------------------------------------------------------
//
// RLIMIT_FSIZE, lowered from the progress callback at a chosen stage and
// with SIGXFSZ ignored, stands for a disk that fills up: from then on every
// write beyond that size fails (EFBIG, where a full disk gives ENOSPC), in
// the temporary files (sort runs, record file) and the output alike.  (The
// tests run as root, whom a read-only directory does not stop, and a small
// tmpfs cannot be mounted in CI.)


// The disk fills up during the sort, the sweep (record file), the output or
// the component files of streaming_orient_files: the run throws one clear
// line naming the file and the reason, and leaves no output, no component
// file and no temporary file; with the space back, the same run succeeds.
TEST(Streaming_faults, DiskFullHalfWayLeavesNothing)
{
  File_size_limit limit;
  if (!limit.usable())
    GTEST_SKIP() << "RLIMIT_FSIZE cannot be lowered here";
  Temporary_directory temporary, files;
  std::mt19937_64 rng(31);
  Test_cloud cloud;
  cloud.ellipsoid(30000, Vec{{0., 0., 0.}}, 3., 1., 0.8, rng);
  cloud.ellipsoid(10000, Vec{{8., 0., 0.}}, 1., 1., 1., rng);
  std::shuffle(cloud.records.begin(), cloud.records.end(), rng);
  const std::uint64_t n = cloud.records.size();
  write_cloud(files.file("in.ply"), cloud.records);
  const std::vector<std::string> before = tree(files.path());

  Stream_options options = streaming_options_in(temporary.path());
  options.batch_size = 2000;                                       // progress per batch of the sweep
  options.sort_memory = 4000 * ns::External_sort_options::bytes_per_record; // 10 runs of 224 kB
  options.component_files.directory = files.file("parts");
  const struct
  {
    NO::Stage stage;
    std::uint64_t at;   // the disk fills once the stage has done this much
    rlim_t bytes;       // files are limited to this size from then on
  } faults[] = {
    {NO::Stage::SORT, n / 2, 100000},      // the next run cannot be written
    {NO::Stage::SWEEP, n / 2, 100000},     // the record file (64 bytes a point) stops growing
    {NO::Stage::OUTPUT, 0, 200000},        // the output (48 bytes a point) stops at 200 kB
    {NO::Stage::COMPONENTS, 0, 200000},    // so does the first component file
  };
  for (const auto& fault : faults) {
    SCOPED_TRACE(NO::stage_name(fault.stage));
    bool reached = false;
    std::size_t most_temporary_files = 0;
    options.callback = [&](const NO::Progress_info& p) {
      most_temporary_files = std::max(most_temporary_files, temporary.count());
      if (p.stage == fault.stage && p.done >= fault.at && !limit.filled()) {
        reached = true;
        limit.fill(fault.bytes);
      }
      return true;
    };
    std::string message;
    try {
      NO::streaming_orient_files(files.file("in.ply"), files.file("out.ply"), params(options));
    } catch (const std::exception& e) {
      message = e.what();
    }
    limit.restore();
    EXPECT_TRUE(reached);
    EXPECT_GE(most_temporary_files, 1u);
    ASSERT_FALSE(message.empty()) << "the run did not fail";
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_NE(message.find("File too large"), std::string::npos) << message;
    EXPECT_NE(message.find("cannot write"), std::string::npos) << message;
    EXPECT_EQ(temporary.count(), 0u) << "temporary files left behind";
    EXPECT_EQ(tree(files.path()), before) << "an output, a component file or a temporary output left behind";
  }

  // the same run with room enough
  options.callback = nullptr;
  const NO::Streaming_result r = NO::streaming_orient_files(files.file("in.ply"), files.file("out.ply"), params(options));
  EXPECT_EQ(r.number_of_points, n);
  EXPECT_EQ(r.number_of_components, 2u);
  EXPECT_EQ(read_cloud(files.file("out.ply")).size(), n);
  EXPECT_EQ(temporary.count(), 0u);
}

// The same at the level of streaming_orient_normals, with a presorted
// source (read by the sweep's own thread) and a sink of the caller's: a write
// failure of the record file in the sweep is a std::system_error naming the
// file, the sink has not been called, nothing is left in the temporary
// directory.
TEST(Streaming_faults, RecordFileWriteFailureInTheSweep)
{
  File_size_limit limit;
  if (!limit.usable())
    GTEST_SKIP() << "RLIMIT_FSIZE cannot be lowered here";
  Temporary_directory temporary;
  std::mt19937_64 rng(37);
  Test_cloud cloud;
  cloud.ellipsoid(40000, Vec{{0., 0., 0.}}, 4., 1., 1., rng);
  const std::uint64_t n = cloud.records.size();
  Vector_source source(sorted_by(cloud.records, 0));
  Stream_options options = streaming_options_in(temporary.path());
  options.presorted_axis = NO::Presorted_axis::X;
  options.batch_size = 1000;
  options.callback = [&](const NO::Progress_info& p) {
    if (p.stage == NO::Stage::SWEEP && p.done >= n / 2 && !limit.filled())
      limit.fill(64 * 1024);
    return true;
  };
  std::vector<Point_record> out;
  bool thrown = false;
  try {
    stream(source, options, out);
  } catch (const std::system_error& e) {
    thrown = true;
    EXPECT_EQ(e.code(), std::errc::file_too_large) << e.what();
    EXPECT_NE(std::string(e.what()).find("normal_orientation_records_"), std::string::npos) << e.what();
  }
  limit.restore();
  EXPECT_TRUE(thrown);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(temporary.count(), 0u);
}

