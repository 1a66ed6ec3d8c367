/*
 * oc_path.c - camera path files (see oc_path.h).
 */
#include "oc_path.h"
#include "conf.h"
#include "ocean_time.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/* Room for a line as messages quote it (conf_show_text: at most
 * CONF_SHOW_MAX display bytes, a 4-byte escape each, and "..."): a path
 * file is text a user may not have written, and what a message quotes is
 * printed to a terminal. */
#define SHOWN (CONF_SHOW_MAX * 4 + 16)

static const char *const FIELD[13] = {"t",       "x",         "y",        "z",         "vx",
                                      "vy",      "vz",        "yaw_deg",  "pitch_deg", "roll_deg",
                                      "fov_y_deg", "viewport_w", "viewport_h"};
static const char *const SHORT[13] = {NULL, NULL, NULL, NULL, NULL, NULL, NULL,
                                      "yaw", "pitch", "roll", "fov", NULL, NULL};

/* Checks a header line (spaces removed); returns its column count (11 or
 * 13) or 0. */
static int header_columns(const char *h)
{
    int col = 0;
    const char *p = h;
    while (col < 13) {
        const char *e = strchr(p, ',');
        size_t n = e ? (size_t)(e - p) : strlen(p);
        int ok = strlen(FIELD[col]) == n && !strncmp(p, FIELD[col], n);
        if (!ok && SHORT[col])
            ok = strlen(SHORT[col]) == n && !strncmp(p, SHORT[col], n);
        if (!ok)
            return 0;
        col++;
        if (!e)
            break;
        p = e + 1;
    }
    if (col == 13 && strchr(p, ','))
        return 0;
    return col == 11 || col == 13 ? col : 0;
}

static char *trim(char *s)
{
    while (*s == ' ' || *s == '\t')
        s++;
    size_t n = strlen(s);
    while (n && (s[n - 1] == ' ' || s[n - 1] == '\t' || s[n - 1] == '\r'))
        s[--n] = 0;
    return s;
}

void oc_path_destroy(oc_path *p)
{
    if (!p)
        return;
    free(p->pts);
    free(p);
}

/* x as the float a CAMERA field carries; a value past float's range is
 * left as it is (converting it is undefined) for check_point to refuse. */
static double as_wire_float(double x)
{
    return fabs(x) <= 1e30 ? (double)(float)x : x;
}

/* Checks one parsed point; returns a static reason or NULL. */
static const char *check_point(const oc_path_point *q, int *field)
{
    const double v[11] = {q->t, q->pos[0], q->pos[1], q->pos[2], q->vel[0], q->vel[1], q->vel[2],
                          q->yaw_deg, q->pitch_deg, q->roll_deg, q->fov_deg};
    for (int i = 0; i < 11; i++)
        if (!isfinite(v[i])) {
            *field = i;
            return "is not a finite number";
        }
    *field = 0;
    if (!ocean_time_ok(q->t))
        return "beyond the time limit +-134217728 s (OCEAN_TIME_MAX)";
    /* the CAMERA bounds (PROTOCOL.md), which the daemon accepts and so
     * records: a recording must replay */
    *field = 1;
    if (fabs(q->pos[0]) > OC_PATH_MAX_XZ)
        return "beyond +-1e10 m (CAMERA x)";
    *field = 2;
    if (fabs(q->pos[1]) > OC_PATH_MAX_Y)
        return "beyond +-1e7 m (CAMERA y)";
    *field = 3;
    if (fabs(q->pos[2]) > OC_PATH_MAX_XZ)
        return "beyond +-1e10 m (CAMERA z)";
    for (int i = 0; i < 3; i++)
        if (fabs(q->vel[i]) > 1e5) {
            *field = 4 + i;
            return "beyond +-1e5 m/s";
        }
    /* CAMERA's orientation bounds (PROTOCOL.md): +-3600 was read, and such a
     * path failed only when replay encoded it */
    static const double most[3] = {360, 90, 180};
    static const char *const why[3] = {"beyond +-360 degrees (CAMERA yaw)", "beyond +-90 degrees (CAMERA pitch)",
                                       "beyond +-180 degrees (CAMERA roll)"};
    for (int i = 0; i < 3; i++) {
        double a = i == 0 ? q->yaw_deg : i == 1 ? q->pitch_deg : q->roll_deg;
        if (fabs(a) > most[i]) {
            *field = 7 + i;
            return why[i];
        }
    }
    *field = 10;
    if (!(q->fov_deg > 0 && q->fov_deg < 180))
        return "outside (0, 180) degrees";
    *field = 11;
    if (q->viewport_w < 1 || q->viewport_w > 16384)
        return "outside 1..16384";
    *field = 12;
    if (q->viewport_h < 1 || q->viewport_h > 16384)
        return "outside 1..16384";
    return NULL;
}

ocean_result oc_path_parse(const char *text, size_t len, const char *name, oc_path **out, char *err,
                           size_t errlen)
{
    if (!out) {
        ocean_seterr(err, errlen, "oc_path_parse: out is NULL");
        return OCEAN_EINVAL;
    }
    *out = NULL;
    if (!text && len) {
        ocean_seterr(err, errlen, "oc_path_parse: text is NULL with len %zu", len);
        return OCEAN_EINVAL;
    }
    if (!name)
        name = "path";
    oc_path *p = calloc(1, sizeof *p);
    if (!p)
        return OCEAN_ENOMEM;
    size_t cap = 0;
    char line[1024];
    size_t pos = 0;
    unsigned lineno = 0;
    int have_header = 0, ncol = 0;
    /* The daemon's "# subscribed at T: mode live|replay" starts a segment:
     * live t is the server's clock (never back), replay t the render_time
     * the client asked for, in its order (it may scrub back). */
    int seg_replay = 0, seg_start = 0;
    p->monotonic = 1;
    ocean_result res = OCEAN_OK;
    while (pos < len) {
        size_t start = pos;
        while (pos < len && text[pos] != '\n')
            pos++;
        size_t ll = pos - start;
        if (pos < len)
            pos++;
        lineno++;
        if (ll >= sizeof line) {
            ocean_seterr(err, errlen, "%s:%u: line longer than %zu bytes", name, lineno, sizeof line - 1);
            res = OCEAN_EFORMAT;
            break;
        }
        if (memchr(text + start, 0, ll)) {
            ocean_seterr(err, errlen, "%s:%u: NUL byte in line", name, lineno);
            res = OCEAN_EFORMAT;
            break;
        }
        memcpy(line, text + start, ll);
        line[ll] = 0;
        char *s = trim(line);
        if (*s == '#') {
            static const char magic[] = "# oceand camera path";
            if (strncmp(s, magic, sizeof magic - 1) == 0) {
                /* exactly " v" and a decimal version: "v1x" and "v01" were
                 * read as version 1 */
                const char *v = s + sizeof magic - 1;
                v += *v == ' ';
                size_t nd = v[0] == 'v' && v[-1] == ' ' ? strspn(v + 1, "0123456789") : 0;
                if (nd == 0 || v[1 + nd] != 0 || (v[1] == '0' && nd > 1)) {
                    char shown[SHOWN];
                    conf_show_text(s, strlen(s), shown, sizeof shown);
                    ocean_seterr(err, errlen, "%s:%u: malformed version line \"%s\" (expected \"%s v1\")", name,
                                 lineno, shown, magic);
                    res = OCEAN_EFORMAT;
                    break;
                }
                if (nd != 1 || v[1] != '1') {
                    ocean_seterr(err, errlen, "%s:%u: camera path format version %s; this reader knows v1", name,
                                 lineno, v + 1);
                    res = OCEAN_EVERSION;
                    break;
                }
            }
            static const char subscribed[] = "# subscribed at ";
            if (strncmp(s, subscribed, sizeof subscribed - 1) == 0) {
                const char *m = strstr(s, ": mode ");
                seg_replay = m && strcmp(m + 7, "replay") == 0;
                seg_start = 1;
            }
            continue;
        }
        if (!*s)
            continue;
        if (!have_header) {
            char hdr[1024];
            size_t k = 0;
            for (char *c = s; *c && k + 1 < sizeof hdr; c++)
                if (*c != ' ' && *c != '\t')
                    hdr[k++] = *c;
            hdr[k] = 0;
            ncol = header_columns(hdr);
            if (!ncol) {
                char shown[SHOWN];
                conf_show_text(s, strlen(s), shown, sizeof shown);
                ocean_seterr(err, errlen, "%s:%u: expected the header \"%s\" (or its first 11 columns), got \"%s\"",
                       name, lineno, OC_PATH_HEADER, shown);
                res = OCEAN_EFORMAT;
                break;
            }
            have_header = 1;
            continue;
        }
        char orig[SHOWN];   /* the line as messages quote it */
        conf_show_text(s, strlen(s), orig, sizeof orig);
        double v[13];
        int nf = 0;
        char *tok = s;
        const char *bad = NULL;
        for (;;) {
            char *comma = strchr(tok, ',');
            if (comma)
                *comma = 0;
            char *f = trim(tok);
            if (nf >= ncol) {
                bad = "too many fields";
                break;
            }
            if (!*f) {
                ocean_seterr(err, errlen, "%s:%u: field %s is empty in \"%s\"", name, lineno, FIELD[nf], orig);
                res = OCEAN_EFORMAT;
                break;
            }
            errno = 0;
            char *end;
            v[nf] = strtod(f, &end);
            /* decimal only (RECORDING.md writes %.17g): strtod also reads
             * hex ("0x10" was 16) */
            if (*end || errno == ERANGE || strpbrk(f, "xX")) {
                char shown[SHOWN];
                conf_show_text(f, strlen(f), shown, sizeof shown);
                ocean_seterr(err, errlen, "%s:%u: field %s \"%s\" is not a number in \"%s\"", name, lineno,
                       FIELD[nf], shown, orig);
                res = OCEAN_EFORMAT;
                break;
            }
            nf++;
            if (!comma)
                break;
            tok = comma + 1;
        }
        if (res != OCEAN_OK)
            break;
        if (bad || nf != ncol) {
            ocean_seterr(err, errlen, "%s:%u: expected %d fields as the header says, got %s%d in \"%s\"", name,
                   lineno, ncol, bad ? "more than " : "", bad ? ncol : nf, orig);
            res = OCEAN_EFORMAT;
            break;
        }
        int vw = OC_PATH_DEFAULT_VIEWPORT_W, vh = OC_PATH_DEFAULT_VIEWPORT_H;
        if (ncol == 13) {
            for (int k = 11; k < 13; k++)
                if (!(v[k] >= 1 && v[k] <= 16384 && v[k] == floor(v[k]))) {
                    ocean_seterr(err, errlen, "%s:%u: field %s must be an integer 1..16384 in \"%s\"", name,
                           lineno, FIELD[k], orig);
                    res = OCEAN_EINVAL;
                    break;
                }
            if (res != OCEAN_OK)
                break;
            vw = (int)v[11];
            vh = (int)v[12];
        }
        /* velocity, angles and fov travel in CAMERA as floats: kept as the
         * floats sent, so the bounds below hold for what the server gets
         * (fov 179.9999999999 is 180.0f, which it refuses) and a path
         * written back (%.9g) reads back to the same values */
        for (int k = 4; k <= 10; k++)
            v[k] = as_wire_float(v[k]);
        oc_path_point q = {v[0], {v[1], v[2], v[3]}, {v[4], v[5], v[6]}, v[7], v[8], v[9], v[10], vw, vh};
        int fi;
        const char *why = check_point(&q, &fi);
        if (why) {
            ocean_seterr(err, errlen, "%s:%u: field %s %s in \"%s\"", name, lineno, FIELD[fi], why, orig);
            res = OCEAN_EINVAL;
            break;
        }
        if (p->count && q.t < p->pts[p->count - 1].t) {
            if (!seg_replay && !seg_start) {
                ocean_seterr(err, errlen, "%s:%u: t %.17g goes back in time (previous line has %.17g) in \"%s\" "
                             "(only a replay-mode segment, after \"# subscribed at T: mode replay\", may)",
                             name, lineno, q.t, p->pts[p->count - 1].t, orig);
                res = OCEAN_EINVAL;
                break;
            }
            if (p->monotonic)
                p->back_line = lineno;
            p->monotonic = 0;
        }
        seg_start = 0;
        if (p->count >= OC_PATH_MAX_POINTS) {
            ocean_seterr(err, errlen, "%s:%u: more than %u points", name, lineno, OC_PATH_MAX_POINTS);
            res = OCEAN_ETOOBIG;
            break;
        }
        if (p->count == cap) {
            size_t nc = cap ? 2 * cap : 256;
            oc_path_point *np = realloc(p->pts, nc * sizeof *np);
            if (!np) {
                res = OCEAN_ENOMEM;
                ocean_seterr(err, errlen, "%s:%u: out of memory", name, lineno);
                break;
            }
            p->pts = np;
            cap = nc;
        }
        p->pts[p->count++] = q;
    }
    if (res == OCEAN_OK && !have_header) {
        ocean_seterr(err, errlen, "%s: no header line \"%s\" (empty file?)", name, OC_PATH_HEADER);
        res = OCEAN_EFORMAT;
    }
    if (res == OCEAN_OK && p->count == 0) {
        ocean_seterr(err, errlen, "%s: no camera reports after the header", name);
        res = OCEAN_EFORMAT;
    }
    if (res != OCEAN_OK) {
        oc_path_destroy(p);
        return res;
    }
    *out = p;
    return OCEAN_OK;
}

ocean_result oc_path_load(const char *file, oc_path **out, char *err, size_t errlen)
{
    if (!file || !out)
        return OCEAN_EINVAL;
    *out = NULL;
    int is_stdin = strcmp(file, "-") == 0;
    FILE *f = is_stdin ? stdin : fopen(file, "rb");
    if (!f) {
        ocean_seterr(err, errlen, "%s: cannot open: %s", file, strerror(errno));
        return errno == ENOENT ? OCEAN_ENOTFOUND : OCEAN_EIO;
    }
    size_t cap = 65536, len = 0;
    char *buf = malloc(cap);
    ocean_result r = OCEAN_OK;
    if (!buf)
        r = OCEAN_ENOMEM;
    while (r == OCEAN_OK) {
        if (len == cap) {
            if (cap > ((size_t)1 << 31)) {
                ocean_seterr(err, errlen, "%s: larger than 2 GiB", file);
                r = OCEAN_ETOOBIG;
                break;
            }
            char *nb = realloc(buf, cap * 2);
            if (!nb) {
                r = OCEAN_ENOMEM;
                break;
            }
            buf = nb;
            cap *= 2;
        }
        size_t n = fread(buf + len, 1, cap - len, f);
        len += n;
        if (n == 0) {
            if (ferror(f)) {
                ocean_seterr(err, errlen, "%s: read error: %s", file, strerror(errno));
                r = OCEAN_EIO;
            }
            break;
        }
    }
    if (!is_stdin)
        fclose(f);
    if (r == OCEAN_OK)
        r = oc_path_parse(buf, len, is_stdin ? "<stdin>" : file, out, err, errlen);
    else if (r == OCEAN_ENOMEM)
        ocean_seterr(err, errlen, "%s: out of memory", file);
    free(buf);
    return r;
}

ocean_result oc_path_write(const oc_path *p, FILE *f)
{
    if (!p || !f)
        return OCEAN_EINVAL;
    if (fprintf(f, "%s\n%s\n", OC_PATH_VERSION_LINE, OC_PATH_HEADER) < 0)
        return OCEAN_EIO;
    /* t that goes back is read only in a replay-mode segment */
    if (!p->monotonic && p->count && fprintf(f, "# subscribed at %.17g: mode replay\n", p->pts[0].t) < 0)
        return OCEAN_EIO;
    for (size_t i = 0; i < p->count; i++) {
        const oc_path_point *q = &p->pts[i];
        if (fprintf(f, "%.17g,%.17g,%.17g,%.17g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%d,%d\n", q->t,
                    q->pos[0], q->pos[1], q->pos[2], q->vel[0], q->vel[1], q->vel[2], q->yaw_deg,
                    q->pitch_deg, q->roll_deg, q->fov_deg, q->viewport_w, q->viewport_h) < 0)
            return OCEAN_EIO;
    }
    return fflush(f) == 0 ? OCEAN_OK : OCEAN_EIO;
}

void oc_path_camera(const oc_path_point *pt, proto_camera *cam)
{
    memset(cam, 0, sizeof *cam);
    for (int i = 0; i < 3; i++) {
        cam->pos[i] = pt->pos[i];
        cam->vel[i] = (float)pt->vel[i];
    }
    cam->yaw_deg = (float)pt->yaw_deg;
    cam->pitch_deg = (float)pt->pitch_deg;
    cam->roll_deg = (float)pt->roll_deg;
    cam->fov_y_deg = (float)pt->fov_deg;
    cam->viewport_w = (uint16_t)pt->viewport_w;
    cam->viewport_h = (uint16_t)pt->viewport_h;
    cam->render_time = pt->t;
}
