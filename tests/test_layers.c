/* Layers (issue 30): rs_splat_layers_window's planes recompose to
 * rs_splat_window's colour within 1/255 (the formula in roadsplat.h), for
 * plain roads, styled roads (casings of one colour and of several, lines,
 * markings, fills, gradients, surface images, textures), alpha-map edges
 * and lit output; any window is the crop of the whole image's planes,
 * with and without a workspace; a workspace allocates nothing; the
 * coverage is the weight output, the normal plane rs_normal_window's, the
 * terrain plane the splat with no roads and the unstyled surface the splat
 * under one road covering the map (what the CLI's shader render baked
 * before the layers). */
#include "roadsplat.h"
#include "harness.h"
#include "scenes.h"
#include "scene_splat.h"
#include "fail_alloc.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static size_t allocs_made; /* the context's allocation calls */
static rs_ctx *ctx;

/* casings of one colour (the composite blends them) */
static const char styled_one[] =
    "style k\n casing 0.5 #606060\n line 0 0.2 #FFFFFF dash 2 5\n line 2.4 0.15 #FFFFFF\nend\n"
    "road a width 8 style=k\n1.5 9.3\n38.1 16.8\nend\n"
    "road b width 6 class=primary\n18.2 1.4\n25.9 38.5\nend\n"
    "road c width 4 class=residential\n2 33\n17 24\n37 36\nend\n"
    "mark arrow_right road=a s=14 t=-2\n"
    "mark word_bus road=b s=10 t=1.5 length=3 width=2\n";

/* casings of several colours (blended per pixel into the terrain), a
 * translucent fill, a gradient, a surface image under a translucent fill */
static const char styled_many[] =
    "style k\n casing 0.6 #A03020C0\n fill #40404080\n line 0 0.15 #FFFF00 dash 3 6\nend\n"
    "style g\n casing 0.3 #2050F0\n gradient #303030 #60606080\n line 1.5 0.2 #FFFFFFC0\nend\n"
    "style im\n surface checker\n fill #00000030\n line 0 0.3 #FFFFFF\nend\n"
    "road a width 7 style=k\n0.5 11.3\n39.1 14.8\nend\n"
    "road b width 6 style=g\n20.2 0.4\n23.9 39.5\nend\n"
    "road c width 5 style=im\n3 35\n18 22\n36 38\nend\n"
    "road d width 4 class=residential\n2 2\n12 30\nend\n"
    "mark arrow_left road=a s=12 t=-1.7\n"
    "mark word_bus road=b s=9 t=1.5 length=3 width=2\n";

/* a bridge record between two ground records over a road, both cased:
 * the bridge's casing lies over the road below (docs/network.md "Bridges
 * and layers"), in the paint with the lines */
static const char styled_deck[] =
    "style p\n casing 0.6 #B8B4AC\n line 2.4 0.15 #FFFFFF\n line -2.4 0.15 #FFFFFF\nend\n"
    "style m\n casing 0.4 #6060F0C0\n line 0 0.2 #FFFFFF dash 2 5\nend\n"
    "road a width 8 style=m\n0.5 20.3\n39.1 19.8\nend\n"
    "road r1 width 6 style=p\n20 0.5\n20.4 12\nend\n"
    "road b width 6 style=p bridge=yes layer=1\n20.4 12\n20.6 28\nend\n"
    "road r2 width 6 style=p\n20.6 28\n21 39.5\nend\n";

static uint8_t checker_px[32 * 32 * 4], road_px[16 * 16 * 4], terrain_px[8 * 8 * 4];

static void images(void)
{
    for (int y = 0; y < 32; y++)
        for (int x = 0; x < 32; x++) {
            uint8_t *p = checker_px + 4 * (y * 32 + x);
            int on = ((x / 8) + (y / 8)) & 1;
            p[0] = on ? 200 : 40;
            p[1] = on ? 120 : 60;
            p[2] = on ? 30 : 90;
            p[3] = (uint8_t)(x < 16 ? 255 : 128);
        }
    sc_rng r;
    sc_rng_seed(&r, 7);
    for (size_t i = 0; i < sizeof road_px; i++) road_px[i] = (uint8_t)(i % 4 == 3 ? 255 : sc_rng_unit(&r) * 255);
    for (size_t i = 0; i < sizeof terrain_px; i++)
        terrain_px[i] = (uint8_t)(i % 4 == 3 ? 255 : 60 + sc_rng_unit(&r) * 120);
}

typedef struct planes {
    uint8_t *terrain, *casing, *surface, *paint, *normal;
    uint16_t *coverage;
    uint32_t w, h;
} planes;

static int planes_alloc(planes *p, uint32_t w, uint32_t h)
{
    size_t n = (size_t)w * h;
    p->w = w;
    p->h = h;
    p->terrain = malloc(n * 4);
    p->casing = malloc(n * 4);
    p->surface = malloc(n * 4);
    p->paint = malloc(n * 4);
    p->normal = malloc(n * 3);
    p->coverage = malloc(n * 2);
    return p->terrain && p->casing && p->surface && p->paint && p->normal && p->coverage;
}

static void planes_free(planes *p)
{
    free(p->terrain);
    free(p->casing);
    free(p->surface);
    free(p->paint);
    free(p->normal);
    free(p->coverage);
}

static rs_splat_layers layers_of(const planes *p, int normal)
{
    rs_splat_layers L;
    memset(&L, 0, sizeof L);
    L.terrain = p->terrain;
    L.terrain_stride = (size_t)p->w * 4;
    L.casing = p->casing;
    L.casing_stride = (size_t)p->w * 4;
    L.surface = p->surface;
    L.surface_stride = (size_t)p->w * 4;
    L.coverage = p->coverage;
    L.coverage_stride = p->w;
    L.paint = p->paint;
    L.paint_stride = (size_t)p->w * 4;
    L.normal = normal ? p->normal : NULL;
    L.normal_stride = (size_t)p->w * 3;
    return L;
}

static uint8_t to_byte(double v) { return (uint8_t)(v >= 0 ? (v >= 255 ? 255 : v + 0.5) : 0); }

/* The recomposition of roadsplat.h, channel ch of pixel i, in 0..255. */
static double recompose(const planes *p, size_t i, int ch)
{
    double t = p->terrain[4 * i + ch], c = p->casing[4 * i + ch], ca = p->casing[4 * i + 3] / 255.0;
    double s = p->surface[4 * i + ch], pc = p->paint[4 * i + ch], pa = p->paint[4 * i + 3] / 255.0;
    double R = p->coverage[i] / 65535.0;
    double ground = t * (1 - ca) + c, road = s * (1 - pa) + pc;
    return ground * (1 - R) + road * R;
}

/* The lighting of roadsplat.h's rs_lighting_options on colour v with the
 * normal decoded from the normal plane (default sun, ambient 0.3). */
static uint8_t light(double v, const uint8_t *nb, double R, double specular)
{
    const double pi = 3.14159265358979323846, az = 315 * pi / 180, alt = 45 * pi / 180;
    double L[3] = { sin(az) * cos(alt), cos(az) * cos(alt), sin(alt) }, H[3] = { L[0], L[1], L[2] + 1 };
    double hl = sqrt(H[0] * H[0] + H[1] * H[1] + H[2] * H[2]), n[3], nl = 0;
    for (int k = 0; k < 3; k++) {
        n[k] = nb[k] / 255.0 * 2 - 1;
        nl += n[k] * n[k];
    }
    nl = sqrt(nl);
    double d = 0, hd = 0;
    for (int k = 0; k < 3; k++) {
        d += n[k] / nl * L[k];
        hd += n[k] / nl * H[k] / hl;
    }
    double f = 0.3 + 0.7 * (d > 0 ? d : 0) / L[2];
    double sp = specular > 0 && R > 0 && hd > 0 ? 255 * specular * R * pow(hd, 40) : 0;
    double x = v * f + sp + 0.5;
    return (uint8_t)(x >= 255 ? 255 : (x > 0 ? x : 0));
}

typedef struct scene_opts {
    const char *name, *text;
    rs_edge_mode edges;
    int plain, textures, lit;
} scene_opts;

static rs_splatter *make_splatter(const rs_dem *dem, const scene_opts *so, const char *text, int style_off,
                                  rs_styles **styles, rs_roads **roads)
{
    static rs_image road_tex = { 16, 16, road_px }, terrain_tex = { 8, 8, terrain_px };
    static rs_surface_image si = { "checker", { 32, 32, checker_px } };
    *styles = NULL;
    *roads = NULL;
    CHECK(rs_styles_create(ctx, styles) == RS_OK);
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.styles = *styles;
    CHECKF(rs_roads_parse_ex(ctx, text, strlen(text), &po, roads) == RS_OK, "%s", rs_ctx_message(ctx));
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 10;
    o.coverage.edges = so->edges;
    o.style.styles = *styles;
    o.style.surface_images = &si;
    o.style.surface_image_count = 1;
    o.style.disable = so->plain || style_off;
    o.markings.disable = so->plain || style_off;
    if (so->textures) {
        o.surface.road_texture = &road_tex;
        o.surface.terrain_texture = &terrain_tex;
        o.surface.texture_scale = 3.7;
    }
    o.lighting.enable = so->lit;
    o.lighting.specular = so->lit ? 0.4 : 0;
    rs_splatter *s = NULL;
    CHECKF(rs_splatter_create(ctx, dem, *roads, NULL, &o, &s) == RS_OK, "%s: %s", so->name, rs_ctx_message(ctx));
    return s;
}

static void free_scene(rs_splatter *s, rs_styles *st, rs_roads *r)
{
    rs_splatter_free(ctx, s);
    rs_roads_free(ctx, r);
    rs_styles_free(ctx, st);
}

/* Every plane of window (x, y, w, h) against the crop of the whole image's
 * planes. */
static int same_crop(const planes *full, const planes *win, uint32_t x, uint32_t y)
{
    for (uint32_t r = 0; r < win->h; r++) {
        size_t fi = (size_t)(y + r) * full->w + x, wi = (size_t)r * win->w;
        if (memcmp(full->terrain + 4 * fi, win->terrain + 4 * wi, (size_t)win->w * 4) ||
            memcmp(full->casing + 4 * fi, win->casing + 4 * wi, (size_t)win->w * 4) ||
            memcmp(full->surface + 4 * fi, win->surface + 4 * wi, (size_t)win->w * 4) ||
            memcmp(full->paint + 4 * fi, win->paint + 4 * wi, (size_t)win->w * 4) ||
            memcmp(full->normal + 3 * fi, win->normal + 3 * wi, (size_t)win->w * 3) ||
            memcmp(full->coverage + fi, win->coverage + wi, (size_t)win->w * 2))
            return 0;
    }
    return 1;
}

static void run_scene(const rs_dem *dem, const scene_opts *so)
{
    rs_styles *styles;
    rs_roads *roads;
    rs_splatter *s = make_splatter(dem, so, so->text, 0, &styles, &roads);
    if (!s) {
        free_scene(s, styles, roads);
        return;
    }
    uint32_t W, H;
    rs_splatter_size(s, &W, &H);
    size_t n = (size_t)W * H;
    planes full;
    uint8_t *ref = malloc(n * 4), *nref = malloc(n * 3);
    uint16_t *wref = malloc(n * 2);
    if (!planes_alloc(&full, W, H) || !ref || !wref || !nref) goto out;
    rs_splat_layers L = layers_of(&full, 1);
    CHECKF(rs_splat_layers_window(ctx, s, NULL, 0, 0, W, H, &L, NULL) == RS_OK, "%s: %s", so->name,
           rs_ctx_message(ctx));
    CHECK(rs_splat_window(ctx, s, 0, 0, W, H, ref, (size_t)W * 4, wref, W, NULL) == RS_OK);
    CHECK(rs_normal_window(ctx, s, 0, 0, W, H, nref, (size_t)W * 3, NULL) == RS_OK);
    CHECKF(!memcmp(full.coverage, wref, n * 2), "%s: the coverage plane is the weight output", so->name);
    CHECKF(!memcmp(full.normal, nref, n * 3), "%s: the normal plane is rs_normal_window's", so->name);
    /* recomposition */
    size_t exact = 0, casing_px = 0, paint_px = 0, part = 0;
    int worst = 0;
    for (size_t i = 0; i < n; i++) {
        casing_px += full.casing[4 * i + 3] != 0;
        paint_px += full.paint[4 * i + 3] != 0;
        part += full.coverage[i] != 0 && full.coverage[i] != 65535;
        int same = 1;
        for (int ch = 0; ch < 3; ch++) {
            double v = recompose(&full, i, ch);
            int got = so->lit ? light(v, full.normal + 3 * i, full.coverage[i] / 65535.0, 0.4) : to_byte(v);
            int d = abs(got - ref[4 * i + ch]);
            if (d > worst) worst = d;
            same &= d == 0;
        }
        exact += same;
    }
    /* lit: the normal plane is rounded to bytes, the lighting reads the
     * unrounded normals (2 levels of 255 at most here) */
    int bound = so->lit ? 3 : 1;
    CHECKF(worst <= bound, "%s: recomposition differs by %d levels (bound %d)", so->name, worst, bound);
    printf("  %s: %zu x %u px, %zu part-road, %zu casing, %zu paint; recomposed = output at %.2f%% of the pixels, "
           "worst %d\n", so->name, (size_t)W, H, part, casing_px, paint_px, 100.0 * exact / n, worst);
    if (!so->plain) CHECKF(paint_px > 0, "%s: the scene has paint", so->name);
    if (!so->plain && so->text == styled_many) CHECKF(casing_px > 0, "%s: the scene has casings", so->name);

    /* windows = crops, with a workspace (allocation-free without the
     * normal plane) and without */
    const uint32_t MW = 97;
    rs_splat_workspace *ws = NULL;
    CHECK(rs_splat_workspace_create(ctx, s, MW, &ws) == RS_OK);
    planes win;
    if (ws && planes_alloc(&win, MW, H)) {
        /* the first call with normals and layers reserves their scratch
         * in the workspace (rs_splat_workspace_bytes grows) */
        size_t bytes0 = rs_splat_workspace_bytes(ws);
        rs_splat_layers Ln;
        memset(&Ln, 0, sizeof Ln);
        Ln.normal = win.normal;
        Ln.normal_stride = 3;
        CHECK(rs_splat_layers_window(ctx, s, ws, W - 1, H - 1, 1, 1, &Ln, NULL) == RS_OK);
        CHECK(rs_splat_workspace_bytes(ws) > bytes0);
        if (so->lit) {
            /* and a lit window through the same workspace: nothing more */
            size_t before = allocs_made;
            CHECK(rs_splat_window_ws(ctx, s, ws, 0, 0, MW, H, win.terrain, (size_t)MW * 4, NULL, 0, NULL) == RS_OK);
            CHECK(!memcmp(win.terrain, ref, (size_t)MW * 4));
            CHECKF(allocs_made == before, "%s: %zu allocations in a lit window through a workspace", so->name,
                   allocs_made - before);
        }
        sc_rng rng;
        sc_rng_seed(&rng, 31);
        size_t same = 0, allocs = 0, tries = 0;
        for (int k = 0; k < 24; k++) {
            uint32_t w = k == 0 ? MW : k == 1 ? 1 : 1 + (uint32_t)(sc_rng_unit(&rng) * MW);
            uint32_t h = k == 0 ? H : k == 2 ? 1 : 1 + (uint32_t)(sc_rng_unit(&rng) * H);
            uint32_t x = (uint32_t)(sc_rng_unit(&rng) * (W - w + 1)) | 1, y = (uint32_t)(sc_rng_unit(&rng) * (H - h + 1));
            if (x + w > W) x = W - w;
            if (k == 3) y = H - h; /* the last rows, a partial DEM-cell row */
            if (k == 4) y = H - 1, h = 1;
            win.w = w;
            win.h = h;
            rs_splat_layers Lw = layers_of(&win, 1);
            size_t before = allocs_made;
            rs_result r = rs_splat_layers_window(ctx, s, k & 1 ? ws : NULL, x, y, w, h, &Lw, NULL);
            if (k & 1) allocs += allocs_made - before;
            if (r != RS_OK) continue;
            tries++;
            same += same_crop(&full, &win, x, y);
        }
        CHECKF(tries == 24 && same == tries, "%s: %zu of %zu windows are crops of the whole image's layers", so->name,
               same, tries);
        CHECKF(allocs == 0, "%s: %zu allocations in 12 windows of all six planes through a workspace", so->name,
               allocs);
        /* misuse */
        rs_splat_layers none;
        memset(&none, 0, sizeof none);
        CHECK(rs_splat_layers_window(ctx, s, ws, 0, 0, 1, 1, &none, NULL) == RS_ERR_INVALID_ARG);
        win.w = MW + 1;
        rs_splat_layers Lb = layers_of(&win, 0);
        CHECK(rs_splat_layers_window(ctx, s, ws, 0, 0, MW + 1, 1, &Lb, NULL) == RS_ERR_INVALID_ARG);
        Lb.terrain_stride = 4 * MW;
        CHECK(rs_splat_layers_window(ctx, s, NULL, 0, 0, MW + 1, 1, &Lb, NULL) == RS_ERR_BUFFER_TOO_SMALL);
        CHECK(rs_splat_layers_window(ctx, s, NULL, W, 0, 1, 1, &Lb, NULL) == RS_ERR_INVALID_ARG);
        win.w = MW;
        planes_free(&win);
    }
    rs_splat_workspace_free(ctx, ws);

    /* what the CLI's shader render baked before: the terrain plane is the
     * splat with no roads; the unstyled surface plane the splat under one
     * road wider than the map, styles off (unlit, analytic edges) */
    if (!so->lit && so->edges == RS_EDGES_ANALYTIC) {
        rs_splat_layers Lu;
        memset(&Lu, 0, sizeof Lu);
        Lu.surface = full.surface;
        Lu.surface_stride = (size_t)W * 4;
        Lu.surface_unstyled = 1;
        CHECK(rs_splat_layers_window(ctx, s, NULL, 0, 0, W, H, &Lu, NULL) == RS_OK);
        static const char *const fake[2] = { "", "road all width 100\n-30 20\n70 20\nend\n" };
        const uint8_t *plane[2] = { full.terrain, full.surface };
        for (int f = 0; f < 2; f++) {
            rs_styles *st2;
            rs_roads *r2;
            rs_splatter *s2 = make_splatter(dem, so, fake[f], 1, &st2, &r2);
            CHECK(s2 && rs_splat_window(ctx, s2, 0, 0, W, H, ref, (size_t)W * 4, NULL, 0, NULL) == RS_OK);
            CHECKF(!memcmp(plane[f], ref, n * 4), "%s: the %s plane is the splat %s", so->name,
                   f ? "unstyled surface" : "terrain", f ? "under a road covering the map" : "with no roads");
            free_scene(s2, st2, r2);
        }
    }
out:
    planes_free(&full);
    free(ref);
    free(wref);
    free(nref);
    free_scene(s, styles, roads);
}

int main(void)
{
    rs_allocator al = count_alloc_hook(&allocs_made);
    if (rs_ctx_create(&al, NULL, &ctx) != RS_OK) return 1;
    images();
    rs_dem *dem = ss_fractal_dem(ctx, 21, 21, 5, 2.0, 0.05);
    CHECK(dem != NULL);
    const scene_opts scenes[] = {
        { "plain", styled_one, RS_EDGES_ANALYTIC, 1, 0, 0 },
        { "styled, one casing colour", styled_one, RS_EDGES_ANALYTIC, 0, 0, 0 },
        { "styled, several casing colours, fills, image, textures", styled_many, RS_EDGES_ANALYTIC, 0, 1, 0 },
        { "alpha-map edges, styled", styled_many, RS_EDGES_ALPHAMAP, 0, 0, 0 },
        { "lit, styled", styled_many, RS_EDGES_ANALYTIC, 0, 1, 1 },
        { "lit, alpha-map edges", styled_one, RS_EDGES_ALPHAMAP, 0, 0, 1 },
        { "a bridge's casing over the road below", styled_deck, RS_EDGES_ANALYTIC, 0, 0, 0 },
        { "a bridge's casing over the road below, alpha-map edges", styled_deck, RS_EDGES_ALPHAMAP, 0, 0, 0 },
    };
    for (size_t k = 0; dem && k < sizeof scenes / sizeof *scenes; k++) run_scene(dem, &scenes[k]);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    return th_finish("test_layers");
}
