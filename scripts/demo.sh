#!/usr/bin/env bash
# The README's first command: builds the four programs it runs (not the tests and benchmarks),
# makes the demo session, starts the real posefuse-server on a free loopback port, runs the
# posefuse client against it, stops the server, prints where the results are and scores them
# against the simulated ground truth (posefuse-score).
#   scripts/demo.sh                      results in build/demo/results
#   DEMO_DIR=/tmp/demo scripts/demo.sh   choose the folder
# The demo session comes from the simulator (posefuse-sim, docs/simulator.md): a short take of
# paper 1's forearm protocol (calibration pose, forearm behind the head, in front of the belly,
# behind the back) on built-in defaults, with its ground truth in gt/ beside the results. The
# server fits the body model by default (fit.enabled), so the results have SMPL and camera
# joints, joint angles and repetitions as well as the forearm results.
#   DEMO_DURATION_S=25 scripts/demo.sh   session length in seconds (default 20)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build_dir=${BUILD_DIR:-$root/build}
demo_dir=${DEMO_DIR:-$build_dir/demo}

BUILD_DIR="$build_dir" "$root/scripts/build.sh" \
  --target posefuse-server --target posefuse --target posefuse-sim --target posefuse-score
server_bin="$build_dir/server/posefuse-server"
client_bin="$build_dir/client/posefuse"

rm -rf "$demo_dir"
mkdir -p "$demo_dir"
sim_bin="$build_dir/tools/sim/posefuse-sim"
duration_s=${DEMO_DURATION_S:-20}
session="$demo_dir/demo-session.pfchunks"
sim_options="$demo_dir/demo-sim.txt"
cat >"$sim_options" <<OPTIONS
# paper 1's protocol once, both arms together (IMUs on both wrists)
motion = forearm_protocol
repetitions = 1
arm = both
duration_s = $duration_s
OPTIONS
echo "demo: simulating a ${duration_s} s session (posefuse-sim --options $sim_options)"
"$sim_bin" --options "$sim_options" --chunk-file "$session" --gt "$demo_dir/gt"

# Port 0: the server picks a free port and logs it (event=server_start ... port=N).
server_log="$demo_dir/server.log"
"$server_bin" --listen 127.0.0.1:0 2>"$server_log" &
server_pid=$!
stop_server() {
  if kill -0 "$server_pid" 2>/dev/null; then
    kill -TERM "$server_pid"
    wait "$server_pid" || true
  fi
}
trap stop_server EXIT

port=""
for _ in $(seq 1 100); do
  port=$(sed -n 's/.*event=server_start .* port=\([0-9]*\).*/\1/p' "$server_log")
  [ -n "$port" ] && break
  kill -0 "$server_pid" 2>/dev/null || { echo "demo: the server did not start:" >&2; cat "$server_log" >&2; exit 1; }
  sleep 0.1
done
[ -n "$port" ] || { echo "demo: the server did not report its port" >&2; exit 1; }
address="127.0.0.1:$port"

for _ in $(seq 1 50); do
  if "$client_bin" health --server "$address" >/dev/null 2>&1; then break; fi
  sleep 0.1
done
echo "demo: posefuse-server on $address is $("$client_bin" health --server "$address")"

results="$demo_dir/results"
"$client_bin" fit "$session" --server "$address" --out "$results"
"$client_bin" report "$results"

stop_server
trap - EXIT
echo
echo "demo: done. Results in $results"
ls "$results"
echo "  imu_orientations/*.csv      W_from_A per IMU sample (t_us,w,x,y,z)"
echo "  forearm_orientations/*.csv  K_from_F and pronation per arm IMU sample"
echo "  imu_positions.csv           arm IMU position in K per camera frame"
echo "  recovered_segments.csv      forearm trajectories recovered through occlusions"
echo "  calibration.json            per IMU gyro bias and field; forearm model; clock offsets"
echo "  summary.json                counts and durations"
echo "  warnings.txt                warnings and per-chunk errors (empty when none)"
echo "  joint_angles.csv            ISB joint angles per frame, with confidences (docs/measures.md)"
echo "  repetitions.csv             repetitions and the range of motion of each"
echo "  report.html                 the session report to open in a browser (docs/report.md)"
echo "Ground truth of the simulated session (same files and columns): $demo_dir/gt"
echo "  session: $session; server log: $server_log"
echo
score_bin="$build_dir/tools/score/posefuse-score"
echo "demo: the results scored against the ground truth ($score_bin $results $demo_dir/gt):"
"$score_bin" "$results" "$demo_dir/gt"
