/*
 * ocean_fft.c - the ocean's FFTW plans: made once per (grid size, batch)
 * at ocean_create from the plan mode (estimate, measure, or a wisdom file
 * every replica shares), and run by the evaluation (ocean_fft_run).
 * FFTW's planner is process-global state: planning, destroying plans and
 * exporting wisdom hold one lock for every ocean; executing a plan does
 * not (one ocean is used by one thread at a time).
 */
#include "ocean.h"
#include "ocean_internal.h"

#include <errno.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* FFTW's planner is process-global state: one lock for every ocean. */
static pthread_mutex_t planner_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_once_t fftw_once = PTHREAD_ONCE_INIT;
static int fftw_threads_ok;

static void fftw_init_once(void)
{
    fftw_threads_ok = fftwf_init_threads();
}

void ocean_fft_init(void)
{
    pthread_once(&fftw_once, fftw_init_once);
}

/* Replaces the process's wisdom by the file's (caller holds planner_lock).
 * Forgetting first keeps plans a MEASURE ocean of this process timed from
 * standing in for the file's, which other replicas do not have. */
static ocean_result wisdom_import(const char *path, char *msg, size_t msglen)
{
    /* A directory opens for reading and then read as "corrupt"; a relative
     * path that is missing is said with the directory it was read from */
    struct stat st;
    FILE *fp = stat(path, &st) == 0 && S_ISDIR(st.st_mode) ? (errno = EISDIR, NULL) : fopen(path, "r");
    if (!fp) {
        int e = errno;
        char cwd[512] = "";
        int rel = path[0] != '/' && getcwd(cwd, sizeof cwd) != NULL;
        if (msg) snprintf(msg, msglen, "wisdom file '%s': %s%s%s (`ocean-sim wisdom --out %s` writes one)",
                          path, strerror(e), rel ? "; relative paths are read from " : "", rel ? cwd : "", path);
        return OCEAN_EIO;
    }
    fftwf_forget_wisdom();
    int ok = fftwf_import_wisdom_from_file(fp);
    fclose(fp);
    if (!ok) {
        fftwf_forget_wisdom();
        if (msg) snprintf(msg, msglen, "wisdom file '%s' is not FFTW single-precision wisdom "
                          "(corrupt, or written by another FFTW build): regenerate it with "
                          "`ocean-sim wisdom --out %s`", path, path);
        return OCEAN_EFORMAT;
    }
    return OCEAN_OK;
}

ocean_result ocean_wisdom_export(const char *path, char *msg, size_t msglen)
{
    if (!path || !*path) {
        if (msg) snprintf(msg, msglen, "wisdom: no output file");
        return OCEAN_EINVAL;
    }
    pthread_once(&fftw_once, fftw_init_once);
    pthread_mutex_lock(&planner_lock);
    FILE *fp = fopen(path, "w");
    int err = fp ? 0 : errno;
    if (fp) {
        fftwf_export_wisdom_to_file(fp);
        if (ferror(fp))
            err = EIO;
        if (fclose(fp) != 0 && !err)
            err = errno;
    }
    pthread_mutex_unlock(&planner_lock);
    if (err) {
        if (msg) snprintf(msg, msglen, "wisdom file '%s': %s", path, strerror(err));
        return OCEAN_EIO;
    }
    return OCEAN_OK;
}

/* Columns of the m-point grid (m = 8 << l) up to the last that holds a wave
 * of cascade cs: ocean_pair_range's hi over the grid's row pairs. */
static int cascade_width(const ocean_cascade *cs, int m)
{
    int w = 0;
    for (int p = 0; p < m / 2; p++) {
        int hi = cs->hi[p] < m / 2 ? cs->hi[p] : m / 2;
        if (cs->lo[p] < hi && hi > w)
            w = hi;
    }
    return w;
}

/* The columns level l's pruned plans transform: a quarter of the m-point
 * grid (m = 8 << l), where a coarse cascade's half disc of radius m/4
 * ends on its full grid.  Fixed rather than each band's own width, so
 * every ocean of an (N, threads) has the same plans: a wisdom file made
 * from the FFT ocean serves the near field's lattice ocean too.  Grids
 * below PARALLEL_MIN_N: 0, no pruned plans (the 2-D plan is a few
 * microseconds there).  Fills every cascade's width at this level. */
static int prune_columns(ocean *o, int l)
{
    int m = 8 << l;
    for (int c = 0; c < o->p.cascades; c++)
        o->cas[c].width[l] = cascade_width(&o->cas[c], m);
    return m >= PARALLEL_MIN_N ? m / 4 : 0;
}

/* The two passes of level l's pruned c transforms (caller holds
 * planner_lock, with the level's thread count set).  The 2-D c2r of the
 * spectra at o->spec is a c2c down each column (the m rows, stride m/2+1)
 * and then a c2r along each row; a column with no wave stays zero through
 * the first pass, so only columns [0, cols) take it, in place.  The
 * second pass is the 2-D plan's own: out of place, free to overwrite its
 * input (the stage writes every column again before the next call). */
static void plan_pruned(ocean *o, int l, int c, float *tmp, unsigned flags)
{
    int m = 8 << l, half = m / 2 + 1;
    ptrdiff_t plane = (ptrdiff_t)m * half;
    fftwf_iodim col = {m, half, half};
    fftwf_iodim col_many[2] = {{o->prune_cols[l], 1, 1}, {c, plane, plane}};
    o->cols_plan[l][c - 1] = fftwf_plan_guru_dft(1, &col, 2, col_many, o->spec, o->spec,
                                                 FFTW_BACKWARD, flags);
    fftwf_iodim row = {m, 1, 1};
    fftwf_iodim row_many[2] = {{m, half, m}, {c, plane, (ptrdiff_t)m * m}};
    o->rows_plan[l][c - 1] = fftwf_plan_guru_dft_c2r(1, &row, 2, row_many, o->spec, tmp, flags);
}

/* The planner flags of p's plan mode (caller holds planner_lock). */
static ocean_result plan_flags(const ocean_params *p, unsigned *flags, char *msg, size_t msglen)
{
    *flags = FFTW_ESTIMATE;
    if (p->plan_measure == OCEAN_PLAN_ESTIMATE) {
        /* An ESTIMATE planner still takes wisdom of a higher patience, so
         * wisdom left by a MEASURE or WISDOM ocean of this process would
         * make its plans differ from another process's. */
        fftwf_forget_wisdom();
    } else if (p->plan_measure == OCEAN_PLAN_MEASURE) {
        *flags = FFTW_MEASURE;
    } else {
        ocean_result r = wisdom_import(p->wisdom, msg, msglen);
        if (r != OCEAN_OK)
            return r;
        *flags = FFTW_MEASURE | FFTW_WISDOM_ONLY;
    }
    return OCEAN_OK;
}

/* Why level l's c-channel plans (m = 8 << l, nthr threads) could not be
 * made: a wisdom file without them, or FFTW itself. */
static ocean_result plan_failure(const ocean *o, int l, int c, int nthr, unsigned flags, char *msg,
                                 size_t msglen)
{
    int m = 8 << l;
    if (flags & FFTW_WISDOM_ONLY) {
        char what[96];
        if (o->plan[l][c - 1])
            snprintf(what, sizeof what, " (its column pass over %d of %d columns)",
                     o->prune_cols[l], m / 2 + 1);
        else
            what[0] = '\0';
        if (msg) snprintf(msg, msglen, "wisdom file '%s' has no plan for a %dx%d x%d "
                          "transform%s on %d thread%s (made for another N, "
                          "ocean.threads or scene, or by an older oceand?): "
                          "regenerate it with `ocean-sim wisdom`",
                          o->p.wisdom, m, m, c, what, nthr, nthr == 1 ? "" : "s");
        return OCEAN_EUNSUPPORTED;
    }
    if (msg) snprintf(msg, msglen, "FFTW could not plan a %dx%d x%d transform", m, m, c);
    return OCEAN_ENOMEM;
}

/* Every (size, batch) planned once, so evaluations only execute (caller
 * holds planner_lock); tmp is the planner's output scratch. */
static ocean_result plan_all(ocean *o, float *tmp, unsigned flags, char *msg, size_t msglen)
{
    int n = o->p.n;
    for (int l = 0; (8 << l) <= n; l++) {
        int m = 8 << l;
        o->levels = l + 1;
        int nthr = m >= PARALLEL_MIN_N ? o->p.threads : 1;
        if (fftw_threads_ok)
            fftwf_plan_with_nthreads(nthr);
        o->prune_cols[l] = prune_columns(o, l);
        for (int c = 1; c <= CH_COUNT; c++) {
            int dims[2] = {m, m};
            o->plan[l][c - 1] = fftwf_plan_many_dft_c2r(
                2, dims, c, o->spec, NULL, 1, m * (m / 2 + 1), tmp, NULL, 1, m * m, flags);
            if (o->plan[l][c - 1] && o->prune_cols[l])
                plan_pruned(o, l, c, tmp, flags);
            if (!o->plan[l][c - 1] || (o->prune_cols[l] && (!o->cols_plan[l][c - 1] || !o->rows_plan[l][c - 1])))
                return plan_failure(o, l, c, nthr, flags, msg, msglen);
        }
    }
    return OCEAN_OK;
}

/* One FFTW call: the 2-D c2r of gn channels of cascade cs's n-point
 * spectra at o->spec into out.  A cascade whose waves all lie in the
 * first prune_cols columns (the coarse cascades: a half disc of radius
 * n/4) runs the 2-D transform as its two passes and leaves the column
 * pass out where no wave is: those columns are zero on input and stay
 * zero through it, so the result is the same transform (bench_core: the
 * column pass is about half of FFTW's work).  Returns 1 when pruned. */
int ocean_fft_run(ocean *o, const ocean_cascade *cs, int n, int gn, float *out)
{
    int l = ocean_level_of(n);
    if (o->prune && o->prune_cols[l] && cs->width[l] <= o->prune_cols[l]) {
        fftwf_execute_dft(o->cols_plan[l][gn - 1], o->spec, o->spec);
        fftwf_execute_dft_c2r(o->rows_plan[l][gn - 1], o->spec, out);
        return 1;
    }
    fftwf_execute_dft_c2r(o->plan[l][gn - 1], o->spec, out);
    return 0;
}

void ocean_force_pruning(ocean *o, int prune)
{
    if (o)
        o->prune = prune != 0;
}

ocean_result ocean_fft_plan(ocean *o, char *msg, size_t msglen)
{
    int n = o->p.n;
    /* the planner's output scratch: plans are made out of place */
    float *tmp = fftwf_malloc(sizeof(float) * CH_COUNT * (size_t)n * n);
    if (!tmp) {
        if (msg) snprintf(msg, msglen, "out of memory for %d-point spectra", n);
        return OCEAN_ENOMEM;
    }
    pthread_mutex_lock(&planner_lock);
    unsigned flags;
    ocean_result r = plan_flags(&o->p, &flags, msg, msglen);
    if (r == OCEAN_OK)
        r = plan_all(o, tmp, flags, msg, msglen);
    pthread_mutex_unlock(&planner_lock);
    fftwf_free(tmp);
    return r;
}

void ocean_fft_planner_lock(void)
{
    ocean_fft_init();
    pthread_mutex_lock(&planner_lock);
}

void ocean_fft_planner_unlock(void) { pthread_mutex_unlock(&planner_lock); }

void ocean_fft_free(ocean *o)
{
    pthread_mutex_lock(&planner_lock);
    for (int l = 0; l < MAX_LEVELS; l++)
        for (int c = 0; c < CH_COUNT; c++) {
            if (o->plan[l][c])
                fftwf_destroy_plan(o->plan[l][c]);
            if (o->cols_plan[l][c])
                fftwf_destroy_plan(o->cols_plan[l][c]);
            if (o->rows_plan[l][c])
                fftwf_destroy_plan(o->rows_plan[l][c]);
        }
    pthread_mutex_unlock(&planner_lock);
}
