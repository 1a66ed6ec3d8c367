/*
 * proto_exr.c - OpenEXR tile codecs, entirely in memory through OpenEXRCore's
 * custom write and read functions (no temporary files).
 *
 * A tile becomes a single-part scanline EXR whose data window is
 * (0,0)-(w-1,h-1), one channel per plane named H, DX, DZ, NU, NV, FOAM, J,
 * row y = grid row (z index).  exr-zip stores FLOAT channels (lossless);
 * exr-piz, exr-b44 and exr-b44a store HALF channels.  Channels are flagged
 * pLinear = 0 so B44 quantises the half values themselves rather than a
 * perceptual transform of them.
 */
#include "codec.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <openexr.h>

/* OpenEXRCore reports details through a callback that has no user pointer
 * of ours during context creation, so keep the last message per thread. */
static _Thread_local char exr_last_msg[200];

static void exr_on_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    snprintf(exr_last_msg, sizeof exr_last_msg, "%s: %s", exr_get_error_code_as_string(code),
             msg ? msg : "");
}

typedef struct wstream {
    proto_buf *out;
    size_t start;   /* offset of the file's first byte in out */
    int failed;
} wstream;

static int64_t exr_write_mem(exr_const_context_t ctxt, void *ud, const void *buf, uint64_t sz,
                             uint64_t off, exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    wstream *s = ud;
    if (off > ((uint64_t)1 << 40) || sz > ((uint64_t)1 << 40)) {
        s->failed = 1;
        return -1;
    }
    size_t end = s->start + (size_t)off + (size_t)sz;
    if (end > s->out->len) {
        uint8_t *p;
        if (proto_buf_grow(s->out, end - s->out->len, &p) != OCEAN_OK) {
            s->failed = 1;
            return -1;
        }
    }
    memcpy(proto_buf_data(s->out) + s->start + off, buf, (size_t)sz);
    return (int64_t)sz;
}

typedef struct rstream {
    const uint8_t *p;
    size_t n;
} rstream;

static int64_t exr_read_mem(exr_const_context_t ctxt, void *ud, void *buf, uint64_t sz,
                            uint64_t off, exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    const rstream *s = ud;
    if (off > s->n)
        return -1;
    uint64_t avail = s->n - off;
    if (sz > avail)
        sz = avail;
    if (sz)
        memcpy(buf, s->p + off, (size_t)sz);
    return (int64_t)sz;
}

static int64_t exr_size_mem(exr_const_context_t ctxt, void *ud)
{
    (void)ctxt;
    return (int64_t)((const rstream *)ud)->n;
}

static int plane_index(unsigned channels, const char *name)
{
    for (int i = 0; i < PROTO_TILE_MAX_PLANES; i++) {
        const char *nm = proto_tile_plane_name(channels, i);
        if (!nm)
            break;
        if (strcmp(nm, name) == 0)
            return i;
    }
    return -1;
}

/* One tile as the file stores it: np planes of n samples, HALF (bpe 2)
 * or FLOAT (bpe 4), from src. */
typedef struct exr_job {
    int w, h;
    unsigned channels;
    int np, half, bpe;
    size_t n;
    const uint8_t *src;
} exr_job;

static ocean_result exr_compression_of(proto_codec c, exr_compression_t *comp, int *half,
                                       char *err, size_t errlen)
{
    *half = 1;
    switch (c) {
    case PROTO_CODEC_EXR_ZIP: *comp = EXR_COMPRESSION_ZIP; *half = 0; break;
    case PROTO_CODEC_EXR_PIZ: *comp = EXR_COMPRESSION_PIZ; break;
    case PROTO_CODEC_EXR_B44: *comp = EXR_COMPRESSION_B44; break;
    case PROTO_CODEC_EXR_B44A: *comp = EXR_COMPRESSION_B44A; break;
    default:
        ocean_seterr(err, errlen, "codec %d is not an EXR codec", (int)c);
        return OCEAN_ETYPE;
    }
    return OCEAN_OK;
}

/* The total samples of planes as half floats into *hbuf (the caller
 * frees it); a value beyond half's range is refused, not clamped. */
static ocean_result exr_to_half(const float *planes, size_t total, uint16_t **hbuf, char *err,
                                size_t errlen)
{
    *hbuf = NULL;
    for (size_t i = 0; i < total; i++)
        if (fabsf(planes[i]) > 65504.0f) {
            ocean_seterr(err, errlen, "value %g beyond the half-float range", (double)planes[i]);
            return OCEAN_ECODEC;
        }
    *hbuf = malloc(total * sizeof **hbuf);
    if (!*hbuf)
        return OCEAN_ENOMEM;
    for (size_t i = 0; i < total; i++)
        (*hbuf)[i] = proto_f16_from_f32(planes[i]);
    return OCEAN_OK;
}

/* The header: one scanline part with the tile's data window and a channel
 * per plane.  *stage names the call that failed. */
static exr_result_t exr_put_header(exr_context_t ctx, const exr_job *j, exr_compression_t comp,
                                   int *part, const char **stage)
{
    *stage = "add_part";
    exr_result_t rv = exr_add_part(ctx, "ocean", EXR_STORAGE_SCANLINE, part);
    if (rv == EXR_ERR_SUCCESS) {
        *stage = "required_attr";
        rv = exr_initialize_required_attr_simple(ctx, *part, j->w, j->h, comp);
    }
    for (int i = 0; i < j->np && rv == EXR_ERR_SUCCESS; i++) {
        *stage = "add_channel";
        rv = exr_add_channel(ctx, *part, proto_tile_plane_name(j->channels, i),
                             j->half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    }
    if (rv == EXR_ERR_SUCCESS) {
        *stage = "write_header";
        rv = exr_write_header(ctx);
    }
    return rv;
}

/* Points each of the encoder's channels at its plane's rows from chunk
 * ci's first. */
static exr_result_t exr_bind_channels(exr_encode_pipeline_t *enc, const exr_chunk_info_t *ci,
                                      const exr_job *j)
{
    for (int k = 0; k < enc->channel_count; k++) {
        exr_coding_channel_info_t *ch = &enc->channels[k];
        int pi = plane_index(j->channels, ch->channel_name);
        if (pi < 0)
            return EXR_ERR_INVALID_ARGUMENT;
        ch->encode_from_ptr = j->src + ((size_t)pi * j->n + (size_t)(ci->start_y) * j->w) * j->bpe;
        ch->user_pixel_stride = j->bpe;
        ch->user_line_stride = j->w * j->bpe;
        ch->user_bytes_per_element = (int16_t)j->bpe;
        ch->user_data_type = j->half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
    }
    return EXR_ERR_SUCCESS;
}

/* Every chunk of scanlines, encoded and written.  *stage names the call
 * that failed. */
static exr_result_t exr_put_chunks(exr_context_t ctx, int part, const exr_job *j, const char **stage)
{
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int have_enc = 0;
    int32_t lpc = 1;
    *stage = "scanlines_per_chunk";
    exr_result_t rv = exr_get_scanlines_per_chunk(ctx, part, &lpc);
    for (int y = 0; y < j->h && rv == EXR_ERR_SUCCESS; y += lpc) {
        exr_chunk_info_t ci;
        *stage = "chunk_info";
        rv = exr_write_scanline_chunk_info(ctx, part, y, &ci);
        if (rv != EXR_ERR_SUCCESS)
            break;
        *stage = "encoding_init";
        rv = have_enc ? exr_encoding_update(ctx, part, &ci, &enc) : exr_encoding_initialize(ctx, part, &ci, &enc);
        if (rv != EXR_ERR_SUCCESS)
            break;
        rv = exr_bind_channels(&enc, &ci, j);
        if (rv != EXR_ERR_SUCCESS)
            break;
        if (!have_enc) {
            have_enc = 1;
            *stage = "choose_routines";
            rv = exr_encoding_choose_default_routines(ctx, part, &enc);
            if (rv != EXR_ERR_SUCCESS)
                break;
        }
        *stage = "encoding_run";
        rv = exr_encoding_run(ctx, part, &enc);
    }
    if (have_enc)
        exr_encoding_destroy(ctx, &enc);
    return rv;
}

ocean_result proto_exr_encode(proto_codec c, const proto_codec_params *p, int w, int h,
                              unsigned channels, const float *planes, proto_buf *out,
                              char *err, size_t errlen)
{
    exr_compression_t comp;
    int half;
    ocean_result r = exr_compression_of(c, &comp, &half, err, errlen);
    if (r != OCEAN_OK)
        return r;
    exr_job job = {w, h, channels, proto_tile_planes(channels), half, half ? 2 : 4,
                   (size_t)w * h, (const uint8_t *)planes};
    uint16_t *hbuf = NULL;
    if (half) {
        r = exr_to_half(planes, job.n * (size_t)job.np, &hbuf, err, errlen);
        if (r != OCEAN_OK)
            return r;
        job.src = (const uint8_t *)hbuf;
    }

    wstream ws = {out, out->len, 0};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_on_error;
    init.user_data = &ws;
    init.write_fn = exr_write_mem;
    if (p && p->zip_level >= 1 && p->zip_level <= 9)
        init.zip_level = p->zip_level;
    exr_context_t ctx = NULL;
    const char *stage = "start_write";
    exr_result_t rv = exr_start_write(&ctx, "tile.exr", EXR_WRITE_FILE_DIRECTLY, &init);
    int part = 0;
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_put_header(ctx, &job, comp, &part, &stage);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_put_chunks(ctx, part, &job, &stage);
    exr_result_t frv = ctx ? exr_finish(&ctx) : EXR_ERR_SUCCESS;
    if (rv == EXR_ERR_SUCCESS && frv != EXR_ERR_SUCCESS) {
        rv = frv;
        stage = "finish";
    }
    free(hbuf);
    if (rv != EXR_ERR_SUCCESS || ws.failed) {
        proto_buf_truncate(out, ws.start);
        if (ws.failed && rv == EXR_ERR_SUCCESS)
            return OCEAN_ENOMEM;
        ocean_seterr(err, errlen, "OpenEXR %s failed: %s (%s)", stage, exr_get_error_code_as_string(rv), exr_last_msg);
        return rv == EXR_ERR_OUT_OF_MEMORY ? OCEAN_ENOMEM : OCEAN_ECODEC;
    }
    return OCEAN_OK;
}

/* exr_check_header's outcomes: the header suits the tile; an OpenEXR call
 * failed (its code in *rv); the header does not suit it (said in err). */
enum { EXR_CHECK_OK, EXR_CHECK_FAIL, EXR_CHECK_REFUSED };

/* One scanline part with the tile's data window and, for each of its
 * planes, a channel of that name sampled 1 x 1 as half or float. */
static int exr_check_header(exr_context_t ctx, int w, int h, unsigned channels, exr_attr_box2i_t *dwp,
                            exr_result_t *rv, char *err, size_t errlen)
{
    int np = proto_tile_planes(channels), count = 0;
    exr_storage_t st;
    const exr_attr_chlist_t *cl = NULL;
    if ((*rv = exr_get_count(ctx, &count)) != EXR_ERR_SUCCESS || (*rv = exr_get_storage(ctx, 0, &st)) ||
        (*rv = exr_get_data_window(ctx, 0, dwp)) || (*rv = exr_get_channels(ctx, 0, &cl)))
        return EXR_CHECK_FAIL;
    exr_attr_box2i_t dw = *dwp;
    if (count != 1 || st != EXR_STORAGE_SCANLINE) {
        ocean_seterr(err, errlen, "EXR tile must be one scanline part (has %d parts, storage %d)", count, (int)st);
        return EXR_CHECK_REFUSED;
    }
    if ((int64_t)dw.max.x - dw.min.x + 1 != w || (int64_t)dw.max.y - dw.min.y + 1 != h) {
        ocean_seterr(err, errlen, "EXR data window %dx%d, tile is %dx%d", dw.max.x - dw.min.x + 1,
               dw.max.y - dw.min.y + 1, w, h);
        return EXR_CHECK_REFUSED;
    }
    if (!cl || cl->num_channels != np) {
        ocean_seterr(err, errlen, "EXR has %d channels, tile needs %d", cl ? cl->num_channels : 0, np);
        return EXR_CHECK_REFUSED;
    }
    for (int k = 0; k < cl->num_channels; k++) {
        const exr_attr_chlist_entry_t *e = &cl->entries[k];
        if (plane_index(channels, e->name.str) < 0 || e->x_sampling != 1 || e->y_sampling != 1 ||
            (e->pixel_type != EXR_PIXEL_HALF && e->pixel_type != EXR_PIXEL_FLOAT)) {
            ocean_seterr(err, errlen, "EXR channel '%s' unexpected (name, sampling or type)", e->name.str);
            return EXR_CHECK_REFUSED;
        }
    }
    return EXR_CHECK_OK;
}

/* Where a decoded tile goes: planes of w x h floats (n each), in the
 * codec's plane order of `channels`. */
typedef struct exr_sink {
    int w, h;
    unsigned channels;
    size_t n;
    float *planes;
    char *err;
    size_t errlen;
} exr_sink;

/* Points each channel of chunk `row`'s pipeline at its plane's rows. */
static int exr_bind_planes(exr_decode_pipeline_t *dec, int64_t row, const exr_sink *k)
{
    for (int c = 0; c < dec->channel_count; c++) {
        exr_coding_channel_info_t *ch = &dec->channels[c];
        int pi = plane_index(k->channels, ch->channel_name);
        if (pi < 0 || ch->width != k->w) {
            ocean_seterr(k->err, k->errlen, "EXR chunk channel layout unexpected");
            return EXR_CHECK_REFUSED;
        }
        ch->decode_to_ptr = (uint8_t *)(k->planes + (size_t)pi * k->n + (size_t)row * k->w);
        ch->user_pixel_stride = 4;
        ch->user_line_stride = k->w * 4;
        ch->user_bytes_per_element = 4;
        ch->user_data_type = EXR_PIXEL_FLOAT;
    }
    return EXR_CHECK_OK;
}

/* Every chunk of scanlines of data window dw, decoded into the sink: the
 * outcomes of exr_check_header; *stage names the call that failed. */
static int exr_get_chunks(exr_context_t ctx, const exr_attr_box2i_t *dw, const exr_sink *k, exr_result_t *rv,
                          const char **stage)
{
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    int have_dec = 0, res = EXR_CHECK_OK;
    int32_t lpc = 1;
    *stage = "scanlines_per_chunk";
    if ((*rv = exr_get_scanlines_per_chunk(ctx, 0, &lpc)) != EXR_ERR_SUCCESS)
        return EXR_CHECK_FAIL;
    if (lpc < 1) {
        ocean_seterr(k->err, k->errlen, "EXR scanlines per chunk %d", lpc);
        return EXR_CHECK_REFUSED;
    }
    for (int64_t y = dw->min.y; y <= dw->max.y && res == EXR_CHECK_OK; y += lpc) {
        exr_chunk_info_t ci;
        *stage = "chunk_info";
        if ((*rv = exr_read_scanline_chunk_info(ctx, 0, (int)y, &ci)) != EXR_ERR_SUCCESS) {
            res = EXR_CHECK_FAIL;
            break;
        }
        int64_t row = (int64_t)ci.start_y - dw->min.y;
        if (row < 0 || row + ci.height > k->h) {
            ocean_seterr(k->err, k->errlen, "EXR chunk rows %d..%d outside the tile", ci.start_y,
                         ci.start_y + ci.height);
            res = EXR_CHECK_REFUSED;
            break;
        }
        *stage = "decoding_init";
        *rv = have_dec ? exr_decoding_update(ctx, 0, &ci, &dec) : exr_decoding_initialize(ctx, 0, &ci, &dec);
        if (*rv != EXR_ERR_SUCCESS) {
            res = EXR_CHECK_FAIL;
            break;
        }
        if ((res = exr_bind_planes(&dec, row, k)) != EXR_CHECK_OK)
            break;
        if (!have_dec) {
            have_dec = 1;
            *stage = "choose_routines";
            if ((*rv = exr_decoding_choose_default_routines(ctx, 0, &dec)) != EXR_ERR_SUCCESS) {
                res = EXR_CHECK_FAIL;
                break;
            }
        }
        *stage = "decoding_run";
        if ((*rv = exr_decoding_run(ctx, 0, &dec)) != EXR_ERR_SUCCESS)
            res = EXR_CHECK_FAIL;
    }
    if (have_dec)
        exr_decoding_destroy(ctx, &dec);
    return res;
}

ocean_result proto_exr_decode(int w, int h, unsigned channels, const uint8_t *data, size_t len,
                              float *planes, char *err, size_t errlen)
{
    exr_sink k = {w, h, channels, (size_t)w * h, planes, err, errlen};
    rstream rs = {data, len};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_on_error;
    init.user_data = &rs;
    init.read_fn = exr_read_mem;
    init.size_fn = exr_size_mem;
    init.flags = EXR_CONTEXT_FLAG_SILENT_HEADER_PARSE;
    init.max_image_width = PROTO_TILE_MAX_SIZE;
    init.max_image_height = PROTO_TILE_MAX_SIZE;
    init.max_tile_width = PROTO_TILE_MAX_SIZE;
    init.max_tile_height = PROTO_TILE_MAX_SIZE;
    exr_last_msg[0] = 0;
    if (len < 8) {
        ocean_seterr(err, errlen, "EXR payload of %zu bytes is too short", len);
        return OCEAN_ECODEC;
    }
    exr_context_t ctx = NULL;
    const char *stage = "start_read";
    exr_result_t rv = exr_start_read(&ctx, "tile.exr", &init);
    exr_attr_box2i_t dw;
    int res = rv != EXR_ERR_SUCCESS ? EXR_CHECK_FAIL : EXR_CHECK_OK;
    if (res == EXR_CHECK_OK) {
        stage = "header";
        res = exr_check_header(ctx, w, h, channels, &dw, &rv, err, errlen);
    }
    if (res == EXR_CHECK_OK)
        res = exr_get_chunks(ctx, &dw, &k, &rv, &stage);
    size_t total = k.n * (size_t)proto_tile_planes(channels);
    for (size_t i = 0; res == EXR_CHECK_OK && i < total; i++)
        if (!isfinite(planes[i])) {
            ocean_seterr(err, errlen, "EXR holds a non-finite value at sample %zu", i);
            res = EXR_CHECK_REFUSED;
        }
    /* OpenEXRCore 3.1 reports corrupt compressed chunks as
     * EXR_ERR_OUT_OF_MEMORY ("unable to decompress"), so every failure
     * while reading is a codec failure of the payload. */
    if (res == EXR_CHECK_FAIL)
        ocean_seterr(err, errlen, "OpenEXR %s failed: %s %s", stage, exr_get_error_code_as_string(rv), exr_last_msg);
    if (ctx)
        exr_finish(&ctx);
    return res == EXR_CHECK_OK ? OCEAN_OK : OCEAN_ECODEC;
}
