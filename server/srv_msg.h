/*
 * srv_msg.h - an outgoing message's bytes: its own, or a reference to bytes
 * several clients' messages share (one FRAME encoding for co-located
 * viewers), with the per-client fields written in when it is sent.
 *
 * Threads: a message belongs to one thread at a time (its maker, then the
 * outbox, then the service thread that sends it); shared bytes are
 * immutable once shared, except the per-client fields the service thread
 * writes just before lws_write.
 */
#ifndef SRV_MSG_H
#define SRV_MSG_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "ocean_result.h"
#include "proto.h"
#include "proto_buf.h"

/* Encoded bytes that several queued messages share: one FRAME encoding for
 * every viewer whose frame differs only in its per-client fields (co-located
 * viewers).  Immutable once shared, except that the service thread - the
 * only thread that sends - writes the per-client fields of the message it is
 * about to send just before lws_write (which hands every byte to the kernel
 * or copies what it could not send before returning). */
typedef struct srv_blob {
    atomic_int refs;
    proto_buf buf;      /* LWS_PRE headroom */
} srv_blob;

/* Offset of camera_seq in an encoded FRAME, as proto_frame_client_fields
 * reports it (checked for every shared frame before it is shared). */
#define SRV_FRAME_CAMERA_SEQ_AT (PROTO_HEADER_SIZE + 40)

/* One queued outgoing message: its own bytes (buf, with LWS_PRE headroom)
 * or a reference to shared ones (blob) with the per-client FRAME fields to
 * write into them when sending. */
typedef struct srv_msg {
    struct srv_msg *next;
    proto_buf buf;
    srv_blob *blob;     /* shared bytes, or NULL: buf */
    uint32_t camera_seq;/* blob FRAMEs: this client's camera_seq ... */
    uint32_t mesh_id;   /*   ... and mesh id, */
    uint32_t mesh_id_at;/*   at this byte offset (0: no mesh) */
    double tick_wall;   /* monotonic time of the tick that made it (0: none) */
    int is_frame;       /* counts as a frame for statistics */
    int live;           /* a live FRAME, or the MESH_TOPOLOGY before it, from the
                           latest-wins slot (srv_link counts it) */
    int close_after;    /* close the connection once this is sent (BYE) */
} srv_msg;

srv_msg *srv_msg_new(void);
/* A new message holding m's encoding, or NULL on OOM or a message the
 * encoder refuses (logged: the daemon built it, so that is a bug). */
srv_msg *srv_msg_encode(const proto_msg *m);
void srv_msg_free(srv_msg *m);
/* Moves m's own bytes into a new blob of one reference (m then refers to
 * it).  OCEAN_ENOMEM leaves m as it was. */
ocean_result srv_msg_make_shared(srv_msg *m);
/* A new message referring to m's blob (one more reference), with m's
 * per-client fields and flags.  NULL on OOM or if m has no blob. */
srv_msg *srv_msg_share(const srv_msg *m);
/* The message's wire bytes, per-client FRAME fields written in for a blob
 * [service thread only: the bytes may be shared]. */
uint8_t *srv_msg_wire(srv_msg *m, size_t *len);
/* Length of the wire bytes. */
size_t srv_msg_len(const srv_msg *m);
/* What a queued message holds in memory: its allocations (the message, its
 * buffer's headroom and capacity, or the shared blob) plus the allocator's
 * per-block overhead.  The output limits count this, not the wire length:
 * a 110-byte ERROR holds about 400 bytes. */
size_t srv_msg_cost(const srv_msg *m);


#endif
