#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Speed and peak memory of the orient_normals program of two build trees on
# the same cloud, run alternately (old, new, old, new, ...) so that both see
# the same machine; prints wall time and peak RSS (/usr/bin/time -v) per run
# and whether the outputs are the same bytes.
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
for ((i = 1; i <= runs; ++i)); do
  for who in old new; do
    dir=$old; [[ $who == new ]] && dir=$new
    /usr/bin/time -v "$dir/examples/orient_normals" --quiet "$@" "$cloud" "$work/$who.ply" 2> "$work/time.txt"
    wall=$(grep "Elapsed (wall" "$work/time.txt" | awk '{print $NF}')
    peak=$(grep "Maximum resident" "$work/time.txt" | awk '{print $NF}')
    echo "$who run $i: wall $wall, peak $peak kB"
  done
done
if cmp -s "$work/old.ply" "$work/new.ply"; then echo "outputs identical"; else echo "outputs DIFFER"; exit 1; fi
