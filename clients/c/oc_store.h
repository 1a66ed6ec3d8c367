/*
 * oc_store.h - frame-store files: what ocean-client record/replay save, so
 * a run can be checked byte for byte against an earlier one.
 *
 * Format (little-endian):
 *   file header, 16 bytes:  "OCFRAMES" (8 bytes), u32 version = 1,
 *                           u32 reserved = 0
 *   then one record per received message, in order of receipt:
 *     u32 length            bytes of the message that follows (>= 32)
 *     u32 reserved = 0
 *     f64 recv_time         seconds since the recording started
 *     length bytes          the complete wire message (header included)
 * A file is truncated at most at a record boundary by a clean close; a
 * reader reports a partial record as OCEAN_ETRUNC with its offset.
 *
 * Comparison (oc_store_compare) looks at the messages whose type is in a
 * mask (default: FRAME, MESH_TOPOLOGY, QUERY_RESULT - the content a replay
 * must reproduce; HELLO carries a per-connection client id) and compares
 * them in order, byte for byte, except the 4-byte header seq (a
 * per-connection message counter, bytes 16..19).  Receive times are
 * ignored.
 */
#ifndef OC_STORE_H
#define OC_STORE_H

#include <stddef.h>
#include <stdint.h>

#include "ocean_result.h"

#define OC_STORE_MAGIC "OCFRAMES"
#define OC_STORE_VERSION 1u
#define OC_STORE_HEADER 16
#define OC_STORE_RECORD_HEAD 16
#define OC_STORE_MAX_MESSAGE (256u << 20)

typedef struct oc_store_writer oc_store_writer;

/* Creates (truncates) path and writes the file header. */
ocean_result oc_store_writer_open(const char *path, oc_store_writer **out, char *err, size_t errlen);
/* Appends one record.  OCEAN_EIO on a write error (sticky), OCEAN_EINVAL for
 * len < 32 or above OC_STORE_MAX_MESSAGE. */
ocean_result oc_store_writer_append(oc_store_writer *w, double recv_time, const void *msg, size_t len);
/* Flushes and closes; OCEAN_EIO if any write failed.  Accepts NULL. */
ocean_result oc_store_writer_close(oc_store_writer *w);
/* Records appended so far. */
uint64_t oc_store_writer_count(const oc_store_writer *w);

typedef struct oc_store_reader oc_store_reader;

/* Opens and checks the file header (OCEAN_EFORMAT: not a frame store,
 * OCEAN_EVERSION: another version). */
ocean_result oc_store_reader_open(const char *path, oc_store_reader **out, char *err, size_t errlen);
/* Next record: *msg valid until the next call.  OCEAN_ENOTFOUND at the
 * clean end of the file; OCEAN_ETRUNC / OCEAN_EFORMAT for damage (err
 * names the record index and file offset). */
ocean_result oc_store_reader_next(oc_store_reader *r, const uint8_t **msg, size_t *len,
                                  double *recv_time, char *err, size_t errlen);
void oc_store_reader_close(oc_store_reader *r);   /* accepts NULL */

/* Type mask bit for a message type. */
#define OC_STORE_TYPE_BIT(t) (1u << (t))
#define OC_STORE_COMPARE_DEFAULT \
    (OC_STORE_TYPE_BIT(4) | OC_STORE_TYPE_BIT(6) | OC_STORE_TYPE_BIT(9))

typedef struct oc_store_diff {
    int identical;            /* 1: same messages, same bytes */
    uint64_t compared;        /* messages compared (in the mask, both sides) */
    uint64_t count_a, count_b;/* messages in the mask in each file */
    int64_t first_index;      /* index among masked messages of the first
                                 difference, -1 if none */
    int64_t first_offset;     /* byte offset inside that message, -1 if the
                                 lengths/counts differ rather than bytes */
    char what[512];           /* human description of the first difference */
} oc_store_diff;

/* Compares two stores as described above.  Returns OCEAN_OK when both files
 * could be read (then out->identical says the verdict), or the reading
 * error. */
ocean_result oc_store_compare(const char *path_a, const char *path_b, unsigned type_mask,
                              oc_store_diff *out, char *err, size_t errlen);

#endif
