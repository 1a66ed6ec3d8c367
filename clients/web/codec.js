/*
 * codec.js - the viewer's tile and mesh decoders: the project's own C
 * (protocol/codec.c, with clients/wasm/oc_wasm.c's exports) compiled to
 * WebAssembly as ocean.wasm by `make`, and zstd's own decoder as
 * vendor/zstd.wasm (from the npm package zstddec, pinned in
 * tests/browser/package.json, copied by its `npm run vendor`).  So the
 * daemon, the C library and the browser decode every codec with one
 * implementation; tests/browser/protocol.test.mjs holds this module to the
 * native decoder bit for bit on every vector.
 *
 * HeldStore runs the C library's store of a time-interpolating stream
 * (clients/c/oc_held.c, with the message decoder protocol/proto.c) in the
 * same module.
 *
 * Both modules load when this module is imported (top-level await), from
 * beside this file: over HTTP in a page or worker, from disk in Node.js.
 * Each worker that imports it gets its own instances; none is shared
 * between threads.
 *
 * Input is hostile, as in C: every failure throws a ProtoError with the C
 * decoder's code (ECODEC for a corrupt payload, EUNSUPPORTED for the EXR
 * codecs, EINVAL for impossible arguments) and its message.
 */
import { ProtoError, R, tilePlanes } from './protocol.js';

async function loadBytes(name) {
    const url = new URL(name, import.meta.url);
    if (url.protocol === 'file:') {
        const { readFile } = await import('node:fs/promises');
        return readFile(url);
    }
    const r = await fetch(url);
    if (!r.ok) throw new Error(`${url.pathname}: HTTP ${r.status}`);
    return r.arrayBuffer();
}

const [zstdBytes, oceanBytes] = await Promise.all([loadBytes('./vendor/zstd.wasm'), loadBytes('./ocean.wasm')]);
/* zstddec's module (Emscripten): it only tells us when its memory grows;
 * views are taken afresh at each use instead. */
const zstd = (await WebAssembly.instantiate(zstdBytes, { env: { emscripten_notify_memory_growth() {} } })).instance.exports;
let oc = null;

/* Copies len bytes at src of ocean.wasm's memory into zstd's; the caller frees. */
function toZstd(src, len) {
    const p = zstd.malloc(Math.max(1, len));
    if (!p) return 0;
    new Uint8Array(zstd.memory.buffer, p, len).set(new Uint8Array(oc.memory.buffer, src, len));
    return p;
}

const imports = {
    zstd: {
        /* ZSTD_findDecompressedSize: an i64, negative for "error" and "unknown" */
        content_size(src, len) {
            const p = toZstd(src, len);
            if (!p) return -1;
            const n = zstd.ZSTD_findDecompressedSize(p, len);
            zstd.free(p);
            return n < 0n ? -1 : Number(n);
        },
        decompress(dst, cap, src, len) {
            const p = toZstd(src, len), d = zstd.malloc(Math.max(1, cap));
            let n = -1;
            if (p && d) {
                const got = zstd.ZSTD_decompress(d, cap, p, len) >>> 0;
                if (!zstd.ZSTD_isError(got) && got <= cap) {
                    new Uint8Array(oc.memory.buffer, dst, got).set(new Uint8Array(zstd.memory.buffer, d, got));
                    n = got;
                }
            }
            if (p) zstd.free(p);
            if (d) zstd.free(d);
            return n;
        },
    },
    /* wasi-libc's stdio (snprintf) links these; nothing here calls them */
    wasi_snapshot_preview1: { fd_close: () => 52, fd_seek: () => 52, fd_write: () => 52 },
};
oc = (await WebAssembly.instantiate(oceanBytes, imports)).instance.exports;

function lastError() {
    const m = new Uint8Array(oc.memory.buffer), p = oc.ocw_error();
    let e = p;
    while (m[e]) e++;
    return new TextDecoder().decode(m.subarray(p, e));
}

/* Runs fn(alloc) with the allocations it asks for freed afterwards;
 * alloc(bytes) returns a pointer into ocean.wasm's memory. */
function withHeap(fn) {
    const held = [];
    const alloc = (n) => {
        const p = oc.ocw_alloc(n);
        if (!p) throw new ProtoError(R.ENOMEM, `cannot allocate ${n} bytes`);
        held.push(p);
        return p;
    };
    try {
        return fn(alloc);
    } finally {
        for (const p of held) oc.ocw_free(p);
    }
}
function put(alloc, u8) {
    const p = alloc(u8.byteLength);
    new Uint8Array(oc.memory.buffer, p, u8.byteLength).set(u8);
    return p;
}
function check(code) {
    if (code !== R.OK) throw new ProtoError(code, lastError() || `decoder failed (code ${code})`);
}
const f32At = (p, n) => new Float32Array(oc.memory.buffer, p, n).slice();

/* Decodes a tile payload for (codec, w, h, channels) into {planes, data}:
 * data a new Float32Array of planes * w * h samples, plane after plane
 * (row = z): proto_tile_decode. */
export function decodeTile(codec, w, h, channels, payload) {
    const np = tilePlanes(channels);
    return withHeap((alloc) => {
        const total = np * w * h;
        const src = put(alloc, payload), out = alloc(4 * Math.max(1, total));
        check(oc.ocw_tile_decode(codec, w, h, channels, src, payload.byteLength, out));
        return { planes: np, data: f32At(out, total) };
    });
}

/* Layout 1: a cascade mip tile as the renderer's texel block (ocw_cascade_block):
 * {disp: (DX, H, DZ, 0) x w h, slope: (d eta/dx, d eta/dz, BI, BQ) x w h};
 * a folded crest's slope is held at maxSlope. */
export function decodeCascadeBlock(t, maxSlope) {
    const { width: w, height: h } = t;
    return withHeap((alloc) => {
        const n = w * h;
        const src = put(alloc, t.payload), disp = alloc(16 * n), slope = alloc(16 * n);
        check(oc.ocw_cascade_block(t.codec, w, h, t.channels, t.spacing, maxSlope, src, t.payload.byteLength,
            disp, slope));
        return { disp: f32At(disp, 4 * n), slope: f32At(slope, 4 * n) };
    });
}

/* Unit normals (x, y, z, 1) per sample from the NU, NV planes (n samples
 * each): proto_normal_oct_decode. */
export function octNormals(nu, nv) {
    const n = nu.length;
    return withHeap((alloc) => {
        const u = put(alloc, new Uint8Array(nu.buffer, nu.byteOffset, 4 * n));
        const v = put(alloc, new Uint8Array(nv.buffer, nv.byteOffset, 4 * n));
        const out = alloc(16 * Math.max(1, n));
        oc.ocw_normals(u, v, n, out);
        return f32At(out, 4 * n);
    });
}

/* The prediction references of a MESH_TOPOLOGY's triangles (Uint32Array
 * indices over vertexCount vertices): proto_mesh_qz_refs. */
export function meshQzRefs(indices, vertexCount) {
    return withHeap((alloc) => {
        const ix = put(alloc, new Uint8Array(indices.buffer, indices.byteOffset, 4 * indices.length));
        const refs = alloc(12 * Math.max(1, vertexCount));
        check(oc.ocw_mesh_qz_refs(ix, indices.length, vertexCount, refs));
        return new Uint32Array(oc.memory.buffer, refs, 3 * vertexCount).slice();
    });
}

/* A has_mesh 2 record's payload (from its format byte) for vertexCount
 * vertices, with its topology's refs, as x, y, z per vertex:
 * proto_mesh_qz_decode. */
export function decodeMeshQz(data, vertexCount, refs) {
    if (refs.length !== 3 * vertexCount)
        throw new ProtoError(R.ECODEC, `mesh qz: topology of ${refs.length / 3} vertices, record has ${vertexCount}`);
    return withHeap((alloc) => {
        const src = put(alloc, data);
        const r = put(alloc, new Uint8Array(refs.buffer, refs.byteOffset, 4 * refs.length));
        const out = alloc(12 * Math.max(1, vertexCount));
        check(oc.ocw_mesh_qz_decode(src, data.byteLength, vertexCount, r, out));
        return f32At(out, 3 * vertexCount);
    });
}

/* Layout 1 with samples in time (PROTOCOL.md "Samples in time"): a
 * connection's store of held samples, clients/c/oc_held.c as the C library
 * runs it (ocw_held_*).  Each FRAME of the connection goes through apply(),
 * every one and in order (a frame alone is incomplete); the store keeps
 * the tiles of its shard (shard of shards, a hash of the tile's place, so
 * decode workers split the tiles between them) as payloads, and blend()
 * decodes what it has not yet and blends the last frame's instant.  Call
 * destroy() when the connection ends. */
export class HeldStore {
    constructor(shard = 0, shards = 1) {
        this.shard = shard;
        this.shards = shards;
        this.h = oc.ocw_held_create();
        if (!this.h) throw new ProtoError(R.ENOMEM, 'cannot allocate the held store');
    }

    /* frame: the whole FRAME message (ArrayBuffer or Uint8Array). */
    apply(frame) {
        const u8 = frame instanceof Uint8Array ? frame : new Uint8Array(frame);
        withHeap((alloc) => {
            const p = put(alloc, u8);
            check(oc.ocw_held_apply(this.h, p, u8.byteLength, this.shard, this.shards));
        });
    }

    /* Blends the last frame's instant: {tiles: [{cascade, mip, ix, iz,
     * width, height, channels, spacing, errorBound}], error: ProtoError or
     * null}; a tile that did not decode is left out and named in error. */
    blend() {
        const r = oc.ocw_held_blend(this.h);
        const error = r === R.OK ? null : new ProtoError(r, lastError() || `held store failed (code ${r})`);
        const n = oc.ocw_held_count(this.h), tiles = [];
        withHeap((alloc) => {
            const v = alloc(72);
            for (let i = 0; i < n; i++) {
                check(oc.ocw_held_tile(this.h, i, v));
                const d = new Float64Array(oc.memory.buffer, v, 9);
                tiles.push({ cascade: d[0], mip: d[1], ix: d[2], iz: d[3], width: d[4], height: d[5],
                    channels: d[6], spacing: d[7], errorBound: d[8] });
            }
        });
        return { tiles, error };
    }

    /* Blended tile i's planes as decodeTile gives them (proto_tile_planes). */
    planes(i, t) {
        const np = tilePlanes(t.channels);
        return { planes: np, data: f32At(oc.ocw_held_planes(this.h, i), np * t.width * t.height) };
    }

    /* Blended tile i (t its blend() record) as decodeCascadeBlock's texel block. */
    texels(i, t, maxSlope) {
        const n = t.width * t.height;
        return withHeap((alloc) => {
            const disp = alloc(16 * n), slope = alloc(16 * n);
            check(oc.ocw_held_texels(this.h, i, maxSlope, disp, slope));
            return { disp: f32At(disp, 4 * n), slope: f32At(slope, 4 * n) };
        });
    }

    destroy() {
        if (this.h) oc.ocw_held_destroy(this.h);
        this.h = 0;
    }
}

/* The ships' wakes (clients/c/oc_wakes.c in the same module): message()
 * takes every ENTITY and WAKE message, grid() reads the wakes on a square
 * of points as the daemon answers them (PROTOCOL.md "WAKE").  Call
 * destroy() when the connection ends. */
export class WakeStore {
    constructor() {
        this.w = oc.ocw_wakes_create();
        if (!this.w) throw new ProtoError(R.ENOMEM, 'cannot allocate the wake store');
    }

    /* msg: a whole ENTITY or WAKE message (ArrayBuffer or Uint8Array). */
    message(msg) {
        const u8 = msg instanceof Uint8Array ? msg : new Uint8Array(msg);
        withHeap((alloc) => check(oc.ocw_wakes_message(this.w, put(alloc, u8), u8.byteLength)));
    }

    /* The wakes at sim time t over `depth` m of water on the n x n points
     * (x0 + i dx, z0 + j dx): a Float32Array of 4 per point (height,
     * dh/dx, dh/dz, 0), row j after row; null while a pattern a ship there
     * needs has not come. */
    grid(t, depth, x0, z0, dx, n) {
        return withHeap((alloc) => {
            const out = alloc(16 * n * n);
            const r = oc.ocw_wakes_grid(this.w, t, depth, x0, z0, dx, n, out);
            if (r === R.ESTATE) return null;
            check(r);
            return f32At(out, 4 * n * n);
        });
    }

    destroy() {
        if (this.w) oc.ocw_wakes_destroy(this.w);
        this.w = 0;
    }
}
