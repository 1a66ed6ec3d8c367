/*
 * rate.js - bytes per second over the last second, as the viewer's stats
 * panel shows it.  The rate counts what arrived in the half-open window
 * (now - 1 s, now] and divides by the window's length: at 30 frames a
 * second of B bytes each that is 30 B, not 30 B over the 29 intervals
 * between the first and last frame of the window (a fencepost that read
 * a steady 3.9 MB/s stream as 4.03).  Until a second has passed since the
 * first message, the window is the time since that message, and the
 * first message itself opens it rather than counting in it.
 */

export class ByteRate {
    /* windowMs: the window's length; minMs: the shortest window a rate is
     * formed over (a rate over a few milliseconds says nothing). */
    constructor(windowMs = 1000, minMs = 250) {
        this.windowMs = windowMs;
        this.minMs = minMs;
        this.events = [];   /* [time ms, bytes], oldest first */
        this.start = null;  /* time of the first message */
    }

    /* One message of `bytes` bytes received at `now` (ms, non-decreasing). */
    add(now, bytes) {
        if (!Number.isFinite(now) || !Number.isFinite(bytes) || bytes < 0) return;
        if (this.start === null) this.start = now;
        this.events.push([now, bytes]);
        this.trim(now);
    }

    trim(now) {
        const e = this.events;
        let i = 0;
        while (i < e.length && e[i][0] <= now - this.windowMs) i++;
        if (i) e.splice(0, i);
    }

    /* Bytes per second at `now`; 0 before any message. */
    perSecond(now) {
        if (this.start === null) return 0;
        this.trim(now);
        const span = Math.min(this.windowMs, now - this.start);
        let s = 0;
        for (const [t, b] of this.events)
            if (span >= this.windowMs || t > this.start) s += b;
        return s * 1000 / Math.max(this.minMs, span);
    }
}
