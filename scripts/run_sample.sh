#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Fresh Debian machine -> oriented sample cloud: installs what is missing,
# builds the command-line program in Release and orients the bundled sample.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
mkdir -p build
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DNORMAL_ORIENTATION_BUILD_EXAMPLES=ON -DNORMAL_ORIENTATION_BUILD_TESTS=OFF \
  -DNORMAL_ORIENTATION_BUILD_BENCHMARKS=OFF > build/run_sample.log 2>&1 || { cat build/run_sample.log; exit 1; }
cmake --build build --target orient_normals -j2 >> build/run_sample.log 2>&1 || { tail -50 build/run_sample.log; exit 1; }
cd build && ./examples/orient_normals "$@"
