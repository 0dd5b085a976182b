#!/usr/bin/env bash
# Where posefuse-server's CPU goes for one live session with the body fit on: perf samples the
# servers of `bench_server_capacity --sessions 1` (the paced session, then the offline one) with
# DWARF call stacks, and each sample is put in the first stage below whose function is on its
# stack (so the fit's LM called from inside the forearm stage's hand-on counts as the fit's).
# Prints the share of each server's samples per stage.
#   bench/server_profile.sh [BUILD_DIR] [bench_server_capacity options, e.g. --session FILE]
# Needs perf (Debian: linux-perf), installed by hand: it is for profiling, not a dependency of
# the build or the tests. Sampling is by cpu-clock, so it works without hardware counters.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
shift || true
command -v perf >/dev/null || { echo "server_profile: perf not found (apt-get install linux-perf)" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
perf record -q -e cpu-clock -F 499 --call-graph dwarf,16384 -o "$work/perf.data" -- \
  "$build/bench/bench_server_capacity" --sessions 1 "$@" >"$work/bench.txt"
cat "$work/bench.txt"
perf script -i "$work/perf.data" -F pid,tid,ip,sym 2>/dev/null >"$work/stacks.txt"
python3 - "$work/stacks.txt" <<'PY'
import collections, re, sys

# (stage, functions any of which on the stack puts the sample there), first match wins.
STAGES = [
    ("body fit: depth preprocessing (fit::prepare_observation)", ["fit::prepare_observation"]),
    ("body fit: LM (fit::FrameFitter, SchurSystem)", ["fit::FrameFitter::", "fit::SchurSystem"]),
    ("body fit: the rest (frame assembly, tracker, packing, cleanup)", ["fit::", "BodyFitStage", "body::"]),
    # Before the forearm stage: the stage decodes its colour rectangles itself.
    ("decoding: colour JPEG to grey (the strap rectangles)", ["decode_color_gray", "ColorImage::"]),
    ("forearm stage: arm axes and strap in depth and colour (measure_arm_frame, find_arm_strap)",
     ["forearm::measure_arm_frame", "forearm::find_arm_strap"]),
    ("forearm stage and gaps: the rest (tracking, clocks, recovery)", ["ForearmStage", "forearm::", "ForearmGapsStage", "sync::"]),
    ("decoding: depth (zstd) and body index (PNG)", ["decode_depth", "decode_body_index", "cv::imdecode"]),
    ("validation", ["SessionValidator", "validate_chunk"]),
    ("IMU orientation filter", ["imu::"]),
    ("frame merge, measures, result encoding", ["FrameMerge", "MeasuresStage", "measures::", "ResultEncoder"]),
    ("pipeline and frame assembly, the rest", ["session::"]),
    ("gRPC, protobuf, sockets", ["grpc", "google::protobuf", "tcp_", "sock_", "__sys_", "epoll", "absl::"]),
]
OTHER = "other (kernel, libc, unresolved)"

def stage_of(stack):
    for name, keys in STAGES:
        if any(key in frame for frame in stack for key in keys):
            return name
    return OTHER

per_pid = collections.defaultdict(collections.Counter)
pid, stack = None, []
def flush():
    if pid is not None and stack:
        per_pid[pid][stage_of(stack)] += 1
for line in open(sys.argv[1]):
    if not line.strip():
        flush()
        pid, stack = None, []
    elif re.fullmatch(r"\s*\d+/\d+\s*", line):
        # A sample's header ("PID/TID", padded to a width that depends on the PIDs' digits).
        flush()
        pid, stack = int(line.split("/")[0]), []
    else:
        stack.append(line.strip())
flush()
# The bench's own process first, then its server children in the order it forked them.
pids = sorted(per_pid)
if len(pids) < 3:
    sys.exit("server_profile: expected the bench and two server processes in the profile")
for label, server in (("paced session", pids[1]), ("offline session", pids[-1])):
    counts = per_pid[server]
    total = sum(counts.values())
    print(f"\nserver CPU by stage, {label} ({total} samples at 499 Hz)")
    print("| stage | share % |")
    print("|---|---:|")
    for name, n in counts.most_common():
        print(f"| {name} | {100.0 * n / total:.1f} |")
PY
