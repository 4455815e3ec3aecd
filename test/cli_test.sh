#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Tests of the orient_normals command-line program: exit codes, one-line
# errors, no output file after a failure, the JSON report, and that the
# output keeps the input order and only changes signs.
# usage: cli_test.sh PATH_TO_orient_normals
set -u
prog=$(realpath "$1")
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
mkdir -p "$dir/tmp"
export TMPDIR="$dir/tmp"
fails=0
passes=0
check() { # description, then a command that must succeed
  local what="$1"; shift
  if "$@"; then passes=$((passes + 1)); else echo "FAILED: $what"; fails=$((fails + 1)); fi
}
expect_exit() { # expected status, description, command...
  local want="$1" what="$2"; shift 2
  "$@" > "$dir/out.txt" 2> "$dir/err.txt"
  local got=$?
  if [ "$got" -ne "$want" ]; then
    echo "FAILED: $what: exit $got, expected $want; stderr: $(cat "$dir/err.txt")"; fails=$((fails + 1))
  else
    passes=$((passes + 1))
  fi
}

# a small cloud: 600 points on a sphere with random normal signs
awk 'BEGIN { srand(3); for (i = 0; i < 600; i++) { z = 2*rand()-1; a = 6.2831853*rand(); r = sqrt(1-z*z);
  x = r*cos(a); y = r*sin(a); s = (rand() < 0.5) ? -1 : 1; printf "%.7f %.7f %.7f %.7f %.7f %.7f\n", x, y, z, s*x, s*y, s*z } }' > "$dir/sphere.xyz"

expect_exit 0 "orients a sphere" "$prog" --quiet "$dir/sphere.xyz" "$dir/out.xyz"
check "output exists" test -s "$dir/out.xyz"
check "same number of lines" test "$(wc -l < "$dir/out.xyz")" -eq 600
check "every normal points outward, order kept" awk 'NR==FNR { x[FNR]=$1; y[FNR]=$2; z[FNR]=$3; next }
  { if ($1 != x[FNR] || $2 != y[FNR] || $3 != z[FNR] || $1*$4 + $2*$5 + $3*$6 <= 0) bad++ } END { exit bad > 0 }' \
  "$dir/sphere.xyz" "$dir/out.xyz"

expect_exit 0 "json report" "$prog" --quiet --json "$dir/sphere.xyz" "$dir/out.ply"
for key in points edges components energy_before energy_after solver seconds; do
  check "json has $key" grep -q "\"$key\"" "$dir/out.txt"
done
check "json is one line" test "$(wc -l < "$dir/out.txt")" -eq 1
check "ply output exists" test -s "$dir/out.ply"
expect_exit 0 "reads its own binary ply" "$prog" --quiet --criterion xie "$dir/out.ply" "$dir/again.xyz"
expect_exit 0 "konig criterion" "$prog" --quiet --criterion konig "$dir/sphere.xyz" "$dir/konig.xyz"
expect_exit 0 "threads and seed" "$prog" --quiet --threads 1 --seed 5 "$dir/sphere.xyz" "$dir/t1.xyz"
expect_exit 0 "two threads" "$prog" --quiet --threads 2 --seed 5 "$dir/sphere.xyz" "$dir/t2.xyz"
check "same result with 1 and 2 threads" cmp -s "$dir/t1.xyz" "$dir/t2.xyz"

expect_exit 0 "qpbo-i solver" "$prog" --quiet --json --solver qpbo-i --orders 2 "$dir/sphere.xyz" "$dir/qpbo.xyz"
check "json names the qpbo-i solver" grep -q '"solver": "qpbo-i"' "$dir/out.txt"
check "qpbo-i normals point outward" awk '{ if ($1*$4 + $2*$5 + $3*$6 <= 0) bad++ } END { exit bad > 0 }' "$dir/qpbo.xyz"

expect_exit 0 "lsa-tr solver" "$prog" --quiet --json --solver lsa-tr "$dir/sphere.xyz" "$dir/lsa.xyz"
check "json names the lsa-tr solver" grep -q '"solver": "lsa-tr"' "$dir/out.txt"
check "lsa-tr normals point outward" awk '{ if ($1*$4 + $2*$5 + $3*$6 <= 0) bad++ } END { exit bad > 0 }' "$dir/lsa.xyz"

# a viewpoint prior from the centre: every solver turns the sphere inward
for solver in mst qpbo-i lsa-tr; do
  expect_exit 0 "viewpoint prior, $solver" "$prog" --quiet --json --solver $solver --viewpoint 0,0,0 --prior-weight 0.05 \
    "$dir/sphere.xyz" "$dir/prior_$solver.xyz"
  check "json counts the unary terms ($solver)" grep -q '"unary_terms": 600' "$dir/out.txt"
  check "prior normals point inward ($solver)" awk '{ if ($1*$4 + $2*$5 + $3*$6 >= 0) bad++ } END { exit bad > 0 }' \
    "$dir/prior_$solver.xyz"
done

# --stream: out of core; every normal outward, each input point exactly once
# (in sweep order), only signs changed; the same with 1 and 2 threads
expect_exit 0 "stream" "$prog" --quiet --json --stream "$dir/sphere.xyz" "$dir/stream.xyz"
check "stream json" grep -q '"mode": "stream"' "$dir/out.txt"
check "stream json has segments" grep -q '"segments": ' "$dir/out.txt"
check "stream json names the segment-graph energies" grep -q '"segment_energy_after": ' "$dir/out.txt"
check "stream output is a permutation of the input with outward normals" awk '
  NR==FNR { key[sprintf("%.7f %.7f %.7f", $1, $2, $3)] = $4 " " $5 " " $6; n++; next }
  { k = sprintf("%.7f %.7f %.7f", $1, $2, $3); if (!(k in key) || seen[k]++ || $1*$4 + $2*$5 + $3*$6 <= 0) bad++;
    split(key[k], m, " ");
    if (($4 != m[1]+0 || $5 != m[2]+0 || $6 != m[3]+0) && ($4 != -m[1] || $5 != -m[2] || $6 != -m[3])) bad++; c++ }
  END { exit (bad > 0 || c != n) }' "$dir/sphere.xyz" "$dir/stream.xyz"
expect_exit 0 "stream to binary ply, 1 thread" "$prog" --quiet --stream --threads 1 "$dir/sphere.xyz" "$dir/s1.ply"
expect_exit 0 "stream to binary ply, 2 threads" "$prog" --quiet --stream --threads 2 "$dir/sphere.xyz" "$dir/s2.ply"
check "stream: same bytes with 1 and 2 threads" cmp -s "$dir/s1.ply" "$dir/s2.ply"
expect_exit 0 "stream reads its own ply" "$prog" --quiet --stream --solver mst "$dir/s1.ply" "$dir/s3.xyz"
awk '{ print $1, $2, $3 }' "$dir/sphere.xyz" > "$dir/nonormals.xyz"
expect_exit 1 "stream needs normals" "$prog" --quiet --stream "$dir/nonormals.xyz" "$dir/none.xyz"
check "no output after a failed stream" test ! -e "$dir/none.xyz"
expect_exit 2 "stream refuses --viewpoint" "$prog" --quiet --stream --viewpoint 0,0,0 "$dir/sphere.xyz" "$dir/none.xyz"
check "no temporary files left in TMPDIR" test -z "$(ls -A "$dir/tmp" 2>/dev/null)"

# SIGTERM during a streamed run: no output, no temporary file left
awk 'BEGIN { srand(5); for (i = 0; i < 400000; i++) { z = 2*rand()-1; a = 6.2831853*rand(); r = sqrt(1-z*z);
  x = r*cos(a); y = r*sin(a); s = (rand() < 0.5) ? -1 : 1; printf "%.7f %.7f %.7f %.7f %.7f %.7f\n", x, y, z, s*x, s*y, s*z } }' > "$dir/big.xyz"
"$prog" --quiet --stream "$dir/big.xyz" "$dir/big_out.ply" 2> /dev/null &
pid=$!
sleep 0.5
kill -TERM $pid 2> /dev/null
wait $pid
status=$?
check "SIGTERM ends the run (status $status)" test "$status" -ne 0 -o -e "$dir/big_out.ply"
check "no partial output after SIGTERM" test -z "$(ls "$dir" | grep '^big_out.ply.tmp')"
if [ ! -e "$dir/big_out.ply" ]; then
  check "no temporary files after SIGTERM" test -z "$(ls -A "$dir/tmp")"
fi

# points without normals: estimated first
awk '{ print $1, $2, $3 }' "$dir/sphere.xyz" > "$dir/bare.xyz"
expect_exit 0 "estimates missing normals" "$prog" --quiet --normals pca "$dir/bare.xyz" "$dir/bare_out.xyz"
check "estimated normals point outward" awk '{ if ($1*$4 + $2*$5 + $3*$6 <= 0) bad++ } END { exit bad > 0 }' "$dir/bare_out.xyz"

# bad options: exit 2, one line on stderr, no output
for args in "--k 0" "--k x" "--radius -1" "--criterion foo" "--solver foo" "--orders 0" "--threads 0" "--bogus" "--viewpoint 1,2" "--prior-weight 1" "--viewpoint 0,0,0 --prior-weight -1" "--viewpoint 0,0,0 --prior-weight nan"; do
  # shellcheck disable=SC2086
  expect_exit 2 "bad option $args" "$prog" $args "$dir/sphere.xyz" "$dir/bad_opt.xyz"
  check "one-line error for $args" test "$(wc -l < "$dir/err.txt")" -eq 1
  check "no output for $args" test ! -e "$dir/bad_opt.xyz"
done

# bad input files: exit 1, one line, no output, no temporary left
expect_exit 1 "missing file" "$prog" "$dir/none.xyz" "$dir/bad_in.xyz"
printf '1 2 3 0 0 1\n4 5 nan 0 0 1\n' > "$dir/nan.xyz"
expect_exit 1 "nan coordinate" "$prog" "$dir/nan.xyz" "$dir/bad_in.xyz"
check "nan error names the line" grep -q "line 2" "$dir/err.txt"
printf '1 2 3 0 0 1\n4 5 6 0 0\n' > "$dir/cols.xyz"
expect_exit 1 "wrong column count" "$prog" "$dir/cols.xyz" "$dir/bad_in.xyz"
printf 'ply\nformat binary_little_endian 1.0\nelement vertex 100\nproperty float x\nproperty float y\nproperty float z\nend_header\n' > "$dir/trunc.ply"
head -c 120 /dev/urandom >> "$dir/trunc.ply"
expect_exit 1 "truncated ply" "$prog" "$dir/trunc.ply" "$dir/bad_in.xyz"
check "one-line error for truncated ply" test "$(wc -l < "$dir/err.txt")" -eq 1
expect_exit 1 "unknown extension" "$prog" "$dir/sphere.xyz" "$dir/out.obj"
expect_exit 1 "unwritable output" "$prog" "$dir/sphere.xyz" "$dir/no/such/dir/out.xyz"
check "no output after failures" test ! -e "$dir/bad_in.xyz"
check "no temporary left behind" test -z "$(find "$dir" -name '*.tmp*')"

# the sample cloud, without arguments, written in the working directory
( cd "$dir" && "$prog" > "$dir/sample_stdout.txt" 2> "$dir/sample_err.txt" )
check "sample run says where it wrote" grep -q "sample_oriented.ply" "$dir/sample_err.txt"
check "sample output exists" test -s "$dir/sample_oriented.ply"

echo "$passes passed, $fails failed"
[ "$fails" -eq 0 ]
