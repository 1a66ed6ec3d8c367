/*
 * srv_link.c - what one connection carries (see srv_link.h).  Service
 * thread only.
 */
#include "srv_link.h"

#include <math.h>
#include <string.h>

/* Confirmed bytes are turned into a rate over windows of this many seconds. */
#define RATE_WINDOW 0.5
/* A congested link is planned for this share of what it delivered. */
#define DECREASE 0.85
/* An uncongested link's plan grows by this share a second. */
#define INCREASE 0.2

void srv_link_init(srv_link *l)
{
    memset(l, 0, sizeof *l);
}

void srv_link_sent(srv_link *l, double sim_t, size_t bytes, double now)
{
    if (l->n == SRV_LINK_RING) { /* nothing confirmed for 64 frames: forget the oldest */
        l->head = (l->head + 1) % SRV_LINK_RING;
        l->n--;
    }
    int i = (l->head + l->n) % SRV_LINK_RING;
    l->ring[i].sim_t = sim_t;
    l->ring[i].bytes = (double)bytes;
    l->ring[i].sent = now;
    l->n++;
}

static int quiet(const srv_link *l, double now)
{
    return l->last_heard == 0 || now - l->last_heard > SRV_LINK_QUIET;
}

/* The delivery rate from the bytes confirmed over the last window. */
static void measure(srv_link *l, double got, double now)
{
    if (quiet(l, now)) { /* a (re)start: the gap says nothing of the link */
        l->win_t0 = now;
        l->win_bytes = 0;
        return;
    }
    l->win_bytes += got;
    double span = now - l->win_t0;
    if (span < RATE_WINDOW) return;
    double r = l->win_bytes / span;
    l->rate = l->rate > 0 ? 0.5 * (l->rate + r) : r;
    l->win_t0 = now;
    l->win_bytes = 0;
}

void srv_link_confirmed(srv_link *l, double sim_t, double ceiling, double now)
{
    double got = 0;
    int popped = 0;
    while (l->n && l->ring[l->head].sim_t <= sim_t) {
        got += l->ring[l->head].bytes;
        l->head = (l->head + 1) % SRV_LINK_RING;
        l->n--;
        popped++;
    }
    if (!popped) {
        if (l->acked_t > 0 && sim_t >= l->acked_t) l->last_heard = now;
        return;
    }
    double dt = quiet(l, now) ? 0 : now - l->last_ack;
    if (dt > 0) l->ack_gap = l->ack_gap > 0 ? 0.8 * l->ack_gap + 0.2 * dt : dt;
    measure(l, got, now);
    l->last_ack = l->last_heard = now;
    l->acked_t = fmax(l->acked_t, sim_t);
    double cur = l->bps > 0 ? l->bps : ceiling;
    if (l->waited || l->n >= SRV_LINK_WINDOW) {
        /* frames waited: the link, not the plan, sets the pace */
        if (l->rate > 0 && now - l->changed > RATE_WINDOW && DECREASE * l->rate < cur) {
            cur = fmax(SRV_LINK_FLOOR, DECREASE * l->rate);
            l->changed = now;
        }
    } else {
        cur *= 1 + INCREASE * fmin(dt, 1.0);
    }
    l->bps = cur >= ceiling ? 0 : cur;
    l->waited = 0;
}

int srv_link_holds(const srv_link *l, double now)
{
    if (quiet(l, now) || l->n < SRV_LINK_WINDOW) return 0;
    /* the oldest frame in flight may just not be reported yet */
    return now - l->ring[l->head].sent > 1.5 * l->ack_gap + 0.1;
}

int srv_link_may_send(srv_link *l, double now)
{
    if (!srv_link_holds(l, now)) return 1;
    l->waited = 1;
    return 0;
}

double srv_link_bps(const srv_link *l)
{
    return l->bps;
}
