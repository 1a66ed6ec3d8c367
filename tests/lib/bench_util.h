/*
 * bench_util.h - what every benchmark program needs: a monotonic clock,
 * medians, and the BENCH_QUICK switch (linked into tests and benchmarks).
 */
#ifndef OCEAN_BENCH_UTIL_H
#define OCEAN_BENCH_UTIL_H

/* Monotonic wall clock, milliseconds. */
double bench_now_ms(void);
/* CPU seconds (user + system) of RUSAGE_SELF or RUSAGE_THREAD. */
double bench_cpu_s(int who);
/* An in-process daemon's CPU seconds: the process's less the calling
 * thread's (the benchmark's own client). */
double bench_daemon_cpu_s(void);

/* Median of v[0..n) (sorts v in place); n >= 1. */
double bench_median(double *v, int n);

/* 1 when BENCH_QUICK (or the older OCEAN_BENCH_QUICK) is set and not "0":
 * every benchmark then shortens its sweeps. */
int bench_quick(void);

#endif
