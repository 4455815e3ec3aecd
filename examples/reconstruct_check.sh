#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Checks reconstruct_surface against issue 5's criteria: the mesh is closed
# and outward, its volume is within 10% of the truth, and (with a reference
# mesh) its vertices lie within 0.5% of the diagonal from the true surface
# on average.
#
# usage: reconstruct_check.sh RECONSTRUCT WORKDIR cloud IN.xyz TRUE_VOLUME
#        reconstruct_check.sh RECONSTRUCT WORKDIR mesh MAKE_CLOUD MESH.off POINTS
set -euo pipefail
bin=$1 work=$2 mode=$3
mkdir -p "$work"
fail() { echo "reconstruct_check: FAILED: $*"; exit 1; }
if [[ $mode == cloud ]]; then
  out=$("$bin" "$4" "$work/cloud.off") || fail "reconstruct_surface exited with $?"
  echo "$out"
  volume=$(echo "$out" | sed -nE 's/.*volume ([0-9.e+-]+)$/\1/p')
  ratio=$(awk -v a="$volume" -v b="$5" 'BEGIN { print a / b }')
else
  name=$(basename "$5" .off)
  "$4" "$5" "$6" "$work/$name" --seed 7 > /dev/null || fail "make_cloud exited with $?"
  out=$("$bin" "$work/$name.xyz" "$work/$name.off" --reference "$5") || fail "reconstruct_surface exited with $?"
  echo "$out"
  mean=$(echo "$out" | sed -nE 's/.*mean distance ([0-9.]+)%.*/\1/p')
  ratio=$(echo "$out" | sed -nE 's/.* = ([0-9.]+)$/\1/p')
  [[ -n $mean ]] || fail "no distance in the output"
  awk -v m="$mean" 'BEGIN { exit !(m < 0.5) }' || fail "mean distance $mean% >= 0.5%"
fi
echo "$out" | grep -q "closed, outward" || fail "the mesh is not closed and outward"
[[ -n $ratio ]] || fail "no volume in the output"
awk -v r="$ratio" 'BEGIN { exit !(r > 0.9 && r < 1.1) }' || fail "volume ratio $ratio outside [0.9, 1.1]"
echo "reconstruct_check: OK (volume ratio $ratio)"
