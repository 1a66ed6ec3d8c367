/*
 * scenes.test.mjs - the layout-1 viewer at three camera heights in one
 * scene, against a running oceand (tests/test_browser.sh starts one per
 * scene: ship-bridge, storm, flight).  For each height (25 m, 300 m,
 * 1500 m) the camera looks toward the sun (the viewer puts it 0.5 rad
 * from the wind direction, 17.7 degrees up), waits for a FRAME made for
 * that camera and takes a screenshot: ARTIFACT_DIR/scene-SCENE-Hm.png.
 * At 1500 m it also checks that the mesh's end does not show (the mesh over
 * the far sea vs the far-sea pass alone, row by row) and takes two
 * screenshots without foam, one with the unresolved slope variance
 * switched off (renderer.roughScale = 0: every pixel a mirror at its mean
 * normal), and asserts that the sun glitter of the real rendering is
 * spread by roughness: many times the bright area and a wider spread than
 * the mirror's (Bruneton, Neyret & Holzschuch 2010: the unresolved slopes
 * widen the glitter lobe; without them a far sea reflects a sharp sun).
 * The glitter of the same sea seen from 25 m and from 1500 m (foam off,
 * one pitch) is recorded in scenes.jsonl for the report.
 * RELIEF_REF (optional, the storm): `ocean-sim render` of the exact sea
 * from 5 m, level, 10 deg, 960x270, t = RELIEF_T; the viewer opens the same
 * view at that instant (?t=, full resolution) and its crests must break the
 * horizon as the exact sea's do (relief, below).
 * SHOTS_OUT (optional): a directory the screenshots are copied to
 * (tests/bench/out for the benchmark report).
 *
 * Env: OCEAN_URL, SCENE, ARTIFACT_DIR, CHROMIUM, VIEWER_TIMEOUT_S, SHOTS_OUT,
 * VIEW_QUERY, RELIEF_REF, RELIEF_T.
 * Prints "N passed, N failed"; exits non-zero on any failure.
 */
import { createRequire } from 'node:module';
import { mkdirSync, writeFileSync, mkdtempSync, rmSync, appendFileSync, readFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { decodePng, glitter, horizonRow, lum, seaEdgeRows, seaEdgeSummary } from './pixels.mjs';

const require = createRequire(new URL('./package.json', import.meta.url));
const { chromium } = require('playwright-core');

const base = process.env.OCEAN_URL || 'http://127.0.0.1:8740/';
const scene = process.env.SCENE || 'scene';
const artifacts = process.env.ARTIFACT_DIR || 'build/test-artifacts';
const shotsOut = process.env.SHOTS_OUT || '';
const timeoutMs = 1000 * Number(process.env.VIEWER_TIMEOUT_S || 60);
const exe = process.env.CHROMIUM || '/usr/bin/chromium';
/* VIEW_QUERY: viewer options every page gets (tests/test_browser.sh asks
 * for fewer pixels, scale=0.25&aa=0: what is judged here does not depend
 * on the resolution, and a software renderer draws 4 times the frames) */
const viewQuery = process.env.VIEW_QUERY || '';
const withView = (u) => (viewQuery ? `${u}${u.includes('?') ? '&' : '?'}${viewQuery}` : u);
mkdirSync(artifacts, { recursive: true });
if (shotsOut) mkdirSync(shotsOut, { recursive: true });

let passed = 0, failed = 0;
function check(name, ok, detail = '') {
    if (ok) { passed++; console.log(`ok - ${scene}: ${name}${detail ? ` (${detail})` : ''}`); }
    else { failed++; console.log(`not ok - ${scene}: ${name}${detail ? ` (${detail})` : ''}`); }
    return ok;
}
function save(name, png, report = true) {
    writeFileSync(join(artifacts, name), png);
    if (shotsOut && report) writeFileSync(join(shotsOut, name), png);
}
async function waitFor(page, pred, arg, ms) {
    try { await page.waitForFunction(pred, arg, { timeout: ms, polling: 200 }); return true; } catch { return false; }
}
const stats = (page) => page.evaluate(() => JSON.parse(JSON.stringify(window.oceanStats || null)));
function variance(img, y0, y1) {
    let s = 0, s2 = 0, n = 0;
    for (let y = y0; y < y1; y++) for (let x = 0; x < img.w; x++) { const l = lum(img, x, y); s += l; s2 += l * l; n++; }
    return s2 / n - (s / n) ** 2;
}

/* Relief: crests break the horizon.  From 5 m over the storm sea (Hs
 * 9.34 m), level, 10 deg high (27 rows a degree), the exact sea's crests
 * 0.7-3 km out rise over the flat sea's horizon and make its edge ragged.
 * The viewer's edge (pixels.mjs seaEdgeRows, per column) must rise over the
 * flat horizon by at least half the rows the exact sea's does, and vary
 * across the columns by at least half the reference's range: the crests'
 * projection, drawn as geometry, not a ruler-straight line. */
async function relief(context) {
    const W = 960, H = 270, T = Number(process.env.RELIEF_T || 123.25), FOVR = 10;
    const page = await context.newPage();
    try {
        await page.setViewportSize({ width: W, height: H });
        await page.goto(`${base}?x=0&y=5&z=0&yaw=0&pitch=0&fov=${FOVR}&t=${T}&overlay=0&scale=1`, { waitUntil: 'load', timeout: timeoutMs });
        const held = await waitFor(page, (t) => window.oceanStats && window.oceanStats.framesRendered >= 2 &&
            window.oceanStats.simTime === t, T, timeoutMs);
        /* the stream filled in: eight more frames decoded and drawn */
        const s0 = await stats(page);
        const more = held && await waitFor(page, ([d, r]) => window.oceanStats.framesDecoded >= d + 8 &&
            window.oceanStats.framesRendered >= r + 8, [s0.framesDecoded, s0.framesRendered], timeoutMs);
        const png = await page.screenshot({ type: 'png' });
        save(`scene-${scene}-relief-5m.png`, png);
        const a = decodePng(png), b = decodePng(readFileSync(process.env.RELIEF_REF));
        const ea = seaEdgeSummary(seaEdgeRows(a)), eb = seaEdgeSummary(seaEdgeRows(b));
        /* a flat sea's horizon from 5 m: sqrt(2h/R) = 0.07 deg below level */
        const flat = Math.round(H / 2 + Math.tan(Math.sqrt(2 * 5 / 6371008.8)) / Math.tan(FOVR * Math.PI / 360) * H / 2);
        const riseV = flat - ea.top, riseR = flat - eb.top;
        const st = await stats(page);
        check('5 m, level, 10 deg: crests break the horizon as the exact sea\'s do (relief)',
            more && a.w === b.w && a.h === b.h && riseR > 2 && riseV >= riseR / 2 && ea.range >= eb.range / 2 &&
            st.serverErrors === 0,
            `highest edge ${riseV} rows over the flat horizon (row ${flat}) against the exact sea's ${riseR}; ` +
            `edge range ${ea.range} rows against ${eb.range}; mesh ${st.vertexCount} vertices, ` +
            `q ${(st.block && st.block.cascades || []).map((c) => c.q.toPrecision(2)).join(' ')}; errors ${st.errors.join(' | ')}`);
    } finally {
        await page.close();
    }
}

const FOV = 60;
const views = [{ h: 25, pitch: -8 }, { h: 300, pitch: -12 }, { h: 1500, pitch: -15 }];
const userDataDir = mkdtempSync(join(tmpdir(), 'ocean-chromium-'));
let context;
try {
    context = await chromium.launchPersistentContext(userDataDir, {
        executablePath: exe, headless: true, viewport: { width: 960, height: 540 },
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
    const page = context.pages()[0] || await context.newPage();
    const pageErrors = [];
    page.on('pageerror', (e) => pageErrors.push(String(e)));
    await page.goto(withView(`${base}?overlay=0&x=0&y=25&z=0&pitch=-8&fov=${FOV}`), { waitUntil: 'load', timeout: timeoutMs });
    const up = await waitFor(page, () => window.oceanStats && window.oceanStats.hello && window.oceanStats.framesRendered >= 2, null, timeoutMs);
    let s = await stats(page);
    check('viewer up on layout 1', up && s.layout === 1 && s.subscription && s.subscription.layout === 1,
        `state ${s && s.state}, layout ${s && s.layout}, error "${s && s.lastError}"`);
    /* look toward the sun: main.js puts it 0.5 rad from the wind direction */
    const sunYaw = s && s.hello ? s.hello.sea.windDirDeg + 0.5 * 180 / Math.PI : 30;
    const summary = [];
    for (const v of views) {
        await page.evaluate(([h, p, y]) => {
            const c = window.oceanViewer.camera;
            c.pos[1] = h; c.pitchDeg = p; c.yawDeg = ((y + 180) % 360 + 360) % 360 - 180; c.speed = 0;
        }, [v.h, v.pitch, sunYaw]);
        /* a FRAME made for this camera, then two renderings of it */
        const got = await waitFor(page, (h) => {
            const st = window.oceanStats;
            return st.block && Math.abs(st.block.camera[1] - h) < 2;
        }, v.h, timeoutMs);
        const r0 = (await stats(page)).framesRendered;
        await waitFor(page, (r) => window.oceanStats.framesRendered >= r + 3, r0, timeoutMs);
        s = await stats(page);
        check(`${v.h} m: frames answer the camera`, got, `block camera y ${s.block && s.block.camera[1]}`);
        const png = await page.screenshot({ type: 'png' });
        save(`scene-${scene}-${v.h}m.png`, png);
        const img = decodePng(png);
        const hz = horizonRow(img.h, v.pitch, FOV);
        const sea0 = Math.min(img.h - 10, hz + Math.round(0.06 * img.h));
        const g = glitter(img, sea0, img.h, 235);
        const varSea = variance(img, sea0, img.h);
        check(`${v.h} m: sea drawn (not blank)`, varSea > 5 && s.decodeErrors === 0 && s.serverErrors === 0,
            `sea luma variance ${varSea.toFixed(1)}, errors ${s.errors.join(' | ')}`);
        const casInfo = (s.cascades || []).map((c) => `${c.patch.toFixed(0)} m: mips ${c.mipsSent.join(',') || '-'} (${c.tiles} tiles)`).join('; ');
        const line = { scene, height: v.h, spacingPerM: s.block.spacingPerM, eTotal: s.block.eTotal, tailMss: s.block.tailMss,
            bytesPerSec: Math.round(s.bytesPerSec), tiles: s.tileCount, cascades: casInfo, foamMean: s.foamMean, glitterArea: g.area, glitterSpread: g.spread, seaLuma: g.lumMean };
        /* the glitter alone, for comparing heights: foam off (whitecaps
         * drawn as patches near the eye and as a mean far away hide
         * different parts of it) and one pitch for both heights, so a wide
         * lobe (the storm's) is cut by the screen's edge alike (the camera's
         * pitch needs no new FRAME: tiles follow its position) */
        if (v.h === 25 || v.h === 1500) {
            const CMP_PITCH = -15;
            const r2 = (await stats(page)).framesRendered;
            await page.evaluate((p) => { window.oceanViewer.renderer.foamScale = 0; window.oceanViewer.camera.pitchDeg = p; }, CMP_PITCH);
            await waitFor(page, (r) => window.oceanStats.framesRendered >= r + 2, r2, timeoutMs);
            const pngF = await page.screenshot({ type: 'png' });
            await page.evaluate((p) => { window.oceanViewer.renderer.foamScale = 1; window.oceanViewer.camera.pitchDeg = p; }, v.pitch);
            save(`scene-${scene}-${v.h}m-nofoam.png`, pngF, false);
            const imgF = decodePng(pngF);
            const gf = glitter(imgF, Math.min(imgF.h - 10, horizonRow(imgF.h, CMP_PITCH, FOV) + Math.round(0.06 * imgF.h)), imgF.h, 235);
            line.glitterAreaNoFoam = gf.area;
            line.glitterSpreadNoFoam = gf.spread;
        }
        if (v.h === 1500) {
            /* one frame held (the worker paused) for the controls */
            await page.evaluate(() => window.oceanViewer.worker.postMessage({ cmd: 'pause', paused: true }));
            const frames = async (k) => {
                const r = await page.evaluate(() => window.oceanStats.framesRendered);
                await page.waitForTimeout(400);
                await waitFor(page, ([r0, n]) => window.oceanStats.framesRendered >= r0 + n, [r, k], timeoutMs);
            };
            await frames(2);
            const pngA = await page.screenshot({ type: 'png' });
            /* no mesh edge: the mesh drawn over the far sea, and the far sea
             * pass alone (drawSea = false), differ by under 1 luma in every
             * row, so nothing marks where the mesh ends */
            await page.evaluate(() => { window.oceanViewer.renderer.drawSea = false; });
            await page.waitForTimeout(1500);   /* drawSea = false renders without counting */
            const pngB = await page.screenshot({ type: 'png' });
            await page.evaluate(() => { window.oceanViewer.renderer.drawSea = true; });
            save(`scene-${scene}-1500m-farsea.png`, pngB, false);
            const A = decodePng(pngA), B = decodePng(pngB);
            /* rows where the mesh ends: its flat extent E (half-side of the
             * outer square ring) seen from height h, between E (straight
             * ahead, less the placement's snap) and E·sqrt(2) (its corners) */
            const E = await page.evaluate(() => window.oceanViewer.renderer.topology1.extent);
            const rowAt = (d) => {
                const a = Math.atan2(v.h, d) - (-v.pitch) * Math.PI / 180;
                return Math.round(A.h / 2 + Math.tan(a) / Math.tan(FOV * Math.PI / 360) * A.h / 2);
            };
            const yTop = Math.max(0, rowAt(E * 1.5) - 6), yBot = Math.min(A.h, rowAt(E * 0.9) + 6);
            let worst = 0, worstRow = -1;
            for (let y = yTop; y < yBot; y++) {
                let d = 0;
                for (let x = 0; x < A.w; x++) d += Math.abs(lum(A, x, y) - lum(B, x, y));
                if (d / A.w > worst) { worst = d / A.w; worstRow = y; }
            }
            line.meshVsFarSea = worst;
            line.meshEndRows = [yTop, yBot];
            check('1500 m: no visible mesh edge (mesh vs far-sea pass where the mesh ends)', yBot > yTop && worst < 1.0,
                `mesh half-side ${E.toFixed(0)} m ends on rows ${yTop}..${yBot}; worst row mean |luma difference| ${worst.toFixed(3)} at row ${worstRow}`);
            /* the glitter of the same frame, and the control: the frame
             * with the unresolved slopes ignored; both without foam, whose
             * whitecaps are bright too (a storm's mirror has a handful of
             * bright pixels, and a whitecap among them is no glitter) */
            const shot = async (rough) => {
                await page.evaluate((k) => { const r = window.oceanViewer.renderer; r.foamScale = 0; r.roughScale = k; }, rough);
                await frames(2);
                return page.screenshot({ type: 'png' });
            };
            const pngG = await shot(1), pngM = await shot(0);
            await page.evaluate(() => {
                const r = window.oceanViewer.renderer;
                r.roughScale = 1;
                r.foamScale = 1;
                window.oceanViewer.worker.postMessage({ cmd: 'pause', paused: false });
            });
            save(`scene-${scene}-1500m-mirror.png`, pngM);
            const g0 = glitter(decodePng(pngG), sea0, img.h, 235), m = glitter(decodePng(pngM), sea0, img.h, 235);
            line.mirrorArea = m.area;
            line.mirrorSpread = m.spread;
            check('1500 m: sun glitter spread by roughness, not a mirror',
                g0.area >= 0.005 && g0.area >= 10 * m.area && g0.spread >= 2 * m.spread,
                `bright area ${(100 * g0.area).toFixed(2)} % vs mirror ${(100 * m.area).toFixed(3)} %, ` +
                `spread ${g0.spread.toFixed(1)} px vs mirror ${m.spread.toFixed(1)} px (no foam in either)`);
        }
        summary.push(line);
        console.log(`# ${JSON.stringify(line)}`);
    }
    if (process.env.RELIEF_REF) await relief(context);
    /* The same sea from 25 m and from 1500 m (foam off, one pitch):
     * glitterAreaNoFoam / glitterSpreadNoFoam in scenes.jsonl.  Not
     * asserted: in ship-bridge and flight they agree within 1.4x, but in the
     * storm the 25 m view's glitter is half the 1500 m one's (1.95 % vs
     * 4.17 % of the sea above luma 235) - open, see the report. */
    check('no page errors', pageErrors.length === 0, pageErrors.slice(0, 3).join(' | '));
    appendFileSync(join(artifacts, 'scenes.jsonl'), summary.map((l) => JSON.stringify(l)).join('\n') + '\n');
} catch (e) {
    check('browser session', false, String(e && e.stack || e));
} finally {
    if (context) await context.close().catch(() => {});
    rmSync(userDataDir, { recursive: true, force: true });
}
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed === 0 && passed > 0 ? 0 : 1);
