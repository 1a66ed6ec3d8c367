/*
 * srv_bucket.c - a token bucket (see srv_bucket.h).
 */
#include "srv_bucket.h"

double srv_bucket_refill(srv_bucket *b, double rate, double depth, double now)
{
    if (b->t == 0) b->tokens = depth;
    else if (now > b->t) b->tokens += (now - b->t) * rate;
    if (b->tokens > depth) b->tokens = depth;
    b->t = now;
    return b->tokens;
}

int srv_bucket_take(srv_bucket *b, double rate, double depth, double now, double n)
{
    if (srv_bucket_refill(b, rate, depth, now) < n) return 0;
    b->tokens -= n;
    return 1;
}

void srv_bucket_spend(srv_bucket *b, double n) { b->tokens -= n; }
