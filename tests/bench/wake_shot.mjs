/*
 * wake_shot.mjs URL OUT.png - one screenshot of the browser viewer at URL
 * (its camera and instant in the query string) once it draws a wake:
 * headless Chromium as look_chromium.mjs runs it, waiting until the page's
 * wakes (window.oceanStats.wakes) are drawn and eight more frames are.
 * Prints one JSON line: {wakes, frames, errors}.
 */
import { writeFileSync, mkdtempSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { createRequire } from 'node:module';

const require = createRequire(new URL('../browser/', import.meta.url));
const { chromium } = require('playwright-core');
const [url, out, size] = process.argv.slice(2);
const [width, height] = (size || '1280x720').split('x').map(Number);
const context = await chromium.launchPersistentContext(mkdtempSync(join(tmpdir(), 'ocean-wake-')), {
    executablePath: process.env.CHROMIUM || '/usr/bin/chromium', headless: true, viewport: { width, height },
    args: ['--headless=new', '--no-sandbox', '--disable-gpu', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
        '--disable-background-timer-throttling', '--disable-renderer-backgrounding'],
});
try {
    const page = await context.newPage();
    await page.goto(url, { waitUntil: 'load', timeout: 240000 });
    await page.waitForFunction(() => window.oceanStats && window.oceanStats.wakes && window.oceanStats.wakes.peak > 0.05,
        null, { timeout: 240000, polling: 250 });
    const r0 = await page.evaluate(() => window.oceanStats.framesRendered);
    await page.waitForFunction((r) => window.oceanStats.framesRendered >= r + 8, r0, { timeout: 240000, polling: 250 });
    writeFileSync(out, await page.screenshot({ type: 'png' }));
    const s = await page.evaluate(() => ({ wakes: window.oceanStats.wakes, frames: window.oceanStats.framesRendered,
        errors: window.oceanStats.errors }));
    console.log(JSON.stringify(s));
} finally {
    await context.close();
}
