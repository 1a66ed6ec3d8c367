/*
 * test_wisdom.c - FFTW plans chosen by timing, shared through a wisdom file
 * (ocean.plan = wisdom): separate processes that import the same file run
 * the same plans and produce bit-identical fields (the coarse cascade's
 * pruned column pass too), and a missing, corrupt or insufficient file is
 * refused with a message naming it.
 *
 * Processes, not oceans in one process: FFTW's planner state is global, so
 * two oceans of one process share plans whatever the mode; only separate
 * processes show whether the file alone fixes the choice.  The children are
 * forked before this process starts any thread pool (libgomp's pool does
 * not survive fork), so the tests run in this order.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmocka.h>

#include "ocean.h"

#define N 64 /* PARALLEL_MIN_N: the largest level plans with 2 threads */

static char dir[] = "/tmp/test_wisdom_XXXXXX";
static char wis[256];

static void params(ocean_params *p, int mode)
{
    ocean_params_default(p);
    p->n = N;
    p->cascades = 2;
    p->threads = 2;
    p->plan_measure = mode;
    if (mode == OCEAN_PLAN_WISDOM)
        snprintf(p->wisdom, sizeof p->wisdom, "%s", wis);
}

/* FNV-1a over every channel of every cascade: a change in any bit of any
 * sample changes it. */
static uint64_t field_hash(ocean *o, double t)
{
    ocean_frame *f = NULL;
    if (ocean_frame_create(o, &f) != OCEAN_OK)
        return 0;
    ocean_request r;
    ocean_request_all(&r, OCEAN_FX_ALL | OCEAN_FX_VELOCITY);
    uint64_t h = 1469598103934665603ull;
    ocean_counters c0, c1;
    ocean_get_counters(o, &c0);
    int ok = ocean_evaluate(o, t, &r, f) == OCEAN_OK;
    ocean_get_counters(o, &c1);
    /* The coarse cascade runs the pruned column pass: those plans must
     * travel in the file too (0: no hash). */
    if (ok && c1.fft_calls_pruned == c0.fft_calls_pruned) {
        fprintf(stderr, "child: the coarse cascade did not run the pruned column pass\n");
        ok = 0;
        h = 0;
    }
    if (ok) {
        for (int c = 0; c < ocean_get_params(o)->cascades; c++) {
            const ocean_field *fl = ocean_frame_field(f, c);
            const float *ch[] = {fl->height, fl->dx, fl->dz, fl->slope_x, fl->slope_z, fl->dxx,
                                 fl->dzz, fl->dxz, fl->jacobian, fl->foam, fl->vel_x, fl->vel_y, fl->vel_z};
            for (size_t k = 0; k < sizeof ch / sizeof ch[0]; k++) {
                if (!ch[k])
                    continue;
                const unsigned char *b = (const unsigned char *)ch[k];
                for (size_t i = 0; i < sizeof(float) * (size_t)fl->n * fl->n; i++)
                    h = (h ^ b[i]) * 1099511628211ull;
            }
        }
    }
    ocean_frame_destroy(f);
    return h;
}

/* In a child process: builds the ocean of `mode` (MEASURE also exports the
 * wisdom), hashes its fields at t, and sends the hash back. */
static uint64_t in_child(int mode)
{
    int fd[2];
    assert_int_equal(pipe(fd), 0);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        close(fd[0]);
        ocean_params p;
        params(&p, mode);
        ocean *o = NULL;
        char msg[600];
        uint64_t h = 0;
        if (ocean_create(&p, &o, msg, sizeof msg) == OCEAN_OK &&
            (mode != OCEAN_PLAN_MEASURE || ocean_wisdom_export(wis, msg, sizeof msg) == OCEAN_OK))
            h = field_hash(o, 1234.5);
        else
            fprintf(stderr, "child: %s\n", msg);
        ocean_destroy(o);
        ssize_t w = write(fd[1], &h, sizeof h);
        _exit(w == (ssize_t)sizeof h ? 0 : 1);
    }
    close(fd[1]);
    uint64_t h = 0;
    ssize_t got = read(fd[0], &h, sizeof h);
    close(fd[0]);
    int st = 0;
    assert_int_equal(waitpid(pid, &st, 0), pid);
    assert_true(WIFEXITED(st) && WEXITSTATUS(st) == 0);
    assert_int_equal(got, (ssize_t)sizeof h);
    return h;
}

static int setup(void **state)
{
    (void)state;
    if (!mkdtemp(dir))
        return -1;
    snprintf(wis, sizeof wis, "%s/ocean.wisdom", dir);
    return 0;
}

static int teardown(void **state)
{
    (void)state;
    char p[300];
    const char *names[] = {"ocean.wisdom", "corrupt.wisdom", "truncated.wisdom"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        snprintf(p, sizeof p, "%s/%s", dir, names[i]);
        unlink(p);
    }
    rmdir(dir);
    return 0;
}

static void test_replicas_share_plans(void **state)
{
    (void)state;
    /* The generator times its plans and exports them... */
    uint64_t measured = in_child(OCEAN_PLAN_MEASURE);
    assert_true(measured != 0);
    assert_int_equal(access(wis, R_OK), 0);
    /* ...two replicas import them and agree bit for bit, with each other
     * and with the process that timed the plans. */
    uint64_t a = in_child(OCEAN_PLAN_WISDOM), b = in_child(OCEAN_PLAN_WISDOM);
    assert_true(a != 0);
    assert_true(a == b);
    assert_true(a == measured);

    /* In this process too, after a MEASURE ocean left its own timed plans
     * in FFTW's global wisdom: the file's plans replace them. */
    ocean_params p;
    params(&p, OCEAN_PLAN_MEASURE);
    ocean *m = NULL, *o = NULL;
    char msg[600];
    assert_int_equal(ocean_create(&p, &m, msg, sizeof msg), OCEAN_OK);
    params(&p, OCEAN_PLAN_WISDOM);
    assert_int_equal(ocean_create(&p, &o, msg, sizeof msg), OCEAN_OK);
    assert_true(field_hash(o, 1234.5) == a);
    ocean_destroy(o);
    ocean_destroy(m);
}

static void expect_refused(const ocean_params *p, ocean_result want, const char *path)
{
    ocean *o = (ocean *)1;
    char msg[600] = "";
    ocean_result r = ocean_create(p, &o, msg, sizeof msg);
    assert_int_equal(r, want);
    assert_null(o);
    if (!strstr(msg, path))
        fail_msg("message does not name '%s': %s", path, msg);
}

static void write_file(const char *path, const char *text, size_t len)
{
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    assert_int_equal(fwrite(text, 1, len, f), len);
    assert_int_equal(fclose(f), 0);
}

static void test_bad_wisdom_refused(void **state)
{
    (void)state;
    ocean_params p;
    char msg[600];
    /* No file named at all. */
    params(&p, OCEAN_PLAN_WISDOM);
    p.wisdom[0] = '\0';
    assert_int_equal(ocean_params_validate(&p, msg, sizeof msg), OCEAN_EINVAL);
    assert_non_null(strstr(msg, "wisdom"));

    /* A file that does not exist. */
    params(&p, OCEAN_PLAN_WISDOM);
    snprintf(p.wisdom, sizeof p.wisdom, "%s/no-such.wisdom", dir);
    expect_refused(&p, OCEAN_EIO, p.wisdom);

    /* A directory is said to be one (it read as "corrupt"), and a missing
     * relative path names the directory it was read from. */
    snprintf(p.wisdom, sizeof p.wisdom, "%s", dir);
    {
        ocean *o = NULL;
        char m2[600] = "";
        assert_int_equal(ocean_create(&p, &o, m2, sizeof m2), OCEAN_EIO);
        if (!strstr(m2, "Is a directory")) fail_msg("a directory as wisdom: %s", m2);
        snprintf(p.wisdom, sizeof p.wisdom, "no-such-relative.wisdom");
        assert_int_equal(ocean_create(&p, &o, m2, sizeof m2), OCEAN_EIO);
        if (!strstr(m2, "relative paths are read from /")) fail_msg("a missing relative wisdom: %s", m2);
    }

    /* Not wisdom. */
    snprintf(p.wisdom, sizeof p.wisdom, "%s/corrupt.wisdom", dir);
    write_file(p.wisdom, "(not wisdom at all\n", 19);
    expect_refused(&p, OCEAN_EFORMAT, p.wisdom);

    /* Valid wisdom (test_replicas_share_plans wrote it; no fork here, a
     * child of a process with a live OpenMP pool can hang) cut short. */
    FILE *f = fopen(wis, "r");
    assert_non_null(f);
    char buf[4096];
    size_t len = fread(buf, 1, sizeof buf, f);
    fclose(f);
    assert_true(len > 200);
    snprintf(p.wisdom, sizeof p.wisdom, "%s/truncated.wisdom", dir);
    write_file(p.wisdom, buf, len / 2);
    expect_refused(&p, OCEAN_EFORMAT, p.wisdom);

    /* Good wisdom for another N: a transform it lacks is refused, never
     * timed on the spot (which would break agreement between replicas). */
    params(&p, OCEAN_PLAN_WISDOM);
    p.n = 2 * N;
    expect_refused(&p, OCEAN_EUNSUPPORTED, wis);
    /* ... and for another thread count. */
    params(&p, OCEAN_PLAN_WISDOM);
    p.threads = 3;
    expect_refused(&p, OCEAN_EUNSUPPORTED, wis);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_replicas_share_plans),
        cmocka_unit_test(test_bad_wisdom_refused),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
