#!/usr/bin/env bash
# Configures and builds posefuse with CMake + Ninja.
#   scripts/build.sh                  release build in build/
#   scripts/build.sh --sanitize       ASan+UBSan debug build in build-sanitize/
#   BUILD_DIR=... scripts/build.sh    choose the build folder
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
sanitize=OFF
build_type=Release
default_dir="$root/build"
for arg in "$@"; do
  case "$arg" in
    --sanitize) sanitize=ON; build_type=RelWithDebInfo; default_dir="$root/build-sanitize" ;;
    *) echo "build: unknown option '$arg'" >&2; exit 2 ;;
  esac
done
build_dir=${BUILD_DIR:-$default_dir}
jobs=${POSEFUSE_JOBS:-$(nproc)}

"$root/scripts/setup.sh"
cmake -S "$root" -B "$build_dir" -G Ninja \
  -DCMAKE_BUILD_TYPE="$build_type" -DPOSEFUSE_SANITIZE="$sanitize" >/dev/null
cmake --build "$build_dir" -j "$jobs"
echo "build: done in $build_dir"
