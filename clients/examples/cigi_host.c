/*
 * cigi_host.c - example: a simulator host that asks oceand for the sea over
 * CIGI, as it would ask an image generator.
 *
 * Every frame (60 Hz) it sends one host message, as a host does: IG
 * Control; Entity Control for its ship (entity 1, clamped to the sea,
 * 120 m x 16 m) and its aircraft (entity 2); a HOT request under each of
 * the ship's four hull points (bow, stern, port, starboard), given as
 * offsets in the ship's frame; and a HAT/HOT Extended request under the
 * aircraft's radar altimeter.  It reads the answers as they come and
 * prints, twice a second, the ship's heave, pitch and roll from its four
 * points, the aircraft's height above the waves and how many frames had
 * their answers; then a summary.  The daemon needs server.cigi_port (and,
 * on another machine, this host's address in server.cigi_hosts).
 *
 *   cigi_host 127.0.0.1:8741 [--lat 43.5 --lon -8.25] [--seconds 10]
 *
 * Build against the installed libraries:
 *   cc cigi_host.c $(pkg-config --cflags --libs oceansim) -lm
 */
#include <arpa/inet.h>
#include <errno.h>
#include <math.h>
#include <netdb.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include <oceand/cigi.h>

#define HULL_L 120.0
#define HULL_B 16.0
#define N_HULL 4

typedef struct opts {
    const char *to;
    double lat, lon, heading, alt, seconds, rate;
    int version, little;
} opts;

typedef struct stats {
    long frames, answered, valid, invalid;
    double heave, pitch, roll, hat;     /* the last answer's */
} stats;

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int num(const char *opt, const char *v, double lo, double hi, double *out)
{
    char *end;
    errno = 0;
    double d = v ? strtod(v, &end) : NAN;
    if (!v || end == v || *end || errno || !isfinite(d) || d < lo || d > hi) {
        fprintf(stderr, "cigi_host: option '%s': '%s' is not a number in [%g, %g]\n", opt, v ? v : "", lo, hi);
        return -1;
    }
    *out = d;
    return 0;
}

static int parse(int argc, char **argv, opts *o)
{
    *o = (opts){.lat = 43.5, .lon = -8.25, .heading = 30, .alt = 300, .seconds = 10, .rate = 60, .version = 3};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        double d;
        int bad = 0, arg = 1;
        if (!strcmp(a, "--lat")) bad = num(a, v, -90, 90, &o->lat);
        else if (!strcmp(a, "--lon")) bad = num(a, v, -180, 180, &o->lon);
        else if (!strcmp(a, "--heading")) bad = num(a, v, -360, 360, &o->heading);
        else if (!strcmp(a, "--altitude")) bad = num(a, v, 1, 20000, &o->alt);
        else if (!strcmp(a, "--seconds")) bad = num(a, v, 0.1, 86400, &o->seconds);
        else if (!strcmp(a, "--rate")) bad = num(a, v, 1, 240, &o->rate);
        else if (!strcmp(a, "--version")) bad = num(a, v, 3, 4, &d), o->version = (int)d;
        else if (!strcmp(a, "--little-endian")) o->little = 1, arg = 0;
        else if (a[0] != '-' && !o->to) o->to = a, arg = 0;
        else {
            fprintf(stderr, "usage: cigi_host HOST:PORT [--lat DEG] [--lon DEG] [--heading DEG] [--altitude M]\n"
                            "       [--seconds S] [--rate HZ] [--version 3|4] [--little-endian]\n");
            return -1;
        }
        if (bad) return -1;
        i += arg;
    }
    if (!o->to) {
        fprintf(stderr, "cigi_host: give the daemon's HOST:PORT (server.cigi_port)\n");
        return -1;
    }
    return 0;
}

static int open_socket(const char *to, struct sockaddr_storage *addr, socklen_t *len)
{
    char host[256];
    const char *colon = strrchr(to, ':');
    if (!colon || colon == to || (size_t)(colon - to) >= sizeof host) {
        fprintf(stderr, "cigi_host: '%s' is not HOST:PORT\n", to);
        return -1;
    }
    memcpy(host, to, (size_t)(colon - to));
    host[colon - to] = 0;
    struct addrinfo hints = {.ai_socktype = SOCK_DGRAM}, *ai;
    int e = getaddrinfo(host, colon + 1, &hints, &ai);
    if (e) {
        fprintf(stderr, "cigi_host: %s: %s\n", to, gai_strerror(e));
        return -1;
    }
    int fd = socket(ai->ai_family, SOCK_DGRAM, 0);
    memcpy(addr, ai->ai_addr, ai->ai_addrlen);
    *len = ai->ai_addrlen;
    freeaddrinfo(ai);
    return fd;
}

enum { SHIP = 1, AIRCRAFT = 2 };

/* Entity `id` where the options put it: CIGI 3 in one Entity Control,
 * CIGI 4 in Entity Control (its state) and Entity Position. */
static void put_entity(proto_buf *b, const cigi_format *f, uint32_t id, const opts *o)
{
    cigi_entity e = {.id = id, .state = CIGI_ENTITY_ACTIVE, .lat = o->lat, .lon = o->lon, .yaw = o->heading};
    e.clamp = id == SHIP ? CIGI_CLAMP_CONFORMAL : CIGI_CLAMP_NONE;
    e.alt = id == SHIP ? 0 : o->alt;
    cigi_packet p = {.kind = CIGI_ENTITY_CONTROL, .u.entity = e};
    cigi_put(b, f, &p);
    if (f->major == 4) {
        p.kind = CIGI_ENTITY_POSITION;
        cigi_put(b, f, &p);
    }
}

/* One host frame: IG Control, the two entities, four HOT requests (ids
 * 1-4) at the hull points relative to the ship, an Extended request (id
 * 5) under the aircraft. */
static void frame_message(proto_buf *b, const cigi_format *f, uint32_t frame, const opts *o)
{
    cigi_packet p = {.kind = CIGI_IG_CONTROL};
    p.u.ig.ig_mode = 1;
    p.u.ig.frame = frame;
    cigi_put(b, f, &p);
    put_entity(b, f, SHIP, o);
    put_entity(b, f, AIRCRAFT, o);
    /* x forward, y right of the ship */
    const double off[N_HULL][2] = {{HULL_L / 2, 0}, {-HULL_L / 2, 0}, {0, -HULL_B / 2}, {0, HULL_B / 2}};
    for (int i = 0; i < N_HULL; i++) {
        cigi_packet q = {.kind = CIGI_HAT_HOT_REQUEST};
        q.u.hat_req = (cigi_hat_hot_request){.id = (uint32_t)i + 1, .type = CIGI_HOT, .coord = CIGI_COORD_ENTITY,
                                             .entity = SHIP, .lat = off[i][0], .lon = off[i][1]};
        cigi_put(b, f, &q);
    }
    cigi_packet a = {.kind = CIGI_HAT_HOT_REQUEST};
    a.u.hat_req = (cigi_hat_hot_request){.id = 5, .type = CIGI_HAT_HOT_EXTENDED, .coord = CIGI_COORD_ENTITY,
                                         .entity = AIRCRAFT};
    cigi_put(b, f, &a);
}

/* An IG message: the ship's attitude from its four HOTs, the aircraft's HAT. */
static void read_answer(const uint8_t *d, size_t n, stats *st)
{
    cigi_format f;
    if (cigi_format_of(d, n, &f, NULL, 0) != OCEAN_OK) return;
    cigi_reader r;
    cigi_reader_init(&r, d, n, &f);
    double hot[N_HULL + 1] = {0};
    int got = 0, done = 0;
    cigi_packet p;
    while (cigi_reader_next(&r, &p, &done, NULL, 0) == OCEAN_OK && !done) {
        if (p.kind == CIGI_HAT_HOT_RESPONSE && p.u.hat_resp.id >= 1 && p.u.hat_resp.id <= N_HULL) {
            st->valid += p.u.hat_resp.valid, st->invalid += !p.u.hat_resp.valid;
            hot[p.u.hat_resp.id - 1] = p.u.hat_resp.height, got++;
        } else if (p.kind == CIGI_HAT_HOT_XRESPONSE && p.u.hat_xresp.id == 5) {
            st->valid += p.u.hat_xresp.valid, st->invalid += !p.u.hat_xresp.valid;
            st->hat = p.u.hat_xresp.hat;
        }
    }
    st->answered++;
    if (got == N_HULL) {
        st->heave = 0.25 * (hot[0] + hot[1] + hot[2] + hot[3]);
        st->pitch = atan2(hot[0] - hot[1], HULL_L) * 180 / M_PI;  /* bow up positive */
        st->roll = atan2(hot[3] - hot[2], HULL_B) * 180 / M_PI;   /* starboard up positive */
    }
}

int main(int argc, char **argv)
{
    opts o;
    if (parse(argc, argv, &o)) return 2;
    struct sockaddr_storage to;
    socklen_t tolen;
    int fd = open_socket(o.to, &to, &tolen);
    if (fd < 0) return 1;
    cigi_format f = {(uint8_t)o.version, o.version == 3 ? 3 : 0, (uint8_t)!o.little};
    stats st = {0};
    proto_buf b;
    proto_buf_init(&b, 0);
    printf("%7s %9s %9s %9s %11s %9s\n", "t_s", "heave_m", "pitch_deg", "roll_deg", "radar_alt_m", "answered");
    double t0 = now_s(), next = t0, print = t0 + 0.5;
    while (now_s() - t0 < o.seconds) {
        if (now_s() >= next) {
            proto_buf_reset(&b);
            frame_message(&b, &f, (uint32_t)++st.frames, &o);
            if (sendto(fd, proto_buf_data(&b), proto_buf_len(&b), 0, (struct sockaddr *)&to, tolen) < 0)
                fprintf(stderr, "cigi_host: send: %s\n", strerror(errno));
            next += 1.0 / o.rate;
        }
        struct pollfd pf = {.fd = fd, .events = POLLIN};
        int wait = (int)(fmax(0, fmin(next, print) - now_s()) * 1000);
        if (poll(&pf, 1, wait) == 1) {
            uint8_t buf[4096];
            ssize_t n = recv(fd, buf, sizeof buf, 0);
            if (n > 0) read_answer(buf, (size_t)n, &st);
        }
        if (now_s() >= print) {
            printf("%7.2f %9.3f %9.2f %9.2f %11.2f %5ld/%ld\n", now_s() - t0, st.heave, st.pitch, st.roll, st.hat,
                   st.answered, st.frames);
            print += 0.5;
        }
    }
    printf("# %ld host frames at %.0f Hz, %ld answered; %ld answers valid, %ld not\n", st.frames, o.rate,
           st.answered, st.valid, st.invalid);
    proto_buf_free(&b);
    close(fd);
    return st.answered > 0 && st.invalid == 0 ? 0 : 1;
}
