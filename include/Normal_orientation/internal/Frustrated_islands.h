// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_FRUSTRATED_ISLANDS_H
#define NORMAL_ORIENTATION_INTERNAL_FRUSTRATED_ISLANDS_H

/// \file Frustrated_islands.h
/// The last step of the winding number's levels: islands that the stage left
/// against their surroundings.  An island is a segment of the final labelling
/// (`labelling_segments()`) whose border weighs mostly against its signs; it
/// is negated when the winding number does not rise (the manual's
/// *Islands left by the stage*).

#include <Normal_orientation/Global_sign.h>
#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/internal/Graph_reduction.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// A segment is an island when at least this share of the weight of its
/// border's edges is against its signs.
constexpr double island_frustration = 0.8;
/// The most rounds of island flips (each round takes islands that touch no
/// island negated in it).
constexpr unsigned int island_rounds = 2;

/// The weight of each segment's border (edges of `inc` to other segments),
/// against and for the signs `labels`: `against[s]` and `along[s]`.
inline void island_borders(const Incidence& inc, const std::vector<Label>& labels,
                           const std::vector<std::uint32_t>& segment, std::size_t number_of_segments,
                           std::vector<double>& against, std::vector<double>& along)
{
  against.assign(number_of_segments, 0.0);
  along.assign(number_of_segments, 0.0);
  const std::size_t n = inc.number_of_vertices();
  for (std::size_t i = 0; i < n; ++i)
    for (std::uint32_t t = inc.first[i]; t < inc.first[i + 1]; ++t) {
      const std::uint32_t j = inc.other[t];
      if (segment[j] == segment[i])
        continue;
      const double c = double(inc.weight[t]) * double(labels[i]) * double(labels[j]);
      (c < 0.0 ? against : along)[segment[i]] += std::abs(c);
    }
}

/// Whether a segment of `size` of the `n` points, with border weights
/// `against` and `along`, is an island: less than half the points, and at
/// least `island_frustration` of its border against it.
inline bool is_island(double against, double along, std::size_t size, std::size_t n)
{
  return 2 * size < n && against > along && against >= island_frustration * (against + along);
}

/// The segments that the island rule looks at, in either driver: per
/// segment the weight of its border against and for its signs, its points,
/// whether it keeps its signs, and its samples (indices in the field).
struct Island_segments
{
  std::vector<double> against, along;
  std::vector<std::uint64_t> size;
  std::vector<char> blocked;
  std::vector<std::vector<std::uint32_t>> members;
};

/// The islands of `segments` (`is_island()` over `n` points) that the
/// field of `search` lets negate: taken by their border's excess, largest
/// first; an island is skipped when a neighbour negated before it in this
/// round, or when it has samples and negating them would raise the winding
/// energy (else they are negated in `search`); an island without a sample
/// follows its border alone.  `neighbours(s, block)` calls `block(t)` for
/// every segment t adjacent to s.  Returns the flags of the segments to
/// negate (in `blocked`, the segments next to them are marked).
template <typename ConcurrencyTag, typename Kernel, typename Neighbours>
std::vector<char> choose_islands(Island_segments& segments, std::uint64_t n, Winding_patch_signs<Kernel>& search,
                                 const Neighbours& neighbours)
{
  const std::size_t ns = segments.size.size();
  std::vector<std::uint32_t> islands;
  for (std::uint32_t s = 0; s < ns; ++s)
    if (!segments.blocked[s] && is_island(segments.against[s], segments.along[s], segments.size[s], n))
      islands.push_back(s);
  std::stable_sort(islands.begin(), islands.end(), [&](std::uint32_t a, std::uint32_t b) {
    return segments.against[a] - segments.along[a] > segments.against[b] - segments.along[b];
  });
  std::vector<char> negate(ns, 0);
  for (std::uint32_t s : islands) {
    if (segments.blocked[s])
      continue;
    if (!segments.members[s].empty() && !search.template negate_unless_worse<ConcurrencyTag>(segments.members[s]))
      continue;
    negate[s] = 1;
    neighbours(s, [&](std::uint32_t t) { segments.blocked[t] = 1; });
  }
  return negate;
}

/// Negates the islands of `labels` on the graph `inc` (its segments are
/// `labelling_segments()`) where the field of `search` (built on the
/// samples `sample_index`, points with the signs `labels`) does not rise
/// (`choose_islands()`).  Points of `keep` (per point, or empty) and their
/// segments keep their signs.  At most `island_rounds` rounds.  Returns the
/// islands negated.
template <typename ConcurrencyTag, typename Kernel>
std::size_t negate_frustrated_islands(const Incidence& inc, const std::vector<std::uint32_t>& sample_index,
                                      const std::vector<char>& keep, Winding_patch_signs<Kernel>& search,
                                      std::vector<Label>& labels)
{
  const std::size_t n = inc.number_of_vertices();
  std::size_t negated = 0;
  for (unsigned int round = 0; round < island_rounds; ++round) {
    std::vector<std::uint32_t> segment;
    const std::size_t ns = labelling_segments(inc, labels, segment);
    Island_segments segments;
    island_borders(inc, labels, segment, ns, segments.against, segments.along);
    segments.size.assign(ns, 0);
    segments.blocked.assign(ns, 0);
    for (std::size_t i = 0; i < n; ++i) {
      ++segments.size[segment[i]];
      if (!keep.empty() && keep[i])
        segments.blocked[segment[i]] = 1;
    }
    segments.members.resize(ns);
    for (std::size_t t = 0; t < sample_index.size(); ++t)
      segments.members[segment[sample_index[t]]].push_back(std::uint32_t(t));
    std::vector<std::uint32_t> first(ns + 1, 0), order(n); // (the points of each segment)
    for (std::size_t i = 0; i < n; ++i)
      ++first[segment[i] + 1];
    for (std::size_t s = 0; s < ns; ++s)
      first[s + 1] += first[s];
    {
      std::vector<std::uint32_t> next(first.begin(), first.end() - 1);
      for (std::size_t i = 0; i < n; ++i)
        order[next[segment[i]]++] = std::uint32_t(i);
    }
    const std::vector<char> negate =
      choose_islands<ConcurrencyTag>(segments, n, search, [&](std::uint32_t s, const auto& block) {
        for (std::uint32_t q = first[s]; q < first[s + 1]; ++q)
          for (std::uint32_t t = inc.first[order[q]]; t < inc.first[order[q] + 1]; ++t)
            block(segment[inc.other[t]]);
      });
    const std::size_t this_round = std::size_t(std::count(negate.begin(), negate.end(), char(1)));
    for (std::size_t i = 0; i < n; ++i)
      if (negate[segment[i]])
        labels[i] = Label(-labels[i]);
    negated += this_round;
    if (this_round == 0)
      break;
  }
  return negated;
}

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_FRUSTRATED_ISLANDS_H
