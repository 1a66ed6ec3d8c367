/*
 * timeline.js - the sea-state timeline as a client keeps it (PROTOCOL.md
 * "Sea-state timeline"): the HELLO's sea holds from the start, each SEA_STATE
 * announce from its effective_time, and a later announce with the same
 * effective_time replaces the earlier.  Announces arrive ahead of their
 * time (a change scheduled seconds ahead, the pending changes behind HELLO),
 * so what is drawn is the state in force at the frame's sim time, never
 * simply the last announce received.
 */

export class SeaTimeline {
    /* max: entries kept; the protocol announces at most 16 pending changes
     * at once, so 64 leaves room for the ones in force. */
    constructor(max = 64) {
        this.entries = [];
        this.max = max;
    }

    /* Enters sea from effectiveTime on (-Infinity: from the start). */
    add(effectiveTime, sea) {
        if (typeof effectiveTime !== 'number' || Number.isNaN(effectiveTime)) return;
        const e = this.entries;
        let i = e.length;
        while (i > 0 && e[i - 1].t > effectiveTime) i--;
        if (i > 0 && e[i - 1].t === effectiveTime) e[i - 1].sea = sea;
        else e.splice(i, 0, { t: effectiveTime, sea });
        /* the oldest entries go first: a client that never draws them
         * again needs only the one in force and those after it */
        while (e.length > this.max) e.shift();
    }

    /* The state in force at sim time t (the first entry if t precedes
     * them all), or null when nothing was entered. */
    at(t) {
        const e = this.entries;
        if (!e.length) return null;
        let lo = 0, hi = e.length - 1;
        if (!(t >= e[0].t)) return e[0].sea;
        while (lo < hi) {
            const mid = (lo + hi + 1) >> 1;
            if (e[mid].t <= t) lo = mid; else hi = mid - 1;
        }
        return e[lo].sea;
    }

    /* Drops the entries superseded before t (keeps the one in force). */
    prune(t) {
        const e = this.entries;
        let k = 0;
        while (k + 1 < e.length && e[k + 1].t <= t) k++;
        if (k > 0) e.splice(0, k);
    }
}
