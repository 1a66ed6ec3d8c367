/*
 * camera.js - the fly camera: world position in double, yaw/pitch/roll in
 * the protocol's convention (PROTOCOL.md "Camera orientation", the same as
 * sim/mesh.c: yaw from +x toward +z, pitch positive up, roll clockwise as
 * seen by the viewer, y up), WASD/QE + mouse-look controls with an
 * adjustable speed, and the velocity the CAMERA report carries (measured
 * from the actual motion, so the server's cutoff follows what the viewer
 * really does).
 */

const D2R = Math.PI / 180;

/* Forward, right and up unit vectors, exactly as mesh_camera_basis. */
export function cameraBasis(yawDeg, pitchDeg, rollDeg) {
    const y = yawDeg * D2R, p = pitchDeg * D2R, ro = rollDeg * D2R;
    const f = [Math.cos(p) * Math.cos(y), Math.sin(p), Math.cos(p) * Math.sin(y)];
    let r0 = [-f[2], 0, f[0]];
    let rn = Math.hypot(r0[0], r0[2]);
    if (rn < 1e-12) { r0 = [-Math.sin(y), 0, Math.cos(y)]; rn = 1; }
    r0 = [r0[0] / rn, 0, r0[2] / rn];
    const u0 = [r0[1] * f[2] - r0[2] * f[1], r0[2] * f[0] - r0[0] * f[2], r0[0] * f[1] - r0[1] * f[0]];
    const cr = Math.cos(ro), sr = Math.sin(ro);
    const right = [0, 1, 2].map((i) => cr * r0[i] - sr * u0[i]);
    const up = [0, 1, 2].map((i) => sr * r0[i] + cr * u0[i]);
    return { fwd: f, right, up };
}

export class FlyCamera {
    constructor(opts = {}) {
        this.pos = [opts.x ?? 0, opts.y ?? 25, opts.z ?? 0];
        this.yawDeg = opts.yaw ?? 30;
        this.pitchDeg = opts.pitch ?? -8;
        this.rollDeg = 0;
        this.fovYDeg = opts.fov ?? 60;
        this.speed = opts.speed ?? 10;          /* m/s */
        this.vel = [opts.vx ?? 0, opts.vy ?? 0, opts.vz ?? 0]; /* scripted constant velocity (tests, demos) */
        this.measuredVel = [0, 0, 0];
        this.keys = new Set();
        this.dragging = false;
        this.lastPos = this.pos.slice();
        this.floorY = 0.5;                      /* lowest eye height (main.js lifts it above the sea under the camera) */
    }

    get basis() { return cameraBasis(this.yawDeg, this.pitchDeg, this.rollDeg); }

    attach(el) {
        const down = (e) => {
            if (e.target && (e.target.tagName === 'INPUT' || e.target.tagName === 'SELECT')) return;
            this.keys.add(e.code);
            if (e.code === 'Equal' || e.code === 'NumpadAdd') this.speed = Math.min(this.speed * 2, 5000);
            if (e.code === 'Minus' || e.code === 'NumpadSubtract') this.speed = Math.max(this.speed / 2, 0.5);
            if (['KeyW', 'KeyA', 'KeyS', 'KeyD', 'KeyQ', 'KeyE', 'Space', 'ArrowUp', 'ArrowDown', 'ArrowLeft', 'ArrowRight'].includes(e.code))
                e.preventDefault();
        };
        window.addEventListener('keydown', down);
        window.addEventListener('keyup', (e) => this.keys.delete(e.code));
        window.addEventListener('blur', () => this.keys.clear());
        el.addEventListener('mousedown', (e) => {
            this.dragging = true;
            if (el.requestPointerLock && e.button === 0 && e.shiftKey) el.requestPointerLock();
        });
        window.addEventListener('mouseup', () => { this.dragging = false; });
        window.addEventListener('mousemove', (e) => {
            if (!this.dragging && document.pointerLockElement !== el) return;
            this.yawDeg = wrapDeg(this.yawDeg + e.movementX * 0.15);
            this.pitchDeg = Math.max(-89, Math.min(89, this.pitchDeg - e.movementY * 0.15));
        });
        el.addEventListener('wheel', (e) => {
            e.preventDefault();
            this.speed = Math.max(0.5, Math.min(5000, this.speed * (e.deltaY < 0 ? 1.25 : 0.8)));
        }, { passive: false });
    }

    /* Advances by dt seconds; returns the distance moved. */
    update(dt) {
        const k = this.keys;
        const { fwd, right } = this.basis;
        let mx = 0, my = 0, mz = 0;
        const boost = k.has('ShiftLeft') || k.has('ShiftRight') ? 4 : 1;
        const sp = this.speed * boost;
        const add = (v, s) => { mx += v[0] * s; my += v[1] * s; mz += v[2] * s; };
        if (k.has('KeyW') || k.has('ArrowUp')) add(fwd, sp);
        if (k.has('KeyS') || k.has('ArrowDown')) add(fwd, -sp);
        if (k.has('KeyD')) add(right, sp);
        if (k.has('KeyA')) add(right, -sp);
        if (k.has('KeyE') || k.has('Space')) my += sp;
        if (k.has('KeyQ')) my -= sp;
        if (k.has('ArrowLeft')) this.yawDeg = wrapDeg(this.yawDeg - 60 * dt);
        if (k.has('ArrowRight')) this.yawDeg = wrapDeg(this.yawDeg + 60 * dt);
        mx += this.vel[0]; my += this.vel[1]; mz += this.vel[2];
        this.lastPos = this.pos.slice();
        this.pos[0] += mx * dt;
        this.pos[1] = Math.max(this.floorY, Math.min(20000, this.pos[1] + my * dt));
        this.pos[2] += mz * dt;
        if (dt > 0) {
            /* smoothed measured velocity (what the server's cutoff policy sees) */
            const a = Math.min(1, dt * 8);
            for (let i = 0; i < 3; i++) {
                const v = (this.pos[i] - this.lastPos[i]) / dt;
                this.measuredVel[i] += a * (v - this.measuredVel[i]);
                if (Math.abs(this.measuredVel[i]) < 1e-4) this.measuredVel[i] = 0;
            }
        }
    }

    report(viewportW, viewportH) {
        return {
            pos: this.pos.slice(), vel: this.measuredVel.slice(), yawDeg: this.yawDeg, pitchDeg: this.pitchDeg,
            rollDeg: this.rollDeg, fovYDeg: this.fovYDeg,
            viewportW: Math.max(1, Math.min(16384, viewportW | 0)), viewportH: Math.max(1, Math.min(16384, viewportH | 0)),
            renderTime: 0,
        };
    }
}

function wrapDeg(a) {
    a = ((a + 180) % 360 + 360) % 360 - 180;
    return a;
}
