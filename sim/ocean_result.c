/*
 * ocean_result.c - descriptions for the project-wide result codes.
 */
#include "ocean_result.h"

#include <stdarg.h>
#include <stdio.h>

const char *ocean_strerror(ocean_result r)
{
    switch (r) {
    case OCEAN_OK: return "success";
    case OCEAN_EINVAL: return "invalid argument";
    case OCEAN_ENOMEM: return "out of memory";
    case OCEAN_EIO: return "input/output error";
    case OCEAN_EFORMAT: return "malformed input";
    case OCEAN_EVERSION: return "unsupported version";
    case OCEAN_ETYPE: return "unknown type or enum value";
    case OCEAN_ETRUNC: return "truncated input";
    case OCEAN_ETOOBIG: return "size limit exceeded";
    case OCEAN_EUNSUPPORTED: return "not supported";
    case OCEAN_EAUTH: return "not authorised";
    case OCEAN_ERATE: return "rate limit exceeded";
    case OCEAN_ESTATE: return "not valid in the current state";
    case OCEAN_ECODEC: return "codec failure";
    case OCEAN_ENOTFOUND: return "not found";
    case OCEAN_EDIVERGED: return "iteration did not converge";
    case OCEAN_RESULT_COUNT_: break;
    }
    return "unknown error";
}

void ocean_seterr(char *err, size_t errlen, const char *fmt, ...)
{
    if (!err || !errlen)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}
