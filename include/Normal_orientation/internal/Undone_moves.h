// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_UNDONE_MOVES_H
#define NORMAL_ORIENTATION_INTERNAL_UNDONE_MOVES_H

/// \file Undone_moves.h
/// The in-core global stage's last correction of the solver: a move away
/// from the solver's start that the stage undid for the most part is undone
/// in full (`complete_undone_moves()`).

#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Signed_union_find.h>
#include <Normal_orientation/internal/Graph_reduction.h>

#include <cstddef>
#include <cstdint>
#include <vector>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// The share of a move's points that the stage must have negated for the
/// rest of the move to follow: more than half.
constexpr double undone_move_share = 0.5;

/// The moves of the solver are the connected sets (over the edges of `inc`)
/// of the points that it negated against its start (`moved`, per point;
/// empty: no start, and nothing is done).  A move of which the stage negated
/// more than `undone_move_share` of the points, but not all, has its other
/// points negated too: the stage found the move wrong, and the rest is
/// what its patches could not reach (too small for the field, or joined
/// across a contact to the other side).  `before` holds the labels the stage
/// started from, `labels` its labels, updated here.  Moves with a point of
/// `keep` (per point, or empty) are left as they are.  Returns the number of
/// moves completed.
inline std::size_t complete_undone_moves(const Incidence& inc, const std::vector<char>& moved,
                                         const std::vector<char>& keep, const std::vector<Label>& before,
                                         std::vector<Label>& labels)
{
  const std::size_t n = inc.number_of_vertices();
  if (moved.size() != n || before.size() != n || labels.size() != n)
    return 0;
  typedef Signed_union_find::Index Index;
  Signed_union_find moves(n);
  for (std::size_t i = 0; i < n; ++i)
    if (moved[i])
      for (std::uint32_t t = inc.first[i]; t < inc.first[i + 1]; ++t)
        if (moved[inc.other[t]] && inc.other[t] > i)
          moves.unite(Index(i), Index(inc.other[t]));
  std::vector<std::uint32_t> size(n, 0), negated(n, 0); // (per root)
  std::vector<char> kept(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    if (moved[i]) {
      const Index r = moves.find(Index(i));
      ++size[r];
      negated[r] += labels[i] != before[i] ? 1 : 0;
      kept[r] = char(kept[r] || (!keep.empty() && keep[i]));
    }
  std::size_t completed = 0;
  for (std::size_t r = 0; r < n; ++r)
    if (!kept[r] && size[r] > 0 && negated[r] < size[r] && double(negated[r]) > undone_move_share * double(size[r])) {
      ++completed;
      size[r] = 0; // (marks the move: complete it below)
    }
  for (std::size_t i = 0; i < n; ++i)
    if (moved[i] && size[moves.find(Index(i))] == 0 && labels[i] == before[i])
      labels[i] = Label(-labels[i]);
  return completed;
}

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_UNDONE_MOVES_H
