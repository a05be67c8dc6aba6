/* Private: the splatter and its stages (docs/design.md, "Stages").
 *
 * rs_splat_window (lib/splat/splatter.c) cuts its window into pieces of at most a
 * few hundred thousand pixels, each inside one DEM-cell row, and runs the
 * four stages on each piece in order. A stage reads what the earlier ones
 * wrote into the piece and never recomputes it. A pixel's value depends
 * only on its own coordinates, so any cut gives the same bytes. */
#ifndef RS_SPLATTER_H
#define RS_SPLATTER_H
#include "internal.h"
#include "mask.h"
#include "roadgrid.h"
#include "avx512.h"

/* Integral tables of one alpha-map (lib/splat/coverage_alphamap.c). */
typedef struct rs__alpha_table {
    uint32_t n;    /* res + 1 samples per side */
    double h2;     /* area of one alpha-map pixel in cell units */
    float *f;      /* samples */
    double *s;     /* S[i][j]: integral over [0,j]x[0,i] (pixel units) */
    double *col;   /* integral of f(j, .) over [0,i] */
    double *row;   /* integral of f(., i) over [0,j] */
} rs__alpha_table;

struct rs_splatter {
    const rs_dem *dem;
    rs_splat_options o;        /* validated, defaults filled */
    uint32_t out_w, out_h;
    const rs_road_grid *grid;  /* in use */
    rs_road_grid *grid_own;    /* when built here */
    const struct rs__roadfield *field; /* the road field the coverage reads: the grid's, or field_own */
    struct rs__roadfield *field_own;   /* the grid's indexed for this splatter's coarser pixels (a grid
                                          built for more texels, as the virtual texture's levels share) */
    rs__mask_table mt;
    rs__alpha_table tab[3];    /* EDGE, INNER, OUTER (alpha-map edges) */
    const float *z;            /* heights, nodata filled (lib/dem.c policy) */
    float *z_own;
    double zmin, zrange;       /* DEM units, valid samples (RS_TINT_RELATIVE without a range) */
    rs_colour_stop *ramp_own;  /* the absolute tint's ramp: a copy of o.surface.ramp */
    double cos_zen, sin_zen, sun_az; /* light: azimuth 315, altitude 45 */
    double texel_m;            /* cell_size / texels */
    /* lighting (o.lighting.enable): unit vector towards the sun and the
     * Blinn half vector (tangent space: X east, Y north, Z up) */
    double light[3], half[3], ambient, specular;
    /* the terrain colour of every DEM sample (rs__surface_colours), when
     * per-sample work would dominate the splat (few texels a cell):
     * per sample row three planes of `width` floats; NULL: computed per
     * window */
    float *tcol;
    /* A patched grid (rs_road_grid_update): a view per patch, this
     * splatter with the patch's grid (and field), drawing the output
     * pixels of view_rect[k], the later over the earlier. */
    uint32_t nview;
    struct rs_splatter *view;
    rs_pixel_rect *view_rect;
};

/* The run of row y's output columns from x (x < x1) that one splatter
 * draws: *by is s, or the view of the latest patch whose rectangle holds
 * the run (the later over the earlier); returns the run's end, at most x1.
 * The runs from x0 on, each taken up to where the drawing splatter
 * changes, cut [x0, x1) at the patches' edges (any number of patches). */
uint32_t rs__segment_next(const struct rs_splatter *s, uint32_t x, uint32_t x1, uint32_t y,
                          const struct rs_splatter **by);

/* Terrain colours (3 floats per sample) of the window's sample columns
 * [c0, c0 + ncol), for the two DEM sample rows last needed: computed once
 * per sample row per rs_splat_window call, reused by every piece of the
 * DEM-cell rows above and below it (lib/splat/surface.c). */
typedef struct rs__terrain_cache {
    uint32_t c0, ncol;
    uint32_t row_of[2]; /* DEM sample row held by rgb[i], UINT32_MAX: none */
    float *rgb[2];
} rs__terrain_cache;

/* One piece of a window: columns [x0, x0+w), image rows [y0, y0+rows), all
 * inside DEM-cell row crow. Buffers are rows x w, row-major. */
typedef struct rs__piece {
    uint32_t x0, w, y0, rows, crow;
    double *cov;      /* coverage: road weight R in [0,1] */
    uint16_t *q;      /* coverage: R quantised to 0..65535 (the weight output) */
    double *ov;       /* overlays: the casing field's coverage, rows x w (only when the grid has styles) */
    double *ls;       /* overlays: the line symbols' scratch, rs__linesym_scratch_len(w) (only with styles);
                       * apart from ov, which the composite still reads (issue 25) */
    float *tc, *sc;   /* surface: terrain and road colour; each row planar: w R, w G, w B */
    rs__terrain_cache *tcache; /* surface: the window's terrain colour rows */
    double *hx;       /* surface: two horizontal interpolants, 6 planes of w */
    /* surface: bilinear texture coordinates, planar (texel i0 then i1,
     * weight 1 - f then f). Columns of the whole window [win_x0, win_x0 +
     * win_w) per texture (terrain [0], road [1]; NULL: no such texture),
     * computed by the window's first piece that needs them (tx_ready);
     * rows per piece. */
    uint32_t win_x0, win_w;
    uint32_t *tix[2], *tiy;
    double *twx[2], *twy;
    int tx_ready[2];
    uint64_t road_pixels;
    uint64_t mark_tests, mark_pixels; /* markings stage counts (added to) */
    /* overlays -> composite: casings of one colour are blended by the
     * composite (one pass over the pixels instead of two): the casing field's
     * coverage C (rows x w, NULL: none) and the colour */
    const double *cas;
    float cas_rgba[4];
    /* layers (rs_splat_layers_window): `all` makes the surface stage colour
     * every pixel with both T and S (the planes hold them everywhere);
     * `lcas`, when not NULL, takes casings of several colours instead of
     * T (each row 4 planes of w: premultiplied R, G, B and alpha; the
     * caller zeroes the alphas), so T stays the bare terrain */
    int all;
    float *lcas;
} rs__piece;

/* Stages. */
rs_result rs__alphamap_tables_build(rs_ctx *ctx, rs_splatter *s);
void rs__alphamap_tables_free(rs_ctx *ctx, rs_splatter *s);
void rs__coverage_alphamap(const rs_splatter *s, rs__piece *p);
void rs__coverage_analytic(const rs_splatter *s, rs__piece *p);
void rs__coverage_quantise(rs__piece *p);
void rs__surface(const rs_splatter *s, rs__piece *p);
/* s->tcol for splatters of at most RS__TCOL_TEXELS texels a cell on DEMs
 * of at most RS__TCOL_SAMPLES samples without a terrain texture (else
 * nothing): the colours rs__surface would compute per window, the same
 * floats. RS_OK, RS_ERR_NOMEM or RS_ERR_CANCELLED (no message). */
#define RS__TCOL_TEXELS 2u
#define RS__TCOL_SAMPLES ((uint64_t)1 << 22)
rs_result rs__surface_colours(rs_ctx *ctx, rs_splatter *s);
/* rs_splatter_create on a grid for a few small windows (rs_road_grid_update
 * compares the pixels of its candidate rectangles): without the per-sample
 * terrain colours, an O(DEM) table that windows do without (the same
 * bytes: they compute their own samples' colours). */
rs_result rs__splatter_create_lean(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *grid,
                                   const rs_splat_options *opts, rs_splatter **out);
void rs__overlays(const rs_splatter *s, rs__piece *p);
/* rs__overlays in its three parts: casings (onto T, or p->cas for the
 * composite, or p->lcas), the styles' surfaces (onto S), then the paint of
 * line symbols and markings onto `rgb` (planar rows as S; S itself for
 * rs__overlays). */
void rs__overlays_casings(const rs_splatter *s, rs__piece *p);
void rs__overlays_surfaces(const rs_splatter *s, rs__piece *p);
void rs__overlays_paint(const rs_splatter *s, rs__piece *p, float *rgb);
/* The normals' scratch (lib/splat/normals.c): a workspace keeps one,
 * reserved (rs__nm_scratch_reserve: for windows up to max_w wide) by its
 * first call that needs normals, so later calls allocate nothing. */
typedef struct rs__nm_scratch {
    double *cov, *ov, *paint, *lum; /* halo region: (rows + 2) x (cols + 2) */
    uint16_t *q;
    float *sc;                      /* halo region, 3 planes per row */
    double *g;                      /* Horn gradients: 4 planes of ncol (x, y at rows crow, crow + 1) */
    size_t npx, ncol;               /* capacity */
} rs__nm_scratch;
rs_result rs__nm_scratch_reserve(rs_ctx *ctx, const rs_splatter *s, uint32_t max_w, rs__nm_scratch *b);
void rs__nm_scratch_free(rs_ctx *ctx, rs__nm_scratch *b);
/* Normal maps (lib/splat/normals.c): the normals of a window (options checked),
 * encoded into rgb (RGB8) or, when rgba is not NULL, lighting the colours
 * already there (o.lighting); scratch from `keep` when it holds enough
 * (NULL: allocated for the call). */
rs_result rs__normals_run(rs_ctx *ctx, const rs_splatter *s, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h,
                          const rs_normal_options *opts, uint8_t *rgb, size_t rgb_stride, uint8_t *rgba,
                          size_t rgba_stride, rs__nm_scratch *keep);
/* rs__normals_run of a window into rgb, by the splatters that draw its
 * pixels (a patched grid's views). */
rs_result rs__normals_window(rs_ctx *ctx, const rs_splatter *s, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h,
                             const rs_normal_options *no, uint8_t *rgb, size_t rgb_stride);
rs_result rs__lighting_check(rs_ctx *ctx, const rs_lighting_options *l);
rs_result rs__normal_check(rs_ctx *ctx, const rs_normal_options *o);
void rs__composite(const rs__piece *p, uint8_t *rgba, size_t rgba_stride, uint16_t *weight, size_t weight_stride);
/* The layers of a piece (lib/splat/composite.c; `at` = the piece's offset
 * in the window, pixels): rs__layers_ground after the casings and
 * surfaces (terrain, casing, coverage; the surface plane unless
 * `surface_early`, which writes it from S before the styles' surfaces),
 * rs__layers_paint after painting over 0 into p0 and over 1 into p1 (S in
 * p->sc is the surface under the paint). */
void rs__layers_surface(const rs__piece *p, const rs_splat_layers *L, uint32_t ax, uint32_t ay);
void rs__layers_ground(const rs__piece *p, const rs_splat_layers *L, uint32_t ax, uint32_t ay);
void rs__layers_paint(const rs__piece *p, const rs_splat_layers *L, uint32_t ax, uint32_t ay, const float *p0,
                      const float *p1);
#endif
