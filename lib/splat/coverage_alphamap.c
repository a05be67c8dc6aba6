/* Coverage stage, alpha-map edges (seed 000): the road weight of a pixel is
 * the exact integral of its road cells' alpha-map tiles over the pixel's
 * footprint (a box filter), via summed-area tables of the bilinear
 * alpha-maps. Overlaps are integers in units of 1/(K*T) DEM cell. */
#include "splatter.h"

#include <math.h>
#include <string.h>

static void table_build(rs__alpha_table *t)
{
    uint32_t n = t->n;
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = 0; j < n; j++) {
            size_t k = (size_t)i * n + j;
            double fv = t->f[k];
            t->col[k] = i ? t->col[k - n] + 0.5 * (t->f[k - n] + fv) : 0;
            t->row[k] = j ? t->row[k - 1] + 0.5 * (t->f[k - 1] + fv) : 0;
            if (!i || !j) t->s[k] = 0;
            else
                t->s[k] = t->s[k - n] + t->s[k - 1] - t->s[k - n - 1] +
                          0.25 * (t->f[k - n - 1] + t->f[k - n] + t->f[k - 1] + fv);
        }
}

void rs__alphamap_tables_free(rs_ctx *ctx, rs_splatter *s)
{
    for (int i = 0; i < 3; i++) {
        rs__free(ctx, s->tab[i].f);
        rs__free(ctx, s->tab[i].s);
        rs__free(ctx, s->tab[i].col);
        rs__free(ctx, s->tab[i].row);
        memset(&s->tab[i], 0, sizeof s->tab[i]);
    }
}

rs_result rs__alphamap_tables_build(rs_ctx *ctx, rs_splatter *s)
{
    static const rs_tile_type types[3] = { RS_TILE_EDGE, RS_TILE_INNER, RS_TILE_OUTER };
    const rs_coverage_options *c = &s->o.coverage;
    uint32_t R = c->alpha_res;
    size_t n = (size_t)(R + 1) * (R + 1);
    for (int i = 0; i < 3; i++) {
        rs__alpha_table *t = &s->tab[i];
        t->n = R + 1;
        t->h2 = 1.0 / ((double)R * R);
        t->f = rs__alloc_array(ctx, n, sizeof *t->f);
        t->s = rs__alloc_array(ctx, n, sizeof *t->s);
        t->col = rs__alloc_array(ctx, n, sizeof *t->col);
        t->row = rs__alloc_array(ctx, n, sizeof *t->row);
        if (!t->f || !t->s || !t->col || !t->row) {
            rs__alphamap_tables_free(ctx, s);
            return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the alpha-map tables");
        }
        rs__alpha_map_float(types[i], R, c->hard_edge ? 0 : c->transition_px, c->jitter_seed,
                            c->jitter ? c->jitter_amount : 0, t->f);
        table_build(t);
    }
    return RS_OK;
}

/* Integral of the bilinear alpha-map over [0,x] x [0,y] (pixel units). */
static double table_F(const rs__alpha_table *t, double x, double y)
{
    uint32_t last = t->n - 1;
    double xf = floor(x), yf = floor(y);
    uint32_t X = xf >= last ? last - 1 : (uint32_t)xf, Y = yf >= last ? last - 1 : (uint32_t)yf;
    double fx = x - X, fy = y - Y;
    size_t k = (size_t)Y * t->n + X;
    double r = t->s[k];
    r += fx * t->col[k] + 0.5 * fx * fx * (t->col[k + 1] - t->col[k]);
    r += fy * t->row[k] + 0.5 * fy * fy * (t->row[k + t->n] - t->row[k]);
    double A = fx - 0.5 * fx * fx, B = 0.5 * fx * fx, C = fy - 0.5 * fy * fy, D = 0.5 * fy * fy;
    r += t->f[k] * A * C + t->f[k + 1] * B * C + t->f[k + t->n] * A * D + t->f[k + t->n + 1] * B * D;
    return r;
}

/* Integral of the canonical tile over [u0,u1]x[v0,v1] (cell-local). */
static double table_rect(const rs__alpha_table *t, double u0, double v0, double u1, double v1)
{
    double s = (double)(t->n - 1);
    u0 *= s; u1 *= s; v0 *= s; v1 *= s;
    return (table_F(t, u1, v1) - table_F(t, u0, v1) - table_F(t, u1, v0) + table_F(t, u0, v0)) * t->h2;
}

/* Integral of the canonical tile turned `rot` quarter turns clockwise. */
static double table_rect_rot(const rs__alpha_table *t, int rot, double u0, double v0, double u1, double v1)
{
    switch (rot & 3) {
    case 1: return table_rect(t, v0, 1 - u1, v1, 1 - u0);
    case 2: return table_rect(t, 1 - u1, 1 - v1, 1 - u0, 1 - v0);
    case 3: return table_rect(t, 1 - v1, u0, 1 - v0, u1);
    default: return table_rect(t, u0, v0, u1, v1);
    }
}

/* Add the road weight of the cells [gx, gx_end) of road-cell row ly (of the
 * piece's DEM row) to the piece's pixels: one boundary cell of `type`, or a
 * run of interior cells (all road: plain overlap areas). Each pixel gets one
 * term per call, computed from integers that do not depend on the piece's
 * bounds, and calls come in the same order for every piece. */
static void add_cells(const rs_splatter *s, rs__piece *p, uint32_t T, uint32_t K, uint32_t gx, uint32_t gx_end,
                      uint32_t ly, rs_tile_type type, int rot)
{
    uint64_t cx0 = (uint64_t)gx * T, cx1 = (uint64_t)gx_end * T, cy0 = (uint64_t)ly * T, cy1 = cy0 + T;
    uint32_t px0 = (uint32_t)(cx0 / K), px1 = (uint32_t)((cx1 - 1) / K);
    uint32_t py0 = (uint32_t)(cy0 / K), py1 = (uint32_t)((cy1 - 1) / K);
    /* the piece's rows, relative to the DEM row */
    uint32_t r_lo = p->y0 - p->crow * T, r_hi = r_lo + p->rows;
    if (py0 < r_lo) py0 = r_lo;
    if (py1 >= r_hi) py1 = r_hi - 1;
    if (px0 < p->x0) px0 = p->x0;
    if (px1 >= p->x0 + p->w) px1 = p->x0 + p->w - 1;
    double inv_t = 1.0 / T, scale = (double)T * T / ((double)K * K);
    for (uint32_t py = py0; py <= py1; py++) {
        uint64_t ty0 = (uint64_t)py * K, ty1 = ty0 + K;
        uint64_t oy0 = ty0 > cy0 ? ty0 : cy0, oy1 = ty1 < cy1 ? ty1 : cy1;
        double v0 = (double)(oy0 - cy0) * inv_t, v1 = (double)(oy1 - cy0) * inv_t;
        double *row = p->cov + (size_t)(py - r_lo) * p->w - p->x0;
        for (uint32_t px = px0; px <= px1; px++) {
            uint64_t tx0 = (uint64_t)px * K, tx1 = tx0 + K;
            uint64_t ox0 = tx0 > cx0 ? tx0 : cx0, ox1 = tx1 < cx1 ? tx1 : cx1;
            double u0 = (double)(ox0 - cx0) * inv_t, u1 = (double)(ox1 - cx0) * inv_t;
            double area = (u1 - u0) * (v1 - v0), alpha = 0;
            if (type == RS_TILE_INTERIOR) {
                row[px] += (double)(ox1 - ox0) * (double)(oy1 - oy0) / ((double)K * K);
                continue;
            }
            switch (type) {
            case RS_TILE_EDGE: alpha = table_rect_rot(&s->tab[0], rot, u0, v0, u1, v1); break;
            case RS_TILE_INNER: alpha = table_rect_rot(&s->tab[1], rot, u0, v0, u1, v1); break;
            case RS_TILE_OUTER: alpha = table_rect_rot(&s->tab[2], rot, u0, v0, u1, v1); break;
            case RS_TILE_SADDLE:
                alpha = table_rect_rot(&s->tab[1], rot, u0, v0, u1, v1) +
                        table_rect_rot(&s->tab[1], rot + 2, u0, v0, u1, v1);
                break;
            default: break;
            }
            row[px] += (area - alpha) * scale;
        }
    }
}

void rs__coverage_alphamap(const rs_splatter *s, rs__piece *p)
{
    const rs_road_grid *g = s->grid;
    const uint32_t T = s->o.texels, K = g->k;
    memset(p->cov, 0, (size_t)p->rows * p->w * sizeof *p->cov);
    /* Road cells overlapping the piece: rows of this DEM row whose pixels
     * reach the piece's rows, columns reaching its columns. */
    uint32_t r_lo = p->y0 - p->crow * T, r_hi = r_lo + p->rows;
    uint32_t ly0 = (uint32_t)((uint64_t)r_lo * K / T), ly1 = (uint32_t)(((uint64_t)r_hi * K - 1) / T);
    uint32_t gx_lo = (uint32_t)((uint64_t)p->x0 * K / T);
    uint32_t gx_hi = (uint32_t)(((uint64_t)(p->x0 + p->w) * K - 1) / T);
    for (uint32_t ly = ly0; ly <= ly1 && ly < K; ly++) {
        uint32_t gy = p->crow * K + ly;
        uint32_t ty = gy >> RS__TILE_SHIFT;
        for (uint32_t tx = gx_lo >> RS__TILE_SHIFT; tx <= gx_hi >> RS__TILE_SHIFT && tx < g->tw; tx++) {
            const uint8_t *tile = rs__grid_tile(g, tx, ty);
            if (!tile) continue;
            const uint8_t *trow = tile + (size_t)(gy & (RS__TILE - 1)) * RS__TILE;
            uint32_t gx0 = tx * RS__TILE, xe = g->gw - gx0 < RS__TILE ? g->gw - gx0 : RS__TILE;
            uint32_t x = gx_lo > gx0 ? gx_lo - gx0 : 0, xend = gx_hi - gx0 + 1 < xe ? gx_hi - gx0 + 1 : xe;
            while (x < xend) {
                uint8_t cell = trow[x];
                if (!(cell & RS__CELL_ROAD)) { x++; continue; }
                unsigned pat = cell & RS__CELL_PATTERN;
                rs_tile_type type = (rs_tile_type)s->mt.type[pat];
                uint32_t x1 = x + 1;
                if (type == RS_TILE_INTERIOR)
                    while (x1 < xe && trow[x1] == cell) x1++;
                if (type != RS_TILE_TERRAIN) add_cells(s, p, T, K, gx0 + x, gx0 + x1, ly, type, s->mt.rot[pat]);
                x = x1;
            }
        }
    }
}
