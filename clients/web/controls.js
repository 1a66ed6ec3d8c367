/*
 * controls.js - the viewer's controls panel: field of view, the sun's
 * position, and (with the daemon's admin token) the sea state: wind speed
 * and direction, set at once or ramped over a chosen time as a series of
 * SEA_STATE sets at increasing effective times (the sea-state timeline
 * schedules them; PROTOCOL.md "Sea-state timeline").  The daemon answers
 * each set by its announce (the page's timeline applies it at its time) or
 * an ERROR (shown on the overlay), and logs who made each change.
 *
 * The sun is (azimuth from +x toward +z, elevation) in degrees; sunFromDeg
 * and sunDefaultDeg are the conventions `ocean-sim render --sun` shares.
 */
const D2R = Math.PI / 180;

/* Unit vector toward the sun. */
export function sunFromDeg(azDeg, elDeg) {
    const a = azDeg * D2R, e = elDeg * D2R;
    return [Math.cos(e) * Math.cos(a), Math.sin(e), Math.cos(e) * Math.sin(a)];
}

/* The default sun of a sea whose wind blows toward windDirDeg: low over
 * the downwind side, 0.5 rad off the wind, 17.7 deg up (glitter on the
 * waves' faces). */
export function sunDefaultDeg(windDirDeg) {
    return [windDirDeg + 0.5 / D2R, Math.atan(0.32) / D2R];
}

/* Most sets a ramp sends: the daemon takes 4 a second after a burst of 20. */
const RAMP_STEPS_MAX = 10;

/* The sets of a ramp from sea `from` to wind (u, dir) over `seconds`,
 * starting at sim time t0: [{t, sea}], the last at t0 + seconds exactly. */
export function seaRamp(from, u, dir, seconds, t0) {
    const n = seconds > 0 ? Math.min(RAMP_STEPS_MAX, Math.max(1, Math.round(seconds / 2))) : 1;
    /* the direction turns the short way round */
    const turn = ((dir - from.windDirDeg) % 360 + 540) % 360 - 180;
    const out = [];
    for (let k = 1; k <= n; k++) {
        const f = k / n;
        out.push({
            t: t0 + f * Math.max(seconds, 0),
            sea: { ...from, windU10: from.windU10 + f * (u - from.windU10), windDirDeg: from.windDirDeg + f * turn, hs: 0, tp: 0 },
        });
    }
    /* |direction| stays within the protocol's [-360, 360] */
    for (const s of out) s.sea.windDirDeg = ((s.sea.windDirDeg % 360) + 360) % 360;
    return out;
}

/* Wires the panel's inputs (index.html #help) to the viewer.  ctx:
 * {renderer, cam, worker, stats, simNow() -> the sim time shown,
 * sunFixed (a sun the URL gave)}. */
export function setupControls(ctx) {
    const $ = (id) => document.getElementById(id);
    const fov = $('ctl-fov'), az = $('ctl-sun-az'), el = $('ctl-sun-el');
    const show = () => {
        $('ctl-fov-v').textContent = `${Number(fov.value).toFixed(0)}°`;
        $('ctl-sun-v').textContent = `${Number(az.value).toFixed(0)}°, ${Number(el.value).toFixed(0)}°`;
    };
    fov.value = ctx.cam.fovYDeg;
    fov.addEventListener('input', () => { ctx.cam.fovYDeg = Number(fov.value); show(); });
    const sun = () => {
        ctx.renderer.sunDir = sunFromDeg(Number(az.value), Number(el.value));
        ctx.sunFixed = true;
        show();
    };
    az.addEventListener('input', sun);
    el.addEventListener('input', sun);
    /* the page's sun, once the HELLO (or the URL) has set it */
    ctx.showSun = ([a, e]) => { az.value = ((a % 360) + 360) % 360; el.value = e; show(); };
    $('ctl-sea-apply').addEventListener('click', () => {
        const sea = ctx.stats.sea, token = $('ctl-token').value;
        const u = Number($('ctl-wind').value), dir = Number($('ctl-dir').value), secs = Number($('ctl-ramp').value);
        if (!sea) { $('ctl-sea-msg').textContent = 'no sea yet (not connected)'; return; }
        if (!token) { $('ctl-sea-msg').textContent = 'the admin token is needed'; return; }
        if (!(u >= 0 && u <= 100) || !Number.isFinite(dir) || !(secs >= 0 && secs <= 3600)) {
            $('ctl-sea-msg').textContent = 'wind 0-100 m/s, a direction in degrees, a ramp of 0-3600 s';
            return;
        }
        const steps = seaRamp(sea, u, dir, secs, ctx.simNow());
        for (const s of steps) ctx.worker.postMessage({ cmd: 'sea', t: s.t, sea: s.sea, token });
        $('ctl-sea-msg').textContent = `${steps.length} change${steps.length > 1 ? 's' : ''} sent` +
            (secs > 0 ? `, over ${secs} s` : '');
        ctx.stats.seaSetsSent = (ctx.stats.seaSetsSent || 0) + steps.length;
    });
    show();
}
