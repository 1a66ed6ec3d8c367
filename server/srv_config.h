/*
 * srv_config.h - the daemon's own settings (server.* keys) and the loader
 * that reads config/oceand.conf through one conf_set: the simulation's
 * ocean table (sea.*, ocean.*) beside the server table, then the scene file
 * named by server.scene on top.
 *
 * A loaded configuration is a plain value (srv_settings): the daemon keeps
 * the one in force and swaps it whole on SIGHUP, so a bad reload changes
 * nothing.
 */
#ifndef SRV_CONFIG_H
#define SRV_CONFIG_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "conf.h"
#include "gerstner.h"
#include "ocean_conf.h"

/* The daemon's name and version: HELLO.server_version, oceand --version. */
#define SRV_VERSION "oceand 0.1"

#define SRV_PATH_MAX 512
#define SRV_TOKEN_MAX 256
#define SRV_BIND_MAX 64
#define SRV_HOSTS_MAX 512
#define SRV_CIGI_HOSTS 16       /* addresses server.cigi_hosts may list */
#define SRV_EPOCH_MAX 64
#define SRV_REDIS_KEY_MAX 128

typedef struct srv_config {
    /* network */
    int port;                    /* TCP port; 0 picks a free one */
    char bind[SRV_BIND_MAX];     /* interface address, "" = all */
    int max_clients;
    int max_message;             /* largest client message, bytes */
    double msg_rate;             /* client messages per second (token bucket) */
    int msg_burst;               /* bucket depth */
    uint64_t output_soft;        /* bytes queued for a client: soft limit */
    double output_soft_seconds;  /* ... tolerated this long */
    uint64_t output_hard;        /* bytes queued: disconnect at once */
    char admin_token[SRV_TOKEN_MAX]; /* "" disables SEA_STATE set */
    char entity_token[SRV_TOKEN_MAX]; /* "" disables ENTITY set and remove */
    double read_rate;            /* bytes/s the service thread reads from one client */
    double partial_seconds;      /* an unfinished message must complete within this */
    double idle_seconds;         /* an unsubscribed connection silent this long gets BYE idle */
    uint64_t partial_total;      /* bytes of unfinished messages held, all clients */
    double admin_lockout;        /* s a connection waits after wrong admin tokens */
    char web_root[SRV_PATH_MAX];
    /* simulation */
    double tick_rate;            /* Hz */
    char epoch[SRV_EPOCH_MAX];   /* sim t = 0: ISO 8601 UTC or Unix seconds; "" = start */
    char redis[SRV_BIND_MAX];    /* "host:port" of the replicated timeline; "" none */
    char redis_stream[SRV_REDIS_KEY_MAX]; /* its stream key */
    int cigi_port;               /* UDP port of the CIGI service; 0: off */
    char cigi_hosts[SRV_HOSTS_MAX]; /* addresses allowed to speak CIGI, comma separated */
    char geo_origin[SRV_BIND_MAX];  /* "LAT,LON" (WGS 84) at x = z = 0 */
    int max_entities;            /* entities the table holds at most (srv_entity.h) */
    int entity_track_keep;       /* samples a track keeps */
    char entity_log[SRV_PATH_MAX]; /* the entities' timeline file; "" off (srv_entlog.h) */
    double sea_lead;             /* replicated: least lead of a change's effective time, s */
    int workers;                 /* threads building frames */
    char scene[SRV_PATH_MAX];    /* scene name (in scene_dir) or path; "" none */
    char scene_dir[SRV_PATH_MAX];
    /* subscriptions */
    unsigned codecs;             /* bit c: codec c allowed */
    double max_frame_rate;       /* Hz */
    int max_tile_size;
    int max_lod_levels;
    int tiles_per_side;          /* tiles per level around the camera (n x n) */
    double base_spacing;         /* level-0 sample spacing when a client gives 0, m */
    double view_range;           /* mesh range when a client gives 0, m */
    double mesh_error_px;        /* concentric mesh screen error budget (layout 0) */
    double flat_mesh_error_px;   /* the same for layout 1's flat mesh */
    double px_per_sample;        /* layout 1: on-screen pixels one tile sample may span */
    double viewer_bytes_per_s;   /* layout 1: tile bytes a viewer may receive per second */
    int cascade_tile;            /* layout 1: tile side, samples (shared by every viewer) */
    int max_query_points;
    int max_pending_queries;     /* per client */
    int replay_queue;            /* pending replay cameras per client */
    int replay_per_tick;         /* replay frames built per client per tick */
    double query_ms;             /* query work per tick (all clients), ms */
    int max_mesh_vertices;       /* a mesh estimated above this is refused */
    double max_sample_rate;      /* tile samples per second one subscription may ask */
    double admit_share;          /* share of the usable cores admitted work may take; 0: off */
    /* near field */
    int near_field_waves;
    double near_field_radius;    /* fade to 0 at this radius, m */
    double near_field_min_wavelength; /* m */
    /* recording */
    int record;                  /* record every client */
    int record_clients;          /* clients may ask with ?record=1 */
    int record_max_files;        /* recordings opened per run */
    uint64_t record_max_bytes;   /* bytes written to recordings per run */
    char record_dir[SRV_PATH_MAX];
    int verbose;
} srv_config;

/* The server.* table (target: srv_config).  Static, never NULL. */
const conf_table *srv_config_table(void);

/* Everything a configuration file determines. */
typedef struct srv_settings {
    srv_config srv;
    ocean_params params;        /* daemon file + scene */
    ocean_scene scene;          /* scene.name "" when no scene is configured */
    unsigned effects;           /* effects the daemon may compute (scene's, or all) */
    char path[SRV_PATH_MAX];    /* file it came from ("" for built-in defaults) */
    /* sea.* and ocean.* keys the file changed from their defaults and the
     * scene replaced ("KEY = FILE (scene: SCENE), ..."; "" if none):
     * the scene wins over the file, so oceand says so at start and reload */
    char overridden[1024];
} srv_settings;

/* Built-in defaults (every table's defaults, no scene, all effects). */
ocean_result srv_settings_default(srv_settings *s, char *err, size_t errlen);

/* Loads path (NULL: defaults only), applies the `nsets` "key=value"
 * overrides in sets[], then the scene file server.scene names (a bare name
 * is looked up as scene_dir/NAME.conf), and validates.  On failure *out is
 * unchanged and err holds "file:line: message: 'text'". */
ocean_result srv_settings_load(const char *path, const char *const *sets, int nsets,
                               srv_settings *out, char *err, size_t errlen);

/* Parses a server.epoch value into Unix seconds (UTC): a decimal number of
 * Unix seconds ("1764000000", "1764000000.25") or an ISO 8601 UTC time
 * "YYYY-MM-DDTHH:MM:SS[.frac]" ending in Z or an offset +HH:MM / -HH:MM (a
 * space may stand for T).  Range: years 1970..9999.  OCEAN_EINVAL with why. */
ocean_result srv_epoch_parse(const char *text, double *unix_s, char *why, size_t whylen);

/* 1 when s serves a Gerstner near field (effect near-field, waves > 0, a
 * band above the FFT's k_max): layout 1 then carries it as one more
 * cascade, after the FFT cascades (PROTOCOL.md "Layouts"). */
int srv_settings_near_cascade(const srv_settings *s);
/* The Gerstner near field the daemon serves with settings s and sea/ocean
 * p (the sea in force: p->sea may differ from s->params.sea after a
 * SEA_STATE change): 1 and *gp filled when there is one, 0 otherwise.  The
 * one definition the daemon, its tests and benchmarks build the same set
 * from. */
int srv_settings_near_field(const srv_settings *s, const ocean_params *p, ocean_gerstner_params *gp);

/* Cascades a layout-1 subscription may receive: the FFT's plus the near
 * field's (HELLO max_layers). */
int srv_settings_layout1_cascades(const srv_settings *s);

/* Prints settings s - every sea.*, ocean.* and server.* key as a config
 * file, the scene's sea and ocean keys applied, with each key's help as
 * comments - that loads back to the same values.  OCEAN_EIO on a write
 * error. */
ocean_result srv_settings_dump(const srv_settings *s, FILE *f);

/* server.cigi_hosts: up to SRV_CIGI_HOSTS IPv4 or IPv6 literals, comma
 * separated, into out[] as IPv6 (IPv4 mapped); *n their count.
 * OCEAN_EINVAL with why. */
struct in6_addr;
ocean_result srv_config_hosts_parse(const char *text, struct in6_addr *out, int *n, char *why, size_t why_len);

#endif
