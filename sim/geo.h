/*
 * geo.h - the ocean's plane on the Earth: geodetic latitude and longitude
 * (WGS 84) to the ocean's x and z and back, about an origin
 * (server.geo_origin) that maps to x = z = 0.
 *
 * Axes: x points north and z east at the origin, y up, so the ocean's
 * angles (degrees from +x toward +z: wind, headings) are compass bearings.
 * The plane is the azimuthal equidistant projection centred on the origin
 * (PROJ's aeqd on the WGS 84 ellipsoid, Karney's geodesics): the distance
 * and the bearing from the origin to any point are those of the geodesic
 * between them, exactly; other distances stretch across the bearing by
 * about (d/R)^2 / 6 (0.4 % at 1000 km).  Heights are not projected: a
 * geodetic altitude above the mean sea level is the ocean's y, as the sea
 * surface is (the plane is the sea unrolled, not a tangent plane, below
 * which a point 1000 km out would sit 78 km deep).
 *
 * Threads: an ocean_geo belongs to one thread (its PROJ context is its
 * own); make one per thread.
 * OOM: OCEAN_ENOMEM, nothing made.
 */
#ifndef OCEAN_GEO_H
#define OCEAN_GEO_H

#include <stddef.h>

#include "ocean_result.h"

typedef struct ocean_geo ocean_geo;

/* "LAT,LON" in degrees (server.geo_origin, ocean-sim query --origin):
 * finite, |LAT| <= 90, |LON| <= 180.  OCEAN_EINVAL with why. */
ocean_result ocean_geo_origin_parse(const char *text, double *lat, double *lon, char *why, size_t why_len);

/* A plane about (lat0, lon0) degrees: |lat0| <= 90, |lon0| <= 180,
 * finite.  OCEAN_EINVAL with why; OCEAN_ENOMEM. */
ocean_result ocean_geo_create(double lat0, double lon0, ocean_geo **out, char *why, size_t why_len);
/* Accepts NULL. */
void ocean_geo_destroy(ocean_geo *g);

/* (lat, lon) degrees to the plane's (x north, z east) in metres.
 * OCEAN_EINVAL: not finite, |lat| > 90, |lon| > 180, or the antipode of
 * the origin (every bearing reaches it). */
ocean_result ocean_geo_to_plane(ocean_geo *g, double lat, double lon, double *x, double *z);
/* (x, z) metres to (lat, lon) degrees, lon in [-180, 180].
 * OCEAN_EINVAL: not finite, or farther than half a meridian from the
 * origin (the projection covers the Earth once within it). */
ocean_result ocean_geo_to_geodetic(ocean_geo *g, double x, double z, double *lat, double *lon);

#endif
