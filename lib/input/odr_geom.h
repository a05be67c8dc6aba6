/* Private: ASAM OpenDRIVE reference-line geometry (issue 32, docs/opendrive.md).
 *
 * The planView of an OpenDRIVE road is a chain of geometry records, each
 * starting at (x, y) with heading hdg at arc length s and running `length`
 * metres: a line, an arc (constant curvature), a spiral (curvature linear in
 * s: a clothoid piece, evaluated through Fresnel integrals), a poly3 (local
 * v = a + b u + c u^2 + d u^3, u along hdg; s is the curve's arc length, so
 * u(s) is found by inverting the arc-length integral) or a paramPoly3 (u(p),
 * v(p) cubic in p, p in [0, length] for pRange arcLength or [0, 1] for
 * normalized, taken as the file gives it). Lateral offsets (t, + to the
 * left of the direction of travel, OpenDRIVE's convention as ours) are
 * applied along the unit normal of the evaluated heading.
 *
 * Pure functions of their arguments: no allocation except in
 * rs__odr_sample, which uses the caller's context. */
#ifndef RS_ODR_GEOM_H
#define RS_ODR_GEOM_H
#include "internal.h"

typedef enum rs__odr_kind {
    RS__ODR_LINE = 0,
    RS__ODR_ARC,
    RS__ODR_SPIRAL,
    RS__ODR_POLY3,
    RS__ODR_PARAMPOLY3
} rs__odr_kind;

typedef struct rs__odr_geom {
    rs__odr_kind kind;
    double s, x, y, hdg, length;  /* start: arc length, position, heading (rad); length > 0 */
    double curv;                  /* arc */
    double curv_start, curv_end;  /* spiral */
    double a, b, c, d;            /* poly3 */
    double au, bu, cu, du, av, bv, cv, dv; /* paramPoly3 */
    int normalized;               /* paramPoly3: pRange normalized (p = ds / length) */
} rs__odr_geom;

/* Fresnel integrals C(x) = int_0^x cos(pi t^2 / 2) dt, S(x) likewise with
 * sin; any finite x (odd functions), absolute error near 1e-15. */
void rs__fresnel(double x, double *c, double *s);

/* Position and heading at ds metres into g (ds clamped to [0, length]). */
void rs__odr_geom_eval(const rs__odr_geom *g, double ds, double *x, double *y, double *hdg);

/* Checks one record: finite numbers, length > 0, |curvatures| and
 * coefficients within what double evaluation keeps exact enough. 1 if ok. */
int rs__odr_geom_valid(const rs__odr_geom *g);

/* A road's reference line: records sorted by s, contiguous. */
typedef struct rs__odr_line {
    const rs__odr_geom *g;
    size_t n;
} rs__odr_line;

/* Position and heading at arc length s along the line (s clamped to the
 * line's range; the record is the last one starting at or before s). */
void rs__odr_line_eval(const rs__odr_line *L, double s, double *x, double *y, double *hdg);

/* Lateral offset function t(s) for sampling: returns t at s. */
typedef double (*rs__odr_offset_fn)(double s, void *user);

/* Samples the curve p(s) + t(s) n(s) over [s0, s1] so that no point of the
 * true curve between two consecutive samples is farther than `tol` metres
 * from their chord (checked at the quarter points of each interval and
 * refined), and every record boundary inside (s0, s1) is a sample. The
 * caller owns *xys (3 doubles per sample: x, y, s; rs__free). At most
 * max_points samples (RS_ERR_LIMIT beyond). */
rs_result rs__odr_sample(rs_ctx *ctx, const rs__odr_line *L, double s0, double s1, rs__odr_offset_fn t, void *user,
                         double tol, size_t max_points, double **xys, size_t *n);
#endif
