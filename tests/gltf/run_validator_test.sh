#!/usr/bin/env bash
# The glTF export's validator test (CTest): writes a small result directory of known poses, runs
# `posefuse export --format gltf` on it, and has the Khronos glTF validator (npm gltf-validator,
# pinned by package-lock.json) check the file (validate_gltf.js): no errors allowed, warnings listed.
#
#   run_validator_test.sh CLIENT FIXTURE_WRITER WORK_DIR
#
# Exit: 0 the validator found no error; 77 (CTest SKIP) only when node or npm is missing and
# POSEFUSE_REQUIRE_INTEROP is not 1 (.ci/run sets it); anything else is a failure naming why.
set -euo pipefail
client=$1 fixture_writer=$2 work=$3
here=$(cd "$(dirname "$0")" && pwd)

# shellcheck source=../npm_packages.sh
. "$here/../npm_packages.sh"
require_node gltf
install_npm_packages gltf "$here" "$work" gltf-validator gltf-validator

run=$work/run
rm -rf "$run"
mkdir -p "$run"
"$fixture_writer" "$run/results"
"$client" export "$run/results" --format gltf --out "$run/body.glb"
node "$here/validate_gltf.js" "$run/body.glb"
