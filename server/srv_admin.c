/*
 * srv_admin.c - the admin token's guard (see srv_admin.h).  Service thread
 * only.
 */
#include "srv_admin.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

int srv_admin_window_miss(srv_admin *a, double now)
{
    /* the last SRV_ADMIN_GLOBAL_MISSES + 1 misses in a ring: the slot
     * written next holds the oldest of them */
    a->miss_t[a->miss_next] = now;
    a->miss_next = (a->miss_next + 1) % (SRV_ADMIN_GLOBAL_MISSES + 1);
    if (a->miss_count <= SRV_ADMIN_GLOBAL_MISSES) a->miss_count++;
    return a->miss_count > SRV_ADMIN_GLOBAL_MISSES && now - a->miss_t[a->miss_next] <= SRV_ADMIN_WINDOW;
}

/* addr's entry, or NULL if it has none (make: take the slot of the address
 * that guessed least recently). */
static srv_admin_addr *entry(srv_admin *a, const char *addr, int make)
{
    srv_admin_addr *oldest = &a->addrs[0];
    for (int i = 0; i < SRV_ADMIN_ADDRS; i++) {
        srv_admin_addr *e = &a->addrs[i];
        if (e->addr[0] && strcmp(e->addr, addr) == 0) return e;
        if (e->last < oldest->last) oldest = e;
    }
    if (!make) return NULL;
    memset(oldest, 0, sizeof *oldest);
    snprintf(oldest->addr, sizeof oldest->addr, "%s", addr);
    return oldest;
}

double srv_admin_locked_until(srv_admin *a, const char *addr, double now)
{
    const srv_admin_addr *e = entry(a, addr, 0);
    if (!e) return 0;
    double until = e->until;
    if (now < a->alarm_until && e->last > 0 && now - e->last <= SRV_ADMIN_WINDOW)
        until = fmax(until, a->alarm_until);
    return until;
}

void srv_admin_miss(srv_admin *a, const char *addr, double lockout, double now, int *alarm)
{
    srv_admin_addr *e = entry(a, addr, 1);
    int k = e->misses < 6 ? e->misses : 6;
    e->misses++;
    e->last = now;
    e->until = now + lockout * (double)(1 << k);
    *alarm = srv_admin_window_miss(a, now);
    if (*alarm) a->alarm_until = now + SRV_ADMIN_WINDOW;
}

void srv_admin_hit(srv_admin *a, const char *addr)
{
    srv_admin_addr *e = entry(a, addr, 0);
    if (e) e->misses = 0;
}
