#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The CTests of the example programs: each runs one example on data generated
# here (a torus cloud whose true outward normals are known, written by awk)
# or by the example itself, and checks a property of the result, then checks
# that a bad command line exits with 2 and bad input with 1, one line on stderr.
#
# usage: example_check.sh EXAMPLE PROGRAM WORKDIR [ARGS...]
#   orient_point_set, custom_policies, stream_ply_file: the torus cloud;
#   orient_mesh_graph [--xie] [MESH.off]: >= 99% of the vertex normals right;
#   guided_orientation: the viewpoint, prior and constraints all face the scanner.
set -euo pipefail
export LC_ALL=C # the decimal point of sort -g and awk
example=$1 bin=$2 work=$3
[[ $bin == /* ]] || bin=$PWD/$bin
shift 3
mkdir -p "$work"
cd "$work"
fail() { echo "example_check $example: FAILED: $*"; exit 1; }

# torus N SEED FORMAT [NOISE]: N points on the torus of radii 1 and 0.35, as
# "x y z nx ny nz" lines (FORMAT xyz), an ascii PLY file (ply) or "x y z"
# lines (xyz3); true normals turned by a random vector of components up to
# NOISE (< 0.57: the sign stays that of the truth), with random signs.
torus() {
  awk -v n="$1" -v seed="$2" -v format="$3" -v noise="${4:-0}" 'BEGIN {
    srand(seed); pi = 3.141592653589793
    if (format == "ply")
      printf "ply\nformat ascii 1.0\nelement vertex %d\nproperty double x\nproperty double y\nproperty double z\n" \
             "property double nx\nproperty double ny\nproperty double nz\nend_header\n", n
    for (i = 0; i < n; ++i) {
      u = 2 * pi * rand(); v = 2 * pi * rand(); s = rand() < 0.5 ? -1 : 1
      x = (1 + 0.35 * cos(v)) * cos(u); y = (1 + 0.35 * cos(v)) * sin(u); z = 0.35 * sin(v)
      nx = cos(v) * cos(u) + noise * (2 * rand() - 1); ny = cos(v) * sin(u) + noise * (2 * rand() - 1)
      nz = sin(v) + noise * (2 * rand() - 1)
      if (format == "xyz3") printf "%.9f %.9f %.9f\n", x, y, z
      else printf "%.9f %.9f %.9f %.9f %.9f %.9f\n", x, y, z, s * nx, s * ny, s * nz
    }
  }'
}
# wrong_normals FILE: "WRONG POINTS", WRONG the normals of FILE (x y z nx ny nz
# lines) that do not point out of the torus
wrong_normals() {
  awk 'NF == 6 { l = sqrt($1 * $1 + $2 * $2); d = ($1 - $1 / l) * $4 + ($2 - $2 / l) * $5 + $3 * $6
                 if (!(d > 0)) ++w; ++n }
       END { printf "%d %d\n", w, n }' "$1"
}
# expect_outward FILE POINTS MAX_WRONG: FILE holds POINTS points, at most MAX_WRONG wrong
expect_outward() {
  read -r wrong points < <(wrong_normals "$1")
  [[ $points == "$2" ]] || fail "$1 holds $points points, not $2"
  ((wrong <= $3)) || fail "$1: $wrong normals point into the torus (at most $3 allowed)"
  echo "$1: $points points, $wrong wrong"
}
# expect_status STATUS ARGS...: the example exits with STATUS, and says why in
# one line "EXAMPLE: ..." or a usage line (the stderr may hold progress
# reports, and CGAL's readers print their own complaints too)
expect_status() {
  local status=$1
  shift
  set +e
  "$bin" "$@" > /dev/null 2> stderr.txt
  local got=$?
  set -e
  ((got == status)) || fail "'$example $*' exited with $got, not $status"
  local own usage
  own=$(grep -c "^$example: " stderr.txt || true)
  usage=$(grep -c "^usage: $example " stderr.txt || true)
  ((own == 1 || (status == 2 && own == 0 && usage == 1))) ||
    fail "'$example $*': not a one-line error: $(cat stderr.txt)"
}
# at_least PERCENT MINIMUM WHAT
at_least() {
  [[ -n $1 ]] && awk -v p="$1" -v m="$2" 'BEGIN { exit !(p >= m) }' || fail "$3: '$1'% < $2%"
}

case $example in
orient_point_set)
  torus 20000 1 ply 0.3 > torus.ply
  out=$("$bin" torus.ply given.xyz) || fail "exited with $?"
  echo "$out"
  grep -q "(given normals)" <<< "$out" || fail "the normals of torus.ply were not used"
  expect_outward given.xyz 20000 0
  torus 20000 2 xyz3 > torus_points.xyz # no normals: jet fitting
  out=$("$bin" torus_points.xyz estimated.xyz --k 10 --solver mst) || fail "exited with $?"
  echo "$out"
  grep -q "(estimated normals), k = 10" <<< "$out" || fail "no estimated normals with k = 10"
  grep -q "^solver mst:" <<< "$out" || fail "the solver is not mst"
  expect_outward estimated.xyz 20000 20
  expect_status 2
  expect_status 2 torus.ply x.xyz --solver none
  expect_status 2 torus.ply x.xyz --k 0
  expect_status 1 missing.xyz x.xyz
  [[ ! -e x.xyz ]] || fail "x.xyz written after an error"
  ;;
orient_mesh_graph)
  out=$("$bin" "$@") || fail "exited with $?"
  echo "$out"
  at_least "$(sed -nE 's/.*\(([0-9.]+)%\) agree.*/\1/p' <<< "$out")" 99 "vertex normals agreeing with the mesh"
  expect_status 2 --bogus
  expect_status 2 a.off b.off
  expect_status 1 missing.off
  ;;
custom_policies)
  torus 20000 1 xyz 0.8 > noisy_torus.xyz # noisy enough for frustrated edges
  out=$("$bin" noisy_torus.xyz) || fail "exited with $?"
  echo "$out"
  line=$(grep "^squared-cosine + best-first:" <<< "$out") || fail "the custom policies were not used"
  awk '{ for (i = 1; i < NF; ++i) if ($i == "->") exit !($(i + 1) + 0 < $(i - 1) + 0) }' <<< "$line" ||
    fail "the custom solver did not lower the energy"
  at_least "$(sed -nE 's/.*agree on ([0-9.]+)%.*/\1/p' <<< "$out")" 99 "normals on which custom and default agree"
  torus 100 1 xyz3 > no_normals.xyz
  expect_status 2
  expect_status 1 no_normals.xyz
  expect_status 1 missing.xyz
  ;;
guided_orientation)
  out=$("$bin") || fail "exited with $?"
  echo "$out"
  for what in "viewpoint sign policy" "viewpoint prior" "3 constrained points"; do
    at_least "$(sed -nE "s/^$what[^:]*: *([0-9.]+)% .*/\1/p" <<< "$out")" 100 "$what: normals facing the scanner"
  done
  grep -q "^the constrained normals were kept" <<< "$out" || fail "a constrained normal was changed"
  outward=$(sed -nE 's/^default \(outward\) *: *([0-9.]+)% .*/\1/p' <<< "$out")
  awk -v p="$outward" 'BEGIN { exit !(p < 50) }' || fail "the default faces the scanner ($outward%): nothing to show"
  torus 100 1 xyz > small.xyz
  expect_status 2 small.xyz 0 0
  expect_status 2 small.xyz 0 0 zero
  expect_status 1 missing.xyz 0 0 0
  ;;
stream_ply_file)
  torus 20000 1 ply 0.3 > torus.ply
  out=$("$bin" torus.ply streamed.xyz) || fail "exited with $?"
  echo "$out"
  grep -q "^20000 points, .* 20000 written" <<< "$out" || fail "not 20000 points streamed"
  expect_outward streamed.xyz 20000 0
  "$bin" streamed.xyz streamed.ply > /dev/null || fail "exited with $? on a .xyz input"
  grep -aq "^element vertex 20000 *$" streamed.ply || fail "streamed.ply does not hold 20000 points"
  sort -g -k1,1 streamed.xyz > sorted.xyz # presorted along x: the output keeps the input order
  out=$("$bin" sorted.xyz presorted.xyz --presorted x) || fail "exited with $? with --presorted x"
  echo "$out"
  grep -q ", presorted, " <<< "$out" || fail "the input was not read as presorted"
  expect_outward presorted.xyz 20000 0
  cmp -s <(cut -d' ' -f1-3 sorted.xyz) <(cut -d' ' -f1-3 presorted.xyz) ||
    fail "presorted.xyz is not in the order of sorted.xyz"
  torus 100 1 xyz3 > no_normals.xyz
  expect_status 2
  expect_status 2 torus.ply x.ply --presorted w
  expect_status 1 torus.ply x.ply --presorted y # not sorted along y
  expect_status 1 no_normals.xyz x.ply
  expect_status 1 missing.ply x.ply
  [[ ! -e x.ply ]] || fail "x.ply written after an error"
  ;;
*)
  fail "unknown example"
  ;;
esac
echo "example_check $example: OK"
