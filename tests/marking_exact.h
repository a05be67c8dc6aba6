/* How exactly a marking covers its rectangle (issue 25): a hard-edged
 * sprite (every texel opaque white) placed with a `mark` on a straight
 * road, painted by the markings stage, against the exact area of each
 * pixel inside the rotated rectangle (polygon clipping, not sampling).
 * Shared by tests/test_markings.c and tests/bench/markings.c. */
#ifndef RS_TESTS_MARKING_EXACT_H
#define RS_TESTS_MARKING_EXACT_H
#include "roadsplat.h"

typedef struct me_stats {
    double mean;     /* mean |painted - exact| over pixels where either is > 0 */
    double p99;      /* its 99th percentile */
    double area;     /* (painted area - L W) / (L W) */
    double centroid; /* distance of the painted centroid from the exact coverage's, pixels */
    long pixels;     /* pixels where either is > 0 */
} me_stats;

typedef struct me_case {
    double angle;         /* road direction, degrees from +x */
    double ox, oy;        /* the road moved by this many pixels */
    double pix;           /* pixel, metres (1 / texels per DEM cell of 1 m) */
    double length, width; /* the sprite, metres */
    uint32_t tw, th;      /* its texels across, along */
    int shape;            /* 0: every texel opaque; 1: a hard-edged arrow (a triangular head of
                           * texel steps over a shaft half as wide), opaque texels or none */
} me_case;

/* Whether texel (i, j) (across, along; row 0 the sprite's front) of a tw x
 * th sprite of shape `shape` is opaque. */
int me_opaque(int shape, uint32_t tw, uint32_t th, uint32_t i, uint32_t j);

/* Paint case c and measure it; 0 on success. */
int me_measure(rs_ctx *ctx, const me_case *c, me_stats *out);

/* Exact area of the unit pixel [x0, x0 + p] x [y0, y0 + p] inside the
 * rectangle with centre (cx, cy), unit axis (dx, dy) (half length hl along
 * it, half width hw across). */
double me_pixel_area(double x0, double y0, double p, double cx, double cy, double dx, double dy, double hl,
                     double hw);
#endif
