#!/usr/bin/env bash
# The report's browser test (CTest): writes a small result directory, runs `posefuse report` on
# it, and has headless Chromium (Debian's chromium, driven by puppeteer-core from npm, pinned by
# package-lock.json) load the file and check its DOM (check_report.js).
#
#   run_browser_test.sh CLIENT FIXTURE_WRITER WORK_DIR
#
# Exit: 0 all checks passed; 77 (CTest SKIP) only when node, npm or chromium is missing and
# POSEFUSE_REQUIRE_INTEROP is not 1 (.ci/run sets it); anything else is a failure naming why.
set -euo pipefail
client=$1 fixture_writer=$2 work=$3
here=$(cd "$(dirname "$0")" && pwd)
chromium=${CHROMIUM:-/usr/bin/chromium}

# shellcheck source=../npm_packages.sh
. "$here/../npm_packages.sh"
require_node report
if [ ! -x "$chromium" ]; then
  message="$chromium is not installed (scripts/setup.sh installs Debian's chromium from scripts/packages.txt)"
  if [ "${POSEFUSE_REQUIRE_INTEROP:-0}" = 1 ]; then
    echo "report: FAILED: $message; POSEFUSE_REQUIRE_INTEROP=1 needs it" >&2
    exit 1
  fi
  echo "report: SKIPPED: $message"
  exit 77
fi
install_npm_packages report "$here" "$work" puppeteer-core puppeteer-core

run=$work/run
rm -rf "$run"
mkdir -p "$run"
"$fixture_writer" "$run/results"
"$client" report "$run/results" --out "$run/report.html"
CHROMIUM=$chromium node "$here/check_report.js" "$run/report.html" "$run/report.png" 2
