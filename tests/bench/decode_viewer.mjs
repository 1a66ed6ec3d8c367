/*
 * decode_viewer.mjs - the browser viewer's side of bench_decode.sh, in
 * Node.js, on one core: every FRAME of a frame store (ocean-client record)
 * decoded as the viewer's decode workers do (helpers/decode_loop.mjs).
 * Prints one line a frame
 *   frame INDEX TILES BYTES MS FNV
 * as decode_native does.
 *   usage: node tests/bench/decode_viewer.mjs FRAMES [WEB_DIR]
 * WEB_DIR (default clients/web) may hold another version of the viewer's
 * modules.
 */
import { readFileSync } from 'node:fs';
import { performance } from 'node:perf_hooks';
import { pathToFileURL } from 'node:url';
import { resolve } from 'node:path';

import { decodeFrames } from './helpers/decode_loop.mjs';

const file = process.argv[2];
if (!file) {
    console.error('usage: node decode_viewer.mjs FRAMES [WEB_DIR]');
    process.exit(2);
}
const web = pathToFileURL(resolve(process.argv[3] || new URL('../../clients/web', import.meta.url).pathname) + '/');
const b = readFileSync(file);
const lines = await decodeFrames(web, b.buffer.slice(b.byteOffset, b.byteOffset + b.byteLength), () => performance.now());
console.log(lines.join('\n'));
