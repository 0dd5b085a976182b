#!/usr/bin/env bash
# The interop test (CTest): starts the real posefuse-server on 127.0.0.1, port 0, and drives it
# with Node's @grpc/grpc-js + @grpc/proto-loader (interop_client.js): Fit, the job calls, health,
# reflection. docs/server.md "Interop test" says why each outcome is what it is.
#
#   run_interop.sh SERVER CLIENT WORK_DIR SOURCE_DIR plain|token
#
# SERVER, CLIENT: the posefuse-server and posefuse executables. WORK_DIR (in the build tree)
# receives the npm packages, pinned by package-lock.json and installed with `npm ci`, and the
# server's data. `token` runs the server with --tokens-file and checks that calls need the token.
#
# Exit: 0 all checks passed; 77 (CTest SKIP) only when node or npm is not installed and
# POSEFUSE_REQUIRE_INTEROP is not 1; anything else is a failure with a message saying why
# (npm packages that cannot be installed, offline included, are a failure, never a pass).
set -euo pipefail
server=$1 client=$2 work=$3 source=$4 mode=$5
here=$(cd "$(dirname "$0")" && pwd)

fail() { echo "interop: FAILED: $*" >&2; exit 1; }

# shellcheck source=../npm_packages.sh
. "$here/../npm_packages.sh"
require_node interop
install_npm_packages interop "$here" "$work" @grpc/grpc-js "@grpc/grpc-js and @grpc/proto-loader"

run=$work/run-$mode
rm -rf "$run"
mkdir -p "$run/recordings" "$run/data"
"$client" demo-session "$run/recordings/demo.pfchunks" >/dev/null

server_args=(--listen 127.0.0.1:0 --workers 2 --max-jobs 1
             --data-dir "$run/data" --recordings-root "$run/recordings")
token_args=()
token=""
if [ "$mode" = token ]; then
  token=$(od -An -N32 -tx1 /dev/urandom | tr -d ' \n')
  printf '# interop test\n%s\n' "$token" >"$run/tokens"
  server_args+=(--tokens-file "$run/tokens")
  token_args=(--token "$token")
fi

# The log exists before the server starts: the redirection happens in the background job, which
# the polling below can otherwise outrun (sed then fails on a missing file).
: >"$run/server.log"
"$server" "${server_args[@]}" 2>"$run/server.log" &
server_pid=$!
stop_server() {
  if kill -0 "$server_pid" 2>/dev/null; then kill -TERM "$server_pid"; fi
  wait "$server_pid"
}
trap 'kill -TERM "$server_pid" 2>/dev/null || true' EXIT

# The bound port is in the structured start line: "... event=server_start ... port=N workers=...".
# The space after N is required: the log may be read while the line is still being written, and
# a cut line would give a prefix of the port.
port=""
for _ in $(seq 1 600); do
  port=$(sed -n 's/.* event=server_start .*port=\([0-9][0-9]*\) .*/\1/p' "$run/server.log")
  [ -n "$port" ] && break
  kill -0 "$server_pid" 2>/dev/null || { cat "$run/server.log" >&2; fail "the server did not start"; }
  sleep 0.1
done
[ -n "$port" ] || { cat "$run/server.log" >&2; fail "no server_start line within 60 s"; }

client_status=0
node "$here/interop_client.js" \
  --address "127.0.0.1:$port" \
  --recording "$run/recordings/demo.pfchunks" --recording-uri demo.pfchunks \
  --proto-dir "$source/proto" --proto-dir "$source/client/proto" --proto-dir "$source/server/proto" \
  "${token_args[@]}" || client_status=$?

server_status=0
stop_server || server_status=$?
trap - EXIT
if [ "$client_status" -ne 0 ]; then
  echo "--- server log" >&2; cat "$run/server.log" >&2
  fail "the Node client's checks failed (exit $client_status)"
fi
[ "$server_status" -eq 0 ] || { cat "$run/server.log" >&2; fail "server exit status $server_status after SIGTERM"; }

# Structured logs: every line of ours is `time=... level=... event=...` (gRPC's own library
# lines, `E1122 08:31:03.0 ...`, are not ours and are left out); nothing from the session's
# header (its subject id) and never the token.
if grep -v -E '^time=[0-9TZ:.-]+ level=(info|warning|error) event=[a-z_]+( |$)' "$run/server.log" |
   grep -v -E '^[EWID][0-9]{4} [0-9:.]+ '; then
  fail "the server log lines above are not structured"
fi
if grep -F -e demo-subject ${token:+-e "$token"} "$run/server.log"; then
  fail "the server log holds the subject id or the token"
fi
grep -q 'event=server_stopped' "$run/server.log" || fail "no server_stopped line after SIGTERM"
echo "interop: $mode: passed"
