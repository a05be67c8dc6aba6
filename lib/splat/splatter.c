/* The splatter: validation and the per-splatter tables once, then any
 * window of the output in pieces, each through the four stages
 * (lib/splat/splatter.h; docs/design.md "Stages"). */
#include "splatter.h"
#include "roadfield.h"
#include "dem.h"
#include "linesym.h"

#include <math.h>
#include <string.h>

/* Output size for options already checked by rs__splat_defaults. */
static rs_result output_size(rs_ctx *ctx, const rs_dem *dem, const rs_splat_options *o, uint32_t *width,
                             uint32_t *height)
{
    uint64_t w = (uint64_t)(dem->width - 1) * o->texels, h = (uint64_t)(dem->height - 1) * o->texels, px;
    if (!rs__mul_u64(w, h, &px) || px > ctx->limits.max_pixels || w > UINT32_MAX || h > UINT32_MAX)
        return rs__fail(ctx, RS_ERR_LIMIT, "output of %llu x %llu pixels exceeds the limit of %llu pixels",
                        (unsigned long long)w, (unsigned long long)h, (unsigned long long)ctx->limits.max_pixels);
    *width = (uint32_t)w;
    *height = (uint32_t)h;
    return RS_OK;
}

rs_result rs_splat_size(rs_ctx *ctx, const rs_dem *dem, const rs_splat_options *opts, uint32_t *width,
                        uint32_t *height)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!dem || !width || !height) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_splat_size");
    rs_splat_options o;
    rs_result r = rs__splat_defaults(ctx, opts, &o);
    if (!r) r = output_size(ctx, dem, &o, width, height);
    if (!r) rs__ok(ctx);
    return r;
}

/* A grid is only valid for the DEM, frame and options it was built with. */
static rs_result check_grid(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *g, const rs_splat_options *o)
{
    const char *what = NULL;
    if (g->dem_w != dem->width || g->dem_h != dem->height) what = "another DEM size";
    else if (g->frame.cell_size != dem->frame.cell_size) what = "another cell size";
    else if (g->frame.origin_x != dem->frame.origin_x || g->frame.origin_y != dem->frame.origin_y)
        what = "another origin";
    else if (g->edges != o->coverage.edges) what = "another edge mode";
    else if (g->style.profile != o->style.profile || g->style.aa != o->style.aa ||
             (g->style.disable != 0) != (o->style.disable != 0))
        what = "other style options";
    else if (g->marks.atlas != o->markings.atlas || (g->marks.no_auto != 0) != (o->markings.no_auto != 0) ||
             (g->marks.disable != 0) != (o->markings.disable != 0))
        what = "other marking options";
    else if (g->edges == RS_EDGES_ALPHAMAP &&
             (g->texels != o->texels || g->opts.buffer != o->grid.buffer || g->opts.road_cell != o->grid.road_cell))
        what = "other texels or grid options";
    else if ((g->styling || g->markings) && g->texels != o->texels)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "road grid with styles or markings was built for %u texels, not %u (its line symbols, "
                        "casings and markings are laid out in its pixels)",
                        g->texels, o->texels);
    if (what) return rs__fail(ctx, RS_ERR_INVALID_ARG, "road grid was built for %s", what);
    return RS_OK;
}

void rs_splatter_free(rs_ctx *ctx, rs_splatter *s)
{
    if (!ctx || !s) return;
    for (uint32_t k = 0; s->view && k < s->nview; k++) rs__roadfield_free(ctx, s->view[k].field_own);
    rs__free(ctx, s->view);
    rs__free(ctx, s->view_rect);
    rs__alphamap_tables_free(ctx, s);
    rs__free(ctx, s->z_own);
    rs__free(ctx, s->tcol);
    rs__roadfield_free(ctx, s->field_own);
    rs__free(ctx, s->ramp_own);
    rs_road_grid_free(ctx, s->grid_own);
    rs__free(ctx, s);
}

static rs_result splatter_make(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_road_grid *grid,
                               const rs_splat_options *opts, int lean, rs_splatter **out);

rs_result rs_splatter_create(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_road_grid *grid,
                             const rs_splat_options *opts, rs_splatter **out)
{
    return splatter_make(ctx, dem, roads, grid, opts, 0, out);
}

rs_result rs__splatter_create_lean(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *grid,
                                   const rs_splat_options *opts, rs_splatter **out)
{
    return splatter_make(ctx, dem, NULL, grid, opts, 1, out);
}

static rs_result splatter_make(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_road_grid *grid,
                               const rs_splat_options *opts, int lean, rs_splatter **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_splatter_create: out is NULL");
    *out = NULL;
    if (!dem || (!roads) == (!grid))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_splatter_create: needs a DEM and exactly one of roads and grid");
    rs_splat_options o;
    rs_result r = rs__splat_defaults(ctx, opts, &o);
    uint32_t w = 0, h = 0;
    if (!r) r = output_size(ctx, dem, &o, &w, &h);
    if (!r && grid) r = check_grid(ctx, dem, grid, &o);
    if (!r && o.lighting.enable) r = rs__lighting_check(ctx, &o.lighting);
    if (r) return r;
    rs_splatter *s = rs__calloc(ctx, 1, sizeof *s);
    if (!s) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the splatter");
    s->dem = dem;
    s->o = o;
    s->out_w = w;
    s->out_h = h;
    s->texel_m = dem->frame.cell_size / o.texels;
    /* progress: the grid build's units (a road per unit in each of its
     * five stages) and one for the rest; polls between the parts (the road
     * field indexed anew polls within). Alpha-map edges: their grid's
     * sweep reports itself, as rs_road_grid_build does. */
    rs__progress pg;
    memset(&pg, 0, sizeof pg);
    pg.nested = 1;
    if (o.coverage.edges == RS_EDGES_ANALYTIC)
        rs__progress_begin(ctx, &pg, o.progress, o.progress_user, (roads ? 5 * (uint64_t)rs_roads_count(roads) + 1 : 0) + 1,
                           64);
    if (roads) {
        /* the grid's progress is the caller's: it is the slow part */
        r = rs_road_grid_build(ctx, dem, roads, &o, &s->grid_own);
        s->grid = s->grid_own;
    } else s->grid = grid;
    if (!r && rs__poll(ctx)) r = RS_ERR_CANCELLED;
    /* a grid made for finer pixels (more texels) is indexed anew for these:
     * its coverage would otherwise search the cells around every pixel.
     * (A grid with styles or markings is drawn at its own texels only:
     * check_grid.) */
    if (!r && s->grid->field && o.coverage.edges == RS_EDGES_ANALYTIC &&
        s->texel_m > rs__roadfield_pixel(s->grid->field))
        r = rs__roadfield_repixel(ctx, s->grid->field, s->texel_m, &s->field_own);
    if (!r) s->field = s->field_own ? s->field_own : s->grid->field;
    rs__mask_table_build(&s->mt);
    if (!r && o.coverage.edges == RS_EDGES_ALPHAMAP) r = rs__alphamap_tables_build(ctx, s);
    int nodata = 0;
    rs_dem_height_range(dem, &s->zmin, &s->zrange, &nodata);
    s->zrange -= s->zmin;
    if (!r && o.surface.ramp) {
        s->ramp_own = rs__alloc_array(ctx, o.surface.ramp_count, sizeof *s->ramp_own);
        if (!s->ramp_own) r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the colour ramp");
        else memcpy(s->ramp_own, o.surface.ramp, o.surface.ramp_count * sizeof *s->ramp_own);
        s->o.surface.ramp = s->ramp_own;
    }
    s->z = dem->z;
    if (!r && nodata && rs__poll(ctx)) r = RS_ERR_CANCELLED;
    if (!r && nodata) {
        r = rs__dem_fill_nodata(ctx, dem, &s->z_own);
        s->z = s->z_own;
    }
    double zen = (90.0 - 45.0) * RS__PI / 180.0;
    s->sun_az = fmod(360.0 - 315.0 + 90.0, 360.0) * RS__PI / 180.0;
    s->cos_zen = cos(zen);
    s->sin_zen = sin(zen);
    if (o.lighting.enable) {
        double az = (o.lighting.sun_given ? o.lighting.sun_azimuth : 315.0) * RS__PI / 180.0;
        double alt = (o.lighting.sun_given ? o.lighting.sun_altitude : 45.0) * RS__PI / 180.0;
        s->light[0] = sin(az) * cos(alt); /* east */
        s->light[1] = cos(az) * cos(alt); /* north */
        s->light[2] = sin(alt);
        double hz = s->light[2] + 1, hl = sqrt(s->light[0] * s->light[0] + s->light[1] * s->light[1] + hz * hz);
        s->half[0] = s->light[0] / hl;
        s->half[1] = s->light[1] / hl;
        s->half[2] = hz / hl;
        s->ambient = o.lighting.ambient > 0 ? o.lighting.ambient : 0.3;
        s->specular = o.lighting.specular;
    }
    /* per-sample terrain colours where they would dominate the splat */
    if (!r && !lean) r = rs__surface_colours(ctx, s);
    /* a patched grid: a view of this splatter per patch, on its grid */
    if (!r && s->grid->npatch) {
        uint32_t n = (uint32_t)s->grid->npatch;
        s->view = rs__calloc(ctx, n, sizeof *s->view);
        s->view_rect = rs__alloc_array(ctx, n, sizeof *s->view_rect);
        if (!s->view || !s->view_rect) r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the splatter");
        for (uint32_t k = 0; !r && k < n; k++) {
            rs_splatter *v = &s->view[k];
            *v = *s;
            v->grid_own = NULL, v->field_own = NULL, v->z_own = NULL, v->ramp_own = NULL;
            v->view = NULL, v->view_rect = NULL, v->nview = 0;
            v->grid = s->grid->patch[k].grid;
            s->view_rect[k] = s->grid->patch[k].rect;
            s->nview = k + 1;
            uint32_t same = 0; /* (one update's rectangles share a grid: its field once) */
            while (same < k && s->view[same].grid != v->grid) same++;
            if (same < k) v->field = s->view[same].field;
            else {
                if (v->grid->field && s->texel_m > rs__roadfield_pixel(v->grid->field))
                    r = rs__roadfield_repixel(ctx, v->grid->field, s->texel_m, &v->field_own);
                v->field = v->field_own ? v->field_own : v->grid->field;
            }
        }
    }
    if (r == RS_ERR_NOMEM) r = rs__fail(ctx, r, "out of memory for the terrain colours");
    r = rs__progress_end(ctx, &pg, r);
    if (r) {
        rs_splatter_free(ctx, s);
        return r;
    }
    *out = s;
    rs__ok(ctx);
    return RS_OK;
}

void rs_splatter_size(const rs_splatter *s, uint32_t *width, uint32_t *height)
{
    if (width) *width = s ? s->out_w : 0;
    if (height) *height = s ? s->out_h : 0;
}

const rs_road_grid *rs_splatter_grid(const rs_splatter *s) { return s ? s->grid : NULL; }

/* Piece size: about 2^18 pixels of scratch (9 MB) whatever the window; per
 * window column, the terrain colour rows and each texture's column
 * coordinates add a few dozen bytes. A workspace (rs_splat_workspace_create)
 * holds the same scratch for every window up to its width, so a window
 * through it allocates nothing. */
#define PIECE_COLS 2048u
#define PIECE_PIXELS (1u << 18)

typedef struct scratch {
    double *cov, *hx, *tf, *ov, *ls;
    uint16_t *q;
    uint32_t *ti;
    float *tc, *sc, *trow0, *trow1;
    float *lx; /* layers, when the grid has styles or markings: casings of several colours
                  (4 planes), then the paint over 1 (3 planes); npx x 4 */
} scratch;

/* Element counts of a scratch set: for one window (w, h), or for every
 * window at most max_w wide (a workspace: h = UINT32_MAX). */
typedef struct scratch_size {
    size_t npx, cols, nax, ncol;
} scratch_size;

static scratch_size scratch_size_of(const rs_splatter *s, uint32_t w, uint32_t h)
{
    const uint32_t T = s->o.texels;
    const size_t ntex = (s->o.surface.terrain_texture != NULL) + (s->o.surface.road_texture != NULL);
    scratch_size z;
    z.cols = w < PIECE_COLS ? w : PIECE_COLS;
    size_t rows = PIECE_PIXELS / z.cols;
    if (rows > T) rows = T;
    if (rows > h) rows = h;
    /* a narrower window may take more rows of fewer columns: never more
     * than PIECE_PIXELS, nor more than cols x T */
    z.npx = z.cols * (size_t)T < PIECE_PIXELS ? z.cols * (size_t)T : PIECE_PIXELS;
    if (h != UINT32_MAX) z.npx = z.cols * rows;
    z.nax = (h != UINT32_MAX ? rows : (T < PIECE_PIXELS ? T : PIECE_PIXELS)) + (size_t)w * ntex;
    z.ncol = (size_t)w / T + 3;
    return z;
}

static void scratch_free(rs_ctx *ctx, scratch *b)
{
    rs__free(ctx, b->cov);
    rs__free(ctx, b->ov);
    rs__free(ctx, b->ls);
    rs__free(ctx, b->hx);
    rs__free(ctx, b->tf);
    rs__free(ctx, b->q);
    rs__free(ctx, b->ti);
    rs__free(ctx, b->tc);
    rs__free(ctx, b->sc);
    rs__free(ctx, b->trow0);
    rs__free(ctx, b->trow1);
    rs__free(ctx, b->lx);
}

/* The layers need the extra planes (casings, paint) only where there are any. */
static int layer_planes(const rs_splatter *s)
{
    return s->grid->styling != NULL || s->grid->markings != NULL;
}

static rs_result scratch_alloc(rs_ctx *ctx, const rs_splatter *s, const scratch_size *z, int layers, scratch *b)
{
    const int styled = s->grid->styling != NULL;
    b->cov = rs__alloc_array(ctx, z->npx, sizeof *b->cov);
    b->ov = styled ? rs__alloc_array(ctx, z->npx, sizeof *b->ov) : NULL;
    b->ls = styled ? rs__alloc_array(ctx, rs__linesym_scratch_len((uint32_t)z->cols), sizeof *b->ls) : NULL;
    b->hx = rs__alloc_array(ctx, z->cols * 6, sizeof *b->hx);
    b->tf = rs__alloc_array(ctx, z->nax * 2, sizeof *b->tf);
    b->q = rs__alloc_array(ctx, z->npx, sizeof *b->q);
    b->ti = rs__alloc_array(ctx, z->nax * 2, sizeof *b->ti);
    /* zeroed: the composite reads both colours of every pixel, selecting one */
    b->tc = rs__calloc(ctx, z->npx * 3, sizeof *b->tc);
    b->sc = rs__calloc(ctx, z->npx * 3, sizeof *b->sc);
    b->trow0 = rs__alloc_array(ctx, z->ncol * 3, sizeof *b->trow0);
    b->trow1 = rs__alloc_array(ctx, z->ncol * 3, sizeof *b->trow1);
    layers = layers && layer_planes(s);
    b->lx = layers ? rs__alloc_array(ctx, z->npx * 4, sizeof *b->lx) : NULL;
    if ((layers && !b->lx) || !b->cov || (styled && (!b->ov || !b->ls)) || !b->hx || !b->tf || !b->q || !b->ti || !b->tc || !b->sc ||
        !b->trow0 || !b->trow1) {
        scratch_free(ctx, b);
        memset(b, 0, sizeof *b);
        return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for splat scratch (%zu pixels)", z->npx);
    }
    return RS_OK;
}

struct rs_splat_workspace {
    const rs_splatter *s;
    uint32_t max_w;
    scratch b;
    rs__nm_scratch nm; /* the normals' (lit windows, normal planes): from the first call that needs them */
    size_t npx;        /* pixels of a piece */
    size_t bytes;      /* of b (but b.lx, the layers', from the first call with layers) */
};

static double now(const rs_splat_profile *pf)
{
    return pf && pf->clock_ms ? pf->clock_ms(pf->clock_user) : 0;
}

/* The layers of one piece (rs_splat_layers_window): the stages up to the
 * paint, with T kept bare (casings apart) and both colours everywhere,
 * then the planes; the paint painted over 0 (into T's scratch, written
 * by then) and over 1 (lx). */
static void layers_piece(const rs_splatter *s, const scratch *b, rs__piece *p, const rs_splat_layers *L, uint32_t ax,
                         uint32_t ay)
{
    const size_t w = p->w, n = (size_t)p->rows * w;
    p->all = 1;
    p->lcas = b->lx;
    rs__surface(s, p);
    if (b->lx)
        for (uint32_t r = 0; r < p->rows; r++) memset(b->lx + (size_t)r * w * 4 + 3 * w, 0, w * sizeof *b->lx);
    rs__overlays_casings(s, p);
    if (L->surface && L->surface_unstyled) rs__layers_surface(p, L, ax, ay);
    rs__overlays_surfaces(s, p);
    rs__layers_ground(p, L, ax, ay);
    if (!L->paint) return;
    if (b->lx && p->road_pixels) {
        for (size_t i = 0; i < 3 * n; i++) {
            p->tc[i] = 0;
            b->lx[i] = 1;
        }
        rs__overlays_paint(s, p, p->tc);
        rs__overlays_paint(s, p, b->lx);
        rs__layers_paint(p, L, ax, ay, p->tc, b->lx);
    } else {
        for (uint32_t r = 0; r < p->rows; r++) memset(L->paint + (size_t)(ay + r) * L->paint_stride + (size_t)ax * 4, 0, w * 4);
    }
}

/* The splatter drawing column x of row y: the latest view whose rectangle
 * holds it, else s */
static const rs_splatter *drawn_by(const rs_splatter *s, uint32_t x, uint32_t y)
{
    for (uint32_t k = s->nview; k-- > 0;) {
        const rs_pixel_rect *R = &s->view_rect[k];
        if (y >= R->y0 && y < R->y1 && x >= R->x0 && x < R->x1) return &s->view[k];
    }
    return s;
}

uint32_t rs__segment_next(const rs_splatter *s, uint32_t x, uint32_t x1, uint32_t y, const rs_splatter **by)
{
    *by = s;
    if (!s->nview) return x1;
    *by = drawn_by(s, x, y);
    for (;;) {
        /* the next rectangle edge on row y after x: the drawing splatter
         * may change only there */
        uint32_t end = x1;
        for (uint32_t k = 0; k < s->nview; k++) {
            const rs_pixel_rect *R = &s->view_rect[k];
            if (y < R->y0 || y >= R->y1) continue;
            if (R->x0 > x && R->x0 < end) end = R->x0;
            if (R->x1 > x && R->x1 < end) end = R->x1;
        }
        if (end >= x1 || drawn_by(s, end, y) != *by) return end;
        x = end;
    }
}

/* rs__normals_run of rows [y, y + h) of one DEM-cell row, by the
 * splatters that draw their columns (rgb or rgba at column x0) */
static rs_result normals_by_segment(rs_ctx *ctx, const rs_splatter *s, uint32_t x0, uint32_t y, uint32_t w, uint32_t h,
                                    const rs_normal_options *no, uint8_t *rgb, size_t rgb_stride, uint8_t *rgba,
                                    size_t rgba_stride, rs__nm_scratch *nm)
{
    rs_result r = RS_OK;
    for (uint32_t x = x0; x < x0 + w && !r;) {
        const rs_splatter *by;
        uint32_t end = rs__segment_next(s, x, x0 + w, y, &by);
        size_t dx = x - x0;
        r = rs__normals_run(ctx, by, x, y, end - x, h, no, rgb ? rgb + 3 * dx : NULL, rgb_stride,
                            rgba ? rgba + 4 * dx : NULL, rgba_stride, nm);
        x = end;
    }
    return r;
}

rs_result rs__normals_window(rs_ctx *ctx, const rs_splatter *s, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h,
                             const rs_normal_options *no, uint8_t *rgb, size_t rgb_stride)
{
    if (!s->nview) return rs__normals_run(ctx, s, x0, y0, w, h, no, rgb, rgb_stride, NULL, 0, NULL);
    rs_result r = RS_OK;
    for (uint32_t y = y0; y < y0 + h && !r;) {
        uint32_t end = (y / s->o.texels + 1) * s->o.texels;
        if (end > y0 + h) end = y0 + h;
        r = normals_by_segment(ctx, s, x0, y, w, end - y, no, rgb + (size_t)(y - y0) * rgb_stride, rgb_stride, NULL, 0,
                               NULL);
        y = end;
    }
    return r;
}

/* The window through the stages with scratch b, which holds at least
 * scratch_size_of(s, w, h) of everything: the colour into rgba (and
 * weight), or the layers L (rgba NULL). */
static rs_result splat_run(rs_ctx *ctx, const rs_splatter *s, scratch *bp, uint32_t x0, uint32_t y0, uint32_t w,
                           uint32_t h, uint8_t *rgba, size_t rgba_stride, uint16_t *weight, size_t weight_stride,
                           const rs_splat_layers *L, rs__nm_scratch *nm, rs_splat_profile *profile)
{
    const scratch b = *bp;
    const uint32_t T = s->o.texels;
    uint32_t cols = w < PIECE_COLS ? w : PIECE_COLS;
    uint32_t max_rows = PIECE_PIXELS / cols;
    if (max_rows > T) max_rows = T;
    if (max_rows > h) max_rows = h;
    /* terrain colour rows: the window's sample columns */
    rs__terrain_cache tcache;
    tcache.c0 = x0 / T;
    tcache.ncol = (x0 + w - 1) / T + 2 - tcache.c0;
    tcache.row_of[0] = tcache.row_of[1] = UINT32_MAX;
    /* texture coordinates: the window's columns per texture, a piece's rows */
    const int has_tex[2] = { s->o.surface.terrain_texture != NULL, s->o.surface.road_texture != NULL };
    rs__piece p;
    memset(&p, 0, sizeof p);
    p.cov = b.cov;
    p.ov = b.ov;
    p.ls = b.ls;
    p.q = b.q;
    p.tc = b.tc;
    p.sc = b.sc;
    p.hx = b.hx;
    p.win_x0 = x0;
    p.win_w = w;
    p.tiy = b.ti;
    p.twy = b.tf;
    size_t at = 2 * (size_t)max_rows;
    for (int t = 0; t < 2; t++) {
        p.tix[t] = has_tex[t] ? b.ti + at : NULL;
        p.twx[t] = has_tex[t] ? b.tf + at : NULL;
        at += has_tex[t] ? 2 * (size_t)w : 0;
    }
    tcache.rgb[0] = b.trow0;
    tcache.rgb[1] = b.trow1;
    p.tcache = &tcache;
    const int analytic = s->o.coverage.edges == RS_EDGES_ANALYTIC;
    /* progress: rows done of h, and a poll after every piece (a band of a
     * wide window is many pieces) */
    rs__progress pg;
    rs__progress_begin(ctx, &pg, s->o.progress, s->o.progress_user, h, 1);
    rs_result r = RS_OK;
    for (uint32_t y = y0; y < y0 + h && !r;) {
        p.crow = y / T;
        uint32_t row_end = (p.crow + 1) * T;
        if (row_end > y0 + h) row_end = y0 + h;
        p.y0 = y;
        p.rows = row_end - y < max_rows ? row_end - y : max_rows;
        for (uint32_t x = x0; x < x0 + w; x += cols) {
            /* the piece's runs by the grid that draws them: a patch's, or the base's */
            uint32_t pw = x0 + w - x < cols ? x0 + w - x : cols;
            for (uint32_t sx = x; sx < x + pw;) {
                const rs_splatter *ps;
                uint32_t send = rs__segment_next(s, sx, x + pw, y, &ps);
                p.x0 = sx;
                p.w = send - sx;
                sx = send;
                double t0 = now(profile);
                if (analytic) rs__coverage_analytic(ps, &p);
                else rs__coverage_alphamap(ps, &p);
                rs__coverage_quantise(&p);
                double t1 = now(profile);
                if (L) {
                    layers_piece(ps, &b, &p, L, p.x0 - x0, p.y0 - y0);
                    if (profile) {
                        profile->composite_ms += now(profile) - t1;
                        profile->pixels += (uint64_t)p.rows * p.w;
                        profile->road_pixels += p.road_pixels;
                        profile->mark_tests += p.mark_tests;
                        profile->mark_pixels += p.mark_pixels;
                    }
                    p.mark_tests = p.mark_pixels = 0;
                } else {
                    rs__surface(ps, &p);
                    double t2 = now(profile);
                    rs__overlays(ps, &p);
                    double t3 = now(profile);
                    rs__composite(&p, rgba + (size_t)(p.y0 - y0) * rgba_stride + (size_t)(p.x0 - x0) * 4, rgba_stride,
                                  weight ? weight + (size_t)(p.y0 - y0) * weight_stride + (p.x0 - x0) : NULL,
                                  weight_stride);
                    if (profile) {
                        double t4 = now(profile);
                        profile->coverage_ms += t1 - t0;
                        profile->surface_ms += t2 - t1;
                        profile->overlays_ms += t3 - t2;
                        profile->composite_ms += t4 - t3;
                        profile->pixels += (uint64_t)p.rows * p.w;
                        profile->road_pixels += p.road_pixels;
                        profile->mark_tests += p.mark_tests;
                        profile->mark_pixels += p.mark_pixels;
                    }
                    p.mark_tests = p.mark_pixels = 0;
                }
            }
            if (x + cols < x0 + w && rs__poll(ctx)) {
                r = RS_ERR_CANCELLED;
                break;
            }
        }
        if (!r && L && L->normal)
            r = normals_by_segment(ctx, s, x0, y, w, p.rows,
                                   L->normal_options ? L->normal_options : &s->o.lighting.normal,
                                   L->normal + (size_t)(y - y0) * L->normal_stride, L->normal_stride, NULL, 0, nm);
        if (!r && !L && s->o.lighting.enable)
            /* these rows of the window, lit by their normals (the normals of
             * a pixel do not depend on the window: same bytes for any cut) */
            r = normals_by_segment(ctx, s, x0, y, w, p.rows, &s->o.lighting.normal, NULL, 0,
                                   rgba + (size_t)(y - y0) * rgba_stride, rgba_stride, nm);
        y += p.rows;
        if (!r && rs__tick(ctx, p.rows)) r = RS_ERR_CANCELLED;
    }
    r = rs__progress_end(ctx, &pg, r);
    if (!r) rs__ok(ctx);
    return r;
}

static rs_result check_window(rs_ctx *ctx, const rs_splatter *s, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h,
                              size_t rgba_stride, const uint16_t *weight, size_t weight_stride)
{
    if (w == 0 || h == 0 || x0 >= s->out_w || y0 >= s->out_h || w > s->out_w - x0 || h > s->out_h - y0)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "window %u,%u %ux%u is empty or outside the %ux%u image", x0, y0, w,
                        h, s->out_w, s->out_h);
    if (rgba_stride / 4 < w)
        return rs__fail(ctx, RS_ERR_BUFFER_TOO_SMALL, "RGBA row stride %zu bytes, need %zu", rgba_stride,
                        (size_t)w * 4);
    if (weight && weight_stride < w)
        return rs__fail(ctx, RS_ERR_BUFFER_TOO_SMALL, "weight row stride %zu values, need %u", weight_stride, w);
    return RS_OK;
}

rs_result rs_splat_window(rs_ctx *ctx, const rs_splatter *s, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h,
                          uint8_t *rgba, size_t rgba_stride, uint16_t *weight, size_t weight_stride,
                          rs_splat_profile *profile)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!s || !rgba) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_splat_window");
    rs_result r = check_window(ctx, s, x0, y0, w, h, rgba_stride, weight, weight_stride);
    if (r) return r;
    scratch_size z = scratch_size_of(s, w, h);
    scratch b;
    if ((r = scratch_alloc(ctx, s, &z, 0, &b)) != RS_OK) return r;
    r = splat_run(ctx, s, &b, x0, y0, w, h, rgba, rgba_stride, weight, weight_stride, NULL, NULL, profile);
    scratch_free(ctx, &b);
    return r;
}

rs_result rs_splat_workspace_create(rs_ctx *ctx, const rs_splatter *s, uint32_t max_width, rs_splat_workspace **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_splat_workspace_create: out is NULL");
    *out = NULL;
    if (!s) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_splat_workspace_create: NULL splatter");
    if (max_width == 0 || max_width > s->out_w)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "workspace width %u must be 1..%u (the image width)", max_width,
                        s->out_w);
    rs_splat_workspace *ws = rs__calloc(ctx, 1, sizeof *ws);
    if (!ws) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for a splat workspace");
    scratch_size z = scratch_size_of(s, max_width, UINT32_MAX);
    rs_result r = scratch_alloc(ctx, s, &z, 0, &ws->b);
    if (r) {
        rs__free(ctx, ws);
        return r;
    }
    ws->s = s;
    ws->max_w = max_width;
    ws->npx = z.npx;
    ws->bytes = sizeof *ws + z.npx * (sizeof(double) * (s->grid->styling ? 2 : 1) + sizeof(uint16_t) + 6 * sizeof(float)) +
                z.cols * 6 * sizeof(double) + z.nax * 2 * (sizeof(double) + sizeof(uint32_t)) +
                z.ncol * 6 * sizeof(float) +
                (s->grid->styling ? rs__linesym_scratch_len((uint32_t)z.cols) * sizeof(double) : 0);
    *out = ws;
    rs__ok(ctx);
    return RS_OK;
}

void rs_splat_workspace_free(rs_ctx *ctx, rs_splat_workspace *ws)
{
    if (!ctx || !ws) return;
    scratch_free(ctx, &ws->b);
    rs__nm_scratch_free(ctx, &ws->nm);
    rs__free(ctx, ws);
}

size_t rs_splat_workspace_bytes(const rs_splat_workspace *ws)
{
    if (!ws) return 0;
    const rs__nm_scratch *n = &ws->nm;
    return ws->bytes + (ws->b.lx ? ws->npx * 4 * sizeof(float) : 0) +
           n->npx * (4 * sizeof(double) + sizeof(uint16_t) + 3 * sizeof(float)) + n->ncol * 4 * sizeof(double);
}

/* The workspace's normal scratch, reserved when this call needs normals. */
static rs_result ws_normals(rs_ctx *ctx, const rs_splatter *s, rs_splat_workspace *ws, int need, rs__nm_scratch **nm)
{
    *nm = NULL;
    if (!need) return RS_OK;
    rs_result r = rs__nm_scratch_reserve(ctx, s, ws->max_w, &ws->nm);
    if (!r) *nm = &ws->nm;
    return r;
}

rs_result rs_splat_window_ws(rs_ctx *ctx, const rs_splatter *s, rs_splat_workspace *ws, uint32_t x0, uint32_t y0,
                             uint32_t w, uint32_t h, uint8_t *rgba, size_t rgba_stride, uint16_t *weight,
                             size_t weight_stride, rs_splat_profile *profile)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!s || !ws || !rgba) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_splat_window_ws");
    if (ws->s != s) return rs__fail(ctx, RS_ERR_INVALID_ARG, "the workspace was made for another splatter");
    rs_result r = check_window(ctx, s, x0, y0, w, h, rgba_stride, weight, weight_stride);
    if (r) return r;
    if (w > ws->max_w)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "window width %u exceeds the workspace's %u", w, ws->max_w);
    rs__nm_scratch *nm;
    if ((r = ws_normals(ctx, s, ws, s->o.lighting.enable, &nm)) != RS_OK) return r;
    return splat_run(ctx, s, &ws->b, x0, y0, w, h, rgba, rgba_stride, weight, weight_stride, NULL, nm, profile);
}

static rs_result check_plane(rs_ctx *ctx, const void *plane, size_t stride, size_t need, const char *what)
{
    if (plane && stride < need)
        return rs__fail(ctx, RS_ERR_BUFFER_TOO_SMALL, "%s row stride %zu, need %zu", what, stride, need);
    return RS_OK;
}

rs_result rs_splat_layers_window(rs_ctx *ctx, const rs_splatter *s, rs_splat_workspace *ws, uint32_t x0, uint32_t y0,
                                 uint32_t w, uint32_t h, const rs_splat_layers *layers, rs_splat_profile *profile)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!s || !layers) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_splat_layers_window");
    rs_splat_layers Lin;
    rs_result ro = RS__OPTS_IN(ctx, layers, &Lin, rs_splat_layers);
    if (ro) return ro;
    const rs_splat_layers *L = &Lin;
    if (ws && ws->s != s) return rs__fail(ctx, RS_ERR_INVALID_ARG, "the workspace was made for another splatter");
    if (!L->terrain && !L->casing && !L->surface && !L->coverage && !L->paint && !L->normal)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_splat_layers_window: no output plane");
    rs_result r = check_window(ctx, s, x0, y0, w, h, (size_t)w * 4, NULL, 0);
    if (!r) r = check_plane(ctx, L->terrain, L->terrain_stride, (size_t)w * 4, "terrain plane");
    if (!r) r = check_plane(ctx, L->casing, L->casing_stride, (size_t)w * 4, "casing plane");
    if (!r) r = check_plane(ctx, L->surface, L->surface_stride, (size_t)w * 4, "surface plane");
    if (!r) r = check_plane(ctx, L->coverage, L->coverage_stride, w, "coverage plane (values)");
    if (!r) r = check_plane(ctx, L->paint, L->paint_stride, (size_t)w * 4, "paint plane");
    if (!r) r = check_plane(ctx, L->normal, L->normal_stride, (size_t)w * 3, "normal plane");
    if (!r && L->normal) r = rs__normal_check(ctx, L->normal_options ? L->normal_options : &s->o.lighting.normal);
    if (r) return r;
    if (ws) {
        if (w > ws->max_w)
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "window width %u exceeds the workspace's %u", w, ws->max_w);
        rs__nm_scratch *nm;
        if ((r = ws_normals(ctx, s, ws, L->normal != NULL, &nm)) != RS_OK) return r;
        if (layer_planes(s) && !ws->b.lx) {
            /* the layers' planes, once (a workspace that never serves
             * layers does without) */
            ws->b.lx = rs__alloc_array(ctx, ws->npx * 4, sizeof *ws->b.lx);
            if (!ws->b.lx) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the layers' scratch");
        }
        return splat_run(ctx, s, &ws->b, x0, y0, w, h, NULL, 0, NULL, 0, L, nm, profile);
    }
    scratch_size z = scratch_size_of(s, w, h);
    scratch b;
    if ((r = scratch_alloc(ctx, s, &z, 1, &b)) != RS_OK) return r;
    r = splat_run(ctx, s, &b, x0, y0, w, h, NULL, 0, NULL, 0, L, NULL, profile);
    scratch_free(ctx, &b);
    return r;
}

rs_result rs_splat(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *grid, const rs_splat_options *opts,
                   uint8_t *rgba, size_t rgba_size, uint16_t *weight, size_t weight_count)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!dem || !grid || !rgba) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_splat");
    /* progress: one sequence, the splatter (a unit) and the window's rows */
    uint32_t W, H;
    rs_result r = rs_splat_size(ctx, dem, opts, &W, &H);
    if (r) return r;
    rs_splat_options o;
    if ((r = RS__OPTS_IN(ctx, opts, &o, rs_splat_options)) != RS_OK) return r; /* (checked: a prefix is read) */
    rs__progress pg;
    rs__progress_begin(ctx, &pg, o.progress, o.progress_user, (uint64_t)H + 1, 1);
    rs_splatter *s;
    r = rs_splatter_create(ctx, dem, NULL, grid, opts, &s);
    if (r) return rs__progress_end(ctx, &pg, r);
    size_t npx = (size_t)s->out_w * s->out_h;
    if (rgba_size / 4 < npx)
        r = rs__fail(ctx, RS_ERR_BUFFER_TOO_SMALL, "RGBA buffer of %zu bytes, need %zu", rgba_size, npx * 4);
    else if (weight && weight_count < npx)
        r = rs__fail(ctx, RS_ERR_BUFFER_TOO_SMALL, "weight buffer of %zu values, need %zu", weight_count, npx);
    else
        r = rs_splat_window(ctx, s, 0, 0, s->out_w, s->out_h, rgba, (size_t)s->out_w * 4, weight, s->out_w, NULL);
    rs_splatter_free(ctx, s);
    return rs__progress_end(ctx, &pg, r);
}
