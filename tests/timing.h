/* Timing and output helpers shared by the benchmarks. */
#ifndef RS_TESTS_TIMING_H
#define RS_TESTS_TIMING_H
#include <stdio.h>
/* Monotonic clock in milliseconds. */
double tm_now_ms(void);
/* This thread's CPU time in milliseconds (one-thread benchmarks on a
 * shared machine, where the wall clock mostly measures the others). */
double tm_thread_cpu_ms(void);
/* Median of n values (sorts v in place; mean of the middle two for even n). */
double tm_median(double *v, int n);
/* A benchmark's section, DIR/NAME.md and DIR/NAME.csv, opened for writing:
 * 0, or 1 (with a line on stderr, neither left open). */
int tm_open_section(const char *dir, const char *name, FILE **md, FILE **csv);
/* Run `python3 ARGS` (then /usr/bin/python3: the first on PATH may lack
 * the module, e.g. under pyenv) with stderr dropped and read the number
 * its output starts with: a peer's time in ms from a Cairo script; < 0
 * when neither ran or printed one. */
double tm_python_ms(const char *args);
#endif
