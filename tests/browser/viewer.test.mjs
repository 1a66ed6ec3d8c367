/*
 * viewer.test.mjs - the web viewer in a real browser: headless Chromium
 * (Debian's /usr/bin/chromium, software GL) driven by playwright-core loads
 * the page from a running oceand and checks that
 *   - the page and its modules load, with no page errors;
 *   - the viewer gets HELLO, a mesh topology and frames, decodes every tile
 *     without error, and measures a latency;
 *   - the canvas is not blank: the screenshot (decoded here from PNG) has
 *     pixel variance above a threshold, and the sea half of it has the fine
 *     structure of waves (not the smooth gradient of an empty scene);
 *   - the sea moves: two screenshots a moment apart differ;
 *   - the overlay shows fps, sim time, cutoff, bytes/s and latency;
 *   - W flies the camera along its forward vector, the reported velocity
 *     follows, and the daemon's frames follow the camera;
 *   - two pages at once are two viewers of one ocean: both get frames,
 *     with distinct client ids, the same sea state and one sim clock;
 *   - the viewer subscribes layout 1 (cascade tiles) with every cascade,
 *     frames carry the cascade block and a mesh placement, and CAMERA
 *     carries the drawing buffer's size and the field of view;
 *   - a control view without the streamed sea has far less structure than
 *     the real one (so the pixel checks can fail); it uses layout 0 and f16
 *     tiles, so that path is exercised too;
 *   - no request leaves the daemon's origin.
 * Screenshots are kept in ARTIFACT_DIR (viewer.png, viewer-2.png,
 * viewer-control.png).
 *
 * Env: OCEAN_URL (http://127.0.0.1:PORT/), ARTIFACT_DIR, CHROMIUM
 * (default /usr/bin/chromium), VIEWER_TIMEOUT_S (default 60), VIEW_QUERY.
 * Prints "N passed, N failed" and exits non-zero on any failure.
 */
import { createRequire } from 'node:module';
import { execFileSync } from 'node:child_process';
import { mkdirSync, writeFileSync, mkdtempSync, rmSync } from 'node:fs';
import { axisSpectra, decodePng, lineRatio, lum, planeLuma } from './pixels.mjs';
import { cameraBasis } from '../../clients/web/camera.js';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

const require = createRequire(new URL('./package.json', import.meta.url));
const { chromium } = require('playwright-core');

const base = process.env.OCEAN_URL || 'http://127.0.0.1:8740/';
const artifacts = process.env.ARTIFACT_DIR || 'build/test-artifacts';
const timeoutMs = 1000 * Number(process.env.VIEWER_TIMEOUT_S || 60);
const exe = process.env.CHROMIUM || '/usr/bin/chromium';
/* VIEW_QUERY: viewer options every page gets (tests/test_browser.sh asks
 * for fewer pixels, scale=0.25&aa=0: what is judged here does not depend
 * on the resolution, and a software renderer draws 4 times the frames) */
const viewQuery = process.env.VIEW_QUERY || '';
const withView = (u) => (viewQuery ? `${u}${u.includes('?') ? '&' : '?'}${viewQuery}` : u);

/* No lattice in the glitter (issue 45: the interpolation of normals drew
 * a diamond grid in the sun's glitter).  The sea of T from 25 m, looking
 * 25 deg down toward the sun, drawn at full resolution (480 x 270); its luma read back
 * onto the mean sea plane over 64 m x 64 m of the glitter (50-114 m ahead),
 * where the mesh's lattices and every mip's samples are lines at fixed
 * frequencies along the world's axes.  At each such frequency and its
 * second and third harmonics, the spectrum along either axis may stand at
 * most LATTICE_MAX over the power law of the bins around it.  The same
 * picture with a lattice of 1 % luma laid over it at each frequency in
 * turn must be found (the check's own control). */
const LATTICE_MAX = 4;
async function glitterLattice(page, T) {
    const view = { pos: [0, 25, 0], yaw: 0, pitch: -25, fov: 40 };
    /* 480 x 270 whole pixels: a texel of the nearest mip spans 10-20 of them
     * there, and a software renderer on a busy host draws them in time */
    await page.setViewportSize({ width: 480, height: 270 });
    await page.goto(withView(`${base}?scale=1&x=0&y=25&z=0&yaw=0&pitch=-25&fov=40&sun=0,30&t=${T}&overlay=0`), { waitUntil: 'load', timeout: timeoutMs });
    const ok = await waitFor(page, (t) => window.oceanStats && window.oceanStats.framesRendered >= 3 && window.oceanStats.simTime === t &&
        window.oceanStats.block && Math.abs(window.oceanStats.block.camera[1] - 25) < 1, T, timeoutMs);
    const info = await page.evaluate(() => {
        const r = window.oceanViewer.renderer;
        return { zones: Array.from(r.topology1 ? r.topology1.zones : []), lod: r.topology1 ? r.topology1.lodLevels : 0,
            cas: r.cas.map((c) => [c.sigma, c.mips]), scale: r.scale };
    });
    const png = await page.screenshot({ type: 'png' });
    writeFileSync(join(artifacts, 'viewer-glitter.png'), png);
    const n = 128, dx = 0.5, x0 = 50, z0 = -32;
    const grid = planeLuma(decodePng(png), view.pos, cameraBasis(view.yaw, view.pitch, 0), view.fov, x0, z0, dx, n);
    const spacings = [];
    info.cas.forEach(([sigma, mips], c) => { for (let m = 0; m < mips; m++) spacings.push([`cascade ${c} mip ${m}`, sigma * 2 ** m]); });
    for (let L = 0; L < info.lod; L++) spacings.push([`mesh level ${L}`, info.zones[4 * L]]);
    const lines = [];
    for (const [name, sp] of spacings)
        for (let hm = 1; hm <= 3; hm++) {
            const k = Math.round(hm * n * dx / sp);
            if (k >= 10 && k <= n / 2 - 4 && !lines.some((l) => l.k === k)) lines.push({ name: `${name} (${sp.toFixed(2)} m) x${hm}`, k, sp: sp / hm });
        }
    const S = axisSpectra(grid);
    let worst = { ratio: 0, name: 'none' }, missed = [];
    for (const l of lines) {
        const r = Math.max(lineRatio(S.along, l.k), lineRatio(S.across, l.k));
        if (r > worst.ratio) worst = { ratio: r, name: l.name };
        /* the control: 1 % of luma in a grid of this spacing */
        const w = 2 * Math.PI / l.sp;
        const lat = grid.map((row, j) => row.map((v, i) => v * (1 + 0.01 * Math.cos(w * (x0 + i * dx)) * Math.cos(w * (z0 + j * dx)))));
        const SL = axisSpectra(lat);
        if (!(Math.max(lineRatio(SL.along, l.k), lineRatio(SL.across, l.k)) > LATTICE_MAX)) missed.push(l.name);
    }
    check('no lattice in the glitter: no line at the mesh\'s or the tiles\' spacings (25 m, full resolution)',
        ok && info.scale === 1 && lines.length >= 4 && worst.ratio <= LATTICE_MAX && missed.length === 0,
        `${lines.length} frequencies, the strongest ${worst.ratio.toFixed(2)} x its surroundings at ${worst.name} ` +
        `(at most ${LATTICE_MAX}); a 1 % lattice laid over the picture found at ${lines.length - missed.length} of them` +
        (missed.length ? `, missed at ${missed.join(', ')}` : ''));
}
mkdirSync(artifacts, { recursive: true });

let passed = 0, failed = 0;
function check(name, ok, detail = '') {
    if (ok) { passed++; console.log(`ok - ${name}${detail ? ` (${detail})` : ''}`); }
    else { failed++; console.log(`not ok - ${name}${detail ? ` (${detail})` : ''}`); }
    return ok;
}


/* variance of luminance over rows [y0, y1) */
function variance(img, y0 = 0, y1 = img.h) {
    let s = 0, s2 = 0, n = 0;
    for (let y = y0; y < y1; y++) for (let x = 0; x < img.w; x++) { const l = lum(img, x, y); s += l; s2 += l * l; n++; }
    const m = s / n;
    return s2 / n - m * m;
}
/* mean |difference| of pixels `stride` apart along a row: the structure
 * waves give; a flat sea varies almost only from row to row */
function detail(img, y0, y1, stride = 4) {
    let s = 0, n = 0;
    for (let y = y0; y < y1; y++) for (let x = stride; x < img.w; x++) { s += Math.abs(lum(img, x, y) - lum(img, x - stride, y)); n++; }
    return s / n;
}
function meanColor(img, y0, y1) {
    const c = [0, 0, 0];
    let n = 0;
    for (let y = y0; y < y1; y++) for (let x = 0; x < img.w; x++) { const o = (y * img.w + x) * 4; c[0] += img.px[o]; c[1] += img.px[o + 1]; c[2] += img.px[o + 2]; n++; }
    return c.map((v) => v / n);
}
function meanAbsDiff(a, b, y0, y1) {
    let s = 0, n = 0;
    for (let y = y0; y < y1; y++) for (let x = 0; x < a.w; x++) { s += Math.abs(lum(a, x, y) - lum(b, x, y)); n++; }
    return s / n;
}

async function waitFor(page, pred, arg, ms) {
    try {
        await page.waitForFunction(pred, arg, { timeout: ms, polling: 200 });
        return true;
    } catch {
        return false;
    }
}

const stats = (page) => page.evaluate(() => JSON.parse(JSON.stringify(window.oceanStats || null)));

const userDataDir = mkdtempSync(join(tmpdir(), 'ocean-chromium-'));
let context;
try {
    context = await chromium.launchPersistentContext(userDataDir, {
        executablePath: exe,
        headless: true,
        viewport: { width: 960, height: 540 },
        args: ['--headless=new', '--no-sandbox', '--disable-gpu', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
            '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run',
            '--disable-quic', '--disable-background-timer-throttling', '--disable-renderer-backgrounding',
            '--disable-backgrounding-occluded-windows'],
        timeout: 60000,
    });
    /* every action (screenshot, click, navigation) waits for its condition
     * up to the test's deadline: a software renderer on a host with a core
     * taken by another process draws a frame in seconds, not milliseconds */
    context.setDefaultTimeout(timeoutMs);
    context.setDefaultNavigationTimeout(timeoutMs);
    /* nothing but the daemon may be contacted */
    const foreign = [];
    const origin = new URL(base).host;
    await context.route('**/*', (route) => {
        const u = new URL(route.request().url());
        if (u.host !== origin && u.protocol !== 'data:' && u.protocol !== 'blob:') { foreign.push(u.href); return route.abort(); }
        return route.continue();
    });

    const url = withView(`${base}?x=0&y=14&z=0&yaw=30&pitch=-12`);
    const page = context.pages()[0] || await context.newPage();
    const pageErrors = [], consoleErrors = [], badResponses = [];
    page.on('pageerror', (e) => pageErrors.push(String(e)));
    page.on('console', (m) => { if (m.type() === 'error') consoleErrors.push(m.text()); });
    page.on('response', (r) => { if (r.status() >= 400) badResponses.push(`${r.status()} ${r.url()}`); });
    const resp = await page.goto(url, { waitUntil: 'load', timeout: timeoutMs });
    check('page loads from the daemon', resp && resp.status() === 200, `HTTP ${resp && resp.status()}`);
    const ctype = resp ? (resp.headers()['content-type'] || '') : '';
    check('page is served as HTML', /text\/html/.test(ctype), ctype);

    const gotFrames = await waitFor(page, () => window.oceanStats && window.oceanStats.framesReceived >= 8 && window.oceanStats.framesRendered >= 4, null, timeoutMs);
    let s = await stats(page);
    check('frames arrive and are rendered', gotFrames,
        s ? `state ${s.state}, received ${s.framesReceived}, rendered ${s.framesRendered}, topologies ${s.topologies}, error "${s.lastError}"` : 'no oceanStats');
    check('module scripts load (no 4xx/5xx)', badResponses.length === 0, badResponses.join(', '));
    check('no page errors', pageErrors.length === 0, pageErrors.slice(0, 3).join(' | '));
    if (s) {
        check('HELLO received (client id, server version)', s.clientId != null && !!s.serverVersion, `client ${s.clientId}, ${s.serverVersion}`);
        check('mesh topology received', s.topologies >= 1 && s.vertexCount > 0, `${s.vertexCount} vertices, ${s.indexCount} indices`);
        check('frames carry the mesh placement', s.framesWithMesh >= 1, `${s.framesWithMesh}`);
        /* layout 1 by default, every cascade the server offers */
        const maxLayers = s.hello ? s.hello.maxLayers : 0;
        check('subscribed with layout 1, every effect of the scene and every cascade (HELLO.max_layers)',
            s.subscription && s.subscription.layout === 1 && s.layout === 1 && s.subscription.layers === maxLayers &&
            s.subscription.effects === s.hello.effects && s.cascades && s.cascades.length >= 1 && s.cascades.length <= maxLayers,
            `layout ${s.subscription && s.subscription.layout}, frames layout ${s.layout}, layers ${s.subscription && s.subscription.layers} of ${maxLayers}, ` +
            `effects ${s.subscription && s.subscription.effects} of ${s.hello && s.hello.effects}, ${s.cascades ? s.cascades.length : 0} cascades in frames`);
        check('cascade block: the camera of the frame, spacing per metre, mip tables', s.block && s.block.spacingPerM > 0 &&
            Math.abs(s.block.camera[1] - 14) < 2 && s.cascades.every((c) => c.mips >= 1 && c.n >= 8),
            s.block ? `q ${s.block.spacingPerM}, camera ${s.block.camera}, E_total ${s.block.eTotal}` : 'no block');
        const vp = await page.evaluate(() => [window.oceanViewer.renderer.canvas.width, window.oceanViewer.renderer.canvas.height]);
        check('CAMERA carries the real viewport and field of view', s.cameraSent && s.cameraSent.viewport[0] === vp[0] &&
            s.cameraSent.viewport[1] === vp[1] && s.cameraSent.fovYDeg === 60, `sent ${JSON.stringify(s.cameraSent)}, drawing buffer ${vp}`);
        check('tiles decoded, none refused', s.tilesDecoded > 0 && s.decodeErrors === 0, `${s.tilesDecoded} tiles, codec ${s.codec}, ${s.decodeErrors} errors: ${s.errors.join(' | ')}`);
        check('no ERROR from the server', s.serverErrors === 0, s.errors.join(' | '));
        check('latency measured', s.latencyMs != null && s.latencyMs >= 0 && s.latencyMs < 5000, `${s.latencyMs} ms`);
        check('sim time advances', s.simTime > 0 || s.tick > 0, `t ${s.simTime}, tick ${s.tick}`);
    }
    /* let the page settle, then read the pixels */
    await page.waitForTimeout(1500);
    const png1 = await page.screenshot({ type: 'png' });
    writeFileSync(join(artifacts, 'viewer.png'), png1);
    const img1 = decodePng(png1);
    const v = variance(img1);
    check('canvas not blank (pixel variance)', v > 60, `variance ${v.toFixed(1)}`);
    const horizon = Math.floor(img1.h * 0.45);
    const sea0 = Math.floor(img1.h * 0.62);
    const skyC = meanColor(img1, Math.floor(img1.h * 0.12), Math.floor(img1.h * 0.3));
    const seaC = meanColor(img1, sea0, img1.h);
    check('sky is above the sea: brighter and blue', lum({ w: 1, h: 1, px: [...skyC, 255] }, 0, 0) > lum({ w: 1, h: 1, px: [...seaC, 255] }, 0, 0) && skyC[2] > skyC[0],
        `sky rgb ${skyC.map((x) => x.toFixed(0))}, sea rgb ${seaC.map((x) => x.toFixed(0))}`);
    const det = detail(img1, sea0, img1.h);
    void horizon;
    /* a newer frame drawn (twice), however long the renderer takes */
    const s0 = await stats(page);
    await page.waitForTimeout(1200);
    await waitFor(page, ([d, r]) => window.oceanStats.framesDecoded > d && window.oceanStats.framesRendered >= r + 2,
        [s0.framesDecoded, s0.framesRendered], timeoutMs);
    const png2 = await page.screenshot({ type: 'png' });
    const img2 = decodePng(png2);
    const moved = meanAbsDiff(img1, img2, sea0, img1.h);
    check('the sea moves between screenshots', moved > 0.5, `mean |diff| ${moved.toFixed(2)}`);
    const hud = await page.evaluate(() => document.getElementById('overlay').textContent);
    check('overlay shows fps, sim time, cutoff, bytes/s, latency',
        /fps \d/.test(hud) && /sim time [\d.]+ s/.test(hud) && /cutoff /.test(hud) && /B\/s/.test(hud) && /latency [\d.]+ ms/.test(hud), hud.slice(0, 300));

    /* fly-camera controls: hold W, the camera moves along its forward
     * vector, and the daemon's frames follow it (frame origin) */
    await page.click('#view', { position: { x: 700, y: 400 } });
    const c0 = (await stats(page)).camera, o0 = (await stats(page)).origin;
    const speed0 = await page.evaluate(() => window.oceanViewer.camera.speed);
    await page.keyboard.press('Equal');          /* '+' doubles the speed, twice */
    await page.keyboard.press('Equal');
    const speed1 = await page.evaluate(() => window.oceanViewer.camera.speed);
    check('+ raises the flying speed', speed1 === 4 * speed0, `${speed0} -> ${speed1} m/s`);
    await page.keyboard.down('KeyW');
    /* fly until 40 m covered (a few seconds; longer on a starved machine) */
    await waitFor(page, (c) => { const p = window.oceanStats.camera; return Math.hypot(p[0] - c[0], p[2] - c[2]) > 40; }, c0, timeoutMs);
    const vWhileFlying = (await stats(page)).cameraVel;
    await page.keyboard.up('KeyW');
    const c1 = (await stats(page)).camera;
    const d = [c1[0] - c0[0], c1[1] - c0[1], c1[2] - c0[2]], dl = Math.hypot(...d);
    const fwd = [Math.cos(-12 * Math.PI / 180) * Math.cos(30 * Math.PI / 180), Math.sin(-12 * Math.PI / 180), Math.cos(-12 * Math.PI / 180) * Math.sin(30 * Math.PI / 180)];
    /* the camera stops 0.5 m above mean sea level, so compare directions in x-z */
    const cosang = (d[0] * fwd[0] + d[2] * fwd[2]) / (Math.hypot(d[0], d[2]) * Math.hypot(fwd[0], fwd[2]) || 1);
    check('W flies the camera forward', Math.hypot(d[0], d[2]) > 40 && cosang > 0.99, `moved ${dl.toFixed(1)} m, cos to forward ${cosang.toFixed(3)}`);
    check('the camera reports its velocity', Math.hypot(...vWhileFlying) > 5, `${vWhileFlying.map((v) => v.toFixed(1))} m/s`);
    /* the origin moves on the mesh's lattice (steps of several metres), so
     * "follows" means: it moved, and now lies nearer the camera than before */
    const follows = await waitFor(page, ([c, o0]) => {
        const o = window.oceanStats.origin;
        return o && (o[0] !== o0[0] || o[2] !== o0[2]) && Math.hypot(o[0] - c[0], o[2] - c[2]) < Math.hypot(o0[0] - c[0], o0[2] - c[2]);
    }, [c1, o0], timeoutMs);
    const o1 = (await stats(page)).origin;
    check('frames follow the camera (frame origin)', follows,
        `origin ${o0.map((v) => v.toFixed(1))} -> ${o1.map((v) => v.toFixed(1))}, camera ${c1.map((v) => v.toFixed(1))}`);

    /* two viewers of one ocean */
    const page2 = await context.newPage();
    const page2Errors = [];
    page2.on('pageerror', (e) => page2Errors.push(String(e)));
    await page2.goto(withView(`${base}?x=40&y=30&z=-25&yaw=-60&pitch=-15&sun=100,30`), { waitUntil: 'load', timeout: timeoutMs });
    const before = (await stats(page)).framesReceived;
    const both = await waitFor(page2, () => window.oceanStats && window.oceanStats.framesReceived >= 5 && window.oceanStats.framesRendered >= 2, null, timeoutMs);
    const s1 = await stats(page), s2 = await stats(page2);
    check('second page gets frames', both, `received ${s2.framesReceived}, state ${s2.state}, error "${s2.lastError}"`);
    check('first page keeps getting frames meanwhile', s1.framesReceived > before, `${before} -> ${s1.framesReceived}`);
    check('two pages are two clients', s1.clientId != null && s2.clientId != null && s1.clientId !== s2.clientId, `${s1.clientId} / ${s2.clientId}`);
    const sea1 = s1.hello && s1.hello.sea, sea2 = s2.hello && s2.hello.sea;
    check('one ocean: same sea state and seed for both', !!sea1 && JSON.stringify(sea1) === JSON.stringify(sea2),
        sea1 ? `seed ${sea1.seed}, wind ${sea1.windU10} m/s` : 'no HELLO');
    /* one clock: both pages show times of the same server clock.  Each
     * shows the frame it drew last, as old as its drawing interval (seconds
     * under software GL on a busy host), so the two are compared until they
     * come within 2 s of each other, up to the deadline: pages on clocks of
     * their own would drift apart by the time between their connections */
    let clock = null;
    for (const until = Date.now() + timeoutMs; Date.now() < until;) {
        const [a, b] = [(await stats(page)).simTime, (await stats(page2)).simTime];
        clock = [a, b];
        if (Math.abs(a - b) < 2) break;
        await page.waitForTimeout(250);
    }
    check('one ocean: both on one sim clock', clock && Math.abs(clock[0] - clock[1]) < 2,
        clock ? `${clock[0].toFixed(2)} / ${clock[1].toFixed(2)}` : 'no reading');
    check('second page: no errors', page2Errors.length === 0 && s2.decodeErrors === 0 && s2.serverErrors === 0, [...page2Errors, ...s2.errors].join(' | '));
    /* the controls panel (issue 45): sun=AZ,EL (in the second page's URL)
     * places the sun as ocean-sim render --sun does; below, the field of
     * view slider reaches the CAMERA reports, and with the admin token a
     * wind change ramped over 3 s arrives as announces the page applies */
    const sunDir = await page2.evaluate(() => window.oceanViewer.renderer.sunDir);
    const sunWant = [Math.cos(30 * Math.PI / 180) * Math.cos(100 * Math.PI / 180), Math.sin(30 * Math.PI / 180),
        Math.cos(30 * Math.PI / 180) * Math.sin(100 * Math.PI / 180)];
    check('sun=AZ,EL places the sun', sunDir.every((v, i) => Math.abs(v - sunWant[i]) < 1e-9), JSON.stringify(sunDir));
    await page2.waitForTimeout(800);
    writeFileSync(join(artifacts, 'viewer-2.png'), await page2.screenshot({ type: 'png' }));

    /* control: the same view without the streamed sea (sky and flat far
     * sea only) must have far less structure than the real view; it runs
     * on layout 0 with f16 tiles, so that path and codec are exercised too */
    await page2.goto(`${url}&sea=0&codec=f16&layout=0`, { waitUntil: 'load', timeout: timeoutMs });
    await waitFor(page2, () => window.oceanStats && window.oceanStats.tilesDecoded > 0, null, timeoutMs);
    await waitFor(page2, () => window.oceanStats && window.oceanStats.framesWithMesh > 0, null, timeoutMs);
    const sC = await stats(page2);
    /* layout 0's mesh positions arrive as qz (mesh_codec 2) and the worker
     * decodes them with the topology: frames carry a mesh, no errors */
    check('the f16 codec and layout 0 (qz mesh positions) work end to end too', sC.codec === 'f16' && sC.layout === 0 &&
        sC.subscription.layout === 0 && sC.subscription.meshCodec === 2 && sC.framesWithMesh > 0 &&
        sC.tilesDecoded > 0 && sC.decodeErrors === 0 && sC.serverErrors === 0,
        `codec ${sC.codec}, layout ${sC.layout}, mesh codec ${sC.subscription.meshCodec}, ${sC.framesWithMesh} frames with a mesh, ${sC.tilesDecoded} tiles, ${sC.decodeErrors} errors ${sC.errors.join(' | ')}; ` +
        `${sC.framesReceived} frames received, ${sC.framesDecoded} decoded, ${sC.framesRendered} rendered, ${sC.topologies} topologies, the last frame's mesh ${JSON.stringify(sC.meshLast || null)}`);
    await page2.waitForTimeout(1500);
    const pngC = await page2.screenshot({ type: 'png' });
    writeFileSync(join(artifacts, 'viewer-control.png'), pngC);
    const detC = detail(decodePng(pngC), sea0, img1.h);
    /* layout 1 carries what its byte budget affords (server.px_per_sample
     * at most, coarser near the water) and shades the rest, with the
     * short-wave tail, as roughness (a smooth lobe, by design), so its sea
     * has less pixel-scale structure than layout 0's did: 1.37-1.51x the
     * flat control measured at 14 m in ship-bridge (2.5x was required of
     * layout 0); a blank or flat sea gives 1.0 */
    check('the sea has wave detail (vs. a view without the mesh)', det > 1.0 && det > 1.3 * detC,
        `structure ${det.toFixed(2)} with the mesh, ${detC.toFixed(2)} without`);
    /* the controls, on the control page while it is live (the sea it
     * changes is the one the checks after this one see) */
    await page2.click('#help-toggle');
    await page2.evaluate(() => {
        const f = document.getElementById('ctl-fov');
        f.value = '20';
        f.dispatchEvent(new Event('input'));
    });
    const fovSent = await waitFor(page2, () => window.oceanStats.cameraSent && window.oceanStats.cameraSent.fovYDeg === 20, null, timeoutMs);
    check('the field-of-view control reaches the camera the daemon plans for', fovSent,
        JSON.stringify((await stats(page2)).cameraSent));
    const token = process.env.ADMIN_TOKEN;
    if (token) {
        await page2.fill('#ctl-token', token);
        await page2.fill('#ctl-wind', '14');
        await page2.fill('#ctl-dir', '45');
        await page2.fill('#ctl-ramp', '3');
        await page2.click('#ctl-sea-apply');
        const ramped = await waitFor(page2, () => window.oceanStats.sea && window.oceanStats.sea.windU10 === 14 &&
            window.oceanStats.sea.windDirDeg === 45, null, timeoutMs);
        const sS = await stats(page2);
        check('the sea-state control ramps the wind with the admin token (announces applied at their times)',
            ramped && sS.seaSetsSent === 2 && sS.serverErrors === 0,
            `sea ${JSON.stringify(sS.sea && [sS.sea.windU10, sS.sea.windDirDeg])}, ${sS.seaSetsSent} sets, errors ${sS.errors.join(' | ')}`);
        await page2.fill('#ctl-token', 'not-the-token');
        await page2.click('#ctl-sea-apply');
        const refused = await waitFor(page2, () => window.oceanStats.errors.some((e) => /EAUTH|token/i.test(e)), null, timeoutMs);
        check('a wrong admin token is refused and said on the overlay', refused, (await stats(page2)).errors.join(' | '));
    } else {
        check('ADMIN_TOKEN given to the test (tests/test_browser.sh)', false, 'no ADMIN_TOKEN');
    }
    /* a ship entered over ENTITY (ocean-client entity, as a simulator
     * does, a sample every 2 s) 150 m ahead of a fresh viewer's eye,
     * steaming across its view: the WAKE patterns come, and the viewer
     * draws a wake there (its WebAssembly reads them on the square ahead
     * of the eye) */
    const entityToken = process.env.ENTITY_TOKEN, oc = process.env.OCEAN_CLIENT;
    if (entityToken && oc) {
        const page3 = await context.newPage();
        await page3.goto(withView(`${base}?x=0&y=25&z=0&yaw=0&pitch=-10`), { waitUntil: 'load', timeout: timeoutMs });
        await waitFor(page3, () => window.oceanStats && window.oceanStats.framesRendered >= 2, null, timeoutMs);
        const e0 = (await stats(page3)).serverErrors;
        const set = (x) => execFileSync(oc, ['entity', base.replace(/^http/, 'ws'), '--set', '--token', entityToken,
            '--id', '77', '--kind', 'ship', '--x', '150', '--z', String(x), '--heading', '90', '--speed', '8',
            '--length', '120', '--beam', '15', '--draught', '5'], { timeout: 30000 });
        let drawn = false;
        for (let k = 0, z = -100; !drawn && k * 2000 < timeoutMs; k++, z += 16) {
            set(z);
            drawn = await waitFor(page3, () => window.oceanStats.wakes && window.oceanStats.wakes.peak > 0.05, null, 2000);
        }
        const sW = await stats(page3);
        check('a ship entered over ENTITY gets its wake drawn (WAKE patterns read on the square ahead of the eye)',
            drawn && sW.serverErrors === e0 && sW.decodeErrors === 0,
            `wakes ${JSON.stringify(sW.wakes)}, patterns ${sW.wakePatterns}, errors ${sW.errors.join(' | ')}`);
        /* the ship gone (the square flat: the other ship, entered far away
         * by tests/test_browser.sh, reaches none of it), a helicopter (16 m
         * rotor) hovering 10 m over the water 60 m ahead: its downwash's
         * dent, 7 cm deep (sim/rotor_wash.h), read by the same WebAssembly
         * from its ENTITY entries alone */
        execFileSync(oc, ['entity', base.replace(/^http/, 'ws'), '--remove', '--token', entityToken, '--id', '77'],
            { timeout: 30000 });
        const none = await waitFor(page3, () => !window.oceanStats.wakes || window.oceanStats.wakes.peak < 1e-3, null,
            timeoutMs);
        execFileSync(oc, ['entity', base.replace(/^http/, 'ws'), '--set', '--token', entityToken, '--id', '78',
            '--kind', 'rotorcraft', '--x', '60', '--z', '0', '--altitude', '10', '--speed', '0', '--length', '16'],
            { timeout: 30000 });
        const dent = await waitFor(page3, () => window.oceanStats.wakes && window.oceanStats.wakes.trough < -0.05,
            null, timeoutMs);
        const sR = await stats(page3);
        check('a rotorcraft entered over ENTITY gets its downwash drawn (the dent under it, on the same square)',
            none && dent && sR.serverErrors === e0 && sR.decodeErrors === 0,
            `square emptied ${none}, dent ${dent}: wakes ${JSON.stringify(sR.wakes)}, server errors ${sR.serverErrors - e0}, decode errors ${sR.decodeErrors} ${sR.errors.join(' | ')}`);
        await page3.close();
    } else {
        check('ENTITY_TOKEN and OCEAN_CLIENT given to the test (tests/test_browser.sh)', false, 'not given');
    }
    /* a daemon that answers nothing for a while (a loaded host, a sea
     * change being built, a debugger, a paused VM) is asked one QUERY at a
     * time: the viewer asked twice a second whatever came back, and with a
     * core busy the questions it queued were refused by the daemon's limit
     * on pending queries (server.max_pending_queries), ERRORs on the
     * overlay.  The daemon is stopped (SIGSTOP) for 3 s, under the viewer's
     * patience of 10 s for one answer and over the 2 s in which asking
     * twice a second fills this daemon's limit of 4 pending queries
     * (tests/test_browser.sh); afterwards it answers, and nothing is
     * refused. */
    const pid = Number(process.env.OCEAND_PID);
    if (pid > 0) {
        const sQ = await stats(page2);
        process.kill(pid, 'SIGSTOP');
        try {
            await page2.waitForTimeout(3000);
        } finally {
            process.kill(pid, 'SIGCONT');
        }
        const sent = ((await stats(page2)).queriesSent || 0) - (sQ.queriesSent || 0);
        const answered = await waitFor(page2, (r) => window.oceanStats.queryResults > r, sQ.queryResults || 0, timeoutMs);
        /* on a loaded host the connection may drop as the daemon resumes;
         * the viewer reconnects on its own */
        const back = await waitFor(page2, () => window.oceanStats.state === 'subscribed', null, timeoutMs);
        const sP = await stats(page2);
        check('a daemon silent for 3 s is asked one QUERY at a time, none refused', sent <= 1 && answered && back &&
            sP.serverErrors === sQ.serverErrors,
            `${sent} queries sent while it was stopped, answered after: ${answered}, state ${sP.state}, errors ` +
            `${sP.errors.slice(sQ.errors.length).join(' | ')}`);
    } else {
        check('OCEAND_PID given to the test (tests/test_browser.sh)', false, 'no OCEAND_PID');
    }
    /* t=T: the sea of one instant (replay mode), the view a reference
     * render of the exact sea is compared with: every frame is the sea at T,
     * so two screenshots a few frames apart are the same picture */
    const T = 123.25;
    await page2.goto(withView(`${base}?x=0&y=14&z=0&yaw=30&pitch=-12&t=${T}&overlay=0`), { waitUntil: 'load', timeout: timeoutMs });
    const held = await waitFor(page2, (t) => window.oceanStats && window.oceanStats.framesRendered >= 3 &&
        window.oceanStats.simTime === t, T, timeoutMs);
    const sR = await stats(page2);
    /* on the live stream's samples in time, so the view judged against
     * the reference carries a live viewer's detail (every tile whole in
     * each frame left it 6x coarser: q 0.39 against 0.07) */
    check('t= opens the sea of that instant (replay mode, frames at T, samples in time as live)', held && sR.subscription &&
        sR.subscription.mode === 1 && sR.subscription.flags === 2 && sR.serverErrors === 0 && sR.decodeErrors === 0,
        `sim time ${sR.simTime}, mode ${sR.subscription && sR.subscription.mode}, flags ${sR.subscription && sR.subscription.flags}, ` +
        `q ${sR.block && sR.block.spacingPerM}, ` +
        `${sR.framesRendered} rendered, errors ${sR.errors.join(' | ')}`);
    const belowAtT = await waitFor(page2, (t) => window.oceanStats.seaBelow && window.oceanStats.seaBelow.t === t, T, timeoutMs);
    const below = (await stats(page2)).seaBelow;
    check('t= keeps the eye above the sea at T (queried at T, not at the live time)', belowAtT, JSON.stringify(below));
    const hudShown = await page2.evaluate(() => ['hud', 'help-toggle'].map((id) => getComputedStyle(document.getElementById(id)).display).join(' '));
    check('overlay=0 hides the overlay and the controls button', hudShown === 'none none', hudShown);
    const pngR1 = await page2.screenshot({ type: 'png' });
    await waitFor(page2, ([d, r]) => window.oceanStats.framesDecoded >= d + 2 && window.oceanStats.framesRendered >= r + 2,
        [sR.framesDecoded, sR.framesRendered], timeoutMs);
    const pngR2 = await page2.screenshot({ type: 'png' });
    writeFileSync(join(artifacts, 'viewer-replay.png'), pngR2);
    const imgR1 = decodePng(pngR1), imgR2 = decodePng(pngR2);
    const still = meanAbsDiff(imgR1, imgR2, 0, imgR1.h);
    const sR2 = await stats(page2);
    check('t= holds the sea: two screenshots frames apart are the same', still < 0.05 && sR2.simTime === T,
        `mean |diff| ${still.toFixed(3)} over ${sR2.framesRendered - sR.framesRendered} frames, sim time ${sR2.simTime}`);
    /* a change of wind (or sun) re-renders the whole sky at once: the
     * HELLO's sea arrives after the first draw, and a sky cube refreshed a
     * face every 250 ms showed the default sky's faces beside the real
     * one's for 1.5 s, so a screenshot soon after the first frames was not
     * the sea of T (seen as a failure of the check above on a busy host) */
    const wind0 = await page2.evaluate(() => {
        const r = window.oceanViewer.renderer, w = r.wind;
        r.wind = [-w[1], w[0]];
        return window.oceanStats.framesRendered;
    });
    await waitFor(page2, (r) => window.oceanStats.framesRendered >= r + 1, wind0, timeoutMs);
    const imgW1 = decodePng(await page2.screenshot({ type: 'png' }));
    await page2.waitForTimeout(1600);   /* past a whole round of faces (6 x 250 ms) */
    await waitFor(page2, (r) => window.oceanStats.framesRendered >= r + 2, wind0, timeoutMs);
    const imgW2 = decodePng(await page2.screenshot({ type: 'png' }));
    const turned = meanAbsDiff(imgR2, imgW2, 0, imgR2.h), settled = meanAbsDiff(imgW1, imgW2, 0, imgW2.h);
    check('a change of wind redraws the whole sky at once (not a face at a time)', turned > 0.05 && settled < 0.05,
        `the wind turned 90 deg changed the picture by ${turned.toFixed(3)}; after one frame it differed from ` +
        `1.6 s later by ${settled.toFixed(3)}`);
    /* the nadir from 10 km: no spot of its own (issue 45: the haze took
     * the sky's colour in the view's azimuth, which turned to the zenith
     * straight down: a dark spot with a bright cone toward the sun, luma 80
     * against 103 +- 12 around it); the centre's luminance lies within the
     * spread of the ring around it */
    await page2.goto(withView(`${base}?x=0&y=10000&z=0&yaw=0&pitch=-89&t=${T}&overlay=0`), { waitUntil: 'load', timeout: timeoutMs });
    await waitFor(page2, (t) => window.oceanStats && window.oceanStats.framesRendered >= 3 && window.oceanStats.simTime === t, T, timeoutMs);
    const pngN = await page2.screenshot({ type: 'png' });
    writeFileSync(join(artifacts, 'viewer-nadir.png'), pngN);
    const imgN = decodePng(pngN);
    const ring = (r0, r1) => {
        let sum = 0, sum2 = 0, n = 0;
        for (let y = 0; y < imgN.h; y++) for (let x = 0; x < imgN.w; x++) {
            const r = Math.hypot(x - imgN.w / 2, y - imgN.h / 2) / imgN.h;
            if (r >= r0 && r < r1) { const l = lum(imgN, x, y); sum += l; sum2 += l * l; n++; }
        }
        const m = sum / n;
        return [m, Math.sqrt(Math.max(sum2 / n - m * m, 0))];
    };
    const [nadirL] = ring(0, 0.03), [aroundL, aroundS] = ring(0.06, 0.15);
    check('10 km, looking down: the nadir within the spread of its surroundings', Math.abs(nadirL - aroundL) <= Math.max(aroundS, 2),
        `luma ${nadirL.toFixed(1)} at the nadir, ${aroundL.toFixed(1)} +- ${aroundS.toFixed(1)} around it`);
    await glitterLattice(page2, T);
    /* a page with no camera in its URL opens where the scene's
     * camera_hint says (served in /status), not at a fixed 25 m */
    const status = await (await fetch(new URL('status', base))).json();
    const h = status.camera_hint;
    check('/status carries the scene camera hint', !!h && [h.x, h.y, h.z, h.yaw, h.pitch].every(Number.isFinite),
        JSON.stringify(h));
    if (h) {
        await page2.goto(withView(base), { waitUntil: 'load', timeout: timeoutMs });
        await waitFor(page2, () => window.oceanViewer && window.oceanStats && window.oceanStats.framesReceived >= 1, null, timeoutMs);
        const c = await page2.evaluate(() => ({ pos: window.oceanViewer.camera.pos.slice(), yaw: window.oceanViewer.camera.yawDeg,
            pitch: window.oceanViewer.camera.pitchDeg }));
        /* the camera may have moved since (its velocity is 0 without vx/vy/vz) */
        const near = Math.hypot(c.pos[0] - h.x, c.pos[1] - h.y, c.pos[2] - h.z) < 1 && Math.abs(c.yaw - h.yaw) < 1e-6 &&
            Math.abs(c.pitch - h.pitch) < 1e-6;
        check('viewer opens at the scene camera hint', near,
            `camera (${c.pos.map((v) => v.toFixed(1))}) yaw ${c.yaw} pitch ${c.pitch}, hint ${JSON.stringify(h)}`);
    }
    check('no request left the daemon', foreign.length === 0, foreign.slice(0, 3).join(', '));
    if (consoleErrors.length) console.log(`# console errors: ${consoleErrors.slice(0, 5).join(' | ')}`);
    const fin = await stats(page);
    console.log(`# page 1: ${fin.framesReceived} frames, ${fin.framesRendered} rendered, ${fin.fps.toFixed(1)} fps, ` +
        `${(fin.bytesPerSec / 1e6).toFixed(2)} MB/s, latency p50 ${fin.latencyP50?.toFixed(1)} ms, codec ${fin.codec}, ` +
        `${fin.levels} levels, decode ${fin.decodeMs.toFixed(1)} ms`);
} catch (e) {
    check('browser session', false, String(e && e.stack || e));
} finally {
    if (context) await context.close().catch(() => {});
    rmSync(userDataDir, { recursive: true, force: true });
}
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed === 0 && passed > 0 ? 0 : 1);
