/* One road's geometry in the local frame (lib/scene/road_local.h). */
#include "road_local.h"

#include <string.h>

void rs__road_local_walk(const rs_roads *roads, size_t ri, int rev, const rs__local_frame *F, double *x, double *y,
                         size_t stride, double *s, size_t *m_io)
{
    const double *xy = NULL;
    size_t n = 0, m = *m_io;
    rs_roads_get(roads, ri, NULL, NULL, &xy, &n);
    double sv = m ? s[m - 1] : 0;
    for (size_t i = 0; i < n; i++) {
        size_t k = rev ? n - 1 - i : i;
        double px, py;
        rs__local_point(F, xy, k, &px, &py);
        if (m > 0) {
            double qx = x[(m - 1) * stride], qy = y[(m - 1) * stride];
            if (px == qx && py == qy) continue;
            sv = rs__arc_add(sv, rs__arc_len(qx, qy, px, py));
        }
        x[m * stride] = px;
        y[m * stride] = py;
        s[m] = sv;
        m++;
    }
    *m_io = m;
}

/* r's bounding box from its points. */
static void local_box(rs__road_local *r)
{
    r->x0 = r->y0 = INFINITY;
    r->x1 = r->y1 = -INFINITY;
    for (size_t k = 0; k < r->n; k++) {
        if (r->x[k] < r->x0) r->x0 = r->x[k];
        if (r->y[k] < r->y0) r->y0 = r->y[k];
        if (r->x[k] > r->x1) r->x1 = r->x[k];
        if (r->y[k] > r->y1) r->y1 = r->y[k];
    }
}

void rs__road_local_free(rs_ctx *ctx, rs__road_local *r)
{
    rs__free(ctx, r->x);
    rs__free(ctx, r->y);
    rs__free(ctx, r->s);
    memset(r, 0, sizeof *r);
}

rs_result rs__road_local_get(rs_ctx *ctx, const rs_roads *roads, size_t ri, const rs_dem *dem, rs__road_local *out)
{
    size_t n = 0;
    memset(out, 0, sizeof *out);
    rs_roads_get(roads, ri, NULL, NULL, NULL, &n);
    out->x = rs__alloc_array(ctx, n ? n : 1, sizeof(double));
    out->y = rs__alloc_array(ctx, n ? n : 1, sizeof(double));
    out->s = rs__alloc_array(ctx, n ? n : 1, sizeof(double));
    if (!out->x || !out->y || !out->s) {
        rs__road_local_free(ctx, out);
        return RS_ERR_NOMEM;
    }
    rs__local_frame F = rs__local_frame_of(dem->frame.origin_x, dem->frame.origin_y, dem->frame.cell_size);
    rs__road_local_walk(roads, ri, 0, &F, out->x, out->y, 1, out->s, &out->n);
    local_box(out);
    return RS_OK;
}

rs_result rs__road_local_all(rs_ctx *ctx, const rs_roads *roads, const rs_dem *dem, rs__road_local **rl_out,
                             double **block_out)
{
    size_t nr = rs_roads_count(roads), total = 0;
    *rl_out = NULL;
    *block_out = NULL;
    for (size_t i = 0; i < nr; i++) {
        size_t n = 0;
        rs_roads_get(roads, i, NULL, NULL, NULL, &n);
        total += n; /* (each road's points are held: no overflow in 3 doubles each) */
    }
    rs__road_local *rl = rs__calloc(ctx, nr ? nr : 1, sizeof *rl);
    double *block = rs__alloc_array(ctx, total ? total : 1, 3 * sizeof(double));
    if (!rl || !block) {
        rs__free(ctx, rl);
        rs__free(ctx, block);
        return RS_ERR_NOMEM;
    }
    rs__local_frame F = rs__local_frame_of(dem->frame.origin_x, dem->frame.origin_y, dem->frame.cell_size);
    double *at = block;
    for (size_t i = 0; i < nr; i++) {
        if (rs__tick(ctx, 0)) {
            rs__free(ctx, rl);
            rs__free(ctx, block);
            return RS_ERR_CANCELLED;
        }
        size_t n = 0;
        rs_roads_get(roads, i, NULL, NULL, NULL, &n);
        rs__road_local *o = &rl[i];
        o->x = at;
        o->y = at + n;
        o->s = at + 2 * n;
        at += 3 * n;
        rs__road_local_walk(roads, i, 0, &F, o->x, o->y, 1, o->s, &o->n);
        local_box(o);
    }
    *rl_out = rl;
    *block_out = block;
    return RS_OK;
}
