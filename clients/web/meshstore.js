/*
 * meshstore.js - the MESH_TOPOLOGYs a layout-0 client with mesh_codec qz
 * keeps to decode compressed positions (PROTOCOL.md "Mesh positions, qz"):
 * the prediction references of each topology, by mesh id.  More than the
 * latest: the worker handles a topology as it arrives but a FRAME only when
 * the decoder pool is free, so a newer topology can overtake the frame sent
 * before it, which still refers to the previous mesh id.  Mesh ids are per
 * connection: clear() on reconnect.
 */
import { meshQzRefs } from './codec.js';

export class MeshQzStore {
    /* keep: topologies kept, oldest dropped first. */
    constructor(keep = 4) {
        this.keep = keep;
        this.byId = new Map();
    }

    /* Enters the topology meshId (its triangle indices over vertexCount
     * vertices). */
    add(meshId, vertexCount, indices) {
        this.byId.delete(meshId);
        this.byId.set(meshId, { vertexCount, refs: meshQzRefs(indices, vertexCount) });
        while (this.byId.size > this.keep) this.byId.delete(this.byId.keys().next().value);
    }

    /* The prediction references of meshId for a frame of vertexCount
     * vertices, or null when that topology is not held. */
    refs(meshId, vertexCount) {
        const m = this.byId.get(meshId);
        return m && m.vertexCount === vertexCount ? m.refs : null;
    }

    clear() {
        this.byId.clear();
    }
}
