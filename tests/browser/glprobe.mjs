/*
 * glprobe.mjs - what the shader tests (lod.test.mjs, foam.test.mjs) run in
 * the page before their probe: glProgram(gl, vs, fs) compiles and links a
 * WebGL2 program, {prog} or {error: "compile: ..." | "link: ..."}.
 * installGlProbe(page) defines it as window.glProgram (page.evaluate's
 * function cannot reach the test module's own).
 */
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

export async function installGlProbe(page) {
    await page.addScriptTag({ content: `window.glProgram = ${glProgram.toString()};` });
}
