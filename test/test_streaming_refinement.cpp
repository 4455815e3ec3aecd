// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
/// \file test_streaming_refinement.cpp
/// \brief Tests of the refinement of the streaming driver (streaming/Refinement.h,
/// streaming/Refine_stage.h): its passes, its energies, its determinism and its
/// failures.

#include "Streaming_test_support.h"

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
  NO::build_neighbor_graph<CGAL::Sequential_tag, K>(points, normals, k, radius, NO::Hoppe_konig_criterion(), graph, // the default
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
    options.global = NO::Global_orientation::NONE; // the refinement's own energy
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
    options.global = NO::Global_orientation::NONE;
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

// The rounds run only when the energy is above a millionth of the total
// weight of the edges (the 20M bunny's 12.7 out of about 1.3e8 is not; a
// 1M cloud's 1,100 out of 6.5e6 is), and never at energy 0, whatever the
// fraction.
TEST(Streaming_refinement, SkippedWhenTheEnergyIsNegligible)
{
  NO::streaming::Refinement_options o;
  EXPECT_EQ(o.negligible_energy, 1e-6);
  EXPECT_FALSE(o.worth_running(12.7, 1.3e8));
  EXPECT_TRUE(o.worth_running(1111.0, 6.5e6));
  EXPECT_FALSE(o.worth_running(0.99, 1e6));
  EXPECT_TRUE(o.worth_running(1.01, 1e6));
  EXPECT_FALSE(o.worth_running(0.0, 0.0));
  o.negligible_energy = 0.0;
  EXPECT_TRUE(o.worth_running(1e-9, 1e9));
  EXPECT_FALSE(o.worth_running(0.0, 1e9));
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

