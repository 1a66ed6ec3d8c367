/*
 * cmd_export.c - `ocean-client export`: save received tiles as OpenEXR
 * files.  With an EXR codec the TILE payload already is a complete .exr
 * file (protocol/codec.h) and is written as is; with any other codec the
 * tile is decoded and re-encoded with exr-zip (lossless on the decoded
 * floats).  An index tiles.csv beside them gives each file's frame, sim
 * time, layout, cascade, level, tile index, origin, spacing, size and
 * channels (layout 1: the origin is cascade-local, periodic on the
 * cascade's patch; PROTOCOL.md "Cascade mips").
 */
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "occli.h"

static int mkdir_p(const char *dir)
{
    char buf[1024];
    snprintf(buf, sizeof buf, "%s", dir);
    for (char *p = buf + 1; *p; p++)
        if (*p == '/') {
            *p = 0;
            if (mkdir(buf, 0755) != 0 && errno != EEXIST)
                return -1;
            *p = '/';
        }
    if (mkdir(buf, 0755) != 0 && errno != EEXIST)
        return -1;
    return 0;
}

static int write_file(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return -1;
    int ok = fwrite(data, 1, n, f) == n;
    ok &= fclose(f) == 0;
    return ok ? 0 : -1;
}

/* What the command was asked. */
typedef struct export_opts {
    const char *out, *url;
    int nframes;
    occli_sub s;
} export_opts;

/* Parses the options into *P (defaults first): 0 go on, 1 help printed, 2
 * refused (said). */
static int export_parse(int argc, char **argv, export_opts *P)
{
    const occli_opt opts[] = {
        {"out", OCCLI_STRING, &P->out, 0, 0, "DIR  directory for the .exr files and tiles.csv (created)", NULL},
        {"frames", OCCLI_INT, &P->nframes, 1, 100000, "N  frames to export", NULL},
        OCCLI_SUB_OPTS(&P->s),
    };
    const char *pos[1];
    int np = 0;
    int pr = occli_parse(argc, argv,
                         "usage: ocean-client export URL --out DIR [--frames N] [options]\n"
                         "Writes every tile of the next N frames as an OpenEXR file (channels H, DX, DZ, NU, NV,\n"
                         "FOAM, J as subscribed), zip-compressed.  EXR codecs' payloads are saved as they arrive;\n"
                         "other codecs' tiles (qz: the most sea within the server's byte budget) are decoded and\n"
                         "re-encoded.",
                         opts, (int)(sizeof opts / sizeof opts[0]), pos, 1, &np);
    if (pr)
        return pr;
    if (np != 1 || !P->out) {
        fprintf(stderr, "ocean-client export: needs URL and --out DIR (see --help)\n");
        return 2;
    }
    if (P->s.time_interp == 1) {
        fprintf(stderr, "ocean-client export: option '--time-interp': on is not offered: a time-interpolating "
                "frame's tiles are samples of other ticks than the frame's, and export writes each frame's "
                "tiles as the sea at its sim time\n");
        return 2;
    }
    P->url = pos[0];
    return 0;
}

/* Creates the directory and its tiles.csv with the header line: the open
 * index, or NULL (said). */
static FILE *export_index_open(const char *out)
{
    if (mkdir_p(out) != 0) {
        fprintf(stderr, "ocean-client export: cannot create %s: %s\n", out, strerror(errno));
        return NULL;
    }
    char idx_path[1200];
    snprintf(idx_path, sizeof idx_path, "%s/tiles.csv", out);
    FILE *idx = fopen(idx_path, "w");
    if (!idx) {
        fprintf(stderr, "ocean-client export: cannot create %s: %s\n", idx_path, strerror(errno));
        return NULL;
    }
    fprintf(idx, "file,frame,sim_time,layout,cascade,level,ix,iz,origin_x,origin_z,spacing,width,height,channels,"
                 "codec,error_bound\n");
    return idx;
}

/* An export in progress: where it writes and what it wrote. */
typedef struct export_run {
    const char *out;
    FILE *idx;
    proto_codec_params cp;
    proto_buf b;              /* a re-encoded tile */
    uint64_t files, bytes;
} export_run;

/* The EXR file of tile i of frame f: its payload as it came (an EXR codec)
 * or re-encoded as exr-zip.  0, or 1 (said). */
static int export_tile_exr(export_run *X, const oc_frame *f, unsigned i, const void **data, size_t *n,
                           proto_codec *written)
{
    const oc_tile *t = &f->tiles[i];
    *written = (proto_codec)t->info.codec;
    if (t->info.codec >= PROTO_CODEC_EXR_ZIP) {
        *data = t->info.payload;
        *n = t->info.payload_len;
        return 0;
    }
    if (!t->data) {
        fprintf(stderr, "ocean-client export: tile %u of frame %llu did not decode: %s\n", i,
                (unsigned long long)f->index, ocean_strerror(t->decode_result));
        return 1;
    }
    char err[256];
    proto_buf_reset(&X->b);
    if (proto_tile_encode(PROTO_CODEC_EXR_ZIP, &X->cp, t->info.width, t->info.height, t->info.channels, t->data,
                          &X->b, NULL, err, sizeof err) != OCEAN_OK) {
        fprintf(stderr, "ocean-client export: EXR encoding failed: %s\n", err);
        return 1;
    }
    *data = proto_buf_data(&X->b);
    *n = proto_buf_len(&X->b);
    *written = PROTO_CODEC_EXR_ZIP;
    return 0;
}

/* Writes tile i of frame f (the got-th exported) and its index line: 0, or
 * 1 (said). */
static int export_tile(export_run *X, const oc_frame *f, unsigned i, int got)
{
    const oc_tile *t = &f->tiles[i];
    const void *data;
    size_t n;
    proto_codec written;
    if (export_tile_exr(X, f, i, &data, &n, &written))
        return 1;
    char name[256], full[1400];
    /* layout 1: tiles of different cascades share (level, ix, iz) */
    snprintf(name, sizeof name, "f%04d_C%u_L%02u_x%d_z%d.exr", got, t->info.cascade, t->info.level, t->info.ix,
             t->info.iz);
    snprintf(full, sizeof full, "%s/%s", X->out, name);
    if (write_file(full, data, n) != 0) {
        fprintf(stderr, "ocean-client export: cannot write %s: %s\n", full, strerror(errno));
        return 1;
    }
    fprintf(X->idx, "%s,%d,%.17g,%u,%u,%u,%d,%d,%.17g,%.17g,%.17g,%u,%u,%u,%s,%.9g\n", name, got, f->hdr.sim_time,
            f->info.layout, t->info.cascade, t->info.level, t->info.ix, t->info.iz, t->info.origin_x,
            t->info.origin_z, t->info.spacing, t->info.width, t->info.height, t->info.channels,
            proto_codec_name(written), (double)t->info.error_bound);
    X->files++;
    X->bytes += n;
    return 0;
}

/* Exports the next P->nframes frames; *got counts them.  0, or 1 (said). */
static int export_frames(const export_opts *P, oc_client *c, export_run *X, int *got)
{
    int rc = 0;
    while (!rc && *got < P->nframes && !occli_stop) {
        oc_frame *f = NULL;
        ocean_result r = oc_client_next_frame(c, P->s.timeout_ms, &f);
        if (r != OCEAN_OK) {
            char err[512];
            oc_client_last_error(c, err, sizeof err);
            fprintf(stderr, "ocean-client export: no frame: %s\n", err[0] ? err : ocean_strerror(r));
            return 1;
        }
        /* tiles the byte budget coarsened: say so rather than export them
         * as if they were the sea */
        if (*got == 0 && f->info.e_error > 0.25)
            fprintf(stderr, "ocean-client export: warning: frame %llu's tiles leave %.0f %% of the sea's "
                    "height variance out (E_error %.3g): the server fitted them to its byte budget "
                    "(server.viewer_bytes_per_s) for codec %s; --codec qz carries the most\n",
                    (unsigned long long)f->index, 100.0 * f->info.e_error, f->info.e_error, P->s.codec);
        for (unsigned i = 0; i < f->info.tile_count && !rc; i++)
            rc = export_tile(X, f, i, *got);
        oc_frame_free(f);
        ++*got;
    }
    return rc;
}

int cmd_export(int argc, char **argv)
{
    export_opts P = {.nframes = 1};
    occli_sub_default(&P.s);
    /* qz: the server fits a frame's tiles to its byte budget per viewer
     * (server.viewer_bytes_per_s), and qz's are the smallest, so they carry
     * the most sea; they are re-encoded as exr-zip here.  exr-zip on the
     * wire (4 bytes a sample) leaves the default scene's frame 3 coarse
     * tiles of one cascade (E_error 0.98, against 31 tiles and 0.0065). */
    P.s.codec = "qz";
    /* frames, not a stream: the server's budget is per second, so at 5 Hz
     * each frame may carry six times what a 30 Hz viewer's does (the
     * shipped 0.85e6 B/s: 170 KB a frame) */
    P.s.rate = 5;
    /* the plain stream: export writes each frame's records as the sea at
     * the frame's sim time, and a time-interpolating frame's records are
     * samples of other ticks (PROTOCOL.md "Samples in time") */
    P.s.time_interp = 0;
    int pr = export_parse(argc, argv, &P);
    if (pr)
        return pr == 1 ? 0 : 2;
    proto_subscribe sub;
    proto_camera cam;
    if (occli_sub_build("export", &P.s, &sub, &cam))
        return 2;
    export_run X = {.out = P.out};
    X.idx = export_index_open(P.out);
    if (!X.idx)
        return 1;
    oc_options o;
    oc_options_default(&o);
    o.frame_queue = 64;
    o.decode_tiles = sub.codec < PROTO_CODEC_EXR_ZIP;
    oc_client *c = occli_connect("export", P.url, &o, P.s.timeout_ms);
    if (!c) {
        fclose(X.idx);
        return 1;
    }
    int rc = 0, got = 0;
    if (oc_client_subscribe(c, &sub) != OCEAN_OK || oc_client_send_camera(c, &cam, NULL) != OCEAN_OK)
        rc = 1;
    proto_codec_params_default(&X.cp);
    proto_buf_init(&X.b, 0);
    if (!rc)
        rc = export_frames(&P, c, &X, &got);
    proto_buf_free(&X.b);
    if (fclose(X.idx) != 0)
        rc = 1;
    oc_client_destroy(c);
    fprintf(stderr, "ocean-client export: %d frame(s), %llu EXR files, %llu bytes in %s\n", got,
            (unsigned long long)X.files, (unsigned long long)X.bytes, P.out);
    if (!rc && X.files == 0) {
        fprintf(stderr, "ocean-client export: the frames held no tiles\n");
        rc = 1;
    }
    return rc;
}
