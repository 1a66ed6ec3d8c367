/*
 * wave_rng.h - counter-based random numbers keyed by a wave's identity.
 *
 * Every random number of the simulation comes from Philox4x32-10
 * (Random123) keyed by the sea's seed and counted by the wave's integer
 * coordinates, so a wave's amplitude does not depend on the grid, the
 * evaluation order or the thread that draws it.
 */
#ifndef OCEAN_WAVE_RNG_H
#define OCEAN_WAVE_RNG_H

#include <stdint.h>

/* Streams keep unrelated uses of the same (seed, a, b) independent. */
enum ocean_rng_stream {
    OCEAN_RNG_FFT = 1,       /* h0 of FFT modes; salt = patch size key */
    OCEAN_RNG_GERSTNER = 2   /* Gerstner near-field waves */
};

/* Two independent standard normal deviates for (seed, stream, salt, a, b),
 * by Box-Muller on two 53-bit uniforms.  Pure function. */
void ocean_rng_normal2(uint64_t seed, uint32_t stream, uint32_t salt,
                       int32_t a, int32_t b, double out[2]);

/* Two independent uniforms in (0, 1) for the same key. */
void ocean_rng_uniform2(uint64_t seed, uint32_t stream, uint32_t salt,
                        int32_t a, int32_t b, double out[2]);

/* A 32-bit salt identifying a patch size, so cascades of different sizes
 * draw different waves and a cascade keeps its waves across configurations. */
uint32_t ocean_rng_patch_salt(double patch_m);

#endif
