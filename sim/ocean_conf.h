/*
 * ocean_conf.h - the simulation's configuration keys and scene files.
 *
 * Two conf tables (see conf.h):
 *   - the ocean table, target ocean_params: sea.* (the sea state) and
 *     ocean.* (resolution, cascades, seed, threads);
 *   - the scene table, target ocean_scene: scene.name, scene.description,
 *     scene.effects, scene.camera_hint.
 * The daemon combines the ocean table with its own server.* table in one
 * conf_set and loads config/oceand.conf through it; ocean-sim loads the
 * same file with ocean_conf_load, which skips server.* and scene.* keys.
 *
 * Wind and Beaufort force: sea.beaufort F (0..12) sets sea.wind to the
 * force's representative U10 (ocean_beaufort_wind) at the moment it is
 * read; it is not stored.  One file may give sea.wind or sea.beaufort, not
 * both (an error naming both lines).  Across layers - the daemon's file, then
 * a scene file, then --set overrides - the later assignment of either key
 * wins, so a scene's sea.beaufort = 10 replaces the daemon's sea.wind.
 */
#ifndef OCEAN_OCEAN_CONF_H
#define OCEAN_OCEAN_CONF_H

#include <stddef.h>

#include "conf.h"
#include "ocean.h"

/* Every effect a scene may name: ocean.h's four channel groups and the
 * Gerstner near field around each camera (OCEAN_FX_NEAR_FIELD). */
#define OCEAN_SCENE_FX_ALL (OCEAN_FX_ALL | OCEAN_FX_NEAR_FIELD)

#define OCEAN_SCENE_NAME_MAX 64
#define OCEAN_SCENE_DESC_MAX 256
#define OCEAN_SCENE_HINT_MAX 128

/* A scene: its identity, the effects it needs and its sea. */
typedef struct ocean_scene {
    char name[OCEAN_SCENE_NAME_MAX];        /* [a-z0-9_-]+, e.g. "storm" */
    char description[OCEAN_SCENE_DESC_MAX];
    unsigned effects;                       /* OCEAN_FX_* bits, near field included */
    char camera_hint[OCEAN_SCENE_HINT_MAX]; /* "x,y,z[,heading[,pitch]]" or "" */
    ocean_params params;                    /* the daemon's defaults + the scene's keys */
} ocean_scene;

/* The ocean table (target: ocean_params) and the scene table (target:
 * ocean_scene; it holds only the scene.* keys - load it beside the ocean
 * table pointed at &scene->params).  Static; never NULL. */
const conf_table *ocean_conf_table(void);
const conf_table *ocean_conf_scene_table(void);

/* Loads a configuration file into *p: ocean_params_default, the table's
 * defaults, then the file's sea.* and ocean.* keys (server.* and scene.*
 * keys are syntax-checked and skipped), then ocean_params_validate.  On
 * failure *p is unchanged and err holds "file:line: message: 'text'" (or
 * "file: message" for a whole-parameter check). */
ocean_result ocean_conf_load(const char *path, ocean_params *p, char *err, size_t errlen);
/* The same from a buffer of len bytes called name in messages. */
ocean_result ocean_conf_load_string(const char *name, const char *text, size_t len,
                                    ocean_params *p, char *err, size_t errlen);

/* Applies one "key=value" override (--set) to *p and validates the result;
 * *p is unchanged on failure. */
ocean_result ocean_conf_apply(const char *keyvalue, ocean_params *p, char *err, size_t errlen);

/* The file of a scene: `scene` itself when it is a path (holds a '/' or
 * ends in ".conf"), else DIR/SCENE.conf: how oceand's server.scene and
 * `ocean-sim render --scene` name one. */
void ocean_conf_scene_path(const char *dir, const char *scene, char *out, size_t len);

/* Loads a scene file: out->params starts as *base (the daemon's effective
 * parameters), the scene keys start empty, then the file is applied (it
 * must give scene.name and scene.effects; sea.* and ocean.* keys override
 * base), then ocean_params_validate.  *out is unchanged on failure. */
ocean_result ocean_conf_scene_load(const char *path, const ocean_params *base,
                                   ocean_scene *out, char *err, size_t errlen);
ocean_result ocean_conf_scene_load_string(const char *name, const char *text, size_t len,
                                          const ocean_params *base, ocean_scene *out,
                                          char *err, size_t errlen);

/* Parses a camera hint "x,y,z[,heading_deg[,pitch_deg]]" (metres, degrees;
 * y up) into v[0..4]; missing heading and pitch read 0.  OCEAN_EINVAL for
 * anything else, including an empty hint. */
ocean_result ocean_conf_camera_hint_parse(const char *hint, double v[5]);

#endif
