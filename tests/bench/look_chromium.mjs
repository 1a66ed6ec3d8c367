/*
 * look_chromium.mjs BASE VIEWS.json - the browser viewer's screenshots of
 * fixed views of one scene's sea, beside the reference renders of the exact
 * sea (ocean-sim render) of the same views, compared by SSIM (Wang, Bovik,
 * Sheikh & Simoncelli 2004, "Image quality assessment: from error
 * visibility to structural similarity", IEEE TIP 13(4); the npm package
 * ssim.js, its 'original' algorithm: 11-tap Gaussian window, K1 0.01,
 * K2 0.03, on luma, with the paper's downsampling of large images).
 *
 * VIEWS.json: [{name, x, y, z, yaw, pitch, fov, t, width, height, ref, shot}]:
 * each view opens BASE?x=..&t=T&overlay=0 (replay mode: every frame is the
 * sea at T) in headless Chromium at width x height as a user's viewer draws
 * (full resolution, multisampling), waits until frames at T have been drawn
 * after the stream filled in (the first frame's tiles plus eight more), and
 * writes the screenshot to `shot` and, if `pair` is given, both pictures
 * side by side at half size as a JPEG there.  Prints one JSON line a view:
 * {name, ssim, mean_abs_diff, frames, errors}; a view with "edge": true (a
 * level view from near the water) adds the sea's top edge in each picture
 * (pixels.mjs seaEdgeRows): edge_viewer and edge_ref {top, range, mean}
 * (the highest row the sea reaches, rows between highest and lowest, mean
 * row) and edge_within_1 (the fraction of columns where the two edges lie
 * within a row of each other).
 * env LOOK_QUERY: more URL parameters for every view (e.g. "&time=0", the
 * plain stream; "&rough=0"), for experiments beside the bench's own run.
 */
import { readFileSync, writeFileSync, mkdtempSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { createRequire } from 'node:module';

const require = createRequire(new URL('../browser/', import.meta.url));
const { chromium } = require('playwright-core');
const { ssim } = require('ssim.js');
const { decodePng, seaEdgeRows, seaEdgeSummary } = await import('../browser/pixels.mjs');

const [base, viewsPath] = process.argv.slice(2);
const views = JSON.parse(readFileSync(viewsPath, 'utf8'));
const exe = process.env.CHROMIUM || '/usr/bin/chromium';
const timeoutMs = 240000;

function meanAbsDiff(a, b) {
    let s = 0;
    for (let i = 0; i < a.px.length; i += 4)
        s += (Math.abs(a.px[i] - b.px[i]) + Math.abs(a.px[i + 1] - b.px[i + 1]) + Math.abs(a.px[i + 2] - b.px[i + 2])) / 3;
    return s / (a.px.length / 4);
}

/* The two pictures side by side at half size, as a JPEG for the report
 * (drawn by the browser itself: no image library needed). */
async function sideBySide(a, b, out) {
    const page = await context.newPage();
    await page.setViewportSize({ width: 1280, height: 360 });
    const img = (p) => `<img src="data:image/png;base64,${p.toString('base64')}" style="width:640px;height:360px">`;
    await page.setContent(`<body style="margin:0;display:flex">${img(a)}${img(b)}</body>`);
    await page.waitForFunction(() => [...document.images].every((i) => i.complete));
    writeFileSync(out, await page.screenshot({ type: 'jpeg', quality: 70 }));
    await page.close();
}

const userDataDir = mkdtempSync(join(tmpdir(), 'ocean-look-'));
const context = await chromium.launchPersistentContext(userDataDir, {
    executablePath: exe,
    headless: true,
    viewport: { width: views[0].width, height: views[0].height },
    args: ['--headless=new', '--no-sandbox', '--disable-gpu', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
        '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run',
        '--disable-background-timer-throttling', '--disable-renderer-backgrounding'],
    timeout: 60000,
});
context.setDefaultTimeout(timeoutMs);
try {
    for (const v of views) {
        const page = await context.newPage();
        await page.setViewportSize({ width: v.width, height: v.height });
        const url = `${base}?x=${v.x}&y=${v.y}&z=${v.z}&yaw=${v.yaw}&pitch=${v.pitch}&fov=${v.fov}&t=${v.t}&overlay=0&scale=1${process.env.LOOK_QUERY || ''}`;
        await page.goto(url, { waitUntil: 'load', timeout: timeoutMs });
        await page.waitForFunction((t) => window.oceanStats && window.oceanStats.framesRendered >= 2 &&
            window.oceanStats.simTime === t, v.t, { timeout: timeoutMs, polling: 200 });
        const s0 = await page.evaluate(() => ({ d: window.oceanStats.framesDecoded, r: window.oceanStats.framesRendered }));
        await page.waitForFunction(([d, r]) => window.oceanStats.framesDecoded >= d + 8 && window.oceanStats.framesRendered >= r + 8,
            [s0.d, s0.r], { timeout: timeoutMs, polling: 200 });
        const png = await page.screenshot({ type: 'png' });
        writeFileSync(v.shot, png);
        const st = await page.evaluate(() => ({ frames: window.oceanStats.framesRendered, errors: window.oceanStats.errors.slice(), vertices: window.oceanStats.vertexCount, zones: window.oceanStats.zones, block: window.oceanStats.block, bytesPerSec: window.oceanStats.bytesPerSec, cascades: window.oceanStats.cascades }));
        await page.close();
        const a = decodePng(png), b = decodePng(readFileSync(v.ref));
        if (a.w !== b.w || a.h !== b.h) throw new Error(`${v.name}: screenshot ${a.w}x${a.h}, reference ${b.w}x${b.h}`);
        const r = ssim({ data: a.px, width: a.w, height: a.h }, { data: b.px, width: b.w, height: b.h }, { ssim: 'original' });
        if (v.pair) await sideBySide(png, readFileSync(v.ref), v.pair);
        const line = { name: v.name, ssim: r.mssim, mean_abs_diff: meanAbsDiff(a, b), frames: st.frames, errors: st.errors, vertices: st.vertices, zones: st.zones, block: st.block, bytesPerSec: st.bytesPerSec, cascades: st.cascades };
        if (v.edge) {
            const ea = seaEdgeRows(a), eb = seaEdgeRows(b);
            Object.assign(line, { edge_viewer: seaEdgeSummary(ea), edge_ref: seaEdgeSummary(eb), edge_within_1: ea.filter((y, i) => Math.abs(y - eb[i]) <= 1).length / ea.length });
        }
        console.log(JSON.stringify(line));
    }
} finally {
    await context.close();
}
