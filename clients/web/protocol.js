/*
 * protocol.js - the ocean.v1 wire protocol in JavaScript: message decoder
 * and the encoders a viewer needs (SUBSCRIBE, CAMERA, QUERY, BYE).
 *
 * Mirrors protocol/proto.c (the C binding of protocol/PROTOCOL.md): every
 * message is a 32-byte little-endian header followed by a typed payload.
 * The decoder treats input as hostile, exactly like the C one: it checks
 * the magic, version, type, reserved bytes, every length and count, enum
 * values, and refuses NaN/Inf where a number must be finite.  Failures
 * throw a ProtoError whose `code` is the ocean_result value the C decoder
 * returns for the same bytes and whose message names the field.
 *
 * Pure functions over bytes: no sockets, no DOM, so it runs in a Worker and
 * under node for tests.
 */

export const SUBPROTOCOL = 'ocean.v1';
export const MAGIC = 0x574e434f; /* "OCNW" */
export const VERSION = 1;
export const HEADER_SIZE = 32;

export const T = Object.freeze({
    HELLO: 1, SUBSCRIBE: 2, CAMERA: 3, FRAME: 4, TILE: 5, MESH_TOPOLOGY: 6,
    MESH_VERTICES: 7, QUERY: 8, QUERY_RESULT: 9, SEA_STATE: 10, ERROR: 11, BYE: 12, ENTITY: 13, WAKE: 14,
});
const TYPE_END = 15;
export const TYPE_NAMES = ['?', 'HELLO', 'SUBSCRIBE', 'CAMERA', 'FRAME', 'TILE', 'MESH_TOPOLOGY',
    'MESH_VERTICES', 'QUERY', 'QUERY_RESULT', 'SEA_STATE', 'ERROR', 'BYE', 'ENTITY', 'WAKE'];

export const FX = Object.freeze({ HEIGHT: 1, DISPLACEMENT: 2, NORMALS: 4, FOAM: 8, NEAR_FIELD: 16, ALL: 31 });
export const MESH = Object.freeze({ CONCENTRIC: 0, CHUNKED: 1, PROJECTED: 2, NONE: 3 });
export const MESH_KIND_COUNT = 4;
export const CUTOFF = Object.freeze({ NONE: 0, SEED: 1, ANTIALIAS: 2 });
export const CUTOFF_POLICY_COUNT = 3;
export const MODE = Object.freeze({ LIVE: 0, REPLAY: 1 });
export const MODE_COUNT = 2;
export const CODEC = Object.freeze({ F32: 0, F16: 1, QZ: 2, EXR_ZIP: 3, EXR_PIZ: 4, EXR_B44: 5, EXR_B44A: 6 });
export const CODEC_COUNT = 7;
export const CODEC_NAMES = ['f32', 'f16', 'qz', 'exr-zip', 'exr-piz', 'exr-b44', 'exr-b44a'];
export const CH = Object.freeze({ HEIGHT: 1, DX: 2, DZ: 4, NORMAL: 8, FOAM: 16, JACOBIAN: 32, BREAKING: 64, ALL: 0x7f });
export const BYE_REASONS = ['normal', 'shutdown', 'slow consumer', 'protocol error', 'auth', 'server full', 'idle'];
export const NO_CAMERA = 0xffffffff;
/* SUBSCRIBE.layout / FRAME.layout (PROTOCOL.md "Layouts"). */
export const LAYOUT = Object.freeze({ WORLD: 0, CASCADE: 1 });
/* SUBSCRIBE.mesh_codec: how layout-0 mesh positions travel (FRAME.has_mesh 1 / 2). */
export const MESH_CODEC = Object.freeze({ F32: 0, QZ: 2 });
/* SUBSCRIBE.flags: FULL_GEOMETRY asks every layout-1 mip with height and
 * displacement, whatever the mesh (PROTOCOL.md "Where each mip is read");
 * TIME_INTERP: the client holds each mip's samples and blends two in time
 * (PROTOCOL.md "Samples in time") */
export const SUB_FLAG = Object.freeze({ FULL_GEOMETRY: 1, TIME_INTERP: 2 });
const SUB_FLAGS_ALL = 3;
export const MESH_QZ_HEAD = 36;
export const LAYOUT_COUNT = 2;
export const MAX_MIPS = 12;
export const MIP_ENTRIES = 13;
/* MESH_TOPOLOGY.flags bit: flat positions and level zones follow. */
export const TOPO_FLAT = 1;

/* ocean_result codes (sim/ocean_result.h). */
export const R = Object.freeze({
    OK: 0, EINVAL: 1, ENOMEM: 2, EIO: 3, EFORMAT: 4, EVERSION: 5, ETYPE: 6, ETRUNC: 7,
    ETOOBIG: 8, EUNSUPPORTED: 9, EAUTH: 10, ERATE: 11, ESTATE: 12, ECODEC: 13, ENOTFOUND: 14,
    EDIVERGED: 15,
});
export const RESULT_NAMES = ['ok', 'invalid argument', 'out of memory', 'i/o error', 'malformed input',
    'unsupported version', 'unknown type', 'truncated input', 'too big', 'unsupported', 'not authorised',
    'rate limited', 'wrong state', 'codec error', 'not found', 'diverged'];

export const LIMITS = Object.freeze({
    maxMessage: 64 << 20,
    maxQueryPoints: 65536,
    maxFrameTiles: 4096,
    maxVertices: 1 << 22,
    maxIndices: 3 * (1 << 23),
    maxLevel: 31,
    maxLodLevels: 16,
    maxLayers: 4,
    maxFrameRate: 240,
    tileMaxSize: 1024,
    accuracyMin: 1e-6,
    accuracyMax: 0.5,
});

const SEA_SIZE = 96, SUBSCRIBE_SIZE = 28, CAMERA_SIZE = 64, TILE_FIXED = 48, FRAME_FIXED = 56;
const RECORD_HEAD = 8, TOPO_FIXED = 16, VERTS_FIXED = 32, QUERY_FIXED = 24, RESULT_FIXED = 16;
const SAMPLE_SIZE = 36, SEASTATE_FIXED = 16 + SEA_SIZE, ERROR_FIXED = 8, BYE_FIXED = 4, ENTITY_FIXED = 56;
const WAKE_FIXED = 48, PLANE_MAX = 4096;
/* sea state flags (PROTOCOL.md "Sea state block") */
export const SEA_NO_WHITECAPS = 0x01;
const SEA_FLAGS_ALL = 0x01;
const CASCADE_FIXED = 56, CASCADE_ENTRY = 320, PLACEMENT_SIZE = 32, FOAM_ROWS = 16, FOAM_TABLE = 8 + 12 * FOAM_ROWS;
/* Cascade block flag KEY, and a layout-1 record tag's sample-B bit
 * (PROTOCOL.md "Samples in time"). */
const CASCADE_KEY = 1, CASCADE_FOAM = 2, CASCADE_READ = 4, TAG_SLOT_B = 0x100;
/* The read table (PROTOCOL.md "Whitecaps in layout 1"): per cascade, per
 * mip < MAX_MIPS, a u16 share / 32768 for each kernel. */
export const READ = Object.freeze({ BILINEAR: 0, KEYS: 1, LANCZOS3: 2, KERNELS: 3 });
const MAX_WORLD = 1e10, MAX_LOCAL = 1e7;
// what the server derives from a camera within MAX_WORLD reaches past it by
// one frame's cover (view range, coarsest tile): as protocol/proto.c
const MAX_ORIGIN = MAX_WORLD + 2 * MAX_LOCAL;

export class ProtoError extends Error {
    constructor(code, message) {
        super(message);
        this.name = 'ProtoError';
        this.code = code;
    }
}

function fail(code, msg) { throw new ProtoError(code, msg); }

function f32(x) { return Math.fround(x); }

function chkRange(what, v, lo, hi) {
    if (!Number.isFinite(v)) fail(R.EINVAL, `${what} is ${v}; must be finite`);
    if (v < lo || v > hi) fail(R.EINVAL, `${what} = ${v} outside [${lo}, ${hi}]`);
}
/* The one time limit (sim/ocean_time.h, PROTOCOL.md "Times"): |t| <= 2^27 s. */
export const TIME_MAX = 134217728;
function chkTime(what, v) {
    if (!(v >= -TIME_MAX && v <= TIME_MAX))
        fail(R.EINVAL, `${what} = ${v} s is beyond the time limit +-${TIME_MAX} s (OCEAN_TIME_MAX)`);
}
function chkMask(what, v, allowed) {
    if ((v & ~allowed) >>> 0) fail(R.ETYPE, `${what} 0x${v.toString(16)} has unknown bits`);
}
function chkEnum(what, v, count) {
    if (v >= count) fail(R.ETYPE, `${what} ${v} unknown (valid 0..${count - 1})`);
}

/* Number of float planes a channel mask makes (the normal counts twice); 0
 * for an empty mask or unknown bits. */
export function tilePlanes(channels) {
    if (channels === 0 || (channels & ~CH.ALL)) return 0;
    return tilePlaneNames(channels).length;
}

/* Plane names of a tile in wire order (H DX DZ NU NV FOAM J BI BQ, present ones). */
export function tilePlaneNames(channels) {
    const names = ['H', 'DX', 'DZ', 'NU', 'NV', 'FOAM', 'J', 'BI', 'BQ'], bit = [0, 1, 2, 3, 3, 4, 5, 6, 6];
    const out = [];
    for (let s = 0; s < names.length; s++) if (channels & (1 << bit[s])) out.push(names[s]);
    return out;
}

/* Bytes of a cascade block of cc cascades with block flags `flags`. */
function cascadeBlockBytes(cc, flags) {
    return CASCADE_FIXED + cc * CASCADE_ENTRY + (flags & CASCADE_FOAM ? FOAM_TABLE : 0) +
        (flags & CASCADE_READ ? cc * 2 * READ.KERNELS * MAX_MIPS : 0);
}

/* ---- reader ----------------------------------------------------------- */

const utf8 = new TextDecoder('utf-8', { fatal: true });
const utf8enc = new TextEncoder();

class Reader {
    constructor(u8, what) {
        this.u8 = u8;
        this.dv = new DataView(u8.buffer, u8.byteOffset, u8.byteLength);
        this.off = HEADER_SIZE;
        this.end = u8.byteLength;
        this.what = what;
    }
    need(k, field) {
        if (this.end - this.off < k)
            fail(R.ETRUNC, `${this.what}: ${field} needs ${k} bytes at offset ${this.off}, only ${this.end - this.off} left`);
    }
    zero(at, n, field) {
        for (let i = 0; i < n; i++)
            if (this.u8[at + i] !== 0)
                fail(R.EFORMAT, `${this.what}: reserved ${field} byte at offset ${at + i} is 0x${this.u8[at + i].toString(16)}, must be 0`);
    }
    u8at(o) { return this.u8[o]; }
    u16(o) { return this.dv.getUint16(o, true); }
    u32(o) { return this.dv.getUint32(o, true); }
    i32(o) { return this.dv.getInt32(o, true); }
    u64(o) { return this.dv.getBigUint64(o, true); }
    f32(o) { return this.dv.getFloat32(o, true); }
    f64(o) { return this.dv.getFloat64(o, true); }
    str(max, field) {
        this.need(2, field);
        const n = this.u16(this.off);
        if (n > max) fail(R.ETOOBIG, `${this.what}: ${field} of ${n} bytes longer than ${max}`);
        this.off += 2;
        this.need(n, field);
        const bytes = this.u8.subarray(this.off, this.off + n);
        let s;
        try { s = utf8.decode(bytes); } catch { fail(R.EFORMAT, `${this.what}: ${field} is not valid UTF-8 (or holds NUL)`); }
        if (s.includes('\0')) fail(R.EFORMAT, `${this.what}: ${field} is not valid UTF-8 (or holds NUL)`);
        this.off += n;
        return s;
    }
    finish() {
        if (this.off !== this.end)
            fail(R.EFORMAT, `${this.what}: ${this.end - this.off} unexpected bytes after the last field (offset ${this.off})`);
    }
    /* Little-endian float32 array copied out (the source may be unaligned). */
    floats(count, field) {
        this.need(count * 4, field);
        const out = new Float32Array(count);
        const o = this.u8.byteOffset + this.off;
        if ((o & 3) === 0 && littleEndianHost) out.set(new Float32Array(this.u8.buffer, o, count));
        else for (let i = 0; i < count; i++) out[i] = this.dv.getFloat32(this.off + 4 * i, true);
        this.off += count * 4;
        return out;
    }
}

const littleEndianHost = new Uint8Array(new Uint32Array([1]).buffer)[0] === 1;

/* ---- header ----------------------------------------------------------- */

/* Reads and checks the 32-byte header of a complete message.  Returns
 * {version, type, flags, length, seq, simTime}. */
export function decodeHeader(u8, limits = LIMITS) {
    if (!(u8 instanceof Uint8Array)) u8 = new Uint8Array(u8);
    const len = u8.byteLength;
    if (len < HEADER_SIZE) fail(R.ETRUNC, `message of ${len} bytes is shorter than the ${HEADER_SIZE}-byte header`);
    const dv = new DataView(u8.buffer, u8.byteOffset, len);
    const magic = dv.getUint32(0, true);
    if (magic !== MAGIC) fail(R.EFORMAT, `bad magic 0x${magic.toString(16).padStart(8, '0')} (expected "OCNW")`);
    const h = {
        version: dv.getUint16(4, true),
        type: dv.getUint16(6, true),
        flags: dv.getUint32(8, true),
        length: dv.getUint32(12, true),
        seq: dv.getUint32(16, true),
        simTime: dv.getFloat64(24, true),
    };
    if (h.version !== VERSION)
        fail(R.EVERSION, `protocol version ${h.version} not supported (this side speaks ${VERSION}, subprotocol ${SUBPROTOCOL})`);
    if (h.type < 1 || h.type >= TYPE_END) fail(R.ETYPE, `message type ${h.type} unknown (valid 1..${TYPE_END - 1})`);
    const name = TYPE_NAMES[h.type];
    if (h.flags !== 0 || dv.getUint32(20, true) !== 0)
        fail(R.EFORMAT, `${name} header: flags / reserved must be 0 in version 1`);
    if (!(h.simTime >= -TIME_MAX && h.simTime <= TIME_MAX))
        fail(R.EINVAL, `${name} header: sim_time = ${h.simTime} s is beyond the time limit +-${TIME_MAX} s (OCEAN_TIME_MAX)`);
    if (h.length + HEADER_SIZE > limits.maxMessage)
        fail(R.ETOOBIG, `${name} of ${h.length + HEADER_SIZE} bytes exceeds the ${limits.maxMessage}-byte message limit`);
    if (h.length + HEADER_SIZE > len)
        fail(R.ETRUNC, `${name} header declares ${h.length} payload bytes, only ${len - HEADER_SIZE} present`);
    if (h.length + HEADER_SIZE < len)
        fail(R.EFORMAT, `${name}: ${len - HEADER_SIZE - h.length} bytes after the declared ${h.length}-byte payload`);
    return h;
}

/* ---- payload decoders ------------------------------------------------- */

function dSea(r) {
    r.need(SEA_SIZE, 'sea state');
    r.zero(r.off + 3, 5, 'sea');
    const o = r.off;
    const s = {
        spectrum: r.u8at(o), spreading: r.u8at(o + 1), flags: r.u8at(o + 2), seed: r.u64(o + 8),
        windU10: r.f64(o + 16), windDirDeg: r.f64(o + 24), fetchM: r.f64(o + 32), depthM: r.f64(o + 40),
        swell: r.f64(o + 48), phillipsA: r.f64(o + 56), smallWaveM: r.f64(o + 64), choppiness: r.f64(o + 72),
        hs: r.f64(o + 80), tp: r.f64(o + 88),
    };
    r.off += SEA_SIZE;
    return s;
}

function vSea(s) {
    chkEnum('sea.spectrum', s.spectrum, 4);
    chkEnum('sea.spreading', s.spreading, 4);
    chkMask('sea.flags', s.flags || 0, SEA_FLAGS_ALL);
    chkRange('sea.wind_u10', s.windU10, 0, 100);
    chkRange('sea.wind_dir_deg', s.windDirDeg, -360, 360);
    chkRange('sea.fetch_m', s.fetchM, 1, 1e7);
    chkRange('sea.depth_m', s.depthM, 0.01, 12000);
    chkRange('sea.swell', s.swell, 0, 1000);
    chkRange('sea.phillips_a', s.phillipsA, 0, 1e6);
    chkRange('sea.small_wave_m', s.smallWaveM, 0, 1e4);
    chkRange('sea.choppiness', s.choppiness, 0, 10);
    chkRange('sea.hs', s.hs, 0, 1000);
    chkRange('sea.tp', s.tp, 0, 1e4);
}

function dHello(r) {
    r.need(32, 'fixed fields');
    const o = r.off;
    const h = {
        codecs: r.u32(o), meshKinds: r.u8at(o + 4), effects: r.u8at(o + 5), cutoffPolicies: r.u8at(o + 6),
        modes: r.u8at(o + 7), maxMessage: r.u32(o + 8), maxQueryPoints: r.u32(o + 12),
        maxTileSize: r.u16(o + 16), maxLodLevels: r.u8at(o + 18), maxLayers: r.u8at(o + 19),
        tickRateHz: r.f32(o + 20), maxFrameRateHz: r.f32(o + 24), clientId: r.u32(o + 28),
    };
    r.off += 32;
    h.sea = dSea(r);
    h.serverVersion = r.str(63, 'server_version');
    r.finish();
    chkMask('hello.codecs', h.codecs, (1 << CODEC_COUNT) - 1);
    chkMask('hello.mesh_kinds', h.meshKinds, (1 << MESH_KIND_COUNT) - 1);
    chkMask('hello.effects', h.effects, FX.ALL);
    chkMask('hello.cutoff_policies', h.cutoffPolicies, (1 << CUTOFF_POLICY_COUNT) - 1);
    chkMask('hello.modes', h.modes, (1 << MODE_COUNT) - 1);
    if (!h.codecs || !h.modes) fail(R.EINVAL, 'hello announces no codec or no mode');
    if (h.maxMessage < HEADER_SIZE) fail(R.EINVAL, `hello.max_message ${h.maxMessage} below the header size`);
    chkRange('hello.max_tile_size', h.maxTileSize, 2, LIMITS.tileMaxSize);
    chkRange('hello.max_lod_levels', h.maxLodLevels, 1, LIMITS.maxLodLevels);
    chkRange('hello.max_layers', h.maxLayers, 1, LIMITS.maxLayers);
    chkRange('hello.tick_rate_hz', h.tickRateHz, 1e-3, 1000);
    chkRange('hello.max_frame_rate_hz', h.maxFrameRateHz, 1e-3, LIMITS.maxFrameRate);
    vSea(h.sea);
    return h;
}

function dSubscribe(r) {
    r.need(SUBSCRIBE_SIZE, 'fixed fields');
    const o = r.off;
    const s = {
        meshCodec: r.u8at(o + 10), flags: r.u8at(o + 11),
        effects: r.u8at(o), meshKind: r.u8at(o + 1), codec: r.u8at(o + 2), cutoffPolicy: r.u8at(o + 3),
        mode: r.u8at(o + 4), layers: r.u8at(o + 5), lodLevels: r.u8at(o + 6), layout: r.u8at(o + 7), tileSize: r.u16(o + 8),
        frameRateHz: r.f32(o + 12), accuracy: r.f32(o + 16), baseSpacingM: r.f32(o + 20), viewRangeM: r.f32(o + 24),
    };
    r.off += SUBSCRIBE_SIZE;
    r.finish();
    vSubscribe(s);
    return s;
}

function vSubscribe(s) {
    chkMask('subscribe.effects', s.effects, FX.ALL);
    if (!s.effects) fail(R.EINVAL, 'subscribe.effects is empty');
    chkEnum('subscribe.mesh_kind', s.meshKind, MESH_KIND_COUNT);
    chkEnum('subscribe.codec', s.codec, CODEC_COUNT);
    chkEnum('subscribe.cutoff_policy', s.cutoffPolicy, CUTOFF_POLICY_COUNT);
    chkEnum('subscribe.mode', s.mode, MODE_COUNT);
    chkRange('subscribe.layers', s.layers, 1, LIMITS.maxLayers);
    chkRange('subscribe.lod_levels', s.lodLevels, 1, LIMITS.maxLodLevels);
    chkEnum('subscribe.layout', s.layout, LAYOUT_COUNT);
    if (s.meshCodec !== MESH_CODEC.F32 && s.meshCodec !== MESH_CODEC.QZ)
        fail(R.ETYPE, `subscribe.mesh_codec ${s.meshCodec} unknown (0 f32, 2 qz)`);
    if (s.flags & ~SUB_FLAGS_ALL)
        fail(R.EFORMAT, `subscribe.flags 0x${s.flags.toString(16)} has unknown bits (bit 0: full geometry, bit 1: time interpolation)`);
    chkRange('subscribe.tile_size', s.tileSize, 2, LIMITS.tileMaxSize);
    chkRange('subscribe.frame_rate_hz', s.frameRateHz, 0, LIMITS.maxFrameRate);
    if (!(s.frameRateHz > 0)) fail(R.EINVAL, 'subscribe.frame_rate_hz must be > 0');
    chkRange('subscribe.accuracy', s.accuracy, f32(LIMITS.accuracyMin), LIMITS.accuracyMax);
    if (s.baseSpacingM !== 0) chkRange('subscribe.base_spacing_m', s.baseSpacingM, 1e-3, 1e4);
    if (s.viewRangeM !== 0) chkRange('subscribe.view_range_m', s.viewRangeM, 1, 1e7);
}

function dCamera(r) {
    r.need(CAMERA_SIZE, 'fixed fields');
    const o = r.off;
    const k = {
        pos: [r.f64(o), r.f64(o + 8), r.f64(o + 16)],
        vel: [r.f32(o + 24), r.f32(o + 28), r.f32(o + 32)],
        yawDeg: r.f32(o + 36), pitchDeg: r.f32(o + 40), rollDeg: r.f32(o + 44), fovYDeg: r.f32(o + 48),
        viewportW: r.u16(o + 52), viewportH: r.u16(o + 54), renderTime: r.f64(o + 56),
    };
    r.off += CAMERA_SIZE;
    r.finish();
    vCamera(k);
    return k;
}

function vCamera(k) {
    chkRange('camera.pos.x', k.pos[0], -MAX_WORLD, MAX_WORLD);
    chkRange('camera.pos.y', k.pos[1], -MAX_LOCAL, MAX_LOCAL);
    chkRange('camera.pos.z', k.pos[2], -MAX_WORLD, MAX_WORLD);
    for (let i = 0; i < 3; i++) chkRange('camera.velocity', k.vel[i], -1e5, 1e5);
    chkRange('camera.yaw_deg', k.yawDeg, -360, 360);
    chkRange('camera.pitch_deg', k.pitchDeg, -90, 90);
    chkRange('camera.roll_deg', k.rollDeg, -180, 180);
    chkRange('camera.fov_y_deg', k.fovYDeg, 0, 180);
    if (k.fovYDeg <= 0 || k.fovYDeg >= 180) fail(R.EINVAL, `camera.fov_y_deg = ${k.fovYDeg} outside (0, 180)`);
    chkRange('camera.viewport_w', k.viewportW, 1, 16384);
    chkRange('camera.viewport_h', k.viewportH, 1, 16384);
    chkTime('camera.render_time', k.renderTime);
}

/* TILE body; r.end must be the body's end.  The payload is a view into the
 * message (no copy).  Structure only: vTile checks the values (the C
 * decoder parses a whole message before it validates, and refusals must
 * carry the same code in the same order). */
function dTile(r) {
    r.need(TILE_FIXED, 'tile fixed fields');
    const o = r.off;
    const t = {
        level: r.u8at(o), codec: r.u8at(o + 1), channels: r.u16(o + 2), width: r.u16(o + 4), height: r.u16(o + 6),
        ix: r.i32(o + 8), iz: r.i32(o + 12), originX: r.f64(o + 16), originZ: r.f64(o + 24), spacing: r.f64(o + 32),
        errorBound: r.f32(o + 40), payloadLen: r.u32(o + 44), payload: null, cascade: 0,
    };
    r.off += TILE_FIXED;
    r.need(t.payloadLen, 'tile payload');
    t.payload = r.u8.subarray(r.off, r.off + t.payloadLen);
    r.off += t.payloadLen;
    r.finish();
    return t;
}

function vTile(t) {
    chkRange('tile.level', t.level, 0, LIMITS.maxLevel);
    chkEnum('tile.codec', t.codec, CODEC_COUNT);
    chkMask('tile.channels', t.channels, CH.ALL);
    if (!t.channels) fail(R.EINVAL, 'tile.channels is empty');
    chkRange('tile.width', t.width, 1, LIMITS.tileMaxSize);
    chkRange('tile.height', t.height, 1, LIMITS.tileMaxSize);
    chkRange('tile.origin_x', t.originX, -MAX_ORIGIN, MAX_ORIGIN);
    chkRange('tile.origin_z', t.originZ, -MAX_ORIGIN, MAX_ORIGIN);
    chkRange('tile.spacing', t.spacing, 0, 1e6);
    if (!(t.spacing > 0)) fail(R.EINVAL, 'tile.spacing must be > 0');
    chkRange('tile.error_bound', t.errorBound, 0, 1e30);
    if (t.codec === CODEC.F32 || t.codec === CODEC.F16) {
        const want = tilePlanes(t.channels) * t.width * t.height * (t.codec === CODEC.F32 ? 4 : 2);
        if (want !== t.payloadLen)
            fail(R.EFORMAT, `tile ${CODEC_NAMES[t.codec]} payload is ${t.payloadLen} bytes, ${t.width}x${t.height} with ${tilePlanes(t.channels)} planes needs ${want}`);
    } else if (t.payloadLen === 0) {
        fail(R.EFORMAT, 'tile payload is empty');
    }
}

/* MESH_VERTICES body (structure; vVertices checks values). */
function dVerticesHead(r, limits) {
    r.need(VERTS_FIXED, 'mesh vertices fixed fields');
    const o = r.off;
    const v = { meshId: r.u32(o), vertexCount: r.u32(o + 4), origin: [r.f64(o + 8), r.f64(o + 16), r.f64(o + 24)] };
    r.off += VERTS_FIXED;
    if (v.vertexCount > limits.maxVertices)
        fail(R.ETOOBIG, `${r.what}: vertex_count ${v.vertexCount} above the limit ${limits.maxVertices}`);
    return v;
}

function dVertices(r, limits) {
    const v = dVerticesHead(r, limits);
    v.positions = r.floats(3 * v.vertexCount, 'positions');
    r.finish();
    return v;
}

function vVerticesHead(v, limits) {
    if (v.vertexCount === 0) fail(R.EINVAL, 'mesh vertex_count is 0');
    if (v.vertexCount > limits.maxVertices) fail(R.ETOOBIG, `mesh vertex_count ${v.vertexCount} above the limit ${limits.maxVertices}`);
    for (let i = 0; i < 3; i++) chkRange('mesh.origin', v.origin[i], -MAX_ORIGIN, MAX_ORIGIN);
}

function vVerticesQz(v, limits) {
    vVerticesHead(v, limits);
    v.qzHeader = meshQzHeader(v.qz, v.vertexCount);
}

function vVertices(v, limits) {
    vVerticesHead(v, limits);
    const p = v.positions;
    for (let i = 0; i < p.length; i++) {
        const x = p[i];
        if (!(x >= -MAX_LOCAL && x <= MAX_LOCAL))
            fail(R.EINVAL, `mesh position component ${i} is ${x} (finite, |v| <= 1e7 required)`);
    }
}

/* The header of a MESH_VERTICES_QZ payload (PROTOCOL.md; data from its
 * format byte on) for vertexCount vertices, as proto_mesh_qz_header checks
 * it: format 1, predictor 1, reserved 0, finite bases, finite steps > 0,
 * nbytes <= 4, R = sum nbytes * V, then exactly one zstd frame of R bytes
 * (zstdFrameSizes; its blocks are decompressed by decodeMeshQz).  Throws
 * ECODEC. */
export function meshQzHeader(data, vertexCount) {
    const bad = (m) => fail(R.ECODEC, m);
    if (data.byteLength < MESH_QZ_HEAD) bad(`mesh qz payload of ${data.byteLength} bytes shorter than its ${MESH_QZ_HEAD}-byte header`);
    if (data[0] !== 1 || data[1] !== 1) bad(`mesh qz format ${data[0]} / predictor ${data[1]} not supported (format 1, predictor 1)`);
    const dv = new DataView(data.buffer, data.byteOffset, data.byteLength);
    if (dv.getUint16(2, true) !== 0 || data[31] !== 0) bad('mesh qz reserved bytes not 0');
    const h = { format: data[0], predictor: data[1], base: [], step: [], nbytes: [], rawLen: dv.getUint32(32, true) };
    let want = 0;
    for (let a = 0; a < 3; a++) {
        const b = dv.getFloat32(4 + 4 * a, true), st = dv.getFloat32(16 + 4 * a, true), k = data[28 + a];
        if (!Number.isFinite(b) || !Number.isFinite(st) || !(st > 0) || k > 4)
            bad(`mesh qz axis ${'xyz'[a]} header invalid (base ${b}, step ${st}, bytes ${k})`);
        h.base.push(b); h.step.push(st); h.nbytes.push(k);
        want += k * vertexCount;
    }
    if (h.rawLen !== want) bad(`mesh qz residual length ${h.rawLen}, header and ${vertexCount} vertices imply ${want}`);
    const z = zstdFrameSizes(data.subarray(MESH_QZ_HEAD));
    if (!z || z.frameLength !== data.byteLength - MESH_QZ_HEAD || z.contentSize !== want)
        bad(`mesh qz: zstd frame malformed, followed by junk or not of ${want} bytes`);
    return h;
}

/* The content size and length of the zstd frame that u8 starts with (RFC
 * 8878 section 3.1.1: frame header, then blocks up to the last one, then
 * the optional checksum), as libzstd's ZSTD_getFrameContentSize and
 * ZSTD_findFrameCompressedSize give them; null when u8 does not start
 * with a whole frame that states its content size.  Headers only: the
 * blocks are not decompressed. */
export function zstdFrameSizes(u8) {
    const n = u8.byteLength;
    if (n < 5 || u8[0] !== 0x28 || u8[1] !== 0xb5 || u8[2] !== 0x2f || u8[3] !== 0xfd) return null;
    const fhd = u8[4];
    if (fhd & 0x08) return null;                      /* reserved bit */
    const single = (fhd >> 5) & 1;
    const fcsLen = [single ? 1 : 0, 2, 4, 8][fhd >> 6];
    let off = 5 + (single ? 0 : 1) + [0, 1, 2, 4][fhd & 3];
    if (fcsLen === 0 || off + fcsLen > n) return null;   /* no content size, or cut short */
    let size = 0;
    for (let i = fcsLen - 1; i >= 0; i--) size = size * 256 + u8[off + i];
    if (fcsLen === 2) size += 256;
    off += fcsLen;
    for (let last = 0; !last;) {
        if (off + 3 > n) return null;
        const bh = u8[off] | (u8[off + 1] << 8) | (u8[off + 2] << 16);
        const type = (bh >> 1) & 3;
        if (type === 3) return null;                  /* reserved block type */
        last = bh & 1;
        off += 3 + (type === 1 ? 1 : bh >>> 3);       /* RLE blocks carry one byte */
        if (off > n) return null;
    }
    off += fhd & 0x04 ? 4 : 0;                        /* content checksum */
    return off > n ? null : { contentSize: size, frameLength: off };
}

/* FRAME has_mesh 2 record: MESH_VERTICES' fixed fields, then the qz
 * payload kept as bytes (positions need the topology: decodeMeshQz). */
function dVerticesQz(r, limits) {
    const v = dVerticesHead(r, limits);
    v.qz = r.u8.subarray(r.off, r.end);
    v.positions = null;
    r.off = r.end;
    return v;
}

/* Layout-1 mesh record body: where the flat mesh goes this frame. */
function dPlacement(r) {
    r.need(PLACEMENT_SIZE, 'mesh placement');
    const o = r.off;
    const pl = { meshId: r.u32(o) };
    r.zero(o + 4, 4, 'mesh placement');
    pl.origin = [r.f64(o + 8), r.f64(o + 16), r.f64(o + 24)];
    r.off += PLACEMENT_SIZE;
    r.finish();
    return pl;
}

const REC_TILE = 0, REC_VERTICES = 1, REC_PLACEMENT = 2, REC_VERTICES_QZ = 3;

/* One FRAME record: u32 body length, u32 tag (<= maxTag), body, zero
 * padding to a multiple of 8.  Returns [body, tag]. */
function dRecord(r, kind, maxTag, limits) {
    r.need(RECORD_HEAD, 'record header');
    const blen = r.u32(r.off);
    const tag = r.u32(r.off + 4);
    if (tag > maxTag) fail(R.EFORMAT, `${r.what}: record tag ${tag} at offset ${r.off + 4} above ${maxTag}`);
    r.off += RECORD_HEAD;
    r.need(blen, kind === REC_TILE ? 'tile record' : 'mesh record');
    const pad = (8 - (blen & 7)) & 7;
    const bodyEnd = r.off + blen;
    const outer = r.end;
    r.end = bodyEnd;
    let body;
    try {
        body = kind === REC_VERTICES ? dVertices(r, limits) : kind === REC_VERTICES_QZ ? dVerticesQz(r, limits)
            : kind === REC_PLACEMENT ? dPlacement(r) : dTile(r);
    } finally {
        r.end = outer;
    }
    if (r.end - bodyEnd < pad) fail(R.ETRUNC, `${r.what}: record padding of ${pad} bytes missing at offset ${bodyEnd}`);
    r.zero(bodyEnd, pad, 'record padding');
    r.off = bodyEnd + pad;
    return [body, tag];
}

/* The cascade block of a layout-1 FRAME at r.off (PROTOCOL.md "Cascade
 * block"); the caller checked that its C entries are present.  Each
 * cascade's mip table is kept whole (13 entries x kc, mss_x, mss_z,
 * mss_xz) as the wire has it. */
function readCascades(r, cc) {
    const o = r.off;
    const b = {
        cascadeCount: cc, order: r.u8at(o + 1), flags: r.u8at(o + 2), spacingPerM: r.f32(o + 4),
        camera: [r.f64(o + 8), r.f64(o + 16), r.f64(o + 24)], minSpacingM: r.f32(o + 32), eTotal: r.f32(o + 36),
        tailMss: [r.f32(o + 40), r.f32(o + 44), r.f32(o + 48)], geometrySpacingM: r.f32(o + 52), cascade: [],
    };
    for (let k = 0; k < cc; k++) {
        const q = o + CASCADE_FIXED + k * CASCADE_ENTRY;
        const mip = new Float32Array(4 * MIP_ENTRIES);
        for (let m = 0; m < 4 * MIP_ENTRIES; m++) mip[m] = r.f32(q + 16 + 4 * m);
        const time = [];
        for (let m = 0; m < MAX_MIPS; m++) {
            const w = q + 16 + 16 * MIP_ENTRIES + 8 * m;
            time.push({ tickA: r.u32(w), interval: r.u16(w + 4), phase: r.u16(w + 6) });
        }
        b.cascade.push({ patchM: r.f64(q), n: r.u16(q + 8), mips: r.u8at(q + 10), fades: r.u8at(q + 11), spacingPerM: r.f32(q + 12), mip, time });
    }
    /* the whitecap table (PROTOCOL.md "Whitecaps in layout 1"): rows
     * {sigma, a, omega}, all 16 kept for the checks */
    b.foamRows = 0;
    b.foamAll = [];
    b.foam = [];
    if (b.flags & CASCADE_FOAM) {
        const q = o + CASCADE_FIXED + cc * CASCADE_ENTRY;
        b.foamRows = r.u8at(q);
        for (let i = 0; i < FOAM_ROWS; i++) {
            const w = q + 8 + 12 * i;
            b.foamAll.push({ sigma: r.f32(w), a: r.f32(w + 4), omega: r.f32(w + 8) });
        }
        b.foam = b.foamAll.slice(0, b.foamRows);
    }
    /* the read table: held[KERNELS * m + kernel] of each cascade, 0 without it */
    const rt = o + cascadeBlockBytes(cc, b.flags & CASCADE_FOAM);
    b.cascade.forEach((e, k) => {
        e.held = new Uint16Array(READ.KERNELS * MAX_MIPS);
        if (b.flags & CASCADE_READ)
            for (let i = 0; i < e.held.length; i++) e.held[i] = r.u16(rt + 2 * (READ.KERNELS * MAX_MIPS * k + i));
    });
    return b;
}

/* proto.c v_read_table: with READ (and FOAM) every mip that holds waves
 * has a share for each kernel. */
function vReadTable(b) {
    if ((b.flags & CASCADE_READ) && !(b.flags & CASCADE_FOAM))
        fail(R.EFORMAT, 'frame.cascades: the READ flag without FOAM (the read table serves the whitecap ramp)');
    b.cascade.forEach((e, k) => e.held.forEach((v, i) => {
        const m = Math.floor(i / READ.KERNELS), given = (b.flags & CASCADE_READ) && m < e.mips;
        if (given ? v === 0 : v !== 0)
            fail(given ? R.EINVAL : R.EFORMAT, `frame.cascades[${k}].mip[${m}].held[${i % READ.KERNELS}] = ${v}; must be ${given ? '1..65535' : '0 (no READ flag, or beyond mips)'}`);
    }));
}

/* proto.c v_foam_table: rows with the FOAM flag alone, sigma ascending. */
function vFoamTable(b) {
    if (!(b.flags & CASCADE_FOAM)) return;
    if (b.foamRows < 1 || b.foamRows > FOAM_ROWS)
        fail(R.EINVAL, `frame.cascades.foam_rows = ${b.foamRows}; must be 1..${FOAM_ROWS}`);
    b.foamAll.forEach((w, i) => {
        if (i >= b.foamRows) {
            if (w.sigma !== 0 || w.a !== 0 || w.omega !== 0)
                fail(R.EFORMAT, `frame.cascades.foam[${i}] beyond foam_rows ${b.foamRows} must be 0`);
            return;
        }
        if (!(w.sigma >= 0 && w.sigma <= 1e3) || (i > 0 && !(w.sigma > b.foamAll[i - 1].sigma)))
            fail(R.EINVAL, `frame.cascades.foam[${i}].sigma = ${w.sigma}; must be in [0, 1e3] and ascend`);
        if (!(w.a >= -1e3 && w.a <= 0.5)) fail(R.EINVAL, `frame.cascades.foam[${i}].a = ${w.a}; must be in [-1e3, 0.5]`);
        if (!(w.omega >= 0 && w.omega <= 1e3)) fail(R.EINVAL, `frame.cascades.foam[${i}].omega = ${w.omega}; must be in [0, 1e3]`);
    });
}

function vCascades(b) {
    chkRange('frame.cascades.cascade_count', b.cascadeCount, 1, LIMITS.maxLayers);
    chkRange('frame.cascades.order', b.order, 1, 64);
    if (b.flags & ~(CASCADE_KEY | CASCADE_FOAM | CASCADE_READ)) fail(R.EFORMAT, `frame.cascades.flags is ${b.flags} (bits 0-2 only)`);
    vFoamTable(b);
    vReadTable(b);
    if (!(b.spacingPerM > 0) || !Number.isFinite(b.spacingPerM))
        fail(R.EINVAL, `frame.cascades.spacing_per_m = ${b.spacingPerM}; must be finite and > 0`);
    for (let i = 0; i < 3; i++) chkRange('frame.cascades.camera', b.camera[i], -MAX_WORLD, MAX_WORLD);
    chkRange('frame.cascades.min_spacing_m', b.minSpacingM, 0, 1e6);
    chkRange('frame.cascades.e_total', b.eTotal, 0, 1);
    chkRange('frame.cascades.tail_mss_x', b.tailMss[0], 0, 1e3);
    chkRange('frame.cascades.tail_mss_z', b.tailMss[1], 0, 1e3);
    chkRange('frame.cascades.tail_mss_xz', b.tailMss[2], -1e3, 1e3);
    chkRange('frame.cascades.geometry_spacing_m', b.geometrySpacingM, 0, 1e6);
    b.cascade.forEach((e, k) => {
        chkRange('frame.cascades.patch_m', e.patchM, 1e-3, 1e7);
        if (e.n < 8 || e.n > 2048 || (e.n & (e.n - 1)))
            fail(R.EINVAL, `frame.cascades[${k}].n = ${e.n}; must be a power of two in 8..2048`);
        chkRange('frame.cascades.mips', e.mips, 1, MAX_MIPS);
        if (e.fades > 1) fail(R.EFORMAT, `frame.cascades[${k}].fades is ${e.fades} (0 or 1)`);
        if ((e.n >> (e.mips - 1)) < 1) fail(R.EINVAL, `frame.cascades[${k}]: ${e.mips} mips of a ${e.n} grid`);
        if (!(e.spacingPerM > 0) || !(e.spacingPerM <= b.spacingPerM))
            fail(R.EINVAL, `frame.cascades[${k}].spacing_per_m = ${e.spacingPerM}; must be > 0 and <= the block's ${b.spacingPerM}`);
        for (let m = 0; m < MIP_ENTRIES; m++) {
            const kc = e.mip[4 * m], sx = e.mip[4 * m + 1], sz = e.mip[4 * m + 2], sxz = e.mip[4 * m + 3];
            if (m > e.mips) {
                if (kc !== 0 || sx !== 0 || sz !== 0 || sxz !== 0)
                    fail(R.EFORMAT, `frame.cascades[${k}].mip[${m}] beyond mips ${e.mips} must be 0`);
                continue;
            }
            if (m === e.mips ? kc !== 0 : !(kc > 0))
                fail(R.EINVAL, `frame.cascades[${k}].mip[${m}].kc = ${kc} (mips ${e.mips})`);
            if (!(sx >= 0 && sx <= 1e3) || !(sz >= 0 && sz <= 1e3) || !(sxz >= -1e3 && sxz <= 1e3))
                fail(R.EINVAL, `frame.cascades[${k}].mip[${m}] slope moments ${sx} ${sz} ${sxz} out of range`);
        }
        e.time.forEach((t, m) => {
            if ((m >= e.mips || !t.interval) && (t.tickA || t.interval || t.phase))
                fail(R.EFORMAT, `frame.cascades[${k}].time[${m}] must be 0 (${m >= e.mips ? 'beyond mips' : 'interval 0'})`);
        });
    });
}

/* A layout-1 tile record's tag (proto.c d_tile_tag): its cascade, and
 * sample B only of a mip with a time interval. */
function tileTag(r, b, t, tag) {
    const c = tag & 0xFF;
    if ((tag & ~(0xFF | TAG_SLOT_B)) || c >= b.cascadeCount)
        fail(R.EFORMAT, `${r.what}: record tag ${tag} names no cascade of ${b.cascadeCount}`);
    t.cascade = c;
    t.slot = tag & TAG_SLOT_B ? 1 : 0;
    const e = b.cascade[c];
    if (t.slot && (t.level >= e.mips || !e.time[t.level].interval))
        fail(R.EINVAL, `${r.what}: sample B of mip ${t.level} of cascade ${c}, which has no time interval`);
}

/* FRAME: parsed whole first, then validated in the C decoder's order
 * (proto.c d_frame, v_frame). */
function dFrame(r, limits) {
    r.need(FRAME_FIXED, 'fixed fields');
    const o = r.off;
    const f = {
        cutoffK: r.f64(o), eError: r.f64(o + 8), origin: [r.f64(o + 16), r.f64(o + 24), r.f64(o + 32)],
        cameraSeq: r.u32(o + 40), tick: r.u32(o + 44), tileCount: r.u16(o + 48), hasMesh: r.u8at(o + 50),
        layout: r.u8at(o + 51), cascades: null, tiles: [], mesh: null, placement: null,
    };
    r.zero(o + 52, 4, 'frame');
    r.off += FRAME_FIXED;
    if (f.layout >= LAYOUT_COUNT) fail(R.ETYPE, `FRAME: layout ${f.layout} unknown (0..1)`);
    let maxTag = 0;
    if (f.layout === LAYOUT.CASCADE) {
        r.need(CASCADE_FIXED, 'cascade block');
        const cc = r.u8at(r.off);
        if (cc < 1 || cc > LIMITS.maxLayers) fail(R.EINVAL, `FRAME: cascade_count ${cc} outside 1..${LIMITS.maxLayers}`);
        const bytes = cascadeBlockBytes(cc, r.u8at(r.off + 2));
        r.need(bytes, 'cascade entries');
        r.zero(r.off + 3, 1, 'cascade block');
        if (r.u8at(r.off + 2) & CASCADE_FOAM) r.zero(r.off + cascadeBlockBytes(cc, 0) + 1, 7, 'whitecap table');
        f.cascades = readCascades(r, cc);
        r.off += bytes;
        maxTag = TAG_SLOT_B | 0xFF;
    }
    if (f.tileCount > limits.maxFrameTiles)
        fail(R.ETOOBIG, `FRAME: tile_count ${f.tileCount} above the limit ${limits.maxFrameTiles}`);
    if (f.hasMesh > 2 || (f.hasMesh === 2 && f.layout !== LAYOUT.WORLD))
        fail(R.EFORMAT, `FRAME: has_mesh is ${f.hasMesh} (0 or 1; 2 in layout 0)`);
    if (f.tileCount * (RECORD_HEAD + TILE_FIXED) > r.end - r.off)
        fail(R.ETRUNC, `FRAME: ${f.tileCount} tiles cannot fit in the ${r.end - r.off} bytes left`);
    for (let i = 0; i < f.tileCount; i++) {
        const [t, tag] = dRecord(r, REC_TILE, maxTag, limits);
        if (f.cascades) tileTag(r, f.cascades, t, tag);
        f.tiles.push(t);
    }
    if (f.hasMesh) {
        if (f.layout === LAYOUT.CASCADE) f.placement = dRecord(r, REC_PLACEMENT, 0, limits)[0];
        else f.mesh = dRecord(r, f.hasMesh === 2 ? REC_VERTICES_QZ : REC_VERTICES, 0, limits)[0];
    }
    r.finish();
    /* values, as v_frame */
    if (Number.isNaN(f.cutoffK) || f.cutoffK < 0) fail(R.EINVAL, `frame.cutoff_k = ${f.cutoffK}; must be >= 0 (or +inf)`);
    chkRange('frame.e_error', f.eError, 0, 1);
    for (let i = 0; i < 3; i++) chkRange('frame.origin', f.origin[i], -MAX_ORIGIN, MAX_ORIGIN);
    if (f.cascades) vCascades(f.cascades);
    for (const t of f.tiles) vTile(t);
    if (f.mesh && f.hasMesh === 2) vVerticesQz(f.mesh, limits);
    else if (f.mesh) vVertices(f.mesh, limits);
    if (f.placement) for (let i = 0; i < 3; i++) chkRange('frame.placement.origin', f.placement.origin[i], -MAX_ORIGIN, MAX_ORIGIN);
    return f;
}

function dTopology(r, limits) {
    r.need(TOPO_FIXED, 'fixed fields');
    const o = r.off;
    const t = {
        meshId: r.u32(o), meshKind: r.u8at(o + 4), lodLevels: r.u8at(o + 5), flags: r.u16(o + 6),
        vertexCount: r.u32(o + 8), indexCount: r.u32(o + 12), flat: null, zones: null,
    };
    if (t.flags & ~TOPO_FLAT) fail(R.EFORMAT, `MESH_TOPOLOGY: flags 0x${t.flags.toString(16)} has unknown bits`);
    r.off += TOPO_FIXED;
    if (t.vertexCount > limits.maxVertices || t.indexCount > limits.maxIndices)
        fail(R.ETOOBIG, `MESH_TOPOLOGY: ${t.vertexCount} vertices / ${t.indexCount} indices above the limits ${limits.maxVertices} / ${limits.maxIndices}`);
    r.need(4 * t.indexCount + 5 * t.vertexCount, 'indices, morph and level arrays');
    const ic = t.indexCount, vc = t.vertexCount;
    const idx = new Uint32Array(ic);
    const base = r.u8.byteOffset + r.off;
    if ((base & 3) === 0 && littleEndianHost) idx.set(new Uint32Array(r.u8.buffer, base, ic));
    else for (let i = 0; i < ic; i++) idx[i] = r.u32(r.off + 4 * i);
    r.off += 4 * ic;
    t.indices = idx;
    t.morph = r.floats(vc, 'morph');
    t.level = r.u8.slice(r.off, r.off + vc);
    r.off += vc;
    if (t.flags & TOPO_FLAT) {
        /* flat floats start 4-aligned from the message start */
        const pad = (4 - (r.off & 3)) & 3;
        r.need(pad, 'flat padding');
        r.zero(r.off, pad, 'flat padding');
        r.off += pad;
        if (t.lodLevels < 1 || t.lodLevels > LIMITS.maxLodLevels)
            fail(R.EINVAL, `MESH_TOPOLOGY: lod_levels ${t.lodLevels} outside 1..${LIMITS.maxLodLevels}`);
        t.flat = r.floats(2 * vc, 'flat positions');
        t.zones = r.floats(4 * t.lodLevels, 'zones');
    }
    r.finish();
    if (t.meshKind >= MESH.NONE) fail(R.ETYPE, `mesh_topology.mesh_kind ${t.meshKind} unknown (0..2)`);
    chkRange('mesh_topology.lod_levels', t.lodLevels, 1, LIMITS.maxLodLevels);
    if (vc === 0 || ic === 0) fail(R.EINVAL, `mesh_topology has ${vc} vertices and ${ic} indices`);
    if (ic % 3) fail(R.EFORMAT, `mesh_topology.index_count ${ic} is not a multiple of 3`);
    for (let i = 0; i < ic; i++)
        if (idx[i] >= vc) fail(R.EINVAL, `mesh_topology index ${i} = ${idx[i]} >= vertex_count ${vc}`);
    for (let i = 0; i < vc; i++) {
        if (!(t.morph[i] >= 0 && t.morph[i] <= 1)) fail(R.EINVAL, `mesh_topology morph[${i}] = ${t.morph[i]} outside [0, 1]`);
        if (t.level[i] >= t.lodLevels) fail(R.EINVAL, `mesh_topology level[${i}] = ${t.level[i]} >= lod_levels ${t.lodLevels}`);
    }
    if (t.flags & TOPO_FLAT) {
        const fl = t.flat;
        for (let i = 0; i < fl.length; i++)
            if (!(Math.abs(fl[i]) <= MAX_LOCAL)) fail(R.EINVAL, `mesh_topology flat[${i}] = ${fl[i]} (finite, |.| <= 1e7)`);
        for (let L = 0; L < t.lodLevels; L++) {
            const z = t.zones.subarray(4 * L, 4 * L + 4);
            if (!(z[0] > 0 && z[0] <= 1e7) || !(z[1] >= 0 && z[1] <= 1e8) || !(z[2] >= 0 && z[2] <= 1e8) || z[3] !== 0)
                fail(R.EINVAL, `mesh_topology zone ${L} = (${z[0]}, ${z[1]}, ${z[2]}, ${z[3]}) out of range`);
            /* the morph rule holds for lattices that double */
            if (L > 0 && z[0] !== 2 * t.zones[4 * (L - 1)])
                fail(R.EINVAL, `mesh_topology zone ${L} lattice ${z[0]} is not twice zone ${L - 1}'s ${t.zones[4 * (L - 1)]}`);
        }
    }
    return t;
}

function dQuery(r, limits) {
    r.need(QUERY_FIXED, 'fixed fields');
    const o = r.off;
    const q = { queryId: r.u32(o), count: r.u32(o + 4), atTime: r.u8at(o + 8), t: r.f64(o + 16) };
    r.zero(o + 9, 7, 'query');
    r.off += QUERY_FIXED;
    if (q.count > limits.maxQueryPoints) fail(R.ETOOBIG, `QUERY: count ${q.count} above the limit ${limits.maxQueryPoints}`);
    r.need(16 * q.count, 'points');
    q.points = new Float64Array(2 * q.count);
    for (let i = 0; i < 2 * q.count; i++) q.points[i] = r.f64(r.off + 8 * i);
    r.off += 16 * q.count;
    r.finish();
    if (q.count === 0) fail(R.EINVAL, 'query.count is 0');
    chkEnum('query.at_time', q.atTime, 2);
    chkTime('query.t', q.t);
    for (let i = 0; i < q.points.length; i++)
        if (!(Math.abs(q.points[i]) <= MAX_WORLD)) fail(R.EINVAL, `query point ${i >> 1} ${(i & 1) ? 'z' : 'x'} = ${q.points[i]} (finite, |v| <= 1e10 required)`);
    return q;
}

function dResult(r, limits) {
    r.need(RESULT_FIXED, 'fixed fields');
    const o = r.off;
    const q = { queryId: r.u32(o), count: r.u32(o + 4), t: r.f64(o + 8), samples: [] };
    r.off += RESULT_FIXED;
    if (q.count > limits.maxQueryPoints) fail(R.ETOOBIG, `QUERY_RESULT: count ${q.count} above the limit ${limits.maxQueryPoints}`);
    r.need(SAMPLE_SIZE * q.count, 'samples');
    for (let i = 0; i < q.count; i++) {
        const b = r.off + SAMPLE_SIZE * i;
        q.samples.push({
            height: r.f32(b), normal: [r.f32(b + 4), r.f32(b + 8), r.f32(b + 12)],
            velocity: [r.f32(b + 16), r.f32(b + 20), r.f32(b + 24)], foam: r.f32(b + 28), errorBound: r.f32(b + 32),
        });
    }
    r.off += SAMPLE_SIZE * q.count;
    r.finish();
    if (q.count === 0) fail(R.EINVAL, 'query_result.count is 0');
    chkTime('query_result.t', q.t);
    q.samples.forEach((s, i) => {
        const v = [s.height, ...s.normal, ...s.velocity, s.foam, s.errorBound];
        v.forEach((x, k) => { if (!Number.isFinite(x)) fail(R.EINVAL, `query_result sample ${i} field ${k} is not finite`); });
        if (s.foam < 0 || s.foam > 1 || s.errorBound < 0) fail(R.EINVAL, `query_result sample ${i}: foam / error_bound out of range`);
    });
    return q;
}

function dSeaState(r) {
    r.need(16, 'fixed fields');
    const s = { op: r.u8at(r.off) };
    r.zero(r.off + 1, 7, 'sea_state');
    s.effectiveTime = r.f64(r.off + 8);
    r.off += 16;
    s.sea = dSea(r);
    s.token = r.str(255, 'token');
    r.finish();
    chkEnum('sea_state.op', s.op, 3);
    chkTime('sea_state.effective_time', s.effectiveTime);
    if (s.op === 2) {
        /* get (client -> server): no state, every field zero bytes */
        const z = s.sea;
        const nums = [s.effectiveTime, z.windU10, z.windDirDeg, z.fetchM, z.depthM, z.swell, z.phillipsA,
                      z.smallWaveM, z.choppiness, z.hs, z.tp];
        if (z.spectrum || z.spreading || z.flags || BigInt(z.seed) !== 0n || !nums.every((v) => Object.is(v, 0)))
            fail(R.EFORMAT, 'sea_state get: effective_time and the sea block must be zero bytes');
        if (s.token) fail(R.EFORMAT, 'sea_state get must not carry a token');
        return s;
    }
    vSea(s.sea);
    if (s.op === 0 && s.token) fail(R.EFORMAT, 'sea_state announce must not carry a token');
    return s;
}

function dError(r) {
    r.need(ERROR_FIXED, 'fixed fields');
    const o = r.off;
    const e = { code: r.u16(o), offendingType: r.u16(o + 2), offendingSeq: r.u32(o + 4) };
    r.off += ERROR_FIXED;
    e.message = r.str(1023, 'message');
    r.finish();
    if (e.code === 0) fail(R.EINVAL, 'error.code is 0 (OCEAN_OK is not an error)');
    return e;
}

function dBye(r) {
    r.need(BYE_FIXED, 'fixed fields');
    const b = { reason: r.u16(r.off) };
    r.zero(r.off + 2, 2, 'bye');
    r.off += BYE_FIXED;
    b.message = r.str(255, 'message');
    r.finish();
    chkEnum('bye.reason', b.reason, BYE_REASONS.length);
    return b;
}

/* ENTITY: op 0 announce and 1 set carry a whole sample and shape; 2
 * remove and 4 gone an id alone, 3 get nothing (PROTOCOL.md "ENTITY"). */
function dEntity(r) {
    r.need(ENTITY_FIXED, 'fixed fields');
    const o = r.off;
    const e = { op: r.u8at(o), kind: r.u8at(o + 1) };
    r.zero(o + 2, 2, 'entity');
    e.id = r.u32(o + 4);
    e.t = r.f64(o + 8);
    e.x = r.f64(o + 16);
    e.z = r.f64(o + 24);
    ['altitudeM', 'headingDeg', 'speed', 'lengthM', 'beamM', 'draughtM'].forEach((k, i) => { e[k] = r.f32(o + 32 + 4 * i); });
    r.off += ENTITY_FIXED;
    e.token = r.str(255, 'token');
    r.finish();
    chkEnum('entity.op', e.op, 5);
    chkEnum('entity.kind', e.kind, 3);
    const nums = [e.t, e.x, e.z, e.altitudeM, e.headingDeg, e.speed, e.lengthM, e.beamM, e.draughtM];
    if (e.op === 0 || e.op === 1) {
        chkTime('entity.t', e.t);
        nums.forEach((v, i) => { if (!Number.isFinite(v)) fail(R.EINVAL, `entity field ${i} = ${v}; must be finite`); });
    } else if (e.kind !== 0 || (e.op === 3 && e.id !== 0) || !nums.every((v) => Object.is(v, 0))) {
        fail(R.EFORMAT, `entity op ${e.op}: every field but op${e.op === 3 ? '' : ', id and the token'} must be zero bytes`);
    }
    if (e.op !== 1 && e.op !== 2 && e.token) fail(R.EFORMAT, `entity op ${e.op} must not carry a token`);
    return e;
}

/* WAKE: a ship's wake pattern, its coefficients' plane a payload view
 * (PROTOCOL.md "WAKE"); ranges as the C decoder checks them. */
function dWake(r) {
    r.need(WAKE_FIXED, 'fixed fields');
    const o = r.off;
    const w = { speed: r.f64(o), length: r.f64(o + 8), beam: r.f64(o + 16), depth: r.f64(o + 24) };
    w.nx = r.u16(o + 32);
    w.nz = r.u16(o + 34);
    w.codec = r.u8at(o + 36);
    r.zero(o + 37, 3, 'wake');
    w.errorBound = r.f32(o + 40);
    w.payloadLen = r.u32(o + 44);
    r.off += WAKE_FIXED;
    r.need(w.payloadLen, 'wake payload');
    w.payload = r.u8.subarray(r.off, r.off + w.payloadLen);
    r.off += w.payloadLen;
    r.finish();
    if (!(Number.isFinite(w.speed) && w.speed > 0 && Number.isFinite(w.length) && w.length > 0))
        fail(R.EINVAL, `wake.speed ${w.speed} and wake.length ${w.length} must be finite and > 0`);
    if (!(Number.isFinite(w.beam) && w.beam >= 0) || !(w.depth > 0))
        fail(R.EINVAL, `wake.beam ${w.beam} must be finite and >= 0, wake.depth ${w.depth} > 0`);
    if (w.nx < 1 || w.nx > PLANE_MAX || w.nz < 1 || w.nz > PLANE_MAX) fail(R.EINVAL, `wake grid ${w.nx} x ${w.nz} outside 1..${PLANE_MAX}`);
    chkEnum('wake.codec', w.codec, CODEC_COUNT);
    if (!(w.errorBound >= 0 && w.errorBound <= 1e30)) fail(R.EINVAL, `wake.error_bound ${w.errorBound} out of range`);
    return w;
}

/* Decodes one complete message (one WebSocket binary message: ArrayBuffer
 * or Uint8Array).  Returns {hdr, type, name, body}.  Tile payloads are views
 * into the input (keep it alive while decoding them); everything else is
 * copied.  Throws ProtoError. */
export function decode(buf, limits = LIMITS) {
    const u8 = buf instanceof Uint8Array ? buf : new Uint8Array(buf);
    const hdr = decodeHeader(u8, limits);
    const r = new Reader(u8.subarray(0, HEADER_SIZE + hdr.length), TYPE_NAMES[hdr.type]);
    let body;
    switch (hdr.type) {
    case T.HELLO: body = dHello(r); break;
    case T.SUBSCRIBE: body = dSubscribe(r); break;
    case T.CAMERA: body = dCamera(r); break;
    case T.FRAME: body = dFrame(r, limits); break;
    case T.TILE: body = dTile(r); vTile(body); break;
    case T.MESH_TOPOLOGY: body = dTopology(r, limits); break;
    case T.MESH_VERTICES: body = dVertices(r, limits); vVertices(body, limits); break;
    case T.QUERY: body = dQuery(r, limits); break;
    case T.QUERY_RESULT: body = dResult(r, limits); break;
    case T.SEA_STATE: body = dSeaState(r); break;
    case T.ERROR: body = dError(r); break;
    case T.BYE: body = dBye(r); break;
    case T.ENTITY: body = dEntity(r); break;
    case T.WAKE: body = dWake(r); break;
    default: fail(R.ETYPE, `message type ${hdr.type} unknown`);
    }
    return { hdr, type: hdr.type, name: TYPE_NAMES[hdr.type], body };
}

/* ---- encoders --------------------------------------------------------- */

class Writer {
    constructor(type, payloadLen, seq, simTime) {
        this.buf = new ArrayBuffer(HEADER_SIZE + payloadLen);
        this.dv = new DataView(this.buf);
        this.u8 = new Uint8Array(this.buf);
        const dv = this.dv;
        dv.setUint32(0, MAGIC, true);
        dv.setUint16(4, VERSION, true);
        dv.setUint16(6, type, true);
        dv.setUint32(8, 0, true);
        dv.setUint32(12, payloadLen, true);
        dv.setUint32(16, seq >>> 0, true);
        dv.setUint32(20, 0, true);
        dv.setFloat64(24, Number.isFinite(simTime) ? simTime : 0, true);
    }
}
const P = HEADER_SIZE;

/* sub: {effects, meshKind, codec, cutoffPolicy, mode, layers, lodLevels,
 * layout (default 0), meshCodec (default f32; layout 0 only), flags
 * (default 0; SUB_FLAG.FULL_GEOMETRY), tileSize,
 * frameRateHz, accuracy, baseSpacingM, viewRangeM}.  Validated as
 * the server will; returns an ArrayBuffer. */
export function encodeSubscribe(sub, seq, simTime = 0) {
    const s = {
        baseSpacingM: 0, viewRangeM: 0, accuracy: 1e-3, mode: MODE.LIVE, layout: LAYOUT.WORLD, meshCodec: MESH_CODEC.F32, flags: 0,
        ...sub,
    };
    for (const k of ['frameRateHz', 'accuracy', 'baseSpacingM', 'viewRangeM']) s[k] = f32(s[k]);
    vSubscribe(s);
    const w = new Writer(T.SUBSCRIBE, SUBSCRIBE_SIZE, seq, simTime);
    const u = w.u8, dv = w.dv;
    u[P] = s.effects; u[P + 1] = s.meshKind; u[P + 2] = s.codec; u[P + 3] = s.cutoffPolicy;
    u[P + 4] = s.mode; u[P + 5] = s.layers; u[P + 6] = s.lodLevels; u[P + 7] = s.layout;
    dv.setUint16(P + 8, s.tileSize, true);
    u[P + 10] = s.meshCodec;
    u[P + 11] = s.flags;
    dv.setFloat32(P + 12, s.frameRateHz, true);
    dv.setFloat32(P + 16, s.accuracy, true);
    dv.setFloat32(P + 20, s.baseSpacingM, true);
    dv.setFloat32(P + 24, s.viewRangeM, true);
    return w.buf;
}

/* cam: {pos:[x,y,z] doubles, vel:[3], yawDeg, pitchDeg, rollDeg, fovYDeg,
 * viewportW, viewportH, renderTime}. */
export function encodeCamera(cam, seq, simTime = 0) {
    const k = {
        pos: cam.pos, vel: cam.vel.map(f32), yawDeg: f32(cam.yawDeg), pitchDeg: f32(cam.pitchDeg),
        rollDeg: f32(cam.rollDeg || 0), fovYDeg: f32(cam.fovYDeg), viewportW: cam.viewportW,
        viewportH: cam.viewportH, renderTime: cam.renderTime || 0,
    };
    vCamera(k);
    const w = new Writer(T.CAMERA, CAMERA_SIZE, seq, simTime);
    const dv = w.dv;
    for (let i = 0; i < 3; i++) {
        dv.setFloat64(P + 8 * i, k.pos[i], true);
        dv.setFloat32(P + 24 + 4 * i, k.vel[i], true);
    }
    dv.setFloat32(P + 36, k.yawDeg, true);
    dv.setFloat32(P + 40, k.pitchDeg, true);
    dv.setFloat32(P + 44, k.rollDeg, true);
    dv.setFloat32(P + 48, k.fovYDeg, true);
    dv.setUint16(P + 52, k.viewportW, true);
    dv.setUint16(P + 54, k.viewportH, true);
    dv.setFloat64(P + 56, k.renderTime, true);
    return w.buf;
}

/* points: flat [x0, z0, x1, z1, ...]; t: sim time or null for the latest tick. */
export function encodeQuery(queryId, points, t, seq, simTime = 0) {
    const count = points.length >> 1;
    if (count === 0 || points.length & 1) fail(R.EINVAL, 'query needs a non-empty list of x, z pairs');
    if (count > LIMITS.maxQueryPoints) fail(R.ETOOBIG, `query.count ${count} above the limit`);
    const w = new Writer(T.QUERY, QUERY_FIXED + 16 * count, seq, simTime);
    const dv = w.dv;
    dv.setUint32(P, queryId >>> 0, true);
    dv.setUint32(P + 4, count, true);
    w.u8[P + 8] = t == null ? 0 : 1;
    dv.setFloat64(P + 16, t == null ? 0 : t, true);
    for (let i = 0; i < 2 * count; i++) {
        if (!(Math.abs(points[i]) <= MAX_WORLD)) fail(R.EINVAL, `query point ${i >> 1} is not finite or absurd`);
        dv.setFloat64(P + QUERY_FIXED + 8 * i, points[i], true);
    }
    return w.buf;
}

/* SEA_STATE: op 1 set (sea and effective time, with the admin token), 2
 * get (no sea, time 0, no token); op 0 (announce) is the server's, encoded
 * only to re-encode a decoded one.  sea: the sea block's fields as dSea
 * reads them (seed a BigInt, a number or a decimal string; hs and tp are
 * informational). */
export function encodeSeaState(op, effectiveTime, sea, token, seq, simTime = 0) {
    chkEnum('sea_state.op', op, 3);
    const bytes = utf8enc.encode(token || '');
    if (bytes.length > 255) fail(R.ETOOBIG, 'sea_state.token longer than 255 bytes');
    if (op !== 1 && bytes.length) fail(R.EFORMAT, 'only a sea_state set carries a token');
    const get = op === 2;
    if (!get) {
        chkTime('sea_state.effective_time', effectiveTime);
        vSea(sea);
    }
    const w = new Writer(T.SEA_STATE, SEASTATE_FIXED + 2 + bytes.length, seq, simTime);
    const u = w.u8, dv = w.dv;
    u[P] = op;
    dv.setFloat64(P + 8, get ? 0 : effectiveTime, true);
    if (!get) {
        const o = P + 16;
        u[o] = sea.spectrum;
        u[o + 1] = sea.spreading;
        u[o + 2] = sea.flags || 0;
        dv.setBigUint64(o + 8, BigInt(sea.seed), true);
        [sea.windU10, sea.windDirDeg, sea.fetchM, sea.depthM, sea.swell, sea.phillipsA, sea.smallWaveM,
            sea.choppiness, sea.hs || 0, sea.tp || 0].forEach((v, i) => dv.setFloat64(o + 16 + 8 * i, v, true));
    }
    dv.setUint16(P + SEASTATE_FIXED, bytes.length, true);
    u.set(bytes, P + SEASTATE_FIXED + 2);
    return w.buf;
}

export function encodeBye(reason, message, seq, simTime = 0) {
    const bytes = utf8enc.encode(message || '');
    if (bytes.length > 255) fail(R.ETOOBIG, 'bye.message longer than 255 bytes');
    chkEnum('bye.reason', reason, BYE_REASONS.length);
    const w = new Writer(T.BYE, BYE_FIXED + 2 + bytes.length, seq, simTime);
    w.dv.setUint16(P, reason, true);
    w.dv.setUint16(P + 4, bytes.length, true);
    w.u8.set(bytes, P + 6);
    return w.buf;
}
