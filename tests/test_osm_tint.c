/* Issue 28, library parts: the terrain tint is a function of absolute
 * height (rs_surface_options: the default ramp, a caller's ramp, the old
 * relative tint and an explicit height range), so crops and tiles of one
 * map agree away from their edges; non-car classes (footway, path,
 * cycleway) make no junctions and get no give-way lines. */
#include "harness.h"
#include <roadsplat.h>

#include <stdlib.h>

static rs_ctx *ctx;

/* A W x H DEM of 10 m cells: a hill of `top` metres over a plain at `base`. */
static rs_dem *hill_dem(uint32_t W, uint32_t H, double base, double top, uint32_t c0, uint32_t r0, uint32_t w,
                        uint32_t h)
{
    float *z = malloc((size_t)w * h * sizeof *z);
    for (uint32_t i = 0; i < h; i++)
        for (uint32_t j = 0; j < w; j++) {
            double x = (double)(c0 + j) - W / 2.0, y = (double)(r0 + i) - H / 2.0;
            z[(size_t)i * w + j] = (float)(base + top * exp(-(x * x + y * y) / 60.0));
        }
    rs_dem *d = NULL;
    rs_dem_frame fr;
    memset(&fr, 0, sizeof fr);
    fr.cell_size = 10;
    CHECK(rs_dem_create(ctx, w, h, z, &d) == RS_OK && rs_dem_set_frame(ctx, d, &fr) == RS_OK);
    free(z);
    return d;
}

/* The whole RGBA splat of dem with no roads. */
static uint8_t *render(const rs_dem *dem, const rs_surface_options *sf, uint32_t *w, uint32_t *h)
{
    rs_roads *roads = NULL;
    rs_splatter *sp = NULL;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    if (sf) o.surface = *sf;
    CHECK(rs_roads_parse(ctx, "", 0, &roads) == RS_OK);
    rs_result r = rs_splatter_create(ctx, dem, roads, NULL, &o, &sp);
    CHECKF(r == RS_OK, "%s", rs_ctx_message(ctx));
    uint8_t *px = NULL;
    if (!r) {
        rs_splatter_size(sp, w, h);
        px = malloc((size_t)*w * *h * 4);
        CHECK(rs_splat_window(ctx, sp, 0, 0, *w, *h, px, (size_t)*w * 4, NULL, 0, NULL) == RS_OK);
    }
    rs_splatter_free(ctx, sp);
    rs_roads_free(ctx, roads);
    return px;
}

/* Crops of one map give the whole map's pixels away from their edges (one
 * cell in: the hillshade there reads the crop's own samples only); the
 * relative tint does not. Returns the mismatching pixels. */
static size_t crop_mismatch(const rs_surface_options *sf)
{
    const uint32_t W = 41, H = 31, T = 4;
    rs_dem *whole = hill_dem(W, H, 50, 88, 0, 0, W, H), *crop = hill_dem(W, H, 50, 88, 10, 5, 21, 21);
    uint32_t ww, wh, cw, ch;
    uint8_t *a = render(whole, sf, &ww, &wh), *b = render(crop, sf, &cw, &ch);
    size_t bad = 0;
    for (uint32_t y = T; a && b && y + T < ch; y++)
        for (uint32_t x = T; x + T < cw; x++)
            bad += memcmp(b + ((size_t)y * cw + x) * 4, a + ((size_t)(y + 5 * T) * ww + x + 10 * T) * 4, 4) != 0;
    free(a);
    free(b);
    rs_dem_free(ctx, whole);
    rs_dem_free(ctx, crop);
    return bad;
}

static void test_absolute_tint(void)
{
    rs_surface_options sf;
    memset(&sf, 0, sizeof sf);
    CHECK_EQ_INT(crop_mismatch(NULL), 0);
    sf.tint = RS_TINT_RELATIVE;
    CHECK(crop_mismatch(&sf) > 1000); /* the old default: each crop its own range */
    sf.height_min = 0;
    sf.height_max = 500;
    CHECK_EQ_INT(crop_mismatch(&sf), 0); /* an explicit range is absolute too */

    /* an 88 m hill is green, not snow: its top pixel under the default ramp */
    rs_dem *d = hill_dem(41, 31, 50, 88, 0, 0, 41, 31);
    uint32_t w, h;
    uint8_t *px = render(d, NULL, &w, &h);
    const uint8_t *top = px + ((size_t)(15 * 4 + 2) * w + 20 * 4 + 2) * 4;
    CHECKF(top[1] > top[0] && top[1] > top[2] && top[0] < 150, "top %u %u %u", top[0], top[1], top[2]);
    free(px);
    memset(&sf, 0, sizeof sf);
    sf.tint = RS_TINT_RELATIVE; /* the old picture: the DEM's top is the palette's white */
    px = render(d, &sf, &w, &h);
    top = px + ((size_t)(15 * 4 + 2) * w + 20 * 4 + 2) * 4;
    CHECKF(top[0] > 180 && top[1] > 180 && top[2] > 180, "top %u %u %u", top[0], top[1], top[2]);
    free(px);

    /* a caller's ramp, copied: freed after rs_splatter_create */
    rs_colour_stop *ramp = malloc(2 * sizeof *ramp);
    ramp[0].height = 0;
    ramp[0].colour.r = 200, ramp[0].colour.g = 0, ramp[0].colour.b = 0, ramp[0].colour.a = 255;
    ramp[1].height = 1000;
    ramp[1].colour.r = 0, ramp[1].colour.g = 0, ramp[1].colour.b = 200, ramp[1].colour.a = 255;
    memset(&sf, 0, sizeof sf);
    sf.ramp = ramp;
    sf.ramp_count = 2;
    rs_roads *roads = NULL;
    rs_splatter *sp = NULL;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    o.surface = sf;
    CHECK(rs_roads_parse(ctx, "", 0, &roads) == RS_OK);
    CHECK(rs_splatter_create(ctx, d, roads, NULL, &o, &sp) == RS_OK);
    ramp[0].colour.r = 0; /* the splatter holds its copy */
    free(ramp);
    uint8_t corner[4 * 4];
    CHECK(rs_splat_window(ctx, sp, 0, 0, 2, 2, corner, 8, NULL, 0, NULL) == RS_OK);
    /* 50 m: 95 % red, 5 % blue, times a flat hillshade (0.3 + 0.7 = 1) */
    CHECKF(corner[0] >= 188 && corner[0] <= 192 && corner[1] == 0 && corner[2] >= 8 && corner[2] <= 12,
           "corner %u %u %u", corner[0], corner[1], corner[2]);
    rs_splatter_free(ctx, sp);

    /* bad ramps and ranges */
    rs_colour_stop two[2];
    memset(two, 0, sizeof two);
    two[0].height = 10;
    two[1].height = 10;
    o.surface.ramp = two;
    o.surface.ramp_count = 2;
    CHECK(rs_splatter_create(ctx, d, roads, NULL, &o, &sp) == RS_ERR_INVALID_ARG &&
          strstr(rs_ctx_message(ctx), "above the previous"));
    o.surface.ramp_count = 1;
    CHECK(rs_splatter_create(ctx, d, roads, NULL, &o, &sp) == RS_ERR_INVALID_ARG);
    two[1].height = NAN;
    o.surface.ramp_count = 2;
    CHECK(rs_splatter_create(ctx, d, roads, NULL, &o, &sp) == RS_ERR_INVALID_ARG);
    memset(&o.surface, 0, sizeof o.surface);
    o.surface.tint = RS_TINT_RELATIVE;
    o.surface.height_min = 5;
    o.surface.height_max = 5;
    CHECK(rs_splatter_create(ctx, d, roads, NULL, &o, &sp) == RS_ERR_INVALID_ARG);
    o.surface.tint = (rs_tint_mode)7;
    o.surface.height_min = o.surface.height_max = 0;
    CHECK(rs_splatter_create(ctx, d, roads, NULL, &o, &sp) == RS_ERR_INVALID_ARG);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, d);
}

/* Automatic markings on roads of `text` over a flat 101 x 101 DEM. */
static uint64_t auto_marks(const char *text)
{
    float *z = calloc(101 * 101, sizeof *z);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    rs_road_grid *g = NULL;
    rs_road_grid_stats st;
    memset(&st, 0, sizeof st);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    CHECK(rs_dem_create(ctx, 101, 101, z, &dem) == RS_OK);
    CHECK(rs_roads_parse(ctx, text, strlen(text), &roads) == RS_OK);
    CHECK(rs_road_grid_build(ctx, dem, roads, &o, &g) == RS_OK);
    if (g) rs_road_grid_get_stats(g, &st);
    rs_road_grid_free(ctx, g);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    free(z);
    return st.marks_auto;
}

static void test_non_car(void)
{
    static const char *const street = "road main width 6 class=residential\n0 50\n100 50\nend\n";
    char text[512];
    /* a service road ending on the street gives way (issue 27: a line of
     * three 0.5 m blocks across its 2 m approach half) */
    snprintf(text, sizeof text, "%sroad s width 4 class=service\n50 95\n50 50\nend\n", street);
    CHECK_EQ_INT(auto_marks(text), 3);
    /* footways, paths and cycleways do not, and the two halves of a crossing footway
     * that end on the street leave its zebra alone (no junction area) */
    static const char *const cls[] = { "footway", "path", "cycleway" };
    for (int k = 0; k < 3; k++) {
        snprintf(text, sizeof text, "%sroad f width 2.5 class=%s\n50 95\n50 50\nend\n", street, cls[k]);
        CHECK_EQ_INT(auto_marks(text), 0);
        snprintf(text, sizeof text,
                 "road main width 6 class=residential\n0 50\n50 50 crossing=zebra\n100 50\nend\n"
                 "road f width 2.5 class=%s\n50 95\n50 50\nend\nroad g width 2.5 class=%s\n50 50\n50 5\nend\n",
                 cls[k], cls[k]);
        CHECK_EQ_INT(auto_marks(text), 6); /* the zebra: six 0.5 m bars across 5.6 m */
    }
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_absolute_tint();
    test_non_car();
    rs_ctx_free(ctx);
    return th_finish("test_osm_tint");
}
