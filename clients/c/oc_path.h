/*
 * oc_path.h - camera paths: the "oceand camera path v1" CSV format that the
 * daemon's recordings use (server/RECORDING.md) and ocean-client
 * record/replay read and write.
 *
 *   # oceand camera path v1
 *   t,x,y,z,vx,vy,vz,yaw_deg,pitch_deg,roll_deg,fov_y_deg,viewport_w,viewport_h
 *   12.5,0,25,0,8,0,0,0,-5,0,60,1280,720
 *
 * t sim seconds, non-decreasing except in a replay-mode segment (after the
 * daemon's "# subscribed at T: mode replay" comment t is the render_time
 * the client asked for, in its order), x/y/z world metres (y up), vx/vy/vz m/s,
 * yaw/pitch/roll degrees (PROTOCOL.md "Camera orientation"), the vertical
 * field of view in degrees, the viewport in pixels.  '#' starts a comment
 * line; a "# oceand camera path vN" comment with N != 1 is refused; blank
 * lines are ignored; fields may be surrounded by spaces.  The first
 * non-comment line is the header: the 13 columns above, or the first 11
 * (viewport 1280 x 720), and the short names yaw,pitch,roll,fov are accepted
 * for the angle columns.  Errors name file:line and quote the text.
 */
#ifndef OC_PATH_H
#define OC_PATH_H

#include <stddef.h>
#include <stdio.h>

#include "ocean_result.h"
#include "proto.h"

#define OC_PATH_VERSION_LINE "# oceand camera path v1"
#define OC_PATH_HEADER "t,x,y,z,vx,vy,vz,yaw_deg,pitch_deg,roll_deg,fov_y_deg,viewport_w,viewport_h"
#define OC_PATH_DEFAULT_VIEWPORT_W 1280
#define OC_PATH_DEFAULT_VIEWPORT_H 720
#define OC_PATH_MAX_POINTS 10000000u
/* Largest |x|, |z| and |y| of a point, metres: PROTOCOL.md's CAMERA bounds
 * (what the daemon accepts and records; proto.c's MAX_WORLD, MAX_LOCAL). */
#define OC_PATH_MAX_XZ 1e10
#define OC_PATH_MAX_Y 1e7

typedef struct oc_path_point {
    double t;
    double pos[3];
    /* vel, the angles and fov hold the floats CAMERA carries (the text's
     * value rounded to float when parsed), so they are what the server
     * receives and check and round-trip through oc_path_write */
    double vel[3];
    double yaw_deg, pitch_deg, roll_deg;
    double fov_deg;
    int viewport_w, viewport_h;   /* 1..16384 */
} oc_path_point;

typedef struct oc_path {
    size_t count;
    oc_path_point *pts;
    /* 1: t never goes back.  0: a replay-mode segment scrubs back (the
     * first such point on line back_line): send it as recorded (replay
     * mode), not paced by t. */
    int monotonic;
    unsigned back_line;
} oc_path;

/* Parses text (len bytes, need not be NUL-terminated); name is used in
 * error messages ("name:line: ...").  *out NULL on failure. */
ocean_result oc_path_parse(const char *text, size_t len, const char *name, oc_path **out,
                           char *err, size_t errlen);
/* Reads and parses a file; "-" reads standard input. */
ocean_result oc_path_load(const char *file, oc_path **out, char *err, size_t errlen);
void oc_path_destroy(oc_path *p);   /* accepts NULL */

/* Writes p in the format above (version line and 13-column header first;
 * %.17g for t and the position, %.9g for the float fields, as the daemon). */
ocean_result oc_path_write(const oc_path *p, FILE *f);

/* The CAMERA for one point, render_time = pt->t (the caller zeroes it for
 * live mode). */
void oc_path_camera(const oc_path_point *pt, proto_camera *cam);

#endif
