/*
 * srv_msg.c - an outgoing message's bytes, owned or shared (see srv_msg.h).
 */
#include "srv_msg.h"

#include <libwebsockets.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "srv_client.h"

srv_msg *srv_msg_new(void)
{
    srv_msg *m = calloc(1, sizeof *m);
    if (m) proto_buf_init(&m->buf, LWS_PRE);
    return m;
}

srv_msg *srv_msg_encode(const proto_msg *m)
{
    srv_msg *q = srv_msg_new();
    if (!q) return NULL;
    char err[256];
    if (proto_encode(&q->buf, m, err, sizeof err) != OCEAN_OK) {
        /* Once a second at most: a failure repeats with every frame, and
         * any thread may get here. */
        static _Atomic int64_t said_s = INT64_MIN;
        static atomic_uint_fast64_t quiet;
        int64_t now = (int64_t)srv_now(), last = atomic_load(&said_s);
        if (now != last && atomic_compare_exchange_strong(&said_s, &last, now)) {
            uint64_t q_n = atomic_exchange(&quiet, 0);
            fprintf(stderr, "oceand: cannot encode %s: %s", proto_type_name(m->hdr.type), err);
            if (q_n) fprintf(stderr, " (%llu more since the last such line)", (unsigned long long)q_n);
            fputc('\n', stderr);
        } else {
            atomic_fetch_add(&quiet, 1);
        }
        srv_msg_free(q);
        return NULL;
    }
    return q;
}

void srv_msg_free(srv_msg *m)
{
    if (!m) return;
    proto_buf_free(&m->buf);
    if (m->blob && atomic_fetch_sub(&m->blob->refs, 1) == 1) {
        proto_buf_free(&m->blob->buf);
        free(m->blob);
    }
    free(m);
}

ocean_result srv_msg_make_shared(srv_msg *m)
{
    if (m->blob) return OCEAN_OK;
    srv_blob *b = malloc(sizeof *b);
    if (!b) return OCEAN_ENOMEM;
    atomic_init(&b->refs, 1);
    b->buf = m->buf;
    proto_buf_init(&m->buf, LWS_PRE);
    m->blob = b;
    return OCEAN_OK;
}

srv_msg *srv_msg_share(const srv_msg *m)
{
    if (!m->blob) return NULL;
    srv_msg *q = srv_msg_new();
    if (!q) return NULL;
    atomic_fetch_add(&m->blob->refs, 1);
    q->blob = m->blob;
    q->camera_seq = m->camera_seq;
    q->mesh_id = m->mesh_id;
    q->mesh_id_at = m->mesh_id_at;
    q->tick_wall = m->tick_wall;
    q->is_frame = m->is_frame;
    q->close_after = m->close_after;
    return q;
}

size_t srv_msg_len(const srv_msg *m)
{
    if (!m) return 0;
    return proto_buf_len(m->blob ? &m->blob->buf : &m->buf);
}

uint8_t *srv_msg_wire(srv_msg *m, size_t *len)
{
    proto_buf *b = m->blob ? &m->blob->buf : &m->buf;
    uint8_t *d = proto_buf_data(b);
    *len = proto_buf_len(b);
    if (m->blob && m->is_frame && *len >= SRV_FRAME_CAMERA_SEQ_AT + 4) {
        proto_st32(d + SRV_FRAME_CAMERA_SEQ_AT, m->camera_seq);
        if (m->mesh_id_at && (size_t)m->mesh_id_at + 4 <= *len) proto_st32(d + m->mesh_id_at, m->mesh_id);
    }
    return d;
}

/* glibc malloc: 16 bytes of header per block, rounded to 16. */
#define MALLOC_OVERHEAD 16

size_t srv_msg_cost(const srv_msg *m)
{
    if (!m) return 0;
    size_t n = sizeof *m + MALLOC_OVERHEAD;
    if (m->buf.mem) n += m->buf.head + m->buf.cap + MALLOC_OVERHEAD;
    if (m->blob) n += sizeof *m->blob + m->blob->buf.head + m->blob->buf.cap + 2 * MALLOC_OVERHEAD;
    return n;
}


