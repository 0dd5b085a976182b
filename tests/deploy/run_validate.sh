#!/usr/bin/env bash
# The Kubernetes manifest test (CTest): every document of every manifest under deploy/kubernetes
# against the API schemas of Kubernetes v1.33.0 (validate_manifests.js, with the npm package
# kubernetes-models), then a broken Deployment written here must be refused.
#
#   run_validate.sh WORK_DIR SOURCE_DIR
#
# WORK_DIR (in the build tree) receives the npm packages, pinned by package-lock.json and
# installed with `npm ci`, like the interop test's (tests/interop/run_interop.sh).
#
# Exit: 0 all checks passed; 77 (CTest SKIP) only when node or npm is not installed and
# POSEFUSE_REQUIRE_INTEROP is not 1 (.ci/run sets it: node and npm must be there); anything else
# is a failure with a message saying why (npm packages that cannot be installed, offline
# included, are a failure, never a pass).
set -euo pipefail
work=$1 source=$2
here=$(cd "$(dirname "$0")" && pwd)

fail() { echo "k8s-validate: FAILED: $*" >&2; exit 1; }

if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  message="node and npm are not installed (scripts/setup.sh installs them from scripts/packages.txt)"
  [ "${POSEFUSE_REQUIRE_INTEROP:-0}" = 1 ] && fail "$message; POSEFUSE_REQUIRE_INTEROP=1 needs them"
  echo "k8s-validate: SKIPPED: $message"
  exit 77
fi

# npm packages: once per build tree and lockfile.
npm_dir=$work/npm
mkdir -p "$npm_dir"
exec 9>"$work/npm.lock"
flock 9
if ! cmp -s "$here/package-lock.json" "$npm_dir/installed-lock.json" ||
   [ ! -d "$npm_dir/node_modules/kubernetes-models" ]; then
  cp "$here/package.json" "$here/package-lock.json" "$npm_dir/"
  rm -f "$npm_dir/installed-lock.json"
  echo "k8s-validate: npm ci in $npm_dir"
  if ! (cd "$npm_dir" && timeout 300 npm ci --ignore-scripts --no-audit --no-fund \
          --fetch-retries=2 --fetch-timeout=60000 --loglevel=error); then
    fail "npm ci could not install kubernetes-models and yaml (pinned by" \
         "tests/deploy/package-lock.json) into $npm_dir: is the npm registry reachable" \
         "(offline?) and is npm's cache writable? The manifest test cannot run without them."
  fi
  cp "$here/package-lock.json" "$npm_dir/installed-lock.json"
fi
flock -u 9
export NODE_PATH=$npm_dir/node_modules

# The manifests themselves, with the validator's self-test (broken documents made from them).
(cd "$source" && node "$here/validate_manifests.js" deploy/kubernetes) ||
  fail "deploy/kubernetes does not validate (errors above)"

# And end to end: a broken manifest file (made here, in the build tree) must fail the run with
# exit status 1 and name the error.
broken=$work/broken
rm -rf "$broken"
mkdir -p "$broken"
cat >"$broken/broken.yaml" <<'EOF'
apiVersion: v1
kind: Service
metadata: {name: fine}
spec:
  ports: [{port: 50051}]
---
apiVersion: apps/v1
kind: Deployment
metadata: {name: broken}
spec:
  selector: {matchLabels: {app: broken}}
  template:
    metadata: {labels: {app: broken}}
    spec:
      containers: "x"
      terminationGracePeriod: 30
EOF
status=0
node "$here/validate_manifests.js" --no-self-test "$broken" >"$broken/out.txt" 2>&1 || status=$?
cat "$broken/out.txt"
[ "$status" -eq 1 ] || fail "the broken manifest gave exit status $status, not 1"
grep -q 'broken.yaml#0 v1 Service/fine: valid' "$broken/out.txt" ||
  fail "the valid Service beside the broken Deployment was not accepted"
grep -q 'broken.yaml#1 (Deployment/broken): /spec/template/spec/containers must be array' "$broken/out.txt" ||
  fail "containers: \"x\" was not refused"
grep -q 'broken.yaml#1 (Deployment/broken): /spec/template/spec/terminationGracePeriod is not a field' "$broken/out.txt" ||
  fail "the unknown field terminationGracePeriod was not refused"
echo "k8s-validate: the broken manifest was refused: passed"
