/*
 * lod.test.mjs - the viewer's shader code for "Where each mip is read"
 * (PROTOCOL.md) against the points protocol/lod.c computes
 * (tests/vectors/lod.txt and lod_mss.txt, written and checked by
 * test_proto).
 *
 * The rule's only copy in the viewer is GLSL (clients/web/render.js:
 * CASCADE_GLSL, CASCADE_FRAG_GLSL, compiled after COMMON as the viewer
 * compiles them).  This test compiles that text in headless Chromium's
 * WebGL2 (software GL, as tests/test_browser.sh runs the viewer) with a
 * main() that calls the rule's functions, and reads the results back from
 * float render targets: per point, the spacing wanted (wantSpacing), the
 * fade (casLod), and what the vertex path (casDisp) and the shading path
 * (seaSample) read from textures whose mip m holds the constant (1, m, m²):
 * the sums Σw, Σw·m, Σw·m² over the mips read, which are those of the C
 * rule's mips and weights exactly when both read the same mips with the
 * same weights (two adjacent mips and their weights are determined by the
 * three sums).  Each point is read through cascade slot (i mod 4), the
 * other slots holding zeros, so each of the four unrolled slots is run.
 *
 * The unresolved slope moments are checked the same way against
 * tests/vectors/lod_mss.txt (the same points, each with a tail_mss and the
 * cascade's mip table): the mss the shading path (seaSample, through
 * casMss) returns with that table in the point's slot and that tail.
 *
 * The whitecap rule ("Whitecaps in layout 1") is checked against
 * tests/vectors/lod_foam.txt: foamAt, the shader's turning of the summed
 * breaking index, its quadrature and the variance the reads hold into foam
 * with a frame's whitecap table, against protocol/lod.c's proto_lod_foam.
 *
 * Tolerances are binary32's (the GPU's floats; the vectors are doubles)
 * and the shader's skip of a second read whose weight is under 1e-4; for
 * the moments 1e-6 of the largest term a component adds (the tail or an
 * entry), about 16 ulp.
 *
 * Run by tests/test_browser.sh with PROTO_VECTORS=tests/vectors
 * (CHROMIUM: the browser, default /usr/bin/chromium).  node --test.
 */
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readFileSync } from 'node:fs';
import { join } from 'node:path';

import { COMMON, CASCADE_GLSL, CASCADE_FRAG_GLSL, MAX_CASCADES, MIP_ENTRIES, FOAM_ROWS } from '../../clients/web/render.js';

import { probeRun } from './glprobe.mjs';


/* The lines of a vector file as [inputs, outputs] number arrays. */
function vectorLines(path) {
    return readFileSync(path, 'utf8').split('\n').filter((l) => l.trim() && !l.startsWith('#'))
        .map((line) => line.split('->').map((h) => h.trim().split(/\s+/).map(Number)));
}

/* The point and cascade of a line's first ten inputs (both files). */
function pointOf([q, minS, camY, dx, dz, floorS, patch, n, mips, fades]) {
    return { q, minS, camY, dx, dz, floorS, patch, n, mips, fades };
}

/* lod.txt: one point a line: inputs, "->", the C rule's reading (see the file's head). */
function readVectors(path) {
    return vectorLines(path).map(([lhs, rhs]) => {
        assert.equal(lhs.length, 10, `input fields of: ${lhs}`);
        assert.equal(rhs.length, 7, `output fields of: ${rhs}`);
        const [s, lambda, mip0, w0, mip1, w1, fade] = rhs;
        const read = [[mip0, w0], [mip1, w1]].filter(([m]) => m >= 0);
        return {
            ...pointOf(lhs), s, lambda, fade,
            sum: read.reduce((a, [, w]) => a + w, 0),
            sumM: read.reduce((a, [m, w]) => a + w * m, 0),
            sumM2: read.reduce((a, [m, w]) => a + w * m * m, 0),
        };
    });
}

/* lod_mss.txt: a point, tail_mss, the mip table's moments of entries
 * 0..mips, "->", the C rule's mss (see the file's head).  tab is the
 * shader's u_mipTab rows (kc, mss_x, mss_z, mss_xz) of the cascade; kc,
 * which the moments do not use, is set apart from them (1000 + m) so a
 * shader that read it would differ. */
function readMssVectors(path) {
    return vectorLines(path).map(([lhs, rhs]) => {
        const p = pointOf(lhs);
        const e = 13 + 3 * (p.mips + 1);
        assert.equal(lhs.length, e + p.mips, `input fields of: ${lhs}`);
        assert.equal(rhs.length, 4, `output fields of: ${rhs}`);
        const tab = [];
        for (let m = 0; m <= p.mips; m++) tab.push(1000 + m, ...lhs.slice(13 + 3 * m, 16 + 3 * m));
        /* the read table's shares as the viewer uploads them (u_mipHeld) */
        const held = lhs.slice(e).map((h) => h / 32768);
        return { ...p, tail: lhs.slice(10, 13), tab, held, mss: rhs.slice(0, 3), v: rhs[3] };
    });
}

/* In the page: compiles the viewer's GLSL with a probe main(), draws one
 * pixel per point (with its mip table and tail_mss when it has them,
 * else zeros), returns the three render targets' floats. */
function runInPage({ common, cascade, frag, cases, maxc, mipe }) {
    const LEVELS = 12, W = 1 << (LEVELS - 1);
    const canvas = document.createElement('canvas');
    const gl = canvas.getContext('webgl2');
    if (!gl) return { error: 'no WebGL2 context' };
    if (!gl.getExtension('EXT_color_buffer_float')) return { error: 'no EXT_color_buffer_float' };
    const vs = '#version 300 es\nvoid main() { gl_Position = vec4(0.0, 0.0, 0.0, 1.0); gl_PointSize = 1.0; }\n';
    const fs = `${common}\n${cascade}\n${frag}
uniform int u_slot;
uniform vec2 u_rel;
uniform float u_floor;
layout(location = 0) out vec4 o_a;
layout(location = 1) out vec4 o_b;
layout(location = 2) out vec4 o_c;
void main() {
    float w;
    float s = wantSpacing(u_slot, u_rel, u_floor);
    casLod(u_slot, s, w);
    vec3 d = casDisp(u_rel, u_floor);
    vec2 slope;
    vec3 mss;
    float foam;
    seaSample(u_rel, u_floor, slope, mss, foam);
    o_a = vec4(s, w, d.x, d.y);
    o_b = vec4(d.z, slope.x, slope.y, foam);
    float lu = log2(s / u_cas[u_slot].y);
    o_c = vec4(mss, casBreakVar(u_slot, lu, casMss(u_slot, lu)));
}
`;
    const made = window.glProgram(gl, vs, fs);
    if (made.error) return { error: made.error };
    const prog = made.prog;
    const loc = (n) => gl.getUniformLocation(prog, n);
    /* textures as the renderer makes them; level m holds (1, m, m^2, 0) */
    const tex = (fmt, comps, value) => {
        const t = gl.createTexture();
        gl.bindTexture(gl.TEXTURE_2D, t);
        gl.texStorage2D(gl.TEXTURE_2D, LEVELS, fmt, W, 1);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR_MIPMAP_NEAREST);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.REPEAT);
        gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.REPEAT);
        for (let m = 0; m < LEVELS; m++) {
            const w = W >> m, data = new Float32Array(4 * w);
            for (let i = 0; i < w; i++) data.set(value(m), 4 * i);
            gl.texSubImage2D(gl.TEXTURE_2D, m, 0, 0, w, 1, comps, gl.FLOAT, comps === gl.RGBA ? data : data.filter((_, k) => k % 4 < 2));
        }
        return t;
    };
    const disp = tex(gl.RGBA16F, gl.RGBA, (m) => [1, m, m * m, 0]);
    const slope = tex(gl.RGBA16F, gl.RGBA, (m) => [1, m, 0, 0]);
    const zeroD = tex(gl.RGBA16F, gl.RGBA, () => [0, 0, 0, 0]);
    const zeroS = tex(gl.RGBA16F, gl.RGBA, () => [0, 0, 0, 0]);
    /* three float targets, one pixel per point */
    const fb = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    [0, 1, 2].forEach((k) => {
        const t = gl.createTexture();
        gl.bindTexture(gl.TEXTURE_2D, t);
        gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, cases.length, 1);
        gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0 + k, gl.TEXTURE_2D, t, 0);
    });
    gl.drawBuffers([gl.COLOR_ATTACHMENT0, gl.COLOR_ATTACHMENT1, gl.COLOR_ATTACHMENT2]);
    if (gl.checkFramebufferStatus(gl.FRAMEBUFFER) !== gl.FRAMEBUFFER_COMPLETE) return { error: 'float framebuffer incomplete' };
    const cam = [100.5, -250.25];   /* the block's camera xz relative to the eye */
    gl.uniform2f(loc('u_blkCam'), cam[0], cam[1]);
    gl.uniform2fv(loc('u_casEye'), new Float32Array(2 * maxc));
    gl.uniform1f(loc('u_roughScale'), 1);
    gl.uniform1f(loc('u_foamScale'), 1);
    for (let k = 0; k < maxc; k++) {
        gl.uniform1i(loc(`u_cd${k}`), k);
        gl.uniform1i(loc(`u_cs${k}`), maxc + k);
    }
    cases.forEach((p, i) => {
        const slot = i % maxc;
        const cas = new Float32Array(4 * maxc), casQ = new Float32Array(maxc).fill(1);
        for (let k = 0; k < slot; k++) cas.set([1, 1, 1, 0], 4 * k);
        cas.set([p.patch, p.patch / p.n, p.mips, p.fades], 4 * slot);
        casQ[slot] = p.q;
        /* the point's mip table in its slot's rows, zeros elsewhere */
        const tab = new Float32Array(4 * mipe * maxc);
        if (p.tab) tab.set(p.tab, 4 * mipe * slot);
        gl.uniform4fv(loc('u_mipTab'), tab);
        const held = new Float32Array(4 * Math.ceil(mipe * maxc / 4)).fill(1);
        if (p.held) held.set(p.held, mipe * slot);
        gl.uniform4fv(loc('u_mipHeld'), held);
        gl.uniform3fv(loc('u_tailMss'), p.tail || [0, 0, 0]);
        for (let k = 0; k < maxc; k++) {
            gl.activeTexture(gl.TEXTURE0 + k);
            gl.bindTexture(gl.TEXTURE_2D, k === slot ? disp : zeroD);
            gl.activeTexture(gl.TEXTURE0 + maxc + k);
            gl.bindTexture(gl.TEXTURE_2D, k === slot ? slope : zeroS);
        }
        gl.uniform1i(loc('u_nCas'), slot + 1);
        gl.uniform1i(loc('u_slot'), slot);
        gl.uniform4fv(loc('u_cas'), cas);
        gl.uniform1fv(loc('u_casQ'), casQ);
        gl.uniform3f(loc('u_blk'), p.q, p.minS, p.camY);
        gl.uniform2f(loc('u_rel'), cam[0] + p.dx, cam[1] + p.dz);
        gl.uniform1f(loc('u_floor'), p.floorS);
        gl.viewport(i, 0, 1, 1);
        gl.drawArrays(gl.POINTS, 0, 1);
    });
    const out = [];
    for (let k = 0; k < 3; k++) {
        gl.readBuffer(gl.COLOR_ATTACHMENT0 + k);
        const px = new Float32Array(4 * cases.length);
        gl.readPixels(0, 0, cases.length, 1, gl.RGBA, gl.FLOAT, px);
        out.push(Array.from(px));
    }
    const err = gl.getError();
    return err ? { error: `GL error 0x${err.toString(16)}` } : { a: out[0], b: out[1], c: out[2] };
}

/* runInPage's render targets for these points. */
async function probe(cases) {
    const r = await probeRun(runInPage, {
        common: COMMON, cascade: CASCADE_GLSL, frag: CASCADE_FRAG_GLSL, cases, maxc: MAX_CASCADES, mipe: MIP_ENTRIES,
    });
    assert.equal(r.error, undefined, r.error);
    return r;
}

/* Checks every point's [what, got, want, tolerance] (checksOf(point, i)),
 * reports the largest difference of each as a fraction of its tolerance
 * and fails listing the first ten disagreements. */
function compare(t, cases, checksOf) {
    const bad = [], worst = {};
    cases.forEach((p, i) => {
        for (const [what, got, want, tol] of checksOf(p, i)) {
            worst[what] = Math.max(worst[what] || 0, Math.abs(got - want) / (tol || 1));
            if (!(Math.abs(got - want) <= tol))
                bad.push(`point ${i} (q ${p.q}, y ${p.camY}, d ${p.dx},${p.dz}, floor ${p.minS}/${p.floorS}, ` +
                    `patch ${p.patch}/${p.n}, mips ${p.mips}, fades ${p.fades}; slot ${i % MAX_CASCADES}): ${what} ${got}, C rule ${want}`);
        }
    });
    t.diagnostic(`${cases.length} points; largest difference as a fraction of its tolerance: ` +
        Object.entries(worst).map(([k, v]) => `${k} ${v.toPrecision(2)}`).join(', '));
    assert.deepEqual(bad.slice(0, 10), [], `${bad.length} disagreements`);
}

test('the viewer\'s GLSL reads the mips protocol/lod.c reads, with the same weights and fade (tests/vectors/lod.txt)', async (t) => {
    const vdir = process.env.PROTO_VECTORS;
    if (!vdir) { t.skip('PROTO_VECTORS not set'); return; }
    const cases = readVectors(join(vdir, 'lod.txt'));
    assert.ok(cases.length >= 100, `${cases.length} points in lod.txt`);
    /* every branch of the rule is among the points */
    assert.ok(cases.some((p) => p.lambda <= 0) && cases.some((p) => p.lambda > 0 && p.lambda < p.mips - 1) &&
        cases.some((p) => p.fades && p.fade > 0 && p.fade < 1) && cases.some((p) => p.fades && p.fade === 0) &&
        cases.some((p) => !p.fades && p.lambda > p.mips), 'the vectors cover every branch');
    const r = await probe(cases);
    compare(t, cases, (p, i) => {
        const [s, w, d0, d1] = r.a.slice(4 * i, 4 * i + 4);
        const [d2, s0, s1, foam] = r.b.slice(4 * i, 4 * i + 4);
        return [
            ['s', s, p.s, 2e-6 * p.s],
            ['fade', w, p.fade, 1e-4],
            ['casDisp sum w', d0, p.sum, 2e-4],
            ['casDisp sum w m', d1, p.sumM, 1e-3],
            ['casDisp sum w m^2', d2, p.sumM2, 5e-3],
            ['seaSample sum w', s0, p.sum, 2e-4],
            ['seaSample sum w m', s1, p.sumM, 1e-3],
            ['seaSample foam', foam, 0, 0],
        ];
    });
});

test('the viewer\'s GLSL adds the unresolved slope moments protocol/lod.c adds (tests/vectors/lod_mss.txt)', async (t) => {
    const vdir = process.env.PROTO_VECTORS;
    if (!vdir) { t.skip('PROTO_VECTORS not set'); return; }
    const cases = readMssVectors(join(vdir, 'lod_mss.txt'));
    const lod = readVectors(join(vdir, 'lod.txt'));
    /* lod.txt's points, whose readings say which branch each is on */
    assert.equal(cases.length, lod.length, 'lod_mss.txt has lod.txt\'s points');
    const inputs = (p) => [p.q, p.minS, p.camY, p.dx, p.dz, p.floorS, p.patch, p.n, p.mips, p.fades];
    cases.forEach((p, i) => assert.deepEqual(inputs(p), inputs(lod[i]), `point ${i}`));
    assert.ok(lod.some((p) => p.lambda <= 0) && lod.some((p) => p.sum && p.lambda % 1 > 0.1 && p.lambda < p.mips - 1) &&
        lod.some((p) => p.fades && p.fade > 0.1 && p.fade < 0.9) && lod.some((p) => p.fades && p.fade === 0) &&
        lod.some((p) => !p.fades && p.lambda > p.mips), 'the vectors cover every branch, mid-blend and mid-fade');
    const r = await probe(cases);
    compare(t, cases, (p, i) => {
        const got = r.c.slice(4 * i, 4 * i + 3);
        /* binary32 rounding of the largest term the sum adds */
        return ['x', 'z', 'xz'].map((k, j) => {
            let scale = Math.abs(p.tail[j]);
            for (let m = 0; m <= p.mips; m++) scale = Math.max(scale, Math.abs(p.tab[4 * m + 1 + j]));
            return [`mss_${k}`, got[j], p.mss[j], 1e-6 * scale];
        }).concat([['breaking var', r.c[4 * i + 3], p.v, 1e-6 * (p.tab[4 * p.mips + 1] + p.tab[4 * p.mips + 2])]]);
    });
});

/* lod_foam.txt: a whitecap table, the variance held, beta, q, "->", foam. */
function readFoamVectors(path) {
    return vectorLines(path).map(([lhs, rhs]) => {
        const rows = lhs[0];
        assert.equal(lhs.length, 1 + 3 * rows + 3, `input fields of: ${lhs}`);
        assert.equal(rhs.length, 1, `output fields of: ${rhs}`);
        return { table: lhs.slice(1, 1 + 3 * rows), rows, v: lhs[1 + 3 * rows], beta: lhs[2 + 3 * rows], q: lhs[3 + 3 * rows], foam: rhs[0] };
    });
}

/* In the page: foamAt of every case, one pixel each. */
function runFoamInPage({ common, cascade, cases, rowsMax }) {
    const canvas = document.createElement('canvas');
    const gl = canvas.getContext('webgl2');
    if (!gl || !gl.getExtension('EXT_color_buffer_float')) return { error: 'no WebGL2 float targets' };
    const vs = '#version 300 es\nvoid main() { gl_Position = vec4(0.0, 0.0, 0.0, 1.0); gl_PointSize = 1.0; }\n';
    const fs = `${common}\n${cascade}
uniform vec3 u_in;
out vec4 o;
void main() { o = vec4(foamAt(u_in.x, u_in.y, u_in.z), 0.0, 0.0, 1.0); }
`;
    const made = window.glProgram(gl, vs, fs);
    if (made.error) return { error: made.error };
    const prog = made.prog;
    const loc = (n) => gl.getUniformLocation(prog, n);
    const rowError = window.glRow(gl, cases.length);
    if (rowError) return { error: rowError };
    cases.forEach((c, i) => {
        const tab = new Float32Array(3 * rowsMax);
        tab.set(c.table);
        gl.uniform3fv(loc('u_foamTab'), tab);
        gl.uniform1i(loc('u_foamRows'), c.rows);
        gl.uniform3f(loc('u_in'), c.beta, c.q, c.v);
        gl.viewport(i, 0, 1, 1);
        gl.drawArrays(gl.POINTS, 0, 1);
    });
    const px = new Float32Array(4 * cases.length);
    gl.readPixels(0, 0, cases.length, 1, gl.RGBA, gl.FLOAT, px);
    const err = gl.getError();
    return err ? { error: `GL error 0x${err.toString(16)}` } : { foam: Array.from(px).filter((_, k) => k % 4 === 0) };
}

test('the viewer\'s GLSL turns the breaking index into the foam protocol/lod.c gives (tests/vectors/lod_foam.txt)', async (t) => {
    const vdir = process.env.PROTO_VECTORS;
    if (!vdir) { t.skip('PROTO_VECTORS not set'); return; }
    const cases = readFoamVectors(join(vdir, 'lod_foam.txt'));
    assert.ok(cases.length >= 100, `${cases.length} points in lod_foam.txt`);
    /* on a ramp or a trail, clamped at 0 and at 1: every branch */
    assert.ok(cases.some((c) => c.foam === 0) && cases.some((c) => c.foam === 1) &&
        cases.filter((c) => c.foam > 0.05 && c.foam < 0.95).length >= 30, 'the vectors cover every branch');
    const r = await probeRun(runFoamInPage, { common: COMMON, cascade: CASCADE_GLSL, cases, rowsMax: FOAM_ROWS });
    assert.equal(r.error, undefined, r.error);
    const bad = [];
    let worst = 0;
    cases.forEach((c, i) => {
        const d = Math.abs(r.foam[i] - c.foam);
        worst = Math.max(worst, d);
        /* binary32 arithmetic; C's fade is a minimax polynomial within 2e-5 */
        if (!(d <= 1e-4)) bad.push(`case ${i} (rows ${c.rows}, var ${c.v}, beta ${c.beta}, q ${c.q}): ${r.foam[i]}, C rule ${c.foam}`);
    });
    t.diagnostic(`${cases.length} points; largest difference ${worst.toPrecision(2)}`);
    assert.deepEqual(bad.slice(0, 10), [], `${bad.length} disagreements`);
});

/* In the page: the shading path's reading of mip 0 (casReadShade at level
 * 0) and the vertex path's (casRead, GL's bilinear filter) of a random
 * n x n periodic texture at each case's point, one pixel each. */
function runMip0InPage({ common, cascade, frag, grid, n, points, maxc }) {
    const canvas = document.createElement('canvas');
    const gl = canvas.getContext('webgl2');
    if (!gl || !gl.getExtension('EXT_color_buffer_float')) return { error: 'no WebGL2 float targets' };
    const vs = '#version 300 es\nvoid main() { gl_Position = vec4(0.0, 0.0, 0.0, 1.0); gl_PointSize = 1.0; }\n';
    const fs = `${common}\n${cascade}\n${frag}
uniform vec2 u_rel;
out vec4 o;
void main() { o = vec4(casReadShade(u_cs0, 0, u_rel, 0.0).x, casRead(u_cs0, 0, u_rel, 0.0).x, 0.0, 1.0); }
`;
    const made = window.glProgram(gl, vs, fs);
    if (made.error) return { error: made.error };
    const prog = made.prog;
    const loc = (name) => gl.getUniformLocation(prog, name);
    const tex = gl.createTexture();
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, tex);
    gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA16F, n, n);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.REPEAT);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.REPEAT);
    const data = new Float32Array(4 * n * n);
    grid.forEach((v, k) => { data[4 * k] = v; });
    gl.texSubImage2D(gl.TEXTURE_2D, 0, 0, 0, n, n, gl.RGBA, gl.FLOAT, data);
    const rowError = window.glRow(gl, points.length);
    if (rowError) return { error: rowError };
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, tex);
    gl.uniform1i(loc('u_cs0'), 0);
    const cas = new Float32Array(4 * maxc);
    cas.set([n, 1, 1, 0]);   /* patch n m, spacing 1 m, one mip */
    gl.uniform4fv(loc('u_cas'), cas);
    gl.uniform2fv(loc('u_casEye'), new Float32Array(2 * maxc));
    points.forEach(([x, z], i) => {
        gl.uniform2f(loc('u_rel'), x, z);
        gl.viewport(i, 0, 1, 1);
        gl.drawArrays(gl.POINTS, 0, 1);
    });
    const px = new Float32Array(4 * points.length);
    gl.readPixels(0, 0, points.length, 1, gl.RGBA, gl.FLOAT, px);
    const err = gl.getError();
    return err ? { error: `GL error 0x${err.toString(16)}` }
        : { keys: Array.from(px).filter((_, k) => k % 4 === 0), linear: Array.from(px).filter((_, k) => k % 4 === 1) };
}

/* Keys (1981) cubic convolution kernel, a = -1/2. */
function keysKernel(x) {
    const t = Math.abs(x);
    if (t < 1) return 1.5 * t ** 3 - 2.5 * t * t + 1;
    if (t < 2) return -0.5 * t ** 3 + 2.5 * t * t - 4 * t + 2;
    return 0;
}

/* Mip 0 holds waves up to its Nyquist, where GL's bilinear filter keeps
 * (2 + cos th) / 3 of a wave's power per axis: read that way, the slopes
 * lost 13 % of their variance and the breaking index 19 %, and the viewer
 * drew 0.43 of the exact sea's whitecaps near the eye (ship-bridge, 5 m).
 * The shading reads mip 0 by Keys' cubic convolution, as the C library
 * reads every mip: its reading of a random periodic texture equals the
 * kernel's sum at every point (within half floats' precision), and differs
 * from the bilinear one's. */
test('the shading reads mip 0 by Keys\' cubic convolution, as the C library does', async (t) => {
    const n = 16;
    let seed = 12345;
    const rnd = () => ((seed = (seed * 1103515245 + 12345) >>> 0) / 4294967296);
    const grid = Array.from({ length: n * n }, () => Math.round((2 * rnd() - 1) * 1024) / 1024);
    const points = Array.from({ length: 96 }, (_, i) => i < 8 ? [3 + i, 5] : [-40 + 80 * rnd(), -40 + 80 * rnd()]);
    const r = await probeRun(runMip0InPage, {
        common: COMMON, cascade: CASCADE_GLSL, frag: CASCADE_FRAG_GLSL, grid, n, points, maxc: MAX_CASCADES,
    });
    assert.equal(r.error, undefined, r.error);
    const at = (i, j) => grid[(((i % n) + n) % n) * n + (((j % n) + n) % n)];
    let worst = 0, apart = 0;
    const bad = [];
    points.forEach(([x, z], k) => {
        const j0 = Math.floor(x), i0 = Math.floor(z);
        let want = 0;
        for (let di = -1; di <= 2; di++)
            for (let dj = -1; dj <= 2; dj++) want += keysKernel(z - (i0 + di)) * keysKernel(x - (j0 + dj)) * at(i0 + di, j0 + dj);
        const d = Math.abs(r.keys[k] - want);
        worst = Math.max(worst, d);
        apart = Math.max(apart, Math.abs(r.linear[k] - want));
        if (!(d <= 4e-3)) bad.push(`(${x.toFixed(3)}, ${z.toFixed(3)}): ${r.keys[k]}, Keys ${want}`);
    });
    t.diagnostic(`${points.length} points; largest difference from Keys ${worst.toPrecision(2)}, the bilinear reading's ${apart.toPrecision(2)}`);
    assert.deepEqual(bad.slice(0, 10), [], `${bad.length} points off Keys' reading`);
    assert.ok(apart > 0.05, 'the bilinear reading differs from Keys\' (the test can tell them apart)');
});
