/*
 * occli.h - shared pieces of the ocean-client subcommands: a table-driven
 * option parser that refuses unknown or malformed options by name, the
 * subscription options every streaming command shares, and small helpers
 * (percentiles, clocks).
 */
#ifndef OCCLI_H
#define OCCLI_H

#include <stddef.h>
#include <stdint.h>
#include <signal.h>
#include <stdio.h>

#include "oceanclient.h"

typedef enum occli_kind {
    OCCLI_DOUBLE,   /* double *, finite, in [min, max] */
    OCCLI_INT,      /* int *, in [min, max] */
    OCCLI_STRING,   /* const char ** */
    OCCLI_FLAG,     /* int *, set to 1 */
    OCCLI_CHOICE    /* int *, index of the value in names[]; -1 = not given */
} occli_kind;

/* One option.  Its default is whatever *target holds when occli_parse
 * starts: --help prints that value (so help cannot disagree with the
 * code), and the help text itself never states a default. */
typedef struct occli_opt {
    const char *name;   /* without "--" */
    occli_kind kind;
    void *target;
    double min, max;
    const char *help;   /* "ARG  text" */
    const char *const *names;   /* OCCLI_CHOICE: NULL-terminated value names */
} occli_opt;

/* Subscription and camera options shared by watch/record/replay/export/load. */
typedef struct occli_sub {
    const char *codec;     /* --codec NAME */
    const char *effects;   /* --effects LIST */
    const char *mesh;      /* --mesh KIND */
    int layout;            /* --layout 0|1 */
    const char *mesh_codec;/* --mesh-codec f32|qz (layout 0) */
    int full_geometry;     /* --full-geometry (layout 1: SUBSCRIBE.flags bit 0) */
    int time_interp;       /* --time-interp off|on (index in occli_off_on;
                              layout 1: SUBSCRIBE.flags bit 1) */
    const char *policy;    /* --cutoff-policy NAME */
    double rate;           /* --rate HZ */
    double accuracy;       /* --accuracy A */
    int tile_size;         /* --tile-size N */
    int levels;            /* --levels N */
    int layers;            /* --layers N */
    double spacing;        /* --spacing M */
    double range;          /* --range M */
    const char *pos;       /* --pos x,y,z */
    const char *vel;       /* --vel vx,vy,vz */
    double yaw, pitch, fov;
    int timeout_ms;        /* --timeout MS (connect and replies) */
} occli_sub;

/* Names of an off/on choice, in that order (OCCLI_CHOICE). */
extern const char *const occli_off_on[];

#define OCCLI_SUB_OPTS(s)                                                                                   \
    {"codec", OCCLI_STRING, &(s)->codec, 0, 0, "NAME  tile codec: f32 f16 qz exr-zip exr-piz exr-b44 exr-b44a", NULL}, \
    {"effects", OCCLI_STRING, &(s)->effects, 0, 0, "LIST  height,displacement,normals,foam,near or all", NULL},        \
    {"mesh", OCCLI_STRING, &(s)->mesh, 0, 0, "KIND  concentric chunked projected none", NULL},                        \
    {"layout", OCCLI_INT, &(s)->layout, 0, 1, "N  0: world tiles summed per camera, mesh displaced by the server;\n"     \
                                              "                       1: shared cascade tiles (the viewer's and the library's)", NULL}, \
    {"mesh-codec", OCCLI_STRING, &(s)->mesh_codec, 0, 0, "NAME  layout-0 mesh positions: f32 or qz (at --accuracy)", NULL}, \
    {"full-geometry", OCCLI_FLAG, &(s)->full_geometry, 0, 0, "layout 1: height and displacement in every mip, also\n"   \
                                                      "                       those finer than the mesh shows", NULL}, \
    {"time-interp", OCCLI_CHOICE, &(s)->time_interp, 0, 0, "MODE  layout 1: samples in time, the viewer's stream: each mip\n" \
                                                      "                       travels once per its update interval and each frame\n" \
                                                      "                       blends two samples the client holds", occli_off_on}, \
    {"cutoff-policy", OCCLI_STRING, &(s)->policy, 0, 0, "NAME  none seed antialias", NULL},                          \
    {"rate", OCCLI_DOUBLE, &(s)->rate, 0.1, 240, "HZ  frame rate asked of the server", NULL},                        \
    {"accuracy", OCCLI_DOUBLE, &(s)->accuracy, 1e-6, 0.5, "A  qz accuracy target", NULL},                           \
    {"tile-size", OCCLI_INT, &(s)->tile_size, 2, 1024, "N  samples per tile side", NULL},                            \
    {"levels", OCCLI_INT, &(s)->levels, 1, 16, "N  tile LOD levels", NULL},                                          \
    {"layers", OCCLI_INT, &(s)->layers, 1, 4, "N  cascades wanted", NULL},                                           \
    {"spacing", OCCLI_DOUBLE, &(s)->spacing, 0, 1e6, "M  level-0 sample spacing, 0 = server default", NULL},         \
    {"range", OCCLI_DOUBLE, &(s)->range, 0, 1e7, "M  view range, 0 = server default", NULL},                         \
    {"pos", OCCLI_STRING, &(s)->pos, 0, 0, "X,Y,Z  camera position", NULL},                                          \
    {"vel", OCCLI_STRING, &(s)->vel, 0, 0, "VX,VY,VZ  camera velocity", NULL},                                       \
    {"yaw", OCCLI_DOUBLE, &(s)->yaw, -360, 360, "DEG  camera yaw", NULL},                                          \
    {"pitch", OCCLI_DOUBLE, &(s)->pitch, -90, 90, "DEG  camera pitch", NULL},                                        \
    {"fov", OCCLI_DOUBLE, &(s)->fov, 0.01, 179.9, "DEG  vertical field of view", NULL},                              \
    {"timeout", OCCLI_INT, &(s)->timeout_ms, 1, 3600000, "MS  connect / reply timeout", NULL}

/* Fills s from the library's own defaults (oc_subscribe_default,
 * oc_camera_default), so the CLI asks for what a library user gets. */
void occli_sub_default(occli_sub *s);
/* Builds SUBSCRIBE and CAMERA from the options; prints the reason and
 * returns 2 on a bad value. */
int occli_sub_build(const char *cmd, const occli_sub *s, proto_subscribe *sub, proto_camera *cam);

/* Parses argv[1..] (argv[0] is the subcommand).  Positional arguments are
 * collected into pos[0..*npos) (at most max_pos).  Returns 0 ok, 1 help
 * (or --show-options) printed, 2 error printed (naming the option).
 * --help shows each option's default as its target held it on entry;
 * --show-options prints every option's value after parsing as
 * --name=value lines, so a script (and the test) sees what the command
 * would run with.  At most OCCLI_MAX_OPTS options. */
#define OCCLI_MAX_OPTS 64
int occli_parse(int argc, char **argv, const char *usage, const occli_opt *opts, int nopts,
                const char **pos, int max_pos, int *npos);

/* Parses "a,b,c" into n doubles; 0 on success. */
int occli_parse_vec(const char *s, double *out, int n);

/* Progress on stderr when it is a terminal, drawn as ocean-sim bake draws
 * it: "\r[#####     ] " and the formatted detail, at most 10 times a second;
 * a newline once done >= total.  occli_progress_end() ends the line early
 * (interrupted, failed).  Both do nothing when stderr is not a terminal. */
void occli_progress(double done, double total, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
void occli_progress_end(void);

/* Connects with the standard options; prints the reason and returns NULL on
 * failure. */
oc_client *occli_connect(const char *cmd, const char *url, const oc_options *base, int timeout_ms);

double occli_mono(void);       /* monotonic seconds */
double occli_wall(void);       /* realtime seconds */
void occli_sleep(double s);

/* Prints a cJSON object (pretty, one trailing newline) to stdout and frees
 * it; prints nothing if cJSON cannot allocate the text. */
struct cJSON;
void occli_print_json(struct cJSON *o);

/* p-th percentile (0..100) of v[0..n) (sorts v in place); NAN if n == 0. */
double occli_percentile(double *v, size_t n, double p);

/* A growable array of doubles. */
typedef struct occli_vec {
    double *v;
    size_t n, cap;
} occli_vec;
int occli_vec_push(occli_vec *a, double x);
void occli_vec_free(occli_vec *a);

/* Set by SIGINT/SIGTERM; streaming commands stop early and still report. */
extern volatile sig_atomic_t occli_stop;

int cmd_watch(int argc, char **argv);
int cmd_query(int argc, char **argv);
int cmd_record(int argc, char **argv);
int cmd_replay(int argc, char **argv);
int cmd_export(int argc, char **argv);
int cmd_load(int argc, char **argv);
int cmd_sea(int argc, char **argv);
int cmd_entity(int argc, char **argv);
int cmd_fidelity(int argc, char **argv);

#endif
