/*
 * srv_fingerprint.c - the determinism fingerprint (see srv_fingerprint.h).
 */
#include "srv_fingerprint.h"

#include <fftw3.h>
#include <stdio.h>
#include <string.h>


static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
    const uint8_t *b = p;
    for (size_t i = 0; i < n; i++) {
        h ^= b[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

static uint64_t fnv_str(uint64_t h, const char *s) { return fnv(h, s, strlen(s) + 1); }

static uint64_t fnv_f64(uint64_t h, double v)
{
    uint64_t u;
    memcpy(&u, &v, 8);
    return fnv(h, &u, 8);
}

static uint64_t fnv_int(uint64_t h, long long v) { return fnv(h, &v, sizeof v); }

void srv_fingerprint(const srv_settings *s, char out[17])
{
    uint64_t h = 0xcbf29ce484222325ull;
    h = fnv_str(h, SRV_VERSION);
    h = fnv_str(h, __VERSION__);
#ifdef __OPTIMIZE__
    h = fnv_int(h, 1);
#endif
    __builtin_cpu_init();
    h = fnv_int(h, __builtin_cpu_supports("avx"));
    h = fnv_int(h, __builtin_cpu_supports("avx2"));
    h = fnv_int(h, __builtin_cpu_supports("fma"));
    h = fnv_int(h, __builtin_cpu_supports("avx512f"));
    h = fnv_str(h, fftwf_version);
    const ocean_params *p = &s->params;
    h = fnv_int(h, p->n);
    h = fnv_int(h, p->cascades);
    h = fnv_f64(h, p->patch_m);
    h = fnv_f64(h, p->cascade_ratio);
    h = fnv_f64(h, p->k_max);
    h = fnv_int(h, p->threads);
    h = fnv_int(h, p->plan_measure);
    h = fnv_f64(h, p->drop_gain);
    const srv_config *c = &s->srv;
    h = fnv_int(h, (long long)s->effects);
    h = fnv_f64(h, c->tick_rate);
    h = fnv_int(h, c->tiles_per_side);
    h = fnv_f64(h, c->base_spacing);
    h = fnv_f64(h, c->view_range);
    h = fnv_f64(h, c->mesh_error_px);
    h = fnv_f64(h, c->flat_mesh_error_px);
    h = fnv_f64(h, c->px_per_sample);
    h = fnv_f64(h, c->viewer_bytes_per_s);
    h = fnv_int(h, c->cascade_tile);
    h = fnv_int(h, c->near_field_waves);
    h = fnv_f64(h, c->near_field_radius);
    h = fnv_f64(h, c->near_field_min_wavelength);
    snprintf(out, 17, "%016llx", (unsigned long long)h);
}
