/*
 * srv_admin.h - the admin token's guard against guessing: it locks out the
 * guesser, never the holder of the right token.  Each connection and each
 * client address that sent a wrong token waits server.admin_lockout before
 * its next attempt is even compared, doubling per further miss (to 64x);
 * when more than SRV_ADMIN_GLOBAL_MISSES misses come within
 * SRV_ADMIN_WINDOW seconds from all addresses together (a guesser with many
 * connections or addresses), every address that missed within that window
 * is locked out for SRV_ADMIN_WINDOW seconds.  An address that has not
 * guessed is compared as ever, so the right token from it always works.
 *
 * Threads: the service thread's (the hub holds one srv_admin).
 */
#ifndef SRV_ADMIN_H
#define SRV_ADMIN_H

#define SRV_ADMIN_GLOBAL_MISSES 20
#define SRV_ADMIN_WINDOW 10
/* Client addresses remembered; the one guessed least recently makes room. */
#define SRV_ADMIN_ADDRS 64
#define SRV_ADMIN_ADDR_MAX 64

typedef struct srv_admin_addr {
    char addr[SRV_ADMIN_ADDR_MAX];
    int misses;          /* wrong tokens in a row from it */
    double until;        /* its attempts wait until then (monotonic) */
    double last;         /* its last miss; 0: none */
} srv_admin_addr;

typedef struct srv_admin {
    double miss_t[SRV_ADMIN_GLOBAL_MISSES + 1]; /* the last misses' times, a ring */
    int miss_next, miss_count;
    double alarm_until;  /* the global alarm: addresses that guessed wait until then */
    srv_admin_addr addrs[SRV_ADMIN_ADDRS];
} srv_admin;

/* Notes a miss at monotonic time now in the global window; 1 when it makes
 * more than SRV_ADMIN_GLOBAL_MISSES within the last SRV_ADMIN_WINDOW
 * seconds.  A sliding window: a fixed one, restarted every 10 s, let 39
 * guesses through in 0.6 s across its edge. */
int srv_admin_window_miss(srv_admin *a, double now);

/* When attempts from addr may be compared again (monotonic; <= now: now). */
double srv_admin_locked_until(srv_admin *a, const char *addr, double now);

/* A wrong token from addr: its backoff doubles (lockout the base), the
 * global window counts it (a global alarm starts when it passes its
 * limit: *alarm 1). */
void srv_admin_miss(srv_admin *a, const char *addr, double lockout, double now, int *alarm);

/* The right token from addr: its count of misses starts again. */
void srv_admin_hit(srv_admin *a, const char *addr);

#endif
