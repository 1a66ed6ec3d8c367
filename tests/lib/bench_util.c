/*
 * bench_util.c - clock, CPU time, median and quick-mode switch for the
 * benchmarks.
 */
#include "bench_util.h"

#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

double bench_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

double bench_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int bench_quick(void)
{
    const char *a = getenv("BENCH_QUICK"), *b = getenv("OCEAN_BENCH_QUICK");
    return (a && *a && strcmp(a, "0") != 0) || (b && *b && strcmp(b, "0") != 0);
}

double bench_cpu_s(int who)
{
    struct rusage u;
    getrusage(who, &u);
    return (double)u.ru_utime.tv_sec + 1e-6 * (double)u.ru_utime.tv_usec + (double)u.ru_stime.tv_sec +
           1e-6 * (double)u.ru_stime.tv_usec;
}

double bench_daemon_cpu_s(void) { return bench_cpu_s(RUSAGE_SELF) - bench_cpu_s(RUSAGE_THREAD); }
