#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Fresh Debian machine -> test results: installs what is missing, builds the
# library's tests, examples and benchmarks in Release and runs the tests.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DNORMAL_ORIENTATION_BUILD_EXAMPLES=ON \
  -DNORMAL_ORIENTATION_BUILD_TESTS=ON -DNORMAL_ORIENTATION_BUILD_BENCHMARKS=ON
cmake --build build -j2
cd build && ctest --output-on-failure -j2
