/* libFuzzer target: the GPU export (rs_gpu_scene_create, issue 26 class 4;
 * and rs_gpu_scene_from_grid, which must give the same bytes).
 * Road text with style blocks, mark lines and point attributes from the
 * input, over a small DEM whose size, cell size and origin come from the
 * first bytes, with the styles, markings and index options they pick.
 * Findings (abort): an unknown result, an object left on failure, a
 * message-less failure, and on success any index that points outside the
 * array it indexes or a float a shader reads that is not finite
 * (tests/gpu_scene_check.h), or a segment missing from a cell it reaches.
 *
 * Input layout (short input reads as zero bytes), then the road text:
 *   0  flags: bit 0 styles off, bit 1 markings off, bit 2 no automatic
 *      markings, bit 3 MUTCD profile, bit 4 keep the text's styles,
 *      bits 5-7 index cell (0 automatic, else map size / 2^(b-1))
 *   1  DEM width - 2 (mod 16), 2  DEM height - 2 (mod 16)
 *   3  cell size: 10^((b mod 25) / 2 - 6) metres (1e-6 .. 1e6)
 *   4  reach: 0 automatic, else b / 16 metres;  5, 6  origin (int8) * 64 m */
#include "roadsplat.h"
#include "../../tests/gpu_scene_check.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define HEAD 7
#define REQUIRE(c) do { if (!(c)) abort(); } while (0)

/* every segment within its reach of a cell's centre is listed there */
static int complete(const rs_gpu_scene *scene)
{
    const gsv view = gsv_of(scene), *g = &view;
    for (uint32_t j = 0; j < g->gh; j++)
        for (uint32_t i = 0; i < g->gw; i++) {
            size_t c = (size_t)j * g->gw + i, e = g->cell_start[c];
            double cx = g->x0 + (i + 0.5) * g->cell, cy = g->y0 + (j + 0.5) * g->cell;
            for (size_t k = 0; k < g->nseg; k++) {
                const float *s = g->seg + RS_GPU_SEG_FLOATS * k;
                double dx = (double)s[2] - s[0], dy = (double)s[3] - s[1], l2 = dx * dx + dy * dy, u = 0;
                if (l2 > 0) u = fmin(1, fmax(0, ((cx - s[0]) * dx + (cy - s[1]) * dy) / l2));
                double d = hypot(cx - s[0] - u * dx, cy - s[1] - u * dy);
                double R = s[4] + g->road[RS_GPU_ROAD_FLOATS * (size_t)s[6] + 2] + g->reach;
                /* the lists are ascending: walk them alongside k */
                while (e < g->cell_start[c + 1] && g->cell_seg[e] < k) e++;
                int listed = e < g->cell_start[c + 1] && g->cell_seg[e] == k;
                if (d < 0.999 * R && !listed) return 0;
            }
        }
    return 1;
}

/* The built-in atlas, made once: its mip chains cost more than the rest of
 * an input (a static the harness keeps, not the library). */
static const rs_atlas *default_atlas(void)
{
    static rs_ctx *actx;
    static rs_atlas *atlas;
    if (!atlas) {
        REQUIRE(rs_ctx_create(NULL, NULL, &actx) == RS_OK);
        REQUIRE(rs_atlas_default(actx, &atlas) == RS_OK);
    }
    return atlas;
}

/* The export from a road grid of the same roads and options has the same
 * bytes (include/roadsplat.h rs_gpu_scene_from_grid), but for the colour
 * floats of a road drawn unstyled (surface 0, no casing, no lines), which a
 * grid with no styled road does not keep. A grid the limits refuse is
 * skipped. */
static void same_from_grid(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                           const rs_gpu_options *go, const rs_gpu_scene *a)
{
    rs_road_grid *grid = NULL;
    if (rs_road_grid_build(ctx, dem, roads, o, &grid) != RS_OK) return;
    rs_gpu_scene *b = NULL;
    REQUIRE(rs_gpu_scene_from_grid(ctx, dem, roads, grid, go, &b) == RS_OK);
    gsv va = gsv_of(a), vb = gsv_of(b);
    REQUIRE(va.nroads == vb.nroads);
    for (int k = 0; k < RS_GPU_ARRAY_COUNT; k++) {
        size_t na = 0, nb = 0;
        const void *pa = rs_gpu_scene_array(a, (rs_gpu_array)k, &na), *pb = rs_gpu_scene_array(b, (rs_gpu_array)k, &nb);
        REQUIRE(na == nb);
        if (k != RS_GPU_ARRAY_ROAD) {
            REQUIRE(na == 0 || memcmp(pa, pb, 4 * na) == 0);
            continue;
        }
        for (size_t i = 0; i < va.nroads; i++) {
            const float *ra = va.road + RS_GPU_ROAD_FLOATS * i, *rb = vb.road + RS_GPU_ROAD_FLOATS * i;
            int plain = ra[0] == 0 && ra[2] == 0 && ra[4] == 0;
            REQUIRE(!memcmp(ra, rb, 8 * sizeof *ra) && !memcmp(ra + 24, rb + 24, (RS_GPU_ROAD_FLOATS - 24) * sizeof *ra));
            REQUIRE(plain || !memcmp(ra + 8, rb + 8, 16 * sizeof *ra));
        }
    }
    rs_gpu_scene_free(ctx, b);
    rs_road_grid_free(ctx, grid);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    uint8_t h[HEAD] = { 0 };
    memcpy(h, data, size < HEAD ? size : HEAD);
    const char *text = size > HEAD ? (const char *)data + HEAD : "";
    size_t tn = size > HEAD ? size - HEAD : 0;
    rs_limits lim = { 0 };
    lim.max_points = 2000;
    lim.max_line_length = 4096;
    rs_ctx *ctx = NULL;
    if (rs_ctx_create(NULL, &lim, &ctx) != RS_OK) return 0;
    rs_styles *styles = NULL;
    rs_roads *roads = NULL;
    rs_dem *dem = NULL;
    REQUIRE(rs_styles_create(ctx, &styles) == RS_OK);
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.profile = (h[0] & 8) ? RS_PROFILE_MUTCD : RS_PROFILE_RMS;
    po.styles = styles;
    if (rs_roads_parse_ex(ctx, text, tn, &po, &roads) != RS_OK) {
        REQUIRE(roads == NULL);
        goto done;
    }
    uint32_t w = 2 + h[1] % 16, ht = 2 + h[2] % 16;
    float z[17 * 17];
    for (uint32_t i = 0; i < w * ht; i++) z[i] = (float)(i % 7);
    REQUIRE(rs_dem_create(ctx, w, ht, z, &dem) == RS_OK);
    rs_dem_frame fr;
    rs_dem_get_frame(dem, &fr);
    fr.cell_size = pow(10.0, (h[3] % 25) / 2.0 - 6);
    fr.origin_x = (int8_t)h[5] * 64.0;
    fr.origin_y = (int8_t)h[6] * 64.0;
    if (rs_dem_set_frame(ctx, dem, &fr) != RS_OK) goto done;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.style.disable = h[0] & 1;
    o.markings.disable = (h[0] >> 1) & 1;
    o.markings.no_auto = (h[0] >> 2) & 1;
    o.style.profile = po.profile;
    o.style.styles = (h[0] & 16) ? styles : NULL;
    o.markings.atlas = default_atlas();
    rs_gpu_options go;
    memset(&go, 0, sizeof go);
    double map = (double)(w > ht ? w : ht) * fr.cell_size;
    if (h[0] >> 5) go.cell = map / (double)(1u << ((h[0] >> 5) - 1));
    go.reach = h[4] / 16.0;
    rs_gpu_scene *g = (rs_gpu_scene *)1;
    rs_result r = rs_gpu_scene_create(ctx, dem, roads, &o, &go, &g);
    REQUIRE(r >= RS_OK && r <= RS_ERR_CANCELLED);
    if (r != RS_OK) {
        REQUIRE(g == NULL && rs_ctx_message(ctx)[0]);
        goto done;
    }
    const char *bad = gpu_scene_check(g);
    if (bad) {
        fprintf(stderr, "gpu_export: %s\n", bad);
        abort();
    }
    gsv v = gsv_of(g);
    REQUIRE((size_t)v.gw * v.gh * v.nseg > 20000 || complete(g));
    same_from_grid(ctx, dem, roads, &o, &go, g);
    rs_gpu_scene_free(ctx, g);
done:
    rs_dem_free(ctx, dem);
    rs_roads_free(ctx, roads);
    rs_styles_free(ctx, styles);
    rs_ctx_free(ctx);
    return 0;
}
