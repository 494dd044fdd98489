#!/bin/bash
# deploy/docker/Dockerfile's runtime stage without Docker: a Debian 12 root file system made by
# debootstrap from Debian's archive, the stage's RUN line run in it with chroot, the built
# photond and photonctl copied in as its COPY does, then its ENTRYPOINT started as its USER with
# a token at /run/secrets/photond-token: /healthz by the HEALTHCHECK's own command, /readyz, a job
# with the token, a refusal without it, and SIGTERM ending it with 0. What this does not cover:
# the build stage (the binaries come from this machine's build, made from the same Debian
# packages), Docker's own isolation and the image's layers. As root (`make test-container`).
# Usage: container_rootfs_test.sh BUILD_DIR [ROOTFS_CACHE]
set -euo pipefail
[ "$(id -u)" = 0 ] || exec sudo -E bash "$0" "$@"
build=$(realpath "${1:?usage: $0 BUILD_DIR [ROOTFS_CACHE]}")
repo=$(cd "$(dirname "$0")/../.." && pwd)
dockerfile="$repo/deploy/docker/Dockerfile"
cache=${2:-/var/tmp/photond-bookworm-minbase.tar}
root=$(mktemp -d /tmp/photond_container.XXXXXX)
chmod 0755 "$root"  # a root file system every user can enter
daemon_pid=""
cleanup() {
    [ -n "$daemon_pid" ] && kill -KILL "$daemon_pid" 2>/dev/null || true
    for mount in proc dev; do umount -R -l "$root/$mount" 2>/dev/null || true; done
    rm -rf --one-file-system "$root"
}
trap cleanup EXIT

# The base image: debian:bookworm-slim is a minbase bootstrap of bookworm (kept as a tarball
# between runs).
if [ ! -s "$cache" ]; then
    debootstrap --variant=minbase bookworm "$root" http://deb.debian.org/debian >/dev/null
    tar -C "$root" -cf "$cache" .
else
    tar -C "$root" -xf "$cache"
fi
if ! mount --rbind /dev "$root/dev" 2>/dev/null || ! mount -t proc proc "$root/proc" 2>/dev/null; then
    echo "SKIP: /dev and /proc cannot be mounted in the root file system here (no CAP_SYS_ADMIN)"
    exit 0
fi
cp /etc/resolv.conf "$root/etc/resolv.conf"

# The runtime stage: its RUN line (after the last FROM), its COPY lines, its USER and ENTRYPOINT.
python3 - "$dockerfile" "$root/run-stage.sh" "$root/entrypoint" <<'PY'
import json, re, sys
text = open(sys.argv[1]).read().replace("\\\n", " ")
stage = text.split("\nFROM ")[-1]
run = [line[4:] for line in stage.splitlines() if line.startswith("RUN ")]
assert len(run) == 1, "the runtime stage has one RUN line"
open(sys.argv[2], "w").write("set -e\nexport DEBIAN_FRONTEND=noninteractive\n" + run[0] + "\n")
entry = [line for line in stage.splitlines() if line.startswith("ENTRYPOINT ")][0]
user = [line for line in stage.splitlines() if line.startswith("USER ")][0].split()[1]
open(sys.argv[3], "w").write(user + "\n" + "\n".join(json.loads(entry[len("ENTRYPOINT "):])) + "\n")
PY
chroot "$root" /bin/bash /run-stage.sh >/dev/null
install -m 0755 "$build/server/photond" "$build/clients/photonctl" "$root/usr/local/bin/"
install -m 0755 "$repo/deploy/docker/healthcheck.sh" "$root/usr/local/bin/photond-healthcheck"
user=$(head -n 1 "$root/entrypoint")
mapfile -t entrypoint < <(tail -n +2 "$root/entrypoint")
# Every library photond loads is in the image.
if chroot "$root" ldd /usr/local/bin/photond | grep -q "not found"; then
    chroot "$root" ldd /usr/local/bin/photond | grep "not found" >&2
    echo "the runtime stage lacks libraries photond needs" >&2
    exit 1
fi

# Without the token the daemon refuses to start (it listens beyond loopback).
if chroot --userspec="$user" "$root" "${entrypoint[@]}" >/dev/null 2>"$root/refusal.txt"; then
    echo "the ENTRYPOINT started without /run/secrets/photond-token" >&2
    exit 1
fi
grep -q "photond-token" "$root/refusal.txt" || { cat "$root/refusal.txt" >&2; exit 1; }

mkdir -p "$root/run/secrets"
token=$(od -An -N16 -tx1 /dev/urandom | tr -d ' \n')
echo "$token" >"$root/run/secrets/photond-token"
chmod 0444 "$root/run/secrets/photond-token"
chroot --userspec="$user" "$root" "${entrypoint[@]}" >"$root/daemon.out" 2>"$root/daemon.err" &
daemon_pid=$!
port=""
for _ in $(seq 100); do
    port=$(sed -n 's|^listening on http://[0-9.]*:\([0-9]*\)$|\1|p' "$root/daemon.out")
    [ -n "$port" ] && break
    sleep 0.1
done
[ -n "$port" ] || { cat "$root/daemon.err" >&2; echo "the ENTRYPOINT did not start listening" >&2; exit 1; }
# The HEALTHCHECK as the image runs it.
health=$(python3 -c 'import json, re, sys
text = open(sys.argv[1]).read().replace("\\\n", " ")
line = [l for l in text.split("\nFROM ")[-1].splitlines() if l.startswith("HEALTHCHECK ")][0]
print("\n".join(json.loads(line[line.index("CMD ") + 4:])))' "$dockerfile")
mapfile -t health_command <<<"$health"
chroot --userspec="$user" "$root" "${health_command[@]}" || { echo "the HEALTHCHECK failed" >&2; exit 1; }
curl -fsS "http://127.0.0.1:$port/readyz" >/dev/null
[ "$(curl -s -o /dev/null -w '%{http_code}' "http://127.0.0.1:$port/v1/jobs")" = 401 ]
id=$(curl -fsS -H "Authorization: Bearer $token" -X POST "http://127.0.0.1:$port/v1/jobs" \
    -d '{"scene": {"builtin": "cornell-box"}, "integrator": "direct", "image": {"width": 32, "height": 24, "spp": 1}}' |
    python3 -c 'import json, sys; print(json.load(sys.stdin)["id"])')
curl -fsS -H "Authorization: Bearer $token" "http://127.0.0.1:$port/v1/jobs/$id/image.exr?wait=true" -o "$root/image.exr"
[ "$(head -c 4 "$root/image.exr" | od -An -tx1 | tr -d ' ')" = 762f3101 ] || { echo "no EXR came back" >&2; exit 1; }
kill -TERM "$daemon_pid"
status=0
wait "$daemon_pid" || status=$?
daemon_pid=""
[ "$status" = 0 ] || { echo "SIGTERM ended the daemon with $status" >&2; exit 1; }
echo "container runtime stage: packages cover photond's libraries; ENTRYPOINT as user $user refuses without the token, serves with it (/healthz by the HEALTHCHECK, /readyz, a job's EXR), SIGTERM -> 0"
