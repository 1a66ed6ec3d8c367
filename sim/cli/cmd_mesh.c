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

int cmd_mesh(int argc, char **argv)
{
    /* Defaults from the library's camera and mesh configuration, except the
     * error budget: the library's 1 px builds 1.6 M vertices over 90 km
     * (135 MB of OBJ); oceand serves 16 px (server.mesh_error_px), so the
     * tool shows by default what a viewer of the daemon gets. */
    mesh_config dcfg;
    mesh_config_default(&dcfg);
    mesh_camera dcam;
    mesh_camera_default(&dcam);
    char viewport_def[32];
    snprintf(viewport_def, sizeof viewport_def, "%dx%d", dcam.viewport_w, dcam.viewport_h);
    const char *kind_s = mesh_kind_name(dcfg.kind), *camera_s = NULL, *viewport_s = viewport_def, *obj = NULL;
    double yaw = dcam.yaw_deg, pitch = -10, roll = dcam.roll_deg, fov = dcam.fov_y_deg, range = dcfg.range_m;
    double err_px = MESH_CLI_ERROR_PX, margin = NAN, max_vertices = 4e6;
    const cli_opt opts[] = {
        {"kind", CLI_STRING, &kind_s, 0, 0, "K     concentric | chunked | projected", NULL},
        {"camera", CLI_STRING, &camera_s, 0, 0, "X,Y,Z camera world position, m (Y above the sea; required)", NULL},
        {"yaw", CLI_DOUBLE, &yaw, -1e6, 1e6, "D     heading, degrees from +x toward +z", NULL},
        {"pitch", CLI_DOUBLE, &pitch, -90, 90, "D     degrees, positive up", NULL},
        {"roll", CLI_DOUBLE, &roll, -1e6, 1e6, "D     degrees", NULL},
        {"fov", CLI_DOUBLE, &fov, 0.01, 170, "D     vertical field of view, degrees", NULL},
        {"viewport", CLI_STRING, &viewport_s, 0, 0, "WxH   viewport, pixels", NULL},
        {"range", CLI_DOUBLE, &range, 10, 1e6, "M     radius the mesh covers, m", NULL},
        {"error-px", CLI_DOUBLE, &err_px, 0.01, 100, "P     concentric error budget, px (1 is film quality: ~1.6 M vertices)", NULL},
        {"margin", CLI_DOUBLE, &margin, 0, 1000,
         "M     projected grid displacement margin, m (not given: 1.2 Hs (1 + choppiness))", NULL},
        {"obj", CLI_STRING, &obj, 0, 0, "FILE  write the displaced mesh as Wavefront OBJ", NULL},
        {"max-vertices", CLI_DOUBLE, &max_vertices, 1e3, 1e9,
         "V     refuse a mesh whose vertex count, priced before building, exceeds V", NULL},
    };
    cli_common c;
    int r = cli_parse(argc, argv,
                      "mesh --camera X,Y,Z [--kind concentric|chunked|projected] [--yaw D "
                      "--pitch D --fov D --viewport WxH] [--range M] [--obj FILE] [--json]",
                      opts, (int)(sizeof opts / sizeof opts[0]), &c, NULL, NULL);
    if (r)
        return r == 1 ? 0 : 2;

    mesh_config cfg;
    mesh_config_default(&cfg);
    if (mesh_kind_parse(kind_s, &cfg.kind) != OCEAN_OK) {
        fprintf(stderr, "error: --kind: '%s' is not concentric, chunked or projected\n", kind_s);
        return 2;
    }
    mesh_camera cam;
    mesh_camera_default(&cam);
    if (!camera_s) {
        fprintf(stderr, "error: --camera X,Y,Z is required (see mesh --help)\n");
        return 2;
    }
    if (parse_triple(camera_s, cam.pos)) {
        fprintf(stderr, "error: --camera: '%s' is not three finite numbers X,Y,Z\n", camera_s);
        return 2;
    }
    if (parse_viewport(viewport_s, &cam.viewport_w, &cam.viewport_h)) {
        fprintf(stderr, "error: --viewport: '%s' is not WxH in pixels (1..65536)\n", viewport_s);
        return 2;
    }
    cam.yaw_deg = yaw;
    cam.pitch_deg = pitch;
    cam.roll_deg = roll;
    cam.fov_y_deg = fov;
    char msg[256];
    if (mesh_camera_validate(&cam, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "error: %s\n", msg);
        return 2;
    }
    const ocean_sea_state *sea = &c.params.sea;
    mesh_lambda_dominant(sea, &cfg.lambda_dominant_m);
    cfg.roughness = mesh_roughness(sea);
    cfg.range_m = range;
    cfg.error_px = err_px;
    double hs = ocean_spectrum_hs(sea);
    cfg.margin_m = !isnan(margin) ? margin
                                  : fmin(1000, fmax(0.5, 1.2 * hs * (1 + sea->choppiness)));
    if (mesh_config_validate(&cfg, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "error: %s\n", msg);
        return 2;
    }

    /* Priced from the plan before anything is built, as oceand does
     * (server.max_mesh_vertices): a 0.01-degree camera would otherwise ask
     * for gigabytes and minutes. */
    double est = 0;
    if (mesh_estimate_vertices(&cfg, &cam, &est) == OCEAN_OK && est > max_vertices) {
        fprintf(stderr, "error: this mesh would have up to %.3g vertices, more than --max-vertices "
                "%.3g: raise --error-px or --fov, lower --range or the viewport, or raise "
                "--max-vertices\n", est, max_vertices);
        return 2;
    }
    ocean *o;
    ocean_frame *f;
    mesh *m = NULL;
    int status = 1;
    if (cli_make_ocean(&c, &o, &f))
        return 1;
    ocean_request req;
    ocean_request_all(&req, OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT);
    double t = isfinite(c.time) ? c.time : 0;
    if ((r = ocean_evaluate(o, t, &req, f)) != OCEAN_OK) {
        fprintf(stderr, "error: evaluation failed: %s\n", ocean_strerror(r));
        goto out;
    }
    if ((r = mesh_create(&cfg, &m)) != OCEAN_OK || (r = mesh_build(m, &cam)) != OCEAN_OK ||
        (r = mesh_displace(m, frame_sampler, f)) != OCEAN_OK) {
        fprintf(stderr, "error: mesh: %s\n", ocean_strerror(r));
        goto out;
    }
    double err = 0;
    if ((r = mesh_error_px(m, &cam, frame_sampler, f, &err)) != OCEAN_OK) {
        fprintf(stderr, "error: mesh error: %s\n", ocean_strerror(r));
        goto out;
    }
    if (obj) {
        FILE *fo = strcmp(obj, "-") == 0 ? stdout : fopen(obj, "w");
        if (!fo) {
            fprintf(stderr, "error: --obj: cannot write '%s'\n", obj);
            goto out;
        }
        r = mesh_write_obj(m, fo);
        if (fo != stdout && fclose(fo) != 0)
            r = OCEAN_EIO;
        if (r != OCEAN_OK) {
            fprintf(stderr, "error: --obj: writing '%s' failed\n", obj);
            goto out;
        }
    }
    mesh_view v;
    mesh_info in;
    mesh_get_view(m, &v);
    mesh_get_info(m, &in);
    char key[24];
    snprintf(key, sizeof key, "%016llx", (unsigned long long)v.topology_key);
    if (c.json) {
        cJSON *j = cJSON_CreateObject();
        cJSON_AddStringToObject(j, "kind", mesh_kind_name(cfg.kind));
        cJSON_AddNumberToObject(j, "vertices", v.vertex_count);
        cJSON_AddNumberToObject(j, "triangles", v.index_count / 3);
        cJSON_AddNumberToObject(j, "levels", v.levels);
        cJSON_AddNumberToObject(j, "max_error_px", err);
        cJSON_AddNumberToObject(j, "near_spacing_m", in.near_spacing_m);
        cJSON_AddNumberToObject(j, "range_m", cfg.range_m);
        cJSON_AddNumberToObject(j, "lambda_dominant_m", cfg.lambda_dominant_m);
        cJSON_AddNumberToObject(j, "build_ms", in.build_ms);
        cJSON_AddStringToObject(j, "topology_key", key);
        cJSON *org = cJSON_AddArrayToObject(j, "origin");
        for (int k = 0; k < 3; k++)
            cJSON_AddItemToArray(org, cJSON_CreateNumber(v.origin[k]));
        if (obj)
            cJSON_AddStringToObject(j, "obj", obj);
        cli_print_json(j);
    } else {
        printf("%s mesh: %u vertices, %u triangles, %d levels, near spacing %g m, "
               "max error %.3f px, built in %.1f ms%s%s\n",
               mesh_kind_name(cfg.kind), v.vertex_count, v.index_count / 3, v.levels,
               in.near_spacing_m, err, in.build_ms, obj ? ", written to " : "", obj ? obj : "");
    }
    status = 0;
out:
    mesh_destroy(m);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return status;
}
