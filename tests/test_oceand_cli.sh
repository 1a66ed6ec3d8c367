#!/usr/bin/env bash
# test_oceand_cli.sh - oceand's command line (issue 17 items 3-5):
#  - an address this host does not have fails at once, non-zero, with a
#    message naming it, instead of a false "listening";
#  - a busy port fails naming the way out (--port, make run ARGS);
#  - --help shows the defaults the daemon really starts with: each equals
#    the value --dump-config gives for the key;
#  - a refusal of keys together (a wisdom plan without a file) names the
#    config, the scene and the command line that set them, not one file;
#  - a relative scene path that does not resolve (oceand started outside
#    the source tree) is explained: the working directory it was read
#    from and the keys that take an absolute path;
#  - --dump-config prints what --config, the scene, --port and --set
#    resolve to, as a file that loads back to the same (the scene's keys
#    applied over it again, so its sea.* --set given again);
#  - /status carries the scene's camera hint (the browser viewer opens
#    there), as config/scenes/flight.conf writes it; /status and /metrics
#    answer GET and HEAD at their exact paths, 405 to other methods; a
#    long path is 404 or 414, never 405;
#  - the shipped configuration starts without a warning; the near field a
#    layout-0 subscription at the default 2 m spacing cannot carry is said
#    when the first such client subscribes, once a run, never for layout 1.
set -u
BUILD=${BUILD:-build}
OD=$BUILD/oceand
tmp=$(mktemp -d /tmp/oc-od.XXXXXX)
holder=
cleanup() { [[ -n $holder ]] && kill "$holder" 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; exit 1; }

echo "== --bind an address not on this host ($SECONDS s)"
# 192.0.2.1 is TEST-NET-1 (RFC 5737): never assigned to a host.
timeout 20 "$OD" --config config/oceand.conf --bind 192.0.2.1 --port 0 >"$tmp/out" 2>"$tmp/err"
rc=$?
[[ $rc -ne 0 && $rc -ne 124 ]] || fail "--bind 192.0.2.1: exit $rc (124 = kept running): $(cat "$tmp/out" "$tmp/err")"
grep -q "listening" "$tmp/out" && fail "false 'listening': $(cat "$tmp/out")"
grep -q "192.0.2.1" "$tmp/err" || fail "message does not name the address: $(cat "$tmp/err")"
timeout 20 "$OD" --config config/oceand.conf --bind no-such-if0 --port 0 >"$tmp/out" 2>"$tmp/err"
rc=$?
[[ $rc -ne 0 && $rc -ne 124 ]] || fail "--bind no-such-if0: exit $rc"
grep -q "no-such-if0" "$tmp/err" || fail "message does not name the bad bind: $(cat "$tmp/err")"

# an IPv6 address is said to be one (oceand listens on IPv4); an interface
# name prints its address in the URL, not http://lo:PORT/
"$OD" --config config/oceand.conf --bind ::1 --port 0 >"$tmp/out" 2>"$tmp/err" && fail "--bind ::1 accepted"
grep -q "'::1' is an IPv6 address; oceand listens on IPv4 only" "$tmp/err" || fail "--bind ::1: $(cat "$tmp/err")"
timeout 3 "$OD" --config config/oceand.conf --bind lo --port 0 >"$tmp/out" 2>&1
grep -q "^oceand: listening on http://127\.0\.0\.1:[0-9]*/" "$tmp/out" || fail "--bind lo: $(head -2 "$tmp/out")"

echo "== a busy port names the way out ($SECONDS s)"
python3 -c '
import socket, sys, time
s = socket.socket(); s.bind(("127.0.0.1", 0)); s.listen()
print(s.getsockname()[1], flush=True); time.sleep(60)' >"$tmp/port" &
holder=$!
for _ in $(seq 100); do [[ -s $tmp/port ]] && break; sleep 0.05; done
busy=$(cat "$tmp/port")
timeout 20 "$OD" --config config/oceand.conf --port "$busy" >"$tmp/out" 2>"$tmp/err"
rc=$?
[[ $rc -ne 0 && $rc -ne 124 ]] || fail "busy port $busy: exit $rc"
grep -q -- "--port" "$tmp/err" && grep -q "ARGS=" "$tmp/err" || fail "busy port: no way out named: $(cat "$tmp/err")"

echo "== started outside the source tree: the relative scene path is explained ($SECONDS s)"
conf=$(pwd)/config/oceand.conf od=$(cd "$(dirname "$OD")" && pwd)/$(basename "$OD")
(cd "$tmp" && timeout 20 "$od" --config "$conf" --port 0 >"$tmp/out" 2>"$tmp/err")
rc=$?
[[ $rc -ne 0 && $rc -ne 124 ]] || fail "started in $tmp: exit $rc"
grep -q "working directory $tmp" "$tmp/err" && grep -q "server.scene_dir" "$tmp/err" ||
    fail "started in $tmp: the message does not say where the relative path was read from: $(cat "$tmp/err")"

echo "== a shorthand's bad value is named by the option typed ($SECONDS s)"
"$OD" --config config/oceand.conf --port 70000 >"$tmp/out" 2>"$tmp/err" && fail "--port 70000 accepted"
grep -q "^oceand: --port: server.port: out of range" "$tmp/err" || fail "--port 70000: $(cat "$tmp/err")"
"$OD" --config config/oceand.conf --set server.port=70000 >"$tmp/out" 2>"$tmp/err" && fail "--set server.port=70000 accepted"
grep -q "^oceand: --set: server.port" "$tmp/err" || fail "--set server.port=70000: $(cat "$tmp/err")"

echo "== a check of keys together names every source that set them ($SECONDS s)"
# the plan comes from --set, the refusal was blamed on the scene file alone
"$OD" --config config/oceand.conf --port 0 --set ocean.plan=wisdom >"$tmp/out" 2>"$tmp/err" &&
    fail "--set ocean.plan=wisdom without a wisdom file accepted"
grep -q "^oceand: config/oceand.conf with its scene config/scenes/ship-bridge.conf and the command line: plan = wisdom needs a wisdom file" "$tmp/err" ||
    fail "--set ocean.plan=wisdom: $(cat "$tmp/err")"
"$OD" --config config/oceand.conf --port 0 --set server.scene= --set ocean.plan=wisdom >"$tmp/out" 2>"$tmp/err" &&
    fail "--set ocean.plan=wisdom without a scene accepted"
grep -q "^oceand: config/oceand.conf and the command line: plan = wisdom needs" "$tmp/err" ||
    fail "--set ocean.plan=wisdom, no scene: $(cat "$tmp/err")"

# keys that contradict each other are refused together, naming both
"$OD" --config config/oceand.conf --port 0 --set server.output_soft=40000000 >"$tmp/out" 2>"$tmp/err" &&
    fail "output_soft above output_hard accepted"
grep -q "server.output_soft 40000000 is above server.output_hard 33554432" "$tmp/err" || fail "output_soft > output_hard: $(cat "$tmp/err")"
"$OD" --config config/oceand.conf --port 0 --set server.partial_total=65536 >"$tmp/out" 2>"$tmp/err" &&
    fail "max_message above partial_total accepted"
grep -q "server.max_message 1048576 is above server.partial_total 65536" "$tmp/err" || fail "max_message > partial_total: $(cat "$tmp/err")"

echo "== --version ($SECONDS s)"
"$OD" --version >"$tmp/ver" || fail "--version exited $?"
grep -qx "oceand [0-9][0-9.]* (protocol ocean\.v[0-9]*)" "$tmp/ver" || fail "--version: $(cat "$tmp/ver")"

echo "== --help defaults are the real defaults ($SECONDS s)"
"$OD" --help >"$tmp/help" || fail "--help"
"$OD" --dump-config >"$tmp/dump" || fail "--dump-config"
n=0
while read -r key val; do
    real=$(sed -n "s/^$key = //p" "$tmp/dump")
    [[ "$val" == "$real" ]] || fail "--help says $key default '$val', the daemon starts with '$real'"
    n=$((n + 1))
done < <(sed -n 's/.*(\(server\.[a-z_]*\); default \(.*\))$/\1 \2/p' "$tmp/help")
[[ $n -ge 3 ]] || fail "--help shows $n defaults: $(cat "$tmp/help")"
echo "== --dump-config prints what the command line resolves to ($SECONDS s)"
"$OD" --config config/oceand.conf --port 18999 --set server.tick_rate=10 --set sea.choppiness=0.9 \
    --dump-config >"$tmp/dump2" || fail "--dump-config with --config"
for want in "server.port = 18999" "server.tick_rate = 10" "sea.choppiness = 0.9" \
            "ocean.cascades = 3" "server.scene = ship-bridge"; do
    grep -qxF "$want" "$tmp/dump2" || fail "--dump-config: no line '$want' (the scene gives 3 cascades)"
done
"$OD" --config "$tmp/dump2" --set sea.choppiness=0.9 --dump-config | diff -q - "$tmp/dump2" >/dev/null ||
    fail "--dump-config output with its --set does not load back to the same configuration"
echo "== a key the scene overrides is named ($SECONDS s)"
# the scene wins over the file: ocean.n = 512 in oceand.conf with the
# shipped scene stayed 256 without a word
sed 's/^ocean.n = 256$/ocean.n = 512/' config/oceand.conf >"$tmp/n512.conf"
"$OD" --config "$tmp/n512.conf" --dump-config 2>"$tmp/n512.err" >/dev/null || fail "--dump-config with ocean.n = 512"
grep -qF "scene 'ship-bridge' sets this key otherwise, and a scene wins over the file: ocean.n = 512 (scene: 256)" \
    "$tmp/n512.err" || fail "ocean.n = 512 under the scene: $(cat "$tmp/n512.err")"
"$OD" --config config/oceand.conf --dump-config 2>"$tmp/shipped.err" >/dev/null || fail "--dump-config"
[[ ! -s $tmp/shipped.err ]] || fail "the shipped configuration is not quiet: $(cat "$tmp/shipped.err")"
echo "== /status carries the scene camera hint ($SECONDS s)"
"$OD" --config config/oceand.conf --scene flight --port 0 >"$tmp/d.log" 2>&1 &
dpid=$!
for _ in $(seq 200); do grep -q "listening on" "$tmp/d.log" && break; sleep 0.05; done
port=$(sed -n 's|^oceand: listening on http://[0-9.]*:\([0-9]*\)/.*|\1|p' "$tmp/d.log")
[[ -n $port ]] || { kill "$dpid"; fail "daemon with --scene flight: $(cat "$tmp/d.log")"; }
curl -sf "http://127.0.0.1:$port/status" -o "$tmp/status.json" || { kill "$dpid"; fail "GET /status"; }
# exact paths, GET and HEAD alike (HEAD got 404, /metricsfoo the metrics),
# other methods 405 naming the two
code() { curl -s -o /dev/null -w "%{http_code}" --max-time 5 "$@"; }
for u in /status /metrics; do
    [[ $(code -I "http://127.0.0.1:$port$u") == 200 ]] || { kill "$dpid"; fail "HEAD $u: $(code -I "http://127.0.0.1:$port$u")"; }
done
for u in /statusz /metricsfoo /status/x; do
    [[ $(code "http://127.0.0.1:$port$u") == 404 ]] || { kill "$dpid"; fail "GET $u: $(code "http://127.0.0.1:$port$u"), want 404"; }
done
[[ $(code -X POST "http://127.0.0.1:$port/metrics") == 405 ]] || { kill "$dpid"; fail "POST /metrics is not 405"; }
# a GET or HEAD path too long for the daemon's 128-byte copy was taken for
# neither (405 "Allow: GET, HEAD"): it is not there (404), and past what
# lws can name as a file under server.web_root (255 bytes) it is 414
long=$(python3 -c 'print("a" * 130)')
for u in "/$long" "/status$long" "/metrics/$long"; do
    for c in "$(code "http://127.0.0.1:$port$u")" "$(code -I "http://127.0.0.1:$port$u")"; do
        [[ $c == 404 ]] || { kill "$dpid"; fail "GET/HEAD of a ${#u}-byte path ${u:0:12}...: $c, want 404"; }
    done
done
long=$(python3 -c 'print("a" * 300)')
for u in "/$long" "/status/$long"; do
    for c in "$(code "http://127.0.0.1:$port$u")" "$(code -I "http://127.0.0.1:$port$u")"; do
        [[ $c == 414 ]] || { kill "$dpid"; fail "GET/HEAD of a ${#u}-byte path ${u:0:12}...: $c, want 414"; }
    done
done
curl -s -D - -o /dev/null -X OPTIONS "http://127.0.0.1:$port/status" | grep -qi "^allow: GET, HEAD" ||
    { kill "$dpid"; fail "OPTIONS /status: no 'Allow: GET, HEAD'"; }
kill -TERM "$dpid"; wait "$dpid"
hint=$(sed -n 's/^scene.camera_hint *= *\([^ #]*\).*/\1/p' config/scenes/flight.conf)
python3 - "$tmp/status.json" "$hint" <<'PY' || fail "/status camera_hint: $(cat "$tmp/status.json") vs flight.conf '$hint'"
import json, sys
h = json.load(open(sys.argv[1]))["camera_hint"]
want = [float(v) for v in sys.argv[2].split(",")] + [0.0] * 2
got = [h["x"], h["y"], h["z"], h["yaw"], h["pitch"]]
sys.exit(0 if all(abs(a - b) < 1e-9 for a, b in zip(got, want[:5])) else 1)
PY
echo "== a web root without the viewer is said at start ($SECONDS s)"
timeout 3 "$OD" --config config/oceand.conf --port 0 --set server.web_root=/nonexistent-web >"$tmp/w.log" 2>&1
grep -q "warning: server.web_root '/nonexistent-web' has no readable index.html" "$tmp/w.log" ||
    fail "a missing web root is not said: $(cat "$tmp/w.log")"

echo "== a long path is never served another file ($SECONDS s)"
# lws names a file as web_root "/" path in 255 bytes and cut the rest, so a
# longer path whose first bytes named a file was served that file
mkdir -p "$tmp/wr"
python3 - "$tmp/wr" >"$tmp/wr.urls" <<'PY'
import os, sys
for L in range(150, 251):
    try:
        open(os.path.join(sys.argv[1], "f" * L + ".txt"), "w").close()
    except OSError:
        pass
    print("/" + "f" * L + ".txt" + "X" * 20)
PY
echo hello >"$tmp/wr/short.txt"
"$OD" --config config/oceand.conf --port 0 --set "server.web_root=$tmp/wr" >"$tmp/wr.log" 2>&1 &
dpid=$!
for _ in $(seq 200); do grep -q "listening on" "$tmp/wr.log" && break; sleep 0.05; done
port=$(sed -n 's|^oceand: listening on http://[0-9.]*:\([0-9]*\)/.*|\1|p' "$tmp/wr.log")
[[ -n $port ]] || { kill "$dpid"; fail "daemon with a web root of long names: $(cat "$tmp/wr.log")"; }
[[ $(code "http://127.0.0.1:$port/short.txt") == 200 ]] || { kill "$dpid"; fail "a file under the web root is not served"; }
while read -r u; do
    c=$(code "http://127.0.0.1:$port$u")
    [[ $c == 404 || $c == 414 ]] || { kill "$dpid"; fail "GET of a ${#u}-byte path naming no file: $c (want 404 or 414)"; }
done <"$tmp/wr.urls"
kill -TERM "$dpid"; wait "$dpid"

echo "== no client can flood the log ($SECONDS s)"
# 40 requests with 9 KB URLs (lws: "Ran out of header data space" a line
# each) and 6 recording clients past server.record_max_files = 1 (a line
# each): a few lines in all
"$OD" --config config/oceand.conf --port 0 --set server.record_clients=on --set "server.record_dir=$tmp/rec" \
    --set server.record_max_files=1 >"$tmp/f.log" 2>&1 &
dpid=$!
for _ in $(seq 200); do grep -q "listening on" "$tmp/f.log" && break; sleep 0.05; done
port=$(sed -n 's|^oceand: listening on http://[0-9.]*:\([0-9]*\)/.*|\1|p' "$tmp/f.log")
[[ -n $port ]] || { kill "$dpid"; fail "daemon for the log flood: $(cat "$tmp/f.log")"; }
long=/$(head -c 9000 /dev/zero | tr '\0' a)
t0=$(date +%s.%N)
for _ in $(seq 40); do curl -s -o /dev/null --max-time 2 "http://127.0.0.1:$port$long"; done
"$BUILD/ocean-client" load "ws://127.0.0.1:$port/?record=1" --clients 6 --seconds 1 --rate 5 >/dev/null 2>&1
kill -TERM "$dpid"; wait "$dpid"
n_lws=$(grep -c "^oceand: lws" "$tmp/f.log")
n_rec=$(grep -c "not recording" "$tmp/f.log")
# lws's lines are held to one a second: at most one per second the requests
# and the shutdown took, plus the shutdown's own, however slow the host
most=$(awk -v a="$t0" -v b="$(date +%s.%N)" 'BEGIN {printf "%d", b - a + 2}')
[[ $n_lws -ge 1 && $n_lws -le $most ]] || fail "40 long URLs: $n_lws lws lines (want 1-$most): $(head -5 "$tmp/f.log")"
[[ $n_rec -eq 1 ]] || fail "6 recording clients past record_max_files 1: $n_rec lines (want 1): $(grep "not recording" "$tmp/f.log" | head -3)"

echo "== the default start says nothing a layout-0 client may never need ($SECONDS s)"
OC=$BUILD/ocean-client
# (admission, server.admit_share, prices layout 0 from this host's speed:
# off, so a busy host does not refuse the layout-0 clients below)
"$OD" --config config/oceand.conf --port 0 --set server.admit_share=0 >"$tmp/d.log" 2>&1 &
dpid=$!
for _ in $(seq 200); do grep -q "listening on" "$tmp/d.log" && break; sleep 0.05; done
port=$(sed -n 's|^oceand: listening on http://[0-9.]*:\([0-9]*\)/.*|\1|p' "$tmp/d.log")
[[ -n $port ]] || { kill "$dpid"; fail "default daemon: $(cat "$tmp/d.log")"; }
grep -q "warning" "$tmp/d.log" && { kill "$dpid"; fail "the shipped configuration starts with a warning: $(cat "$tmp/d.log")"; }
"$OC" load "ws://127.0.0.1:$port/" --clients 2 --seconds 1 --rate 10 --layout 1 >/dev/null 2>&1 ||
    { kill "$dpid"; fail "layout-1 load against the default daemon"; }
grep -q "near field" "$tmp/d.log" && { kill "$dpid"; fail "layout 1 carries the near field, yet: $(cat "$tmp/d.log")"; }
for _ in 1 2; do
    "$OC" load "ws://127.0.0.1:$port/" --clients 2 --seconds 1 --rate 10 --layout 0 >/dev/null 2>&1 ||
        { kill "$dpid"; fail "layout-0 load against the default daemon"; }
done
kill -TERM "$dpid"; wait "$dpid"
n=$(grep -c "layout 0 at a 2 m level-0 spacing: the near field's waves (0.1 m to 0.423 m).*<= 0.211 m can" "$tmp/d.log")
[[ $n -eq 1 ]] || fail "4 layout-0 clients at 2 m: the near-field note said $n times (want once): $(cat "$tmp/d.log")"
echo "ok ($SECONDS s)"
