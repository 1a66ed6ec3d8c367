/*
 * main.js - the viewer page: starts the network worker, feeds the renderer,
 * runs the fly camera, sends CAMERA reports at the subscription's rate and
 * keeps the overlay (fps, sim time, cutoff, bytes/s, latency).
 *
 * URL parameters (all optional):
 *   ws=URL          WebSocket endpoint (default: same host/port as the page)
 *   codec=qz|f16|f32   tile codec to ask for (default qz, the daemon's default)
 *   policy=antialias|seed|none   cutoff policy (default antialias)
 *   layout=1|0      what travels (default 1, cascade tiles summed here; 0 world
 *                   tiles and server-displaced mesh, for comparison)
 *   meshcodec=qz|f32   layout 0: how the mesh positions travel (default qz)
 *   rate=HZ tile=N levels=N layers=N accuracy=A range=M spacing=M
 *   rough=0         layout 1: shade without the unresolved slope variance
 *                   (a mirror; the browser test's control)
 *   x= y= z= yaw= pitch= fov= speed=   initial camera (default: the scene's
 *                   scene.camera_hint from GET /status, else 0,25,0 yaw 30 pitch -10)
 *   vx= vy= vz=     constant camera velocity (m/s), for demos and tests
 *   debug=1         tint the sea by tile level
 *   overlay=0       hide the overlay
 *   t=T             replay: the sea held at sim time T (s); every CAMERA asks
 *                   for its frame at T (PROTOCOL.md "Replay mode"), so a
 *                   screenshot shows the sea of that instant (with x= y= z=
 *                   yaw= pitch= fov=, the view `ocean-sim` renders)
 *
 * window.oceanStats exposes live counters (the browser test reads them).
 */
import { Renderer } from './render.js';
import { FlyCamera } from './camera.js';
import { CODEC, CUTOFF, LAYOUT, MESH_CODEC, MODE, T as MSG } from './protocol.js';
import { SeaTimeline } from './timeline.js';
import { setupControls, sunDefaultDeg, sunFromDeg } from './controls.js';

const qs = new URLSearchParams(location.search);
const num = (k, d) => (qs.has(k) && Number.isFinite(Number(qs.get(k))) ? Number(qs.get(k)) : d);
/* t=T: the sea of one instant (replay mode); a t that is no number is said
 * on the overlay once the page is up, and the sea is live */
const replayT = num('t', NaN);
const replay = Number.isFinite(replayT);

const stats = {
    state: 'starting', url: '', clientId: null, serverVersion: '', codec: '', cutoffPolicy: '',
    framesReceived: 0, framesRendered: 0, framesWithMesh: 0, topologies: 0, tilesDecoded: 0, levels: 0,
    bytes: 0, bytesPerSec: 0, latencyMs: null, latencyP50: null, latencyP99: null, simTime: 0, tick: 0,
    cutoffK: null, eError: null, fps: 0, decodeErrors: 0, serverErrors: 0, skipped: 0, lastError: '',
    vertexCount: 0, indexCount: 0, decodeMs: 0, bye: null, errors: [],
};
window.oceanStats = stats;

const canvas = document.getElementById('view');
const overlay = document.getElementById('overlay');
const statusEl = document.getElementById('status');
/* overlay=0: nothing over the sea (screenshots compared with reference renders) */
if (qs.get('overlay') === '0') for (const id of ['hud', 'help-toggle']) document.getElementById(id).style.display = 'none';

let renderer;
try {
    renderer = new Renderer(canvas, { antialias: qs.get('aa') !== '0', scale: num('scale', 0) });
} catch (e) {
    stats.state = 'no-webgl';
    stats.lastError = String(e.message || e);
    statusEl.textContent = `Cannot render: ${stats.lastError}`;
    throw e;
}
/* a GPU reset loses every buffer and texture: rebuild by reloading */
canvas.addEventListener('webglcontextlost', (e) => { e.preventDefault(); stats.state = 'webgl-context-lost'; });
canvas.addEventListener('webglcontextrestored', () => location.reload());
renderer.debug = qs.get('debug') === '1';
renderer.drawSea = qs.get('sea') !== '0';   /* sea=0: sky and far sea only (the test's blank-scene control) */
renderer.roughScale = qs.get('rough') === '0' ? 0 : 1;
const layout = qs.get('layout') === '0' ? LAYOUT.WORLD : LAYOUT.CASCADE;
renderer.layout = layout;

/* The scene's camera hint (GET /status, "camera_hint"), unless the URL
 * places the camera: the flight scene opens at its 1500 m, not at 25 m.
 * Plain HTTP the daemon already serves; no protocol message involved. */
async function sceneHint() {
    if (['x', 'y', 'z', 'yaw', 'pitch'].some((k) => qs.has(k))) return null;
    try {
        const ctl = new AbortController();
        const timer = setTimeout(() => ctl.abort(), 2000);
        const r = await fetch(new URL('status', location.href), { signal: ctl.signal, cache: 'no-store' });
        clearTimeout(timer);
        if (!r.ok) return null;
        const h = (await r.json()).camera_hint;
        return h && [h.x, h.y, h.z, h.yaw, h.pitch].every(Number.isFinite) ? h : null;
    } catch (e) {
        return null;
    }
}
const hint = await sceneHint();
stats.cameraHint = hint;
const cam = new FlyCamera({
    x: num('x', hint ? hint.x : 0), y: num('y', hint ? hint.y : 25), z: num('z', hint ? hint.z : 0),
    yaw: num('yaw', hint ? hint.yaw : 30), pitch: num('pitch', hint ? hint.pitch : -10),
    fov: num('fov', 60), speed: num('speed', 15), vx: num('vx', 0), vy: num('vy', 0), vz: num('vz', 0),
});
cam.attach(canvas);

const codecByName = { qz: CODEC.QZ, f16: CODEC.F16, f32: CODEC.F32 };
const policyByName = { none: CUTOFF.NONE, seed: CUTOFF.SEED, antialias: CUTOFF.ANTIALIAS };
const want = {
    layout,
    codec: codecByName[qs.get('codec')] ?? CODEC.QZ,
    /* layout 0: the server-displaced mesh positions as qz at the same
     * accuracy (about 1/5 of f32; PROTOCOL.md "MESH_VERTICES_QZ") unless
     * meshcodec=f32 */
    meshCodec: layout === LAYOUT.WORLD && qs.get('meshcodec') !== 'f32' ? MESH_CODEC.QZ : MESH_CODEC.F32,
    cutoffPolicy: policyByName[qs.get('policy')] ?? CUTOFF.ANTIALIAS,
    /* software GL draws a few frames per second: do not make the daemon
     * send (and the worker decode) 30 */
    frameRateHz: num('rate', renderer.software ? 10 : 30),
    tileSize: num('tile', undefined),
    lodLevels: num('levels', undefined),
    layers: num('layers', undefined),
    /* qz 5e-3: height tiles >= 50 dB PSNR (peak = tile range) at ~1/8.5 of
     * f32 (bench_codec, layout-1 table); finer costs bytes the planner
     * takes back from geometry under server.viewer_bytes_per_s */
    accuracy: num('accuracy', 5e-3),
    viewRangeM: num('range', 0),
    baseSpacingM: num('spacing', 0),
    /* layout 1: mips sent once per their update interval and blended in
     * time here (PROTOCOL.md "Samples in time"); time=0 takes every
     * tick's tiles, for comparison.  Replay (t=T) takes the same stream as
     * live: a screenshot at T shows the detail a live viewer gets (every
     * frame's tiles whole would cost the budget's share of each cascade in
     * each frame, at T held the same tiles again and again) */
    timeInterp: qs.get('time') !== '0',
    mode: replay ? MODE.REPLAY : MODE.LIVE,
};
/* Layout 0 only: unless the URL fixes it, the level-0 tile spacing follows
 * the camera's altitude (about 1/28 of the height, a power of two in
 * [0.25, 64] m): low over the water the viewer asks for fine detail, high
 * up for coarse tiles that cover more sea for the same bytes.
 * Re-subscribes on a change held for a second (a change of at least 2x, so
 * no flapping).  Layout 1 needs none of this: the server picks each
 * cascade's mips from the camera's pixel footprint (viewport and field of
 * view in CAMERA), and base_spacing_m is only a floor (0: server default). */
const autoSpacing = !qs.has('spacing') && layout === LAYOUT.WORLD;
const spacingFor = (h) => 2 ** Math.max(-2, Math.min(6, Math.round(Math.log2(Math.max(h, 1) / 28))));
if (autoSpacing) want.baseSpacingM = spacingFor(cam.pos[1]);
let spacingWish = want.baseSpacingM, spacingSince = 0;
function adaptSpacing(now) {
    if (!autoSpacing || !sub) return;
    const s = spacingFor(cam.pos[1]);
    if (s === sub.baseSpacingM) { spacingWish = s; return; }
    if (s !== spacingWish) { spacingWish = s; spacingSince = now; return; }
    if (now - spacingSince > 1000) {
        worker.postMessage({ cmd: 'subscribe', sub: { baseSpacingM: s } });
        spacingSince = now + 1e9;   /* until the worker confirms */
    }
}
Object.keys(want).forEach((k) => want[k] === undefined && delete want[k]);

const wsUrl = qs.get('ws') || `${location.protocol === 'https:' ? 'wss' : 'ws'}://${location.host}/`;
stats.url = wsUrl;
const worker = new Worker(new URL('./worker.js', import.meta.url), { type: 'module' });
worker.onerror = (e) => { stats.lastError = `worker: ${e.message}`; stats.state = 'worker-error'; };

let sub = null;
let lastFrameSim = 0, lastFrameWall = 0, haveFrame = false;
/* The sea-state timeline (HELLO, then announces ahead of their time): the
 * renderer's wind and Hs follow the state in force at each frame's time. */
let seaTimeline = new SeaTimeline();
let seaShown = null;
function applySea(sea) {
    if (!sea || sea === seaShown) return;
    seaShown = sea;
    const d = sea.windDirDeg * Math.PI / 180;
    renderer.wind = [Math.cos(d), Math.sin(d)];
    if (sea.hs > 0) renderer.hs = sea.hs;
    stats.sea = sea;
}
let pendingFrame = null;
const latencies = [];
let sendTimer = null;

function pushError(msg) {
    stats.lastError = msg;
    stats.errors.push(msg);
    if (stats.errors.length > 20) stats.errors.shift();
}
if (qs.has('t') && !replay) pushError(`t=${qs.get('t')} is not a sim time in seconds: showing the live sea`);

/* The controls panel, set up before any message can reach the handler
 * below (its HELLO case places the default sun through it); sun=AZ,EL
 * (degrees): a sun of the URL's, which no HELLO moves (ocean-sim render
 * --sun takes the same). */
const sunQ = (qs.get('sun') || '').split(',').map(Number);
const controls = { renderer, cam, worker, stats, simNow: () => (replay ? replayT : lastFrameSim), sunFixed: false };
setupControls(controls);
if (sunQ.length === 2 && sunQ.every(Number.isFinite) && Math.abs(sunQ[1]) <= 90) {
    renderer.sunDir = sunFromDeg(sunQ[0], sunQ[1]);
    controls.sunFixed = true;
    controls.showSun(sunQ);
} else if (qs.has('sun')) {
    pushError(`sun=${qs.get('sun')} is not AZ,EL in degrees (elevation within +-90)`);
}

worker.onmessage = (ev) => {
    const m = ev.data;
    switch (m.kind) {
    case 'status':
        stats.state = m.state;
        if (m.state === 'closed') {
            stats.closeCode = m.code;
            stats.closeReason = m.reason;
            stats.disconnects = (stats.disconnects || 0) + 1;
            if (m.retryMs != null) stats.state = `closed, retrying in ${(m.retryMs / 1000).toFixed(1)} s`;
            if (sendTimer) { clearInterval(sendTimer); sendTimer = null; }
            sub = null;
        }
        break;
    case 'hello': {
        stats.clientId = m.hello.clientId;
        stats.serverVersion = m.hello.serverVersion;
        stats.hello = { tickRateHz: m.hello.tickRateHz, codecs: m.hello.codecs, sea: m.hello.sea, maxLayers: m.hello.maxLayers, effects: m.hello.effects };
        seaTimeline = new SeaTimeline();
        seaTimeline.add(-Infinity, m.hello.sea);
        applySea(m.hello.sea);
        /* sun low over the downwind side (glitter on the waves' faces),
         * unless the URL or the controls placed it */
        if (!controls.sunFixed) {
            const s = sunDefaultDeg(m.hello.sea.windDirDeg);
            renderer.sunDir = sunFromDeg(s[0], s[1]);
            controls.showSun(s);
        }
        lastFrameSim = m.simTime;
        break;
    }
    case 'subscribed':
        sub = m.sub;
        stats.state = 'subscribed';
        stats.codec = m.codecName;
        stats.cutoffPolicy = Object.keys(policyByName).find((k) => policyByName[k] === sub.cutoffPolicy);
        stats.subscription = sub;
        startCameraReports();
        startQueries();
        stats.lastError = '';
        break;
    case 'topology':
        renderer.setTopology(m);
        stats.topologies++;
        stats.vertexCount = m.vertexCount;
        stats.indexCount = m.indices.length;
        stats.zones = m.zones ? Array.from(m.zones) : null;
        break;
    case 'vertices':
        renderer.setVertices(m);
        break;
    case 'frame':
        stats.framesReceived = m.stats.frames;   /* FRAMEs that reached the worker */
        stats.framesDecoded = (stats.framesDecoded || 0) + 1;
        pendingFrame = m;       /* latest wins: uploaded on the next animation frame */
        break;
    case 'error':
        if (m.source === 'server' && m.offendingType === MSG.QUERY) queryOut = null;
        if (m.source === 'server') stats.serverErrors++;
        else stats.decodeErrors++;
        pushError(`${m.source}: ${m.message}`);
        break;
    case 'bye':
        stats.bye = `${m.reason}${m.message ? `: ${m.message}` : ''}`;
        pushError(`server said bye (${stats.bye})`);
        break;
    case 'capture':
        window.oceanCapture = new Uint8Array(m.bytes);
        break;
    case 'result': {
        const r = m.result;
        if (queryOut && r.queryId === queryOut.id) queryOut = null;
        stats.queryResults = (stats.queryResults || 0) + 1;
        if (r.samples && r.samples.length) {
            const q = r.samples[0];
            stats.seaBelow = { t: r.t, height: q.height, foam: q.foam, errorBound: q.errorBound };
            /* keep the eye above the waves (the answer is up to 0.5 s old: margin) */
            cam.floorY = Math.max(0.5, q.height + 0.8);
        }
        break;
    }
    case 'sea':
        /* in force from its effective time, which may be ahead: applied
         * by the frame whose sim time reaches it */
        seaTimeline.add(m.effectiveTime, m.sea);
        break;
    default:
        break;
    }
};

/* Twice a second, ask the daemon for the sea under the camera (QUERY):
 * the overlay shows the height above the waves, and the eye is kept above
 * them.  In replay mode the sea drawn is the sea at T: asked at T (the
 * live sea's height lifted the eye of a fixed view by metres).  One query
 * at a time: a daemon slow to answer (a loaded host, a sea change being
 * built) is not sent a queue of stale questions, which its limit on
 * pending queries (server.max_pending_queries) would refuse with ERRORs;
 * one unanswered for QUERY_PATIENCE_MS is given up. */
const QUERY_PATIENCE_MS = 10000;
let queryId = 0, queryTimer = null, queryOut = null;
function startQueries() {
    if (queryTimer) clearInterval(queryTimer);
    queryOut = null;
    queryTimer = setInterval(() => {
        if (!sub) return;
        const now = performance.now();
        if (queryOut && now - queryOut.at < QUERY_PATIENCE_MS) return;
        queryOut = { id: ++queryId, at: now };
        stats.queriesSent = (stats.queriesSent || 0) + 1;
        worker.postMessage({ cmd: 'query', id: queryId, points: [cam.pos[0], cam.pos[2]], t: replay ? replayT : null });
    }, 500);
}

function startCameraReports() {
    if (sendTimer) clearInterval(sendTimer);
    const hz = Math.max(1, Math.min(sub ? sub.frameRateHz : 30, 30));
    /* the real viewport: the drawing buffer the renderer draws (CSS size x
     * device pixel ratio x render scale) and the camera's field of view, so
     * the server's pixel footprint is the one on screen */
    const sendNow = () => {
        const [w, h] = renderer.resize();
        const rep = cam.report(w, h);
        if (replay) rep.renderTime = replayT;
        stats.cameraSent = { viewport: [rep.viewportW, rep.viewportH], fovYDeg: rep.fovYDeg, pos: rep.pos.slice(),
            yawDeg: rep.yawDeg };
        worker.postMessage({ cmd: 'camera', cam: rep });
    };
    sendNow();
    sendTimer = setInterval(sendNow, 1000 / hz);
}

function applyFrame(m) {
    if (m.layout === LAYOUT.CASCADE) {
        const b = m.cascades;
        stats.tilesWritten = (stats.tilesWritten || 0) + renderer.setCascadeFrame(b, m.blocks, m.placement);
        if (m.placement) {
            stats.framesWithMesh++;
            stats.placement = m.placement.origin.slice();
        }
        stats.layout = 1;
        const hr = b.cascade.map(() => [Infinity, -Infinity]);
        for (const x of m.blocks) {
            const r = hr[x.cascade];
            if (!r) continue;
            for (let k = 1; k < x.disp.length; k += 4) { const v = x.disp[k]; if (v < r[0]) r[0] = v; if (v > r[1]) r[1] = v; }
        }
        stats.cascades = b.cascade.map((e, c) => ({
            patch: e.patchM, n: e.n, mips: e.mips, fades: e.fades, heightRange: hr[c],
            tiles: m.blocks.filter((x) => x.cascade === c).length,
            mipsSent: [...new Set(m.blocks.filter((x) => x.cascade === c).map((x) => x.mip))].sort((a, z) => a - z),
        }));
        stats.block = { spacingPerM: b.spacingPerM, minSpacingM: b.minSpacingM, eTotal: b.eTotal, tailMss: b.tailMss, camera: b.camera,
            cascades: b.cascade.map((e) => ({ patchM: e.patchM, n: e.n, mips: e.mips, fades: e.fades, q: e.spacingPerM })) };
        stats.foamRows = b.foam.length;
        stats.levels = b.cascadeCount;
    } else if (m.mesh) {
        if (renderer.setVertices(m.mesh)) stats.framesWithMesh++;
        /* what a frame's mesh met: its id and size against the topology held */
        const t = renderer.topology;
        stats.meshLast = { id: m.mesh.meshId, vertices: m.mesh.positions.length / 3,
            topology: t ? [t.meshId, t.vertexCount] : null };
        let lo = Infinity, hi = -Infinity;
        const p = m.mesh.positions;
        for (let i = 1; i < p.length; i += 3) { if (p[i] < lo) lo = p[i]; if (p[i] > hi) hi = p[i]; }
        stats.meshY = [lo, hi];
    }
    if (m.layout !== LAYOUT.CASCADE) {
        renderer.setLevels(m.levels);
        stats.levels = m.levels.length;
        stats.layout = 0;
    }
    if (m.wakes !== undefined) {
        renderer.setWakes(m.wakes);
        stats.wakes = m.wakes ? { n: m.wakes.n, dx: m.wakes.dx, t: m.wakes.t, peak: m.wakes.peak, trough: m.wakes.trough } : null;
    }
    lastFrameSim = m.simTime;
    lastFrameWall = performance.now();
    haveFrame = true;
    applySea(seaTimeline.at(m.simTime));
    seaTimeline.prune(m.simTime);
    stats.simTime = m.simTime;
    stats.tick = m.tick;
    stats.origin = m.placement ? m.placement.origin.slice() : m.origin;
    stats.cutoffK = m.cutoffK;
    stats.eError = m.eError;
    stats.bytes = m.stats.bytes;
    stats.bytesPerSec = m.bytesPerSec;
    stats.tilesDecoded = m.stats.tiles;
    stats.skipped = m.stats.skipped;
    stats.decodeMs = m.stats.decodeMs;
    stats.decodeWorkers = m.decodeWorkers;
    if (m.codecs) stats.codec = m.codecs;
    stats.tileCount = m.tileCount;
    stats.levelInfo = m.levels.map((L) => ({ level: L.level, spacing: L.spacing, w: L.width, h: L.height, tiles: L.tiles, err: L.errorBound, foamMax: L.foamMax, foamMean: L.foamMean }));
    if (m.latencyMs != null) {
        stats.latencyMs = m.latencyMs;
        latencies.push(m.latencyMs);
        if (latencies.length > 300) latencies.shift();
        const s = latencies.slice().sort((a, b) => a - b);
        stats.latencyP50 = s[Math.floor(0.5 * (s.length - 1))];
        stats.latencyP99 = s[Math.floor(0.99 * (s.length - 1))];
    }
}

function fmtBytes(b) {
    if (b >= 1e6) return `${(b / 1e6).toFixed(2)} MB`;
    if (b >= 1e3) return `${(b / 1e3).toFixed(1)} kB`;
    return `${b.toFixed(0)} B`;
}
function fmtCutoff(k) {
    if (k == null) return '–';
    if (!Number.isFinite(k)) return '∞ (unfiltered)';
    return `${k.toFixed(3)} rad/m (λ ${(2 * Math.PI / k).toFixed(2)} m)`;
}

function updateOverlay() {
    const v = cam.measuredVel, sp = Math.hypot(v[0], v[1], v[2]);
    const lines = [
        `<b>oceand viewer</b> ${stats.serverVersion ? `· server ${esc(stats.serverVersion)}` : ''} · client ${stats.clientId ?? '–'} · ${esc(stats.state)}`,
        `fps ${stats.fps.toFixed(1)} · frames ${stats.framesReceived} (skipped ${stats.skipped}) · decode ${stats.decodeMs.toFixed(1)} ms (${stats.decodeWorkers ?? 0} workers)`,
        `sim time ${stats.simTime.toFixed(2)} s · tick ${stats.tick}`,
        `cutoff ${fmtCutoff(stats.cutoffK)} · E_error ${stats.eError == null ? '–' : (100 * stats.eError).toFixed(2) + ' %'} · ${esc(stats.cutoffPolicy || '')}`,
        `${fmtBytes(stats.bytesPerSec)}/s · total ${fmtBytes(stats.bytes)} · codec ${esc(stats.codec || '–')} · tiles ${stats.tileCount ?? 0} in ${stats.levels} ${stats.layout === 1 ? 'cascades' : 'levels'}`
            + (stats.layout === 1 && stats.block ? ` · E_total ${(100 * stats.block.eTotal).toFixed(2)} % · q ${stats.block.spacingPerM.toPrecision(3)}` : ''),
        `latency ${stats.latencyMs == null ? '–' : stats.latencyMs.toFixed(1) + ' ms'} (p50 ${stats.latencyP50 == null ? '–' : stats.latencyP50.toFixed(1)}, p99 ${stats.latencyP99 == null ? '–' : stats.latencyP99.toFixed(1)})`,
        `camera (${cam.pos[0].toFixed(1)}, ${cam.pos[1].toFixed(1)}, ${cam.pos[2].toFixed(1)}) yaw ${cam.yawDeg.toFixed(0)}° pitch ${cam.pitchDeg.toFixed(0)}° · ${sp.toFixed(1)} m/s · speed ${cam.speed.toFixed(1)} m/s`,
        `mesh ${stats.vertexCount} vertices${stats.seaBelow ? ` · sea below ${stats.seaBelow.height.toFixed(2)} m (camera ${(cam.pos[1] - stats.seaBelow.height).toFixed(1)} m above it)` : ''}`,
    ];
    if (stats.lastError) lines.push(`<span class="err">${esc(stats.lastError)}</span>`);
    overlay.innerHTML = lines.join('<br>');
    statusEl.textContent = stats.state.startsWith('closed') ? `Disconnected from ${stats.url} (${stats.state})`
        : haveFrame ? '' : `Connecting to ${stats.url} …`;
}

function esc(s) { return String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c])); }

let lastT = performance.now(), fpsT = lastT, fpsN = 0, overlayT = 0;
function tick(now) {
    const dt = Math.min(0.5, (now - lastT) / 1000);   /* real-time motion even at a few fps; no leap after a hidden tab */
    lastT = now;
    cam.update(dt);
    stats.camera = cam.pos.slice();
    stats.cameraVel = cam.measuredVel.slice();
    adaptSpacing(now);
    if (pendingFrame) {
        applyFrame(pendingFrame);
        pendingFrame = null;
        worker.postMessage({ cmd: 'taken' });   /* the worker decodes the next frame only now */
    }
    /* live: the last frame's time carried on by the wall clock; replay: the
     * instant asked for, held */
    const simNow = replay ? replayT : haveFrame ? lastFrameSim + Math.min(0.5, (now - lastFrameWall) / 1000) : lastFrameSim;
    try {
        if (renderer.draw({ pos: cam.pos, basis: cam.basis, fovYDeg: cam.fovYDeg }, simNow)) stats.framesRendered++;
    } catch (e) {
        pushError(`render: ${e.message || e}`);
    }
    fpsN++;
    if (now - fpsT >= 500) { stats.fps = fpsN * 1000 / (now - fpsT); fpsN = 0; fpsT = now; }
    if (now - overlayT > 250) { updateOverlay(); overlayT = now; }
    requestAnimationFrame(tick);
}
requestAnimationFrame(tick);

worker.postMessage({ cmd: 'connect', url: wsUrl, sub: want });
window.addEventListener('beforeunload', () => worker.postMessage({ cmd: 'close' }));
/* a hidden tab draws nothing: the worker stops decoding until it is back */
document.addEventListener('visibilitychange', () => worker.postMessage({ cmd: 'pause', paused: document.hidden }));
document.getElementById('help-toggle').addEventListener('click', () => document.getElementById('help').classList.toggle('hidden'));

/* for debugging from the console and for tests */
window.oceanViewer = { renderer, camera: cam, worker };
