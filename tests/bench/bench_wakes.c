/*
 * bench_wakes.c - what ships' wakes cost (issue 43): the daemon on the
 * configuration `make run` serves (config/oceand.conf, ship-bridge) in this
 * process, one viewer with the browser viewer's subscription (layout 1,
 * oc_subscribe_default) 25 m above the middle of a 4 x 4 lattice of ships
 * 250 m apart, all in its view.  The daemon's tick (the simulation
 * thread's work per tick, srv_stats tick_ns) and its CPU with no ship,
 * then with the 16 ships steaming at 6-10 m/s (a sample each a second, as a
 * simulator feeds them), once every pattern they need is built and sent,
 * in alternating spells (the ships removed and entered again), so the
 * host's own drift falls on both alike;
 * the WAKE bytes the viewer received, and what reading the wakes costs the
 * reader: oc_client_wakes on the square the browser viewer reads (192 x 192
 * points at 4 m), the C library's reading the viewer runs as WebAssembly,
 * and the same with 4 hovering helicopters' downwash besides.
 * Markdown on stdout, CSV in tests/bench/out/wakes.csv.
 */
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../lib/bench_util.h"
#include "oceanclient.h"
#include "srv_daemon.h"
#include "srv_hub.h"
#include "srv_wakes.h"

#define SHIPS 16
#define SPACING 250.0
#define GRID_N 192
#define GRID_DX 4.0
#define ROTORS 4
#define PAIRS 8
#define ROTOR_X(i) (-152.0 + 100.0 * (i)) /* on points of the square */
#define ROTOR_Z 60.0



typedef struct phase {
    double tick_ms;      /* mean simulation thread's time per tick (wall: its OpenMP team's too) */
    double cpu_ms;       /* the daemon's CPU per tick, every thread */
    long ticks;
} phase;

static double ship_speed(int i) { return 6.0 + 4.0 * i / (SHIPS - 1); }

/* Ship i's sample at sim time t: on its lane, steaming along +x. */
static proto_entity ship(int i, double t, double t0)
{
    proto_entity e = {.op = PROTO_ENTITY_SET, .kind = 0, .id = 100 + (uint32_t)i, .t = t};
    e.x = (i % 4 - 1.5) * SPACING + ship_speed(i) * (t - t0) - 100;
    e.z = (i / 4 - 1.5) * SPACING;
    e.speed = (float)ship_speed(i);
    e.length_m = 120, e.beam_m = 15, e.draught_m = 5;
    snprintf(e.token, sizeof e.token, "bench-entity");
    return e;
}

/* Drains the viewer for secs, feeding the ships a sample a second when
 * ships; measures the daemon meanwhile. */
static void run(oc_client *v, srv_hub *h, double secs, int ships, double t0, phase *p)
{
    uint64_t n0 = atomic_load(&h->stats.ticks), ns0 = atomic_load(&h->stats.tick_ns_total);
    double c0 = bench_daemon_cpu_s(), w0 = bench_now_ms(), fed = -1e9;
    while (bench_now_ms() - w0 < 1e3 * secs) {
        if (ships && bench_now_ms() - fed >= 1000) {
            fed = bench_now_ms();
            double t = oc_client_sim_time(v);
            for (int i = 0; i < SHIPS; i++) {
                proto_entity e = ship(i, t, t0);
                oc_client_send_entity(v, &e);
            }
        }
        oc_service(v, 20);
        oc_frame *f;
        while (oc_client_next_frame(v, 0, &f) == OCEAN_OK) oc_frame_free(f);
    }
    p->ticks = (long)(atomic_load(&h->stats.ticks) - n0);
    p->tick_ms = p->ticks ? 1e-6 * (double)(atomic_load(&h->stats.tick_ns_total) - ns0) / (double)p->ticks : 0;
    p->cpu_ms = p->ticks ? 1e3 * (bench_daemon_cpu_s() - c0) / (double)p->ticks : 0;
}

int main(void)
{
    double secs = bench_quick() ? 6 : 20;
    const char *sets[] = {"server.port=0", "server.bind=127.0.0.1", "server.entity_token=\"bench-entity\""};
    srv_settings st;
    srv_daemon *d;
    char err[512], url[64];
    if (srv_settings_load("config/oceand.conf", sets, 3, &st, err, sizeof err) != OCEAN_OK ||
        srv_daemon_start(&st, &d, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "bench_wakes: %s\n", err);
        return 1;
    }
    srv_hub *h = srv_daemon_hub(d);
    snprintf(url, sizeof url, "ws://127.0.0.1:%d/", srv_daemon_port(d));
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    o.frame_queue = 64;
    oc_client *v = NULL;
    if (oc_connect(&o, 10000, &v, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "bench_wakes: %s\n", err);
        return 1;
    }
    proto_subscribe sub;
    oc_subscribe_default(&sub);
    oc_client_subscribe(v, &sub);
    proto_camera cam;
    oc_camera_default(&cam);
    cam.pos[0] = 0, cam.pos[1] = 25, cam.pos[2] = 0;
    cam.pitch_deg = -10;
    oc_client_send_camera(v, &cam, NULL);
    phase none = {0}, with = {0}, p, spell[2] = {{0}};
    run(v, h, 3, 0, 0, &p);            /* the stream fills in */
    /* the ships enter; their patterns are built and sent before measuring */
    double t0 = oc_client_sim_time(v), wb = bench_now_ms();
    do run(v, h, 2, 1, t0, &p);
    while ((srv_wakes_pending(h->wakes) > 0 || atomic_load(&h->stats.wake_patterns) == 0) && bench_now_ms() - wb < 300e3);
    double build_s = 1e-9 * (double)atomic_load(&h->stats.wake_build_ns);
    long patterns = (long)atomic_load(&h->stats.wake_patterns);
    oc_client_stats cs0;
    oc_client_get_stats(v, &cs0);
    /* PAIRS pairs of spells, one without the ships and one with them, in
     * turn first (the host's drift falls on both alike); the ratio of each
     * pair, and their median */
    double ratios[PAIRS];
    for (int k = 0; k < 2 * PAIRS; k++) {
        int ships = (k + k / 2 + 1) % 2; /* the last spell with them */
        if (!ships)   /* out of the sea for this spell */
            for (int i = 0; i < SHIPS; i++) {
                proto_entity e = {.op = PROTO_ENTITY_REMOVE, .id = 100 + (uint32_t)i};
                snprintf(e.token, sizeof e.token, "bench-entity");
                oc_client_send_entity(v, &e);
            }
        run(v, h, 1, ships, t0, &p);   /* the change settles */
        run(v, h, secs / PAIRS, ships, t0, &p);
        spell[ships] = p;
        if (k % 2) ratios[k / 2] = spell[0].cpu_ms > 0 ? spell[1].cpu_ms / spell[0].cpu_ms : 0;
        phase *to = ships ? &with : &none;
        double n = fmax(1, to->ticks + p.ticks);
        to->tick_ms = (to->tick_ms * to->ticks + p.tick_ms * p.ticks) / n;
        to->cpu_ms = (to->cpu_ms * to->ticks + p.cpu_ms * p.ticks) / n;
        to->ticks += p.ticks;
    }
    double ratio = bench_median(ratios, PAIRS), ratio_lo = ratios[0], ratio_hi = ratios[PAIRS - 1];
    /* what the reader pays: the square ahead of a viewer, as the browser reads it */
    double *xz = malloc(sizeof *xz * 2 * GRID_N * GRID_N), ms[9];
    oc_wake *w = malloc(sizeof *w * GRID_N * GRID_N);
    double peak = 0;
    for (int k = 0; k < GRID_N * GRID_N; k++)
        xz[2 * k] = -384 + (k % GRID_N) * GRID_DX, xz[2 * k + 1] = -384 + (k / GRID_N) * GRID_DX;
    for (int r = 0; r < 9; r++) {
        double a = bench_now_ms();
        if (oc_client_wakes(v, oc_client_sim_time(v), xz, GRID_N * GRID_N, w) != OCEAN_OK) fprintf(stderr, "bench_wakes: no wakes read\n");
        ms[r] = bench_now_ms() - a;
    }
    for (int k = 0; k < GRID_N * GRID_N; k++) peak = fmax(peak, fabs(w[k].height));
    oc_client_stats cs;
    oc_client_get_stats(v, &cs);
    /* and with 4 helicopters on the square besides, hovering 10 m up: each
     * a dent and, read 3 s after they came, the rings of its coming.  The
     * ships go unfed meanwhile (on at their last velocities), so the same
     * instant read before the helicopters came holds the ships' wakes
     * alone, and the difference under each rotor is its own */
    run(v, h, 1.5, 0, t0, &p);
    double t_rotor = oc_client_sim_time(v), rotor_ms[9];
    oc_wake *w0 = malloc(sizeof *w0 * GRID_N * GRID_N);
    if (oc_client_wakes(v, t_rotor + 3, xz, GRID_N * GRID_N, w0) != OCEAN_OK) fprintf(stderr, "bench_wakes: no wakes read\n");
    for (int i = 0; i < ROTORS; i++) {
        proto_entity e = {.op = PROTO_ENTITY_SET, .kind = 1, .id = 200 + (uint32_t)i, .t = t_rotor,
                          .x = ROTOR_X(i), .z = ROTOR_Z, .altitude_m = 10, .length_m = 16};
        snprintf(e.token, sizeof e.token, "bench-entity");
        oc_client_send_entity(v, &e);
    }
    run(v, h, 3, 0, t0, &p);
    for (int r = 0; r < 9; r++) {
        double a = bench_now_ms();
        if (oc_client_wakes(v, t_rotor + 3, xz, GRID_N * GRID_N, w) != OCEAN_OK) fprintf(stderr, "bench_wakes: no wakes read\n");
        rotor_ms[r] = bench_now_ms() - a;
    }
    double dent_lo = INFINITY, dent_hi = -INFINITY;
    for (int i = 0; i < ROTORS; i++) {
        int k = (int)lround((ROTOR_Z + 384) / GRID_DX) * GRID_N + (int)lround((ROTOR_X(i) + 384) / GRID_DX);
        double dent = w[k].height - w0[k].height;
        dent_lo = fmin(dent_lo, dent), dent_hi = fmax(dent_hi, dent);
    }
    free(w0);
    double rotor_read_ms = bench_median(rotor_ms, 9);
    double read_ms = bench_median(ms, 9);

    printf("The daemon on `make run`'s configuration (ship-bridge) with one viewer (the browser viewer's layout-1 "
           "subscription) 25 m above the middle of 16 ships (120 m, 5 m draught, 6-10 m/s, 250 m apart, a sample "
           "each a second), %.0f s each way; medians of 9 readings for the reader.\n\n", secs);
    printf("| ships | ticks | daemon CPU ms a tick (every thread) | simulation thread's ms a tick (wall) |\n"
           "|---:|---:|---:|---:|\n");
    printf("| 0 | %ld | %.3f | %.3f |\n| %d | %ld | %.3f | %.3f |\n\n", none.ticks, none.cpu_ms, none.tick_ms, SHIPS,
           with.ticks, with.cpu_ms, with.tick_ms);
    printf("- **16 ships cost the daemon %.2fx the CPU a tick that none cost**, the median of %d pairs of %.1f s "
           "spells taken in turn (pairs %.2f-%.2fx; all spells together %.2fx; target: at most 1.25x; the "
           "simulation thread's wall time a tick, %.2fx, stretches with whatever else holds the other core): the "
           "wakes add no per-tick work for viewers but finding the patterns each viewer lacks; each pattern is "
           "built once (%ld patterns, %.2f s on the builder thread at nice 10, before the measurement) and sent "
           "once to each viewer.\n", ratio, PAIRS, secs / PAIRS, ratio_lo, ratio_hi,
           none.cpu_ms > 0 ? with.cpu_ms / none.cpu_ms : 0, none.tick_ms > 0 ? with.tick_ms / none.tick_ms : 0,
           patterns, build_s);
    printf("- The viewer received %llu WAKE patterns; its stream over the measured spells: %.0f B/s.\n",
           (unsigned long long)cs.wakes_rx, (double)(cs.bytes_rx - cs0.bytes_rx) / (2 * secs + 2 * PAIRS));
    printf("- Reading the wakes on the square the browser viewer reads (%d x %d points at %g m, all 16 ships): "
           "%.1f ms in the C library (largest wake there %.2f m); the viewer runs the same C as WebAssembly at "
           "most 10 times a second.\n", GRID_N, GRID_N, GRID_DX, read_ms, peak);
    printf("- With %d helicopters on the square besides (16 m rotors hovering 10 m up, read 3 s after they came: "
           "each a dent and the rings of its coming, sim/rotor_wash.h): %.1f ms; under each rotor the helicopters "
           "add %.4f to %.4f m to the ships' wakes (the thrust's hydrostatic head: -0.0697 m).\n", ROTORS, rotor_read_ms, dent_lo, dent_hi);
    FILE *f = fopen("tests/bench/out/wakes.csv", "w");
    if (f) {
        fprintf(f, "ships,ticks,cpu_ms,tick_ms\n0,%ld,%.6f,%.6f\n%d,%ld,%.6f,%.6f\n", none.ticks, none.cpu_ms,
                none.tick_ms, SHIPS, with.ticks, with.cpu_ms, with.tick_ms);
        fclose(f);
    }
    free(xz);
    free(w);
    oc_client_destroy(v);
    srv_daemon_stop(d);
    return 0;
}
