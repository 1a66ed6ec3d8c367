# bench_lib.sh - what the shell benchmarks share: the repository root as the
# working directory, a temporary directory removed on exit with the daemon
# they started, and oceand started on a free loopback port.
#   BUILD=... . tests/bench/helpers/bench_lib.sh NAME
# sets OUT (tests/bench/out), tmp, die MESSAGE, bench_daemon [OCEAND ARGS...]
# (oceand on config/oceand.conf; sets dpid and base, http://HOST:PORT/) and
# bench_daemon_stop.
bench_name=$1
cd "$(dirname "${BASH_SOURCE[0]}")/../../.." || exit 1
OUT=tests/bench/out
mkdir -p "$OUT"
tmp=$(mktemp -d "/tmp/oc-$bench_name.XXXXXX")
dpid=
cleanup() { [[ -n $dpid ]] && kill "$dpid" 2>/dev/null; wait 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
die() { echo "$bench_name: $*" >&2; exit 1; }

bench_daemon() {
    "$BUILD/oceand" --config config/oceand.conf --bind 127.0.0.1 --port 0 "$@" >"$tmp/oceand.log" 2>&1 &
    dpid=$!
    base=
    for _ in $(seq 400); do
        base=$(sed -n 's|^oceand: listening on \(http://[0-9.:]*/\).*|\1|p' "$tmp/oceand.log" | head -1)
        [[ -n $base ]] && break
        kill -0 "$dpid" 2>/dev/null || break
        sleep 0.05
    done
    [[ -n $base ]] || die "oceand did not start: $(tail -3 "$tmp/oceand.log")"
}

bench_daemon_stop() {
    [[ -n $dpid ]] && kill "$dpid" 2>/dev/null
    wait "$dpid" 2>/dev/null
    dpid=
}
