/*
 * assemble.js - turns the tiles of one level of a FRAME into the renderer's
 * texture-ready grids: disp = (H, DX, DZ, FOAM) and nrm = (normal xyz,
 * coverage), both RGBA float, row = z.  Tiles are placed by their world
 * origin, so tiles that share edge samples or leave gaps both come out
 * right (gaps keep coverage 0 and an upward normal).  Used by the decode
 * pool (decoder.js) and, without a pool, by the network worker itself.
 */
import { decodeTile, decodeCascadeBlock, octNormals } from './codec.js';
import { CH, CODEC_NAMES } from './protocol.js';

/* A folded crest's slope in the renderer's slope textures: steep enough
 * for any real facet, bounded so one texel cannot dominate a mip's mean. */
const MAX_SLOPE = 20;

/* Splits tiles by level: Map level -> tiles, levels ascending. */
export function groupByLevel(tiles) {
    const byLevel = new Map();
    for (const t of tiles) {
        if (!byLevel.has(t.level)) byLevel.set(t.level, []);
        byLevel.get(t.level).push(t);
    }
    return new Map([...byLevel.entries()].sort((a, b) => a[0] - b[0]));
}

/* tiles: one level's tiles {level, codec, channels, width, height, ix, iz,
 * originX, originZ, spacing, errorBound, payload}.  onError(e, what) is
 * told about each tile that fails to decode (the rest still assemble).
 * Returns the level record, or null if nothing could be placed. */
export function assembleLevel(level, tiles, onError) {
    const s = tiles[0].spacing;
    let ox = Infinity, oz = Infinity;
    for (const t of tiles) { ox = Math.min(ox, t.originX); oz = Math.min(oz, t.originZ); }
    let W = 0, H = 0;
    const place = [];
    for (const t of tiles) {
        if (Math.abs(t.spacing - s) > 1e-9 * s) continue;     /* mixed spacing in one level: skip the odd one */
        const col = Math.round((t.originX - ox) / s), row = Math.round((t.originZ - oz) / s);
        if (col > 4096 || row > 4096) continue;                /* absurd layout: refuse to allocate */
        place.push([t, col, row]);
        W = Math.max(W, col + t.width);
        H = Math.max(H, row + t.height);
    }
    if (!place.length) return null;
    const disp = new Float32Array(W * H * 4);
    const nrm = new Float32Array(W * H * 4);
    for (let i = 0; i < W * H; i++) nrm[4 * i + 1] = 1;        /* up, not covered */
    let errorBound = 0, foamMax = 0, foamSum = 0, foamN = 0, decoded = 0, hasNormals = false;
    for (const [t, col, row] of place) {
        let dec;
        try {
            dec = decodeTile(t.codec, t.width, t.height, t.channels, t.payload);
        } catch (e) {
            onError(e, `tile L${t.level} (${t.ix},${t.iz}) ${CODEC_NAMES[t.codec]}`);
            continue;
        }
        decoded++;
        errorBound = Math.max(errorBound, t.errorBound);
        const n = t.width * t.height, d = dec.data;
        const plane = {};
        let p = 0;
        for (const [bit, names] of [[CH.HEIGHT, ['H']], [CH.DX, ['DX']], [CH.DZ, ['DZ']], [CH.NORMAL, ['NU', 'NV']], [CH.FOAM, ['FOAM']], [CH.JACOBIAN, ['J']]])
            if (t.channels & bit) for (const nm of names) { plane[nm] = p * n; p++; }
        const pH = plane.H, pX = plane.DX, pZ = plane.DZ, pU = plane.NU, pV = plane.NV, pF = plane.FOAM;
        const nrmT = pU !== undefined ? octNormals(d.subarray(pU, pU + n), d.subarray(pV, pV + n)) : null;
        if (nrmT) hasNormals = true;
        for (let r = 0; r < t.height; r++) {
            for (let c = 0; c < t.width; c++) {
                const k = r * t.width + c;
                const o = 4 * ((row + r) * W + col + c);
                disp[o] = pH !== undefined ? d[pH + k] : 0;
                disp[o + 1] = pX !== undefined ? d[pX + k] : 0;
                disp[o + 2] = pZ !== undefined ? d[pZ + k] : 0;
                const fo = pF !== undefined ? d[pF + k] : 0;
                disp[o + 3] = fo;
                if (fo > foamMax) foamMax = fo;
                foamSum += fo;
                if (nrmT) { nrm[o] = nrmT[4 * k]; nrm[o + 1] = nrmT[4 * k + 1]; nrm[o + 2] = nrmT[4 * k + 2]; }
                nrm[o + 3] = 1;
            }
        }
        foamN += n;
    }
    return {
        level, spacing: s, originX: ox, originZ: oz, width: W, height: H, disp, nrm, errorBound,
        foamMax, foamMean: foamN ? foamSum / foamN : 0, tiles: decoded, hasNormals,
    };
}

/* Layout 1 (PROTOCOL.md "Cascade mips"): one tile of mip `level` of
 * cascade `cascade` becomes the renderer's texel block at texel (x, y) =
 * (ix·T, iz·T) of that mip, T the tile's side.  disp = (DX, H, DZ, 0)
 * (RGBA, so a vertex adds disp.xyz to its flat position); slope = (∂η/∂x,
 * ∂η/∂z, BI, BQ), the slopes from the octahedral normal
 * (n = normalise(−sx, 1, −sz), so s = −n.xz / n.y) or, if the tile has no
 * normal planes, from central differences of H.  Slopes, not normals,
 * because cascades add: the surface's slope is the sum of the cascades'
 * slopes, and a mip's (GL-filtered) mean slope is the mean of its texels'
 * slopes.  The breaking index and its quadrature add likewise; the shader
 * turns their sum into foam (PROTOCOL.md "Whitecaps in layout 1").
 * Returns null (and tells onError) if the tile does not decode. */
export function assembleCascadeTile(t, onError) {
    let b;
    try {
        b = decodeCascadeBlock(t, MAX_SLOPE);
    } catch (e) {
        onError(e, `cascade ${t.cascade} mip ${t.level} tile (${t.ix},${t.iz}) ${CODEC_NAMES[t.codec]}`);
        return null;
    }
    return texelBlock(t.cascade, t.level, t, b);
}

/* The renderer's record of one texel block b of mip `mip` of cascade
 * `cascade` for tile t. */
function texelBlock(cascade, mip, t, b) {
    const w = t.width, h = t.height;
    return {
        cascade, mip, x: t.ix * w, y: t.iz * h, w, h, disp: b.disp, slope: b.slope,
        errorBound: t.errorBound, n: w * h,
        hasNormals: (t.channels & CH.NORMAL) !== 0,
    };
}

/* Layout 1 with samples in time (PROTOCOL.md "Samples in time"): the
 * tiles a HeldStore (codec.js) blends at its last frame's instant, as the
 * texel blocks assembleCascadeTile makes of a frame's own tiles.
 * onError(e, what) is told about tiles that did not decode (left out). */
export function heldBlocks(store, onError) {
    const { tiles, error } = store.blend();
    if (error) onError(error, 'held samples');
    const blocks = [];
    tiles.forEach((t, i) => {
        try {
            blocks.push(texelBlock(t.cascade, t.mip, t, store.texels(i, t, MAX_SLOPE)));
        } catch (e) {
            onError(e, `cascade ${t.cascade} mip ${t.mip} tile (${t.ix},${t.iz}) blended`);
        }
    });
    return blocks;
}
