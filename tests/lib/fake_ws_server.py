#!/usr/bin/env python3
"""fake_ws_server.py - a scripted WebSocket server for the load generator's
framing tests (tests/test_load_framing.sh).

oceand, being libwebsockets, sends every message as one frame and rarely
pings, so the daemon alone never exercises what a WebSocket client must also
handle: fragmented messages, control frames between fragments, text frames,
a server-initiated close, and protocol violations.  This server plays them on
purpose, with real protocol messages from tests/vectors, and checks what the
client answers (pong payloads, the close handshake).

  usage: fake_ws_server.py SCENARIO VECTORS_DIR RESULT_JSON
  prints the listening port on stdout, serves one connection, writes what it
  observed to RESULT_JSON and exits 0 when the client behaved, 1 otherwise.

Scenarios:
  fragments  HELLO, then FRAMES FRAMEs each split into three fragments with a
             ping between the first two, a text message and a one-byte first
             fragment among them, then a close (1001).  The client must pong
             every ping with its payload and echo the close.
  violation  HELLO, one good FRAME, then a frame with RSV1 set (no extension
             was negotiated): the client must fail the connection with a
             close frame carrying 1002 (protocol error).
"""
import base64
import hashlib
import json
import socket
import struct
import sys
import time

GUID = b"258EAFA5-E914-47DA-95CA-C5AB0DC85B11"
FRAMES = 20


def frame(opcode, payload, fin=True, rsv1=False):
    b0 = (0x80 if fin else 0) | (0x40 if rsv1 else 0) | opcode
    n = len(payload)
    if n < 126:
        head = struct.pack("!BB", b0, n)
    elif n < 65536:
        head = struct.pack("!BBH", b0, 126, n)
    else:
        head = struct.pack("!BBQ", b0, 127, n)
    return head + payload


class Reader:
    """Client frames (masked), one at a time, with a deadline."""

    def __init__(self, sock):
        self.s = sock
        self.buf = b""

    def _need(self, n, deadline):
        while len(self.buf) < n:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("client sent nothing in time")
            self.s.settimeout(left)
            d = self.s.recv(65536)
            if not d:
                raise EOFError("client closed the socket")
            self.buf += d

    def next(self, timeout=5.0):
        deadline = time.monotonic() + timeout
        self._need(2, deadline)
        b0, b1 = self.buf[0], self.buf[1]
        if not b1 & 0x80:
            raise ValueError("client frame not masked")
        n, off = b1 & 0x7F, 2
        if n == 126:
            self._need(4, deadline)
            n, off = struct.unpack("!H", self.buf[2:4])[0], 4
        elif n == 127:
            self._need(10, deadline)
            n, off = struct.unpack("!Q", self.buf[2:10])[0], 10
        self._need(off + 4 + n, deadline)
        mask = self.buf[off:off + 4]
        data = bytes(c ^ mask[i % 4] for i, c in enumerate(self.buf[off + 4:off + 4 + n]))
        self.buf = self.buf[off + 4 + n:]
        return b0 & 0x0F, bool(b0 & 0x80), data


def handshake(conn):
    req = b""
    while b"\r\n\r\n" not in req:
        d = conn.recv(4096)
        if not d:
            raise EOFError("no upgrade request")
        req += d
    head, _, rest = req.partition(b"\r\n\r\n")
    hdr = {}
    for line in head.split(b"\r\n")[1:]:
        k, _, v = line.partition(b":")
        hdr[k.strip().lower()] = v.strip()
    accept = base64.b64encode(hashlib.sha1(hdr[b"sec-websocket-key"] + GUID).digest())
    proto = hdr.get(b"sec-websocket-protocol", b"").split(b",")[0].strip()
    resp = (b"HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
            b"Sec-WebSocket-Accept: " + accept + b"\r\n")
    if proto:
        resp += b"Sec-WebSocket-Protocol: " + proto + b"\r\n"
    conn.sendall(resp + b"\r\n")
    return rest


def wait_subscribed(rd, seen):
    """The client answers HELLO with SUBSCRIBE and CAMERA (binary)."""
    got = 0
    while got < 2:
        op, fin, data = rd.next()
        seen.append(op)
        if op == 2:
            got += 1


def close_code(data):
    return struct.unpack("!H", data[:2])[0] if len(data) >= 2 else None


def run(scenario, vec, result):
    hello = open(vec + "/hello.bin", "rb").read()
    frm = open(vec + "/frame.bin", "rb").read()
    ls = socket.socket()
    ls.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    ls.bind(("127.0.0.1", 0))
    ls.listen(1)
    print(ls.getsockname()[1], flush=True)
    ls.settimeout(20)
    conn, _ = ls.accept()
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    rest = handshake(conn)
    rd = Reader(conn)
    rd.buf = rest
    seen = []
    ok = True
    why = []
    conn.sendall(frame(2, hello))
    wait_subscribed(rd, seen)
    time.sleep(0.4)  # past the client's --warmup, so every FRAME is measured
    if scenario == "fragments":
        pings = []
        for i in range(FRAMES):
            cut1 = 1 if i == 7 else 10
            cut2 = len(frm) // 2
            ping = b"ping-%d" % i
            pings.append(ping)
            conn.sendall(frame(2, frm[:cut1], fin=False) + frame(9, ping) +
                         frame(0, frm[cut1:cut2], fin=False) + frame(0, frm[cut2:]))
            if i == 5:
                conn.sendall(frame(1, b"a text message the client must ignore"))
            time.sleep(0.03)
        conn.sendall(frame(8, struct.pack("!H", 1001) + b"test over"))
        pongs, closed = [], None
        try:
            while closed is None:
                op, fin, data = rd.next()
                seen.append(op)
                if op == 10:
                    pongs.append(data)
                elif op == 8:
                    closed = close_code(data)
        except (TimeoutError, EOFError) as e:
            why.append("before the client's close: %s" % e)
        if pongs != pings:
            ok = False
            why.append("pongs %r, expected %r" % (pongs, pings))
        if closed != 1001:
            ok = False
            why.append("client's close code %r, expected 1001 echoed" % closed)
        out = {"frames_sent": FRAMES, "pongs": len(pongs), "close_code": closed}
    else:
        conn.sendall(frame(2, frm))
        time.sleep(0.05)
        conn.sendall(frame(2, frm, rsv1=True))
        closed = None
        try:
            while closed is None:
                op, fin, data = rd.next()
                seen.append(op)
                if op == 8:
                    closed = close_code(data)
        except (TimeoutError, EOFError) as e:
            why.append("no close frame: %s" % e)
        if closed != 1002:
            ok = False
            why.append("client's close code %r, expected 1002 (protocol error)" % closed)
        out = {"frames_sent": 1, "close_code": closed}
    out.update({"ok": ok, "why": why, "client_opcodes": seen})
    with open(result, "w") as f:
        json.dump(out, f)
    conn.close()
    return 0 if ok else 1


if __name__ == "__main__":
    if len(sys.argv) != 4 or sys.argv[1] not in ("fragments", "violation"):
        sys.stderr.write(__doc__)
        sys.exit(2)
    sys.exit(run(*sys.argv[1:]))
