/*
 * test_cigi_service.c - oceand's CIGI service (server/srv_cigi.h) driven
 * over loopback UDP by a scripted host: every HAT/HOT answer is the
 * WebSocket side's QUERY answer at the same point and sim time (the Start
 * of Frame's timestamp), in CIGI 3.3 of either byte order and in 4.0;
 * an entity-relative request is answered as the geodetic one at the point
 * it names, and Valid = 0 for an entity the daemon does not hold; the
 * host's surface wind sets the sea; hostile datagrams are dropped and
 * counted by reason, and the daemon answers on afterwards.
 */
#include <arpa/inet.h>
#include <math.h>
#include <netinet/in.h>
#include <poll.h>
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmocka.h>

#include "cigi.h"
#include "lib/test_net.h"
#include "lib/test_pcap.h"
#include "geo.h"
#include "oceanclient.h"
#include "srv_daemon.h"
#include "srv_entity.h"
#include "srv_hub.h"

static const double LAT0 = 43.5, LON0 = -8.25;

typedef struct fixture {
    srv_daemon *d;
    srv_settings set;
    int port;               /* the CIGI service's UDP port */
    oc_client *ws;          /* a WebSocket client asking the same points */
} fixture;

static int setup(void **state)
{
    static fixture fx;
    char port[40], err[512];
    fx.port = test_free_udp_port();
    snprintf(port, sizeof port, "server.cigi_port=%d", fx.port);
    const char *sets[] = {"server.port=0", "server.scene=ship-bridge", "ocean.threads=1", "server.workers=1",
                          "server.admit_share=0", port, "server.geo_origin=43.5,-8.25"};
    assert_int_equal(srv_settings_load(NULL, sets, 7, &fx.set, err, sizeof err), OCEAN_OK);
    ocean_result r = srv_daemon_start(&fx.set, &fx.d, err, sizeof err);
    if (r != OCEAN_OK) fprintf(stderr, "%s\n", err);
    assert_int_equal(r, OCEAN_OK);
    char url[64];
    snprintf(url, sizeof url, "ws://127.0.0.1:%d/", srv_daemon_port(fx.d));
    oc_options o;
    oc_options_default(&o);
    o.url = url;
    assert_int_equal(oc_connect(&o, 10000, &fx.ws, err, sizeof err), OCEAN_OK);
    *state = &fx;
    return 0;
}

static int teardown(void **state)
{
    fixture *fx = *state;
    oc_client_destroy(fx->ws);
    srv_daemon_stop(fx->d);
    return 0;
}

/* A host socket on loopback address `from` (127.0.0.x). */
static int host_socket(const char *from)
{
    int fd = socket(AF_INET, SOCK_DGRAM, 0);
    struct sockaddr_in a = {.sin_family = AF_INET};
    inet_pton(AF_INET, from, &a.sin_addr);
    assert_int_equal(bind(fd, (struct sockaddr *)&a, sizeof a), 0);
    return fd;
}

static void send_to(int fd, int port, const proto_buf *b)
{
    struct sockaddr_in to = {.sin_family = AF_INET, .sin_port = htons((uint16_t)port)};
    inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
    assert_int_equal(sendto(fd, proto_buf_data(b), proto_buf_len(b), 0, (struct sockaddr *)&to, sizeof to),
                     (ssize_t)proto_buf_len(b));
}

/* The next datagram within ms, its length (0: none). */
static size_t receive(int fd, uint8_t *buf, size_t cap, int ms)
{
    struct pollfd p = {.fd = fd, .events = POLLIN};
    if (poll(&p, 1, ms) != 1) return 0;
    ssize_t n = recv(fd, buf, cap, 0);
    return n > 0 ? (size_t)n : 0;
}

static void put(proto_buf *b, const cigi_format *f, cigi_packet p)
{
    assert_int_equal(cigi_put(b, f, &p), OCEAN_OK);
}

static cigi_packet ig_control(uint32_t frame)
{
    cigi_packet p = {.kind = CIGI_IG_CONTROL};
    p.u.ig.ig_mode = 1;
    p.u.ig.frame = frame;
    return p;
}

static cigi_packet request(uint32_t id, uint32_t type, uint32_t coord, double lat, double lon, double alt)
{
    cigi_packet p = {.kind = CIGI_HAT_HOT_REQUEST};
    p.u.hat_req = (cigi_hat_hot_request){.id = id, .type = type, .coord = coord, .lat = lat, .lon = lon, .alt = alt};
    return p;
}

/* The four requests of a host frame: Extended at the origin, HAT and HOT
 * 300 m north-east, and one relative to entity 5. */
static const struct {
    uint32_t id, type, coord;
    double lat, lon, alt;
} reqs[] = {
    {11, CIGI_HAT_HOT_EXTENDED, CIGI_COORD_GEODETIC, 43.5, -8.25, 25.0},
    {12, CIGI_HAT, CIGI_COORD_GEODETIC, 43.5019, -8.2474, 3.0},
    {13, CIGI_HOT, CIGI_COORD_GEODETIC, 43.5019, -8.2474, 0},
    {14, CIGI_HAT, CIGI_COORD_ENTITY, 0, 0, 10},
};
#define NREQ 4

/* Sends one host frame in format f, reads the answer, checks it against
 * the WebSocket QUERY at the Start of Frame's time; both datagrams go to
 * pcap when it is not NULL.  Returns the Extended Response's HOT. */
static double ask_and_check(fixture *fx, const cigi_format *f, uint32_t frame, FILE *pcap)
{
    double hot = NAN;
    int fd = host_socket("127.0.0.1");
    proto_buf b;
    proto_buf_init(&b, 0);
    put(&b, f, ig_control(frame));
    for (int i = 0; i < NREQ; i++)
        put(&b, f, request(reqs[i].id, reqs[i].type, reqs[i].coord, reqs[i].lat, reqs[i].lon, reqs[i].alt));
    send_to(fd, fx->port, &b);
    static uint8_t buf[65536];
    size_t n = receive(fd, buf, sizeof buf, 30000);
    assert_true(n > 0);
    if (pcap) {
        test_pcap_datagram(pcap, 0, proto_buf_data(&b), proto_buf_len(&b));
        test_pcap_datagram(pcap, 1, buf, n);
    }
    cigi_format got;
    char why[200];
    assert_int_equal(cigi_format_of(buf, n, &got, why, sizeof why), OCEAN_OK);
    assert_true(got.major == f->major && got.big_endian == f->big_endian);
    cigi_reader rd;
    cigi_reader_init(&rd, buf, n, &got);
    cigi_packet p;
    int done;
    assert_int_equal(cigi_reader_next(&rd, &p, &done, why, sizeof why), OCEAN_OK);
    assert_int_equal(p.kind, CIGI_START_OF_FRAME);
    assert_int_equal(p.u.sof.last_host_frame, frame);
    assert_int_equal(p.u.sof.timestamp_valid, 1);
    /* the answers' sim time: a tick, k / tick_rate, said in 10 us ticks */
    double rate = fx->set.srv.tick_rate, t = round(p.u.sof.timestamp * 1e-5 * rate) / rate;
    /* the same points asked over WebSocket at that time */
    ocean_geo *g;
    assert_int_equal(ocean_geo_create(LAT0, LON0, &g, why, sizeof why), OCEAN_OK);
    double xz[2 * NREQ];
    for (int i = 0; i < 3; i++)
        assert_int_equal(ocean_geo_to_plane(g, reqs[i].lat, reqs[i].lon, &xz[2 * i], &xz[2 * i + 1]), OCEAN_OK);
    ocean_geo_destroy(g);
    oc_query_result q;
    assert_int_equal(oc_client_query(fx->ws, xz, 3, 1, t, 30000, &q), OCEAN_OK);
    for (int i = 0; i < NREQ; i++) {
        assert_int_equal(cigi_reader_next(&rd, &p, &done, why, sizeof why), OCEAN_OK);
        assert_false(done);
        double h = i < 3 ? q.samples[i].height : 0;
        if (reqs[i].type == CIGI_HAT_HOT_EXTENDED) {
            assert_int_equal(p.kind, CIGI_HAT_HOT_XRESPONSE);
            assert_int_equal(p.u.hat_xresp.id, reqs[i].id);
            assert_int_equal(p.u.hat_xresp.valid, 1);
            assert_int_equal(p.u.hat_xresp.frame_lsn, frame & 0xF);
            print_message("t %.4f: extended at the origin: HOT %.6f m (WebSocket %.6f), HAT %.6f, normal %.3f / %.3f "
                          "deg\n", t, p.u.hat_xresp.hot, h, p.u.hat_xresp.hat, p.u.hat_xresp.normal_az,
                          p.u.hat_xresp.normal_el);
            assert_true(p.u.hat_xresp.hot == h);
            hot = p.u.hat_xresp.hot;
            assert_true(p.u.hat_xresp.hat == reqs[i].alt - h);
            /* the normal's elevation: the sea's slope, some degrees off vertical */
            double el = asin(q.samples[i].normal[1]) * 180 / M_PI;
            assert_true(fabs(p.u.hat_xresp.normal_el - el) < 1e-3 && el > 60);
        } else {
            assert_int_equal(p.kind, CIGI_HAT_HOT_RESPONSE);
            assert_int_equal(p.u.hat_resp.id, reqs[i].id);
            if (reqs[i].coord == CIGI_COORD_ENTITY) {
                assert_int_equal(p.u.hat_resp.valid, 0); /* no entity 5 in the daemon's table */
                continue;
            }
            assert_int_equal(p.u.hat_resp.valid, 1);
            assert_int_equal(p.u.hat_resp.type, reqs[i].type == CIGI_HOT);
            assert_true(p.u.hat_resp.height == (reqs[i].type == CIGI_HOT ? h : reqs[i].alt - h));
        }
    }
    assert_int_equal(cigi_reader_next(&rd, &p, &done, why, sizeof why), OCEAN_OK);
    assert_true(done);
    oc_query_result_free(&q);
    proto_buf_free(&b);
    close(fd);
    return hot;
}

static void answers_are_the_queries(void **state)
{
    fixture *fx = *state;
    /* the service is no connection: it takes no slot of server.max_clients */
    srv_hub *hub = srv_daemon_hub(fx->d);
    pthread_mutex_lock(&hub->lock);
    int conns = hub->n_clients;
    pthread_mutex_unlock(&hub->lock);
    assert_int_equal(conns, 1); /* the WebSocket client */
    const cigi_format v3be = {3, 3, 1}, v3le = {3, 3, 0}, v4be = {4, 0, 1}, v4le = {4, 0, 0};
    char path[32];
    FILE *pcap = test_pcap_open(path);
    double hot[2] = {ask_and_check(fx, &v3be, 100, pcap), ask_and_check(fx, &v3le, 101, pcap)};
    ask_and_check(fx, &v4be, 102, NULL);
    ask_and_check(fx, &v4le, 103, NULL);
    /* Debian's tshark reads both CIGI 3.3 exchanges (it has no CIGI 4):
     * the host frames, and answers whose fields are the ones decoded above */
    cJSON *js = test_pcap_tshark(pcap, path);
    assert_int_equal(cJSON_GetArraySize(js), 4);
    for (int k = 0; k < 2; k++) {
        const cJSON *ans = test_pcap_cigi(js, 2 * k + 1), *req = test_pcap_cigi(js, 2 * k);
        const cJSON *sof = cJSON_GetObjectItemCaseSensitive(ans, "cigi.sof");
        const cJSON *x = cJSON_GetObjectItemCaseSensitive(ans, "cigi.hat_hot_ext_response");
        assert_non_null(cJSON_GetObjectItemCaseSensitive(req, "cigi.hat_hot_request"));
        assert_non_null(sof);
        assert_non_null(x);
        assert_string_equal(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(sof, "cigi.sof.last_host_frame_number")),
                            k ? "101" : "100");
        assert_string_equal(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(x, "cigi.hat_hot_ext_response.hat_hot_id")),
                            "11");
        double t_hot = strtod(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(x, "cigi.hat_hot_ext_response.hot")), NULL);
        print_message("tshark: answer %d, HOT %.9g (decoded %.9g)\n", k, t_hot, hot[k]);
        assert_true(fabs(t_hot - hot[k]) <= 1e-9 * fmax(1, fabs(hot[k])));
    }
    cJSON_Delete(js);
    srv_hub *h = srv_daemon_hub(fx->d);
    assert_true(atomic_load(&h->stats.cigi_messages) >= 4);
    assert_true(atomic_load(&h->stats.cigi_answers) >= 16);
}

/* Hostile datagrams: each dropped and counted by its reason; the service
 * answers a good host frame afterwards. */
static void hostile_datagrams_dropped(void **state)
{
    fixture *fx = *state;
    srv_hub *h = srv_daemon_hub(fx->d);
    const cigi_format f = {3, 3, 1};
    uint64_t host0 = atomic_load(&h->stats.cigi_drop_host), frame0 = atomic_load(&h->stats.cigi_drop_framing),
             value0 = atomic_load(&h->stats.cigi_drop_value);
    /* from an address not in server.cigi_hosts (127.0.0.2 is loopback too) */
    int stranger = host_socket("127.0.0.2");
    proto_buf b;
    proto_buf_init(&b, 0);
    put(&b, &f, ig_control(1));
    put(&b, &f, request(1, CIGI_HAT, CIGI_COORD_GEODETIC, 43.5, -8.25, 10));
    send_to(stranger, fx->port, &b);
    uint8_t buf[4096];
    assert_int_equal(receive(stranger, buf, sizeof buf, 300), 0); /* nothing answers it */
    close(stranger);
    int fd = host_socket("127.0.0.1");
    /* framing: no IG Control first, a size past the datagram, 3 bytes */
    static const uint8_t junk1[24] = {24, 24, 3, 0, 0, 0, 0x80, 0};
    uint8_t junk2[40];
    memcpy(junk2, proto_buf_data(&b), 24);
    junk2[24] = 24, junk2[25] = 64;
    static const uint8_t junk3[3] = {1, 24, 3};
    const struct {
        const uint8_t *d;
        size_t n;
    } junk[] = {{junk1, sizeof junk1}, {junk2, sizeof junk2}, {junk3, sizeof junk3}};
    for (size_t i = 0; i < 3; i++) {
        struct sockaddr_in to = {.sin_family = AF_INET, .sin_port = htons((uint16_t)fx->port)};
        inet_pton(AF_INET, "127.0.0.1", &to.sin_addr);
        assert_true(sendto(fd, junk[i].d, junk[i].n, 0, (struct sockaddr *)&to, sizeof to) >= 0);
    }
    /* a NaN latitude: that request is dropped, the frame still answered */
    proto_buf_reset(&b);
    put(&b, &f, ig_control(2));
    put(&b, &f, request(2, CIGI_HAT, CIGI_COORD_GEODETIC, NAN, -8.25, 10));
    send_to(fd, fx->port, &b);
    size_t n;
    int sof = 0;
    /* the junk with an IG Control first (junk2) is answered with a Start of
     * Frame; the NaN frame with a Start of Frame and no response */
    while ((n = receive(fd, buf, sizeof buf, 3000)) > 0) {
        cigi_format g;
        assert_int_equal(cigi_format_of(buf, n, &g, NULL, 0), OCEAN_OK);
        assert_int_equal(buf[0], 101);
        assert_int_equal(n, 24);
        if (++sof == 2) break;
    }
    assert_int_equal(sof, 2);
    print_message("dropped: host %llu, framing %llu, value %llu\n",
                  (unsigned long long)(atomic_load(&h->stats.cigi_drop_host) - host0),
                  (unsigned long long)(atomic_load(&h->stats.cigi_drop_framing) - frame0),
                  (unsigned long long)(atomic_load(&h->stats.cigi_drop_value) - value0));
    assert_int_equal(atomic_load(&h->stats.cigi_drop_host) - host0, 1);
    assert_int_equal(atomic_load(&h->stats.cigi_drop_framing) - frame0, 3);
    assert_int_equal(atomic_load(&h->stats.cigi_drop_value) - value0, 1);
    close(fd);
    proto_buf_free(&b);
    /* and a good frame is answered as before */
    const cigi_format v3 = {3, 3, 1};
    ask_and_check(fx, &v3, 200, NULL);
}

/* The sea at the end of the daemon's timeline: its wind. */
static void timeline_wind(srv_hub *h, double *u10, double *dir)
{
    pthread_mutex_lock(&h->lock);
    const ocean_params *p = h->n_sea_pending ? &h->sea_pending[h->n_sea_pending - 1].params : &h->settings.params;
    *u10 = p->sea.wind_u10;
    *dir = p->sea.wind_dir_deg;
    pthread_mutex_unlock(&h->lock);
}

/* Waits (a deadline, not a speed) for the timeline to end with wind u10
 * toward dir; 1 if it did. */
static int wait_wind(srv_hub *h, double u10, double dir)
{
    double u, d;
    for (int i = 0; i < 1500; i++) {
        timeline_wind(h, &u, &d);
        if (fabs(u - u10) < 1e-3 && fabs(d - dir) < 1e-3) return 1;
        usleep(20000);
    }
    print_message("the timeline ends with wind %.3f m/s toward %.2f deg, not %.3f toward %.2f\n", u, d, u10, dir);
    return 0;
}

static cigi_packet atmosphere(double speed, double from_deg)
{
    cigi_packet p = {.kind = CIGI_ATMOSPHERE_CONTROL};
    p.u.atmosphere.enable = 1;
    p.u.atmosphere.humidity = 60;
    p.u.atmosphere.air_temp = 15;
    p.u.atmosphere.visibility = 20000;
    p.u.atmosphere.wind_h = speed;
    p.u.atmosphere.wind_dir = from_deg;
    p.u.atmosphere.pressure = 1013;
    return p;
}

static cigi_packet weather(double base, double thickness, double speed, double from_deg)
{
    cigi_packet p = {.kind = CIGI_WEATHER_CONTROL};
    cigi_weather *w = &p.u.weather;
    w->enable = 1;
    w->scope = CIGI_SCOPE_GLOBAL;
    w->humidity = 60;
    w->air_temp = 15;
    w->visibility = 20000;
    w->base = base;
    w->thickness = thickness;
    w->wind_h = speed;
    w->wind_dir = from_deg;
    w->pressure = 1013;
    return p;
}

/* A host's surface wind sets the sea through the timeline: Atmosphere
 * Control's wind from the west is a sea wind toward the east (90 deg from
 * north); the same wind every frame changes nothing more; a Weather Control
 * layer aloft is no surface wind, a global one holding 10 m is. */
static void host_wind_sets_the_sea(void **state)
{
    fixture *fx = *state;
    srv_hub *h = srv_daemon_hub(fx->d);
    const cigi_format f = {3, 3, 1};
    int fd = host_socket("127.0.0.1");
    proto_buf b;
    proto_buf_init(&b, 0);
    put(&b, &f, ig_control(300));
    put(&b, &f, atmosphere(14.0, 270.0));
    uint64_t changes0 = atomic_load(&h->stats.sea_changes);
    send_to(fd, fx->port, &b);
    assert_true(wait_wind(h, 14.0, 90.0));
    for (int i = 0; i < 1500 && atomic_load(&h->stats.sea_changes) == changes0; i++) usleep(20000);
    assert_int_equal(atomic_load(&h->stats.sea_changes) - changes0, 1);
    /* a WebSocket client is told the same sea, in force */
    proto_sea sea;
    double eff;
    assert_int_equal(oc_client_sea_state_fetch(fx->ws, 10000, &sea, &eff), OCEAN_OK);
    print_message("WebSocket: wind %.3f m/s toward %.2f deg from t = %.3f s\n", sea.wind_u10, sea.wind_dir_deg, eff);
    assert_true(fabs(sea.wind_u10 - 14.0) < 1e-3 && fabs(sea.wind_dir_deg - 90.0) < 1e-3);
    /* the host says it again, frame after frame: no further change */
    for (int i = 0; i < 10; i++) {
        send_to(fd, fx->port, &b);
        usleep(50000);
    }
    usleep(500000);
    assert_int_equal(atomic_load(&h->stats.sea_changes) - changes0, 1);
    pthread_mutex_lock(&h->lock);
    int pending = h->n_sea_pending;
    pthread_mutex_unlock(&h->lock);
    assert_int_equal(pending, 0);
    /* a layer from 1000 m up: winds aloft, ignored */
    uint64_t ignored0 = atomic_load(&h->stats.cigi_ignored);
    proto_buf_reset(&b);
    put(&b, &f, ig_control(301));
    put(&b, &f, weather(1000, 500, 30.0, 0));
    send_to(fd, fx->port, &b);
    for (int i = 0; i < 300 && atomic_load(&h->stats.cigi_ignored) == ignored0; i++) usleep(20000);
    assert_true(atomic_load(&h->stats.cigi_ignored) > ignored0);
    double u, d;
    timeline_wind(h, &u, &d);
    assert_true(fabs(u - 14.0) < 1e-3);
    /* a global layer from the sea up to 50 m, wind from the north: toward
     * the south (180 deg), 9 m/s; in CIGI 3.3 of the other byte order */
    const cigi_format le = {3, 3, 0};
    proto_buf_reset(&b);
    put(&b, &le, ig_control(302));
    put(&b, &le, weather(0, 50, 9.0, 0));
    send_to(fd, fx->port, &b);
    assert_true(wait_wind(h, 9.0, 180.0));
    close(fd);
    proto_buf_free(&b);
}

/* The largest foam QUERY answers on a 50 x 50 lattice, 3 m apart, at the
 * latest tick. */
static double query_foam(fixture *fx)
{
    enum { K = 50 };
    static double xz[2 * K * K];
    for (int i = 0; i < K * K; i++) xz[2 * i] = 3.0 * (i % K), xz[2 * i + 1] = 3.0 * (i / K);
    oc_query_result qr;
    assert_int_equal(oc_client_query(fx->ws, xz, K * K, 0, 0, 60000, &qr), OCEAN_OK);
    double most = 0;
    for (uint32_t i = 0; i < qr.count; i++) most = fmax(most, qr.samples[i].foam);
    oc_query_result_free(&qr);
    return most;
}

/* Waits (a deadline) for the sea in force to have whitecaps on or off,
 * nothing pending; 1 if it did. */
static int wait_whitecaps(srv_hub *h, int on)
{
    for (int i = 0; i < 1500; i++) {
        pthread_mutex_lock(&h->lock);
        int now = h->settings.params.sea.whitecaps, pending = h->n_sea_pending || h->sea_applying;
        pthread_mutex_unlock(&h->lock);
        if (now == on && !pending) return 1;
        usleep(20000);
    }
    return 0;
}

/* A host's Maritime Surface Conditions Control of global scope with
 * whitecaps off enters the sea through the timeline, as its wind does: a
 * WebSocket client is told the sea has none (SEA_STATE flags) and every
 * QUERY answers foam 0; turned on again, the whitecaps come back. */
static void host_whitecaps_set_the_sea(void **state)
{
    fixture *fx = *state;
    srv_hub *h = srv_daemon_hub(fx->d);
    int fd = host_socket("127.0.0.1");
    double before = query_foam(fx);
    for (int on = 0; on <= 1; on++) {
        cigi_packet pk = {.kind = CIGI_MARITIME_CONTROL};
        pk.u.maritime = (cigi_maritime_control){.enable = 1, .whitecaps = (uint8_t)on, .scope = CIGI_SCOPE_GLOBAL,
                                                .water_temp = 15, .clarity = 80};
        const cigi_format f = {3, 3, 1};
        proto_buf b;
        proto_buf_init(&b, 0);
        put(&b, &f, ig_control(600 + (uint32_t)on));
        put(&b, &f, pk);
        send_to(fd, fx->port, &b);
        proto_buf_free(&b);
        assert_true(wait_whitecaps(h, on));
        proto_sea sea;
        double eff;
        assert_int_equal(oc_client_sea_state_fetch(fx->ws, 10000, &sea, &eff), OCEAN_OK);
        double most = query_foam(fx);
        print_message("whitecaps %s from t = %.3f s (SEA_STATE flags %u): the largest foam QUERY answers %.3f "
                      "(%.3f before)\n", on ? "on" : "off", eff, sea.flags, most, before);
        assert_int_equal(sea.flags & PROTO_SEA_NO_WHITECAPS, on ? 0 : PROTO_SEA_NO_WHITECAPS);
        if (on) assert_true(most > 0);
        else assert_true(most == 0);
    }
    assert_true(before > 0);
    close(fd);
}

/* One host message: IG Control and the packets given, sent; its answer
 * read into buf (asserted to come), its length returned. */
static size_t exchange(fixture *fx, int fd, const cigi_format *f, uint32_t frame, const cigi_packet *pk, int n,
                       uint8_t *buf, size_t cap)
{
    proto_buf b;
    proto_buf_init(&b, 0);
    put(&b, f, ig_control(frame));
    for (int i = 0; i < n; i++) put(&b, f, pk[i]);
    send_to(fd, fx->port, &b);
    proto_buf_free(&b);
    size_t got = receive(fd, buf, cap, 30000);
    assert_true(got > 0);
    return got;
}

/* The Extended Responses of an answer, in order, into x (at most n). */
static int xresponses(const uint8_t *buf, size_t len, cigi_hat_hot_xresponse *x, int n)
{
    cigi_format f;
    assert_int_equal(cigi_format_of(buf, len, &f, NULL, 0), OCEAN_OK);
    cigi_reader rd;
    cigi_reader_init(&rd, buf, len, &f);
    int k = 0, done = 0;
    cigi_packet p;
    while (cigi_reader_next(&rd, &p, &done, NULL, 0) == OCEAN_OK && !done)
        if (p.kind == CIGI_HAT_HOT_XRESPONSE && k < n) x[k++] = p.u.hat_xresp;
    return k;
}

static cigi_packet entity_at(cigi_kind kind, uint32_t id, uint32_t state, double lat, double lon, double yaw)
{
    cigi_packet p = {.kind = kind};
    p.u.entity = (cigi_entity){.id = id, .state = state, .clamp = CIGI_CLAMP_CONFORMAL, .lat = lat, .lon = lon,
                               .yaw = yaw};
    return p;
}

/* A host's entity enters the daemon's table (Entity Control in 3.3, Entity
 * Position in 4.0): a request 50 m ahead of a ship heading east and 10 m
 * up is answered as the geodetic request at that point, in the same
 * message (HOT, HAT and normal); destroyed, its requests are Valid = 0;
 * an aircraft the host repositions is answered where the host put it. */
static void entity_relative_requests(void **state)
{
    fixture *fx = *state;
    const cigi_format fmts[] = {{3, 3, 1}, {4, 0, 0}};
    ocean_geo *g;
    assert_int_equal(ocean_geo_create(LAT0, LON0, &g, NULL, 0), OCEAN_OK);
    int fd = host_socket("127.0.0.1");
    static uint8_t buf[65536];
    for (int v = 0; v < 2; v++) {
        const cigi_format *f = &fmts[v];
        uint32_t id = 7 + (uint32_t)v;
        double lat = 43.51, lon = -8.25 + 0.01 * v, x, z, plat, plon;
        cigi_packet pk[2];
        pk[0] = entity_at(f->major == 3 ? CIGI_ENTITY_CONTROL : CIGI_ENTITY_POSITION, id, CIGI_ENTITY_ACTIVE, lat,
                          lon, 90.0);
        exchange(fx, fd, f, 400 + (uint32_t)v, pk, 1, buf, sizeof buf);
        assert_int_equal(ocean_geo_to_plane(g, lat, lon, &x, &z), OCEAN_OK);
        assert_int_equal(ocean_geo_to_geodetic(g, x, z + 50.0, &plat, &plon), OCEAN_OK);
        pk[0] = request(21, CIGI_HAT_HOT_EXTENDED, CIGI_COORD_ENTITY, 50.0, 0.0, -10.0);
        pk[0].u.hat_req.entity = id;
        pk[1] = request(22, CIGI_HAT_HOT_EXTENDED, CIGI_COORD_GEODETIC, plat, plon, 10.0);
        size_t n = exchange(fx, fd, f, 410 + (uint32_t)v, pk, 2, buf, sizeof buf);
        cigi_hat_hot_xresponse r[2];
        assert_int_equal(xresponses(buf, n, r, 2), 2);
        print_message("CIGI %d: entity %u + 50 m ahead: HOT %.6f HAT %.6f normal %.4f/%.4f; geodetic: HOT %.6f HAT "
                      "%.6f normal %.4f/%.4f\n", f->major, id, r[0].hot, r[0].hat, r[0].normal_az, r[0].normal_el,
                      r[1].hot, r[1].hat, r[1].normal_az, r[1].normal_el);
        assert_true(r[0].valid && r[1].valid);
        assert_true(fabs(r[0].hot - r[1].hot) < 1e-5 && fabs(r[0].hat - r[1].hat) < 1e-5);
        assert_true(fabs(r[0].normal_el - r[1].normal_el) < 1e-3);
        assert_true(fabs(r[0].hat - (10.0 - r[0].hot)) < 1e-9);
        /* destroyed: out of the table, its requests Valid = 0 */
        pk[0] = entity_at(CIGI_ENTITY_CONTROL, id, CIGI_ENTITY_DESTROYED, lat, lon, 90.0);
        exchange(fx, fd, f, 420 + (uint32_t)v, pk, 1, buf, sizeof buf);
        pk[0] = request(23, CIGI_HAT_HOT_EXTENDED, CIGI_COORD_ENTITY, 50.0, 0.0, -10.0);
        pk[0].u.hat_req.entity = id;
        n = exchange(fx, fd, f, 430 + (uint32_t)v, pk, 1, buf, sizeof buf);
        assert_int_equal(xresponses(buf, n, r, 1), 1);
        assert_int_equal(r[0].valid, 0);
    }
    /* an unclamped entity: an aircraft at 3000 m, which the host then puts
     * 44 km north at once (a reposition, faster than anything flies): its
     * requests follow it there */
    const cigi_format *f = &fmts[0];
    cigi_packet pk[2];
    pk[0] = entity_at(CIGI_ENTITY_CONTROL, 30, CIGI_ENTITY_ACTIVE, 43.52, -8.25, 0.0);
    pk[0].u.entity.clamp = CIGI_CLAMP_NONE;
    pk[0].u.entity.alt = 3000.0;
    exchange(fx, fd, f, 440, pk, 1, buf, sizeof buf);
    pk[0].u.entity.lat = 43.9;
    exchange(fx, fd, f, 441, pk, 1, buf, sizeof buf);
    pk[0] = request(31, CIGI_HAT_HOT_EXTENDED, CIGI_COORD_ENTITY, 0.0, 0.0, 0.0);
    pk[0].u.hat_req.entity = 30;
    pk[1] = request(32, CIGI_HAT_HOT_EXTENDED, CIGI_COORD_GEODETIC, 43.9, -8.25, 3000.0);
    size_t n = exchange(fx, fd, f, 442, pk, 2, buf, sizeof buf);
    cigi_hat_hot_xresponse r[2];
    assert_int_equal(xresponses(buf, n, r, 2), 2);
    print_message("aircraft 30 repositioned: HAT %.6f (geodetic %.6f)\n", r[0].hat, r[1].hat);
    assert_true(r[0].valid && r[1].valid && fabs(r[0].hat - r[1].hat) < 1e-5 && r[0].hat > 2990);
    assert_int_equal(srv_entities_count(srv_daemon_hub(fx->d)->entities), 1);
    ocean_geo_destroy(g);
    close(fd);
}

/* Environmental Conditions Requests: the maritime one is answered with a
 * Maritime Surface Conditions Response (the sea's mean level 0, the water
 * a global Maritime Surface Conditions Control set); a weather one, no
 * ocean's, is not answered; in CIGI 3.3 and 4.0. */
static void environmental_requests(void **state)
{
    fixture *fx = *state;
    const cigi_format fmts[] = {{3, 3, 1}, {4, 0, 0}};
    int fd = host_socket("127.0.0.1");
    static uint8_t buf[65536];
    for (int v = 0; v < 2; v++) {
        cigi_packet pk[3] = {{.kind = CIGI_MARITIME_CONTROL}, {.kind = CIGI_ENV_REQUEST},
                             {.kind = CIGI_ENV_REQUEST}};
        pk[0].u.maritime = (cigi_maritime_control){.enable = 1, .whitecaps = 1, .scope = CIGI_SCOPE_GLOBAL,
                                                   .water_temp = 14.5 + v, .clarity = 80};
        pk[1].u.env_req = (cigi_env_request){.type = CIGI_ENV_MARITIME, .id = 9 + (uint32_t)v, .lat = LAT0,
                                             .lon = LON0};
        pk[2].u.env_req = (cigi_env_request){.type = CIGI_ENV_WEATHER, .id = 20, .lat = LAT0, .lon = LON0};
        size_t n = exchange(fx, fd, &fmts[v], 500 + (uint32_t)v, pk, 3, buf, sizeof buf);
        cigi_format f;
        assert_int_equal(cigi_format_of(buf, n, &f, NULL, 0), OCEAN_OK);
        cigi_reader rd;
        cigi_reader_init(&rd, buf, n, &f);
        cigi_packet p;
        int done = 0, responses = 0;
        while (cigi_reader_next(&rd, &p, &done, NULL, 0) == OCEAN_OK && !done) {
            if (p.kind != CIGI_MARITIME_RESPONSE) continue;
            responses++;
            const cigi_maritime_response *r = &p.u.maritime_resp;
            print_message("CIGI %d: Maritime Surface Conditions Response %u: height %g m, water %g C, clarity %g %%\n",
                          f.major, r->id, r->surface_height, r->water_temp, r->clarity);
            assert_int_equal(r->id, 9 + v);
            assert_true(r->surface_height == 0 && r->water_temp == 14.5 + v && r->clarity == 80);
        }
        assert_int_equal(responses, 1);
    }
    close(fd);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(answers_are_the_queries),
        cmocka_unit_test(hostile_datagrams_dropped),
        cmocka_unit_test(entity_relative_requests),
        cmocka_unit_test(environmental_requests),
        cmocka_unit_test(host_wind_sets_the_sea),
        cmocka_unit_test(host_whitecaps_set_the_sea),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
