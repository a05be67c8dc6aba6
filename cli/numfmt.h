/* Number text for large text outputs (the OBJ writer): the same bytes as
 * the C library's printf in the "C" locale, several times faster.
 * tests/tools/numfmt_check.c compares both on millions of values. */
#ifndef RS_CLI_NUMFMT_H
#define RS_CLI_NUMFMT_H
#include <stddef.h>

/* Longest text cli_fmt_g writes, without a terminator ("-1.2345678901234567e-308"). */
#define CLI_FMT_G_MAX 32

/* What snprintf(out, CLI_FMT_G_MAX, "%.*g", prec, v) writes, for prec 1 to
 * 17; out gets no terminator. Returns the length. */
size_t cli_fmt_g(char *out, double v, int prec);

/* Decimal digits of v into out (at most 20), no terminator; the length. */
size_t cli_fmt_u(char *out, unsigned long v);

#endif
