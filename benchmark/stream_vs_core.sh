#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Streamed against in-core orientation, in wrong (inward) normals against the
# mesh: for each mesh and noise level, samples a cloud (make_cloud), orients
# it in core (default solver) and with --stream, and counts the wrong normals
# of both outputs with count_wrong_normals.  Prints a Markdown table; the
# last column is the streamed run's excess, in percent of the points (issue 4
# asks for at most 0.5 at 200k points).
#
# usage: stream_vs_core.sh BUILD_DIR [--points N] [--noise a,b,...] [--seed S]
#                          [--meshes FILES...] [--ours-args "..."] [--stream-args "..."]
# (--ours-args go to both runs, --stream-args only to the streamed one, e.g.
# "--refine 0")
set -euo pipefail
if [[ $# -lt 1 || ! -d "$1" ]]; then
  echo "usage: stream_vs_core.sh BUILD_DIR [--points N] [--noise a,b,...] [--seed S] [--meshes FILES...] [--ours-args \"...\"] [--stream-args \"...\"]" >&2
  exit 2
fi
build=$1
shift
points=200000
noise=0,0.001
seed=1
args=""
stream_args=""
meshes=()
while [[ $# -gt 0 ]]; do
  case $1 in
    --points) points=$2; shift 2 ;;
    --noise) noise=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --ours-args) args=$2; shift 2 ;;
    --stream-args) stream_args=$2; shift 2 ;;
    --meshes) shift; while [[ $# -gt 0 && $1 != --* ]]; do meshes+=("$1"); shift; done ;;
    *) echo "stream_vs_core.sh: unknown option '$1'" >&2; exit 2 ;;
  esac
done
if [[ ${#meshes[@]} -eq 0 ]]; then
  meshes=("$(dirname "$0")"/../../shared/data/meshes/*.off)
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
ours="$build/examples/orient_normals"
wrong() { "$build/benchmark/count_wrong_normals" "$1" "$2" --json 2>/dev/null | sed -E 's/.*"wrong": ([0-9]+).*/\1/'; }

echo "| mesh | points | noise | in core wrong | streamed wrong | segments | excess (% of points) |"
echo "|---|---:|---:|---:|---:|---:|---:|"
total_core=0
total_stream=0
total_points=0
IFS=, read -r -a levels <<< "$noise"
for mesh in "${meshes[@]}"; do
  name=$(basename "$mesh" .off)
  for f in "${levels[@]}"; do
    "$build/benchmark/make_cloud" "$mesh" "$points" "$work/c" --noise "$f" --seed "$seed" > /dev/null
    # shellcheck disable=SC2086
    "$ours" --quiet $args "$work/c.xyz" "$work/core.ply"
    # shellcheck disable=SC2086
    segments=$("$ours" --quiet --json --stream $args $stream_args "$work/c.xyz" "$work/stream.ply" |
               sed -E 's/.*"segments": ([0-9]+).*/\1/')
    wc=$(wrong "$mesh" "$work/core.ply")
    ws=$(wrong "$mesh" "$work/stream.ply")
    excess=$(awk -v a="$ws" -v b="$wc" -v n="$points" 'BEGIN { printf "%+.2f", 100 * (a - b) / n }')
    pc=$(awk -v a="$wc" -v n="$points" 'BEGIN { printf "%.2f", 100 * a / n }')
    ps=$(awk -v a="$ws" -v n="$points" 'BEGIN { printf "%.2f", 100 * a / n }')
    echo "| $name | $points | $f | $wc ($pc%) | $ws ($ps%) | $segments | $excess |"
    total_core=$((total_core + wc))
    total_stream=$((total_stream + ws))
    total_points=$((total_points + points))
  done
done
echo "| total | $total_points | | $total_core | $total_stream | | $(awk -v a="$total_stream" -v b="$total_core" -v n="$total_points" 'BEGIN { printf "%+.2f", 100 * (a - b) / n }') |"
