/*
 * fuzz_path.c - libFuzzer target for the camera-path parser (clients/c
 * oc_path_parse: the files `ocean-client record` and `replay` read, the
 * daemon's recordings among them; server/RECORDING.md).
 *
 * Checks beyond "no crash, no sanitizer report":
 *   - a refused file leaves *out NULL with a message that names the file
 *     and holds no control bytes (it is printed to a terminal);
 *   - a parsed path has at least one point, every field finite and within
 *     the bounds the parser promises (viewport 1..16384, fov in (0, 180)),
 *     monotonic exactly when t never goes back;
 *   - a parsed path written back (oc_path_write) parses again to the same
 *     points, bit for bit (%.17g round-trips t and the position; the other
 *     fields hold the floats CAMERA carries, and %.9g round-trips a float).
 *     It found fov 179.9999999999 accepted, written as "180" and refused.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "oc_path.h"
#include "oceanclient.h"

static void check_point(const oc_path_point *p)
{
    double v[] = {p->t, p->pos[0], p->pos[1], p->pos[2], p->vel[0], p->vel[1], p->vel[2],
                  p->yaw_deg, p->pitch_deg, p->roll_deg, p->fov_deg};
    for (size_t i = 0; i < sizeof v / sizeof v[0]; i++)
        if (!isfinite(v[i]))
            abort();
    if (p->viewport_w < 1 || p->viewport_w > 16384 || p->viewport_h < 1 || p->viewport_h > 16384)
        abort();
    if (!(p->fov_deg > 0 && p->fov_deg < 180))
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    oc_path *p = (oc_path *)1;
    char err[256] = "";
    ocean_result r = oc_path_parse((const char *)data, size, "fuzz.csv", &p, err, sizeof err);
    if (r != OCEAN_OK) {
        if (p != NULL || strncmp(err, "fuzz.csv", 8) != 0)
            abort();
        for (const char *c = err; *c; c++)
            if ((unsigned char)*c < 0x20 || *c == 0x7f)
                abort();
        return 0;
    }
    if (!p || p->count == 0)
        abort();
    int mono = 1;
    for (size_t i = 0; i < p->count; i++) {
        check_point(&p->pts[i]);
        if (i > 0 && p->pts[i].t < p->pts[i - 1].t)
            mono = 0;
        proto_camera cam;
        oc_path_camera(&p->pts[i], &cam);
    }
    if (mono != p->monotonic)
        abort();
    /* written back, it parses to the same points */
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    if (!f)
        return 0;
    if (oc_path_write(p, f) != OCEAN_OK) {
        fclose(f);
        free(buf);
        abort();
    }
    fclose(f);
    oc_path *q = NULL;
    r = oc_path_parse(buf, len, "written", &q, err, sizeof err);
    free(buf);
    if (r != OCEAN_OK || q->count != p->count)
        abort();
    if (memcmp(p->pts, q->pts, p->count * sizeof *p->pts) != 0)
        abort();
    oc_path_destroy(q);
    oc_path_destroy(p);
    return 0;
}
