#!/usr/bin/env bash
# test_h2_websocket.sh - a WebSocket inside HTTP/2 is refused, and the
# daemon survives one.  libwebsockets 4.1.6 (built with HTTP/2) accepts an
# h2c upgrade on the plain port and RFC 8441's extended CONNECT for
# websocket; ocean.v1 is RFC 6455 over its own TCP connection, and oceand's
# frame tracker and send path assume so: one SUBSCRIBE on such a stream
# made lws_write read before the message buffer and killed the daemon,
# every client with it.  Now the stream gets no 200 (no HELLO), a SUBSCRIBE
# sent on it anyway changes nothing, and the daemon goes on serving HTTP
# and plain WebSockets.
set -u
BUILD=${BUILD:-build}
OD=$BUILD/oceand
OC=$BUILD/ocean-client
tmp=$(mktemp -d /tmp/oc-h2.XXXXXX)
pid=
cleanup() { [[ -n $pid ]] && kill "$pid" 2>/dev/null; wait 2>/dev/null; rm -rf "$tmp"; }
trap cleanup EXIT
fail() { echo "FAIL: $*"; echo "--- oceand log:"; tail -20 "$tmp/d.log"; exit 1; }

"$OD" --config config/oceand.conf --scene "" --port 0 >"$tmp/d.log" 2>&1 &
pid=$!
for _ in $(seq 200); do grep -q "listening on" "$tmp/d.log" && break; sleep 0.05; done
port=$(sed -n 's|^oceand: listening on http://[0-9.]*:\([0-9]*\)/.*|\1|p' "$tmp/d.log")
[[ -n $port ]] || fail "daemon did not start"

python3 - "$port" <<'PY' || fail "WebSocket over HTTP/2"
import socket, struct, sys, time
port = int(sys.argv[1])
def lit(n, v):  # HPACK literal header field without indexing, no Huffman
    return b'\x00' + bytes([len(n)]) + n + bytes([len(v)]) + v
def h2(t, fl, sid, p):
    return len(p).to_bytes(3, 'big') + bytes([t, fl]) + sid.to_bytes(4, 'big') + p
def frames(d):
    i, out = 0, []
    while i + 9 <= len(d):
        n = int.from_bytes(d[i:i + 3], 'big')
        out.append((d[i + 3], d[i + 4], int.from_bytes(d[i + 5:i + 9], 'big') & 0x7fffffff, d[i + 9:i + 9 + n]))
        i += 9 + n
    return out
def read_for(s, secs):
    s.settimeout(0.2)
    d, end = b'', time.time() + secs
    while time.time() < end:
        try:
            b = s.recv(65536)
        except socket.timeout:
            continue
        if not b:
            break
        d += b
    return d
s = socket.create_connection(('127.0.0.1', port), timeout=3)
s.sendall(b'GET / HTTP/1.1\r\nHost: x\r\nConnection: Upgrade, HTTP2-Settings\r\nUpgrade: h2c\r\n'
          b'HTTP2-Settings: AAMAAABkAARAAAAAAAIAAAAA\r\n\r\n')
head = b''
while b'\r\n\r\n' not in head:  # the 101 first, as an HTTP/2 client waits for it
    b = s.recv(4096)
    if not b:
        sys.exit('closed before the upgrade answer')
    head += b
s.sendall(b'PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n' + h2(4, 0, 0, b'') + h2(4, 1, 0, b''))
s.sendall(h2(1, 4, 3, lit(b':method', b'CONNECT') + lit(b':protocol', b'websocket') + lit(b':scheme', b'http')
              + lit(b':path', b'/') + lit(b':authority', b'x') + lit(b'sec-websocket-version', b'13')
              + lit(b'sec-websocket-protocol', b'ocean.v1')))
# past the 101's head, HTTP/2 frames
body = head.split(b'\r\n\r\n', 1)[1] + read_for(s, 1.0)
got = [f for f in frames(body) if f[2] == 3 and f[0] in (0, 1)]
if got:
    sys.exit('stream 3 (WebSocket over HTTP/2) was answered: %r' % [(t, len(p)) for t, _, _, p in got])
# a SUBSCRIBE on the stream anyway (a masked binary WebSocket frame in a DATA frame)
sub = (b'OCNW' + struct.pack('<HHIIIId', 1, 2, 0, 28, 0, 0, 0.0)
       + struct.pack('<BBBBBBBBHBBffff', 31, 0, 2, 2, 0, 4, 8, 1, 64, 0, 0, 30.0, 5e-3, 0.0, 0.0))
s.sendall(h2(0, 0, 3, bytes([0x82, 0x80 | len(sub)]) + b'\0\0\0\0' + sub))
read_for(s, 1.0)
s.close()
PY
sleep 0.5
kill -0 "$pid" 2>/dev/null || fail "oceand died"
curl -sf "http://127.0.0.1:$port/status" >/dev/null || fail "GET /status after the HTTP/2 attempt"
"$OC" watch "ws://127.0.0.1:$port/" --frames 2 --seconds 5 --mesh none >/dev/null 2>"$tmp/w.err" ||
    fail "a plain WebSocket client after the HTTP/2 attempt: $(cat "$tmp/w.err")"
echo "ok ($SECONDS s)"
