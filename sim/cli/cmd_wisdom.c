/*
 * cmd_wisdom.c - `ocean-sim wisdom`: times FFTW plans once and writes them
 * as a wisdom file that every replica imports (ocean.plan = wisdom).
 *
 * FFTW_MEASURE chooses among candidate algorithms by timing them, so two
 * daemons that plan for themselves can choose differently and their fields
 * then differ in the last bits.  Planning once here and shipping the
 * result fixes the choice for every process that imports the file.  The
 * file must be made on the CPU and FFTW build the replicas run, for every
 * (ocean.n, ocean.threads) they serve: the base configuration and each
 * scene file given as an argument.
 */
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "ocean_conf.h"

/* Plans (by creating an ocean with MEASURE) everything p's ocean needs;
 * the plans stay in FFTW's process-wide wisdom. */
static int plan_one(const char *what, ocean_params p)
{
    p.plan_measure = OCEAN_PLAN_MEASURE;
    p.wisdom[0] = '\0';
    char msg[600];
    double t0 = cli_now_ms();
    ocean *o = NULL;
    if (ocean_create(&p, &o, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "error: %s: %s\n", what, msg);
        return 1;
    }
    ocean_destroy(o);
    fprintf(stderr, "wisdom: %s: N = %d, %d thread%s planned in %.1f s\n", what, p.n, p.threads,
            p.threads == 1 ? "" : "s", (cli_now_ms() - t0) / 1e3);
    return 0;
}

int cmd_wisdom(int argc, char **argv)
{
    cli_common c;
    const char *out = NULL;
    const cli_opt opts[] = {
        {"out", CLI_STRING, &out, 0, 0, "FILE  where to write the wisdom (required)", NULL},
    };
    const char *pos[64];
    int npos = 64;
    int r = cli_parse(argc, argv,
                      "wisdom --out FILE [--config FILE] [options] [SCENE.conf ...]\n\n"
                      "Times the FFTW plans of the ocean the options (or --config) describe and of\n"
                      "each scene file over it, and writes them to FILE.  Daemons with\n"
                      "ocean.plan = wisdom and ocean.wisdom = FILE then run those plans: all\n"
                      "replicas sharing FILE agree bit for bit.  Run it on the machine the\n"
                      "replicas run on (CPU and FFTW build); about a minute at N = 1024.",
                      opts, 1, &c, pos, &npos);
    if (r)
        return r == 1 ? 0 : 2;
    if (!out || !*out) {
        fprintf(stderr, "error: --out FILE is required\n");
        return 2;
    }
    /* Every input is checked before the first plan is timed (about a
     * minute each at N = 1024): a typo in the last scene or an unwritable
     * --out must not cost the planning first. */
    char dir[4096];
    snprintf(dir, sizeof dir, "%s", out);
    char *slash = strrchr(dir, '/');
    if (slash)
        *(slash == dir ? slash + 1 : slash) = '\0';
    else
        snprintf(dir, sizeof dir, ".");
    if (access(dir, W_OK | X_OK) != 0) {
        fprintf(stderr, "error: --out %s: cannot write in %s: %s\n", out, dir, strerror(errno));
        return 2;
    }
    for (int pass = 0; pass < 2; pass++) {
        if (pass == 1 && plan_one(c.config ? c.config : "options", c.params))
            return 1;
        for (int i = 0; i < npos; i++) {
            ocean_scene sc;
            char err[600];
            if (ocean_conf_scene_load(pos[i], &c.params, &sc, err, sizeof err) != OCEAN_OK) {
                fprintf(stderr, "error: %s\n", err);
                return 2;
            }
            if (pass == 1 && plan_one(pos[i], sc.params))
                return 1;
        }
    }
    char msg[600];
    if (ocean_wisdom_export(out, msg, sizeof msg) != OCEAN_OK) {
        fprintf(stderr, "error: %s\n", msg);
        return 1;
    }
    fprintf(stderr, "wisdom: wrote %s\n", out);
    return 0;
}
