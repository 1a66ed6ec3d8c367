/*
 * cigi.c - CIGI packets (see cigi.h): one table of field layouts per
 * version, read by one encoder and one decoder.  The layouts and their
 * sources are written down in protocol/CIGI.md.
 *
 * Threads: pure functions.
 */
#include "cigi.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* ---- the layouts ------------------------------------------------------------ */

enum wire { W_U8, W_I8, W_U16, W_U32, W_F32, W_F64, W_BITS };

typedef struct field {
    uint16_t off;       /* byte offset in the packet, header included */
    uint8_t wire;
    uint8_t shift, width; /* W_BITS: bits shift..shift+width-1 of the byte at off */
    uint16_t member;    /* offset in cigi_packet */
} field;

#define M(T, m) ((uint16_t)(offsetof(cigi_packet, u) + offsetof(T, m)))
#define F(T, o, w, m) {(o), (w), 0, 0, M(T, m)}
#define B(T, o, s, n, m) {(o), W_BITS, (s), (n), M(T, m)}
#define COUNT(a) ((uint8_t)(sizeof a / sizeof a[0]))

typedef struct layout {
    cigi_kind kind;
    uint16_t opcode, size;
    const field *f;
    uint8_t nf;
} layout;

/* CIGI 3.2 / 3.3 (ICD 3.3; Wireshark's packet-cigi.c, the CIGI Class
 * Library 3.3): opcode byte 0, size byte 1. */
static const field v3_ig[] = {
    F(cigi_ig_control, 3, W_I8, database), B(cigi_ig_control, 4, 0, 2, ig_mode),
    B(cigi_ig_control, 4, 2, 1, timestamp_valid), F(cigi_ig_control, 8, W_U32, frame),
    F(cigi_ig_control, 12, W_U32, timestamp), F(cigi_ig_control, 16, W_U32, last_ig_frame)};
static const field v3_sof[] = {
    F(cigi_start_of_frame, 3, W_I8, database), F(cigi_start_of_frame, 4, W_U8, ig_status),
    B(cigi_start_of_frame, 5, 0, 2, ig_mode), B(cigi_start_of_frame, 5, 2, 1, timestamp_valid),
    B(cigi_start_of_frame, 5, 3, 1, earth_model), F(cigi_start_of_frame, 8, W_U32, frame),
    F(cigi_start_of_frame, 12, W_U32, timestamp), F(cigi_start_of_frame, 16, W_U32, last_host_frame)};
static const field v3_entity[] = {
    F(cigi_entity, 2, W_U16, id), B(cigi_entity, 4, 0, 2, state), B(cigi_entity, 4, 2, 1, attach),
    B(cigi_entity, 4, 5, 2, clamp), F(cigi_entity, 8, W_U16, type), F(cigi_entity, 10, W_U16, parent),
    F(cigi_entity, 12, W_F32, roll), F(cigi_entity, 16, W_F32, pitch), F(cigi_entity, 20, W_F32, yaw),
    F(cigi_entity, 24, W_F64, lat), F(cigi_entity, 32, W_F64, lon), F(cigi_entity, 40, W_F64, alt)};
static const field v3_atmosphere[] = {
    B(cigi_atmosphere, 2, 0, 1, enable), F(cigi_atmosphere, 3, W_U8, humidity),
    F(cigi_atmosphere, 4, W_F32, air_temp), F(cigi_atmosphere, 8, W_F32, visibility),
    F(cigi_atmosphere, 12, W_F32, wind_h), F(cigi_atmosphere, 16, W_F32, wind_v),
    F(cigi_atmosphere, 20, W_F32, wind_dir), F(cigi_atmosphere, 24, W_F32, pressure)};
static const field v3_weather[] = {
    F(cigi_weather, 2, W_U16, region), F(cigi_weather, 4, W_U8, layer), F(cigi_weather, 5, W_U8, humidity),
    B(cigi_weather, 6, 0, 1, enable), B(cigi_weather, 7, 0, 2, scope), B(cigi_weather, 7, 2, 3, severity),
    F(cigi_weather, 8, W_F32, air_temp), F(cigi_weather, 12, W_F32, visibility), F(cigi_weather, 24, W_F32, base),
    F(cigi_weather, 28, W_F32, thickness), F(cigi_weather, 32, W_F32, transition),
    F(cigi_weather, 36, W_F32, wind_h), F(cigi_weather, 40, W_F32, wind_v), F(cigi_weather, 44, W_F32, wind_dir),
    F(cigi_weather, 48, W_F32, pressure)};
static const field v3_maritime[] = {
    F(cigi_maritime_control, 2, W_U16, region), B(cigi_maritime_control, 4, 0, 1, enable),
    B(cigi_maritime_control, 4, 1, 1, whitecaps), B(cigi_maritime_control, 4, 2, 2, scope),
    F(cigi_maritime_control, 8, W_F32, surface_height), F(cigi_maritime_control, 12, W_F32, water_temp),
    F(cigi_maritime_control, 16, W_F32, clarity)};
static const field v3_wave[] = {
    F(cigi_wave, 2, W_U16, region), F(cigi_wave, 4, W_U8, wave_id), B(cigi_wave, 5, 0, 1, enable),
    B(cigi_wave, 5, 1, 2, scope), B(cigi_wave, 5, 3, 2, breaker), F(cigi_wave, 8, W_F32, height),
    F(cigi_wave, 12, W_F32, wavelength), F(cigi_wave, 16, W_F32, period), F(cigi_wave, 20, W_F32, direction),
    F(cigi_wave, 24, W_F32, phase), F(cigi_wave, 28, W_F32, leading)};
static const field v3_hat_req[] = {
    F(cigi_hat_hot_request, 2, W_U16, id), B(cigi_hat_hot_request, 4, 0, 2, type),
    B(cigi_hat_hot_request, 4, 2, 1, coord), F(cigi_hat_hot_request, 5, W_U8, period),
    F(cigi_hat_hot_request, 6, W_U16, entity), F(cigi_hat_hot_request, 8, W_F64, lat),
    F(cigi_hat_hot_request, 16, W_F64, lon), F(cigi_hat_hot_request, 24, W_F64, alt)};
static const field v3_env_req[] = {
    B(cigi_env_request, 2, 0, 4, type), F(cigi_env_request, 3, W_U8, id), F(cigi_env_request, 8, W_F64, lat),
    F(cigi_env_request, 16, W_F64, lon), F(cigi_env_request, 24, W_F64, alt)};
static const field v3_hat_resp[] = {
    F(cigi_hat_hot_response, 2, W_U16, id), B(cigi_hat_hot_response, 4, 0, 1, valid),
    B(cigi_hat_hot_response, 4, 1, 1, type), B(cigi_hat_hot_response, 4, 4, 4, frame_lsn),
    F(cigi_hat_hot_response, 8, W_F64, height)};
static const field v3_hat_xresp[] = {
    F(cigi_hat_hot_xresponse, 2, W_U16, id), B(cigi_hat_hot_xresponse, 4, 0, 1, valid),
    B(cigi_hat_hot_xresponse, 4, 4, 4, frame_lsn), F(cigi_hat_hot_xresponse, 8, W_F64, hat),
    F(cigi_hat_hot_xresponse, 16, W_F64, hot), F(cigi_hat_hot_xresponse, 24, W_U32, material),
    F(cigi_hat_hot_xresponse, 28, W_F32, normal_az), F(cigi_hat_hot_xresponse, 32, W_F32, normal_el)};
static const field v3_maritime_resp[] = {
    F(cigi_maritime_response, 2, W_U8, id), F(cigi_maritime_response, 4, W_F32, surface_height),
    F(cigi_maritime_response, 8, W_F32, water_temp), F(cigi_maritime_response, 12, W_F32, clarity)};

static const layout v3[] = {
    {CIGI_IG_CONTROL, 1, 24, v3_ig, COUNT(v3_ig)},
    {CIGI_ENTITY_CONTROL, 2, 48, v3_entity, COUNT(v3_entity)},
    {CIGI_ATMOSPHERE_CONTROL, 10, 32, v3_atmosphere, COUNT(v3_atmosphere)},
    {CIGI_WEATHER_CONTROL, 12, 56, v3_weather, COUNT(v3_weather)},
    {CIGI_MARITIME_CONTROL, 13, 24, v3_maritime, COUNT(v3_maritime)},
    {CIGI_WAVE_CONTROL, 14, 32, v3_wave, COUNT(v3_wave)},
    {CIGI_HAT_HOT_REQUEST, 24, 32, v3_hat_req, COUNT(v3_hat_req)},
    {CIGI_ENV_REQUEST, 28, 32, v3_env_req, COUNT(v3_env_req)},
    {CIGI_START_OF_FRAME, 101, 24, v3_sof, COUNT(v3_sof)},
    {CIGI_HAT_HOT_RESPONSE, 102, 16, v3_hat_resp, COUNT(v3_hat_resp)},
    {CIGI_HAT_HOT_XRESPONSE, 103, 40, v3_hat_xresp, COUNT(v3_hat_xresp)},
    {CIGI_MARITIME_RESPONSE, 111, 16, v3_maritime_resp, COUNT(v3_maritime_resp)},
};

/* CIGI 4.0 (the CIGI Class Library 4.0's packing; CIGI.md says what
 * was and was not checked): size bytes 0-1, opcode bytes 2-3. */
static const field v4_ig[] = {
    F(cigi_ig_control, 5, W_I8, database), B(cigi_ig_control, 7, 0, 2, ig_mode),
    B(cigi_ig_control, 7, 2, 1, timestamp_valid), F(cigi_ig_control, 8, W_U32, frame),
    F(cigi_ig_control, 12, W_U32, last_ig_frame), F(cigi_ig_control, 16, W_U32, timestamp)};
static const field v4_sof[] = {
    F(cigi_start_of_frame, 5, W_I8, database), B(cigi_start_of_frame, 7, 0, 2, ig_mode),
    B(cigi_start_of_frame, 7, 2, 1, timestamp_valid), B(cigi_start_of_frame, 7, 3, 1, earth_model),
    F(cigi_start_of_frame, 8, W_U32, frame), F(cigi_start_of_frame, 12, W_U32, timestamp),
    F(cigi_start_of_frame, 16, W_U32, last_host_frame)};
static const field v4_position[] = {
    B(cigi_entity, 4, 0, 1, attach), B(cigi_entity, 4, 1, 2, clamp), F(cigi_entity, 6, W_U16, id),
    F(cigi_entity, 8, W_U16, parent), F(cigi_entity, 12, W_F32, roll), F(cigi_entity, 16, W_F32, pitch),
    F(cigi_entity, 20, W_F32, yaw), F(cigi_entity, 24, W_F64, lat), F(cigi_entity, 32, W_F64, lon),
    F(cigi_entity, 40, W_F64, alt)};
static const field v4_entity[] = {B(cigi_entity, 4, 0, 2, state), F(cigi_entity, 6, W_U16, id)};
static const field v4_weather[] = {
    F(cigi_weather, 4, W_U8, layer), F(cigi_weather, 5, W_U8, humidity), B(cigi_weather, 6, 0, 1, enable),
    B(cigi_weather, 7, 0, 2, scope), B(cigi_weather, 7, 2, 3, severity), F(cigi_weather, 8, W_U16, region),
    F(cigi_weather, 12, W_F32, air_temp), F(cigi_weather, 16, W_F32, visibility), F(cigi_weather, 28, W_F32, base),
    F(cigi_weather, 32, W_F32, thickness), F(cigi_weather, 36, W_F32, transition),
    F(cigi_weather, 40, W_F32, wind_h), F(cigi_weather, 44, W_F32, wind_v), F(cigi_weather, 48, W_F32, wind_dir),
    F(cigi_weather, 52, W_F32, pressure)};
static const field v4_maritime[] = {
    B(cigi_maritime_control, 4, 0, 1, enable), B(cigi_maritime_control, 4, 1, 1, whitecaps),
    B(cigi_maritime_control, 4, 2, 2, scope), F(cigi_maritime_control, 6, W_U16, region),
    F(cigi_maritime_control, 8, W_F32, surface_height), F(cigi_maritime_control, 12, W_F32, water_temp),
    F(cigi_maritime_control, 16, W_F32, clarity)};
static const field v4_wave[] = {
    F(cigi_wave, 4, W_U8, wave_id), B(cigi_wave, 5, 0, 1, enable), B(cigi_wave, 5, 1, 2, scope),
    B(cigi_wave, 5, 3, 2, breaker), F(cigi_wave, 6, W_U16, region), F(cigi_wave, 8, W_F32, height),
    F(cigi_wave, 12, W_F32, wavelength), F(cigi_wave, 16, W_F32, period), F(cigi_wave, 20, W_F32, direction),
    F(cigi_wave, 24, W_F32, phase), F(cigi_wave, 28, W_F32, leading)};
static const field v4_hat_req[] = {
    F(cigi_hat_hot_request, 4, W_U16, id), F(cigi_hat_hot_request, 6, W_U16, entity),
    B(cigi_hat_hot_request, 8, 0, 2, type), B(cigi_hat_hot_request, 8, 2, 1, coord),
    F(cigi_hat_hot_request, 9, W_U8, period), F(cigi_hat_hot_request, 16, W_F64, lat),
    F(cigi_hat_hot_request, 24, W_F64, lon), F(cigi_hat_hot_request, 32, W_F64, alt)};
static const field v4_env_req[] = {
    B(cigi_env_request, 4, 0, 4, type), F(cigi_env_request, 5, W_U8, id), F(cigi_env_request, 8, W_F64, lat),
    F(cigi_env_request, 16, W_F64, lon), F(cigi_env_request, 24, W_F64, alt)};
static const field v4_hat_resp[] = {
    B(cigi_hat_hot_response, 4, 0, 1, valid), B(cigi_hat_hot_response, 4, 1, 1, type),
    B(cigi_hat_hot_response, 4, 4, 4, frame_lsn), F(cigi_hat_hot_response, 6, W_U16, id),
    F(cigi_hat_hot_response, 8, W_F64, height)};
static const field v4_hat_xresp[] = {
    B(cigi_hat_hot_xresponse, 4, 0, 1, valid), B(cigi_hat_hot_xresponse, 4, 4, 4, frame_lsn),
    F(cigi_hat_hot_xresponse, 6, W_U16, id), F(cigi_hat_hot_xresponse, 8, W_F64, hat),
    F(cigi_hat_hot_xresponse, 16, W_F64, hot), F(cigi_hat_hot_xresponse, 24, W_U32, material),
    F(cigi_hat_hot_xresponse, 28, W_F32, normal_az), F(cigi_hat_hot_xresponse, 32, W_F32, normal_el)};
static const field v4_maritime_resp[] = {
    F(cigi_maritime_response, 4, W_U8, id), F(cigi_maritime_response, 8, W_F32, surface_height),
    F(cigi_maritime_response, 12, W_F32, water_temp), F(cigi_maritime_response, 16, W_F32, clarity)};

static const layout v4[] = {
    {CIGI_IG_CONTROL, 0x0000, 24, v4_ig, COUNT(v4_ig)},
    {CIGI_ENTITY_POSITION, 0x0001, 48, v4_position, COUNT(v4_position)},
    {CIGI_WEATHER_CONTROL, 0x000B, 72, v4_weather, COUNT(v4_weather)},
    {CIGI_MARITIME_CONTROL, 0x000C, 24, v4_maritime, COUNT(v4_maritime)},
    {CIGI_WAVE_CONTROL, 0x000D, 32, v4_wave, COUNT(v4_wave)},
    {CIGI_HAT_HOT_REQUEST, 0x0017, 40, v4_hat_req, COUNT(v4_hat_req)},
    {CIGI_ENV_REQUEST, 0x001B, 32, v4_env_req, COUNT(v4_env_req)},
    {CIGI_ENTITY_CONTROL, 0x0025, 16, v4_entity, COUNT(v4_entity)},
    {CIGI_START_OF_FRAME, 0xFFFF, 24, v4_sof, COUNT(v4_sof)},
    {CIGI_HAT_HOT_RESPONSE, 0x0FFF, 16, v4_hat_resp, COUNT(v4_hat_resp)},
    {CIGI_HAT_HOT_XRESPONSE, 0x0FFE, 40, v4_hat_xresp, COUNT(v4_hat_xresp)},
    {CIGI_MARITIME_RESPONSE, 0x0FF6, 24, v4_maritime_resp, COUNT(v4_maritime_resp)},
};

static const layout *table_of(const cigi_format *f, size_t *n)
{
    *n = f->major == 4 ? COUNT(v4) : COUNT(v3);
    return f->major == 4 ? v4 : v3;
}

static const layout *layout_by_opcode(const cigi_format *f, unsigned opcode)
{
    size_t n;
    const layout *t = table_of(f, &n);
    for (size_t i = 0; i < n; i++)
        if (t[i].opcode == opcode) return &t[i];
    return NULL;
}

static const layout *layout_by_kind(const cigi_format *f, cigi_kind k)
{
    size_t n;
    const layout *t = table_of(f, &n);
    for (size_t i = 0; i < n; i++)
        if (t[i].kind == k) return &t[i];
    return NULL;
}

/* ---- bytes in either order --------------------------------------------------- */

static uint64_t load(const uint8_t *p, int bytes, int big)
{
    uint64_t v = 0;
    for (int i = 0; i < bytes; i++) v |= (uint64_t)p[big ? i : bytes - 1 - i] << (8 * (bytes - 1 - i));
    return v;
}

static void store(uint8_t *p, uint64_t v, int bytes, int big)
{
    for (int i = 0; i < bytes; i++) p[big ? i : bytes - 1 - i] = (uint8_t)(v >> (8 * (bytes - 1 - i)));
}

/* ---- one field --------------------------------------------------------------- */

static void field_read(const field *fd, const uint8_t *pk, int big, cigi_packet *p)
{
    char *m = (char *)p + fd->member;
    const uint8_t *q = pk + fd->off;
    uint32_t u;
    int32_t i;
    float f;
    double d;
    switch (fd->wire) {
    case W_U8: u = q[0]; memcpy(m, &u, sizeof u); break;
    case W_I8: i = (int8_t)q[0]; memcpy(m, &i, sizeof i); break;
    case W_U16: u = (uint32_t)load(q, 2, big); memcpy(m, &u, sizeof u); break;
    case W_U32: u = (uint32_t)load(q, 4, big); memcpy(m, &u, sizeof u); break;
    case W_BITS: u = (uint32_t)(q[0] >> fd->shift) & ((1u << fd->width) - 1); memcpy(m, &u, sizeof u); break;
    case W_F32:
        u = (uint32_t)load(q, 4, big);
        memcpy(&f, &u, sizeof f);
        d = f;
        memcpy(m, &d, sizeof d);
        break;
    default: { /* W_F64 */
        uint64_t v = load(q, 8, big);
        memcpy(&d, &v, sizeof d);
        memcpy(m, &d, sizeof d);
    }
    }
}

/* 0, or -1 when an integer does not fit its field */
static int field_write(const field *fd, const cigi_packet *p, int big, uint8_t *pk)
{
    const char *m = (const char *)p + fd->member;
    uint8_t *q = pk + fd->off;
    uint32_t u = 0;
    int32_t i = 0;
    double d = 0;
    if (fd->wire == W_F32 || fd->wire == W_F64) memcpy(&d, m, sizeof d);
    else if (fd->wire == W_I8) memcpy(&i, m, sizeof i);
    else memcpy(&u, m, sizeof u);
    switch (fd->wire) {
    case W_U8: if (u > 0xFF) return -1; q[0] = (uint8_t)u; break;
    case W_I8: if (i < -128 || i > 127) return -1; q[0] = (uint8_t)(int8_t)i; break;
    case W_U16: if (u > 0xFFFF) return -1; store(q, u, 2, big); break;
    case W_U32: store(q, u, 4, big); break;
    case W_BITS:
        if (u >> fd->width) return -1;
        q[0] |= (uint8_t)(u << fd->shift);
        break;
    case W_F32: {
        float f = (float)d;
        memcpy(&u, &f, sizeof u);
        store(q, u, 4, big);
        break;
    }
    default: {
        uint64_t v;
        memcpy(&v, &d, sizeof v);
        store(q, v, 8, big);
    }
    }
    return 0;
}

/* ---- messages ------------------------------------------------------------------ */

static ocean_result format_v3(const uint8_t *d, size_t n, cigi_format *out, char *why, size_t wl)
{
    if (d[0] != 1 && d[0] != 101) {
        ocean_seterr(why, wl, "CIGI 3 message opens with packet %u, not IG Control (1) or Start of Frame (101)", d[0]);
        return OCEAN_EFORMAT;
    }
    if (d[1] != 24) {
        ocean_seterr(why, wl, "CIGI 3 %s of %u bytes: only CIGI 3.2 and 3.3 (24 bytes) are read", d[0] == 1 ? "IG Control" :
            "Start of Frame", d[1]);
        return d[1] == 16 ? OCEAN_EVERSION : OCEAN_EFORMAT;
    }
    if (n < 24) {
        ocean_seterr(why, wl, "message of %zu bytes, its first packet has 24", n);
        return OCEAN_ETRUNC;
    }
    if (d[6] == 0x80 && d[7] == 0x00) out->big_endian = 1;
    else if (d[6] == 0x00 && d[7] == 0x80) out->big_endian = 0;
    else {
        ocean_seterr(why, wl, "byte-swap magic 0x%02x%02x, not 0x8000 in either order", d[6], d[7]);
        return OCEAN_EFORMAT;
    }
    out->major = 3;
    out->minor = (uint8_t)((d[0] == 1 ? d[4] : d[5]) >> 4);
    if (out->minor < 2) {
        ocean_seterr(why, wl, "CIGI 3.%u with 24-byte packets: only 3.2 and 3.3 are read", out->minor);
        return OCEAN_EVERSION;
    }
    return OCEAN_OK;
}

static ocean_result format_v4(const uint8_t *d, size_t n, cigi_format *out, char *why, size_t wl)
{
    if (n < 24) {
        ocean_seterr(why, wl, "message of %zu bytes, shorter than a CIGI 4 IG Control or Start of Frame", n);
        return OCEAN_ETRUNC;
    }
    if (d[0] == 24 && d[1] == 0) out->big_endian = 0;
    else if (d[0] == 0 && d[1] == 24) out->big_endian = 1;
    else {
        ocean_seterr(why, wl, "CIGI 4 message whose first packet is not 24 bytes long");
        return OCEAN_EFORMAT;
    }
    unsigned op = (unsigned)load(d + 2, 2, out->big_endian);
    if (op != 0x0000 && op != 0xFFFF) {
        ocean_seterr(why, wl, "CIGI 4 message opens with packet 0x%04x, not IG Control or Start of Frame", op);
        return OCEAN_EFORMAT;
    }
    if (d[4] != 4) {
        ocean_seterr(why, wl, "CIGI 4 opcode with major version %u", d[4]);
        return OCEAN_EVERSION;
    }
    out->major = 4;
    out->minor = (uint8_t)(d[7] >> 4);
    return OCEAN_OK;
}

ocean_result cigi_format_of(const uint8_t *d, size_t n, cigi_format *out, char *why, size_t why_len)
{
    memset(out, 0, sizeof *out);
    if (!d || n < 8) {
        ocean_seterr(why, why_len, "message of %zu bytes: no CIGI packet is that short", d ? n : 0);
        return OCEAN_ETRUNC;
    }
    /* byte 2 is the major version in CIGI 1-3, and half of the opcode
     * 0x0000 or 0xFFFF of a CIGI 4 IG Control or Start of Frame */
    if (d[2] == 3) return format_v3(d, n, out, why, why_len);
    if (d[2] == 0x00 || d[2] == 0xFF) return format_v4(d, n, out, why, why_len);
    ocean_seterr(why, why_len, "CIGI version %u: 3.2, 3.3 and 4.0 are read", d[2]);
    return OCEAN_EVERSION;
}

void cigi_reader_init(cigi_reader *r, const uint8_t *d, size_t n, const cigi_format *fmt)
{
    r->d = d;
    r->n = d ? n : 0;
    r->off = 0;
    r->fmt = *fmt;
}

ocean_result cigi_reader_next(cigi_reader *r, cigi_packet *p, int *done, char *why, size_t why_len)
{
    memset(p, 0, sizeof *p);
    *done = r->off >= r->n;
    if (*done) return OCEAN_OK;
    size_t left = r->n - r->off, head = r->fmt.major == 4 ? 4 : 2;
    const uint8_t *q = r->d + r->off;
    if (left < head) {
        ocean_seterr(why, why_len, "%zu bytes left at offset %zu: not a packet header", left, r->off);
        r->off = r->n;
        return OCEAN_ETRUNC;
    }
    int big = r->fmt.big_endian;
    unsigned op = r->fmt.major == 4 ? (unsigned)load(q + 2, 2, big) : q[0];
    size_t size = r->fmt.major == 4 ? (size_t)load(q, 2, big) : q[1];
    const layout *l = layout_by_opcode(&r->fmt, op);
    ocean_result res = OCEAN_OK;
    if (size == 0 || size % 8) {
        ocean_seterr(why, why_len, "packet %u at offset %zu: size %zu is not a positive multiple of 8", op, r->off, size);
        res = OCEAN_EFORMAT;
    } else if (size > left) {
        ocean_seterr(why, why_len, "packet %u at offset %zu: size %zu runs past the message (%zu bytes left)", op, r->off, size,
            left);
        res = OCEAN_ETRUNC;
    } else if (l && size < l->size) {
        ocean_seterr(why, why_len, "%s at offset %zu: %zu bytes, its layout has %u", cigi_kind_name(l->kind), r->off, size,
            l->size);
        res = OCEAN_EFORMAT;
    }
    if (res != OCEAN_OK) {
        r->off = r->n;
        return res;
    }
    p->opcode = (uint16_t)op;
    p->size = (uint16_t)size;
    p->kind = l ? l->kind : CIGI_UNKNOWN;
    for (int i = 0; l && i < l->nf; i++) field_read(&l->f[i], q, big, p);
    r->off += size;
    return OCEAN_OK;
}

/* The version fields of IG Control and Start of Frame, and CIGI 3's magic. */
static void put_version(const cigi_format *f, cigi_kind k, uint8_t *q)
{
    if (f->major == 4) {
        q[4] = 4;
        q[7] |= (uint8_t)(f->minor << 4);
        return;
    }
    q[2] = 3;
    q[k == CIGI_IG_CONTROL ? 4 : 5] |= (uint8_t)(f->minor << 4);
    store(q + 6, 0x8000, 2, f->big_endian);
}

ocean_result cigi_put(proto_buf *b, const cigi_format *f, const cigi_packet *p)
{
    const layout *l = layout_by_kind(f, p->kind);
    if (!l) return OCEAN_EUNSUPPORTED;
    size_t start = proto_buf_len(b);
    uint8_t *q;
    ocean_result r = proto_buf_grow(b, l->size, &q);
    if (r != OCEAN_OK) return r;
    if (f->major == 4) {
        store(q, l->size, 2, f->big_endian);
        store(q + 2, l->opcode, 2, f->big_endian);
    } else {
        q[0] = (uint8_t)l->opcode;
        q[1] = (uint8_t)l->size;
    }
    for (int i = 0; i < l->nf; i++)
        if (field_write(&l->f[i], p, f->big_endian, q)) {
            proto_buf_truncate(b, start);
            return OCEAN_EINVAL;
        }
    if (p->kind == CIGI_IG_CONTROL || p->kind == CIGI_START_OF_FRAME) put_version(f, p->kind, q);
    return OCEAN_OK;
}

/* ---- values ---------------------------------------------------------------------- */

enum { C_GEO = 1,       /* a latitude or longitude range, when the packet is geodetic */
       C_READ_BY_HAT = 2 /* an altitude a HOT request does not read */ };

typedef struct check {
    cigi_kind kind;
    char type;          /* 'u' uint32_t, 'd' double */
    uint8_t flags;
    uint16_t member;
    const char *name;
    double lo, hi;      /* the range; a double must also be finite */
} check;

#define CU(K, T, m, n, lo, hi) {K, 'u', 0, M(T, m), n, lo, hi}
#define CD(K, T, m, f, n, lo, hi) {K, 'd', f, M(T, m), n, lo, hi}
#define BIG 1e300       /* any finite value */
#define ALT 1e6         /* |altitude| in m: far above anything that flies */

static const check checks[] = {
    CU(CIGI_ENTITY_CONTROL, cigi_entity, state, "entity state", 0, 2),
    CU(CIGI_ENTITY_CONTROL, cigi_entity, clamp, "ground/ocean clamp", 0, 2),
    CD(CIGI_ENTITY_CONTROL, cigi_entity, roll, 0, "roll", -BIG, BIG),
    CD(CIGI_ENTITY_CONTROL, cigi_entity, pitch, 0, "pitch", -BIG, BIG),
    CD(CIGI_ENTITY_CONTROL, cigi_entity, yaw, 0, "yaw", -BIG, BIG),
    CD(CIGI_ENTITY_CONTROL, cigi_entity, lat, C_GEO, "latitude", -90, 90),
    CD(CIGI_ENTITY_CONTROL, cigi_entity, lon, C_GEO, "longitude", -180, 180),
    CD(CIGI_ENTITY_CONTROL, cigi_entity, alt, 0, "altitude", -ALT, ALT),
    CU(CIGI_ENTITY_POSITION, cigi_entity, clamp, "ground/ocean clamp", 0, 2),
    CD(CIGI_ENTITY_POSITION, cigi_entity, roll, 0, "roll", -BIG, BIG),
    CD(CIGI_ENTITY_POSITION, cigi_entity, pitch, 0, "pitch", -BIG, BIG),
    CD(CIGI_ENTITY_POSITION, cigi_entity, yaw, 0, "yaw", -BIG, BIG),
    CD(CIGI_ENTITY_POSITION, cigi_entity, lat, C_GEO, "latitude", -90, 90),
    CD(CIGI_ENTITY_POSITION, cigi_entity, lon, C_GEO, "longitude", -180, 180),
    CD(CIGI_ENTITY_POSITION, cigi_entity, alt, 0, "altitude", -ALT, ALT),
    CD(CIGI_ATMOSPHERE_CONTROL, cigi_atmosphere, wind_h, 0, "horizontal wind speed", 0, BIG),
    CD(CIGI_ATMOSPHERE_CONTROL, cigi_atmosphere, wind_dir, 0, "wind direction", -BIG, BIG),
    CU(CIGI_WEATHER_CONTROL, cigi_weather, scope, "scope", 0, 2),
    CD(CIGI_WEATHER_CONTROL, cigi_weather, wind_h, 0, "horizontal wind speed", 0, BIG),
    CD(CIGI_WEATHER_CONTROL, cigi_weather, wind_dir, 0, "wind direction", -BIG, BIG),
    CD(CIGI_WEATHER_CONTROL, cigi_weather, base, 0, "base elevation", -BIG, BIG),
    CD(CIGI_WEATHER_CONTROL, cigi_weather, thickness, 0, "thickness", 0, BIG),
    CU(CIGI_MARITIME_CONTROL, cigi_maritime_control, scope, "scope", 0, 2),
    CD(CIGI_MARITIME_CONTROL, cigi_maritime_control, surface_height, 0, "sea surface height", -BIG, BIG),
    CU(CIGI_WAVE_CONTROL, cigi_wave, scope, "scope", 0, 2),
    CD(CIGI_WAVE_CONTROL, cigi_wave, height, 0, "wave height", 0, BIG),
    CD(CIGI_WAVE_CONTROL, cigi_wave, wavelength, 0, "wavelength", 0, BIG),
    CD(CIGI_WAVE_CONTROL, cigi_wave, period, 0, "period", 0, BIG),
    CD(CIGI_WAVE_CONTROL, cigi_wave, direction, 0, "direction", -BIG, BIG),
    CD(CIGI_WAVE_CONTROL, cigi_wave, phase, 0, "phase offset", -BIG, BIG),
    CU(CIGI_HAT_HOT_REQUEST, cigi_hat_hot_request, type, "request type", 0, 2),
    CD(CIGI_HAT_HOT_REQUEST, cigi_hat_hot_request, lat, C_GEO, "latitude", -90, 90),
    CD(CIGI_HAT_HOT_REQUEST, cigi_hat_hot_request, lon, C_GEO, "longitude", -180, 180),
    CD(CIGI_HAT_HOT_REQUEST, cigi_hat_hot_request, alt, C_READ_BY_HAT, "altitude", -ALT, ALT),
    CD(CIGI_ENV_REQUEST, cigi_env_request, lat, C_GEO, "latitude", -90, 90),
    CD(CIGI_ENV_REQUEST, cigi_env_request, lon, C_GEO, "longitude", -180, 180),
};

/* Latitude and longitude are degrees, not a child's or an entity-relative
 * request's offsets in metres. */
static int geodetic(const cigi_packet *p)
{
    if (p->kind == CIGI_HAT_HOT_REQUEST) return p->u.hat_req.coord == CIGI_COORD_GEODETIC;
    if (p->kind == CIGI_ENTITY_CONTROL || p->kind == CIGI_ENTITY_POSITION) return !p->u.entity.attach;
    return 1;
}

ocean_result cigi_packet_check(const cigi_packet *p, char *why, size_t why_len)
{
    for (size_t i = 0; i < COUNT(checks); i++) {
        const check *c = &checks[i];
        if (c->kind != p->kind) continue;
        if ((c->flags & C_READ_BY_HAT) && p->u.hat_req.type == CIGI_HOT) continue;
        double lo = c->lo, hi = c->hi, v;
        if ((c->flags & C_GEO) && !geodetic(p)) lo = -BIG, hi = BIG;
        if (c->type == 'u') {
            uint32_t u;
            memcpy(&u, (const char *)p + c->member, sizeof u);
            v = u;
        } else {
            memcpy(&v, (const char *)p + c->member, sizeof v);
        }
        if (isfinite(v) && v >= lo && v <= hi) continue;
        if (hi == BIG && lo == -BIG) ocean_seterr(why, why_len, "%s: %s %g is not a finite number", cigi_kind_name(p->kind), c->name, v);
        else if (hi == BIG) ocean_seterr(why, why_len, "%s: %s %g, not a finite number >= %g", cigi_kind_name(p->kind), c->name, v, lo);
        else ocean_seterr(why, why_len, "%s: %s %g outside [%g, %g]", cigi_kind_name(p->kind), c->name, v, lo, hi);
        return OCEAN_EINVAL;
    }
    return OCEAN_OK;
}

static const char *const kind_names[CIGI_KIND_COUNT_] = {
    [CIGI_UNKNOWN] = "unknown packet",
    [CIGI_IG_CONTROL] = "IG Control",
    [CIGI_ENTITY_CONTROL] = "Entity Control",
    [CIGI_ENTITY_POSITION] = "Entity Position",
    [CIGI_ATMOSPHERE_CONTROL] = "Atmosphere Control",
    [CIGI_WEATHER_CONTROL] = "Weather Control",
    [CIGI_MARITIME_CONTROL] = "Maritime Surface Conditions Control",
    [CIGI_WAVE_CONTROL] = "Wave Control",
    [CIGI_HAT_HOT_REQUEST] = "HAT/HOT Request",
    [CIGI_ENV_REQUEST] = "Environmental Conditions Request",
    [CIGI_START_OF_FRAME] = "Start of Frame",
    [CIGI_HAT_HOT_RESPONSE] = "HAT/HOT Response",
    [CIGI_HAT_HOT_XRESPONSE] = "HAT/HOT Extended Response",
    [CIGI_MARITIME_RESPONSE] = "Maritime Surface Conditions Response",
};

const char *cigi_kind_name(cigi_kind k)
{
    return (unsigned)k < CIGI_KIND_COUNT_ ? kind_names[k] : "?";
}
