/* An independent reference for line-symbol bands (lib/scene/linesym.c): the
 * SPEC's definition evaluated point by point with a brute-force nearest
 * point of the polyline, for tests/test_linesym.c and tests/bench/styles.c. */
#ifndef RS_TESTS_BANDREF_H
#define RS_TESTS_BANDREF_H
#include "linesym.h"

#define BANDREF_MAX_POINTS 64

typedef struct bandref_line {
    const double *x, *y; /* local points (borrowed) */
    double s[BANDREF_MAX_POINTS];
    size_t n;
} bandref_line;

/* n <= BANDREF_MAX_POINTS points; arc lengths summed here. */
void bandref_init(bandref_line *L, const double *x, const double *y, size_t n);
/* Is (x, y) in band b? q = nearest point of the polyline, s its arc length,
 * t the signed offset (+ left of travel); at a vertex q the offset is the
 * distance, signed by the side of the bend; beyond the first or last point:
 * no band (flat ends). */
int bandref_in(const bandref_line *L, const rs__band *b, double x, double y);
/* Fraction of pixel (px, py) of side pix in the band: n x n point samples. */
double bandref_cover(const bandref_line *L, const rs__band *b, double pix, uint32_t px, uint32_t py, int n);
/* Distance from (x, y) to the polyline (to skip pixels far from a band). */
double bandref_dist(const bandref_line *L, double x, double y);
#endif
