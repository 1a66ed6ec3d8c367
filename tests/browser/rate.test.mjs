// The viewer's byte rate (clients/web/rate.js): what arrived in the last
// second, over one second.  The old estimate divided a window's bytes by
// the time from its first message to now, one frame interval short, and
// read a steady 3.9 MB/s stream at 30 Hz as 4.03 MB/s.
import test from 'node:test';
import assert from 'node:assert/strict';
import { ByteRate } from '../../clients/web/rate.js';

/* n messages of `bytes` each at `hz`, from t0 (ms) */
function feed(r, n, hz, bytes, t0 = 0) {
    let t = t0;
    for (let i = 0; i < n; i++) {
        t = t0 + (i * 1000) / hz;
        r.add(t, bytes);
    }
    return t;
}

test('a steady stream reads at its rate, at any phase of the window', () => {
    const r = new ByteRate();
    const per = 3.9e6 / 30;
    const last = feed(r, 300, 30, per);
    /* at a message, between messages, and just before the next */
    for (const dt of [0, 10, 33]) {
        const got = r.perSecond(last + dt);
        assert.ok(Math.abs(got / 3.9e6 - 1) < 1e-9, `${got} at +${dt} ms`);
    }
});

test('the first second: the first message opens the window', () => {
    const r = new ByteRate();
    assert.equal(r.perSecond(0), 0);
    /* 10 messages of 1000 B at 20 Hz: 9 arrive after the first, over 450 ms */
    const last = feed(r, 10, 20, 1000);
    assert.equal(last, 450);
    assert.ok(Math.abs(r.perSecond(last) - 20000) < 1e-9);
    /* a window shorter than 250 ms is read as 250 ms */
    const s = new ByteRate();
    s.add(0, 500);
    s.add(100, 500);
    assert.equal(s.perSecond(100), 2000);
});

test('a burst leaves the window a second later; a quiet link reads 0', () => {
    const r = new ByteRate();
    feed(r, 30, 30, 1000);
    r.add(1500, 64000);                      /* a topology message */
    assert.ok(r.perSecond(1500) >= 64000);
    assert.equal(r.perSecond(2499), 64000);
    assert.equal(r.perSecond(2500), 0);      /* (1500, 2500]: nothing */
});

test('bad input is ignored', () => {
    const r = new ByteRate();
    r.add(NaN, 10);
    r.add(0, -5);
    r.add(0, Infinity);
    assert.equal(r.perSecond(0), 0);
    assert.equal(r.events.length, 0);
});
