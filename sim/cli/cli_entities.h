/*
 * cli_entities.h - ships for the offline tools: a file of entity entries
 * (the JSON `ocean-client entity` prints, a track of several samples per
 * id allowed) into an entity table, and the ships' wakes added to point
 * answers as the daemon adds them to QUERY (sim/wake_field.h).
 *
 * The file: a JSON array of objects, entered in order, each a sample
 * {"id", "kind" ("ship", "rotorcraft", "aircraft"), "t", "x", "z",
 * "altitude_m", "heading_deg", "speed", "length_m", "beam_m",
 * "draught_m"} in force from "from" (s; default its "t"), or a removal
 * {"id", "gone": true, "from"}.  Every rule of the daemon's table holds
 * (sim/entity.h): a refused entry is named by its index and reason.
 *
 * Threads: the command's one thread.
 */
#ifndef OCEAN_CLI_ENTITIES_H
#define OCEAN_CLI_ENTITIES_H

#include <stddef.h>

#include "entity.h"
#include "query.h"

/* Reads path ("-": stdin) into a new table (*out).  0, or 2 with the
 * reason printed. */
int cli_entities_load(const char *path, ocean_entities **out);

/* Adds the wakes of the ships of e in the sea at t, over water of depth m,
 * to the n answers res at the points xz (patterns built here).  0, or 1
 * with the reason printed. */
int cli_wakes_apply(const ocean_entities *e, double t, double depth, const double *xz, size_t n,
                    ocean_query_result *res);

#endif
