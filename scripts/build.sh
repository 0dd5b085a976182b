#!/usr/bin/env bash
# Configures and builds posefuse with CMake + Ninja.
#   scripts/build.sh                  release build in build/
#   scripts/build.sh --sanitize       ASan+UBSan debug build in build-sanitize/ with clang (it
#                                     compiles this build about twice as fast as GCC: CI time),
#                                     without the benchmarks (the tests do not use them)
#   scripts/build.sh --target NAME    only that CMake target and what it needs (repeatable;
#                                     default: everything, tests and benchmarks included)
#   BUILD_DIR=... scripts/build.sh    choose the build folder
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
sanitize=OFF
bench=ON
build_type=Release
default_dir="$root/build"
targets=()
compilers=()
while [ $# -gt 0 ]; do
  case "$1" in
    --sanitize)
      sanitize=ON; bench=OFF; build_type=RelWithDebInfo; default_dir="$root/build-sanitize"
      compilers=(-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++) ;;
    --target)
      [ $# -ge 2 ] || { echo "build: --target needs a target name" >&2; exit 2; }
      targets+=(--target "$2"); shift ;;
    *) echo "build: unknown option '$1'" >&2; exit 2 ;;
  esac
  shift
done
build_dir=${BUILD_DIR:-$default_dir}
jobs=${POSEFUSE_JOBS:-$(nproc)}

"$root/scripts/setup.sh"
cmake -S "$root" -B "$build_dir" -G Ninja \
  -DCMAKE_BUILD_TYPE="$build_type" -DPOSEFUSE_SANITIZE="$sanitize" -DPOSEFUSE_BUILD_BENCH="$bench" \
  "${compilers[@]}" >/dev/null
cmake --build "$build_dir" -j "$jobs" "${targets[@]}"
echo "build: done in $build_dir"
