#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# This file is part of Normal_orientation.
#
# ipsr_orient.sh IPSR_BINARY IN.xyz OUT.xyz
#
# Orients the normals of IN.xyz (x y z nx ny nz) with iPSR, an optional peer of the benchmark
# (build it with build_ipsr.sh; its code never enters this project, only its binary is run):
#   1. the points of IN go to an ASCII PLY (x y z only: iPSR ignores normals);
#   2. iPSR runs with its default settings and writes the surface it reconstructs (a mesh);
#   3. transfer_signs writes OUT: the INPUT points with the INPUT normals, in the input order,
#      each negated where it disagrees with the normal of the closest triangle of iPSR's mesh.
# Environment:
#   TRANSFER_SIGNS  path of benchmark/transfer_signs (default: found in PATH)
#   IPSR_ARGS       extra arguments for iPSR (default none: its defaults)
#   IPSR_KEEP       a directory where the PLY input, iPSR's mesh and log are kept
# Prints iPSR's wall time in seconds to stderr ("ipsr_seconds S"). Exit status 0 when OUT is
# written, 1 when iPSR or the transfer failed (OUT is then absent), 2 on bad usage.
set -euo pipefail

if [[ $# -ne 3 || "$1" == -h || "$1" == --help ]]; then
  echo "usage: ipsr_orient.sh IPSR_BINARY IN.xyz OUT.xyz" >&2
  exit 2
fi
ipsr=$1
input=$2
output=$3
transfer=${TRANSFER_SIGNS:-$(command -v transfer_signs || true)}
if [[ ! -x "$ipsr" ]]; then echo "ipsr_orient.sh: '$ipsr' is not an executable" >&2; exit 1; fi
if [[ ! -r "$input" ]]; then echo "ipsr_orient.sh: cannot read '$input'" >&2; exit 1; fi
if [[ -z "$transfer" || ! -x "$transfer" ]]; then
  echo "ipsr_orient.sh: transfer_signs not found (set TRANSFER_SIGNS to benchmark/transfer_signs of a build)" >&2
  exit 1
fi
ipsr=$(cd "$(dirname "$ipsr")" && pwd)/$(basename "$ipsr")

work=$(mktemp -d "${TMPDIR:-/tmp}/ipsr_orient.XXXXXX")
trap 'rm -rf "$work"' EXIT
rm -f "$output"

# 1. Points only, in the input order (comment lines, blank lines and a count line skipped).
awk 'NF >= 3 && $1 !~ /^#/ { print $1, $2, $3 }' "$input" > "$work/points.txt"
count=$(wc -l < "$work/points.txt")
if [[ "$count" -eq 0 ]]; then echo "ipsr_orient.sh: '$input' holds no point" >&2; exit 1; fi
{
  printf 'ply\nformat ascii 1.0\nelement vertex %d\n' "$count"
  printf 'property float x\nproperty float y\nproperty float z\nend_header\n'
  cat "$work/points.txt"
} > "$work/in.ply"

# 2. iPSR, in the work directory (it exits with 0 even on failure: the mesh is the test).
read -r -a extra <<< "${IPSR_ARGS:-}"
start=$(date +%s.%N)
status=0
(cd "$work" && "$ipsr" --in in.ply --out mesh.ply "${extra[@]}") > "$work/ipsr.log" 2>&1 || status=$?
end=$(date +%s.%N)
seconds=$(awk -v a="$start" -v b="$end" 'BEGIN { printf "%.2f", b - a }')
if [[ -n "${IPSR_KEEP:-}" ]]; then
  mkdir -p "$IPSR_KEEP"
  cp -f "$work/in.ply" "$work/ipsr.log" "$IPSR_KEEP/"
  [[ -f "$work/mesh.ply" ]] && cp -f "$work/mesh.ply" "$IPSR_KEEP/"
fi
if [[ $status -ne 0 || ! -s "$work/mesh.ply" ]]; then
  echo "ipsr_orient.sh: iPSR failed (status $status, no mesh); the end of its log:" >&2
  tail -5 "$work/ipsr.log" >&2
  exit 1
fi
echo "ipsr_seconds $seconds ($(grep -c '^Iter:' "$work/ipsr.log" || true) iterations)" >&2

# 3. The input normals, with the signs of iPSR's surface.
"$transfer" "$input" "$work/mesh.ply" "$output"
