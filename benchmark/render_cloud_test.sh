#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Test of render_cloud (CTest render_cloud_png): renders the bundled sample cloud and checks
# that the PNG exists, has the PNG signature and the requested size, and that the same run
# gives the same bytes; a bad input or a bad option gives its exit status (1, 2), one line
# on stderr and no file.
# usage: render_cloud_test.sh PATH_TO_render_cloud SAMPLE_CLOUD
set -u
prog=$(realpath "$1")
sample="$2"
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
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
png_signature() { od -An -tx1 -N8 "$1" | tr -d ' \n'; }
png_size() { # width x height from the IHDR chunk (big-endian, bytes 16-23)
  od -An -tu1 -j16 -N8 "$1" | awk '{ printf "%dx%d", (($1*256+$2)*256+$3)*256+$4, (($5*256+$6)*256+$7)*256+$8 }'
}

expect_exit 0 "renders the sample cloud" "$prog" --width 120 --height 90 --view 20,10 --up z "$sample" "$dir/a.png"
check "the PNG exists" test -s "$dir/a.png"
check "PNG signature" test "$(png_signature "$dir/a.png")" = "89504e470d0a1a0a"
check "requested size 120x90 (got $(png_size "$dir/a.png"))" test "$(png_size "$dir/a.png")" = "120x90"
check "a summary line on stdout" grep -q "20000 points, 120x90" "$dir/out.txt"
expect_exit 0 "renders again" "$prog" --quiet --width 120 --height 90 --view 20,10 --up z "$sample" "$dir/b.png"
check "deterministic: the same bytes" cmp -s "$dir/a.png" "$dir/b.png"
check "nothing printed with --quiet" test ! -s "$dir/out.txt"
expect_exit 0 "default size" "$prog" --quiet "$sample" "$dir/default.png"
check "default size 800x800" test "$(png_size "$dir/default.png")" = "800x800"

# bad inputs: exit 1, one line, no file (and an existing file left unchanged)
printf '1 2 3 0 0 1\n4 5 nan 0 0 1\n' > "$dir/nan.xyz"
awk '{ print $1, $2, $3 }' "$sample" > "$dir/bare.xyz"
for input in "$dir/none.ply" "$dir/nan.xyz" "$dir/bare.xyz"; do
  expect_exit 1 "bad input $(basename "$input")" "$prog" "$input" "$dir/bad.png"
  check "one-line error for $(basename "$input")" test "$(wc -l < "$dir/err.txt")" -eq 1
  check "no file for $(basename "$input")" test -z "$(find "$dir" -name 'bad.png*')"
done
expect_exit 1 "no segment property" "$prog" --color segments "$sample" "$dir/bad.png"
check "the error names the property" grep -q "no vertex property 'segment'" "$dir/err.txt"
check "no file without the property" test -z "$(find "$dir" -name 'bad.png*')"
expect_exit 1 "missing reference mesh" "$prog" --color wrong --reference "$dir/none.off" "$sample" "$dir/bad.png"
check "no file without the mesh" test -z "$(find "$dir" -name 'bad.png*')"
cp "$dir/a.png" "$dir/keep.png"
expect_exit 1 "bad input over an existing file" "$prog" "$dir/nan.xyz" "$dir/keep.png"
check "the existing file is unchanged" cmp -s "$dir/a.png" "$dir/keep.png"
expect_exit 1 "unwritable output" "$prog" "$sample" "$dir/no/such/dir/x.png"
check "one-line error for an unwritable output" test "$(wc -l < "$dir/err.txt")" -eq 1

# bad options: exit 2, one line, no file
for args in "--width 0" "--width x" "--view 10" "--view 0,100" "--up w" "--color foo" "--color wrong" \
    "--reference m.off" "--splat 0" "--bogus"; do
  # shellcheck disable=SC2086
  expect_exit 2 "bad option $args" "$prog" $args "$sample" "$dir/bad.png"
  check "one-line error for $args" test "$(wc -l < "$dir/err.txt")" -eq 1
  check "no file for $args" test ! -e "$dir/bad.png"
done
check "no temporary file left" test -z "$(find "$dir" -name '*.tmp.*')"

echo "$passes passed, $fails failed"
[ "$fails" -eq 0 ]
