/*
 * conf.c - the table-driven `key = value` parser (see conf.h for the file
 * syntax and the error contract).
 *
 * Kept deliberately small: a source is split into lines, each line is
 * checked for length, control bytes and UTF-8 before anything looks at it,
 * then split into key and value, and the value is converted by its entry's
 * type into a scratch copy of the target.  Only a fully good source is
 * copied back, so callers never see half a configuration.
 */
#include "conf.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* Longest offending text quoted in a message (display bytes). */
#define SHOW_MAX CONF_SHOW_MAX
/* Value messages are composed here before the location is added. */
#define MSG_MAX 256

typedef struct loader {
    const conf_set *set;
    const conf_load_opts *opts;
    void **scratch;      /* one copy per table */
    int *seen;           /* per entry (flat over the tables): line it was set on */
    size_t *base;        /* index of table i's first entry in seen[] */
    const char *name;    /* source name for messages */
    int line;            /* 0: no line (overrides, whole-file checks) */
    char *err;
    size_t errlen;
} loader;

/* ---- small text helpers ------------------------------------------------- */

static bool is_blank(char c) { return c == ' ' || c == '\t'; }

/* Length of the valid UTF-8 sequence at s (n bytes available), or 0.
 * Strict: no overlong forms, no surrogates, nothing above U+10FFFF. */
static size_t utf8_seq(const unsigned char *s, size_t n)
{
    unsigned c = s[0];
    size_t len;
    unsigned cp;
    if (c < 0x80) return 1;
    if (c >= 0xC2 && c <= 0xDF) { len = 2; cp = c & 0x1F; }
    else if (c >= 0xE0 && c <= 0xEF) { len = 3; cp = c & 0x0F; }
    else if (c >= 0xF0 && c <= 0xF4) { len = 4; cp = c & 0x07; }
    else return 0;
    if (n < len) return 0;
    for (size_t i = 1; i < len; i++) {
        if ((s[i] & 0xC0) != 0x80) return 0;
        cp = (cp << 6) | (s[i] & 0x3F);
    }
    if ((len == 3 && cp < 0x800) || (len == 4 && (cp < 0x10000 || cp > 0x10FFFF)) ||
        (cp >= 0xD800 && cp <= 0xDFFF))
        return 0;
    return len;
}

/* Format characters that display as nothing. */
static bool invisible(unsigned cp)
{
    return cp == 0xFEFF || (cp >= 0x200B && cp <= 0x200F) || (cp >= 0x2028 && cp <= 0x202E) ||
           (cp >= 0x2060 && cp <= 0x2069);
}

void conf_show_text(const char *text, size_t len, char *out, size_t outlen)
{
    const unsigned char *s = (const unsigned char *)text;
    size_t o = 0, i = 0;
    if (outlen == 0) return;
    while (i < len && o + 8 < outlen) {
        if (o >= SHOW_MAX) {
            memcpy(out + o, "...", 3);
            o += 3;
            break;
        }
        size_t q = (s[i] >= 0x20 && s[i] != 0x7F) ? utf8_seq(s + i, len - i) : 0;
        unsigned cp = q == 3 ? ((s[i] & 0x0Fu) << 12) | ((s[i + 1] & 0x3Fu) << 6) | (s[i + 2] & 0x3Fu) : 0;
        if (invisible(cp)) {
            /* A byte-order mark or bidi control in a key would print as
             * nothing, leaving the reader staring at a correct-looking key. */
            o += (size_t)snprintf(out + o, outlen - o, "\\u%04X", cp);
            i += q;
        } else if (q > 0) {
            memcpy(out + o, s + i, q);
            o += q;
            i += q;
        } else {
            o += (size_t)snprintf(out + o, outlen - o, "\\x%02X", s[i]);
            i++;
        }
    }
    out[o < outlen ? o : outlen - 1] = '\0';
}

/* Writes "name:line: msg: 'text'" (or "name: ..." without a line). */
static ocean_result fail(loader *ld, ocean_result code, const char *msg,
                         const char *text, size_t textlen)
{
    if (ld->err && ld->errlen) {
        char shown[SHOW_MAX * 4 + 16];
        conf_show_text(text ? text : "", text ? textlen : 0, shown, sizeof shown);
        if (ld->line > 0)
            snprintf(ld->err, ld->errlen, "%s:%d: %s: '%s'", ld->name, ld->line, msg, shown);
        else
            snprintf(ld->err, ld->errlen, "%s: %s: '%s'", ld->name, msg, shown);
    }
    return code;
}

/* The last step of every fixed-size type: the entry's hook may veto the
 * parsed value, then (when storing) it is copied into the target field. */
static ocean_result accept_value(const conf_entry *e, void *target, void *field, void *v,
                                 size_t size, int store, char *msg, size_t msglen)
{
    if (e->hook) {
        ocean_result r = e->hook(target, e, v, msg, msglen);
        if (r != OCEAN_OK) return r;
    }
    if (store) memcpy(field, v, size);
    return OCEAN_OK;
}

/* Shortest of %.15g/%.16g/%.17g that reads back to exactly v. */
static int fmt_double(double v, char *buf, size_t len)
{
    char tmp[40];
    if (isinf(v)) return snprintf(buf, len, v > 0 ? "inf" : "-inf");
    for (int prec = 15; prec <= 17; prec++) {
        snprintf(tmp, sizeof tmp, "%.*g", prec, v);
        if (strtod(tmp, NULL) == v || prec == 17) break;
    }
    return snprintf(buf, len, "%s", tmp);
}

/* Range text for messages and dumps: "[0, 100]". */
static void fmt_range(const conf_entry *e, char *buf, size_t len)
{
    char lo[40], hi[40];
    if (e->type == CONF_U64 && e->max >= 18446744073709551616.0)
        snprintf(hi, sizeof hi, "%" PRIu64, UINT64_MAX);
    else
        fmt_double(e->max, hi, sizeof hi);
    fmt_double(e->min, lo, sizeof lo);
    snprintf(buf, len, "[%s, %s]", lo, hi);
}

/* Key syntax: segments of [a-z0-9_-], the first starting with a letter,
 * joined by single dots. */
static bool key_valid(const char *k, size_t len)
{
    if (len == 0 || len > CONF_MAX_KEY || !(k[0] >= 'a' && k[0] <= 'z'))
        return false;
    for (size_t i = 0; i < len; i++) {
        char c = k[i];
        bool ok = (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' || c == '-';
        if (c == '.') ok = i + 1 < len && k[i + 1] != '.';
        if (!ok) return false;
    }
    return true;
}

static size_t edit_distance(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    size_t row[CONF_MAX_KEY + 2];
    if (la > CONF_MAX_KEY || lb > CONF_MAX_KEY) return SIZE_MAX;
    for (size_t j = 0; j <= lb; j++) row[j] = j;
    for (size_t i = 1; i <= la; i++) {
        size_t diag = row[0];
        row[0] = i;
        for (size_t j = 1; j <= lb; j++) {
            size_t up = row[j];
            size_t best = diag + (a[i - 1] != b[j - 1]);
            if (up + 1 < best) best = up + 1;
            if (row[j - 1] + 1 < best) best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    return row[lb];
}

/* ---- entries -------------------------------------------------------------- */

const conf_entry *conf_find(const conf_set *set, const char *key, size_t *table)
{
    if (!set || !key) return NULL;
    for (size_t t = 0; t < set->n; t++)
        for (size_t i = 0; i < set->tables[t]->count; i++)
            if (strcmp(set->tables[t]->entries[i].name, key) == 0) {
                if (table) *table = t;
                return &set->tables[t]->entries[i];
            }
    return NULL;
}

/* Lists an entry's names for messages: "a, b, c". */
static void names_list(const conf_entry *e, char *buf, size_t len)
{
    size_t o = 0;
    buf[0] = '\0';
    for (const conf_name *n = e->names; n && n->name && o < len; n++)
        o += (size_t)snprintf(buf + o, len - o, "%s%s", o ? ", " : "", n->name);
}

static bool name_match(const char *want, size_t wlen, const char *name)
{
    return strlen(name) == wlen && strncasecmp(want, name, wlen) == 0;
}

/* One value being parsed for its entry (parse_value's arguments, and what
 * every type's parser reports a refusal with). */
typedef struct pv_ctx {
    const conf_entry *e;
    void *target;
    char *field;               /* the entry's field in target */
    const char *text;
    size_t tlen;
    bool store;                /* !CONF_F_NOSTORE */
    char *msg;
    size_t msglen;
    const char *range, *unit, *usp;  /* for "out of range" */
    const char **bad;          /* the part of text a refusal quotes */
    size_t *badlen;
} pv_ctx;

/* Stores v (n bytes) as x's value: accept_value with x's entry. */
static ocean_result accept(const pv_ctx *x, void *v, size_t n)
{
    return accept_value(x->e, x->target, x->field, v, n, x->store, x->msg, x->msglen);
}

static ocean_result pv_int(const pv_ctx *x)
{
    const conf_entry *e = x->e;
    const char *text = x->text;
    const char *p = text + (text[0] == '+' || text[0] == '-');
    if (!(*p >= '0' && *p <= '9')) {
        ocean_seterr(x->msg, x->msglen, "%s: not an integer", e->name);
        return OCEAN_EFORMAT;
    }
    char *end;
    errno = 0;
    long long v = strtoll(text, &end, 10);
    if (*end) {
        ocean_seterr(x->msg, x->msglen, "%s: %s", e->name,
                end > text ? "trailing text after the integer" : "not an integer");
        return OCEAN_EFORMAT;
    }
    if (errno == ERANGE || (double)v < e->min || (double)v > e->max) {
        ocean_seterr(x->msg, x->msglen, "%s: out of range %s%s%s", e->name, x->range, x->usp, x->unit);
        return OCEAN_EINVAL;
    }
    int iv = (int)v;
    return accept(x, &iv, sizeof iv);
}

static ocean_result pv_u64(const pv_ctx *x)
{
    const conf_entry *e = x->e;
    const char *text = x->text;
    const char *p = text + (text[0] == '+');
    int base = 10;
    if (p[0] == '0' && (p[1] == 'x' || p[1] == 'X')) {
        base = 16;
        p += 2;
    }
    /* Scan the digits ourselves: strtoull would also take blanks, a
     * sign and a second "0x". */
    const char *q = p;
    while ((*q >= '0' && *q <= '9') ||
           (base == 16 && ((*q >= 'a' && *q <= 'f') || (*q >= 'A' && *q <= 'F'))))
        q++;
    if (q == p || *q) {
        ocean_seterr(x->msg, x->msglen, "%s: %s", e->name,
                q == p ? "not an unsigned integer" : "trailing text after the integer");
        return OCEAN_EFORMAT;
    }
    errno = 0;
    unsigned long long v = strtoull(p, NULL, base);
    bool over = errno == ERANGE || (double)v < e->min ||
                (e->max < 18446744073709551616.0 && v > (unsigned long long)e->max);
    if (over) {
        ocean_seterr(x->msg, x->msglen, "%s: out of range %s%s%s", e->name, x->range, x->usp, x->unit);
        return OCEAN_EINVAL;
    }
    uint64_t uv = v;
    return accept(x, &uv, sizeof uv);
}

static ocean_result pv_double(const pv_ctx *x)
{
    const conf_entry *e = x->e;
    const char *text = x->text;
    double v;
    const char *p = text + (text[0] == '+');
    if ((e->flags & CONF_F_INF_OK) &&
        (strcasecmp(p, "inf") == 0 || strcasecmp(p, "infinity") == 0)) {
        v = INFINITY;
    } else {
        /* Decimal only: strtod would also take nan, inf and hex floats. */
        for (const char *q = text; *q; q++)
            if (!strchr("0123456789+-.eE", *q)) {
                const char *u = text + (text[0] == '+' || text[0] == '-');
                bool nonfinite = strncasecmp(u, "nan", 3) == 0 || strncasecmp(u, "inf", 3) == 0;
                if (nonfinite)
                    ocean_seterr(x->msg, x->msglen, "%s: NaN and infinity are not allowed", e->name);
                else if ((*text >= '0' && *text <= '9') || *text == '.' ||
                         ((*text == '-' || *text == '+') && text[1] >= '0' && text[1] <= '9'))
                    ocean_seterr(x->msg, x->msglen, "%s: trailing text after the number", e->name);
                else
                    ocean_seterr(x->msg, x->msglen, "%s: not a number", e->name);
                return OCEAN_EFORMAT;
            }
        char *end;
        errno = 0;
        v = strtod(text, &end);
        if (end == text || *end) {
            ocean_seterr(x->msg, x->msglen, "%s: not a number", e->name);
            return OCEAN_EFORMAT;
        }
        if (!isfinite(v)) {
            ocean_seterr(x->msg, x->msglen, "%s: too large for a double, out of range %s%s%s",
                    e->name, x->range, x->usp, x->unit);
            return OCEAN_EINVAL;
        }
    }
    if (!(v >= e->min && v <= e->max)) {
        ocean_seterr(x->msg, x->msglen, "%s: out of range %s%s%s", e->name, x->range, x->usp, x->unit);
        return OCEAN_EINVAL;
    }
    return accept(x, &v, sizeof v);
}

static ocean_result pv_bool(const pv_ctx *x)
{
    const conf_entry *e = x->e;
    const char *text = x->text;
    static const char *const yes[] = {"on", "true", "yes", "1"};
    static const char *const no[] = {"off", "false", "no", "0"};
    int v = -1;
    for (int i = 0; i < 4; i++) {
        if (strcasecmp(text, yes[i]) == 0) v = 1;
        if (strcasecmp(text, no[i]) == 0) v = 0;
    }
    if (v < 0) {
        ocean_seterr(x->msg, x->msglen, "%s: not a boolean (on/off, true/false, yes/no, 1/0)", e->name);
        return OCEAN_EFORMAT;
    }
    return accept(x, &v, sizeof v);
}

static ocean_result pv_enum(const pv_ctx *x)
{
    const conf_entry *e = x->e;
    const char *text = x->text;
    for (const conf_name *n = e->names; n && n->name; n++)
        if (name_match(text, x->tlen, n->name)) {
            int v = (int)n->value;
            return accept(x, &v, sizeof v);
        }
    char names[MSG_MAX];
    names_list(e, names, sizeof names);
    ocean_seterr(x->msg, x->msglen, "%s: unknown name (one of %s)", e->name, names);
    return OCEAN_EFORMAT;
}

static ocean_result pv_flags(const pv_ctx *x)
{
    const conf_entry *e = x->e;
    const char *text = x->text;
    unsigned v = 0, all = 0;
    for (const conf_name *n = e->names; n && n->name; n++) all |= n->value;
    if (strcasecmp(text, "none") == 0) {
        v = 0;
    } else if (strcasecmp(text, "all") == 0) {
        v = all;
    } else {
        const char *p = text;
        for (;;) {
            const char *comma = strchr(p, ',');
            const char *end = comma ? comma : p + strlen(p);
            const char *a = p, *b = end;
            while (a < b && is_blank(*a)) a++;
            while (b > a && is_blank(b[-1])) b--;
            *x->bad = a;
            *x->badlen = (size_t)(b - a);
            if (a == b) {
                ocean_seterr(x->msg, x->msglen, "%s: empty item in the list", e->name);
                return OCEAN_EFORMAT;
            }
            const conf_name *hit = NULL;
            for (const conf_name *n = e->names; n && n->name && !hit; n++)
                if (name_match(a, (size_t)(b - a), n->name)) hit = n;
            if (!hit) {
                char names[MSG_MAX];
                names_list(e, names, sizeof names);
                /* none and all stand alone, so the message offers them
                 * as words of their own, and none only where the key may
                 * be empty */
                ocean_seterr(x->msg, x->msglen, "%s: unknown name in the list (names: %s; or, alone, %s)",
                             e->name, names, e->min >= 1 ? "all" : "none or all");
                return OCEAN_EFORMAT;
            }
            if ((v & hit->value) == hit->value) {
                ocean_seterr(x->msg, x->msglen, "%s: listed twice", e->name);
                return OCEAN_EFORMAT;
            }
            v |= hit->value;
            if (!comma) break;
            p = comma + 1;
        }
        *x->bad = text;
        *x->badlen = x->tlen;
    }
    if (v == 0 && e->min >= 1) {
        ocean_seterr(x->msg, x->msglen, "%s: at least one name is needed", e->name);
        return OCEAN_EINVAL;
    }
    return accept(x, &v, sizeof v);
}

static ocean_result pv_string(const pv_ctx *x)
{
    const conf_entry *e = x->e;
    const char *text = x->text;
    if (x->tlen + 1 > e->size) {
        ocean_seterr(x->msg, x->msglen, "%s: string too long (%zu bytes, at most %zu)", e->name,
                x->tlen, e->size - 1);
        return OCEAN_ETOOBIG;
    }
    if (e->hook) {
        ocean_result r = e->hook(x->target, e, text, x->msg, x->msglen);
        if (r != OCEAN_OK) return r;
    }
    if (x->store) {
        memset(x->field, 0, e->size);
        memcpy(x->field, text, x->tlen);
    }
    return OCEAN_OK;
}

/* The parser of each value type (index: conf_type). */
static ocean_result (*const pv_of[])(const pv_ctx *x) = {
    [CONF_INT] = pv_int,   [CONF_U64] = pv_u64,   [CONF_DOUBLE] = pv_double, [CONF_BOOL] = pv_bool,
    [CONF_ENUM] = pv_enum, [CONF_FLAGS] = pv_flags, [CONF_STRING] = pv_string,
};

/* Parses text (NUL-terminated, already trimmed; quoted says it came in
 * quotes) as entry e's type and stores it into target.  On failure writes
 * a message in msg and sets *bad and *badlen to the offending part of text. */
static ocean_result parse_value(const conf_entry *e, void *target, const char *text,
                                bool quoted, char *msg, size_t msglen,
                                const char **bad, size_t *badlen)
{
    char range[96];
    size_t tlen = strlen(text);
    *bad = text;
    *badlen = tlen;
    fmt_range(e, range, sizeof range);
    if (quoted && e->type != CONF_STRING) {
        ocean_seterr(msg, msglen, "%s: quotes are only for string values", e->name);
        return OCEAN_EFORMAT;
    }
    if (tlen == 0 && e->type != CONF_STRING) {
        ocean_seterr(msg, msglen, "%s: missing value", e->name);
        return OCEAN_EFORMAT;
    }
    if ((unsigned)e->type >= sizeof pv_of / sizeof pv_of[0] || !pv_of[e->type]) {
        ocean_seterr(msg, msglen, "%s: entry has an unknown type %d", e->name, (int)e->type);
        return OCEAN_EINVAL;
    }
    pv_ctx x = {.e = e, .target = target, .field = (char *)target + e->offset, .text = text, .tlen = tlen,
                .store = !(e->flags & CONF_F_NOSTORE), .msg = msg, .msglen = msglen, .range = range,
                .unit = e->unit ? e->unit : "", .usp = e->unit ? " " : "", .bad = bad, .badlen = badlen};
    return pv_of[e->type](&x);
}

/* ---- lines ------------------------------------------------------------------ */

/* Checks a raw line (no line end) for control bytes and UTF-8. */
static ocean_result line_check(loader *ld, const char *s, size_t len)
{
    const unsigned char *u = (const unsigned char *)s;
    char msg[MSG_MAX];
    if (len > CONF_MAX_LINE) {
        ocean_seterr(msg, sizeof msg, "line too long (%zu bytes, at most %d)", len, CONF_MAX_LINE);
        return fail(ld, OCEAN_ETOOBIG, msg, s, len);
    }
    for (size_t i = 0; i < len;) {
        if ((u[i] < 0x20 && u[i] != '\t') || u[i] == 0x7F) {
            ocean_seterr(msg, sizeof msg, "control character 0x%02X at column %zu", u[i], i + 1);
            return fail(ld, OCEAN_EFORMAT, msg, s, len);
        }
        size_t q = utf8_seq(u + i, len - i);
        if (q == 0) {
            ocean_seterr(msg, sizeof msg, "invalid UTF-8 at column %zu", i + 1);
            return fail(ld, OCEAN_EFORMAT, msg, s, len);
        }
        i += q;
    }
    return OCEAN_OK;
}

static bool ignored(const loader *ld, const char *key, size_t klen)
{
    const char *dot = memchr(key, '.', klen);
    size_t ns = dot ? (size_t)(dot - key) : klen;
    for (const char *const *p = ld->opts ? ld->opts->ignore : NULL; p && *p; p++)
        if (strlen(*p) == ns && strncmp(*p, key, ns) == 0) return true;
    return false;
}

/* The key at *pp, up to its '=' (checked): *key, *klen; *pp then points
 * past the '=' and the blanks after it.  lend ends the trimmed line. */
static ocean_result line_key(loader *ld, char **pp, const char *lend, char **key, size_t *klen)
{
    char *p = *pp;
    *key = p;
    while (*p && *p != '=' && *p != '#' && !is_blank(*p)) p++;
    *klen = (size_t)(p - *key);
    while (is_blank(*p)) p++;
    if (*p != '=')
        return fail(ld, OCEAN_EFORMAT, "missing '=' (expected key = value)", *key,
                    (size_t)(lend - *key));
    if (*klen == 0)
        return fail(ld, OCEAN_EFORMAT, "missing key before '='", *key, (size_t)(lend - *key));
    if (!key_valid(*key, *klen))
        return fail(ld, OCEAN_EFORMAT,
                    "bad key (lower-case words of a-z, 0-9, '_', '-' joined by '.')", *key, *klen);
    p++;
    while (is_blank(*p)) p++;
    *pp = p;
    return OCEAN_OK;
}

/* The quoted value whose opening quote is at p, unescaped in place into
 * [*val, *vend); only blanks and a comment may follow it. */
static ocean_result quoted_value(loader *ld, char *p, const char *lend, char **val, char **vend)
{
    char *w = ++p;
    *val = w;
    for (;;) {
        if (*p == '\0')
            return fail(ld, OCEAN_EFORMAT, "unterminated quoted value", *val - 1,
                        (size_t)(lend - (*val - 1)));
        if (*p == '"') break;
        if (*p == '\\') {
            if (p[1] != '"' && p[1] != '\\')
                return fail(ld, OCEAN_EFORMAT, "bad escape in quoted value (only \\\" and \\\\)",
                            p, p[1] ? 2 : 1);
            p++;
        }
        *w++ = *p++;
    }
    *vend = w;
    p++;
    while (is_blank(*p)) p++;
    if (*p != '\0' && *p != '#')
        return fail(ld, OCEAN_EFORMAT, "trailing text after the quoted value", p,
                    (size_t)(lend - p));
    return OCEAN_OK;
}

/* The value at p (the line ends at end, trimmed at lend): quoted, or up
 * to a comment, blanks trimmed; NUL-terminated in place. */
static ocean_result line_value(loader *ld, char *p, char *end, const char *lend, char **val,
                               bool *quoted)
{
    char *vend;
    *val = p;
    *quoted = false;
    if (*p == '"') {
        *quoted = true;
        ocean_result r = quoted_value(ld, p, lend, val, &vend);
        if (r != OCEAN_OK) return r;
    } else {
        vend = strchr(p, '#');
        if (!vend) vend = end;
        while (vend > *val && is_blank(vend[-1])) vend--;
    }
    *vend = '\0';
    return OCEAN_OK;
}

/* A key no table has: fine in an ignored namespace, else an error naming
 * the nearest known key when one is close. */
static ocean_result unknown_key(loader *ld, const char *key, size_t klen)
{
    char msg[MSG_MAX];
    if (ignored(ld, key, klen)) return OCEAN_OK;
    const char *best = NULL;
    size_t bestd = SIZE_MAX;
    for (size_t i = 0; i < ld->set->n; i++)
        for (size_t j = 0; j < ld->set->tables[i]->count; j++) {
            size_t d = edit_distance(key, ld->set->tables[i]->entries[j].name);
            if (d < bestd) {
                bestd = d;
                best = ld->set->tables[i]->entries[j].name;
            }
        }
    if (best && bestd <= 2)
        ocean_seterr(msg, sizeof msg, "unknown key (did you mean '%s'?)", best);
    else
        ocean_seterr(msg, sizeof msg, "unknown key");
    return fail(ld, OCEAN_EFORMAT, msg, key, klen);
}

/* Entry e (table t, index idx over all tables) already given, or another
 * of its group: the error, else OCEAN_OK. */
static ocean_result key_repeat(loader *ld, const conf_entry *e, size_t t, size_t idx,
                               const char *key, size_t klen)
{
    char msg[MSG_MAX];
    const conf_table *tab = ld->set->tables[t];
    if (ld->seen && ld->seen[idx]) {
        ocean_seterr(msg, sizeof msg, "duplicate key (first set on line %d)", ld->seen[idx]);
        return fail(ld, OCEAN_EFORMAT, msg, key, klen);
    }
    if (ld->seen && e->group > 0)
        for (size_t j = 0; j < tab->count; j++) {
            const conf_entry *o = &tab->entries[j];
            if (o != e && o->group == e->group && ld->seen[ld->base[t] + j]) {
                ocean_seterr(msg, sizeof msg, "%s conflicts with %s on line %d; give one of them",
                        e->name, o->name, ld->seen[ld->base[t] + j]);
                return fail(ld, OCEAN_EINVAL, msg, key, klen);
            }
        }
    return OCEAN_OK;
}

/* Parses one checked line (s NUL-terminated).  *empty reports a blank or
 * comment-only line. */
static ocean_result line_parse(loader *ld, char *s, bool *empty)
{
    size_t slen = strlen(s);
    char *p = s;
    *empty = false;
    while (is_blank(*p)) p++;
    if (*p == '\0' || *p == '#') {
        *empty = true;
        return OCEAN_OK;
    }
    /* Trimmed line, for messages about the line as a whole. */
    char *lend = s + slen;
    while (lend > p && is_blank(lend[-1])) lend--;
    char *key, *val;
    size_t klen;
    bool quoted;
    ocean_result r = line_key(ld, &p, lend, &key, &klen);
    if (r == OCEAN_OK)
        r = line_value(ld, p, s + slen, lend, &val, &quoted);
    if (r != OCEAN_OK) return r;
    key[klen] = '\0'; /* the key ended at a blank or '=' already consumed */

    size_t t;
    const conf_entry *e = conf_find(ld->set, key, &t);
    if (!e) return unknown_key(ld, key, klen);
    size_t idx = ld->base[t] + (size_t)(e - ld->set->tables[t]->entries);
    r = key_repeat(ld, e, t, idx, key, klen);
    if (r != OCEAN_OK) return r;
    char msg[MSG_MAX];
    const char *bad;
    size_t badlen;
    r = parse_value(e, ld->scratch[t], val, quoted, msg, sizeof msg, &bad, &badlen);
    if (r != OCEAN_OK) return fail(ld, r, msg, bad, badlen);
    if (ld->seen) ld->seen[idx] = ld->line > 0 ? ld->line : 1;
    return OCEAN_OK;
}

/* ---- load ------------------------------------------------------------------ */

static void loader_free(loader *ld)
{
    if (ld->scratch)
        for (size_t t = 0; t < ld->set->n; t++) free(ld->scratch[t]);
    free(ld->scratch);
    free(ld->seen);
    free(ld->base);
}

/* Sets up scratch copies of the targets (and, if track, per-entry state). */
static ocean_result loader_init(loader *ld, const conf_set *set, const conf_load_opts *opts,
                                const char *name, bool track, char *err, size_t errlen)
{
    memset(ld, 0, sizeof *ld);
    ld->set = set;
    ld->opts = opts;
    ld->name = name ? name : "(config)";
    ld->err = err;
    ld->errlen = errlen;
    if (err && errlen) err[0] = '\0';
    if (!set || (set->n && (!set->tables || !set->targets))) {
        ld->set = NULL;
        return fail(ld, OCEAN_EINVAL, "no configuration tables given", "", 0);
    }
    size_t n = set->n ? set->n : 1, total = 0;
    ld->scratch = calloc(n, sizeof *ld->scratch);
    ld->base = calloc(n, sizeof *ld->base);
    if (!ld->scratch || !ld->base) goto oom;
    for (size_t t = 0; t < set->n; t++) {
        ld->base[t] = total;
        total += set->tables[t]->count;
        ld->scratch[t] = malloc(set->tables[t]->target_size ? set->tables[t]->target_size : 1);
        if (!ld->scratch[t]) goto oom;
        memcpy(ld->scratch[t], set->targets[t], set->tables[t]->target_size);
    }
    if (track) {
        ld->seen = calloc(total ? total : 1, sizeof *ld->seen);
        if (!ld->seen) goto oom;
    }
    return OCEAN_OK;
oom:
    loader_free(ld);
    return fail(ld, OCEAN_ENOMEM, "out of memory loading the configuration", "", 0);
}

static void loader_commit(loader *ld)
{
    for (size_t t = 0; t < ld->set->n; t++)
        memcpy(ld->set->targets[t], ld->scratch[t], ld->set->tables[t]->target_size);
}

/* Writes every default into the scratch copies. */
static ocean_result apply_defaults(loader *ld)
{
    char msg[MSG_MAX];
    for (size_t t = 0; t < ld->set->n; t++) {
        const conf_table *tab = ld->set->tables[t];
        for (size_t i = 0; i < tab->count; i++) {
            const conf_entry *e = &tab->entries[i];
            if (e->def == NULL) {
                if (e->type == CONF_STRING && !(e->flags & CONF_F_NOSTORE))
                    memset((char *)ld->scratch[t] + e->offset, 0, e->size);
                continue;
            }
            char buf[CONF_MAX_LINE + 1];
            snprintf(buf, sizeof buf, "%s", e->def);
            const char *bad;
            size_t badlen;
            ocean_result r = parse_value(e, ld->scratch[t], buf, false, msg, sizeof msg, &bad, &badlen);
            if (r != OCEAN_OK) {
                char full[MSG_MAX + 32];
                snprintf(full, sizeof full, "bad default in table %s: %s", tab->name, msg);
                return fail(ld, r, full, bad, badlen);
            }
        }
    }
    return OCEAN_OK;
}

ocean_result conf_defaults(const conf_set *set, char *err, size_t errlen)
{
    loader ld;
    ocean_result r = loader_init(&ld, set, NULL, "defaults", false, err, errlen);
    if (r != OCEAN_OK) return r;
    r = apply_defaults(&ld);
    if (r == OCEAN_OK) loader_commit(&ld);
    loader_free(&ld);
    return r;
}

ocean_result conf_load_string(const char *name, const char *text, size_t len,
                              const conf_set *set, const conf_load_opts *opts,
                              char *err, size_t errlen)
{
    loader ld;
    char msg[MSG_MAX];
    ocean_result r = loader_init(&ld, set, opts, name, true, err, errlen);
    if (r != OCEAN_OK) return r;
    if (!text && len) {
        r = fail(&ld, OCEAN_EINVAL, "no text given", "", 0);
        goto out;
    }
    if (len > CONF_MAX_FILE) {
        ocean_seterr(msg, sizeof msg, "file too large (%zu bytes, at most %u)", len, CONF_MAX_FILE);
        r = fail(&ld, OCEAN_ETOOBIG, msg, "", 0);
        goto out;
    }
    if (!(opts && (opts->flags & CONF_NO_DEFAULTS)) && (r = apply_defaults(&ld)) != OCEAN_OK)
        goto out;

    size_t pos = 0;
    if (len >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0) pos = 3;
    char buf[CONF_MAX_LINE + 1];
    while (pos < len) {
        const char *s = text + pos;
        const char *nl = memchr(s, '\n', len - pos);
        size_t l = nl ? (size_t)(nl - s) : len - pos;
        pos += l + (nl ? 1 : 0);
        ld.line++;
        if (l > 0 && s[l - 1] == '\r') l--; /* CRLF files */
        if ((r = line_check(&ld, s, l)) != OCEAN_OK) goto out;
        memcpy(buf, s, l);
        buf[l] = '\0';
        bool empty;
        if ((r = line_parse(&ld, buf, &empty)) != OCEAN_OK) goto out;
    }
    ld.line = 0;
    for (size_t t = 0; t < set->n; t++)
        for (size_t i = 0; i < set->tables[t]->count; i++) {
            const conf_entry *e = &set->tables[t]->entries[i];
            if ((e->flags & CONF_F_REQUIRED) && !ld.seen[ld.base[t] + i]) {
                r = fail(&ld, OCEAN_EFORMAT, "missing required key", e->name, strlen(e->name));
                goto out;
            }
        }
    loader_commit(&ld);
    r = OCEAN_OK;
out:
    loader_free(&ld);
    return r;
}

ocean_result conf_load_file(const char *path, const conf_set *set,
                            const conf_load_opts *opts, char *err, size_t errlen)
{
    if (err && errlen) err[0] = '\0';
    if (!path) {
        if (err && errlen) snprintf(err, errlen, "(config): no file name given");
        return OCEAN_EINVAL;
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        if (err && errlen) snprintf(err, errlen, "%s: cannot open: %s", path, strerror(errno));
        return OCEAN_EIO;
    }
    /* Read one byte past the limit so an oversized file is recognised. */
    char *text = malloc(CONF_MAX_FILE + 1);
    if (!text) {
        fclose(f);
        if (err && errlen) snprintf(err, errlen, "%s: out of memory", path);
        return OCEAN_ENOMEM;
    }
    size_t len = fread(text, 1, CONF_MAX_FILE + 1, f);
    int rerr = ferror(f) ? errno : 0;
    fclose(f);
    ocean_result r;
    if (rerr) {
        if (err && errlen) snprintf(err, errlen, "%s: cannot read: %s", path, strerror(rerr));
        r = OCEAN_EIO;
    } else if (len > CONF_MAX_FILE) {
        if (err && errlen)
            snprintf(err, errlen, "%s: file too large (more than %u bytes)", path, CONF_MAX_FILE);
        r = OCEAN_ETOOBIG;
    } else {
        r = conf_load_string(path, text, len, set, opts, err, errlen);
    }
    free(text);
    return r;
}

ocean_result conf_apply(const char *keyvalue, const conf_set *set, char *err, size_t errlen)
{
    loader ld;
    ocean_result r = loader_init(&ld, set, NULL, "--set", false, err, errlen);
    if (r != OCEAN_OK) return r;
    size_t len = keyvalue ? strlen(keyvalue) : 0;
    if ((r = line_check(&ld, keyvalue ? keyvalue : "", len)) == OCEAN_OK) {
        char buf[CONF_MAX_LINE + 1];
        memcpy(buf, keyvalue, len);
        buf[len] = '\0';
        bool empty;
        r = line_parse(&ld, buf, &empty);
        if (r == OCEAN_OK && empty)
            r = fail(&ld, OCEAN_EFORMAT, "expected key=value", keyvalue ? keyvalue : "", len);
        if (r == OCEAN_OK) loader_commit(&ld);
    }
    loader_free(&ld);
    return r;
}

/* ---- checks ----------------------------------------------------------------- */

ocean_result conf_set_check(const conf_set *set, char *err, size_t errlen)
{
    loader ld;
    char msg[MSG_MAX];
    ocean_result r = loader_init(&ld, set, NULL, "table", false, err, errlen);
    if (r != OCEAN_OK) return r;
    for (size_t t = 0; t < set->n && r == OCEAN_OK; t++) {
        const conf_table *tab = set->tables[t];
        if (!tab->entries && tab->count) {
            r = fail(&ld, OCEAN_EINVAL, "table has no entries array", tab->name, strlen(tab->name));
            break;
        }
        for (size_t i = 0; i < tab->count && r == OCEAN_OK; i++) {
            const conf_entry *e = &tab->entries[i];
            size_t ft;
            const char *why = NULL;
            if (!e->name || !key_valid(e->name, strlen(e->name))) why = "bad key name";
            else if (conf_find(set, e->name, &ft) != e || ft != t) why = "key defined twice";
            else if (!e->help || !*e->help) why = "no help text";
            else if ((e->flags & CONF_F_NOSTORE) && !e->hook) why = "NOSTORE entry without a hook";
            else if (!(e->flags & CONF_F_NOSTORE) && e->offset >= tab->target_size) why = "offset outside the target";
            else if (e->type == CONF_STRING && (e->size < 2 || e->offset + e->size > tab->target_size)) why = "bad string size";
            else if ((e->type == CONF_ENUM || e->type == CONF_FLAGS) && (!e->names || !e->names[0].name)) why = "no names";
            else if ((e->type == CONF_INT || e->type == CONF_U64 || e->type == CONF_DOUBLE) &&
                     !(e->min <= e->max))
                why = "min > max";
            else if (e->type == CONF_INT && (e->min < -2147483648.0 || e->max > 2147483647.0)) why = "int range beyond int";
            else if ((e->flags & CONF_F_REQUIRED) && e->def) why = "required key with a default";
            if (why) {
                ocean_seterr(msg, sizeof msg, "table %s: %s", tab->name, why);
                r = fail(&ld, OCEAN_EINVAL, msg, e->name ? e->name : "", e->name ? strlen(e->name) : 0);
            }
        }
    }
    if (r == OCEAN_OK) r = apply_defaults(&ld);
    loader_free(&ld);
    return r;
}

/* ---- output ------------------------------------------------------------------ */

int conf_format(const conf_entry *e, const void *target, char *buf, size_t len)
{
    const char *field = (const char *)target + e->offset;
    if (e->flags & CONF_F_NOSTORE) return snprintf(buf, len, "%s", "");
    switch (e->type) {
    case CONF_INT: {
        int v;
        memcpy(&v, field, sizeof v);
        return snprintf(buf, len, "%d", v);
    }
    case CONF_U64: {
        uint64_t v;
        memcpy(&v, field, sizeof v);
        return snprintf(buf, len, "%" PRIu64, v);
    }
    case CONF_DOUBLE: {
        double v;
        memcpy(&v, field, sizeof v);
        return fmt_double(v, buf, len);
    }
    case CONF_BOOL: {
        int v;
        memcpy(&v, field, sizeof v);
        return snprintf(buf, len, "%s", v ? "on" : "off");
    }
    case CONF_ENUM: {
        int v;
        memcpy(&v, field, sizeof v);
        for (const conf_name *n = e->names; n && n->name; n++)
            if ((int)n->value == v) return snprintf(buf, len, "%s", n->name);
        return snprintf(buf, len, "%d", v); /* not a name: reloading will refuse it */
    }
    case CONF_FLAGS: {
        unsigned v, done = 0;
        memcpy(&v, field, sizeof v);
        if (v == 0) return snprintf(buf, len, "none");
        size_t o = 0;
        int need = 0;
        for (const conf_name *n = e->names; n && n->name; n++)
            if (n->value && (v & n->value) == n->value && (done & n->value) != n->value) {
                int k = snprintf(o < len ? buf + o : NULL, o < len ? len - o : 0, "%s%s",
                                 need ? "," : "", n->name);
                need += k;
                o += (size_t)k;
                done |= n->value;
            }
        if (done != v) { /* bits without a name: show them so the problem is visible */
            int k = snprintf(o < len ? buf + o : NULL, o < len ? len - o : 0, "%s0x%x",
                             need ? "," : "", v & ~done);
            need += k;
        }
        return need;
    }
    case CONF_STRING: {
        size_t n = strnlen(field, e->size);
        bool quote = n == 0 || is_blank(field[0]) || is_blank(field[n - 1]) || field[0] == '"' ||
                     memchr(field, '#', n) != NULL;
        if (!quote) return snprintf(buf, len, "%.*s", (int)n, field);
        size_t o = 0;
        char tmp[4];
        /* Builds "...", escaping quote and backslash; counts even past len. */
        for (size_t i = 0; i <= n + 1; i++) {
            size_t k = 0;
            if (i == 0 || i == n + 1) tmp[k++] = '"';
            else {
                char c = field[i - 1];
                if (c == '"' || c == '\\') tmp[k++] = '\\';
                tmp[k++] = c;
            }
            for (size_t j = 0; j < k; j++, o++)
                if (o + 1 < len) buf[o] = tmp[j];
        }
        if (len) buf[o < len ? o : len - 1] = '\0';
        return (int)o;
    }
    }
    return snprintf(buf, len, "?");
}

/* Writes text as "# " comment lines wrapped at about 78 columns. */
static void put_wrapped(FILE *out, const char *text)
{
    const char *p = text;
    while (*p) {
        while (*p == ' ') p++;
        if (!*p) break;
        size_t n = strlen(p), cut = n;
        if (n > 76) {
            cut = 76;
            while (cut > 0 && p[cut] != ' ') cut--;
            if (cut == 0) cut = 76;
        }
        fprintf(out, "# %.*s\n", (int)cut, p);
        p += cut;
    }
}

ocean_result conf_dump(FILE *out, const conf_set *set, unsigned flags)
{
    if (!out || !set) return OCEAN_EINVAL;
    char val[CONF_MAX_LINE], line[CONF_MAX_LINE * 2];
    for (size_t t = 0; t < set->n; t++) {
        const conf_table *tab = set->tables[t];
        fprintf(out, "%s# ---- %s ----\n", t ? "\n" : "", tab->title ? tab->title : tab->name);
        for (size_t i = 0; i < tab->count; i++) {
            const conf_entry *e = &tab->entries[i];
            if (flags & CONF_DUMP_HELP) {
                fputs("\n", out);
                put_wrapped(out, e->help);
                size_t o = 0;
                char range[96];
                fmt_range(e, range, sizeof range);
                if (e->unit) o += (size_t)snprintf(line + o, sizeof line - o, "Unit: %s. ", e->unit);
                if (e->type == CONF_INT || e->type == CONF_U64 || e->type == CONF_DOUBLE)
                    o += (size_t)snprintf(line + o, sizeof line - o, "Range: %s%s. ", range,
                                          (e->flags & CONF_F_INF_OK) && isfinite(e->max) ? " or inf" : "");
                if (e->type == CONF_BOOL)
                    o += (size_t)snprintf(line + o, sizeof line - o, "Boolean: on/off. ");
                if (e->type == CONF_STRING)
                    o += (size_t)snprintf(line + o, sizeof line - o, "Text, at most %zu bytes. ",
                                          e->size - 1);
                if (e->type == CONF_ENUM || e->type == CONF_FLAGS) {
                    names_list(e, val, sizeof val);
                    o += (size_t)snprintf(line + o, sizeof line - o, "%s: %s%s. ",
                                          e->type == CONF_ENUM ? "One of" : "Comma list of", val,
                                          e->type == CONF_FLAGS ? (e->min >= 1 ? "; or all" : "; or none, all") : "");
                }
                if (e->flags & CONF_F_REQUIRED)
                    o += (size_t)snprintf(line + o, sizeof line - o, "Required. ");
                else if (e->def)
                    o += (size_t)snprintf(line + o, sizeof line - o, "Default: %s.",
                                          *e->def ? e->def : "empty");
                else
                    o += (size_t)snprintf(line + o, sizeof line - o, "Optional, unset by default.");
                if (o >= sizeof line) o = sizeof line - 1;
                while (o > 0 && line[o - 1] == ' ') line[--o] = '\0';
                put_wrapped(out, line);
            }
            if (e->flags & CONF_F_NOSTORE) {
                fprintf(out, "# %s =\n", e->name);
            } else {
                conf_format(e, set->targets[t], val, sizeof val);
                fprintf(out, "%s = %s\n", e->name, val);
            }
        }
    }
    return ferror(out) ? OCEAN_EIO : OCEAN_OK;
}
