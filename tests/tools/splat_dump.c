/* splat_dump OUTDIR: renders a fixed list of scenes and option sets (city
 * scene, 1025^2 fractal, small synthetic DEMs, nodata holes, textures,
 * jitter, dilate, hard edge, analytic edges, odd texel counts, steep and
 * negative z-scales) and writes each RGBA image and road weight raw to
 * OUTDIR/NAME.rgba and OUTDIR/NAME.w. Built against two versions of the
 * library, `cmp` of the two folders checks a change for byte identity
 * (docs/design.md, "Kernel speed"). */
#include "roadsplat.h"
#include "scenes.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *outdir;
static rs_ctx *ctx;
static rs_image tex_a, tex_b;

static int dump(const char *name, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o)
{
    uint32_t w, h;
    rs_splatter *s = NULL;
    if (rs_splatter_create(ctx, dem, roads, NULL, o, &s)) {
        fprintf(stderr, "splat_dump %s: %s\n", name, rs_ctx_message(ctx));
        return -1;
    }
    rs_splatter_size(s, &w, &h);
    size_t n = (size_t)w * h;
    uint8_t *rgba = malloc(n * 4);
    uint16_t *wt = malloc(n * 2);
    if (!rgba || !wt || rs_splat_window(ctx, s, 0, 0, w, h, rgba, (size_t)w * 4, wt, w, NULL)) return -1;
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.rgba", outdir, name);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(rgba, 4, n, f) != n || fclose(f)) return -1;
    snprintf(path, sizeof path, "%s/%s.w", outdir, name);
    f = fopen(path, "wb");
    if (!f || fwrite(wt, 2, n, f) != n || fclose(f)) return -1;
    free(rgba);
    free(wt);
    rs_splatter_free(ctx, s);
    printf("%s %ux%u\n", name, w, h);
    return 0;
}

static void make_texture(rs_image *img, uint32_t w, uint32_t h, uint32_t mul)
{
    uint8_t *p = malloc((size_t)w * h * 4);
    for (size_t i = 0; i < (size_t)w * h * 4; i++) p[i] = (uint8_t)((i * mul) >> 24);
    img->width = w;
    img->height = h;
    img->rgba = p;
}

/* The option groups on one DEM and road set. */
static int groups(const char *scene, const rs_dem *dem, const rs_roads *roads, unsigned T)
{
    char name[128];
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = T;
    static const rs_colour_stop ramp3[3] = { { -50, { 10, 60, 20, 255 } }, { 40, { 200, 180, 90, 255 } },
                                             { 300, { 250, 250, 250, 255 } } };
    rs_colour_stop ramp12[12];
    for (int k = 0; k < 12; k++) {
        ramp12[k].height = -20 + 17.5 * k + (k & 1) * 0.37;
        ramp12[k].colour = (rs_colour){ (uint8_t)(20 * k + 7), (uint8_t)(250 - 19 * k), (uint8_t)(90 + 13 * k), 255 };
    }
    for (int v = 0; v < 18; v++) {
        static const char *what[] = { "default", "tex_terrain", "tex_road", "tex_both", "jitter", "dilate",
                                      "hard", "analytic", "analytic_tex", "texscale", "T3", "T1",
                                      "relative", "relative_range", "ramp3", "ramp12", "lit", "T2_ramp8" };
        rs_splat_options q = o;
        if (v == 1 || v == 3 || v == 8) q.surface.terrain_texture = &tex_a;
        if (v == 2 || v == 3 || v == 8) q.surface.road_texture = &tex_b;
        if (v == 4) { q.coverage.jitter = 1; q.coverage.jitter_seed = 3; }
        if (v == 5) q.grid.buffer = RS_BUFFER_DILATE;
        if (v == 6) q.coverage.hard_edge = 1;
        if (v == 7 || v == 8) q.coverage.edges = RS_EDGES_ANALYTIC;
        if (v == 9) { q.surface.terrain_texture = &tex_b; q.surface.road_texture = &tex_a; q.surface.texture_scale = 3.7; }
        if (v == 10) q.texels = 3;
        if (v == 11) q.texels = 1;
        /* the terrain tints (each a path of lib/splat/surface.c) */
        if (v == 12) q.surface.tint = RS_TINT_RELATIVE;
        if (v == 13) { q.surface.tint = RS_TINT_RELATIVE; q.surface.height_min = -3; q.surface.height_max = 41.5; }
        if (v == 14) { q.surface.ramp = ramp3; q.surface.ramp_count = 3; q.texels = 1; }
        if (v == 15) { q.surface.ramp = ramp12; q.surface.ramp_count = 12; }
        if (v == 16) q.lighting.enable = 1;
        if (v == 17) { q.surface.ramp = ramp12; q.surface.ramp_count = 8; q.texels = 2; }
        snprintf(name, sizeof name, "%s_%s", scene, what[v]);
        if (dump(name, dem, roads, &q)) return -1;
    }
    return 0;
}

static rs_roads *scene_roads(const sc_scene *sc)
{
    rs_roads *r = NULL;
    if (rs_roads_create(ctx, &r)) return NULL;
    for (size_t i = 0; i < sc->nroads; i++)
        if (rs_roads_add(ctx, r, NULL, sc->roads[i].width, sc->roads[i].xy, sc->roads[i].n)) return NULL;
    return r;
}

/* The city styled: every road's `style` attribute STYLE, the styles from
 * TEXT (casings of one colour go through the composite, an opaque fill of
 * one colour through the overlays' whole-road shortcut); and the classes
 * (the default class styles: casings of several colours). */
static int styled(const char *name, const rs_dem *dem, const sc_scene *sc, const char *text, unsigned T)
{
    rs_roads *r = scene_roads(sc);
    rs_styles *st = NULL;
    if (!r) return -1;
    for (size_t i = 0; i < sc->nroads; i++)
        if (text ? rs_roads_set_attr(ctx, r, i, "style", "s") : rs_roads_set_attr(ctx, r, i, "class", sc_city_class(sc->roads[i].width)))
            return -1;
    if (text && rs_styles_parse(ctx, text, strlen(text), &st)) return -1;
    rs_splat_options o = { .texels = T };
    o.style.styles = st;
    int rc = dump(name, dem, r, &o);
    rs_styles_free(ctx, st);
    rs_roads_free(ctx, r);
    return rc;
}

int main(int argc, char **argv)
{
    if (argc != 2) { fprintf(stderr, "usage: splat_dump OUTDIR\n"); return 2; }
    outdir = argv[1];
    if (rs_ctx_create(NULL, NULL, &ctx)) return 1;
    make_texture(&tex_a, 256, 256, 2654435761u);
    make_texture(&tex_b, 37, 53, 2246822519u);

    /* city scene: z-scales 0.01 (the benches'), 1 (steep), -0.05 */
    sc_scene sc;
    if (sc_city_default(&sc, 1)) return 1;
    rs_roads *roads = scene_roads(&sc);
    const double zs[] = { 0.01, 1, -0.05 };
    for (int i = 0; i < 3; i++) {
        rs_dem *dem;
        rs_dem_frame fr = { sc.cell_size, zs[i], 0, 0 };
        if (!roads || rs_dem_create(ctx, sc.w, sc.h, sc.z, &dem) || rs_dem_set_frame(ctx, dem, &fr)) return 1;
        char name[32];
        snprintf(name, sizeof name, "city%d", i);
        if (i == 0 ? groups(name, dem, roads, 4) : dump(name, dem, roads, &(rs_splat_options){ .texels = 4 })) return 1;
        if (i == 0 &&
            (styled("city_casing", dem, &sc,
                    "style s\n fill #383838\n casing 0.5 #A0A0A0\n line 0 0.15 #FFFFFF dash 6 12\nend\n", 4) ||
             styled("city_casing_T3", dem, &sc, "style s\n fill #38383880\n casing 0.7 #A0A0A0C0\nend\n", 3) ||
             styled("city_classes", dem, &sc, NULL, 4)))
            return 1;
        rs_dem_free(ctx, dem);
    }
    /* nodata holes in the city DEM */
    {
        float *z = malloc(sizeof(float) * sc.w * sc.h);
        memcpy(z, sc.z, sizeof(float) * sc.w * sc.h);
        for (uint32_t y = 0; y < sc.h; y++)
            for (uint32_t x = 0; x < sc.w; x++)
                if ((x - 40) * (x - 40) + (y - 30) * (y - 30) < 60 || (x * 7 + y * 13) % 97 == 0 || x == sc.w - 1)
                    z[(size_t)y * sc.w + x] = NAN;
        rs_dem *dem;
        rs_dem_frame fr = { sc.cell_size, 0.01, 0, 0 };
        if (rs_dem_create(ctx, sc.w, sc.h, z, &dem) || rs_dem_set_frame(ctx, dem, &fr)) return 1;
        if (groups("nodata", dem, roads, 4)) return 1;
        rs_dem_free(ctx, dem);
        free(z);
    }
    rs_roads_free(ctx, roads);
    sc_scene_free(&sc);

    /* small synthetic DEMs: flat, checker, ridge, spike (gradient zero in x or y, ties) */
    for (int k = 0; k < 5; k++) {
        const uint32_t W = 41, H = 37;
        float z[41 * 37];
        if (k == 0) sc_dem_constant(z, W, H, 17);
        if (k == 1) sc_dem_checker(z, W, H, 3);
        if (k == 2) sc_dem_ridge(z, W, H, 0.0, 4, 30);
        if (k == 3) sc_dem_ridge(z, W, H, 0.7853981633974483, 5, 30);
        if (k == 4) sc_dem_spike(z, W, H, 10, 90, 18, 20);
        const double zk[] = { 1, 0.01, 37.5 };
        for (int j = 0; j < 3; j++) {
            rs_dem *dem;
            rs_dem_frame fr = { 1.0, zk[j], 0, 0 };
            rs_roads *r = NULL;
            double xy[4] = { 3.3, 2.1, 35.7, 30.2 };
            if (rs_dem_create(ctx, W, H, z, &dem) || rs_dem_set_frame(ctx, dem, &fr) || rs_roads_create(ctx, &r) ||
                rs_roads_add(ctx, r, NULL, 3.0, xy, 2))
                return 1;
            char name[32];
            snprintf(name, sizeof name, "syn%d_%d", k, j);
            if (dump(name, dem, r, &(rs_splat_options){ .texels = 5 })) return 1;
            /* small windows at 1 and 3 texels: rows narrower than a vector */
            snprintf(name, sizeof name, "syn%d_%d_T1", k, j);
            if (dump(name, dem, r, &(rs_splat_options){ .texels = 1 })) return 1;
            snprintf(name, sizeof name, "syn%d_%d_T3", k, j);
            if (dump(name, dem, r, &(rs_splat_options){ .texels = 3, .surface.tint = RS_TINT_RELATIVE })) return 1;
            rs_roads_free(ctx, r);
            rs_dem_free(ctx, dem);
        }
    }

    /* the 1025^2 fractal of tests/bench/sparse.c, one short road */
    {
        const uint32_t W = 1025;
        float *z = malloc(sizeof(float) * W * W);
        sc_dem_fractal(z, W, W, 5, 0.5);
        rs_dem *dem;
        rs_dem_frame fr = { 0, 0.01, 0, 0 };
        rs_roads *r = NULL;
        double xy[4] = { 500, 500, 550, 518.5 };
        if (rs_dem_create(ctx, W, W, z, &dem) || rs_dem_set_frame(ctx, dem, &fr) || rs_roads_create(ctx, &r) ||
            rs_roads_add(ctx, r, NULL, 6, xy, 2))
            return 1;
        rs_splat_options o = { .texels = 4 };
        if (dump("fractal", dem, r, &o)) return 1;
        o.surface.terrain_texture = &tex_a;
        if (dump("fractal_tex", dem, r, &o)) return 1;
        rs_dem_frame f2 = { 0, 0.5, 0, 0 };
        rs_splat_options o2 = { .texels = 2 };
        if (rs_dem_set_frame(ctx, dem, &f2) || dump("fractal_steep", dem, r, &o2)) return 1;
        rs_roads_free(ctx, r);
        rs_dem_free(ctx, dem);
        free(z);
    }
    free((void *)tex_a.rgba);
    free((void *)tex_b.rgba);
    rs_ctx_free(ctx);
    return 0;
}
