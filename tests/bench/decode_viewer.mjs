/*
 * decode_viewer.mjs - the browser viewer's side of bench_decode.sh, in
 * Node.js: decodes every FRAME of a frame store (ocean-client record) the
 * way the viewer's decode workers do, on one core: the message
 * (protocol.js) and each tile into its texel block (assemble.js
 * assembleCascadeTile; today protocol/codec.c compiled to WebAssembly and
 * zstd's own decoder as WebAssembly, through codec.js).  Prints one line a frame
 *   frame INDEX TILES BYTES MS FNV
 * as decode_native does, FNV the FNV-1a (32 bit) of the decoded planes'
 * bytes (decodeTile, outside the timed part), tile after tile, so the two
 * builds can be compared bit for bit.
 *   usage: node tests/bench/decode_viewer.mjs FRAMES [WEB_DIR]
 * WEB_DIR (default clients/web) may hold another version of the viewer's
 * modules (bench_decode.sh times the JavaScript decoders it replaced).
 */
import { readFileSync } from 'node:fs';
import { performance } from 'node:perf_hooks';
import { pathToFileURL } from 'node:url';
import { resolve } from 'node:path';

const web = pathToFileURL(resolve(process.argv[3] || new URL('../../clients/web', import.meta.url).pathname) + '/');
const { decode, T } = await import(new URL('protocol.js', web));
const { decodeTile } = await import(new URL('codec.js', web));
const { assembleCascadeTile } = await import(new URL('assemble.js', web));

const file = process.argv[2];
if (!file) {
    console.error('usage: node decode_viewer.mjs FRAMES');
    process.exit(2);
}
const buf = readFileSync(file);
if (buf.toString('latin1', 0, 8) !== 'OCFRAMES') throw new Error(`${file}: not a frame store`);

function fnv1a(h, u8) {
    for (let i = 0; i < u8.length; i++) h = Math.imul(h ^ u8[i], 16777619) >>> 0;
    return h;
}

let off = 16, index = 0;
const dv = new DataView(buf.buffer, buf.byteOffset, buf.byteLength);
while (off + 16 <= buf.length) {
    const len = dv.getUint32(off, true);
    const msg = new Uint8Array(buf.buffer, buf.byteOffset + off + 16, len);
    off += 16 + len;
    if (len < 32 || (msg[6] | (msg[7] << 8)) !== T.FRAME) continue;
    const copy = msg.slice().buffer;
    const t0 = performance.now();
    const f = decode(copy).body;
    for (const t of f.tiles) {
        if (!assembleCascadeTile(t, (e) => { throw e; })) throw new Error(`frame ${index}: a tile did not decode`);
    }
    const ms = performance.now() - t0;
    let h = 2166136261;
    for (const t of f.tiles) {
        const d = decodeTile(t.codec, t.width, t.height, t.channels, t.payload).data;
        h = fnv1a(h, new Uint8Array(d.buffer, d.byteOffset, d.byteLength));
    }
    console.log(`frame ${index} ${f.tiles.length} ${len} ${ms.toFixed(4)} ${h.toString(16).padStart(8, '0')}`);
    index++;
}
