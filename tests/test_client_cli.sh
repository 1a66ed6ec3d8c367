#!/usr/bin/env bash
# test_client_cli.sh - ocean-client and the ship example against a real
# oceand on a free loopback port: watch --json, bad options refused by
# name, record, replay twice with --check (identical) and once changed
# (refused), export (files any EXR reader opens), load (following the
# viewer's time-interpolating stream, and the plain one), query, ship; help
# defaults equal the parser's, no option silently ignored, progress on a
# terminal (issue 17 items 5-7).
set -u
BUILD=${BUILD:-build}
OC=$BUILD/ocean-client
OD=$BUILD/oceand
SHIP=$BUILD/examples/ship
CIGI_HOST=$BUILD/examples/cigi_host
for b in "$OC" "$OD" "$SHIP" "$CIGI_HOST"; do
    [[ -x $b ]] || { echo "missing $b"; exit 1; }
done
tmp=$(mktemp -d /tmp/oc-cli.XXXXXX)
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
URL=ws://127.0.0.1:$port/
cport=$(python3 -c 'import socket; s=socket.socket(type=socket.SOCK_DGRAM); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
TOKEN=test-token-17
EPOCH=$(date +%s)
# admission (server.admit_share) prices layout 0 from this host's speed: off,
# so a busy host does not refuse the layout-0 commands judged here
"$OD" --config config/oceand.conf --port "$port" --set server.admin_token=$TOKEN --set server.epoch="$EPOCH" \
    --set server.admit_share=0 --set server.cigi_port="$cport" --set server.geo_origin=43.5,-8.25 \
    --set server.entity_token=cli-entity >"$tmp/oceand.log" 2>&1 &
pid=$!
pid2=
cleanup() { kill "$pid" $pid2 2>/dev/null; wait "$pid" $pid2 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; echo "--- oceand log:"; tail -20 "$tmp/oceand.log"; exit 1; }
json() { python3 -c "import json,sys; d=json.load(open('$1')); sys.exit(0 if ($2) else 1)" || fail "$1: $2: $(cat "$1")"; }
# sea_until FILE EXPR: the sea in force into FILE until EXPR holds of it (a
# change applies at a tick: a deadline, not a speed), then judged
sea_until() {
    for _ in $(seq 50); do
        "$OC" sea "$URL" >"$1" || fail "sea exited $?"
        python3 -c "import json,sys; d=json.load(open('$1')); sys.exit(0 if ($2) else 1)" && break
        sleep 0.1
    done
    json "$1" "$2"
}

for i in $(seq 50); do
    "$OC" watch "$URL" --frames 1 --seconds 2 --mesh none >/dev/null 2>&1 && break
    sleep 0.1
done

echo "== watch --json ($SECONDS s)"
"$OC" watch "$URL" --seconds 2 --json --mesh none >"$tmp/watch.json" || fail "watch exited $?"
json "$tmp/watch.json" "d['frames'] > 0 and d['bytes'] > 0 and d['latency_p50_ms'] is not None and d['latency_p99_ms'] >= d['latency_p50_ms'] and d['decode_errors'] == 0"

# a rate needs two frames: one frame 10 ms after the start is not 100 fps
"$OC" watch "$URL" --frames 1 --seconds 5 --json --mesh none >"$tmp/watch1.json" || fail "watch --frames 1 exited $?"
json "$tmp/watch1.json" "d['frames'] == 1 and d['fps'] is None"

# --layout is every subscribing command's (watch had only --mesh-codec,
# for layout 0, and no way to ask for it)
"$OC" watch "$URL" --frames 2 --seconds 5 --json --layout 0 --mesh-codec qz >"$tmp/watch0.json" || fail "watch --layout 0 exited $?"
json "$tmp/watch0.json" "d['frames'] == 2 and d['frames_layout0'] == 2 and d['frames_layout1'] == 0 and d['decode_errors'] == 0"

# a refused SUBSCRIBE is said, not only "no frame received" (60 Hz above
# the 30 Hz ticks)
"$OC" watch "$URL" --seconds 1 --rate 60 >/dev/null 2>"$tmp/err" && fail "watch --rate 60 above the ticks succeeded"
grep -q "no frame received; the server said: .*frame_rate_hz 60 above the server's tick rate" "$tmp/err" ||
    fail "watch --rate 60: the server's reason is not shown: $(cat "$tmp/err")"

echo "== bad options are refused by name ($SECONDS s)"
"$OC" watch "$URL" --bogus 2>"$tmp/err" && fail "--bogus accepted"
grep -q -- "--bogus" "$tmp/err" || fail "message does not name --bogus: $(cat "$tmp/err")"
"$OC" watch "$URL" --seconds abc 2>"$tmp/err"; [[ $? -eq 2 ]] || fail "--seconds abc: wrong exit"
grep -q -- "--seconds" "$tmp/err" || fail "message does not name --seconds"
"$OC" query "$URL" --points "1,2;x" 2>"$tmp/err" && fail "bad --points accepted"
grep -q -- "--points" "$tmp/err" || fail "message does not name --points"
# one time limit (sim/ocean_time.h): beyond 2^27 s refused, naming it
"$OC" query "$URL" --points "1,2" --t 134217729 2>"$tmp/err"; [[ $? -eq 2 ]] || fail "--t beyond the time limit accepted"
grep -q -- "OCEAN_TIME_MAX" "$tmp/err" || fail "message does not name OCEAN_TIME_MAX: $(cat "$tmp/err")"
"$OC" watch "$URL" --mesh-codec f16 2>"$tmp/err"; [[ $? -eq 2 ]] || fail "--mesh-codec f16 accepted"
grep -q -- "--mesh-codec" "$tmp/err" || fail "message does not name --mesh-codec: $(cat "$tmp/err")"
"$OC" frobnicate 2>/dev/null; [[ $? -eq 2 ]] || fail "unknown command accepted"
for c in watch query record replay export load sea entity; do
    "$OC" $c --help >/dev/null || fail "$c --help"
done
printf 't,x,y,z\n0,1,2,3\n' >"$tmp/bad.csv"
"$OC" replay "$URL" "$tmp/bad.csv" --out "$tmp/x.frames" 2>"$tmp/err" && fail "bad path accepted"
grep -q "bad.csv:1:" "$tmp/err" || fail "path error lacks file:line: $(cat "$tmp/err")"

echo "== --help defaults are what the parser yields ($SECONDS s)"
# (one awk a command: a sed and a grep a line took 11 s of the suite)
for c in watch query record replay export load sea; do
    "$OC" $c --help >"$tmp/help.txt" || fail "$c --help"
    "$OC" $c --show-options >"$tmp/show.txt" || fail "$c --show-options"
    why=$(awk 'FNR == NR { if (match($0, /^--[a-z0-9-]+=/)) show[substr($0, 3, RLENGTH - 3)] = substr($0, RLENGTH + 1); next }
        match($0, /^  --[a-z0-9-]+ /) {
            name = substr($0, 5, RLENGTH - 5)
            if (name == "help" || name == "show-options") next
            if (!(name in show)) { print "--" name " in --help but not in --show-options"; bad = 1; exit }
            if (match($0, / \(default .*\)$/)) {
                def = substr($0, RSTART + 10, RLENGTH - 11); n++
                if (def != show[name]) { print "--help says --" name " defaults to \x27" def "\x27, the parser gives \x27" show[name] "\x27"; bad = 1; exit }
            }
        }
        END { if (!bad && !n) print "--help shows no default" }' "$tmp/show.txt" "$tmp/help.txt")
    [[ -z $why ]] || fail "$c: $why"
done
# The subscription defaults are the library's (oc_subscribe_default), the
# two the old help text had wrong among them; samples in time are the
# viewer's stream (export alone reads the plain one).
"$OC" watch --help | grep -- "--cutoff-policy" | grep -q "(default antialias)" || fail "--cutoff-policy default"
"$OC" watch --help | grep -- "--tile-size" | grep -q "(default 64)" || fail "--tile-size default"
for c in watch record replay load; do
    "$OC" $c --show-options | grep -qx -- "--time-interp=on" || fail "$c --time-interp default"
    "$OC" $c --help | grep -A2 -- "--time-interp" | grep -q "(default on)" || fail "$c --help: --time-interp default"
done
"$OC" export --show-options | grep -qx -- "--time-interp=off" || fail "export --time-interp default"
# layout 0's mesh positions travel compressed unless asked otherwise (issue 14)
"$OC" load --help | grep -- "--mesh-codec" | grep -q "(default qz)" || fail "--mesh-codec default"

echo "== nothing is silently ignored ($SECONDS s)"
"$OC" sea "$URL" --wind 20 >"$tmp/out" 2>"$tmp/err"; rc=$?
[[ $rc -eq 2 ]] || fail "sea --wind without --set: exit $rc"
grep -q -- "--wind" "$tmp/err" && grep -q -- "--set" "$tmp/err" || fail "sea --wind without --set: $(cat "$tmp/err")"
"$OC" sea "$URL" --spectrum 2 2>"$tmp/err"; [[ $? -eq 2 ]] || fail "sea --spectrum 2 (a number) accepted"
grep -q "jonswap" "$tmp/err" || fail "sea --spectrum: the names are not listed: $(cat "$tmp/err")"
"$SHIP" "$URL" --wind 30 --seconds 1 >"$tmp/out" 2>"$tmp/err"; rc=$?
[[ $rc -eq 2 ]] || fail "ship URL --wind: exit $rc"
grep -q -- "--offline" "$tmp/err" || fail "ship URL --wind does not explain: $(cat "$tmp/err")"
t0=$SECONDS
"$OC" replay "$URL" clients/paths/jet.csv --out "$tmp/never.frames" --check "$tmp/missing.frames" 2>"$tmp/err"; rc=$?
[[ $rc -eq 2 ]] || fail "replay --check missing: exit $rc"
grep -q -- "--check" "$tmp/err" && grep -q "missing.frames" "$tmp/err" || fail "replay --check missing: $(cat "$tmp/err")"
grep -q "answered" "$tmp/err" && fail "replay ran before checking --check: $(cat "$tmp/err")"
[[ ! -e $tmp/never.frames ]] || fail "replay wrote --out before checking --check"
# export writes each frame's tiles as the sea at its time: samples in time
# (whose tiles are of other ticks) are refused by name, not exported
"$OC" export "$URL" --out "$tmp/never-exr" --time-interp on 2>"$tmp/err"; rc=$?
[[ $rc -eq 2 ]] || fail "export --time-interp on: exit $rc"
grep -q -- "--time-interp" "$tmp/err" || fail "export --time-interp on: $(cat "$tmp/err")"
[[ ! -e $tmp/never-exr ]] || fail "export --time-interp on created its directory"

echo "== replay twice, --check ($SECONDS s)"
head -n 33 clients/paths/jet.csv >"$tmp/jet.csv"   # 30 reports, 1 s of the pass
"$OC" replay "$URL" "$tmp/jet.csv" --out "$tmp/r1.frames" --mesh none 2>"$tmp/r1.log" || fail "replay 1: $(cat "$tmp/r1.log")"
"$OC" replay "$URL" "$tmp/jet.csv" --out "$tmp/r2.frames" --check "$tmp/r1.frames" --mesh none 2>"$tmp/r2.log" ||
    fail "replay 2 differs: $(cat "$tmp/r2.log")"
grep -q "identical" "$tmp/r2.log" || fail "no verdict: $(cat "$tmp/r2.log")"
"$OC" replay "$URL" "$tmp/jet.csv" --out "$tmp/r3.frames" --check "$tmp/r1.frames" --mesh none --accuracy 0.01 2>"$tmp/r3.log" &&
    fail "a different subscription passed --check"
grep -q "DIFFERENT" "$tmp/r3.log" || fail "no difference reported: $(cat "$tmp/r3.log")"

echo "== record ($SECONDS s)"
head -n 23 clients/paths/ship.csv >"$tmp/ship.csv"   # 2 s of the ship path
"$OC" record "$URL" --path "$tmp/ship.csv" --out "$tmp/rec.frames" --tail 0.3 --mesh none 2>"$tmp/rec.log" ||
    fail "record: $(cat "$tmp/rec.log")"
grep -qE " [1-9][0-9]* frames" "$tmp/rec.log" || fail "record got no frames: $(cat "$tmp/rec.log")"
head -n 8 clients/paths/helicopter.csv | "$OC" record "$URL" --path - --out "$tmp/rec2.frames" --tail 0.2 --mesh none 2>"$tmp/rec2.log" ||
    fail "record from stdin: $(cat "$tmp/rec2.log")"
grep -q "5 camera reports" "$tmp/rec2.log" || fail "record from stdin: $(cat "$tmp/rec2.log")"

echo "== progress on a terminal, none in a pipe ($SECONDS s)"
# script(1) gives the command a pseudo-terminal, as a person at a shell has.
grep -q $'\r\[' "$tmp/rec.log" && fail "record drew progress into a file"
script -qec "'$OC' record '$URL' --path '$tmp/ship.csv' --out '$tmp/rec3.frames' --tail 0.3 --mesh none" /dev/null \
    >"$tmp/tty.log" 2>&1 || fail "record on a terminal: $(cat "$tmp/tty.log")"
grep -q "\[####.*camera reports" "$tmp/tty.log" || fail "record shows no progress on a terminal: $(cat -v "$tmp/tty.log")"
script -qec "'$OC' load '$URL' --clients 2 --seconds 1 --rate 10 --mesh none --ramp 0.1" /dev/null \
    >"$tmp/tty.log" 2>&1 || fail "load on a terminal: $(cat "$tmp/tty.log")"
grep -q "\[#.*load: 2 viewers" "$tmp/tty.log" || fail "load shows no progress on a terminal: $(cat -v "$tmp/tty.log")"

echo "== export ($SECONDS s)"
# the default codec is the one that carries the most sea within the byte
# budget (qz, re-encoded): exr-zip on the wire left 3 tiles of cascade 0
"$OC" export "$URL" --out "$tmp/exr" --mesh none 2>"$tmp/exp.log" || fail "export: $(cat "$tmp/exp.log")"
[[ $(cut -d, -f5 "$tmp/exr/tiles.csv" | sed 1d | sort -u | wc -l) -ge 3 ]] ||
    fail "export by default: tiles of fewer than 3 cascades: $(cut -d, -f5 "$tmp/exr/tiles.csv" | sort | uniq -c)"
grep -q "warning" "$tmp/exp.log" && fail "export by default warns: $(cat "$tmp/exp.log")"
"$OC" export "$URL" --out "$tmp/exr-zip" --mesh none --codec exr-zip 2>"$tmp/exp2.log" || fail "export exr-zip: $(cat "$tmp/exp2.log")"
grep -q "warning: .*E_error" "$tmp/exp2.log" || fail "export --codec exr-zip: no warning of the coarsened tiles: $(cat "$tmp/exp2.log")"
n=$(ls "$tmp/exr"/*.exr | wc -l)
[[ $n -gt 0 ]] || fail "no EXR files"
first=$(ls "$tmp/exr"/*.exr | head -1)
if command -v exrinfo >/dev/null; then
    exrinfo "$first" | grep -q "'H'" || fail "exrinfo cannot read $first"
fi
[[ $(wc -l <"$tmp/exr/tiles.csv") -eq $((n + 1)) ]] || fail "tiles.csv does not list every file"

echo "== load ($SECONDS s)"
"$OC" load "$URL" --clients 4 --seconds 2 --rate 10 --mesh none --ramp 0.2 --json >"$tmp/load.json" || fail "load exited $?"
json "$tmp/load.json" "d['connected'] == 4 and d['frames_per_viewer_min'] > 0 and d['latency_p99_ms'] is not None and d['bytes_per_viewer_per_s'] > 0"
# with the daemon's epoch, latency is each frame's age from its tick: at
# least 0 (no frame leaves before its tick) and far under a second here
"$OC" load "$URL" --clients 2 --seconds 2 --rate 10 --mesh none --ramp 0.2 --epoch "$EPOCH" --json \
    >"$tmp/load-age.json" || fail "load --epoch exited $?"
json "$tmp/load-age.json" "'age from its tick' in d['latency_basis'] and 0 <= d['latency_p50_ms'] <= d['latency_p99_ms'] < 1000"

echo "== load follows the viewer's time-interpolating stream ($SECONDS s)"
# The viewer's subscription samples in time: a frame is read from the
# samples its connection holds, so a follower decodes every frame in order
# through its own store and reads the sea at the frame's camera.  A frame
# applied out of order, missed, or read alone reads nothing there (ENOTFOUND
# or ESTATE: a decode error), so every frame verified without one is a
# stream followed.  --verify-every 1: every viewer follows.
"$OC" load "$URL" --clients 2 --seconds 2 --rate 30 --ramp 0.2 --verify-every 1 --json >"$tmp/load-ti.json" ||
    fail "load --time-interp on exited $?"
json "$tmp/load-ti.json" "d['time_interp'] and d['stream'] == 'time-interpolating' and d['streams_followed'] == 2 and d['frames'] > 0 and d['frames_verified'] == d['frames'] == d['frames_layout1'] and d['decode_errors'] == 0"
# every 2nd viewer follows; the others' frames are counted, not read
"$OC" load "$URL" --clients 4 --seconds 2 --rate 30 --ramp 0.2 --verify-every 2 --json >"$tmp/load-ti2.json" ||
    fail "load --verify-every 2 exited $?"
json "$tmp/load-ti2.json" "d['streams_followed'] == 2 and 0 < d['frames_verified'] < d['frames'] and d['decode_errors'] == 0"
# the client library follows it by itself when it decodes
"$OC" load "$URL" --clients 2 --seconds 2 --rate 30 --ramp 0.2 --library --decode --json >"$tmp/load-ti-lib.json" ||
    fail "load --library --decode exited $?"
json "$tmp/load-ti-lib.json" "d['streams_followed'] == 2 and d['frames'] > 0 and d['decode_errors'] == 0"
# the plain stream on request: every frame whole
"$OC" load "$URL" --clients 2 --seconds 2 --rate 30 --ramp 0.2 --verify-every 1 --time-interp off --json \
    >"$tmp/load-plain.json" || fail "load --time-interp off exited $?"
json "$tmp/load-plain.json" "not d['time_interp'] and d['stream'] == 'plain' and d['streams_followed'] == 0 and d['frames'] > 0 and d['frames_verified'] == d['frames'] and d['decode_errors'] == 0"
python3 -c "import json; a=json.load(open('$tmp/load-ti.json')); b=json.load(open('$tmp/load-plain.json')); print('bytes per viewer per second: time-interpolating %.0f, plain %.0f' % (a['bytes_per_viewer_per_s'], b['bytes_per_viewer_per_s']))"

echo "== query ($SECONDS s)"
"$OC" query "$URL" --points "0,0;10.5,-3" --json >"$tmp/q.json" 2>"$tmp/q.err" || fail "query: $(cat "$tmp/q.err")"
json "$tmp/q.json" "len(d['points']) == 2 and all(abs(p['height']) < 50 and abs(p['normal'][1]) > 0.5 for p in d['points'])"

echo "== entity ($SECONDS s)"
"$OC" entity "$URL" >"$tmp/ent0.json" || fail "entity exited $?"
json "$tmp/ent0.json" "d == []"
"$OC" entity "$URL" --set --token cli-entity --id 5 --kind ship --x 10 --z 20 --heading 90 --speed 4 --length 80 \
    --beam 12 --draught 4 >"$tmp/ent1.json" || fail "entity --set exited $?"
json "$tmp/ent1.json" "len(d) == 1 and d[0]['id'] == 5 and d[0]['kind'] == 'ship' and d[0]['x'] == 10 and d[0]['speed'] == 4 and d[0]['t'] > 0"
# what the table refuses comes back as the server's reason, and nothing is printed
"$OC" entity "$URL" --set --token cli-entity --id 5 --kind ship --x 5000 --z 20 --length 80 --beam 12 --draught 4 \
    >"$tmp/ent.out" 2>"$tmp/ent.err" && fail "a teleport was entered"
grep -q "teleport" "$tmp/ent.err" && [[ ! -s $tmp/ent.out ]] || fail "teleport: $(cat "$tmp/ent.err" "$tmp/ent.out")"
"$OC" entity "$URL" --x 4 2>"$tmp/ent.err"; [[ $? -eq 2 ]] || fail "entity --x without --set accepted"
"$OC" entity "$URL" --set --token cli-entity --id 6 --x 1 --z 2 2>"$tmp/ent.err"; [[ $? -eq 2 ]] ||
    fail "entity --set without --kind and --length accepted"
"$OC" entity "$URL" --remove --token cli-entity --id 5 >"$tmp/ent3.json" || fail "entity --remove exited $?"
json "$tmp/ent3.json" "d == []"
"$OC" entity "$URL" --remove --token cli-entity --id 5 2>"$tmp/ent.err" && fail "removing an unknown id succeeded"
grep -q "no entity 5" "$tmp/ent.err" || fail "remove of an unknown id: $(cat "$tmp/ent.err")"

echo "== sea ($SECONDS s)"
"$OC" sea "$URL" >"$tmp/sea.json" || fail "sea exited $?"
json "$tmp/sea.json" "d['wind_u10'] >= 0 and d['depth_m'] > 0 and d['tp'] >= 0"
"$OC" sea "$URL" --set --token not-the-token --wind 3 >"$tmp/sea.out" 2>"$tmp/sea.err" && fail "sea --set with a wrong token succeeded"
# a refused --set prints only the error (it printed the unchanged state too)
[[ -s $tmp/sea.out ]] && fail "sea --set refused, yet stdout has: $(head -3 "$tmp/sea.out")"
grep -q "SEA_STATE" "$tmp/sea.err" || fail "no server ERROR shown: $(cat "$tmp/sea.err")"
"$OC" sea "$URL" --set 2>"$tmp/sea.err"; [[ $? -eq 2 ]] || fail "--set without --token accepted"
"$OC" sea "$URL" --set --token $TOKEN 2>"$tmp/sea.err"; [[ $? -eq 2 ]] || fail "--set with nothing to change accepted"
grep -q "nothing to change" "$tmp/sea.err" || fail "--set with nothing to change: $(cat "$tmp/sea.err")"
# The sea's enums travel as names both ways.
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); sys.exit(0 if d['spectrum'] in ('phillips','pierson-moskowitz','jonswap','tma') and isinstance(d['spreading'], str) else 1)" "$tmp/sea.json" ||
    fail "sea JSON spectrum/spreading are not names: $(cat "$tmp/sea.json")"

echo "== ship against the daemon ($SECONDS s)"
"$SHIP" "$URL" --seconds 5 --dt 0.1 --quiet >"$tmp/ship.out" 2>&1 || fail "ship: $(cat "$tmp/ship.out")"
grep -q "heave spectrum peak" "$tmp/ship.out" || fail "ship printed no summary"

echo "== the CIGI host example against the daemon ($SECONDS s)"
# a ship's four hull points and an aircraft's radar altimeter at 60 Hz over
# CIGI: it exits 0 when frames were answered and every answer was valid
"$CIGI_HOST" "127.0.0.1:$cport" --seconds 2 >"$tmp/cigi.out" 2>&1 || fail "cigi_host: $(cat "$tmp/cigi.out")"
grep -q "answers valid, 0 not" "$tmp/cigi.out" || fail "cigi_host summary: $(cat "$tmp/cigi.out")"
"$CIGI_HOST" "127.0.0.1:$cport" --seconds 1 --version 4 --little-endian >"$tmp/cigi4.out" 2>&1 ||
    fail "cigi_host CIGI 4: $(cat "$tmp/cigi4.out")"

echo "== load against a full server fails with the server's reason ($SECONDS s)"
# it printed "only 2 of 4 viewers connected" and exited 0, the BYE unsaid
port2=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
"$OD" --config config/oceand.conf --scene "" --port "$port2" --set server.max_clients=2 >"$tmp/full.log" 2>&1 &
pid2=$!
for i in $(seq 50); do
    "$OC" watch "ws://127.0.0.1:$port2/" --frames 1 --seconds 2 --mesh none >/dev/null 2>&1 && break
    sleep 0.1
done
for path in "" --library; do
    "$OC" load "ws://127.0.0.1:$port2/" --clients 4 --seconds 1 --rate 10 --mesh none --ramp 0.1 $path \
        >"$tmp/full.out" 2>"$tmp/full.err"
    rc=$?
    [[ $rc -eq 1 ]] || fail "load ${path:-(direct)} with 2 of 4 viewers served: exit $rc"
    grep -q "2 of 4 viewers were not served: .*server full" "$tmp/full.err" ||
        fail "load ${path:-(direct)}: the server's reason is not given: $(cat "$tmp/full.err")"
done
kill "$pid2"; wait "$pid2"; pid2=

echo "== sea --set by name ($SECONDS s)"
"$OC" sea "$URL" --set --token $TOKEN --spectrum jonswap --wind 12 >"$tmp/sea2.json" 2>"$tmp/sea.err" ||
    fail "sea --set --spectrum jonswap: $(cat "$tmp/sea.err")"
sea_until "$tmp/sea3.json" "d['spectrum'] == 'jonswap' and d['wind_u10'] == 12"
# the state in force is reported with the time the change took effect, not
# the time it was read (HELLO's sea carries none: SEA_STATE get does)
python3 -c "import json,sys; a=json.load(open(sys.argv[1])); b=json.load(open(sys.argv[2])); sys.exit(0 if a['effective_time'] == b['effective_time'] > 0 else 1)" "$tmp/sea2.json" "$tmp/sea3.json" ||
    fail "sea reports effective_time $(grep effective "$tmp/sea3.json") for the change entered at $(grep effective "$tmp/sea2.json")"
# a change asked for a past instant takes effect at the server's clock,
# and the asker is told both times
"$OC" sea "$URL" --set --token $TOKEN --wind 12 --at 0.5 >"$tmp/sea4.json" 2>"$tmp/sea.err" ||
    fail "sea --set --at 0.5: $(cat "$tmp/sea.err")"
grep -q "asked for t = 0.500 s, in force from t = " "$tmp/sea.err" || fail "sea --at in the past: not said: $(cat "$tmp/sea.err")"
python3 -c "import json,sys; sys.exit(0 if json.load(open(sys.argv[1]))['effective_time'] > 0.5 else 1)" "$tmp/sea4.json" ||
    fail "sea --at 0.5 reports $(grep effective "$tmp/sea4.json")"
# the daemon logs every change with who made it
grep -q "sea state set by client [0-9]* (127.0.0.1), in force from t = .*wind 12.00 m/s" "$tmp/oceand.log" ||
    fail "the change is not logged with its client and address: $(grep 'sea state' "$tmp/oceand.log" | head -3)"

echo "== sea --whitecaps off, then on ($SECONDS s)"
for w in off on; do
    "$OC" sea "$URL" --set --token $TOKEN --whitecaps $w >/dev/null 2>"$tmp/sea.err" || fail "sea --set --whitecaps $w: $(cat "$tmp/sea.err")"
    sea_until "$tmp/sea4.json" "d['whitecaps'] is $([[ $w == on ]] && echo True || echo False) and d['wind_u10'] == 12"
done
"$OC" sea "$URL" --whitecaps maybe 2>"$tmp/sea.err"; [[ $? -eq 2 ]] || fail "sea --whitecaps maybe accepted"

echo "== sea --set takes what the config takes: swell 5, a seed past 2^53 ($SECONDS s)"
# --swell had [0, 1] where sea.swell is [0, 10]; --seed went through a double,
# so 2^53 + 1 arrived as 2^53, and the JSON printed seeds rounded
"$OC" sea "$URL" --set --token $TOKEN --swell 5 --seed 9007199254740993 >/dev/null 2>"$tmp/sea.err" ||
    fail "sea --set --swell 5 --seed 2^53+1: $(cat "$tmp/sea.err")"
for _ in $(seq 50); do
    "$OC" sea "$URL" >"$tmp/sea4.json" || fail "sea after set"
    grep -q '"seed":[[:space:]]*9007199254740993,' "$tmp/sea4.json" && break
    sleep 0.1
done
grep -q '"seed":[[:space:]]*9007199254740993,' "$tmp/sea4.json" || fail "seed not 9007199254740993: $(cat "$tmp/sea4.json")"
json "$tmp/sea4.json" "d['swell'] == 5"
"$OC" sea "$URL" --set --token $TOKEN --swell 11 2>"$tmp/sea.err"; [[ $? -eq 2 ]] || fail "--swell 11 accepted"
grep -q "\[0, 10\]" "$tmp/sea.err" || fail "--swell 11: the range is not sea.swell's: $(cat "$tmp/sea.err")"

kill -TERM "$pid"
wait "$pid"
rc=$?
[[ $rc -eq 0 ]] || fail "oceand exited $rc after SIGTERM"
echo "all ocean-client checks passed"
