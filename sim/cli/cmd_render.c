/*
 * cmd_render.c - `ocean-sim render`: the reference image of the exact sea
 * of a scene from one camera at one instant (render.h), as PNG, to judge
 * the viewer's screenshot of the same view (its ?t=T&x=..&yaw=..&fov=..).
 * Threads: the main thread; render_image runs --threads workers of its own.
 */
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cJSON.h>

#include "cli.h"
#include "ocean_conf.h"
#include "render.h"

typedef struct render_args {
    const char *scene, *scene_dir, *pos, *size, *out, *sun;
    double yaw, pitch, fov;
    int supersample, threads, nf_waves;
    double nf_min_wavelength;
    render_view view;
} render_args;

/* "X,Y,Z" and "WxH" into the view.  0, or 2 with the reason printed. */
static int render_args_view(render_args *a)
{
    char end;
    render_view *v = &a->view;
    if (sscanf(a->pos, "%lf,%lf,%lf%c", &v->eye[0], &v->eye[1], &v->eye[2], &end) != 3 || !isfinite(v->eye[0]) ||
        !isfinite(v->eye[1]) || !isfinite(v->eye[2])) {
        fprintf(stderr, "error: --pos '%s' is not three finite numbers X,Y,Z\n", a->pos);
        return 2;
    }
    if (sscanf(a->size, "%dx%d%c", &v->width, &v->height, &end) != 2 || v->width < 1 || v->width > 8192 ||
        v->height < 1 || v->height > 8192) {
        fprintf(stderr, "error: --size '%s' is not WxH with each 1..8192\n", a->size);
        return 2;
    }
    if (a->sun) {
        if (sscanf(a->sun, "%lf,%lf%c", &v->sun_deg[0], &v->sun_deg[1], &end) != 2 || !isfinite(v->sun_deg[0]) ||
            !(fabs(v->sun_deg[1]) <= 90)) {
            fprintf(stderr, "error: --sun '%s' is not AZ,EL in degrees (elevation within +-90)\n", a->sun);
            return 2;
        }
        v->sun_given = 1;
    }
    v->yaw_deg = a->yaw;
    v->pitch_deg = a->pitch;
    v->fov_deg = a->fov;
    v->supersample = a->supersample;
    v->threads = a->threads;
    return 0;
}

static int render_args_parse(int argc, char **argv, render_args *a, cli_common *c)
{
    *a = (render_args){.scene_dir = "config/scenes", .pos = "0,25,0", .size = "640x360", .yaw = 0, .pitch = -5,
                       .fov = 60, .supersample = 3, .threads = 2, .nf_waves = 64, .nf_min_wavelength = 0.1};
    const cli_opt opts[] = {
        {"scene", CLI_STRING, &a->scene, 0, 0,
         "NAME  a scene of --scene-dir (or a .conf path) on top of the sea options: its sea and effects", NULL},
        {"scene-dir", CLI_STRING, &a->scene_dir, 0, 0, "DIR   where scene names are looked up", NULL},
        {"pos", CLI_STRING, &a->pos, 0, 0, "X,Y,Z camera position, m (y up)", NULL},
        {"yaw", CLI_DOUBLE, &a->yaw, -1e6, 1e6, "DEG   heading from +x toward +z (the viewer's yaw)", NULL},
        {"pitch", CLI_DOUBLE, &a->pitch, -90, 90, "DEG   pitch, up positive", NULL},
        {"fov", CLI_DOUBLE, &a->fov, 0.01, 179, "DEG   vertical field of view", NULL},
        {"size", CLI_STRING, &a->size, 0, 0, "WxH   image size, pixels", NULL},
        {"supersample", CLI_INT, &a->supersample, 1, 8, "N     N x N samples a pixel", NULL},
        {"threads", CLI_INT, &a->threads, 1, 64, "N     render threads", NULL},
        {"near-field-waves", CLI_INT, &a->nf_waves, 0, 1024,
         "M     Gerstner waves of a near-field scene (oceand's server.near_field_waves)", NULL},
        {"near-field-min-wavelength", CLI_DOUBLE, &a->nf_min_wavelength, 0.0151, 100,
         "M     shortest near-field wave, m (oceand's server.near_field_min_wavelength)", NULL},
        {"sun", CLI_STRING, &a->sun, 0, 0,
         "AZ,EL the sun's azimuth (from +x toward +z) and elevation, deg, as the viewer's sun=AZ,EL "
         "(not given: the viewer's default for the wind)", NULL},
        {"out", CLI_STRING, &a->out, 0, 0, "FILE  the PNG to write (required)", NULL},
    };
    int r = cli_parse(argc, argv,
                      "render [--config config/oceand.conf] --scene NAME --pos X,Y,Z --yaw DEG --pitch DEG --fov DEG "
                      "--size WxH --time T --out FILE.png [--json]",
                      opts, (int)(sizeof opts / sizeof opts[0]), c, NULL, NULL);
    if (r) return r;
    if (!a->out) {
        fprintf(stderr, "error: render needs --out FILE.png\n");
        return 2;
    }
    return render_args_view(a);
}

/* The scene's sea and effects on top of c's parameters.  0 or 2. */
static int render_scene(const render_args *a, cli_common *c, unsigned *effects)
{
    *effects = c->effects;
    if (!a->scene) return 0;
    char path[1024];
    ocean_conf_scene_path(a->scene_dir, a->scene, path, sizeof path);
    ocean_scene sc;
    char err[512];
    if (ocean_conf_scene_load(path, &c->params, &sc, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "error: scene: %s\n", err);
        return 2;
    }
    c->params = sc.params;
    *effects = sc.effects;
    return 0;
}

static int png_write(const char *path, const float *rgb, int w, int h)
{
    FILE *fp = fopen(path, "wb");
    if (!fp) {
        perror(path);
        return 1;
    }
    png_image img = {.version = PNG_IMAGE_VERSION, .width = (png_uint_32)w, .height = (png_uint_32)h,
                     .format = PNG_FORMAT_RGB};
    unsigned char *px = malloc((size_t)w * h * 3);
    int ok = px != NULL;
    for (size_t i = 0; ok && i < (size_t)w * h * 3; i++) px[i] = (unsigned char)lrint(fmin(fmax(rgb[i], 0.0), 1.0) * 255);
    ok = ok && png_image_write_to_stdio(&img, fp, 0, px, 0, NULL);
    free(px);
    if (fclose(fp) != 0 || !ok) {
        fprintf(stderr, "error: writing %s failed%s%s\n", path, img.message[0] ? ": " : "", img.message);
        return 1;
    }
    return 0;
}

static void render_print_json(const render_args *a, const render_stats *st, double ms_sea, int levels)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddStringToObject(j, "out", a->out);
    cJSON_AddNumberToObject(j, "width", a->view.width);
    cJSON_AddNumberToObject(j, "height", a->view.height);
    cJSON_AddNumberToObject(j, "supersample", a->view.supersample);
    cJSON_AddNumberToObject(j, "sea_ms", ms_sea);
    cJSON_AddNumberToObject(j, "render_ms", st->ms);
    cJSON_AddNumberToObject(j, "levels", levels);
    cJSON_AddNumberToObject(j, "rays", (double)st->rays);
    cJSON_AddNumberToObject(j, "sea_rays", (double)st->sea_rays);
    cJSON_AddNumberToObject(j, "evaluations", (double)st->evaluations);
    cJSON_AddNumberToObject(j, "max_height_error_m", st->max_height_error);
    cli_print_json(j);
}

int cmd_render(int argc, char **argv)
{
    render_args a;
    cli_common c;
    unsigned effects;
    int r = render_args_parse(argc, argv, &a, &c);
    if (r) return r == 1 ? 0 : 2;
    if ((r = render_scene(&a, &c, &effects))) return r;
    ocean_gerstner_params gp;
    int near = 0;
    if (effects & OCEAN_FX_NEAR_FIELD) {
        ocean_gerstner_near_cut(&c.params, a.nf_waves);
        near = ocean_gerstner_near_params(&c.params, a.nf_waves, a.nf_min_wavelength, &gp);
    }
    char msg[512] = "";
    render_sea *sea;
    double t0 = cli_now_ms();
    ocean_result or = render_sea_create(&c.params, near ? &gp : NULL, effects, c.time, a.threads, &sea, msg, sizeof msg);
    if (or != OCEAN_OK) {
        fprintf(stderr, "error: the sea: %s%s%s\n", ocean_strerror(or), msg[0] ? ": " : "", msg);
        return 1;
    }
    double ms_sea = cli_now_ms() - t0;
    float *rgb = malloc(sizeof(float) * 3 * (size_t)a.view.width * (size_t)a.view.height);
    render_stats st;
    if (!rgb) {
        fprintf(stderr, "error: out of memory for a %dx%d image\n", a.view.width, a.view.height);
        r = 1;
    } else if ((or = render_image(sea, &a.view, rgb, NULL, &st, msg, sizeof msg)) != OCEAN_OK) {
        fprintf(stderr, "error: %s: %s\n", ocean_strerror(or), msg);
        r = 2;
    } else if (!(r = png_write(a.out, rgb, a.view.width, a.view.height)) && c.json) {
        render_print_json(&a, &st, ms_sea, render_sea_levels(sea));
    }
    free(rgb);
    render_sea_destroy(sea);
    return r;
}
