/*
 * cmd_bake.c - `ocean-sim bake`: OpenEXR image sequences of each cascade's
 * displacement, unit normals and foam, written with OpenEXRCore,
 * ZIP-compressed 32-bit float.
 *
 * Files: DIR/displacement_cC_FFFF.exr, DIR/normal_cC_FFFF.exr,
 *        DIR/foam_cC_FFFF.exr (C = cascade, FFFF = frame).
 *
 * Channels are named layers, the "layer.channel" convention of the OpenEXR
 * multi-view/multi-layer documents that Nuke, Houdini and Blender read as a
 * layer with red/green/blue:
 *   displacement.R, .G, .B = Dx, height, Dz  (metres; y-up vector
 *                                              displacement, R,G,B = x,y,z)
 *   normal.R, .G, .B       = nx, ny, nz      (unit normal, y up)
 *   foam.Y                 = foam coverage 0..1
 * Every file's header says what it holds (so a tool needs no side file):
 * framesPerSecond (the standard rational), and oceand.* attributes for the
 * frame, time, cascade, patch size, grid, sample spacing, the sea state
 * (spectrum, spreading, wind, fetch, depth, swell, choppiness, seed, Hs) and
 * the channel mapping in words.
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openexr.h>

#include "cli.h"

typedef struct exr_plane {
    const char *name;   /* EXR channel name */
    const float *data;  /* n x n, row-major */
} exr_plane;

/* What a baked file's header says about it. */
typedef struct bake_meta {
    const ocean_params *params;
    double fps, time, patch_m, hs;
    int frame, cascade;
    const char *channels;   /* the mapping in words */
} bake_meta;

/* Nearest rational num/den to fps with den <= 1001 (30000/1001 for NTSC). */
static exr_attr_rational_t fps_rational(double fps)
{
    exr_attr_rational_t best = {(int32_t)lround(fps), 1};
    double err = fabs(fps - best.num);
    for (uint32_t den = 2; den <= 1001 && err > 1e-9; den++) {
        double num = round(fps * den);
        if (num > 2147483647.0)
            break;
        double e = fabs(fps - num / den);
        if (e < err - 1e-12) {
            err = e;
            best.num = (int32_t)num;
            best.denom = den;
        }
    }
    return best;
}

/* The header attributes of one baked file (before exr_write_header). */
static exr_result_t write_meta(exr_context_t ctx, int part, int n, const bake_meta *m)
{
    const ocean_sea_state *sea = &m->params->sea;
    char seed[32];
    snprintf(seed, sizeof seed, "%llu", (unsigned long long)m->params->seed);
    exr_attr_rational_t fr = fps_rational(m->fps);
    exr_result_t rv = exr_attr_set_rational(ctx, part, "framesPerSecond", &fr);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_int(ctx, part, "oceand.frame", m->frame);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_double(ctx, part, "oceand.time", m->time);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_int(ctx, part, "oceand.cascade", m->cascade);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_double(ctx, part, "oceand.patchSize", m->patch_m);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_int(ctx, part, "oceand.gridSize", n);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_double(ctx, part, "oceand.sampleSpacing", m->patch_m / n);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_string(ctx, part, "oceand.spectrum", ocean_spectrum_name(sea->spectrum));
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_string(ctx, part, "oceand.spreading", ocean_spreading_name(sea->spreading));
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_double(ctx, part, "oceand.windSpeed", sea->wind_u10);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_double(ctx, part, "oceand.windDirection", sea->wind_dir_deg);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_double(ctx, part, "oceand.fetch", sea->fetch_m);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_double(ctx, part, "oceand.depth", sea->depth_m);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_double(ctx, part, "oceand.swell", sea->swell);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_double(ctx, part, "oceand.choppiness", sea->choppiness);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_string(ctx, part, "oceand.seed", seed);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_double(ctx, part, "oceand.significantWaveHeight", m->hs);
    if (rv == EXR_ERR_SUCCESS) rv = exr_attr_set_string(ctx, part, "oceand.channels", m->channels);
    return rv;
}

/* Writes planes (any order; OpenEXR stores channels sorted by name) as a
 * scanline ZIP file.  Returns 0 or prints the reason and returns -1. */
static int write_exr(const char *path, int n, const exr_plane *planes, int np, const bake_meta *meta)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctx = NULL;
    int part = 0;
    exr_result_t rv = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_add_part(ctx, "ocean", EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_initialize_required_attr_simple(ctx, part, n, n, EXR_COMPRESSION_ZIP);
    if (rv == EXR_ERR_SUCCESS)
        rv = write_meta(ctx, part, n, meta);
    for (int i = 0; i < np && rv == EXR_ERR_SUCCESS; i++)
        rv = exr_add_channel(ctx, part, planes[i].name, EXR_PIXEL_FLOAT,
                             EXR_PERCEPTUALLY_LINEAR, 1, 1);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_write_header(ctx);
    int32_t lines = 1;
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_get_scanlines_per_chunk(ctx, part, &lines);
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    int have_enc = 0;
    for (int y = 0; y < n && rv == EXR_ERR_SUCCESS; y += lines) {
        exr_chunk_info_t ci;
        rv = exr_write_scanline_chunk_info(ctx, part, y, &ci);
        if (rv != EXR_ERR_SUCCESS)
            break;
        rv = have_enc ? exr_encoding_update(ctx, part, &ci, &enc)
                      : exr_encoding_initialize(ctx, part, &ci, &enc);
        if (rv != EXR_ERR_SUCCESS)
            break;
        for (int k = 0; k < enc.channel_count; k++) {
            exr_coding_channel_info_t *ch = &enc.channels[k];
            const float *src = NULL;
            for (int i = 0; i < np; i++)
                if (strcmp(ch->channel_name, planes[i].name) == 0)
                    src = planes[i].data;
            if (!src) {
                /* the header was written from planes[]: a channel it
                 * does not name means the library renamed it */
                rv = EXR_ERR_INVALID_ARGUMENT;
                break;
            }
            ch->encode_from_ptr = (const uint8_t *)(src + (size_t)y * n);
            ch->user_pixel_stride = sizeof(float);
            ch->user_line_stride = (int32_t)(sizeof(float) * n);
            ch->user_bytes_per_element = sizeof(float);
            ch->user_data_type = EXR_PIXEL_FLOAT;
        }
        if (rv != EXR_ERR_SUCCESS)
            break;
        if (!have_enc) {
            rv = exr_encoding_choose_default_routines(ctx, part, &enc);
            have_enc = 1;
        }
        if (rv == EXR_ERR_SUCCESS)
            rv = exr_encoding_run(ctx, part, &enc);
    }
    if (have_enc)
        exr_encoding_destroy(ctx, &enc);
    exr_result_t frv = ctx ? exr_finish(&ctx) : EXR_ERR_SUCCESS;
    if (rv == EXR_ERR_SUCCESS)
        rv = frv;
    if (rv != EXR_ERR_SUCCESS) {
        fprintf(stderr, "error: writing %s: %s\n", path, exr_get_default_error_message(rv));
        return -1;
    }
    return 0;
}

static void progress(int done, int total)
{
    int width = 40, fill = total ? done * width / total : width;
    fprintf(stderr, "\r[%.*s%*s] %d/%d frames", fill, "########################################",
            width - fill, "", done, total);
    if (done == total)
        fputc('\n', stderr);
}

/* Unit normals (nx, ny, nz planes of nn samples each) from the field's
 * slopes: n = normalise(-sx, 1, -sz). */
static void normals_from_slopes(const ocean_field *fd, float *nrm)
{
    size_t nn = (size_t)fd->n * fd->n;
    for (size_t k = 0; k < nn; k++) {
        double sx = fd->slope_x[k], sz = fd->slope_z[k];
        double len = sqrt(sx * sx + 1.0 + sz * sz);
        nrm[k] = (float)(-sx / len);
        nrm[nn + k] = (float)(1.0 / len);
        nrm[2 * nn + k] = (float)(-sz / len);
    }
}

/* Writes the files of one cascade of one frame, those of the effects fx:
 * 0, or 1 (said).  nrm holds 3 n x n planes; zero is an n x n plane of 0
 * for a displacement component not computed. */
static int bake_cascade(const char *out, unsigned fx, const ocean_field *fd, bake_meta *meta, float *nrm,
                        const float *zero)
{
    char path[4096];
    int m = fd->n, status = 0, cs = meta->cascade, i = meta->frame;
    if (fx & (OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT)) {
        exr_plane p[3] = {{"displacement.R", fd->dx ? fd->dx : zero},
                          {"displacement.G", fd->height ? fd->height : zero},
                          {"displacement.B", fd->dz ? fd->dz : zero}};
        meta->channels = "displacement.R = Dx, displacement.G = height, displacement.B = Dz "
                         "(metres, y up; R,G,B = x,y,z)";
        snprintf(path, sizeof path, "%s/displacement_c%d_%04d.exr", out, cs, i);
        status |= write_exr(path, m, p, 3, meta) ? 1 : 0;
    }
    if (fx & OCEAN_FX_NORMALS) {
        size_t nn = (size_t)m * m;
        normals_from_slopes(fd, nrm);
        exr_plane p[3] = {{"normal.R", nrm}, {"normal.G", nrm + nn}, {"normal.B", nrm + 2 * nn}};
        meta->channels = "normal.R, normal.G, normal.B = nx, ny, nz (unit normal, y up)";
        snprintf(path, sizeof path, "%s/normal_c%d_%04d.exr", out, cs, i);
        status |= write_exr(path, m, p, 3, meta) ? 1 : 0;
    }
    if (fx & OCEAN_FX_FOAM) {
        exr_plane p[1] = {{"foam.Y", fd->foam}};
        meta->channels = "foam.Y = foam coverage 0..1";
        snprintf(path, sizeof path, "%s/foam_c%d_%04d.exr", out, cs, i);
        status |= write_exr(path, m, p, 1, meta) ? 1 : 0;
    }
    return status;
}

int cmd_bake(int argc, char **argv)
{
    cli_common c;
    int frames = 1;
    double fps = 30.0;
    const char *out = NULL;
    const cli_opt opts[] = {
        {"frames", CLI_INT, &frames, 1, 1000000, "N     frames to bake", NULL},
        {"fps", CLI_DOUBLE, &fps, 1e-3, 1000, "F     frames per second of the sequence", NULL},
        {"out", CLI_STRING, &out, 0, 0, "DIR   output directory (created if missing; required)", NULL},
    };
    int r = cli_parse(argc, argv, "bake --out DIR [--frames N] [--fps F] [options]", opts, 3, &c,
                      NULL, NULL);
    if (r)
        return r == 1 ? 0 : 2;
    if (!out) {
        fprintf(stderr, "error: bake needs --out DIR\n");
        return 2;
    }
    /* The whole sequence's times are checked before anything is written:
     * a bake must not stop half-way at the time limit. */
    char tmsg[256];
    if (ocean_time_check(c.time + (frames - 1) / fps, "last frame time --time + (frames - 1) / fps",
                         tmsg, sizeof tmsg) != OCEAN_OK) {
        fprintf(stderr, "error: %s\n", tmsg);
        return 2;
    }
    if (mkdir(out, 0777) != 0 && errno != EEXIST) {
        fprintf(stderr, "error: cannot create %s: %s\n", out, strerror(errno));
        return 1;
    }
    ocean *o;
    ocean_frame *f;
    if (cli_make_ocean(&c, &o, &f))
        return 1;
    /* Bake only what was asked: --effects height,normals skips the rest. */
    unsigned fx = c.effects;
    int n = c.params.n, tty = isatty(STDERR_FILENO), status = 0;
    float *nrm = malloc(sizeof(float) * 3 * (size_t)n * n);
    float *zero = calloc((size_t)n * n, sizeof(float));
    if (!nrm || !zero) {
        fprintf(stderr, "error: out of memory\n");
        status = 1;
    }
    ocean_request req;
    ocean_request_all(&req, fx);
    double hs = ocean_spectrum_hs(&c.params.sea);   /* Hs of the spectrum, m */
    for (int i = 0; i < frames && status == 0; i++) {
        double t = c.time + i / fps;
        if (ocean_evaluate(o, t, &req, f) != OCEAN_OK) {
            fprintf(stderr, "error: evaluation at t = %.15g failed\n", t);
            status = 1;
            break;
        }
        for (int cs = 0; cs < c.params.cascades && status == 0; cs++) {
            const ocean_field *fd = ocean_frame_field(f, cs);
            bake_meta meta = {.params = &c.params, .fps = fps, .time = t, .patch_m = fd->patch_m,
                              .hs = hs, .frame = i, .cascade = cs};
            status |= bake_cascade(out, fx, fd, &meta, nrm, zero);
        }
        if (tty)
            progress(i + 1, frames);
    }
    if (status == 0)
        printf("baked %d frame(s) of %d cascade(s) into %s\n", frames, c.params.cascades, out);
    free(nrm);
    free(zero);
    ocean_frame_destroy(f);
    ocean_destroy(o);
    return status;
}
