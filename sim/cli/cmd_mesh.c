/*
 * cmd_mesh.c - ocean-sim mesh: one LOD mesh for one camera, displaced by
 * the FFT ocean at --time, written as Wavefront OBJ (Blender, MeshLab),
 * with its size and its screen-space error against the ocean itself.
 *
 *   ocean-sim mesh --kind concentric|chunked|projected --camera X,Y,Z
 *       [--yaw D --pitch D --roll D --fov D --viewport WxH] [--range M]
 *       [--error-px P] [--margin M] [--obj FILE] [--json] [sea options]
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>

#include "cli.h"
#include "mesh.h"

/* oceand's default server.mesh_error_px (server/srv_config.c). */
#define MESH_CLI_ERROR_PX 16.0

/* The FFT ocean's displacement at a world point; reentrant (read only). */
static void frame_sampler(void *ctx, double x, double z, double d[3])
{
    ocean_point p;
    ocean_frame_sample((const ocean_frame *)ctx, x, z, &p);
    d[0] = p.dx;
    d[1] = p.height;
    d[2] = p.dz;
}

static int parse_triple(const char *s, double out[3])
{
    char *end;
    for (int i = 0; i < 3; i++) {
        out[i] = strtod(s, &end);
        if (end == s || !isfinite(out[i]))
            return -1;
        s = end;
        if (i < 2) {
            if (*s != ',')
                return -1;
            s++;
        }
    }
    return *s ? -1 : 0;
}

static int parse_viewport(const char *s, int *w, int *h)
{
    char *end;
    long a = strtol(s, &end, 10);
    if (end == s || (*end != 'x' && *end != 'X'))
        return -1;
    const char *t = end + 1;
    long b = strtol(t, &end, 10);
    if (end == t || *end || a < 1 || b < 1 || a > 65536 || b > 65536)
        return -1;
    *w = (int)a;
    *h = (int)b;
    return 0;
}

/* What the command line sets beyond the common options. */
typedef struct mesh_args {
    const char *kind_s, *camera_s, *viewport_s, *obj;
    double yaw, pitch, roll, fov, range, err_px, margin, max_vertices;
    char viewport_def[32];
} mesh_args;

/* Defaults from the library's camera and mesh configuration, except the
 * error budget: the library's 1 px builds 1.6 M vertices over 90 km
 * (135 MB of OBJ); oceand serves 16 px (server.mesh_error_px), so the
 * tool shows by default what a viewer of the daemon gets. */
static void mesh_args_default(mesh_args *a)
{
    mesh_config dcfg;
    mesh_config_default(&dcfg);
    mesh_camera dcam;
    mesh_camera_default(&dcam);
    snprintf(a->viewport_def, sizeof a->viewport_def, "%dx%d", dcam.viewport_w, dcam.viewport_h);
    a->kind_s = mesh_kind_name(dcfg.kind);
    a->camera_s = NULL;
    a->viewport_s = a->viewport_def;
    a->obj = NULL;
    a->yaw = dcam.yaw_deg;
    a->pitch = -10;
    a->roll = dcam.roll_deg;
    a->fov = dcam.fov_y_deg;
    a->range = dcfg.range_m;
    a->err_px = MESH_CLI_ERROR_PX;
    a->margin = NAN;
    a->max_vertices = 4e6;
}

/* Returns cli_parse's 0, 1 (help printed) or 2 (error printed). */
static int mesh_args_parse(int argc, char **argv, mesh_args *a, cli_common *c)
{
    mesh_args_default(a);
    const cli_opt opts[] = {
        {"kind", CLI_STRING, &a->kind_s, 0, 0, "K     concentric | chunked | projected", NULL},
        {"camera", CLI_STRING, &a->camera_s, 0, 0, "X,Y,Z camera world position, m (Y above the sea; required)", NULL},
        {"yaw", CLI_DOUBLE, &a->yaw, -1e6, 1e6, "D     heading, degrees from +x toward +z", NULL},
        {"pitch", CLI_DOUBLE, &a->pitch, -90, 90, "D     degrees, positive up", NULL},
        {"roll", CLI_DOUBLE, &a->roll, -1e6, 1e6, "D     degrees", NULL},
        {"fov", CLI_DOUBLE, &a->fov, 0.01, 170, "D     vertical field of view, degrees", NULL},
        {"viewport", CLI_STRING, &a->viewport_s, 0, 0, "WxH   viewport, pixels", NULL},
        {"range", CLI_DOUBLE, &a->range, 10, 1e6, "M     radius the mesh covers, m", NULL},
        {"error-px", CLI_DOUBLE, &a->err_px, 0.01, 100, "P     concentric error budget, px (1 is film quality: ~1.6 M vertices)", NULL},
        {"margin", CLI_DOUBLE, &a->margin, 0, 1000,
         "M     projected grid displacement margin, m (not given: 1.2 Hs (1 + choppiness))", NULL},
        {"obj", CLI_STRING, &a->obj, 0, 0, "FILE  write the displaced mesh as Wavefront OBJ", NULL},
        {"max-vertices", CLI_DOUBLE, &a->max_vertices, 1e3, 1e9,
         "V     refuse a mesh whose vertex count, priced before building, exceeds V", NULL},
    };
    return cli_parse(argc, argv,
                     "mesh --camera X,Y,Z [--kind concentric|chunked|projected] [--yaw D "
                     "--pitch D --fov D --viewport WxH] [--range M] [--obj FILE] [--json]",
                     opts, (int)(sizeof opts / sizeof opts[0]), c, NULL, NULL);
}

/* Returns 0, or 2 with the reason printed. */
static int mesh_args_camera(const mesh_args *a, mesh_camera *cam)
{
    mesh_camera_default(cam);
    if (!a->camera_s) {
        fprintf(stderr, "error: --camera X,Y,Z is required (see mesh --help)\n");
        return 2;
    }
    if (parse_triple(a->camera_s, cam->pos)) {
        fprintf(stderr, "error: --camera: '%s' is not three finite numbers X,Y,Z\n", a->camera_s);
        return 2;
    }
    if (parse_viewport(a->viewport_s, &cam->viewport_w, &cam->viewport_h)) {
        fprintf(stderr, "error: --viewport: '%s' is not WxH in pixels (1..65536)\n", a->viewport_s);
        return 2;
    }
    cam->yaw_deg = a->yaw;
    cam->pitch_deg = a->pitch;
    cam->roll_deg = a->roll;
    cam->fov_y_deg = a->fov;
    char msg[256];
    if (mesh_camera_validate(cam, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "error: %s\n", msg);
        return 2;
    }
    return 0;
}

/* The mesh configuration for the sea: its dominant wavelength, roughness
 * and (unless --margin) a margin its waves stay within.  Returns 0, or 2
 * with the reason printed. */
static int mesh_args_config(const mesh_args *a, const ocean_sea_state *sea, mesh_config *cfg)
{
    mesh_lambda_dominant(sea, &cfg->lambda_dominant_m);
    cfg->roughness = mesh_roughness(sea);
    cfg->range_m = a->range;
    cfg->error_px = a->err_px;
    double hs = ocean_spectrum_hs(sea);
    cfg->margin_m = !isnan(a->margin) ? a->margin
                                      : fmin(1000, fmax(0.5, 1.2 * hs * (1 + sea->choppiness)));
    char msg[256];
    if (mesh_config_validate(cfg, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "error: %s\n", msg);
        return 2;
    }
    return 0;
}

/* Priced from the plan before anything is built, as oceand does
 * (server.max_mesh_vertices): a 0.01-degree camera would otherwise ask for
 * gigabytes and minutes.  Returns 0, or 2 with the reason printed. */
static int mesh_check_size(const mesh_config *cfg, const mesh_camera *cam, double max_vertices)
{
    double est = 0;
    if (mesh_estimate_vertices(cfg, cam, &est) == OCEAN_OK && est > max_vertices) {
        fprintf(stderr, "error: this mesh would have up to %.3g vertices, more than --max-vertices "
                "%.3g: raise --error-px or --fov, lower --range or the viewport, or raise "
                "--max-vertices\n", est, max_vertices);
        return 2;
    }
    return 0;
}

/* Returns 0, or 1 with the reason printed. */
static int mesh_write_obj_file(const mesh *m, const char *obj)
{
    FILE *fo = strcmp(obj, "-") == 0 ? stdout : fopen(obj, "w");
    if (!fo) {
        fprintf(stderr, "error: --obj: cannot write '%s'\n", obj);
        return 1;
    }
    ocean_result r = mesh_write_obj(m, fo);
    if (fo != stdout && fclose(fo) != 0)
        r = OCEAN_EIO;
    if (r != OCEAN_OK) {
        fprintf(stderr, "error: --obj: writing '%s' failed\n", obj);
        return 1;
    }
    return 0;
}

static void mesh_print(const mesh *m, const mesh_config *cfg, double err, const char *obj, int json)
{
    mesh_view v;
    mesh_info in;
    mesh_get_view(m, &v);
    mesh_get_info(m, &in);
    char key[24];
    snprintf(key, sizeof key, "%016llx", (unsigned long long)v.topology_key);
    if (!json) {
        printf("%s mesh: %u vertices, %u triangles, %d levels, near spacing %g m, "
               "max error %.3f px, built in %.1f ms%s%s\n",
               mesh_kind_name(cfg->kind), v.vertex_count, v.index_count / 3, v.levels,
               in.near_spacing_m, err, in.build_ms, obj ? ", written to " : "", obj ? obj : "");
        return;
    }
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "kind", mesh_kind_name(cfg->kind));
    cJSON_AddNumberToObject(j, "vertices", v.vertex_count);
    cJSON_AddNumberToObject(j, "triangles", v.index_count / 3);
    cJSON_AddNumberToObject(j, "levels", v.levels);
    cJSON_AddNumberToObject(j, "max_error_px", err);
    cJSON_AddNumberToObject(j, "near_spacing_m", in.near_spacing_m);
    cJSON_AddNumberToObject(j, "range_m", cfg->range_m);
    cJSON_AddNumberToObject(j, "lambda_dominant_m", cfg->lambda_dominant_m);
    cJSON_AddNumberToObject(j, "build_ms", in.build_ms);
    cJSON_AddStringToObject(j, "topology_key", key);
    cJSON *org = cJSON_AddArrayToObject(j, "origin");
    for (int k = 0; k < 3; k++)
        cJSON_AddItemToArray(org, cJSON_CreateNumber(v.origin[k]));
    if (obj)
        cJSON_AddStringToObject(j, "obj", obj);
    cli_print_json(j);
}

/* Builds the mesh for cam on the sea evaluated at --time, displaced by it,
 * and measures its screen-space error against it.  Returns 0, or 1 with
 * the reason printed. */
static int mesh_make(const cli_common *c, const mesh_config *cfg, const mesh_camera *cam,
                     const char *obj)
{
    ocean *o;
    ocean_frame *f;
    mesh *m = NULL;
    int status = 1;
    if (cli_make_ocean(c, &o, &f))
        return 1;
    ocean_request req;
    ocean_request_all(&req, OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT);
    double t = isfinite(c->time) ? c->time : 0;
    int r;
    if ((r = ocean_evaluate(o, t, &req, f)) != OCEAN_OK) {
        fprintf(stderr, "error: evaluation failed: %s\n", ocean_strerror(r));
        goto out;
    }
    if ((r = mesh_create(cfg, &m)) != OCEAN_OK || (r = mesh_build(m, cam)) != OCEAN_OK ||
        (r = mesh_displace(m, frame_sampler, f)) != OCEAN_OK) {
        fprintf(stderr, "error: mesh: %s\n", ocean_strerror(r));
        goto out;
    }
    double err = 0;
    if ((r = mesh_error_px(m, cam, frame_sampler, f, &err)) != OCEAN_OK) {
        fprintf(stderr, "error: mesh error: %s\n", ocean_strerror(r));
        goto out;
    }
    if (obj && mesh_write_obj_file(m, obj))
        goto out;
    mesh_print(m, cfg, err, obj, c->json);
    status = 0;
out:
    mesh_destroy(m);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return status;
}

int cmd_mesh(int argc, char **argv)
{
    mesh_args a;
    cli_common c;
    int r = mesh_args_parse(argc, argv, &a, &c);
    if (r)
        return r == 1 ? 0 : 2;
    mesh_config cfg;
    mesh_config_default(&cfg);
    if (mesh_kind_parse(a.kind_s, &cfg.kind) != OCEAN_OK) {
        fprintf(stderr, "error: --kind: '%s' is not concentric, chunked or projected\n", a.kind_s);
        return 2;
    }
    mesh_camera cam;
    if (mesh_args_camera(&a, &cam) || mesh_args_config(&a, &c.params.sea, &cfg) ||
        mesh_check_size(&cfg, &cam, a.max_vertices))
        return 2;
    return mesh_make(&c, &cfg, &cam, a.obj);
}
