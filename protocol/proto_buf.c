/*
 * proto_buf.c - growable byte buffer and little-endian scalar access.
 */
#include "proto_buf.h"

#include <stdlib.h>
#include <string.h>

void proto_buf_init(proto_buf *b, size_t headroom)
{
    b->mem = NULL;
    b->head = headroom;
    b->len = 0;
    b->cap = 0;
}

void proto_buf_free(proto_buf *b)
{
    if (!b)
        return;
    free(b->mem);
    b->mem = NULL;
    b->len = 0;
    b->cap = 0;
}

void proto_buf_reset(proto_buf *b) { b->len = 0; }

ocean_result proto_buf_reserve(proto_buf *b, size_t extra)
{
    if (extra > SIZE_MAX / 2 - b->head - b->len)
        return OCEAN_ENOMEM;
    size_t need = b->len + extra;
    if (need <= b->cap && b->mem)
        return OCEAN_OK;
    size_t cap = b->cap ? b->cap : 256;
    while (cap < need)
        cap *= 2;
    uint8_t *m = realloc(b->mem, b->head + cap);
    if (!m)
        return OCEAN_ENOMEM;
    if (!b->mem)
        memset(m, 0, b->head);
    b->mem = m;
    b->cap = cap;
    return OCEAN_OK;
}

ocean_result proto_buf_append(proto_buf *b, const void *p, size_t n)
{
    ocean_result r = proto_buf_reserve(b, n);
    if (r != OCEAN_OK)
        return r;
    if (n)
        memcpy(b->mem + b->head + b->len, p, n);
    b->len += n;
    return OCEAN_OK;
}

ocean_result proto_buf_grow(proto_buf *b, size_t n, uint8_t **out)
{
    ocean_result r = proto_buf_reserve(b, n);
    if (r != OCEAN_OK)
        return r;
    uint8_t *p = b->mem + b->head + b->len;
    memset(p, 0, n);
    b->len += n;
    *out = p;
    return OCEAN_OK;
}

void proto_buf_truncate(proto_buf *b, size_t len)
{
    if (len < b->len)
        b->len = len;
}

void proto_stf32(uint8_t *p, float v)
{
    uint32_t u;
    memcpy(&u, &v, 4);
    proto_st32(p, u);
}

void proto_stf64(uint8_t *p, double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    proto_st64(p, u);
}

float proto_ldf32(const uint8_t *p)
{
    uint32_t u = proto_ld32(p);
    float v;
    memcpy(&v, &u, 4);
    return v;
}

double proto_ldf64(const uint8_t *p)
{
    uint64_t u = proto_ld64(p);
    double v;
    memcpy(&v, &u, 8);
    return v;
}
