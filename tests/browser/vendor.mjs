/*
 * vendor.mjs (`npm run vendor`) - copies zstd's WebAssembly decoder out of
 * the pinned npm package zstddec into clients/web/vendor/zstd.wasm, with its
 * licence.  zstddec ships the module as base64 inside its JavaScript; the
 * viewer instantiates the bytes itself (clients/web/codec.js), so the
 * daemon serves one binary file and no copy of zstddec's loader.
 */
import { readFileSync, writeFileSync } from 'node:fs';
import { join } from 'node:path';
import { fileURLToPath } from 'node:url';

const pkg = fileURLToPath(new URL('./node_modules/zstddec/', import.meta.url));
const src = readFileSync(join(pkg, 'dist/zstddec.mjs'), 'utf8');
const m = /const wasm\s*=\s*'([A-Za-z0-9+/=]+)'/.exec(src) || /const wasm\s*=\s*"([A-Za-z0-9+/=]+)"/.exec(src);
if (!m) throw new Error('zstddec: no embedded WebAssembly module found in dist/zstddec.mjs');
const bytes = Buffer.from(m[1], 'base64');
WebAssembly.validate(bytes) || (() => { throw new Error('zstddec: the embedded module does not validate'); })();
const out = new URL('../../clients/web/vendor/', import.meta.url);
writeFileSync(new URL('zstd.wasm', out), bytes);
writeFileSync(new URL('zstd.LICENSE', out), readFileSync(join(pkg, 'LICENSE')));
console.log(`vendor: clients/web/vendor/zstd.wasm, ${bytes.length} bytes, from zstddec ${JSON.parse(readFileSync(join(pkg, 'package.json'), 'utf8')).version}`);
