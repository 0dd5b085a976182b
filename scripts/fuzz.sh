#!/usr/bin/env bash
# Builds the libFuzzer harnesses (fuzz/, clang + ASan + UBSan) into build-fuzz/ and runs each
# for a bounded time on its seeds (written by the harness itself) and the corpus it grew before,
# then prints a table: harness, executions, seconds, corpus files, findings, and the total.
#   scripts/fuzz.sh [SECONDS]     seconds per harness (default 30)
#   FUZZERS="image wav" scripts/fuzz.sh 10     only these harnesses
#   FUZZ_JOBS=2 scripts/fuzz.sh 600            a campaign: two harnesses at a time
#   BUILD_DIR=... scripts/fuzz.sh              choose the build folder (default build-fuzz/)
# Exits non-zero on any crash, leak, timeout or memory limit, printing the reproducer's path;
# rerun one with build-fuzz/fuzz/fuzz_NAME REPRODUCER.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
seconds=${1:-30}
build_dir=${BUILD_DIR:-$root/build-fuzz}
jobs=${POSEFUSE_JOBS:-$(nproc)}
fuzz_jobs=${FUZZ_JOBS:-1}
all_fuzzers="chunk_file image imu_batch json wav csv session_validator bvh npz result_reader server_files
  directory_reader session_pipeline"
fuzzers=${FUZZERS:-$all_fuzzers}

"$root/scripts/setup.sh"
export CCACHE_DIR=${CCACHE_DIR:-$HOME/.cache/ccache}
export CCACHE_BASEDIR=${CCACHE_BASEDIR:-$root} CCACHE_NOHASHDIR=${CCACHE_NOHASHDIR:-1}

start=$SECONDS
# -O1 with line tables (enough for the sanitizers' stack traces) and without NDEBUG: a failed
# assert() is a finding too.
cmake -S "$root" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only" \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DPOSEFUSE_FUZZ=ON >/dev/null
targets=()
for name in $fuzzers; do targets+=(--target "fuzz_$name"); done
cmake --build "$build_dir" -j "$jobs" "${targets[@]}"
echo "fuzz: built in $((SECONDS - start)) s"

# Leaks inside system libraries that posefuse does not call directly (scripts/lsan.supp).
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:allocator_may_return_null=0}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$root/scripts/lsan.supp:print_suppressions=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

# -malloc_limit_mb: one larger allocation is a finding (a memory bomb). Inputs are at most
# 64 KiB (-max_len), so 16 MiB is far above what any of them needs, except:
# - colour images: 4096x3072 (kMaxColorPixels) grey is 12 MiB, and libjpeg holds a
#   progressive JPEG's coefficients (2 bytes a pixel per component) while decoding it; a
#   recording directory's frames are such images;
# - SessionChunk parsing: protobuf reserves what a string inside a nested message claims, up
#   to its safe size of 50 MB, before it finds the message short (docs/server.md, Fuzzing);
# - npz: deflate holds at most about 1032 output bytes per input byte, so a 64 KiB archive can
#   truly inflate to 66 MiB (the string holding it grows to twice that at most).
malloc_limit_mb() {
  case "$1" in
    image | chunk_file | session_validator | directory_reader) echo 64 ;;
    npz) echo 160 ;;
    *) echo 16 ;;
  esac
}

results=$(mktemp -d)
trap 'rm -rf "$results"' EXIT

# Runs one harness; leaves "EXECUTIONS SECONDS CORPUS FINDINGS" in $results/NAME.
run_harness() {
  local name=$1
  local binary="$build_dir/fuzz/fuzz_$name"
  local corpus="$build_dir/fuzz-corpus/$name"
  local artifacts="$build_dir/fuzz-artifacts/$name"
  mkdir -p "$corpus" "$artifacts"
  POSEFUSE_FUZZ_WRITE_SEEDS="$corpus" "$binary" >/dev/null
  local log="$artifacts/fuzz.log"
  local run_start=$SECONDS findings=0
  # A fixed seed (FUZZ_SEED, default 1): a CI run mutates the same way each time.
  if ! "$binary" "$corpus" -seed="${FUZZ_SEED:-1}" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
       -malloc_limit_mb="$(malloc_limit_mb "$name")" -max_len=65536 -print_final_stats=1 \
       -artifact_prefix="$artifacts/" >"$log" 2>&1; then
    findings=1
    {
      echo "fuzz: $name FAILED; log $log"
      grep -E "^(==[0-9]+==ERROR|SUMMARY|posefuse fuzz invariant|.*runtime error)" "$log" | head -5 || true
      for reproducer in $(sed -n 's/.*Test unit written to \(.*\)$/\1/p' "$log"); do
        echo "fuzz: reproducer $reproducer (rerun: $binary $reproducer)"
      done
    } >&2
  fi
  local execs
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  echo "${execs:-0} $((SECONDS - run_start)) $(find "$corpus" -type f | wc -l) $findings" >"$results/$name"
}

run_start=$SECONDS
for name in $fuzzers; do
  while [ "$(jobs -rp | wc -l)" -ge "$fuzz_jobs" ]; do wait -n || true; done
  run_harness "$name" &
done
wait

printf '%-18s %12s %8s %8s %9s\n' harness executions seconds corpus findings
total_execs=0 total_findings=0 failed=()
for name in $fuzzers; do
  read -r execs secs corpus findings <"$results/$name"
  printf '%-18s %12s %8s %8s %9s\n' "$name" "$execs" "$secs" "$corpus" "$findings"
  total_execs=$((total_execs + execs))
  total_findings=$((total_findings + findings))
  [ "$findings" -eq 0 ] || failed+=("$name")
done
printf '%-18s %12s %8s %8s %9s\n' total "$total_execs" "$((SECONDS - run_start))" "" "$total_findings"
echo "fuzz: done in $((SECONDS - start)) s"
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz: findings in: ${failed[*]}" >&2
  exit 1
fi
