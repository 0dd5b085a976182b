#!/usr/bin/env bash
# ISB joint angles and repetitions (docs/measures.md) through the real server and client, scored
# against the simulator's true angles (posefuse-score): per angle the RMS and max error pooled
# over the sessions (all frames, and the frames the result gives confidence >= 0.5), and per
# session the repetitions counted against the truth's and the range of motion error per
# repetition (all matched ones, and those whose range has confidence >= 0.5).
#   bench/joint_angles.sh [BUILD_DIR] [MOTION:SEED:SPEED ...]     MOTION: an exercise's name or a .bvh clip
# KEEP=DIR keeps each session's recording, results and gt/ under DIR (e.g. for posefuse report).
# SIM_OPTIONS='key = value\n...' adds posefuse-sim options to every session (e.g. a tilted camera:
# 'camera_pitch_deg = 12\ncamera_roll_deg = -4').
# SUBJECT='key = value\n...' replaces the subject's posefuse-sim options (default: 'sex = female\nbetas =
# 1.5,-1,0.5\nclothing = true'; e.g. the fitted template's own shape, 'sex = female\nbetas = 0\nclothing = true').
# FIT_OPTIONS='KEY=VALUE ...' adds stage options to every fit call (e.g. 'fit.trusted_energy=100'
# for bench/fit_energy_confidence.py).
# Default sessions: the scripted exercises at seeds 71 and 72 and speeds 0.9 and 1.15, both arms,
# three repetitions, a subject unlike the template (female, betas 1.5,-1,0.5, clothing on), body
# fit on. Seeds 61 and 62 (speeds 0.8, 1.25) are where the repetitions' resting-half rule was
# designed (docs/benchmarks.md, "Joint angles and repetitions"); nothing was chosen on 71 and 72.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
shift || true
specs=("$@")
if [ ${#specs[@]} -eq 0 ]; then
  specs=(arm_raising:71:0.9 arm_raising:72:1.15 shoulder_lift:71:1.15 shoulder_lift:72:0.9
         forearm_rolling:71:0.9 forearm_rolling:72:1.15 hair_combing:71:1.15 hair_combing:72:0.9
         torso_tilt:71:0.9 torso_tilt:72:1.15 forearm_protocol:71:1.0 forearm_protocol:72:1.0)
fi
fit_options=()
for option in ${FIT_OPTIONS:-}; do fit_options+=(--option "$option"); done
work=${KEEP:-$(mktemp -d)}
mkdir -p "$work"
server_pid=
cleanup() {
  [ -n "$server_pid" ] && kill "$server_pid" 2>/dev/null || true
  [ -n "${KEEP:-}" ] || rm -rf "$work"
}
trap cleanup EXIT
: >"$work/server.log"  # before the background job's redirection, which the polling can outrun
"$build/server/posefuse-server" --listen 127.0.0.1:0 >"$work/server.log" 2>&1 &
server_pid=$!
for _ in $(seq 100); do
  port=$(sed -n 's/.*event=server_start.* port=\([0-9]*\).*/\1/p' "$work/server.log" | head -1)
  [ -n "$port" ] && break
  sleep 0.1
done
[ -n "$port" ] || { echo "server did not start: $(cat "$work/server.log")" >&2; exit 1; }
for spec in "${specs[@]}"; do
  IFS=: read -r motion seed speed <<<"$spec"
  subject="${SUBJECT:-sex = female\nbetas = 1.5,-1,0.5\nclothing = true}\n${SIM_OPTIONS:+$SIM_OPTIONS\n}"
  if [[ "$motion" == *.bvh ]]; then  # a whole mocap clip, the same subject
    name="$(basename "$motion" .bvh)-$seed-$speed"
    printf "motion = bvh\nbvh_path = %s\nspeed = %s\narm = both\nduration_s = clip\n$subject" \
      "$motion" "$speed" >"$work/$name.options"
  else
    name="$motion-$seed-$speed"
    printf "motion = %s\nspeed = %s\narm = both\nrepetitions = 3\n$subject" "$motion" "$speed" >"$work/$name.options"
  fi
  "$build/tools/sim/posefuse-sim" --options "$work/$name.options" --seed "$seed" --duration clip --quiet \
    --chunk-file "$work/$name.pfchunks" --gt "$work/$name.gt" >/dev/null
  "$build/client/posefuse" fit "$work/$name.pfchunks" --server "127.0.0.1:$port" --out "$work/$name.out" \
    --option fit.enabled=true "${fit_options[@]}" >/dev/null 2>"$work/$name.fit.log" || { cat "$work/$name.fit.log" >&2; exit 1; }
  "$build/tools/score/posefuse-score" "$work/$name.out" "$work/$name.gt" >"$work/$name.score"
done
python3 - "$work" "${specs[@]}" <<'PY'
import csv, math, re, sys
work, specs = sys.argv[1], sys.argv[2:]
pooled = {}  # angle -> [sum n*rms^2, n, max]
sessions = []
for spec in specs:
    motion, seed, speed = spec.split(":")
    if motion.endswith(".bvh"):
        motion = motion.rsplit("/", 1)[-1][: -len(".bvh")]
    name = f"{motion}-{seed}-{speed}"
    text = open(f"{work}/{name}.score").read()
    section = text.split("ISB joint angle error (deg)\n", 1)[1].split("\n\n", 1)[0] if "ISB joint" in text else ""
    for line in section.splitlines()[1:]:
        f = line.split()
        if len(f) < 7 or not f[1].isdigit() or int(f[1]) == 0: continue
        angle, n, rms, mx, cn = f[0], int(f[1]), float(f[2]), float(f[3]), int(f[4])
        p = pooled.setdefault(angle, [0.0, 0, 0.0, 0.0, 0, 0.0])
        p[0] += n * rms * rms; p[1] += n; p[2] = max(p[2], mx)
        if cn > 0:
            crms, cmx = float(f[5]), float(f[6])
            p[3] += cn * crms * crms; p[4] += cn; p[5] = max(p[5], cmx)
    m = re.search(r"Repetitions.*\n.*\n(\S+)\s+(\S+)\s+(\d+)\s+(\d+)\s+(\d+)\s+(\S+)\s+(\S+)\s+(\d+)\s+(\S+)\s+(\S+)",
                  text)
    # The truth's own choice of angle and its count: posefuse-score scores a result that chose
    # another angle against the truth's series of that angle, which hides a wrong choice.
    own = [r for r in csv.DictReader(open(f"{work}/{name}.gt/repetitions.csv")) if r["counted"] == "1"]
    truth_own = f"{own[0]['angle']}: {len(own)}" if own else "none"
    sessions.append((name, m.groups() if m else None, truth_own))
print("Joint angle error, pooled over the sessions (deg)\n")
print("| angle | frames | RMS | max | confident frames | confident RMS | confident max |")
print("|---|---|---|---|---|---|---|")
for angle, (s, n, mx, cs, cn, cmx) in pooled.items():
    confident = f"{cn} | {math.sqrt(cs / cn):.2f} | {cmx:.2f}" if cn else "0 | - | -"
    print(f"| {angle} | {n} | {math.sqrt(s / n):.2f} | {mx:.2f} | {confident} |")
print()
print("Repetitions per session (counted; ROM error per matched repetition, deg; confident: those whose range")
print("the result gives confidence >= 0.5)\n")
print("| session | angle | true angle | count | true count | ROM error RMS | ROM error max | confident | confident RMS | confident max | the truth's own angle: count |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for name, g, truth_own in sessions:
    if g is None:
        print(f"| {name} | (no repetitions in the results) | | | | | | | | | {truth_own} |"); continue
    angle, true_angle, count, true_count, matched, rms, mx, cn, crms, cmx = g
    print(f"| {name} | {angle} | {true_angle} | {count} | {true_count} | {rms} | {mx} | {cn} of {matched} | {crms} | {cmx} | {truth_own} |")

import json
def up_of(q):  # W's z (up) in K from a K_from_W quaternion
    w, x, y, z = (q.get(k, 0.0) for k in "wxyz")
    return (2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y))
def angle(a, b):
    dot = sum(p * q for p, q in zip(a, b)) / math.sqrt(sum(p * p for p in a) * sum(q * q for q in b))
    return math.degrees(math.acos(max(-1.0, min(1.0, dot))))
print()
print("The vertical of the thorax angles (calibration.json's `vertical` against the true K_from_W; deg)\n")
print("| session | true pitch | true roll | source | confidence | error | floor spread | IMU error |")
print("|---|---|---|---|---|---|---|---|")
for name, *_ in sessions:
    out = json.load(open(f"{work}/{name}.out/calibration.json"))
    true_up = up_of(json.load(open(f"{work}/{name}.gt/calibration.json"))["K_from_W"])
    v = out.get("vertical", {})
    up = v.get("up_K", {})
    used = (up.get("x", 0.0), up.get("y", 0.0), up.get("z", 0.0))
    pitch = math.degrees(math.asin(-true_up[2]))
    roll = math.degrees(math.atan2(-true_up[0], true_up[1]))
    imu = out.get("K_from_W")
    imu_error = f"{angle(up_of(imu), true_up):.2f}" if imu and any(imu.get(k, 0) for k in "wxyz") else "-"
    spread = f"{v['floor_spread_deg']:.2f}" if v.get("source") == "FLOOR" else "-"
    print(f"| {name} | {pitch:.1f} | {roll:.1f} | {v.get('source', '-')} | {v.get('confidence', 0):.2f} | "
          f"{angle(used, true_up):.2f} | {spread} | {imu_error} |")
PY
