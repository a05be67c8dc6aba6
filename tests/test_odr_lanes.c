/* OpenDRIVE lanes to road text (lib/input/odr_lanes.c, docs/opendrive.md) on
 * documents built in C: lane boundaries, dash phase through lane sections,
 * error messages, every allocation failing in turn, and the road attribute
 * junction_cuts=no that keeps explicit marks from being cut by the surface
 * under them. The XML side and the accuracy against an independent
 * evaluator are tests/cli_odr_test.sh + tests/odr_check.py. */
#include "harness.h"
#include "fail_alloc.h"
#include "odr_lanes.h"

#include <stdlib.h>
#include <string.h>

static rs_ctx *ctx;

/* A straight road along +x from (0, 0), 100 m, two lane sections (s = 0,
 * 40): lane 1 (3 m, then widening), centre broken yellow, lane -1 3.5 m
 * with a solid line; a laneOffset of 0.25 m. */
typedef struct fixture {
    rs__odr_doc doc;
    rs__odr_road road;
    rs__odr_geom geom;
    rs__odr_poly polys[4];
    rs__odr_section secs[2];
    rs__odr_lane lanes[6];
    rs__odr_mark marks[3];
    rs__odr_mark_line lines[1]; /* none used: the arrays are never NULL */
    rs__odr_object objects[1];
} fixture;

static void fixture_init(fixture *F)
{
    memset(F, 0, sizeof *F);
    F->geom.kind = RS__ODR_LINE;
    F->geom.length = 100;
    /* polys: 0 laneOffset, 1 lane 1 (sec 0), 2 lane 1 (sec 1), 3 lane -1 (both) */
    F->polys[0] = (rs__odr_poly){ 0, 0.25, 0, 0, 0 };
    F->polys[1] = (rs__odr_poly){ 0, 3, 0, 0, 0 };
    F->polys[2] = (rs__odr_poly){ 40, 3, 0.01, 0, 0 };
    F->polys[3] = (rs__odr_poly){ 0, 3.5, 0, 0, 0 };
    F->marks[0] = (rs__odr_mark){ 0, RS__ODR_MARK_BROKEN, 0.12, 0xF2B705FFu, 0, NULL, 0, 0, 5 };
    F->marks[1] = (rs__odr_mark){ 40, RS__ODR_MARK_BROKEN, 0.12, 0xF2B705FFu, 0, NULL, 0, 0, 9 };
    F->marks[2] = (rs__odr_mark){ 0, RS__ODR_MARK_SOLID, 0.15, 0xF4F4F0FFu, 0, NULL, 0, 0, 6 };
    /* section 0: lanes 1, 0, -1 (left to right) */
    F->lanes[0] = (rs__odr_lane){ 1, RS__ODR_SURF_ROAD, 1, 1, 0, 0, 4 };
    F->lanes[1] = (rs__odr_lane){ 0, RS__ODR_SURF_NONE, 0, 0, 0, 1, 5 };
    F->lanes[2] = (rs__odr_lane){ -1, RS__ODR_SURF_ROAD, 3, 1, 2, 1, 6 };
    F->lanes[3] = (rs__odr_lane){ 1, RS__ODR_SURF_ROAD, 2, 1, 0, 0, 8 };
    F->lanes[4] = (rs__odr_lane){ 0, RS__ODR_SURF_NONE, 0, 0, 1, 1, 9 };
    F->lanes[5] = (rs__odr_lane){ -1, RS__ODR_SURF_ROAD, 3, 1, 0, 0, 10 };
    F->secs[0] = (rs__odr_section){ 0, 0, 3, 3 };
    F->secs[1] = (rs__odr_section){ 40, 3, 3, 7 };
    F->road = (rs__odr_road){ "r1", 100, 0, 0, 1, 0, 1, 0, 2, 0, 0, 2 };
    F->doc.name = "t.xodr";
    F->doc.roads = &F->road;
    F->doc.nroads = 1;
    F->doc.geoms = &F->geom;
    F->doc.ngeoms = 1;
    F->doc.polys = F->polys;
    F->doc.npolys = 4;
    F->doc.sections = F->secs;
    F->doc.nsections = 2;
    F->doc.lanes = F->lanes;
    F->doc.nlanes = 6;
    F->doc.marks = F->marks;
    F->doc.nmarks = 3;
    F->doc.lines = F->lines;
    F->doc.objects = F->objects;
}

static void test_boundaries(void)
{
    fixture F;
    fixture_init(&F);
    CHECK_NEAR(rs__odr_boundary_t(&F.doc, &F.road, &F.secs[0], 0, 10), 0.25, 1e-15);
    CHECK_NEAR(rs__odr_boundary_t(&F.doc, &F.road, &F.secs[0], 1, 10), 3.25, 1e-15);
    CHECK_NEAR(rs__odr_boundary_t(&F.doc, &F.road, &F.secs[0], -1, 10), -3.25, 1e-15);
    CHECK_NEAR(rs__odr_boundary_t(&F.doc, &F.road, &F.secs[1], 1, 60), 0.25 + 3 + 0.2, 1e-12);
    CHECK_NEAR(rs__odr_poly_at(F.polys + 1, 2, 50), 3.1, 1e-12);
    CHECK_NEAR(rs__odr_poly_at(F.polys + 1, 2, 20), 3, 1e-15);
}

/* Road text records (name, first x, last x) of the centre lane. */
static size_t centre_dashes(const char *text, double *x0, double *x1, size_t cap)
{
    rs_roads *roads = NULL;
    rs_styles *styles = NULL;
    size_t n = 0;
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    if (rs_styles_create(ctx, &styles) != RS_OK) return 0;
    po.styles = styles;
    if (rs_roads_parse_ex(ctx, text, strlen(text), &po, &roads) == RS_OK) {
        for (size_t i = 0; i < rs_roads_count(roads); i++) {
            const char *name;
            const double *xy;
            size_t np;
            double w;
            rs_roads_get(roads, i, &name, &w, &xy, &np);
            const char *jc = rs_roads_get_attr(roads, i, "junction_cuts");
            CHECK(jc && !strcmp(jc, "no"));
            if (!strstr(name, "/lane0") || n == cap) continue;
            x0[n] = xy[0];
            x1[n] = xy[2 * (np - 1)];
            n++;
        }
    }
    rs_roads_free(ctx, roads);
    rs_styles_free(ctx, styles);
    return n;
}

/* The 3 m / 6 m dashes run on across the section boundary at s = 40 (not a
 * multiple of the 9 m period): dashes start at 0, 9, ..., 36 (cut at 39),
 * 45, ... and the one over s = 40 is cut there, not restarted. */
static void test_dash_phase(void)
{
    fixture F;
    fixture_init(&F);
    char *text = NULL;
    size_t size = 0;
    rs_result r = rs__odr_to_text(ctx, &F.doc, 0, &text, &size);
    CHECK_EQ_INT(r, RS_OK);
    if (r) return;
    CHECK_EQ_INT(strlen(text), size);
    double x0[64], x1[64];
    size_t n = centre_dashes(text, x0, x1, 64);
    CHECK_EQ_INT(n, 12); /* 0..36 (5), 45..99 (7); 36..39 ends before the section */
    int ok = 1;
    for (size_t i = 0; i < n; i++) {
        double k = x0[i] / 9;
        ok &= fabs(k - floor(k + 0.5)) < 1e-9 && fabs(x1[i] - fmin(x0[i] + 3, 100)) < 1e-9;
    }
    CHECKF(ok, "dashes off the 3/6 m pattern of the road's s");
    rs__free(ctx, text);
    /* the same with the second section's mark starting 1 m later: 45 .. 48 is unchanged, 40 .. 41 not drawn */
    F.marks[1].s = 41;
    r = rs__odr_to_text(ctx, &F.doc, 0, &text, &size);
    CHECK_EQ_INT(r, RS_OK);
    if (!r) {
        n = centre_dashes(text, x0, x1, 64);
        CHECK_EQ_INT(n, 12);
        rs__free(ctx, text);
    }
}

static void test_errors(void)
{
    fixture F;
    fixture_init(&F);
    char *text = NULL;
    size_t size = 0;
    F.geom.curv_start = 0;
    F.geom.kind = RS__ODR_SPIRAL;
    F.geom.curv_end = 1e9;
    CHECK_EQ_INT(rs__odr_to_text(ctx, &F.doc, 0, &text, &size), RS_ERR_PARSE);
    CHECKF(strstr(rs_ctx_message(ctx), "t.xodr: road 'r1' (line 2): geometry 1") != NULL, "%s", rs_ctx_message(ctx));
    CHECK(text == NULL);
    fixture_init(&F);
    F.polys[2].d = 1; /* 60^3 m */
    CHECK_EQ_INT(rs__odr_to_text(ctx, &F.doc, 0, &text, &size), RS_ERR_PARSE);
    CHECKF(strstr(rs_ctx_message(ctx), "t.xodr line 8: road 'r1' lane 1: width record 1 may reach beyond 1000 m") != NULL,
           "%s", rs_ctx_message(ctx));
    fixture_init(&F);
    F.secs[1].s = 120;
    CHECK_EQ_INT(rs__odr_to_text(ctx, &F.doc, 0, &text, &size), RS_ERR_PARSE);
    CHECKF(strstr(rs_ctx_message(ctx), "t.xodr line 7: road 'r1': laneSection s=120") != NULL, "%s", rs_ctx_message(ctx));
    fixture_init(&F);
    CHECK_EQ_INT(rs__odr_to_text(ctx, &F.doc, 20, &text, &size), RS_ERR_LIMIT);
    CHECKF(strstr(rs_ctx_message(ctx), "more than 20 points") != NULL, "%s", rs_ctx_message(ctx));
    CHECK(text == NULL);
}

static rs_result convert_try(rs_ctx *c, void *user, int *wrong)
{
    char *text = NULL;
    size_t size = 0;
    rs_result r = rs__odr_to_text(c, (const rs__odr_doc *)user, 0, &text, &size);
    if (r == RS_OK) rs__free(c, text);
    else if (text) *wrong = 1;
    return r;
}

static void test_alloc_failures(void)
{
    fixture F;
    fixture_init(&F);
    fail_sweep fs = fail_alloc_sweep(2000, convert_try, &F.doc);
    CHECK_SWEEP(fs, 3);
}

/* A record with a line lying on another record's surface: its line is cut
 * away by default, drawn with junction_cuts=no (both records). */
static int line_pixel(const char *text, uint8_t out[4])
{
    enum { W = 21, H = 11 };
    static float z[W * H];
    rs_dem *dem = NULL;
    rs_styles *styles = NULL;
    rs_roads *roads = NULL;
    rs_splatter *s = NULL;
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    int ok = rs_dem_create(ctx, W, H, z, &dem) == RS_OK && rs_styles_create(ctx, &styles) == RS_OK;
    po.styles = styles;
    ok = ok && rs_roads_parse_ex(ctx, text, strlen(text), &po, &roads) == RS_OK;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 10;
    o.style.styles = styles;
    ok = ok && rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_OK;
    uint8_t px[4 * 10 * 10];
    /* the 10 x 10 texels of cell (10, 5): the line runs along y = 5.05 */
    ok = ok && rs_splat_window(ctx, s, 100, 45, 10, 10, px, 40, NULL, 0, NULL) == RS_OK;
    if (ok) memcpy(out, px + 4 * (10 * 5 + 5), 4); /* texel centre (10.55, 5.05) */
    rs_splatter_free(ctx, s);
    rs_roads_free(ctx, roads);
    rs_styles_free(ctx, styles);
    rs_dem_free(ctx, dem);
    return ok;
}

static void test_junction_cuts(void)
{
    const char *base = "style red\n  line 0 0.2 #FF0000\nend\n"
                       "road surface width 6%s\n  0 5\n  20 5\nend\n"
                       "road mark width 0.2 style=red%s\n  2 5.05\n  18 5.05\nend\n";
    char text[400];
    uint8_t cut[4] = { 0 }, kept[4] = { 0 };
    snprintf(text, sizeof text, base, "", "");
    CHECK(line_pixel(text, cut));
    snprintf(text, sizeof text, base, " junction_cuts=no", " junction_cuts=no");
    CHECK(line_pixel(text, kept));
    CHECKF(kept[0] > 240 && kept[1] < 30, "junction_cuts=no: %u %u %u", kept[0], kept[1], kept[2]);
    CHECKF(!(cut[0] > 240 && cut[1] < 30), "default: the line is cut by the surface under it: %u %u %u", cut[0], cut[1],
           cut[2]);
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_boundaries();
    test_dash_phase();
    test_errors();
    test_alloc_failures();
    test_junction_cuts();
    rs_ctx_free(ctx);
    return th_finish("test_odr_lanes");
}
