/* OpenDRIVE lanes, road marks and marking objects to road text (issue 32,
 * docs/opendrive.md; lib/input/odr_lanes.h).
 *
 * The renderer draws a road record as a band of constant width round a
 * polyline, and its style's lines at constant offsets from that polyline.
 * OpenDRIVE lane boundaries move along s (laneOffset, lane widths as
 * cubics), so each thing is its own record that follows its own curve:
 *
 * - a surface band (a run of neighbouring lanes drawn alike: carriageway,
 *   sidewalk, bike lane) is its midline between its outer boundaries, cut
 *   into pieces over which the half width varies by at most 2 * TOL_W, each
 *   piece as wide as the middle of its range;
 * - every line of a road mark (both lines of a double mark, each line of
 *   an explicit <type>) is a record following the boundary at the line's
 *   offset; a solid line is one record, a broken line one record per dash,
 *   its ends placed at the road's s (on from s_offset + k * period), so the
 *   pattern runs on through lane sections and bends exactly;
 * - crosswalks are stripes along s, stop lines one line across.
 *
 * Every record carries junction_cuts=no: its surface cuts no other
 * record's lines and its lines are not cut (docs/linesym.md "Junctions"),
 * since OpenDRIVE says where each mark is. */
#include "odr_lanes.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define TOL_CURVE (0.25 * RS__ODR_TOL) /* chord error of every sampled curve */
#define TOL_W (0.5 * RS__ODR_TOL)      /* half-width error of a surface piece */

/* ---- text buffer ----------------------------------------------------------- */

typedef struct tbuf {
    rs_ctx *ctx;
    char *p;
    size_t n, cap;
    int failed;
} tbuf;

static void tb_put(tbuf *b, const char *s, size_t n)
{
    if (b->failed) return;
    if (b->n + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 4096;
        while (cap < b->n + n + 1) {
            if (cap > ((size_t)-1) / 2) {
                b->failed = 1;
                return;
            }
            cap *= 2;
        }
        char *q = rs__realloc(b->ctx, b->p, cap);
        if (!q) {
            b->failed = 1;
            return;
        }
        b->p = q;
        b->cap = cap;
    }
    memcpy(b->p + b->n, s, n);
    b->n += n;
    b->p[b->n] = '\0';
}

static void tb_printf(tbuf *b, const char *fmt, ...) RS__PRINTF(2, 3);
static void tb_printf(tbuf *b, const char *fmt, ...)
{
    char tmp[512];
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (k < 0 || (size_t)k >= sizeof tmp) {
        b->failed = 1;
        return;
    }
    tb_put(b, tmp, (size_t)k);
}

/* A road-text quoted string: \" and \\ escaped, control bytes as '?'. */
static void tb_quoted(tbuf *b, const char *s)
{
    tb_put(b, "\"", 1);
    for (; *s; s++) {
        char c = *s;
        if (c == '"' || c == '\\') tb_put(b, "\\", 1);
        if ((unsigned char)c < 0x20 || c == 0x7f) c = '?';
        tb_put(b, &c, 1);
    }
    tb_put(b, "\"", 1);
}

/* ---- lane geometry ------------------------------------------------------------ */

double rs__odr_poly_at(const rs__odr_poly *p, size_t n, double s)
{
    if (!n || s < p[0].s0) return n ? p[0].a : 0;
    size_t lo = 0, hi = n; /* last with s0 <= s */
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (p[mid].s0 <= s) lo = mid;
        else hi = mid;
    }
    double ds = s - p[lo].s0;
    return p[lo].a + ds * (p[lo].b + ds * (p[lo].c + ds * p[lo].d));
}

static double lane_width(const rs__odr_doc *doc, const rs__odr_lane *l, double s)
{
    return rs__odr_poly_at(doc->polys + l->width0, l->nwidth, s);
}

double rs__odr_boundary_t(const rs__odr_doc *doc, const rs__odr_road *road, const rs__odr_section *sec, int lane_id,
                          double s)
{
    double t = rs__odr_poly_at(doc->polys + road->off0, road->noff, s);
    const rs__odr_lane *L = doc->lanes + sec->lane0;
    /* sums in order from the centre out, so a boundary never depends on the
     * order of the lanes in the file */
    if (lane_id > 0) {
        for (int id = 1; id <= lane_id; id++)
            for (size_t k = 0; k < sec->nlane; k++)
                if (L[k].id == id) t += lane_width(doc, &L[k], s);
    } else if (lane_id < 0) {
        for (int id = -1; id >= lane_id; id--)
            for (size_t k = 0; k < sec->nlane; k++)
                if (L[k].id == id) t -= lane_width(doc, &L[k], s);
    }
    return t;
}

/* A curve to sample: t(s) = (boundary(a) + boundary(b)) / 2 + dt, or the
 * boundaries' half difference (half width). */
typedef struct curve {
    const rs__odr_doc *doc;
    const rs__odr_road *road;
    const rs__odr_section *sec;
    int left_b, right_b; /* boundary ids (INT32_MIN: the reference line, t = 0) */
    double dt;
} curve;

#define REF_LINE (-2147483647 - 1)

static double bnd(const curve *c, int b, double s)
{
    return b == REF_LINE ? 0 : rs__odr_boundary_t(c->doc, c->road, c->sec, b, s);
}

static double curve_t(double s, void *user)
{
    const curve *c = user;
    return 0.5 * (bnd(c, c->left_b, s) + bnd(c, c->right_b, s)) + c->dt;
}

static double curve_half(const curve *c, double s)
{
    return 0.5 * (bnd(c, c->left_b, s) - bnd(c, c->right_b, s));
}

static void line_point(const rs__odr_line *line, double s, double t, double *x, double *y)
{
    double h;
    rs__odr_line_eval(line, s, x, y, &h);
    *x -= t * sin(h);
    *y += t * cos(h);
}

/* Distance from (mx, my) to edge b along the normal of the unit tangent
 * (tx, ty), the edge point found by Newton from s: where the band's middle
 * drifts across the road (a lane opening on one side), the edge point
 * beside it is not the one at the same s. */
static double edge_across(const rs__odr_line *line, const curve *c, int b, double s, double mx, double my, double tx,
                          double ty)
{
    const double e = 1e-4;
    double q = s, ex, ey;
    for (int it = 0; it < 8; it++) { /* Newton on (E(q) - M) . tangent = 0 */
        double e0x, e0y, e1x, e1y;
        line_point(line, q, bnd(c, b, q), &ex, &ey);
        line_point(line, q - e, bnd(c, b, q - e), &e0x, &e0y);
        line_point(line, q + e, bnd(c, b, q + e), &e1x, &e1y);
        double f = (ex - mx) * tx + (ey - my) * ty, df = ((e1x - e0x) * tx + (e1y - e0y) * ty) / (2 * e);
        if (!(fabs(df) > 1e-9)) break;
        double step = f / df;
        if (step > 1) step = 1;
        if (step < -1) step = -1;
        q -= step;
        if (fabs(step) < 1e-10) break;
    }
    line_point(line, q, bnd(c, b, q), &ex, &ey);
    return (ex - mx) * -ty + (ey - my) * tx; /* + to the left */
}

/* The point of the band's middle at s that is as far from both edges
 * (across the middle's own direction), and that distance. */
static void medial(const rs__odr_line *line, const curve *c, double s, double *x, double *y, double *r)
{
    const double e = 1e-4;
    double mx, my, ax, ay, bx, by;
    line_point(line, s, curve_t(s, (void *)c), &mx, &my);
    line_point(line, s - e, curve_t(s - e, (void *)c), &ax, &ay);
    line_point(line, s + e, curve_t(s + e, (void *)c), &bx, &by);
    double tx = bx - ax, ty = by - ay, tn = hypot(tx, ty);
    *x = mx, *y = my;
    if (!(tn > 0)) {
        *r = fabs(curve_half(c, s));
        return;
    }
    tx /= tn, ty /= tn;
    double dl = edge_across(line, c, c->left_b, s, mx, my, tx, ty), dr = edge_across(line, c, c->right_b, s, mx, my, tx, ty);
    double shift = 0.5 * (dl + dr); /* dl > 0 > dr: the middle moves towards the farther edge */
    *x = mx - shift * ty, *y = my + shift * tx;
    *r = 0.5 * (dl - dr);
}

/* ---- conversion state ------------------------------------------------------------ */

typedef struct style_key {
    double width;
    uint32_t rgba;
} style_key;

typedef struct conv {
    rs_ctx *ctx;
    const rs__odr_doc *doc;
    tbuf roads, styles;
    style_key *sk;
    size_t nsk, capsk;
    size_t points, max_points;
    double ch, sh; /* header offset rotation */
    rs__odr_line line;
    const rs__odr_road *road;
    size_t sec_idx;   /* the lane section being drawn ((size_t)-1: objects), for record names */
    double *bp; /* breakpoints scratch */
    size_t capbp;
    double *rr; /* half width per sample of a surface band */
    size_t caprr;
    double *xs; /* sample scratch: x, y, s */
    size_t nxs, capxs;
} conv;

static rs_result nomem(conv *C)
{
    return rs__fail(C->ctx, RS_ERR_NOMEM, "%s: out of memory converting OpenDRIVE", C->doc->name);
}

/* Style name of a line of this width and colour (defined once). */
static rs_result line_style(conv *C, double width, uint32_t rgba, size_t *idx)
{
    for (size_t i = 0; i < C->nsk; i++)
        if (C->sk[i].width == width && C->sk[i].rgba == rgba) {
            *idx = i;
            return RS_OK;
        }
    if (C->nsk == C->capsk) {
        size_t cap = C->capsk ? 2 * C->capsk : 16;
        style_key *k = rs__realloc(C->ctx, C->sk, cap * sizeof *k);
        if (!k) return nomem(C);
        C->sk = k;
        C->capsk = cap;
    }
    C->sk[C->nsk].width = width;
    C->sk[C->nsk].rgba = rgba;
    tb_printf(&C->styles, "style odr-line-%zu\n  line 0 %.15g #%08X\nend\n", C->nsk, width, (unsigned)rgba);
    *idx = C->nsk++;
    return RS_OK;
}

/* Appends the sampled curve over [a, b] to C->xs (x, y, s per point),
 * sampled piecewise between the breakpoints where a lane polynomial or
 * laneOffset record starts. */
static rs_result sample_curve(conv *C, curve *cv, double a, double b)
{
    C->nxs = 0;
    size_t nbp = 0;
    const rs__odr_doc *doc = C->doc;
    /* breakpoints: laneOffset and width records inside (a, b) */
    size_t need = C->road->noff + 2;
    if (cv->sec) {
        const rs__odr_lane *L = doc->lanes + cv->sec->lane0;
        for (size_t k = 0; k < cv->sec->nlane; k++) need += L[k].nwidth;
    }
    if (need > C->capbp) {
        double *q = rs__realloc(C->ctx, C->bp, need * sizeof *q);
        if (!q) return nomem(C);
        C->bp = q;
        C->capbp = need;
    }
    C->bp[nbp++] = a;
    for (size_t k = 0; k < C->road->noff; k++) {
        double s = doc->polys[C->road->off0 + k].s0;
        if (s > a && s < b) C->bp[nbp++] = s;
    }
    if (cv->sec) {
        const rs__odr_lane *L = doc->lanes + cv->sec->lane0;
        for (size_t k = 0; k < cv->sec->nlane; k++)
            for (size_t w = 0; w < L[k].nwidth; w++) {
                double s = doc->polys[L[k].width0 + w].s0;
                if (s > a && s < b) C->bp[nbp++] = s;
            }
    }
    C->bp[nbp++] = b;
    /* sort (few, nearly sorted) and drop repeats */
    for (size_t i = 1; i < nbp; i++)
        for (size_t j = i; j > 0 && C->bp[j - 1] > C->bp[j]; j--) {
            double t = C->bp[j];
            C->bp[j] = C->bp[j - 1];
            C->bp[j - 1] = t;
        }
    for (size_t i = 0; i + 1 < nbp; i++) {
        double s0 = C->bp[i], s1 = C->bp[i + 1];
        if (!(s1 > s0)) continue;
        double *v = NULL;
        size_t n = 0;
        size_t left = C->max_points > C->points + C->nxs ? C->max_points - C->points - C->nxs : 0;
        rs_result r = rs__odr_sample(C->ctx, &C->line, s0, s1, curve_t, cv, TOL_CURVE, left + 1, &v, &n);
        if (r == RS_ERR_LIMIT)
            return rs__fail(C->ctx, RS_ERR_LIMIT, "%s line %lu: road '%s': more than %zu points in the converted roads",
                            doc->name, C->road->xml_line, C->road->id, C->max_points);
        if (r) return r;
        size_t first = C->nxs ? 1 : 0; /* the shared point once */
        if (C->nxs + n > C->capxs) {
            size_t cap = C->capxs ? C->capxs : 256;
            while (cap < C->nxs + n) cap *= 2;
            double *q = rs__realloc(C->ctx, C->xs, cap * 3 * sizeof *q);
            if (!q) {
                rs__free(C->ctx, v);
                return nomem(C);
            }
            C->xs = q;
            C->capxs = cap;
        }
        memcpy(C->xs + 3 * C->nxs, v + 3 * first, (n - first) * 3 * sizeof *v);
        C->nxs += n - first;
        rs__free(C->ctx, v);
    }
    return RS_OK;
}

/* One record of points xs[i0..i1] (x, y, s). */
static void emit_record(conv *C, const char *kind, double width, const char *style, double dt, size_t i0, size_t i1)
{
    tbuf *b = &C->roads;
    tb_put(b, "road ", 5);
    char name[600];
    if (C->sec_idx == (size_t)-1) snprintf(name, sizeof name, "%.500s/obj/%s", C->road->id, kind);
    else snprintf(name, sizeof name, "%.500s/%zu/%s", C->road->id, C->sec_idx, kind);
    tb_quoted(b, name);
    tb_printf(b, " width %.15g", width);
    if (style) tb_printf(b, " style=%s", style);
    if (dt != 0) tb_printf(b, " t_offset=%.15g", dt);
    tb_put(b, " junction_cuts=no\n", 18);
    for (size_t i = i0; i <= i1; i++) {
        double x = C->xs[3 * i], y = C->xs[3 * i + 1];
        double X = C->doc->off_x + C->ch * x - C->sh * y, Y = C->doc->off_y + C->sh * x + C->ch * y;
        tb_printf(b, "  %.15g %.15g\n", X, Y);
    }
    tb_put(b, "end\n", 4);
    C->points += i1 - i0 + 1;
}

static rs_result check_points(conv *C)
{
    if (C->points > C->max_points)
        return rs__fail(C->ctx, RS_ERR_LIMIT, "%s line %lu: road '%s': more than %zu points in the converted roads",
                        C->doc->name, C->road->xml_line, C->road->id, C->max_points);
    return C->roads.failed || C->styles.failed ? nomem(C) : RS_OK;
}

/* ---- surfaces ------------------------------------------------------------------- */

/* Inserts samples where the half width changes by more than TOL_W between
 * neighbours (a lane opening over a straight needs no points for its
 * curve, but does for its width). */
static rs_result densify_width(conv *C, curve *cv)
{
    size_t i = 0;
    while (i + 1 < C->nxs) {
        double sa = C->xs[3 * i + 2], sb = C->xs[3 * i + 5];
        double ha = curve_half(cv, sa), hb = curve_half(cv, sb), hm = curve_half(cv, 0.5 * (sa + sb));
        double lo = fmin(ha, fmin(hb, hm)), hi = fmax(ha, fmax(hb, hm));
        if (hi - lo <= TOL_W || sb - sa < 1e-4) {
            i++;
            continue;
        }
        if (C->points + C->nxs >= C->max_points)
            return rs__fail(C->ctx, RS_ERR_LIMIT, "%s line %lu: road '%s': more than %zu points in the converted roads",
                            C->doc->name, C->road->xml_line, C->road->id, C->max_points);
        if (C->nxs == C->capxs) {
            double *q = rs__realloc(C->ctx, C->xs, 2 * C->capxs * 3 * sizeof *q);
            if (!q) return nomem(C);
            C->xs = q;
            C->capxs *= 2;
        }
        memmove(C->xs + 3 * (i + 2), C->xs + 3 * (i + 1), (C->nxs - i - 1) * 3 * sizeof *C->xs);
        double sm = 0.5 * (sa + sb), x, y, h;
        rs__odr_line_eval(&C->line, sm, &x, &y, &h);
        double t = curve_t(sm, cv);
        C->xs[3 * (i + 1)] = x - t * sin(h);
        C->xs[3 * (i + 1) + 1] = y + t * cos(h);
        C->xs[3 * (i + 1) + 2] = sm;
        C->nxs++;
    }
    return RS_OK;
}

static rs_result band(conv *C, const rs__odr_section *sec, double a, double b, int left_b, int right_b,
                      rs__odr_surface kind)
{
    curve cv = { C->doc, C->road, sec, left_b, right_b, 0 };
    rs_result r = sample_curve(C, &cv, a, b);
    if (!r) r = densify_width(C, &cv);
    if (r) return r;
    /* the middle made medial, and its half width per sample */
    if (C->caprr < C->nxs) {
        double *q = rs__realloc(C->ctx, C->rr, C->nxs * sizeof *q);
        if (!q) return nomem(C);
        C->rr = q;
        C->caprr = C->nxs;
    }
    for (size_t k = 0; k < C->nxs; k++)
        medial(&C->line, &cv, C->xs[3 * k + 2], &C->xs[3 * k], &C->xs[3 * k + 1], &C->rr[k]);
    const char *style = kind == RS__ODR_SURF_SIDEWALK ? "odr-sidewalk" : kind == RS__ODR_SURF_BIKE ? "odr-bike" : NULL;
    char what[64];
    snprintf(what, sizeof what, "%s[%d,%d]",
             kind == RS__ODR_SURF_SIDEWALK ? "sidewalk" : kind == RS__ODR_SURF_BIKE ? "bike" : "surface", left_b, right_b);
    size_t i = 0;
    while (i + 1 < C->nxs) {
        double lo = C->rr[i], hi = C->rr[i];
        size_t j = i + 1;
        lo = fmin(lo, C->rr[j]);
        hi = fmax(hi, C->rr[j]);
        while (j + 1 < C->nxs) {
            double rn = C->rr[j + 1];
            if (fmax(hi, rn) - fmin(lo, rn) > 2 * TOL_W) break;
            lo = fmin(lo, rn);
            hi = fmax(hi, rn);
            j++;
        }
        /* a round cap where the band narrows beyond it (or widens before
         * it) bulges m^2 r / 2 past the true edge (m: the half width's
         * slope there); the piece gives up half of that */
        double sa = C->xs[3 * i + 2], sb = C->xs[3 * j + 2], e = 1e-3;
        double m_end = (curve_half(&cv, sb) - curve_half(&cv, sb - e)) / e;
        double m_start = (curve_half(&cv, sa + e) - curve_half(&cv, sa)) / e;
        double m = fmax(fmax(-m_end, 0), fmax(m_start, 0)), rad = 0.5 * (lo + hi);
        rad -= 0.25 * m * m * rad;
        if (rad > 1e-3) emit_record(C, what, 2 * rad, style, 0, i, j);
        i = j;
    }
    return check_points(C);
}

/* Surface bands of one lane section: runs of neighbouring lanes drawn alike. */
static rs_result section_surfaces(conv *C, const rs__odr_section *sec, double a, double b)
{
    const rs__odr_lane *L = C->doc->lanes + sec->lane0;
    size_t k = 0;
    while (k < sec->nlane) {
        if (L[k].id == 0 || L[k].surface == RS__ODR_SURF_NONE) {
            k++;
            continue;
        }
        size_t m = k; /* last lane of the run (skipping the centre lane) */
        for (size_t q = k + 1; q < sec->nlane; q++) {
            if (L[q].id == 0) continue;
            if (L[q].surface != L[k].surface) break;
            m = q;
        }
        int top = L[k].id, bot = L[m].id;
        int left_b = top > 0 ? top : top + 1, right_b = bot > 0 ? bot - 1 : bot;
        rs_result r = band(C, sec, a, b, left_b, right_b, L[k].surface);
        if (r) return r;
        k = m + 1;
    }
    return RS_OK;
}

/* ---- road marks ------------------------------------------------------------------- */

typedef struct mline {
    double dt, width, on, off, s_offset; /* on <= 0 or off <= 0: solid */
    uint32_t rgba;
} mline;

static uint32_t curb_rgba(uint32_t rgba)
{
    return rgba == 0xF4F4F0FFu ? 0xB4B0A8FFu : rgba; /* "standard": the kerb grey */
}

/* The lines a mark draws (docs/opendrive.md "Road marks"); side: +1 for a
 * left lane, -1 right, 0 the centre lane (its first-named line left). */
static size_t mark_lines(const rs__odr_doc *doc, const rs__odr_mark *m, int side, mline *out, size_t cap)
{
    double w = m->width > 0 ? m->width : m->bold ? 0.25 : 0.12;
    double in = side > 0 ? -1 : side < 0 ? 1 : 1; /* towards the first-named (inner) line */
    size_t n = 0;
    if (m->nline) {
        for (size_t i = 0; i < m->nline && n < cap; i++) {
            const rs__odr_mark_line *l = &doc->lines[m->line0 + i];
            mline o = { l->t_offset, l->width > 0 ? l->width : w, l->length, l->space, l->s_offset,
                        l->rgba ? l->rgba : m->rgba };
            if (!(l->length > 0)) continue; /* nothing visible */
            out[n++] = o;
        }
        return n;
    }
    mline solid = { 0, w, 0, 0, 0, m->rgba }, broken = { 0, w, RS__ODR_DASH_ON, RS__ODR_DASH_OFF, 0, m->rgba };
    switch (m->type) {
    case RS__ODR_MARK_SOLID:
    case RS__ODR_MARK_EDGE:
        out[n++] = solid;
        break;
    case RS__ODR_MARK_BROKEN:
        out[n++] = broken;
        break;
    case RS__ODR_MARK_SOLID_SOLID:
    case RS__ODR_MARK_SOLID_BROKEN:
    case RS__ODR_MARK_BROKEN_SOLID:
    case RS__ODR_MARK_BROKEN_BROKEN: {
        int first_broken = m->type == RS__ODR_MARK_BROKEN_SOLID || m->type == RS__ODR_MARK_BROKEN_BROKEN;
        int second_broken = m->type == RS__ODR_MARK_SOLID_BROKEN || m->type == RS__ODR_MARK_BROKEN_BROKEN;
        mline a = first_broken ? broken : solid, b = second_broken ? broken : solid;
        a.dt = in * w; /* centres 2 w apart: a gap as wide as a line */
        b.dt = -in * w;
        out[n++] = a;
        out[n++] = b;
        break;
    }
    case RS__ODR_MARK_BOTTS_DOTS: {
        mline d = { 0, m->width > 0 ? m->width : 0.1, 0, 0, 0, m->rgba };
        d.on = d.width;
        d.off = 1.2 - d.width > 0.05 ? 1.2 - d.width : 0.05;
        out[n++] = d;
        break;
    }
    case RS__ODR_MARK_CURB: {
        mline c = { 0, m->width > 0 ? m->width : 0.15, 0, 0, 0, curb_rgba(m->rgba) };
        out[n++] = c;
        break;
    }
    case RS__ODR_MARK_GRASS: {
        mline g = { 0, m->width > 0 ? m->width : 0.5, 0, 0, 0, m->rgba == 0xF4F4F0FFu ? 0x5E7D3AFFu : m->rgba };
        out[n++] = g;
        break;
    }
    default: /* none, and a custom type without <line>s */
        break;
    }
    return n;
}

static rs_result draw_line(conv *C, const rs__odr_section *sec, int bid, const mline *l, double a, double b,
                           const char *what)
{
    size_t st;
    rs_result r = line_style(C, l->width, l->rgba, &st);
    if (r) return r;
    char sname[32];
    snprintf(sname, sizeof sname, "odr-line-%zu", st);
    curve cv = { C->doc, C->road, sec, bid, bid, l->dt };
    if (!(l->on > 0) || !(l->off > 0)) {
        r = sample_curve(C, &cv, a, b);
        if (r) return r;
        if (C->nxs >= 2) emit_record(C, what, l->width, sname, l->dt, 0, C->nxs - 1);
        return check_points(C);
    }
    double P = l->on + l->off;
    double k0 = floor((a - l->s_offset) / P), k1 = ceil((b - l->s_offset) / P);
    if (k1 - k0 > (double)C->max_points)
        return rs__fail(C->ctx, RS_ERR_LIMIT, "%s line %lu: road '%s': more than %zu dashes", C->doc->name,
                        C->road->xml_line, C->road->id, C->max_points);
    for (double k = k0; k <= k1; k++) {
        double d0 = l->s_offset + k * P, d1 = d0 + l->on;
        double s0 = fmax(d0, a), s1 = fmin(d1, b);
        if (!(s1 - s0 > 1e-6)) continue;
        r = sample_curve(C, &cv, s0, s1);
        if (r) return r;
        if (C->nxs >= 2) emit_record(C, what, l->width, sname, l->dt, 0, C->nxs - 1);
        r = check_points(C);
        if (r) return r;
    }
    return RS_OK;
}

static rs_result section_marks(conv *C, const rs__odr_section *sec, double a, double b)
{
    const rs__odr_doc *doc = C->doc;
    const rs__odr_lane *L = doc->lanes + sec->lane0;
    for (size_t k = 0; k < sec->nlane; k++) {
        const rs__odr_lane *ln = &L[k];
        for (size_t q = 0; q < ln->nmark; q++) {
            const rs__odr_mark *m = &doc->marks[ln->mark0 + q];
            double ma = fmax(m->s, a), mb = q + 1 < ln->nmark ? fmin(doc->marks[ln->mark0 + q + 1].s, b) : b;
            if (!(mb > ma)) continue;
            mline ls[16];
            size_t n = mark_lines(doc, m, ln->id > 0 ? 1 : ln->id < 0 ? -1 : 0, ls, 16);
            char what[48];
            snprintf(what, sizeof what, "lane%d", ln->id);
            for (size_t i = 0; i < n; i++) {
                rs_result r = draw_line(C, sec, ln->id, &ls[i], ma, mb, what);
                if (r) return r;
            }
        }
    }
    return RS_OK;
}

/* ---- objects ------------------------------------------------------------------------ */

/* The t range of the carriageway lanes on one side of the centre lane at s
 * (empty when there are none). */
static void side_span(conv *C, double s, int side, double *t0, double *t1)
{
    const rs__odr_road *R = C->road;
    *t0 = *t1 = 0;
    const rs__odr_section *S = NULL;
    for (size_t k = 0; k < R->nsec; k++)
        if (C->doc->sections[R->sec0 + k].s <= s) S = &C->doc->sections[R->sec0 + k];
    if (!S) return;
    int outer = 0;
    for (size_t k = 0; k < S->nlane; k++) {
        const rs__odr_lane *l = &C->doc->lanes[S->lane0 + k];
        if (l->surface != RS__ODR_SURF_ROAD || (side > 0 ? l->id <= 0 : l->id >= 0)) continue;
        if (side > 0 ? l->id > outer : l->id < outer) outer = l->id;
    }
    if (!outer) return;
    double a = rs__odr_boundary_t(C->doc, R, S, 0, s), b = rs__odr_boundary_t(C->doc, R, S, outer, s);
    *t0 = fmin(a, b);
    *t1 = fmax(a, b);
}

static rs_result road_objects(conv *C)
{
    const rs__odr_road *R = C->road;
    for (size_t i = 0; i < R->nobj; i++) {
        const rs__odr_object *o = &C->doc->objects[R->obj0 + i];
        double s0 = fmax(o->s0, 0), s1 = fmin(o->s1, R->length);
        if (o->kind == RS__ODR_OBJ_CROSSWALK) {
            /* stripes along s, 0.5 m wide, 0.5 m apart, centred in the box */
            if (!(s1 - s0 > 1e-3)) continue;
            double span = o->t1 - o->t0;
            double nst = floor((span + 0.5) / 1.0);
            if (nst < 1) continue;
            if (nst > 1e5) nst = 1e5;
            double first = 0.5 * (o->t0 + o->t1) - 0.5 * (nst - 1);
            mline l = { 0, 0.5, 0, 0, 0, 0xF4F4F0FFu };
            for (double k = 0; k < nst; k++) {
                l.dt = first + k;
                rs_result r = draw_line(C, NULL, REF_LINE, &l, s0, s1, "crosswalk");
                if (r) return r;
            }
        } else {
            /* one line across the box at its middle s, as wide as the box is long (at least 0.3 m) */
            double sm = 0.5 * (o->s0 + o->s1), t0 = o->t0, t1 = o->t1;
            if (sm < 0) sm = 0;
            if (sm > R->length) sm = R->length;
            if (o->side) side_span(C, sm, o->side, &t0, &t1);
            if (!(t1 - t0 > 1e-3)) continue;
            double x, y, h;
            rs__odr_line_eval(&C->line, sm, &x, &y, &h);
            double w = fmax(o->s1 - o->s0, 0.3);
            size_t st;
            rs_result r = line_style(C, w, 0xF4F4F0FFu, &st);
            if (r) return r;
            char sname[32];
            snprintf(sname, sizeof sname, "odr-line-%zu", st);
            if (C->capxs < 2) {
                double *q = rs__realloc(C->ctx, C->xs, 2 * 3 * sizeof *q);
                if (!q) return nomem(C);
                C->xs = q;
                C->capxs = 2;
            }
            /* from the right end to the left: the line's left is then along +s */
            C->xs[0] = x - t0 * sin(h), C->xs[1] = y + t0 * cos(h), C->xs[2] = 0;
            C->xs[3] = x - t1 * sin(h), C->xs[4] = y + t1 * cos(h), C->xs[5] = 0;
            C->nxs = 2;
            emit_record(C, "stop_line", w, sname, 0, 0, 1);
            r = check_points(C);
            if (r) return r;
        }
    }
    return RS_OK;
}

/* ---- checks and the driver ------------------------------------------------------------ */

/* A bound of |p| over [p.s0, end]: within 1000 m (the road text's line
 * offsets), so no boundary runs off to where sampling it costs millions
 * of points. */
static int poly_bounded(const rs__odr_poly *p, double end)
{
    double L = end - p->s0;
    if (!(L >= 0)) L = 0;
    double b = fabs(p->a) + L * (fabs(p->b) + L * (fabs(p->c) + L * fabs(p->d)));
    return b <= 1000;
}

static rs_result road_check(conv *C)
{
    const rs__odr_doc *doc = C->doc;
    const rs__odr_road *R = C->road;
    if (!(R->length > 0) || !(R->length <= 1e7))
        return rs__fail(C->ctx, RS_ERR_PARSE, "%s line %lu: road '%s': length %.15g must be in (0, 1e7] m", doc->name,
                        R->xml_line, R->id, R->length);
    if (!R->ngeom)
        return rs__fail(C->ctx, RS_ERR_PARSE, "%s line %lu: road '%s' has no planView geometry", doc->name,
                        R->xml_line, R->id);
    for (size_t i = 0; i < R->ngeom; i++) {
        const rs__odr_geom *g = &doc->geoms[R->geom0 + i];
        if (!rs__odr_geom_valid(g))
            return rs__fail(C->ctx, RS_ERR_PARSE,
                            "%s: road '%s' (line %lu): geometry %zu at s=%.15g is not valid (non-finite number, length "
                            "not in (0, 1e7] m, |curvature| over 1e4 /m or a poly3 steeper than 1e4)",
                            doc->name, R->id, R->xml_line, i + 1, g->s);
        if (i && !(g->s >= doc->geoms[R->geom0 + i - 1].s))
            return rs__fail(C->ctx, RS_ERR_PARSE, "%s: road '%s' (line %lu): geometry %zu at s=%.15g comes before the "
                            "previous one's s", doc->name, R->id, R->xml_line, i + 1, g->s);
    }
    for (size_t i = 0; i < R->nsec; i++) {
        const rs__odr_section *S = &doc->sections[R->sec0 + i];
        if (!(S->s >= 0) || !(S->s <= R->length) || (i && !(S->s >= doc->sections[R->sec0 + i - 1].s)))
            return rs__fail(C->ctx, RS_ERR_PARSE,
                            "%s line %lu: road '%s': laneSection s=%.15g must lie in [0, %.15g] and not before the "
                            "previous section", doc->name, S->xml_line, R->id, S->s, R->length);
        for (size_t k = 0; k < S->nlane; k++) {
            const rs__odr_lane *l = &doc->lanes[S->lane0 + k];
            double send = i + 1 < R->nsec ? doc->sections[R->sec0 + i + 1].s : R->length;
            for (size_t w = 0; w < l->nwidth; w++) {
                if (w && !(doc->polys[l->width0 + w].s0 >= doc->polys[l->width0 + w - 1].s0))
                    return rs__fail(C->ctx, RS_ERR_PARSE, "%s line %lu: road '%s' lane %d: width sOffsets must not "
                                    "decrease", doc->name, l->xml_line, R->id, l->id);
                double end = w + 1 < l->nwidth ? doc->polys[l->width0 + w + 1].s0 : send;
                if (!poly_bounded(&doc->polys[l->width0 + w], end))
                    return rs__fail(C->ctx, RS_ERR_PARSE, "%s line %lu: road '%s' lane %d: width record %zu may reach "
                                    "beyond 1000 m (|a| + |b| L + |c| L^2 + |d| L^3 over its %.15g m)", doc->name,
                                    l->xml_line, R->id, l->id, w + 1, end - doc->polys[l->width0 + w].s0);
            }
            for (size_t m = 1; m < l->nmark; m++)
                if (!(doc->marks[l->mark0 + m].s >= doc->marks[l->mark0 + m - 1].s))
                    return rs__fail(C->ctx, RS_ERR_PARSE, "%s line %lu: road '%s' lane %d: roadMark sOffsets must not "
                                    "decrease", doc->name, doc->marks[l->mark0 + m].xml_line, R->id, l->id);
            for (size_t m = 0; m < l->nmark; m++) {
                const rs__odr_mark *mk = &doc->marks[l->mark0 + m];
                for (size_t q = 0; q < mk->nline; q++) {
                    const rs__odr_mark_line *ml = &doc->lines[mk->line0 + q];
                    if (ml->length > 0 && ml->space > 0 && ml->length + ml->space < 1e-3)
                        return rs__fail(C->ctx, RS_ERR_PARSE, "%s line %lu: road '%s' lane %d: a <line> pattern "
                                        "shorter than 1 mm", doc->name, mk->xml_line, R->id, l->id);
                }
            }
        }
    }
    for (size_t i = 0; i < R->noff; i++) {
        if (i && !(doc->polys[R->off0 + i].s0 >= doc->polys[R->off0 + i - 1].s0))
            return rs__fail(C->ctx, RS_ERR_PARSE, "%s line %lu: road '%s': laneOffset s must not decrease", doc->name,
                            R->xml_line, R->id);
        double end = i + 1 < R->noff ? doc->polys[R->off0 + i + 1].s0 : R->length;
        if (!poly_bounded(&doc->polys[R->off0 + i], end))
            return rs__fail(C->ctx, RS_ERR_PARSE, "%s line %lu: road '%s': laneOffset %zu may reach beyond 1000 m",
                            doc->name, R->xml_line, R->id, i + 1);
    }
    return RS_OK;
}

rs_result rs__odr_to_text(rs_ctx *ctx, const rs__odr_doc *doc, size_t max_points, char **text, size_t *size)
{
    *text = NULL;
    *size = 0;
    conv C;
    memset(&C, 0, sizeof C);
    C.ctx = ctx;
    C.doc = doc;
    C.roads.ctx = C.styles.ctx = ctx;
    C.max_points = max_points ? max_points : 10000000;
    C.ch = cos(doc->off_hdg);
    C.sh = sin(doc->off_hdg);
    rs_result r = RS_OK;
    for (size_t i = 0; i < doc->nroads && !r; i++) {
        C.road = &doc->roads[i];
        C.line.g = doc->geoms + C.road->geom0;
        C.line.n = C.road->ngeom;
        r = road_check(&C);
        for (size_t k = 0; k < C.road->nsec && !r; k++) {
            const rs__odr_section *S = &doc->sections[C.road->sec0 + k];
            double a = S->s, b = k + 1 < C.road->nsec ? doc->sections[C.road->sec0 + k + 1].s : C.road->length;
            if (b > C.road->length) b = C.road->length;
            if (!(b - a > 1e-9)) continue;
            C.sec_idx = k;
            r = section_surfaces(&C, S, a, b);
            C.sec_idx = k;
            if (!r) r = section_marks(&C, S, a, b);
        }
        C.sec_idx = (size_t)-1;
        if (!r) r = road_objects(&C);
    }
    tbuf out = { ctx, NULL, 0, 0, 0 };
    if (!r) {
        if (doc->geo_reference) {
            tb_put(&out, "frame world ", 12);
            tb_quoted(&out, doc->geo_reference);
            tb_put(&out, "\n", 1);
        } else {
            tb_put(&out, "frame world\n", 12);
        }
        tb_printf(&out, "# from %.400s: %zu roads, %zu junctions (roadsplat, docs/opendrive.md)\n", doc->name,
                  doc->nroads, doc->njunctions);
        static const char fills[] = "style odr-sidewalk\n  fill #C0BAB0\nend\nstyle odr-bike\n  fill #B05040\nend\n";
        tb_put(&out, fills, sizeof fills - 1);
        if (C.styles.n) tb_put(&out, C.styles.p, C.styles.n);
        if (C.roads.n) tb_put(&out, C.roads.p, C.roads.n);
        if (out.failed) r = nomem(&C);
    }
    rs__free(ctx, C.roads.p);
    rs__free(ctx, C.styles.p);
    rs__free(ctx, C.sk);
    rs__free(ctx, C.bp);
    rs__free(ctx, C.xs);
    rs__free(ctx, C.rr);
    if (r) {
        rs__free(ctx, out.p);
        return r;
    }
    *text = out.p;
    *size = out.n;
    return RS_OK;
}
