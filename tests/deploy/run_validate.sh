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

# shellcheck source=../npm_packages.sh
. "$here/../npm_packages.sh"
require_node k8s-validate
install_npm_packages k8s-validate "$here" "$work" kubernetes-models "kubernetes-models and yaml"

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
