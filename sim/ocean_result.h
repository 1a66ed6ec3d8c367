/*
 * ocean_result.h - the one result enum of the whole oceand project.
 *
 * Every fallible function in sim/, protocol/, server/ and clients/ returns an
 * ocean_result; outputs travel through pointer arguments.  Codes are stable
 * (they appear on the wire in ERROR messages), so append, never renumber.
 *
 * Out-of-memory policy: a failed allocation is reported as OCEAN_ENOMEM and
 * the object being built is left unchanged (or, for *_create, not created).
 * Nothing aborts on OOM; the daemon drops the frame or client concerned and
 * carries on.
 */
#ifndef OCEAN_RESULT_H
#define OCEAN_RESULT_H

#include <stddef.h>

typedef enum ocean_result {
    OCEAN_OK = 0,
    OCEAN_EINVAL = 1,      /* an argument is out of range, NaN/Inf or absurd */
    OCEAN_ENOMEM = 2,      /* an allocation failed */
    OCEAN_EIO = 3,         /* a file or socket operation failed */
    OCEAN_EFORMAT = 4,     /* malformed input: config text, message, file */
    OCEAN_EVERSION = 5,    /* unsupported protocol or file version */
    OCEAN_ETYPE = 6,       /* unknown message type or enum value */
    OCEAN_ETRUNC = 7,      /* input shorter than its header says */
    OCEAN_ETOOBIG = 8,     /* input or output exceeds a configured limit */
    OCEAN_EUNSUPPORTED = 9,/* valid request this build or state cannot serve */
    OCEAN_EAUTH = 10,      /* admin token missing or wrong */
    OCEAN_ERATE = 11,      /* rate limit exceeded */
    OCEAN_ESTATE = 12,     /* request not valid in the current state */
    OCEAN_ECODEC = 13,     /* a codec failed to encode or decode */
    OCEAN_ENOTFOUND = 14,  /* a named thing (scene, file, key) does not exist */
    OCEAN_EDIVERGED = 15,  /* an iteration did not converge */
    OCEAN_RESULT_COUNT_
} ocean_result;

/* Returns a static, human-readable description of r; never NULL (unknown
 * codes give "unknown error"). */
const char *ocean_strerror(ocean_result r);

/* printf into a caller's error buffer; does nothing when err is NULL or
 * errlen is 0, so every "char *err, size_t errlen" API can make the
 * buffer optional.  The text is always NUL-terminated (cut if too long). */
void ocean_seterr(char *err, size_t errlen, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

#endif
