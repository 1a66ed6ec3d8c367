/*
 * srv_record.c - camera-path recordings (format: server/RECORDING.md).
 */
#include "srv_record.h"

#include <errno.h>
#include <fcntl.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

struct srv_record {
    FILE *f;
    double last_flush;
    int failed;
    int err_no;                   /* errno of the first failed write, flush or close */
    char path[1024];
    atomic_uint_fast64_t *used;   /* bytes written by every recording of the run */
    uint64_t quota;
};

/* Longest report line srv_record_format writes: 4 %.17g (24 chars each),
 * 7 %.9g (16), 2 %u (5), 12 commas and a newline. */
#define LINE_MAX_BYTES 320

/* Names tried for one recording: client-<id>-<time>.csv, then that with a
 * random 32-bit suffix (-<8 hex digits>), up to 99 times. */
#define SRV_RECORD_NAME_TRIES 100

static double mono(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

ocean_result srv_record_open(const char *dir, uint32_t client_id, const char *scene,
                             srv_record **out, char *path, size_t pathlen, char *msg, size_t msglen)
{
    *out = NULL;
    if (mkdir(dir, 0755) != 0 && errno != EEXIST) {
        snprintf(msg, msglen, "cannot create recording directory %s: %s", dir, strerror(errno));
        return OCEAN_EIO;
    }
    /* A new file, never an existing name: fopen "w" followed a symlink
     * planted at the predictable name (overwriting whatever it pointed at
     * that the daemon could write) and truncated another run's recording
     * of the same client id and second.  O_EXCL fails on any existing
     * name, a symlink included (dangling or not).  A taken name moves on to
     * one with a random suffix, as mkstemp does: a fixed sequence of
     * alternatives (-1 .. -99) could be filled in advance by anyone who
     * can write the directory, refusing every later recording of that
     * client id and second. */
    long long now = (long long)time(NULL);
    char name[1024];
    int fd = -1, err = 0;
    for (int k = 0; k < SRV_RECORD_NAME_TRIES && fd < 0; k++) {
        uint32_t tag = 0;
        if (k > 0 && getrandom(&tag, sizeof tag, 0) != (ssize_t)sizeof tag) {
            err = errno;
            break;
        }
        int len = k == 0 ? snprintf(name, sizeof name, "%s/client-%u-%lld.csv", dir, client_id, now)
                         : snprintf(name, sizeof name, "%s/client-%u-%lld-%08x.csv", dir, client_id, now, tag);
        if (len < 0 || (size_t)len >= sizeof name) { /* a cut name could be another file's */
            snprintf(msg, msglen, "cannot create a recording in %.200s...: the path is over %zu bytes; "
                     "choose a shorter server.record_dir", dir, sizeof name - 1);
            return OCEAN_EIO;
        }
        fd = open(name, O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
        err = errno;
        if (fd < 0 && err != EEXIST) break;
    }
    if (fd < 0) {
        if (err == EEXIST)
            snprintf(msg, msglen, "cannot create a recording for client %u in %s: client-%u-%lld.csv and "
                     "%d names with a random suffix all exist; move old recordings out of server.record_dir",
                     client_id, dir, client_id, now, SRV_RECORD_NAME_TRIES - 1);
        else
            snprintf(msg, msglen, "cannot create recording %s: %s%s", name, strerror(err),
                     err == ELOOP ? " (a symbolic link: recordings are never written through one)" : "");
        return OCEAN_EIO;
    }
    srv_record *r = calloc(1, sizeof *r);
    FILE *f = r ? fdopen(fd, "w") : NULL;
    if (!f) {
        err = r ? errno : ENOMEM;
        close(fd);
        unlink(name);
        free(r);
        snprintf(msg, msglen, "cannot open recording %s: %s", name, strerror(err));
        return err == ENOMEM ? OCEAN_ENOMEM : OCEAN_EIO;
    }
    r->f = f;
    snprintf(r->path, sizeof r->path, "%s", name);
    fprintf(r->f, "# oceand camera path v1\n# client %u scene %s\n"
                  "t,x,y,z,vx,vy,vz,yaw_deg,pitch_deg,roll_deg,fov_y_deg,viewport_w,viewport_h\n",
            client_id, scene && *scene ? scene : "-");
    r->last_flush = mono();
    if (path && pathlen) snprintf(path, pathlen, "%s", name);
    *out = r;
    return OCEAN_OK;
}

int srv_record_format(FILE *f, double t, const proto_camera *c)
{
    return fprintf(f, "%.17g,%.17g,%.17g,%.17g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%u,%u\n", t,
                   c->pos[0], c->pos[1], c->pos[2], (double)c->vel[0], (double)c->vel[1],
                   (double)c->vel[2], (double)c->yaw_deg, (double)c->pitch_deg,
                   (double)c->roll_deg, (double)c->fov_y_deg, c->viewport_w, c->viewport_h);
}

void srv_record_set_quota(srv_record *r, atomic_uint_fast64_t *used, uint64_t quota)
{
    if (!r) return;
    r->used = used;
    r->quota = quota;
}

/* One write of n bytes done: counted, flushed once a second; a failure
 * stops the recording (OCEAN_EIO, once). */
static ocean_result wrote(srv_record *r, int n)
{
    int bad = n < 0;
    if (bad) r->err_no = errno;
    if (!bad && r->used) atomic_fetch_add(r->used, (uint64_t)n);
    double now = mono();
    if (!bad && now - r->last_flush >= 1.0) {
        bad = fflush(r->f) != 0;
        if (bad) r->err_no = errno;
        r->last_flush = now;
    }
    if (bad) {
        r->failed = 1;
        return OCEAN_EIO;
    }
    return OCEAN_OK;
}

const char *srv_record_why(const srv_record *r, char *buf, size_t n)
{
    if (!r) return "";
    snprintf(buf, n, "%s: %s", r->path, r->err_no ? strerror(r->err_no) : "write error");
    return buf;
}

ocean_result srv_record_camera(srv_record *r, double t, const proto_camera *cam)
{
    if (!r || r->failed) return OCEAN_OK;
    if (r->used && atomic_load(r->used) + LINE_MAX_BYTES > r->quota) {
        r->failed = 1;
        fflush(r->f);
        return OCEAN_ETOOBIG;
    }
    return wrote(r, srv_record_format(r->f, t, cam));
}

ocean_result srv_record_mode(srv_record *r, double t, int replay)
{
    if (!r || r->failed) return OCEAN_OK;
    if (r->used && atomic_load(r->used) + LINE_MAX_BYTES > r->quota) {
        r->failed = 1;
        fflush(r->f);
        return OCEAN_ETOOBIG;
    }
    return wrote(r, fprintf(r->f, "# subscribed at %.17g: mode %s\n", t, replay ? "replay" : "live"));
}

ocean_result srv_record_close(srv_record *r, char *why, size_t whylen)
{
    if (why && whylen) why[0] = 0;
    if (!r) return OCEAN_OK;
    /* the buffered tail is written here: a full disk shows at fclose, and
     * a short recording would otherwise be left empty with nothing said */
    int bad = r->f && fclose(r->f) != 0;
    if (bad && !r->err_no) r->err_no = errno;
    ocean_result res = bad || (r->failed && r->err_no) ? OCEAN_EIO : OCEAN_OK;
    if (res != OCEAN_OK && why) srv_record_why(r, why, whylen);
    free(r);
    return res;
}
