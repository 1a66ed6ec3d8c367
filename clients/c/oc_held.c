/*
 * oc_held.c - the samples a time-interpolating client holds (see
 * oc_held.h).
 *
 * OOM policy: a tile that cannot be stored or decoded is not held (the
 * frame's view then reports the point it would have covered,
 * OCEAN_ENOTFOUND); a blend that cannot be allocated fails with
 * OCEAN_ENOMEM.
 */
#include "oc_held.h"

#include <stdlib.h>
#include <string.h>

#include "codec.h"
#include "ocean_result.h"

typedef struct held_tile {
    proto_tile info;         /* payload NULL */
    float *data;             /* decoded planes, or NULL while still a payload */
    uint8_t *payload;        /* the codec bytes until decoded (oc_held_decode) */
} held_tile;

typedef struct held_slot {
    held_tile *t;
    unsigned n, cap;
} held_slot;

typedef struct held_mip {
    int valid;
    uint32_t tick_a;
    uint16_t interval;
    held_slot slot[2];
} held_mip;

struct oc_held {
    held_mip mip[PROTO_MAX_LAYERS][PROTO_MAX_MIPS];
};

ocean_result oc_held_create(oc_held **out)
{
    *out = calloc(1, sizeof **out);
    return *out ? OCEAN_OK : OCEAN_ENOMEM;
}

static void tile_free(held_tile *t)
{
    free(t->data);
    free(t->payload);
    t->data = NULL;
    t->payload = NULL;
}

static void slot_empty(held_slot *s)
{
    for (unsigned i = 0; i < s->n; i++) tile_free(&s->t[i]);
    s->n = 0;
}

static void mip_drop(held_mip *m)
{
    m->valid = 0;
    slot_empty(&m->slot[0]);
    slot_empty(&m->slot[1]);
}

void oc_held_destroy(oc_held *h)
{
    if (!h) return;
    for (int c = 0; c < PROTO_MAX_LAYERS; c++)
        for (int m = 0; m < PROTO_MAX_MIPS; m++) {
            mip_drop(&h->mip[c][m]);
            free(h->mip[c][m].slot[0].t);
            free(h->mip[c][m].slot[1].t);
        }
    free(h);
}

int oc_held_frame_timed(const proto_frame *f)
{
    if (f->layout != PROTO_LAYOUT_CASCADE) return 0;
    if (f->cascades.flags & PROTO_CASCADE_KEY) return 1;
    for (unsigned c = 0; c < f->cascades.cascade_count && c < PROTO_MAX_LAYERS; c++)
        for (int m = 0; m < PROTO_MAX_MIPS; m++)
            if (f->cascades.cascade[c].time[m].interval) return 1;
    return 0;
}

/* A new, empty entry at the end of slot s; NULL: out of memory. */
static held_tile *slot_append(held_slot *s)
{
    if (s->n == s->cap) {
        unsigned nc = s->cap ? 2 * s->cap : 16;
        held_tile *nt = realloc(s->t, nc * sizeof *nt);
        if (!nt) return NULL;
        s->t = nt;
        s->cap = nc;
    }
    held_tile *e = &s->t[s->n++];
    e->data = NULL;
    e->payload = NULL;
    return e;
}

static held_tile *slot_find(held_slot *s, int32_t ix, int32_t iz)
{
    for (unsigned i = 0; i < s->n; i++)
        if (s->t[i].info.ix == ix && s->t[i].info.iz == iz) return &s->t[i];
    return NULL;
}

/* The spec's A <- B: each tile held in B becomes A; a tile held in A whose
 * B has not come stays A (read alone until its new A comes).  The A-only
 * tiles join B before the swap; one that cannot (out of memory) goes. */
static void slot_shift(held_mip *hm)
{
    held_slot *a = &hm->slot[0], *b = &hm->slot[1];
    for (unsigned i = 0; i < a->n; i++) {
        held_tile *t = &a->t[i];
        if (slot_find(b, t->info.ix, t->info.iz)) continue;
        held_tile *e = slot_append(b);
        if (!e) continue;
        *e = *t;
        t->data = NULL;
        t->payload = NULL;
    }
    held_slot x = *a;
    *a = *b;
    *b = x;
    slot_empty(b);
}

/* The spec's window rule for one mip: a new window that starts where the
 * held one ends (PROTO_WINDOW_SHIFT), or anywhere else (a frame was
 * skipped), moves each tile's newest sample to A; the server counts what
 * is not the new window's own A as lacking and sends it again first. */
static void mip_advance(held_mip *hm, const proto_mip_time *t)
{
    proto_window_step step = proto_window_next(hm->valid, hm->tick_a, hm->interval, t);
    if (step == PROTO_WINDOW_KEEP) return;
    if (t->interval && hm->valid)
        slot_shift(hm);
    else
        mip_drop(hm);
    if (!t->interval) return; /* the frame's own time: nothing held */
    hm->valid = 1;
    hm->tick_a = t->tick_a;
    hm->interval = t->interval;
}

/* A copy of tile t's samples: its decoded planes d, or (d NULL) its
 * payload; *data or *payload gets it, the other NULL. */
static ocean_result tile_copy(const proto_tile *t, const float *d, float **data, uint8_t **payload)
{
    size_t n = d ? (size_t)proto_tile_planes(t->channels) * t->width * t->height * sizeof *d : t->payload_len;
    void *copy = malloc(n ? n : 1);
    if (!copy) return OCEAN_ENOMEM;
    memcpy(copy, d ? (const void *)d : (const void *)t->payload, n);
    *data = d ? copy : NULL;
    *payload = d ? NULL : copy;
    return OCEAN_OK;
}

/* Stores tile t (decoded planes d, or its payload) in slot s, replacing
 * one at its place. */
static ocean_result slot_put(held_slot *s, const proto_tile *t, const float *d)
{
    float *data;
    uint8_t *payload;
    if (tile_copy(t, d, &data, &payload) != OCEAN_OK) return OCEAN_ENOMEM;
    held_tile *e = slot_find(s, t->ix, t->iz);
    if (!e) e = slot_append(s);
    if (!e) {
        free(data);
        free(payload);
        return OCEAN_ENOMEM;
    }
    tile_free(e);
    e->info = *t;
    e->info.payload = NULL;
    e->data = data;
    e->payload = payload;
    return OCEAN_OK;
}

ocean_result oc_held_apply(oc_held *h, const proto_frame *f, const float *const *data, char *err, size_t errlen)
{
    const proto_cascade_block *b = &f->cascades;
    if (f->layout != PROTO_LAYOUT_CASCADE) {
        ocean_seterr(err, errlen, "not a layout-1 frame");
        return OCEAN_ESTATE;
    }
    for (int c = 0; c < PROTO_MAX_LAYERS; c++)
        for (int m = 0; m < PROTO_MAX_MIPS; m++) {
            held_mip *hm = &h->mip[c][m];
            if (c >= b->cascade_count || m >= b->cascade[c].mips) {
                mip_drop(hm);
                continue;
            }
            /* KEY empties the store, and the window rule still runs: the
             * mip's window becomes the entry's, so the next frame's window
             * keeps or shifts what this KEY frame brings (dropping alone
             * left no window, and the next frame dropped every sample) */
            if (b->flags & PROTO_CASCADE_KEY) mip_drop(hm);
            mip_advance(hm, &b->cascade[c].time[m]);
        }
    ocean_result res = OCEAN_OK;
    for (unsigned i = 0; i < f->tile_count; i++) {
        const proto_tile *t = &f->tiles[i];
        if ((data && !data[i]) || t->cascade >= PROTO_MAX_LAYERS || t->level >= PROTO_MAX_MIPS) continue;
        ocean_result r = slot_put(&h->mip[t->cascade][t->level].slot[t->slot ? 1 : 0], t, data ? data[i] : NULL);
        if (r != OCEAN_OK && res == OCEAN_OK) {
            ocean_seterr(err, errlen, "out of memory holding tile %u", i);
            res = r;
        }
    }
    return res;
}

/* Decodes tile t's payload into its planes; the payload goes either way. */
static ocean_result tile_decode(held_tile *t, char *err, size_t errlen)
{
    const proto_tile *i = &t->info;
    size_t cnt = (size_t)proto_tile_planes(i->channels) * i->width * i->height;
    float *d = malloc(cnt * sizeof *d + 1);
    ocean_result r = d ? proto_tile_decode((proto_codec)i->codec, i->width, i->height, i->channels, t->payload,
                                           i->payload_len, d, err, errlen)
                       : OCEAN_ENOMEM;
    free(t->payload);
    t->payload = NULL;
    if (r != OCEAN_OK) {
        free(d);
        if (r == OCEAN_ENOMEM) ocean_seterr(err, errlen, "out of memory decoding a held tile");
        return r;
    }
    t->data = d;
    return OCEAN_OK;
}

ocean_result oc_held_decode(oc_held *h, char *err, size_t errlen)
{
    ocean_result res = OCEAN_OK;
    char e[256];
    for (int c = 0; c < PROTO_MAX_LAYERS; c++)
        for (int m = 0; m < PROTO_MAX_MIPS; m++)
            for (int k = 0; k < 2; k++) {
                held_slot *s = &h->mip[c][m].slot[k];
                for (unsigned i = 0; i < s->n;) {
                    held_tile *t = &s->t[i];
                    ocean_result r = t->data ? OCEAN_OK : tile_decode(t, e, sizeof e);
                    if (r == OCEAN_OK) {
                        i++;
                        continue;
                    }
                    if (res == OCEAN_OK) {
                        ocean_seterr(err, errlen, "cascade %d mip %d tile (%d, %d): %s", c, m, (int)t->info.ix,
                                     (int)t->info.iz, e);
                        res = r;
                    }
                    tile_free(t);
                    *t = s->t[--s->n];
                }
            }
    return res;
}

void oc_held_blend_free(proto_tile *tiles, float **data, unsigned n)
{
    for (unsigned i = 0; data && i < n; i++) free(data[i]);
    free(data);
    free(tiles);
}

/* Whether a (and b, when blended) hold decoded samples of one shape. */
static int blendable(const held_tile *a, const held_tile *b)
{
    if (!a->data) return 0;
    return !b || (b->data && (a->info.channels & b->info.channels) && b->info.width == a->info.width &&
                  b->info.height == a->info.height);
}

/* (1 - w) a + w b over the channels both tiles carry; NULL: out of memory. */
static float *blend_tile(const held_tile *a, const held_tile *b, double w, unsigned *channels)
{
    unsigned ch = b ? a->info.channels & b->info.channels : a->info.channels;
    size_t plane = (size_t)a->info.width * a->info.height;
    float *out = malloc((size_t)proto_tile_planes(ch) * plane * sizeof *out + 1);
    if (!out) return NULL;
    int oa[PROTO_SLOT_COUNT], ob[PROTO_SLOT_COUNT], oo[PROTO_SLOT_COUNT];
    proto_tile_plane_offsets(a->info.channels, plane, oa);
    proto_tile_plane_offsets(b ? b->info.channels : 0, plane, ob);
    proto_tile_plane_offsets(ch, plane, oo);
    float wa = (float)(1.0 - w), wb = (float)w;
    for (int p = 0; p < PROTO_SLOT_COUNT; p++) {
        if (oo[p] < 0) continue;
        const float *pa = a->data + oa[p];
        float *po = out + oo[p];
        if (!b) {
            memcpy(po, pa, plane * sizeof *po);
            continue;
        }
        const float *pb = b->data + ob[p];
        for (size_t i = 0; i < plane; i++) po[i] = wa * pa[i] + wb * pb[i];
    }
    *channels = ch;
    return out;
}

ocean_result oc_held_blend(const oc_held *h, const proto_frame *f, proto_tile **tiles, float ***data,
                           unsigned *n)
{
    *tiles = NULL;
    *data = NULL;
    *n = 0;
    unsigned cap = 0;
    const proto_cascade_block *b = &f->cascades;
    for (unsigned c = 0; c < b->cascade_count && c < PROTO_MAX_LAYERS; c++)
        for (int m = 0; m < b->cascade[c].mips && m < PROTO_MAX_MIPS; m++) cap += h->mip[c][m].slot[0].n;
    if (!cap) return OCEAN_OK;
    proto_tile *ti = calloc(cap, sizeof *ti);
    float **d = calloc(cap, sizeof *d);
    if (!ti || !d) {
        oc_held_blend_free(ti, d, 0);
        return OCEAN_ENOMEM;
    }
    unsigned k = 0;
    for (unsigned c = 0; c < b->cascade_count && c < PROTO_MAX_LAYERS; c++)
        for (int m = 0; m < b->cascade[c].mips && m < PROTO_MAX_MIPS; m++) {
            const held_mip *hm = &h->mip[c][m];
            const proto_mip_time *tm = &b->cascade[c].time[m];
            double w = tm->interval ? tm->phase / 65536.0 : 0.0;
            for (unsigned i = 0; i < hm->slot[0].n; i++) {
                const held_tile *a = &hm->slot[0].t[i];
                held_tile *bt = tm->interval ? slot_find((held_slot *)&hm->slot[1], a->info.ix, a->info.iz) : NULL;
                /* B not come yet: A alone (the spec's rule) */
                if (bt && !blendable(a, bt)) bt = NULL;
                if (!blendable(a, bt)) continue;
                unsigned ch = 0;
                float *out = blend_tile(a, bt, w, &ch);
                if (!out) {
                    oc_held_blend_free(ti, d, k);
                    return OCEAN_ENOMEM;
                }
                ti[k] = a->info;
                ti[k].channels = (uint16_t)ch;
                ti[k].slot = 0;
                if (bt && bt->info.error_bound > ti[k].error_bound) ti[k].error_bound = bt->info.error_bound;
                d[k++] = out;
            }
        }
    *tiles = ti;
    *data = d;
    *n = k;
    return OCEAN_OK;
}
