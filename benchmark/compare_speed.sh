#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Speed and peak memory of the orient_normals program of two build trees on
# the same cloud, run alternately (old, new, old, new, ...) so that both see
# the same machine; prints wall time and peak RSS (/usr/bin/time -v) per run,
# the medians, the new build's throughput in percent of the old one's (the
# ratio of the median wall times), and whether the outputs are the same
# bytes (exit status 1 when they differ).
#
# usage: compare_speed.sh OLD_BUILD NEW_BUILD CLOUD [RUNS] [-- ORIENT_NORMALS_ARGS...]
set -euo pipefail
if [[ $# -lt 3 || ! -d "$1" || ! -d "$2" || ! -f "$3" ]]; then
  echo "usage: compare_speed.sh OLD_BUILD NEW_BUILD CLOUD [RUNS] [-- ORIENT_NORMALS_ARGS...]" >&2
  exit 2
fi
old=$1 new=$2 cloud=$3
shift 3
runs=3
if [[ $# -gt 0 && $1 != -- ]]; then runs=$1; shift; fi
[[ $# -gt 0 && $1 == -- ]] && shift
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# seconds of /usr/bin/time's wall time ([h:]m:ss.ss)
to_seconds() { awk -F: '{ s = 0; for (i = 1; i <= NF; ++i) s = s * 60 + $i; printf "%.2f\n", s }' <<< "$1"; }
# the median of the numbers on standard input
median() { sort -g | awk '{ v[NR] = $1 } END { if (NR % 2) print v[(NR + 1) / 2]; else printf "%.10g\n", (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
for ((i = 1; i <= runs; ++i)); do
  for who in old new; do
    dir=$old; [[ $who == new ]] && dir=$new
    /usr/bin/time -v "$dir/examples/orient_normals" --quiet "$@" "$cloud" "$work/$who.ply" 2> "$work/time.txt"
    wall=$(grep "Elapsed (wall" "$work/time.txt" | awk '{print $NF}')
    peak=$(grep "Maximum resident" "$work/time.txt" | awk '{print $NF}')
    echo "$who run $i: wall $wall, peak $peak kB"
    to_seconds "$wall" >> "$work/$who.walls"
    echo "$peak" >> "$work/$who.peaks"
  done
done
old_wall=$(median < "$work/old.walls") new_wall=$(median < "$work/new.walls")
echo "median wall: old $old_wall s, new $new_wall s; median peak: old $(median < "$work/old.peaks") kB," \
  "new $(median < "$work/new.peaks") kB"
awk -v o="$old_wall" -v n="$new_wall" 'BEGIN { printf "new throughput: %.1f%% of old\n", 100 * o / n }'
if cmp -s "$work/old.ply" "$work/new.ply"; then echo "outputs identical"; else echo "outputs DIFFER"; exit 1; fi
