#!/usr/bin/env bash
# Builds docker/Dockerfile with podman, starts the image and checks that the server in it answers,
# without any image registry: the Debian 12 base images come from Debian packages (mmdebstrap).
# Run by hand (tens of minutes: the build stage compiles the server); not part of CTest or CI.
#   scripts/container_image.sh
#   POSEFUSE_IMAGE_CACHE=DIR   where the base image tarballs are kept (default ~/.cache/posefuse-image)
#   POSEFUSE_IMAGE_TAG=NAME    tag of the built image (default localhost/posefuse:local)
# Needs root (apt-get, mmdebstrap, podman all run as root here). Every failure ends with one
# "container_image: ..." line on stderr naming the step, and a non-zero exit status.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cache=${POSEFUSE_IMAGE_CACHE:-$HOME/.cache/posefuse-image}
tag=${POSEFUSE_IMAGE_TAG:-localhost/posefuse:local}
suite=bookworm
mirror=http://deb.debian.org/debian
security=http://deb.debian.org/debian-security

fail() { echo "container_image: $*" >&2; exit 1; }
[ "$(id -u)" -eq 0 ] || fail "run as root (apt-get, mmdebstrap and rootful podman)"

# 1. Tools, from Debian. runc as well as podman's default crun: crun 1.8 (Debian 12) refuses a host
# whose cgroup v2 hierarchy still holds a controller beside cgroup v1 ("cgroups in hybrid mode not
# supported"); runc runs there, and on plain cgroup v1 or v2 hosts too, so it is always used.
if ! command -v podman >/dev/null || ! command -v mmdebstrap >/dev/null || ! command -v runc >/dev/null; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q || fail "apt-get update failed"
  apt-get install -y -q podman mmdebstrap runc || fail "apt-get install podman mmdebstrap runc failed"
fi
echo "container_image: $(podman --version), mmdebstrap $(mmdebstrap --version | awk '{print $2}'), runc $(runc --version | awk 'NR==1{print $3}')"

# 2. Base images. The Dockerfile's FROM lines name debian:12 and debian:12-slim; podman resolves
# a short name to a local localhost/ image first, so `--pull=never` finds these and asks no registry.
# Both are the minbase variant (apt, dpkg, bash) with the same sources as Debian's own images;
# the slim one leaves out documentation, manual pages and translations like debian:12-slim does.
# The tarballs are cached; delete them to pick up newer Debian point releases.
sources=("deb $mirror $suite main" "deb $mirror $suite-updates main" "deb $security $suite-security main")
slim_opts=(--dpkgopt='path-exclude=/usr/share/doc/*' --dpkgopt='path-include=/usr/share/doc/*/copyright'
  --dpkgopt='path-exclude=/usr/share/man/*' --dpkgopt='path-exclude=/usr/share/info/*'
  --dpkgopt='path-exclude=/usr/share/locale/*' --dpkgopt='path-exclude=/usr/share/lintian/*')
mkdir -p "$cache"
make_base() {  # NAME TARBALL [mmdebstrap options...]
  local name=$1 tarball=$2
  shift 2
  if [ ! -s "$tarball" ]; then
    echo "container_image: mmdebstrap $suite -> $tarball"
    mmdebstrap --variant=minbase --format=tar "$@" "$suite" "$tarball.part" "${sources[@]}" ||
      fail "mmdebstrap could not make $tarball"
    mv "$tarball.part" "$tarball"
  fi
  podman image exists "$name" || podman import --change 'CMD ["bash"]' "$tarball" "$name" >/dev/null ||
    fail "podman import $tarball as $name failed"
}
make_base localhost/debian:12 "$cache/debian12.tar"
make_base localhost/debian:12-slim "$cache/debian12-slim.tar" "${slim_opts[@]}"

# Limits for every `podman run`: podman 4.3 as root gives a container RLIMIT_NOFILE 1048576 and
# RLIMIT_NPROC kernel.pid_max unless told; where the hard limits are lower and root lacks
# CAP_SYS_RESOURCE (this machine is itself a container) the runtime cannot set them ("error
# setting rlimit type 7: operation not permitted"), so they are set to what this shell has.
# (podman build's RUN steps get buildah's lower defaults and need nothing.)
nofile=$(ulimit -Hn); [ "$nofile" = unlimited ] && nofile=1048576
nproc=$(cat /proc/sys/kernel/pid_max); hard_nproc=$(ulimit -Hu)
[ "$hard_nproc" != unlimited ] && [ "$hard_nproc" -lt "$nproc" ] && nproc=$hard_nproc
run_opts=(--runtime runc --ulimit "nofile=$nofile:$nofile" --ulimit "nproc=$nproc:$nproc")

# 3. Can this machine run a container at all? Cheaper to learn before the long build.
podman run --rm "${run_opts[@]}" --network=none localhost/debian:12 true ||
  fail "podman cannot run a container here (podman run localhost/debian:12 true failed; see above)"

# 4. The image, from the working tree as it is (docker/Dockerfile.dockerignore leaves out build*/
# and .git/). --network=host: the build stage runs apt-get against the Debian mirror.
start=$(date +%s)
podman build --pull=never --runtime runc --network=host -f "$root/docker/Dockerfile" -t "$tag" "$root" ||
  fail "podman build -f docker/Dockerfile failed (see the step above)"
echo "container_image: built $tag in $(( $(date +%s) - start )) s," \
  "$(podman image inspect --format '{{.Size}}' "$tag") bytes"

# 5. Start it as documented (its own CMD: --listen 0.0.0.0:50051 with TLS and tokens from
# /etc/posefuse/tls and /etc/posefuse/tokens) with the port published on a loopback port that
# podman picks free. A throwaway CA, a server certificate for 127.0.0.1 and a token, made here.
secrets=$(mktemp -d)
stop() { rm -rf "$secrets"; }
trap stop EXIT
mkdir -p "$secrets/tls" "$secrets/tokens"
ec=(-newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes)
{ openssl req -x509 "${ec[@]}" -days 2 -subj /CN=container-image-ca -keyout "$secrets/ca.key" -out "$secrets/ca.crt" &&
  openssl req -new "${ec[@]}" -subj /CN=posefuse -keyout "$secrets/tls/tls.key" -out "$secrets/server.csr" &&
  printf 'subjectAltName=IP:127.0.0.1\nextendedKeyUsage=serverAuth\n' >"$secrets/server.ext" &&
  openssl x509 -req -days 2 -in "$secrets/server.csr" -CA "$secrets/ca.crt" -CAkey "$secrets/ca.key" \
    -CAcreateserial -extfile "$secrets/server.ext" -out "$secrets/tls/tls.crt" &&
  openssl rand -hex 32 >"$secrets/tokens/tokens"; } >"$secrets/openssl.log" 2>&1 ||
  fail "openssl could not make the test certificate and token ($(tail -1 "$secrets/openssl.log"))"
chmod -R a+rX "$secrets"  # the server runs as uid 10001
container=$(podman run -d "${run_opts[@]}" -p 127.0.0.1::50051 \
  -v "$secrets/tls:/etc/posefuse/tls:ro" -v "$secrets/tokens:/etc/posefuse/tokens:ro" "$tag") ||
  fail "podman run -d $tag failed"
stop() { podman rm -f "$container" >/dev/null 2>&1 || true; rm -rf "$secrets"; }
address=$(podman port "$container" 50051/tcp) || fail "podman port: no published port for 50051"
echo "container_image: server container ${container:0:12} on $address"

# 6. Health (and a short fit) with the image's own client, from a second container on the host's
# network so it reaches the published port. The server takes a moment to listen: retry for 30 s.
client=(podman run --rm "${run_opts[@]}" --network=host -v "$secrets:/secrets:ro" --entrypoint /bin/sh "$tag" -c)
secured="--tls-ca /secrets/ca.crt --token-file /secrets/tokens/tokens"
healthy=no
for _ in $(seq 1 30); do
  if "${client[@]}" "/usr/local/bin/posefuse health --server $address $secured"; then healthy=yes; break; fi
  [ "$(podman inspect --format '{{.State.Running}}' "$container")" = true ] || break
  sleep 1
done
if [ "$healthy" != yes ]; then
  podman logs "$container" >&2 || true
  fail "the server in $tag did not answer posefuse health on $address (its log is above)"
fi
"${client[@]}" "/usr/local/bin/posefuse demo-session /tmp/demo.pfchunks &&
  /usr/local/bin/posefuse fit /tmp/demo.pfchunks --server $address $secured --out /tmp/results && ls /tmp/results" ||
  fail "posefuse fit of the demo session through $address failed"
echo "container_image: ok: $tag built, started, healthy and fitted the demo session"
