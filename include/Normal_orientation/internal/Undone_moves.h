// SPDX-License-Identifier: GPL-3.0-or-later
// This file is part of Normal_orientation.
#ifndef NORMAL_ORIENTATION_INTERNAL_UNDONE_MOVES_H
#define NORMAL_ORIENTATION_INTERNAL_UNDONE_MOVES_H

/// \file Undone_moves.h
/// The in-core global stage's last correction of the solver: a move away
/// from the solver's start that the stage undid for the most part is undone
/// in full (`complete_undone_moves()`); a move it undid in full is one the
/// stage starts again without (`rejected_moves()`).

#include <Normal_orientation/Orientation_problem.h>
#include <Normal_orientation/Signed_union_find.h>
#include <Normal_orientation/internal/Graph_reduction.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

/// \cond SKIP_IN_MANUAL
namespace Normal_orientation {
namespace internal {

/// The share of a move's points that the stage must have negated for the
/// rest of the move to follow: more than half.
constexpr double undone_move_share = 0.5;

/// The solver's moves: the connected sets (over the edges of `inc`) of the
/// points of `moved` (per point), as the sets of a union-find.
inline Signed_union_find solver_move_sets(const Incidence& inc, const std::vector<char>& moved)
{
  typedef Signed_union_find::Index Index;
  const std::size_t n = inc.number_of_vertices();
  Signed_union_find moves(n);
  for (std::size_t i = 0; i < n; ++i)
    if (moved[i])
      for (std::uint32_t t = inc.first[i]; t < inc.first[i + 1]; ++t)
        if (moved[inc.other[t]] && inc.other[t] > i)
          moves.unite(Index(i), Index(inc.other[t]));
  return moves;
}

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
  Signed_union_find moves = solver_move_sets(inc, moved);
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

/// The stage runs again without the moves it rejected only when they hold
/// at least this share of the points: smaller moves change the field at few
/// samples, and the second run costs a whole stage.
constexpr double rejected_move_share = 0.003;

/// What `rejected_moves()` leaves for the stage's second run.
struct Stage_restart
{
  std::size_t rejected = 0; ///< the moves the stage negated in full (0: no second run)
  std::vector<char> moved;  ///< the solver's moves that remain (per point)
};

/// The solver's moves (as for `complete_undone_moves()`) whose every point
/// the stage negated: it found them wrong, but took its other decisions,
/// and the component signs before it, with the cloud that had them.  When
/// there is one, and they hold at least `rejected_move_share` of the points,
/// `remaining` gets `moved` without them: the solver's labels negated where
/// the two differ are those to sign and stage again.  Else `remaining` is
/// left empty.  `before` holds the labels the stage started from, `after`
/// its labels.  Moves with a point of `keep` (per point, or empty) are never
/// rejected, as in `complete_undone_moves()`.  Returns the number of those
/// moves (0 when they are too small).
inline std::size_t rejected_moves(const Incidence& inc, const std::vector<char>& moved,
                                  const std::vector<char>& keep, const std::vector<Label>& before,
                                  const std::vector<Label>& after, std::vector<char>& remaining)
{
  remaining.clear();
  const std::size_t n = inc.number_of_vertices();
  if (moved.size() != n || before.size() != n || after.size() != n ||
      double(std::count(moved.begin(), moved.end(), char(1))) < rejected_move_share * double(n))
    return 0;
  typedef Signed_union_find::Index Index;
  Signed_union_find moves = solver_move_sets(inc, moved);
  std::vector<char> kept(n, 0); // (per root: a point that the stage left as it was, or that keeps its sign)
  for (std::size_t i = 0; i < n; ++i)
    if (moved[i] && (after[i] == before[i] || (!keep.empty() && keep[i])))
      kept[moves.find(Index(i))] = 1;
  std::size_t rejected = 0, points = 0; // (points: of the rejected moves)
  for (std::size_t i = 0; i < n; ++i)
    if (moved[i] && !kept[moves.find(Index(i))]) {
      ++points;
      rejected += moves.find(Index(i)) == Index(i) ? 1 : 0;
    }
  if (rejected == 0 || double(points) < rejected_move_share * double(n))
    return 0;
  remaining = moved;
  for (std::size_t i = 0; i < n; ++i)
    if (moved[i] && !kept[moves.find(Index(i))])
      remaining[i] = 0;
  return rejected;
}

} // namespace internal
} // namespace Normal_orientation
/// \endcond

#endif // NORMAL_ORIENTATION_INTERNAL_UNDONE_MOVES_H
