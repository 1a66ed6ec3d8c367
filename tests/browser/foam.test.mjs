/*
 * foam.test.mjs - how the viewer draws whitecaps near the eye (render.js
 * foamBreakUp, in COMMON), run in headless Chromium's WebGL2 as the viewer
 * compiles it, over a 256 m x 256 m patch of sea 2 m a sample at a carried
 * coverage c, the wind blowing 30 deg from +x, with the viewer's own grain
 * texture (cloudTextureBytes):
 *   - the drawn foam keeps the coverage the tiles carry: its mean is c
 *     within 10 % (the white fraction of the area, which whitecap laws
 *     give, Monahan & O'Muircheartaigh 1980);
 *   - its luminance is continuous, not two-valued: at least 40 distinct
 *     levels of 256 and under 5 % of the samples at 0 or at its largest
 *     (thresholded patches put nearly every sample at one of two values);
 *   - it streaks along the wind: its autocorrelation at 6 m lag is larger
 *     along the wind than across it (wind-blown foam lies in streaks
 *     along the wind);
 *   - far away (5 km), where the grain would alias, c itself.
 * Run by tests/test_browser.sh (node --test).
 */
import { test } from 'node:test';
import assert from 'node:assert/strict';

import { COMMON, cloudTextureBytes } from '../../clients/web/render.js';

import { probeRun } from './glprobe.mjs';


const N = 128, STEP = 2;   /* samples a side, metres a sample */
const WIND_DEG = 30;

/* In the page: foamBreakUp at every sample of the patch, as floats. */
function runInPage({ common, cloud, n, step, wind, c, dist }) {
    const canvas = document.createElement('canvas');
    const gl = canvas.getContext('webgl2');
    if (!gl || !gl.getExtension('EXT_color_buffer_float')) return { error: 'no WebGL2 float targets' };
    const vs = '#version 300 es\nin vec2 a_p;\nvoid main() { gl_Position = vec4(a_p, 0.0, 1.0); }\n';
    const fs = `${common}
uniform float u_c, u_step, u_dist;
out vec4 o;
void main() {
    vec2 rel = (gl_FragCoord.xy - 0.5) * u_step;
    o = vec4(foamBreakUp(u_c, rel, u_dist), 0.0, 0.0, 1.0);
}`;
    const made = window.glProgram(gl, vs, fs);
    if (made.error) return { error: made.error };
    const prog = made.prog;
    const loc = (k) => gl.getUniformLocation(prog, k);
    const tex = gl.createTexture();
    gl.activeTexture(gl.TEXTURE2);
    gl.bindTexture(gl.TEXTURE_2D, tex);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
    const side = Math.sqrt(cloud.length);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.R8, side, side, 0, gl.RED, gl.UNSIGNED_BYTE, new Uint8Array(cloud));
    gl.generateMipmap(gl.TEXTURE_2D);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR_MIPMAP_LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.REPEAT);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.REPEAT);
    gl.uniform1i(loc('u_cloudTex'), 2);
    gl.uniform2f(loc('u_wind'), Math.cos(wind), Math.sin(wind));
    gl.uniform2f(loc('u_grainOff'), 0.3, 0.7);
    gl.uniform1f(loc('u_c'), c);
    gl.uniform1f(loc('u_step'), step);
    gl.uniform1f(loc('u_dist'), dist);
    const fb = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    gl.activeTexture(gl.TEXTURE0);   /* unit 2 keeps the grain */
    const t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, t);
    gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, n, n);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, t, 0);
    const buf = gl.createBuffer();
    gl.bindBuffer(gl.ARRAY_BUFFER, buf);
    gl.bufferData(gl.ARRAY_BUFFER, new Float32Array([-1, -1, 3, -1, -1, 3]), gl.STATIC_DRAW);
    const a = gl.getAttribLocation(prog, 'a_p');
    gl.enableVertexAttribArray(a);
    gl.vertexAttribPointer(a, 2, gl.FLOAT, false, 0, 0);
    gl.viewport(0, 0, n, n);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    const px = new Float32Array(4 * n * n);
    gl.readPixels(0, 0, n, n, gl.RGBA, gl.FLOAT, px);
    const err = gl.getError();
    return err ? { error: `GL error 0x${err.toString(16)}` } : { foam: Array.from(px.filter((_, i) => i % 4 === 0)) };
}

async function foamAt(c, dist) {
    const r = await probeRun(runInPage, {
        common: COMMON, cloud: Array.from(cloudTextureBytes()), n: N, step: STEP, wind: WIND_DEG * Math.PI / 180, c, dist,
    });
    assert.equal(r.error, undefined, r.error);
    return r.foam;
}

/* Correlation of the field with itself shifted by `lag` metres along unit (ux, uz). */
function autocorr(f, ux, uz, lag) {
    const mean = f.reduce((a, b) => a + b, 0) / f.length;
    const dx = Math.round(ux * lag / STEP), dz = Math.round(uz * lag / STEP);
    let num = 0, den = 0;
    for (let z = 0; z < N; z++)
        for (let x = 0; x < N; x++) {
            const a = f[z * N + x] - mean;
            den += a * a;
            const x2 = x + dx, z2 = z + dz;
            if (x2 >= 0 && x2 < N && z2 >= 0 && z2 < N) num += a * (f[z2 * N + x2] - mean);
        }
    return num / den;
}

test('whitecaps near the eye: coverage kept, continuous, streaked along the wind', async (t) => {
    for (const c of [0.05, 0.3]) {
        const f = await foamAt(c, 50);
        const mean = f.reduce((a, b) => a + b, 0) / f.length;
        const max = Math.max(...f);
        const levels = new Set(f.map((v) => Math.round(v / max * 255))).size;
        const ends = f.filter((v) => v <= 0 || v >= max * 0.999).length / f.length;
        const w = WIND_DEG * Math.PI / 180;
        const along = autocorr(f, Math.cos(w), Math.sin(w), 6), across = autocorr(f, -Math.sin(w), Math.cos(w), 6);
        t.diagnostic(`c ${c}: mean ${mean.toFixed(4)}, ${levels} levels, ${(100 * ends).toFixed(1)} % at 0 or max, ` +
            `autocorrelation at 6 m along the wind ${along.toFixed(3)}, across ${across.toFixed(3)}`);
        assert.ok(Math.abs(mean / c - 1) < 0.1, `mean ${mean} for coverage ${c}`);
        assert.ok(levels >= 40, `${levels} distinct levels`);
        assert.ok(ends < 0.05, `${ends} of the samples at 0 or at the largest value`);
        assert.ok(along > across + 0.1, `along ${along}, across ${across}`);
    }
    const far = await foamAt(0.2, 5000);
    assert.ok(far.every((v) => Math.abs(v - 0.2) < 1e-6), 'far away the coverage is drawn as it is');
});
