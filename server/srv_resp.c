/*
 * srv_resp.c - a bounded RESP 2 reader (see srv_resp.h).
 *
 * The protocol: https://redis.io/docs/reference/protocol-spec/ (RESP 2):
 * every element starts with a type byte and a line ending in CRLF; a bulk
 * string's line gives its length, then come that many bytes and CRLF; an
 * array's line gives its element count.  Lengths are read before any
 * payload, which is what lets this reader drop what it will not keep.
 */
#include "srv_resp.h"

#include <errno.h>
#include <poll.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define LINE_MAX_BYTES 512  /* a type line: a number, or a status or error text */
#define DEPTH_MAX 8         /* nesting Redis never needs more of for one command */

typedef struct reader {
    int fd;
    const srv_resp_limits *lim;
    unsigned char buf[16384];
    size_t at, end;
    size_t kept_bytes, kept_nodes;
    int failed;
    char *why;
    size_t whylen;
} reader;

static void fail(reader *r, const char *what)
{
    if (!r->failed) snprintf(r->why, r->whylen, "Redis reply: %s", what);
    r->failed = 1;
}

/* Refills the buffer; 0 on failure.  It waits in poll, not in read: a
 * socket with a receive timeout of its own would make the wait twice as
 * long. */
static int fill(reader *r)
{
    if (r->failed) return 0;
    r->at = r->end = 0;
    for (;;) {
        struct pollfd p = {.fd = r->fd, .events = POLLIN};
        int ready = poll(&p, 1, (int)(r->lim->idle_s * 1e3));
        if (ready < 0 && errno == EINTR) continue;
        if (ready <= 0) {
            fail(r, ready < 0 ? strerror(errno) : "no bytes within the timeout");
            return 0;
        }
        ssize_t n = read(r->fd, r->buf, sizeof r->buf);
        if (n > 0) {
            r->end = (size_t)n;
            return 1;
        }
        if (n < 0 && (errno == EINTR || errno == EAGAIN || errno == EWOULDBLOCK)) continue;
        fail(r, n == 0 ? "connection closed" : strerror(errno));
        return 0;
    }
}

/* One CRLF-terminated line into out (without CRLF); 0 on failure. */
static int read_line(reader *r, char *out, size_t cap)
{
    size_t k = 0;
    for (;;) {
        if (r->at == r->end && !fill(r)) return 0;
        char ch = (char)r->buf[r->at++];
        if (ch == '\n') break;
        if (k + 1 >= cap) {
            fail(r, "a line too long");
            return 0;
        }
        out[k++] = ch;
    }
    if (k == 0 || out[k - 1] != '\r') {
        fail(r, "a line without CRLF");
        return 0;
    }
    out[k - 1] = '\0';
    return 1;
}

/* n payload bytes into dst, or dropped (dst NULL); 0 on failure. */
static int read_bytes(reader *r, char *dst, size_t n)
{
    while (n > 0) {
        if (r->at == r->end && !fill(r)) return 0;
        size_t k = r->end - r->at < n ? r->end - r->at : n;
        if (dst) {
            memcpy(dst, r->buf + r->at, k);
            dst += k;
        }
        r->at += k;
        n -= k;
    }
    return 1;
}

static int parse_number(reader *r, const char *s, long long *out)
{
    char *end;
    errno = 0;
    *out = strtoll(s, &end, 10);
    if (end == s || *end || errno) {
        fail(r, "a bad number");
        return 0;
    }
    return 1;
}

static int parse(reader *r, srv_resp *out, int depth);

/* A bulk string of length len (after its line). */
static int parse_bulk(reader *r, srv_resp *out, long long len)
{
    size_t n = (size_t)len;
    int keep = out && n <= r->lim->max_string && (n <= SRV_RESP_SMALL || r->kept_bytes + n <= r->lim->max_total);
    char *s = keep ? malloc(n + 1) : NULL;
    if (keep && !s) {
        fail(r, "out of memory");
        return 0;
    }
    if (!read_bytes(r, s, n)) {
        free(s);
        return 0;
    }
    char crlf[2];
    if (!read_bytes(r, crlf, 2) || crlf[0] != '\r' || crlf[1] != '\n') {
        free(s);
        fail(r, "a bulk string without CRLF");
        return 0;
    }
    if (!out) return 1;
    if (!keep) {
        out->type = SRV_RESP_SKIPPED;
        out->integer = len;
        return 1;
    }
    s[n] = '\0';
    r->kept_bytes += n;
    out->type = SRV_RESP_STRING;
    out->str = s;
    out->len = n;
    return 1;
}

/* An array of n elements (after its line). */
static int parse_array(reader *r, srv_resp *out, long long n, int depth)
{
    size_t count = (size_t)n;
    int keep = out && count <= r->lim->max_array && r->kept_nodes + count <= r->lim->max_nodes;
    if (keep && count) {
        out->elem = calloc(count, sizeof *out->elem);
        if (!out->elem) {
            fail(r, "out of memory");
            return 0;
        }
        r->kept_nodes += count;
    }
    if (out) {
        out->type = keep ? SRV_RESP_ARRAY : SRV_RESP_SKIPPED;
        out->integer = n;
        out->n = keep ? count : 0;
    }
    for (size_t i = 0; i < count; i++)
        if (!parse(r, keep ? &out->elem[i] : NULL, depth + 1)) return 0;
    return 1;
}

/* One element into out (NULL: read and dropped). */
static int parse(reader *r, srv_resp *out, int depth)
{
    char line[LINE_MAX_BYTES];
    if (depth > DEPTH_MAX) {
        fail(r, "nested too deep");
        return 0;
    }
    if (!read_line(r, line, sizeof line)) return 0;
    long long v = 0;
    switch (line[0]) {
    case '+':
    case '-':
        if (out) {
            out->type = line[0] == '+' ? SRV_RESP_STATUS : SRV_RESP_ERROR;
            out->str = strdup(line + 1);
            out->len = out->str ? strlen(out->str) : 0;
            if (!out->str) fail(r, "out of memory");
        }
        return !r->failed;
    case ':':
        if (!parse_number(r, line + 1, &v)) return 0;
        if (out) {
            out->type = SRV_RESP_INTEGER;
            out->integer = v;
        }
        return 1;
    case '$':
    case '*':
        if (!parse_number(r, line + 1, &v)) return 0;
        if (v < -1) {
            fail(r, "a negative length");
            return 0;
        }
        if (v == -1) {
            if (out) out->type = SRV_RESP_NIL;
            return 1;
        }
        return line[0] == '$' ? parse_bulk(r, out, v) : parse_array(r, out, v, depth);
    default:
        fail(r, "an unknown type byte");
        return 0;
    }
}

ocean_result srv_resp_read(int fd, const srv_resp_limits *lim, srv_resp **out, char *why, size_t whylen)
{
    *out = NULL;
    reader *r = calloc(1, sizeof *r);
    srv_resp *root = calloc(1, sizeof *root);
    if (!r || !root) {
        free(r);
        free(root);
        snprintf(why, whylen, "Redis reply: out of memory");
        return OCEAN_ENOMEM;
    }
    r->fd = fd;
    r->lim = lim;
    r->why = why;
    r->whylen = whylen;
    int ok = parse(r, root, 0);
    if (ok && r->at != r->end) {
        fail(r, "bytes after the reply");
        ok = 0;
    }
    free(r);
    if (!ok) {
        srv_resp_free(root);
        return OCEAN_EIO;
    }
    *out = root;
    return OCEAN_OK;
}

static void free_node(srv_resp *n)
{
    for (size_t i = 0; i < n->n; i++) free_node(&n->elem[i]);
    free(n->elem);
    free(n->str);
}

void srv_resp_free(srv_resp *r)
{
    if (!r) return;
    free_node(r);
    free(r);
}
