// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
// Tests of the global sign stage (part of the test_winding_number program):
// the adjoint of the field against per-patch fields, decide_patch_signs on
// known configurations, and orient_normals on clouds whose local energy has a
// wrong minimum (nested, touching and flat-faced closed objects), with the
// stage and without it; open sheets are left as they were.

#include <Normal_orientation/Exterior_visibility.h>
#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/internal/Canopy_rule.h>
#include <Normal_orientation/internal/Core_global_sign.h>
#include <Normal_orientation/internal/Frustrated_islands.h>
#include <Normal_orientation/internal/Layer_edges.h>
#include <Normal_orientation/internal/Seen_side_rules.h>
#include <Normal_orientation/internal/Two_layer_fit.h>
#include <Normal_orientation/internal/Undone_moves.h>
#include <Normal_orientation/orient_normals.h>
#include <Normal_orientation/streaming/Patch_units.h>
#include <Normal_orientation/streaming/Unit_islands.h>

#include <CGAL/pca_estimate_normals.h>

#include "Counting_solver.h"
#include "Hard_shapes.h"
#include "Synthetic_shapes.h"

#include <gtest/gtest.h>

#include <CGAL/property_map.h>

#include <boost/range/iterator_range.hpp>

#ifdef CGAL_LINKED_WITH_TBB
#include <tbb/global_control.h>
#endif

#include <algorithm>
#include <array>
#include <initializer_list>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numeric>
#include <random>
#include <string>
#include <stdexcept>
#include <utility>
#include <vector>

namespace NO = Normal_orientation;
using NO::test::Kernel;
using NO::test::Point;
using NO::test::Sample;
using NO::test::Vector;
using NO::test::noisy_cloud;

namespace {

typedef std::pair<Point, Vector> Point_with_normal;

/// the named parameters of a vector of Point_with_normal
auto pwn_params()
{
  return NO::parameters::point_map(CGAL::First_of_pair_property_map<Point_with_normal>())
    .normal_map(CGAL::Second_of_pair_property_map<Point_with_normal>());
}

/// orient_normals with the given global stage and Hoppe's criterion; returns the wrong count
std::size_t orient_and_count(const std::vector<Sample>& truth, NO::Global_orientation global, unsigned seed,
                             NO::Orientation_result* result = nullptr)
{
  std::mt19937_64 rng(seed);
  std::vector<Point_with_normal> cloud = NO::test::unoriented(truth, rng);
  // Hoppe's criterion: the local energy whose failures the stage is for
  const NO::Orientation_result r =
    NO::orient_normals(cloud, pwn_params().global_orientation(global).flip_criterion(NO::Hoppe_criterion()));
  if (result)
    *result = r;
  return NO::test::count_wrong(truth, cloud);
}

std::vector<Sample> hollow_ball(std::size_t n, std::mt19937_64& rng)
{
  std::vector<Sample> s = NO::test::sphere(n * 3 / 5, rng, Point(0, 0, 0), 1.0);
  for (const Sample& t : NO::test::sphere(n - s.size(), rng, Point(0, 0, 0), 0.75))
    s.push_back({t.p, -t.n}); // the inner wall faces the cavity
  return s;
}

std::vector<Sample> touching_spheres(std::size_t n, std::mt19937_64& rng)
{
  std::vector<Sample> s = NO::test::sphere(n / 2, rng, Point(-1, 0, 0), 1.0);
  for (const Sample& t : NO::test::sphere(n - n / 2, rng, Point(1, 0, 0), 1.0))
    s.push_back(t);
  return s;
}

/// A unit sphere of 8000 samples (seed 5) cut into octants (patch: x < 0 adds
/// 1, y < 0 adds 2, z < 0 adds 4), the octants `inverted` facing inward, with
/// the samples' areas.
struct Octant_sphere
{
  std::vector<Sample> samples; ///< with their outward normals
  std::vector<Point> points;
  std::vector<Vector> normals; ///< outward but in the inverted octants
  std::vector<std::uint32_t> patch;
  std::vector<double> areas;
};

Octant_sphere octant_sphere(std::initializer_list<std::uint32_t> inverted)
{
  std::mt19937_64 rng(5);
  Octant_sphere o;
  o.samples = NO::test::sphere(8000, rng);
  for (const Sample& t : o.samples) {
    const std::uint32_t P = (t.p.x() < 0 ? 1 : 0) + (t.p.y() < 0 ? 2 : 0) + (t.p.z() < 0 ? 4 : 0);
    const bool in = std::find(inverted.begin(), inverted.end(), P) != inverted.end();
    o.points.push_back(t.p);
    o.normals.push_back(in ? -t.n : t.n);
    o.patch.push_back(P);
  }
  o.areas = NO::estimate_point_areas(o.points, o.normals);
  return o;
}

/// an open spherical cap (z >= 0.5: a quarter of the sphere's area) with outward normals
std::vector<Sample> cap(std::size_t n, std::mt19937_64& rng)
{
  std::vector<Sample> s;
  for (const Sample& t : NO::test::sphere(5 * n, rng))
    if (t.p.z() >= 0.5 && s.size() < n)
      s.push_back(t);
  return s;
}

} // namespace

TEST(Winding_number_field, MomentDerivativesMatchTheFieldsOfPatches)
{
  // sum_{i in P} moment(i) . v_i = sum_j c_j w_P(p_j), with w_P the field of P alone
  std::mt19937_64 rng(3);
  const std::vector<Sample> s = NO::test::torus(6000, rng);
  std::vector<Point> p;
  std::vector<Vector> n;
  for (const Sample& t : s) {
    p.push_back(t.p);
    n.push_back(t.n);
  }
  const std::vector<double> a = NO::estimate_point_areas(p, n);
  NO::Winding_number_field<Kernel> field;
  field.build(p, n, a);
  std::vector<double> c(p.size());
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (double& x : c)
    x = u(rng) * 1e-3;
  std::vector<Vector> v, coarse;
  field.moment_derivatives<CGAL::Sequential_tag>(c, v);
  // the screening of the global stage opens fewer nodes: coarser, still close
  const double screening = NO::Global_sign_options().screening_opening_ratio;
  ASSERT_LT(screening, field.opening_ratio());
  field.moment_derivatives<CGAL::Sequential_tag>(c, coarse, screening);
  for (int side = 0; side < 2; ++side) { // P: the points with x < 0, then those with x >= 0
    std::vector<Point> pp;
    std::vector<Vector> pn;
    std::vector<double> pa;
    double adjoint = 0.0, screened = 0.0;
    for (std::size_t i = 0; i < p.size(); ++i)
      if ((p[i].x() < 0.0) == (side == 0)) {
        pp.push_back(p[i]);
        pn.push_back(n[i]);
        pa.push_back(a[i]);
        adjoint += field.moment(i) * v[i];
        screened += field.moment(i) * coarse[i];
      }
    NO::Winding_number_field<Kernel> own;
    own.build(pp, pn, pa);
    double direct = 0.0, scale = 0.0;
    for (std::size_t j = 0; j < p.size(); ++j) {
      const double w = own.direct_value(p[j]);
      direct += c[j] * w;
      scale += std::abs(c[j] * w);
    }
    EXPECT_NEAR(adjoint, direct, 0.01 * scale) << "side " << side;
    EXPECT_NEAR(screened, direct, 0.03 * scale) << "side " << side; // (measured: 0.4% and 0.9%)
  }
  // the same bits for 1 and 2 threads
#ifdef CGAL_LINKED_WITH_TBB
  std::vector<Vector> v1, v2;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    field.moment_derivatives<CGAL::Parallel_tag>(c, v1);
  }
  {
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    field.moment_derivatives<CGAL::Parallel_tag>(c, v2);
  }
  ASSERT_EQ(v1.size(), v2.size());
  for (std::size_t i = 0; i < v1.size(); ++i)
    ASSERT_TRUE(v1[i] == v2[i]) << i;
#endif
  EXPECT_THROW(field.moment_derivatives(std::vector<double>(3, 0.0), v), std::invalid_argument);
  EXPECT_THROW(field.moment_derivatives(c, v, 0.0), std::invalid_argument);
  EXPECT_THROW(field.moment_derivatives(c, v, std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
}

TEST(Global_sign, DecidePatchSignsFixesInvertedPatchesOfAClosedSurface)
{
  // A sphere cut into octants; three of them are inverted.  The stage negates
  // exactly those, and a fixed inverted octant stays as it is.
  const Octant_sphere o = octant_sphere({1, 2, 7});
  const std::vector<Sample>& s = o.samples;
  const std::vector<Point>& p = o.points;
  const std::vector<Vector>& n = o.normals;
  const std::vector<std::uint32_t>& patch = o.patch;
  const std::vector<double>& a = o.areas;
  const std::vector<std::uint32_t> component(8, 0);
  std::vector<char> flip;
  const NO::Global_sign_summary r = NO::decide_patch_signs(p, n, a, patch, component, {}, flip);
  EXPECT_EQ(flip, std::vector<char>({0, 1, 1, 0, 0, 0, 0, 1}));
  EXPECT_EQ(r.patches_flipped, 3u);
  EXPECT_EQ(r.closed_components, 1u);
  EXPECT_GT(r.closedness, 0.9);
  EXPECT_LT(r.energy_after, 0.05 * r.energy_before);
  std::vector<char> fixed(8, 0);
  fixed[7] = 1;
  NO::decide_patch_signs(p, n, a, patch, component, fixed, flip);
  EXPECT_EQ(flip, std::vector<char>({0, 1, 1, 0, 0, 0, 0, 0}));
  // a whole inverted sphere (one patch) is negated: w was -1/2 on it
  std::vector<Vector> inward;
  for (const Sample& t : s)
    inward.push_back(-t.n);
  NO::decide_patch_signs(p, inward, a, std::vector<std::uint32_t>(p.size(), 0), std::vector<std::uint32_t>(1, 0),
                         {}, flip);
  EXPECT_EQ(flip, std::vector<char>({1}));
  // errors
  EXPECT_THROW(NO::decide_patch_signs(p, n, std::vector<double>(3, 1.0), patch, component, {}, flip),
               std::invalid_argument);
  std::vector<std::uint32_t> bad = patch;
  bad[0] = 8;
  EXPECT_THROW(NO::decide_patch_signs(p, n, a, bad, component, {}, flip), std::invalid_argument);
  EXPECT_THROW(NO::decide_patch_signs(p, n, a, patch, component, std::vector<char>(3, 0), flip),
               std::invalid_argument);
}

namespace {

/// A sampled sphere sorted by z (segments grow from earlier neighbours: an
/// order along the sphere, as the drivers' spatial order) and its k nearest
/// neighbours, brute force, with the weights n_i . n_j > 0.
std::vector<Sample> sorted_sphere(std::size_t n, std::size_t k, NO::internal::Array_problem& problem)
{
  std::mt19937_64 rng(3);
  std::vector<Sample> s = NO::test::sphere(n, rng);
  std::sort(s.begin(), s.end(), [](const Sample& a, const Sample& b) { return a.p.z() > b.p.z(); });
  problem.number_of_vertices = s.size();
  for (std::size_t i = 0; i < s.size(); ++i) {
    std::vector<std::pair<double, std::uint32_t>> d;
    for (std::size_t j = 0; j < s.size(); ++j)
      if (j != i)
        d.emplace_back(CGAL::squared_distance(s[i].p, s[j].p), std::uint32_t(j));
    std::partial_sort(d.begin(), d.begin() + k, d.end());
    for (std::size_t t = 0; t < k; ++t) {
      problem.tail.push_back(std::uint32_t(i));
      problem.head.push_back(d[t].second);
      problem.weight.push_back(s[i].n * s[d[t].second].n);
    }
  }
  return s;
}

} // namespace

TEST(Global_sign, FrustratedIslandsAreNegatedWhereTheFieldAgrees)
{
  // A sampled sphere whose cap (1.5% of its area) has the other sign from
  // the rest: its border weighs wholly against it.  When the cap is the
  // inverted part, w is 1/2 - f on the sphere (f its area fraction), and
  // negating it brings w to 1/2: it is negated.  When the rest is inverted,
  // negating the cap brings w from -1/2 + f to -1/2, so the field rises and
  // the cap stays.  Points to keep keep their island.
  NO::internal::Array_problem problem;
  const std::vector<Sample> s = sorted_sphere(3000, 10, problem);
  const std::size_t n = s.size();
  const NO::internal::Incidence inc(problem);
  std::vector<Point> points;
  for (const Sample& t : s)
    points.push_back(t.p);
  const std::vector<double> areas(n, 4.0 * M_PI / double(n));
  std::vector<std::uint32_t> index(n);
  std::iota(index.begin(), index.end(), 0u);
  auto cap = [&](std::size_t i) { return s[i].p.z() > 0.97; };
  auto run = [&](int cap_label, const std::vector<char>& keep, std::vector<NO::Label>& labels) {
    labels.assign(n, NO::Label(-cap_label));
    for (std::size_t i = 0; i < n; ++i)
      if (cap(i))
        labels[i] = NO::Label(cap_label);
    std::vector<Vector> oriented;
    for (std::size_t i = 0; i < n; ++i)
      oriented.push_back(labels[i] > 0 ? s[i].n : -s[i].n);
    NO::Winding_patch_signs<Kernel> search;
    search.build(points, oriented, areas);
    const double before = search.energy();
    const std::size_t negated =
      NO::internal::negate_frustrated_islands<CGAL::Sequential_tag, Kernel>(inc, index, keep, search, labels);
    EXPECT_LE(search.energy(), before + 1e-12);
    return negated;
  };
  std::size_t in_cap = 0;
  for (std::size_t i = 0; i < n; ++i)
    in_cap += cap(i) ? 1 : 0;
  ASSERT_GT(in_cap, 20u);
  std::vector<NO::Label> labels;
  EXPECT_EQ(run(-1, {}, labels), 1u); // the inverted cap is negated
  EXPECT_EQ(std::count(labels.begin(), labels.end(), NO::Label(1)), std::ptrdiff_t(n));
  EXPECT_EQ(run(1, {}, labels), 0u); // the right cap of an inverted sphere stays
  for (std::size_t i = 0; i < n; ++i)
    EXPECT_EQ(labels[i], cap(i) ? 1 : -1);
  std::vector<char> keep(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    if (cap(i)) {
      keep[i] = 1; // (one point of the cap)
      break;
    }
  EXPECT_EQ(run(-1, keep, labels), 0u); // a kept point keeps its island
  // the rule of an island: most of its border against it, less than half the points
  EXPECT_TRUE(NO::internal::is_island(9.0, 1.0, 10, 100));
  EXPECT_FALSE(NO::internal::is_island(7.0, 3.0, 10, 100));
  EXPECT_FALSE(NO::internal::is_island(9.0, 1.0, 50, 100));
}

TEST(Global_sign, SheetsMostlyUnseenAreLeftToTheWindingNumber)
{
  // Four sheets of ten samples of area 1: sheet 0 seen over 6 samples
  // (60%), sheet 1 over 7, sheet 2 over all, sheet 3 over none.  Each seen
  // sample votes -1 (faces away).  The rule keeps sheets 0 and 3 from the
  // sheets' tier; visibility_flips() would turn all but sheet 3.
  std::vector<double> vote, areas;
  std::vector<std::uint32_t> group;
  const int seen[4] = {6, 7, 10, 0};
  for (std::uint32_t g = 0; g < 4; ++g)
    for (int j = 0; j < 10; ++j) {
      vote.push_back(j < seen[g] ? -1.0 : 0.0);
      areas.push_back(1.0);
      group.push_back(g);
    }
  const std::vector<char> unseen = NO::internal::mostly_unseen(vote, areas, group, 5);
  EXPECT_EQ(unseen, (std::vector<char>{1, 0, 0, 1, 0})); // (group 4 has no samples)
  const std::vector<char> flips = NO::visibility_flips(vote, areas, group, std::vector<char>(5, 1));
  EXPECT_EQ(flips, (std::vector<char>{1, 1, 1, 0, 0}));
}

namespace {
// The incidence of a chain of `n` points, edges of weight 1.
NO::internal::Incidence chain_incidence(std::size_t n)
{
  NO::internal::Array_problem problem;
  problem.number_of_vertices = n;
  for (std::size_t i = 0; i + 1 < n; ++i) {
    problem.tail.push_back(std::uint32_t(i));
    problem.head.push_back(std::uint32_t(i + 1));
    problem.weight.push_back(1.0);
  }
  return NO::internal::Incidence(problem);
}
} // namespace

TEST(Global_sign, MovesThatTheStageMostlyUndidAreUndoneInFull)
{
  // A chain of 40 points.  The solver moved three runs of it: A (5-14),
  // B (20-29) and C (32-35).  The stage negated 6 points of A, 5 of B and
  // all of C: only A, more than half undone, is completed.  A kept point
  // keeps its move as it is, and without a start nothing moves.
  const std::size_t n = 40;
  const NO::internal::Incidence inc = chain_incidence(n);
  std::vector<char> moved(n, 0);
  auto in = [](std::size_t i, std::size_t a, std::size_t b) { return a <= i && i <= b; };
  for (std::size_t i = 0; i < n; ++i)
    moved[i] = char(in(i, 5, 14) || in(i, 20, 29) || in(i, 32, 35));
  std::vector<NO::Label> before(n, NO::Label(1));
  for (std::size_t i = 0; i < n; ++i)
    if (moved[i])
      before[i] = NO::Label(-1);
  auto stage = [&]() {
    std::vector<NO::Label> labels = before;
    for (std::size_t i = 0; i < n; ++i)
      if (in(i, 5, 10) || in(i, 20, 24) || in(i, 32, 35))
        labels[i] = NO::Label(-labels[i]);
    return labels;
  };
  std::vector<NO::Label> labels = stage();
  EXPECT_EQ(NO::internal::complete_undone_moves(inc, moved, {}, before, labels), 1u);
  for (std::size_t i = 0; i < n; ++i) {
    const bool negated = in(i, 5, 14) || in(i, 20, 24) || in(i, 32, 35);
    EXPECT_EQ(labels[i], negated ? NO::Label(-before[i]) : before[i]) << i;
  }
  std::vector<char> keep(n, 0);
  keep[14] = 1;
  labels = stage();
  const std::vector<NO::Label> staged = labels;
  EXPECT_EQ(NO::internal::complete_undone_moves(inc, moved, keep, before, labels), 0u);
  EXPECT_EQ(labels, staged);
  EXPECT_EQ(NO::internal::complete_undone_moves(inc, std::vector<char>(), {}, before, labels), 0u);
  EXPECT_EQ(labels, staged);
}

TEST(Global_sign, MovesThatTheStageNegatedInFullAreTakenBackBeforeItRunsAgain)
{
  // The chain of the test above, after the stage and the completion: A
  // (5-14) and C (32-35) negated in full, B (20-29) in part; the stage also
  // negated points 0-2, outside every move.  Only B is left as a move.
  const std::size_t n = 40;
  const NO::internal::Incidence inc = chain_incidence(n);
  auto in = [](std::size_t i, std::size_t a, std::size_t b) { return a <= i && i <= b; };
  std::vector<char> moved(n, 0);
  std::vector<NO::Label> before(n, NO::Label(1)), after(n);
  for (std::size_t i = 0; i < n; ++i) {
    moved[i] = char(in(i, 5, 14) || in(i, 20, 29) || in(i, 32, 35));
    before[i] = NO::Label(i % 3 == 0 ? -1 : 1); // (any start)
    const bool negated = in(i, 0, 2) || in(i, 5, 14) || in(i, 20, 24) || in(i, 32, 35);
    after[i] = negated ? NO::Label(-before[i]) : before[i];
  }
  std::vector<char> remaining;
  EXPECT_EQ(NO::internal::rejected_moves(inc, moved, {}, before, after, remaining), 2u);
  ASSERT_EQ(remaining.size(), n);
  for (std::size_t i = 0; i < n; ++i)
    EXPECT_EQ(remaining[i], char(in(i, 20, 29))) << i;
  // A kept point keeps its move: C stays.
  std::vector<char> keep(n, 0);
  keep[33] = 1;
  EXPECT_EQ(NO::internal::rejected_moves(inc, moved, keep, before, after, remaining), 1u);
  EXPECT_EQ(remaining[33], 1);
  EXPECT_EQ(remaining[7], 0);
  // When A and C leave one point each as it was, no move is negated in full.
  std::vector<NO::Label> partly = after;
  partly[14] = before[14];
  partly[35] = before[35];
  EXPECT_EQ(NO::internal::rejected_moves(inc, moved, {}, before, partly, remaining), 0u);
  EXPECT_TRUE(remaining.empty());
  // Without a start, nothing was moved.
  EXPECT_EQ(NO::internal::rejected_moves(inc, std::vector<char>(), {}, before, after, remaining), 0u);
  EXPECT_TRUE(remaining.empty());
  // The same moves on a chain long enough that they hold fewer than
  // `rejected_move_share` of its points: too small to run again.
  const std::size_t long_n = std::size_t(24.0 / NO::internal::rejected_move_share) + 100;
  std::vector<char> long_moved(long_n, 0);
  std::vector<NO::Label> long_before(long_n, NO::Label(1)), long_after(long_n, NO::Label(1));
  for (std::size_t i = 0; i < n; ++i) {
    long_moved[i] = moved[i];
    long_before[i] = before[i];
    long_after[i] = after[i];
  }
  EXPECT_EQ(NO::internal::rejected_moves(chain_incidence(long_n), long_moved, {}, long_before, long_after, remaining), 0u);
  EXPECT_TRUE(remaining.empty());
}

TEST(Global_sign, StreamedIslandsAreNegatedOnUnitsAsInCore)
{
  // The sphere of FrustratedIslandsAreNegatedWhereTheFieldAgrees, pushed
  // into patch units in its order with its earlier edges: the islands of
  // the units follow the same rule.
  NO::internal::Array_problem problem;
  const std::vector<Sample> s = sorted_sphere(3000, 10, problem);
  const std::size_t n = s.size();
  std::vector<std::vector<NO::streaming::Earlier_edge>> earlier(n);
  std::uint64_t span = 1;
  for (std::size_t t = 0; t < problem.tail.size(); ++t) { // (each edge once, at its later end)
    const std::uint32_t a = std::min(problem.tail[t], problem.head[t]), b = std::max(problem.tail[t], problem.head[t]);
    auto& list = earlier[b];
    if (std::none_of(list.begin(), list.end(), [&](const auto& e) { return e.offset == b - a; }))
      list.push_back({b - a, float(problem.weight[t])});
    span = std::max<std::uint64_t>(span, b - a);
  }
  auto cap = [&](std::size_t i) { return s[i].p.z() > 0.97; };
  std::vector<Point> points;
  for (const Sample& t : s)
    points.push_back(t.p);
  const std::vector<double> areas(n, 4.0 * M_PI / double(n));
  auto run = [&](int cap_sign, std::vector<char>& point_negated) {
    // pushed with the cap of sign cap_sign, the rest the other; each point
    // its own sample
    NO::streaming::internal::Patch_units units(span, 0.2);
    std::vector<std::uint32_t> unit(n);
    std::vector<Vector> oriented;
    for (std::size_t i = 0; i < n; ++i) {
      const int sign = cap(i) ? cap_sign : -cap_sign;
      oriented.push_back(sign > 0 ? s[i].n : -s[i].n);
      unit[i] = units.push(s[i].p, oriented.back(), cap(i) ? 1u : 0u, 0u, earlier[i].data(), earlier[i].size(), sign);
    }
    EXPECT_FALSE(units.overflowed());
    NO::Winding_patch_signs<Kernel> search;
    search.build(points, oriented, areas);
    const double before = search.energy();
    std::vector<char> negated(units.number_of_units(), 0);
    point_negated.assign(n, 0);
    const std::size_t count = NO::streaming::internal::negate_unit_islands<CGAL::Sequential_tag, Kernel>(
      units, n, unit, search, negated, point_negated);
    EXPECT_LE(search.energy(), before + 1e-12);
    for (std::size_t i = 0; i < n; ++i)
      EXPECT_EQ(point_negated[i], negated[unit[i]]);
    return count;
  };
  std::vector<char> negated;
  EXPECT_EQ(run(-1, negated), 1u); // the inverted cap is negated, and only it
  for (std::size_t i = 0; i < n; ++i)
    EXPECT_EQ(negated[i], char(cap(i))) << i;
  EXPECT_EQ(run(1, negated), 0u); // the right cap of an inverted sphere stays
  EXPECT_EQ(std::count(negated.begin(), negated.end(), char(1)), 0);
}

TEST(Global_sign, WholeSheetsNeedLessEvidence)
{
  // One inverted octant of a sphere lowers E by about 0.2 per unit of its
  // area when negated: below the default bound (0.3), above that of a level
  // of whole sheets (winding_level_options(true)).
  const Octant_sphere o = octant_sphere({5});
  const std::vector<std::uint32_t> component(8, 0);
  std::vector<char> flip;
  NO::decide_patch_signs(o.points, o.normals, o.areas, o.patch, component, {}, flip,
                         NO::internal::winding_level_options(false));
  EXPECT_EQ(flip, std::vector<char>(8, 0));
  NO::decide_patch_signs(o.points, o.normals, o.areas, o.patch, component, {}, flip,
                         NO::internal::winding_level_options(true));
  EXPECT_EQ(flip, std::vector<char>({0, 0, 0, 0, 0, 1, 0, 0}));
}

TEST(Global_sign, HollowBallInnerWallFacesTheCavity)
{
  std::mt19937_64 rng(11);
  const std::vector<Sample> s = hollow_ball(20000, rng);
  NO::Orientation_result r;
  EXPECT_EQ(orient_and_count(s, NO::Global_orientation::WINDING, 1, &r), 0u);
  EXPECT_TRUE(r.global.ran);
  EXPECT_EQ(r.global.closed_components, 2u);
  // without the stage, the outward vote turns the inner wall outward
  EXPECT_GT(orient_and_count(s, NO::Global_orientation::NONE, 1), s.size() / 4);
}

TEST(Global_sign, TouchingSpheresAndFlatFacedBoxes)
{
  std::mt19937_64 rng(12);
  const std::vector<Sample> two = touching_spheres(20000, rng);
  // what is left is the tangent zone, where the points of both spheres interleave
  EXPECT_LE(orient_and_count(two, NO::Global_orientation::WINDING, 2), two.size() / 16);
  EXPECT_GT(orient_and_count(two, NO::Global_orientation::NONE, 2), two.size() / 4);
  const std::vector<Sample> plate = NO::test::box(20000, rng, 1.0, 1.0, 0.2);
  EXPECT_LE(orient_and_count(plate, NO::Global_orientation::WINDING, 3), plate.size() / 1000);
}

TEST(Global_sign, OpenSheetsAreLeftAsTheyWere)
{
  std::mt19937_64 rng(13);
  const std::vector<Sample> s = cap(8000, rng);
  NO::Orientation_result with, without;
  const std::size_t a = orient_and_count(s, NO::Global_orientation::WINDING, 4, &with);
  const std::size_t b = orient_and_count(s, NO::Global_orientation::NONE, 4, &without);
  EXPECT_EQ(a, b);
  EXPECT_TRUE(with.global.ran);
  EXPECT_FALSE(without.global.ran);
  EXPECT_EQ(with.global.open_components, 1u);
  EXPECT_EQ(with.global.closed_components, 0u);
  EXPECT_EQ(with.global.points_flipped, 0u);
}

TEST(Global_sign, DefaultIsWindingUnlessTheUserSaysWhichSide)
{
  std::mt19937_64 rng(14);
  const std::vector<Sample> s = hollow_ball(6000, rng);
  std::vector<Point_with_normal> cloud = NO::test::unoriented(s, rng);
  const auto np = pwn_params();
  const NO::Orientation_result r = NO::orient_normals(cloud, np);
  EXPECT_TRUE(r.global.ran);
  EXPECT_TRUE(r.global.visibility);
  EXPECT_EQ(NO::test::count_wrong(s, cloud), 0u);
  EXPECT_FALSE(NO::orient_normals(cloud, np.component_sign(NO::Viewpoint_component_sign(0.0, 0.0, 0.0))).global.ran);
  EXPECT_TRUE(NO::orient_normals(cloud, np.component_sign(NO::Viewpoint_component_sign(0.0, 0.0, 0.0))
                                          .global_orientation(NO::Global_orientation::WINDING))
                .global.ran);
}

TEST(Global_sign, SameOutputForOneAndTwoThreads)
{
  std::mt19937_64 rng(15);
  const std::vector<Sample> s = touching_spheres(12000, rng);
  std::mt19937_64 r1(9), r2(9);
  std::vector<Point_with_normal> a = NO::test::unoriented(s, r1), b = NO::test::unoriented(s, r2);
  const auto np = pwn_params();
  NO::orient_normals(a, np.number_of_threads(1));
  NO::orient_normals(b, np.number_of_threads(2));
  EXPECT_TRUE(a == b);
}

namespace {

/// the mean of `vote`, weighted by `areas`
double mean_vote(const std::vector<double>& vote, const std::vector<double>& areas)
{
  double s = 0.0, a = 0.0;
  for (std::size_t j = 0; j < vote.size(); ++j) {
    s += areas[j] * vote[j];
    a += areas[j];
  }
  return s / a;
}

/// the votes of exterior_visibility() for samples with their normals times `sign`
std::vector<double> visibility_votes(const std::vector<Sample>& s, double sign, std::vector<double>& areas,
                                     const NO::Exterior_visibility_options& options = {})
{
  std::vector<Point> p;
  std::vector<Vector> n;
  for (const Sample& t : s) {
    p.push_back(t.p);
    n.push_back(sign * t.n);
  }
  areas = NO::estimate_point_areas<CGAL::Sequential_tag>(p, n);
  return NO::exterior_visibility<CGAL::Sequential_tag>(p, n, areas, options);
}

/// `s` turned so that its +z axis becomes +y: (x, y, z) -> (x, z, -y)
std::vector<Sample> z_up_to_y_up(const std::vector<Sample>& s)
{
  std::vector<Sample> out;
  for (const Sample& t : s)
    out.push_back({Point(t.p.x(), t.p.z(), -t.p.y()), Vector(t.n.x(), t.n.z(), -t.n.y())});
  return out;
}

} // namespace

TEST(Exterior_visibility, VotesOfAClosedSurfaceAndOfASheet)
{
  std::mt19937_64 rng(16);
  const std::vector<Sample> ball = NO::test::sphere(4000, rng);
  std::vector<double> areas;
  // outward normals face every view that sees them (a few samples at the
  // bottom, seen only from below and at a graze, may be hidden in all 32)
  std::vector<double> out = visibility_votes(ball, 1.0, areas), in = visibility_votes(ball, -1.0, areas);
  std::size_t unseen = 0;
  for (std::size_t j = 0; j < ball.size(); ++j) {
    EXPECT_GE(out[j], 0.0);
    EXPECT_DOUBLE_EQ(in[j], -out[j]);
    unseen += out[j] == 0.0 ? 1 : 0;
  }
  EXPECT_LE(unseen, ball.size() / 100);
  EXPECT_GT(mean_vote(out, areas), 0.15);
  // a flat sheet, normals up: seen from both sides, up only by the up direction
  std::vector<Sample> sheet;
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 4000; ++i)
    sheet.push_back({Point(u(rng), u(rng), 0.0), Vector(0, 0, 1)});
  NO::Exterior_visibility_options o;
  EXPECT_GT(mean_vote(visibility_votes(sheet, 1.0, areas, o), areas), 0.2);
  o.up = {{0.0, 0.0, -2.0}};
  EXPECT_LT(mean_vote(visibility_votes(sheet, 1.0, areas, o), areas), -0.2);
  o.up = {{0.0, 0.0, 0.0}};
  EXPECT_LT(std::abs(mean_vote(visibility_votes(sheet, 1.0, areas, o), areas)), 0.02);
  // the same votes for any thread count
  std::vector<Point> p;
  std::vector<Vector> n;
  for (const Sample& t : ball) {
    p.push_back(t.p);
    n.push_back(t.n);
  }
  areas = NO::estimate_point_areas<CGAL::Sequential_tag>(p, n);
  const std::vector<double> one = NO::exterior_visibility<CGAL::Sequential_tag>(p, n, areas);
  tbb::global_control two_threads(tbb::global_control::max_allowed_parallelism, 2);
  EXPECT_TRUE(one == NO::exterior_visibility<CGAL::Parallel_tag>(p, n, areas));
}

TEST(Exterior_visibility, OneDrawingGivesBothWeightings)
{
  // the even votes drawn with the weighted ones are those of the views
  // without an up direction, bit for bit, also when views below weigh 0
  std::mt19937_64 rng(17);
  std::vector<Sample> cup = NO::test::sphere(3000, rng);
  cup.erase(std::remove_if(cup.begin(), cup.end(), [](const Sample& t) { return t.p.z() > 0.5; }), cup.end());
  std::vector<Point> p;
  std::vector<Vector> n;
  for (const Sample& t : cup) {
    p.push_back(t.p);
    n.push_back(t.n);
  }
  const std::vector<double> areas = NO::estimate_point_areas<CGAL::Sequential_tag>(p, n);
  for (double below : {0.1, 0.0}) {
    NO::Exterior_visibility_options weighted, even;
    weighted.below_horizon_weight = below;
    even.up = {{0.0, 0.0, 0.0}};
    std::vector<double> even_votes;
    const std::vector<double> votes =
      NO::internal::visibility_votes<CGAL::Parallel_tag>(p, n, areas, weighted, &even_votes);
    EXPECT_TRUE(votes == NO::exterior_visibility<CGAL::Sequential_tag>(p, n, areas, weighted)) << below;
    EXPECT_TRUE(even_votes == NO::exterior_visibility<CGAL::Sequential_tag>(p, n, areas, even)) << below;
    EXPECT_FALSE(votes == even_votes) << below; // (the open cup faces up: the weights matter)
  }
}

TEST(Exterior_visibility, BadInputThrows)
{
  std::vector<Point> p = {Point(0, 0, 0), Point(1, 0, 0)};
  std::vector<Vector> n = {Vector(0, 0, 1), Vector(0, 0, 1)};
  std::vector<double> a = {1.0, 1.0};
  EXPECT_THROW(NO::exterior_visibility(p, n, std::vector<double>{1.0}), std::invalid_argument);
  EXPECT_THROW(NO::exterior_visibility(p, n, std::vector<double>{1.0, std::nan("")}), std::invalid_argument);
  EXPECT_THROW(NO::exterior_visibility(p, n, std::vector<double>{1.0, -1.0}), std::invalid_argument);
  NO::Exterior_visibility_options o;
  o.number_of_directions = 0;
  EXPECT_THROW(NO::exterior_visibility(p, n, a, o), std::invalid_argument);
  o = NO::Exterior_visibility_options();
  o.up[1] = std::nan("");
  EXPECT_THROW(NO::exterior_visibility(p, n, a, o), std::invalid_argument);
  o = NO::Exterior_visibility_options();
  o.below_horizon_weight = -0.5;
  EXPECT_THROW(NO::exterior_visibility(p, n, a, o), std::invalid_argument);
  EXPECT_THROW(NO::visibility_flips({0.1, -0.1}, a, {0, 2}, {1, 1}), std::invalid_argument);
  EXPECT_EQ(NO::visibility_flips({0.1, -0.1}, a, {0, 1}, {1, 1}), (std::vector<char>{0, 1}));
  EXPECT_EQ(NO::visibility_flips({0.1, -0.1}, a, {0, 1}, {1, 0}), (std::vector<char>{0, 0}));
  const auto np = pwn_params();
  std::vector<Point_with_normal> cloud = {{Point(0, 0, 0), Vector(0, 0, 1)}, {Point(1, 0, 0), Vector(0, 0, 1)}};
  EXPECT_THROW(NO::orient_normals(cloud, np.up_direction(Vector(0, std::nan(""), 1))), std::invalid_argument);
}

TEST(Global_sign, OpenScansFaceTheSideTheyWereSeenFrom)
{
  // A terrain with buildings (no floors, no ground under them): the winding
  // number alone leaves it as the outward vote made it, ground and roofs
  // down; exterior visibility turns it up, from random signs and from its own
  // consistent normals alike.
  std::mt19937_64 rng(17);
  const std::vector<Sample> tile = NO::hard_shapes::terrain_with_buildings(20000, rng);
  const double n = double(tile.size());
  NO::Orientation_result r;
  EXPECT_LE(double(orient_and_count(tile, NO::Global_orientation::VISIBILITY_AND_WINDING, 22, &r)) / n, 0.01);
  EXPECT_TRUE(r.global.visibility);
  EXPECT_GE(double(orient_and_count(tile, NO::Global_orientation::WINDING, 22)) / n, 0.5);
  std::vector<Point_with_normal> given;
  for (const Sample& t : tile)
    given.emplace_back(t.p, t.n);
  const auto np = pwn_params();
  EXPECT_TRUE(NO::orient_normals(given, np).global.visibility); // the default
  EXPECT_LE(double(NO::test::count_wrong(tile, given)) / n, 0.01);
  // the same tile with +y up: right when the up direction says so
  const std::vector<Sample> turned = z_up_to_y_up(tile);
  std::mt19937_64 signs(23);
  std::vector<Point_with_normal> cloud = NO::test::unoriented(turned, signs);
  NO::orient_normals(cloud, np.up_direction(Vector(0, 1, 0)));
  EXPECT_LE(double(NO::test::count_wrong(turned, cloud)) / n, 0.01);
  // an urban tile whose alleys the winding number mistakes for closed walls
  std::mt19937_64 g(1);
  const std::vector<Sample> city = NO::hard_shapes::city_block(20000, g);
  EXPECT_LE(double(orient_and_count(city, NO::Global_orientation::VISIBILITY_AND_WINDING, 24, &r)) / n, 0.05);
  EXPECT_GE(r.global.seen_components_flipped, 1u);
  EXPECT_GE(double(orient_and_count(city, NO::Global_orientation::WINDING, 24)) / n, 0.3);
  // the other open scans and the closed classes keep what the winding number gets
  for (const char* name : {"open_box", "single_view_scan", "hollow_ball", "bored_cylinder"}) {
    std::mt19937_64 g(1);
    const std::vector<Sample> s = NO::hard_shapes::hard_shape(name, 20000, g);
    EXPECT_LE(double(orient_and_count(s, NO::Global_orientation::VISIBILITY_AND_WINDING, 21)) / double(s.size()),
              0.01)
      << name;
  }
}

TEST(Global_sign, HardShapesOfTheFailureClasses)
{
  // Clouds of Hard_shapes.h (true normals, random signs): the share of wrong
  // normals with the stage must be at most `after`; without it, at least
  // `before` (the failure the shape was made for), where given.
  struct Case
  {
    const char* name;
    double after, before;
  };
  const Case cases[] = {{"touching_ellipsoids", 0.03, 0.3}, {"touching_boxes", 0.15, 0.3},
                        {"hollow_ball", 0.0, 0.3},          {"bored_cylinder", 0.01, 0.2},
                        {"open_box", 0.01, 0.2},            {"single_view_scan", 0.0, -1.0}};
  for (const Case& c : cases) {
    std::mt19937_64 rng(1);
    const std::vector<Sample> s = NO::hard_shapes::hard_shape(c.name, 20000, rng);
    const double n = double(s.size());
    const double after = double(orient_and_count(s, NO::Global_orientation::WINDING, 21)) / n;
    const double before = double(orient_and_count(s, NO::Global_orientation::NONE, 21)) / n;
    std::printf("%-20s wrong without the stage %6.2f%%, with it %6.2f%%\n", c.name, 100.0 * before, 100.0 * after);
    EXPECT_LE(after, c.after) << c.name;
    if (c.before >= 0.0) {
      EXPECT_GE(before, c.before) << c.name;
    }
  }
}

namespace {

/// `n` points on a torus of radii `R` and `r` (area-uniform), outward normals
std::vector<Sample> torus(std::size_t n, double R, double r, std::mt19937_64& rng)
{
  std::uniform_real_distribution<double> u(0.0, 2.0 * M_PI), w(0.0, 1.0);
  std::vector<Sample> s;
  while (s.size() < n) {
    const double a = u(rng), b = u(rng);
    if (w(rng) * (R + r) > R + r * std::cos(b)) // the area element is (R + r cos b) da db
      continue;
    const Vector normal(std::cos(a) * std::cos(b), std::sin(a) * std::cos(b), std::sin(b));
    s.push_back({Point((R + r * std::cos(b)) * std::cos(a), (R + r * std::cos(b)) * std::sin(a), r * std::sin(b)),
                 normal});
  }
  return s;
}

/// the share of wrong normals among those whose line is within 60 degrees of the truth
double clear_wrong(const std::vector<Point_with_normal>& cloud, const std::vector<Sample>& truth)
{
  std::size_t clear = 0, wrong = 0;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const double c = cloud[i].second * truth[i].n / std::sqrt(cloud[i].second.squared_length());
    if (std::abs(c) >= 0.5) {
      ++clear;
      wrong += c <= 0.0;
    }
  }
  return clear > 0 ? double(wrong) / double(clear) : 0.0;
}

} // namespace

TEST(Exterior_visibility, TopViewFacingAndDownwardTopFlips)
{
  // A sphere seen from straight above: the samples of its upper half face
  // up (n . u > 0, outward normals), those of its lower half are hidden (0).
  std::mt19937_64 rng(31);
  const std::vector<Sample> s = NO::test::sphere(6000, rng);
  std::vector<Point> points;
  std::vector<Vector> normals, inverted;
  for (const Sample& t : s) {
    points.push_back(t.p);
    normals.push_back(t.n);
    inverted.push_back(-t.n);
  }
  const std::vector<double> areas = NO::estimate_point_areas<CGAL::Sequential_tag>(points, normals);
  const std::vector<double> facing = NO::top_view_facing<CGAL::Sequential_tag>(points, normals, areas);
  std::size_t cap = 0, seen_cap = 0;
  for (std::size_t j = 0; j < s.size(); ++j) {
    if (s[j].p.z() < -0.2) {
      EXPECT_EQ(facing[j], 0.0) << j; // hidden by the upper half
    } else if (facing[j] != 0.0) {
      EXPECT_NEAR(facing[j], s[j].n.z(), 1e-9) << j; // n . u where seen
    }
    if (s[j].n.z() >= 0.8660254) { // the top cap, within 30 degrees of horizontal
      ++cap;
      seen_cap += facing[j] > 0.0 ? 1 : 0;
    }
  }
  EXPECT_GE(double(seen_cap), 0.9 * double(cap));
  // Whole (one group): right side up, nothing; inverted, negated; not
  // eligible or a top too small, nothing.
  const std::vector<std::uint32_t> one(s.size(), 0);
  EXPECT_EQ(NO::downward_top_flips(facing, areas, one, {1}), std::vector<char>{0});
  const std::vector<double> down = NO::top_view_facing<CGAL::Sequential_tag>(points, inverted, areas);
  EXPECT_EQ(NO::downward_top_flips(down, areas, one, {1}), std::vector<char>{1});
  EXPECT_EQ(NO::downward_top_flips(down, areas, one, {0}), std::vector<char>{0});
  EXPECT_EQ(NO::downward_top_flips(down, areas, one, {1}, 0.1), std::vector<char>{0}); // the cap holds 6.7%
  // Two groups (the upper and the lower half) with the upper inverted:
  // only the upper one is negated (the lower one has no top surface).
  std::vector<std::uint32_t> halves(s.size());
  std::vector<Vector> mixed(normals);
  for (std::size_t j = 0; j < s.size(); ++j) {
    halves[j] = s[j].p.z() > 0.0 ? 0 : 1;
    if (halves[j] == 0)
      mixed[j] = -mixed[j];
  }
  const std::vector<double> f2 = NO::top_view_facing<CGAL::Sequential_tag>(points, mixed, areas);
  EXPECT_EQ(NO::downward_top_flips(f2, areas, halves, {1, 1}), (std::vector<char>{1, 0}));
  // No up direction: no facing, no flip.
  NO::Exterior_visibility_options none;
  none.up = {{0.0, 0.0, 0.0}};
  for (double f : NO::top_view_facing<CGAL::Sequential_tag>(points, inverted, areas, none))
    ASSERT_EQ(f, 0.0);
  // Bad input.
  EXPECT_THROW(NO::top_view_facing(points, std::vector<Vector>(3), areas), std::invalid_argument);
  std::vector<double> bad(areas);
  bad[5] = -1.0;
  EXPECT_THROW(NO::top_view_facing(points, normals, bad), std::invalid_argument);
  EXPECT_THROW(NO::downward_top_flips(facing, areas, std::vector<std::uint32_t>(s.size(), 3), {1}),
               std::invalid_argument);
  EXPECT_THROW(NO::downward_top_flips(facing, std::vector<double>(2), one, {1}), std::invalid_argument);
}

TEST(Global_sign, ClosedSurfacesReadClosedAndSheetsOpen)
{
  // Two components: a sphere (closed, outward normals) and, far from it, a
  // flat disc (open, normals up).
  std::mt19937_64 rng(47);
  std::vector<Point> points;
  std::vector<Vector> normals;
  std::vector<std::uint32_t> component;
  for (const Sample& t : NO::test::sphere(4000, rng)) {
    points.push_back(t.p);
    normals.push_back(t.n);
    component.push_back(0);
  }
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  while (component.size() < 6000) {
    const double x = u(rng), y = u(rng);
    if (x * x + y * y <= 1.0) {
      points.push_back(Point(10.0 + x, y, 0.0));
      normals.push_back(Vector(0, 0, 1));
      component.push_back(1);
    }
  }
  const std::vector<double> areas = NO::estimate_point_areas<CGAL::Sequential_tag>(points, normals);
  NO::Winding_patch_signs<Kernel> search;
  search.build(points, normals, areas);
  EXPECT_EQ(NO::internal::groups_read_closed(search.values(), areas, component, 2, NO::Global_sign_options()),
            (std::vector<char>{1, 0}));
  // Inverted, the sphere does not read closed (w near -1/2 on its surface).
  std::vector<Vector> inverted(normals);
  for (std::size_t j = 0; j < inverted.size(); ++j)
    if (component[j] == 0)
      inverted[j] = -inverted[j];
  NO::Winding_patch_signs<Kernel> flipped;
  flipped.build(points, inverted, areas);
  EXPECT_EQ(NO::internal::groups_read_closed(flipped.values(), areas, component, 2, NO::Global_sign_options()),
            (std::vector<char>{0, 0}));
}

TEST(Global_sign, TopRuleReadsTheSamplesWhoseNormalsAgree)
{
  // Component 0: a square of ground, normals down (inverted), under a slab
  // of scatter over three quarters of it (a canopy: random normals, most of
  // them up).  Component 1: the same with the ground's normals up.
  // Component 2, far away: the scatter alone, normals mostly down.
  std::mt19937_64 rng(53);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Point> points;
  std::vector<Vector> normals;
  std::vector<std::uint32_t> component;
  auto scatter_normal = [&](double bias) {
    const double x = u(rng), y = u(rng), z = u(rng);
    return Vector(x, y, z + bias);
  };
  for (std::uint32_t c = 0; c < 2; ++c) {
    const double x0 = 10.0 * c;
    for (int i = 0; i < 2000; ++i) {
      const double x = u(rng), y = u(rng);
      points.push_back(Point(x0 + x, y, 0.0));
      normals.push_back(Vector(0, 0, c == 0 ? -1.0 : 1.0));
      component.push_back(c);
    }
    for (int i = 0; i < 3000; ++i) {
      const double x = u(rng), y = u(rng), z = u(rng);
      points.push_back(Point(x0 - 0.25 + 0.75 * x, y, 0.3 + 0.1 * z));
      normals.push_back(scatter_normal(1.5));
      component.push_back(c);
    }
  }
  for (int i = 0; i < 3000; ++i) {
    const double x = u(rng), y = u(rng), z = u(rng);
    points.push_back(Point(19.75 + 0.75 * x, y, 0.3 + 0.1 * z));
    normals.push_back(scatter_normal(-1.5));
    component.push_back(2);
  }
  const std::vector<char> agree = NO::internal::normals_agree<CGAL::Sequential_tag>(points, normals);
  std::size_t ground_agree = 0, scatter_agree = 0;
  for (std::size_t j = 0; j < points.size(); ++j)
    (points[j].z() == 0.0 ? ground_agree : scatter_agree) += agree[j] ? 1 : 0;
  EXPECT_GE(ground_agree, 3800u);  // of 4000 (a few have scatter among their neighbours)
  EXPECT_LE(scatter_agree, 450u);  // of 9000
  EXPECT_EQ(agree, NO::internal::normals_agree<CGAL::Parallel_tag>(points, normals));
  const std::vector<double> areas = NO::estimate_point_areas<CGAL::Sequential_tag>(points, normals);
  // All samples counted, the scatter's top outvotes the ground it hides.
  const std::vector<double> facing = NO::top_view_facing<CGAL::Sequential_tag>(points, normals, areas);
  EXPECT_EQ(NO::downward_top_flips(facing, areas, component, {1, 1, 1}), (std::vector<char>{0, 0, 1}));
  // The rule reads the samples that agree (the ground) where they hold a tenth
  // of the area; the scatter alone, all of its samples.
  NO::internal::Global_settings settings;
  settings.orientation = NO::Global_orientation::VISIBILITY_AND_WINDING;
  EXPECT_EQ(NO::internal::top_side_flips<CGAL::Sequential_tag>(points, normals, areas, component, 3, {}, settings),
            (std::vector<char>{1, 0, 1}));
  EXPECT_EQ(NO::internal::top_side_flips<CGAL::Sequential_tag>(points, normals, areas, component, 3, {1, 0, 0},
                                                               settings),
            (std::vector<char>{0, 0, 1}));
  settings.orientation = NO::Global_orientation::WINDING;
  EXPECT_EQ(NO::internal::top_side_flips<CGAL::Sequential_tag>(points, normals, areas, component, 3, {}, settings),
            (std::vector<char>{0, 0, 0}));
  // The test that spares reading agreement: component 1's top faces up
  // (nothing to flip); a flip under any counting that keeps a tenth of the
  // area implies it passes.
  EXPECT_TRUE(NO::internal::top_flip_possible(facing, areas, component, {1, 0, 0}));
  EXPECT_TRUE(NO::internal::top_flip_possible(facing, areas, component, {0, 0, 1}));
  EXPECT_FALSE(NO::internal::top_flip_possible(facing, areas, component, {0, 1, 0}));
  std::bernoulli_distribution keep(0.15);
  std::size_t flips = 0;
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<double> counted(areas);
    for (double& a : counted)
      a = keep(rng) ? a : 0.0;
    const std::vector<char> flip = NO::downward_top_flips(facing, counted, component, {1, 1, 1});
    for (std::uint32_t c = 0; c < 3; ++c) {
      std::vector<char> only(3, 0);
      only[c] = 1;
      flips += flip[c] ? 1 : 0;
      if (flip[c]) {
        EXPECT_TRUE(NO::internal::top_flip_possible(facing, areas, component, only)) << "trial " << trial;
      }
    }
  }
  EXPECT_GE(flips, 40u); // (the implication was tested)
}

TEST(Global_sign, TopSurfacesOfScenesFaceUp)
{
  // A street between two facades, PCA normals (the creases round, so ground
  // and facades make one sheet): the solver, visibility and the winding
  // number (which takes the U for part of a closed surface) leave it inside
  // out; its top surface, the ground, faces down, and the last rule
  // negates it.  Without an up direction the rule is off.
  std::mt19937_64 rng(41);
  const std::vector<Sample> street = NO::hard_shapes::street_canyon(20000, rng);
  const double n = double(street.size());
  const auto np = pwn_params();
  std::vector<Point_with_normal> cloud = noisy_cloud(street, 0.0, 42);
  const NO::Orientation_result r = NO::orient_normals(cloud, np);
  EXPECT_LE(double(NO::test::count_wrong(street, cloud)) / n, 0.01);
  EXPECT_GE(r.global.top_components_flipped, 1u);
  cloud = noisy_cloud(street, 0.0, 42);
  NO::orient_normals(cloud, np.up_direction(Vector(0, 0, 0)));
  EXPECT_GE(double(NO::test::count_wrong(street, cloud)) / n, 0.5);
  // A bowl (the lower half of a sphere, outward normals): with +z up it is
  // a scene open to the sky and faces up, the side seen from above; without
  // an up direction (an object scanned from below) the solver and the
  // winding number keep it outward.
  std::vector<Sample> bowl;
  for (const Sample& t : NO::test::sphere(40000, rng))
    if (t.p.z() < 0.0)
      bowl.push_back(t);
  std::mt19937_64 signs(25);
  std::vector<Point_with_normal> given = NO::test::unoriented(bowl, signs);
  NO::orient_normals(given, np);
  EXPECT_GE(NO::test::count_wrong(bowl, given), bowl.size() - bowl.size() / 1000); // (all but a thousandth)
  given = NO::test::unoriented(bowl, signs);
  NO::orient_normals(given, np.up_direction(Vector(0, 0, 0)));
  EXPECT_EQ(NO::test::count_wrong(bowl, given), 0u);
}

TEST(Canopy_rule, CellsOfVolumeScatterOnlyAndOpenScenesOnly)
{
  // Three patches fed to the coarse pass's grid (neighbour radius 1: the
  // canopy's cells are 0.5 wide, their blocks 1.5): a blob of random points
  // with random normals (a crown), a plane with random normals and noise of
  // a tenth of the radius (a noisy surface), and a plane with one normal.
  std::mt19937_64 g(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> gauss(0.0, 1.0);
  auto random_unit = [&]() {
    std::array<double, 3> n{{gauss(g), gauss(g), gauss(g)}};
    const double l = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    return std::array<double, 3>{{n[0] / l, n[1] / l, n[2] / l}};
  };
  NO::internal::Coarse_scale coarse(1.0);
  for (int i = 0; i < 20000; ++i) {
    coarse.add({{3.0 * u(g), 3.0 * u(g), 10.0 + 3.0 * u(g)}}, random_unit()); // the blob around (0, 0, 10)
    coarse.add({{20.0 + 4.0 * u(g), 4.0 * u(g), 0.1 * gauss(g)}}, random_unit()); // the noisy plane
    coarse.add({{-20.0 + 4.0 * u(g), 4.0 * u(g), 0.0}}, {{0.0, 0.0, 1.0}}); // the clean plane
  }
  coarse.decide(60000);
  const NO::internal::Canopy_cells cells(coarse);
  EXPECT_GT(cells.size(), 0u);
  EXPECT_TRUE(cells.contains({{0.0, 0.0, 10.0}}));
  EXPECT_TRUE(cells.contains({{1.0, -1.5, 9.0}}));
  for (double x : {-2.0, 0.0, 2.0}) {
    EXPECT_FALSE(cells.contains({{20.0 + x, x, 0.0}})) << x; // noise at a few spacings is not a volume
    EXPECT_FALSE(cells.contains({{-20.0 + x, x, 0.0}})) << x;
  }
  EXPECT_FALSE(cells.contains({{0.0, 0.0, 30.0}})); // no points
  const std::array<double, 3> up{{0.0, 0.0, 1.0}};
  EXPECT_TRUE(cells.faces_down({{0.0, 0.0, 10.0}}, {{0.0, 0.6, -0.8}}, 1, up));
  EXPECT_FALSE(cells.faces_down({{0.0, 0.0, 10.0}}, {{0.0, 0.6, -0.8}}, -1, up)); // faces up
  EXPECT_FALSE(cells.faces_down({{0.0, 0.0, 10.0}}, {{0.0, 0.9, -0.43}}, 1, up)); // over 60 degrees from the up line
  EXPECT_FALSE(cells.faces_down({{20.0, 0.0, 0.0}}, {{0.0, 0.0, -1.0}}, 1, up));
  EXPECT_EQ(NO::internal::Canopy_cells().size(), 0u);
  EXPECT_FALSE(NO::internal::Canopy_cells().contains({{0.0, 0.0, 0.0}}));

  // The components where the rule applies: those that read open in the
  // field, or that the top rule negated, with samples and not fixed.
  NO::internal::Global_settings settings;
  settings.orientation = NO::Global_orientation::VISIBILITY_AND_WINDING;
  const std::vector<double> w{0.5, 0.45, 0.0, 0.1, 0.5, 0.5, 0.0, 0.5};
  const std::vector<double> areas(w.size(), 1.0);
  const std::vector<std::uint32_t> component{0, 0, 1, 1, 2, 2, 3, 3}; // (component 4 has no sample)
  const std::vector<char> top{0, 0, 1, 0, 0}, fixed{0, 1, 0, 0, 0};
  // (component 3 has half its area at w = 1/2: `closed_fraction`, closed)
  EXPECT_EQ(NO::internal::open_scene_components(w, areas, component, 5, top, {}, settings),
            (std::vector<char>{0, 1, 1, 0, 0}));
  EXPECT_EQ(NO::internal::open_scene_components(w, areas, component, 5, top, fixed, settings),
            (std::vector<char>{0, 0, 1, 0, 0}));
  settings.up = {{0.0, 0.0, 0.0}}; // no up direction: no rule
  EXPECT_EQ(NO::internal::open_scene_components(w, areas, component, 5, top, {}, settings), std::vector<char>(5, 0));
  settings.up = {{0.0, 0.0, 2.0}};
  settings.orientation = NO::Global_orientation::WINDING;
  EXPECT_EQ(NO::internal::open_scene_components(w, areas, component, 5, top, {}, settings), std::vector<char>(5, 0));
  EXPECT_EQ(NO::internal::canopy_up(settings)[2], 0.0);
  settings.orientation = NO::Global_orientation::VISIBILITY_AND_WINDING;
  EXPECT_EQ(NO::internal::canopy_up(settings)[2], 1.0);
}

TEST(Coarse_scale, NoiseWiderThanTheSpacingIsOrientedAtACoarserScale)
{
  // 100k points on a torus of radii 1 and 0.1 (area 3.9): a spacing of about
  // 0.0063, noise of deviation 0.02, a sixth of the tube's diameter.  The input
  // normals do not agree; without the global stage about 46% of the clear
  // normals are wrong (the fine pipeline with the stage but without the
  // coarse pass gets no better: it is less closed than the coarse one).
  const auto np = pwn_params();
  std::mt19937_64 rng(31);
  const std::vector<Sample> truth = torus(100000, 1.0, 0.1, rng);
  std::vector<Point_with_normal> cloud = noisy_cloud(truth, 0.02, 32);
  std::vector<Point_with_normal> without = cloud;
  const NO::Orientation_result r = NO::orient_normals(cloud, np);
  NO::orient_normals(without, np.global_orientation(NO::Global_orientation::NONE));
  const double after = clear_wrong(cloud, truth), before = clear_wrong(without, truth);
  std::printf("noisy torus: coherence %.3f, %zu coarse points; clear normals wrong: %.2f%% without the "
              "global stage, %.2f%% with it\n",
              r.global.coherence, r.global.coarse_points, 100.0 * before, 100.0 * after);
  EXPECT_LT(r.global.coherence, NO::internal::coarse_coherence_threshold);
  EXPECT_TRUE(r.global.coarse_used);
  EXPECT_LE(after, 0.02);
  EXPECT_GE(before, 0.2);
  // the coarse signs were taken against the labelling that QPBO-I starts
  // from (its MST's): QPBO-I itself only ran on the coarse cloud
  EXPECT_TRUE(r.global.coarse_before_solver);
  const NO::test::Counting_solver counting;
  std::vector<Point_with_normal> again = noisy_cloud(truth, 0.02, 32);
  const NO::Orientation_result rc = NO::orient_normals(again, np.solver(counting));
  EXPECT_TRUE(rc.global.coarse_before_solver);
  EXPECT_EQ(*counting.sizes, std::vector<std::size_t>({rc.global.coarse_points}));
  // the fine field is on the sparse samples: every 7th point
  EXPECT_EQ(r.global.number_of_samples, (cloud.size() + 6) / 7);
  // only signs change
  for (std::size_t i = 0; i < cloud.size(); ++i)
    EXPECT_TRUE(cloud[i].second == without[i].second || cloud[i].second == -without[i].second);
}

TEST(Global_sign, GlobalSamplesAreDenseWhereTheNormalsAgree)
{
  // n / 4 (dense) or n / 16 points, at least 2^14 (or n), at most 2^16
  for (bool dense : {false, true}) {
    EXPECT_EQ(NO::global_samples(0, dense), 0u);
    EXPECT_EQ(NO::global_samples(4000, dense), 4000u);
    EXPECT_EQ(NO::global_samples(30000, dense), 16384u);
    EXPECT_EQ(NO::global_samples(20000000, dense), 65536u);
  }
  EXPECT_EQ(NO::global_samples(200000, false), 16384u);
  EXPECT_EQ(NO::global_samples(200000, true), 50000u);
  EXPECT_EQ(NO::global_samples(400000, false), 25000u);
  EXPECT_EQ(NO::global_samples(400000, true), 65536u);
}

TEST(Coarse_scale, CleanCloudsAreLeftToTheFinePipeline)
{
  // The same torus without noise, and the hollow ball: the normals agree, the
  // coarse pass does not run.
  const auto np = pwn_params();
  std::mt19937_64 rng(31);
  const std::vector<Sample> truth = torus(100000, 1.0, 0.1, rng);
  std::vector<Point_with_normal> cloud = noisy_cloud(truth, 0.0, 32);
  NO::Orientation_result r = NO::orient_normals(cloud, np);
  EXPECT_GE(r.global.coherence, NO::internal::coarse_coherence_threshold);
  EXPECT_EQ(r.global.coarse_points, 0u);
  EXPECT_FALSE(r.global.coarse_used);
  EXPECT_EQ(clear_wrong(cloud, truth), 0.0);
  // the field is on the dense samples: every 4th point
  EXPECT_EQ(r.global.number_of_samples, cloud.size() / 4);
  const std::vector<Sample> s = hollow_ball(20000, rng);
  EXPECT_EQ(orient_and_count(s, NO::Global_orientation::WINDING, 1, &r), 0u);
  EXPECT_GE(r.global.coherence, NO::internal::coarse_coherence_threshold);
  EXPECT_EQ(r.global.coarse_points, 0u);
}

TEST(Coarse_scale, GridStartsAtTheFirstPointInMortonOrderInAnyOrder)
{
  // The in-core driver adds the points in Morton order; the streamed one in
  // the sweep's order, with the origin found by `Morton_first` over the
  // points' box (ties by index).  Both must name the same point, whatever
  // order the points come in; coincident points test the ties.
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<double> u(-3.0, 5.0);
  std::vector<Point> points;
  for (int i = 0; i < 5000; ++i)
    points.emplace_back(u(rng), 0.25 * u(rng), 2.0 * u(rng));
  points.push_back(points[17]); // (a coincident copy, index 5000)
  points[40] = points[5000];    // (and one of lower index)
  const std::uint32_t first = NO::internal::morton_order<CGAL::Sequential_tag>(points).front();
  std::vector<std::uint32_t> order(points.size());
  std::iota(order.begin(), order.end(), 0u);
  std::shuffle(order.begin(), order.end(), rng);
  NO::internal::Morton_code box;
  for (std::uint32_t i : order) {
    const double p[3] = {points[i].x(), points[i].y(), points[i].z()};
    box.add(p);
  }
  box.close();
  NO::internal::Morton_first found(box);
  for (std::uint32_t i : order) {
    const double p[3] = {points[i].x(), points[i].y(), points[i].z()};
    found.add(p, i);
  }
  EXPECT_EQ(found.index(), std::uint64_t(first));
  EXPECT_EQ(found.position()[1], points[first].y());
  // the origin is set before any point, or not at all
  NO::internal::Coarse_scale scale(1.0);
  scale.set_origin({{points[first].x(), points[first].y(), points[first].z()}});
  scale.add({{0.0, 0.0, 0.0}}, {{0.0, 0.0, 1.0}});
  EXPECT_EQ(scale.origin()[0], points[first].x());
  EXPECT_THROW(scale.set_origin({{0.0, 0.0, 0.0}}), std::logic_error);
}

namespace {

/// Two parallel square layers of `n` points each (jittered grid of spacing
/// `h`), `gap` apart along z, with normals +z on both: the lower layer faces
/// the upper one, as a wrong side of a contact or of a thin plate does.
void two_layers(std::size_t n, double h, double gap, std::vector<Point>& points, std::vector<Vector>& normals)
{
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> jitter(-0.25 * h, 0.25 * h);
  const std::size_t side = std::size_t(std::sqrt(double(n)));
  for (int layer = 0; layer < 2; ++layer)
    for (std::size_t a = 0; a < side; ++a)
      for (std::size_t b = 0; b < side; ++b) {
        points.emplace_back(double(a) * h + jitter(rng), double(b) * h + jitter(rng), layer * gap);
        normals.emplace_back(0, 0, 1);
      }
}

/// `two_layers()` of spacing 1 and its 12-neighbour graph
void two_layer_graph(std::size_t n, double gap, std::vector<Point>& points, std::vector<Vector>& normals,
                     NO::Neighbor_graph& graph)
{
  two_layers(n, 1.0, gap, points, normals);
  NO::build_neighbor_graph<CGAL::Sequential_tag, Kernel>(points, normals, 12, 0.0, NO::Hoppe_criterion(), graph);
}

/// the points and the normals of `cloud`, apart
void split_cloud(const std::vector<Point_with_normal>& cloud, std::vector<Point>& points, std::vector<Vector>& normals)
{
  for (const Point_with_normal& p : cloud) {
    points.push_back(p.first);
    normals.push_back(p.second);
  }
}

/// An unoriented torus of 20,000 points (random signs, from `rng`) in
/// `points` and `normals`, and its 12-neighbour graph.
NO::Neighbor_graph_report torus_graph(std::mt19937_64& rng, std::vector<Point>& points, std::vector<Vector>& normals,
                                      NO::Neighbor_graph& graph)
{
  split_cloud(NO::test::unoriented(torus(20000, 1.0, 0.3, rng), rng), points, normals);
  return NO::build_neighbor_graph<CGAL::Sequential_tag, Kernel>(points, normals, 12, 0.0, NO::Hoppe_criterion(),
                                                                graph);
}

/// the median of all the edge slopes `slopes` (of `edge_slopes()`)
double median_slope(std::vector<float> slopes)
{
  std::sort(slopes.begin(), slopes.end());
  return double(slopes[slopes.size() / 2]);
}

} // namespace

TEST(Global_sign, PatchesSeparateLayersCloserThanTheSpacing)
{
  // Two layers half a spacing apart: the kNN graph joins them, the sheets
  // (slope 0.5) make one patch of them, patches of the slope of a clean cloud
  // (the floor) one per layer.  (Here about half the edges cross between the
  // layers, so the median slope of this cloud alone would not be the floor:
  // patch_slope() is tested on a whole surface below.)
  std::vector<Point> points;
  std::vector<Vector> normals;
  NO::Neighbor_graph graph;
  two_layer_graph(900, 0.5, points, normals, graph);
  std::size_t across = 0;
  for (auto e : boost::make_iterator_range(edges(graph)))
    across += points[source(e, graph)].z() != points[target(e, graph)].z() ? 1 : 0;
  ASSERT_GT(across, 0u);
  const std::vector<NO::Label> labels(points.size(), NO::Label(1));
  const std::vector<char> is_sample(points.size(), 1);
  const std::vector<float> slopes = NO::internal::edge_slopes<Kernel>(graph, points, normals);
  std::size_t sheets = 0, patches = 0;
  const std::vector<std::uint32_t> sheet = NO::internal::build_patches<Kernel>(
    graph, points, normals, labels, {}, 0.0, slopes, NO::internal::sheet_slope, is_sample, sheets);
  const std::vector<std::uint32_t> patch = NO::internal::build_patches<Kernel>(
    graph, points, normals, labels, {}, 0.0, slopes, NO::internal::patch_slope_floor, is_sample, patches);
  EXPECT_EQ(sheets, 1u);
  EXPECT_EQ(patches, 2u);
  for (std::size_t i = 0; i < points.size(); ++i)
    EXPECT_EQ(patch[i], patch[points[i].z() == 0.0 ? 0 : points.size() - 1]) << i;
  // Where the solver negated one layer against its start and kept the other,
  // even the sheets part them.
  ASSERT_EQ(points[0].z(), 0.0);
  std::vector<char> moved(points.size());
  for (std::size_t i = 0; i < points.size(); ++i)
    moved[i] = points[i].z() != 0.0;
  std::size_t parted = 0;
  const std::vector<std::uint32_t> apart = NO::internal::build_patches<Kernel>(
    graph, points, normals, labels, moved, 0.0, slopes, NO::internal::sheet_slope, is_sample, parted);
  EXPECT_EQ(parted, 2u);
  for (std::size_t i = 0; i < points.size(); ++i)
    EXPECT_EQ(apart[i] == apart[0], !moved[i]) << i;
}

TEST(Patch_units, UnitsFollowTheSheetsAcrossSegments)
{
  // Two layers 1.5 spacings apart, pushed in the order of x as a sweep would
  // push them: every edge between the layers is steeper than sheet_slope, so
  // the units never join the layers, even where one final segment holds both
  // (segments here are stripes of x, across the layers), and the patches of
  // the current signs are the layers: one each whatever the segments, two
  // per layer where half of one layer is negated.
  std::vector<Point> points;
  std::vector<Vector> normals;
  NO::Neighbor_graph graph;
  two_layer_graph(2500, 1.5, points, normals, graph);
  std::vector<std::size_t> order(points.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return points[a].x() < points[b].x(); });
  std::vector<std::size_t> rank(points.size());
  for (std::size_t t = 0; t < order.size(); ++t)
    rank[order[t]] = t;
  std::vector<std::vector<NO::streaming::Earlier_edge>> earlier(points.size());
  std::uint64_t span = 1;
  std::size_t across = 0;
  for (auto e : boost::make_iterator_range(edges(graph))) {
    std::size_t a = rank[source(e, graph)], b = rank[target(e, graph)];
    if (a < b)
      std::swap(a, b);
    earlier[a].push_back({std::uint32_t(a - b), 1.0f});
    span = std::max<std::uint64_t>(span, a - b);
    across += points[source(e, graph)].z() != points[target(e, graph)].z() ? 1 : 0;
  }
  ASSERT_GT(across, 0u);
  NO::streaming::internal::Patch_units units(span, 4.0); // (cells hold both layers)
  std::vector<std::uint32_t> unit(points.size());
  const Vector up(0, 0, 1);
  for (std::size_t t = 0; t < order.size(); ++t) {
    const Point& p = points[order[t]];
    const std::uint32_t segment = std::uint32_t(p.x() / 7.0); // stripes across both layers
    unit[order[t]] = units.push(p, up, segment, 0, earlier[t].data(), earlier[t].size());
  }
  const std::size_t nu = units.number_of_units();
  ASSERT_GT(nu, 2u);
  auto layer_of = [&](std::size_t i) { return points[i].z() == 0.0 ? 0 : 1; };
  std::vector<int> unit_layer(nu, -1);
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_TRUE(unit_layer[unit[i]] == -1 || unit_layer[unit[i]] == layer_of(i)) << i;
    unit_layer[unit[i]] = layer_of(i);
  }
  const double slope = units.patch_slope();
  EXPECT_GE(slope, NO::internal::patch_slope_floor);
  EXPECT_LE(slope, NO::internal::sheet_slope);
  for (int level = 0; level < 3; ++level) {
    const std::vector<std::uint32_t> sheet = units.patches(std::vector<char>(nu, 0), NO::internal::sheet_slope, level);
    if (level == 0) {
      std::uint32_t id[2] = {std::uint32_t(sheet.size()), std::uint32_t(sheet.size())};
      for (std::size_t u = 0; u < nu; ++u) {
        std::uint32_t& layer_id = id[unit_layer[u]];
        if (layer_id == std::uint32_t(sheet.size()))
          layer_id = sheet[u];
        EXPECT_EQ(sheet[u], layer_id) << u;
      }
      EXPECT_NE(id[0], id[1]);
    } else {
      for (std::size_t u = 0; u < nu; ++u) // cells part the layers further, never join them
        for (std::size_t v = 0; v < nu; ++v)
          if (unit_layer[u] != unit_layer[v]) {
            EXPECT_NE(sheet[u], sheet[v]);
          }
    }
  }
  // Negate the units of the lower layer with x < 24: its two halves now
  // disagree along x = 24, so they are two patches; the upper layer stays one.
  std::vector<char> negated(nu, 0);
  for (std::size_t i = 0; i < points.size(); ++i)
    if (layer_of(i) == 0 && points[i].x() < 24.0)
      negated[unit[i]] = 1;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (layer_of(i) == 0 && points[i].x() >= 24.0) {
      ASSERT_FALSE(negated[unit[i]]) << "a unit straddles x = 24"; // (a cell border)
    }
  const std::vector<std::uint32_t> patch = units.patches(negated, NO::internal::sheet_slope, 0);
  std::vector<std::vector<std::uint32_t>> of_part(3);
  for (std::size_t u = 0; u < nu; ++u)
    of_part[unit_layer[u] == 1 ? 2 : negated[u]].push_back(patch[u]);
  for (const auto& ids : of_part) {
    ASSERT_FALSE(ids.empty());
    EXPECT_TRUE(std::all_of(ids.begin(), ids.end(), [&](std::uint32_t id) { return id == ids[0]; }));
  }
  EXPECT_NE(of_part[0][0], of_part[1][0]);
  EXPECT_NE(of_part[0][0], of_part[2][0]);
  EXPECT_NE(of_part[1][0], of_part[2][0]);
  // Beyond the maximum number of units, the units overflow and stop growing.
  EXPECT_FALSE(units.overflowed());
  NO::streaming::internal::Patch_units few(span, 4.0, 3);
  for (std::size_t t = 0; t < order.size() && !few.overflowed(); ++t)
    few.push(points[order[t]], up, std::uint32_t(points[order[t]].x() / 7.0), 0, earlier[t].data(), earlier[t].size());
  EXPECT_TRUE(few.overflowed());
  EXPECT_LE(few.number_of_units(), 3u);
  // An edge reaching farther back than the span is an error.
  NO::streaming::internal::Patch_units short_units(1, 1.0);
  const NO::streaming::Earlier_edge far{2, 1.0f};
  short_units.push(points[0], up, 0, 0, nullptr, 0);
  short_units.push(points[1], up, 0, 0, nullptr, 0);
  EXPECT_THROW(short_units.push(points[2], up, 0, 0, &far, 1), std::runtime_error);
}

TEST(Global_sign, PatchesAreTheSameForAnyNumberOfThreads)
{
  // A torus with random labels, cells of a few spacings and every 7th point
  // a sample (so that patches without one join a neighbour): the parallel
  // edge tests give the sequential patches, and every edge that the rule
  // joins (same cell, same sheet) has both ends in one patch.
  std::mt19937_64 rng(43);
  std::vector<Point> points;
  std::vector<Vector> normals;
  NO::Neighbor_graph graph;
  const NO::Neighbor_graph_report report = torus_graph(rng, points, normals, graph);
  std::vector<NO::Label> labels(points.size());
  std::vector<char> is_sample(points.size(), 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    labels[i] = NO::Label(rng() % 8 == 0 ? -1 : 1);
    is_sample[i] = i % 7 == 0;
  }
  const std::vector<float> slopes = NO::internal::edge_slopes<Kernel>(graph, points, normals);
  const double cell = 4.0 * report.radius;
  std::size_t sequential = 0, parallel = 0;
  const std::vector<std::uint32_t> a = NO::internal::build_patches<Kernel, CGAL::Sequential_tag>(
    graph, points, normals, labels, {}, cell, slopes, NO::internal::sheet_slope, is_sample, sequential);
  const std::vector<std::uint32_t> b = NO::internal::build_patches<Kernel, CGAL::Parallel_tag>(
    graph, points, normals, labels, {}, cell, slopes, NO::internal::sheet_slope, is_sample, parallel);
  EXPECT_GT(sequential, 20u);
  EXPECT_EQ(sequential, parallel);
  EXPECT_EQ(a, b);
  double lo[3] = {points[0].x(), points[0].y(), points[0].z()}; // the cells' grid starts at the lowest corner
  for (const Point& p : points)
    for (int c = 0; c < 3; ++c)
      lo[c] = std::min(lo[c], p[c]);
  std::size_t joined = 0, e = 0;
  for (auto edge : boost::make_iterator_range(edges(graph))) {
    const std::size_t i = source(edge, graph), j = target(edge, graph);
    const Vector mi = labels[i] < 0 ? -normals[i] : normals[i], mj = labels[j] < 0 ? -normals[j] : normals[j];
    bool same_cell = true;
    for (int c = 0; c < 3; ++c)
      same_cell = same_cell && std::floor((points[i][c] - lo[c]) / cell) == std::floor((points[j][c] - lo[c]) / cell);
    if (same_cell && NO::internal::same_sheet(mi * mj, slopes[e], NO::internal::sheet_slope)) {
      ++joined;
      EXPECT_EQ(a[i], a[j]) << i << " " << j;
    }
    ++e;
  }
  EXPECT_GT(joined, num_edges(graph) / 4);
}

TEST(Global_sign, BlockwiseUnionsGiveTheSetsOfUnitingEveryEdgeInOrder)
{
  // Random joining edges on a torus's graph: uniting them block by block (in
  // parallel, then the edges between blocks) gives the sets of uniting them
  // one by one, for blocks smaller and larger than the cloud.
  std::mt19937_64 rng(47);
  std::vector<Point> points;
  std::vector<Vector> normals;
  NO::Neighbor_graph graph;
  torus_graph(rng, points, normals, graph);
  std::vector<unsigned char> joins(num_edges(graph));
  for (unsigned char& j : joins)
    j = rng() % 8 == 0; // one edge in eight: thousands of sets, many spanning blocks
  auto canonical = [&](NO::Signed_union_find& uf) { // each point's set, numbered by its first point
    std::vector<std::uint32_t> id(points.size(), ~0u), set(points.size());
    std::uint32_t next = 0;
    for (std::uint32_t i = 0; i < points.size(); ++i) {
      const std::uint32_t r = uf.find(i);
      if (id[r] == ~0u)
        id[r] = next++;
      set[i] = id[r];
    }
    return set;
  };
  NO::Signed_union_find one_by_one(points.size());
  std::size_t e = 0;
  for (auto edge : boost::make_iterator_range(edges(graph)))
    if (joins[e++])
      one_by_one.unite(std::uint32_t(source(edge, graph)), std::uint32_t(target(edge, graph)));
  const std::vector<std::uint32_t> expected = canonical(one_by_one);
  std::size_t sets = 0;
  for (std::uint32_t s : expected)
    sets = std::max<std::size_t>(sets, s + 1);
  EXPECT_GT(sets, 100u);
  EXPECT_LT(sets, points.size() / 2);
  for (std::size_t block : {std::size_t(1), std::size_t(997), std::size_t(1) << 16}) {
    NO::Signed_union_find sequential(points.size()), parallel(points.size());
    NO::internal::unite_joined_edges<CGAL::Sequential_tag>(graph, joins, sequential, block);
    NO::internal::unite_joined_edges<CGAL::Parallel_tag>(graph, joins, parallel, block);
    EXPECT_EQ(canonical(sequential), expected) << block;
    EXPECT_EQ(canonical(parallel), expected) << block;
  }
}

TEST(Global_sign, PatchSlopeIsTheMedianEdgeSlopeWithinItsBounds)
{
  // patch_slope() takes the median of every 16th edge: close to the median of
  // all of them, clamped to [patch_slope_floor, sheet_slope].  Clean, light
  // and heavy noise on a torus (PCA normals).
  std::mt19937_64 rng(41);
  const std::vector<Sample> truth = torus(20000, 1.0, 0.25, rng);
  const double sigmas[] = {0.0, 0.004, 0.05};
  for (double sigma : sigmas) {
    std::vector<Point> points;
    std::vector<Vector> normals;
    split_cloud(noisy_cloud(truth, sigma, 42), points, normals);
    NO::Neighbor_graph graph;
    NO::build_neighbor_graph<CGAL::Sequential_tag, Kernel>(points, normals, 12, 0.0, NO::Hoppe_criterion(), graph);
    const std::vector<float> slopes = NO::internal::edge_slopes<Kernel>(graph, points, normals);
    const double median = median_slope(slopes);
    const double slope = NO::internal::patch_slope(slopes);
    std::printf("torus, noise %.3f: median edge slope %.3f, patch slope %.3f\n", sigma, median, slope);
    EXPECT_NEAR(slope,
                std::min(NO::internal::sheet_slope, std::max(NO::internal::patch_slope_floor, median)), 0.02);
    if (sigma == 0.0) {
      EXPECT_EQ(slope, NO::internal::patch_slope_floor);
    }
    if (sigma == 0.05) {
      EXPECT_EQ(slope, NO::internal::sheet_slope);
    }
  }
}

TEST(Two_layer_fit, TwoParallelLayersAndTheirGap)
{
  // The point on z = 0 with 8 neighbours there and 6 on z = g; its normal
  // line is 5 degrees off.  Exact planes: the fit finds them and their gap.
  const double g = 0.03, c = std::cos(0.0873), s = std::sin(0.0873);
  std::vector<std::array<double, 3>> q = {{0.0, 0.0, 0.0}};
  for (int k = 0; k < 8; ++k)
    q.push_back({0.1 * std::cos(0.8 * k), 0.1 * std::sin(0.8 * k), 0.0});
  for (int k = 0; k < 6; ++k)
    q.push_back({0.07 * std::cos(1.1 * k + 0.3), 0.07 * std::sin(1.1 * k + 0.3), g});
  std::vector<std::pair<double, std::uint32_t>> scratch;
  NO::internal::Two_layer_fit f = NO::internal::fit_two_layers(q, {{s, 0.0, c}}, scratch);
  ASSERT_TRUE(f.two_layers);
  EXPECT_NEAR(f.gap, g, 1e-9);
  EXPECT_NEAR(f.to_other[0], 0.0, 1e-9);
  EXPECT_NEAR(f.to_other[1], 0.0, 1e-9);
  EXPECT_NEAR(f.to_other[2], g, 1e-9);
  // seen from the upper layer, the other one is below
  std::swap(q[0], q[9]);
  f = NO::internal::fit_two_layers(q, {{0.0, s, -c}}, scratch);
  ASSERT_TRUE(f.two_layers);
  EXPECT_NEAR(f.to_other[2], -g, 1e-9);
  // one curved layer (a sphere of radius 1, neighbours 0.05 away) is not two
  std::mt19937_64 rng(3);
  std::vector<std::array<double, 3>> one = {{0.0, 0.0, 1.0}};
  for (int k = 0; k < 15; ++k) {
    const double a = NO::hard_shapes::internal::uniform(rng, 0.0, 6.283), r = NO::hard_shapes::internal::uniform(rng, 0.01, 0.05);
    one.push_back({r * std::cos(a), r * std::sin(a), std::sqrt(1.0 - r * r)});
  }
  EXPECT_FALSE(NO::internal::fit_two_layers(one, {{0.0, 0.0, 1.0}}, scratch).two_layers);
  // nor is a noisy one, nor two layers whose spread is over a twentieth of their gap
  std::normal_distribution<double> noise(0.0, 0.003);
  for (auto& p : one)
    p[2] += noise(rng);
  EXPECT_FALSE(NO::internal::fit_two_layers(one, {{0.0, 0.0, 1.0}}, scratch).two_layers);
  std::vector<std::array<double, 3>> spread = q;
  for (auto& p : spread)
    p[2] += NO::hard_shapes::internal::uniform(rng, -0.004, 0.004);
  EXPECT_FALSE(NO::internal::fit_two_layers(spread, {{0.0, 0.0, 1.0}}, scratch).two_layers);
  // and fewer than 3 points on either side is not a layer
  q.resize(6);
  EXPECT_FALSE(NO::internal::fit_two_layers(q, {{0.0, 0.0, 1.0}}, scratch).two_layers);
}

TEST(Two_layer_fit, FacesAtACreaseAreNotTwoLayers)
{
  // Exact planes z = 0 (x < 0.05) and z = 0.2 (x - 0.05) meet at a crease;
  // the point and 9 neighbours lie on the first, 4 on the second in a narrow
  // band at x = 0.1, all at the same height over the first plane.  Side by
  // side, they are one bent surface; moved over the first face at the same
  // height, they are a second layer.
  std::mt19937_64 rng(5);
  std::vector<std::array<double, 3>> q = {{0.0, 0.0, 0.0}};
  for (int k = 0; k < 9; ++k)
    q.push_back({NO::hard_shapes::internal::uniform(rng, -0.1, 0.05), NO::hard_shapes::internal::uniform(rng, -0.1, 0.1), 0.0});
  const double height = 0.2 * (0.1 - 0.05);
  for (int k = 0; k < 4; ++k)
    q.push_back({0.1, NO::hard_shapes::internal::uniform(rng, -0.1, 0.1), height});
  std::vector<std::pair<double, std::uint32_t>> scratch;
  EXPECT_FALSE(NO::internal::fit_two_layers(q, {{0.0, 0.0, 1.0}}, scratch).two_layers);
  for (std::size_t k = 10; k < q.size(); ++k)
    q[k][0] = NO::hard_shapes::internal::uniform(rng, -0.1, 0.05);
  const NO::internal::Two_layer_fit f = NO::internal::fit_two_layers(q, {{0.0, 0.0, 1.0}}, scratch);
  ASSERT_TRUE(f.two_layers);
  EXPECT_NEAR(f.gap, height, 1e-9);
}

TEST(Two_layer_fit, ALayerMustStepNotClimb)
{
  // The point and 9 neighbours on z = 0 within 0.05 of it; 3 more at height
  // 0.006 all around, 0.1 away (the faces around a mesh vertex bending up):
  // the surface climbs 0.006 over 0.05, one layer.  The same 3 under the
  // point, 0.02 away, step 0.006 at once: two layers.
  for (const double radius : {0.1, 0.02}) {
    std::vector<std::array<double, 3>> q = {{0.0, 0.0, 0.0}};
    for (int k = 0; k < 9; ++k)
      q.push_back({0.05 * std::cos(0.7 * k + 0.2), 0.05 * std::sin(0.7 * k + 0.2), 0.0});
    for (int k = 0; k < 3; ++k)
      q.push_back({radius * std::cos(2.1 * k), radius * std::sin(2.1 * k), 0.006});
    std::vector<std::pair<double, std::uint32_t>> scratch;
    const NO::internal::Two_layer_fit f = NO::internal::fit_two_layers(q, {{0.0, 0.0, 1.0}}, scratch);
    EXPECT_EQ(f.two_layers, radius < 0.05) << radius;
  }
}

TEST(Layer_edges, NegatedAcrossTwoLayersOnly)
{
  // Two jittered grids of spacing 1 at z = 0 and z = 0.3 with the same
  // normal (0, 0, 1), as PCA gives on both sides of a thin part: Hoppe's
  // criterion asks every edge for the same sign; the graph negates exactly
  // the edges between the layers, and every point away from the border knows
  // the other layer, 0.3 away along z.  One grid alone: nothing changes.
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1);
  std::vector<Point> points;
  std::vector<Vector> normals;
  for (int layer = 0; layer < 2; ++layer)
    for (int x = 0; x < 30; ++x)
      for (int y = 0; y < 30; ++y) {
        points.emplace_back(x + jitter(rng), y + jitter(rng), 0.3 * layer);
        normals.emplace_back(0.0, 0.0, 1.0);
      }
  auto count = [&](std::size_t n, bool negate, std::size_t& across, std::size_t& wrong_sign,
                   std::vector<std::array<float, 3>>* offsets) {
    NO::Neighbor_graph g;
    NO::build_neighbor_graph<CGAL::Sequential_tag, Kernel>(
      std::vector<Point>(points.begin(), points.begin() + std::ptrdiff_t(n)),
      std::vector<Vector>(normals.begin(), normals.begin() + std::ptrdiff_t(n)), 12, 0.0, NO::Hoppe_criterion(), g,
      NO::Progress_reporter(), negate, offsets);
    across = wrong_sign = 0;
    for (const auto e : boost::make_iterator_range(edges(g))) {
      const bool between = (source(e, g) < 900) != (target(e, g) < 900);
      const double w = g[e].weight;
      across += between ? 1 : 0;
      wrong_sign += (between && negate) == (w > 0.0) ? 1 : 0;
    }
  };
  std::size_t across = 0, wrong_sign = 0;
  std::vector<std::array<float, 3>> offsets;
  count(1800, true, across, wrong_sign, &offsets);
  EXPECT_GT(across, 900u);
  EXPECT_EQ(wrong_sign, 0u);
  ASSERT_EQ(offsets.size(), 1800u);
  for (std::size_t i = 0; i < 1800; ++i) {
    const double x = CGAL::to_double(points[i].x()), y = CGAL::to_double(points[i].y());
    if (x < 2 || x > 27 || y < 2 || y > 27)
      continue;
    EXPECT_NEAR(offsets[i][2], i < 900 ? 0.3 : -0.3, 1e-6) << i;
    EXPECT_NEAR(std::abs(offsets[i][0]) + std::abs(offsets[i][1]), 0.0, 1e-6) << i;
  }
  count(1800, false, across, wrong_sign, &offsets); // not negated: every weight > 0, no offset
  EXPECT_EQ(wrong_sign, 0u);
  EXPECT_TRUE(offsets.empty());
  count(900, true, across, wrong_sign, &offsets); // one layer
  EXPECT_EQ(across, 0u);
  EXPECT_EQ(wrong_sign, 0u);
  for (const auto& t : offsets)
    EXPECT_EQ(t, (std::array<float, 3>{{0.f, 0.f, 0.f}}));
  // The fill: a point takes its offset from a two-layer neighbour at q,
  // whose other layer is 0.3 up: 0.2 up from 0.1 above q's layer, back down
  // 0.25 from the other layer's side.
  const double q[3] = {0.0, 0.0, 0.0}, on[3] = {0.5, 0.0, 0.1}, beyond[3] = {0.5, 0.5, 0.25};
  const std::array<float, 3> up = {{0.f, 0.f, 0.3f}};
  EXPECT_NEAR(NO::internal::filled_offset(on, q, up)[2], 0.2, 1e-6);
  EXPECT_NEAR(NO::internal::filled_offset(beyond, q, up)[2], -0.25, 1e-6);
  // An edge across the gap is negated only between nearly parallel normal
  // lines (within 60 degrees), not towards a face at right angles.
  const double p_up[3] = {0.0, 0.0, 0.3}, n_z[3] = {0.0, 0.0, -2.0}, n_x[3] = {1.0, 0.0, 0.0},
               n_tilt[3] = {0.0, 0.8, 0.6}, zero[3] = {0.0, 0.0, 0.0};
  const std::array<float, 3> none = {{0.f, 0.f, 0.f}};
  EXPECT_TRUE(NO::internal::edge_across_layers(q, up, n_z, p_up, none, n_z));
  EXPECT_TRUE(NO::internal::edge_across_layers(p_up, none, n_z, q, up, n_z)); // (seen from either end)
  EXPECT_TRUE(NO::internal::edge_across_layers(q, up, n_z, p_up, none, n_tilt));
  EXPECT_FALSE(NO::internal::edge_across_layers(q, up, n_z, p_up, none, n_x));
  EXPECT_FALSE(NO::internal::edge_across_layers(q, up, n_z, p_up, none, zero));
  EXPECT_FALSE(NO::internal::edge_across_layers(q, up, n_z, on, none, n_z)); // (on the same layer)
}

TEST(Global_sign, LayerEdgesAndCuesFixThinPartsAndContacts)
{
  // Parts thinner than the neighbour distance and flat contacts (Hard_shapes.h;
  // true normals, random signs, Hoppe's criterion): the local energy left a
  // whole layer inward (about half of the points of the thin shells, an
  // eighth of the boxes).  The graph negates the edges across the layers,
  // and the far field across each layer pair gives the layers their signs.
  struct Case
  {
    const char* name;
    double after;
  };
  const Case cases[] = {{"thin_plate", 0.005}, {"thin_pipe", 0.005}, {"thin_dome", 0.005}, {"touching_boxes", 0.03}};
  std::size_t rounds = 0;
  for (const Case& c : cases) {
    std::mt19937_64 rng(1);
    const std::vector<Sample> s = NO::hard_shapes::hard_shape(c.name, 30000, rng);
    const double n = double(s.size());
    NO::Orientation_result r;
    const double after = double(orient_and_count(s, NO::Global_orientation::VISIBILITY_AND_WINDING, 21, &r)) / n;
    std::printf("%-16s wrong %6.2f%% (%zu points on two layers, %zu sure cues, %zu against)\n", c.name, 100.0 * after,
                r.global.layer_pairs, r.global.layer_cues, r.global.layer_cues_against);
    EXPECT_LE(after, c.after) << c.name;
    EXPECT_GE(double(r.global.layer_pairs), (c.after < 0.01 ? 0.8 : 0.1) * n) << c.name;
    // (the coarse pass's figures outlive the layer cues' round)
    EXPECT_FALSE(std::isnan(r.global.coherence)) << c.name;
    rounds += r.global.layer_cue_round ? 1 : 0;
  }
  EXPECT_GE(rounds, 1u); // (the thin dome's cues ask for a round)
  // A clean closed surface with no thin part: no point on two layers, and
  // no second solve.
  std::mt19937_64 rng(2);
  const std::vector<Sample> ball = NO::test::sphere(20000, rng, Point(0, 0, 0), 1.0);
  NO::Orientation_result r;
  EXPECT_EQ(orient_and_count(ball, NO::Global_orientation::VISIBILITY_AND_WINDING, 3, &r), 0u);
  EXPECT_EQ(r.global.layer_pairs, 0u);
  EXPECT_FALSE(r.global.layer_cue_round);
}
