/*
 * bench_util.h - what every benchmark program needs: a monotonic clock,
 * medians, and the BENCH_QUICK switch (linked into tests and benchmarks).
 */
#ifndef OCEAN_BENCH_UTIL_H
#define OCEAN_BENCH_UTIL_H

/* Monotonic wall clock, milliseconds. */
double bench_now_ms(void);

/* Median of v[0..n) (sorts v in place); n >= 1. */
double bench_median(double *v, int n);

/* 1 when BENCH_QUICK (or the older OCEAN_BENCH_QUICK) is set and not "0":
 * every benchmark then shortens its sweeps. */
int bench_quick(void);

#endif
