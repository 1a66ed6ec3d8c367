/*
 * srv_record.h - opt-in recording of a client's camera path in the text
 * format of server/RECORDING.md (CSV, one line per CAMERA report), which
 * `ocean-client replay` reads back.
 */
#ifndef SRV_RECORD_H
#define SRV_RECORD_H

#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>

#include "ocean_result.h"
#include "proto.h"

typedef struct srv_record srv_record;

/* Creates dir/client-<id>-<unix time>.csv (creating dir) and writes the
 * header.  Only a new file: an existing name, a symlink included, is never
 * opened; the next free of client-<id>-<unix time>-1.csv .. -99.csv is
 * taken instead.  *out is NULL on failure (OCEAN_EIO, OCEAN_ENOMEM); msg
 * says why, naming the path.  path (if not NULL) receives the file name. */
ocean_result srv_record_open(const char *dir, uint32_t client_id, const char *scene,
                             srv_record **out, char *path, size_t pathlen, char *msg, size_t msglen);
/* Notes an accepted SUBSCRIBE's mode at sim time t as a comment line: the
 * t column of the lines after it is the server's clock (live) or the
 * CAMERA's render_time (replay), and the mode is known only then, not when
 * the file is opened.  Counted and stopped as srv_record_camera. */
ocean_result srv_record_mode(srv_record *r, double t, int replay);
/* Counts what r writes into *used, shared by every recording of a run; a
 * report that could take *used past quota stops the recording instead. */
void srv_record_set_quota(srv_record *r, atomic_uint_fast64_t *used, uint64_t quota);
/* Appends one report at sim time t.  Buffered; flushed at most once a
 * second.  After a write error the recording stops and OCEAN_EIO is
 * returned (once); at the quota, OCEAN_ETOOBIG (once). */
ocean_result srv_record_camera(srv_record *r, double t, const proto_camera *cam);
/* Writes one report line to f in the recording format (shared with tests). */
int srv_record_format(FILE *f, double t, const proto_camera *cam);
/* "PATH: reason" of r's write failure into buf (n bytes); returns buf. */
const char *srv_record_why(const srv_record *r, char *buf, size_t n);
/* Flushes, closes and frees r.  OCEAN_EIO when a write, flush or the close
 * failed (lines were lost): why (if not NULL) gets "PATH: reason".  Accepts
 * NULL. */
ocean_result srv_record_close(srv_record *r, char *why, size_t whylen);

#endif
