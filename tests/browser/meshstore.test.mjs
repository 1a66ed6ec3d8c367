// The layout-0 qz mesh topologies the viewer's worker keeps
// (clients/web/meshstore.js): a FRAME decoded after a newer MESH_TOPOLOGY
// arrived must still find the topology it was sent with (the worker decodes
// frames when its pool is free, topologies at once; the browser test hit
// "no MESH_TOPOLOGY for the frame's mesh 1" when the store held one).
import test from 'node:test';
import assert from 'node:assert/strict';
import { MeshQzStore } from '../../clients/web/meshstore.js';
import { meshQzRefs } from '../../clients/web/codec.js';

const quad = new Uint32Array([0, 1, 2, 1, 3, 2]);               // 4 vertices
const fan = new Uint32Array([0, 1, 2, 0, 2, 3, 0, 3, 4]);      // 5 vertices

test('a frame sent before a newer topology still finds its own', () => {
    const s = new MeshQzStore();
    s.add(1, 4, quad);
    s.add(2, 5, fan);                      // overtakes the frame of mesh 1
    assert.deepEqual(s.refs(1, 4), meshQzRefs(quad, 4));
    assert.deepEqual(s.refs(2, 5), meshQzRefs(fan, 5));
});

test('an unknown mesh or another vertex count finds nothing', () => {
    const s = new MeshQzStore();
    s.add(1, 4, quad);
    assert.equal(s.refs(3, 4), null);
    assert.equal(s.refs(1, 5), null);
});

test('bounded, oldest dropped first; clear() on a new connection', () => {
    const s = new MeshQzStore(4);
    for (let id = 1; id <= 6; id++) s.add(id, 4, quad);
    assert.equal(s.refs(1, 4), null);
    assert.equal(s.refs(2, 4), null);
    for (let id = 3; id <= 6; id++) assert.notEqual(s.refs(id, 4), null);
    s.clear();
    assert.equal(s.refs(6, 4), null);
});
