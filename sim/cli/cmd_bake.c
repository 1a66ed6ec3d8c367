/*
 * cmd_bake.c - `ocean-sim bake`: OpenEXR image sequences of each cascade's
 * displacement (R = Dx, G = height, B = Dz: y-up vector displacement as
 * Blender, Houdini and Nuke expect), unit normals (R, G, B = nx, ny, nz) and
 * foam (Y), written with OpenEXRCore, ZIP-compressed 32-bit float.
 *
 * Files: DIR/displacement_cC_FFFF.exr, DIR/normal_cC_FFFF.exr,
 *        DIR/foam_cC_FFFF.exr (C = cascade, FFFF = frame).
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

/* Writes planes (any order; OpenEXR stores channels sorted by name) as a
 * scanline ZIP file.  Returns 0 or prints the reason and returns -1. */
static int write_exr(const char *path, int n, const exr_plane *planes, int np)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctx = NULL;
    int part = 0;
    exr_result_t rv = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_add_part(ctx, "ocean", EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS)
        rv = exr_initialize_required_attr_simple(ctx, part, n, n, EXR_COMPRESSION_ZIP);
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
            ch->encode_from_ptr = (const uint8_t *)(src + (size_t)y * n);
            ch->user_pixel_stride = sizeof(float);
            ch->user_line_stride = (int32_t)(sizeof(float) * n);
            ch->user_bytes_per_element = sizeof(float);
            ch->user_data_type = EXR_PIXEL_FLOAT;
        }
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
    char path[4096];
    for (int i = 0; i < frames && status == 0; i++) {
        double t = c.time + i / fps;
        if (ocean_evaluate(o, t, &req, f) != OCEAN_OK) {
            fprintf(stderr, "error: evaluation at t = %g failed\n", t);
            status = 1;
            break;
        }
        for (int cs = 0; cs < c.params.cascades && status == 0; cs++) {
            const ocean_field *fd = ocean_frame_field(f, cs);
            int m = fd->n;
            if (fx & (OCEAN_FX_HEIGHT | OCEAN_FX_DISPLACEMENT)) {
                exr_plane p[3] = {{"R", fd->dx ? fd->dx : zero}, {"G", fd->height ? fd->height : zero},
                                  {"B", fd->dz ? fd->dz : zero}};
                snprintf(path, sizeof path, "%s/displacement_c%d_%04d.exr", out, cs, i);
                status |= write_exr(path, m, p, 3) ? 1 : 0;
            }
            if (fx & OCEAN_FX_NORMALS) {
                size_t nn = (size_t)m * m;
                for (size_t k = 0; k < nn; k++) {
                    double sx = fd->slope_x[k], sz = fd->slope_z[k];
                    double len = sqrt(sx * sx + 1.0 + sz * sz);
                    nrm[k] = (float)(-sx / len);
                    nrm[nn + k] = (float)(1.0 / len);
                    nrm[2 * nn + k] = (float)(-sz / len);
                }
                exr_plane p[3] = {{"R", nrm}, {"G", nrm + nn}, {"B", nrm + 2 * nn}};
                snprintf(path, sizeof path, "%s/normal_c%d_%04d.exr", out, cs, i);
                status |= write_exr(path, m, p, 3) ? 1 : 0;
            }
            if (fx & OCEAN_FX_FOAM) {
                exr_plane p[1] = {{"Y", fd->foam}};
                snprintf(path, sizeof path, "%s/foam_c%d_%04d.exr", out, cs, i);
                status |= write_exr(path, m, p, 1) ? 1 : 0;
            }
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
