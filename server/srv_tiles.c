/*
 * srv_tiles.c - layout 0's tiles, made once however many clients ask: each
 * sampled from an evaluated ocean, encoded, and kept in a cache (a chained
 * hash table swept once a tick) keyed by what decides its bytes (see
 * srv_tiles.h).
 */
#include "srv_tiles.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#define NBUCKETS 4096

/* The encoding context of the calling thread (the sim thread and the
 * OpenMP workers srv_sim.c builds tiles on), made on its first tile and
 * freed when the thread exits: a new zstd context per tile costs about a
 * fifth of qz encoding.  NULL if it cannot be made; the codec then makes
 * one per call. */
static pthread_key_t codec_key;
static pthread_once_t codec_once = PTHREAD_ONCE_INIT;
static int codec_key_ok;

static void codec_ctx_free(void *p) { proto_codec_ctx_destroy(p); }
static void codec_key_make(void) { codec_key_ok = pthread_key_create(&codec_key, codec_ctx_free) == 0; }

proto_codec_ctx *srv_tiles_codec_ctx(void)
{
    pthread_once(&codec_once, codec_key_make);
    if (!codec_key_ok) return NULL;
    proto_codec_ctx *c = pthread_getspecific(codec_key);
    if (!c && proto_codec_ctx_create(&c) == OCEAN_OK && pthread_setspecific(codec_key, c) != 0) {
        proto_codec_ctx_destroy(c);
        c = NULL;
    }
    return c;
}

struct srv_tile_cache {
    srv_tile *b[NBUCKETS];
    size_t count;
    size_t bytes;          /* of the entries the last sweep kept */
};

ocean_result srv_tiles_create(srv_tile_cache **out)
{
    *out = calloc(1, sizeof **out);
    return *out ? OCEAN_OK : OCEAN_ENOMEM;
}

static void tile_free(srv_tile *t)
{
    free(t->payload);
    free(t);
}

void srv_tiles_clear(srv_tile_cache *c)
{
    for (int i = 0; i < NBUCKETS; i++) {
        while (c->b[i]) {
            srv_tile *t = c->b[i];
            c->b[i] = t->next;
            tile_free(t);
        }
    }
    c->count = 0;
    c->bytes = 0;
}

void srv_tiles_destroy(srv_tile_cache *c)
{
    if (!c) return;
    srv_tiles_clear(c);
    free(c);
}

void srv_tile_key_init(srv_tile_key *k) { memset(k, 0, sizeof *k); }

static uint64_t key_hash(const srv_tile_key *k)
{
    const unsigned char *p = (const unsigned char *)k;
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < sizeof *k; i++) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

srv_tile *srv_tiles_get(srv_tile_cache *c, const srv_tile_key *k, uint64_t gen, int *fresh)
{
    uint64_t h = key_hash(k);
    srv_tile **slot = &c->b[h % NBUCKETS];
    for (srv_tile *t = *slot; t; t = t->next) {
        if (t->hash == h && memcmp(&t->key, k, sizeof *k) == 0) {
            t->last_use = gen;
            *fresh = 0;
            return t;
        }
    }
    srv_tile *t = calloc(1, sizeof *t);
    if (!t) return NULL;
    t->key = *k;
    t->hash = h;
    t->last_use = gen;
    t->next = *slot;
    *slot = t;
    c->count++;
    *fresh = 1;
    return t;
}

void srv_tiles_sweep(srv_tile_cache *c, uint64_t keep_from)
{
    size_t bytes = 0;
    for (int i = 0; i < NBUCKETS; i++) {
        srv_tile **p = &c->b[i];
        while (*p) {
            srv_tile *t = *p;
            if (t->last_use < keep_from) {
                *p = t->next;
                tile_free(t);
                c->count--;
            } else {
                bytes += sizeof *t + t->payload_len;
                p = &t->next;
            }
        }
    }
    c->bytes = bytes;
}

size_t srv_tiles_count(const srv_tile_cache *c) { return c->count; }

size_t srv_tiles_bytes(const srv_tile_cache *c) { return c->bytes; }

unsigned srv_tiles_channels(unsigned effects)
{
    unsigned ch = 0;
    if (effects & PROTO_FX_HEIGHT) ch |= PROTO_CH_HEIGHT;
    if (effects & PROTO_FX_DISPLACEMENT) ch |= PROTO_CH_DX | PROTO_CH_DZ;
    if (effects & PROTO_FX_NORMALS) ch |= PROTO_CH_NORMAL;
    if (effects & PROTO_FX_FOAM) ch |= PROTO_CH_FOAM;
    return ch;
}

int32_t srv_tiles_first(double x, double w, int n)
{
    double f = floor(x / w - (n - 1) / 2.0);
    if (f < -2e9) f = -2e9;
    if (f > 2e9) f = 2e9;
    return (int32_t)f;
}

void srv_tile_build(srv_tile *t, const ocean_frame *f)
{
    const srv_tile_key *k = &t->key;
    int n = k->size;
    size_t ns = (size_t)n * n;
    int planes = proto_tile_planes(k->channels);
    float *buf = malloc(sizeof(float) * ns * ((size_t)planes + 2));
    t->ready = 1;
    if (!buf) {
        t->result = OCEAN_ENOMEM;
        return;
    }
    float *sx = buf + ns * (size_t)planes, *sz = sx + ns;
    double x0 = (double)k->ix * n * k->spacing, z0 = (double)k->iz * n * k->spacing;
    float *out[PROTO_TILE_MAX_PLANES] = {0};
    int pi = 0;
    float *ph = NULL, *pdx = NULL, *pdz = NULL, *pnu = NULL, *pnv = NULL, *pfoam = NULL, *pj = NULL;
    if (k->channels & PROTO_CH_HEIGHT) ph = out[pi] = buf + ns * (size_t)pi, pi++;
    if (k->channels & PROTO_CH_DX) pdx = out[pi] = buf + ns * (size_t)pi, pi++;
    if (k->channels & PROTO_CH_DZ) pdz = out[pi] = buf + ns * (size_t)pi, pi++;
    if (k->channels & PROTO_CH_NORMAL) {
        pnu = buf + ns * (size_t)pi++;
        pnv = buf + ns * (size_t)pi++;
    }
    if (k->channels & PROTO_CH_FOAM) pfoam = buf + ns * (size_t)pi++;
    if (k->channels & PROTO_CH_JACOBIAN) pj = buf + ns * (size_t)pi++;
    /* Only the channel groups this tile carries are interpolated. */
    unsigned want = (ph ? OCEAN_SAMPLE_HEIGHT : 0) | (pdx || pdz ? OCEAN_SAMPLE_DISPLACEMENT : 0) |
                    (pnu ? OCEAN_SAMPLE_SLOPE : 0) | (pfoam || pj ? OCEAN_SAMPLE_FOAM : 0);
    for (int i = 0; i < n; i++) {
        double z = z0 + i * k->spacing;
        for (int j = 0; j < n; j++) {
            ocean_point p;
            ocean_frame_sample_some(f, x0 + j * k->spacing, z, want, &p);
            size_t s = (size_t)i * n + j;
            if (ph) ph[s] = (float)p.height;
            if (pdx) pdx[s] = (float)p.dx;
            if (pdz) pdz[s] = (float)p.dz;
            sx[s] = (float)p.slope_x;
            sz[s] = (float)p.slope_z;
            if (pfoam) pfoam[s] = (float)p.foam;
            if (pj) pj[s] = (float)p.jacobian;
        }
    }
    if (pnu) proto_normals_from_slopes(sx, sz, ns, pnu, pnv);
    proto_buf pb;
    double max_err = 0;
    t->result = srv_tiles_encode(k, n, buf, &pb, &max_err);
    free(buf);
    if (t->result == OCEAN_OK)
        t->result = srv_tile_take_payload(t, &pb);
    if (t->result != OCEAN_OK)
        return;
    t->error_bound = isfinite(max_err) && max_err >= 0 ? (float)max_err : 0.0f;
}

ocean_result srv_tile_take_payload(srv_tile *t, proto_buf *b)
{
    if (b->len > UINT32_MAX) {
        proto_buf_free(b);
        return OCEAN_ETOOBIG;
    }
    /* headroom 0: the bytes start at mem.  glibc shrinks a heap block in
     * place and hands its tail back; if realloc fails, the block stays as
     * it was and still holds the bytes. */
    uint8_t *m = b->mem ? realloc(b->mem, b->len ? b->len : 1) : NULL;
    t->payload = m ? m : b->mem;
    t->payload_len = (uint32_t)b->len;
    proto_buf_init(b, 0);
    return OCEAN_OK;
}

ocean_result srv_tiles_encode(const srv_tile_key *k, int n, const float *planes, proto_buf *out, double *max_err)
{
    proto_codec_params cp;
    proto_codec_params_default(&cp);
    cp.accuracy = k->accuracy;
    proto_buf_init(out, 0);
    *max_err = 0;
    ocean_result r = proto_tile_encode_ctx(srv_tiles_codec_ctx(), (proto_codec)k->codec, &cp, n, n, k->channels,
                                           planes, out, max_err, NULL, 0);
    if (r == OCEAN_OK && out->len > UINT32_MAX) r = OCEAN_ETOOBIG;
    if (r != OCEAN_OK) proto_buf_free(out);
    return r;
}

void srv_tile_to_proto(const srv_tile *t, proto_tile *o)
{
    memset(o, 0, sizeof *o);
    o->level = t->key.level;
    o->codec = t->key.codec;
    o->channels = t->key.channels;
    o->width = o->height = t->key.size;
    o->ix = t->key.ix;
    o->iz = t->key.iz;
    o->origin_x = (double)t->key.ix * t->key.size * t->key.spacing;
    o->origin_z = (double)t->key.iz * t->key.size * t->key.spacing;
    o->spacing = t->key.spacing;
    o->error_bound = t->error_bound;
    o->payload_len = t->payload_len;
    o->payload = t->payload;
}
