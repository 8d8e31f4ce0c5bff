#!/usr/bin/env bash
# Start a local shapeflow cluster: a PostgreSQL server in a temporary directory
# (Debian's postgresql package; run as the `postgres` user when started as root)
# and N `shapeflow serve` nodes on 127.0.0.1:8081.. sharing it. Ctrl-C stops them
# all and removes the directory. See docs/cluster.md.
#
#   scripts/cluster.sh [NODES=3] [WORKERS_PER_NODE=2]
#
# Environment: SHAPEFLOW (the binary; default target/release/shapeflow, built if
# missing), PGPORT (default 54329), BASE_PORT (default 8081), LEASE_SECONDS
# (default 15).
set -euo pipefail
cd "$(dirname "$0")/.."
NODES=${1:-3}
WORKERS=${2:-2}
PGPORT=${PGPORT:-54329}
BASE_PORT=${BASE_PORT:-8081}
LEASE_SECONDS=${LEASE_SECONDS:-15}
SHAPEFLOW=${SHAPEFLOW:-target/release/shapeflow}
[ -x "$SHAPEFLOW" ] || cargo build --release --bin shapeflow

PGBIN=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -1)
[ -n "$PGBIN" ] || { echo "PostgreSQL is not installed: apt-get install postgresql" >&2; exit 1; }
DIR=$(mktemp -d /tmp/shapeflow-cluster.XXXXXX)
chmod 777 "$DIR"
as_pg() { if [ "$(id -u)" = 0 ]; then runuser -u postgres -- "$@"; else "$@"; fi; }

pids=()
cleanup() {
    for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
    wait "${pids[@]}" 2>/dev/null || true
    as_pg "$PGBIN/pg_ctl" -D "$DIR/data" -m fast stop >/dev/null 2>&1 || true
    rm -rf "$DIR"
}
trap cleanup EXIT INT TERM

as_pg "$PGBIN/initdb" -D "$DIR/data" -U postgres -A trust --no-sync >/dev/null
as_pg "$PGBIN/pg_ctl" -D "$DIR/data" -l "$DIR/postgres.log" -w \
    -o "-k $DIR -p $PGPORT -c listen_addresses=127.0.0.1" start >/dev/null
DATABASE="postgres://postgres@127.0.0.1:$PGPORT/postgres"
echo "PostgreSQL: $DATABASE (log $DIR/postgres.log)"

for k in $(seq 0 $((NODES - 1))); do
    port=$((BASE_PORT + k))
    "$SHAPEFLOW" serve --bind "127.0.0.1:$port" --database "$DATABASE" --workers "$WORKERS" \
        --lease-seconds "$LEASE_SECONDS" 2>"$DIR/node$k.log" &
    pids+=($!)
    echo "node $k: http://127.0.0.1:$port/ (log $DIR/node$k.log)"
done
echo "Ctrl-C stops the cluster."
wait
