/*
 * protocol.test.mjs - cross-checks the web viewer's JavaScript protocol code
 * (clients/web/protocol.js) and its decoders (clients/web/codec.js: the C
 * codecs compiled to WebAssembly) against the native C implementation in
 * protocol/, through tests/browser/gen_vectors.c:
 *
 *  - messages encoded in C decode in JS to the same fields, and tiles
 *    (qz, f16, f32) decode in WebAssembly to the same float32 samples, bit
 *    for bit;
 *  - messages encoded in JS (SUBSCRIBE, CAMERA, QUERY, BYE) decode in C to
 *    the same fields;
 *  - hostile input: thousands of truncated and byte-flipped variants of the
 *    vectors are decoded by both; both must accept or refuse each one alike
 *    and, when refusing, report the same ocean_result code;
 *  - corrupt qz payloads are refused with ECODEC, never decoded to junk;
 *  - the committed qz payload vectors (tests/vectors/codec, formats 2 and 1)
 *    decode to their committed samples bit for bit, as the C decoder's;
 *  - the protocol's own vectors (tests/vectors, PROTO_VECTORS) decode to
 *    their stated fields, bad ones get their stated code, and the messages
 *    the viewer sends re-encode to identical bytes;
 *  - the stream of tests/vectors/held (PROTOCOL.md "Samples in time")
 *    through the viewer's HeldStore, whole and split into shards as the
 *    decode pool splits it, blends to the committed tiles bit for bit.
 *
 * Run by tests/test_browser.sh with VECTOR_DIR (output of `gen_vectors gen`)
 * and GEN_VECTORS (the helper binary) set.  node --test.
 */
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync, writeFileSync, mkdtempSync, rmSync, readdirSync } from 'node:fs';
import { execFileSync } from 'node:child_process';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

import {
    decode, encodeSubscribe, encodeCamera, encodeQuery, encodeBye, encodeSeaState, ProtoError, R, T, CODEC, FX, tilePlanes,
    LAYOUT, MIP_ENTRIES, TOPO_FLAT, zstdFrameSizes, SUB_FLAG,
} from '../../clients/web/protocol.js';
import { decodeTile, decodeCascadeBlock, octNormals, decodeMeshQz, meshQzRefs, HeldStore, WakeStore } from '../../clients/web/codec.js';

const dir = process.env.VECTOR_DIR;
const gen = process.env.GEN_VECTORS;
if (!dir || !gen) throw new Error('VECTOR_DIR and GEN_VECTORS must be set (see tests/test_browser.sh)');
const expected = JSON.parse(readFileSync(join(dir, 'expected.json'), 'utf8'));
const vec = (name) => new Uint8Array(readFileSync(join(dir, `${name}.bin`)));

/* Runs the C decoder over a list of byte arrays; returns its JSON lines. */
function cDecode(buffers) {
    const tmp = mkdtempSync(join(tmpdir(), 'ocean-vec-'));
    try {
        const files = buffers.map((b, i) => {
            const f = join(tmp, `m${i}.bin`);
            writeFileSync(f, b);
            return f;
        });
        const out = [];
        /* keep argv modest */
        for (let i = 0; i < files.length; i += 500) {
            const text = execFileSync(gen, ['decode', ...files.slice(i, i + 500)], { encoding: 'utf8', maxBuffer: 64 << 20 });
            out.push(...text.trim().split('\n').map((l) => JSON.parse(l)));
        }
        return out;
    } finally {
        rmSync(tmp, { recursive: true, force: true });
    }
}

function jsCode(bytes) {
    try {
        decode(bytes);
        return 0;
    } catch (e) {
        if (!(e instanceof ProtoError)) throw e;   /* anything else is a bug */
        return e.code;
    }
}

test('HELLO from C decodes with every field', () => {
    const m = decode(vec('hello'));
    const e = expected.hello;
    assert.equal(m.type, T.HELLO);
    assert.equal(m.hdr.seq, e.seq);
    assert.equal(m.hdr.simTime, e.simTime);
    assert.equal(m.body.codecs, e.codecs);
    assert.equal(m.body.clientId, e.clientId);
    assert.equal(m.body.sea.seed.toString(), e.seed);
    assert.equal(m.body.sea.windU10, e.windU10);
    assert.equal(m.body.sea.tp, e.tp);
    assert.equal(m.body.tickRateHz, e.tickRateHz);
    assert.equal(m.body.serverVersion, e.serverVersion);
});

test('FRAME from C: header, mesh and tiles decode; tile samples equal the C decoder bit for bit', () => {
    const m = decode(vec('frame'));
    const e = expected.frame;
    const f = m.body;
    assert.equal(m.type, T.FRAME);
    assert.equal(f.cutoffK, Infinity);
    assert.equal(f.eError, e.eError);
    assert.equal(f.cameraSeq, e.cameraSeq);
    assert.equal(f.tick, e.tick);
    assert.equal(m.hdr.simTime, e.simTime);
    assert.equal(f.mesh.meshId, e.meshId);
    assert.deepEqual(Array.from(f.mesh.positions), e.positions);
    assert.equal(f.tiles.length, e.tiles.length);
    const seen = new Set();
    f.tiles.forEach((t, i) => {
        const x = e.tiles[i];
        for (const k of ['codec', 'channels', 'width', 'height', 'ix', 'iz', 'originX', 'originZ', 'spacing', 'payloadLen'])
            assert.equal(t[k], x[k], `tile ${i} ${k}`);
        assert.equal(t.errorBound, Math.fround(x.errorBound));
        const d = decodeTile(t.codec, t.width, t.height, t.channels, t.payload);
        assert.equal(d.planes, tilePlanes(t.channels));
        assert.equal(d.data.length, x.decoded.length);
        for (let k = 0; k < d.data.length; k++)
            assert.equal(d.data[k], Math.fround(x.decoded[k]), `tile ${i} sample ${k}`);
        seen.add(t.codec);
    });
    assert.deepEqual([...seen].sort(), [CODEC.F32, CODEC.F16, CODEC.QZ].sort());
    /* the qz tile is format 2 and must exercise the LSX predictor (3) with
     * the H plane as reference, so the C and JS reference paths are compared */
    const qz = f.tiles.find((t) => t.codec === CODEC.QZ);
    assert.equal(qz.payload[1], 2, 'qz format');
    const preds = new Set(), refs = new Set();
    for (let c = 0, o = 4; c < qz.payload[0]; c++) {
        const p = qz.payload[o + 9], r = qz.payload[o + 10];
        preds.add(p); refs.add(r);
        o += 12 + (p === 3 ? 2 * (r === 255 ? 8 : 17) : 0);
    }
    assert.ok(preds.has(3), `qz predictors used: ${[...preds]}`);
    assert.ok(refs.has(0), `qz reference planes used: ${[...refs]}`);
    /* and a format-1 payload (recordings before format 2) decoded alike above */
    assert.ok(f.tiles.some((t) => t.codec === CODEC.QZ && t.payload[1] === 1), 'a qz format 1 tile');
});

test('zstd frames from libzstd: the JS frame walk gives libzstd\'s content size and length, and refuses every cut and any junk', () => {
    const frames = expected.zstd_frames;
    assert.ok(frames.length >= 5);
    const seen = { fcs: new Set(), checksum: 0, window: 0, blocks: 0, rle: 0 };
    for (const z of frames) {
        const u8 = Uint8Array.from(z.hex.match(/../g).map((h) => parseInt(h, 16)));
        assert.equal(u8.length, z.frameLength);
        assert.deepEqual(zstdFrameSizes(u8), { contentSize: z.contentSize, frameLength: z.frameLength });
        /* zstd's WebAssembly decoder (vendor/zstd.wasm) reads each as one
         * qz residual stream: a 1x1 single-plane tile whose nbytes makes R
         * the frame's content size is out of reach, so the frame goes in
         * a planar qz payload of w x 1 samples, one byte plane */
        if (z.contentSize <= 1024) {
            const p = new Uint8Array(4 + 12 + 4 + u8.length);
            const dv = new DataView(p.buffer);
            p.set([1, 2, 0, 0]);
            dv.setFloat32(4, 0, true); dv.setFloat32(8, 1, true);
            p.set([1, 1, 255, 0], 12);
            dv.setUint32(16, z.contentSize, true);
            p.set(u8, 20);
            let ok = true;
            try { decodeTile(CODEC.QZ, z.contentSize, 1, 1, p); } catch (e) { ok = e.code !== R.ECODEC || !/zstd/.test(e.message); }
            assert.ok(ok, `zstd frame of ${z.contentSize} bytes refused by the WebAssembly decoder`);
        }
        /* what the header forms cover (the descriptor byte: RFC 8878 3.1.1.1.1) */
        const d = z.descriptor, single = (d >> 5) & 1;
        seen.fcs.add([single ? 1 : 0, 2, 4, 8][d >> 6]);
        seen.checksum += (d >> 2) & 1;
        seen.window += single ? 0 : 1;
        let off = 5 + (single ? 0 : 1) + [0, 1, 2, 4][d & 3] + [single ? 1 : 0, 2, 4, 8][d >> 6], nb = 0;
        for (let last = 0; !last; nb++) {
            const bh = u8[off] | (u8[off + 1] << 8) | (u8[off + 2] << 16), type = (bh >> 1) & 3;
            seen.rle += type === 1;
            last = bh & 1;
            off += 3 + (type === 1 ? 1 : bh >>> 3);
        }
        seen.blocks = Math.max(seen.blocks, nb);
        /* cut anywhere: not a whole frame; junk behind it: a longer input, the same frame */
        const step = Math.max(1, Math.floor(u8.length / 4000));
        for (let cut = 0; cut < u8.length; cut += step)
            assert.equal(zstdFrameSizes(u8.subarray(0, cut)), null, `cut at ${cut} of ${u8.length}`);
        const longer = new Uint8Array(u8.length + 3);
        longer.set(u8);
        assert.equal(zstdFrameSizes(longer).frameLength, z.frameLength);
    }
    assert.deepEqual([...seen.fcs].sort(), [1, 2, 4]);
    assert.ok(seen.checksum > 0 && seen.window > 0 && seen.rle > 0 && seen.blocks > 1, JSON.stringify({ ...seen, fcs: [...seen.fcs] }));
});

test('layout-0 FRAME with qz mesh positions from C: refs and positions equal the C decoder bit for bit', () => {
    const e = expected.frame_mesh_qz;
    const t = decode(vec('topology_mesh_qz')).body;
    const m = decode(vec('frame_mesh_qz'));
    const f = m.body;
    assert.equal(f.hasMesh, 2);
    assert.equal(f.layout, LAYOUT.WORLD);
    assert.equal(f.mesh.meshId, e.meshId);
    assert.equal(f.mesh.vertexCount, e.vertexCount);
    assert.equal(f.mesh.qz.length, e.qzLen);
    assert.equal(f.mesh.positions, null);
    /* every prediction rule occurs: parallelogram, midpoint, previous vertex */
    assert.ok(e.refKinds.every((n) => n > 0), `ref kinds ${e.refKinds}`);
    const refs = meshQzRefs(t.indices, t.vertexCount);
    assert.deepEqual(Array.from(refs), e.refs);
    const pos = decodeMeshQz(f.mesh.qz, f.mesh.vertexCount, refs);
    assert.equal(pos.length, e.positions.length);
    for (let i = 0; i < pos.length; i++) assert.equal(pos[i], Math.fround(e.positions[i]), `component ${i}`);
    /* within the stated bound of the input: half the axis step + f32 rounding */
    const h = f.mesh.qzHeader;
    for (let i = 0; i < pos.length; i++) {
        const a = i % 3, x = Math.fround(e.input[i]);
        assert.ok(Math.abs(pos[i] - x) <= 0.5 * h.step[a] + Math.abs(x) * 2 ** -24, `component ${i}: ${pos[i]} vs ${x}`);
    }
    /* hostile payloads: refused with ECODEC or decoded to finite positions, never anything else */
    const rand = rng(77);
    let refused = 0;
    for (let k = 0; k < 300; k++) {
        const b = f.mesh.qz.slice();
        const i = Math.floor(rand() * b.length);
        b[i] = [0, 0xff, 0x80, b[i] ^ (1 << Math.floor(rand() * 8))][Math.floor(rand() * 4)];
        const cut = k % 10 === 0 ? b.subarray(0, Math.floor(rand() * b.length)) : b;
        try {
            const p = decodeMeshQz(cut, f.mesh.vertexCount, refs);
            assert.ok(p.every((x) => Math.abs(x) <= 1e7));
        } catch (err) {
            assert.ok(err instanceof ProtoError && err.code === R.ECODEC, String(err));
            refused++;
        }
    }
    assert.ok(refused > 0);
    assert.throws(() => decodeMeshQz(f.mesh.qz, f.mesh.vertexCount - 1, refs), (err) => err.code === R.ECODEC);
});

test('layout-1 FRAME from C: cascade block, mip tables, tags, placement; tiles bit for bit', () => {
    const m = decode(vec('frame_cascade'));
    const e = expected.frame_cascade;
    const f = m.body;
    assert.equal(f.layout, LAYOUT.CASCADE);
    assert.equal(f.cameraSeq, e.cameraSeq);
    assert.equal(f.mesh, null);
    assert.equal(f.placement.meshId, e.meshId);
    assert.deepEqual(f.placement.origin, e.placement);
    const b = f.cascades;
    assert.equal(b.cascadeCount, e.cascadeCount);
    assert.equal(b.order, e.order);
    assert.equal(b.spacingPerM, Math.fround(e.spacingPerM));
    assert.deepEqual(b.camera, e.camera);
    assert.equal(b.minSpacingM, Math.fround(e.minSpacingM));
    assert.equal(b.eTotal, Math.fround(e.eTotal));
    assert.deepEqual(b.tailMss, e.tailMss.map(Math.fround));
    assert.equal(b.geometrySpacingM, Math.fround(e.geometrySpacingM));
    assert.equal(b.cascade.length, e.cascades.length);
    b.cascade.forEach((c, i) => {
        const x = e.cascades[i];
        for (const k of ['patchM', 'n', 'mips', 'fades']) assert.equal(c[k], x[k], `cascade ${i} ${k}`);
        assert.equal(c.spacingPerM, Math.fround(x.spacingPerM), `cascade ${i} spacingPerM`);
        assert.equal(c.mip.length, 4 * MIP_ENTRIES);
        for (let k = 0; k < 4 * MIP_ENTRIES; k++)
            assert.equal(c.mip[k], x.mip[k] === 'inf' ? Infinity : Math.fround(x.mip[k]), `cascade ${i} mip word ${k}`);
    });
    assert.equal(f.tiles.length, e.tiles.length);
    f.tiles.forEach((t, i) => {
        const x = e.tiles[i];
        for (const k of ['cascade', 'level', 'ix', 'iz', 'originX', 'originZ', 'spacing']) assert.equal(t[k], x[k], `tile ${i} ${k}`);
        const d = decodeTile(t.codec, t.width, t.height, t.channels, t.payload);
        for (let k = 0; k < d.data.length; k++) assert.equal(d.data[k], Math.fround(x.decoded[k]), `tile ${i} sample ${k}`);
    });
    assert.ok(new Set(f.tiles.map((t) => t.cascade)).size === 2, 'both cascade tags seen');
});

test('FLAT MESH_TOPOLOGY from C: flat positions and level zones', () => {
    const t = decode(vec('topology_flat')).body;
    const e = expected.topology_flat;
    assert.equal(t.meshId, e.meshId);
    assert.equal(t.flags, TOPO_FLAT);
    assert.equal(t.lodLevels, e.lodLevels);
    assert.deepEqual(Array.from(t.level), e.level);
    assert.deepEqual(Array.from(t.flat), e.flat);
    assert.deepEqual(Array.from(t.zones), e.zones);
    /* without FLAT there are no flat arrays */
    const p = decode(vec('topology')).body;
    assert.equal(p.flags, 0);
    assert.equal(p.flat, null);
});

test('MESH_TOPOLOGY, QUERY_RESULT, SEA_STATE, ERROR, BYE from C decode', () => {
    const t = decode(vec('topology')).body;
    assert.equal(t.meshId, expected.topology.meshId);
    assert.deepEqual(Array.from(t.indices), expected.topology.indices);
    assert.deepEqual(Array.from(t.morph), expected.topology.morph);
    assert.deepEqual(Array.from(t.level), expected.topology.level);
    const r = decode(vec('result')).body;
    assert.equal(r.queryId, expected.result.queryId);
    assert.equal(r.t, expected.result.t);
    assert.equal(r.samples[1].height, expected.result.height1);
    assert.equal(r.samples[0].foam, expected.result.foam0);
    const s = decode(vec('sea')).body;
    assert.equal(s.effectiveTime, expected.sea.effectiveTime);
    assert.equal(s.sea.windDirDeg, expected.sea.windDirDeg);
    const er = decode(vec('error')).body;
    assert.deepEqual({ code: er.code, offendingType: er.offendingType, offendingSeq: er.offendingSeq, message: er.message }, expected.error);
    const b = decode(vec('bye')).body;
    assert.deepEqual({ reason: b.reason, message: b.message }, expected.bye);
});

test('SUBSCRIBE, CAMERA, QUERY, BYE encoded in JS decode in C to the same fields', () => {
    const sub = {
        effects: FX.ALL, meshKind: 0, codec: CODEC.QZ, cutoffPolicy: 2, mode: 0, layers: 3, lodLevels: 6,
        tileSize: 64, frameRateHz: 30, accuracy: 1e-3, baseSpacingM: 0.5, viewRangeM: 20000,
    };
    const cam = {
        pos: [1234567.890625, 31.5, -98765.4321], vel: [250, -1.5, 3.25], yawDeg: -123.4, pitchDeg: -12.5,
        rollDeg: 3, fovYDeg: 55, viewportW: 1920, viewportH: 1080, renderTime: 0,
    };
    const pts = [1e6 + 0.125, -3.5, 42, 1e9];
    const sub1 = { ...sub, layout: LAYOUT.CASCADE, lodLevels: 1, baseSpacingM: 0, meshCodec: 2, flags: SUB_FLAG.FULL_GEOMETRY };
    const [cs, cc, cq, cb, cs1] = cDecode([
        new Uint8Array(encodeSubscribe(sub, 7, 1.5)), new Uint8Array(encodeCamera(cam, 8, 2.5)),
        new Uint8Array(encodeQuery(99, pts, 12.75, 9, 3.5)), new Uint8Array(encodeBye(0, 'viewer closed ✓', 10, 4.5)),
        new Uint8Array(encodeSubscribe(sub1, 11, 5.5)),
    ]);
    assert.equal(cs1.code, 0, cs1.err);
    assert.equal(cs1.layout, LAYOUT.CASCADE);
    assert.equal(cs1.lodLevels, 1);
    assert.equal(cs.layout, LAYOUT.WORLD, 'layout defaults to 0');
    assert.equal(cs.meshCodec, 0, 'mesh_codec defaults to f32');
    assert.equal(cs1.meshCodec, 2, 'mesh_codec qz');
    assert.equal(cs.flags, 0, 'flags default to 0');
    assert.equal(cs1.flags, SUB_FLAG.FULL_GEOMETRY, 'flags: full geometry');
    assert.equal(cs.code, 0, cs.err);
    assert.equal(cs.type, T.SUBSCRIBE);
    assert.equal(cs.seq, 7);
    assert.equal(cs.simTime, 1.5);
    for (const k of ['effects', 'meshKind', 'codec', 'cutoffPolicy', 'mode', 'layers', 'lodLevels', 'tileSize'])
        assert.equal(cs[k], sub[k], k);
    for (const k of ['frameRateHz', 'accuracy', 'baseSpacingM', 'viewRangeM'])
        assert.equal(Math.fround(cs[k]), Math.fround(sub[k]), k);   /* C prints 9 digits: exact for float32 */
    assert.equal(cc.code, 0, cc.err);
    assert.deepEqual(cc.pos, cam.pos);
    assert.deepEqual(cc.vel.map(Math.fround), cam.vel.map(Math.fround));
    for (const k of ['yawDeg', 'pitchDeg', 'rollDeg', 'fovYDeg']) assert.equal(Math.fround(cc[k]), Math.fround(cam[k]), k);
    assert.equal(cc.viewportW, 1920);
    assert.equal(cc.viewportH, 1080);
    assert.equal(cq.code, 0, cq.err);
    assert.equal(cq.queryId, 99);
    assert.equal(cq.atTime, 1);
    assert.equal(cq.t, 12.75);
    assert.deepEqual(cq.points, pts);
    assert.equal(cb.code, 0, cb.err);
    assert.equal(cb.message, 'viewer closed ✓');
});

test('JS encoders refuse what the C decoder would refuse', () => {
    const base = { effects: FX.ALL, meshKind: 0, codec: CODEC.QZ, cutoffPolicy: 2, mode: 0, layers: 1, lodLevels: 4, tileSize: 64, frameRateHz: 30 };
    assert.throws(() => encodeSubscribe({ ...base, effects: 0 }, 1), (e) => e.code === R.EINVAL);
    assert.throws(() => encodeSubscribe({ ...base, codec: 9 }, 1), (e) => e.code === R.ETYPE);
    assert.throws(() => encodeSubscribe({ ...base, frameRateHz: NaN }, 1), (e) => e.code === R.EINVAL);
    assert.throws(() => encodeSubscribe({ ...base, layout: 2 }, 1), (e) => e.code === R.ETYPE);
    assert.throws(() => encodeSubscribe({ ...base, meshCodec: 1 }, 1), (e) => e.code === R.ETYPE);
    assert.throws(() => encodeSubscribe({ ...base, flags: 4 }, 1), (e) => e.code === R.EFORMAT);
    const cam = { pos: [0, 10, 0], vel: [0, 0, 0], yawDeg: 0, pitchDeg: 0, fovYDeg: 60, viewportW: 10, viewportH: 10 };
    assert.throws(() => encodeCamera({ ...cam, pos: [NaN, 0, 0] }, 1), (e) => e.code === R.EINVAL);
    assert.throws(() => encodeCamera({ ...cam, fovYDeg: 180 }, 1), (e) => e.code === R.EINVAL);
    assert.throws(() => encodeCamera({ ...cam, pitchDeg: 95 }, 1), (e) => e.code === R.EINVAL);
    assert.throws(() => encodeQuery(1, [], null, 1), (e) => e.code === R.EINVAL);
});

/* Deterministic PRNG for the mutation test. */
function rng(seed) {
    let s = seed >>> 0;
    return () => { s = (s * 1664525 + 1013904223) >>> 0; return s / 4294967296; };
}

test('hostile input: truncated and corrupted messages get the same verdict and code in JS and C', () => {
    const names = ['hello', 'frame', 'frame_cascade', 'topology', 'topology_flat', 'result', 'sea', 'error', 'bye'];
    const variants = [];
    const rand = rng(20240611);
    const setU32 = (b, o, v) => new DataView(b.buffer).setUint32(o, v >>> 0, true);
    for (const n of names) {
        const v = vec(n);
        /* truncations (keeping the header's length honest or not) */
        for (let len = 0; len < v.length; len += Math.max(1, Math.floor(v.length / 60))) variants.push(v.slice(0, len));
        for (let len = 33; len < v.length; len += Math.max(1, Math.floor(v.length / 40))) {
            const b = v.slice(0, len);
            setU32(b, 12, len - 32);    /* header agrees; the payload itself is short */
            variants.push(b);
        }
        /* one trailing byte, header adjusted and not */
        const longer = new Uint8Array(v.length + 1);
        longer.set(v);
        variants.push(longer.slice());
        setU32(longer, 12, v.length + 1 - 32);
        variants.push(longer);
        /* every header byte flipped */
        for (let i = 0; i < 32; i++) {
            const b = v.slice();
            b[i] ^= 0xff;
            variants.push(b);
        }
        /* random byte overwrites in the payload */
        for (let k = 0; k < 250; k++) {
            const b = v.slice();
            const i = 32 + Math.floor(rand() * (v.length - 32));
            const choices = [0, 0xff, 0x7f, 0x80, b[i] ^ (1 << Math.floor(rand() * 8)), Math.floor(rand() * 256)];
            b[i] = choices[Math.floor(rand() * choices.length)];
            variants.push(b);
        }
    }
    /* NaN / Inf in doubles that must be finite (FRAME e_error, header sim_time) */
    const fr = vec('frame');
    for (const [off, val] of [[24, NaN], [24, Infinity], [32 + 8, NaN], [32 + 0, NaN], [32 + 0, -1], [32 + 16, Infinity]]) {
        const b = fr.slice();
        new DataView(b.buffer).setFloat64(off, val, true);
        variants.push(b);
    }
    /* layout 1: targeted corruptions of the cascade block, tags and placement */
    const fc = vec('frame_cascade');
    const B = 32 + 56;                                  /* cascade block */
    const E = B + 56;                                   /* first cascade entry */
    const put = (edits) => {
        const b = fc.slice(), dv = new DataView(b.buffer);
        for (const [kind, off, val] of edits) {
            if (kind === 'u8') b[off] = val;
            else if (kind === 'u16') dv.setUint16(off, val, true);
            else if (kind === 'u32') dv.setUint32(off, val >>> 0, true);
            else if (kind === 'f32') dv.setFloat32(off, val, true);
            else dv.setFloat64(off, val, true);
        }
        variants.push(b);
    };
    for (const v of [0, 3, 5, 255]) put([['u8', B, v]]);              /* cascade_count */
    for (const v of [0, 65]) put([['u8', B + 1, v]]);                 /* order */
    for (const v of [NaN, 0, -1, Infinity]) put([['f32', B + 4, v]]); /* spacing_per_m */
    for (const v of [NaN, 2e10]) put([['f64', B + 8, v]]);            /* camera x */
    for (const v of [NaN, -1]) put([['f32', B + 32, v]]);             /* min_spacing_m */
    for (const v of [NaN, 1.5]) put([['f32', B + 36, v]]);            /* e_total */
    for (const v of [NaN, -1e-3, 2e3]) put([['f32', B + 40, v]]);     /* tail_mss_x */
    for (const v of [-2e3, Infinity]) put([['f32', B + 48, v]]);      /* tail_mss_xz */
    put([['u8', B + 2, 1]]);                                          /* reserved */
    for (const v of [NaN, -1, Infinity, 2e6]) put([['f32', B + 52, v]]);  /* geometry_spacing_m */
    for (const v of [NaN, 0, 2e7]) put([['f64', E, v]]);              /* patch_m */
    for (const v of [0, 100, 4096, 7]) put([['u16', E + 8, v]]);      /* n */
    for (const v of [0, 13, 9]) put([['u8', E + 10, v]]);             /* mips (9 of 256 ok, 13 not) */
    put([['u16', E + 8, 8], ['u8', E + 10, 6]]);                      /* 6 mips of an 8 grid: fine; 5 of 8 */
    put([['u16', E + 8, 16], ['u8', E + 10, 12]]);                    /* 12 mips of 16: refused */
    put([['u8', E + 11, 2]]);                                         /* fades */
    for (const v of [NaN, 0, -1, Infinity, 1]) put([['f32', E + 12, v]]);        /* the entry's own q (1: above the block's) */
    for (const v of [NaN, 0.5]) put([['f32', E + 320 + 12, v]]);                /* the second entry's */
    put([['f32', E + 16, NaN]]);                                      /* mip 0 kc */
    put([['f32', E + 16, 0]]);
    put([['f32', E + 16 + 16 * 6, 1]]);                               /* entry mips must have kc 0 */
    put([['f32', E + 16 + 16 * 7, 1]]);                               /* beyond mips: 0 */
    put([['f32', E + 16 + 16 * 12 + 12, -0.5]]);
    put([['f32', E + 16 + 4, -1]]);                                   /* mss_x < 0 */
    put([['f32', E + 16 + 12, NaN]]);                                 /* mss_xz */
    put([['u8', 32 + 51, 2]]);                                        /* layout */
    put([['u8', 32 + 51, 0]]);                                        /* layout 0 with a block: misparsed, refused */
    const rec0 = E + 2 * 320;                                         /* first tile record */
    for (const v of [1, 2, 7, 0xffffffff]) put([['u32', rec0 + 4, v]]);   /* tags: 1 fine, 2+ refused */
    /* the placement record is the last 8 + 32 bytes */
    put([['u32', fc.length - 28, 1]]);                                /* placement reserved */
    put([['u32', fc.length - 36, 1]]);                                /* mesh record tag */
    put([['u32', fc.length - 40, 24]]);                               /* short placement */
    for (const v of [NaN, 1e11]) put([['f64', fc.length - 24, v]]);   /* placement origin */
    /* FLAT topology: flags, zones, flat values */
    const tf = vec('topology_flat');
    const tput = (off, kind, val) => {
        const b = tf.slice(), dv = new DataView(b.buffer);
        if (kind === 'u16') dv.setUint16(off, val, true); else if (kind === 'u8') b[off] = val; else dv.setFloat32(off, val, true);
        variants.push(b);
    };
    const zonesAt = tf.length - 48, flatAt = zonesAt - 32;
    for (const v of [2, 3, 0x8000]) tput(32 + 6, 'u16', v);
    tput(32 + 6, 'u16', 0);                                           /* FLAT cleared: trailing bytes */
    tput(32 + 5, 'u8', 0);                                            /* lod_levels 0 */
    tput(32 + 5, 'u8', 17);
    tput(32 + 5, 'u8', 2);                                            /* levels >= lod_levels, zones misread */
    for (const v of [NaN, 2e7, -Infinity]) tput(flatAt + 4, 'f32', v);
    for (const v of [0, -1, NaN]) tput(zonesAt, 'f32', v);            /* g_L */
    tput(zonesAt + 4, 'f32', -1);                                     /* R_L */
    tput(zonesAt + 8, 'f32', 2e8);                                    /* b_L */
    tput(zonesAt + 12, 'f32', 1);                                     /* reserved */
    const c = cDecode(variants);
    assert.equal(c.length, variants.length);
    let refused = 0;
    const mismatches = [];
    variants.forEach((b, i) => {
        const j = jsCode(b);
        if (j !== 0) refused++;
        if (j !== c[i].code && process.env.DUMP_MISMATCH) writeFileSync(join(process.env.DUMP_MISMATCH, `v${i}.bin`), b);
        if (j !== c[i].code) mismatches.push(`variant ${i} (${b.length} bytes): JS ${j}, C ${c[i].code} ${c[i].err || ''}`);
    });
    assert.deepEqual(mismatches.slice(0, 10), [], `${mismatches.length} of ${variants.length} verdicts differ`);
    assert.ok(refused > variants.length / 3, `only ${refused} of ${variants.length} variants were refused`);
});

test('qz payload vectors (tests/vectors/codec): formats 2 and 1 decode to the committed samples, bit for bit', (t) => {
    const vdir = process.env.PROTO_VECTORS;
    if (!vdir) { t.skip('PROTO_VECTORS not set'); return; }
    const dir = join(vdir, 'codec');
    const names = readdirSync(dir).filter((f) => f.endsWith('.qz')).map((f) => f.slice(0, -3));
    assert.ok(names.length >= 2, `codec vectors in ${dir}: ${names}`);
    const formats = new Set();
    for (const name of names) {
        const meta = Object.fromEntries(readFileSync(join(dir, `${name}.txt`), 'utf8').trim().split('\n')
            .map((l) => l.split(' = ')));
        const payload = new Uint8Array(readFileSync(join(dir, `${name}.qz`)));
        const want = readFileSync(join(dir, `${name}.f32`));
        const w = Number(meta.width), h = Number(meta.height), ch = Number(meta.channels);
        assert.equal(payload[1], Number(meta.format));
        formats.add(payload[1]);
        const d = decodeTile(CODEC.QZ, w, h, ch, payload);
        assert.equal(d.data.length * 4, want.length);
        const got = new Uint8Array(d.data.buffer, d.data.byteOffset, d.data.byteLength);
        for (let i = 0; i < want.length; i++)
            if (got[i] !== want[i]) assert.fail(`${name}: byte ${i} of the samples differs`);
        for (let l = 0; l < payload.length; l += 7)
            assert.throws(() => decodeTile(CODEC.QZ, w, h, ch, payload.subarray(0, l)), (e) => e.code === R.ECODEC);
    }
    assert.deepEqual([...formats].sort(), [1, 2]);
});

/* tests/vectors/held frame i's expected tiles: [{key, channels, bytes}] */
function heldExpected(hdir, i) {
    const lines = readFileSync(join(hdir, `frame_${i}.txt`), 'utf8').trim().split('\n').filter((l) => l);
    const f32 = new Uint8Array(readFileSync(join(hdir, `frame_${i}.f32`)));
    let off = 0;
    return lines.map((l) => {
        const [mip, ix, iz, channels] = l.split(' ').map(Number);
        const n = 4 * tilePlanes(channels) * 16;   /* 4 x 4 samples per plane */
        const bytes = f32.subarray(off, off + n);
        off += n;
        return { key: `0/${mip}/${ix}/${iz}`, channels, bytes };
    });
}

test('samples in time (tests/vectors/held): the viewer\'s store blends every frame\'s instant bit for bit, whole and in shards', (t) => {
    const vdir = process.env.PROTO_VECTORS;
    if (!vdir) { t.skip('PROTO_VECTORS not set'); return; }
    const hdir = join(vdir, 'held');
    const frames = readdirSync(hdir).filter((f) => /^frame_\d+\.bin$/.test(f)).length;
    assert.ok(frames >= 6, `held vectors in ${hdir}`);
    for (const shards of [1, 2, 3]) {
        const stores = Array.from({ length: shards }, (_, i) => new HeldStore(i, shards));
        for (let i = 0; i < frames; i++) {
            const bytes = new Uint8Array(readFileSync(join(hdir, `frame_${i}.bin`)));
            const got = new Map();
            for (const s of stores) {
                s.apply(bytes);
                const { tiles, error } = s.blend();
                assert.equal(error, null);
                tiles.forEach((tile, k) => {
                    const key = `${tile.cascade}/${tile.mip}/${tile.ix}/${tile.iz}`;
                    assert.ok(!got.has(key), `frame ${i}: ${key} in two shards`);
                    const p = s.planes(k, tile).data;
                    got.set(key, { channels: tile.channels, bytes: new Uint8Array(p.buffer, p.byteOffset, p.byteLength) });
                });
            }
            const want = heldExpected(hdir, i);
            assert.deepEqual([...got.keys()].sort(), want.map((w) => w.key).sort(), `frame ${i}, ${shards} shards`);
            for (const w of want) {
                const g = got.get(w.key);
                assert.equal(g.channels, w.channels, `frame ${i} ${w.key}`);
                assert.ok(Buffer.compare(Buffer.from(g.bytes), Buffer.from(w.bytes)) === 0, `frame ${i} ${w.key}: samples differ`);
            }
        }
        for (const s of stores) s.destroy();
    }
    /* hostile: a truncated frame is refused with the decoder's code, and
     * the store carries on */
    const s = new HeldStore();
    const f0 = new Uint8Array(readFileSync(join(hdir, 'frame_0.bin')));
    assert.throws(() => s.apply(f0.subarray(0, f0.length - 9)), (e) => e instanceof ProtoError && e.code !== R.OK);
    s.apply(f0);
    assert.equal(s.blend().tiles.length, heldExpected(hdir, 0).length);
    s.destroy();
});

test('corrupt qz payloads are refused with ECODEC, never decoded to junk', () => {
    const t = decode(vec('frame')).body.tiles.find((x) => x.codec === CODEC.QZ);
    const ok = decodeTile(t.codec, t.width, t.height, t.channels, t.payload);
    assert.ok(ok.data.every(Number.isFinite));
    const rand = rng(7);
    let refused = 0, accepted = 0;
    for (let k = 0; k < 400; k++) {
        const p = t.payload.slice();
        const i = Math.floor(rand() * p.length);
        p[i] ^= 1 + Math.floor(rand() * 255);
        try {
            const d = decodeTile(t.codec, t.width, t.height, t.channels, p);
            assert.ok(d.data.every(Number.isFinite));   /* a flip in a residual may decode to other finite values */
            accepted++;
        } catch (e) {
            assert.ok(e instanceof ProtoError, `non-protocol exception: ${e}`);
            assert.equal(e.code, R.ECODEC);
            refused++;
        }
    }
    assert.ok(refused > 100, `only ${refused} of 400 corruptions refused`);
    /* structural cases */
    assert.throws(() => decodeTile(CODEC.QZ, t.width, t.height, t.channels, t.payload.subarray(0, 10)), (e) => e.code === R.ECODEC);
    assert.throws(() => decodeTile(CODEC.QZ, t.width + 1, t.height, t.channels, t.payload), (e) => e.code === R.ECODEC);
    assert.throws(() => decodeTile(CODEC.QZ, t.width, t.height, 1, t.payload), (e) => e.code === R.ECODEC);
    assert.throws(() => decodeTile(CODEC.F16, 2, 2, 1, new Uint8Array([0, 0x7c, 0, 0, 0, 0, 0, 0])), (e) => e.code === R.ECODEC);
    assert.throws(() => decodeTile(CODEC.F32, 2, 2, 1, new Uint8Array(15)), (e) => e.code === R.ECODEC);
    assert.throws(() => decodeTile(CODEC.EXR_ZIP, 2, 2, 1, new Uint8Array(16)), (e) => e.code === R.EUNSUPPORTED);
    void accepted;
});

test('half floats, octahedral normals and cascade blocks through the WebAssembly build', () => {
    /* binary16 as proto_f32_from_f16: 1, -2, the largest finite, the smallest subnormal */
    const f16 = new Uint8Array(new Uint16Array([0x3c00, 0xc000, 0x7bff, 0x0001]).buffer);
    assert.deepEqual(Array.from(decodeTile(CODEC.F16, 2, 2, 1, f16).data), [1, -2, 65504, 2 ** -24]);
    for (const bad of [0x7c00, 0x7e00])          /* inf and NaN are refused */
        assert.throws(() => decodeTile(CODEC.F16, 1, 1, 1, new Uint8Array(new Uint16Array([bad]).buffer)), (e) => e.code === R.ECODEC);
    const n = octNormals(new Float32Array([0, 1, 0, 0.9]), new Float32Array([0, 0, -1, 0.8]));
    assert.deepEqual(Array.from(n.subarray(0, 12)), [0, 1, 0, 1, 1, 0, 0, 1, 0, 0, -1, 1]);
    assert.ok(n[13] < 0, 'lower hemisphere fold');
    assert.ok(Math.abs(Math.hypot(n[12], n[13], n[14]) - 1) < 1e-6);
    /* a cascade block: (DX, H, DZ, 0) and (the slopes of the octahedral
     * normal, BI, BQ), a folded crest held at the maximum slope */
    const planes = new Float32Array([0.5, -0.25, 0.1, 0.2, 0, 0.9, 0.3, 0.7, -0.125, 0.0625]);   /* H, NU, NV, BI, BQ; 2 samples */
    const t = { codec: CODEC.F32, width: 2, height: 1, channels: 1 | 8 | 64, spacing: 1, payload: new Uint8Array(planes.buffer) };
    const b = decodeCascadeBlock(t, 20);
    assert.deepEqual(Array.from(b.disp), [0, 0.5, 0, 0, 0, -0.25, 0, 0]);
    const y = 1 - 0.1 - 0.0;
    assert.ok(Math.abs(b.slope[0] + Math.fround(0.1) / y) < 1e-6 && Math.abs(b.slope[1]) < 1e-7, `slopes ${b.slope}`);
    const folded = Math.hypot(b.slope[4], b.slope[5]);
    assert.ok(folded > 19 && folded <= 20, `folded crest slope ${b.slope[4]}, ${b.slope[5]}`);
    assert.deepEqual([b.slope[2], b.slope[3], b.slope[6], b.slope[7]], [Math.fround(0.3), -0.125, Math.fround(0.7), 0.0625]);
});

/* ---- the protocol's own vectors (tests/vectors, PROTOCOL.md "Test vectors") ---- */

const snake = (k) => k.replace(/[A-Z]/g, (c) => `_${c.toLowerCase()}`).replace(/u_10$/, 'u10');

/* A decoded message as `field = value` strings, named as the .txt files
 * name them. */
function flatten(m) {
    /* the vectors name a stand-alone MESH_VERTICES' fields mesh.*, a TILE's tile.* */
    if (m.type === T.MESH_VERTICES) m = { ...m, body: { mesh: m.body } };
    if (m.type === T.TILE) m = { ...m, body: { tile: m.body } };
    const flat = { type: m.name, version: String(m.hdr.version), flags: String(m.hdr.flags), seq: String(m.hdr.seq), sim_time: String(m.hdr.simTime) };
    const val = (k, v) => {
        if (v instanceof Uint8Array && (k === 'payload' || k === 'qz')) return Array.from(v, (b) => b.toString(16).padStart(2, '0')).join(' ');
        if (ArrayBuffer.isView(v) || Array.isArray(v)) return Array.from(v).join(' ');
        return String(v);
    };
    const walk = (o, prefix) => {
        for (const [k, v] of Object.entries(o)) {
            if (k === 'tiles') { v.forEach((t, i) => walk(t, `${prefix}tile[${i}].`)); continue; }
            if (v === null) continue;
            /* cascade entries are named cascade[c].* at the top, their mip
             * table entries 0..mips one line each (kc mss_x mss_z mss_xz) */
            if (k === 'cascade' && Array.isArray(v)) {
                v.forEach((e, c) => {
                    for (const key of ['patchM', 'n', 'mips', 'fades', 'spacingPerM']) flat[`cascade[${c}].${snake(key)}`] = String(e[key]);
                    for (let m = 0; m <= e.mips; m++) flat[`cascade[${c}].mip[${m}]`] = Array.from(e.mip.subarray(4 * m, 4 * m + 4)).join(' ');
                    /* the read table's shares, a line per mip (bilinear Keys Lanczos-3) */
                    for (let m = 0; m < e.mips && e.held[0]; m++) flat[`cascade[${c}].held[${m}]`] = Array.from(e.held.subarray(3 * m, 3 * m + 3)).join(' ');
                });
                continue;
            }
            /* the whitecap table: its rows one line each (sigma a omega) */
            if (k === 'foamAll') continue;
            if (k === 'foam' && Array.isArray(v)) {
                v.forEach((w, i) => { flat[`${prefix}foam[${i}]`] = `${w.sigma} ${w.a} ${w.omega}`; });
                continue;
            }
            if (k === 'samples') {
                v.forEach((s, i) => { flat[`${prefix}sample[${i}]`] = `${s.height} | ${s.normal.join(' ')} | ${s.velocity.join(' ')} | ${s.foam} | ${s.errorBound}`; });
                continue;
            }
            if (v && typeof v === 'object' && !ArrayBuffer.isView(v) && !Array.isArray(v)) { walk(v, `${prefix}${snake(k)}.`); continue; }
            flat[prefix + snake(k)] = val(k, v);
        }
        if ('viewportW' in o) flat[`${prefix}viewport`] = `${o.viewportW} ${o.viewportH}`;
    };
    walk(m.body, '');
    return flat;
}

function sameValue(want, got) {
    if (want === got) return true;
    const a = want.split(/\s+/), b = got.split(/\s+/);
    if (a.length !== b.length) return false;
    return a.every((x, i) => {
        if (x === b[i]) return true;
        const num = (t) => (/^[+-]?inf$/.test(t) ? (t[0] === '-' ? -Infinity : Infinity) : Number(t));   /* C's %g prints inf */
        const p = num(x), q = num(b[i]);
        if (p === q) return true;
        if (Number.isNaN(p) || Number.isNaN(q)) return false;
        return Math.abs(p - q) <= 1e-8 * Math.max(1, Math.abs(p));   /* %.9g prints float32 to 9 digits */
    });
}

test('the protocol vectors in tests/vectors decode to their stated fields; bad ones get their stated code', (t) => {
    const vdir = process.env.PROTO_VECTORS;
    if (!vdir) { t.skip('PROTO_VECTORS not set'); return; }
    const names = readdirSync(vdir).filter((f) => f.endsWith('.bin')).map((f) => f.slice(0, -4));
    assert.ok(names.length >= 10, `only ${names.length} vectors in ${vdir}`);
    let good = 0, bad = 0, seaAgain = 0;
    for (const n of names) {
        const bytes = new Uint8Array(readFileSync(join(vdir, `${n}.bin`)));
        const lines = readFileSync(join(vdir, `${n}.txt`), 'utf8').split('\n').filter((l) => l.includes(' = '));
        const want = Object.fromEntries(lines.map((l) => [l.slice(0, l.indexOf(' = ')), l.slice(l.indexOf(' = ') + 3)]));
        if (n.startsWith('bad_')) {
            const code = Number(/\((\d+)\)/.exec(want.error)[1]);
            assert.equal(jsCode(bytes), code, `${n}: expected ${want.error}`);
            bad++;
            continue;
        }
        const m = decode(bytes);
        if (m.type === T.FRAME && m.body.hasMesh === 2) {
            /* positions need the topology: the mesh_topology vector's (PROTOCOL.md "Test vectors") */
            const topo = decode(new Uint8Array(readFileSync(join(vdir, 'mesh_topology.bin')))).body;
            m.body.mesh.positions = decodeMeshQz(m.body.mesh.qz, m.body.mesh.vertexCount, meshQzRefs(topo.indices, topo.vertexCount));
        }
        const flat = flatten(m);
        let compared = 0;
        for (const [k, v] of Object.entries(want)) {
            if (!(k in flat)) continue;
            assert.ok(sameValue(v, flat[k]), `${n}: ${k} = ${flat[k]}, vector says ${v}`);
            compared++;
        }
        assert.ok(compared >= 0.8 * Object.keys(want).length,
            `${n}: only ${compared} of ${Object.keys(want).length} fields compared (missing: ${Object.keys(want).filter((k) => !(k in flat)).join(', ')})`);
        /* what the viewer encodes must re-encode to the identical bytes */
        let again = null;
        const b = m.body, seq = m.hdr.seq, st = m.hdr.simTime;
        if (m.type === T.SUBSCRIBE) again = encodeSubscribe(b, seq, st);
        if (m.type === T.CAMERA) again = encodeCamera(b, seq, st);
        if (m.type === T.QUERY) again = encodeQuery(b.queryId, Array.from(b.points), b.atTime ? b.t : null, seq, st);
        if (m.type === T.BYE) again = encodeBye(b.reason, b.message, seq, st);
        if (m.type === T.SEA_STATE) again = encodeSeaState(b.op, b.effectiveTime, b.sea, b.token, seq, st);
        if (again) assert.deepEqual(new Uint8Array(again), bytes, `${n}: re-encoding differs`);
        if (again && m.type === T.SEA_STATE) seaAgain++;
        good++;
    }
    assert.ok(good >= 8 && bad >= 5, `${good} good and ${bad} bad vectors checked`);
    assert.ok(seaAgain >= 3, `${seaAgain} SEA_STATE vectors (set, announce, get) re-encoded`);
});

test('the viewer reads the ships\' wakes as the C library does: tests/vectors/wake_read.txt from its ENTITY and WAKE', (t) => {
    const vdir = process.env.PROTO_VECTORS;
    if (!vdir) { t.skip('PROTO_VECTORS not set'); return; }
    const want = Object.fromEntries(readFileSync(join(vdir, 'wake_read.txt'), 'utf8').split('\n')
        .filter((l) => l.includes(' = ')).map((l) => [l.slice(0, l.indexOf(' = ')), l.slice(l.indexOf(' = ') + 3)]));
    const w = new WakeStore();
    const n = Number(want.n), dx = Number(want.dx);
    /* before its pattern comes, a ship there has no wake to read */
    w.message(new Uint8Array(readFileSync(join(vdir, 'wake_read_entity.bin'))));
    assert.equal(w.grid(Number(want.t), Number(want.depth), Number(want.x0), Number(want.z0), dx, n), null);
    w.message(new Uint8Array(readFileSync(join(vdir, 'wake_read_wake.bin'))));
    const g = w.grid(Number(want.t), Number(want.depth), Number(want.x0), Number(want.z0), dx, n);
    w.destroy();
    let peak = 0;
    ['height', 'dhdx', 'dhdz', 'mss'].forEach((name, c) => {
        const v = want[name].split(' ').map(Number);
        assert.equal(v.length, n * n);
        for (let k = 0; k < n * n; k++) {
            assert.ok(Math.abs(g[4 * k + c] - v[k]) <= 1e-8 * Math.max(1, Math.abs(v[k])), `${name}[${k}]: ${g[4 * k + c]}, C read ${v[k]}`);
            if (c === 0) peak = Math.max(peak, Math.abs(v[k]));
        }
    });
    assert.ok(peak > 0.005, `the square holds a wake (peak ${peak} m)`);
});
