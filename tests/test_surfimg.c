/* Road-aligned surface images (`surface IMG [length L]`) and lit output
 * (rs_lighting_options), issue 16 (docs/surface.md):
 * - the parser's keyword and its errors, the API checks;
 * - the mapping follows a curved road: a stripe of the strip at a known t
 *   lands at that t (left of travel = the image's left edge);
 * - the repeat along s is seamless (the colour along the centre line is the
 *   wrapped bilinear sample, no jump at the wrap);
 * - mipmaps: a fine checkerboard seen from far is smooth grey;
 * - windows and threads give the bytes of the whole image, with and without
 *   lighting;
 * - the normal map picks up the strip's luminance;
 * - lighting: a plane facing the sun is brighter than one facing away, in the
 *   documented ratio; flat ground keeps its colour (factor 1); the specular
 *   term; bad options. */
#include "harness.h"
#include "fail_alloc.h"
#include "roadsplat.h"
#include "band_threads.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static rs_ctx *ctx;

/* A DEM of W x H samples on the plane z = 100 + a x + b y (metres). */
static rs_dem *plane(uint32_t W, uint32_t H, double cs, double a, double b)
{
    float *z = malloc((size_t)W * H * sizeof *z);
    for (uint32_t i = 0; i < H; i++)
        for (uint32_t j = 0; j < W; j++) z[(size_t)i * W + j] = (float)(100 + a * j * cs + b * i * cs);
    rs_dem *d = NULL;
    CHECK(rs_dem_create(ctx, W, H, z, &d) == RS_OK);
    rs_dem_frame fr = { cs, 1, 0, 0 };
    CHECK(rs_dem_set_frame(ctx, d, &fr) == RS_OK);
    free(z);
    return d;
}

static rs_roads *parse(const char *text, rs_styles *styles)
{
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.styles = styles;
    rs_roads *r = NULL;
    rs_result rc = rs_roads_parse_ex(ctx, text, strlen(text), &po, &r);
    CHECKF(rc == RS_OK, "%s", rs_ctx_message(ctx));
    return r;
}

/* Whole image of a splatter. */
static uint8_t *splat_whole(const rs_splatter *s, uint16_t **wt, uint32_t *w, uint32_t *h)
{
    rs_splatter_size(s, w, h);
    uint8_t *px = malloc((size_t)*w * *h * 4);
    if (wt) *wt = malloc((size_t)*w * *h * 2);
    rs_result r = rs_splat_window(ctx, s, 0, 0, *w, *h, px, (size_t)*w * 4, wt ? *wt : NULL, *w, NULL);
    CHECKF(r == RS_OK, "%s", rs_ctx_message(ctx));
    return px;
}

/* ---- parser ------------------------------------------------------------- */

/* A splatter of `roads` with the styles S and the one surface image si,
 * markings off; NULL on failure (counted). */
static rs_splatter *strip_splatter(const rs_dem *dem, const rs_roads *roads, rs_styles *S, const rs_surface_image *si,
                                   uint32_t texels)
{
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = texels;
    o.style.styles = S;
    o.style.surface_images = si;
    o.style.surface_image_count = 1;
    o.markings.disable = 1;
    rs_splatter *s = NULL;
    CHECKF(rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_OK, "%s", rs_ctx_message(ctx));
    return s;
}

static int parse_fails(const char *text, const char *want)
{
    rs_styles *S = NULL;
    rs_result r = rs_styles_parse(ctx, text, strlen(text), &S);
    rs_styles_free(ctx, S);
    if (r == RS_OK) return 0;
    if (!strstr(rs_ctx_message(ctx), want)) {
        fprintf(stderr, "    message: %s\n    wanted: %s\n", rs_ctx_message(ctx), want);
        return 0;
    }
    return 1;
}

static void test_parse(void)
{
    static const char ok[] = "style a\n  surface strips/asphalt.png length 28\n  fill #00000040\nend\n"
                             "style \"b c\"\n  line 0 0.1 #FFFFFF\n  surface \"my strips/x # y.png\"\nend\n";
    rs_styles *S = NULL;
    CHECK(rs_styles_parse(ctx, ok, sizeof ok - 1, &S) == RS_OK);
    const rs_style *a = rs_styles_find(S, "a"), *b = rs_styles_find(S, "b c");
    CHECK(a && !strcmp(a->surface_image, "strips/asphalt.png") && a->surface_length == 28 && a->surface_line == 2);
    CHECK(a && a->surface == RS_SURFACE_FILL);
    CHECK(b && !strcmp(b->surface_image, "my strips/x # y.png") && b->surface_length == 0 && b->surface_line == 7);
    rs_styles_free(ctx, S);

    CHECK(parse_fails("style a\nsurface\nend\n", "line 2: 'surface' needs an image"));
    CHECK(parse_fails("style a\nsurface x.png\nsurface y.png\nend\n", "line 3: style 'a': 'surface' given twice"));
    CHECK(parse_fails("style a\nsurface x.png length 0\nend\n", "line 2: surface length '0' must be"));
    CHECK(parse_fails("style a\nsurface x.png length\nend\n", "line 2: surface length is missing"));
    CHECK(parse_fails("style a\nsurface x.png length 2e6\nend\n", "surface length '2e6' must be"));
    CHECK(parse_fails("style a\nsurface x.png length 4 more\nend\n", "line 2: extra token 'more'"));
    CHECK(parse_fails("style a\nsurface x.png size 4\nend\n", "line 2: unexpected 'size' after the surface image"));
    CHECK(parse_fails("style a\nsurface \"\"\nend\n", "line 2: surface image '\"\"' must be 1..255 bytes"));
    CHECK(parse_fails("style a\nsurface \"x\n", "line 2:"));
    char longname[400];
    memset(longname, 'x', sizeof longname);
    memcpy(longname, "style a\nsurface ", 16);
    memcpy(longname + 16 + 256, "\nend\n", 6);
    CHECK(parse_fails(longname, "line 2: surface image"));
    CHECK(parse_fails("style a\nsurfac x.png\nend\n", "expected fill, gradient, surface, casing, line or end"));

    /* the API's checks */
    rs_style st;
    memset(&st, 0, sizeof st);
    strcpy(st.name, "api");
    CHECK(rs_styles_create(ctx, &S) == RS_OK);
    st.surface_length = 5; /* a length without an image */
    CHECK(rs_styles_add(ctx, S, &st) == RS_ERR_INVALID_ARG && strstr(rs_ctx_message(ctx), "surface length"));
    strcpy(st.surface_image, "a\tb");
    CHECK(rs_styles_add(ctx, S, &st) == RS_ERR_INVALID_ARG && strstr(rs_ctx_message(ctx), "control character"));
    memset(st.surface_image, 'x', sizeof st.surface_image); /* no NUL */
    CHECK(rs_styles_add(ctx, S, &st) == RS_ERR_INVALID_ARG && strstr(rs_ctx_message(ctx), "longer than 255"));
    strcpy(st.surface_image, "ok.png");
    CHECK(rs_styles_add(ctx, S, &st) == RS_OK);
    rs_styles_free(ctx, S);
}

/* ---- mapping ------------------------------------------------------------ */

/* A 64 x 64 grey strip with a red stripe over columns [16, 24): u in
 * [0.25, 0.375), i.e. t in (1, 2] on an 8 m road (t = 4 - 8 u). */
static void stripe_image(uint8_t *px)
{
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++) {
            uint8_t *p = px + 4 * (y * 64 + x);
            int red = x >= 16 && x < 24;
            p[0] = red ? 230 : 100;
            p[1] = red ? 20 : 100;
            p[2] = red ? 20 : 100;
            p[3] = 255;
        }
}

static void test_curve(void)
{
    static uint8_t px[64 * 64 * 4];
    stripe_image(px);
    rs_surface_image si = { "stripe.png", { 64, 64, px } };
    /* a quarter circle of radius 20 around (2, 2), travelling clockwise on
     * the map (y down): left of travel is the outside of the bend */
    char text[4096];
    size_t n = (size_t)snprintf(text, sizeof text, "style s\n surface stripe.png\nend\nroad arc width 8 style=s\n");
    for (int k = 0; k <= 24; k++) {
        double a = k * (3.14159265358979 / 2) / 24;
        n += (size_t)snprintf(text + n, sizeof text - n, "%.6f %.6f\n", 2 + 20 * cos(a), 2 + 20 * sin(a));
    }
    snprintf(text + n, sizeof text - n, "end\n");
    rs_styles *S;
    CHECK(rs_styles_create(ctx, &S) == RS_OK);
    rs_roads *roads = parse(text, S);
    rs_dem *dem = plane(31, 31, 1, 0, 0);
    /* 0.125 m pixels: one image texel across and along (level 0) */
    rs_splatter *s = strip_splatter(dem, roads, S, &si, 8);
    uint32_t w, h;
    uint16_t *wt;
    uint8_t *img = splat_whole(s, &wt, &w, &h);
    long in = 0, in_red = 0, out = 0, out_red = 0;
    const double pix = 0.125;
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            if (wt[(size_t)y * w + x] != 65535) continue;
            rs_road_point rp;
            if (!rs_road_grid_query(rs_splatter_grid(s), (x + 0.5) * pix, (y + 0.5) * pix, 0, &rp)) continue;
            const uint8_t *p = img + 4 * ((size_t)y * w + x);
            int red = p[0] > 200 && p[1] < 50;
            if (rp.t > 1.2 && rp.t < 1.8) in++, in_red += red;
            if (rp.t < 0.7 || rp.t > 2.3) out++, out_red += red;
        }
    CHECKF(in > 1000 && in_red == in, "stripe pixels %ld, red %ld", in, in_red);
    CHECKF(out > 10000 && out_red == 0, "other pixels %ld, red %ld", out, out_red);
    free(img);
    free(wt);
    rs_splatter_free(ctx, s);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_styles_free(ctx, S);
}

/* ---- seamless repeat along s ------------------------------------------- */

static double wave(int y) { return 128 + 100 * sin(2 * 3.14159265358979 * 3 * (y + 0.5) / 64); }

static void test_wrap(void)
{
    static uint8_t px[16 * 64 * 4];
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 16; x++) {
            uint8_t *p = px + 4 * (y * 16 + x);
            p[0] = (uint8_t)(wave(y) + 0.5);
            p[1] = p[2] = 90;
            p[3] = 255;
        }
    rs_surface_image si = { "wave", { 16, 64, px } };
    /* along x at y = 8.0625 (a pixel centre row): s = x - 1; 6.4 m per image height */
    static const char text[] = "style w\n surface wave length 6.4\nend\nroad r width 4 style=w\n1 8.0625\n39 8.0625\nend\n";
    rs_styles *S;
    CHECK(rs_styles_create(ctx, &S) == RS_OK);
    rs_roads *roads = parse(text, S);
    rs_dem *dem = plane(41, 17, 1, 0, 0);
    rs_splatter *s = strip_splatter(dem, roads, S, &si, 8);
    uint32_t w, h;
    uint8_t *img = splat_whole(s, NULL, &w, &h);
    /* footprint: across 0.125 * 16 / 4 = 0.5, along 0.125 * 64 / 6.4 = 1.25
     * texels: log2(1.25) = 0.32 between levels 0 and 1 */
    uint32_t row = 64; /* pixel centre y = 8.0625 */
    int worst = 0, bad = 0, wraps = 0;
    double prev_v = -1;
    for (uint32_t x = 16; x < 38 * 8; x++) {
        int c = img[4 * ((size_t)row * w + x)], d = img[4 * ((size_t)row * w + x + 1)];
        int diff = abs(c - d);
        if (diff > worst) worst = diff;
        double v = ((x + 0.5) * 0.125 - 1) / 6.4;
        v -= floor(v);
        if (prev_v >= 0 && v < prev_v) wraps++;
        prev_v = v;
        /* level 0 reference (the mix with level 1 moves it by at most the
         * wave's change over 2 texels: 100 * 2 pi * 3 * 2 / 64 = 59) */
        double yy = v * 64 - 0.5, fy = floor(yy), f = yy - fy;
        int y0 = ((int)fy + 64) % 64, y1 = (y0 + 1) % 64;
        double ref = px[4 * (y0 * 16)] * (1 - f) + px[4 * (y1 * 16)] * f;
        if (fabs(ref - c) > 25) bad++;
    }
    /* the wave changes by at most 100 * 2 pi * 3 / 64 * 1.25 = 37 per pixel
     * along; a jump at the wrap would be up to 200 */
    CHECKF(worst <= 40, "largest step along the road %d", worst);
    CHECKF(wraps >= 5, "wraps %d", wraps);
    CHECKF(bad == 0, "%d pixels far from the wrapped sample", bad);
    free(img);
    rs_splatter_free(ctx, s);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_styles_free(ctx, S);
}

/* ---- mipmaps: a fine checkerboard from far ------------------------------ */

static void test_lod(void)
{
    static uint8_t px[256 * 256 * 4];
    for (int y = 0; y < 256; y++)
        for (int x = 0; x < 256; x++) {
            uint8_t *p = px + 4 * (y * 256 + x);
            p[0] = p[1] = p[2] = (uint8_t)(((x ^ y) & 1) ? 255 : 0);
            p[3] = 255;
        }
    rs_surface_image si = { "checker", { 256, 256, px } };
    static const char text[] = "style c\n surface checker\nend\nroad r width 8 style=c\n0 10\n40 13\nend\n";
    rs_styles *S;
    CHECK(rs_styles_create(ctx, &S) == RS_OK);
    rs_roads *roads = parse(text, S);
    rs_dem *dem = plane(41, 21, 1, 0, 0);
    for (uint32_t texels = 2; texels <= 64; texels *= 32) {
        /* 2: 16 texels per pixel (level 4); 64: half a texel (level 0) */
        rs_splatter *s = strip_splatter(dem, roads, S, &si, texels);
        uint32_t w, h;
        uint16_t *wt;
        uint8_t *img = splat_whole(s, &wt, &w, &h);
        double lo = 255, hi = 0;
        long n = 0;
        for (size_t i = 0; i < (size_t)w * h; i++)
            if (wt[i] == 65535) {
                double v = img[4 * i];
                lo = v < lo ? v : lo;
                hi = v > hi ? v : hi;
                n++;
            }
        if (texels == 2) CHECKF(n > 100 && lo >= 117 && hi <= 138, "coarse: %ld pixels in %g..%g", n, lo, hi);
        else CHECKF(n > 100 && lo <= 30 && hi >= 225, "fine: %ld pixels in %g..%g", n, lo, hi);
        free(img);
        free(wt);
        rs_splatter_free(ctx, s);
    }
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_styles_free(ctx, S);
}

/* ---- bad input ---------------------------------------------------------- */

static void test_bad_input(void)
{
    static uint8_t px[4 * 4 * 4];
    static const char text[] = "style c\n surface \"a.png\"\nend\nroad \"r 1\" width 8 style=c\n0 10\n40 13\nend\n";
    rs_styles *S;
    CHECK(rs_styles_create(ctx, &S) == RS_OK);
    rs_roads *roads = parse(text, S);
    rs_dem *dem = plane(41, 21, 1, 0, 0);
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 2;
    o.style.styles = S;
    rs_road_grid *g = NULL;
    CHECK(rs_road_grid_build(ctx, dem, roads, &o, &g) == RS_ERR_INVALID_ARG && !g);
    CHECKF(strstr(rs_ctx_message(ctx), "road 0 ('r 1'): style 'c': surface image 'a.png' was not given"), "%s",
           rs_ctx_message(ctx));
    rs_surface_image si[2] = { { "b.png", { 4, 4, px } }, { "a.png", { 0, 4, px } } };
    o.style.surface_images = si;
    o.style.surface_image_count = 2;
    CHECK(rs_road_grid_build(ctx, dem, roads, &o, &g) == RS_ERR_INVALID_ARG && !g);
    CHECKF(strstr(rs_ctx_message(ctx), "surface image 'a.png' is empty"), "%s", rs_ctx_message(ctx));
    si[1].image.width = 70000;
    CHECK(rs_road_grid_build(ctx, dem, roads, &o, &g) == RS_ERR_LIMIT && !g);
    CHECKF(strstr(rs_ctx_message(ctx), "surface image 'a.png' of 70000 x 4 pixels exceeds"), "%s", rs_ctx_message(ctx));
    si[1].image.width = 4;
    CHECK(rs_road_grid_build(ctx, dem, roads, &o, &g) == RS_OK && g);
    rs_road_grid_free(ctx, g);
    /* lighting options */
    o.style.surface_images = NULL;
    o.style.surface_image_count = 0;
    o.style.disable = 1;
    o.lighting.enable = 1;
    rs_splatter *s = NULL;
    o.lighting.sun_given = 1;
    o.lighting.sun_azimuth = 10;
    o.lighting.sun_altitude = 0;
    CHECK(rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_ERR_INVALID_ARG && !s &&
          strstr(rs_ctx_message(ctx), "sun altitude 0 must be in (0, 90]"));
    o.lighting.sun_altitude = 30;
    o.lighting.ambient = 1.5;
    CHECK(rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_ERR_INVALID_ARG && !s &&
          strstr(rs_ctx_message(ctx), "ambient 1.5"));
    o.lighting.ambient = 0;
    o.lighting.specular = -1;
    CHECK(rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_ERR_INVALID_ARG && !s &&
          strstr(rs_ctx_message(ctx), "specular -1"));
    o.lighting.specular = 0;
    o.lighting.normal.strength = -2;
    CHECK(rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_ERR_INVALID_ARG && !s &&
          strstr(rs_ctx_message(ctx), "strength -2"));
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_styles_free(ctx, S);
}

/* ---- windows and threads ------------------------------------------------ */

static int tiled_equal(const rs_splatter *s, const uint8_t *ref, uint32_t w, uint32_t h, uint32_t tw, uint32_t th,
                       uint32_t off)
{
    size_t stride = (size_t)w * 4 + 12;
    uint8_t *px = malloc(stride * h);
    memset(px, 0xA5, stride * h);
    int ok = 1;
    for (uint32_t y = 0; ok && y < h;) {
        uint32_t hh = y == 0 && off ? off : th;
        if (hh > h - y) hh = h - y;
        for (uint32_t x = 0; ok && x < w;) {
            uint32_t ww = x == 0 && off ? off : tw;
            if (ww > w - x) ww = w - x;
            ok = rs_splat_window(ctx, s, x, y, ww, hh, px + y * stride + (size_t)x * 4, stride, NULL, 0, NULL) == RS_OK;
            x += ww;
        }
        y += hh;
    }
    for (uint32_t y = 0; ok && y < h; y++) ok = memcmp(px + y * stride, ref + (size_t)y * w * 4, (size_t)w * 4) == 0;
    free(px);
    return ok;
}

static void test_windows(void)
{
    static uint8_t strip[32 * 96 * 4];
    for (size_t i = 0; i < sizeof strip; i++) strip[i] = (uint8_t)(i % 4 == 3 ? 200 + i % 56 : (i * 37 + (i * i) % 97));
    rs_surface_image si = { "s", { 32, 96, strip } };
    static const char text[] = "style s\n surface s length 7.3\n gradient #00000000 #40302080\n"
                               " line 0 0.2 #FFFFFF dash 2 1\nend\n"
                               "road a width 6 style=s\n3 4\n20 18\n41 30\nend\n"
                               "road b width 7 class=primary\n2 30\n44 6\nend\n";
    rs_styles *S;
    CHECK(rs_styles_create(ctx, &S) == RS_OK);
    rs_roads *roads = parse(text, S);
    enum { W = 23, H = 19 };
    float z[W * H];
    for (int i = 0; i < H; i++)
        for (int j = 0; j < W; j++) z[i * W + j] = (float)(20 * sin(j * 0.37) * cos(i * 0.29) + 0.5 * i);
    rs_dem *dem = NULL;
    CHECK(rs_dem_create(ctx, W, H, z, &dem) == RS_OK);
    rs_dem_frame fr = { 2.0, 0.5, 0, 0 };
    CHECK(rs_dem_set_frame(ctx, dem, &fr) == RS_OK);
    for (int mode = 0; mode < 4; mode++) {
        rs_splat_options o;
        memset(&o, 0, sizeof o);
        o.texels = 5;
        o.coverage.edges = mode & 1 ? RS_EDGES_ALPHAMAP : RS_EDGES_ANALYTIC;
        o.style.styles = S;
        o.style.surface_images = &si;
        o.style.surface_image_count = 1;
        if (mode & 2) {
            o.lighting.enable = 1;
            o.lighting.specular = 0.2;
            o.lighting.sun_given = 1;
            o.lighting.sun_azimuth = 200;
            o.lighting.sun_altitude = 35;
        }
        rs_splatter *s = NULL;
        CHECKF(rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_OK, "%s", rs_ctx_message(ctx));
        uint32_t w, h;
        uint8_t *ref = splat_whole(s, NULL, &w, &h);
        CHECKF(tiled_equal(s, ref, w, h, 1, 1, 0), "mode %d: 1 x 1 windows", mode);
        CHECKF(tiled_equal(s, ref, w, h, 7, 3, 2), "mode %d: 7 x 3 windows", mode);
        CHECKF(tiled_equal(s, ref, w, h, 13, 11, 5), "mode %d: 13 x 11 windows", mode);
        CHECKF(tiled_equal(s, ref, w, h, w, 4, 3), "mode %d: row bands", mode);
        for (uint32_t nt = 2; nt <= 3; nt++)
            CHECKF(bt_threads_equal(s, NULL, ref, w, h, 6, nt), "mode %d: %u threads", mode, nt);
        free(ref);
        rs_splatter_free(ctx, s);
    }
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_styles_free(ctx, S);
}

/* ---- the normal map picks up the strip ---------------------------------- */

static void test_normals(void)
{
    static uint8_t px[64 * 64 * 4];
    stripe_image(px);
    rs_surface_image si = { "stripe.png", { 64, 64, px } };
    static const char with[] = "style s\n surface stripe.png\nend\nroad r width 8 style=s\n0 10\n40 13\nend\n";
    static const char without[] = "road r width 8\n0 10\n40 13\nend\n";
    rs_dem *dem = plane(41, 21, 1, 0, 0);
    long tilted[2] = { 0, 0 };
    for (int k = 0; k < 2; k++) {
        rs_styles *S;
        CHECK(rs_styles_create(ctx, &S) == RS_OK);
        rs_roads *roads = parse(k ? with : without, S);
        rs_splat_options o;
        memset(&o, 0, sizeof o);
        o.texels = 8;
        o.style.styles = S;
        o.style.surface_images = &si;
        o.style.surface_image_count = 1;
        rs_splatter *s = NULL;
        CHECKF(rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_OK, "%s", rs_ctx_message(ctx));
        uint32_t w, h;
        rs_splatter_size(s, &w, &h);
        uint8_t *nm = malloc((size_t)w * h * 3);
        rs_normal_options no;
        memset(&no, 0, sizeof no);
        no.no_paint = 1;
        CHECK(rs_normal_window(ctx, s, 0, 0, w, h, nm, (size_t)w * 3, &no) == RS_OK);
        for (size_t i = 0; i < (size_t)w * h; i++) tilted[k] += nm[3 * i] != 128 || nm[3 * i + 1] != 128;
        free(nm);
        rs_splatter_free(ctx, s);
        rs_roads_free(ctx, roads);
        rs_styles_free(ctx, S);
    }
    CHECKF(tilted[0] == 0 && tilted[1] > 500, "tilted normals: plain road %ld, with the strip %ld", tilted[0],
           tilted[1]);
    rs_dem_free(ctx, dem);
}

/* ---- lighting ----------------------------------------------------------- */

static uint8_t *lit(rs_dem *dem, rs_roads *roads, int enable, double az, double alt, double spec, uint16_t **wt,
                    uint32_t *w, uint32_t *h)
{
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    o.markings.disable = 1;
    o.lighting.enable = enable;
    o.lighting.sun_given = 1;
    o.lighting.sun_azimuth = az;
    o.lighting.sun_altitude = alt;
    o.lighting.specular = spec;
    rs_splatter *s = NULL;
    CHECKF(rs_splatter_create(ctx, dem, roads, NULL, &o, &s) == RS_OK, "%s", rs_ctx_message(ctx));
    uint8_t *img = splat_whole(s, wt, w, h);
    rs_splatter_free(ctx, s);
    return img;
}

static void test_lighting(void)
{
    static const char text[] = "road r width 6\n0 20\n40 20\nend\n";
    rs_roads *roads = parse(text, NULL);
    /* planes rising west (facing east) and east (facing west), sun in the east */
    rs_dem *east = plane(41, 41, 1, -0.5, 0), *west = plane(41, 41, 1, 0.5, 0);
    uint32_t w, h, w2, h2;
    uint8_t *a = lit(east, roads, 1, 90, 45, 0, NULL, &w, &h), *b = lit(west, roads, 1, 90, 45, 0, NULL, &w2, &h2);
    /* f = 0.3 + 0.7 (N.L) / L.z: N = (+-0.5, 0, 1) / 1.118, L = (0.707, 0, 0.707) */
    double n = sqrt(1.25), fa = 0.3 + 0.7 * (0.5 + 1) / n, fb = 0.3 + 0.7 * (1 - 0.5) / n;
    double sa = 0, sb = 0;
    long cnt = 0;
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            /* the tints of the two planes are mirror images */
            const uint8_t *pa = a + 4 * ((size_t)y * w + x), *pb = b + 4 * ((size_t)y * w + (w - 1 - x));
            if (y > 60 && y < 100) continue; /* the road */
            if (pa[1] >= 250 || pb[1] < 20) continue;
            sa += pa[1], sb += pb[1], cnt++;
        }
    CHECKF(cnt > 10000 && sa > sb, "facing the sun %g, facing away %g over %ld pixels", sa, sb, cnt);
    CHECKF(fabs(sa / sb - fa / fb) < 0.03 * fa / fb, "brightness ratio %g, expected %g", sa / sb, fa / fb);
    free(a);
    free(b);
    /* flat ground: the factor is 1, the same bytes as without lighting */
    rs_dem *flat = plane(41, 41, 1, 0, 0);
    uint16_t *wt;
    uint8_t *c = lit(flat, roads, 0, 0, 0, 0, NULL, &w, &h), *d = lit(flat, roads, 1, 123, 17, 0, NULL, &w, &h);
    CHECK(memcmp(c, d, (size_t)w * h * 4) == 0);
    free(d);
    /* specular: the sun overhead adds 0.1 * 255 * R of white on the road */
    d = lit(flat, roads, 1, 0, 90, 0.1, &wt, &w, &h);
    long more = 0, road = 0, same = 0, terrain = 0;
    for (size_t i = 0; i < (size_t)w * h; i++) {
        if (wt[i] == 65535) road++, more += d[4 * i] >= c[4 * i] + 25 && d[4 * i] <= c[4 * i] + 26;
        if (wt[i] == 0) terrain++, same += d[4 * i] == c[4 * i];
    }
    CHECKF(road > 1000 && more == road && same == terrain, "specular: %ld of %ld road pixels, %ld of %ld terrain",
           more, road, same, terrain);
    free(c);
    free(d);
    free(wt);
    rs_dem_free(ctx, east);
    rs_dem_free(ctx, west);
    rs_dem_free(ctx, flat);
    rs_roads_free(ctx, roads);
}

/* ---- allocation failures ------------------------------------------------ */

typedef struct alloc_case {
    rs_dem *dem;
    rs_roads *roads;
    rs_styles *styles;
    const rs_surface_image *si;
    int lit;
} alloc_case;

static rs_result alloc_try(rs_ctx *c, void *user, int *wrong)
{
    const alloc_case *ac = user;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    o.style.styles = ac->styles;
    o.style.surface_images = ac->si;
    o.style.surface_image_count = 1;
    o.lighting.enable = ac->lit;
    rs_splatter *s = NULL;
    uint8_t px[13 * 9 * 4];
    rs_result r = rs_splatter_create(c, ac->dem, ac->roads, NULL, &o, &s);
    if (r && s) *wrong = 1;
    if (!r) r = rs_splat_window(c, s, 30, 50, 13, 9, px, 13 * 4, NULL, 0, NULL);
    rs_splatter_free(c, s);
    return r;
}

static void test_alloc_failures(void)
{
    static uint8_t px[64 * 64 * 4];
    stripe_image(px);
    rs_surface_image si = { "stripe.png", { 64, 64, px } };
    static const char text[] = "style s\n surface stripe.png\n line 0 0.2 #FFFFFF\nend\n"
                               "road r width 8 style=s\n0 10\n40 13\nend\n";
    alloc_case ac;
    CHECK(rs_styles_create(ctx, &ac.styles) == RS_OK);
    ac.roads = parse(text, ac.styles);
    ac.dem = plane(41, 21, 1, 0.1, 0);
    ac.si = &si;
    for (ac.lit = 0; ac.lit < 2; ac.lit++) {
        fail_sweep fs = fail_alloc_sweep(5000, alloc_try, &ac);
        CHECK_SWEEP(fs, 5);
    }
    rs_roads_free(ctx, ac.roads);
    rs_styles_free(ctx, ac.styles);
    rs_dem_free(ctx, ac.dem);
}

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_parse();
    test_curve();
    test_wrap();
    test_lod();
    test_bad_input();
    test_windows();
    test_normals();
    test_lighting();
    test_alloc_failures();
    rs_ctx_free(ctx);
    return th_finish("test_surfimg");
}
