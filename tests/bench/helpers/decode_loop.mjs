/*
 * decode_loop.mjs - the timed loop of bench_decode.sh's viewer side, the
 * same in Node.js (decode_viewer.mjs) and in headless Chromium
 * (decode_chromium.mjs, in a module Worker like the viewer's decode
 * workers): every FRAME of a frame store (ocean-client record) decoded as
 * the viewer's workers decode it, from the viewer's own modules at `web`
 * (a URL ending in '/'): the message (protocol.js), then each tile into its
 * texel block (assemble.js assembleCascadeTile), or, for a
 * time-interpolating stream (PROTOCOL.md "Samples in time"), the frame
 * applied to the viewer's HeldStore (codec.js: the C library's store) and
 * its instant blended into texel blocks (assemble.js heldBlocks).
 *
 * Returns one line a frame, "frame INDEX TILES BYTES MS FNV", as
 * decode_native prints: FNV the FNV-1a (32 bit) of the planes of the tiles
 * the frame's instant reads (decodeTile, or the store's blend, outside the
 * timed part), blends in (cascade, mip, iz, ix) order, so the builds can be
 * compared bit for bit.
 */
const CASCADE_KEY = 1;

function fnv1a(h, u8) {
    for (let i = 0; i < u8.length; i++) h = Math.imul(h ^ u8[i], 16777619) >>> 0;
    return h;
}
const bytesOf = (f32) => new Uint8Array(f32.buffer, f32.byteOffset, f32.byteLength);

/* Whether frame f (decoded) belongs to a time-interpolating stream. */
function timed(f) {
    return f.layout === 1 && f.cascades &&
        ((f.cascades.flags & CASCADE_KEY) !== 0 || f.cascades.cascade.some((c) => (c.time || []).some((t) => t.interval)));
}

/* The frame's instant through the store: [ms, hash]. */
function heldFrame(mods, held, msg, t0, now) {
    held.apply(msg);
    mods.assemble.heldBlocks(held, (e) => { throw e; });
    const ms = now() - t0;
    const { tiles } = held.blend();
    const ord = tiles.map((t, i) => [t, i]).sort(([a], [b]) => a.cascade - b.cascade || a.mip - b.mip || a.iz - b.iz || a.ix - b.ix);
    let h = 2166136261;
    for (const [t, i] of ord) h = fnv1a(h, bytesOf(held.planes(i, t).data));
    return [ms, h];
}

/* A plain frame: every tile into its block: [ms, hash]. */
function plainFrame(mods, f, t0, now) {
    for (const t of f.tiles)
        if (!mods.assemble.assembleCascadeTile(t, (e) => { throw e; })) throw new Error('a tile did not decode');
    const ms = now() - t0;
    let h = 2166136261;
    for (const t of f.tiles) h = fnv1a(h, bytesOf(mods.codec.decodeTile(t.codec, t.width, t.height, t.channels, t.payload).data));
    return [ms, h];
}

/* Decodes every FRAME of the frame store in buf (an ArrayBuffer); now()
 * is the clock (performance.now). */
export async function decodeFrames(web, buf, now) {
    const mods = {
        protocol: await import(new URL('protocol.js', web)),
        codec: await import(new URL('codec.js', web)),
        assemble: await import(new URL('assemble.js', web)),
    };
    const u8 = new Uint8Array(buf);
    if (new TextDecoder('latin1').decode(u8.subarray(0, 8)) !== 'OCFRAMES') throw new Error('not a frame store');
    /* a module from before samples in time has no store */
    const held = mods.codec.HeldStore ? new mods.codec.HeldStore() : null;
    const dv = new DataView(buf);
    const lines = [];
    for (let off = 16, index = 0; off + 16 <= u8.length;) {
        const len = dv.getUint32(off, true);
        const msg = u8.subarray(off + 16, off + 16 + len);
        off += 16 + len;
        if (len < 32 || (msg[6] | (msg[7] << 8)) !== mods.protocol.T.FRAME) continue;
        const copy = msg.slice().buffer;
        const t0 = now();
        const f = mods.protocol.decode(copy).body;
        let r;
        if (timed(f)) {
            if (!held) throw new Error('a time-interpolating stream, and these modules have no HeldStore');
            r = heldFrame(mods, held, msg, t0, now);
        } else {
            r = plainFrame(mods, f, t0, now);
        }
        lines.push(`frame ${index} ${f.tiles.length} ${len} ${r[0].toFixed(4)} ${r[1].toString(16).padStart(8, '0')}`);
        index++;
    }
    if (held) held.destroy();
    return lines;
}
