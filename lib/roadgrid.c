/* Road grid: which road cells are road, and their 8-neighbour class.
 *
 * Both marking modes aim the drawn road edge (which runs through the
 * centres of the outermost road cells, seed 000 section 2.2) at the road's
 * true half-width; docs/design.md derives the offsets used here. */
#include "roadgrid.h"
#include "mask.h"
#include "roadfield.h"

#include <math.h>
#include <string.h>

typedef struct marker {
    rs_ctx *ctx;
    rs_road_grid *g;
} marker;

static rs_result mark_span(marker *m, int64_t gy, int64_t x0, int64_t x1)
{
    rs_road_grid *g = m->g;
    if (gy < 0 || gy >= (int64_t)g->gh) return RS_OK;
    if (x0 < 0) x0 = 0;
    if (x1 >= (int64_t)g->gw) x1 = (int64_t)g->gw - 1;
    uint32_t ty = (uint32_t)gy >> RS__TILE_SHIFT, ry = (uint32_t)gy & (RS__TILE - 1);
    while (x0 <= x1) {
        uint32_t tx = (uint32_t)x0 >> RS__TILE_SHIFT;
        uint32_t rx0 = (uint32_t)x0 & (RS__TILE - 1);
        int64_t tile_end = ((int64_t)tx + 1) * RS__TILE - 1;
        int64_t e = x1 < tile_end ? x1 : tile_end;
        uint8_t **slot = &g->tiles[(size_t)ty * g->tw + tx];
        if (!*slot) {
            *slot = rs__calloc(m->ctx, RS__TILE * RS__TILE, 1);
            if (!*slot) return rs__fail(m->ctx, RS_ERR_NOMEM, "out of memory for road grid tiles");
            g->stats.tiles_allocated++;
        }
        memset(*slot + (size_t)ry * RS__TILE + rx0, RS__CELL_ROAD, (size_t)(e - x0 + 1));
        x0 = e + 1;
    }
    return RS_OK;
}

/* Intersect [*lo,*hi] with {x : lo_v <= a*x + b <= hi_v}. */
static void clip_linear(double a, double b, double lo_v, double hi_v, double *lo, double *hi)
{
    if (a == 0) {
        if (b < lo_v || b > hi_v) { *lo = 1; *hi = 0; }
        return;
    }
    double x0 = (lo_v - b) / a, x1 = (hi_v - b) / a;
    if (a < 0) { double t = x0; x0 = x1; x1 = t; }
    if (x0 > *lo) *lo = x0;
    if (x1 < *hi) *hi = x1;
}

/* Mark cells whose centre x (cell units, centre at j + 0.5) lies in [lo,hi]. */
static rs_result mark_interval(marker *m, int64_t gy, double lo, double hi)
{
    if (!(lo <= hi)) return RS_OK;
    double j0 = ceil(lo - 0.5), j1 = floor(hi - 0.5);
    if (j1 < 0 || j0 >= (double)m->g->gw || j0 > j1) return RS_OK;
    if (j0 < 0) j0 = 0;
    if (j1 > (double)m->g->gw - 1) j1 = (double)m->g->gw - 1;
    return mark_span(m, gy, (int64_t)j0, (int64_t)j1);
}

/* Rows whose centre lies in [y0,y1] (cell units), clamped to the grid. */
static void row_range(const rs_road_grid *g, double y0, double y1, int64_t *i0, int64_t *i1)
{
    double a = ceil(y0 - 0.5), b = floor(y1 - 0.5);
    if (a < 0) a = 0;
    if (b > (double)g->gh - 1) b = (double)g->gh - 1;
    *i0 = (int64_t)a;
    *i1 = (int64_t)b;
}

/* Round end or join of the distance mode: the cell centre at offset d from
 * the point is road when |d| <= h + (|dx| + |dy|) / (2|d|), the radial form
 * of the band offset (cell units). */
static rs_result mark_cap(marker *m, double px, double py, double h)
{
    double rmax = h + 0.7072;
    int64_t i0, i1;
    row_range(m->g, py - rmax, py + rmax, &i0, &i1);
    for (int64_t i = i0; i <= i1; i++) {
        double dy = (double)i + 0.5 - py;
        double jlo = floor(px - rmax), jhi = ceil(px + rmax);
        if (jlo < 0) jlo = 0;
        if (jhi > (double)m->g->gw - 1) jhi = (double)m->g->gw - 1;
        if (jlo > jhi) continue;
        int64_t j0 = (int64_t)jlo, j1 = (int64_t)jhi;
        int64_t run = -1;
        for (int64_t j = j0; j <= j1 + 1; j++) {
            int in = 0;
            if (j <= j1) {
                double dx = (double)j + 0.5 - px, d = sqrt(dx * dx + dy * dy);
                in = d == 0 || d <= h + (fabs(dx) + fabs(dy)) / (2 * d);
            }
            if (in && run < 0) run = j;
            if (!in && run >= 0) {
                rs_result r = mark_span(m, i, run, j - 1);
                if (r) return r;
                run = -1;
            }
        }
    }
    return RS_OK;
}

/* Distance mode, one segment (cell units): the band of cell centres within
 * h + (|nx|+|ny|)/2 of the segment, n its unit normal. */
static rs_result mark_segment_distance(marker *m, double ax, double ay, double bx, double by, double h)
{
    double dx = bx - ax, dy = by - ay, len = hypot(dx, dy);
    if (!(len > 0)) return RS_OK;
    double tx = dx / len, ty = dy / len;
    double r = h + 0.5 * (fabs(tx) + fabs(ty));
    int64_t i0, i1;
    row_range(m->g, fmin(ay, by) - r, fmax(ay, by) + r, &i0, &i1);
    for (int64_t i = i0; i <= i1; i++) {
        double yc = (double)i + 0.5 - ay;
        double lo = -1e300, hi = 1e300;
        /* along: 0 <= (x-ax)*tx + yc*ty <= len; across: |-(x-ax)*ty + yc*tx| <= r */
        clip_linear(tx, -ax * tx + yc * ty, 0, len, &lo, &hi);
        clip_linear(-ty, ax * ty + yc * tx, -r, r, &lo, &hi);
        rs_result res = mark_interval(m, i, lo, hi);
        if (res) return res;
    }
    return RS_OK;
}

/* Clip segment A-B to a disc around the grid grown by `pad` cells, so that
 * far-away or huge coordinates never reach an integer conversion and lose
 * no precision across the line. Segments already inside are left exactly as
 * they are. Returns 0 when nothing is left. */
static int clip_segment(const rs_road_grid *g, double pad, double *ax, double *ay, double *bx, double *by)
{
    double lo_x = -pad, lo_y = -pad, hi_x = (double)g->gw + pad, hi_y = (double)g->gh + pad;
    if (*ax >= lo_x && *ax <= hi_x && *bx >= lo_x && *bx <= hi_x && *ay >= lo_y && *ay <= hi_y && *by >= lo_y &&
        *by <= hi_y)
        return 1;
    double dx = *bx - *ax, dy = *by - *ay, len = hypot(dx, dy);
    if (!(len > 0) || !isfinite(len)) return 0;
    double tx = dx / len, ty = dy / len, cx = 0.5 * g->gw, cy = 0.5 * g->gh;
    double rad = 0.5 * hypot((double)g->gw, (double)g->gh) + pad;
    double ex = cx - *ax, ey = cy - *ay;
    double dist = -ty * ex + tx * ey; /* signed distance of the centre from the line */
    if (fabs(dist) > rad) return 0;   /* the line misses the disc */
    /* Foot of the perpendicular from the centre: built from the centre, so it
     * keeps full precision however far away A and B are. */
    double px = cx + ty * dist, py = cy - tx * dist;
    double sc = ex * tx + ey * ty, s0 = -sc, s1 = len - sc;
    if (s0 < -rad) s0 = -rad;
    if (s1 > rad) s1 = rad;
    if (s0 > s1) return 0;
    *ax = px + s0 * tx;
    *ay = py + s0 * ty;
    *bx = px + s1 * tx;
    *by = py + s1 * ty;
    return 1;
}

/* Dilate mode: the k x k square around centreline cell (x, y). */
static rs_result mark_square(marker *m, int64_t x, int64_t y, int64_t k)
{
    if (x + k < 0 || x - k >= (int64_t)m->g->gw) return RS_OK;
    for (int64_t yy = y - k; yy <= y + k; yy++) {
        rs_result r = mark_span(m, yy, x - k, x + k);
        if (r) return r;
    }
    return RS_OK;
}

/* Dilate mode, one segment: 8-connected centreline raster between the cells
 * holding the end points, each cell dilated by a k x k square. One cell per
 * step along the major axis, the minor coordinate rounded to nearest; where
 * the line passes exactly between two cells both are taken, so the raster
 * is the same whichever end it starts from and under every 90-degree turn or
 * mirroring (plain Bresenham breaks such ties towards its start point). */
static rs_result mark_segment_dilate(marker *m, double ax, double ay, double bx, double by, double h)
{
    double dx = bx - ax, dy = by - ay, len = hypot(dx, dy);
    double nx = len > 0 ? fabs(dy / len) : 0, ny = len > 0 ? fabs(dx / len) : 1;
    /* The dilated band's edge lands at k(|nx|+|ny|) - min(|nx|,|ny|)/2 cells. */
    double kf = (h + 0.5 * fmin(nx, ny)) / (nx + ny);
    /* A band wider than the grid covers it all; keeps the casts defined. */
    double kmax = (double)m->g->gw + (double)m->g->gh + 2;
    if (!(kf <= kmax)) kf = kmax;
    int64_t k = (int64_t)floor(kf + 0.5);
    if (k < 0) k = 0;
    if (!clip_segment(m->g, (double)k + 2, &ax, &ay, &bx, &by)) return RS_OK;
    int64_t x0 = (int64_t)floor(ax), y0 = (int64_t)floor(ay), x1 = (int64_t)floor(bx), y1 = (int64_t)floor(by);
    int64_t ddx = x1 > x0 ? x1 - x0 : x0 - x1, ddy = y1 > y0 ? y1 - y0 : y0 - y1;
    int xmajor = ddx >= ddy;
    /* major/minor start, step and length; minor offset at step s is
     * s*dmin/dmaj = q + rem/(2*dmaj) with rem in [0, 2*dmaj) */
    int64_t p0 = xmajor ? x0 : y0, q0 = xmajor ? y0 : x0;
    int64_t sp = (xmajor ? x1 > x0 : y1 > y0) ? 1 : -1, sq = (xmajor ? y1 > y0 : x1 > x0) ? 1 : -1;
    int64_t dmaj = xmajor ? ddx : ddy, dmin = xmajor ? ddy : ddx, q = 0, rem = 0;
    for (int64_t s = 0; s <= dmaj; s++) {
        int64_t lo = rem > dmaj ? q + 1 : q, hi = rem >= dmaj && dmaj > 0 ? q + 1 : q;
        for (int64_t t = lo; t <= hi; t++) {
            int64_t p = p0 + sp * s, c = q0 + sq * t;
            rs_result r = xmajor ? mark_square(m, p, c, k) : mark_square(m, c, p, k);
            if (r) return r;
        }
        rem += 2 * dmin;
        if (rem >= 2 * dmaj && dmaj > 0) { rem -= 2 * dmaj; q++; }
    }
    return RS_OK;
}

static int inside_box(const rs_road_grid *g, double x0, double y0, double x1, double y1, double pad)
{
    return !(fmax(x0, x1) + pad < 0 || fmin(x0, x1) - pad > (double)g->gw ||
             fmax(y0, y1) + pad < 0 || fmin(y0, y1) - pad > (double)g->gh);
}

static rs_result mark_road(marker *m, const double *pts, size_t n, double width, rs_buffer_mode mode,
                           double ox, double oy, double *scratch)
{
    const rs_road_grid *g = m->g;
    double per_unit = rs__local_quantum(g->cell_size);
    for (size_t i = 0; i < n; i++) {
        scratch[2 * i] = rs__local_coord(pts[2 * i], ox, per_unit);
        scratch[2 * i + 1] = rs__local_coord(pts[2 * i + 1], oy, per_unit);
    }
    const double *xy = scratch;
    double inv = 1.0 / g->c, h = 0.5 * width * inv;
    double hmax = (double)g->gw + (double)g->gh + 2; /* wider covers the whole grid anyway */
    if (h > hmax) h = hmax;
    double pad = h + 2.0;
    int moving = 0; /* some segment has non-zero length */
    for (size_t i = 0; i + 1 < n && !moving; i++)
        moving = xy[2 * i] != xy[2 * i + 2] || xy[2 * i + 1] != xy[2 * i + 3];
    for (size_t i = 0; i < n; i++) {
        double ax = xy[2 * i] * inv, ay = xy[2 * i + 1] * inv;
        rs_result r = RS_OK;
        if (mode == RS_BUFFER_DISTANCE) {
            if (inside_box(g, ax, ay, ax, ay, pad)) r = mark_cap(m, ax, ay, h);
            if (!r && i + 1 < n) {
                double bx = xy[2 * i + 2] * inv, by = xy[2 * i + 3] * inv, cx = ax, cy = ay;
                /* clip first: the band's direction is kept, far parts can't matter */
                if (inside_box(g, ax, ay, bx, by, pad) && clip_segment(g, pad, &cx, &cy, &bx, &by))
                    r = mark_segment_distance(m, cx, cy, bx, by, h);
            }
        } else if (i + 1 < n || n == 1) {
            double bx = i + 1 < n ? xy[2 * i + 2] * inv : ax, by = i + 1 < n ? xy[2 * i + 3] * inv : ay;
            /* A repeated point is no segment: it would get the square of an
             * axis-aligned road, wider than a diagonal road's band. Only a
             * road that is one point throughout is drawn as that square. */
            int dot = bx == ax && by == ay;
            if ((!dot || (!moving && i == 0)) && inside_box(g, ax, ay, bx, by, pad))
                r = mark_segment_dilate(m, ax, ay, bx, by, h);
        }
        if (r) return r;
    }
    return RS_OK;
}

/* Road bit of cell (x, y), clamped to the grid: outside, a neighbour copies
 * the nearest inside cell, so roads leaving the map get no border there. */
static unsigned road_at(const rs_road_grid *g, int64_t x, int64_t y)
{
    if (x < 0) x = 0;
    if (y < 0) y = 0;
    if (x >= (int64_t)g->gw) x = (int64_t)g->gw - 1;
    if (y >= (int64_t)g->gh) y = (int64_t)g->gh - 1;
    const uint8_t *t = rs__grid_tile(g, (uint32_t)x >> RS__TILE_SHIFT, (uint32_t)y >> RS__TILE_SHIFT);
    if (!t) return 0;
    return t[((uint32_t)y & (RS__TILE - 1)) * RS__TILE + ((uint32_t)x & (RS__TILE - 1))] & RS__CELL_ROAD;
}

static void classify_tile(rs_road_grid *g, const rs__mask_table *mt, uint32_t tx, uint32_t ty)
{
    /* Road bits (0/1) of the tile plus a one-cell ring from its neighbours. */
    enum { W = RS__TILE + 2 };
    uint8_t win[W * W], h3[W * W];
    uint8_t *t = g->tiles[(size_t)ty * g->tw + tx];
    int64_t bx = (int64_t)tx * RS__TILE, by = (int64_t)ty * RS__TILE;
    for (uint32_t y = 0; y < RS__TILE; y++)
        for (uint32_t x = 0; x < RS__TILE; x++) win[(y + 1) * W + x + 1] = t[y * RS__TILE + x] >> 7;
    for (uint32_t k = 0; k < W; k++) {
        win[k] = (uint8_t)(road_at(g, bx + k - 1, by - 1) >> 7);
        win[(W - 1) * W + k] = (uint8_t)(road_at(g, bx + k - 1, by + RS__TILE) >> 7);
        win[k * W] = (uint8_t)(road_at(g, bx - 1, by + k - 1) >> 7);
        win[k * W + W - 1] = (uint8_t)(road_at(g, bx + RS__TILE, by + k - 1) >> 7);
    }
    /* Cells past the grid's right/bottom edge copy the nearest inside cell. */
    uint32_t xe = g->gw - (uint32_t)bx < RS__TILE ? g->gw - (uint32_t)bx : RS__TILE;
    uint32_t ye = g->gh - (uint32_t)by < RS__TILE ? g->gh - (uint32_t)by : RS__TILE;
    if (xe < RS__TILE)
        for (uint32_t y = 0; y < W; y++)
            for (uint32_t x = xe + 1; x < W; x++) win[y * W + x] = win[y * W + xe];
    if (ye < RS__TILE)
        for (uint32_t y = ye + 1; y < W; y++) memcpy(win + y * W, win + ye * W, W);
    /* h3 = AND of three horizontal neighbours: interior iff three rows agree. */
    for (uint32_t y = 0; y < W; y++)
        for (uint32_t x = 1; x + 1 < W; x++)
            h3[y * W + x] = win[y * W + x - 1] & win[y * W + x] & win[y * W + x + 1];
    static const int ox[8] = { 0, 1, 1, 1, 0, -1, -1, -1 }, oy[8] = { -1, -1, 0, 1, 1, 1, 0, -1 };
    for (uint32_t y = 0; y < ye; y++) {
        for (uint32_t x = 0; x < xe; x++) {
            uint8_t *cell = &t[y * RS__TILE + x];
            if (!(*cell & RS__CELL_ROAD)) continue;
            size_t c = (size_t)(y + 1) * W + x + 1;
            g->stats.road_cells++;
            if (h3[c - W] & h3[c] & h3[c + W]) {
                *cell = RS__CELL_ROAD; /* pattern 0: interior */
                g->stats.interior_cells++;
                continue;
            }
            unsigned mask = 0;
            for (int b = 0; b < 8; b++)
                if (win[c + oy[b] * W + ox[b]]) mask |= 1u << b;
            unsigned p = mt->corners[mask];
            *cell = (uint8_t)(RS__CELL_ROAD | p);
            g->stats.boundary_cells++;
            g->stats.by_type[mt->type[p]]++;
        }
    }
}

/* Road cells per DEM cell side. Automatic: the narrowest road spans at least
 * 4 road cells and a road cell is at most half a texel, so the drawn edge is
 * finer than the output; capped at 64 and by the road-cell limit. */
static rs_result choose_k(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, double cs, uint32_t texels,
                          double road_cell, uint32_t *k_out)
{
    uint64_t cw = dem->width - 1, ch = dem->height - 1, cells;
    uint64_t k;
    if (road_cell > 0) {
        double kf = floor(cs / road_cell + 0.5);
        if (kf < 1) kf = 1;
        if (kf > 65536) return rs__fail(ctx, RS_ERR_LIMIT, "road cell %g m is too small for cell size %g m", road_cell, cs);
        k = (uint64_t)kf;
        if (!rs__mul_u64(cw * k, ch * k, &cells) || cells > ctx->limits.max_road_cells || cw * k > UINT32_MAX ||
            ch * k > UINT32_MAX)
            return rs__fail(ctx, RS_ERR_LIMIT, "road cell %g m gives more than %llu road cells", road_cell,
                            (unsigned long long)ctx->limits.max_road_cells);
        *k_out = (uint32_t)k;
        return RS_OK;
    }
    double wmin = INFINITY;
    for (size_t i = 0; i < rs_roads_count(roads); i++) {
        double w;
        if (rs_roads_get(roads, i, NULL, &w, NULL, NULL) == RS_OK && w < wmin) wmin = w;
    }
    double target = 0.5 * cs / texels;
    if (wmin / 4 < target) target = wmin / 4;
    double kf = ceil(cs / target - 1e-9);
    k = kf < 1 ? 1 : (kf > 64 ? 64 : (uint64_t)kf);
    while (k > 1 && (!rs__mul_u64(cw * k, ch * k, &cells) || cells > ctx->limits.max_road_cells)) k--;
    *k_out = (uint32_t)k;
    return RS_OK;
}

void rs_road_grid_free(rs_ctx *ctx, rs_road_grid *grid)
{
    if (!ctx || !grid) return;
    rs__roadfield_free(ctx, grid->field);
    if (grid->tiles) {
        for (size_t i = 0; i < (size_t)grid->tw * grid->th; i++) rs__free(ctx, grid->tiles[i]);
        rs__free(ctx, grid->tiles);
    }
    rs__free(ctx, grid);
}

void rs_road_grid_get_stats(const rs_road_grid *grid, rs_road_grid_stats *out)
{
    if (grid && out) *out = grid->stats;
}

void rs__grid_size(const rs_road_grid *g, uint32_t *gw, uint32_t *gh)
{
    *gw = g->tiles ? g->gw : 0;
    *gh = g->tiles ? g->gh : 0;
}

int rs__grid_cell(const rs_road_grid *g, uint32_t x, uint32_t y, unsigned *pattern)
{
    if (!g->tiles || x >= g->gw || y >= g->gh) return 0;
    const uint8_t *t = rs__grid_tile(g, x >> RS__TILE_SHIFT, y >> RS__TILE_SHIFT);
    unsigned c = t ? t[(y & (RS__TILE - 1)) * RS__TILE + (x & (RS__TILE - 1))] : 0;
    if (!(c & RS__CELL_ROAD)) return 0;
    *pattern = c & RS__CELL_PATTERN;
    return 1;
}

int rs_road_grid_query(const rs_road_grid *grid, double x, double y, double reach, rs_road_point *out)
{
    rs__road_point p;
    if (!grid || !grid->field || !out || !(reach >= 0) || !rs__roadfield_nearest(grid->field, x, y, reach, &p))
        return 0;
    out->road = p.road;
    out->segment = p.seg;
    out->s = p.s;
    out->t = p.t;
    out->distance = p.dist;
    return 1;
}

/* Analytic edges: the road field over the map. */
static rs_result build_field(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, uint32_t texels,
                             rs_road_grid *g)
{
    rs__roadfield_params p;
    memset(&p, 0, sizeof p);
    p.origin_x = dem->frame.origin_x;
    p.origin_y = dem->frame.origin_y;
    p.cell_size = dem->frame.cell_size;
    p.width_m = (double)(dem->width - 1) * dem->frame.cell_size;
    p.height_m = (double)(dem->height - 1) * dem->frame.cell_size;
    p.pixel = dem->frame.cell_size / texels;
    rs_result r = rs__roadfield_build(ctx, roads, &p, &g->field);
    if (r == RS_OK) {
        for (size_t i = 0; i < rs_roads_count(roads); i++) {
            size_t np = 0;
            rs_roads_get(roads, i, NULL, NULL, NULL, &np);
            g->stats.segments += np > 1 ? np - 1 : 1;
        }
        g->stats.bytes += rs__roadfield_bytes(g->field);
    }
    return r;
}

rs_result rs_road_grid_build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *opts,
                             rs_road_grid **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_road_grid_build");
    *out = NULL;
    if (!dem || !roads) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_road_grid_build");
    rs_splat_options o;
    rs_result r = rs__splat_defaults(ctx, opts, &o);
    if (r) return r;
    rs_road_grid *g = rs__calloc(ctx, 1, sizeof *g);
    if (!g) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the road grid");
    g->dem_w = dem->width;
    g->dem_h = dem->height;
    g->frame = dem->frame;
    g->texels = o.texels;
    g->opts = o.grid;
    g->edges = o.coverage.edges;
    g->cell_size = dem->frame.cell_size;
    g->stats.bytes = sizeof *g;
    if (o.coverage.edges == RS_EDGES_ANALYTIC) {
        r = build_field(ctx, dem, roads, o.texels, g);
        if (r) {
            rs_road_grid_free(ctx, g);
            return r;
        }
        *out = g;
        rs__ok(ctx);
        return RS_OK;
    }
    uint32_t k = 1;
    r = choose_k(ctx, dem, roads, dem->frame.cell_size, o.texels, o.grid.road_cell, &k);
    if (r) {
        rs__free(ctx, g);
        return r;
    }
    g->k = k;
    g->c = g->cell_size / k;
    g->gw = (dem->width - 1) * k;
    g->gh = (dem->height - 1) * k;
    g->tw = (g->gw + RS__TILE - 1) / RS__TILE;
    g->th = (g->gh + RS__TILE - 1) / RS__TILE;
    g->stats.k = k;
    g->stats.road_cell = g->c;
    g->tiles = rs__calloc(ctx, (size_t)g->tw * g->th, sizeof *g->tiles);
    if (!g->tiles) {
        rs__free(ctx, g);
        return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the road grid directory");
    }
    marker m = { ctx, g };
    size_t n = rs_roads_count(roads), most = 0;
    for (size_t i = 0; i < n; i++) {
        size_t np;
        rs_roads_get(roads, i, NULL, NULL, NULL, &np);
        if (np > most) most = np;
    }
    double *scratch = rs__alloc_array(ctx, most ? 2 * most : 2, sizeof *scratch);
    if (!scratch) {
        rs_road_grid_free(ctx, g);
        return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for road points");
    }
    for (size_t i = 0; i < n && !r; i++) {
        const double *xy;
        size_t np;
        double w;
        rs_roads_get(roads, i, NULL, &w, &xy, &np);
        r = mark_road(&m, xy, np, w, o.grid.buffer, dem->frame.origin_x, dem->frame.origin_y, scratch);
        if (!r && o.progress && o.progress(o.progress_user, i + 1, n)) r = rs__fail(ctx, RS_ERR_CANCELLED, "cancelled");
    }
    rs__free(ctx, scratch);
    rs__mask_table mt;
    rs__mask_table_build(&mt);
    if (!r)
        for (uint32_t ty = 0; ty < g->th; ty++)
            for (uint32_t tx = 0; tx < g->tw; tx++)
                if (g->tiles[(size_t)ty * g->tw + tx]) classify_tile(g, &mt, tx, ty);
    if (r) {
        rs_road_grid_free(ctx, g);
        return r;
    }
    g->stats.bytes = sizeof *g + (uint64_t)g->tw * g->th * sizeof *g->tiles +
                     g->stats.tiles_allocated * RS__TILE * RS__TILE;
    *out = g;
    rs__ok(ctx);
    return RS_OK;
}
