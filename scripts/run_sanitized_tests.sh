#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The test suite under sanitizers, in a build directory of its own: by
# default AddressSanitizer + UndefinedBehaviorSanitizer (what .ci/run runs
# after the normal suite): every GoogleTest, the command-line tests and the
# examples, compiled with -O1 -g. A finding fails its test: UBSan does not
# recover, and every sanitizer exits with status 86, which no test expects.
# Built with clang++ (installed when missing, if possible: it compiles the
# sanitized CGAL code about twice as fast as g++), else with g++.
#
#   bash scripts/run_sanitized_tests.sh              # ASan + UBSan, in build-asan
#   NORMAL_ORIENTATION_SANITIZE=thread bash scripts/run_sanitized_tests.sh
#                                                    # TSan, in build-tsan
#
# TSan and TBB: Debian's libtbb is not instrumented, so TSan cannot see the
# synchronisation of TBB's scheduler and reports every parallel_for body.
# In thread mode the script therefore builds the installed TBB version
# (Debian's onetbb source package, fetched with apt-get through a source
# list of its own) with -fsanitize=thread into BUILD/tbb-tsan, and runs the
# tests with it (LD_LIBRARY_PATH); NORMAL_ORIENTATION_TSAN_TBB=DIR uses the
# TSan libtbb.so.12 and libtbbmalloc.so.2 of DIR instead. When neither is
# possible, the tests run with Debian's TBB and test/tsan.supp, which drops
# every report in which a TBB task takes part (far slower, and blind to
# races between TBB tasks).
#
# Environment: NORMAL_ORIENTATION_SANITIZE ("address;undefined",
# "address,undefined", "thread"), CXX (the compiler), JOBS (parallel builds
# and tests, default 2), CTEST_ARGS (more ctest arguments, e.g.
# "-R Streaming").
# Left out: the header check, the find_package consumer build and the
# Doxygen build (nothing sanitized runs in them), and the Poisson example
# example_reconstruct_surface: CGAL 5.5's Poisson_reconstruction_function
# (Cell_hint::get) binds a reference to a null pointer, which UBSan reports
# (fixed in CGAL 6.0, CGAL issue #8260); not the library's code.
set -euo pipefail
cd "$(dirname "$0")/.."
sanitize=${NORMAL_ORIENTATION_SANITIZE:-address;undefined}
case "$sanitize" in
  *thread*) thread=1; default_build=build-tsan ;;
  *) thread=0; default_build=build-asan ;;
esac
build=$(realpath -m "${1:-$default_build}")
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
case "$cxx" in
  *clang++*) cc=${cxx/clang++/clang} ;;
  *) cc=${cxx/g++/gcc} ;;
esac

cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER="$cxx" \
  -DNORMAL_ORIENTATION_SANITIZE="$sanitize" -DNORMAL_ORIENTATION_BUILD_EXAMPLES=ON \
  -DNORMAL_ORIENTATION_BUILD_TESTS=ON -DNORMAL_ORIENTATION_BUILD_BENCHMARKS=OFF \
  -DNORMAL_ORIENTATION_BUILD_FUZZERS=OFF
cmake --build "$build" -j"$jobs"

# prints the directory of a TSan build of the installed TBB version, building it if needed
tsan_tbb() {
  local dir="$build/tbb-tsan" version codename src lib
  lib=$(find "$dir/build" -name libtbb.so.12 -printf '%h\n' 2> /dev/null | head -1)
  if [ -n "$lib" ] && [ -e "$lib/libtbbmalloc.so.2" ]; then echo "$lib"; return 0; fi
  command -v apt-get > /dev/null 2>&1 || return 1
  version=$(dpkg-query -W -f='${Version}' libtbb-dev 2> /dev/null) || return 1
  codename=$(. /etc/os-release && echo "${VERSION_CODENAME:-}")
  [ -n "$codename" ] || return 1
  mkdir -p "$dir/apt/lists/partial" "$dir/apt/cache/archives/partial"
  printf 'deb-src http://deb.debian.org/debian %s main\ndeb-src http://deb.debian.org/debian %s-updates main\ndeb-src http://deb.debian.org/debian-security %s-security main\n' \
    "$codename" "$codename" "$codename" > "$dir/apt/sources.list"
  local opts=(-o Dir::Etc::SourceList="$dir/apt/sources.list" -o Dir::Etc::SourceParts=/dev/null
              -o Dir::State::Lists="$dir/apt/lists" -o Dir::Cache="$dir/apt/cache")
  apt-get "${opts[@]}" -qq update >&2 || return 1
  (cd "$dir" && apt-get "${opts[@]}" -qq source --download-only "onetbb=$version" >&2) || return 1
  tar xf "$dir"/onetbb_*.orig.tar.* -C "$dir" || return 1
  src=$(find "$dir" -maxdepth 1 -type d -name 'oneTBB-*' | head -1)
  [ -n "$src" ] || return 1
  cmake -S "$src" -B "$dir/build" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_C_COMPILER="$cc" \
    -DCMAKE_CXX_COMPILER="$cxx" -DTBB_SANITIZE=thread -DTBB_TEST=OFF -DTBB_EXAMPLES=OFF \
    -DTBB_STRICT=OFF -DTBBMALLOC_BUILD=ON > "$dir/configure.log" 2>&1 || return 1
  cmake --build "$dir/build" -j"$jobs" --target tbb tbbmalloc > "$dir/build.log" 2>&1 || return 1
  lib=$(find "$dir/build" -name libtbb.so.12 -printf '%h\n' | head -1)
  [ -n "$lib" ] && [ -e "$lib/libtbbmalloc.so.2" ] && echo "$lib"
}

common="exitcode=86:print_stacktrace=1:halt_on_error=1"
export ASAN_OPTIONS="$common:detect_leaks=1:strict_string_checks=1:check_initialization_order=1${ASAN_OPTIONS:+:$ASAN_OPTIONS}"
export UBSAN_OPTIONS="$common${UBSAN_OPTIONS:+:$UBSAN_OPTIONS}"
if [ "$thread" -eq 1 ]; then
  tbb=${NORMAL_ORIENTATION_TSAN_TBB:-}
  if [ -z "$tbb" ]; then
    echo "== building TBB with ThreadSanitizer in $build/tbb-tsan"
    tbb=$(tsan_tbb) || tbb=""
  fi
  if [ -n "$tbb" ]; then
    echo "== TBB with ThreadSanitizer: $tbb"
    export LD_LIBRARY_PATH="$tbb${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
    export TSAN_OPTIONS="$common:second_deadlock_stack=1${TSAN_OPTIONS:+:$TSAN_OPTIONS}"
  else
    echo "run_sanitized_tests.sh: no TSan build of TBB; Debian's TBB with test/tsan.supp (TBB tasks unchecked, slow)"
    export TSAN_OPTIONS="$common:second_deadlock_stack=1:suppressions=$PWD/test/tsan.supp${TSAN_OPTIONS:+:$TSAN_OPTIONS}"
  fi
fi
cd "$build"
# shellcheck disable=SC2086
ctest --output-on-failure -j"$jobs" \
  -E '^(consumer_find_package|headers_self_contained|doc_builds_without_warnings|example_reconstruct_surface.*)$' \
  ${CTEST_ARGS:-}
