#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The Poisson pipeline (examples/reconstruct_surface) on clouds sampled from
# closed meshes with randomly signed normals: per mesh, whether the mesh is
# closed and outward, the mean and largest vertex distance to the true
# surface (% of the bounding-box diagonal) and the volume ratio. Issue 5 asks
# for closed, outward, mean < 0.5% and volume within 10%.
#
# usage: reconstruction_quality.sh BUILD_DIR [--points N] [--noise F] [--seed S] [MESH.off...]
set -euo pipefail
if [[ $# -lt 1 || ! -d "$1" ]]; then
  echo "usage: reconstruction_quality.sh BUILD_DIR [--points N] [--noise F] [--seed S] [MESH.off...]" >&2
  exit 2
fi
build=$1
shift
points=30000 noise=0 seed=1
meshes=()
while [[ $# -gt 0 ]]; do
  case $1 in
    --points) points=$2; shift 2 ;;
    --noise) noise=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --*) echo "reconstruction_quality.sh: unknown option '$1'" >&2; exit 2 ;;
    *) meshes+=("$1"); shift ;;
  esac
done
[[ ${#meshes[@]} -gt 0 ]] || meshes=("$(dirname "$0")"/../../shared/data/meshes/*.off)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
echo "| mesh | points | noise | closed, outward | mean distance | largest distance | volume ratio | seconds |"
echo "|---|---:|---:|---|---:|---:|---:|---:|"
for mesh in "${meshes[@]}"; do
  name=$(basename "$mesh" .off)
  "$build/benchmark/make_cloud" "$mesh" "$points" "$work/$name" --noise "$noise" --seed "$seed" > /dev/null 2>&1
  start=$(date +%s.%N)
  if out=$("$build/examples/reconstruct_surface" "$work/$name.xyz" "$work/$name.off" --reference "$mesh" 2>&1); then
    end=$(date +%s.%N)
    ok=$(echo "$out" | grep -q "closed, outward" && echo yes || echo NO)
    mean=$(echo "$out" | sed -nE 's/.*mean distance ([0-9.]+%).*/\1/p')
    largest=$(echo "$out" | sed -nE 's/.*largest ([0-9.]+%).*/\1/p')
    ratio=$(echo "$out" | sed -nE 's/.* = ([0-9.]+)$/\1/p')
    echo "| $name | $points | $noise | $ok | $mean | $largest | $ratio | $(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.1f", b - a }') |"
  else
    echo "| $name | $points | $noise | FAILED: $(echo "$out" | tail -1) | | | | |"
  fi
done
