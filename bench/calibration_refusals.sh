#!/usr/bin/env bash
# Paper 1's calibration (forearm/arm_calibration.hpp) on simulated sessions: per session and arm,
# the hold taken (frames, eq. 9 spread, upper arm d_ul) or the reason it was refused, and the
# forearm orientation error of what the stage streamed (posefuse-score, deg RMS / max; for a
# refused hold, of the mounting from motion the stage falls back to).
#   bench/calibration_refusals.sh [BUILD_DIR] [MOTION:SEED:SPEED ...]
# Default sessions: seeds 41-43 (used to choose nothing) of the calibration pose and paper 1's
# protocol at speeds 0.8 and 1.2, and exercises without the pose (arm_raising, shoulder_lift,
# hair_combing, forearm_rolling) at seeds 41-42; both arms, 12 s, the body render, no body fit.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
shift || true
specs=("$@")
if [ ${#specs[@]} -eq 0 ]; then
  for seed in 41 42 43; do
    for motion in calibration_pose forearm_protocol; do specs+=("$motion:$seed:0.8" "$motion:$seed:1.2"); done
  done
  for seed in 41 42; do
    for motion in arm_raising shoulder_lift hair_combing forearm_rolling; do specs+=("$motion:$seed:1.0"); done
  done
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf '%-26s %-5s %-9s %s\n' session arm "RMS/max" "calibration"
for spec in "${specs[@]}"; do
  IFS=: read -r motion seed speed <<<"$spec"
  name="$motion-$seed-$speed"
  printf 'motion = %s\nspeed = %s\narm = both\n' "$motion" "$speed" >"$work/$name.options"
  "$build/tools/sim/posefuse-sim" --options "$work/$name.options" --seed "$seed" --duration 12 --quiet \
    --chunk-file "$work/$name.pfchunks" --gt "$work/$name.gt" >/dev/null
  "$build/bench/bench_sim_forearm" replay "$work/$name.pfchunks" "$work/$name.gt" "$work/$name.out" >"$work/$name.score"
  python3 - "$name" "$work/$name.out" "$work/$name.score" <<'PY'
import json, math, re, sys
name, out, score = sys.argv[1:]
errors = {}
for line in open(score):
    m = re.match(r"forearm_orientations/imu_(left|right)\.csv\s+\S+\s+\d+\s+([\d.]+)\s+([\d.]+)", line)
    # The orientation table comes first; posefuse-score's confidence table repeats the stream.
    if m and m.group(1).upper() not in errors:
        errors[m.group(1).upper()] = f"{float(m.group(2)):.1f}/{float(m.group(3)):.1f}"
calibrated = {f["arm"]: f for f in json.load(open(out + "/calibration.json")).get("forearms", [])
              if f.get("mounting_source", "CALIBRATION_POSE") == "CALIBRATION_POSE"}
from_motion = {f["arm"] for f in json.load(open(out + "/calibration.json")).get("forearms", [])
               if f.get("mounting_source") == "MOTION"}
refusals = {}
for line in open(out + "/warnings.txt"):
    m = re.match(r"warning \[FOREARM_CALIBRATION\] forearm\[imu_(left|right)\]\.calibration: .*? s: frames: (.*?) \(\d+ tracked", line)
    if m: refusals[m.group(1).upper()] = "refused: " + m.group(2)
for arm in ("LEFT", "RIGHT"):
    if arm in calibrated:
        f = calibrated[arm]
        what = (f"{f['calibration_frames']} frames, spread {math.degrees(f.get('A_from_F_spread_rad', 0)):.1f} deg, "
                f"upper arm {100 * f['d_ul_m']:.1f} cm")
    else:
        what = refusals.get(arm, "no calibration")
        if arm in from_motion: what += " (mounting from motion: bench/forearm_anywhere.sh)"
    print(f"{name:26s} {arm:5s} {errors.get(arm, '-'):9s} {what}")
PY
done
