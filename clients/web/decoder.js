/*
 * decoder.js - one worker of the tile decode pool.  The network worker
 * sends it whole levels of a FRAME (tile headers with their payload bytes);
 * it decodes and assembles them (assemble.js) and returns the grids with
 * their buffers transferred.  Several of these run in parallel on machines
 * with the cores for it, so a 30 Hz qz stream keeps up.
 *
 * In:  {id, levels: [{level, tiles: [...]}]}
 * Out: {id, levels: [record...], errors: [string...]}
 */
import { assembleLevel } from './assemble.js';

self.onmessage = (ev) => {
    const { id, levels } = ev.data;
    const out = [], transfer = [], errors = [];
    for (const { level, tiles } of levels) {
        const rec = assembleLevel(level, tiles, (e, what) => errors.push(`${what}: ${e.message || e}`));
        if (rec) {
            out.push(rec);
            transfer.push(rec.disp.buffer, rec.nrm.buffer);
        }
    }
    self.postMessage({ id, levels: out, errors }, transfer);
};
