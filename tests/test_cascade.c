/*
 * test_cascade.c - the simulation side of the cascade tile layout
 * (PROTOCOL.md "Cascade mips"): each cascade's mip pyramid, the
 * per-cascade cutoffs that evaluate a whole mip level in one call, and the
 * slope moments of what a mip does not carry (the unresolved roughness of
 * Bruneton, Neyret & Holzschuch 2010).
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "filter.h"
#include "ocean.h"

static ocean *make(int n, int cascades)
{
    ocean_params p;
    ocean_params_default(&p);
    p.n = n;
    p.cascades = cascades;
    p.threads = 1;
    p.sea.wind_u10 = 12;
    ocean *o = NULL;
    char msg[256];
    assert_int_equal(ocean_create(&p, &o, msg, sizeof msg), OCEAN_OK);
    return o;
}

/* Mip m's cutoff is half its grid's Nyquist, so the evaluation at it runs
 * on exactly n / 2^m; mips stop where the band holds no wave. */
static void mips_have_their_grids(void **state)
{
    (void)state;
    ocean *o = make(256, 3);
    ocean_frame *f;
    assert_int_equal(ocean_frame_create(o, &f), OCEAN_OK);
    for (int c = 0; c < 3; c++) {
        double patch, klo, khi, kc[12];
        int mips = 0;
        ocean_cascade_band(o, c, &patch, &klo, &khi);
        assert_int_equal(ocean_cascade_mips(o, c, 6, 12, &mips, kc), OCEAN_OK);
        assert_true(mips >= 1);
        assert_true(isinf(kc[0]));
        double dk = 2 * M_PI / patch;
        for (int m = 1; m < mips; m++) {
            assert_true(fabs(kc[m] - (256 >> (m + 2)) * dk) <= 1e-12 * kc[m]);
            /* every mip holds some wave of the band, up to the gain-1/2 point */
            assert_true(klo < ocean_filter_negligible_k(kc[m], 6, OCEAN_DROP_GAIN_DEFAULT));
            ocean_request rq;
            memset(&rq, 0, sizeof rq);
            rq.effects[c] = OCEAN_FX_HEIGHT | OCEAN_FX_NORMALS;
            rq.cascade_cutoff_k[c] = kc[m];
            rq.cutoff_k = INFINITY;
            rq.order = 6;
            rq.low_boost = 1;
            rq.per_cascade = 1;
            assert_int_equal(ocean_evaluate(o, 12.5, &rq, f), OCEAN_OK);
            assert_int_equal(ocean_frame_field(f, c)->n, 256 >> m);
        }
        /* the next coarser mip would hold nothing of this band */
        if (mips < 6) {
            double next = (256 >> (mips + 2)) * dk;
            assert_true(klo >= ocean_filter_negligible_k(next, 6, OCEAN_DROP_GAIN_DEFAULT));
        }
        /* the coarsest cascade keeps its long waves down to an 8-point grid */
        if (c == 0) assert_int_equal(mips, 6);
    }
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

/* One evaluation holds the same mip level of every cascade, each at its
 * own cutoff, and gives the same floats as evaluating each alone. */
static void per_cascade_cutoffs(void **state)
{
    (void)state;
    ocean *o = make(128, 2);
    ocean_frame *both, *one;
    assert_int_equal(ocean_frame_create(o, &both), OCEAN_OK);
    assert_int_equal(ocean_frame_create(o, &one), OCEAN_OK);
    double kc[2][12];
    int mips[2];
    for (int c = 0; c < 2; c++) assert_int_equal(ocean_cascade_mips(o, c, 6, 12, &mips[c], kc[c]), OCEAN_OK);
    ocean_request rq;
    memset(&rq, 0, sizeof rq);
    rq.cutoff_k = INFINITY;
    rq.order = 6;
    rq.low_boost = 1;
    rq.per_cascade = 1;
    for (int c = 0; c < 2; c++) {
        rq.effects[c] = OCEAN_FX_HEIGHT;
        rq.cascade_cutoff_k[c] = kc[c][1];
    }
    assert_int_equal(ocean_evaluate(o, 3.25, &rq, both), OCEAN_OK);
    ocean_frame_info info;
    ocean_frame_get_info(both, &info);
    assert_true(info.e_error == 0.0);
    for (int c = 0; c < 2; c++) {
        ocean_request r1;
        memset(&r1, 0, sizeof r1);
        r1.effects[c] = OCEAN_FX_HEIGHT;
        r1.cutoff_k = kc[c][1];
        r1.order = 6;
        r1.low_boost = 1;
        assert_int_equal(ocean_evaluate(o, 3.25, &r1, one), OCEAN_OK);
        const ocean_field *a = ocean_frame_field(both, c), *b = ocean_frame_field(one, c);
        assert_int_equal(a->n, b->n);
        assert_memory_equal(a->height, b->height, sizeof(float) * (size_t)a->n * a->n);
    }
    /* hostile input */
    rq.cascade_cutoff_k[1] = NAN;
    assert_int_equal(ocean_evaluate(o, 3.25, &rq, both), OCEAN_EINVAL);
    rq.cascade_cutoff_k[1] = kc[1][1];
    rq.redistribute = 1;
    assert_int_equal(ocean_evaluate(o, 3.25, &rq, both), OCEAN_EINVAL);
    ocean_frame_destroy(both);
    ocean_frame_destroy(one);
    ocean_destroy(o);
}

/* Spatial mean of a*b over a field's grid. */
static double mean2(const float *a, const float *b, int n)
{
    double s = 0;
    for (size_t i = 0; i < (size_t)n * n; i++) s += (double)a[i] * b[i];
    return s / ((double)n * n);
}

/* What a mip does not carry: nothing for mip 0, the whole cascade for
 * kc = 0 (its variance, as the spectrum statistics count it), more as the
 * cutoff falls; and the moments are those of the evaluated field (by
 * Parseval the spatial mean square of a slope is the sum of its modes'
 * energies: the finest cascade has enough modes that one draw sits within
 * a few per cent of the expectation). */
static void moments_of_what_mips_lack(void **state)
{
    (void)state;
    ocean *o = make(256, 3);
    ocean_spectrum_stats ss;
    ocean_get_spectrum_stats(o, &ss);
    for (int c = 0; c < 3; c++) {
        ocean_moments none, all;
        assert_int_equal(ocean_cascade_moments(o, c, INFINITY, 6, &none), OCEAN_OK);
        assert_true(none.var_h == 0 && none.mss_x == 0 && none.mss_z == 0);
        assert_int_equal(ocean_cascade_moments(o, c, 0.0, 6, &all), OCEAN_OK);
        assert_true(fabs(all.var_h - all.total_var_h) <= 1e-12 * all.total_var_h);
        assert_true(fabs(all.total_var_h - ss.cascade_variance[c]) <= 1e-6 * ss.cascade_variance[c]);
        assert_true(all.mss_x > 0 && all.mss_z > 0);
        double kc[12];
        int mips;
        assert_int_equal(ocean_cascade_mips(o, c, 6, 12, &mips, kc), OCEAN_OK);
        double prev = 0;
        for (int m = 1; m < mips; m++) {
            ocean_moments mo;
            assert_int_equal(ocean_cascade_moments(o, c, kc[m], 6, &mo), OCEAN_OK);
            assert_true(mo.mss_x + mo.mss_z >= prev);
            assert_true(mo.mss_x + mo.mss_z <= all.mss_x + all.mss_z);
            prev = mo.mss_x + mo.mss_z;
        }
    }
    /* the finest cascade's field: its slope moments are the expectation's */
    ocean_frame *f;
    assert_int_equal(ocean_frame_create(o, &f), OCEAN_OK);
    ocean_request rq;
    memset(&rq, 0, sizeof rq);
    rq.effects[2] = OCEAN_FX_NORMALS;
    rq.cutoff_k = INFINITY;
    rq.order = 6;
    rq.low_boost = 1;
    assert_int_equal(ocean_evaluate(o, 40.0, &rq, f), OCEAN_OK);
    const ocean_field *fd = ocean_frame_field(f, 2);
    ocean_moments all;
    assert_int_equal(ocean_cascade_moments(o, 2, 0.0, 6, &all), OCEAN_OK);
    double sx = mean2(fd->slope_x, fd->slope_x, fd->n), sz = mean2(fd->slope_z, fd->slope_z, fd->n);
    double sxz = mean2(fd->slope_x, fd->slope_z, fd->n);
    print_message("finest cascade: mss_x %.5f field %.5f, mss_z %.5f field %.5f, xz %.6f field %.6f\n",
                  all.mss_x, sx, all.mss_z, sz, all.mss_xz, sxz);
    assert_true(fabs(sx - all.mss_x) <= 0.05 * all.mss_x);
    assert_true(fabs(sz - all.mss_z) <= 0.05 * all.mss_z);
    assert_true(fabs(sxz - all.mss_xz) <= 0.05 * (all.mss_x + all.mss_z));
    /* hostile input */
    ocean_moments mo;
    assert_int_equal(ocean_cascade_moments(o, 3, 1.0, 6, &mo), OCEAN_EINVAL);
    assert_int_equal(ocean_cascade_moments(o, 0, NAN, 6, &mo), OCEAN_EINVAL);
    assert_int_equal(ocean_cascade_moments(o, 0, 1.0, 0, &mo), OCEAN_EINVAL);
    int mips;
    double kc[12];
    assert_int_equal(ocean_cascade_mips(o, 0, 6, 0, &mips, kc), OCEAN_EINVAL);
    ocean_frame_destroy(f);
    ocean_destroy(o);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(mips_have_their_grids),
        cmocka_unit_test(per_cascade_cutoffs),
        cmocka_unit_test(moments_of_what_mips_lack),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
