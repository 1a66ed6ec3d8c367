/*
 * decoder.js - one worker of the tile decode pool.  The network worker
 * sends it whole levels of a layout-0 FRAME, or a share of the tiles of a
 * layout-1 FRAME (tile headers with their payload bytes); it decodes and
 * assembles them (assemble.js) and returns the grids with their buffers
 * transferred.  Several of these run in parallel on machines with the
 * cores for it, so a 30 Hz qz stream keeps up.
 *
 * In:  {id, levels: [{level, tiles: [...]}]} or {id, tiles: [...]}
 * Out: {id, levels: [record...], blocks: [block...], errors: [string...]}
 */
import { assembleLevel, assembleCascadeTile } from './assemble.js';

self.onmessage = (ev) => {
    const { id, levels, tiles } = ev.data;
    const out = [], blocks = [], transfer = [], errors = [];
    const onError = (e, what) => errors.push(`${what}: ${e.message || e}`);
    for (const { level, tiles: lt } of levels || []) {
        const rec = assembleLevel(level, lt, onError);
        if (rec) {
            out.push(rec);
            transfer.push(rec.disp.buffer, rec.nrm.buffer);
        }
    }
    for (const t of tiles || []) {
        const b = assembleCascadeTile(t, onError);
        if (b) {
            blocks.push(b);
            transfer.push(b.disp.buffer, b.slope.buffer);
        }
    }
    self.postMessage({ id, levels: out, blocks, errors }, transfer);
};
