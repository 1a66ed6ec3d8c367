/*
 * test_interp.c - the kernels that read a sampled field between its nodes
 * (sim/interp.h): their weights reproduce what each kernel is defined to
 * reproduce, the share of a wave's power each keeps is the mean over the
 * point read (brute force), and the cascade moments' kept slope variance
 * per kernel (ocean_cascade_moments, the daemon's read table) is each
 * wave's slope variance times those shares.
 */
#include <complex.h>
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "interp.h"
#include "ocean.h"

/* Highest power of the offset each kernel reproduces exactly: bilinear
 * lines, Keys (1981, a = -1/2) quadratics, cubic Lagrange cubics; Lanczos
 * only constants (it is normalised to sum 1). */
static const int reproduces[OCEAN_INTERP_KERNELS] = {1, 3, 2, 0};

static void each_kernel_interpolates(void **state)
{
    (void)state;
    for (int k = 0; k < OCEAN_INTERP_KERNELS; k++)
        for (int i = 0; i < 16; i++) {
            double t = i / 16.0, w[OCEAN_INTERP_MAX_TAPS];
            int R = ocean_interp_weights((ocean_interp)k, t, w);
            assert_true(R >= 1 && 2 * R <= OCEAN_INTERP_MAX_TAPS);
            for (int p = 0; p <= reproduces[k]; p++) {
                double s = 0;
                for (int j = 0; j < 2 * R; j++)
                    s += w[j] * pow(j + 1 - R, p);
                if (fabs(s - pow(t, p)) > 1e-12)
                    fail_msg("kernel %d at t = %g: sum w_j j^%d = %.15g, not t^%d = %.15g", k, t, p, s, p,
                             pow(t, p));
            }
            if (i == 0)
                for (int j = 0; j < 2 * R; j++)
                    assert_true(fabs(w[j] - (j == R - 1)) < 1e-12); /* the node itself */
        }
}

/* E_u |sum_j w_j(u) e^{i j th}|^2 by the midpoint rule on N points. */
static double power_brute(ocean_interp k, double th)
{
    enum { N = 20000 };
    double acc = 0;
    for (int i = 0; i < N; i++) {
        double w[OCEAN_INTERP_MAX_TAPS];
        int R = ocean_interp_weights(k, (i + 0.5) / N, w);
        double complex z = 0;
        for (int j = 0; j < 2 * R; j++)
            z += w[j] * cexp(I * (j + 1 - R) * th);
        acc += creal(z * conj(z));
    }
    return acc / N;
}

static void powers_are_the_mean_over_the_point_read(void **state)
{
    (void)state;
    enum { M = 8 };
    for (int k = 0; k < OCEAN_INTERP_KERNELS; k++) {
        double p[M];
        ocean_interp_powers((ocean_interp)k, M_PI / (M - 1), M, p);
        assert_true(fabs(p[0] - 1.0) < 1e-12); /* a constant passes whole */
        for (int m = 0; m < M; m++) {
            double th = m * M_PI / (M - 1), want = power_brute((ocean_interp)k, th);
            if (fabs(p[m] - want) > 1e-7)
                fail_msg("kernel %d, th = %g: %.12g, brute force %.12g", k, th, p[m], want);
            if (k == OCEAN_INTERP_BILINEAR)
                assert_true(fabs(p[m] - (2.0 + cos(th)) / 3.0) < 1e-12);
        }
    }
    /* at the Nyquist: bilinear keeps 1/3, Keys 17/35 (0.4857), Lanczos-3
     * about half; at half the Nyquist Lanczos overshoots */
    double b[3], ks[3], l[3];
    ocean_interp_powers(OCEAN_INTERP_BILINEAR, M_PI / 2, 3, b);
    ocean_interp_powers(OCEAN_INTERP_KEYS, M_PI / 2, 3, ks);
    ocean_interp_powers(OCEAN_INTERP_LANCZOS3, M_PI / 2, 3, l);
    assert_true(fabs(b[2] - 1.0 / 3.0) < 1e-12);
    assert_true(fabs(ks[2] - 17.0 / 35.0) < 1e-12);
    assert_true(b[1] < ks[1] && ks[1] < 1.0 && l[1] > 1.0);
}

/* Two waves on a 16-node lattice patch of 16 m (h = 1 m): each keeps
 * P(kx h) P(kz h) of its slope variance A^2 k^2 / 2 per kernel (to the
 * binary32 the spectrum's variances are stored in). */
static void a_waves_share_is_its_kernels(void **state)
{
    (void)state;
    const int n = 16;
    const ocean_lattice_wave w[2] = {{3, 5, 0.02, 0.3}, {-6, 1, 0.01, 1.1}};
    ocean_params op;
    ocean_params_default(&op);
    op.n = n;
    op.threads = 1;
    ocean *oc = NULL;
    char msg[256] = "";
    assert_int_equal(ocean_create_lattice(&op, (double)n, w, 2, &oc, msg, sizeof msg), OCEAN_OK);
    ocean_moments mo;
    assert_int_equal(ocean_cascade_moments(oc, 0, INFINITY, 6, &mo), OCEAN_OK);
    const double dk = 2.0 * M_PI / n;
    for (int k = 0; k < OCEAN_INTERP_KERNELS; k++) {
        double p[9], s = 0, all = 0;
        ocean_interp_powers((ocean_interp)k, dk, 9, p);
        for (int i = 0; i < 2; i++) {
            double v = 0.5 * w[i].amplitude * w[i].amplitude * (w[i].mx * w[i].mx + w[i].mz * w[i].mz) * dk * dk;
            all += v;
            s += v * p[abs(w[i].mx)] * p[abs(w[i].mz)];
        }
        if (fabs(mo.kept_mss - all) > 1e-6 * all || fabs(mo.kept_mss_read[k] - s) > 1e-6 * all)
            fail_msg("kernel %d: kept %.12g (waves %.12g), read %.12g (waves %.12g)", k, mo.kept_mss, all,
                     mo.kept_mss_read[k], s);
    }
    ocean_destroy(oc);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(each_kernel_interpolates),
        cmocka_unit_test(powers_are_the_mean_over_the_point_read),
        cmocka_unit_test(a_waves_share_is_its_kernels),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
