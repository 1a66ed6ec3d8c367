/*
 * mock_server.mjs - a development stand-in for oceand, for working on the
 * web viewer's rendering without the daemon: serves clients/web/ over HTTP
 * and speaks enough ocean.v1 over a hand-rolled WebSocket (RFC 6455, no
 * dependencies) to drive the page: HELLO, MESH_TOPOLOGY once, then FRAMEs
 * with f32/f16 tiles of a few Gerstner waves and a polar concentric mesh
 * (layout 0), or periodic cascade mip tiles, a cascade block and a flat
 * mesh placed per frame (layout 1, what the viewer asks by default).
 *
 * Not used by `make test` (the browser test drives the real daemon).
 *   node tests/browser/mock_server.mjs [PORT]
 */
import http from 'node:http';
import crypto from 'node:crypto';
import { readFileSync, existsSync } from 'node:fs';
import { join, extname, normalize } from 'node:path';
import { fileURLToPath } from 'node:url';

const root = fileURLToPath(new URL('../../clients/web/', import.meta.url));
const port = Number(process.argv[2] || 8099);
const MIME = { '.html': 'text/html; charset=utf-8', '.js': 'application/javascript', '.css': 'text/css' };

const MAGIC = 0x574e434f;
function msg(type, payload, seq, t) {
    const b = Buffer.alloc(32 + payload.length);
    b.writeUInt32LE(MAGIC, 0); b.writeUInt16LE(1, 4); b.writeUInt16LE(type, 6);
    b.writeUInt32LE(payload.length, 12); b.writeUInt32LE(seq, 16); b.writeDoubleLE(t, 24);
    payload.copy(b, 32);
    return b;
}
function hello(id) {
    const p = Buffer.alloc(32 + 96 + 2 + 4);
    p.writeUInt32LE(0b111, 0); p[4] = 1; p[5] = 31; p[6] = 7; p[7] = 1;
    p.writeUInt32LE(1 << 20, 8); p.writeUInt32LE(4096, 12); p.writeUInt16LE(256, 16); p[18] = 8; p[19] = 4;
    p.writeFloatLE(30, 20); p.writeFloatLE(60, 24); p.writeUInt32LE(id, 28);
    const s = 32;
    p[s] = 1; p[s + 1] = 1; p.writeBigUInt64LE(1n, s + 8);
    [10, 20, 1e5, 4000, 0, 0.00405, 0, 1, 2.1, 7.5].forEach((v, i) => p.writeDoubleLE(v, s + 16 + 8 * i));
    p.writeUInt16LE(4, 128); p.write('mock', 130);
    return p;
}

/* waves: [kx, kz, amplitude, phase] */
const waves = [];
{
    let seed = 7;
    const r = () => { seed = (seed * 16807) % 2147483647; return seed / 2147483647; };
    for (let i = 0; i < 24; i++) {
        const lambda = 80 * Math.pow(0.78, i) + 0.8;
        const k = 2 * Math.PI / lambda;
        const dir = 20 * Math.PI / 180 + (r() - 0.5) * 1.6;
        waves.push([k * Math.cos(dir), k * Math.sin(dir), 0.12 * lambda / (2 * Math.PI) * 0.7 * (0.5 + r()), r() * 6.283]);
    }
}
function sample(x, z, t, out) {
    let h = 0, dx = 0, dz = 0, sx = 0, sz = 0, j = 0;
    for (const [kx, kz, a, ph] of waves) {
        const k = Math.hypot(kx, kz), w = Math.sqrt(9.81 * k);
        const th = kx * x + kz * z - w * t + ph;
        const c = Math.cos(th), s = Math.sin(th);
        h += a * c; dx -= kx / k * a * s; dz -= kz / k * a * s;
        sx -= a * kx * s; sz -= a * kz * s;
        j += a * k * c;
    }
    out[0] = h; out[1] = dx; out[2] = dz; out[3] = sx; out[4] = sz; out[5] = Math.max(0, Math.min(1, (j - 0.55) * 2.5));
}
function octEncode(nx, ny, nz) {
    const s = Math.abs(nx) + Math.abs(ny) + Math.abs(nz);
    return [nx / s, nz / s];
}

function tile(level, ix, iz, size, spacing, t, codec) {
    const chans = 1 | 2 | 4 | 8 | 16;
    const n = size * size, planes = 6;
    const data = new Float32Array(n * planes);
    const o = [0, 0, 0, 0, 0, 0];
    const x0 = ix * size * spacing, z0 = iz * size * spacing;
    for (let i = 0; i < size; i++)
        for (let j = 0; j < size; j++) {
            sample(x0 + j * spacing, z0 + i * spacing, t, o);
            const k = i * size + j;
            const [u, v] = octEncode(-o[3], 1, -o[4]);
            data[k] = o[0]; data[n + k] = o[1]; data[2 * n + k] = o[2]; data[3 * n + k] = u; data[4 * n + k] = v; data[5 * n + k] = o[5];
        }
    let payload;
    if (codec === 0) payload = Buffer.from(data.buffer);
    else {
        payload = Buffer.alloc(2 * data.length);
        for (let i = 0; i < data.length; i++) payload.writeUInt16LE(f16(data[i]), 2 * i);
    }
    const b = Buffer.alloc(48 + payload.length);
    b[0] = level; b[1] = codec; b.writeUInt16LE(chans, 2); b.writeUInt16LE(size, 4); b.writeUInt16LE(size, 6);
    b.writeInt32LE(ix, 8); b.writeInt32LE(iz, 12); b.writeDoubleLE(x0, 16); b.writeDoubleLE(z0, 24);
    b.writeDoubleLE(spacing, 32); b.writeFloatLE(0, 40); b.writeUInt32LE(payload.length, 44);
    payload.copy(b, 48);
    return b;
}
const f32b = new Float32Array(1), u32b = new Uint32Array(f32b.buffer);
function f16(v) {
    f32b[0] = v;
    const x = u32b[0], sign = (x >>> 16) & 0x8000, a = x & 0x7fffffff;
    if (a >= 0x477ff000) return sign | 0x7c00;
    if (a < 0x38800000) return sign | Math.round((a & 0x7fffff | 0x800000) / 2 ** (126 - (a >>> 23)));
    return sign | Math.round((a - 0x38000000) / 8192);
}

/* polar concentric mesh: center fan + rings r_k = r0 * g^k, M per ring */
const M = 192, RINGS = 96, R0 = 1.5, G = 1.075;
function meshBase() {
    const pos = [0, 0, 0];
    for (let k = 0; k < RINGS; k++) {
        const r = R0 * Math.pow(G, k);
        for (let j = 0; j < M; j++) pos.push(r * Math.cos(2 * Math.PI * j / M), 0, r * Math.sin(2 * Math.PI * j / M));
    }
    const idx = [];
    for (let j = 0; j < M; j++) idx.push(0, 1 + (j + 1) % M, 1 + j);
    for (let k = 0; k + 1 < RINGS; k++)
        for (let j = 0; j < M; j++) {
            const a = 1 + k * M + j, b = 1 + k * M + (j + 1) % M, c = a + M, d = b + M;
            idx.push(a, d, c, a, b, d);
        }
    return { pos: new Float32Array(pos), idx: new Uint32Array(idx) };
}
const base = meshBase();
console.log(`mock mesh: ${base.pos.length / 3} vertices, range ${(R0 * Math.pow(G, RINGS - 1)).toFixed(0)} m`);
function topology() {
    const vc = base.pos.length / 3, ic = base.idx.length;
    const b = Buffer.alloc(16 + 4 * ic + 5 * vc);
    b.writeUInt32LE(1, 0); b[4] = 0; b[5] = 1; b.writeUInt32LE(vc, 8); b.writeUInt32LE(ic, 12);
    Buffer.from(base.idx.buffer).copy(b, 16);
    return b;
}
function record(body) {
    const pad = (8 - (body.length & 7)) & 7;
    const b = Buffer.alloc(8 + body.length + pad);
    b.writeUInt32LE(body.length, 0);
    body.copy(b, 8);
    return b;
}
function frame(cam, t, camSeq, tick, sub) {
    const size = Math.min(sub.tileSize, 48), n = 4;
    const recs = [];
    const codec = sub.codec === 0 ? 0 : 1;
    for (let L = 0; L < Math.min(sub.lodLevels, 6); L++) {
        const sp = 0.5 * 2 ** L, w = size * sp;
        const fx = Math.floor(cam.x / w - (n - 1) / 2), fz = Math.floor(cam.z / w - (n - 1) / 2);
        for (let a = 0; a < n; a++) for (let c = 0; c < n; c++) recs.push(record(tile(L, fx + c, fz + a, size, sp, t, codec)));
    }
    const step = 4;
    const ox = Math.round(cam.x / step) * step, oz = Math.round(cam.z / step) * step;
    const mv = Buffer.alloc(32 + base.pos.length * 4);
    mv.writeUInt32LE(1, 0); mv.writeUInt32LE(base.pos.length / 3, 4);
    mv.writeDoubleLE(ox, 8); mv.writeDoubleLE(0, 16); mv.writeDoubleLE(oz, 24);
    Buffer.from(base.pos.buffer).copy(mv, 32);
    recs.push(record(mv));
    const head = Buffer.alloc(56);
    head.writeDoubleLE(Infinity, 0); head.writeDoubleLE(0.01, 8);
    head.writeDoubleLE(ox, 16); head.writeDoubleLE(0, 24); head.writeDoubleLE(oz, 32);
    head.writeUInt32LE(camSeq, 40); head.writeUInt32LE(tick, 44); head.writeUInt16LE(recs.length - 1, 48); head[50] = 1;
    return Buffer.concat([head, ...recs]);
}

/* ---- layout 1 (cascade tiles, PROTOCOL.md "Layouts") --------------------
 * Three periodic cascades of a few waves each (wave vectors on each
 * patch's lattice, so every cascade repeats exactly on its patch), cut into
 * mips that leave out the waves a mip's spacing cannot hold, with the slope
 * moments of what each mip leaves out in the mip table; a flat square-ring
 * mesh with level zones; every tile of every mip in each FRAME (the mock
 * has small grids).  Enough to develop the page's layout-1 path. */
const CAS = [{ P: 1000, n: 64 }, { P: 233, n: 64 }, { P: 54, n: 64 }].map((c, i) => {
    let seed = 11 + i;
    const r = () => { seed = (seed * 16807) % 2147483647; return seed / 2147483647; };
    const sigma = c.P / c.n, waves = [];
    for (let k = 0; k < 14; k++) {
        const lambda = Math.exp(Math.log(c.P / 2) + (Math.log(3 * sigma) - Math.log(c.P / 2)) * (k + r() * 0.5) / 14);
        const dir = 20 * Math.PI / 180 + (r() - 0.5) * 1.4;
        const kx = Math.round(c.P / lambda * Math.cos(dir)) * 2 * Math.PI / c.P, kz = Math.round(c.P / lambda * Math.sin(dir)) * 2 * Math.PI / c.P;
        const kk = Math.hypot(kx, kz);
        if (kk === 0) continue;
        waves.push([kx, kz, 0.08 / kk * (0.5 + r()) * (i === 0 ? 1 : 0.7), r() * 6.283]);
    }
    return { ...c, sigma, waves, mips: Math.log2(c.n) - 1, fades: i === 0 ? 0 : 1 };
});
function casKc(c, m) { return m === 0 ? Infinity : Math.PI / (c.sigma * 2 ** m) * 0.5; }
function casMss(c, kc) {
    let sx = 0, sz = 0, sxz = 0;
    for (const [kx, kz, a] of c.waves) if (Math.hypot(kx, kz) >= kc) { sx += 0.5 * a * a * kx * kx; sz += 0.5 * a * a * kz * kz; sxz += 0.5 * a * a * kx * kz; }
    return [sx, sz, sxz];
}
function cascadeTile(ci, m, ix, iz, T, t, codec) {
    const c = CAS[ci], sp = c.sigma * 2 ** m, kc = casKc(c, m);
    const chans = 1 | 2 | 4 | 8 | 16, n = T * T, data = new Float32Array(6 * n);
    const ws = c.waves.filter(([kx, kz]) => Math.hypot(kx, kz) < kc);
    for (let i = 0; i < T; i++)
        for (let j = 0; j < T; j++) {
            const x = (ix * T + j) * sp, z = (iz * T + i) * sp;
            let h = 0, dx = 0, dz = 0, sx = 0, sz = 0, jac = 0;
            for (const [kx, kz, a, ph] of ws) {
                const k = Math.hypot(kx, kz), th = kx * x + kz * z - Math.sqrt(9.81 * k) * t + ph;
                const cs = Math.cos(th), sn = Math.sin(th);
                h += a * cs; dx -= kx / k * a * sn; dz -= kz / k * a * sn; sx -= a * kx * sn; sz -= a * kz * sn; jac += a * k * cs;
            }
            const k = i * T + j, [u, v] = octEncode(-sx, 1, -sz);
            data[k] = h; data[n + k] = dx; data[2 * n + k] = dz; data[3 * n + k] = u; data[4 * n + k] = v;
            data[5 * n + k] = Math.max(0, Math.min(1, (jac - 0.35) * 3));
        }
    let payload;
    if (codec === 0) payload = Buffer.from(data.buffer);
    else {
        payload = Buffer.alloc(2 * data.length);
        for (let i = 0; i < data.length; i++) payload.writeUInt16LE(f16(data[i]), 2 * i);
    }
    const b = Buffer.alloc(48 + payload.length);
    b[0] = m; b[1] = codec; b.writeUInt16LE(chans, 2); b.writeUInt16LE(T, 4); b.writeUInt16LE(T, 6);
    b.writeInt32LE(ix, 8); b.writeInt32LE(iz, 12); b.writeDoubleLE(ix * T * sp, 16); b.writeDoubleLE(iz * T * sp, 24);
    b.writeDoubleLE(sp, 32); b.writeFloatLE(0, 40); b.writeUInt32LE(payload.length, 44);
    payload.copy(b, 48);
    return b;
}
/* flat mesh: level L is a square ring of cells g_L = 2^L m, half-width K g_L */
const FK = 32, FL = 8;
function flatMesh() {
    const pos = [], lev = [], idx = [];
    for (let L = 0; L < FL; L++) {
        const g = 2 ** L, inner = L ? FK / 2 : 0, map = new Map();
        const vid = (i, j) => {
            const key = `${i},${j}`;
            if (!map.has(key)) { map.set(key, pos.length / 2); pos.push(j * g, i * g); lev.push(L); }
            return map.get(key);
        };
        for (let i = -FK; i < FK; i++)
            for (let j = -FK; j < FK; j++) {
                if (inner && i >= -inner && i < inner && j >= -inner && j < inner) continue;
                const a = vid(i, j), b = vid(i, j + 1), c = vid(i + 1, j), d = vid(i + 1, j + 1);
                idx.push(a, c, b, b, c, d);
            }
    }
    const zones = [];
    for (let L = 0; L < FL; L++) { const H = FK * 2 ** L; zones.push(1 * 2 ** L, 0.75 * H - 4, 0.2 * H, 0); }
    return { flat: new Float32Array(pos), level: new Uint8Array(lev), idx: new Uint32Array(idx), zones: new Float32Array(zones) };
}
const flat = flatMesh();
function topologyFlat() {
    const vc = flat.level.length, ic = flat.idx.length;
    const head = 16 + 4 * ic + 5 * vc, pad = (4 - ((32 + head) & 3)) & 3;
    const b = Buffer.alloc(head + pad + 8 * vc + 16 * FL);
    b.writeUInt32LE(2, 0); b[4] = 0; b[5] = FL; b.writeUInt16LE(1, 6); b.writeUInt32LE(vc, 8); b.writeUInt32LE(ic, 12);
    Buffer.from(flat.idx.buffer).copy(b, 16);
    Buffer.from(flat.level.buffer).copy(b, 16 + 4 * ic + 4 * vc);
    Buffer.from(flat.flat.buffer).copy(b, head + pad);
    Buffer.from(flat.zones.buffer).copy(b, head + pad + 8 * vc);
    return b;
}
function record1(body, tag) {
    const r = record(body);
    r.writeUInt32LE(tag, 4);
    return r;
}
function frameCascade(cam, t, camSeq, tick, sub) {
    const codec = sub.codec === 0 ? 0 : 1, recs = [];
    const nc = Math.min(sub.layers || 3, CAS.length);
    for (let ci = 0; ci < nc; ci++) {
        const c = CAS[ci];
        for (let m = 0; m < c.mips; m++) {
            const side = c.n >> m, T = Math.min(sub.tileSize, side);
            for (let iz = 0; iz < side / T; iz++) for (let ix = 0; ix < side / T; ix++) recs.push(record1(cascadeTile(ci, m, ix, iz, T, t, codec), ci));
        }
    }
    const g2 = 4, ox = Math.round(cam.x / g2) * g2, oz = Math.round(cam.z / g2) * g2;
    const pl = Buffer.alloc(32);
    pl.writeUInt32LE(2, 0); pl.writeDoubleLE(ox, 8); pl.writeDoubleLE(0, 16); pl.writeDoubleLE(oz, 24);
    recs.push(record1(pl, 0));
    const blk = Buffer.alloc(56 + 320 * nc);
    blk[0] = nc; blk[1] = 8;
    blk.writeFloatLE(cam.q, 4);
    blk.writeDoubleLE(cam.x, 8); blk.writeDoubleLE(cam.y, 16); blk.writeDoubleLE(cam.z, 24);
    blk.writeFloatLE(0, 32); blk.writeFloatLE(0.01, 36);
    blk.writeFloatLE(0.008, 40); blk.writeFloatLE(0.006, 44); blk.writeFloatLE(0.001, 48);
    for (let ci = 0; ci < nc; ci++) {
        const c = CAS[ci], e = 56 + 320 * ci;
        blk.writeDoubleLE(c.P, e); blk.writeUInt16LE(c.n, e + 8); blk[e + 10] = c.mips; blk[e + 11] = c.fades;
        /* each cascade its own q (the finest at half the block's), as oceand
         * sends when the byte budget lets fine cascades refine */
        blk.writeFloatLE(ci === nc - 1 && nc > 1 ? cam.q / 2 : cam.q, e + 12);
        for (let m = 0; m <= c.mips; m++) {
            const kc = m === c.mips ? 0 : casKc(c, m), mss = casMss(c, m === c.mips ? 0 : kc);
            blk.writeFloatLE(kc, e + 16 + 16 * m);
            mss.forEach((v, k) => blk.writeFloatLE(v, e + 20 + 16 * m + 4 * k));
        }
    }
    const head = Buffer.alloc(56);
    head.writeDoubleLE(Infinity, 0); head.writeDoubleLE(0, 8);
    head.writeDoubleLE(ox, 16); head.writeDoubleLE(0, 24); head.writeDoubleLE(oz, 32);
    head.writeUInt32LE(camSeq, 40); head.writeUInt32LE(tick, 44); head.writeUInt16LE(recs.length - 1, 48); head[50] = 1; head[51] = 1;
    return Buffer.concat([head, blk, ...recs]);
}

function wsSend(sock, data) {
    const len = data.length;
    let h;
    if (len < 126) h = Buffer.from([0x82, len]);
    else if (len < 65536) { h = Buffer.alloc(4); h[0] = 0x82; h[1] = 126; h.writeUInt16BE(len, 2); }
    else { h = Buffer.alloc(10); h[0] = 0x82; h[1] = 127; h.writeBigUInt64BE(BigInt(len), 2); }
    sock.write(Buffer.concat([h, data]));
}

let nextId = 1;
const server = http.createServer((req, res) => {
    let p = decodeURIComponent(new URL(req.url, 'http://x').pathname);
    if (p === '/') p = '/index.html';
    const f = normalize(join(root, p));
    if (!f.startsWith(root) || !existsSync(f)) { res.writeHead(404); res.end('not found'); return; }
    res.writeHead(200, { 'content-type': MIME[extname(f)] || 'application/octet-stream' });
    res.end(readFileSync(f));
});
server.on('upgrade', (req, sock) => {
    const key = req.headers['sec-websocket-key'];
    const accept = crypto.createHash('sha1').update(key + '258EAFA5-E914-47DA-95CA-C5AB0DC85B11').digest('base64');
    sock.write(`HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Accept: ${accept}\r\nSec-WebSocket-Protocol: ocean.v1\r\n\r\n`);
    const id = nextId++;
    const t0 = Date.now();
    let seq = 0, tick = 0, sub = null, cam = { x: 0, y: 25, z: 0, q: 0.002 }, camSeq = 0xffffffff, timer = null, buf = Buffer.alloc(0);
    const simT = () => (Date.now() - t0) / 1000 + 100;
    wsSend(sock, msg(1, hello(id), ++seq, simT()));
    sock.on('data', (d) => {
        buf = Buffer.concat([buf, d]);
        while (buf.length >= 2) {
            let len = buf[1] & 0x7f, off = 2;
            if (len === 126) { len = buf.readUInt16BE(2); off = 4; } else if (len === 127) { len = Number(buf.readBigUInt64BE(2)); off = 10; }
            if (buf.length < off + 4 + len) break;
            const mask = buf.subarray(off, off + 4);
            const pl = Buffer.from(buf.subarray(off + 4, off + 4 + len));
            for (let i = 0; i < len; i++) pl[i] ^= mask[i & 3];
            const op = buf[0] & 15;
            buf = buf.subarray(off + 4 + len);
            if (op === 8) { sock.end(); return; }
            if (op !== 2 || pl.length < 32) continue;
            const type = pl.readUInt16LE(6);
            if (type === 2) {
                sub = { codec: pl[32 + 2], layers: pl[32 + 5], lodLevels: pl[32 + 6], layout: pl[32 + 7], tileSize: pl.readUInt16LE(32 + 8), rate: pl.readFloatLE(32 + 12) };
                wsSend(sock, msg(6, sub.layout === 1 ? topologyFlat() : topology(), ++seq, simT()));
                if (timer) clearInterval(timer);
                timer = setInterval(() => {
                    const t = simT();
                    wsSend(sock, msg(4, sub.layout === 1 ? frameCascade(cam, t, camSeq, ++tick, sub) : frame(cam, t, camSeq, ++tick, sub), ++seq, t));
                }, 1000 / Math.min(sub.rate, 15));
            } else if (type === 3) {
                /* q: one sample per pixel at the viewport's angular pixel size */
                const fov = pl.readFloatLE(32 + 48), vh = pl.readUInt16LE(32 + 54);
                cam = { x: pl.readDoubleLE(32), y: pl.readDoubleLE(40), z: pl.readDoubleLE(48), q: 2 * Math.tan(fov * Math.PI / 360) / Math.max(1, vh) };
                camSeq = pl.readUInt32LE(16);
            }
        }
    });
    const stop = () => { if (timer) clearInterval(timer); timer = null; };
    sock.on('close', stop);
    sock.on('error', stop);
});
server.listen(port, '127.0.0.1', () => console.log(`mock oceand on http://127.0.0.1:${port}/`));
