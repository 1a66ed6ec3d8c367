/*
 * worker.js - the viewer's network side, run as a module Worker so that
 * decoding never stalls rendering.  It owns the WebSocket (subprotocol
 * ocean.v1), answers HELLO with SUBSCRIBE, turns the page's camera reports
 * into CAMERA messages, decodes every message (protocol.js) and every tile
 * (codec.js), assembles each tile level into one texture-ready grid, and
 * posts the results to the page with their buffers transferred.
 *
 * Latest wins, as on the server: FRAMEs that arrive while one is being
 * decoded, or while the page has not yet drawn the last one decoded, are
 * coalesced and only the newest is decoded (counted in `skipped`).  So the
 * decoding follows the page's drawing rate: a page that draws 2 frames a
 * second (software GL on a busy host) costs 2 decodes a second, not 30.
 * Latency is measured here, on one clock: the time from sending CAMERA
 * seq s to receiving the first FRAME that answers s.
 *
 * Tiles are decoded by a pool of decoder workers (decoder.js), whole
 * levels at a time (layout 0) or shares of a frame's cascade tiles
 * balanced by samples (layout 1), so decoding uses the cores a machine has.
 *
 * Layout 1 (the default, PROTOCOL.md "Layouts"): a FRAME's tiles are mip
 * tiles of periodic cascades, the same for every viewer; each becomes a
 * texel block {cascade, mip, x, y, w, h, disp, slope} that the renderer
 * writes into its per-cascade mipmapped textures, and the FRAME's cascade
 * block (mip tables, camera, spacing_per_m, min_spacing) and mesh
 * placement go with them.
 *
 * Page -> worker: {cmd:'connect', url, sub}, {cmd:'camera', cam},
 *                 {cmd:'taken'} (the page applied the last frame posted),
 *                 {cmd:'subscribe', sub} (change), {cmd:'query', id, points},
 *                 {cmd:'pause', paused}, {cmd:'capture'} (next FRAME's raw
 *                 bytes, for debugging), {cmd:'close'}.
 * Worker -> page: {kind:'status'|'hello'|'subscribed'|'topology'|'vertices'|
 *                 'frame'|'error'|'bye'|'sea'|'result'|'capture', ...}.
 */
import {
    CODEC, CODEC_NAMES, CUTOFF, FX, LAYOUT, MESH, MESH_CODEC, MODE, SUB_FLAG, SUBPROTOCOL, T, BYE_REASONS, RESULT_NAMES,
    decode, decodeHeader, encodeCamera, encodeSubscribe, encodeQuery, encodeBye, encodeSeaState, ProtoError, tilePlanes,
} from './protocol.js';
import { ByteRate } from './rate.js';

let ws = null;
let seq = 0;
let hello = null;
let subscription = null;
const entities = new Map();   /* ENTITY announces: id -> the newest (PROTOCOL.md "ENTITY") */
/* The ships' wakes (PROTOCOL.md "WAKE"): every ENTITY and WAKE goes to the
 * WebAssembly store, which reads them on a square around the camera for
 * the page at most WAKE_EVERY_MS apart (a ship moves 1 m in that time at
 * 10 m/s; the square is WAKE_N points a side at WAKE_DX m, twice that from
 * a camera 300 m up and four times from 600 m: a pixel's footprint grows
 * with height, and a helicopter sees the wake of kilometres for the same
 * cost; 8 m still keeps five points to the 41 m transverse wave of a ship
 * at 8 m/s). */
let wakeStore = null;
let wakeDone = -Infinity;
let seaDepth = 1000;
let wakeYaw = 0;              /* the camera's yaw, degrees: the square lies ahead of the eye */
const WAKE_N = 192, WAKE_DX = 4, WAKE_EVERY_MS = 100;

function wakeFeed(data) {
    try {
        if (!wakeStore) wakeStore = new WakeStore();
        wakeStore.message(data);
    } catch (e) {
        noteError(e, 'wake');
    }
}

/* The wakes on the square around the frame's camera at its instant
 * (grid points snapped to the spacing, so the square does not swim), or
 * undefined when not due (the page keeps the last). */
function wakeGrid(meta, now) {
    if (!wakeStore || !entities.size || now - wakeDone < WAKE_EVERY_MS) return entities.size ? undefined : null;
    const cam = meta.cascades && meta.cascades.camera;
    if (!cam) return undefined;
    wakeDone = now;
    const dx = WAKE_DX * (cam[1] >= 600 ? 4 : cam[1] >= 300 ? 2 : 1);
    /* centred 0.4 of its side ahead of the eye: what the eye sees nearest */
    const half = WAKE_N * dx / 2, a = wakeYaw * Math.PI / 180;
    const cx = cam[0] + 0.8 * half * Math.cos(a), cz = cam[2] + 0.8 * half * Math.sin(a);
    const x0 = Math.round((cx - half) / dx) * dx, z0 = Math.round((cz - half) / dx) * dx;
    const t0 = performance.now();
    try {
        const data = wakeStore.grid(meta.simTime, seaDepth, x0, z0, dx, WAKE_N);
        if (!data) return undefined;       /* a pattern on its way */
        let peak = 0, trough = 0;
        for (let k = 0; k < data.length; k += 4) {
            peak = Math.max(peak, Math.abs(data[k]));
            trough = Math.min(trough, data[k]);
        }
        stats.wakePeak = peak;
        stats.wakeMs = performance.now() - t0;
        return { x0, z0, dx, n: WAKE_N, t: meta.simTime, peak, trough, data };
    } catch (e) {
        noteError(e, 'wake grid');
        return undefined;
    }
}
/* The decoders (codec.js) load their WebAssembly modules as they are
 * imported; a static import would hold this module's evaluation, and with
 * it the onmessage handler below, until they have loaded, and a message
 * the page sends meanwhile would be lost.  So they come in dynamically and
 * the socket opens once they are here. */
let assembleLevel, assembleCascadeTile, groupByLevel, heldBlocks, decodeMeshQz, HeldStore, WakeStore, meshQz;
const decodersReady = Promise.all([import('./assemble.js'), import('./codec.js'), import('./meshstore.js')])
    .then(([a, c, m]) => {
        ({ assembleLevel, assembleCascadeTile, groupByLevel, heldBlocks } = a);
        ({ decodeMeshQz, HeldStore, WakeStore } = c);
        meshQz = new m.MeshQzStore();  /* layout 0 with mesh_codec qz: the topologies' prediction refs */
    });
let wantSub = null;
let lastSimTime = 0;         /* sim time of the last FRAME received */
let pendingFrame = null;     /* newest undecoded FRAME bytes */
let pageHolds = false;       /* a decoded frame is posted and the page has not taken it yet */
let frameScheduled = false;
const sentAt = new Map();    /* CAMERA seq -> performance.now() at send */
let answeredSeq = -1;
let lastLatency = null;      /* newest camera -> frame round trip, ms (consumed by the next posted frame) */

const stats = {
    messages: 0, frames: 0, framesDecoded: 0, skipped: 0, bytes: 0, tiles: 0, topologies: 0,
    entities: 0, decodeErrors: 0, serverErrors: 0, camerasSent: 0, decodeMs: 0, lastError: '',
};
const byteRate = new ByteRate(); /* bytes a second over the last second */

function post(msg, transfer) { self.postMessage(msg, transfer || []); }

function nextSeq() { seq = (seq + 1) >>> 0; return seq; }

function send(buf) {
    if (ws && ws.readyState === 1) ws.send(buf);
}

/* Chooses the subscription from what the page asked and what HELLO offers. */
function chooseSubscription(h, want) {
    const codecOrder = want.codec != null ? [want.codec, CODEC.QZ, CODEC.F16, CODEC.F32] : [CODEC.QZ, CODEC.F16, CODEC.F32];
    const codec = codecOrder.find((c) => c <= CODEC.QZ && (h.codecs & (1 << c)));
    if (codec === undefined) throw new ProtoError(9, `server offers no codec this viewer decodes (codecs 0x${h.codecs.toString(16)})`);
    let policy = want.cutoffPolicy ?? CUTOFF.ANTIALIAS;
    if (!(h.cutoffPolicies & (1 << policy))) policy = [CUTOFF.ANTIALIAS, CUTOFF.SEED, CUTOFF.NONE].find((p) => h.cutoffPolicies & (1 << p)) ?? 0;
    const meshKind = (h.meshKinds & (1 << MESH.CONCENTRIC)) ? MESH.CONCENTRIC : MESH.NONE;
    const layout = want.layout === LAYOUT.WORLD ? LAYOUT.WORLD : LAYOUT.CASCADE;
    const effects = (want.effects ?? FX.ALL) & (h.effects || FX.ALL);
    return {
        effects: effects || FX.HEIGHT,
        meshKind,
        codec,
        cutoffPolicy: policy,
        /* replay (the page's t=): each CAMERA asks for its frame at its render_time */
        mode: want.mode === MODE.REPLAY ? MODE.REPLAY : MODE.LIVE,
        layers: Math.max(1, Math.min(want.layers ?? h.maxLayers, h.maxLayers)),
        lodLevels: Math.max(1, Math.min(want.lodLevels ?? 8, h.maxLodLevels)),
        tileSize: Math.max(2, Math.min(want.tileSize ?? 64, h.maxTileSize)),
        frameRateHz: Math.min(want.frameRateHz ?? 30, h.maxFrameRateHz),
        accuracy: want.accuracy ?? 5e-3,
        baseSpacingM: want.baseSpacingM ?? 0,
        viewRangeM: want.viewRangeM ?? 0,
        layout,
        /* layout 0: mesh positions compressed unless the page asks for f32;
         * layout 1 sends none (and an older daemon wants 0 there) */
        meshCodec: layout === LAYOUT.WORLD && want.meshCodec !== MESH_CODEC.F32 ? MESH_CODEC.QZ : MESH_CODEC.F32,
        /* layout 1: each mip travels once per its own update interval and
         * the decode workers hold and blend its samples (PROTOCOL.md
         * "Samples in time"), unless the page asks for every tick's tiles */
        flags: layout === LAYOUT.CASCADE && want.timeInterp !== false ? SUB_FLAG.TIME_INTERP : 0,
    };
}

let wsUrl = '';
let closing = false;         /* the page asked to close: do not reconnect */
let retryMs = 500;
let paused = false;
let captureNext = false;          /* page hidden: frames are counted, not decoded */

/* Opens the socket; after a loss it reconnects with backoff (0.5 s doubling
 * to 10 s) and the new HELLO re-subscribes, so a restarted daemon or a
 * dropped link heals without a reload. */
function connect(url, want) {
    wsUrl = url;
    if (want) wantSub = want;
    post({ kind: 'status', state: 'connecting', url });
    try {
        ws = new WebSocket(url, SUBPROTOCOL);
    } catch (e) {
        post({ kind: 'status', state: 'failed', reason: String(e.message || e) });
        return;
    }
    ws.binaryType = 'arraybuffer';
    ws.onopen = () => { retryMs = 500; post({ kind: 'status', state: 'open', protocol: ws.protocol }); };
    ws.onclose = (ev) => {
        subscription = null;
        hello = null;
        if (meshQz) meshQz.clear();   /* mesh ids are per connection */
        heldReset();                  /* so are held samples */
        post({ kind: 'status', state: 'closed', code: ev.code, reason: ev.reason, retryMs: closing ? null : retryMs });
        if (!closing) {
            setTimeout(() => connect(wsUrl, null), retryMs);
            retryMs = Math.min(retryMs * 2, 10000);
        }
    };
    ws.onerror = () => post({ kind: 'status', state: 'error' });
    ws.onmessage = (ev) => onMessage(ev.data);
}

function noteError(e, what) {
    stats.decodeErrors++;
    stats.lastError = `${what}: ${e.message || e}`;
    post({ kind: 'error', source: 'client', message: stats.lastError, code: e.code ?? 0 });
}

function onMessage(data) {
    const now = performance.now();
    if (typeof data === 'string') {
        noteError(new Error('text message on a binary protocol'), 'message');
        return;
    }
    stats.messages++;
    stats.bytes += data.byteLength;
    byteRate.add(now, data.byteLength);
    let hdr;
    try {
        hdr = decodeHeader(new Uint8Array(data));
    } catch (e) {
        noteError(e, 'header');
        return;
    }
    if (hdr.type === T.FRAME) {
        /* what every message we send says we received last (PROTOCOL.md
         * "Header"): the daemon paces this link's frames by it */
        lastSimTime = hdr.simTime;
        stats.frames++;
        if (pendingFrame) stats.skipped++;
        /* latency is taken at arrival, before any decoding queue */
        let latencyMs = null;
        if (hdr.length >= 56) {
            const s = new DataView(data).getUint32(32 + 40, true);
            if (s !== 0xffffffff && s !== answeredSeq && sentAt.has(s)) {
                latencyMs = now - sentAt.get(s);
                answeredSeq = s;
                for (const k of sentAt.keys()) if (((s - k) >>> 0) < 0x80000000) sentAt.delete(k); else break;
            }
        }
        if (latencyMs != null) lastLatency = latencyMs;
        if (captureNext) { captureNext = false; post({ kind: 'capture', bytes: data.slice(0) }); }
        if (timed()) heldApply(data);  /* every frame, in order, drawn or not */
        if (paused) return;
        pendingFrame = data;
        schedule();
        return;
    }
    let msg;
    try {
        msg = decode(data);
    } catch (e) {
        noteError(e, hdr ? `decoding ${hdr.type}` : 'decode');
        return;
    }
    switch (msg.type) {
    case T.HELLO: {
        hello = msg.body;
        sentAt.clear();  /* a new connection answers none of the old CAMERAs */
        /* its server sends the entities and the patterns anew */
        if (wakeStore) wakeStore.destroy();
        wakeStore = null;
        entities.clear();
        seaDepth = hello.sea.depthM;
        const h = { ...hello, sea: { ...hello.sea, seed: hello.sea.seed.toString() } };
        post({ kind: 'hello', hello: h, simTime: hdr.simTime });
        try {
            subscription = chooseSubscription(hello, wantSub || {});
            send(encodeSubscribe(subscription, nextSeq(), lastSimTime));
            post({ kind: 'subscribed', sub: subscription, codecName: CODEC_NAMES[subscription.codec] });
        } catch (e) {
            noteError(e, 'subscribe');
        }
        break;
    }
    case T.MESH_TOPOLOGY: {
        stats.topologies++;
        const t = msg.body;
        /* kept before the arrays go to the page: has_mesh 2 frames are
         * predicted over this topology's triangles */
        if (subscription && subscription.meshCodec === MESH_CODEC.QZ) {
            meshQz.add(t.meshId, t.vertexCount, t.indices);
        }
        const transfer = [t.indices.buffer, t.morph.buffer, t.level.buffer];
        if (t.flat) transfer.push(t.flat.buffer, t.zones.buffer);
        post({ kind: 'topology', meshId: t.meshId, meshKind: t.meshKind, lodLevels: t.lodLevels, flags: t.flags,
            vertexCount: t.vertexCount, indices: t.indices, morph: t.morph, level: t.level, flat: t.flat, zones: t.zones },
        transfer);
        break;
    }
    case T.MESH_VERTICES: {
        const v = msg.body;
        post({ kind: 'vertices', meshId: v.meshId, origin: v.origin, positions: v.positions, simTime: hdr.simTime },
            [v.positions.buffer]);
        break;
    }
    case T.TILE:
        /* Standalone tiles are not part of a live subscription's stream. */
        break;
    case T.SEA_STATE: {
        const s = msg.body;
        seaDepth = s.sea.depthM;   /* the depth a new pattern is for: the newest sea's */
        post({ kind: 'sea', effectiveTime: s.effectiveTime, sea: { ...s.sea, seed: s.sea.seed.toString() } });
        break;
    }
    case T.QUERY_RESULT:
        post({ kind: 'result', result: msg.body });
        break;
    case T.ERROR: {
        stats.serverErrors++;
        const e = msg.body;
        stats.lastError = `server: ${RESULT_NAMES[e.code] || e.code}: ${e.message}`;
        post({ kind: 'error', source: 'server', code: e.code, message: e.message, offendingType: e.offendingType });
        break;
    }
    case T.BYE:
        post({ kind: 'bye', reason: BYE_REASONS[msg.body.reason] || String(msg.body.reason), message: msg.body.message });
        break;
    case T.ENTITY: {
        /* the entities in the sea, newest sample each (drawn by none yet:
         * counted for the overlay and the tests) */
        const e = msg.body;
        if (e.op === 0) entities.set(e.id, e);
        else if (e.op === 4) entities.delete(e.id);
        stats.entities = entities.size;
        wakeFeed(data);
        break;
    }
    case T.WAKE:
        stats.wakePatterns = (stats.wakePatterns || 0) + 1;
        wakeFeed(data);
        break;
    default:
        break;
    }
}

/* ---- decode pool -------------------------------------------------------- */

/* Tile decoding is the expensive part (qz: zstd + prediction), so levels
 * are spread over a pool of decoder workers, balanced by sample count.
 * One frame is in flight at a time; newer frames coalesce meanwhile. */
const POOL_SIZE = Math.max(1, Math.min(4, ((self.navigator && self.navigator.hardwareConcurrency) || 2) - 1));
let pool = null;             /* Worker[]; [] = decode here (no pool) */
let inflight = null;         /* {id, meta, remaining, levels, t0} */
let jobId = 0;

function getPool() {
    if (pool) return pool;
    pool = [];
    try {
        for (let i = 0; i < POOL_SIZE; i++) {
            const w = new Worker(new URL('./decoder.js', import.meta.url), { type: 'module' });
            w.onmessage = onPoolResult;
            w.onerror = (e) => {
                /* a broken pool must not stall the stream: decode here from now on */
                noteError(new Error(e.message || 'decoder worker failed'), 'decode pool');
                for (const x of pool) x.terminate();
                pool = [];
                inflight = null;
                /* the samples it held are gone: a new connection starts
                 * with a KEY frame, which the store here then follows */
                if (timed() && ws) ws.close(4000, 'decode pool failed');
                schedule();
            };
            pool.push(w);
        }
    } catch (e) {
        for (const x of pool) x.terminate();
        pool = [];
    }
    return pool;
}

function schedule() {
    if (!frameScheduled && pendingFrame && !pageHolds) {
        frameScheduled = true;
        setTimeout(processFrame, 0);
    }
}

function processFrame() {
    frameScheduled = false;
    if (inflight) return;                   /* resumed when the pool answers */
    const data = pendingFrame;
    pendingFrame = null;
    if (!data) return;
    const t0 = performance.now();
    let msg;
    try {
        msg = decode(data);
    } catch (e) {
        noteError(e, 'FRAME');
        return;
    }
    const f = msg.body;
    const meta = {
        simTime: msg.hdr.simTime, tick: f.tick, cutoffK: f.cutoffK, eError: f.eError, origin: f.origin,
        cameraSeq: f.cameraSeq, tileCount: f.tileCount, bytes: data.byteLength, layout: f.layout,
        codecs: [...new Set(f.tiles.map((t) => CODEC_NAMES[t.codec]))].join('+'),
        mesh: f.mesh ? { meshId: f.mesh.meshId, origin: f.mesh.origin, positions: f.mesh.positions } : null,
    };
    if (f.mesh && f.hasMesh === 2) {
        /* compressed positions: decoded here with the topology's refs */
        try {
            const refs = meshQz.refs(f.mesh.meshId, f.mesh.vertexCount);
            if (!refs)
                throw new ProtoError(12, `no MESH_TOPOLOGY for the frame's mesh ${f.mesh.meshId}`);
            meta.mesh.positions = decodeMeshQz(f.mesh.qz, f.mesh.vertexCount, refs);
        } catch (e) {
            noteError(e, 'FRAME mesh');
            meta.mesh = null;
        }
    }
    if (f.layout === LAYOUT.CASCADE) {
        meta.cascades = f.cascades;
        meta.placement = f.placement;
        if (timed()) processHeldFrame(meta, t0);
        else processCascadeFrame(f, meta, t0);
        return;
    }
    const groups = groupByLevel(f.tiles);
    const p = getPool();
    if (!p.length) {
        const levels = [];
        for (const [L, tiles] of groups) {
            const rec = assembleLevel(L, tiles, noteError);
            if (rec) levels.push(rec);
        }
        finishFrame({ meta, levels, t0 });
        return;
    }
    const buckets = p.map(() => ({ levels: [], load: 0, transfer: [] }));
    for (const [L, tiles] of groups) {
        let load = 0;
        for (const t of tiles) load += t.width * t.height * tilePlanes(t.channels);
        const b = buckets.reduce((m, x) => (x.load < m.load ? x : m), buckets[0]);
        const copies = tiles.map((t) => ({ ...t, payload: t.payload.slice() }));
        for (const c of copies) b.transfer.push(c.payload.buffer);
        b.levels.push({ level: L, tiles: copies });
        b.load += load;
    }
    dispatchBuckets(p, buckets, 'levels', meta, t0);
}

/* Posts each bucket's work (its `field`: 'levels' or 'tiles') to its pool
 * worker as one job, the frame's inflight record counting the answers; a
 * frame with no work for any worker is finished at once. */
function dispatchBuckets(p, buckets, field, meta, t0) {
    const busy = buckets.map((b, i) => [b, i]).filter(([b]) => b[field].length);
    inflight = { id: ++jobId, meta, remaining: busy.length, levels: [], blocks: [], t0 };
    if (!busy.length) {
        const job = inflight;
        inflight = null;
        finishFrame(job);
        return;
    }
    for (const [b, i] of busy) p[i].postMessage({ id: inflight.id, [field]: b[field] }, b.transfer);
}

/* Layout 1: every tile is independent (its own place in its own mip), so
 * the pool gets shares of the tiles balanced by sample count. */
function processCascadeFrame(f, meta, t0) {
    meta.layout = LAYOUT.CASCADE;
    meta.mesh = null;
    const p = getPool();
    if (!p.length) {
        const blocks = [];
        for (const t of f.tiles) {
            const b = assembleCascadeTile(t, noteError);
            if (b) blocks.push(b);
        }
        finishFrame({ meta, levels: [], blocks, t0 });
        return;
    }
    const buckets = p.map(() => ({ tiles: [], load: 0, transfer: [] }));
    for (const t of f.tiles) {
        const b = buckets.reduce((m, x) => (x.load < m.load ? x : m), buckets[0]);
        const c = { ...t, payload: t.payload.slice() };
        b.tiles.push(c);
        b.transfer.push(c.payload.buffer);
        b.load += t.width * t.height * tilePlanes(t.channels);
    }
    dispatchBuckets(p, buckets, 'tiles', meta, t0);
}

/* ---- samples in time ---------------------------------------------------- */

/* A time-interpolating stream (PROTOCOL.md "Samples in time"): a FRAME
 * carries only the samples that are new, so the store of what this
 * connection holds must see every frame in order, while drawing still
 * takes the newest only.  Each pool worker holds the tiles of its shard
 * (HeldStore, the C library's store): every frame goes to all of them as
 * it arrives (cheap: the payloads are copied, decoded only when first
 * blended), and a frame to draw asks each for its blend.  Without a pool
 * the store is here. */
let localHeld = null;

function timed() {
    return !!subscription && subscription.layout === LAYOUT.CASCADE && (subscription.flags & SUB_FLAG.TIME_INTERP) !== 0;
}

function heldApply(data) {
    const p = getPool();
    if (!p.length) {
        try {
            if (!localHeld) localHeld = new HeldStore(0, 1);
            localHeld.apply(data);
        } catch (e) {
            noteError(e, 'FRAME (held samples)');
        }
        return;
    }
    p.forEach((w, i) => {
        const copy = data.slice(0);
        w.postMessage({ held: 'apply', frame: copy, shard: i, shards: p.length }, [copy]);
    });
}

function heldReset() {
    if (localHeld) localHeld.destroy();
    localHeld = null;
    if (pool) for (const w of pool) w.postMessage({ held: 'reset' });
}

function processHeldFrame(meta, t0) {
    meta.layout = LAYOUT.CASCADE;
    meta.mesh = null;
    const p = getPool();
    if (!p.length) {
        finishFrame({ meta, levels: [], blocks: localHeld ? heldBlocks(localHeld, noteError) : [], t0 });
        return;
    }
    inflight = { id: ++jobId, meta, remaining: p.length, levels: [], blocks: [], t0 };
    for (const w of p) w.postMessage({ id: inflight.id, held: 'blend' });
}

function onPoolResult(ev) {
    const r = ev.data;
    if (!inflight || r.id !== inflight.id) return;
    inflight.levels.push(...r.levels);
    if (r.blocks) inflight.blocks.push(...r.blocks);
    for (const e of r.errors) noteError(new ProtoError(13, e), 'decode');
    if (--inflight.remaining > 0) return;
    const job = inflight;
    inflight = null;
    job.levels.sort((a, b) => a.level - b.level);
    finishFrame(job);
    schedule();
}

function finishFrame(job) {
    const { meta, levels, t0 } = job;
    const blocks = job.blocks || [];
    const now = performance.now();
    stats.tiles += levels.reduce((n, L) => n + L.tiles, 0) + blocks.length;
    stats.decodeMs = now - t0;
    stats.framesDecoded++;
    const latencyMs = lastLatency;
    lastLatency = null;
    const transfer = [];
    for (const L of levels) transfer.push(L.disp.buffer, L.nrm.buffer);
    for (const b of blocks) transfer.push(b.disp.buffer, b.slope.buffer);
    const wakes = wakeGrid(meta, now);
    if (wakes) transfer.push(wakes.data.buffer);
    const out = {
        kind: 'frame', ...meta, mesh: meta.mesh, levels, blocks, latencyMs, bytesPerSec: byteRate.perSecond(now),
        decodeWorkers: pool ? pool.length : 0, stats: { ...stats }, wakes,
    };
    if (meta.mesh) transfer.push(meta.mesh.positions.buffer);
    pageHolds = true;
    post(out, transfer);
}

self.onmessage = (ev) => {
    const m = ev.data;
    switch (m.cmd) {
    case 'connect':
        decodersReady.then(() => connect(m.url, m.sub || {}), (e) => {
            stats.lastError = `decoders: ${e.message || e}`;
            post({ kind: 'status', state: 'failed', reason: stats.lastError });
            post({ kind: 'error', source: 'client', message: stats.lastError, code: 0 });
        });
        break;
    case 'camera': {
        if (Number.isFinite(m.cam.yawDeg)) wakeYaw = m.cam.yawDeg;
        if (!subscription) return;
        /* replay: every CAMERA is answered by a frame; two in flight keep
         * the stream full without queueing on the daemon */
        if (subscription.mode === MODE.REPLAY && sentAt.size >= 2) return;
        const s = nextSeq();
        try {
            send(encodeCamera(m.cam, s, lastSimTime));
        } catch (e) {
            noteError(e, 'camera');
            return;
        }
        stats.camerasSent++;
        sentAt.set(s, performance.now());
        if (sentAt.size > 1000) sentAt.delete(sentAt.keys().next().value);
        break;
    }
    case 'subscribe':
        /* change of subscription (e.g. base spacing after a climb) */
        wantSub = { ...(wantSub || {}), ...m.sub };
        if (hello && ws && ws.readyState === 1) {
            try {
                subscription = chooseSubscription(hello, wantSub);
                send(encodeSubscribe(subscription, nextSeq(), lastSimTime));
                post({ kind: 'subscribed', sub: subscription, codecName: CODEC_NAMES[subscription.codec] });
            } catch (e) {
                noteError(e, 'subscribe');
            }
        }
        break;
    case 'query':
        try { send(encodeQuery(m.id, m.points, m.t ?? null, nextSeq(), lastSimTime)); } catch (e) { noteError(e, 'query'); }
        break;
    case 'sea':
        /* an admin's SEA_STATE set: answered by its announce, or an ERROR */
        try { send(encodeSeaState(1, m.t, m.sea, m.token, nextSeq(), lastSimTime)); } catch (e) { noteError(e, 'sea state'); }
        break;
    case 'capture':
        /* debugging aid: the next FRAME's raw bytes go to the page */
        captureNext = true;
        break;
    case 'taken':
        /* the page applied the frame we posted: decode the newest next */
        pageHolds = false;
        schedule();
        break;
    case 'pause':
        paused = !!m.paused;
        break;
    case 'close':
        closing = true;
        if (ws) {
            try { send(encodeBye(0, 'viewer closed', nextSeq(), lastSimTime)); } catch { /* closing anyway */ }
            ws.close(1000, 'bye');
        }
        break;
    default:
        break;
    }
};
