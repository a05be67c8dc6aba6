/* Allocation-free windows (issue 30): rs_splat_window_ws through a
 * workspace allocates nothing (counted through the context's allocator)
 * and gives rs_splat_window's bytes, for styled roads with markings, in
 * both edge modes, for windows of any size up to the workspace's width. */
#include "roadsplat.h"
#include "harness.h"
#include "scenes.h"

#include <stdlib.h>
#include <string.h>

typedef struct counter { size_t calls; } counter;

static void *count_malloc(void *u, size_t n) { ((counter *)u)->calls++; return malloc(n); }
static void *count_realloc(void *u, void *p, size_t n) { ((counter *)u)->calls++; return realloc(p, n); }
static void count_free(void *u, void *p) { (void)u; free(p); }

static const char scene_text[] =
    "style k\n casing 0.4 #707070\n line 0 0.15 #FFFFFF dash 3 6\n line -2.6 0.2 #FFFFFF\nend\n"
    "road a width 7 style=k\n0.5 11.3\n39.1 14.8\nend\n"
    "road b width 6 class=primary\n20.2 0.4\n23.9 39.5\nend\n"
    "road c width 4 class=residential\n3 35\n18 22\n36 38\nend\n"
    "mark arrow_left road=a s=12 t=-1.7\n"
    "mark word_bus road=b s=9 t=1.5 length=3 width=2\n";

static void run(rs_ctx *ctx, counter *cnt, const rs_dem *dem, rs_edge_mode edges)
{
    rs_styles *styles = NULL;
    rs_roads *roads = NULL;
    rs_splatter *s = NULL, *other = NULL;
    rs_splat_workspace *ws = NULL;
    CHECK(rs_styles_create(ctx, &styles) == RS_OK);
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.styles = styles;
    CHECK(rs_roads_parse_ex(ctx, scene_text, strlen(scene_text), &po, &roads) == RS_OK);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 10;
    o.coverage.edges = edges;
    o.style.styles = styles;
    CHECK(rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_OK);
    CHECK(rs_splatter_create(ctx, dem, roads, NULL, &o, &other) == RS_OK);
    if (!s || !other) goto out;
    uint32_t W, H;
    rs_splatter_size(s, &W, &H);
    const uint32_t MW = 173;
    CHECK(rs_splat_workspace_create(ctx, s, 0, &ws) == RS_ERR_INVALID_ARG && !ws);
    CHECK(rs_splat_workspace_create(ctx, s, W + 1, &ws) == RS_ERR_INVALID_ARG && !ws);
    CHECK(rs_splat_workspace_create(ctx, s, MW, &ws) == RS_OK && ws);
    CHECK(rs_splat_workspace_bytes(ws) > 0 && rs_splat_workspace_bytes(ws) < ((size_t)12 << 20));
    if (!ws) goto out;
    uint8_t *a = malloc((size_t)MW * H * 4), *b = malloc((size_t)MW * H * 4);
    uint16_t *wa = malloc((size_t)MW * H * 2), *wb = malloc((size_t)MW * H * 2);
    sc_rng rng;
    sc_rng_seed(&rng, 30);
    size_t same = 0, allocs = 0, n = 0;
    for (int k = 0; k < 40 && a && b && wa && wb; k++) {
        /* 1-px rows and columns, the full workspace width, the whole height */
        uint32_t w = k == 0 ? MW : k == 1 ? 1 : 1 + (uint32_t)(sc_rng_unit(&rng) * MW);
        uint32_t h = k == 0 ? H : k == 2 ? 1 : 1 + (uint32_t)(sc_rng_unit(&rng) * H);
        uint32_t x = (uint32_t)(sc_rng_unit(&rng) * (W - w + 1)), y = (uint32_t)(sc_rng_unit(&rng) * (H - h + 1));
        size_t before = cnt->calls;
        rs_result r = rs_splat_window_ws(ctx, s, ws, x, y, w, h, a, (size_t)w * 4, wa, w, NULL);
        allocs += cnt->calls - before;
        if (r != RS_OK || rs_splat_window(ctx, s, x, y, w, h, b, (size_t)w * 4, wb, w, NULL) != RS_OK) continue;
        n++;
        same += !memcmp(a, b, (size_t)w * h * 4) && !memcmp(wa, wb, (size_t)w * h * 2);
    }
    CHECKF(n == 40 && same == n, "edges %d: %zu of %zu windows through the workspace equal rs_splat_window",
           (int)edges, same, n);
    CHECKF(allocs == 0, "edges %d: %zu allocations in 40 windows through the workspace", (int)edges, allocs);
    /* misuse */
    CHECK(rs_splat_window_ws(ctx, s, ws, 0, 0, MW + 1, 1, a, (size_t)(MW + 1) * 4, NULL, 0, NULL) ==
          RS_ERR_INVALID_ARG);
    CHECK(rs_splat_window_ws(ctx, other, ws, 0, 0, 1, 1, a, 4, NULL, 0, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_splat_window_ws(ctx, s, NULL, 0, 0, 1, 1, a, 4, NULL, 0, NULL) == RS_ERR_INVALID_ARG);
    free(a);
    free(b);
    free(wa);
    free(wb);
out:
    rs_splat_workspace_free(ctx, ws);
    rs_splatter_free(ctx, s);
    rs_splatter_free(ctx, other);
    rs_roads_free(ctx, roads);
    rs_styles_free(ctx, styles);
}

int main(void)
{
    counter cnt = { 0 };
    rs_allocator al = { count_malloc, count_realloc, count_free, &cnt };
    rs_ctx *ctx = NULL;
    if (rs_ctx_create(&al, NULL, &ctx) != RS_OK) return 1;
    enum { DW = 21, DH = 21 };
    float z[DW * DH];
    sc_dem_fractal(z, DW, DH, 5, 0.5);
    rs_dem *dem = NULL;
    rs_dem_frame fr = { 2.0, 0.001, 0, 0 };
    CHECK(rs_dem_create(ctx, DW, DH, z, &dem) == RS_OK && rs_dem_set_frame(ctx, dem, &fr) == RS_OK);
    if (dem) {
        run(ctx, &cnt, dem, RS_EDGES_ANALYTIC);
        run(ctx, &cnt, dem, RS_EDGES_ALPHAMAP);
    }
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    return th_finish("test_workspace");
}
