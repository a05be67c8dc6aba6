/* GPU export (lib/gpu/gpu_export.c, docs/render.md "Shader mode"): segments with
 * their arc length and flags, the index grid (every segment near a cell is
 * listed there, ascending), styles and bands as rs_road_style gives them,
 * continuations, markings in road coordinates with the atlas's mip chains,
 * errors, and no leak under allocation failures. */
#include "harness.h"
#include "fail_alloc.h"
#include "gpu_scene_check.h"
#include "roadsplat.h"
#include "scene_splat.h"

#include <math.h>
#include <stdio.h>
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
    CHECK_EQ_INT(gsv_of(g).nroads, 4);
    CHECK_EQ_INT(gsv_of(g).nseg, 2 + 1 + 1 + 2);
    CHECK_NEAR(gsv_of(g).map_w, 80, 0);
    CHECK_NEAR(gsv_of(g).cell, 2, 0);
    CHECK(gsv_of(g).gw == 42 && gsv_of(g).gh == 42);
    /* segments: end points, s, road, flags */
    const float *s = gsv_of(g).seg;
    CHECK(s[0] == 0 && s[1] == 40 && s[2] == 20 && s[3] == 40 && s[4] == 5 && s[5] == 0 && s[6] == 0 &&
          s[7] == RS_GPU_SEG_FIRST);
    s += RS_GPU_SEG_FLOATS;
    CHECK(s[0] == 20 && s[5] == 20 && s[6] == 0 && s[7] == RS_GPU_SEG_LAST);
    s = gsv_of(g).seg + 4 * RS_GPU_SEG_FLOATS;
    CHECK(s[6] == 3 && s[4] == 1.5f && s[7] == RS_GPU_SEG_FIRST);
    CHECK_NEAR(s[RS_GPU_SEG_FLOATS + 5], hypot(10, 7), 1e-5);
    CHECK_NEAR(s[9], hypot(10, 7), 1e-5);
    CHECK_NEAR(s[10], 10 / hypot(10, 7), 1e-6);
    CHECK(s[8] == 0);
    CHECK(gsv_of(g).seg[8] == (float)gsv_of(g).road[2]);
    /* the index: per cell ascending, and complete: a segment within its half
     * width + casing + reach of a cell's centre is listed there */
    int complete = 1, ascending = 1;
    for (uint32_t j = 0; j < gsv_of(g).gh; j++)
        for (uint32_t i = 0; i < gsv_of(g).gw; i++) {
            size_t c = (size_t)j * gsv_of(g).gw + i;
            double cx = gsv_of(g).x0 + (i + 0.5) * gsv_of(g).cell, cy = gsv_of(g).y0 + (j + 0.5) * gsv_of(g).cell;
            for (uint32_t e = gsv_of(g).cell_start[c]; e + 1 < gsv_of(g).cell_start[c + 1]; e++)
                ascending &= gsv_of(g).cell_seg[e] < gsv_of(g).cell_seg[e + 1];
            for (size_t k = 0; k < gsv_of(g).nseg; k++) {
                const float *q = gsv_of(g).seg + RS_GPU_SEG_FLOATS * k;
                double R = q[4] + gsv_of(g).road[RS_GPU_ROAD_FLOATS * (size_t)q[6] + 2] + gsv_of(g).reach;
                if (seg_dist(q, cx, cy) > R) continue;
                int found = 0;
                for (uint32_t e = gsv_of(g).cell_start[c]; e < gsv_of(g).cell_start[c + 1]; e++) found |= gsv_of(g).cell_seg[e] == k;
                complete &= found;
            }
        }
    CHECK(complete && ascending);
    CHECK(gpu_scene_check(g) == NULL);
    CHECK(gsv_of(g).nseg_entries == gsv_of(g).cell_start[(size_t)gsv_of(g).gw * gsv_of(g).gh]);
    /* styles: as rs_road_style resolves them */
    for (size_t i = 0; i < 4; i++) {
        rs_style st;
        CHECK(rs_road_style(ctx, roads, i, NULL, RS_PROFILE_RMS, &st) == RS_OK);
        const float *rd = gsv_of(g).road + RS_GPU_ROAD_FLOATS * i;
        CHECK(rd[0] == (float)st.surface && rd[2] == (float)st.casing_width && rd[4] == (float)st.line_count);
        CHECK(rd[20] == st.casing.r && rd[23] == st.casing.a / 255.0f);
        for (uint32_t j = 0; j < st.line_count; j++) {
            const float *b = gsv_of(g).band + RS_GPU_BAND_FLOATS * ((size_t)rd[3] + j);
            double period = 0;
            for (uint32_t d = 0; d < st.line[j].dash_count; d++) period += st.line[j].dash[d];
            CHECK(b[0] == (float)st.line[j].offset && b[1] == (float)st.line[j].width &&
                  b[4] == st.line[j].colour.r && b[8] == (float)st.line[j].dash_count);
            CHECK_NEAR(b[3], period, 1e-5);
        }
    }
    CHECK(gsv_of(g).road[4] > 0); /* a primary road has lines */
    {
        rs_style st;
        rs_road_style(ctx, roads, 0, NULL, RS_PROFILE_RMS, &st);
        double reach = 0;
        for (uint32_t j = 0; j < st.line_count; j++)
            reach = fmax(reach, fabs(st.line[j].offset) + 0.5 * st.line[j].width);
        CHECK_NEAR(gsv_of(g).road[7], reach, 1e-5);
        CHECK(gsv_of(g).road[3 * RS_GPU_ROAD_FLOATS + 7] == 0);
    }
    CHECK(gsv_of(g).road[3 * RS_GPU_ROAD_FLOATS + 4] == 0 && gsv_of(g).road[3 * RS_GPU_ROAD_FLOATS + 0] == 0); /* unstyled */
    /* continuations: main_w's end and main_e's end meet head on; north meets them at right angles.
     * main_e runs against the stroke it forms with main_w: its points are exported last to first
     * with the stroke's arc length (40 .. 80), so its start is where main_w ends */
    CHECK(gsv_of(g).road[6] == 1 && gsv_of(g).road[RS_GPU_ROAD_FLOATS + 5] == 0 && gsv_of(g).road[RS_GPU_ROAD_FLOATS + 6] == -1);
    CHECK(gsv_of(g).road[5] == -1 && gsv_of(g).road[2 * RS_GPU_ROAD_FLOATS + 6] == -1);
    {
        const float *e = gsv_of(g).seg + 2 * RS_GPU_SEG_FLOATS;
        CHECK(e[6] == 1 && e[0] == 40 && e[2] == 80 && e[5] == 40 && e[10] == 1);
    }
    /* markings: the two explicit ones first, then the automatic ones */
    CHECK(gsv_of(g).nmarks >= 3);
    CHECK(gsv_of(g).mark[0] == 0 && gsv_of(g).mark[2] == 8 && gsv_of(g).mark[3] == -2.5f && gsv_of(g).mark[4] == 1.5f && gsv_of(g).mark[5] == 1 &&
          gsv_of(g).mark[6] == 0);
    CHECK(gsv_of(g).mark[RS_GPU_MARK_FLOATS] == 2 && gsv_of(g).mark[RS_GPU_MARK_FLOATS + 6] == 1);
    /* the marking's cells include the cell at its centre: main_w runs along y = 40 eastwards, t = -2.5 is south */
    {
        uint32_t i = (uint32_t)floor((8 - gsv_of(g).x0) / gsv_of(g).cell), j = (uint32_t)floor((42.5 - gsv_of(g).y0) / gsv_of(g).cell);
        size_t c = (size_t)j * gsv_of(g).gw + i;
        int found = 0;
        for (uint32_t e = gsv_of(g).mark_start[c]; e < gsv_of(g).mark_start[c + 1]; e++) found |= gsv_of(g).mark_ids[e] == 0;
        CHECK(found);
    }
    /* the atlas: every type's levels halve, texels inside atlas_px */
    rs_atlas *atlas = NULL;
    CHECK(rs_atlas_default(ctx, &atlas) == RS_OK);
    CHECK_EQ_INT(gsv_of(g).ntypes, rs_atlas_count(atlas));
    int levels_ok = 1;
    for (size_t t = 0; t < gsv_of(g).ntypes; t++) {
        uint32_t w, h;
        rs_atlas_get(atlas, t, NULL, NULL, NULL, &w, &h);
        const uint32_t *L = gsv_of(g).levels + RS_GPU_LEVEL_INTS * gsv_of(g).types[RS_GPU_TYPE_INTS * t];
        levels_ok &= L[1] == w && L[2] == h && gsv_of(g).types[RS_GPU_TYPE_INTS * t + 1] >= 1;
        for (uint32_t l = 0; l < gsv_of(g).types[RS_GPU_TYPE_INTS * t + 1]; l++) {
            const uint32_t *M = L + RS_GPU_LEVEL_INTS * l;
            levels_ok &= (size_t)M[0] + (size_t)M[1] * M[2] <= gsv_of(g).atlas_texels;
        }
    }
    CHECK(levels_ok);
    {
        /* kx: level-0 texels per metre across */
        uint32_t w;
        long ti = rs_atlas_find(atlas, "word_bus");
        rs_atlas_get(atlas, (size_t)ti, NULL, NULL, NULL, &w, NULL);
        CHECK(gsv_of(g).mark[1] == (float)ti);
        CHECK_NEAR(gsv_of(g).mark[7], w / 2.0, 1e-4);
    }
    rs_atlas_free(ctx, atlas);
    rs_gpu_scene_free(ctx, g);

    /* options: disabled styles and markings */
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.style.disable = 1;
    o.markings.disable = 1;
    CHECK(rs_gpu_scene_create(ctx, dem, roads, &o, NULL, &g) == RS_OK);
    CHECK(g && gsv_of(g).nbands == 0 && gsv_of(g).nmarks == 0 && gsv_of(g).road[0] == 0 && gsv_of(g).nmark_entries == 0);
    rs_gpu_scene_free(ctx, g);
    /* a given cell and reach */
    rs_gpu_options go = { 0, 8, 3 };
    CHECK(rs_gpu_scene_create(ctx, dem, roads, NULL, &go, &g) == RS_OK);
    CHECK(g && gsv_of(g).cell == 8 && gsv_of(g).reach == 3 && gsv_of(g).gw == 12);
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
    const rs_road_grid *grid; /* NULL: rs_gpu_scene_create, else rs_gpu_scene_from_grid */
} sweep_in;

static rs_result try_export(rs_ctx *c, void *user, int *wrong)
{
    const sweep_in *in = user;
    rs_gpu_scene *g = (rs_gpu_scene *)1;
    rs_result r = in->grid ? rs_gpu_scene_from_grid(c, in->dem, in->roads, in->grid, NULL, &g)
                           : rs_gpu_scene_create(c, in->dem, in->roads, NULL, NULL, &g);
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
    sweep_in in = { dem, roads, NULL };
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
    size_t c = (size_t)floor((y - gsv_of(g).y0) / gsv_of(g).cell) * gsv_of(g).gw + (size_t)floor((x - gsv_of(g).x0) / gsv_of(g).cell);
    for (uint32_t e = gsv_of(g).cell_start[c]; e < gsv_of(g).cell_start[c + 1]; e++)
        if (gsv_of(g).seg[RS_GPU_SEG_FLOATS * (size_t)gsv_of(g).cell_seg[e] + 6] == road) return 1;
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
        for (size_t k = 0; k < gsv_of(g).nseg; k++) {
            const float *s = gsv_of(g).seg + RS_GPU_SEG_FLOATS * k;
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
        const float *m = gsv_of(g).road, *sd = gsv_of(g).road + RS_GPU_ROAD_FLOATS, *aw = gsv_of(g).road + 2 * RS_GPU_ROAD_FLOATS;
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
        CHECK_EQ_INT(gsv_of(g).nseg, 2 + 1 + 1);
        const float *s = gsv_of(g).seg;
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

/* Joints (RS_GPU_SEG_JOIN_*): two records the CPU draws as one line are
 * flagged at the point they share, whichever way the second one's points
 * run; records whose lines differ (the lanes change there) are not, nor a
 * record end that meets no continuation. */
static const char joints_text[] = "road a width 7 class=secondary\n10 20\n40 20\nend\n"
                                  "road a width 7 class=secondary\n40 20\n55 15\n68 10\nend\n"
                                  "road b width 7 class=secondary\n10 45\n40 45\nend\n"
                                  "road b width 7 class=secondary\n68 55\n40 45\nend\n"
                                  "road c width 9 class=secondary lanes=1\n10 70\n40 70\nend\n"
                                  "road c width 9 class=secondary lanes=2\n40 70\n68 75\nend\n";

static void test_joints(void)
{
    rs_ctx *ctx = NULL;
    rs_roads *roads = NULL;
    CHECK(rs_ctx_create(NULL, NULL, &ctx) == RS_OK);
    rs_dem *dem = make_dem(ctx);
    rs_gpu_scene *g = export_text(ctx, dem, joints_text, &roads);
    if (g) {
        const gsv v = gsv_of(g);
        CHECK_EQ_INT(v.nseg, 7);
        uint32_t f[7];
        for (int k = 0; k < 7; k++) f[k] = (uint32_t)v.seg[RS_GPU_SEG_FLOATS * k + 7];
        const uint32_t F = RS_GPU_SEG_FIRST, L = RS_GPU_SEG_LAST, JF = RS_GPU_SEG_JOIN_FIRST, JL = RS_GPU_SEG_JOIN_LAST;
        CHECKF(f[0] == (F | L | JL) && f[1] == (F | JF) && f[2] == L, "a: %u %u %u", f[0], f[1], f[2]);
        /* b's second record runs against its stroke: exported last to first */
        CHECKF(f[3] == (F | L | JL) && f[4] == (F | L | JF), "b: %u %u", f[3], f[4]);
        CHECK(v.seg[RS_GPU_SEG_FLOATS * 4] == 40 && v.seg[RS_GPU_SEG_FLOATS * 4 + 1] == 45);
        CHECKF(f[5] == (F | L) && f[6] == (F | L), "c: %u %u", f[5], f[6]);
        for (int i = 0; i < 6; i++) CHECK(v.road[RS_GPU_ROAD_FLOATS * i + 39] == (float)(i < 2 ? i : i + 1));
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

/* Two scenes are the same: every scalar and every array byte for byte. */
static int same_scene(const rs_gpu_scene *a, const rs_gpu_scene *b, char *why, size_t n)
{
    rs_gpu_scene_info ia, ib;
    rs_gpu_scene_get_info(a, &ia);
    rs_gpu_scene_get_info(b, &ib);
    if (memcmp(&ia, &ib, sizeof ia)) { snprintf(why, n, "info differs (segments %zu / %zu, bytes %zu / %zu)", ia.nseg, ib.nseg, ia.bytes, ib.bytes); return 0; }
    for (int k = 0; k < RS_GPU_ARRAY_COUNT; k++) {
        size_t na = 0, nb = 0;
        const void *pa = rs_gpu_scene_array(a, (rs_gpu_array)k, &na), *pb = rs_gpu_scene_array(b, (rs_gpu_array)k, &nb);
        if (!pa || !pb || na != nb || (na && memcmp(pa, pb, na * 4))) {
            snprintf(why, n, "array %d differs (%zu / %zu values)", k, na, nb);
            return 0;
        }
    }
    return 1;
}

/* rs_gpu_scene_from_grid gives rs_gpu_scene_create's bytes with the
 * grid's options; the style table may be gone by then. */
static void from_grid_case(rs_ctx *ctx, const char *what, const rs_dem *dem, const rs_roads *roads,
                           const rs_splat_options *o, rs_styles *styles_to_free)
{
    rs_gpu_scene *a = NULL, *b = NULL;
    rs_road_grid *grid = NULL;
    rs_result ra = rs_gpu_scene_create(ctx, dem, roads, o, NULL, &a);
    CHECKF(ra == RS_OK, "%s: create: %s", what, rs_ctx_message(ctx));
    rs_result rg = rs_road_grid_build(ctx, dem, roads, o, &grid);
    CHECKF(rg == RS_OK, "%s: grid: %s", what, rs_ctx_message(ctx));
    if (styles_to_free) rs_styles_free(ctx, styles_to_free); /* the grid keeps what it resolved */
    if (grid) {
        rs_result rb = rs_gpu_scene_from_grid(ctx, dem, roads, grid, NULL, &b);
        CHECKF(rb == RS_OK, "%s: from grid: %s", what, rs_ctx_message(ctx));
    }
    if (a && b) {
        char why[160] = "";
        CHECKF(same_scene(a, b, why, sizeof why), "%s: %s", what, why);
        const char *bad = gpu_scene_check(b);
        CHECKF(bad == NULL, "%s: %s", what, bad ? bad : "");
    }
    rs_gpu_scene_free(ctx, a);
    rs_gpu_scene_free(ctx, b);
    rs_road_grid_free(ctx, grid);
}

static const char *styled_text =
    "style town\n  fill #808080\n  casing 0.5 #FFffFF80\n  line 0 0.12 #fafafa dash 3 6 phase 1.5\n"
    "  line -3.1 0.25 #ffffff\n  line 2.5 0.1 #FFD700 dash 1 2 3 4\nend\n"
    "style big\n  gradient #202020 #404040c0\n  line 0.2 0.1 #ffffff phase 2 dash 5 5\nend\n"
    "style bare\nend\n";
static const char *styled_roads =
    "road a width 7 style=town\n2 30\n40 30\nend\n"
    "road b width 7 style=town\n40 30\n78 31\nend\n"
    "road c width 9 style=big\n40 2\n40 30\nend\n"
    "road d width 5 style=bare class=residential\n5 70\n70 70\nend\n"
    "road e width 6 class=primary lanes=4 turn:lanes=left|through|through|right\n10 50\n75 50 crossing=zebra\nend\n"
    "mark word_bus road=a s=8 t=-2 length=3 width=2\n";

static void test_from_grid(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_dem *dem = make_dem(ctx);
    rs_roads *roads = NULL;
    CHECK(rs_roads_parse(ctx, scene_text, strlen(scene_text), &roads) == RS_OK);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    from_grid_case(ctx, "defaults", dem, roads, NULL, NULL);
    o.style.driving_side = RS_DRIVING_LEFT;
    o.style.profile = RS_PROFILE_MUTCD;
    from_grid_case(ctx, "left, MUTCD", dem, roads, &o, NULL);
    memset(&o, 0, sizeof o);
    o.markings.no_auto = 1;
    from_grid_case(ctx, "explicit markings only", dem, roads, &o, NULL);
    memset(&o, 0, sizeof o);
    o.style.disable = 1;
    o.markings.disable = 1;
    from_grid_case(ctx, "styles and markings off", dem, roads, &o, NULL);
    memset(&o, 0, sizeof o);
    o.coverage.edges = RS_EDGES_ALPHAMAP;
    o.texels = 2;
    from_grid_case(ctx, "alpha-map edges, 2 texels", dem, roads, &o, NULL);
    rs_roads_free(ctx, roads);

    /* named styles (casing, gradient, dashes, an empty style), the table
     * freed before the export from the grid */
    rs_styles *styles = NULL;
    roads = NULL;
    CHECK(rs_styles_parse(ctx, styled_text, strlen(styled_text), &styles) == RS_OK);
    CHECK(rs_roads_parse(ctx, styled_roads, strlen(styled_roads), &roads) == RS_OK);
    memset(&o, 0, sizeof o);
    o.style.styles = styles;
    if (styles && roads) from_grid_case(ctx, "named styles", dem, roads, &o, styles);
    rs_roads_free(ctx, roads);

    /* no road styled (the grid keeps no styles) */
    const char *plain = "road p width 4\n5 5\n70 60\nend\nroad q width 3\n70 5\n5 60\nend\n";
    CHECK(rs_roads_parse(ctx, plain, strlen(plain), &roads) == RS_OK);
    from_grid_case(ctx, "unstyled", dem, roads, NULL, NULL);

    /* wrong uses */
    rs_road_grid *grid = NULL;
    rs_gpu_scene *g = (rs_gpu_scene *)1;
    CHECK(rs_road_grid_build(ctx, dem, roads, NULL, &grid) == RS_OK);
    CHECK(rs_gpu_scene_from_grid(ctx, dem, roads, NULL, NULL, &g) == RS_ERR_INVALID_ARG && g == NULL);
    rs_dem *other = NULL;
    float z[9] = { 0 };
    CHECK(rs_dem_create(ctx, 3, 3, z, &other) == RS_OK);
    g = (rs_gpu_scene *)1;
    CHECK(rs_gpu_scene_from_grid(ctx, other, roads, grid, NULL, &g) == RS_ERR_INVALID_ARG && g == NULL);
    CHECK(strstr(rs_ctx_message(ctx), "another DEM") != NULL);
    CHECK(rs_gpu_scene_from_grid(NULL, dem, roads, grid, NULL, &g) == RS_ERR_INVALID_ARG);
    /* a styled grid and other roads: refused, never read past its tables */
    {
        rs_roads *styled = NULL, *more = NULL;
        rs_road_grid *sg = NULL;
        const char *one = "road a width 6 class=primary\n5 40\n75 40\nend\n";
        const char *two = "road a width 6 class=primary\n5 40\n75 40\nend\nroad b width 6 class=primary\n40 5\n40 75\nend\n";
        CHECK(rs_roads_parse(ctx, one, strlen(one), &styled) == RS_OK && rs_roads_parse(ctx, two, strlen(two), &more) == RS_OK);
        CHECK(styled && rs_road_grid_build(ctx, dem, styled, NULL, &sg) == RS_OK);
        g = (rs_gpu_scene *)1;
        CHECK(sg && more && rs_gpu_scene_from_grid(ctx, dem, more, sg, NULL, &g) == RS_ERR_INVALID_ARG && g == NULL);
        CHECK(strstr(rs_ctx_message(ctx), "other roads") != NULL);
        rs_road_grid_free(ctx, sg);
        rs_roads_free(ctx, styled);
        rs_roads_free(ctx, more);
    }
    rs_gpu_options go;
    memset(&go, 0, sizeof go);
    go.cell = -1;
    CHECK(rs_gpu_scene_from_grid(ctx, dem, roads, grid, &go, &g) == RS_ERR_INVALID_ARG && g == NULL);
    rs_dem_free(ctx, other);
    rs_road_grid_free(ctx, grid);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
}

/* The city (1000 roads) unstyled, and with classes (styles, casings,
 * automatic markings): the same bytes from the grid. */
static void test_from_grid_city(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    sc_scene sc;
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    CHECK(ss_city(ctx, &sc, &dem, &roads) == 0);
    CHECK(roads && rs_roads_count(roads) > 900);
    if (dem && roads) from_grid_case(ctx, "city, unstyled", dem, roads, NULL, NULL);
    /* the benchmarks' styled city: OSM classes by width (lines, casings,
     * automatic markings) */
    int classed = roads != NULL;
    for (size_t i = 0; classed && i < sc.nroads; i++)
        classed = rs_roads_set_attr(ctx, roads, i, "class", sc_city_class(sc.roads[i].width)) == RS_OK;
    CHECK(classed);
    if (dem && classed) {
        rs_gpu_scene *g = NULL;
        CHECK(rs_gpu_scene_create(ctx, dem, roads, NULL, NULL, &g) == RS_OK);
        CHECKF(g && gsv_of(g).nbands > 100 && gsv_of(g).nmarks > 1000 && gsv_of(g).ncuts > 100,
               "bands %zu, marks %zu, cuts %zu", g ? (size_t)gsv_of(g).nbands : 0, g ? (size_t)gsv_of(g).nmarks : 0,
               g ? (size_t)gsv_of(g).ncuts : 0);
        rs_gpu_scene_free(ctx, g);
        from_grid_case(ctx, "city, styled", dem, roads, NULL, NULL);
    }
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    rs_ctx_free(ctx);
}

static void test_from_grid_alloc_failures(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_dem *dem = make_dem(ctx);
    rs_roads *roads = NULL;
    rs_road_grid *grid = NULL;
    rs_roads_parse(ctx, scene_text, strlen(scene_text), &roads);
    CHECK(rs_road_grid_build(ctx, dem, roads, NULL, &grid) == RS_OK);
    sweep_in in = { dem, roads, grid };
    fail_sweep fs = fail_alloc_sweep(4000, try_export, &in);
    CHECKF(fs.succeeded && fs.wrong == 0 && fs.leaks == 0, "tries %ld wrong %ld leaks %ld", fs.tries, fs.wrong,
           fs.leaks);
    rs_road_grid_free(ctx, grid);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
}

/* The marking tables the shader samples (RS_GPU_ARRAY_MARK_LEVELS and
 * MARK_SAT): per type, its level-0 texels (times 255, rounded) are the
 * second differences of its summed-area corners, and the corners start
 * with a row and a column of zeros; the level records are LEVELS but for
 * each type's level-0 fourth int, its first corner. */
static void test_mark_tables(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_dem *dem = make_dem(ctx);
    rs_roads *roads = NULL;
    rs_gpu_scene *g = export_text(ctx, dem, scene_text, &roads);
    if (g) {
        gsv v = gsv_of(g);
        size_t nl = 0, ns = 0;
        CHECK(rs_gpu_scene_array(g, RS_GPU_ARRAY_MARK_LEVELS, &nl) == v.mark_levels && nl == v.nlevels * RS_GPU_LEVEL_INTS);
        CHECK(rs_gpu_scene_array(g, RS_GPU_ARRAY_MARK_SAT, &ns) == v.mark_sat && ns == 4 * v.sat_corners);
        CHECK(v.ntypes > 0 && v.sat_corners > 0);
        long bad = 0;
        for (size_t l = 0; l < v.nlevels; l++)
            for (int k = 0; k < 3; k++) bad += v.mark_levels[4 * l + k] != v.levels[4 * l + k];
        for (size_t t = 0; t < v.ntypes; t++) {
            const uint32_t *L = v.mark_levels + RS_GPU_LEVEL_INTS * v.types[RS_GPU_TYPE_INTS * t];
            size_t w = L[1], h = L[2], w1 = w + 1, first = L[3];
            if (!v.types[RS_GPU_TYPE_INTS * t + 1]) continue;
            CHECK(first + w1 * (h + 1) <= v.sat_corners);
            if (first + w1 * (h + 1) > v.sat_corners) break;
            const int32_t *S = v.mark_sat + 4 * first;
            const float *px = v.atlas_px + 4 * (size_t)L[0];
            for (size_t i = 0; i < 4 * w1; i++) bad += S[i] != 0;
            for (size_t j = 0; j < h; j++) {
                for (int c = 0; c < 4; c++) bad += S[4 * (j + 1) * w1 + (size_t)c] != 0;
                for (size_t i = 0; i < w; i++)
                    for (int c = 0; c < 4; c++) {
                        int64_t d = (int64_t)S[4 * ((j + 1) * w1 + i + 1) + c] - S[4 * (j * w1 + i + 1) + c] -
                                    S[4 * ((j + 1) * w1 + i) + c] + S[4 * (j * w1 + i) + c];
                        bad += d != (int64_t)lrintf(px[4 * (j * w + i) + c] * 255.0f);
                    }
            }
        }
        CHECK_EQ_INT(bad, 0);
        /* the samplers: names the fragment shader uses, and their formats */
        uint32_t ch = 9, kind = 9;
        CHECK(!strcmp(rs_gpu_array_sampler(RS_GPU_ARRAY_MARK_SAT, &ch, &kind), "u_atlas") && ch == 4 && kind == 2);
        CHECK(!strcmp(rs_gpu_array_sampler(RS_GPU_ARRAY_CELL_SEG, &ch, &kind), "u_cseg") && ch == 1 && kind == 1);
        CHECK(rs_gpu_array_sampler(RS_GPU_ARRAY_ATLAS_PX, NULL, NULL) == NULL);
        CHECK(rs_gpu_array_sampler(RS_GPU_ARRAY_COUNT, &ch, &kind) == NULL && ch == 0);
        size_t n = 5;
        CHECK(rs_gpu_scene_array(g, RS_GPU_ARRAY_COUNT, &n) == NULL && n == 0);
        CHECK(rs_gpu_scene_array(NULL, RS_GPU_ARRAY_SEG, &n) == NULL && n == 0);
        rs_gpu_scene_free(ctx, g);
    }
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
}

int main(void)
{
    test_from_grid();
    test_from_grid_city();
    test_from_grid_alloc_failures();
    test_mark_tables();
    test_glsl();
    test_far_points();
    test_repeated_points();
    test_joints();
    test_tee_fields();
    test_scene();
    test_alloc_failures();
    return th_finish("test_gpu_export");
}
