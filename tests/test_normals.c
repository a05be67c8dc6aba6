/* Normal maps (issue 16, docs/normals.md): tilted planes in the four
 * directions under both conventions against the analytic normal, flat
 * ground, road relief present, window and thread byte-identity, argument
 * checks and allocation failure. */
#include "harness.h"
#include "fail_alloc.h"
#include "roadsplat.h"
#include "band_threads.h"

#include <stdlib.h>
#include <string.h>

static rs_ctx *ctx;

/* A DEM of W x H samples on the plane z = 100 + a x + b y (x right, y down,
 * metres; cell size cs, z-scale zs). */
static rs_dem *plane(uint32_t W, uint32_t H, double cs, double zs, double a, double b)
{
    float *z = malloc((size_t)W * H * sizeof *z);
    for (uint32_t i = 0; i < H; i++)
        for (uint32_t j = 0; j < W; j++) z[(size_t)i * W + j] = (float)((100 + a * j * cs + b * i * cs) / zs);
    rs_dem *d = NULL;
    CHECK(rs_dem_create(ctx, W, H, z, &d) == RS_OK);
    rs_dem_frame fr = { cs, zs, 0, 0 };
    CHECK(rs_dem_set_frame(ctx, d, &fr) == RS_OK);
    free(z);
    return d;
}

static uint8_t *normals_whole(const rs_splatter *s, const rs_normal_options *o, uint32_t *w, uint32_t *h)
{
    rs_splatter_size(s, w, h);
    uint8_t *px = malloc((size_t)*w * *h * 3);
    CHECK(rs_normal_window(ctx, s, 0, 0, *w, *h, px, (size_t)*w * 3, o) == RS_OK);
    return px;
}

static double dec(uint8_t v) { return v / 255.0 * 2 - 1; }

/* Tilted planes: east, west, north and south rising; both conventions. */
static void test_planes(void)
{
    static const struct { double a, b; const char *name; } dirs[] = {
        { 0.5, 0, "rising east" }, { -0.5, 0, "rising west" }, { 0, -0.5, "rising north" }, { 0, 0.5, "rising south" },
        { 0.3, -1.7, "rising north-east" }, { 0, 0, "flat" },
    };
    rs_roads *none = NULL;
    CHECK(rs_roads_create(ctx, &none) == RS_OK);
    for (size_t d = 0; d < sizeof dirs / sizeof dirs[0]; d++)
        for (int dx = 0; dx < 2; dx++) {
            rs_dem *dem = plane(9, 7, 2.0, 0.25, dirs[d].a, dirs[d].b);
            rs_splat_options so;
            memset(&so, 0, sizeof so);
            so.texels = 3;
            rs_splatter *s = NULL;
            CHECK(rs_splatter_create(ctx, dem, none, NULL, &so, &s) == RS_OK);
            rs_normal_options o;
            memset(&o, 0, sizeof o);
            o.directx = dx;
            uint32_t w, h;
            uint8_t *px = normals_whole(s, &o, &w, &h);
            /* analytic: (-dz/dx, dz/dy, 1) normalised, tangent Y north */
            double a = dirs[d].a, b = dirs[d].b, l = sqrt(a * a + b * b + 1);
            double n[3] = { -a / l, (dx ? -b : b) / l, 1 / l };
            double worst = 0;
            for (size_t i = 0; i < (size_t)w * h; i++)
                for (int c = 0; c < 3; c++) {
                    double e = fabs(dec(px[3 * i + c]) - n[c]);
                    worst = e > worst ? e : worst;
                }
            /* one step of 2/255 per component for rounding plus 1/255 */
            CHECKF(worst <= 1.0 / 255 + 1.0 / 255 + 1e-9, "%s %s: worst component error %g", dirs[d].name,
                   dx ? "dx" : "gl", worst);
            const uint8_t *c = px + 3 * ((size_t)(h / 2) * w + w / 2);
            if (d == 0) CHECK(c[0] < 128 && c[1] == 128);   /* faces west */
            if (d == 1) CHECK(c[0] > 128 && c[1] == 128);   /* faces east */
            if (d == 2) CHECK(c[0] == 128 && (dx ? c[1] > 128 : c[1] < 128)); /* faces south */
            if (d == 3) CHECK(c[0] == 128 && (dx ? c[1] < 128 : c[1] > 128)); /* faces north */
            if (d == 5) {
                int flat = 1;
                for (size_t i = 0; i < (size_t)w * h; i++)
                    flat &= px[3 * i] == 128 && px[3 * i + 1] == 128 && px[3 * i + 2] == 255;
                CHECKF(flat, "flat ground is (128, 128, 255) (%s)", dx ? "dx" : "gl");
            }
            free(px);
            rs_splatter_free(ctx, s);
            rs_dem_free(ctx, dem);
        }
    rs_roads_free(ctx, none);
}

/* A hilly scene with styled roads (lines), markings and a road texture. */
typedef struct scene {
    rs_dem *dem;
    rs_roads *roads;
    rs_styles *styles;
    rs_image tex;
    uint8_t tex_px[7 * 5 * 4];
} scene;

static void scene_init(scene *f)
{
    memset(f, 0, sizeof *f);
    enum { W = 23, H = 19 };
    float z[W * H];
    for (int i = 0; i < H; i++)
        for (int j = 0; j < W; j++) z[i * W + j] = (float)(20 * sin(j * 0.37) * cos(i * 0.29) + 0.5 * i);
    CHECK(rs_dem_create(ctx, W, H, z, &f->dem) == RS_OK);
    rs_dem_frame fr = { 2.0, 0.5, 0, 0 };
    CHECK(rs_dem_set_frame(ctx, f->dem, &fr) == RS_OK);
    static const char text[] = "style lined\n"
                               "  line 0 0.3 #FFFFFF dash 1.5 1 phase 0.4\n"
                               "  line 2.2 0.2 #FFFF00\n"
                               "end\n"
                               "road a width 6 style=lined\n3 4\n20 18\n41 30\nend\n"
                               "road b width 7 class=primary\n2 30\n44 6\nend\n"
                               "mark arrow_straight road=a s=12 t=-1.5\n"
                               "mark zebra road=b s=20 t=0 width=5\n";
    CHECK(rs_styles_create(ctx, &f->styles) == RS_OK);
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.styles = f->styles;
    CHECK(rs_roads_parse_ex(ctx, text, sizeof text - 1, &po, &f->roads) == RS_OK);
    for (size_t i = 0; i < sizeof f->tex_px; i++) f->tex_px[i] = (uint8_t)(i * 37 + (i * i) % 53);
    f->tex.width = 7;
    f->tex.height = 5;
    f->tex.rgba = f->tex_px;
}

static void scene_free(scene *f)
{
    rs_roads_free(ctx, f->roads);
    rs_styles_free(ctx, f->styles);
    rs_dem_free(ctx, f->dem);
}

static void scene_options(const scene *f, int mode, rs_splat_options *o)
{
    memset(o, 0, sizeof *o);
    o->texels = 5;
    o->coverage.edges = mode & 1 ? RS_EDGES_ALPHAMAP : RS_EDGES_ANALYTIC;
    o->style.styles = f->styles;
    if (mode & 2) o->surface.road_texture = &f->tex;
    o->surface.texture_scale = 3.3;
}

/* Windows of odd sizes, offset, into a padded buffer: the bytes of the whole. */
static int tiled_equal(const rs_splatter *s, const rs_normal_options *o, const uint8_t *ref, uint32_t w, uint32_t h,
                       uint32_t tw, uint32_t th, uint32_t off)
{
    size_t stride = (size_t)w * 3 + 11;
    uint8_t *px = malloc(stride * h);
    memset(px, 0xA5, stride * h);
    int ok = 1;
    for (uint32_t y = 0; ok && y < h;) {
        uint32_t hh = y == 0 && off ? off : th;
        if (hh > h - y) hh = h - y;
        for (uint32_t x = 0; ok && x < w;) {
            uint32_t ww = x == 0 && off ? off : tw;
            if (ww > w - x) ww = w - x;
            ok = rs_normal_window(ctx, s, x, y, ww, hh, px + y * stride + (size_t)x * 3, stride, o) == RS_OK;
            x += ww;
        }
        y += hh;
    }
    for (uint32_t y = 0; ok && y < h; y++) {
        ok = memcmp(px + y * stride, ref + (size_t)y * w * 3, (size_t)w * 3) == 0;
        for (size_t k = (size_t)w * 3; ok && k < stride; k++) ok = px[y * stride + k] == 0xA5;
    }
    free(px);
    return ok;
}

static void test_windows(void)
{
    scene f;
    scene_init(&f);
    for (int mode = 0; mode < 4; mode++) {
        rs_splat_options so;
        scene_options(&f, mode, &so);
        rs_splatter *s = NULL;
        CHECK(rs_splatter_create(ctx, f.dem, f.roads, NULL, &so, &s) == RS_OK);
        if (!s) continue;
        rs_normal_options o;
        memset(&o, 0, sizeof o);
        o.directx = mode == 3;
        o.strength = mode == 2 ? 3.5 : 0;
        uint32_t w, h;
        uint8_t *ref = normals_whole(s, &o, &w, &h);
        CHECKF(tiled_equal(s, &o, ref, w, h, 7, 3, 0), "mode %d: 7x3 windows", mode);
        CHECKF(tiled_equal(s, &o, ref, w, h, 13, 11, 4), "mode %d: 13x11 windows offset 4", mode);
        CHECKF(tiled_equal(s, &o, ref, w, h, 1, 1, 0), "mode %d: 1x1 windows", mode);
        CHECKF(tiled_equal(s, &o, ref, w, h, w, 1, 0), "mode %d: rows", mode);
        for (uint32_t n = 2; n <= 3; n++)
            CHECKF(bt_threads_equal(s, &o, ref, w, h, 4, n), "mode %d: %u threads differ", mode, n);
        /* the road relief shows: paint and texture change road pixels only */
        uint16_t *wt = malloc((size_t)w * h * 2);
        uint8_t *rgba = malloc((size_t)w * h * 4);
        CHECK(rs_splat_window(ctx, s, 0, 0, w, h, rgba, (size_t)w * 4, wt, w, NULL) == RS_OK);
        rs_normal_options flat = o;
        flat.no_paint = 1;
        uint8_t *np = normals_whole(s, &flat, &w, &h);
        size_t changed = 0, off_road = 0;
        for (size_t i = 0; i < (size_t)w * h; i++) {
            int diff = memcmp(np + 3 * i, ref + 3 * i, 3) != 0;
            changed += diff;
            off_road += diff && wt[i] == 0;
        }
        CHECKF(changed > 0 && off_road == 0, "mode %d: paint changes %zu pixels, %zu off the road", mode, changed,
               off_road);
        if (mode & 2) {
            /* without the texture: only the terrain outside the road */
            rs_splat_options so2;
            scene_options(&f, mode & 1, &so2);
            rs_splatter *s2 = NULL;
            CHECK(rs_splatter_create(ctx, f.dem, f.roads, NULL, &so2, &s2) == RS_OK);
            uint8_t *nt = normals_whole(s2, &flat, &w, &h);
            size_t tchanged = 0, toff = 0;
            for (size_t i = 0; i < (size_t)w * h; i++) {
                int diff = memcmp(np + 3 * i, nt + 3 * i, 3) != 0;
                tchanged += diff;
                toff += diff && wt[i] == 0;
            }
            CHECKF(tchanged > 100 && toff == 0, "mode %d: texture changes %zu pixels, %zu off the road", mode,
                   tchanged, toff);
            free(nt);
            rs_splatter_free(ctx, s2);
        }
        free(np);
        free(wt);
        free(rgba);
        free(ref);
        rs_splatter_free(ctx, s);
    }
    scene_free(&f);
}

static void test_arguments(void)
{
    scene f;
    scene_init(&f);
    rs_splat_options so;
    scene_options(&f, 0, &so);
    rs_splatter *s = NULL;
    CHECK(rs_splatter_create(ctx, f.dem, f.roads, NULL, &so, &s) == RS_OK);
    uint32_t w, h;
    rs_splatter_size(s, &w, &h);
    uint8_t px[16 * 3];
    rs_normal_options o;
    static const double bad_strength[] = { -1, 2e6, NAN, INFINITY };
    for (size_t i = 0; i < 4; i++) {
        memset(&o, 0, sizeof o);
        o.strength = bad_strength[i];
        CHECK(rs_normal_window(ctx, s, 0, 0, 4, 4, px, 12, &o) == RS_ERR_INVALID_ARG);
        CHECK(strstr(rs_ctx_message(ctx), "strength") != NULL);
    }
    static const double bad_paint[] = { -0.001, 1.5, NAN, -INFINITY };
    for (size_t i = 0; i < 4; i++) {
        memset(&o, 0, sizeof o);
        o.paint_height = bad_paint[i];
        CHECK(rs_normal_window(ctx, s, 0, 0, 4, 4, px, 12, &o) == RS_ERR_INVALID_ARG);
        CHECK(strstr(rs_ctx_message(ctx), "paint_height") != NULL);
    }
    CHECK(rs_normal_window(ctx, s, 0, 0, 4, 4, px, 12, NULL) == RS_OK);
    CHECK(rs_normal_window(ctx, s, 0, 0, 4, 4, px, 11, NULL) == RS_ERR_BUFFER_TOO_SMALL);
    CHECK(rs_normal_window(ctx, s, 0, 0, 0, 4, px, 12, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_normal_window(ctx, s, w - 3, 0, 4, 4, px, 12, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_normal_window(ctx, s, 0, h, 4, 1, px, 12, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_normal_window(ctx, NULL, 0, 0, 4, 4, px, 12, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_normal_window(ctx, s, 0, 0, 4, 4, NULL, 12, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_normal_window(NULL, s, 0, 0, 4, 4, px, 12, NULL) == RS_ERR_INVALID_ARG);
    rs_splatter_free(ctx, s);
    scene_free(&f);
}

typedef struct alloc_case {
    const scene *f;
    int mode;
} alloc_case;

static rs_result alloc_try(rs_ctx *c, void *user, int *wrong)
{
    const alloc_case *ac = user;
    rs_splat_options so;
    scene_options(ac->f, ac->mode, &so);
    rs_splatter *s = NULL;
    uint8_t px[11 * 9 * 3];
    rs_result r = rs_splatter_create(c, ac->f->dem, ac->f->roads, NULL, &so, &s);
    if (!r) r = rs_normal_window(c, s, 20, 25, 11, 9, px, 11 * 3, NULL);
    (void)wrong;
    rs_splatter_free(c, s);
    return r;
}

static void test_alloc_failures(void)
{
    scene f;
    scene_init(&f);
    for (int mode = 0; mode < 4; mode++) {
        alloc_case ac = { &f, mode };
        fail_sweep fs = fail_alloc_sweep(5000, alloc_try, &ac);
        CHECK_SWEEP(fs, 3);
    }
    scene_free(&f);
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_planes();
    test_windows();
    test_arguments();
    test_alloc_failures();
    rs_ctx_free(ctx);
    return th_finish("test_normals");
}
