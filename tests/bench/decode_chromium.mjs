/*
 * decode_chromium.mjs - the browser viewer's side of bench_decode.sh in
 * headless Chromium: the same loop as decode_viewer.mjs
 * (helpers/decode_loop.mjs) run in a module Worker, as the viewer's decode
 * workers run, on the viewer's modules served over HTTP.  A loopback HTTP
 * server here serves clients/web/ at /web/, the loop at /bench/ and the
 * frame store at /frames; Debian's chromium is driven by playwright-core
 * (tests/browser's pinned dev dependency).  Prints the loop's lines.
 *   usage: node tests/bench/decode_chromium.mjs FRAMES
 * Env: CHROMIUM (default /usr/bin/chromium).
 */
import { createServer } from 'node:http';
import { createRequire } from 'node:module';
import { readFileSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join, normalize } from 'node:path';

const file = process.argv[2];
if (!file) {
    console.error('usage: node decode_chromium.mjs FRAMES');
    process.exit(2);
}
const root = new URL('../../', import.meta.url).pathname;
const require = createRequire(join(root, 'tests/browser/package.json'));
const { chromium } = require('playwright-core');

const PAGE = `<!doctype html><meta charset="utf-8"><script type="module">
const w = new Worker('/bench/worker.mjs', { type: 'module' });
w.onmessage = (e) => { window.result = e.data; };
w.onerror = (e) => { window.result = { error: String(e.message || e) }; };
</script>`;
const WORKER = `import { decodeFrames } from '/bench/decode_loop.mjs';
try {
    const buf = await (await fetch('/frames')).arrayBuffer();
    self.postMessage({ lines: await decodeFrames(new URL('/web/', self.location.origin), buf, () => performance.now()) });
} catch (e) {
    self.postMessage({ error: String(e.stack || e) });
}`;

/* Only these paths are served: the page, the worker, the loop, the frames
 * and clients/web/ (no path may climb out of it). */
function serve(req, res) {
    const path = decodeURIComponent(new URL(req.url, 'http://x').pathname);
    const send = (type, body) => { res.writeHead(200, { 'content-type': type }); res.end(body); };
    try {
        if (path === '/') return send('text/html', PAGE);
        if (path === '/bench/worker.mjs') return send('text/javascript', WORKER);
        if (path === '/bench/decode_loop.mjs') return send('text/javascript', readFileSync(join(root, 'tests/bench/helpers/decode_loop.mjs')));
        if (path === '/frames') return send('application/octet-stream', readFileSync(file));
        const rel = normalize(path.slice('/web/'.length));
        if (path.startsWith('/web/') && !rel.startsWith('..')) {
            const type = rel.endsWith('.wasm') ? 'application/wasm' : 'text/javascript';
            return send(type, readFileSync(join(root, 'clients/web', rel)));
        }
    } catch { /* not found below */ }
    res.writeHead(404);
    res.end();
}

const server = createServer(serve);
await new Promise((ok) => server.listen(0, '127.0.0.1', ok));
const userDataDir = mkdtempSync(join(tmpdir(), 'ocean-bdecode-'));
let context, status = 0;
try {
    context = await chromium.launchPersistentContext(userDataDir, {
        executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
        headless: true,
        args: ['--headless=new', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
            '--disable-component-update', '--no-first-run', '--disable-background-timer-throttling',
            '--disable-renderer-backgrounding'],
    });
    const page = context.pages()[0] || await context.newPage();
    await page.goto(`http://127.0.0.1:${server.address().port}/`);
    await page.waitForFunction(() => window.result, null, { timeout: 600000, polling: 200 });
    const r = await page.evaluate(() => window.result);
    if (r.error) throw new Error(r.error);
    console.log(r.lines.join('\n'));
} catch (e) {
    console.error(`decode_chromium: ${e.message || e}`);
    status = 1;
} finally {
    if (context) await context.close();
    server.close();
    rmSync(userDataDir, { recursive: true, force: true });
}
process.exit(status);
