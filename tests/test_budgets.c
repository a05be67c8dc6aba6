/* Issue 26 (library side): budgets for totals and work that stays near
 * linear in the input.
 * - Road field (row 7): the segment relations of one 100 m road of n tiny
 *   segments cost O(n) work units, not n times the cell lists (the work
 *   counter, not a clock); a run of repeated points is skipped in one step;
 *   rs_limits.max_field_work stops a build that would pass it, with a
 *   message naming the budget.
 * - Line symbols: a styled road of many tiny segments builds within a
 *   work budget linear in its points (each piece steps over its own road's
 *   surfaces in one binary search); many roads crossing in one place pass
 *   the budget (their cuts grow with the square of the roads).
 * - Line-symbol memory: the pieces of all roads' lines and dashes and
 *   their index entries stay within rs_limits.max_linesym_bytes.
 * - Atlas (row 8): types with the same rectangle share one mip chain; the
 *   chains of all types together stay within rs_limits.max_atlas_bytes,
 *   checked before they are made.
 * - Surface images: the images the styles use, together, stay within
 *   rs_limits.max_texture_pixels.
 * - Markings: marks alternating between roads make each road's local
 *   points once (counted in allocations); the points the marks' stretches
 *   copy, and the markings themselves, count against rs_limits.max_points. */
#include "roadsplat.h"
#include "harness.h"
#include "gpu_scene_view.h"
#include "roadfield.h"
#include "scene_splat.h"

#include <stdlib.h>

static rs_ctx *ctx;

static rs__roadfield_params field_params(void)
{
    rs__roadfield_params p;
    memset(&p, 0, sizeof p);
    p.cell_size = 1;
    p.width_m = 128;
    p.height_m = 32;
    p.pixel = 0.25;
    return p;
}

/* Relation work per segment of a field of `roads`, or -1. */
static double work_per_segment(const rs_roads *roads, rs__roadfield_stats *st)
{
    rs__roadfield_params p = field_params();
    rs__roadfield *f = NULL;
    if (rs__roadfield_build(ctx, roads, &p, &f) != RS_OK) return -1;
    rs__roadfield_get_stats(f, st);
    rs__roadfield_free(ctx, f);
    return st->segments ? (double)st->relation_work / (double)st->segments : -1;
}

static void test_field_work(void)
{
    /* 100 m with 4000 and 16000 points: the cell lists hold thousands of
     * segments; the old scan did ~list length per segment (~5800 and
     * ~23000 units), growing 4x with 4x the points */
    double per[2];
    size_t ns[2] = { 4000, 16000 };
    for (int i = 0; i < 2; i++) {
        rs_roads *R = ss_crowded_road(ctx, ns[i], 100, NULL);
        rs__roadfield_stats st;
        per[i] = R ? work_per_segment(R, &st) : -1;
        CHECKF(per[i] > 0 && per[i] < 400, "%zu points: %.1f work units per segment (longest list %zu)", ns[i],
               per[i], st.max_list);
        CHECKF(st.max_list > ns[i] / 16, "longest list %zu", st.max_list); /* the lists really are long */
        rs_roads_free(ctx, R);
    }
    CHECKF(per[1] < 2 * per[0], "work per segment %.1f -> %.1f for 4x the points", per[0], per[1]);

    /* 20000 copies of one point (then one more): zero-length segments whose
     * joint partner was searched for past every later copy */
    rs_roads *R = NULL;
    size_t n = 20001;
    double *xy = malloc(2 * n * sizeof *xy);
    CHECK(xy && rs_roads_create(ctx, &R) == RS_OK);
    if (xy && R) {
        for (size_t k = 0; k < n; k++) xy[2 * k] = 40, xy[2 * k + 1] = 16;
        xy[2 * n - 2] = 60;
        CHECK(rs_roads_add(ctx, R, "p", 4, xy, n) == RS_OK);
        rs__roadfield_stats st;
        double w = work_per_segment(R, &st);
        CHECKF(w > 0 && w < 400, "repeated points: %.1f work units per segment", w);
        CHECK(st.redundant + 1 >= st.segments - 1); /* every copy but one is held by another */
    }
    free(xy);
    rs_roads_free(ctx, R);
}

/* The whole grid build of ss_crowded_road(n, 100 m, cls) on a 129 x 33 DEM at
 * 4 texels, on a context with max_field_work = budget (0: default); its
 * message into msg. A failure that leaves a grid is reported as
 * RS_ERR_INVALID_ARG (*out must be cleared). */
/* n motorways (several lines each) crossing at the centre of a 65 x 65
 * DEM (sc, freed by the caller); NULL when they cannot be made. */
static rs_roads *motorway_star(sc_scene *sc, int n)
{
    memset(sc, 0, sizeof *sc);
    if (sc_scene_init(sc, 65, 65, 1) != 0) return NULL;
    for (int i = 0; i < n; i++) sc_road_straight(sc, 3.14159265358979 * i / n, 60, 8);
    rs_roads *R = ss_roads(ctx, sc);
    for (size_t i = 0; R && i < rs_roads_count(R); i++)
        if (rs_roads_set_attr(ctx, R, i, "class", "motorway") != 0) {
            rs_roads_free(ctx, R);
            return NULL;
        }
    return R;
}

/* The star of 200 motorways (motorway_star) on a context with limits lim:
 * RS_ERR_LIMIT with a message holding both strings and no grid; then the
 * default limits build it. */
static void star_over_limit(const rs_limits *lim, const char *say, const char *budget)
{
    sc_scene sc;
    rs_roads *R = motorway_star(&sc, 200);
    rs_ctx *c = NULL;
    rs_dem *d = NULL;
    CHECK(R && rs_ctx_create(NULL, lim, &c) == RS_OK && rs_dem_create(c, 65, 65, sc.z, &d) == RS_OK);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 2;
    rs_road_grid *g = NULL;
    if (d) {
        CHECK_EQ_INT(rs_road_grid_build(c, d, R, &o, &g), RS_ERR_LIMIT);
        const char *m = rs_ctx_message(c);
        CHECKF(strstr(m, say) && strstr(m, budget), "message: %s", m);
        CHECK(g == NULL);
        CHECKF(rs_road_grid_build(ctx, d, R, &o, &g) == RS_OK, "%s", rs_ctx_message(ctx));
        rs_road_grid_free(ctx, g);
    }
    rs_dem_free(c, d);
    rs_ctx_free(c);
    rs_roads_free(ctx, R);
    sc_scene_free(&sc);
}

static rs_result crowded_build_ex(size_t n, const char *cls, uint64_t budget, uint64_t linesym_bytes, char *msg,
                                  size_t cap)
{
    static float z[129 * 33];
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_field_work = budget;
    lim.max_linesym_bytes = linesym_bytes;
    rs_ctx *c = NULL;
    if (rs_ctx_create(NULL, &lim, &c) != RS_OK) return RS_ERR_NOMEM;
    rs_dem *d = NULL;
    rs_roads *R = ss_crowded_road(c, n, 100, cls);
    rs_result r = R ? rs_dem_create(c, 129, 33, z, &d) : RS_ERR_NOMEM;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    rs_road_grid *g = (rs_road_grid *)(uintptr_t)1;
    if (!r) {
        r = rs_road_grid_build(c, d, R, &o, &g);
        if (r && g) r = RS_ERR_INVALID_ARG;
        if (!r) rs_road_grid_free(c, g);
    }
    snprintf(msg, cap, "%s", rs_ctx_message(c));
    rs_roads_free(c, R);
    rs_dem_free(c, d);
    rs_ctx_free(c);
    return r;
}

static rs_result crowded_build(size_t n, const char *cls, uint64_t budget, char *msg, size_t cap)
{
    return crowded_build_ex(n, cls, budget, 0, msg, cap);
}

/* Line-symbol memory has a total (rs_limits.max_linesym_bytes): a motorway
 * (several lines, dashed lanes) along n tiny segments needs pieces for
 * every segment of every line; a budget of 64 KiB stops the build with
 * RS_ERR_LIMIT naming the budget, and no grid; 2,000 bytes a point builds
 * it (the pieces cost ~470 bytes each, a few a point), and so does the
 * default. Before, only the piece count (UINT32_MAX) bounded it. */
static void test_linesym_bytes(void)
{
    char m[512];
    size_t n = 4000;
    CHECK_EQ_INT(crowded_build_ex(n, "motorway", 0, (uint64_t)64 << 10, m, sizeof m), RS_ERR_LIMIT);
    CHECKF(strstr(m, "line symbols") && strstr(m, "rs_limits.max_linesym_bytes"), "message: %s", m);
    rs_result r = crowded_build_ex(n, "motorway", 0, 2000 * (uint64_t)n, m, sizeof m);
    CHECKF(r == RS_OK, "%s", m);
    CHECKF(crowded_build(n, "motorway", 0, m, sizeof m) == RS_OK, "%s", m);
    /* an unstyled road makes no line symbols: any budget */
    CHECKF(crowded_build_ex(n, NULL, 0, 1, m, sizeof m) == RS_OK, "%s", m);
    rs_limits lim = { 0 };
    rs_ctx_limits(ctx, &lim);
    CHECK(lim.max_linesym_bytes == (uint64_t)1 << 32);
    /* the lines (with room for their dashes) of many styled roads count
     * before their pieces: 200 motorways of two points on 16 KiB */
    memset(&lim, 0, sizeof lim);
    lim.max_linesym_bytes = 16 << 10;
    star_over_limit(&lim, "styled lines take more than", "rs_limits.max_linesym_bytes");
}

/* A budget the work passes: RS_ERR_LIMIT naming rs_limits.max_field_work,
 * through the public grid build; the default budget builds the same road.
 * Line symbols of a motorway (several lines) along 20000 tiny segments: a
 * budget of 64 units per point suffices (each piece skips its own road's
 * run of a cell list in one step; scanning it took ~10^4 units per piece). */
static void test_field_budget(void)
{
    char m[512];
    CHECK_EQ_INT(crowded_build(5000, NULL, 1000, m, sizeof m), RS_ERR_LIMIT);
    CHECKF(strstr(m, "rs_limits.max_field_work") != NULL, "message: %s", m);
    CHECK(crowded_build(5000, NULL, 0, m, sizeof m) == RS_OK);
    size_t n = 20000;
    rs_result r = crowded_build(n, "motorway", 64 * (uint64_t)n, m, sizeof m);
    CHECKF(r == RS_OK, "%s", m);
}

/* Many roads through one place: n motorways (several lines each) crossing
 * at the centre of a 65 x 65 DEM. Their lines cut each other n^2 times;
 * the cuts count against max_field_work (a clip as CUT_WORK steps), so a
 * star of 200 passes a budget of 10^6 (RS_ERR_LIMIT naming the budget)
 * and builds with the default. */
static void test_star(void)
{
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_field_work = 1000000;
    star_over_limit(&lim, "line symbols", "rs_limits.max_field_work");
}

/* --- atlas ----------------------------------------------------------------------- */

/* An allocator that refuses to hold more than `cap` bytes at once. */
typedef struct cap_alloc { size_t cap, live, peak, calls; } cap_alloc;

static void *cap_malloc(void *user, size_t n)
{
    cap_alloc *a = user;
    a->calls++;
    if (n > a->cap - a->live) return NULL;
    size_t *p = malloc(n + sizeof(size_t) * 2);
    if (!p) return NULL;
    p[0] = n;
    a->live += n;
    if (a->live > a->peak) a->peak = a->live;
    return p + 2;
}

static void cap_free(void *user, void *q)
{
    cap_alloc *a = user;
    size_t *p = (size_t *)q - 2;
    a->live -= p[0];
    free(p);
}

static void *cap_realloc(void *user, void *q, size_t n)
{
    if (!q) return cap_malloc(user, n);
    size_t old = ((size_t *)q)[-2];
    void *nq = cap_malloc(user, n);
    if (!nq) return NULL;
    memcpy(nq, q, old < n ? old : n);
    cap_free(user, q);
    return nq;
}

/* An s x s atlas image: an opaque disc on transparency. */
static uint8_t *atlas_image(uint32_t s)
{
    uint8_t *px = malloc((size_t)s * s * 4);
    if (!px) return NULL;
    for (uint32_t y = 0; y < s; y++)
        for (uint32_t x = 0; x < s; x++) {
            uint8_t *p = px + ((size_t)y * s + x) * 4;
            double dx = x - 0.5 * s, dy = y - 0.5 * s;
            p[0] = (uint8_t)x, p[1] = (uint8_t)y, p[2] = 200;
            p[3] = dx * dx + dy * dy < 0.2 * s * s ? 255 : 0;
        }
    return px;
}

/* rs_atlas_create on the 1024 x 1024 image with `index`, on a context
 * whose allocator holds at most 64 MB and whose atlas budget is `budget`
 * (0: default); the atlas is freed again. Its type count into *count, the
 * message into msg; ca gets the peak and what stayed allocated after the
 * context was freed. */
static rs_result atlas_capped(const rs_image *img, const char *index, uint64_t budget, cap_alloc *ca,
                              size_t *count, char *msg, size_t cap)
{
    ca->cap = (size_t)64 << 20;
    ca->live = ca->peak = ca->calls = 0;
    rs_allocator al = { cap_malloc, cap_realloc, cap_free, ca };
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_atlas_bytes = budget;
    rs_ctx *c = NULL;
    if (rs_ctx_create(&al, &lim, &c) != RS_OK) return RS_ERR_NOMEM;
    rs_atlas *a = (rs_atlas *)(uintptr_t)1;
    rs_result r = rs_atlas_create(c, img, index, strlen(index), &a);
    snprintf(msg, cap, "%s", rs_ctx_message(c));
    *count = r == RS_OK ? rs_atlas_count(a) : 0;
    if (r != RS_OK && a != NULL) r = RS_ERR_INVALID_ARG; /* *out must be cleared */
    if (r == RS_OK) rs_atlas_free(c, a);
    rs_ctx_free(c);
    return r;
}

static void test_atlas(void)
{
    const uint32_t S = 1024;
    uint8_t *px = atlas_image(S);
    CHECK(px != NULL);
    if (!px) return;
    rs_image img = { S, S, px };
    cap_alloc ca;
    size_t n = 0;
    char m[512];
    /* six types on the same whole-image rectangle (the 6-line
     * index): one mip chain of ~22 MB, not six; the old per-type copies
     * (134 MB) ran out of the 64 MB */
    rs_result r = atlas_capped(&img, "a 0 0 1024 1024 3 1\nb 0 0 1024 1024 3 1\nc 0 0 1024 1024 3 1\n"
                                     "d 0 0 1024 1024 3 1\ne 0 0 1024 1024 3 1\nf 0 0 1024 1024 3 1\n",
                               0, &ca, &n, m, sizeof m);
    CHECKF(r == RS_OK && n == 6, "%d: %s (peak %zu bytes)", (int)r, m, ca.peak);
    CHECK(ca.peak < (size_t)32 << 20);
    CHECK_EQ_INT(ca.live, 0); /* the shared chain is freed once */
    /* distinct rectangles count one by one against max_atlas_bytes, before
     * their chains are made: 3 x ~22 MB over a 48 MB budget */
    static const char distinct[] = "a 0 0 1024 1024 3 1\nb 0 0 1024 1024 3 1\nc 1 0 1023 1024 3 1\n"
                                   "d 0 1 1024 1023 3 1\n";
    r = atlas_capped(&img, distinct, (uint64_t)48 << 20, &ca, &n, m, sizeof m);
    CHECK_EQ_INT(r, RS_ERR_LIMIT);
    CHECKF(strstr(m, "line 4") && strstr(m, "'d'") && strstr(m, "max_atlas_bytes"), "message: %s", m);
    CHECK(ca.peak < (size_t)48 << 20);
    CHECK_EQ_INT(ca.live, 0);
    /* the default budget (256 MiB) takes them */
    rs_atlas *a = NULL;
    CHECK(rs_atlas_create(ctx, &img, distinct, sizeof distinct - 1, &a) == RS_OK && rs_atlas_count(a) == 4);
    rs_atlas_free(ctx, a);
    free(px);
}

/* The GPU export keeps the sharing: types on one rectangle point to the
 * same level records, whose texels are exported once. */
static void test_atlas_gpu(void)
{
    uint8_t *px = atlas_image(64);
    rs_image img = { 64, 64, px };
    static const char same[] = "a 0 0 64 64 3 1\nb 0 0 64 64 3 1\nc 0 0 64 64 3 1\nd 0 0 32 64 3 1\n";
    rs_atlas *a = NULL;
    CHECK(px && rs_atlas_create(ctx, &img, same, sizeof same - 1, &a) == RS_OK);
    float z[9 * 9] = { 0 };
    rs_dem *d = NULL;
    rs_roads *R = ss_crowded_road(ctx, 2, 5, NULL);
    rs_mark mk;
    memset(&mk, 0, sizeof mk);
    mk.type = "b";
    mk.s = 2;
    CHECK(R && rs_roads_add_mark(ctx, R, &mk) == RS_OK && rs_dem_create(ctx, 9, 9, z, &d) == RS_OK);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.markings.atlas = a;
    rs_gpu_scene *gs = NULL;
    CHECK(a && d && rs_gpu_scene_create(ctx, d, R, &o, NULL, &gs) == RS_OK);
    if (gs) {
        /* 64 x 64 and 32 x 64 chains: 5461 + 2731 texels (levels down to 1 x 1) */
        CHECK_EQ_INT(gsv_of(gs).ntypes, 4);
        CHECK_EQ_INT(gsv_of(gs).atlas_texels, 5461 + 2731);
        CHECK(gsv_of(gs).types[2] == gsv_of(gs).types[0] && gsv_of(gs).types[4] == gsv_of(gs).types[0] && gsv_of(gs).types[6] != gsv_of(gs).types[0]);
    }
    rs_gpu_scene_free(ctx, gs);
    rs_dem_free(ctx, d);
    rs_roads_free(ctx, R);
    rs_atlas_free(ctx, a);
    free(px);
}

/* --- markings ----------------------------------------------------------------------- */

/* Two parallel roads of n points over 100 m (y = 10 and 20), `marks`
 * explicit arrows of length `len` (0: the type's) at s = 50 alternating
 * between them; the grid build on a context with max_points = budget (0:
 * default) whose allocator counts its calls (*calls). */
static rs_result marked_build(size_t n, size_t marks, double len, uint64_t budget, size_t *calls, char *msg,
                              size_t cap)
{
    static float z[129 * 33];
    sc_scene sc;
    memset(&sc, 0, sizeof sc);
    rs_roads *R = NULL;
    if (!sc_road_crowded(&sc, 10, 10, 100, n, 6) && !sc_road_crowded(&sc, 10, 20, 100, n, 6)) R = ss_roads(ctx, &sc);
    sc_scene_free(&sc);
    for (size_t i = 0; R && i < marks; i++) {
        rs_mark m;
        memset(&m, 0, sizeof m);
        m.type = "arrow_straight";
        m.road = i % 2;
        m.s = 50;
        m.length = len;
        if (rs_roads_add_mark(ctx, R, &m)) { rs_roads_free(ctx, R); R = NULL; }
    }
    cap_alloc ca = { (size_t)1 << 30, 0, 0, 0 };
    rs_allocator al = { cap_malloc, cap_realloc, cap_free, &ca };
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_points = budget;
    rs_ctx *c = NULL;
    rs_dem *d = NULL;
    rs_result r = R && rs_ctx_create(&al, &lim, &c) == RS_OK ? rs_dem_create(c, 129, 33, z, &d) : RS_ERR_NOMEM;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    o.style.disable = 1;
    rs_road_grid *g = NULL;
    size_t before = ca.calls;
    if (!r) r = rs_road_grid_build(c, d, R, &o, &g);
    *calls = ca.calls - before;
    snprintf(msg, cap, "%s", c ? rs_ctx_message(c) : "");
    rs_road_grid_free(c, g);
    rs_dem_free(c, d);
    rs_ctx_free(c);
    rs_roads_free(ctx, R);
    return r;
}

static void test_markings(void)
{
    /* 400 marks alternating between two roads of 5000 points: each road's
     * local points are made once (they were remade at every switch: 5000
     * points each time, marks x points in all) */
    size_t few = 0, many = 0;
    char m[512];
    CHECK(marked_build(5000, 2, 0, 0, &few, m, sizeof m) == RS_OK);
    CHECKF(marked_build(5000, 400, 0, 0, &many, m, sizeof m) == RS_OK, "%s", m);
    CHECKF(many < few + 100, "allocations: %zu for 2 marks, %zu for 400", few, many);
    /* the marks' stretches count together against max_points: 40 marks of
     * 50 m over 2 x 5000 points (~100,000 stretch points) pass 50,000 */
    CHECK_EQ_INT(marked_build(5000, 40, 50, 50000, &many, m, sizeof m), RS_ERR_LIMIT);
    CHECKF(strstr(m, "stretches") && strstr(m, "rs_limits.max_points"), "message: %s", m);
    CHECKF(marked_build(5000, 40, 50, 200000, &many, m, sizeof m) == RS_OK, "%s", m);
    /* and the markings themselves: 300 on roads of 2 x 100 points, budget 250 */
    CHECK_EQ_INT(marked_build(100, 300, 0, 250, &many, m, sizeof m), RS_ERR_LIMIT);
    CHECKF(strstr(m, "more than 250 markings") && strstr(m, "rs_limits.max_points"), "message: %s", m);
}

/* --- surface images ---------------------------------------------------------------- */

static void test_surface_image_total(void)
{
    /* two styles with a 2 x 2 image each: 8 pixels in use; a limit of 6
     * pixels (each image alone fits) refuses the second */
    static const char text[] = "style s1\n surface one\nend\nstyle s2\n surface two\nend\n"
                               "road a width 4 style=s1\n1 4\n9 4\nend\nroad b width 4 style=s2\n1 8\n9 8\nend\n";
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_texture_pixels = 6;
    rs_ctx *c = NULL;
    CHECK(rs_ctx_create(NULL, &lim, &c) == RS_OK);
    if (!c) return;
    rs_styles *st = NULL;
    rs_roads *R = NULL;
    rs_dem *d = NULL;
    float z[11 * 11] = { 0 };
    CHECK(rs_styles_create(c, &st) == RS_OK);
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.styles = st;
    CHECK(rs_roads_parse_ex(c, text, sizeof text - 1, &po, &R) == RS_OK);
    CHECK(rs_dem_create(c, 11, 11, z, &d) == RS_OK);
    uint8_t px[16] = { 255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 9, 9, 9, 255 };
    rs_surface_image si[2] = { { "one", { 2, 2, px } }, { "two", { 2, 2, px } } };
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 2;
    o.style.styles = st;
    o.style.surface_images = si;
    o.style.surface_image_count = 2;
    rs_road_grid *g = NULL;
    CHECK_EQ_INT(rs_road_grid_build(c, d, R, &o, &g), RS_ERR_LIMIT);
    CHECKF(strstr(rs_ctx_message(c), "max_texture_pixels") != NULL, "message: %s", rs_ctx_message(c));
    CHECK(g == NULL);
    /* with room for both (8 pixels) the same build succeeds */
    rs_ctx *c2 = NULL;
    lim.max_texture_pixels = 8;
    CHECK(rs_ctx_create(NULL, &lim, &c2) == RS_OK);
    CHECKF(c2 && rs_road_grid_build(c2, d, R, &o, &g) == RS_OK, "%s", c2 ? rs_ctx_message(c2) : "");
    rs_road_grid_free(c2, g);
    rs_ctx_free(c2);
    rs_roads_free(c, R);
    rs_styles_free(c, st);
    rs_dem_free(c, d);
    rs_ctx_free(c);
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_field_work();
    test_field_budget();
    test_star();
    test_linesym_bytes();
    test_atlas();
    test_atlas_gpu();
    test_markings();
    test_surface_image_total();
    rs_ctx_free(ctx);
    return th_finish("test_budgets");
}
