# Sourced by the tests that run Node (tests/interop, tests/deploy): node and npm present, and the
# test's npm packages, pinned by its package-lock.json, installed once per build tree with
# `npm ci`. Every failure names why; npm packages that cannot be installed (offline included)
# are a failure, never a pass.

# require_node TAG: exit 77 (CTest SKIP) without node or npm, unless POSEFUSE_REQUIRE_INTEROP=1
# (.ci/run sets it), which makes it a failure.
require_node() {
  local tag=$1
  if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
    local message="node and npm are not installed (scripts/setup.sh installs them from scripts/packages.txt)"
    if [ "${POSEFUSE_REQUIRE_INTEROP:-0}" = 1 ]; then
      echo "$tag: FAILED: $message; POSEFUSE_REQUIRE_INTEROP=1 needs them" >&2
      exit 1
    fi
    echo "$tag: SKIPPED: $message"
    exit 77
  fi
}

# install_npm_packages TAG PACKAGE_DIR WORK_DIR MODULE WHAT: PACKAGE_DIR's package.json and
# package-lock.json installed into WORK_DIR/npm (skipped when that lockfile is installed and
# node_modules/MODULE exists); tests of one build tree take turns. Sets NODE_PATH.
install_npm_packages() {
  local tag=$1 package_dir=$2 work=$3 module=$4 what=$5
  local npm_dir=$work/npm
  mkdir -p "$npm_dir"
  exec 9>"$work/npm.lock"
  flock 9
  if ! cmp -s "$package_dir/package-lock.json" "$npm_dir/installed-lock.json" ||
     [ ! -d "$npm_dir/node_modules/$module" ]; then
    cp "$package_dir/package.json" "$package_dir/package-lock.json" "$npm_dir/"
    rm -f "$npm_dir/installed-lock.json"
    echo "$tag: npm ci in $npm_dir"
    if ! (cd "$npm_dir" && timeout 300 npm ci --ignore-scripts --no-audit --no-fund \
            --fetch-retries=2 --fetch-timeout=60000 --loglevel=error); then
      echo "$tag: FAILED: npm ci could not install $what (pinned by $package_dir/package-lock.json)" \
           "into $npm_dir: is the npm registry reachable (offline?) and is npm's cache writable?" \
           "The test cannot run without them." >&2
      exit 1
    fi
    cp "$package_dir/package-lock.json" "$npm_dir/installed-lock.json"
  fi
  flock -u 9
  export NODE_PATH=$npm_dir/node_modules
}
