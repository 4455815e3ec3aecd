#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# This file is part of Normal_orientation.
#
# build_ipsr.sh CHECKOUT_DIR BUILD_DIR
#
# Builds iPSR (Hou et al., SIGGRAPH 2022; MIT; https://github.com/houfei0801/ipsr), an optional
# peer of benchmark/global_quality.sh, from a checkout the user provides. Nothing of iPSR enters
# this project: the script only compiles the checkout's Src/*.cpp, the way its makefile does
# (C++11, -O3, OpenMP), into BUILD_DIR/ipsr. Never used by CI.
#   CXX      compiler (default g++)
#   CXXFLAGS replaces the default flags "-std=c++11 -O3 -DNDEBUG -fopenmp -w"
# Prints the path of the binary on success; exit status 1 on a failed build, 2 on bad usage.
set -euo pipefail

if [[ $# -ne 2 || "$1" == -h || "$1" == --help ]]; then
  echo "usage: build_ipsr.sh CHECKOUT_DIR BUILD_DIR   (e.g. git clone https://github.com/houfei0801/ipsr CHECKOUT_DIR)" >&2
  exit 2
fi
checkout=$1
build=$2
if [[ ! -f "$checkout/Src/main.cpp" || ! -f "$checkout/Src/PoissonRecon.h" ]]; then
  echo "build_ipsr.sh: '$checkout' is not an iPSR checkout (no Src/main.cpp, Src/PoissonRecon.h)" >&2
  exit 1
fi
mkdir -p "$build"
cxx=${CXX:-g++}
read -r -a flags <<< "${CXXFLAGS:--std=c++11 -O3 -DNDEBUG -fopenmp -w}"
shopt -s nullglob
sources=("$checkout"/Src/*.cpp)
# Link to a temporary name, renamed when complete: BUILD_DIR/ipsr is either whole or absent.
if ! "$cxx" "${flags[@]}" "${sources[@]}" -o "$build/ipsr.tmp.$$"; then
  rm -f "$build/ipsr.tmp.$$"
  echo "build_ipsr.sh: the build failed (compiler: $cxx)" >&2
  exit 1
fi
mv -f "$build/ipsr.tmp.$$" "$build/ipsr"
echo "$(cd "$build" && pwd)/ipsr"
