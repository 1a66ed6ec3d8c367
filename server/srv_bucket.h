/*
 * srv_bucket.h - a token bucket: the one shape of every per-connection rate
 * budget (messages a second, SUBSCRIBE changes a second, bytes read a
 * second).  Tokens accrue at `rate` a second up to `depth`; a bucket never
 * used starts full.
 *
 * Threads: a bucket belongs to its session (srv_session.h): service thread
 * only.
 */
#ifndef SRV_BUCKET_H
#define SRV_BUCKET_H

typedef struct srv_bucket {
    double tokens;
    double t;           /* monotonic time of the last refill; 0: never used */
} srv_bucket;

/* The tokens after refilling to `now`. */
double srv_bucket_refill(srv_bucket *b, double rate, double depth, double now);
/* Takes n tokens when the refilled bucket holds them: 1; else 0 and none
 * are taken. */
int srv_bucket_take(srv_bucket *b, double rate, double depth, double now, double n);
/* Spends n tokens whatever the bucket holds (it may go into debt, which
 * later refills pay back). */
void srv_bucket_spend(srv_bucket *b, double n);

#endif
