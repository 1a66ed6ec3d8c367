/*
 * wave_rng.c - Philox-keyed uniforms and normals (see wave_rng.h).
 */
#include "wave_rng.h"

#include <math.h>
#include <string.h>

#include <Random123/philox.h>

void ocean_rng_uniform2(uint64_t seed, uint32_t stream, uint32_t salt,
                        int32_t a, int32_t b, double out[2])
{
    philox4x32_key_t key = {{(uint32_t)seed, (uint32_t)(seed >> 32)}};
    philox4x32_ctr_t ctr = {{(uint32_t)a, (uint32_t)b, salt, stream}};
    philox4x32_ctr_t r = philox4x32(ctr, key);
    for (int i = 0; i < 2; i++) {
        uint64_t bits = ((uint64_t)r.v[2 * i] << 32 | r.v[2 * i + 1]) >> 11;
        /* (bits + 0.5) / 2^53 lies strictly inside (0, 1): log() stays finite. */
        out[i] = ((double)bits + 0.5) * (1.0 / 9007199254740992.0);
    }
}

void ocean_rng_normal2(uint64_t seed, uint32_t stream, uint32_t salt,
                       int32_t a, int32_t b, double out[2])
{
    double u[2];
    ocean_rng_uniform2(seed, stream, salt, a, b, u);
    double r = sqrt(-2.0 * log(u[0]));
    double phi = 2.0 * M_PI * u[1];
    out[0] = r * cos(phi);
    out[1] = r * sin(phi);
}

uint32_t ocean_rng_patch_salt(double patch_m)
{
    uint64_t bits;
    memcpy(&bits, &patch_m, sizeof bits);
    /* splitmix64 finaliser: nearby sizes get unrelated salts. */
    bits ^= bits >> 30; bits *= 0xbf58476d1ce4e5b9ULL;
    bits ^= bits >> 27; bits *= 0x94d049bb133111ebULL;
    bits ^= bits >> 31;
    return (uint32_t)bits ^ (uint32_t)(bits >> 32);
}
