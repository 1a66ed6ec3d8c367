#!/usr/bin/env bash
# test_load_framing.sh - the load generator's WebSocket framing (libwslay)
# against tests/lib/fake_ws_server.py, which plays what oceand never sends:
# fragmented FRAMEs with pings between fragments, a text message, a
# one-byte first fragment, a server close; then a protocol violation
# (RSV1 without an extension).  The client must count every FRAME once and
# decode it whole (--verify-every 1), pong every ping with its payload, echo
# the close, and fail the violating connection with 1002 and a decode error.
set -u
BUILD=${BUILD:-build}
OC=$BUILD/ocean-client
[[ -x $OC ]] || { echo "missing $OC"; exit 1; }
tmp=$(mktemp -d /tmp/oc-framing.XXXXXX)
srv=""
cleanup() { [[ -n $srv ]] && kill "$srv" 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; for f in "$tmp"/*.json "$tmp"/*.err; do [[ -f $f ]] && { echo "--- $f"; cat "$f"; }; done; exit 1; }
json() { python3 -c "import json,sys; d=json.load(open('$1')); sys.exit(0 if ($2) else 1)" || fail "$1: $2"; }

# scenario -> the fake server on a fresh port; load runs 1 viewer for 2 s
play() {
    local sc=$1
    python3 tests/lib/fake_ws_server.py "$sc" tests/vectors "$tmp/$sc.server.json" >"$tmp/$sc.port" 2>"$tmp/$sc.server.err" &
    srv=$!
    for _ in $(seq 50); do [[ -s $tmp/$sc.port ]] && break; sleep 0.1; done
    local port
    port=$(head -1 "$tmp/$sc.port")
    [[ -n $port ]] || fail "$sc: fake server did not start"
    "$OC" load "ws://127.0.0.1:$port/" --clients 1 --seconds 2 --rate 30 --ramp 0 --warmup 0.1 \
        --verify-every 1 --mesh none --json >"$tmp/$sc.load.json" 2>"$tmp/$sc.load.err"
    echo "load exited $? for $sc"
    wait "$srv"
    local rc=$?
    srv=""
    [[ $rc -eq 0 ]] || fail "$sc: the fake server saw the client misbehave (exit $rc)"
}

echo "== fragmented FRAMEs, pings between fragments, text message, server close"
play fragments
json "$tmp/fragments.server.json" "d['ok'] and d['pongs'] == 20 and d['close_code'] == 1001"
json "$tmp/fragments.load.json" "d['frames'] == 20 and d['frames_verified'] == 20 and d['decode_errors'] == 0 and d['disconnects'] == 1"

echo "== protocol violation (RSV1 set): connection failed with 1002"
play violation
json "$tmp/violation.server.json" "d['ok'] and d['close_code'] == 1002"
json "$tmp/violation.load.json" "d['frames'] == 1 and d['decode_errors'] >= 1"
echo "all framing checks passed"
