#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Runs the orient_normals program on every file of test/bad_inputs/ (small invalid
# point clouds), in core and with --stream, and checks that each run fails cleanly:
# an exit status between 1 and 125 (not 0: the input was accepted; not 124: it hung;
# not >= 128: killed by a signal), exactly one line on stderr (the error message, with
# no sanitizer report), nothing on stdout, and no output or temporary file left behind.
# usage: bad_input_test.sh PATH_TO_orient_normals [BAD_INPUTS_DIRECTORY]
set -u
if [ $# -lt 1 ]; then
  echo "usage: $0 PATH_TO_orient_normals [BAD_INPUTS_DIRECTORY]" >&2
  exit 2
fi
prog=$(realpath "$1")
inputs=${2:-$(dirname "$0")/bad_inputs}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
mkdir -p "$dir/tmp" "$dir/out"
export TMPDIR="$dir/tmp"
fails=0
passes=0
fail() {
  echo "FAILED: $*"
  fails=$((fails + 1))
}

shopt -s nullglob
files=("$inputs"/*)
if [ ${#files[@]} -eq 0 ]; then
  echo "FAILED: no bad input in $inputs"
  exit 1
fi
for input in "${files[@]}"; do
  name=$(basename "$input")
  case "$name" in README.md | *.license) continue ;; esac
  for mode in core stream; do
    args=()
    if [ "$mode" = stream ]; then args=(--stream); fi
    what="$name ($mode)"
    timeout 120 "$prog" "${args[@]}" "$input" "$dir/out/result.ply" > "$dir/stdout.txt" 2> "$dir/stderr.txt"
    status=$?
    failed_before=$fails
    lines=$(awk 'END { print NR }' "$dir/stderr.txt")
    if [ "$status" -eq 0 ]; then
      fail "$what: accepted (exit status 0)"
    elif [ "$status" -eq 124 ]; then
      fail "$what: no answer after 120 s"
    elif [ "$status" -gt 125 ]; then
      fail "$what: exit status $status (killed by a signal?)"
    fi
    if grep -aqE 'Sanitizer|runtime error:|terminate called|Assertion .* failed' "$dir/stderr.txt"; then
      fail "$what: sanitizer report, failed assertion or uncaught exception"
    fi
    if [ "$lines" -ne 1 ]; then
      fail "$what: $lines lines on stderr, expected 1"
    elif ! grep -aq '^orient_normals: ' "$dir/stderr.txt"; then
      fail "$what: the message does not start with 'orient_normals: '"
    fi
    if [ -s "$dir/stdout.txt" ]; then
      fail "$what: output on stdout"
    fi
    if [ -n "$(ls -A "$dir/out")" ]; then
      fail "$what: files left in the output directory: $(ls -A "$dir/out" | tr '\n' ' ')"
    fi
    if [ -n "$(ls -A "$dir/tmp")" ]; then
      fail "$what: temporary files left in TMPDIR: $(ls -A "$dir/tmp" | tr '\n' ' ')"
    fi
    if [ "$fails" -ne "$failed_before" ]; then
      echo "  stderr of $what (exit status $status):"
      head -c 2000 "$dir/stderr.txt" | sed 's/^/    /'
    else
      passes=$((passes + 1))
    fi
    rm -rf "${dir:?}/out/"* "${dir:?}/out/".[!.]* "${dir:?}/tmp/"* "${dir:?}/tmp/".[!.]* 2> /dev/null
  done
done

echo "$passes passed, $fails failed"
[ "$fails" -eq 0 ]
