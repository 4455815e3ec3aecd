// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file test_streaming.cpp
/// \brief Tests of streaming/external_sort.h and streaming/Sweep_frame.h: the sweep
/// frame, the external sort (runs, merges, in-memory case), degenerate clouds,
/// the temporary files (creation, removal on success, on exceptions, on write
/// failures, from a signal handler) and determinism.

#include "Streaming_test_support.h"

namespace {

// ---------------------------------------------------------------------------
// (a) the frame
// ---------------------------------------------------------------------------

TEST(Sweep_frame, AxisMatchesKnownDirection)
{
  Vector_source source(elongated_cloud());
  const Sweep_frame frame = ns::compute_sweep_frame(source, 4096);
  expect_valid_frame(frame);
  EXPECT_EQ(frame.size, 50000u);
  EXPECT_EQ(frame.non_finite, 0u);
  const Vec d = normalized(known_direction);
  EXPECT_GT(std::abs(dot(frame.axis, d)), 0.99);
  EXPECT_GT(dot(frame.axis, d), 0.999); // largest component (y) positive
  EXPECT_NEAR(frame.centroid[0], 1e6, 0.5);
  EXPECT_NEAR(frame.centroid[1], -2e6, 0.5);
  EXPECT_NEAR(frame.centroid[2], 3e5, 0.5);
  EXPECT_NEAR(frame.variances[0], 100., 5.);
  EXPECT_NEAR(frame.variances[1], 4., 0.2);
  EXPECT_NEAR(frame.variances[2], 1., 0.05);
  EXPECT_EQ(source.position(), 0u); // rewound

  // key and (u, v) reconstruct the position
  const Point_record& r = source.records()[123];
  const double k = frame.key(r);
  const std::array<double, 2> uv = frame.uv(r);
  EXPECT_EQ(uv[0], frame.u_coordinate(r));
  EXPECT_EQ(uv[1], frame.v_coordinate(r));
  for (int j = 0; j < 3; ++j)
    EXPECT_NEAR(frame.centroid[j] + k * frame.axis[j] + uv[0] * frame.u[j] + uv[1] * frame.v[j], r.position[j],
                1e-6);
}

TEST(Sweep_frame, SeveralDirections)
{
  const Vec directions[] = {{{1., 0., 0.}}, {{0., 0., -1.}}, {{-3., 1., 0.5}}, {{1., 1., 1.}}, {{0.2, -5., 0.}}};
  unsigned seed = 1;
  for (const Vec& direction : directions) {
    Vector_source source(gaussian_cloud(20000, Vec{{-5., 7., 1.}}, basis_along(direction), Vec{{5., 1., 0.5}}, seed++));
    const Sweep_frame frame = ns::compute_sweep_frame(source);
    expect_valid_frame(frame);
    EXPECT_GT(std::abs(dot(frame.axis, normalized(direction))), 0.99);
  }
}

TEST(Sweep_frame, JacobiDiagonalizes)
{
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> uniform(-10., 10.);
  for (int trial = 0; trial < 200; ++trial) {
    double m[3][3];
    for (int i = 0; i < 3; ++i)
      for (int j = i; j < 3; ++j)
        m[i][j] = m[j][i] = (trial % 5 == 0 && i != j) ? 0. : uniform(rng);
    double values[3], vectors[3][3];
    ns::internal::symmetric_eigen_3(m, values, vectors);
    for (int k = 0; k < 3; ++k)
      for (int i = 0; i < 3; ++i) {
        const double mv = m[i][0] * vectors[0][k] + m[i][1] * vectors[1][k] + m[i][2] * vectors[2][k];
        EXPECT_NEAR(mv, values[k] * vectors[i][k], 1e-10);
      }
  }
}

// ---------------------------------------------------------------------------
// (b) the sort
// ---------------------------------------------------------------------------

TEST(External_sorter, ManyRunsMatchInMemorySort)
{
  Temporary_directory directory;
  Vector_source source(elongated_cloud());
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  const std::vector<Point_record> expected = sorted_in_memory(source.records(), frame);

  ns::Sorted_run_reader reader = ns::external_sort(source, frame, options_with(8000, directory.path()));
  EXPECT_EQ(reader.size(), 50000u);
  EXPECT_EQ(reader.report().points, 50000u);
  EXPECT_EQ(reader.report().runs, 7u);
  EXPECT_GE(reader.report().runs, 5u);
  EXPECT_EQ(reader.report().intermediate_merges, 0u);
  EXPECT_EQ(reader.report().merged_runs, 7u);
  EXPECT_EQ(reader.report().bytes_written, 50000u * sizeof(Point_record));
  EXPECT_EQ(reader.report().temporary_directory, directory.path());
  EXPECT_GE(reader.report().seconds, 0.);
  EXPECT_EQ(reader.number_of_temporary_files(), 7u);
  EXPECT_EQ(directory.count(), 7u);

  const std::vector<Point_record> got = read_all(reader, 777);
  expect_identical(got, expected);
  // each index exactly once
  std::vector<bool> seen(got.size(), false);
  for (const Point_record& r : got) {
    ASSERT_LT(r.index, seen.size());
    EXPECT_FALSE(seen[r.index]);
    seen[r.index] = true;
  }
  // the reader is a source: rewind and read again, in other chunk sizes
  reader.rewind();
  expect_identical(read_all(reader, 1), expected);
  reader.rewind();
  expect_identical(read_all(reader, 100000), expected);
}

TEST(External_sorter, OneRunInMemoryOrInFile)
{
  Temporary_directory directory;
  Vector_source source(elongated_cloud(20000, 7));
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  const std::vector<Point_record> expected = sorted_in_memory(source.records(), frame);

  ns::External_sort_options options = options_with(1 << 20, directory.path());
  {
    ns::Sorted_run_reader reader = ns::External_sorter(options).sort(source, frame);
    EXPECT_EQ(reader.report().runs, 1u);
    EXPECT_EQ(reader.report().bytes_written, 0u);
    EXPECT_EQ(reader.report().merged_runs, 0u);
    EXPECT_EQ(reader.number_of_temporary_files(), 0u);
    EXPECT_EQ(directory.count(), 0u);
    expect_identical(read_all(reader, 1000), expected);
    reader.rewind();
    expect_identical(read_all(reader, 333), expected);
  }
  options.keep_single_run_in_memory = false;
  {
    ns::Sorted_run_reader reader = ns::External_sorter(options).sort(source, frame);
    EXPECT_EQ(reader.report().runs, 1u);
    EXPECT_EQ(reader.report().merged_runs, 1u);
    EXPECT_EQ(reader.report().bytes_written, 20000u * sizeof(Point_record));
    EXPECT_EQ(directory.count(), 1u);
    expect_identical(read_all(reader, 1000), expected);
  }
  EXPECT_EQ(directory.count(), 0u);
  // exactly one full run: still in memory
  options = options_with(20000, directory.path());
  ns::Sorted_run_reader reader = ns::external_sort(source, frame, options);
  EXPECT_EQ(reader.report().runs, 1u);
  EXPECT_EQ(reader.number_of_temporary_files(), 0u);
  expect_identical(read_all(reader, 4096), expected);
}

TEST(External_sorter, IntermediateMerges)
{
  Temporary_directory directory;
  Vector_source source(elongated_cloud(30000, 11));
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  const std::vector<Point_record> expected = sorted_in_memory(source.records(), frame);

  ns::External_sort_options options = options_with(500, directory.path()); // 60 runs
  options.max_merge_fan_in = 3;
  std::size_t most_files = 0;
  source.on_read = [&](std::size_t) { most_files = std::max(most_files, directory.count()); };
  ns::Sorted_run_reader reader = ns::external_sort(source, frame, options);
  source.on_read = nullptr;
  EXPECT_EQ(reader.report().runs, 60u);
  EXPECT_GT(reader.report().intermediate_merges, 0u);
  EXPECT_LE(reader.report().merged_runs, 3u);
  EXPECT_LE(reader.number_of_temporary_files(), 3u);
  EXPECT_GT(reader.report().bytes_written, 30000u * sizeof(Point_record));
  EXPECT_LE(most_files, 3u * 4u); // (fan_in - 1) per level, 4 levels
  expect_identical(read_all(reader, 1000), expected);
}

// ---------------------------------------------------------------------------
// (c) degenerate inputs
// ---------------------------------------------------------------------------

/// Sorts `records` with a small and a big budget and checks the result.
void check_sort(const std::vector<Point_record>& records, const Sweep_frame& frame, const std::string& directory)
{
  Vector_source source(records);
  const std::vector<Point_record> expected = sorted_in_memory(records, frame);
  for (std::size_t per_run : {std::size_t(16), std::size_t(100), std::size_t(1) << 20}) {
    ns::Sorted_run_reader reader = ns::external_sort(source, frame, options_with(per_run, directory));
    EXPECT_EQ(reader.size(), records.size());
    expect_identical(read_all(reader, 50), expected);
  }
}

TEST(Degenerate, EmptyCloud)
{
  Temporary_directory directory;
  Vector_source source({});
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  expect_valid_frame(frame);
  EXPECT_EQ(frame.size, 0u);
  EXPECT_EQ(frame.axis, (Vec{{1., 0., 0.}}));
  EXPECT_EQ(frame.centroid, (Vec{{0., 0., 0.}}));
  check_sort({}, frame, directory.path());
  ns::External_sort_options options = options_with(16, directory.path());
  options.keep_single_run_in_memory = false;
  ns::Sorted_run_reader reader = ns::external_sort(source, frame, options);
  EXPECT_EQ(reader.report().runs, 0u);
  EXPECT_TRUE(read_all(reader, 10).empty());
  ns::Sorted_run_reader empty;
  EXPECT_TRUE(read_all(empty, 10).empty());
}

TEST(Degenerate, OnePoint)
{
  Temporary_directory directory;
  const std::vector<Point_record> records{make_record(Vec{{3., -4., 5.}}, 0)};
  Vector_source source(records);
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  expect_valid_frame(frame);
  EXPECT_EQ(frame.centroid, (Vec{{3., -4., 5.}}));
  EXPECT_EQ(frame.axis, (Vec{{1., 0., 0.}}));
  EXPECT_EQ(frame.key(records[0]), 0.);
  check_sort(records, frame, directory.path());
}

TEST(Degenerate, IdenticalPoints)
{
  Temporary_directory directory;
  std::vector<Point_record> records;
  for (std::uint64_t i = 0; i < 1000; ++i)
    records.push_back(make_record(Vec{{0.1, 0.2, 0.3}}, (i * 7919) % 1000));
  Vector_source source(records);
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  expect_valid_frame(frame);
  EXPECT_EQ(frame.variances, (Vec{{0., 0., 0.}}));
  check_sort(records, frame, directory.path());
  ns::Sorted_run_reader reader = ns::external_sort(source, frame, options_with(16, directory.path()));
  const std::vector<Point_record> got = read_all(reader, 64);
  for (std::size_t i = 0; i < got.size(); ++i)
    EXPECT_EQ(got[i].index, i);
}

TEST(Degenerate, Collinear)
{
  Temporary_directory directory;
  const Vec d = normalized(Vec{{3., -1., 2.}});
  std::vector<Point_record> records;
  for (int i = 0; i < 2000; ++i) {
    const double t = double((i * 37) % 2000) * 0.01 - 5.;
    records.push_back(make_record(Vec{{1. + t * d[0], 2. + t * d[1], 3. + t * d[2]}}, std::uint64_t(i)));
  }
  Vector_source source(records);
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  expect_valid_frame(frame);
  EXPECT_GT(dot(frame.axis, d), 1. - 1e-12);
  EXPECT_NEAR(frame.variances[1], 0., 1e-12);
  check_sort(records, frame, directory.path());
}

TEST(Degenerate, Planar)
{
  Temporary_directory directory;
  const Vec e1 = normalized(Vec{{1., 1., 0.}}), e2{{0., 0., 1.}};
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> uniform(-1., 1.);
  std::vector<Point_record> records;
  for (int i = 0; i < 3000; ++i) {
    const double s = 10. * uniform(rng), t = uniform(rng);
    records.push_back(make_record(Vec{{s * e1[0] + t * e2[0], s * e1[1] + t * e2[1], s * e1[2] + t * e2[2]}},
                                  std::uint64_t(i)));
  }
  Vector_source source(records);
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  expect_valid_frame(frame);
  EXPECT_GT(dot(frame.axis, e1), 0.999);
  EXPECT_GT(std::abs(dot(frame.u, e2)), 0.999);
  EXPECT_GT(std::abs(dot(frame.v, normalized(Vec{{1., -1., 0.}}))), 0.999);
  EXPECT_NEAR(frame.variances[2], 0., 1e-12);
  check_sort(records, frame, directory.path());
}

TEST(Degenerate, NonFinitePositionsGoLast)
{
  Temporary_directory directory;
  std::vector<Point_record> records = elongated_cloud(3000, 9);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  records[10].position[1] = nan;
  records[500].position[0] = std::numeric_limits<double>::infinity();
  records[2000].position[2] = nan;
  Vector_source source(records);
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  expect_valid_frame(frame);
  EXPECT_EQ(frame.size, 3000u);
  EXPECT_EQ(frame.non_finite, 3u);
  EXPECT_GT(dot(frame.axis, normalized(known_direction)), 0.99);
  ns::Sorted_run_reader reader = ns::external_sort(source, frame, options_with(100, directory.path()));
  const std::vector<Point_record> got = read_all(reader, 128);
  ASSERT_EQ(got.size(), 3000u);
  for (std::size_t i = 0; i + 3 < got.size(); ++i)
    EXPECT_TRUE(std::isfinite(frame.key(got[i])));
  const std::uint64_t last[3] = {records[10].index, records[500].index, records[2000].index};
  // +infinity (key +inf) before the NaN keys (by index): compare as sets
  std::vector<std::uint64_t> tail{got[2997].index, got[2998].index, got[2999].index};
  std::sort(tail.begin(), tail.end());
  std::vector<std::uint64_t> expected_tail(last, last + 3);
  std::sort(expected_tail.begin(), expected_tail.end());
  EXPECT_EQ(tail, expected_tail);
  check_sort(records, frame, directory.path());
}

// ---------------------------------------------------------------------------
// (d) temporary files
// ---------------------------------------------------------------------------

TEST(Temporary_files, AppearDuringSortAndVanishAfter)
{
  Temporary_directory directory;
  Vector_source source(elongated_cloud(20000, 3));
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  std::size_t most_files = 0;
  source.on_read = [&](std::size_t) { most_files = std::max(most_files, directory.count()); };
  {
    ns::Sorted_run_reader reader = ns::external_sort(source, frame, options_with(3000, directory.path()));
    // the 7th run is written after the last read; the 6th may still be
    // being written by the sort's thread when the last read happens
    EXPECT_GE(most_files, 5u);
    EXPECT_LE(most_files, 6u);
    EXPECT_EQ(directory.count(), 7u);
    ns::Sorted_run_reader moved = std::move(reader);
    EXPECT_EQ(directory.count(), 7u);
    EXPECT_EQ(read_all(moved, 5000).size(), 20000u);
  }
  EXPECT_EQ(directory.count(), 0u);
}

TEST(Temporary_files, TmpdirIsHonoured)
{
  Temporary_directory directory;
  const char* old = std::getenv("TMPDIR");
  const std::string saved = old != nullptr ? old : "";
  ::setenv("TMPDIR", directory.path().c_str(), 1);
  Vector_source source(elongated_cloud(5000, 4));
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  {
    ns::Sorted_run_reader reader = ns::external_sort(source, frame, options_with(1000, ""));
    EXPECT_EQ(reader.report().temporary_directory, directory.path());
    EXPECT_EQ(directory.count(), 5u);
  }
  EXPECT_EQ(directory.count(), 0u);
  if (old != nullptr)
    ::setenv("TMPDIR", saved.c_str(), 1);
  else
    ::unsetenv("TMPDIR");
}

TEST(Temporary_files, ThrowingSourceLeavesNothing)
{
  Temporary_directory directory;
  Vector_source source(elongated_cloud(20000, 5));
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  std::size_t most_files = 0;
  source.on_read = [&](std::size_t delivered) {
    most_files = std::max(most_files, directory.count());
    if (delivered >= 12000)
      throw std::runtime_error("disk on fire");
  };
  EXPECT_THROW(ns::external_sort(source, frame, options_with(2000, directory.path())), std::runtime_error);
  EXPECT_GE(most_files, 4u); // 5 runs written by then, the last one perhaps still in progress
  EXPECT_EQ(directory.count(), 0u);
  // also during an intermediate merge's lifetime
  ns::External_sort_options options = options_with(500, directory.path());
  options.max_merge_fan_in = 2;
  EXPECT_THROW(ns::external_sort(source, frame, options), std::runtime_error);
  EXPECT_EQ(directory.count(), 0u);
}

TEST(Temporary_files, FailingWriteLeavesNothing)
{
  Temporary_directory directory;
  Vector_source source(elongated_cloud(20000, 6));
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  // files larger than 100 kB cannot be written: write() fails with EFBIG
  rlimit saved;
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &saved), 0);
  if (saved.rlim_max != RLIM_INFINITY && saved.rlim_max < 100000)
    GTEST_SKIP() << "file size limit too low already";
  void (*old_handler)(int) = std::signal(SIGXFSZ, SIG_IGN);
  rlimit limited = saved;
  limited.rlim_cur = 100000;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &limited), 0);
  bool thrown = false;
  try {
    ns::external_sort(source, frame, options_with(4000, directory.path())); // runs of 224 kB
  }
  catch (const std::system_error& e) {
    thrown = true;
    EXPECT_NE(std::string(e.what()).find("cannot write"), std::string::npos) << e.what();
  }
  ::setrlimit(RLIMIT_FSIZE, &saved);
  std::signal(SIGXFSZ, old_handler);
  EXPECT_TRUE(thrown);
  EXPECT_EQ(directory.count(), 0u);
}

TEST(Temporary_files, MissingDirectoryThrows)
{
  Temporary_directory directory;
  Vector_source source(elongated_cloud(5000, 6));
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  EXPECT_THROW(ns::external_sort(source, frame, options_with(1000, directory.path() + "/missing")),
               std::system_error);
}

TEST(Temporary_files, SignalSafeRemoval)
{
  Temporary_directory directory;
  Vector_source source(elongated_cloud(10000, 8));
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  ns::Sorted_run_reader reader = ns::external_sort(source, frame, options_with(2500, directory.path()));
  EXPECT_EQ(directory.count(), 4u);
  EXPECT_GE(ns::remove_temporary_files(), 4u);
  EXPECT_EQ(directory.count(), 0u);
  EXPECT_EQ(ns::remove_temporary_files(), 0u);
  // the owners cope: a new sort in the same directory, then the old reader's destruction
  ns::Sorted_run_reader other = ns::external_sort(source, frame, options_with(2500, directory.path()));
  EXPECT_EQ(directory.count(), 4u);
  reader = ns::Sorted_run_reader();
  EXPECT_EQ(directory.count(), 4u); // the other reader's files are untouched
  other = ns::Sorted_run_reader();
  EXPECT_EQ(directory.count(), 0u);
}

TEST(Temporary_files, UnlinkOnCreation)
{
  Temporary_directory directory;
  Vector_source source(elongated_cloud(20000, 10));
  const Sweep_frame frame = ns::compute_sweep_frame(source);
  ns::External_sort_options options = options_with(1000, directory.path());
  options.unlink_on_creation = true;
  options.max_merge_fan_in = 4;
  std::size_t most_files = 0;
  source.on_read = [&](std::size_t) { most_files = std::max(most_files, directory.count()); };
  ns::Sorted_run_reader reader = ns::external_sort(source, frame, options);
  EXPECT_EQ(most_files, 0u);
  EXPECT_EQ(directory.count(), 0u);
  EXPECT_GT(reader.report().intermediate_merges, 0u);
  expect_identical(read_all(reader, 999), sorted_in_memory(source.records(), frame));
}

// ---------------------------------------------------------------------------
// (e) determinism
// ---------------------------------------------------------------------------

TEST(Determinism, SameInputSameOutput)
{
  Temporary_directory directory;
  Vector_source first(elongated_cloud(20000, 12));
  Vector_source second(elongated_cloud(20000, 12));
  const Sweep_frame frame_1 = ns::compute_sweep_frame(first, 1000);
  const Sweep_frame frame_2 = ns::compute_sweep_frame(second, 3000); // other chunking: same frame
  EXPECT_EQ(std::memcmp(frame_1.axis.data(), frame_2.axis.data(), sizeof(Vec)), 0);
  EXPECT_EQ(std::memcmp(frame_1.u.data(), frame_2.u.data(), sizeof(Vec)), 0);
  EXPECT_EQ(std::memcmp(frame_1.centroid.data(), frame_2.centroid.data(), sizeof(Vec)), 0);
  ns::Sorted_run_reader reader_1 = ns::external_sort(first, frame_1, options_with(1500, directory.path()));
  ns::Sorted_run_reader reader_2 = ns::external_sort(second, frame_2, options_with(1500, directory.path()));
  expect_identical(read_all(reader_1, 512), read_all(reader_2, 2048));
}

} // namespace
