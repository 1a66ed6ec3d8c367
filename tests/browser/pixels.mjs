/*
 * pixels.mjs - reading the viewer's screenshots in the browser tests: a
 * minimal PNG decoder (8-bit RGB/RGBA, non-interlaced: what Chromium
 * writes) and the pixel measures the tests assert on.
 */
import { inflateSync } from 'node:zlib';

export function decodePng(buf) {
    const sig = [137, 80, 78, 71, 13, 10, 26, 10];
    if (!sig.every((b, i) => buf[i] === b)) throw new Error('not a PNG');
    let off = 8, w = 0, h = 0, depth = 0, ctype = 0, interlace = 0;
    const idat = [];
    while (off < buf.length) {
        const len = buf.readUInt32BE(off), type = buf.toString('latin1', off + 4, off + 8);
        const data = buf.subarray(off + 8, off + 8 + len);
        if (type === 'IHDR') { w = data.readUInt32BE(0); h = data.readUInt32BE(4); depth = data[8]; ctype = data[9]; interlace = data[12]; }
        else if (type === 'IDAT') idat.push(data);
        else if (type === 'IEND') break;
        off += 12 + len;
    }
    if (depth !== 8 || (ctype !== 2 && ctype !== 6) || interlace) throw new Error(`unsupported PNG (depth ${depth}, type ${ctype})`);
    const bpp = ctype === 6 ? 4 : 3, stride = w * bpp;
    const raw = inflateSync(Buffer.concat(idat));
    const px = new Uint8Array(w * h * 4);
    let prev = new Uint8Array(stride), cur = new Uint8Array(stride);
    for (let y = 0; y < h; y++) {
        const f = raw[y * (stride + 1)], line = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
        for (let i = 0; i < stride; i++) {
            const a = i >= bpp ? cur[i - bpp] : 0, b = prev[i], c = i >= bpp ? prev[i - bpp] : 0;
            let v = line[i];
            if (f === 1) v += a;
            else if (f === 2) v += b;
            else if (f === 3) v += (a + b) >> 1;
            else if (f === 4) { const p = a + b - c, pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c); v += pa <= pb && pa <= pc ? a : pb <= pc ? b : c; }
            cur[i] = v & 255;
        }
        for (let x = 0; x < w; x++) {
            const o = (y * w + x) * 4;
            px[o] = cur[x * bpp]; px[o + 1] = cur[x * bpp + 1]; px[o + 2] = cur[x * bpp + 2]; px[o + 3] = bpp === 4 ? cur[x * bpp + 3] : 255;
        }
        [prev, cur] = [cur, prev];
    }
    return { w, h, px };
}

/* Rec. 709 luma of pixel (x, y), 0..255 */
export function lum(img, x, y) { const o = (y * img.w + x) * 4; return 0.2126 * img.px[o] + 0.7152 * img.px[o + 1] + 0.0722 * img.px[o + 2]; }

/* The sun glitter in rows [y0, y1) (the sea below the horizon): pixels at
 * least `thresh` bright.  area = their fraction of the region; rows /
 * cols = the extent (count of rows / columns holding any); spread = the
 * standard deviation of their positions (px); lumMean = mean luma of the
 * region; p99 = its 99th percentile. */
export function glitter(img, y0, y1, thresh = 200) {
    let n = 0, sx = 0, sy = 0, sxx = 0, syy = 0, sl = 0;
    const rows = new Set(), cols = new Set(), all = [];
    for (let y = y0; y < y1; y++)
        for (let x = 0; x < img.w; x++) {
            const l = lum(img, x, y);
            sl += l;
            all.push(l);
            if (l < thresh) continue;
            n++; sx += x; sy += y; sxx += x * x; syy += y * y;
            rows.add(y); cols.add(x);
        }
    const tot = (y1 - y0) * img.w;
    all.sort((a, b) => a - b);
    const sp = n ? Math.sqrt(Math.max(0, sxx / n - (sx / n) ** 2) + Math.max(0, syy / n - (sy / n) ** 2)) : 0;
    return { area: n / tot, pixels: n, rows: rows.size, cols: cols.size, spread: sp, lumMean: sl / tot, p99: all[Math.floor(0.99 * (all.length - 1))] };
}

/* Row of the horizon for a camera pitched `pitchDeg` with vertical field
 * of view `fovDeg` in an image `h` rows high (eye height neglected). */
export function horizonRow(h, pitchDeg, fovDeg) {
    const t = Math.tan(-pitchDeg * Math.PI / 180) / Math.tan(fovDeg * Math.PI / 360);
    return Math.round(h / 2 - t * h / 2);
}

/* Luma of the picture on the sea's mean plane y = 0: an n x n grid of world
 * points (x0 + i dx, 0, z0 + j dx), row j, column i, each projected through
 * the camera (eye, basis {fwd, right, up} as camera.js's cameraBasis,
 * vertical field of view fovDeg) and read bilinearly.  Lattices of the
 * mesh and the tiles lie along the world's axes at fixed spacings, so on
 * this grid each is a line at its own frequency wherever it is in the
 * picture.  Throws if a point falls off the picture. */
export function planeLuma(img, eye, basis, fovDeg, x0, z0, dx, n) {
    const f = img.h / 2 / Math.tan(fovDeg * Math.PI / 360), out = [];
    const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    for (let j = 0; j < n; j++) {
        const row = new Float64Array(n);
        for (let i = 0; i < n; i++) {
            const v = [x0 + i * dx - eye[0], -eye[1], z0 + j * dx - eye[2]];
            const cz = dot(v, basis.fwd);
            const sx = img.w / 2 + f * dot(v, basis.right) / cz - 0.5, sy = img.h / 2 - f * dot(v, basis.up) / cz - 0.5;
            const x = Math.floor(sx), y = Math.floor(sy), a = sx - x, b = sy - y;
            if (!(cz > 0) || x < 0 || y < 0 || x + 1 >= img.w || y + 1 >= img.h)
                throw new Error(`plane point (${x0 + i * dx}, ${z0 + j * dx}) is off the picture`);
            row[i] = (1 - b) * ((1 - a) * lum(img, x, y) + a * lum(img, x + 1, y)) + b * ((1 - a) * lum(img, x, y + 1) + a * lum(img, x + 1, y + 1));
        }
        out.push(row);
    }
    return out;
}

/* Power spectra of a square grid g (rows of equal length n) along each
 * axis: each line's mean removed and a Hann window applied, the lines'
 * periodograms averaged (Welch 1967).  {along: P over the rows' direction
 * (i), across: P over the columns' (j)}, P[k] for k = 0 .. n/2 cycles per
 * n samples. */
export function axisSpectra(g) {
    const n = g.length, cosT = new Float64Array(n), sinT = new Float64Array(n), w = new Float64Array(n);
    for (let i = 0; i < n; i++) {
        cosT[i] = Math.cos(2 * Math.PI * i / n); sinT[i] = Math.sin(2 * Math.PI * i / n); w[i] = 0.5 - 0.5 * cosT[i];
    }
    const line = new Float64Array(n);
    const add = (P, get) => {
        let m = 0;
        for (let i = 0; i < n; i++) { line[i] = get(i); m += line[i]; }
        m /= n;
        for (let i = 0; i < n; i++) line[i] = (line[i] - m) * w[i];
        for (let k = 0; k <= n / 2; k++) {
            let re = 0, im = 0;
            for (let i = 0, j = 0; i < n; i++, j = (j + k) % n) { re += line[i] * cosT[j]; im -= line[i] * sinT[j]; }
            P[k] += (re * re + im * im) / n;
        }
    };
    const along = new Float64Array(n / 2 + 1), across = new Float64Array(n / 2 + 1);
    for (let j = 0; j < n; j++) add(along, (i) => g[j][i]);
    for (let i = 0; i < n; i++) add(across, (j) => g[j][i]);
    return { along, across };
}

/* How far spectrum P stands out at bin k: the power at k - 1 .. k + 1 (a
 * line leaks into its neighbours through the window) over what a power
 * law fitted to the bins around it (k / 1.6 .. 1.6 k, less k - 3 .. k + 3,
 * least squares in log P against log k) gives there.  A lattice is a
 * narrow line at its frequency; the sea's own spectrum follows a smooth
 * law across such a span, whatever its slope. */
export function lineRatio(P, k) {
    let n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (let j = Math.max(1, Math.floor(k / 1.6)); j <= Math.min(P.length - 1, Math.ceil(k * 1.6)); j++) {
        if (Math.abs(j - k) <= 3 || !(P[j] > 0)) continue;
        const x = Math.log(j), y = Math.log(P[j]);
        n++; sx += x; sy += y; sxx += x * x; sxy += x * y;
    }
    if (n < 4) return NaN;
    const slope = (n * sxy - sx * sy) / (n * sxx - sx * sx), icpt = (sy - slope * sx) / n;
    const peak = Math.max(P[k - 1] || 0, P[k], P[k + 1] || 0);
    return peak / Math.exp(icpt + slope * Math.log(k));
}

/* The sea's top edge in each column of a level view: the first row, from
 * the top, darker than halfway between the sky at the top of that column
 * and the sea at its bottom (sky and sea differ by 80+ luma at a level
 * view; haze only narrows it).  Returns the rows, one a column. */
export function seaEdgeRows(img) {
    const rows = new Int32Array(img.w);
    for (let x = 0; x < img.w; x++) {
        const cut = (lum(img, x, 2) + lum(img, x, img.h - 3)) / 2;
        let y = 0;
        while (y < img.h && lum(img, x, y) > cut) y++;
        rows[x] = y;
    }
    return rows;
}

/* seaEdgeRows summed up: the highest row the sea reaches, the rows between
 * its highest and lowest, and the mean row. */
export function seaEdgeSummary(rows) {
    let top = Infinity, bottom = -Infinity, sum = 0;
    for (const y of rows) { top = Math.min(top, y); bottom = Math.max(bottom, y); sum += y; }
    return { top, range: bottom - top, mean: sum / rows.length };
}
