/*
 * oc_store.c - frame-store files (see oc_store.h).
 */
#include "oc_store.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "proto.h"

struct oc_store_writer {
    FILE *f;
    int failed;
    uint64_t count;
};

ocean_result oc_store_writer_open(const char *path, oc_store_writer **out, char *err, size_t errlen)
{
    if (!path || !out)
        return OCEAN_EINVAL;
    *out = NULL;
    oc_store_writer *w = calloc(1, sizeof *w);
    if (!w)
        return OCEAN_ENOMEM;
    w->f = fopen(path, "wb");
    if (!w->f) {
        ocean_seterr(err, errlen, "%s: cannot create: %s", path, strerror(errno));
        free(w);
        return OCEAN_EIO;
    }
    uint8_t h[OC_STORE_HEADER];
    memcpy(h, OC_STORE_MAGIC, 8);
    proto_st32(h + 8, OC_STORE_VERSION);
    proto_st32(h + 12, 0);
    if (fwrite(h, 1, sizeof h, w->f) != sizeof h) {
        ocean_seterr(err, errlen, "%s: write failed: %s", path, strerror(errno));
        fclose(w->f);
        free(w);
        return OCEAN_EIO;
    }
    *out = w;
    return OCEAN_OK;
}

ocean_result oc_store_writer_append(oc_store_writer *w, double recv_time, const void *msg, size_t len)
{
    if (!w || !msg || len < PROTO_HEADER_SIZE || len > OC_STORE_MAX_MESSAGE)
        return OCEAN_EINVAL;
    if (w->failed)
        return OCEAN_EIO;
    uint8_t h[OC_STORE_RECORD_HEAD];
    proto_st32(h, (uint32_t)len);
    proto_st32(h + 4, 0);
    proto_stf64(h + 8, recv_time);
    if (fwrite(h, 1, sizeof h, w->f) != sizeof h || fwrite(msg, 1, len, w->f) != len) {
        w->failed = 1;
        return OCEAN_EIO;
    }
    w->count++;
    return OCEAN_OK;
}

uint64_t oc_store_writer_count(const oc_store_writer *w) { return w ? w->count : 0; }

ocean_result oc_store_writer_close(oc_store_writer *w)
{
    if (!w)
        return OCEAN_OK;
    int bad = w->failed;
    if (fclose(w->f) != 0)
        bad = 1;
    free(w);
    return bad ? OCEAN_EIO : OCEAN_OK;
}

struct oc_store_reader {
    FILE *f;
    char *path;
    uint8_t *buf;
    size_t cap;
    uint64_t index;
    uint64_t offset;
};

ocean_result oc_store_reader_open(const char *path, oc_store_reader **out, char *err, size_t errlen)
{
    if (!path || !out)
        return OCEAN_EINVAL;
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) {
        ocean_seterr(err, errlen, "%s: cannot open: %s", path, strerror(errno));
        return errno == ENOENT ? OCEAN_ENOTFOUND : OCEAN_EIO;
    }
    uint8_t h[OC_STORE_HEADER];
    size_t n = fread(h, 1, sizeof h, f);
    if (n != sizeof h || memcmp(h, OC_STORE_MAGIC, 8) != 0) {
        ocean_seterr(err, errlen, "%s: not a frame store (no \"%s\" header)", path, OC_STORE_MAGIC);
        fclose(f);
        return OCEAN_EFORMAT;
    }
    if (proto_ld32(h + 8) != OC_STORE_VERSION) {
        ocean_seterr(err, errlen, "%s: frame store version %u, this build reads %u", path, proto_ld32(h + 8),
               OC_STORE_VERSION);
        fclose(f);
        return OCEAN_EVERSION;
    }
    if (proto_ld32(h + 12) != 0) {
        ocean_seterr(err, errlen, "%s: reserved header field is not zero", path);
        fclose(f);
        return OCEAN_EFORMAT;
    }
    oc_store_reader *r = calloc(1, sizeof *r);
    char *p = strdup(path);
    if (!r || !p) {
        free(r);
        free(p);
        fclose(f);
        return OCEAN_ENOMEM;
    }
    r->f = f;
    r->path = p;
    r->offset = OC_STORE_HEADER;
    *out = r;
    return OCEAN_OK;
}

ocean_result oc_store_reader_next(oc_store_reader *r, const uint8_t **msg, size_t *len,
                                  double *recv_time, char *err, size_t errlen)
{
    if (!r || !msg || !len)
        return OCEAN_EINVAL;
    uint8_t h[OC_STORE_RECORD_HEAD];
    size_t n = fread(h, 1, sizeof h, r->f);
    if (n == 0 && feof(r->f))
        return OCEAN_ENOTFOUND;
    if (n != sizeof h) {
        ocean_seterr(err, errlen, "%s: record %llu at offset %llu: truncated record header", r->path,
               (unsigned long long)r->index, (unsigned long long)r->offset);
        return OCEAN_ETRUNC;
    }
    uint32_t l = proto_ld32(h);
    if (proto_ld32(h + 4) != 0 || l < PROTO_HEADER_SIZE || l > OC_STORE_MAX_MESSAGE) {
        ocean_seterr(err, errlen, "%s: record %llu at offset %llu: bad length %u or reserved field", r->path,
               (unsigned long long)r->index, (unsigned long long)r->offset, l);
        return OCEAN_EFORMAT;
    }
    if (l > r->cap) {
        uint8_t *nb = realloc(r->buf, l);
        if (!nb)
            return OCEAN_ENOMEM;
        r->buf = nb;
        r->cap = l;
    }
    if (fread(r->buf, 1, l, r->f) != l) {
        ocean_seterr(err, errlen, "%s: record %llu at offset %llu: message cut short (%u bytes announced)",
               r->path, (unsigned long long)r->index, (unsigned long long)r->offset, l);
        return OCEAN_ETRUNC;
    }
    *msg = r->buf;
    *len = l;
    if (recv_time)
        *recv_time = proto_ldf64(h + 8);
    r->index++;
    r->offset += OC_STORE_RECORD_HEAD + l;
    return OCEAN_OK;
}

void oc_store_reader_close(oc_store_reader *r)
{
    if (!r)
        return;
    fclose(r->f);
    free(r->buf);
    free(r->path);
    free(r);
}

/* Names the field of a message at byte offset off (for diff reports). */
static const char *field_at(const uint8_t *m, size_t len, size_t off)
{
    if (off < 4)
        return "header magic";
    if (off < 6)
        return "header version";
    if (off < 8)
        return "header type";
    if (off < 12)
        return "header flags";
    if (off < 16)
        return "header length";
    if (off < 24)
        return "header seq/reserved";
    if (off < 32)
        return "header sim_time";
    unsigned type = len >= 8 ? proto_ld16(m + 6) : 0;
    size_t p = off - 32;
    if (type == PROTO_FRAME) {
        if (p < 8)
            return "FRAME cutoff_k";
        if (p < 16)
            return "FRAME e_error";
        if (p < 40)
            return "FRAME origin";
        if (p < 44)
            return "FRAME camera_seq";
        if (p < 48)
            return "FRAME tick";
        if (p < 56)
            return "FRAME tile_count/has_mesh";
        return "FRAME tile or mesh records";
    }
    return "payload";
}

/* Next message of r whose type is in mask; OCEAN_ENOTFOUND at the end. */
static ocean_result next_masked(oc_store_reader *r, unsigned mask, const uint8_t **m, size_t *len,
                                char *err, size_t errlen)
{
    for (;;) {
        ocean_result res = oc_store_reader_next(r, m, len, NULL, err, errlen);
        if (res != OCEAN_OK)
            return res;
        unsigned type = proto_ld16(*m + 6);
        if (type < 32 && (mask & (1u << type)))
            return OCEAN_OK;
    }
}

ocean_result oc_store_compare(const char *path_a, const char *path_b, unsigned type_mask,
                              oc_store_diff *out, char *err, size_t errlen)
{
    if (!path_a || !path_b || !out)
        return OCEAN_EINVAL;
    memset(out, 0, sizeof *out);
    out->identical = 1;
    out->first_index = -1;
    out->first_offset = -1;
    if (!type_mask)
        type_mask = OC_STORE_COMPARE_DEFAULT;
    oc_store_reader *a = NULL, *b = NULL;
    ocean_result r = oc_store_reader_open(path_a, &a, err, errlen);
    if (r == OCEAN_OK)
        r = oc_store_reader_open(path_b, &b, err, errlen);
    if (r != OCEAN_OK) {
        oc_store_reader_close(a);
        return r;
    }
    /* Each reader owns its buffer, so ma and mb stay valid side by side. */
    int a_end = 0, b_end = 0;
    for (;;) {
        const uint8_t *ma = NULL, *mb = NULL;
        size_t la = 0, lb = 0;
        if (!a_end) {
            r = next_masked(a, type_mask, &ma, &la, err, errlen);
            if (r == OCEAN_ENOTFOUND)
                a_end = 1;
            else if (r != OCEAN_OK)
                break;
            else
                out->count_a++;
        }
        if (!b_end) {
            r = next_masked(b, type_mask, &mb, &lb, err, errlen);
            if (r == OCEAN_ENOTFOUND)
                b_end = 1;
            else if (r != OCEAN_OK)
                break;
            else
                out->count_b++;
        }
        r = OCEAN_OK;
        if (a_end && b_end)
            break;
        if (a_end || b_end)
            continue;   /* count the rest of the longer file */
        if (out->identical) {
            int64_t idx = (int64_t)out->compared;
            if (la != lb) {
                out->identical = 0;
                out->first_index = idx;
                snprintf(out->what, sizeof out->what,
                         "message %lld (%s): %zu bytes in %s, %zu bytes in %s", (long long)idx,
                         proto_type_name(proto_ld16(ma + 6)), la, path_a, lb, path_b);
            } else {
                for (size_t i = 0; i < la; i++) {
                    if (i >= 16 && i < 20)
                        continue;   /* header seq */
                    if (ma[i] != mb[i]) {
                        out->identical = 0;
                        out->first_index = idx;
                        out->first_offset = (int64_t)i;
                        snprintf(out->what, sizeof out->what,
                                 "message %lld (%s, sim_time %.9g): first differing byte at offset %zu "
                                 "(%s): 0x%02x vs 0x%02x",
                                 (long long)idx, proto_type_name(proto_ld16(ma + 6)), proto_ldf64(ma + 24),
                                 i, field_at(ma, la, i), ma[i], mb[i]);
                        break;
                    }
                }
            }
        }
        out->compared++;
    }
    if (r == OCEAN_OK && out->count_a != out->count_b) {
        if (out->identical) {
            out->first_index = (int64_t)out->compared;
            snprintf(out->what, sizeof out->what, "%s has %llu compared messages, %s has %llu", path_a,
                     (unsigned long long)out->count_a, path_b, (unsigned long long)out->count_b);
        }
        out->identical = 0;
    }
    oc_store_reader_close(a);
    oc_store_reader_close(b);
    return r;
}
