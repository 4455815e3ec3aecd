#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Tests of the orient_normals command-line program: exit codes, one-line
# errors, no output file after a failure, the JSON report, and that the
# output keeps the input order and only changes signs.
# usage: cli_test.sh PATH_TO_orient_normals
set -u
prog=$(realpath "$1")
here=$(cd "$(dirname "$0")" && pwd)
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

# determinism on a cloud large enough for every parallel path (the readers
# and writers, the Morton order, the kNN, the graph, the sweep's batches):
# the 20,000-point sample with random signs gives the same bytes with 1 and 2
# threads (and with 0: all cores) for every solver, in core and with --stream
awk 'BEGIN { srand(11) } { s = (rand() < 0.5) ? -1 : 1; print $1, $2, $3, s*$4, s*$5, s*$6 }' \
  "$here/../examples/data/sample.xyz" > "$dir/det.xyz"
check "the determinism cloud has 20,000 points" test "$(wc -l < "$dir/det.xyz")" -eq 20000
for solver in mst qpbo-i lsa-tr; do
  for t in 1 2 0; do
    expect_exit 0 "$solver with --threads $t" "$prog" --quiet --solver $solver --threads $t "$dir/det.xyz" \
      "$dir/det_${solver}_$t.xyz"
  done
  check "$solver: same bytes with 1 and 2 threads" cmp -s "$dir/det_${solver}_1.xyz" "$dir/det_${solver}_2.xyz"
  check "$solver: same bytes with 1 thread and all cores" cmp -s "$dir/det_${solver}_1.xyz" "$dir/det_${solver}_0.xyz"
done
expect_exit 0 "qpbo-i to binary ply, 1 thread" "$prog" --quiet --threads 1 "$dir/det.xyz" "$dir/det_ply_1.ply"
expect_exit 0 "qpbo-i to binary ply, 2 threads" "$prog" --quiet --threads 2 "$dir/det.xyz" "$dir/det_ply_2.ply"
check "binary ply: same bytes with 1 and 2 threads" cmp -s "$dir/det_ply_1.ply" "$dir/det_ply_2.ply"
for solver in mst qpbo-i lsa-tr; do
  for t in 1 2; do
    expect_exit 0 "stream, $solver with --threads $t" "$prog" --quiet --stream --solver $solver --threads $t \
      "$dir/det.xyz" "$dir/det_stream_${solver}_$t.ply"
  done
  check "stream, $solver: same bytes with 1 and 2 threads" \
    cmp -s "$dir/det_stream_${solver}_1.ply" "$dir/det_stream_${solver}_2.ply"
done
# --return-memory changes how the allocator reuses memory, not the result
expect_exit 0 "qpbo-i with --return-memory" "$prog" --quiet --return-memory "$dir/det.xyz" "$dir/det_returned.xyz"
check "--return-memory: the same bytes" cmp -s "$dir/det_qpbo-i_0.xyz" "$dir/det_returned.xyz"
expect_exit 0 "stream to xyz, 1 thread" "$prog" --quiet --stream --threads 1 "$dir/det.xyz" "$dir/det_stream_1.xyz"
expect_exit 0 "stream to xyz, 2 threads" "$prog" --quiet --stream --threads 2 "$dir/det.xyz" "$dir/det_stream_2.xyz"
check "stream to xyz: same bytes with 1 and 2 threads" cmp -s "$dir/det_stream_1.xyz" "$dir/det_stream_2.xyz"
# the batch size of the sweep changes how the work is cut, not the result
expect_exit 0 "stream with batches of 1000" "$prog" --quiet --stream --batch-size 1000 "$dir/det.xyz" \
  "$dir/det_stream_b1000.xyz"
check "stream: same bytes with batches of 1000 and the default" cmp -s "$dir/det_stream_1.xyz" "$dir/det_stream_b1000.xyz"

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
# --viewpoint, --sign keep and --prior-weight work with --stream as in core:
# the sphere's centre as the viewpoint turns every normal inward, in both
inward() { awk '{ if ($1 * $4 + $2 * $5 + $3 * $6 >= 0) bad++; c++ } END { exit (bad > 0 || c != 600) }' "$1"; }
expect_exit 0 "stream with a viewpoint" "$prog" --quiet --stream --viewpoint 0,0,0 "$dir/sphere.xyz" "$dir/sv.xyz"
check "stream with a viewpoint: every normal faces it" inward "$dir/sv.xyz"
expect_exit 0 "in core with a viewpoint" "$prog" --quiet --viewpoint 0,0,0 "$dir/sphere.xyz" "$dir/cv.xyz"
check "in core with a viewpoint: every normal faces it" inward "$dir/cv.xyz"
expect_exit 0 "stream with a viewpoint prior" "$prog" --quiet --json --stream --viewpoint 0,0,0 --prior-weight 0.5 "$dir/sphere.xyz" "$dir/sp.xyz"
check "stream with a viewpoint prior: every normal faces it" inward "$dir/sp.xyz"
check "stream with a prior: unary terms reported" grep -q '"unary_terms": 600' "$dir/out.txt"
expect_exit 0 "stream --sign keep" "$prog" --quiet --json --stream --sign keep "$dir/sphere.xyz" "$dir/sk.xyz"
check "stream --sign keep: reported" grep -q '"component_sign": "keep"' "$dir/out.txt"
check "no temporary files left in TMPDIR" test -z "$(ls -A "$dir/tmp" 2>/dev/null)"
# no progress line when stderr is not a terminal
expect_exit 0 "stream, not quiet" "$prog" --json --stream "$dir/sphere.xyz" "$dir/loud.xyz"
check "no progress line on a stderr that is not a terminal" test "$(tr -cd '\r' < "$dir/err.txt" | wc -c)" -eq 0
check "stream summary on stderr" grep -q "oriented 600 points out of core" "$dir/err.txt"
check "stream json is one line" test "$(wc -l < "$dir/out.txt")" -eq 1

# --write-segments: the segment of each point as the PLY vertex property
# 'int segment', as many distinct values (0 to segments - 1) as the JSON says
expect_exit 0 "stream --write-segments (ascii ply)" "$prog" --quiet --json --stream --write-segments --ascii \
  "$dir/det.xyz" "$dir/seg.ply"
segments=$(sed -n 's/.*"segments": \([0-9]*\),.*/\1/p' "$dir/out.txt")
check "the segment property is declared" grep -q "^property int segment$" "$dir/seg.ply"
check "one segment per point, $segments distinct values, 0 to segments - 1" awk -v n="$segments" '
  header { if ($0 == "end_header") header = 0; else if ($1 == "property") column++; next }
  { if (NF != column || $column < 0 || $column >= n || $column != int($column)) bad++; if (!($column in seen)) distinct++;
    seen[$column] = 1; points++ }
  END { exit (bad > 0 || distinct != n || points != 20000 || n < 2) }' header=1 column=0 "$dir/seg.ply"
expect_exit 0 "stream --write-segments (binary ply)" "$prog" --quiet --stream --write-segments "$dir/det.xyz" \
  "$dir/seg_bin.ply"
check "binary: the segment property is declared" grep -aq "^property int segment$" "$dir/seg_bin.ply"
check "binary: 52 bytes per point" test "$(wc -c < "$dir/seg_bin.ply")" -eq \
  "$(( $(grep -abo "end_header" "$dir/seg_bin.ply" | head -1 | cut -d: -f1) + 11 + 20000 * 52 ))"
expect_exit 0 "a cloud with segments reads back" "$prog" --quiet --solver mst "$dir/seg_bin.ply" "$dir/seg_back.ply"

# --presorted: a file sorted by x gives the same oriented points as the sorted
# path, in its own order; an unsorted one fails at once
sort -g -k1,1 "$dir/sphere.xyz" > "$dir/sphere_x.xyz"
expect_exit 0 "stream --presorted x" "$prog" --quiet --json --stream --presorted x "$dir/sphere_x.xyz" "$dir/presorted.xyz"
check "json says presorted x" grep -q '"presorted": "x"' "$dir/out.txt"
check "presorted output keeps the input order" awk 'NR==FNR { k[FNR] = $1 " " $2 " " $3; n++; next }
  { if (sprintf("%.7f %.7f %.7f", $1, $2, $3) != k[FNR]) bad++; c++ } END { exit (bad > 0 || c != n) }' \
  "$dir/sphere_x.xyz" "$dir/presorted.xyz"
check "presorted: same oriented points as the sorted path" cmp -s <(sort "$dir/stream.xyz") <(sort "$dir/presorted.xyz")
expect_exit 1 "--presorted x on an unsorted file" "$prog" --quiet --stream --presorted x "$dir/sphere.xyz" "$dir/unsorted.xyz"
check "one-line error for an unsorted --presorted input" test "$(wc -l < "$dir/err.txt")" -eq 1
check "the error says the input is not sorted" grep -q "not sorted by increasing x" "$dir/err.txt"
check "no output for an unsorted --presorted input" test -z "$(find "$dir" -name 'unsorted.xyz*')"
check "no temporary files after an unsorted --presorted input" test -z "$(ls -A "$dir/tmp")"

# --components-dir and --min-component-size: two spheres (800 and 400 points)
# and three isolated points
awk 'BEGIN { srand(7); for (i = 0; i < 1200; i++) { c = (i < 800) ? 0 : 4; R = (i < 800) ? 1 : 0.7;
  z = 2*rand()-1; a = 6.2831853*rand(); r = sqrt(1-z*z); x = r*cos(a); y = r*sin(a); s = (rand() < 0.5) ? -1 : 1;
  printf "%.7f %.7f %.7f %.7f %.7f %.7f\n", c + R*x, R*y, R*z, s*x, s*y, s*z }
  for (i = 0; i < 3; i++) printf "%.7f 5.0000000 5.0000000 0 0 1\n", 10 + 3*i }' > "$dir/parts.xyz"
expect_exit 0 "components and a minimum size" "$prog" --quiet --json --stream --radius 0.5 --min-component-size 10 \
  --components-dir "$dir/comps" "$dir/parts.xyz" "$dir/parts_out.xyz"
check "json counts the dropped points" grep -q '"dropped_points": 3,' "$dir/out.txt"
check "json counts the dropped components" grep -q '"dropped_components": 3,' "$dir/out.txt"
check "json counts the component files" grep -q '"component_files": 2,' "$dir/out.txt"
check "one file per kept component, nothing else" test "$(ls "$dir/comps" | tr '\n' ' ')" = "component_000000.xyz component_000001.xyz "
check "the largest component first" test "$(wc -l < "$dir/comps/component_000000.xyz")" -eq 800
check "the second component" test "$(wc -l < "$dir/comps/component_000001.xyz")" -eq 400
check "the output without the dropped points" test "$(wc -l < "$dir/parts_out.xyz")" -eq 1200
check "the component files hold the output" cmp -s <(sort "$dir/parts_out.xyz") <(cat "$dir"/comps/*.xyz | sort)
check "components face outward" awk '{ c = (FILENAME ~ /000000/) ? 0 : 4; if (($1-c)*$4 + $2*$5 + $3*$6 <= 0) bad++ }
  END { exit bad > 0 }' "$dir/comps/component_000000.xyz" "$dir/comps/component_000001.xyz"
expect_exit 0 "component files in the output's format (binary ply)" "$prog" --quiet --stream --radius 0.5 \
  --min-component-size 10 --components-dir "$dir/comps_ply" "$dir/parts.xyz" "$dir/parts_out.ply"
check "ply component file" test "$(head -c 3 "$dir/comps_ply/component_000001.ply")" = "ply"
expect_exit 0 "a component file reads back" "$prog" --quiet --stream "$dir/comps_ply/component_000001.ply" "$dir/back.xyz"
check "it holds the component" test "$(wc -l < "$dir/back.xyz")" -eq 400
expect_exit 0 "components without a minimum" "$prog" --quiet --json --stream --radius 0.5 --components-dir "$dir/comps_all" \
  "$dir/parts.xyz" "$dir/parts_all.xyz"
check "every component kept without a minimum" test "$(ls "$dir/comps_all" | wc -l)" -eq 5
check "nothing dropped without a minimum" grep -q '"dropped_points": 0,' "$dir/out.txt"
touch "$dir/a_file"
expect_exit 1 "--components-dir on a file" "$prog" --quiet --stream --components-dir "$dir/a_file" "$dir/parts.xyz" "$dir/nodir.xyz"
check "one-line error for --components-dir on a file" test "$(wc -l < "$dir/err.txt")" -eq 1
check "no output when the components cannot be written" test -z "$(find "$dir" -name 'nodir.xyz*')"
check "no temporary files after the component runs" test -z "$(ls -A "$dir/tmp")"
check "no temporary component file left" test -z "$(find "$dir"/comps* -name '*.tmp*')"

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

# SIGINT likewise
"$prog" --quiet --stream "$dir/big.xyz" "$dir/big_int.ply" 2> /dev/null &
pid=$!
sleep 0.5
kill -INT $pid 2> /dev/null
wait $pid
status=$?
check "SIGINT ends the run (status $status)" test "$status" -ne 0 -o -e "$dir/big_int.ply"
check "no partial output after SIGINT" test -z "$(ls "$dir" | grep '^big_int.ply.tmp')"
if [ ! -e "$dir/big_int.ply" ]; then
  check "no temporary files after SIGINT" test -z "$(ls -A "$dir/tmp")"
fi

# SIGKILL cannot be caught, but the output is written to a temporary name and
# renamed when complete: killed while it writes its output (a text output,
# slow enough to be caught once its temporary file holds 1 MB), the run
# leaves nothing at the output path (the temporary files stay: nothing can
# remove them)
"$prog" --quiet --stream "$dir/big.xyz" "$dir/big_kill.xyz" 2> /dev/null &
pid=$!
for _ in $(seq 1 6000); do
  size=$(cat "$dir"/big_kill.xyz.tmp.* 2> /dev/null | wc -c)
  [ "$size" -gt 1000000 ] && break
  kill -0 $pid 2> /dev/null || break
  sleep 0.01
done
kill -KILL $pid 2> /dev/null
wait $pid 2> /dev/null # (no "Killed" notice)
status=$?
if [ -e "$dir/big_kill.xyz" ]; then # too late: the run had finished, the output must be whole
  check "an output after SIGKILL is complete" test "$(wc -l < "$dir/big_kill.xyz")" -eq 400000
else
  check "SIGKILL while writing: killed (status $status)" test "$status" -eq 137
  check "SIGKILL while writing: the temporary output was being written" test "$size" -gt 1000000
fi
rm -f "$dir"/big_kill.xyz* "$dir"/tmp/*

# the disk fills up half way through a streamed run: files limited with
# ulimit -f (SIGXFSZ ignored, so that writes beyond the limit fail with EFBIG
# as they fail with ENOSPC on a full disk), first in the sweep (the record
# file, 64 bytes a point, stops at 512 kB of 1.25 MB), then while writing the
# output (a text output of 2 MB or more stops at 1.6 MB, after a record file
# of 1.25 MB): exit 1, one line naming the file, no output, no temporary file
limited() { # KB, then a command: runs it with files limited to KB kB
  local kb="$1"; shift
  ( trap '' XFSZ; ulimit -f "$kb"; exec "$@" )
}
expect_exit 1 "disk full during the sweep" limited 512 "$prog" --quiet --stream "$dir/det.xyz" "$dir/full.ply"
check "disk full during the sweep: one-line error" test "$(wc -l < "$dir/err.txt")" -eq 1
check "disk full during the sweep: the error says why" grep -q "cannot write .*normal_orientation_records_.*: File too large" "$dir/err.txt"
check "disk full during the sweep: no output" test -z "$(find "$dir" -name 'full.ply*')"
check "disk full during the sweep: no temporary file" test -z "$(ls -A "$dir/tmp")"
awk 'BEGIN { srand(13) } { s = (rand() < 0.5) ? -1 : 1; printf "%.17g %.17g %.17g %.17g %.17g %.17g\n",
  $1 + 1e-7 * rand(), $2 + 1e-7 * rand(), $3 + 1e-7 * rand(), s * ($4 + 1e-9 * rand()), s * ($5 + 1e-9 * rand()),
  s * ($6 + 1e-9 * rand()) }' "$dir/det.xyz" > "$dir/long.xyz"
expect_exit 0 "long text output" "$prog" --quiet --stream "$dir/long.xyz" "$dir/long_out.xyz"
check "the long text output is larger than the limit" test "$(wc -c < "$dir/long_out.xyz")" -gt 2000000
expect_exit 1 "disk full while writing the output" limited 1600 "$prog" --quiet --stream "$dir/long.xyz" "$dir/full.xyz"
check "disk full while writing the output: one-line error" test "$(wc -l < "$dir/err.txt")" -eq 1
check "disk full while writing the output: the error says why" grep -q "full.xyz.*File too large" "$dir/err.txt"
check "disk full while writing the output: no output" test -z "$(find "$dir" -name 'full.xyz*')"
check "disk full while writing the output: no temporary file" test -z "$(ls -A "$dir/tmp")"
expect_exit 1 "a missing TMPDIR" env TMPDIR="$dir/no_such_dir" "$prog" --quiet --stream "$dir/det.xyz" "$dir/notmp.ply"
check "a missing TMPDIR: one-line error" test "$(wc -l < "$dir/err.txt")" -eq 1
check "a missing TMPDIR: no output" test -z "$(find "$dir" -name 'notmp.ply*')"

# the progress line of --stream on a terminal (through script(1), when there):
# stages and percentages on stderr, erased at the end, never in the JSON on
# stdout; nothing with --quiet
if command -v script > /dev/null 2>&1; then
  script -qfec "'$prog' --json --stream '$dir/big.xyz' '$dir/big_tty.ply' > '$dir/tty_json.txt'" /dev/null > "$dir/tty.txt" 2>&1
  check "progress on a terminal names the sweep" grep -q "sweep .*%" "$dir/tty.txt"
  check "the progress line is erased before the summary" grep -q $'\r *\roriented 400000 points' "$dir/tty.txt"
  check "no progress in the JSON on stdout" test "$(tr -cd '\r' < "$dir/tty_json.txt" | wc -c)" -eq 0
  check "the JSON is one line" test "$(wc -l < "$dir/tty_json.txt")" -eq 1
  script -qfec "'$prog' --quiet --stream '$dir/big.xyz' '$dir/big_tty.ply'" /dev/null > "$dir/tty_quiet.txt" 2>&1
  check "nothing on a terminal with --quiet" test ! -s "$dir/tty_quiet.txt"
fi

# points without normals: estimated first
awk '{ print $1, $2, $3 }' "$dir/sphere.xyz" > "$dir/bare.xyz"
expect_exit 0 "estimates missing normals" "$prog" --quiet --normals pca "$dir/bare.xyz" "$dir/bare_out.xyz"
check "estimated normals point outward" awk '{ if ($1*$4 + $2*$5 + $3*$6 <= 0) bad++ } END { exit bad > 0 }' "$dir/bare_out.xyz"

# a placeholder is not a normal: a file whose normals are all zero is oriented
# as the same file without normals is (jet or --normals pca), and says so on
# stderr and in the JSON; a file with some zero normals leaves those points as
# they were and says how many; --stream refuses an all-zero file (one line, no
# output, no temporary file)
awk '{ print $1, $2, $3, 0, 0, 0 }' "$dir/sphere.xyz" > "$dir/zero.xyz"
expect_exit 0 "no normals, jet" "$prog" --quiet --json "$dir/bare.xyz" "$dir/bare_jet.xyz"
check "no normals: the JSON says why they were estimated" \
  grep -q '"normals_estimated": true, "normals_estimated_because": "the input has no normals"' "$dir/out.txt"
expect_exit 0 "all-zero normals" "$prog" --json "$dir/zero.xyz" "$dir/zero_jet.xyz"
check "all-zero normals: oriented as the file without normals (jet)" cmp -s "$dir/bare_jet.xyz" "$dir/zero_jet.xyz"
check "all-zero normals: said on stderr" grep -q "zero.xyz: all 600 normals are zero: estimating them (jet)" "$dir/err.txt"
check "all-zero normals: the JSON says they were estimated and why" \
  grep -q '"normals_estimated": true, "normals_estimated_because": "all input normals are zero"' "$dir/out.txt"
check "all-zero normals: one component" grep -q '"components": 1,' "$dir/out.txt"
expect_exit 0 "all-zero normals, pca" "$prog" --quiet --normals pca "$dir/zero.xyz" "$dir/zero_pca.xyz"
check "all-zero normals: oriented as the file without normals (pca)" cmp -s "$dir/bare_out.xyz" "$dir/zero_pca.xyz"
check "all-zero normals, --quiet: nothing on stderr" test ! -s "$dir/err.txt"
awk '{ if (NR % 50 == 0) print $1, $2, $3, 0, 0, 0; else print }' "$dir/sphere.xyz" > "$dir/some_zero.xyz"
expect_exit 0 "some zero normals" "$prog" --json "$dir/some_zero.xyz" "$dir/some_zero_out.xyz"
check "some zero normals: the JSON counts them" grep -q '"zero_normals": 12,' "$dir/out.txt"
check "some zero normals: not estimated" grep -q '"normals_estimated": false,' "$dir/out.txt"
check "some zero normals: stderr counts them" grep -q "^12 of 600 points have a zero normal: left as they were$" \
  "$dir/err.txt"
check "some zero normals: those points left as they were, the others outward" awk '
  { if (NR % 50 == 0) { if ($4 != 0 || $5 != 0 || $6 != 0) bad++ } else if ($1*$4 + $2*$5 + $3*$6 <= 0) bad++ }
  END { exit (bad > 0 || NR != 600) }' "$dir/some_zero_out.xyz"
expect_exit 0 "no zero normal: no count on stderr" "$prog" "$dir/sphere.xyz" "$dir/none_zero.xyz"
check "no zero normal: no count on stderr" test -z "$(grep "zero normal" "$dir/err.txt")"
expect_exit 1 "stream refuses all-zero normals" "$prog" --quiet --stream "$dir/zero.xyz" "$dir/zero_stream.xyz"
check "stream, all-zero normals: one-line error" test "$(wc -l < "$dir/err.txt")" -eq 1
check "stream, all-zero normals: the error says to run in core" \
  grep -q "^orient_normals: error: .*zero.xyz: every normal is zero.*run without --stream" "$dir/err.txt"
check "stream, all-zero normals: no output" test -z "$(find "$dir" -name 'zero_stream.xyz*')"
check "stream, all-zero normals: no temporary file" test -z "$(ls -A "$dir/tmp")"
expect_exit 0 "stream, some zero normals" "$prog" --quiet --stream "$dir/some_zero.xyz" "$dir/some_zero_stream.xyz"
head -3 "$dir/zero.xyz" > "$dir/zero3.xyz"
expect_exit 1 "all-zero normals, too few points to estimate them" "$prog" "$dir/zero3.xyz" "$dir/zero3_out.xyz"
check "all-zero normals, too few points: one-line error" test "$(wc -l < "$dir/err.txt")" -eq 1
check "all-zero normals, too few points: the error says why" grep -q "all normals are zero, and too few points" \
  "$dir/err.txt"
check "all-zero normals, too few points: no output" test -z "$(find "$dir" -name 'zero3_out.xyz*')"

# --keep-order: OUT is IN itself, in its order and with its text, only the
# signs of the normals changed, and the same signs as the sweep-order output
expect_exit 0 "stream --keep-order" "$prog" --quiet --json --stream --keep-order "$dir/sphere.xyz" "$dir/kept.xyz"
check "json says keep_order" grep -q '"keep_order": true' "$dir/out.txt"
check "--keep-order: the input's lines, the normals outward" awk 'NR==FNR { l[FNR] = $1 " " $2 " " $3; n++; next }
  { if ($1 " " $2 " " $3 != l[FNR] || $1*$4 + $2*$5 + $3*$6 <= 0) bad++; c++ } END { exit (bad > 0 || c != n) }' \
  "$dir/sphere.xyz" "$dir/kept.xyz"
check "--keep-order: the same normals as the sweep order" awk '
  NR==FNR { v[sprintf("%.7f %.7f %.7f", $1, $2, $3)] = sprintf("%.7f %.7f %.7f", $4, $5, $6); n++; next }
  { k = sprintf("%.7f %.7f %.7f", $1, $2, $3); if (!(k in v) || v[k] != sprintf("%.7f %.7f %.7f", $4, $5, $6)) bad++; c++ }
  END { exit (bad > 0 || c != n) }' "$dir/stream.xyz" "$dir/kept.xyz"
expect_exit 2 "--keep-order into another format" "$prog" --quiet --stream --keep-order "$dir/sphere.xyz" "$dir/kept.ply"
check "no output for --keep-order into another format" test ! -e "$dir/kept.ply"

# the global sign stage: on by default, reported in the JSON; --global none turns it off
expect_exit 0 "default: global stage in the json" "$prog" --quiet --json "$dir/sphere.xyz" "$dir/g_default.xyz"
check "json has a global object with a closedness" grep -q '"global": {"stage": "visibility", "closedness": ' "$dir/out.txt"
check "json reports the seen side" grep -q '"seen_components_flipped": [0-9]*, "seen_patches_flipped": [0-9]*, "seen_vetoes": [0-9]*, "top_components_flipped": ' "$dir/out.txt"
expect_exit 0 "--global winding" "$prog" --quiet --json --global winding "$dir/sphere.xyz" "$dir/g_winding.xyz"
check "json global stage is winding with --global winding" grep -q '"global": {"stage": "winding"' "$dir/out.txt"
expect_exit 0 "--up 0,1,0" "$prog" --quiet --json --up 0,1,0 "$dir/sphere.xyz" "$dir/g_up.xyz"
check "a sphere faces outward whatever the up direction" awk '{ if ($1*$4 + $2*$5 + $3*$6 <= 0) bad++ } END { exit bad > 0 }' \
  "$dir/g_up.xyz"
expect_exit 0 "--global none" "$prog" --quiet --json --global none "$dir/sphere.xyz" "$dir/g_none.xyz"
check "json global is null with --global none" grep -q '"global": null' "$dir/out.txt"
expect_exit 0 "--viewpoint: no global stage by default" "$prog" --quiet --json --viewpoint 0,0,0 "$dir/sphere.xyz" \
  "$dir/g_vp.xyz"
check "json global is null with --viewpoint" grep -q '"global": null' "$dir/out.txt"
check "with --viewpoint 0,0,0 every normal points inward" awk '{ if ($1*$4 + $2*$5 + $3*$6 >= 0) bad++ } END { exit bad > 0 }' \
  "$dir/g_vp.xyz"
expect_exit 0 "--stream: global stage in the json" "$prog" --quiet --json --stream "$dir/sphere.xyz" "$dir/g_stream.xyz"
check "streamed json has a global object" grep -q '"global": {"stage": "visibility"' "$dir/out.txt"
expect_exit 0 "--stream --global none" "$prog" --quiet --json --stream --global none "$dir/sphere.xyz" "$dir/g_sn.xyz"
check "streamed json global is null with --global none" grep -q '"global": null' "$dir/out.txt"
# two layers 0.006 apart, closer than the spacing (0.02), normals +-z at random:
# the layer edges give them opposite signs, and without them the graph makes
# both alike
awk 'BEGIN { srand(3); for (i = 0; i < 50; i++) for (j = 0; j < 50; j++) {
  x = (i + 0.3 * rand()) / 50; y = (j + 0.3 * rand()) / 50
  print x, y, 0, 0, 0, (rand() < 0.5 ? 1 : -1); print x + 0.007, y + 0.005, 0.006, 0, 0, (rand() < 0.5 ? 1 : -1) } }' \
  > "$dir/two_layers.xyz"
# prints the number of points on the upper layer whose normal points up, then on the lower one
layer_signs() { awk '{ if ($3 > 0.003) { if ($6 > 0) t++ } else if ($6 > 0) b++ } END { print t + 0, b + 0 }' "$1"; }
for mode in "" "--stream"; do
  # shellcheck disable=SC2086
  expect_exit 0 "$mode two layers" "$prog" --quiet --json $mode "$dir/two_layers.xyz" "$dir/le_on.xyz"
  check "$mode two layers: json counts the points on two layers" grep -q '"layer_pairs": [1-9]' "$dir/out.txt"
  check "$mode two layers: opposite signs" test "$(layer_signs "$dir/le_on.xyz")" = "2500 0" -o \
    "$(layer_signs "$dir/le_on.xyz")" = "0 2500"
  # shellcheck disable=SC2086
  expect_exit 0 "$mode --layer-edges off" "$prog" --quiet --json $mode --layer-edges off "$dir/two_layers.xyz" \
    "$dir/le_off.xyz"
  check "$mode --layer-edges off: no point on two layers" grep -q '"layer_pairs": 0,' "$dir/out.txt"
  check "$mode --layer-edges off: both layers alike" test "$(layer_signs "$dir/le_off.xyz")" = "2500 2500" -o \
    "$(layer_signs "$dir/le_off.xyz")" = "0 0"
done

# bad options: exit 2, one line on stderr, no output (the options of --stream
# need it)
for args in "--k 0" "--k x" "--radius -1" "--criterion foo" "--solver foo" "--orders 0" "--threads -1" "--threads x" \
    "--threads 1025" "--threads" "--bogus" "--viewpoint 1,2" "--prior-weight 1" "--viewpoint 0,0,0 --prior-weight -1" "--viewpoint 0,0,0 --prior-weight nan" \
    "--presorted x" "--stream --presorted w" "--stream --presorted" "--components-dir $dir/cd" "--min-component-size 5" \
    "--stream --min-component-size -1" "--stream --min-component-size x" "--write-segments" \
    "--stream --write-segments" "--batch-size 10" "--stream --batch-size 0" "--stream --batch-size x" \
    "--keep-order" "--stream --keep-order --ascii" "--stream --keep-order --write-segments" "--refine 1" \
    "--stream --refine 65" "--stream --refine x" "--global foo" "--global" "--stream --global x" "--up 1,2" "--up" "--up 0,0,nan" "--stream --up x,y,z" \
    "--layer-edges" "--layer-edges yes" "--stream --layer-edges 0"; do
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
