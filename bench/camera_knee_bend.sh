#!/usr/bin/env bash
# The camera skeleton's knee bend against the bend that frees a leg in the body fit
# (fit/limb_bend.hpp, docs/fitting.md "Legs"): per simulated session and leg, the bend of the
# tracked hip - knee - ankle (median, 99th percentile, max) and the share of frames above
# atan(2e / thigh) + atan(2e / shank), e = 5 cm; with the true knee bend (gt/smpl_joints.csv) beside
# it. Straight-legged scripted sessions say how often a straight leg would be freed; the mocap
# clips how often a bent one is.
#   bench/camera_knee_bend.sh [BUILD_DIR] [MOTION:SEED:SPEED ...]   (MOTION a scripted exercise or a .bvh)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
shift || true
specs=("$@")
if [ ${#specs[@]} -eq 0 ]; then
  for seed in 61 62 71 72 81 82 91 92 101 102; do specs+=("arm_raising:$seed:1.0"); done
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
subject="sex = female\nbetas = 1.5,-1,0.5\nclothing = true\n"  # bench/joint_angles.sh's subject
for spec in "${specs[@]}"; do
  IFS=: read -r motion seed speed <<<"$spec"
  if [[ "$motion" == *.bvh ]]; then
    name="$(basename "$motion" .bvh)-$seed-$speed"
    printf "motion = bvh\nbvh_path = %s\nspeed = %s\narm = both\nduration_s = clip\n$subject" "$motion" "$speed" \
      >"$work/$name.options"
  else
    name="$motion-$seed-$speed"
    printf "motion = %s\nspeed = %s\narm = both\nrepetitions = 2\n$subject" "$motion" "$speed" >"$work/$name.options"
  fi
  "$build/tools/sim/posefuse-sim" --options "$work/$name.options" --seed "$seed" --duration clip --quiet \
    --chunk-file "$work/$name.pfchunks" --gt "$work/$name.gt" >/dev/null
  "$build/client/posefuse" convert "$work/$name.pfchunks" "$work/$name" >/dev/null
  rm -f "$work/$name.pfchunks"
  echo "$name" >>"$work/names"
done
python3 - "$work" <<'PY'
import collections, csv, math, sys
work = sys.argv[1]
E = 0.05  # fit::kCameraJointErrorM

def bend(h, k, a):
    u = [k[i] - h[i] for i in range(3)]
    v = [a[i] - k[i] for i in range(3)]
    c = sum(u[i] * v[i] for i in range(3)) / math.sqrt(sum(x * x for x in u) * sum(x * x for x in v))
    return math.degrees(math.acos(max(-1.0, min(1.0, c)))), math.dist(h, k), math.dist(k, a)

def percentile(v, q):
    return sorted(v)[min(len(v) - 1, int(q * len(v)))]

print("| session | leg | tracked frames | camera bend median | p99 | max | freed (above 2e) | true bend median |")
print("|---|---|---:|---:|---:|---:|---:|---:|")
for name in open(f"{work}/names").read().split():
    camera = collections.defaultdict(dict)
    for r in csv.DictReader(open(f"{work}/{name}/skeleton.csv")):
        camera[r["t_us"]][r["joint_name"]] = (r["state"], [float(r[c]) for c in ("x_m", "y_m", "z_m")])
    truth = collections.defaultdict(dict)
    for r in csv.DictReader(open(f"{work}/{name}.gt/smpl_joints.csv")):
        truth[r["t_us"]][r["joint_name"]] = [float(r[c]) for c in ("x_m", "y_m", "z_m")]
    for side in ("Left", "Right"):
        bends, freed = [], 0
        for joints in camera.values():
            legs = [joints.get(j + side) for j in ("Hip", "Knee", "Ankle")]
            if any(j is None or j[0] != "TRACKED" for j in legs):
                continue
            b, thigh, shank = bend(*(j[1] for j in legs))
            bends.append(b)
            freed += b > math.degrees(math.atan2(2 * E, thigh) + math.atan2(2 * E, shank))
        s = side.lower()
        true = [bend(j[s + "_hip"], j[s + "_knee"], j[s + "_ankle"])[0] for j in truth.values()]
        if not bends:
            print(f"| {name} | {s} | 0 | - | - | - | - | {percentile(true, 0.5):.1f} |")
            continue
        print(f"| {name} | {s} | {len(bends)} | {percentile(bends, 0.5):.1f} | {percentile(bends, 0.99):.1f} | "
              f"{max(bends):.1f} | {100 * freed / len(bends):.1f} % | {percentile(true, 0.5):.1f} |")
PY
