#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Install-and-consume test: installs the project from its build tree into a
# prefix, configures and builds the separate project test/consumer against
# that prefix alone (find_package(Normal_orientation)), checks that it
# compiled with the installed headers and not the source tree's, and runs it.
#
# usage: consumer_test.sh BUILD_DIR WORK_DIR SOURCE_INCLUDE_DIR CONSUMER_SOURCE_DIR
#                         CXX_COMPILER CONFIG GENERATOR EXPECT_EIGEN3 EXPECT_TBB
#   WORK_DIR          emptied, then holds prefix/, consumer_build/ and the logs
#   EXPECT_EIGEN3/TBB 1 when the library's own build has CGAL::Eigen3_support /
#                     CGAL::TBB_support: the consumer must get them too
# The cmake program is $CMAKE when set (the test sets the one of the build).
set -u
if [ $# -ne 9 ]; then
  echo "usage: consumer_test.sh BUILD_DIR WORK_DIR SOURCE_INCLUDE_DIR CONSUMER_SOURCE_DIR CXX_COMPILER CONFIG GENERATOR EXPECT_EIGEN3 EXPECT_TBB" >&2
  exit 2
fi
build=$(realpath "$1")
work="$2"
source_include=$(realpath "$3")
consumer_src=$(realpath "$4")
cxx="$5"
config="$6"
generator="$7"
expect_eigen="$8"
expect_tbb="$9"

fail() { echo "consumer_test: FAILED: $*"; exit 1; }
show_log() { echo "---- $1 (last 40 lines) ----"; tail -n 40 "$1"; echo "----"; }

cmake=${CMAKE:-cmake}
work=$(realpath -m "$work")
case "$work" in
  "$build"/?*) ;;
  *) fail "WORK_DIR $work is not inside BUILD_DIR $build (it is deleted first)" ;;
esac
rm -rf "$work" && mkdir -p "$work" || fail "cannot create $work"
prefix="$work/prefix"
consumer_build="$work/consumer_build"

# 1. Install. The install script writes install_manifest.txt into the build
#    tree: keep the one of a real installation (and leave none if there was none).
[ -f "$build/cmake_install.cmake" ] || fail "no $build/cmake_install.cmake (install rules disabled?)"
manifest="$build/install_manifest.txt"
[ -f "$manifest" ] && cp -p "$manifest" "$work/install_manifest.saved"
"$cmake" --install "$build" --prefix "$prefix" --config "$config" > "$work/install.log" 2>&1
install_status=$?
if [ -f "$work/install_manifest.saved" ]; then
  mv -f "$work/install_manifest.saved" "$manifest"
else
  rm -f "$manifest"
fi
[ $install_status -eq 0 ] || { show_log "$work/install.log"; fail "$cmake --install $build --prefix $prefix"; }
config_file=$(find "$prefix" -name Normal_orientationConfig.cmake | head -n 1)
[ -n "$config_file" ] || fail "install: no Normal_orientationConfig.cmake under $prefix"
[ -f "$prefix/include/Normal_orientation/orient_normals.h" ] || fail "install: no headers under $prefix/include"

# 2. Configure the consumer against the prefix only (no package registry).
if ! "$cmake" -S "$consumer_src" -B "$consumer_build" -G "$generator" \
       -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_BUILD_TYPE="$config" \
       -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF \
       -DCMAKE_EXPORT_COMPILE_COMMANDS=ON > "$work/configure.log" 2>&1; then
  show_log "$work/configure.log"; fail "configure the consumer (find_package(Normal_orientation) in $prefix)"
fi
found_dir=$(sed -n 's/^Normal_orientation_DIR:[A-Z]*=//p' "$consumer_build/CMakeCache.txt")
case "$found_dir" in
  "$prefix"/*) ;;
  *) fail "configure: Normal_orientation_DIR is '$found_dir', not under $prefix" ;;
esac

# 3. Build (one translation unit, but CGAL headers: 30 s to a minute).
if ! "$cmake" --build "$consumer_build" --config "$config" -j1 > "$work/build.log" 2>&1; then
  show_log "$work/build.log"; fail "build the consumer"
fi

# 4. It compiled from the installed headers, never the source tree's.
commands="$consumer_build/compile_commands.json"
[ -f "$commands" ] || fail "no $commands (generator '$generator' does not export compile commands?)"
grep -qF -e "-I$prefix/include" -e "-isystem $prefix/include" "$commands" \
  || fail "the consumer's compile command has no include path into $prefix/include"
if grep -rqF -- "$source_include" "$consumer_build"; then
  fail "the consumer's build refers to the source tree's $source_include: $(grep -rlF -- "$source_include" "$consumer_build" | head -n 3 | tr '\n' ' ')"
fi
# the compiler's dependency files (when the generator keeps them) name the installed header
if [ -n "$(find "$consumer_build" -name '*.d' -print -quit)" ] \
   && ! grep -rqF --include='*.d' -- "$prefix/include/Normal_orientation/orient_normals.h" "$consumer_build"; then
  fail "the consumer's dependency files do not name $prefix/include/Normal_orientation/orient_normals.h"
fi
# and it got the optional support targets the library's build has
if [ "$expect_eigen" = 1 ] && ! grep -q -- "-DCGAL_EIGEN3_ENABLED" "$commands"; then
  fail "the library's build has CGAL::Eigen3_support but the consumer was not compiled with it"
fi
if [ "$expect_tbb" = 1 ] && ! grep -q -- "-DCGAL_LINKED_WITH_TBB" "$commands"; then
  fail "the library's build has CGAL::TBB_support but the consumer was not compiled with it"
fi

# 5. Run it.
exe=$(find "$consumer_build" -type f -name consumer -perm -u+x | head -n 1)
[ -n "$exe" ] || fail "no consumer executable in $consumer_build"
"$exe"
status=$?
[ $status -eq 0 ] || fail "the consumer exited with status $status"
echo "consumer_test: passed (installed to $prefix, consumer built with $cxx, $config)"
