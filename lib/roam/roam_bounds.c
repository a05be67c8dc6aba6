/* ROAM error bounds: the largest vertical distance of a triangle's samples
 * from its plane, by scan or in closed form for the finest levels, and the
 * per-patch cache they are kept in (docs/roam.md, "Error bound"). */
#include "roam.h"

#include <float.h>
#include <stddef.h>
#include <math.h>
#include <string.h>

#define ERR_OUTSIDE (-1.0f)       /* node entirely off the map: never split for error */

/* max over t in [0, n) of |r[t] - (p0 + g t)|: four independent lanes so the
 * compiler can keep them in vector registers; t is exact in double. Short
 * rows (most rows of the triangles refinement tests: blocks have rows of 1
 * to 5 samples) take a plain loop; each sample's term is the same double
 * either way, so the max is too. */
static inline double row_max(const float *r, int n, double p0, double g)
{
    double m0 = 0.0, m1 = 0.0, m2 = 0.0, m3 = 0.0, t = 0.0;
    int i = 0;
    if (n < 8) {
        for (; i < n; i++) {
            double d0 = fabs((double)r[i] - (p0 + g * (double)i));
            m0 = d0 > m0 ? d0 : m0;
        }
        return m0;
    }
    for (; i + 4 <= n; i += 4, t += 4.0) {
        double d0 = fabs((double)r[i] - (p0 + g * t));
        double d1 = fabs((double)r[i + 1] - (p0 + g * (t + 1.0)));
        double d2 = fabs((double)r[i + 2] - (p0 + g * (t + 2.0)));
        double d3 = fabs((double)r[i + 3] - (p0 + g * (t + 3.0)));
        m0 = d0 > m0 ? d0 : m0;
        m1 = d1 > m1 ? d1 : m1;
        m2 = d2 > m2 ? d2 : m2;
        m3 = d3 > m3 ? d3 : m3;
    }
    for (; i < n; i++, t += 1.0) {
        double d0 = fabs((double)r[i] - (p0 + g * t));
        m0 = d0 > m0 ? d0 : m0;
    }
    if (m1 > m0) m0 = m1;
    if (m3 > m2) m2 = m3;
    return m0 > m2 ? m0 : m2;
}

/* tri_max_error for a block (legs 4 on the axes, 15 samples; most of the
 * triangles refinement scans): the same rows and the same terms, with the
 * loops' bounds known so the compiler lays them out flat. */
static double block_max_error(const float *z, size_t W, int ax, int ay, int hx, int vy, double za, double gx,
                              double gy)
{
    /* g * t of row_max, t = 0..4 */
    const double g0 = gx * 0.0, g1 = gx * 1.0, g2 = gx * 2.0, g3 = gx * 3.0, g4 = gx * 4.0;
    const ptrdiff_t step = vy > 0 ? (ptrdiff_t)W : -(ptrdiff_t)W;
    const float *r = z + (size_t)ay * W + (size_t)(hx > 0 ? ax : ax - 4);
    const int left = hx < 0, down = vy > 0;
    double m = 0.0, p0;
    const float *row;
#define TERM(i) do { double d_ = fabs((double)row[i] - (p0 + g##i)); m = d_ > m ? d_ : m; } while (0)
    /* row k: 5 - k samples from the apex column towards the hypotenuse */
#define ROW(k) row = r + (k) * step + (left ? (k) : 0); \
    p0 = za + gx * (double)(left ? (k) - 4 : 0) + gy * (double)(down ? (k) : -(k))
    ROW(0); TERM(0); TERM(1); TERM(2); TERM(3); TERM(4);
    ROW(1); TERM(0); TERM(1); TERM(2); TERM(3);
    ROW(2); TERM(0); TERM(1); TERM(2);
    ROW(3); TERM(0); TERM(1);
    ROW(4); TERM(0);
#undef ROW
#undef TERM
    return m;
}

/* Max |z - plane| over every sample inside (or on) the triangle, the plane
 * through the three corner heights, in double. Bintree legs are either both
 * on the axes (even levels) or both diagonal (odd levels), so every row of
 * the triangle is one run of samples whose ends are exact integers: the
 * triangle is scanned row by row without divisions or edge tests.
 * With a finite `stop`, the scan returns as soon as the max exceeds it
 * (refinement only needs to know that), starting with the row through the
 * hypotenuse midpoint, the longest or the one most likely to exceed; every
 * row is computed the same way whatever the order, so a full scan gives
 * the same double. */
static double tri_max_error(const rs_roam *L, int ax, int ay, int bx, int by, int cx, int cy, double stop)
{
    const float *z = L->z;
    const size_t W = L->w;
    double za = z[(size_t)ay * W + (size_t)ax];
    double zb = z[(size_t)by * W + (size_t)bx];
    double zc = z[(size_t)cy * W + (size_t)cx];
    int p = bx - ax, q = by - ay; /* left leg; the right leg is (-q, p) */
    /* plane gradient; |leg|^2 is a power of two, so inv is exact */
    double inv = 1.0 / (double)(p * p + q * q);
    double db = zb - za, dc = zc - za;
    double gx = (db * p - dc * q) * inv, gy = (db * q + dc * p) * inv;
    double m = 0.0, d;
    int early = stop < INFINITY;
    if (p * p + q * q == 16) /* a block */
        return block_max_error(z, W, ax, ay, q == 0 ? p : -q, q == 0 ? p : q, za, gx, gy);
    if (p == 0 || q == 0) {
        /* right angle at the apex, legs on the axes: row k from the apex
         * runs from the apex column s - k samples along the horizontal leg */
        int hx = q == 0 ? p : -q, vy = q == 0 ? p : q;
        int s = hx > 0 ? hx : -hx, sy = vy > 0 ? 1 : -1;
        int first = early ? s / 2 : -1;
        for (int j = early ? -1 : 0; j <= s; j++) {
            int k = j < 0 ? first : j;
            if (j == first) continue;
            int y = ay + sy * k, n = s - k + 1;
            int lo = hx > 0 ? ax : ax - (s - k);
            double p0 = za + gx * (double)(lo - ax) + gy * (double)(y - ay);
            d = row_max(z + (size_t)y * W + (size_t)lo, n, p0, gx);
            if (d > m && (m = d) > stop) return m;
        }
    } else if (p == q) {
        /* hypotenuse b-c horizontal; rows from it towards the apex shrink by
         * one at each end (row 0, the hypotenuse, goes first anyway) */
        int h = p > 0 ? p : -p, sy = q > 0 ? -1 : 1, yh = ay + q;
        int x0 = bx < cx ? bx : cx;
        for (int k = 0; k <= h; k++) {
            int y = yh + sy * k, lo = x0 + k, n = 2 * (h - k) + 1;
            double p0 = za + gx * (double)(lo - ax) + gy * (double)(y - ay);
            d = row_max(z + (size_t)y * W + (size_t)lo, n, p0, gx);
            if (d > m && (m = d) > stop) return m;
        }
    } else {
        /* hypotenuse vertical at x = ax + p; row y spans h - |y - ay| samples
         * from it towards the apex */
        int h = p > 0 ? p : -p, xh = ax + p;
        for (int j = ay - h - (early ? 1 : 0); j <= ay + h; j++) {
            int y = j < ay - h ? ay : j;
            if (early && j == ay) continue;
            int dy = y > ay ? y - ay : ay - y, len = h - dy;
            int lo = p > 0 ? xh - len : xh;
            double p0 = za + gx * (double)(lo - ax) + gy * (double)(y - ay);
            d = row_max(z + (size_t)y * W + (size_t)lo, len + 1, p0, gx);
            if (d > m && (m = d) > stop) return m;
        }
    }
    return m;
}

/* Round up to float so the stored bound is never below the double one
 * (v >= 0: the next float up is the next bit pattern). */
static float round_up_float(double v)
{
    float f = (float)v;
    if ((double)f < v && f < FLT_MAX) {
        uint32_t u;
        memcpy(&u, &f, sizeof u);
        u++;
        memcpy(&f, &u, sizeof f);
    }
    return f;
}

/* Bound of a triangle whose only non-corner sample is the midpoint of its
 * hypotenuse (x0, y0)-(x1, y1): the legs-sqrt(2) level. */
static float midpoint_err(const rs_roam *L, int x0, int y0, int x1, int y1)
{
    const float *z = L->z;
    size_t W = L->w;
    double d = (double)z[(size_t)((y0 + y1) / 2) * W + (size_t)((x0 + x1) / 2)]
               - 0.5 * ((double)z[(size_t)y0 * W + (size_t)x0] + (double)z[(size_t)y1 * W + (size_t)x1]);
    return round_up_float(fabs(d));
}

void rs__roam_load_s_terms(const rs_roam *L, s_terms *o)
{
    const float *z = L->z;
    const size_t W = L->w;
    const tri *t = &o->S;
    /* The nine samples by index: every one is an integer point, and the
     * index y * W + x is affine, so midpoints are half sums of indices (the
     * sums are even) and the quarter points of the hypotenuse (4 samples
     * long on an axis) are a quarter of its index difference away. */
    const size_t ia = (size_t)t->ay * W + (size_t)t->ax, ib = (size_t)t->by * W + (size_t)t->bx;
    const size_t ic = (size_t)t->cy * W + (size_t)t->cx, im = (ib + ic) / 2;
    const ptrdiff_t q = ((ptrdiff_t)ic - (ptrdiff_t)ib) / 4;
    double za = z[ia], zb = z[ib], zc = z[ic], zm = z[im];
    double zla = z[(ia + ib) / 2], zlc = z[(ia + ic) / 2];
    double zh1 = z[(ptrdiff_t)ib + q], zh3 = z[(ptrdiff_t)ic - q];
    double zi = z[(ia + im) / 2];
    double la = fabs(zla - 0.5 * (za + zb)), lc = fabs(zlc - 0.5 * (za + zc));
    double sm = fabs(zm - 0.5 * (zb + zc));
    double sh1 = fabs(zh1 - (0.75 * zb + 0.25 * zc)), sh3 = fabs(zh3 - (0.25 * zb + 0.75 * zc));
    double si = fabs(zi - 0.5 * (za + 0.5 * (zb + zc)));
    double i = fabs(zi - 0.5 * (zm + za)), h1 = fabs(zh1 - 0.5 * (zm + zb)), h3 = fabs(zh3 - 0.5 * (zm + zc));
    double e = la;
    if (lc > e) e = lc;
    if (sm > e) e = sm;
    if (sh1 > e) e = sh1;
    if (sh3 > e) e = sh3;
    if (si > e) e = si;
    o->s = round_up_float(e);
    o->q[0][0] = round_up_float(i); o->q[0][1] = round_up_float(h1);
    o->q[1][0] = round_up_float(h3); o->q[1][1] = o->q[0][0];
    o->r[0] = round_up_float(la > h1 ? (la > i ? la : i) : (h1 > i ? h1 : i));
    o->r[1] = round_up_float(lc > h3 ? (lc > i ? lc : i) : (h3 > i ? h3 : i));
    o->have = 1;
}

/* Error bound of a triangle wholly on the map (DEM units). The three
 * finest levels with samples inside have closed forms: legs sqrt 2 (the
 * base midpoint), legs 2 on the axes (three edge midpoints), legs 2 sqrt 2
 * (two leg midpoints, three hypotenuse points, and the midpoint of apex and
 * base midpoint). Cell halves have no sample inside. */
float rs__roam_on_map_err(const rs_roam *L, const tri *t)
{
    const float *z = L->z;
    const size_t W = L->w;
    int ax = t->ax, ay = t->ay, bx = t->bx, by = t->by, cx = t->cx, cy = t->cy;
    int p = bx - ax, q = by - ay, l2 = p * p + q * q;
#define Z(x, y) ((double)z[(size_t)(y) * W + (size_t)(x)])
    if (l2 == 1) return 0.0f;
    if (l2 == 2) return midpoint_err(L, bx, by, cx, cy);
    if (l2 > 8) return round_up_float(tri_max_error(L, ax, ay, bx, by, cx, cy, INFINITY));
    if (l2 == 8) {
        s_terms st;
        st.S = *t;
        rs__roam_load_s_terms(L, &st);
        return st.s;
    }
    double za = Z(ax, ay), zb = Z(bx, by), zc = Z(cx, cy), d, m;
    m = fabs(Z((ax + bx) / 2, (ay + by) / 2) - 0.5 * (za + zb));
    d = fabs(Z((ax + cx) / 2, (ay + cy) / 2) - 0.5 * (za + zc)); if (d > m) m = d;
    d = fabs(Z((bx + cx) / 2, (by + cy) / 2) - 0.5 * (zb + zc)); if (d > m) m = d;
#undef Z
    return round_up_float(m);
}

/* Error bound of a triangle (DEM units): ERR_OUTSIDE off the map, +inf
 * when it straddles the map edge. */
float rs__roam_compute_err(const rs_roam *L, const tri *t)
{
    int c = tri_class(L, t);
    if (c == NODE_OUTSIDE) return ERR_OUTSIDE;
    if (c == NODE_STRADDLES) return INFINITY;
    return rs__roam_on_map_err(L, t);
}

/* Cache slot of heap index hh in patch `patch`: indices below epp / 2, the
 * levels above the R level (legs 2 on the axes). The R level (three samples
 * besides the corners) and the level below it (one) are cheaper to
 * recompute than to cache. */
static uint32_t slot_of(const rs_roam *L, uint32_t patch, uint32_t hh)
{
    uint32_t half = (uint32_t)(L->epp / 2);
    return hh < half ? patch * half + hh : NIL;
}

uint32_t rs__roam_err_slot(const rs_roam *L, const roam_node *n)
{
    if (n->e == NIL) return NIL;
    return slot_of(L, n->e >> L->elog, n->e & (uint32_t)(L->epp - 1));
}

/* Slot of implicit position pos of block node n: the heap index continues
 * below the block's (h -> 2h, 2h + 1). */
uint32_t rs__roam_imp_slot(const rs_roam *L, const roam_node *n, uint32_t pos)
{
    uint32_t d = pos_depth(pos);
    uint32_t hh = ((n->e & (uint32_t)(L->epp - 1)) << d) + pos - (1u << d);
    return slot_of(L, n->e >> L->elog, hh);
}

/* Error bound (DEM units) of triangle t with cache slot `slot` (NIL: not
 * cached), computed on first use: most deep nodes are never asked for at a
 * large threshold. */
float rs__roam_slot_err(rs_roam *L, uint32_t slot, const tri *t)
{
    if (slot == NIL) return rs__roam_compute_err(L, t);
    float v = err_get(L, slot);
    if (v != v) {
        v = rs__roam_compute_err(L, t);
        err_put(L, slot, v);
        L->err_empty = 0;
    }
    return v;
}

/* Error bound of an explicit node; cell halves have none. */
float rs__roam_node_err(rs_roam *L, const roam_node *n, const tri *t)
{
    if (n->e == NIL) return 0.0f;
    return rs__roam_slot_err(L, rs__roam_err_slot(L, n), t);
}

/* Refinement's test in error mode: is the bound of t (cache slot `slot`)
 * above max_error (metres)? The same answer as comparing the exact bound,
 * but a scan that finds a sample above L->err_stop returns there: the
 * triangle is split and its bound stays uncomputed (NaN) until something
 * asks for it. On the 1025^2 fractal at E = 2 most scanned samples lie in
 * triangles that are split. */
int rs__roam_err_above(rs_roam *L, uint32_t slot, const tri *t, double max_error)
{
    /* nothing cached yet: no need to wait for the slot's cache line */
    float v = slot == NIL || L->err_empty ? NAN : err_get(L, slot);
    if (v != v) {
        int p = t->bx - t->ax, q = t->by - t->ay;
        if (p * p + q * q > 8 && tri_class(L, t) == NODE_ON) {
            double m = tri_max_error(L, t->ax, t->ay, t->bx, t->by, t->cx, t->cy, L->err_stop);
            if (m > L->err_stop) return 1;
            v = round_up_float(m);
        } else v = rs__roam_compute_err(L, t);
        if (slot != NIL) err_put(L, slot, v);
    }
    return v == INFINITY || (v > 0.0f && (double)v * L->zs > max_error);
}

/* The early exit of rs__roam_err_above for max_error: the largest double s
 * such that every m > s rounds up to a float bound v with v * z_scale >
 * max_error, and no m <= s does. With f the smallest float for which
 * (double)f * zs > max_error, s is the float just below f (no float lies
 * between, and rounding up is monotone). +inf when no finite bound is
 * above max_error. */
double rs__roam_err_stop(double max_error, double zs)
{
    uint32_t lo = 1, hi = 0x7F7FFFFFu; /* smallest positive .. FLT_MAX */
    float f;
    memcpy(&f, &hi, sizeof f);
    if (!((double)f * zs > max_error)) return INFINITY;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        memcpy(&f, &mid, sizeof f);
        if ((double)f * zs > max_error) hi = mid; else lo = mid + 1;
    }
    lo--; /* the float below f (0 when f is the smallest subnormal) */
    memcpy(&f, &lo, sizeof f);
    return (double)f;
}
