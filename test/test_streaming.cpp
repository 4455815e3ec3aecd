// SPDX-License-Identifier: GPL-3.0-or-later
/// \file test_streaming.cpp
/// \brief Tests of Normal_orientation/streaming/external_sort.h: the sweep frame,
/// the external sort (runs, merges, in-memory case), degenerate clouds, the
/// temporary files (creation, removal on success, on exceptions, on write
/// failures, from a signal handler) and determinism; of the options of
/// streaming_orient_normals.h: presorted input, component files and the
/// minimum component size, progress and cancellation, and the bounded window;
/// and of the refinement (streaming/Refinement.h): its passes, its energies,
/// its determinism and its failures.

#include <Normal_orientation/internal/Graph_reduction.h>
#include <Normal_orientation/streaming/Point_range.h>
#include <Normal_orientation/streaming/Refinement.h>
#include <Normal_orientation/streaming/external_sort.h>
#include <Normal_orientation/streaming_orient_normals.h>

#include "Streaming_test_options.h"
#include "Test_directory.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/property_map.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <iterator>
#include <limits>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include <sys/resource.h>
#include <unistd.h>

namespace {

namespace fs = std::filesystem;
namespace ns = Normal_orientation::streaming;
using Normal_orientation::Point_record;
using ns::Sweep_frame;
using Vec = std::array<double, 3>;

/// \brief A fresh temporary directory for the running test (see Test_directory.h).
class Temporary_directory : public Normal_orientation::test::Test_directory
{
public:
  Temporary_directory() : Test_directory("normal_orientation_test_streaming_") {}
};

/// \brief An in-memory source; `on_read` (if set) is called before every read, with the
/// number of records delivered so far (it may throw).
class Vector_source
{
public:
  explicit Vector_source(std::vector<Point_record> records) : records_(std::move(records)) {}

  std::size_t read(std::vector<Point_record>& chunk, std::size_t maximum)
  {
    if (on_read)
      on_read(position_);
    const std::size_t n = std::min(maximum, records_.size() - position_);
    chunk.insert(chunk.end(), records_.begin() + std::ptrdiff_t(position_),
                 records_.begin() + std::ptrdiff_t(position_ + n));
    position_ += n;
    delivered_ += n;
    return n;
  }
  void rewind() { position_ = 0; }

  std::size_t position() const { return position_; }
  const std::vector<Point_record>& records() const { return records_; }
  /// the number of records delivered since the construction, over all passes
  std::uint64_t delivered() const { return delivered_; }

  std::function<void(std::size_t)> on_read;

private:
  std::vector<Point_record> records_;
  std::size_t position_ = 0;
  std::uint64_t delivered_ = 0;
};

Point_record make_record(const Vec& p, std::uint64_t index)
{
  Point_record r;
  for (int k = 0; k < 3; ++k) {
    r.position[k] = p[k];
    r.normal[k] = 0.25 * double(k + 1) - double(index % 7); // arbitrary payload
  }
  r.index = index;
  return r;
}

double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec cross(const Vec& a, const Vec& b)
{
  return {{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}};
}
Vec normalized(Vec a)
{
  const double l = std::sqrt(dot(a, a));
  for (double& x : a)
    x /= l;
  return a;
}

/// Gaussian cloud around `center`: standard deviation `sigma[k]` along the (orthonormal) direction `basis[k]`.
/// Input order shuffled; the indices are 0..n-1 in the shuffled order's origin (i.e. a permutation).
std::vector<Point_record> gaussian_cloud(std::size_t n, const Vec& center, const std::array<Vec, 3>& basis,
                                         const Vec& sigma, unsigned seed)
{
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0., 1.);
  std::vector<Point_record> records;
  records.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    Vec p = center;
    for (int k = 0; k < 3; ++k) {
      const double t = sigma[k] * gauss(rng);
      for (int j = 0; j < 3; ++j)
        p[j] += t * basis[k][j];
    }
    records.push_back(make_record(p, i));
  }
  std::shuffle(records.begin(), records.end(), rng);
  return records;
}

/// Orthonormal basis whose first vector is `d` (normalized).
std::array<Vec, 3> basis_along(const Vec& d)
{
  const Vec a = normalized(d);
  const Vec e1 = normalized(cross(a, std::abs(a[0]) < 0.9 ? Vec{{1., 0., 0.}} : Vec{{0., 1., 0.}}));
  return {{a, e1, cross(a, e1)}};
}

/// Checks that the frame is finite, orthonormal and right-handed.
void expect_valid_frame(const Sweep_frame& f)
{
  for (const Vec* d : {&f.axis, &f.u, &f.v})
    for (double x : *d)
      ASSERT_TRUE(std::isfinite(x));
  for (double x : f.centroid)
    ASSERT_TRUE(std::isfinite(x));
  EXPECT_NEAR(dot(f.axis, f.axis), 1., 1e-12);
  EXPECT_NEAR(dot(f.u, f.u), 1., 1e-12);
  EXPECT_NEAR(dot(f.v, f.v), 1., 1e-12);
  EXPECT_NEAR(dot(f.axis, f.u), 0., 1e-12);
  EXPECT_NEAR(dot(f.axis, f.v), 0., 1e-12);
  EXPECT_NEAR(dot(f.u, f.v), 0., 1e-12);
  EXPECT_NEAR(dot(cross(f.axis, f.u), f.v), 1., 1e-12);
  EXPECT_GE(f.variances[0], f.variances[1]);
  EXPECT_GE(f.variances[1], f.variances[2]);
  EXPECT_GE(f.variances[2], 0.);
}

/// The expected order: std::sort of everything in memory by (key, index), NaN keys last.
std::vector<Point_record> sorted_in_memory(std::vector<Point_record> records, const Sweep_frame& frame)
{
  std::sort(records.begin(), records.end(), [&](const Point_record& a, const Point_record& b) {
    const double ka = frame.key(a), kb = frame.key(b);
    const bool na = std::isnan(ka), nb = std::isnan(kb);
    if (na != nb)
      return nb;
    if (!na && ka != kb)
      return ka < kb;
    return a.index < b.index;
  });
  return records;
}

/// Reads everything from `reader` in chunks of `chunk` records.
template <class Reader>
std::vector<Point_record> read_all(Reader& reader, std::size_t chunk)
{
  std::vector<Point_record> out, part;
  for (;;) {
    part.clear();
    const std::size_t n = reader.read(part, chunk);
    EXPECT_EQ(n, part.size());
    if (n == 0)
      break;
    EXPECT_LE(n, chunk);
    out.insert(out.end(), part.begin(), part.end());
  }
  return out;
}

/// Bit-identical sequences of records.
void expect_identical(const std::vector<Point_record>& a, const std::vector<Point_record>& b)
{
  ASSERT_EQ(a.size(), b.size());
  if (!a.empty()) {
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(Point_record)), 0);
  }
}

ns::External_sort_options options_with(std::size_t records_per_run, const std::string& directory)
{
  ns::External_sort_options options;
  options.memory_budget = records_per_run * ns::External_sort_options::bytes_per_record;
  options.temporary_directory = directory;
  return options;
}

const Vec known_direction{{1., 2., -1.}};

std::vector<Point_record> elongated_cloud(std::size_t n = 50000, unsigned seed = 42)
{
  // far from the origin, to exercise the stable accumulation; a few exact duplicates
  // of positions (equal keys) to exercise the tie-break by index across runs
  std::vector<Point_record> records =
    gaussian_cloud(n, Vec{{1e6, -2e6, 3e5}}, basis_along(known_direction), Vec{{10., 2., 1.}}, seed);
  for (std::size_t i = 0; i + 1 < records.size(); i += 97)
    std::memcpy(records[i + 1].position, records[i].position, sizeof records[i].position);
  return records;
}

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

// ---------------------------------------------------------------------------
// (f) streaming_orient_normals: presorted input, component files, minimum
//     component size, progress and cancellation, bounded window
// ---------------------------------------------------------------------------

namespace NO = Normal_orientation;
using NO::test::Stream_options;
using NO::test::params;

/// a record with the given position, normal and index
Point_record oriented_record(const Vec& p, const Vec& n, std::uint64_t index)
{
  Point_record r;
  for (int k = 0; k < 3; ++k) {
    r.position[k] = p[k];
    r.normal[k] = n[k];
  }
  r.index = index;
  return r;
}

/// A cloud with its true outward normals (`truth[index]`), the records
/// carrying them with random signs, indices 0..n-1 in the order of `records`.
struct Test_cloud
{
  std::vector<Point_record> records;
  std::vector<Vec> truth;
  /// appends a point of true normal `n`, its sign drawn by `rng`
  void add(const Vec& p, const Vec& n, std::mt19937_64& rng)
  {
    const double s = (rng() & 1) ? 1.0 : -1.0;
    records.push_back(oriented_record(p, Vec{{s * n[0], s * n[1], s * n[2]}}, records.size()));
    truth.push_back(n);
  }
  /// the points of an ellipsoid of semi-axes a, b, c centred at `c0`
  void ellipsoid(std::size_t n, const Vec& c0, double a, double b, double c, std::mt19937_64& rng)
  {
    std::normal_distribution<double> g;
    for (std::size_t i = 0; i < n; ++i) {
      const Vec d = normalized(Vec{{g(rng), g(rng), g(rng)}});
      add(Vec{{c0[0] + a * d[0], c0[1] + b * d[1], c0[2] + c * d[2]}},
          normalized(Vec{{d[0] / a, d[1] / b, d[2] / c}}), rng);
    }
  }
  /// the number of records of `out` whose normal does not face outward
  std::size_t wrong(const std::vector<Point_record>& out) const
  {
    std::size_t w = 0;
    for (const Point_record& r : out)
      w += dot(Vec{{r.normal[0], r.normal[1], r.normal[2]}}, truth[r.index]) <= 0.0 ? 1 : 0;
    return w;
  }
};

/// `records` sorted by coordinate `axis` (ties: by index)
std::vector<Point_record> sorted_by(std::vector<Point_record> records, int axis)
{
  std::sort(records.begin(), records.end(), [axis](const Point_record& a, const Point_record& b) {
    return a.position[axis] != b.position[axis] ? a.position[axis] < b.position[axis] : a.index < b.index;
  });
  return records;
}

/// options whose temporary files all go to `directory`
Stream_options streaming_options_in(const std::string& directory)
{
  Stream_options options;
  options.temporary_directory = directory;
  return options;
}

/// runs streaming_orient_normals on `source`, collecting the sink's records
NO::Streaming_result stream(Vector_source& source, const Stream_options& options,
                            std::vector<Point_record>& out)
{
  out.clear();
  auto sink = [&out](const Point_record& r) { out.push_back(r); };
  return NO::streaming_orient_normals(source, sink, params(options));
}

/// writes `records` to the point file `path`
void write_cloud(const std::string& path, const std::vector<Point_record>& records)
{
  NO::IO::Point_stream_writer writer(path);
  writer.write(records);
  writer.commit();
}

/// reads every record of the point file `path`
std::vector<Point_record> read_cloud(const std::string& path)
{
  NO::IO::Point_stream_reader reader(path);
  return read_all(reader, 4096);
}

/// the positions of `records`, sorted (to compare clouds whatever their order)
std::vector<std::array<double, 6>> sorted_points(const std::vector<Point_record>& records)
{
  std::vector<std::array<double, 6>> v;
  for (const Point_record& r : records)
    v.push_back({{r.position[0], r.position[1], r.position[2], r.normal[0], r.normal[1], r.normal[2]}});
  std::sort(v.begin(), v.end());
  return v;
}

/// the bytes of the file `path`
std::string file_bytes(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

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
  // the record file, the refinement's last label file and the group files of a round
  EXPECT_LE(most_temporary, 2u + 3u);
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
                                       NO::Stage::SIGN,   NO::Stage::OUTPUT};
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
             NO::Stage::REFINE, NO::Stage::SIGN, NO::Stage::OUTPUT,
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

namespace {

/// \brief Lowers RLIMIT_FSIZE on demand; restores it, and SIGXFSZ, when destroyed.
class File_size_limit
{
public:
  File_size_limit()
  {
    m_ok = ::getrlimit(RLIMIT_FSIZE, &m_saved) == 0;
    m_old_handler = std::signal(SIGXFSZ, SIG_IGN);
  }
  ~File_size_limit()
  {
    if (m_ok)
      ::setrlimit(RLIMIT_FSIZE, &m_saved);
    std::signal(SIGXFSZ, m_old_handler);
  }
  File_size_limit(const File_size_limit&) = delete;
  File_size_limit& operator=(const File_size_limit&) = delete;
  /// false when the limit cannot be lowered, or is too low already for the test's files
  bool usable() const { return m_ok && (m_saved.rlim_cur == RLIM_INFINITY || m_saved.rlim_cur >= (rlim_t(1) << 30)); }
  /// from now on, no file grows beyond `bytes`
  void fill(rlim_t bytes)
  {
    rlimit limited = m_saved;
    limited.rlim_cur = bytes;
    ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &limited), 0);
    m_filled = true;
  }
  /// the former limit again
  void restore()
  {
    ::setrlimit(RLIMIT_FSIZE, &m_saved);
    m_filled = false;
  }
  bool filled() const { return m_filled; }

private:
  rlimit m_saved{};
  void (*m_old_handler)(int) = SIG_DFL;
  bool m_ok = false, m_filled = false;
};

/// every file and directory under `root`, recursively, as paths relative to it
std::vector<std::string> tree(const std::string& root)
{
  std::vector<std::string> names;
  for (const auto& entry : fs::recursive_directory_iterator(root))
    names.push_back(fs::relative(entry.path(), root).string());
  std::sort(names.begin(), names.end());
  return names;
}

} // namespace

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

// ---------------------------------------------------------------------------
// (h) the refinement: windowed passes of single-point moves and
//     re-segmentation, solved again (streaming/Refinement.h)
// ---------------------------------------------------------------------------

namespace {

/// A random signed graph on points in a sweep order: each point has up to
/// `degree` earlier neighbours, at most `span` points back, with weights
/// that are floats (so that the in-core incidence lists hold them exactly).
struct Window_graph
{
  std::vector<std::vector<ns::Earlier_edge>> earlier; // per point
  std::uint64_t span = 0;

  Window_graph() = default;

  Window_graph(std::size_t n, std::size_t degree, std::uint32_t max_offset, std::mt19937_64& rng)
  {
    std::uniform_real_distribution<float> w(-1.f, 1.f);
    earlier.resize(n);
    for (std::size_t i = 1; i < n; ++i) {
      std::vector<std::uint32_t> offsets;
      for (std::size_t t = 0; t < degree; ++t)
        offsets.push_back(1 + std::uint32_t(rng() % std::min<std::uint64_t>(i, max_offset)));
      std::sort(offsets.begin(), offsets.end());
      offsets.erase(std::unique(offsets.begin(), offsets.end()), offsets.end());
      for (const std::uint32_t o : offsets) {
        earlier[i].push_back(ns::Earlier_edge{o, w(rng)});
        span = std::max<std::uint64_t>(span, o);
      }
    }
  }
  /// the same graph as an in-core problem
  NO::internal::Array_problem problem() const
  {
    NO::internal::Array_problem p;
    p.number_of_vertices = earlier.size();
    for (std::size_t i = 0; i < earlier.size(); ++i)
      for (const ns::Earlier_edge& e : earlier[i]) {
        p.tail.push_back(std::uint32_t(i - e.offset));
        p.head.push_back(std::uint32_t(i));
        p.weight.push_back(double(e.weight));
      }
    return p;
  }
};

/// one pass of `Relabelling_window` over `g` from `labels`; returns the labels
/// and the segments that come out, and the report
NO::streaming::internal::Relabelling_report window_pass(const Window_graph& g, const std::vector<NO::Label>& labels,
                                                          NO::Segmenter* segmenter, std::vector<NO::Label>& out,
                                                          std::vector<std::uint32_t>& segments)
{
  ns::internal::Relabelling_window pass(g.span, segmenter, true);
  out.clear();
  segments.clear();
  auto sink = [&](NO::Label l, std::uint32_t s) {
    out.push_back(l);
    segments.push_back(s);
  };
  for (std::size_t i = 0; i < labels.size(); ++i)
    pass.push(labels[i], g.earlier[i].data(), g.earlier[i].size(), sink);
  pass.finish(sink);
  return pass.report();
}

} // namespace

// A pass of the window is exactly one sweep of single-vertex moves of the
// in-core solvers (internal::improve_by_sweeps) in the sweep order, whatever
// the span, and it measures the energies before and after exactly.
TEST(Streaming_refinement, WindowPassIsOneSweepOfSingleVertexMoves)
{
  std::mt19937_64 rng(41);
  for (const std::uint32_t max_offset : {1u, 7u, 300u}) {
    SCOPED_TRACE(max_offset);
    const Window_graph g(5000, 6, max_offset, rng);
    const NO::internal::Array_problem p = g.problem();
    const NO::internal::Incidence incidence(p);
    std::vector<NO::Label> labels(g.earlier.size());
    for (NO::Label& l : labels)
      l = (rng() & 1) ? NO::Label(1) : NO::Label(-1);
    std::vector<NO::Label> expected = labels;
    const std::size_t moves = NO::internal::improve_by_sweeps(incidence, {}, expected, 1);
    ASSERT_GT(moves, 0u);
    std::vector<NO::Label> out;
    std::vector<std::uint32_t> segments;
    const auto report = window_pass(g, labels, nullptr, out, segments);
    EXPECT_EQ(out, expected);
    EXPECT_EQ(report.moves, moves);
    EXPECT_EQ(report.points, labels.size());
    EXPECT_NEAR(report.energy_before, p.energy(labels), 1e-9 * p.energy(labels));
    EXPECT_NEAR(report.energy_after, p.energy(expected), 1e-9 * p.energy(labels));
    EXPECT_LT(report.energy_after, report.energy_before);
    // an edge farther back than the span is refused
    ns::internal::Relabelling_window narrow(0, nullptr);
    const ns::Earlier_edge far{1, 0.5f};
    auto ignore = [](NO::Label, std::uint32_t) {};
    narrow.push(1, nullptr, 0, ignore);
    EXPECT_THROW(narrow.push(1, &far, 1, ignore), std::invalid_argument);
  }
}

// A wrong patch, consistent inside, that single-point moves cannot flip (each
// of its points agrees with most of its neighbours) is flipped by one round:
// the re-segmentation around the current labelling makes it a segment of its
// own, and the solve of the new segment graph flips it.
TEST(Streaming_refinement, OneRoundFlipsAPlantedWrongPatch)
{
  const std::size_t side = 60, n = side * side;
  Window_graph g;
  g.earlier.assign(n, {});
  std::vector<NO::Label> labels(n, NO::Label(1));
  for (std::size_t y = 0; y < side; ++y)
    for (std::size_t x = 0; x < side; ++x) {
      const std::size_t i = y * side + x; // the sweep order: row after row
      if (x > 0)
        g.earlier[i].push_back(ns::Earlier_edge{1, 1.0f});
      if (y > 0)
        g.earlier[i].push_back(ns::Earlier_edge{std::uint32_t(side), 1.0f});
      if (x >= 20 && x < 35 && y >= 25 && y < 40)
        labels[i] = NO::Label(-1); // the planted patch, 15 x 15 points
    }
  g.span = side;
  const NO::internal::Array_problem p = g.problem();
  const double planted = p.energy(labels);
  EXPECT_EQ(planted, 4.0 * 15.0); // its border

  // single-point moves alone leave the patch where it is
  std::vector<NO::Label> moved;
  std::vector<std::uint32_t> segments;
  auto r = window_pass(g, labels, nullptr, moved, segments);
  EXPECT_EQ(moved, labels);
  EXPECT_EQ(r.moves, 0u);

  // one round: moves, re-segmentation (segments of at most 1000 points), solve
  NO::Segmentation_thresholds theta{0.5, 0.5, 1000};
  NO::Segmenter segmenter(theta, false);
  r = window_pass(g, labels, &segmenter, moved, segments);
  EXPECT_EQ(segmenter.point_energy(std::vector<NO::Label>(segmenter.number_of_segments(), NO::Label(1))), planted);
  double change = 0.0;
  const std::vector<NO::Label> x = ns::internal::solve_segment_graph(segmenter, NO::Qpbo_i_solver(), change);
  EXPECT_EQ(change, -planted);
  EXPECT_EQ(segmenter.point_energy(x), 0.0);
  std::vector<NO::Label> refined(n);
  for (std::size_t i = 0; i < n; ++i)
    refined[i] = NO::Label(moved[i] * x[segments[i]]);
  EXPECT_EQ(p.energy(refined), 0.0);
  EXPECT_TRUE(std::all_of(refined.begin(), refined.end(), [&](NO::Label l) { return l == refined[0]; }));
  // the warm-started QPBO-I alone finds it too, and never ends above the start
  const std::vector<NO::Label> warm = ns::internal::improve_segment_labelling(segmenter);
  EXPECT_EQ(ns::internal::segment_energy_change(segmenter, warm), -planted);
}

namespace {

/// An ellipsoid whose normals are turned far from the truth (Gaussian noise
/// of 0.6 per component), and a few far points: a cloud whose labellings all
/// contradict many edges, so that the refinement has work to do.
Test_cloud frustrated_cloud(std::size_t n, std::mt19937_64& rng)
{
  Test_cloud cloud;
  cloud.ellipsoid(n, Vec{{0., 0., 0.}}, 3., 1., 0.8, rng);
  std::normal_distribution<double> g(0.0, 0.6);
  for (Point_record& r : cloud.records)
    for (double& c : r.normal)
      c += g(rng);
  for (int i = 0; i < 5; ++i)
    cloud.add(Vec{{10. + 2. * i, 5., 5.}}, Vec{{0., 0., 1.}}, rng);
  std::shuffle(cloud.records.begin(), cloud.records.end(), rng);
  return cloud;
}

/// the energy, in core, of the labels of the streamed `out` (relative to the
/// input normals of `in`), on the graph of `build_neighbor_graph()` with k and r
double in_core_energy(const std::vector<Point_record>& in, const std::vector<Point_record>& out, unsigned int k,
                      double radius)
{
  typedef CGAL::Exact_predicates_inexact_constructions_kernel K;
  std::vector<K::Point_3> points;
  std::vector<K::Vector_3> normals;
  std::vector<std::size_t> position(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    points.emplace_back(in[i].position[0], in[i].position[1], in[i].position[2]);
    normals.emplace_back(in[i].normal[0], in[i].normal[1], in[i].normal[2]);
    position[in[i].index] = i;
  }
  NO::Neighbor_graph graph;
  NO::build_neighbor_graph<CGAL::Sequential_tag, K>(points, normals, k, radius, NO::Hoppe_criterion(), graph,
                                                    NO::Progress_reporter());
  std::vector<NO::Label> labels(in.size(), NO::Label(1));
  for (const Point_record& r : out) {
    const Point_record& a = in[position[r.index]];
    const double d = r.normal[0] * a.normal[0] + r.normal[1] * a.normal[1] + r.normal[2] * a.normal[2];
    labels[position[r.index]] = d < 0.0 ? NO::Label(-1) : NO::Label(1);
  }
  return NO::energy(graph, get(&NO::Neighbor_edge::weight, graph), CGAL::make_property_map(labels));
}

} // namespace

// On a frustrated cloud: the refinement never raises the energy of the point
// graph, lowers it here, and reports it exactly (the energy of its output
// computed in core, on the same graph); without refinement the energy of the
// segment graph's solution is reported as well; every round count gives the
// same start; the output is the same for any thread count and batch size;
// no temporary file is left.
TEST(Streaming_refinement, NeverRaisesTheEnergyAndReportsItExactly)
{
  Temporary_directory directory;
  std::mt19937_64 rng(43);
  const Test_cloud cloud = frustrated_cloud(20000, rng);
  const std::size_t n = cloud.records.size();
  double before = -1.0, unrefined = 0.0, one_round = 0.0;
  std::vector<Point_record> reference;
  for (const unsigned int rounds : {0u, 1u, 3u}) {
    SCOPED_TRACE(rounds);
    Vector_source source(cloud.records);
    Stream_options options = streaming_options_in(directory.path());
    options.refinement_rounds = rounds;
    options.radius = 0.12;
    options.batch_size = 3000;
    std::vector<Point_record> out;
    const NO::Streaming_result r = stream(source, options, out);
    ASSERT_EQ(out.size(), n);
    EXPECT_GT(r.energy_before_refinement, 0.0);
    if (before < 0.0)
      before = r.energy_before_refinement;
    EXPECT_EQ(r.energy_before_refinement, before); // the same sweep and solve
    EXPECT_LE(r.energy_after_refinement, r.energy_before_refinement);
    const double exact = in_core_energy(cloud.records, out, options.number_of_neighbors, r.neighbor_radius);
    EXPECT_NEAR(r.energy_after_refinement, exact, 1e-9 * exact);
    if (rounds == 0) {
      EXPECT_EQ(r.energy_after_refinement, r.energy_before_refinement);
      EXPECT_EQ(r.refinement_moves, 0u);
      unrefined = r.energy_after_refinement;
    } else {
      EXPECT_LT(r.energy_after_refinement, unrefined); // there is work to do here
      EXPECT_GT(r.refinement_rounds_accepted, 0u);
      EXPECT_GT(r.edge_span, 0u);
      EXPECT_LT(r.edge_span, n / 4);
      if (rounds == 1)
        one_round = r.energy_after_refinement;
      else // the same first round, then rounds that never raise the energy
        EXPECT_LE(r.energy_after_refinement, one_round);
    }
    std::cout << "[ info ] " << rounds << " rounds: energy " << r.energy_before_refinement << " -> "
              << r.energy_after_refinement << ", " << r.refinement_rounds_accepted << " rounds accepted, "
              << r.refinement_moves << " moves, edge span " << r.edge_span << "\n";
    if (rounds == 3)
      reference = out;
    EXPECT_EQ(directory.count(), 0u);
  }
  // the same bytes with one thread (no prefetching) and another batch size
  {
    Vector_source source(cloud.records);
    Stream_options options = streaming_options_in(directory.path());
    options.refinement_rounds = 3;
    options.radius = 0.12;
    options.batch_size = 700;
    std::vector<Point_record> out;
    auto sink = [&out](const Point_record& r) { out.push_back(r); };
    NO::streaming_orient_normals<CGAL::Sequential_tag>(source, sink, params(options));
    expect_identical(out, reference);
  }
  EXPECT_EQ(directory.count(), 0u);
}

// The refinement is skipped when no edge contradicts the labelling (energy 0):
// the stage is reported, no pass is made, the output is that without it.
TEST(Streaming_refinement, SkippedWhenNothingContradicts)
{
  Temporary_directory directory;
  std::mt19937_64 rng(47);
  Test_cloud cloud;
  cloud.ellipsoid(10000, Vec{{0., 0., 0.}}, 2., 1., 1., rng);
  std::vector<Point_record> with, without;
  Stream_options options = streaming_options_in(directory.path());
  std::vector<NO::Stage> stages;
  options.callback = [&stages](const NO::Progress_info& p) {
    if (stages.empty() || stages.back() != p.stage)
      stages.push_back(p.stage);
    return true;
  };
  Vector_source source(cloud.records);
  const NO::Streaming_result r = stream(source, options, with);
  EXPECT_EQ(r.energy_before_refinement, 0.0);
  EXPECT_EQ(r.energy_after_refinement, 0.0);
  EXPECT_EQ(r.refinement_moves, 0u);
  EXPECT_NE(std::find(stages.begin(), stages.end(), NO::Stage::REFINE), stages.end());
  options.refinement_rounds = 0;
  options.callback = nullptr;
  stream(source, options, without);
  expect_identical(with, without);
  EXPECT_EQ(cloud.wrong(with), 0u);
  EXPECT_EQ(directory.count(), 0u);
}

// The disk fills up during the refinement (its label files), or the run is
// cancelled there: one clear error, nothing handed to the sink, no temporary
// file left (the record file, the edge file and the label files).
TEST(Streaming_refinement, FailuresAndCancellationLeaveNothing)
{
  Temporary_directory temporary;
  std::mt19937_64 rng(53);
  const Test_cloud cloud = frustrated_cloud(40000, rng);
  const std::uint64_t n = cloud.records.size();
  Stream_options options = streaming_options_in(temporary.path());
  options.radius = 0.12;
  options.batch_size = 2000;
  std::vector<Point_record> out;
  {
    Stream_options co = options;
    co.callback = [&](const NO::Progress_info& p) {
      return !(p.stage == NO::Stage::REFINE && p.done >= n);
    };
    Vector_source source(cloud.records);
    EXPECT_TRUE(stream(source, co, out).interrupted);
    EXPECT_TRUE(out.empty());
    EXPECT_EQ(temporary.count(), 0u);
  }
  File_size_limit limit;
  if (!limit.usable())
    GTEST_SKIP() << "RLIMIT_FSIZE cannot be lowered here";
  bool reached = false;
  options.callback = [&](const NO::Progress_info& p) {
    if (p.stage == NO::Stage::REFINE && p.done >= n / 2 && !limit.filled()) {
      reached = true;
      limit.fill(64 * 1024); // a label file holds 4 bytes a point
    }
    return true;
  };
  Vector_source source(cloud.records);
  std::string message;
  try {
    stream(source, options, out);
  } catch (const std::system_error& e) {
    message = e.what();
    EXPECT_EQ(e.code(), std::errc::file_too_large) << e.what();
  }
  limit.restore();
  EXPECT_TRUE(reached);
  EXPECT_NE(message.find("cannot write the temporary file"), std::string::npos) << message;
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(temporary.count(), 0u);
}
