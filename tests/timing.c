#include "timing.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

double tm_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

double tm_thread_cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec / 1e6;
}

static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

double tm_median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_d);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

int tm_open_section(const char *dir, const char *name, FILE **md, FILE **csv)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s.md", dir, name);
    *md = fopen(path, "w");
    snprintf(path, sizeof path, "%s/%s.csv", dir, name);
    *csv = fopen(path, "w");
    if (*md && *csv) return 0;
    fprintf(stderr, "%s bench: cannot write to %s\n", name, dir);
    if (*md) fclose(*md);
    if (*csv) fclose(*csv);
    *md = *csv = NULL;
    return 1;
}

double tm_python_ms(const char *args)
{
    const char *py[2] = { "python3", "/usr/bin/python3" };
    for (int i = 0; i < 2; i++) {
        char cmd[4096];
        snprintf(cmd, sizeof cmd, "%s %s 2>/dev/null", py[i], args);
        FILE *p = popen(cmd, "r");
        if (!p) continue;
        double ms = -1;
        if (fscanf(p, "%lf", &ms) != 1) ms = -1;
        if (pclose(p) == 0 && ms >= 0) return ms;
    }
    return -1;
}
