#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The test suite under sanitizers, in a build directory of its own: by
# default AddressSanitizer + UndefinedBehaviorSanitizer (what .ci/run runs
# after the normal suite), every GoogleTest, the command-line tests and the
# example, with -O1 -g; a finding fails its test (UBSan does not recover,
# and every sanitizer exits with status 86, which no test expects).  Built
# with clang++ when it is installed (it compiles the sanitized CGAL code
# about twice as fast as g++), else with g++.
#
#   bash scripts/run_sanitized_tests.sh                 # ASan + UBSan in build-asan
#   NORMAL_ORIENTATION_SANITIZE=thread bash scripts/run_sanitized_tests.sh build-tsan
#                                                       # TSan (test/tsan.supp: TBB only)
#
# Environment: NORMAL_ORIENTATION_SANITIZE ("address;undefined", "thread"),
# CXX (the compiler), JOBS (parallel builds and tests, default 2), and
# CTEST_ARGS (more ctest arguments, e.g. "-R test_streaming").
# Left out: the header check, the find_package consumer build and the
# Doxygen build, which compile or run nothing sanitized.
set -euo pipefail
cd "$(dirname "$0")/.."
sanitize=${NORMAL_ORIENTATION_SANITIZE:-address;undefined}
case "$sanitize" in
  *thread*) default_build=build-tsan ;;
  *) default_build=build-asan ;;
esac
build=${1:-$default_build}
jobs=${JOBS:-2}
bash scripts/setup.sh
cxx=${CXX:-}
if [ -z "$cxx" ]; then
  if ! command -v clang++ > /dev/null 2>&1 && command -v apt-get > /dev/null 2>&1; then
    sudo=""
    [ "$(id -u)" -eq 0 ] || sudo="sudo"
    echo "installing: clang"
    { $sudo apt-get update -qq && DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq clang; } ||
      echo "run_sanitized_tests.sh: clang could not be installed, building with g++ (slower)"
  fi
  if command -v clang++ > /dev/null 2>&1; then cxx=clang++; else cxx=g++; fi
fi
cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER="$cxx" \
  -DNORMAL_ORIENTATION_SANITIZE="$sanitize" -DNORMAL_ORIENTATION_BUILD_EXAMPLES=ON \
  -DNORMAL_ORIENTATION_BUILD_TESTS=ON -DNORMAL_ORIENTATION_BUILD_BENCHMARKS=OFF \
  -DNORMAL_ORIENTATION_BUILD_FUZZERS=OFF
cmake --build "$build" -j"$jobs"
common="exitcode=86:print_stacktrace=1:halt_on_error=1"
export ASAN_OPTIONS="$common:detect_leaks=1:strict_string_checks=1:check_initialization_order=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="$common${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
export TSAN_OPTIONS="$common:second_deadlock_stack=1:suppressions=$PWD/test/tsan.supp${TSAN_OPTIONS:+:$TSAN_OPTIONS}"
cd "$build"
# shellcheck disable=SC2086
ctest --output-on-failure -j"$jobs" -E '^(consumer_find_package|headers_self_contained|doc_builds_without_warnings)$' ${CTEST_ARGS:-}
