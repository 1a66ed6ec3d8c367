/*
 * geo.c - the ocean's plane on the Earth (see geo.h): PROJ's azimuthal
 * equidistant projection on WGS 84, with the axes turned to the ocean's.
 *
 * Threads: one ocean_geo per thread (see geo.h).
 */
#include "geo.h"

#include <math.h>
#include <proj.h>
#include <stdio.h>
#include <stdlib.h>

/* Half a meridian of WGS 84 (m): the farthest any point is, along a
 * geodesic, from the origin; beyond it the projection's inverse wraps. */
#define HALF_MERIDIAN 20003931.4586

struct ocean_geo {
    PJ_CONTEXT *ctx;
    PJ *pj;
    double lat0, lon0;
};

static int geodetic_ok(double lat, double lon)
{
    return isfinite(lat) && isfinite(lon) && fabs(lat) <= 90 && fabs(lon) <= 180;
}

ocean_result ocean_geo_origin_parse(const char *text, double *lat, double *lon, char *why, size_t why_len)
{
    char *end;
    *lat = strtod(text, &end);
    if (end != text && *end == ',') {
        const char *q = end + 1;
        *lon = strtod(q, &end);
        if (end != q && *end == 0 && geodetic_ok(*lat, *lon)) return OCEAN_OK;
    }
    ocean_seterr(why, why_len, "expected LAT,LON in degrees, |LAT| <= 90, |LON| <= 180");
    return OCEAN_EINVAL;
}

ocean_result ocean_geo_create(double lat0, double lon0, ocean_geo **out, char *why, size_t why_len)
{
    *out = NULL;
    if (!geodetic_ok(lat0, lon0)) {
        ocean_seterr(why, why_len, "origin %.9g, %.9g: latitude in [-90, 90] and longitude in [-180, 180] degrees", lat0, lon0);
        return OCEAN_EINVAL;
    }
    ocean_geo *g = calloc(1, sizeof *g);
    if (!g) return OCEAN_ENOMEM;
    g->lat0 = lat0;
    g->lon0 = lon0;
    g->ctx = proj_context_create();
    char def[160];
    snprintf(def, sizeof def, "+proj=aeqd +lat_0=%.17g +lon_0=%.17g +ellps=WGS84 +units=m", lat0, lon0);
    g->pj = g->ctx ? proj_create(g->ctx, def) : NULL;
    if (!g->pj) {
        ocean_result r = g->ctx ? OCEAN_EINVAL : OCEAN_ENOMEM;
        ocean_seterr(why, why_len, "PROJ could not make the plane about %.9g, %.9g: %s", lat0, lon0,
            g->ctx ? proj_context_errno_string(g->ctx, proj_context_errno(g->ctx)) : "no context (out of memory)");
        ocean_geo_destroy(g);
        return r;
    }
    *out = g;
    return OCEAN_OK;
}

void ocean_geo_destroy(ocean_geo *g)
{
    if (!g) return;
    if (g->pj) proj_destroy(g->pj);
    if (g->ctx) proj_context_destroy(g->ctx);
    free(g);
}

ocean_result ocean_geo_to_plane(ocean_geo *g, double lat, double lon, double *x, double *z)
{
    *x = *z = 0;
    if (!geodetic_ok(lat, lon)) return OCEAN_EINVAL;
    proj_errno_reset(g->pj);
    PJ_COORD c = proj_coord(proj_torad(lon), proj_torad(lat), 0, 0);
    PJ_COORD p = proj_trans(g->pj, PJ_FWD, c);
    /* aeqd gives (easting, northing); the ocean's x is north, z east */
    if (proj_errno(g->pj) || !isfinite(p.xy.x) || !isfinite(p.xy.y)) return OCEAN_EINVAL;
    *x = p.xy.y;
    *z = p.xy.x;
    return OCEAN_OK;
}

ocean_result ocean_geo_to_geodetic(ocean_geo *g, double x, double z, double *lat, double *lon)
{
    *lat = *lon = 0;
    if (!isfinite(x) || !isfinite(z) || hypot(x, z) > HALF_MERIDIAN) return OCEAN_EINVAL;
    proj_errno_reset(g->pj);
    PJ_COORD p = proj_trans(g->pj, PJ_INV, proj_coord(z, x, 0, 0));
    if (proj_errno(g->pj) || !isfinite(p.lp.lam) || !isfinite(p.lp.phi)) return OCEAN_EINVAL;
    *lat = proj_todeg(p.lp.phi);
    *lon = remainder(proj_todeg(p.lp.lam), 360.0);
    return OCEAN_OK;
}
