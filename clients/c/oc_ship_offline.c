/*
 * oc_ship_offline.c - the ship's hull floated on a local ocean (see
 * oc_ship_offline.h).
 */
#include "oc_ship_offline.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "query.h"

/* The scratch of one run: the hull points, their heights and answers, and
 * the frame the ocean is evaluated into. */
typedef struct offline_run {
    size_t n;
    double *xz, *h;
    ocean_query_result *qr;
    ocean_frame *f;
    ocean_request req;
    ocean_query_options qo;
} offline_run;

static void offline_run_free(offline_run *u)
{
    ocean_frame_destroy(u->f);
    free(u->xz);
    free(u->h);
    free(u->qr);
}

/* The run's scratch for n points and the trace's steps + 1 rows. */
static ocean_result offline_run_alloc(offline_run *u, const ocean *o, size_t n, size_t steps,
                                      oc_ship_trace *out)
{
    memset(u, 0, sizeof *u);
    u->n = n;
    u->xz = malloc(2 * n * sizeof *u->xz);
    u->h = malloc(n * sizeof *u->h);
    u->qr = malloc(n * sizeof *u->qr);
    out->t = malloc((steps + 1) * sizeof(double));
    out->heave = malloc((steps + 1) * sizeof(double));
    out->pitch = malloc((steps + 1) * sizeof(double));
    out->roll = malloc((steps + 1) * sizeof(double));
    out->eta = malloc((steps + 1) * sizeof(double));
    ocean_result r = ocean_frame_create(o, &u->f);
    if (r == OCEAN_OK && (!u->xz || !u->h || !u->qr || !out->t || !out->heave || !out->pitch ||
                          !out->roll || !out->eta))
        r = OCEAN_ENOMEM;
    ocean_request_all(&u->req, OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT);
    ocean_query_options_default(&u->qo);
    /* The bilinear reading smooths the shortest waves of this coarse grid;
     * the heave tests (test_ship) are calibrated on it. */
    u->qo.bilinear = 1;
    return r;
}

/* One step at the ship's time t: the sea under its points, their mean
 * height into *eta, then the hull advanced by dt. */
static ocean_result offline_step(offline_run *u, ocean *o, oc_ship *s, double t, double dt, double *eta,
                                 char *msg, size_t msglen)
{
    ocean_result r = ocean_evaluate(o, t, &u->req, u->f);
    if (r != OCEAN_OK) {
        if (msg && msglen) snprintf(msg, msglen, "ocean_evaluate at t = %g: %s", t, ocean_strerror(r));
        return r;
    }
    oc_ship_points(s, u->xz);
    r = ocean_query_points(u->f, NULL, NULL, t, u->xz, u->n, &u->qo, u->qr, NULL);
    if (r != OCEAN_OK) {
        if (msg && msglen) snprintf(msg, msglen, "ocean_query_points at t = %g: %s", t, ocean_strerror(r));
        return r;
    }
    double mean = 0;
    for (size_t j = 0; j < u->n; j++) {
        u->h[j] = u->qr[j].height;
        mean += u->h[j];
    }
    *eta = mean / (double)u->n;
    r = oc_ship_step(s, u->h, dt);
    if (r != OCEAN_OK && msg && msglen)
        snprintf(msg, msglen, "ship step at t = %g: %s", t, ocean_strerror(r));
    return r;
}

ocean_result oc_ship_run_offline(const oc_ship_params *p, ocean *o, double t0, double seconds, double dt,
                                 oc_ship_trace *out, char *msg, size_t msglen)
{
    if (!p || !o || !out || !(seconds > 0 && seconds <= 1e6) || !(dt > 0 && dt <= 0.5)) {
        if (msg && msglen) snprintf(msg, msglen, "bad arguments to the offline ship run");
        return OCEAN_EINVAL;
    }
    memset(out, 0, sizeof *out);
    oc_ship *s;
    ocean_result r = oc_ship_create(p, t0, &s, msg, msglen);
    if (r != OCEAN_OK)
        return r;
    size_t steps = (size_t)ceil(seconds / dt);
    offline_run u;
    r = offline_run_alloc(&u, o, oc_ship_point_count(s), steps, out);
    out->dt = dt;
    for (size_t i = 0; r == OCEAN_OK && i <= steps; i++) {
        oc_ship_state st;
        oc_ship_get_state(s, &st);
        out->t[i] = st.t;
        out->heave[i] = st.heave;
        out->pitch[i] = st.pitch;
        out->roll[i] = st.roll;
        out->eta[i] = i ? out->eta[i - 1] : 0;
        out->n = i + 1;
        if (i < steps)
            r = offline_step(&u, o, s, st.t, dt, &out->eta[i], msg, msglen);
    }
    offline_run_free(&u);
    oc_ship_destroy(s);
    if (r != OCEAN_OK && r != OCEAN_EDIVERGED)
        oc_ship_trace_free(out);
    return r;
}
