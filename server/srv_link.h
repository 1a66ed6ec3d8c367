/*
 * srv_link.h - what one connection carries: the live FRAMEs in flight to a
 * client, the rate its link delivers them at, and the byte rate its frames
 * are planned for, the way adaptive video streaming follows a link (the
 * stream gets coarser on a slow link, never older).
 *
 * A client's messages carry, in the header's sim_time, the sim time of the
 * last FRAME it received (PROTOCOL.md "Header"); every CAMERA therefore
 * confirms the frames up to that one.  The link counts the bytes confirmed
 * per second (the delivery rate; a MESH_TOPOLOGY sent ahead of its frame,
 * with that frame's sim time, travels and is confirmed as part of it, so a
 * large topology on a slow link counts as the link's time it takes), holds
 * the next frame while
 * SRV_LINK_WINDOW frames are unconfirmed and the oldest of them has waited
 * longer than the client's confirmations are apart (1.5 times their mean
 * gap, plus 0.1 s: a client that reports twice a second is not held to
 * three frames a report), so a newer frame replaces it: latest wins at the
 * sender, and no frame waits in a socket buffer for seconds;
 * and when frames had to wait, plans this client's frames for 85 % of the
 * delivery rate, raising that by a fifth a second while none waits, up to
 * the ceiling (server.viewer_bytes_per_s).  A client that confirms nothing
 * (no message naming a frame it was sent for SRV_LINK_QUIET seconds: a
 * fixed camera sends no CAMERA) is served as before: no window, the
 * ceiling.  A client that keeps naming the last frame it confirmed is
 * there, its next frames still on their way (behind a topology of a
 * megabyte on a 0.4 MB/s link): not quiet, so the window keeps holding.
 *
 * Threads: a srv_link belongs to its connection's service thread; the
 * planner (simulation thread) reads only srv_client.link_bps, which the
 * service thread stores.
 */
#ifndef SRV_LINK_H
#define SRV_LINK_H

#include <stddef.h>

/* Frames in flight (sent, not confirmed) before the next one is held. */
#define SRV_LINK_WINDOW 3
/* Seconds without a confirmation after which the window no longer holds. */
#define SRV_LINK_QUIET 1.0
/* The least byte rate a congested link is planned for, bytes/s. */
#define SRV_LINK_FLOOR 16e3
#define SRV_LINK_RING 64

typedef struct srv_link {
    struct {
        double sim_t;     /* the frame's sim time (header) */
        double bytes;     /* its wire size */
        double sent;      /* monotonic time it was written */
    } ring[SRV_LINK_RING];/* live frames sent and not yet confirmed, oldest first */
    int head, n;
    double last_ack;      /* monotonic time of the last confirmation; 0: none */
    double last_heard;    /* ... of the last message naming a frame sent (a
                             confirmation, or the last one named again) */
    double acked_t;       /* sim time of the newest frame confirmed */
    double ack_gap;       /* mean time between confirmations, s (0: not known yet) */
    double win_t0, win_bytes; /* delivery-rate window: start, bytes confirmed since */
    double rate;          /* delivered bytes/s (0: not measured yet) */
    double bps;           /* the byte rate frames are planned for; 0: the ceiling */
    double changed;       /* monotonic time bps last went down */
    int waited;           /* a frame was held since the last confirmation */
} srv_link;

void srv_link_init(srv_link *l);
/* A live FRAME (or the MESH_TOPOLOGY sent ahead of it, with its sim time)
 * of `bytes` bytes with header sim time sim_t was written at monotonic time
 * now. */
void srv_link_sent(srv_link *l, double sim_t, size_t bytes, double now);
/* A message from the client said it has received the frame of sim time
 * sim_t (its header's sim_time); ceiling is server.viewer_bytes_per_s. */
void srv_link_confirmed(srv_link *l, double sim_t, double ceiling, double now);
/* 1 if the link holds live frames back at now: its window is in flight
 * and the oldest is overdue (no side effect). */
int srv_link_holds(const srv_link *l, double now);
/* 1 if the next live FRAME may be written now; 0: hold it (and remember
 * that a frame waited). */
int srv_link_may_send(srv_link *l, double now);
/* The byte rate to plan this client's frames for: 0 means the ceiling. */
double srv_link_bps(const srv_link *l);

#endif
