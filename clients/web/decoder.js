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
 * A time-interpolating stream (PROTOCOL.md "Samples in time") is held
 * here instead: each worker keeps a HeldStore (codec.js) of its shard of
 * the tiles, gets every FRAME of the connection in order ({held: 'apply'},
 * no answer) and blends the last one's instant when asked ({held:
 * 'blend'}, answered like a share of tiles).  Errors of applying go out
 * with the next answer.
 *
 * In:  {id, levels: [{level, tiles: [...]}]} or {id, tiles: [...]}
 *      {held: 'apply', frame: ArrayBuffer, shard, shards}
 *      {id, held: 'blend'}    {held: 'reset'} (the connection ended)
 * Out: {id, levels: [record...], blocks: [block...], errors: [string...]}
 */
const ready = Promise.all([import('./assemble.js'), import('./codec.js')]);
let store = null;            /* HeldStore of this worker's shard, or null */
let heldErrors = [];

function onHeld(m, modules) {
    const [a, c] = modules;
    const onError = (e, what) => heldErrors.push(`${what}: ${e.message || e}`);
    if (m.held === 'reset' || (m.held === 'apply' && store && (store.shard !== m.shard || store.shards !== m.shards))) {
        if (store) store.destroy();
        store = null;
    }
    if (m.held === 'apply') {
        try {
            if (!store) store = new c.HeldStore(m.shard, m.shards);
            store.apply(m.frame);
        } catch (e) {
            onError(e, 'FRAME (held samples)');
        }
    } else if (m.held === 'blend') {
        const blocks = store ? a.heldBlocks(store, onError) : [];
        const transfer = [];
        for (const b of blocks) transfer.push(b.disp.buffer, b.slope.buffer);
        const errors = heldErrors;
        heldErrors = [];
        self.postMessage({ id: m.id, levels: [], blocks, errors }, transfer);
    }
}

self.onmessage = async (ev) => {
    if (ev.data.held) {
        let modules;
        try {
            modules = await ready;
        } catch (e) {
            heldErrors.push(`loading the decoders: ${e.message || e}`);
            if (ev.data.held === 'blend') self.postMessage({ id: ev.data.id, levels: [], blocks: [], errors: heldErrors });
            return;
        }
        onHeld(ev.data, modules);
        return;
    }
    const { id, levels, tiles } = ev.data;
    const out = [], blocks = [], transfer = [], errors = [];
    const onError = (e, what) => errors.push(`${what}: ${e.message || e}`);
    let a;
    try {
        [a] = await ready;
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
