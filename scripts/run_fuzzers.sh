#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Builds the libFuzzer targets of the point cloud readers (fuzz/) with clang in a
# build directory of their own and runs each for a bounded time on a copy of its seed
# corpus (fuzz/corpus/<target>/, which is not modified).
#
# usage: scripts/run_fuzzers.sh [TARGET...]    (default: every target)
# environment:
#   FUZZ_SECONDS     seconds per target (default 60; 0: only run the seed corpus once)
#   FUZZ_MAX_LEN     largest input in bytes (default 4096)
#   FUZZ_BUILD_DIR   build directory (default build_fuzz at the top of the repository)
#   FUZZ_BUILD_JOBS  parallel build jobs (default 2)
#   FUZZ_ARTIFACTS   where crashing inputs are kept (default FUZZ_BUILD_DIR/fuzz_artifacts)
#
# Exit status: 0 when no target found anything; 1 when a target crashed, hung, ran
# out of memory or broke an invariant (the reproducer files are printed, with the
# command that replays them); 2 when the build fails.
set -uo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
seconds=${FUZZ_SECONDS:-60}
max_len=${FUZZ_MAX_LEN:-4096}
build=${FUZZ_BUILD_DIR:-$root/build_fuzz}
jobs=${FUZZ_BUILD_JOBS:-2}
artifacts=${FUZZ_ARTIFACTS:-$build/fuzz_artifacts}
all_targets=(fuzz_read_ply fuzz_read_xyz fuzz_stream_reader)
if [ $# -gt 0 ]; then targets=("$@"); else targets=("${all_targets[@]}"); fi

if ! [[ "$seconds" =~ ^[0-9]+$ ]] || ! [[ "$max_len" =~ ^[0-9]+$ ]]; then
  echo "run_fuzzers.sh: FUZZ_SECONDS and FUZZ_MAX_LEN must be whole numbers" >&2
  exit 2
fi
if [ "$seconds" -eq 0 ]; then
  limit=(-runs=0) # libFuzzer runs the seed corpus, then stops
else
  limit=(-max_total_time="$seconds")
fi
for tool in clang clang++ cmake; do
  if ! command -v "$tool" > /dev/null 2>&1; then
    echo "run_fuzzers.sh: $tool not found (Debian: apt-get install clang cmake)" >&2
    exit 2
  fi
done

start=$(date +%s)
# Scratch space: the corpus copies and the files the targets write (in memory when
# /dev/shm is there).
if [ -d /dev/shm ] && [ -w /dev/shm ]; then
  work=$(mktemp -d /dev/shm/normal_orientation_fuzz.XXXXXX)
else
  work=$(mktemp -d "${TMPDIR:-/tmp}/normal_orientation_fuzz.XXXXXX")
fi
trap 'rm -rf "$work"' EXIT
echo "== configuring $build (clang, fuzzers only)"
if ! CC=clang CXX=clang++ cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Debug \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
    -DNORMAL_ORIENTATION_BUILD_FUZZERS=ON -DNORMAL_ORIENTATION_BUILD_TESTS=OFF \
    -DNORMAL_ORIENTATION_BUILD_EXAMPLES=OFF -DNORMAL_ORIENTATION_BUILD_BENCHMARKS=OFF \
    -DNORMAL_ORIENTATION_INSTALL=OFF > "$work/configure.log" 2>&1; then
  cat "$work/configure.log" >&2
  echo "run_fuzzers.sh: configuring failed" >&2
  exit 2
fi
echo "== building ${targets[*]}"
if ! cmake --build "$build" -j"$jobs" --target "${targets[@]}"; then
  echo "run_fuzzers.sh: building the fuzz targets failed" >&2
  exit 2
fi

mkdir -p "$artifacts"

failed=()
for target in "${targets[@]}"; do
  binary="$build/fuzz/$target"
  if [ ! -x "$binary" ]; then
    echo "run_fuzzers.sh: no fuzz target $binary" >&2
    failed+=("$target")
    continue
  fi
  mkdir -p "$work/$target/corpus" "$work/$target/tmp" "$artifacts/$target"
  if [ -d "fuzz/corpus/$target" ]; then
    cp -R "fuzz/corpus/$target/." "$work/$target/corpus/"
  fi
  dict=()
  if [ -f "fuzz/$target.dict" ]; then dict=(-dict="$root/fuzz/$target.dict"); fi
  log="$work/$target/log.txt"
  echo "== $target: ${seconds} s, inputs up to $max_len bytes"
  before=$(ls -A "$artifacts/$target")
  TMPDIR="$work/$target/tmp" "$binary" "${limit[@]}" -max_len="$max_len" -timeout=60 \
    -report_slow_units=60 -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$artifacts/$target/" "${dict[@]}" \
    "$work/$target/corpus" > "$log" 2>&1
  status=$?
  # every libFuzzer report ends the run; a sanitizer report, a broken invariant
  # (abort) or an uncaught exception counts even if the status were 0
  if [ $status -ne 0 ] || grep -aqE '^(==[0-9]+==ERROR|SUMMARY: (Address|Undefined|Leak)Sanitizer|\*\*\* invariant broken|terminate called)' "$log"; then
    echo "FAILED: $target (exit status $status); the end of its log:"
    grep -avE '^#[0-9]+' "$log" | tail -n 40
    echo "reproducer(s):"
    for file in "$artifacts/$target"/{crash,timeout,oom,leak}-*; do
      [ -e "$file" ] || continue
      name=$(basename "$file")
      if ! printf '%s\n' "$before" | grep -qxF "$name"; then
        echo "  $file"
        echo "  replay: $binary $file"
      fi
    done
    failed+=("$target")
  else
    grep -aE '^stat::number_of_executed_units|^stat::peak_rss_mb' "$log" | sed "s/^/   $target /"
    echo "   $target: no crash (corpus: $(ls "$work/$target/corpus" | wc -l) inputs)"
  fi
done

echo "== fuzzing took $(( $(date +%s) - start )) s in all"
if [ ${#failed[@]} -ne 0 ]; then
  echo "run_fuzzers.sh: failures in ${failed[*]} (crashing inputs in $artifacts)" >&2
  exit 1
fi
echo "run_fuzzers.sh: all ${#targets[@]} targets ran without finding anything"
