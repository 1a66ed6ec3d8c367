/*
 * srv_work.h - client work the simulation thread does beside frames, cut
 * into bounded slices so that no client's request delays the tick that
 * serves everyone.
 *
 * QUERY: a query is answered over as many ticks as it needs.  Each tick
 * the simulation thread gives queries a time budget (server.query_ms, less
 * when the tick leaves less before the next one: srv_sim.c query_turn),
 * spent in slices of points sized from the measured cost per point, the
 * clients taking turns one slice at a time (one query per client in the
 * rotation; the client's other queries wait in its own FIFO).  The points'
 * results collect in the query's array; the QUERY_RESULT goes out whole
 * when the last slice is done.  ocean_query_points is independent of how
 * the points are split (sim/query.h), so the answer is the one a single
 * pass would give.  The ships' wakes at the points are added to each
 * slice's answers (srv_wakes.h), from the entities' states at the
 * query's time.
 *
 * The time each slice takes is charged to its client (client.cpu_ns,
 * /metrics oceand_client_cpu_seconds_total).
 */
#ifndef SRV_WORK_H
#define SRV_WORK_H

#include "gerstner.h"
#include "ocean.h"
#include "srv_client.h"

typedef struct srv_work srv_work;

ocean_result srv_work_create(srv_work **out);
/* Drops every query still in progress (their clients' references too).
 * Accepts NULL. */
void srv_work_destroy(srv_work *w);

/* Moves the oldest pending query of c into the rotation if c has none
 * there yet; a query without its own time is answered at t_now (the tick
 * it was taken on) [sim; hub.lock held]. */
void srv_work_take(srv_work *w, srv_client *c, double t_now);
/* 1 if queries are in progress [sim]. */
int srv_work_busy(const srv_work *w);
/* The sim time the next turn's first query is answered at (0 when none is
 * queued). */
int srv_work_next_time(const srv_work *w, double *t);

/* An evaluation of the ocean at time t holding OCEAN_QUERY_EFFECTS,
 * unfiltered; NULL on failure, or with cached_only when none is at hand
 * (evaluating would cost an FFT pass).  Valid until the next call. */
typedef const ocean_frame *(*srv_work_eval_fn)(void *ctx, double t, int cached_only);

/* Runs query slices for about budget_s seconds after the turn's first
 * evaluation, if it needs one (at least one slice, but none while a wake
 * pattern the next slice needs is being built),
 * answering queries that complete and refusing those with a bad point.
 * g: the near field, or NULL; depth: the sea's, m, for the wakes [sim]. */
void srv_work_queries(srv_work *w, srv_hub *h, srv_work_eval_fn eval, void *ctx,
                      const ocean_gerstner *g, double depth, double budget_s);

#endif
