// The viewer's sea-state timeline (clients/web/timeline.js) against the
// rules of PROTOCOL.md "Sea-state timeline": HELLO's sea from the start,
// each announce from its effective_time, same time -> the later replaces.
import test from 'node:test';
import assert from 'node:assert/strict';
import { SeaTimeline } from '../../clients/web/timeline.js';

test('an announce ahead of its time does not take effect early', () => {
    const tl = new SeaTimeline();
    tl.add(-Infinity, { wind: 10 });
    tl.add(105, { wind: 20 });             // scheduled 5 s ahead of t = 100
    assert.equal(tl.at(100).wind, 10);
    assert.equal(tl.at(104.999).wind, 10);
    assert.equal(tl.at(105).wind, 20);
    assert.equal(tl.at(1e6).wind, 20);
});

test('announces out of order, and a replacement at the same time', () => {
    const tl = new SeaTimeline();
    tl.add(-Infinity, { wind: 10 });
    tl.add(30, { wind: 30 });
    tl.add(20, { wind: 20 });              // arrives after the later change
    tl.add(30, { wind: 31 });              // same effective time: replaces
    assert.deepEqual([tl.at(19).wind, tl.at(20).wind, tl.at(29.5).wind, tl.at(30).wind], [10, 20, 20, 31]);
    assert.equal(tl.entries.length, 3);
});

test('prune keeps the state in force; bad times are ignored; bounded', () => {
    const tl = new SeaTimeline(4);
    assert.equal(tl.at(0), null);
    tl.add(-Infinity, { wind: 1 });
    tl.add(NaN, { wind: 99 });
    tl.add('5', { wind: 99 });
    assert.equal(tl.entries.length, 1);
    for (let i = 1; i <= 6; i++) tl.add(i * 10, { wind: i });
    assert.equal(tl.entries.length, 4);
    assert.equal(tl.at(60).wind, 6);
    tl.prune(45);
    assert.equal(tl.at(45).wind, 4);
    assert.equal(tl.entries[0].t, 40);
});
