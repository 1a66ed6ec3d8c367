/*
 * decoder.js - one worker of the tile decode pool.  The network worker
 * sends it whole levels of a layout-0 FRAME, or a share of the tiles of a
 * layout-1 FRAME (tile headers with their payload bytes); it decodes and
 * assembles them (assemble.js, on the WebAssembly decoders of codec.js)
 * and returns the grids with their buffers transferred.  Several of these
 * run in parallel on machines with the cores for it.
 *
 * The handler is installed before the decoders have loaded (a dynamic
 * import), so no job posted meanwhile is lost: it waits for them.
 *
 * In:  {id, levels: [{level, tiles: [...]}]} or {id, tiles: [...]}
 * Out: {id, levels: [record...], blocks: [block...], errors: [string...]}
 */
const ready = import('./assemble.js');

self.onmessage = async (ev) => {
    const { id, levels, tiles } = ev.data;
    const out = [], blocks = [], transfer = [], errors = [];
    const onError = (e, what) => errors.push(`${what}: ${e.message || e}`);
    let a;
    try {
        a = await ready;
    } catch (e) {
        onError(e, 'loading the decoders');
        self.postMessage({ id, levels: out, blocks, errors });
        return;
    }
    for (const { level, tiles: lt } of levels || []) {
        const rec = a.assembleLevel(level, lt, onError);
        if (rec) {
            out.push(rec);
            transfer.push(rec.disp.buffer, rec.nrm.buffer);
        }
    }
    for (const t of tiles || []) {
        const b = a.assembleCascadeTile(t, onError);
        if (b) {
            blocks.push(b);
            transfer.push(b.disp.buffer, b.slope.buffer);
        }
    }
    self.postMessage({ id, levels: out, blocks, errors }, transfer);
};
