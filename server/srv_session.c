/*
 * srv_session.c - one WebSocket connection as the service thread sees it
 * (see srv_session.h).  Service thread only.
 */
#include "srv_session.h"

#include <stdio.h>
#include <stdlib.h>

#include "srv_admit.h"
#include "srv_record.h"

ocean_result srv_session_create(srv_hub *h, struct lws *wsi, srv_session **out)
{
    srv_session *s = calloc(1, sizeof *s);
    if (!s) return OCEAN_ENOMEM;
    ocean_result r = srv_client_create(h, &s->c);
    if (r != OCEAN_OK) {
        free(s);
        return r;
    }
    srv_client_ref(s->c);
    s->wsi = wsi;
    s->last_progress = s->last_rx = srv_now();
    srv_link_init(&s->link);
    *out = s;
    return OCEAN_OK;
}

void srv_session_rx_release(srv_session *s)
{
    s->c->hub->partial_held -= s->rx_held;
    s->rx_held = 0;
    free(s->rx);
    s->rx = NULL;
    s->rx_cap = s->rx_len = 0;
}

/* Closes the recording, saying what was lost if its file could not take
 * the last lines. */
static void close_recording(srv_session *s)
{
    char why[1200];
    if (s->rec && srv_record_close(s->rec, why, sizeof why) != OCEAN_OK)
        fprintf(stderr, "oceand: client %u: recording incomplete: %s\n", s->c->id, why);
    s->rec = NULL;
}

void srv_session_destroy(srv_session *s)
{
    if (!s) return;
    srv_session_rx_release(s);
    close_recording(s);
    srv_admit_release(s->c->hub->admit, s->price);
    srv_client_remove(s->c);
    srv_client_unref(s->c);
    free(s);
}
