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
    /* CAMERA's orientation bounds (PROTOCOL.md), checked as the path is
     * read: a path the encoder would refuse fails at its line, not when
     * replay sends it */
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

/* A path being read, line by line. */
typedef struct path_reader {
    const char *name;
    unsigned lineno;
    int have_header, ncol;
    /* The daemon's "# subscribed at T: mode live|replay" starts a segment:
     * live t is the server's clock (never back), replay t the render_time
     * the client asked for, in its order (it may scrub back). */
    int seg_replay, seg_start;
    size_t cap;
    oc_path *p;
    char *err;
    size_t errlen;
} path_reader;

/* A comment line: the version line is checked, a "# subscribed at" line
 * starts a segment; others are ignored. */
static ocean_result comment_line(path_reader *r, const char *s)
{
    static const char magic[] = "# oceand camera path";
    if (strncmp(s, magic, sizeof magic - 1) == 0) {
        /* exactly " v" and a decimal version without leading zeros: "v1x"
         * and "v01" are not version 1 */
        const char *v = s + sizeof magic - 1;
        v += *v == ' ';
        size_t nd = v[0] == 'v' && v[-1] == ' ' ? strspn(v + 1, "0123456789") : 0;
        if (nd == 0 || v[1 + nd] != 0 || (v[1] == '0' && nd > 1)) {
            char shown[SHOWN];
            conf_show_text(s, strlen(s), shown, sizeof shown);
            ocean_seterr(r->err, r->errlen, "%s:%u: malformed version line \"%s\" (expected \"%s v1\")", r->name,
                         r->lineno, shown, magic);
            return OCEAN_EFORMAT;
        }
        if (nd != 1 || v[1] != '1') {
            ocean_seterr(r->err, r->errlen, "%s:%u: camera path format version %s; this reader knows v1", r->name,
                         r->lineno, v + 1);
            return OCEAN_EVERSION;
        }
    }
    static const char subscribed[] = "# subscribed at ";
    if (strncmp(s, subscribed, sizeof subscribed - 1) == 0) {
        const char *m = strstr(s, ": mode ");
        r->seg_replay = m && strcmp(m + 7, "replay") == 0;
        r->seg_start = 1;
    }
    return OCEAN_OK;
}

static ocean_result header_line(path_reader *r, const char *s)
{
    char hdr[1024];
    size_t k = 0;
    for (const char *c = s; *c && k + 1 < sizeof hdr; c++)
        if (*c != ' ' && *c != '\t')
            hdr[k++] = *c;
    hdr[k] = 0;
    r->ncol = header_columns(hdr);
    if (!r->ncol) {
        char shown[SHOWN];
        conf_show_text(s, strlen(s), shown, sizeof shown);
        ocean_seterr(r->err, r->errlen, "%s:%u: expected the header \"%s\" (or its first 11 columns), got \"%s\"",
                     r->name, r->lineno, OC_PATH_HEADER, shown);
        return OCEAN_EFORMAT;
    }
    r->have_header = 1;
    return OCEAN_OK;
}

/* The comma-separated numbers of a data line into v (as many as the header
 * has columns; decimal only: RECORDING.md writes %.17g, and strtod would
 * also read hex, "0x10" as 16). */
static ocean_result line_fields(path_reader *r, char *s, const char *orig, double v[13])
{
    int nf = 0;
    char *tok = s;
    const char *bad = NULL;
    for (;;) {
        char *comma = strchr(tok, ',');
        if (comma)
            *comma = 0;
        char *f = trim(tok);
        if (nf >= r->ncol) {
            bad = "too many fields";
            break;
        }
        if (!*f) {
            ocean_seterr(r->err, r->errlen, "%s:%u: field %s is empty in \"%s\"", r->name, r->lineno, FIELD[nf], orig);
            return OCEAN_EFORMAT;
        }
        errno = 0;
        char *end;
        v[nf] = strtod(f, &end);
        if (*end || errno == ERANGE || strpbrk(f, "xX")) {
            char shown[SHOWN];
            conf_show_text(f, strlen(f), shown, sizeof shown);
            ocean_seterr(r->err, r->errlen, "%s:%u: field %s \"%s\" is not a number in \"%s\"", r->name, r->lineno,
                         FIELD[nf], shown, orig);
            return OCEAN_EFORMAT;
        }
        nf++;
        if (!comma)
            break;
        tok = comma + 1;
    }
    if (bad || nf != r->ncol) {
        ocean_seterr(r->err, r->errlen, "%s:%u: expected %d fields as the header says, got %s%d in \"%s\"", r->name,
                     r->lineno, r->ncol, bad ? "more than " : "", bad ? r->ncol : nf, orig);
        return OCEAN_EFORMAT;
    }
    return OCEAN_OK;
}

/* The point of fields v (checked; the viewport defaulted when the header
 * has 11 columns). */
static ocean_result line_point(path_reader *r, double v[13], const char *orig, oc_path_point *q)
{
    int vw = OC_PATH_DEFAULT_VIEWPORT_W, vh = OC_PATH_DEFAULT_VIEWPORT_H;
    if (r->ncol == 13) {
        for (int k = 11; k < 13; k++)
            if (!(v[k] >= 1 && v[k] <= 16384 && v[k] == floor(v[k]))) {
                ocean_seterr(r->err, r->errlen, "%s:%u: field %s must be an integer 1..16384 in \"%s\"", r->name,
                             r->lineno, FIELD[k], orig);
                return OCEAN_EINVAL;
            }
        vw = (int)v[11];
        vh = (int)v[12];
    }
    /* velocity, angles and fov travel in CAMERA as floats: kept as the
     * floats sent, so the bounds below hold for what the server gets (fov
     * 179.9999999999 is 180.0f, which it refuses) and a path written back
     * (%.9g) reads back to the same values */
    for (int k = 4; k <= 10; k++)
        v[k] = as_wire_float(v[k]);
    *q = (oc_path_point){v[0], {v[1], v[2], v[3]}, {v[4], v[5], v[6]}, v[7], v[8], v[9], v[10], vw, vh};
    int fi;
    const char *why = check_point(q, &fi);
    if (why) {
        ocean_seterr(r->err, r->errlen, "%s:%u: field %s %s in \"%s\"", r->name, r->lineno, FIELD[fi], why, orig);
        return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

/* A camera report: parsed, checked, in time order unless in a replay
 * segment, appended. */
static ocean_result data_line(path_reader *r, char *s)
{
    oc_path *p = r->p;
    char orig[SHOWN]; /* the line as messages quote it */
    conf_show_text(s, strlen(s), orig, sizeof orig);
    double v[13];
    oc_path_point q;
    ocean_result res = line_fields(r, s, orig, v);
    if (res == OCEAN_OK) res = line_point(r, v, orig, &q);
    if (res != OCEAN_OK) return res;
    if (p->count && q.t < p->pts[p->count - 1].t) {
        if (!r->seg_replay && !r->seg_start) {
            ocean_seterr(r->err, r->errlen, "%s:%u: t %.17g goes back in time (previous line has %.17g) in \"%s\" "
                         "(only a replay-mode segment, after \"# subscribed at T: mode replay\", may)",
                         r->name, r->lineno, q.t, p->pts[p->count - 1].t, orig);
            return OCEAN_EINVAL;
        }
        if (p->monotonic)
            p->back_line = r->lineno;
        p->monotonic = 0;
    }
    r->seg_start = 0;
    if (p->count >= OC_PATH_MAX_POINTS) {
        ocean_seterr(r->err, r->errlen, "%s:%u: more than %u points", r->name, r->lineno, OC_PATH_MAX_POINTS);
        return OCEAN_ETOOBIG;
    }
    if (p->count == r->cap) {
        size_t nc = r->cap ? 2 * r->cap : 256;
        oc_path_point *np = realloc(p->pts, nc * sizeof *np);
        if (!np) {
            ocean_seterr(r->err, r->errlen, "%s:%u: out of memory", r->name, r->lineno);
            return OCEAN_ENOMEM;
        }
        p->pts = np;
        r->cap = nc;
    }
    p->pts[p->count++] = q;
    return OCEAN_OK;
}

/* The next line of text (at *pos) into line, trimmed: NULL with *res set
 * when it is too long or holds a NUL byte. */
static char *next_line(path_reader *r, const char *text, size_t len, size_t *pos, char *line, size_t cap,
                       ocean_result *res)
{
    size_t start = *pos;
    while (*pos < len && text[*pos] != '\n')
        (*pos)++;
    size_t ll = *pos - start;
    if (*pos < len)
        (*pos)++;
    r->lineno++;
    *res = OCEAN_EFORMAT;
    if (ll >= cap) {
        ocean_seterr(r->err, r->errlen, "%s:%u: line longer than %zu bytes", r->name, r->lineno, cap - 1);
        return NULL;
    }
    if (memchr(text + start, 0, ll)) {
        ocean_seterr(r->err, r->errlen, "%s:%u: NUL byte in line", r->name, r->lineno);
        return NULL;
    }
    *res = OCEAN_OK;
    memcpy(line, text + start, ll);
    line[ll] = 0;
    return trim(line);
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
    path_reader r = {.name = name ? name : "path", .err = err, .errlen = errlen};
    r.p = calloc(1, sizeof *r.p);
    if (!r.p)
        return OCEAN_ENOMEM;
    r.p->monotonic = 1;
    char line[1024];
    size_t pos = 0;
    ocean_result res = OCEAN_OK;
    while (pos < len && res == OCEAN_OK) {
        char *s = next_line(&r, text, len, &pos, line, sizeof line, &res);
        if (!s || !*s)
            continue;
        res = *s == '#' ? comment_line(&r, s) : !r.have_header ? header_line(&r, s) : data_line(&r, s);
    }
    if (res == OCEAN_OK && !r.have_header) {
        ocean_seterr(err, errlen, "%s: no header line \"%s\" (empty file?)", r.name, OC_PATH_HEADER);
        res = OCEAN_EFORMAT;
    }
    if (res == OCEAN_OK && r.p->count == 0) {
        ocean_seterr(err, errlen, "%s: no camera reports after the header", r.name);
        res = OCEAN_EFORMAT;
    }
    if (res != OCEAN_OK) {
        oc_path_destroy(r.p);
        return res;
    }
    *out = r.p;
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
