/*
 * lod.test.mjs - the viewer's shader code for "Where each mip is read"
 * (PROTOCOL.md) against the points protocol/lod.c computes
 * (tests/vectors/lod.txt, written and checked by test_proto).
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
 * Tolerances are binary32's (the GPU's floats; the vectors are doubles)
 * and the shader's skip of a second read whose weight is under 1e-4.
 *
 * Run by tests/test_browser.sh with PROTO_VECTORS=tests/vectors
 * (CHROMIUM: the browser, default /usr/bin/chromium).  node --test.
 */
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { createRequire } from 'node:module';
import { readFileSync, mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

import { COMMON, CASCADE_GLSL, CASCADE_FRAG_GLSL, MAX_CASCADES } from '../../clients/web/render.js';

const require = createRequire(new URL('./package.json', import.meta.url));
const { chromium } = require('playwright-core');

/* One point a line: inputs, "->", the C rule's reading (see the file's head). */
function readVectors(path) {
    const cases = [];
    for (const line of readFileSync(path, 'utf8').split('\n')) {
        if (!line.trim() || line.startsWith('#')) continue;
        const [lhs, rhs] = line.split('->').map((h) => h.trim().split(/\s+/).map(Number));
        assert.equal(lhs.length, 10, `input fields of: ${line}`);
        assert.equal(rhs.length, 7, `output fields of: ${line}`);
        const [q, minS, camY, dx, dz, floorS, patch, n, mips, fades] = lhs;
        const [s, lambda, mip0, w0, mip1, w1, fade] = rhs;
        const read = [[mip0, w0], [mip1, w1]].filter(([m]) => m >= 0);
        cases.push({
            q, minS, camY, dx, dz, floorS, patch, n, mips, fades, s, lambda, fade,
            sum: read.reduce((a, [, w]) => a + w, 0),
            sumM: read.reduce((a, [m, w]) => a + w * m, 0),
            sumM2: read.reduce((a, [m, w]) => a + w * m * m, 0),
        });
    }
    return cases;
}

/* In the page: compiles the viewer's GLSL with a probe main(), draws one
 * pixel per point, returns the two render targets' floats. */
function runInPage({ common, cascade, frag, cases, maxc }) {
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
void main() {
    float w;
    float s = wantSpacing(u_slot, u_rel, u_floor);
    casLod(u_slot, s, w);
    vec4 d = casDisp(u_rel, u_floor);
    vec2 slope;
    vec3 mss;
    float foam;
    seaSample(u_rel, u_floor, slope, mss, foam);
    o_a = vec4(s, w, d.x, d.y);
    o_b = vec4(d.z, slope.x, slope.y, foam);
}
`;
    const shader = (type, src) => {
        const sh = gl.createShader(type);
        gl.shaderSource(sh, src);
        gl.compileShader(sh);
        if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(sh));
        return sh;
    };
    const prog = gl.createProgram();
    try {
        gl.attachShader(prog, shader(gl.VERTEX_SHADER, vs));
        gl.attachShader(prog, shader(gl.FRAGMENT_SHADER, fs));
    } catch (e) {
        return { error: `compile: ${e.message}` };
    }
    gl.linkProgram(prog);
    if (!gl.getProgramParameter(prog, gl.LINK_STATUS)) return { error: `link: ${gl.getProgramInfoLog(prog)}` };
    gl.useProgram(prog);
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
    const slope = tex(gl.RG16F, gl.RG, (m) => [1, m, 0, 0]);
    const zeroD = tex(gl.RGBA16F, gl.RGBA, () => [0, 0, 0, 0]);
    const zeroS = tex(gl.RG16F, gl.RG, () => [0, 0, 0, 0]);
    /* two float targets, one pixel per point */
    const fb = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    const targets = [0, 1].map((k) => {
        const t = gl.createTexture();
        gl.bindTexture(gl.TEXTURE_2D, t);
        gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, cases.length, 1);
        gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0 + k, gl.TEXTURE_2D, t, 0);
        return t;
    });
    gl.drawBuffers([gl.COLOR_ATTACHMENT0, gl.COLOR_ATTACHMENT1]);
    if (gl.checkFramebufferStatus(gl.FRAMEBUFFER) !== gl.FRAMEBUFFER_COMPLETE) return { error: 'float framebuffer incomplete' };
    const cam = [100.5, -250.25];   /* the block's camera xz relative to the eye */
    gl.uniform2f(loc('u_blkCam'), cam[0], cam[1]);
    gl.uniform2fv(loc('u_casEye'), new Float32Array(2 * maxc));
    gl.uniform4fv(loc('u_mipTab'), new Float32Array(4 * 13 * maxc));
    gl.uniform3f(loc('u_tailMss'), 0, 0, 0);
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
    for (let k = 0; k < 2; k++) {
        gl.readBuffer(gl.COLOR_ATTACHMENT0 + k);
        const px = new Float32Array(4 * cases.length);
        gl.readPixels(0, 0, cases.length, 1, gl.RGBA, gl.FLOAT, px);
        out.push(Array.from(px));
    }
    const err = gl.getError();
    return err ? { error: `GL error 0x${err.toString(16)}` } : { a: out[0], b: out[1] };
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
    const userDataDir = mkdtempSync(join(tmpdir(), 'ocean-lod-'));
    let context;
    try {
        context = await chromium.launchPersistentContext(userDataDir, {
            executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
            headless: true,
            args: ['--headless=new', '--no-sandbox', '--disable-gpu', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
                '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'],
            timeout: 180000,
        });
        const page = context.pages()[0] || await context.newPage();
        const r = await page.evaluate(runInPage, {
            common: COMMON, cascade: CASCADE_GLSL, frag: CASCADE_FRAG_GLSL, cases, maxc: MAX_CASCADES,
        });
        assert.equal(r.error, undefined, r.error);
        const bad = [], worst = {};
        const near = (what, got, want, tol) => {
            worst[what] = Math.max(worst[what] || 0, Math.abs(got - want) / (tol || 1));
            return Math.abs(got - want) <= tol;
        };
        cases.forEach((p, i) => {
            const [s, w, d0, d1] = r.a.slice(4 * i, 4 * i + 4);
            const [d2, s0, s1, foam] = r.b.slice(4 * i, 4 * i + 4);
            const checks = [
                ['s', s, p.s, 2e-6 * p.s],
                ['fade', w, p.fade, 1e-4],
                ['casDisp sum w', d0, p.sum, 2e-4],
                ['casDisp sum w m', d1, p.sumM, 1e-3],
                ['casDisp sum w m^2', d2, p.sumM2, 5e-3],
                ['seaSample sum w', s0, p.sum, 2e-4],
                ['seaSample sum w m', s1, p.sumM, 1e-3],
                ['seaSample foam', foam, 0, 0],
            ];
            for (const [what, got, want, tol] of checks)
                if (!near(what, got, want, tol)) bad.push(`point ${i} (q ${p.q}, y ${p.camY}, d ${p.dx},${p.dz}, floor ${p.minS}/${p.floorS}, ` +
                    `patch ${p.patch}/${p.n}, mips ${p.mips}, fades ${p.fades}; slot ${i % MAX_CASCADES}): ${what} ${got}, C rule ${want}`);
        });
        t.diagnostic(`${cases.length} points; largest difference as a fraction of its tolerance: ` +
            Object.entries(worst).map(([k, v]) => `${k} ${v.toPrecision(2)}`).join(', '));
        assert.deepEqual(bad.slice(0, 10), [], `${bad.length} disagreements`);
    } finally {
        if (context) await context.close();
        rmSync(userDataDir, { recursive: true, force: true });
    }
});
