/* GPU export (lib/gpu/gpu_export.c, docs/render.md "Shader mode"): segments with
 * their arc length and flags, the index grid (every segment near a cell is
 * listed there, ascending), styles and bands as rs_road_style gives them,
 * continuations, markings in road coordinates with the atlas's mip chains,
 * errors, and no leak under allocation failures. */
#include "harness.h"
#include "fail_alloc.h"
#include "gpu_scene_check.h"
#include "roadsplat.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static const char *scene_text =
    "road main_w width 10 class=primary turn:lanes=left|through;right\n0 40\n20 40 crossing=zebra\n40 40\nend\n"
    "road main_e width 10 class=primary\n80 40\n40 40\nend\n"
    "road north width 7 class=residential\n40 0\n40 40\nend\n"
    "road plain width 3\n5 5\n15 12\n25 5\nend\n"
    "mark word_bus road=main_w s=8 t=-2.5 length=3 width=2\n"
    "mark cycle road=north s=6 t=-1.75 flip\n";

static rs_dem *make_dem(rs_ctx *ctx)
{
    static float z[41 * 41];
    for (int i = 0; i < 41 * 41; i++) z[i] = (float)(i % 41);
    rs_dem *d = NULL;
    rs_dem_create(ctx, 41, 41, z, &d);
    rs_dem_frame fr;
    rs_dem_get_frame(d, &fr);
    fr.cell_size = 2;
    fr.z_scale = 0.01;
    rs_dem_set_frame(ctx, d, &fr);
    return d;
}

static double seg_dist(const float *s, double x, double y)
{
    double dx = s[2] - s[0], dy = s[3] - s[1], l2 = dx * dx + dy * dy, u = 0;
    if (l2 > 0) {
        u = ((x - s[0]) * dx + (y - s[1]) * dy) / l2;
        u = u < 0 ? 0 : u > 1 ? 1 : u;
    }
    return hypot(x - s[0] - u * dx, y - s[1] - u * dy);
}

static void test_scene(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_dem *dem = make_dem(ctx);
    rs_roads *roads = NULL;
    CHECK(rs_roads_parse(ctx, scene_text, strlen(scene_text), &roads) == RS_OK);
    rs_gpu_scene *g = NULL;
    CHECK(rs_gpu_scene_create(ctx, dem, roads, NULL, NULL, &g) == RS_OK);
    if (!g) { rs_roads_free(ctx, roads); rs_dem_free(ctx, dem); rs_ctx_free(ctx); return; }
    CHECK_EQ_INT(g->nroads, 4);
    CHECK_EQ_INT(g->nseg, 2 + 1 + 1 + 2);
    CHECK_NEAR(g->map_w, 80, 0);
    CHECK_NEAR(g->cell, 2, 0);
    CHECK(g->gw == 42 && g->gh == 42);
    /* segments: end points, s, road, flags */
    const float *s = g->seg;
    CHECK(s[0] == 0 && s[1] == 40 && s[2] == 20 && s[3] == 40 && s[4] == 5 && s[5] == 0 && s[6] == 0 &&
          s[7] == RS_GPU_SEG_FIRST);
    s += RS_GPU_SEG_FLOATS;
    CHECK(s[0] == 20 && s[5] == 20 && s[6] == 0 && s[7] == RS_GPU_SEG_LAST);
    s = g->seg + 4 * RS_GPU_SEG_FLOATS;
    CHECK(s[6] == 3 && s[4] == 1.5f && s[7] == RS_GPU_SEG_FIRST);
    CHECK_NEAR(s[RS_GPU_SEG_FLOATS + 5], hypot(10, 7), 1e-5);
    CHECK_NEAR(s[9], hypot(10, 7), 1e-5);
    CHECK_NEAR(s[10], 10 / hypot(10, 7), 1e-6);
    CHECK(s[8] == 0);
    CHECK(g->seg[8] == (float)g->road[2]);
    /* the index: per cell ascending, and complete: a segment within its half
     * width + casing + reach of a cell's centre is listed there */
    int complete = 1, ascending = 1;
    for (uint32_t j = 0; j < g->gh; j++)
        for (uint32_t i = 0; i < g->gw; i++) {
            size_t c = (size_t)j * g->gw + i;
            double cx = g->x0 + (i + 0.5) * g->cell, cy = g->y0 + (j + 0.5) * g->cell;
            for (uint32_t e = g->cell_start[c]; e + 1 < g->cell_start[c + 1]; e++)
                ascending &= g->cell_seg[e] < g->cell_seg[e + 1];
            for (size_t k = 0; k < g->nseg; k++) {
                const float *q = g->seg + RS_GPU_SEG_FLOATS * k;
                double R = q[4] + g->road[RS_GPU_ROAD_FLOATS * (size_t)q[6] + 2] + g->reach;
                if (seg_dist(q, cx, cy) > R) continue;
                int found = 0;
                for (uint32_t e = g->cell_start[c]; e < g->cell_start[c + 1]; e++) found |= g->cell_seg[e] == k;
                complete &= found;
            }
        }
    CHECK(complete && ascending);
    CHECK(gpu_scene_check(g) == NULL);
    CHECK(g->nseg_entries == g->cell_start[(size_t)g->gw * g->gh]);
    /* styles: as rs_road_style resolves them */
    for (size_t i = 0; i < 4; i++) {
        rs_style st;
        CHECK(rs_road_style(ctx, roads, i, NULL, RS_PROFILE_RMS, &st) == RS_OK);
        const float *rd = g->road + RS_GPU_ROAD_FLOATS * i;
        CHECK(rd[0] == (float)st.surface && rd[2] == (float)st.casing_width && rd[4] == (float)st.line_count);
        CHECK(rd[20] == st.casing.r && rd[23] == st.casing.a / 255.0f);
        for (uint32_t j = 0; j < st.line_count; j++) {
            const float *b = g->band + RS_GPU_BAND_FLOATS * ((size_t)rd[3] + j);
            double period = 0;
            for (uint32_t d = 0; d < st.line[j].dash_count; d++) period += st.line[j].dash[d];
            CHECK(b[0] == (float)st.line[j].offset && b[1] == (float)st.line[j].width &&
                  b[4] == st.line[j].colour.r && b[8] == (float)st.line[j].dash_count);
            CHECK_NEAR(b[3], period, 1e-5);
        }
    }
    CHECK(g->road[4] > 0); /* a primary road has lines */
    {
        rs_style st;
        rs_road_style(ctx, roads, 0, NULL, RS_PROFILE_RMS, &st);
        double reach = 0;
        for (uint32_t j = 0; j < st.line_count; j++)
            reach = fmax(reach, fabs(st.line[j].offset) + 0.5 * st.line[j].width);
        CHECK_NEAR(g->road[7], reach, 1e-5);
        CHECK(g->road[3 * RS_GPU_ROAD_FLOATS + 7] == 0);
    }
    CHECK(g->road[3 * RS_GPU_ROAD_FLOATS + 4] == 0 && g->road[3 * RS_GPU_ROAD_FLOATS + 0] == 0); /* unstyled */
    /* continuations: main_w's end and main_e's end meet head on; north meets them at right angles.
     * main_e runs against the stroke it forms with main_w: its points are exported last to first
     * with the stroke's arc length (40 .. 80), so its start is where main_w ends */
    CHECK(g->road[6] == 1 && g->road[RS_GPU_ROAD_FLOATS + 5] == 0 && g->road[RS_GPU_ROAD_FLOATS + 6] == -1);
    CHECK(g->road[5] == -1 && g->road[2 * RS_GPU_ROAD_FLOATS + 6] == -1);
    {
        const float *e = g->seg + 2 * RS_GPU_SEG_FLOATS;
        CHECK(e[6] == 1 && e[0] == 40 && e[2] == 80 && e[5] == 40 && e[10] == 1);
    }
    /* markings: the two explicit ones first, then the automatic ones */
    CHECK(g->nmarks >= 3);
    CHECK(g->mark[0] == 0 && g->mark[2] == 8 && g->mark[3] == -2.5f && g->mark[4] == 1.5f && g->mark[5] == 1 &&
          g->mark[6] == 0);
    CHECK(g->mark[RS_GPU_MARK_FLOATS] == 2 && g->mark[RS_GPU_MARK_FLOATS + 6] == 1);
    /* the marking's cells include the cell at its centre: main_w runs along y = 40 eastwards, t = -2.5 is south */
    {
        uint32_t i = (uint32_t)floor((8 - g->x0) / g->cell), j = (uint32_t)floor((42.5 - g->y0) / g->cell);
        size_t c = (size_t)j * g->gw + i;
        int found = 0;
        for (uint32_t e = g->mark_start[c]; e < g->mark_start[c + 1]; e++) found |= g->mark_ids[e] == 0;
        CHECK(found);
    }
    /* the atlas: every type's levels halve, texels inside atlas_px */
    rs_atlas *atlas = NULL;
    CHECK(rs_atlas_default(ctx, &atlas) == RS_OK);
    CHECK_EQ_INT(g->ntypes, rs_atlas_count(atlas));
    int levels_ok = 1;
    for (size_t t = 0; t < g->ntypes; t++) {
        uint32_t w, h;
        rs_atlas_get(atlas, t, NULL, NULL, NULL, &w, &h);
        const uint32_t *L = g->levels + RS_GPU_LEVEL_INTS * g->types[RS_GPU_TYPE_INTS * t];
        levels_ok &= L[1] == w && L[2] == h && g->types[RS_GPU_TYPE_INTS * t + 1] >= 1;
        for (uint32_t l = 0; l < g->types[RS_GPU_TYPE_INTS * t + 1]; l++) {
            const uint32_t *M = L + RS_GPU_LEVEL_INTS * l;
            levels_ok &= (size_t)M[0] + (size_t)M[1] * M[2] <= g->atlas_texels;
        }
    }
    CHECK(levels_ok);
    {
        /* kx: level-0 texels per metre across */
        uint32_t w;
        long ti = rs_atlas_find(atlas, "word_bus");
        rs_atlas_get(atlas, (size_t)ti, NULL, NULL, NULL, &w, NULL);
        CHECK(g->mark[1] == (float)ti);
        CHECK_NEAR(g->mark[7], w / 2.0, 1e-4);
    }
    rs_atlas_free(ctx, atlas);
    rs_gpu_scene_free(ctx, g);

    /* options: disabled styles and markings */
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.style.disable = 1;
    o.markings.disable = 1;
    CHECK(rs_gpu_scene_create(ctx, dem, roads, &o, NULL, &g) == RS_OK);
    CHECK(g && g->nbands == 0 && g->nmarks == 0 && g->road[0] == 0 && g->nmark_entries == 0);
    rs_gpu_scene_free(ctx, g);
    /* a given cell and reach */
    rs_gpu_options go = { 0, 8, 3 };
    CHECK(rs_gpu_scene_create(ctx, dem, roads, NULL, &go, &g) == RS_OK);
    CHECK(g && g->cell == 8 && g->reach == 3 && g->gw == 12);
    rs_gpu_scene_free(ctx, g);
    go.cell = -1;
    g = (rs_gpu_scene *)1;
    CHECK(rs_gpu_scene_create(ctx, dem, roads, NULL, &go, &g) == RS_ERR_INVALID_ARG && g == NULL);
    CHECK(strstr(rs_ctx_message(ctx), "cell") != NULL);
    CHECK(rs_gpu_scene_create(ctx, NULL, roads, NULL, NULL, &g) == RS_ERR_INVALID_ARG);
    /* an unknown mark type fails naming the line */
    rs_roads *bad = NULL;
    const char *bt = "road a width 4\n0 0\n10 0\nend\nmark nosuch road=a s=2 t=0\n";
    CHECK(rs_roads_parse(ctx, bt, strlen(bt), &bad) == RS_OK);
    CHECK(rs_gpu_scene_create(ctx, dem, bad, NULL, NULL, &g) == RS_ERR_INVALID_ARG);
    CHECK(strstr(rs_ctx_message(ctx), "line 5") && strstr(rs_ctx_message(ctx), "nosuch"));
    rs_roads_free(ctx, bad);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
}

typedef struct sweep_in {
    const rs_dem *dem;
    const rs_roads *roads;
} sweep_in;

static rs_result try_export(rs_ctx *c, void *user, int *wrong)
{
    const sweep_in *in = user;
    rs_gpu_scene *g = (rs_gpu_scene *)1;
    rs_result r = rs_gpu_scene_create(c, in->dem, in->roads, NULL, NULL, &g);
    if (r != RS_OK && g != NULL) *wrong = 1;
    rs_gpu_scene_free(c, r == RS_OK ? g : NULL);
    return r;
}

static void test_alloc_failures(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_dem *dem = make_dem(ctx);
    rs_roads *roads = NULL;
    rs_roads_parse(ctx, scene_text, strlen(scene_text), &roads);
    sweep_in in = { dem, roads };
    fail_sweep fs = fail_alloc_sweep(4000, try_export, &in);
    CHECKF(fs.succeeded && fs.wrong == 0 && fs.leaks == 0, "tries %ld wrong %ld leaks %ld", fs.tries, fs.wrong,
           fs.leaks);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
}

/* A segment of road `road` is listed in the cell holding (x, y). */
static int listed_at(const rs_gpu_scene *g, double road, double x, double y)
{
    size_t c = (size_t)floor((y - g->y0) / g->cell) * g->gw + (size_t)floor((x - g->x0) / g->cell);
    for (uint32_t e = g->cell_start[c]; e < g->cell_start[c + 1]; e++)
        if (g->seg[RS_GPU_SEG_FLOATS * (size_t)g->cell_seg[e] + 6] == road) return 1;
    return 0;
}

/* Road text exported over make_dem's DEM with the defaults, the scene
 * checked (tests/gpu_scene_check.h): the scene, or NULL after a failed check. */
static rs_gpu_scene *export_text(rs_ctx *ctx, const rs_dem *dem, const char *text, rs_roads **roads)
{
    *roads = NULL;
    CHECK(rs_roads_parse(ctx, text, strlen(text), roads) == RS_OK);
    rs_gpu_scene *g = NULL;
    CHECK(*roads && rs_gpu_scene_create(ctx, dem, *roads, NULL, NULL, &g) == RS_OK);
    const char *bad = gpu_scene_check(g);
    CHECKF(bad == NULL, "%s", bad ? bad : "");
    if (bad) {
        rs_gpu_scene_free(ctx, g);
        return NULL;
    }
    return g;
}

/* Issue 26 row 1: points at 1e300 (valid road text) made float casts give
 * inf and NaN, and the index's count and fill passes disagree: a heap
 * overflow. Far parts are cut to the disc around the map (every float near
 * the map, every index in range), and what crosses the map is still drawn. */
static void test_far_points(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_dem *dem = make_dem(ctx);
    const char *t = "road east width 4\n10 10\n1e300 10\n20 1e300\nend\n"
                    "road diag width 3 class=primary\n-1e300 -1e300\n1e300 1e300\nend\n"
                    "road wide width 1e300\n1e300 -1e300\n-1e300 -1e300\nend\n"
                    "road near width 2\n30 70\n60 70\nend\n"
                    "mark cycle road=diag s=1e12 t=0\n";
    rs_roads *roads = NULL;
    rs_gpu_scene *g = export_text(ctx, dem, t, &roads);
    if (g) {
        CHECK(listed_at(g, 0, 30, 10));  /* east runs along y = 10 */
        CHECK(listed_at(g, 1, 40, 40));  /* diag crosses the map through its centre */
        CHECK(listed_at(g, 3, 45, 70));
        /* the far segments' near parts keep their line */
        int along = 0;
        for (size_t k = 0; k < g->nseg; k++) {
            const float *s = g->seg + RS_GPU_SEG_FLOATS * k;
            if (s[6] == 0 && s[0] == 10 && s[1] == 10 && s[3] == 10 && s[2] > 80 && s[2] < 1e6) along = 1;
        }
        CHECK(along);
    }
    rs_gpu_scene_free(ctx, g);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
}

/* The T rule (docs/network.md): a side road ending on a through road's
 * centre line carries the through stroke at that end and how far from its
 * centre line its surface keeps cutting the lines (half width - 2 m); the
 * through road is flagged; the export is checked like the fuzz target's. */
static void test_tee_fields(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_dem *dem = make_dem(ctx);
    const char *t = "road main width 9 class=primary\n2 20\n78 20\nend\n"
                    "road side width 6 class=secondary\n41 40\n41 20\nend\n"
                    "road away width 5\n5 60\n30 60\nend\n";
    rs_roads *roads = NULL;
    rs_gpu_scene *g = export_text(ctx, dem, t, &roads);
    if (g) {
        const float *m = g->road, *sd = g->road + RS_GPU_ROAD_FLOATS, *aw = g->road + 2 * RS_GPU_ROAD_FLOATS;
        CHECK(m[24] >= 0 && sd[24] >= 0 && m[24] != sd[24]);
        CHECK(sd[25] == -1 && sd[26] == m[24]); /* its end meets main at a T */
        CHECK_NEAR(sd[28], 0.5 * 9 - 2, 1e-6);
        CHECK(m[29] == 1 && sd[29] == 0 && aw[29] == 0);
        CHECK(m[25] == -1 && m[26] == -1 && aw[25] == -1 && aw[26] == -1);
        const char *why = gpu_scene_check(g);
        CHECKF(why == NULL, "%s", why ? why : "");
        rs_gpu_scene_free(ctx, g);
    }
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
}

/* Issue 26 row 2: a repeated point (valid) was counted as a segment from
 * the raw points but never written (the points are de-duplicated): the
 * last segments stayed uninitialised. Segments exist where the double
 * points differ, whatever float makes of them. */
static void test_repeated_points(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_dem *dem = make_dem(ctx);
    const char *t = "road r width 4\n10 10\n10 10\n30 10\n30 10\n30 10\n30 30\nend\n"
                    "road tiny width 2\n50 50\n50.000001 50\nend\n"
                    "road dot width 3\n60 20\n60 20\nend\n";
    rs_roads *roads = NULL;
    rs_gpu_scene *g = export_text(ctx, dem, t, &roads);
    if (g) {
        CHECK_EQ_INT(g->nseg, 2 + 1 + 1);
        const float *s = g->seg;
        CHECK(s[0] == 10 && s[2] == 30 && s[5] == 0 && s[7] == RS_GPU_SEG_FIRST);
        s += RS_GPU_SEG_FLOATS;
        CHECK(s[0] == 30 && s[3] == 30 && s[5] == 20 && s[7] == RS_GPU_SEG_LAST);
        s += RS_GPU_SEG_FLOATS; /* float ends equal, the doubles are not: one segment, its direction kept */
        CHECK(s[6] == 1 && s[10] == 1 && s[11] == 0 && s[9] > 0 && s[7] == (RS_GPU_SEG_FIRST | RS_GPU_SEG_LAST));
        s += RS_GPU_SEG_FLOATS; /* one point throughout: one segment of length 0 */
        CHECK(s[6] == 2 && s[9] == 0 && s[0] == 60 && s[2] == 60);
        CHECK(listed_at(g, 2, 60, 20));
    }
    rs_gpu_scene_free(ctx, g);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
}

/* The library's GLSL (rs_gpu_glsl): every shader of version 330 in parts a
 * C99 compiler takes, the fragment shader reading every buffer the GPU
 * export fills; other versions none. (The CLI's shader render compiles and
 * draws with them: tests/cli_render_test.sh.) */
static void test_glsl(void)
{
    static const char *const bufs[] = { "u_seg", "u_cstart", "u_cseg", "u_roadt", "u_band", "u_mark",
                                        "u_mstart", "u_mids", "u_types", "u_levels", "u_atlas", "u_cut",
                                        "u_terrain", "u_road" };
    for (int w = 0; w < 4; w++) {
        size_t n = 99, total = 0;
        const char *const *src = rs_gpu_glsl(330, (rs_gpu_shader)w, &n);
        CHECK(src != NULL && n >= 1);
        if (!src) continue;
        CHECK(!strncmp(src[0], "#version 330 core\n", 18));
        int has_main = 0;
        for (size_t k = 0; k < n; k++) {
            CHECK(src[k] != NULL && strlen(src[k]) > 0 && strlen(src[k]) <= 4095);
            total += strlen(src[k]);
            has_main |= strstr(src[k], "void main()") != NULL;
        }
        CHECK(has_main);
        CHECK(total > 100);
        if (w == RS_GPU_SHADER_TERRAIN_FRAGMENT)
            for (size_t b = 0; b < sizeof bufs / sizeof bufs[0]; b++) {
                int found = 0;
                for (size_t k = 0; k < n; k++) found |= strstr(src[k], bufs[b]) != NULL;
                CHECKF(found, "the fragment shader never names %s", bufs[b]);
            }
    }
    size_t n = 7;
    CHECK(rs_gpu_glsl(300, RS_GPU_SHADER_TERRAIN_FRAGMENT, &n) == NULL && n == 0);
    n = 7;
    CHECK(rs_gpu_glsl(330, (rs_gpu_shader)4, &n) == NULL && n == 0);
    CHECK(rs_gpu_glsl(330, RS_GPU_SHADER_TERRAIN_VERTEX, NULL) != NULL);
}

int main(void)
{
    test_glsl();
    test_far_points();
    test_repeated_points();
    test_tee_fields();
    test_scene();
    test_alloc_failures();
    return th_finish("test_gpu_export");
}
