/* Timing helpers shared by the benchmarks. */
#ifndef RS_TESTS_TIMING_H
#define RS_TESTS_TIMING_H
/* Monotonic clock in milliseconds. */
double tm_now_ms(void);
/* This thread's CPU time in milliseconds (one-thread benchmarks on a
 * shared machine, where the wall clock mostly measures the others). */
double tm_thread_cpu_ms(void);
/* Median of n values (sorts v in place; mean of the middle two for even n). */
double tm_median(double *v, int n);
#endif
