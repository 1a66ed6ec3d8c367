/*
 * fuzz_frame.c - libFuzzer target for what a simulator's client library
 * does with a FRAME from the server (clients/c): oc_frame_decode (the
 * message decoder, every tile's codec, then the layout-1 view that indexes
 * the tiles by cascade, mip and position) and the point readers a
 * simulator calls on it.  A server is another program on the network: a
 * buggy or hostile one must cost the client a clean error, never a crash
 * or a read outside a tile.
 *
 * Checks beyond "no crash, no sanitizer report":
 *   - a failed decode leaves *out NULL and says why;
 *   - on a decoded frame, oc_frame_sample, oc_frame_sample_interp (every
 *     kernel) and oc_frame_surface at points spread over and beyond the
 *     frame's tiles either return a documented code or give finite values
 *     (foam in [0, 1], a unit normal), and a failed read leaves its output
 *     zeroed as the contract says;
 *   - on a frame with a view, a non-finite point or spacing and an unknown
 *     kernel are OCEAN_EINVAL.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "oc_cascade.h"
#include "oceanclient.h"

static int zeroed(const oc_sample *s)
{
    static const oc_sample z;
    return memcmp(s, &z, sizeof z) == 0;
}

static void check_sample(ocean_result r, const oc_sample *s, int surface)
{
    if (r == OCEAN_OK || (surface && r == OCEAN_EDIVERGED)) {
        double v[] = {s->height, s->dx, s->dz, s->slope_x, s->slope_z, s->normal[0], s->normal[1],
                      s->normal[2], s->foam, s->mss[0], s->mss[1], s->mss[2], s->s};
        for (size_t i = 0; i < sizeof v / sizeof v[0]; i++)
            if (!isfinite(v[i]))
                abort();
        if (s->foam < 0 || s->foam > 1)
            abort();
        double nl = s->normal[0] * s->normal[0] + s->normal[1] * s->normal[1] + s->normal[2] * s->normal[2];
        if (fabs(nl - 1) > 1e-6)
            abort();
        return;
    }
    if (r != OCEAN_ENOTFOUND && r != OCEAN_ESTATE && r != OCEAN_EINVAL && r != OCEAN_EFORMAT)
        abort();
    if (!surface && !zeroed(s))
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    oc_frame *f = (oc_frame *)1;
    char err[256] = "";
    ocean_result r = oc_frame_decode(data, size, &f, err, sizeof err);
    if (r != OCEAN_OK) {
        if (f != NULL || !err[0])
            abort();
        return 0;
    }
    if (!f)
        abort();
    /* points over the frame's tiles and past them: the centre, the tile
     * edges of a few spacings, far away (wrapping), and negative */
    static const double xs[] = {0, 0.37, -1.5, 7.9, 31.99, 32.0, 63.5, -250.0, 1000.25, 1e6, -3.3e7};
    static const double sp[] = {0, 0.25, 4, 1e5};
    oc_sample s;
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; i++)
        for (size_t j = 0; j < sizeof xs / sizeof xs[0]; j += 3)
            for (size_t k = 0; k < sizeof sp / sizeof sp[0]; k++) {
                double x = xs[i] + f->info.origin[0], z = xs[j] + f->info.origin[2];
                check_sample(oc_frame_sample(f, x, z, sp[k], &s), &s, 0);
                if (k == 0) {
                    check_sample(oc_frame_sample_interp(f, x, z, 0, OC_INTERP_LINEAR, &s), &s, 0);
                    check_sample(oc_frame_surface(f, x, z, 0, &s), &s, 1);
                }
            }
    /* a frame with a view refuses a non-finite point or spacing */
    if (f->view && (oc_frame_sample(f, NAN, 0, 0, &s) != OCEAN_EINVAL ||
                    oc_frame_sample(f, 0, INFINITY, 0, &s) != OCEAN_EINVAL ||
                    oc_frame_sample(f, 0, 0, NAN, &s) != OCEAN_EINVAL ||
                    oc_frame_sample_interp(f, 0, 0, 0, (oc_interp)7, &s) != OCEAN_EINVAL))
        abort();
    for (int in = OC_INTERP_CUBIC; in <= OC_INTERP_LANCZOS3; in++)
        check_sample(oc_frame_sample_interp(f, f->info.origin[0] + 3.1, f->info.origin[2] - 2.2, 0, (oc_interp)in, &s),
                     &s, 0);
    oc_frame_free(f);
    return 0;
}
