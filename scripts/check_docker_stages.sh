#!/usr/bin/env bash
# Dev-only: the Dockerfile's two stages without a Docker engine (none runs on the
# build machines of this project). Run as root on a Debian bookworm host (the
# build stage's base, rust:1-bookworm, is bookworm with a Rust toolchain):
#   1. build stage: copy exactly the files the Dockerfile COPYs into an empty
#      directory and run its RUN line there (cargo build --locked, strip);
#   2. runtime stage: a debootstrap'ed bookworm minbase root (debian:bookworm-slim
#      is minbase) with the Dockerfile's useradd, the binary and the examples;
#      serve as the unprivileged user from / with --data-dir /data, submit two
#      examples with curl, validate their glb with the Khronos validator, stop with
#      SIGTERM (what `docker stop` sends to PID 1), restart on the same /data.
# Usage: scripts/check_docker_stages.sh [WORKDIR]   (default /tmp/shapeflow-docker)
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
work=${1:-/tmp/shapeflow-docker}
port=18080
mkdir -p "$work"

echo "== build stage"
rm -rf "$work/src" && mkdir -p "$work/src"
(cd "$repo" && cp -r Cargo.toml Cargo.lock build.rs rustfmt.toml src migrations api benches examples "$work/src/")
# the target directory sits beside the copy, so that a rerun builds incrementally
(cd "$work/src" && CARGO_TARGET_DIR="$work/target" cargo build --release --locked --bin shapeflow \
    && strip -o "$work/shapeflow" "$work/target/release/shapeflow")

echo "== runtime stage"
root="$work/root"
if [ ! -x "$root/usr/sbin/useradd" ]; then
    command -v debootstrap >/dev/null || apt-get install -y debootstrap
    debootstrap --variant=minbase bookworm "$root" http://deb.debian.org/debian
fi
chroot "$root" sh -c 'id shapeflow >/dev/null 2>&1 || useradd --system --home /data shapeflow; mkdir -p /data && chown shapeflow /data'
cp "$work/shapeflow" "$root/usr/local/bin/shapeflow"
rm -rf "$root/usr/share/shapeflow" && mkdir -p "$root/usr/share/shapeflow"
cp -r "$repo/examples" "$root/usr/share/shapeflow/examples"
ls -la "$root/usr/local/bin/shapeflow"
for m in proc dev sys; do mountpoint -q "$root/$m" || mount --bind "/$m" "$root/$m"; done
trap 'pkill -TERM -f "shapeflow serve --bind 0.0.0.0:$port" || true; sleep 1; for m in proc dev sys; do umount "$root/$m" || true; done' EXIT

serve() {
    chroot --userspec=shapeflow:shapeflow "$root" /bin/sh -c \
        "cd / && exec /usr/local/bin/shapeflow serve --bind 0.0.0.0:$port --data-dir /data" >"$work/serve.log" 2>&1 &
    for _ in $(seq 50); do curl -sf "localhost:$port/healthz" >/dev/null && return; sleep 0.2; done
    cat "$work/serve.log"; exit 1
}
serve
a=$(curl -si -X POST -H 'Content-Type: application/json' --data @"$repo/examples/circle.json" "localhost:$port/v1/jobs" | tr -d '\r' | awk 'tolower($1)=="location:"{print $2}')
b=$(curl -si -F spec=@"$repo/examples/segment_star.json" -F image=@"$repo/examples/data/star.png" "localhost:$port/v1/jobs" | tr -d '\r' | awk 'tolower($1)=="location:"{print $2}')
for job in "$a" "$b"; do
    for _ in $(seq 300); do
        curl -s "localhost:$port$job" | grep -q '"status":"successful"' && break
        sleep 0.2
    done
    curl -s "localhost:$port$job"; echo
    curl -sf -o "$work/$(basename "$job").glb" "localhost:$port$job/results/shape.glb"
    (cd "$repo" && node -e "
const v = require('gltf-validator'); const fs = require('fs');
v.validateBytes(new Uint8Array(fs.readFileSync('$work/$(basename "$job").glb'))).then(r => {
  console.log('glTF errors', r.issues.numErrors, 'warnings', r.issues.numWarnings);
  process.exit(r.issues.numErrors + r.issues.numWarnings ? 1 : 0);
});")
done
curl -sf -o "$work/mask.png" "localhost:$port$b/results/mask.png"
pkill -TERM -f "shapeflow serve --bind 0.0.0.0:$port"
sleep 2
! pgrep -f "shapeflow serve --bind 0.0.0.0:$port" >/dev/null || { echo "did not stop on SIGTERM"; exit 1; }
serve
curl -s "localhost:$port/v1/jobs" | grep -q "$(basename "$a")" || { echo "job lost across restart"; exit 1; }
echo "== both stages OK"
