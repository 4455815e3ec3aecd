// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file Streaming_test_support.h
/// \brief The helpers of the streaming tests (test_streaming*.cpp): temporary
/// directories, sources over vectors, generated clouds, and the runs of
/// streaming_orient_normals() whose outputs they compare.
#ifndef NORMAL_ORIENTATION_TEST_STREAMING_TEST_SUPPORT_H
#define NORMAL_ORIENTATION_TEST_STREAMING_TEST_SUPPORT_H

#include <Normal_orientation/internal/Graph_reduction.h>
#include <Normal_orientation/streaming/Point_range.h>
#include <Normal_orientation/streaming/Refinement.h>
#include <Normal_orientation/streaming/external_sort.h>
#include <Normal_orientation/streaming_orient_normals.h>


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

#include "Streaming_test_options.h"
#include "Test_directory.h"

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

inline Point_record make_record(const Vec& p, std::uint64_t index)
{
  Point_record r;
  for (int k = 0; k < 3; ++k) {
    r.position[k] = p[k];
    r.normal[k] = 0.25 * double(k + 1) - double(index % 7); // arbitrary payload
  }
  r.index = index;
  return r;
}

inline double dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
inline Vec cross(const Vec& a, const Vec& b)
{
  return {{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}};
}
inline Vec normalized(Vec a)
{
  const double l = std::sqrt(dot(a, a));
  for (double& x : a)
    x /= l;
  return a;
}

/// Gaussian cloud around `center`: standard deviation `sigma[k]` along the (orthonormal) direction `basis[k]`.
/// Input order shuffled; the indices are 0..n-1 in the shuffled order's origin (i.e. a permutation).
inline std::vector<Point_record> gaussian_cloud(std::size_t n, const Vec& center, const std::array<Vec, 3>& basis,
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
inline std::array<Vec, 3> basis_along(const Vec& d)
{
  const Vec a = normalized(d);
  const Vec e1 = normalized(cross(a, std::abs(a[0]) < 0.9 ? Vec{{1., 0., 0.}} : Vec{{0., 1., 0.}}));
  return {{a, e1, cross(a, e1)}};
}

/// Checks that the frame is finite, orthonormal and right-handed.
inline void expect_valid_frame(const Sweep_frame& f)
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
inline std::vector<Point_record> sorted_in_memory(std::vector<Point_record> records, const Sweep_frame& frame)
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
inline void expect_identical(const std::vector<Point_record>& a, const std::vector<Point_record>& b)
{
  ASSERT_EQ(a.size(), b.size());
  if (!a.empty()) {
    EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(Point_record)), 0);
  }
}

inline ns::External_sort_options options_with(std::size_t records_per_run, const std::string& directory)
{
  ns::External_sort_options options;
  options.memory_budget = records_per_run * ns::External_sort_options::bytes_per_record;
  options.temporary_directory = directory;
  return options;
}

const Vec known_direction{{1., 2., -1.}};

inline std::vector<Point_record> elongated_cloud(std::size_t n = 50000, unsigned seed = 42)
{
  // far from the origin, to exercise the stable accumulation; a few exact duplicates
  // of positions (equal keys) to exercise the tie-break by index across runs
  std::vector<Point_record> records =
    gaussian_cloud(n, Vec{{1e6, -2e6, 3e5}}, basis_along(known_direction), Vec{{10., 2., 1.}}, seed);
  for (std::size_t i = 0; i + 1 < records.size(); i += 97)
    std::memcpy(records[i + 1].position, records[i].position, sizeof records[i].position);
  return records;
}


namespace NO = Normal_orientation;
using NO::test::Stream_options;
using NO::test::params;

/// a record with the given position, normal and index
inline Point_record oriented_record(const Vec& p, const Vec& n, std::uint64_t index)
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
inline std::vector<Point_record> sorted_by(std::vector<Point_record> records, int axis)
{
  std::sort(records.begin(), records.end(), [axis](const Point_record& a, const Point_record& b) {
    return a.position[axis] != b.position[axis] ? a.position[axis] < b.position[axis] : a.index < b.index;
  });
  return records;
}

/// options whose temporary files all go to `directory`
inline Stream_options streaming_options_in(const std::string& directory)
{
  Stream_options options;
  options.temporary_directory = directory;
  return options;
}

/// runs streaming_orient_normals on `source`, collecting the sink's records
inline NO::Streaming_result stream(Vector_source& source, const Stream_options& options,
                            std::vector<Point_record>& out)
{
  out.clear();
  auto sink = [&out](const Point_record& r) { out.push_back(r); };
  return NO::streaming_orient_normals(source, sink, params(options));
}

/// writes `records` to the point file `path`
inline void write_cloud(const std::string& path, const std::vector<Point_record>& records)
{
  NO::IO::Point_stream_writer writer(path);
  writer.write(records);
  writer.commit();
}

/// reads every record of the point file `path`
inline std::vector<Point_record> read_cloud(const std::string& path)
{
  NO::IO::Point_stream_reader reader(path);
  return read_all(reader, 4096);
}

/// the positions of `records`, sorted (to compare clouds whatever their order)
inline std::vector<std::array<double, 6>> sorted_points(const std::vector<Point_record>& records)
{
  std::vector<std::array<double, 6>> v;
  for (const Point_record& r : records)
    v.push_back({{r.position[0], r.position[1], r.position[2], r.normal[0], r.normal[1], r.normal[2]}});
  std::sort(v.begin(), v.end());
  return v;
}

/// the bytes of the file `path`
inline std::string file_bytes(const std::string& path)
{
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}


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
inline std::vector<std::string> tree(const std::string& root)
{
  std::vector<std::string> names;
  for (const auto& entry : fs::recursive_directory_iterator(root))
    names.push_back(fs::relative(entry.path(), root).string());
  std::sort(names.begin(), names.end());
  return names;
}

} // namespace

#endif // NORMAL_ORIENTATION_TEST_STREAMING_TEST_SUPPORT_H
