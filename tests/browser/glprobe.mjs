/*
 * glprobe.mjs - what the shader tests (lod.test.mjs, foam.test.mjs) share:
 * one headless Chromium (software GL, as tests/test_browser.sh runs the
 * viewer), launched on first use and closed after the tests, whose page
 * holds window.glProgram(gl, vs, fs): a compiled and linked WebGL2
 * program, {prog} or {error: "compile: ..." | "link: ..."}, and
 * window.glRow(gl, count): a bound framebuffer of one RGBA32F row of
 * `count` pixels (one a probed case), null or an error (page.evaluate's
 * function cannot reach the test module's own functions).
 *   const r = await probeRun(fn, args);   // page.evaluate(fn, args)
 */
import { after } from 'node:test';
import { createRequire } from 'node:module';
import { mkdtempSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';

const require = createRequire(new URL('./package.json', import.meta.url));
const { chromium } = require('playwright-core');

function glProgram(gl, vs, fs) {
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
    return { prog };
}

function glRow(gl, count) {
    const fb = gl.createFramebuffer(), t = gl.createTexture();
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    gl.bindTexture(gl.TEXTURE_2D, t);
    gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA32F, count, 1);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, t, 0);
    return gl.checkFramebufferStatus(gl.FRAMEBUFFER) === gl.FRAMEBUFFER_COMPLETE ? null : 'float framebuffer incomplete';
}

let browser = null, page = null;
const userDataDir = mkdtempSync(join(tmpdir(), 'ocean-glprobe-'));
after(async () => {
    if (browser) await browser.close();
    rmSync(userDataDir, { recursive: true, force: true });
});

export async function probeRun(fn, args) {
    if (!browser) {
        browser = await chromium.launchPersistentContext(userDataDir, {
            executablePath: process.env.CHROMIUM || '/usr/bin/chromium',
            headless: true,
            args: ['--headless=new', '--no-sandbox', '--disable-gpu', '--use-angle=swiftshader', '--enable-unsafe-swiftshader',
                '--disable-background-networking', '--disable-component-update', '--disable-sync', '--no-first-run'],
            timeout: 180000,
        });
        page = browser.pages()[0] || await browser.newPage();
        await page.addScriptTag({ content: `window.glProgram = ${glProgram.toString()}; window.glRow = ${glRow.toString()};` });
    }
    return page.evaluate(fn, args);
}
