/*
 * proto_buf.h - the growable byte buffer every encoder in protocol/ writes to.
 *
 * A proto_buf may reserve "headroom" in front of the message so that the
 * daemon can hand the bytes to libwebsockets, which needs LWS_PRE writable
 * bytes before the data, without copying.  The message itself always starts
 * at proto_buf_data(b) and is proto_buf_len(b) bytes long.
 *
 * Encoders append.  On failure (OCEAN_ENOMEM or a refused value) an encoder
 * truncates the buffer back to the length it had on entry, so a failed
 * encode never leaves half a message behind.
 */
#ifndef PROTO_BUF_H
#define PROTO_BUF_H

#include <stddef.h>
#include <stdint.h>

#include "ocean_result.h"

typedef struct proto_buf {
    uint8_t *mem;     /* allocation; the message starts at mem + head */
    size_t head;      /* headroom bytes reserved before the message */
    size_t len;       /* message bytes written after the headroom */
    size_t cap;       /* bytes allocated after the headroom */
} proto_buf;

/* Initialises an empty buffer with `headroom` bytes reserved in front of the
 * message (0 for none, LWS_PRE for libwebsockets).  Allocates nothing. */
void proto_buf_init(proto_buf *b, size_t headroom);

/* Releases the memory and leaves b empty (re-usable).  Accepts NULL. */
void proto_buf_free(proto_buf *b);

/* Forgets the contents but keeps the allocation. */
void proto_buf_reset(proto_buf *b);

/* The message bytes and their count. */
static inline uint8_t *proto_buf_data(const proto_buf *b) { return b->mem ? b->mem + b->head : NULL; }
static inline size_t proto_buf_len(const proto_buf *b) { return b->len; }

/* Makes room for at least `extra` more bytes.  OCEAN_ENOMEM leaves b as is. */
ocean_result proto_buf_reserve(proto_buf *b, size_t extra);

/* Appends n bytes (n may be 0).  OCEAN_ENOMEM leaves b as is. */
ocean_result proto_buf_append(proto_buf *b, const void *p, size_t n);

/* Appends n zero bytes and returns a pointer to them through *out (valid
 * until the next call that grows b). */
ocean_result proto_buf_grow(proto_buf *b, size_t n, uint8_t **out);

/* Shrinks the message to len bytes (len <= current length). */
void proto_buf_truncate(proto_buf *b, size_t len);

/* Little-endian stores and loads used by every encoder/decoder; they work on
 * any alignment and any host byte order. */
static inline void proto_st16(uint8_t *p, uint16_t v) { p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); }
static inline void proto_st32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)v; p[1] = (uint8_t)(v >> 8); p[2] = (uint8_t)(v >> 16); p[3] = (uint8_t)(v >> 24);
}
static inline void proto_st64(uint8_t *p, uint64_t v) { proto_st32(p, (uint32_t)v); proto_st32(p + 4, (uint32_t)(v >> 32)); }
static inline uint16_t proto_ld16(const uint8_t *p) { return (uint16_t)(p[0] | (p[1] << 8)); }
static inline uint32_t proto_ld32(const uint8_t *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}
static inline uint64_t proto_ld64(const uint8_t *p) { return (uint64_t)proto_ld32(p) | ((uint64_t)proto_ld32(p + 4) << 32); }
void proto_stf32(uint8_t *p, float v);
void proto_stf64(uint8_t *p, double v);
float proto_ldf32(const uint8_t *p);
double proto_ldf64(const uint8_t *p);

#endif
