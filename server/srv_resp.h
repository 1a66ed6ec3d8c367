/*
 * srv_resp.h - one Redis reply (RESP 2) read from a socket within limits.
 *
 * A reply from a shared Redis is as hostile as any client message: a stream
 * entry may hold 512 MB.  This reader keeps at most srv_resp_limits of it
 * in memory: a bulk string over max_string bytes, or past max_total kept in
 * all, is read off the socket and dropped, its node saying only its length
 * (SRV_RESP_SKIPPED); an array over max_array elements, or past max_nodes,
 * is read off and dropped the same way.  A string of at most SRV_RESP_SMALL
 * bytes (an id, a field name) is kept past max_total, so the keys of a
 * reply survive its large values; max_nodes bounds those.  The connection stays in step: the
 * whole reply is always consumed.  hiredis 0.14 (Debian 12) has no such
 * limit: its reader builds the whole reply in memory.
 *
 * Threads: none of its own; a reply belongs to the caller.
 */
#ifndef SRV_RESP_H
#define SRV_RESP_H

#include <stddef.h>

#include "ocean_result.h"

#define SRV_RESP_SMALL 64

typedef enum srv_resp_type {
    SRV_RESP_STRING,    /* bulk string: str, len */
    SRV_RESP_SKIPPED,   /* bulk string or array over the limits: its length in integer */
    SRV_RESP_INTEGER,
    SRV_RESP_ARRAY,     /* elem, n */
    SRV_RESP_NIL,
    SRV_RESP_STATUS,    /* +OK: str */
    SRV_RESP_ERROR,     /* -ERR ...: str */
} srv_resp_type;

typedef struct srv_resp {
    srv_resp_type type;
    long long integer;
    char *str;          /* NUL-terminated copy (a string may hold NULs: len counts them) */
    size_t len;
    struct srv_resp *elem;
    size_t n;
} srv_resp;

typedef struct srv_resp_limits {
    size_t max_string;  /* bytes of one kept bulk string */
    size_t max_total;   /* bytes of strings kept in one reply */
    size_t max_array;   /* elements of one kept array */
    size_t max_nodes;   /* nodes kept in one reply */
    double idle_s;      /* the longest wait for the next bytes */
} srv_resp_limits;

/* Reads one reply from fd (a blocking or non-blocking socket) into *out.
 * OCEAN_EIO (why filled) when the connection fails, stalls for idle_s, or
 * sends no RESP; the connection is then out of step and must be closed.
 * OCEAN_ENOMEM likewise. */
ocean_result srv_resp_read(int fd, const srv_resp_limits *lim, srv_resp **out, char *why, size_t whylen);
/* Accepts NULL. */
void srv_resp_free(srv_resp *r);

#endif
