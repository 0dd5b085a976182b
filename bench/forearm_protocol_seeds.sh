#!/usr/bin/env bash
# Paper 1's protocol with both arms on many simulated sessions (posefuse-sim, the body render,
# no body fit): per session and arm the visual IMU positions (frames, and the largest error:
# a wrong band accepted shows here) and the upper arm d_ul against the truth with its claimed
# sigma, then a summary line per set.
#   bench/forearm_protocol_seeds.sh [BUILD_DIR] [SEED:SPEED ...]
# Default sessions: seeds 31-50 at speeds 0.8 and 1.2 (used to choose nothing), 12 s each.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
shift || true
specs=("$@")
if [ ${#specs[@]} -eq 0 ]; then
  for seed in $(seq 31 50); do specs+=("$seed:0.8" "$seed:1.2"); done
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for spec in "${specs[@]}"; do
  IFS=: read -r seed speed <<<"$spec"
  name="$seed-$speed"
  printf 'motion = forearm_protocol\nrepetitions = 1\narm = both\nspeed = %s\n' "$speed" >"$work/$name.options"
  "$build/tools/sim/posefuse-sim" --options "$work/$name.options" --seed "$seed" --duration 12 --quiet \
    --chunk-file "$work/$name.pfchunks" --gt "$work/$name.gt" >/dev/null
  "$build/bench/bench_sim_forearm" replay "$work/$name.pfchunks" "$work/$name.gt" "$work/$name.out" \
    >"$work/$name.score"
  rm -rf "$work/$name.pfchunks" "$work/$name.gt" "$work/$name.out"
done
python3 - "$work" "${specs[@]}" <<'PY'
import math, re, sys
work, specs = sys.argv[1], sys.argv[2:]
print(f"{'session':10s} {'arm':5s} {'visual n':>8s} {'max (m)':>8s} {'d_ul error (m)':>14s} {'claimed sigma':>13s}")
visual_frames = arms_over = 0
largest = 0.0
errors, sigmas = [], []
for spec in specs:
    name = spec.replace(":", "-")
    visual, d_ul = {}, {}
    for line in open(f"{work}/{name}.score"):
        m = re.match(r"imu_(left|right)\s+VISUAL\s+(\d+)\s+[\d.]+\s+([\d.]+)", line)
        if m: visual[m.group(1).upper()] = (int(m.group(2)), float(m.group(3)))
        m = re.match(r"(LEFT|RIGHT) d_ul\s+m\s+\S+\s+\S+\s+(\S+)\s+(\S+)", line)
        if m: d_ul[m.group(1)] = (float(m.group(2)), float(m.group(3)))
    for arm in ("LEFT", "RIGHT"):
        n, worst = visual.get(arm, (0, 0.0))
        error, sigma = d_ul.get(arm, (math.nan, math.nan))
        visual_frames += n
        arms_over += worst > 0.05
        largest = max(largest, worst)
        if not math.isnan(error): errors.append(error); sigmas.append(sigma)
        print(f"{name:10s} {arm:5s} {n:8d} {worst:8.4f} {error:14.4f} {sigma:13.4f}")
rms = math.sqrt(sum(e * e for e in errors) / len(errors)) if errors else math.nan
print(f"\n{len(specs)} sessions: {visual_frames} visual frames, {arms_over} arm(s) with one beyond 5 cm, "
      f"largest {largest:.4f} m; d_ul on {len(errors)} arms: RMS error {rms:.4f} m, "
      f"largest {max(map(abs, errors), default=math.nan):.4f} m, claimed sigma {max(sigmas, default=math.nan):.4f} m")
PY
