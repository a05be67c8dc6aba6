/* Road ends at a T (issue 27 target 3, docs/network.md "Ends at a T"):
 * which record ends lie on a road passing through their node, and that
 * road's normal there. The road field trims such ends (lib/scene/roadfield.c,
 * rs__roadfield_set_tees); the GPU export gives them to the shader. */
#include "roadfield.h"
#include "network.h"

#include <math.h>

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

double rs__tee_offset(const rs_roads *roads, uint32_t r, int end, const rs_network_leg *tl, double nx, double ny,
                      double tol)
{
    const double *xy = NULL, *txy = NULL;
    size_t np = 0, tn = 0;
    if (rs__is_end_leg(tl)) return 0;
    rs_roads_get(roads, r, NULL, NULL, &xy, &np);
    rs_roads_get(roads, tl->road, NULL, NULL, &txy, &tn);
    if (np < 1 || (size_t)tl->segment + 1 >= tn) return 0;
    const double *e = xy + 2 * (end ? np - 1 : 0), *a = txy + 2 * (size_t)tl->segment, *b = a + 2;
    double dx = b[0] - a[0], dy = b[1] - a[1], dd = dx * dx + dy * dy;
    double u = dd > 0 ? ((e[0] - a[0]) * dx + (e[1] - a[1]) * dy) / dd : 0;
    u = u > 0 ? (u < 1 ? u : 1) : 0;
    double fx = e[0] - (a[0] + u * dx), fy = e[1] - (a[1] + u * dy);
    if (!(hypot(fx, fy) > tol)) return 0;
    double off = nx * fx + ny * fy;
    return isfinite(off) ? off : 0;
}

rs_result rs__tee_ends(rs_ctx *ctx, const rs_roads *roads, const rs_network *net, rs__tee_end **out, size_t *nout)
{
    return rs__tee_ends_at(ctx, roads, net, NULL, out, nout);
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
            t->far = roads ? 0.5 * th[bj].R - rs__tee_offset(roads, r, L[k].kind == RS_LEG_END, th[bj].leg[0], nx, ny, net->tol)
                           : -INFINITY;
            t->grow = 0;
        }
    }
    *out = T;
    *nout = cnt;
    return RS_OK;
}
