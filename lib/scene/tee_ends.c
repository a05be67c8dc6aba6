/* Road ends at a T (issue 27 target 3, docs/network.md "Ends at a T"):
 * which record ends lie on a road passing through their node, and that
 * road's normal there. The road field trims such ends (lib/scene/roadfield.c,
 * rs__roadfield_set_tees); the GPU export gives them to the shader. */
#include "roadfield.h"
#include "network.h"

#include <math.h>
#include <string.h>

/* An end with the strip this close to the through road's direction keeps
 * its round cap (the flat end would reach 1 / sine half widths along it) */
#define TEE_MIN_SINE 0.2

/* Through roads at one node looked at (more: every end there keeps its cap) */
#define MAX_THROUGH 4

/* A road passing through a node: its stroke (stroke2: the second record's,
 * for two ends going straight on), its two legs, its direction there and
 * the narrower of its two widths. */
typedef struct tee_through {
    uint32_t stroke, stroke2;
    const rs_network_leg *leg[2];
    int n, live;
    double tx, ty, R;
} tee_through;

/* The point of segment a-b nearest (px, py) into f (a when a = b). */
static void segment_foot(const double *a, const double *b, double px, double py, double *f)
{
    double dx = b[0] - a[0], dy = b[1] - a[1], dd = dx * dx + dy * dy;
    double v = dd > 0 ? ((px - a[0]) * dx + (py - a[1]) * dy) / dd : 0;
    v = v > 0 ? (v < 1 ? v : 1) : 0;
    f[0] = a[0] + v * dx, f[1] = a[1] + v * dy;
}

double rs__tee_offset(const rs_roads *roads, uint32_t r, int end, const rs_network_leg *tl, double nx, double ny,
                      double tol)
{
    const double *xy = NULL, *txy = NULL;
    size_t np = 0, tn = 0;
    if (rs__is_end_leg(tl)) return 0;
    rs_roads_get(roads, r, NULL, NULL, &xy, &np);
    rs_roads_get(roads, tl->road, NULL, NULL, &txy, &tn);
    if (np < 1 || (size_t)tl->segment + 1 >= tn) return 0;
    const double *e = xy + 2 * (end ? np - 1 : 0), *a = txy + 2 * (size_t)tl->segment;
    double f[2];
    segment_foot(a, a + 2, e[0], e[1], f);
    double fx = e[0] - f[0], fy = e[1] - f[1];
    if (!(hypot(fx, fy) > tol)) return 0;
    double off = nx * fx + ny * fy;
    return isfinite(off) ? off : 0;
}

/* How far the street of through leg tl runs on from its node along the
 * leg, metres: to its stroke's end (a part's strokes are the whole map's:
 * s_off and s_len), INFINITY on a ring. */
static double leg_run(const rs_network *net, const rs_network_leg *tl)
{
    uint32_t q = tl->road;
    double L = net->s_len[q];
    if (!(L < INFINITY)) return INFINITY;
    int along = (tl->kind == RS_LEG_START || tl->kind == RS_LEG_FORWARD) != (net->rev[q] != 0);
    double S = net->rev[q] ? net->s_off[q] - tl->s : net->s_off[q] + tl->s;
    return along ? L - S : S;
}

/* The distance from (px, py) to segment a-b. */
static double segment_distance(const double *a, const double *b, double px, double py)
{
    double f[2];
    segment_foot(a, b, px, py, f);
    double ex = px - f[0], ey = py - f[1];
    return sqrt(ex * ex + ey * ey); /* (not hypot: a T end asks it for each segment near it) */
}

/* How far (px, py) lies beyond the surface of the street of leg L (half
 * width R), metres (negative: inside): against the leg's record from the
 * foot (fx, fy) on along the leg, as far as a straight street would
 * matter (the distance to the foot and 2 R of arc: a long record is not
 * walked whole for each T end), and where the stroke goes on past the
 * record's end within that (run: leg_run), against its last segment
 * carried on straight (the next record is not looked at: a part need not
 * hold it). Returns as soon as it is no more than `enough` (the caller's
 * test). */
static double past_street(const rs_roads *roads, const rs_network *net, const rs_network_leg *L, double run, double R,
                          double fx, double fy, double px, double py, double enough)
{
    const double *xy;
    size_t np;
    rs_roads_get(roads, L->road, NULL, NULL, &xy, &np);
    if (!np) return INFINITY;
    int fwd = L->kind == RS_LEG_START || L->kind == RS_LEG_FORWARD;
    double reach = sqrt((px - fx) * (px - fx) + (py - fy) * (py - fy)) + 2 * R, arc = 0, best = INFINITY;
    if (np == 1) return segment_distance(xy, xy, px, py) - R;
    /* (a T on a segment: that segment; a point: the segments after it or before) */
    size_t k = L->segment < np - 1 ? L->segment : np - 2;
    for (int first = 1;; first = 0) {
        const double *a = xy + 2 * k, *b = a + 2;
        double dx = b[0] - a[0], dy = b[1] - a[1], len = sqrt(dx * dx + dy * dy);
        best = fmin(best, segment_distance(a, b, px, py));
        if (best - R <= enough) return best - R; /* (on the street: no need to look further) */
        if (first && len > 0) { /* (the arc from the foot only) */
            double t = ((fx - a[0]) * dx + (fy - a[1]) * dy) / (len * len);
            t = t > 0 ? (t < 1 ? t : 1) : 0;
            arc += (fwd ? 1 - t : t) * len;
        } else arc += len;
        if (arc > reach || (fwd ? k + 2 >= np : k == 0)) break;
        k = fwd ? k + 1 : k - 1;
    }
    if (!(arc > reach)) { /* (the record ends within reach: the stroke on past it) */
        double rest = fwd ? net->length[L->road] - L->s : L->s, on = fmin(run - rest, reach);
        size_t ke = rs__end_segment(xy, np, fwd); /* (past repeated points) */
        if (on > net->tol && ke != SIZE_MAX) {
            const double *p = xy + 2 * (fwd ? np - 1 : 0), *q = xy + 2 * (fwd ? ke : ke + 1);
            double dx = p[0] - q[0], dy = p[1] - q[1], len = hypot(dx, dy);
            if (len > 0) {
                double e[2] = { p[0] + on * dx / len, p[1] + on * dy / len };
                best = fmin(best, segment_distance(p, e, px, py));
            }
        }
    }
    return best - R;
}

/* 1 when the flat strip of road r's end (end 1: its last point), run on
 * to the clip line n.p = n.E + far, paints no more off the street it
 * meets (half width R, direction t; legs tl[0] on t's side, tl[1]) than
 * the end's round cap would (r - far past the far edge, r the road's half
 * width), or than a tenth of r (a bent street's sagitta under a corner:
 * the cap's notch on the near side at a slant is as deep); else the end
 * keeps its cap. At a slant one edge of the strip reaches (far + r cos) /
 * sin along the street (30 m for an 11 m road meeting another at 17
 * degrees): a street that stops or turns before that left a spike of the
 * side road's surface off both roads (found by the edits fuzzer). The
 * strip's two far corners are measured against the street (past_street),
 * each on its side of the foot. */
static int strip_on_street(const rs_roads *roads, const rs_network *net, size_t nd, uint32_t r, int end,
                           const rs_network_leg *const *tl, double tx, double ty, double nx, double ny, double far,
                           double R)
{
    const double *xy;
    size_t np;
    double w = 0;
    if (rs_roads_get(roads, r, NULL, &w, &xy, &np) || !np) return 0;
    size_t ke = rs__end_segment(xy, np, end);
    if (ke == SIZE_MAX) return 1; /* (no segment: a build draws no strip) */
    const double *E = xy + 2 * (end ? np - 1 : 0), *a = xy + 2 * ke;
    double ux = a[2] - a[0], uy = a[3] - a[1], len = hypot(ux, uy);
    if (!(len > 0)) return 1;
    ux /= len, uy /= len;
    if (!end) ux = -ux, uy = -uy;
    double sn = nx * ux + ny * uy;
    if (!(sn > 0)) return 1; /* (no strip made: rs__roadfield_set_tees) */
    /* the foot: the through road's point nearest E on its leg's segment
     * (the node where the street passes by its records' ends) */
    const double *txy;
    size_t tn;
    double F[2] = { net->node[nd].x, net->node[nd].y };
    rs_roads_get(roads, tl[0]->road, NULL, NULL, &txy, &tn);
    if (!rs__is_end_leg(tl[0]) && (size_t)tl[0]->segment + 1 < tn) {
        const double *p = txy + 2 * (size_t)tl[0]->segment;
        segment_foot(p, p + 2, E[0], E[1], F);
    }
    const double fx = F[0], fy = F[1];
    const double cap = fmax(0.5 * w - far, fmax(0.05 * w, net->tol));
    for (int sg = -1; sg <= 1; sg += 2) {
        double vx = -sg * 0.5 * w * uy, vy = sg * 0.5 * w * ux;
        double d = (far - (nx * vx + ny * vy)) / sn; /* (<= 0: that side is cut before E) */
        if (!(d > 0)) continue;
        double cx = E[0] + vx + d * ux, cy = E[1] + vy + d * uy;
        const rs_network_leg *L = tx * (cx - fx) + ty * (cy - fy) >= 0 ? tl[0] : tl[1];
        if (!(past_street(roads, net, L, leg_run(net, L), R, fx, fy, cx, cy, cap) <= cap)) return 0;
    }
    return 1;
}

rs_result rs__tee_ends(rs_ctx *ctx, const rs_roads *roads, const rs_network *net, rs__tee_end **out, size_t *nout)
{
    return rs__tee_ends_at(ctx, roads, net, NULL, out, nout);
}

rs_result rs__tee_ends_from(rs_ctx *ctx, const rs__tees *T, const rs_roads *roads, const rs_network *net,
                            rs__tee_end **out, size_t *n)
{
    if (!T) return rs__tee_ends(ctx, roads, net, out, n);
    *out = NULL;
    *n = 0;
    if (!T->n) return RS_OK;
    if (!(*out = rs__alloc_array(ctx, T->n, sizeof **out))) return RS_ERR_NOMEM;
    memcpy(*out, T->t, T->n * sizeof **out);
    *n = T->n;
    return RS_OK;
}

rs_result rs__tee_ends_at(rs_ctx *ctx, const rs_roads *roads, const rs_network *net, const uint8_t *nodes,
                          rs__tee_end **out, size_t *nout)
{
    *out = NULL;
    *nout = 0;
    size_t n = roads ? rs_roads_count(roads) : net ? rs_network_road_count(net) : 0;
    if (!net || rs_network_road_count(net) != n || n < 2) return RS_OK;
    size_t cap = 0, cnt = 0;
    rs__tee_end *T = NULL;
    for (size_t nd = 0; nd < net->nnodes; nd++) {
        if ((nd & 4095) == 0 && rs__poll(ctx)) {
            rs__free(ctx, T);
            return RS_ERR_CANCELLED;
        }
        const rs_network_leg *L = net->leg + net->leg_start[nd];
        uint32_t d = net->leg_start[nd + 1] - net->leg_start[nd];
        if (d < 3 || (nodes && !nodes[nd])) continue;
        /* the strokes passing through the node (a road through a shared
         * point or a T, or a record end its stroke continues), each with
         * its two legs: at most MAX_THROUGH of them, each passing once */
        tee_through th[MAX_THROUGH];
        int nth = 0, ok = 1;
        for (uint32_t k = 0; k < d && ok; k++) {
            if (!rs__leg_passes(net, &L[k])) continue;
            uint32_t st = net->stroke_of[L[k].road];
            int j = 0;
            while (j < nth && th[j].stroke != st) j++;
            if (j == nth) {
                if (nth == MAX_THROUGH) { ok = 0; break; }
                th[nth].stroke = st, th[nth].stroke2 = st, th[nth].n = 0;
                nth++;
            }
            if (th[j].n == 2) ok = 0; /* passing twice: a loop through its own node */
            else th[j].leg[th[j].n++] = &L[k];
        }
        for (int j = 0; j < nth; j++) ok &= th[j].n == 2;
        /* none passing: two record ends going straight on that do not
         * draw alike (a street whose width, lanes or class change where
         * a side road ends on it): the through road, as wide as the
         * narrower (the wider one's surface fills the rest) */
        if (ok && nth == 0) {
            const rs_network_leg *pa = NULL, *pb = NULL;
            if (!rs__straight_pair(L, d, &pa, &pb)) continue;
            th[0].leg[0] = pa, th[0].leg[1] = pb, th[0].n = 2;
            th[0].stroke = net->stroke_of[pa->road], th[0].stroke2 = net->stroke_of[pb->road];
            nth = 1;
        }
        /* every through road passing once (two legs); else every end keeps its cap */
        if (!ok || nth == 0) continue;
        int live = 0;
        for (int j = 0; j < nth; j++) {
            const rs_network_leg *const *tl = th[j].leg;
            th[j].live = rs__through_dir(tl[0], tl[1], &th[j].tx, &th[j].ty);
            if (!th[j].live) continue;
            live++;
            double R = 0, R2 = 0;
            if (roads) {
                rs_roads_get(roads, tl[0]->road, NULL, &R, NULL, NULL);
                rs_roads_get(roads, tl[1]->road, NULL, &R2, NULL, NULL);
            }
            th[j].R = R2 < R ? R2 : R;
        }
        if (!live) continue;
        for (uint32_t k = 0; k < d; k++) {
            uint32_t r = L[k].road;
            if (!rs__is_end_leg(&L[k]) || rs__leg_passes(net, &L[k])) continue;
            int own = 0;
            for (int j = 0; j < nth; j++) own |= net->stroke_of[r] == th[j].stroke || net->stroke_of[r] == th[j].stroke2;
            if (own) continue;
            /* the through road the leg meets most squarely (the first of
             * equals): its far edge line is the nearest one across */
            double wx = cos(L[k].angle), wy = sin(L[k].angle), best = 0, nx = 0, ny = 0, dn = 0;
            int bj = -1;
            for (int j = 0; j < nth; j++) {
                if (!th[j].live) continue;
                /* the normal (-ty, tx), turned to point from the leg across the road */
                double cx = -th[j].ty, cy = th[j].tx, c = -(cx * wx + cy * wy);
                double sn = rs__meet_sine(wx, wy, th[j].tx, th[j].ty); /* (= |c|) */
                if (bj < 0 || sn > best) bj = j, best = sn, nx = cx, ny = cy, dn = c;
            }
            if (!(fabs(dn) > TEE_MIN_SINE)) continue;
            if (dn < 0) nx = -nx, ny = -ny;
            double far = -INFINITY;
            if (roads) {
                int e = L[k].kind == RS_LEG_END;
                far = 0.5 * th[bj].R - rs__tee_offset(roads, r, e, th[bj].leg[0], nx, ny, net->tol);
                if (!strip_on_street(roads, net, nd, r, e, th[bj].leg, th[bj].tx, th[bj].ty, nx, ny, far,
                                     0.5 * th[bj].R)) continue;
            }
            if (cnt == cap) {
                size_t nc = cap ? 2 * cap : 16, bytes;
                rs__tee_end *nt = rs__mul_size(nc, sizeof *T, &bytes) ? rs__realloc(ctx, T, bytes) : NULL;
                if (!nt) {
                    rs__free(ctx, T);
                    return RS_ERR_NOMEM;
                }
                T = nt;
                cap = nc;
            }
            rs__tee_end *t = &T[cnt++];
            t->road = r;
            t->end = L[k].kind == RS_LEG_END;
            t->through = th[bj].leg[0]->road;
            t->nx = nx;
            t->ny = ny;
            t->far = far;
            t->grow = 0;
        }
    }
    *out = T;
    *nout = cnt;
    return RS_OK;
}
