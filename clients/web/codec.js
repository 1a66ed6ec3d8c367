/*
 * codec.js - tile payload decoders for the browser: f32, f16 and qz
 * (quantised + least-squares spatial prediction + zstd; formats 1 and 2),
 * plus octahedral normals.
 * Mirrors protocol/codec.c (byte layouts in PROTOCOL.md).  The EXR codecs
 * are not decoded here; the viewer never subscribes with them.
 *
 * qz needs zstd: we vendor fzstd (MIT, ~24 KB, pure JS, no run-time fetch)
 * in vendor/fzstd.js because qz is the daemon's default and several times
 * smaller on the wire than f16 (the point of the codec: a remote viewer on
 * a real link), and a decoder that understands it keeps the viewer honest
 * against the default subscription.
 *
 * Decoders treat input as hostile, as the C ones do: sizes, headers and the
 * zstd frame are checked and non-finite results are refused; any failure
 * throws a ProtoError with code ECODEC.
 */
import { decompress } from './vendor/fzstd.js';
import { CODEC, CODEC_NAMES, MESH_QZ_HEAD, ProtoError, R, meshQzHeader, tilePlanes } from './protocol.js';

const QZ_FORMAT = 1;          /* format 1: fixed 24-byte plane headers, planar / LS6 */
const QZ2_FORMAT = 2;         /* format 2 (what oceand writes): LSX with a reference plane */
const QZ2_PLANE_HEAD = 12;    /* base f32, step f32, nbytes u8, predictor u8, ref u8, reserved u8 */
const QZ_PRED_LSX = 3;
const QZ_NOREF = 255;
/* LSX taps (di, dj): own causal 8 (written out in qz2Decode in this order:
 * (0,-1) (-1,0) (-1,-1) (-1,1) (0,-2) (-2,0) (-1,-2) (-2,-1)), then the reference plane's 9 */
const QZ_REF = [[0, 0], [0, -1], [0, 1], [-1, 0], [1, 0], [0, -2], [0, 2], [-2, 0], [2, 0]];
const QZ_HEAD = 4;            /* planes u8, format u8, reserved u16 */
const QZ_PLANE_HEAD = 24;     /* base f32, step f32, nbytes u8, predictor u8, reserved u16, coef i16[6] */
const QZ_PRED_PLANAR = 1;
const QZ_PRED_LS6 = 2;
const QZ_NCOEF = 6;
const QZ_Q_LIMIT = 2 ** 30;   /* keeps every predictor sum far below 2^53: exact in doubles */

function bad(msg) { throw new ProtoError(R.ECODEC, msg); }

/* binary16 -> float32 table (65536 entries, built once). */
const F16 = (() => {
    const t = new Float32Array(65536);
    for (let h = 0; h < 65536; h++) {
        const s = h & 0x8000 ? -1 : 1, e = (h >> 10) & 0x1f, m = h & 0x3ff;
        if (e === 0) t[h] = s * m * 2 ** -24;
        else if (e === 31) t[h] = m ? NaN : s * Infinity;
        else t[h] = s * (1 + m / 1024) * 2 ** (e - 15);
    }
    return t;
})();

export function f32FromF16(h) { return F16[h & 0xffff]; }

/* Decodes a tile payload for (codec, w, h, channels) into a new
 * Float32Array of planes * w * h samples, plane after plane (row = z).
 * Returns {planes, data}. */
export function decodeTile(codec, w, h, channels, payload) {
    const np = tilePlanes(channels);
    if (!np) bad(`bad channel mask 0x${channels.toString(16)}`);
    if (!(w >= 1 && h >= 1 && w <= 1024 && h <= 1024)) bad(`tile size ${w}x${h} outside 1..1024`);
    const n = w * h, total = n * np;
    const out = new Float32Array(total);
    const dv = new DataView(payload.buffer, payload.byteOffset, payload.byteLength);
    switch (codec) {
    case CODEC.F32:
        if (payload.byteLength !== total * 4) bad(`f32 payload is ${payload.byteLength} bytes, ${w}x${h} x ${np} planes needs ${total * 4}`);
        for (let i = 0; i < total; i++) {
            const f = dv.getFloat32(4 * i, true);
            if (!Number.isFinite(f)) bad(`f32 payload holds a non-finite value at sample ${i}`);
            out[i] = f;
        }
        break;
    case CODEC.F16:
        if (payload.byteLength !== total * 2) bad(`f16 payload is ${payload.byteLength} bytes, ${w}x${h} x ${np} planes needs ${total * 2}`);
        for (let i = 0; i < total; i++) {
            const f = F16[payload[2 * i] | (payload[2 * i + 1] << 8)];
            if (!Number.isFinite(f)) bad(`f16 payload holds a non-finite value at sample ${i}`);
            out[i] = f;
        }
        break;
    case CODEC.QZ:
        qzDecode(w, h, np, payload, dv, out);
        break;
    default:
        throw new ProtoError(R.EUNSUPPORTED, `codec ${CODEC_NAMES[codec] || codec} is not decoded by the web viewer`);
    }
    return { planes: np, data: out };
}

/* Scratch reused across calls (decoding is single-threaded per worker). */
let qScratch = new Float64Array(0);
let rScratch = new Int32Array(0);

function qzDecode(w, h, np, data, dv, out) {
    if (data.byteLength >= 2 && data[1] === QZ2_FORMAT) return qz2Decode(w, h, np, data, dv, out);
    const len = data.byteLength;
    const headlen = QZ_HEAD + QZ_PLANE_HEAD * np + 4;
    if (len < headlen) bad(`qz payload of ${len} bytes shorter than its ${headlen}-byte header`);
    if (data[0] !== np) bad(`qz header says ${data[0]} planes, tile has ${np}`);
    if (data[1] !== QZ_FORMAT || dv.getUint16(2, true) !== 0)
        bad(`qz format ${data[1]} / reserved ${dv.getUint16(2, true)} not supported`);
    const n = w * h;
    const base = [], step = [], nb = [], pred = [], coefs = [];
    let want = 0;
    for (let c = 0; c < np; c++) {
        const o = QZ_HEAD + QZ_PLANE_HEAD * c;
        const b = dv.getFloat32(o, true), s = dv.getFloat32(o + 4, true), k = data[o + 8], p = data[o + 9];
        const coef = new Float64Array(QZ_NCOEF);
        let nonzero = false;
        for (let i = 0; i < QZ_NCOEF; i++) {
            coef[i] = dv.getInt16(o + 12 + 2 * i, true);
            if (coef[i] !== 0) nonzero = true;
        }
        if (!Number.isFinite(b) || !Number.isFinite(s) || !(s > 0) || k > 4 || dv.getUint16(o + 10, true) !== 0 ||
            (p !== QZ_PRED_PLANAR && p !== QZ_PRED_LS6) || (p === QZ_PRED_PLANAR && nonzero))
            bad(`qz plane ${c} header invalid (base ${b}, step ${s}, bytes ${k}, predictor ${p})`);
        base.push(b); step.push(s); nb.push(k); pred.push(p); coefs.push(coef);
        want += k * n;
    }
    const rawlen = dv.getUint32(headlen - 4, true);
    if (rawlen !== want) bad(`qz residual length ${rawlen}, header implies ${want}`);
    const zsrc = data.subarray(headlen);
    /* fzstd validates the frame and block structure and allocates exactly
     * the content size; we insist on exactly `want` bytes of output (a
     * frame that says otherwise, or extra frames, change the length). */
    const raw = inflate(zsrc, want);
    if (qScratch.length < n) { qScratch = new Float64Array(n); rScratch = new Int32Array(n); }
    const q = qScratch, res = rScratch;
    let off = 0;
    for (let c = 0; c < np; c++) {
        const k = nb[c], bs = base[c], st = step[c], ls6 = pred[c] === QZ_PRED_LS6;
        const [c0, c1, c2, c3, c4, c5] = coefs[c];
        const dst = c * n;
        /* residuals: k little-endian byte planes, zigzag-decoded */
        residuals(raw, off, k, n, res);
        off += k * n;
        /* prediction, in the order the encoder used (row by row) */
        let lo = 0, hi = 0;
        for (let i = 0; i < h; i++) {
            const row = i * w;
            for (let j = 0; j < w; j++) {
                const idx = row + j;
                let p;
                if (i === 0) p = j === 0 ? 0 : q[idx - 1];
                else if (j === 0) p = q[idx - w];
                else if (ls6 && i >= 2 && j >= 2 && j + 1 < w)
                    p = Math.floor((c0 * q[idx - 1] + c1 * q[idx - w] + c2 * q[idx - w - 1] + c3 * q[idx - w + 1] +
                                    c4 * q[idx - 2] + c5 * q[idx - 2 * w] + 2048) / 4096);
                else p = q[idx - 1] + q[idx - w] - q[idx - w - 1];
                const v = p + res[idx];
                if (v > QZ_Q_LIMIT || v < -QZ_Q_LIMIT) bad(`qz plane ${c}: level ${v} out of range at (${i},${j})`);
                q[idx] = v;
                if (v < lo) lo = v; else if (v > hi) hi = v;
            }
        }
        /* values: base + q * step; finite unless the plane's extremes overflow */
        if (!Number.isFinite(Math.fround(bs + lo * st)) || !Number.isFinite(Math.fround(bs + hi * st)))
            bad(`qz plane ${c}: non-finite values (base ${bs}, step ${st}, levels ${lo}..${hi})`);
        for (let i = 0; i < n; i++) out[dst + i] = bs + q[i] * st;   /* Float32Array store rounds as (float) */
    }
}

/* A qz residual stream: exactly one zstd frame of `want` bytes.  fzstd
 * validates the frame and block structure and allocates exactly the
 * content size; a frame that says otherwise, or extra frames, change the
 * length. */
function inflate(zsrc, want) {
    let raw;
    try { raw = decompress(zsrc); } catch (e) { bad(`qz: zstd: ${e.message || e}`); }
    if (raw.length !== want) bad(`qz: zstd frame content size ${raw.length} does not match ${want}`);
    return raw;
}

/* Residual stream: for plane c, nb little-endian byte planes -> res (zigzag-decoded). */
function residuals(raw, off, k, n, res) {
    if (k === 0) res.fill(0, 0, n);
    else if (k === 1) for (let i = 0; i < n; i++) { const z = raw[off + i]; res[i] = (z >>> 1) ^ -(z & 1); }
    else if (k === 2) for (let i = 0; i < n; i++) { const z = raw[off + i] | (raw[off + n + i] << 8); res[i] = (z >>> 1) ^ -(z & 1); }
    else if (k === 3) for (let i = 0; i < n; i++) { const z = raw[off + i] | (raw[off + n + i] << 8) | (raw[off + 2 * n + i] << 16); res[i] = (z >>> 1) ^ -(z & 1); }
    else for (let i = 0; i < n; i++) { const z = (raw[off + i] | (raw[off + n + i] << 8) | (raw[off + 2 * n + i] << 16) | (raw[off + 3 * n + i] << 24)) >>> 0; res[i] = (z >>> 1) ^ -(z & 1); }
}

let q2Scratch = new Float64Array(0);

/* qz format 2 (PROTOCOL.md "qz"): variable plane headers; LSX = 8 causal
 * taps plus, with a reference plane, 9 taps of that (already decoded)
 * plane with coordinates clamped into the tile.  Sums stay below 2^50:
 * exact in doubles, as the C decoder's int64. */
function qz2Decode(w, h, np, data, dv, out) {
    const len = data.byteLength;
    if (len < QZ_HEAD + 4) bad(`qz payload of ${len} bytes shorter than its header`);
    if (data[0] !== np) bad(`qz header says ${data[0]} planes, tile has ${np}`);
    if (dv.getUint16(2, true) !== 0) bad(`qz format 2 reserved ${dv.getUint16(2, true)} not 0`);
    const n = w * h;
    const base = [], step = [], nb = [], pred = [], refs = [], coefs = [];
    let want = 0, off = QZ_HEAD;
    for (let c = 0; c < np; c++) {
        if (len - off < QZ2_PLANE_HEAD + 4) bad(`qz payload of ${len} bytes ends inside plane ${c}'s header`);
        const b = dv.getFloat32(off, true), s = dv.getFloat32(off + 4, true), k = data[off + 8], p = data[off + 9], r = data[off + 10];
        const nt = p === QZ_PRED_LSX ? (r === QZ_NOREF ? 8 : 17) : 0;
        if (!Number.isFinite(b) || !Number.isFinite(s) || !(s > 0) || k > 4 || data[off + 11] !== 0 ||
            (p !== QZ_PRED_PLANAR && p !== QZ_PRED_LSX) || (p === QZ_PRED_PLANAR && r !== QZ_NOREF) || (r !== QZ_NOREF && r >= c))
            bad(`qz plane ${c} header invalid (base ${b}, step ${s}, bytes ${k}, predictor ${p}, ref ${r})`);
        if (len - off - QZ2_PLANE_HEAD < 2 * nt + 4) bad(`qz payload of ${len} bytes ends inside plane ${c}'s weights`);
        const coef = new Float64Array(nt);
        for (let i = 0; i < nt; i++) coef[i] = dv.getInt16(off + QZ2_PLANE_HEAD + 2 * i, true);
        off += QZ2_PLANE_HEAD + 2 * nt;
        base.push(b); step.push(s); nb.push(k); pred.push(p); refs.push(r); coefs.push(coef);
        want += k * n;
    }
    const rawlen = dv.getUint32(off, true);
    off += 4;
    if (rawlen !== want) bad(`qz residual length ${rawlen}, header implies ${want}`);
    const raw = inflate(data.subarray(off), want);
    if (q2Scratch.length < n * np) q2Scratch = new Float64Array(n * np);
    if (rScratch.length < n) rScratch = new Int32Array(n);
    const qa = q2Scratch, res = rScratch;
    let ro = 0;
    for (let c = 0; c < np; c++) {
        const k = nb[c], bs = base[c], st = step[c], lsx = pred[c] === QZ_PRED_LSX, cf = coefs[c];
        const qo = c * n, ref = refs[c] === QZ_NOREF ? -1 : refs[c] * n;
        residuals(raw, ro, k, n, res);
        ro += k * n;
        let lo = 0, hi = 0;
        for (let i = 0; i < h; i++) {
            for (let j = 0; j < w; j++) {
                const idx = qo + i * w + j;
                let p;
                if (i === 0) p = j === 0 ? 0 : qa[idx - 1];
                else if (j === 0) p = qa[idx - w];
                else if (lsx && i >= 2 && j >= 2 && j + 1 < w) {
                    let s = cf[0] * qa[idx - 1] + cf[1] * qa[idx - w] + cf[2] * qa[idx - w - 1] + cf[3] * qa[idx - w + 1] +
                            cf[4] * qa[idx - 2] + cf[5] * qa[idx - 2 * w] + cf[6] * qa[idx - w - 2] + cf[7] * qa[idx - 2 * w - 1];
                    if (ref >= 0) {
                        if (i + 2 < h && j + 2 < w) {
                            /* away from the edges the clamp does not bite */
                            const r = ref + i * w + j;
                            s += cf[8] * qa[r] + cf[9] * qa[r - 1] + cf[10] * qa[r + 1] + cf[11] * qa[r - w] + cf[12] * qa[r + w] +
                                 cf[13] * qa[r - 2] + cf[14] * qa[r + 2] + cf[15] * qa[r - 2 * w] + cf[16] * qa[r + 2 * w];
                        } else {
                            for (let t = 0; t < 9; t++) {
                                const ii = Math.min(Math.max(i + QZ_REF[t][0], 0), h - 1), jj = Math.min(Math.max(j + QZ_REF[t][1], 0), w - 1);
                                s += cf[8 + t] * qa[ref + ii * w + jj];
                            }
                        }
                    }
                    p = Math.floor((s + 2048) / 4096);
                } else p = qa[idx - 1] + qa[idx - w] - qa[idx - w - 1];
                const v = p + res[i * w + j];
                if (v > QZ_Q_LIMIT || v < -QZ_Q_LIMIT) bad(`qz plane ${c}: level ${v} out of range at (${i},${j})`);
                qa[idx] = v;
                if (v < lo) lo = v; else if (v > hi) hi = v;
            }
        }
        if (!Number.isFinite(Math.fround(bs + lo * st)) || !Number.isFinite(Math.fround(bs + hi * st)))
            bad(`qz plane ${c}: non-finite values (base ${bs}, step ${st}, levels ${lo}..${hi})`);
        for (let i = 0; i < n; i++) out[qo + i] = bs + qa[qo + i] * st;
    }
}

/* Octahedral unit normal (y up) -> [nx, ny, nz], as proto_normal_oct_decode. */
export function octDecode(u, v, out = [0, 0, 0]) {
    let x = u, z = v;
    const y = 1 - Math.abs(u) - Math.abs(v);
    if (y < 0) {
        const ox = (1 - Math.abs(z)) * (x >= 0 ? 1 : -1);
        const oz = (1 - Math.abs(x)) * (z >= 0 ? 1 : -1);
        x = ox; z = oz;
    }
    const l = Math.hypot(x, y, z);
    if (!(l > 0)) { out[0] = 0; out[1] = 1; out[2] = 0; return out; }
    out[0] = x / l; out[1] = y / l; out[2] = z / l;
    return out;
}

/* ---- MESH_VERTICES_QZ (PROTOCOL.md; protocol/codec.c proto_mesh_qz_*) ---- */

const MESH_QZ_NONE = 0xffffffff;

/* The prediction references of a topology (indices: Uint32Array, every
 * index < vertexCount, checked by the MESH_TOPOLOGY decoder): per vertex v
 * (a, b, c) for the parallelogram a + b - c, (a, b, NONE) for the floor of
 * their mean, (NONE, NONE, NONE) for the previous vertex; the rule of
 * proto_mesh_qz_refs, so both sides predict alike. */
export function meshQzRefs(indices, vertexCount) {
    const ni = indices.length, start = new Uint32Array(vertexCount + 1), tri = new Uint32Array(ni);
    for (let i = 0; i < ni; i++) start[indices[i] + 1]++;
    for (let v = 0; v < vertexCount; v++) start[v + 1] += start[v];
    const fill = start.slice();
    for (let i = 0; i < ni; i++) tri[fill[indices[i]]++] = (i / 3) | 0;
    const refs = new Uint32Array(3 * vertexCount).fill(MESH_QZ_NONE);
    for (let v = 0; v < vertexCount; v++) {
        const r = 3 * v;
        for (let k = start[v]; k < start[v + 1] && refs[r + 2] === MESH_QZ_NONE; k++) {
            const t = 3 * tri[k], t0 = indices[t], t1 = indices[t + 1], t2 = indices[t + 2];
            let a, b;
            if (t0 === v) { a = t1; b = t2; } else if (t1 === v) { a = t2; b = t0; } else { a = t0; b = t1; }
            if (a >= v || b >= v || a === b) continue;
            if (refs[r] === MESH_QZ_NONE) { refs[r] = a; refs[r + 1] = b; }
            for (let m = start[a]; m < start[a + 1]; m++) {
                if (tri[m] === tri[k]) continue;
                const u = 3 * tri[m], u0 = indices[u], u1 = indices[u + 1], u2 = indices[u + 2];
                const hasB = u0 === b || u1 === b || u2 === b;
                const c = u0 !== a && u0 !== b ? u0 : u1 !== a && u1 !== b ? u1 : u2;
                if (hasB && c !== a && c !== b && c < v) {
                    refs[r] = a; refs[r + 1] = b; refs[r + 2] = c;
                    break;
                }
            }
        }
    }
    return refs;
}

/* Decodes a has_mesh 2 record's payload (Uint8Array from its format byte)
 * for vertexCount vertices with the refs of its topology into a new
 * Float32Array of x, y, z per vertex.  Throws ECODEC (as the C decoder). */
export function decodeMeshQz(data, vertexCount, refs) {
    const h = meshQzHeader(data, vertexCount);
    if (refs.length !== 3 * vertexCount) bad(`mesh qz: topology of ${refs.length / 3} vertices, record has ${vertexCount}`);
    const raw = inflate(data.subarray(MESH_QZ_HEAD), h.rawLen);
    const n = vertexCount, q = new Float64Array(3 * n), res = new Int32Array(n), out = new Float32Array(3 * n);
    let ro = 0;
    for (let a = 0; a < 3; a++) {
        residuals(raw, ro, h.nbytes[a], n, res);
        ro += h.nbytes[a] * n;
        const bs = h.base[a], st = h.step[a];
        for (let v = 0; v < n; v++) {
            const r = 3 * v, ra = refs[r], rb = refs[r + 1], rc = refs[r + 2];
            let p;
            if (rc !== MESH_QZ_NONE) p = q[3 * ra + a] + q[3 * rb + a] - q[3 * rc + a];
            else if (ra !== MESH_QZ_NONE) p = Math.floor((q[3 * ra + a] + q[3 * rb + a]) / 2);
            else p = v ? q[3 * (v - 1) + a] : 0;
            const lv = p + res[v];
            if (!(Math.abs(lv) <= QZ_Q_LIMIT)) bad(`mesh qz axis ${'xyz'[a]}: level ${lv} out of range at vertex ${v}`);
            q[r + a] = lv;
            const f = Math.fround(bs + lv * st);
            if (!(Math.abs(f) <= 1e7)) bad(`mesh qz axis ${'xyz'[a]}: position ${f} at vertex ${v} (finite, |.| <= 1e7)`);
            out[r + a] = f;
        }
    }
    return out;
}
