/* Private: one road's geometry in the local frame (docs/design.md "Frames"),
 * the one place its points, arc lengths and box are made: the road field,
 * the road grid, the network, the line symbols, the markings, the automatic
 * markings and the GPU export all read a road through these (issue 27: they
 * were five copies of the same loop). */
#ifndef RS_ROAD_LOCAL_H
#define RS_ROAD_LOCAL_H
#include "internal.h"

#include <float.h>
#include <math.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

/* The local frame of a map: its origin (world coordinates of DEM sample
 * (0, 0)) and the quantum that local coordinates are rounded to
 * (rs__local_quantum of its cell size). */
typedef struct rs__local_frame {
    double ox, oy, per_unit;
} rs__local_frame;

static inline rs__local_frame rs__local_frame_of(double origin_x, double origin_y, double cell_size)
{
    rs__local_frame F;
    F.ox = origin_x;
    F.oy = origin_y;
    F.per_unit = rs__local_quantum(cell_size);
    return F;
}

/* Point k of a road's world points xy (x, y pairs) in local metres. */
static inline void rs__local_point(const rs__local_frame *F, const double *xy, size_t k, double *x, double *y)
{
    *x = rs__local_coord(xy[2 * k], F->ox, F->per_unit);
    *y = rs__local_coord(xy[2 * k + 1], F->oy, F->per_unit);
}

/* The length of segment a-b as every part measures it: twice the length of
 * the halves (the difference of two finite coordinates cannot overflow
 * then). */
static inline double rs__arc_len(double ax, double ay, double bx, double by)
{
    return 2 * hypot(0.5 * bx - 0.5 * ax, 0.5 * by - 0.5 * ay);
}

/* Arc lengths up to 2^32 m keep a micrometre in a double; past that a
 * mark placed by one (a zebra on a road from 10^33 m) would land anywhere
 * along its stretch, so marks are placed only where the arc lengths they
 * use stay below this (docs/roadfield.md "Far roads"). */
#define RS__ARC_MEASURED 4294967296.0

/* Segment A-B with one end near the map (a_near: A; else B) and the other
 * far (10^20 m away, say), cut to the disc of radius rad around (cx, cy)
 * along the line from the near end (unit direction (ux, uy) from A to B,
 * len = |B - A|, huge, possibly DBL_MAX): the line from the near end
 * keeps its digits where it meets the map, while the line from the
 * disc's centre (rs__clip_far for two far ends) carries the far end's
 * rounding, metres at 10^20 m, and misses the near end. The near end
 * stays exactly where it is when inside the disc. *along: the new A's
 * distance from the old one. Returns 0 when nothing reaches the disc. */
static inline int rs__cut_far_end(double *ax, double *ay, double *bx, double *by, int a_near, double ux, double uy,
                                  double len, double cx, double cy, double rad, double *along)
{
    double sg = a_near ? 1 : -1, nx = a_near ? *ax : *bx, ny = a_near ? *ay : *by, dx = sg * ux, dy = sg * uy;
    double ex = cx - nx, ey = cy - ny, tc = ex * dx + ey * dy, dist = -dy * ex + dx * ey;
    if (!(fabs(dist) <= rad)) return 0;
    double t0 = tc - rad > 0 ? tc - rad : 0, t1 = tc + rad < len ? tc + rad : len;
    if (!(t0 <= t1)) return 0;
    double px = nx + t1 * dx, py = ny + t1 * dy; /* the far end's cut */
    if (t0 > 0) nx += t0 * dx, ny += t0 * dy;
    if (a_near) {
        *along = t0;
        *ax = nx, *ay = ny, *bx = px, *by = py;
    } else {
        *along = len - t1;
        *ax = px, *ay = py, *bx = nx, *by = ny;
    }
    return 1;
}

/* s + len, at most DBL_MAX (a road over 1.8e308 m long has no finite arc
 * length: s saturates instead of becoming inf). */
static inline double rs__arc_add(double s, double len)
{
    s += len;
    return s <= DBL_MAX ? s : DBL_MAX;
}

/* Road ri's points from local point *m on: a point equal to the one before
 * it is left out (also the first, when it equals point *m - 1: a stroke's
 * records one after the other), s running on from s[*m - 1] (0 for the
 * first point); rev: the road's points last to first. Point i goes to
 * x[i * stride], y[i * stride] (stride in doubles: separate arrays or an
 * array of (x, y) pairs) and s[i]; the arrays hold *m + the road's point
 * count. *m becomes the count. */
void rs__road_local_walk(const rs_roads *roads, size_t ri, int rev, const rs__local_frame *F, double *x, double *y,
                         size_t stride, double *s, size_t *m);

/* One road in local coordinates: distinct consecutive points, their arc
 * lengths and the box of the points (x0 > x1 when there are none). */
typedef struct rs__road_local {
    double *x, *y, *s;
    size_t n;
    double x0, y0, x1, y1;
} rs__road_local;
/* Road ri over dem's frame into *out (the caller's: rs__road_local_free). */
rs_result rs__road_local_get(rs_ctx *ctx, const rs_roads *roads, size_t ri, const rs_dem *dem, rs__road_local *out);
void rs__road_local_free(rs_ctx *ctx, rs__road_local *r);
/* Every road of roads into *rl (rs_roads_count entries), their points in
 * one block *block (both the caller's: rs__free each; not
 * rs__road_local_free). One allocation instead of three per road: freeing
 * 3 x 10^5 small blocks cost ~30 ms of allocator consolidation on the
 * 10^5-road city, all of it after a cancel. Ticks per road;
 * RS_ERR_CANCELLED or RS_ERR_NOMEM (nothing held). */
rs_result rs__road_local_all(rs_ctx *ctx, const rs_roads *roads, const rs_dem *dem, rs__road_local **rl,
                             double **block);

/* fmin and fmax inline, as glibc's x86-64 ones answer (minsd / maxsd: the
 * second argument on a tie, the other one when one is NaN): the library
 * calls were 3 % of the styled city's line-symbol build. */
static inline double rs__fmin(double a, double b) { return a < b || b != b ? a : b; }
static inline double rs__fmax(double a, double b) { return a > b || b != b ? a : b; }

/* Ask for the cache line at p ahead of its read (a hint; no effect on
 * results): the builds that read by id or list order at random places in
 * arrays of megabytes (the road field's lists, the network's gathers). */
static inline void rs__prefetch(const void *p)
{
#if defined(__SSE2__)
    _mm_prefetch((const char *)p, _MM_HINT_T0);
#else
    (void)p;
#endif
}

#endif
