// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_STREAMING_UNIT_ISLANDS_H
#define NORMAL_ORIENTATION_STREAMING_UNIT_ISLANDS_H

/// \file Unit_islands.h
/// The islands left by the streamed global stage, on its patch units: the
/// in-core rule (`choose_islands()`, the manual's *Islands left by the
/// stage*) on segments made of units instead of points.

#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/internal/Frustrated_islands.h>
#include <Normal_orientation/streaming/Patch_units.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace Normal_orientation {
namespace streaming {
/// \cond SKIP_IN_MANUAL
namespace internal {

/// Two units are in one segment of the final signs when at most this share
/// of the weight of the edges between them is against those signs, and no
/// pair of the segment's units has more, as the segmentation joins a point
/// to a segment only without contradicting votes.
constexpr double unit_contradiction = 0.1;

/// The segments of the final signs over the units of `units`, with the
/// negations `negated` (per unit, relative to the orientation pushed): the
/// pairs of units (`Patch_units::visit_couplings()`) whose edges weigh
/// against the signs at most `unit_contradiction` of their weight join
/// their segments, heaviest first, unless another pair between the two
/// segments weighs more against them.  Fills `segments` (its members are
/// the samples, each in the unit `sample_unit`), and the sorted adjacency
/// of the segments (`first`, `neighbour`); returns the segment of every
/// unit.  Deterministic.
inline std::vector<std::uint32_t> unit_segments(const Patch_units& units, const std::vector<char>& negated,
                                                const std::vector<std::uint32_t>& sample_unit,
                                                Normal_orientation::internal::Island_segments& segments,
                                                std::vector<std::uint32_t>& first, std::vector<std::uint32_t>& neighbour)
{
  const std::size_t nu = units.number_of_units();
  // the weight of a pair against and for the signs
  auto split = [&](std::uint32_t a, std::uint32_t b, double coupling, double magnitude) {
    const double c = negated[a] != negated[b] ? -coupling : coupling;
    return std::make_pair(0.5 * (magnitude - c), 0.5 * (magnitude + c));
  };
  struct Join
  {
    double weight;
    std::uint32_t a, b;
  };
  std::vector<Join> joins;
  std::vector<std::vector<std::uint32_t>> foes(nu); // (per root: the units across contradicted pairs)
  units.visit_couplings([&](std::uint32_t a, std::uint32_t b, double coupling, double magnitude) {
    if (!(magnitude > 0.0))
      return;
    if (split(a, b, coupling, magnitude).first <= unit_contradiction * magnitude) {
      joins.push_back({magnitude, a, b});
    } else {
      foes[a].push_back(b);
      foes[b].push_back(a);
    }
  });
  std::sort(joins.begin(), joins.end(), [](const Join& x, const Join& y) {
    return x.weight != y.weight ? x.weight > y.weight : (x.a != y.a ? x.a < y.a : x.b < y.b);
  });
  std::vector<std::uint32_t> parent(nu);
  for (std::size_t u = 0; u < nu; ++u)
    parent[u] = std::uint32_t(u);
  auto find = [&](std::uint32_t u) {
    while (parent[u] != u)
      u = parent[u] = parent[parent[u]];
    return u;
  };
  for (const Join& j : joins) {
    std::uint32_t ra = find(j.a), rb = find(j.b);
    if (ra == rb)
      continue;
    if (foes[ra].size() < foes[rb].size())
      std::swap(ra, rb);
    if (std::any_of(foes[rb].begin(), foes[rb].end(), [&](std::uint32_t f) { return find(f) == ra; }))
      continue;
    parent[rb] = ra;
    foes[ra].insert(foes[ra].end(), foes[rb].begin(), foes[rb].end());
    std::vector<std::uint32_t>().swap(foes[rb]);
  }
  const std::uint32_t unset = ~std::uint32_t(0);
  std::vector<std::uint32_t> id(nu, unset), segment(nu);
  std::uint32_t ns = 0;
  for (std::size_t u = 0; u < nu; ++u) {
    const std::uint32_t r = find(std::uint32_t(u));
    if (id[r] == unset)
      id[r] = ns++;
    segment[u] = id[r];
  }
  segments.against.assign(ns, 0.0);
  segments.along.assign(ns, 0.0);
  segments.size.assign(ns, 0);
  segments.blocked.assign(ns, 0);
  segments.members.assign(ns, {});
  for (std::size_t u = 0; u < nu; ++u)
    segments.size[segment[u]] += units.unit_size()[u];
  for (std::size_t j = 0; j < sample_unit.size(); ++j)
    segments.members[segment[sample_unit[j]]].push_back(std::uint32_t(j));
  std::vector<std::pair<std::uint32_t, std::uint32_t>> adjacent;
  units.visit_couplings([&](std::uint32_t a, std::uint32_t b, double coupling, double magnitude) {
    const std::uint32_t sa = segment[a], sb = segment[b];
    if (sa == sb)
      return;
    const auto w = split(a, b, coupling, magnitude);
    for (std::uint32_t s : {sa, sb}) {
      segments.against[s] += w.first;
      segments.along[s] += w.second;
    }
    adjacent.emplace_back(sa, sb);
    adjacent.emplace_back(sb, sa);
  });
  std::sort(adjacent.begin(), adjacent.end());
  adjacent.erase(std::unique(adjacent.begin(), adjacent.end()), adjacent.end());
  first.assign(ns + 1, 0);
  neighbour.resize(adjacent.size());
  for (std::size_t t = 0; t < adjacent.size(); ++t) {
    ++first[adjacent[t].first + 1];
    neighbour[t] = adjacent[t].second;
  }
  for (std::size_t s = 0; s < ns; ++s)
    first[s + 1] += first[s];
  return segment;
}

/// Negates the islands of the streamed global stage's signs, as in core
/// (`Normal_orientation::internal::negate_frustrated_islands()`), on the
/// segments of units (`unit_segments()`) of the `n` points: `negated` (per
/// unit) and `sample_negated` (per sample, the sample of unit
/// `sample_unit`) are the negations relative to the orientation pushed,
/// updated; `search` holds the samples with those signs.  Returns the
/// islands negated.
template <typename ConcurrencyTag, typename Kernel>
std::size_t negate_unit_islands(const Patch_units& units, std::uint64_t n,
                                const std::vector<std::uint32_t>& sample_unit,
                                Winding_patch_signs<Kernel>& search, std::vector<char>& negated,
                                std::vector<char>& sample_negated)
{
  std::size_t total = 0;
  for (unsigned int round = 0; round < Normal_orientation::internal::island_rounds; ++round) {
    Normal_orientation::internal::Island_segments segments;
    std::vector<std::uint32_t> first, neighbour;
    const std::vector<std::uint32_t> segment = unit_segments(units, negated, sample_unit, segments, first, neighbour);
    const std::vector<char> negate = Normal_orientation::internal::choose_islands<ConcurrencyTag>(
      segments, n, search, [&](std::uint32_t s, const auto& block) {
        for (std::uint32_t t = first[s]; t < first[s + 1]; ++t)
          block(neighbour[t]);
      });
    const std::size_t this_round = std::size_t(std::count(negate.begin(), negate.end(), char(1)));
    for (std::size_t u = 0; u < negated.size(); ++u)
      if (negate[segment[u]])
        negated[u] = char(!negated[u]);
    for (std::size_t j = 0; j < sample_unit.size(); ++j)
      if (negate[segment[sample_unit[j]]])
        sample_negated[j] = char(!sample_negated[j]);
    total += this_round;
    if (this_round == 0)
      break;
  }
  return total;
}

} // namespace internal
/// \endcond
} // namespace streaming
} // namespace Normal_orientation

#endif // NORMAL_ORIENTATION_STREAMING_UNIT_ISLANDS_H
