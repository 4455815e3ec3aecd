#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Behaviour check for refactorings: runs the orient_normals program of two
# build trees on the same clouds, with default options and a few others, in
# core and with --stream, and compares the outputs byte for byte (cmp).
# Clouds: the bundled sample, and make_cloud samples of the meshes given
# (default: ../shared/data/meshes/*.off when present) at two sizes and two
# noise levels.  Prints one line per run and "N passed, M failed".
#
# usage: compare_builds.sh OLD_BUILD NEW_BUILD [--points "N1 N2"] [--meshes FILES...]
#                          [--args-set "ARGS1|ARGS2|..."]
set -euo pipefail
if [[ $# -lt 2 || ! -d "$1" || ! -d "$2" ]]; then
  echo "usage: compare_builds.sh OLD_BUILD NEW_BUILD [--points \"N1 N2\"] [--meshes FILES...] [--args-set \"A|B\"]" >&2
  exit 2
fi
old=$1 new=$2
shift 2
here=$(cd "$(dirname "$0")" && pwd)
points="30000 200000"
argsets="|--stream|--solver mst|--stream --refine 0|--criterion xie|--stream --presorted x --refine 1"
meshes=()
while [[ $# -gt 0 ]]; do
  case $1 in
    --points) points=$2; shift 2 ;;
    --args-set) argsets=$2; shift 2 ;;
    --meshes) shift; while [[ $# -gt 0 && $1 != --* ]]; do meshes+=("$1"); shift; done ;;
    *) echo "compare_builds.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
if [[ ${#meshes[@]} -eq 0 && -d "$here/../../shared/data/meshes" ]]; then
  meshes=("$here"/../../shared/data/meshes/*.off)
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
clouds=("$here/../examples/data/sample.xyz")
for mesh in "${meshes[@]}"; do
  for n in $points; do
    for f in 0 0.002; do
      c="$work/$(basename "$mesh" .off)_${n}_$f"
      "$old/benchmark/make_cloud" "$mesh" "$n" "$c" --noise "$f" --seed 7 > /dev/null
      rm -f "$c.gt.xyz"
      clouds+=("$c.xyz")
    done
  done
done
passed=0 failed=0
IFS='|' read -r -a sets <<< "$argsets"
for cloud in "${clouds[@]}"; do
  for a in "${sets[@]}"; do
    if [[ $a == *presorted* ]]; then # presorted input: sort the cloud along x first
      sorted="$work/sorted_$(basename "$cloud")"
      [[ -f $sorted ]] || sort -g -k1,1 -s "$cloud" > "$sorted"
      in=$sorted
    else
      in=$cloud
    fi
    ext=ply
    [[ $a == *keep-order* ]] && ext=${in##*.} # a copy in the input's own format
    rm -f "$work/old.$ext" "$work/new.$ext"
    # shellcheck disable=SC2086
    "$old/examples/orient_normals" --quiet $a "$in" "$work/old.$ext" > /dev/null 2>&1 || echo "(failed: $?)" > "$work/old.$ext"
    # shellcheck disable=SC2086
    "$new/examples/orient_normals" --quiet $a "$in" "$work/new.$ext" > /dev/null 2>&1 || echo "(failed: $?)" > "$work/new.$ext"
    if cmp -s "$work/old.$ext" "$work/new.$ext"; then
      passed=$((passed + 1)); echo "same      $(basename "$cloud") [$a]"
    else
      failed=$((failed + 1)); echo "DIFFERENT $(basename "$cloud") [$a]"
    fi
  done
done
echo "$passed passed, $failed failed"
[[ $failed -eq 0 ]]
