#!/usr/bin/env bash
# Builds posefuse and runs the whole test suite with CTest.
#   scripts/test.sh               release build
#   scripts/test.sh --sanitize    AddressSanitizer + UndefinedBehaviorSanitizer build
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/build.sh" "$@"
build_dir=${BUILD_DIR:-$root/build}
for arg in "$@"; do
  if [ "$arg" = --sanitize ]; then build_dir=${BUILD_DIR:-$root/build-sanitize}; fi
done
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1}
# Leaks inside system libraries that posefuse does not call directly (scripts/lsan.supp says which).
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$root/scripts/lsan.supp:print_suppressions=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
ctest --test-dir "$build_dir" --output-on-failure -j "${POSEFUSE_JOBS:-$(nproc)}"
