/*
 * srv_held.c - the model of what a time-interpolating client holds (see
 * srv_held.h).
 *
 * OOM policy: a (cascade, mip) whose bitmap cannot be allocated is held
 * empty: its tiles are sent again, never assumed.
 */
#include "srv_held.h"

#include <stdlib.h>
#include <string.h>

typedef struct held_slot {
    unsigned channels;
    uint64_t *bits;          /* tiles held, one bit per tile index */
} held_slot;

typedef struct held_mip {
    int valid;               /* a window is in force */
    uint32_t tick_a;
    uint16_t interval;
    int tiles;               /* bits per slot */
    held_slot slot[2];
} held_mip;

struct srv_held {
    held_mip mip[PROTO_MAX_LAYERS][PROTO_MAX_MIPS];
    int key;                 /* cleared: the next frame carries KEY */
};

static size_t words(int tiles)
{
    return ((size_t)tiles + 63) / 64;
}

ocean_result srv_held_create(srv_held **out)
{
    *out = calloc(1, sizeof **out);
    if (!*out) return OCEAN_ENOMEM;
    (*out)->key = 1;
    return OCEAN_OK;
}

void srv_held_destroy(srv_held *h)
{
    if (!h) return;
    for (int c = 0; c < PROTO_MAX_LAYERS; c++)
        for (int m = 0; m < PROTO_MAX_MIPS; m++)
            for (int s = 0; s < 2; s++) free(h->mip[c][m].slot[s].bits);
    free(h);
}

static void slot_empty(held_mip *hm, int s)
{
    hm->slot[s].channels = 0;
    if (hm->slot[s].bits) memset(hm->slot[s].bits, 0, words(hm->tiles) * sizeof(uint64_t));
}

static void mip_drop(held_mip *hm)
{
    hm->valid = 0;
    slot_empty(hm, 0);
    slot_empty(hm, 1);
}

void srv_held_drop(srv_held *h, int c, int m0)
{
    for (int m = m0 < 0 ? 0 : m0; m < PROTO_MAX_MIPS; m++) mip_drop(&h->mip[c][m]);
}

void srv_held_clear(srv_held *h)
{
    if (!h) return;
    for (int c = 0; c < PROTO_MAX_LAYERS; c++) srv_held_drop(h, c, 0);
    h->key = 1;
}

int srv_held_key(const srv_held *h)
{
    return !h || h->key;
}

void srv_held_keyed(srv_held *h)
{
    h->key = 0;
}

/* Gives (c, m) bitmaps of `tiles` bits, empty. */
static ocean_result mip_size(held_mip *hm, int tiles)
{
    if (hm->tiles != tiles || !hm->slot[0].bits || !hm->slot[1].bits) {
        for (int s = 0; s < 2; s++) {
            free(hm->slot[s].bits);
            hm->slot[s].bits = calloc(words(tiles), sizeof(uint64_t));
        }
        hm->tiles = tiles;
        if (!hm->slot[0].bits || !hm->slot[1].bits) {
            for (int s = 0; s < 2; s++) {
                free(hm->slot[s].bits);
                hm->slot[s].bits = NULL;
            }
            hm->tiles = 0;
            hm->valid = 0;
            return OCEAN_ENOMEM;
        }
    }
    return OCEAN_OK;
}

ocean_result srv_held_advance(srv_held *h, int c, int m, const proto_mip_time *t, int tiles)
{
    held_mip *hm = &h->mip[c][m];
    if (!t->interval) {
        mip_drop(hm);
        return OCEAN_OK;
    }
    if (hm->tiles != tiles) mip_drop(hm);
    ocean_result r = mip_size(hm, tiles);
    if (r != OCEAN_OK) return r;
    proto_window_step step = proto_window_next(hm->valid, hm->tick_a, hm->interval, t);
    if (step == PROTO_WINDOW_KEEP)
        return OCEAN_OK;
    if (step == PROTO_WINDOW_SHIFT) {
        /* B becomes A; the new B is empty */
        held_slot a = hm->slot[0];
        hm->slot[0] = hm->slot[1];
        hm->slot[1] = a;
        slot_empty(hm, 1);
    } else {
        mip_drop(hm);
    }
    hm->valid = 1;
    hm->tick_a = t->tick_a;
    hm->interval = t->interval;
    return OCEAN_OK;
}

int srv_held_has(const srv_held *h, int c, int m, int slot, int i, unsigned channels)
{
    const held_mip *hm = &h->mip[c][m];
    if (!hm->valid || !hm->slot[slot].bits || i < 0 || i >= hm->tiles || hm->slot[slot].channels != channels)
        return 0;
    return (int)((hm->slot[slot].bits[i / 64] >> (i % 64)) & 1u);
}

void srv_held_add(srv_held *h, int c, int m, int slot, int i, unsigned channels)
{
    held_mip *hm = &h->mip[c][m];
    if (!hm->valid || !hm->slot[slot].bits || i < 0 || i >= hm->tiles) return;
    if (hm->slot[slot].channels != channels) {
        slot_empty(hm, slot);
        hm->slot[slot].channels = channels;
    }
    hm->slot[slot].bits[i / 64] |= (uint64_t)1 << (i % 64);
}

void srv_held_meet(srv_held *dst, const srv_held *src)
{
    for (int c = 0; c < PROTO_MAX_LAYERS; c++)
        for (int m = 0; m < PROTO_MAX_MIPS; m++) {
            held_mip *d = &dst->mip[c][m];
            const held_mip *s = &src->mip[c][m];
            if (!d->valid) continue;
            if (!s->valid || s->tiles != d->tiles || s->tick_a != d->tick_a || s->interval != d->interval ||
                !s->slot[0].bits || !d->slot[0].bits) {
                mip_drop(d);
                continue;
            }
            for (int k = 0; k < 2; k++) {
                if (s->slot[k].channels != d->slot[k].channels) {
                    slot_empty(d, k);
                    continue;
                }
                for (size_t w = 0; w < words(d->tiles); w++) d->slot[k].bits[w] &= s->slot[k].bits[w];
            }
        }
    dst->key = dst->key || src->key;
}

ocean_result srv_held_copy(srv_held *dst, const srv_held *src)
{
    ocean_result res = OCEAN_OK;
    for (int c = 0; c < PROTO_MAX_LAYERS; c++)
        for (int m = 0; m < PROTO_MAX_MIPS; m++) {
            const held_mip *s = &src->mip[c][m];
            held_mip *d = &dst->mip[c][m];
            if (!s->valid || !s->slot[0].bits) {
                mip_drop(d);
                continue;
            }
            if (mip_size(d, s->tiles) != OCEAN_OK) {
                res = OCEAN_ENOMEM;
                continue;
            }
            d->valid = 1;
            d->tick_a = s->tick_a;
            d->interval = s->interval;
            for (int k = 0; k < 2; k++) {
                d->slot[k].channels = s->slot[k].channels;
                memcpy(d->slot[k].bits, s->slot[k].bits, words(s->tiles) * sizeof(uint64_t));
            }
        }
    dst->key = src->key;
    if (res != OCEAN_OK) srv_held_clear(dst);
    return res;
}
