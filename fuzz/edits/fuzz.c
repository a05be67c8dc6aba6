/* libFuzzer target: road edits and rs_road_grid_update, checked against a
 * fresh build (issue 30). Input: one flags byte, road text up to the first
 * NUL byte, then edits of 6 bytes each (at most 6): remove, replace (moved,
 * new width), set_attr (class, lanes, oneway, layer), set_point_attr (a zebra on
 * or off), add a road, rs_styles_replace. After every edit that succeeds:
 *  - the updated grid splats to the same bytes (colour and weight) as a
 *    grid built anew from the edited roads;
 *  - every pixel that differs from the splat before the edit lies in a
 *    dirty rectangle, and the rectangles lie in the image, sorted, not
 *    overlapping;
 *  - where rs_road_grid_rect_has_roads says 0, the pixels equal the
 *    road-free render;
 *  - windows (odd offsets, a one-pixel row, the last rows) equal the crops
 *    of the whole image;
 *  - the network the updated grid keeps for the next update (updated in
 *    place, lib/scene/network.c) equals one built anew.
 * Flags bit 7: the edits two at a time (one update for both: patches of
 * their own when far apart); bit 5: the roads copied at the first update
 * (rs_roads_copy), built whole from the copy, and the last grid rebased
 * onto that (rs_road_grid_rebase: the same bytes as a fresh build, no
 * dirty rectangle); bit 3: rs_limits.max_patches 2 (whole builds between).
 * A small DEM (16 x 12 samples of 5 m) at 1 to 4 texels, or (flags bit 6)
 * 64 x 48 samples at 1 or 2 texels, where an edit changes a small part of
 * the map and the update patches it; analytic or alpha-map edges, class
 * styles with automatic markings. Findings (abort):
 * any of those broken, an unknown result code, or a sanitizer report. */
#include "roadsplat.h"
#include "grid_edit.h" /* (rs__grid_track_net_check: the network an update keeps, against a build) */

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define REQUIRE(c) do { if (!(c)) abort(); } while (0)
#define DW 16
#define DH 12
#define BIG_W 64 /* flags bit 6: a map of 315 x 235 m, where an edit's area is a small part (patches) */
#define BIG_H 48
#define MAX_EDITS 6

typedef struct image {
    uint32_t w, h;
    uint8_t *rgba;
    uint16_t *wt;
} image;

static void image_free(image *im)
{
    free(im->rgba);
    free(im->wt);
    memset(im, 0, sizeof *im);
}

/* The splat of a grid, or -1 (a limit or an allocation: not a finding). */
static int render(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *g, const rs_splat_options *o, image *im)
{
    rs_splatter *s = NULL;
    memset(im, 0, sizeof *im);
    rs_result r = rs_splatter_create(ctx, dem, NULL, g, o, &s);
    if (r == RS_OK) {
        rs_splatter_size(s, &im->w, &im->h);
        im->rgba = malloc((size_t)im->w * im->h * 4);
        im->wt = malloc((size_t)im->w * im->h * 2);
        r = im->rgba && im->wt ? rs_splat_window(ctx, s, 0, 0, im->w, im->h, im->rgba, (size_t)im->w * 4, im->wt,
                                                 im->w, NULL)
                               : RS_ERR_NOMEM;
    }
    /* windows (odd offsets and sizes, a one-pixel row, the last rows) are
     * crops of the whole image (issue 25) */
    for (int k = 0; r == RS_OK && k < 3; k++) {
        uint32_t x0 = k == 0 ? im->w / 3 : k == 1 ? 1 : 0, y0 = k == 0 ? im->h / 4 : k == 1 ? im->h / 2 : im->h - 3;
        uint32_t ww = k == 0 ? im->w / 2 + 1 : k == 1 ? im->w - 2 : im->w, hh = k == 1 ? 1 : 3;
        if (k == 0) hh = im->h / 2 + 1;
        if (!ww || !hh || x0 + ww > im->w || y0 + hh > im->h || im->h < 3) continue;
        uint8_t *win = malloc((size_t)ww * hh * 4);
        uint16_t *wwt = malloc((size_t)ww * hh * 2);
        REQUIRE(win && wwt);
        if (rs_splat_window(ctx, s, x0, y0, ww, hh, win, (size_t)ww * 4, wwt, ww, NULL) == RS_OK)
            for (uint32_t y = 0; y < hh; y++) {
                size_t i = (size_t)(y0 + y) * im->w + x0;
                REQUIRE(memcmp(win + (size_t)y * ww * 4, im->rgba + 4 * i, (size_t)ww * 4) == 0);
                REQUIRE(memcmp(wwt + (size_t)y * ww, im->wt + i, (size_t)ww * 2) == 0);
            }
        free(win);
        free(wwt);
    }
    rs_splatter_free(ctx, s);
    REQUIRE(rs_strerror(r) != NULL);
    if (r) image_free(im);
    return r ? -1 : 0;
}

static int differs(const image *a, const image *b, size_t p)
{
    return memcmp(a->rgba + 4 * p, b->rgba + 4 * p, 4) != 0 || a->wt[p] != b->wt[p];
}

/* The update's promises against the splats before (a), after (c, from a
 * fresh build) and without roads (t). */
static void check(const rs_road_grid *g1, const image *a, const image *b, const image *c, const image *t)
{
    REQUIRE(b->w == c->w && b->h == c->h && a->w == c->w && a->h == c->h);
    size_t n = (size_t)a->w * a->h;
    REQUIRE(memcmp(b->rgba, c->rgba, n * 4) == 0 && memcmp(b->wt, c->wt, n * 2) == 0);
    size_t nr = rs_road_grid_dirty(g1, NULL, 0);
    rs_pixel_rect *R = malloc((nr ? nr : 1) * sizeof *R);
    uint8_t *mask = calloc(n, 1);
    REQUIRE(R && mask);
    REQUIRE(rs_road_grid_dirty(g1, R, nr) == nr);
    for (size_t k = 0; k < nr; k++) {
        REQUIRE(R[k].x0 < R[k].x1 && R[k].y0 < R[k].y1 && R[k].x1 <= a->w && R[k].y1 <= a->h);
        if (k) REQUIRE(R[k].y0 > R[k - 1].y0 || (R[k].y0 == R[k - 1].y0 && R[k].x0 > R[k - 1].x0));
        for (uint32_t y = R[k].y0; y < R[k].y1; y++)
            for (uint32_t x = R[k].x0; x < R[k].x1; x++) {
                REQUIRE(!mask[(size_t)y * a->w + x]);
                mask[(size_t)y * a->w + x] = 1;
            }
    }
    for (size_t p = 0; p < n; p++)
        if (differs(a, c, p)) REQUIRE(mask[p]);
    for (uint32_t ty = 0; ty < c->h; ty += 8)
        for (uint32_t tx = 0; tx < c->w; tx += 8) {
            uint32_t x1 = tx + 8 < c->w ? tx + 8 : c->w, y1 = ty + 8 < c->h ? ty + 8 : c->h;
            if (rs_road_grid_rect_has_roads(g1, tx, ty, x1, y1)) continue;
            for (uint32_t y = ty; y < y1; y++)
                for (uint32_t x = tx; x < x1; x++) REQUIRE(!differs(c, t, (size_t)y * c->w + x));
        }
    free(R);
    free(mask);
}

static const char *const classes[] = { "primary", "secondary", "residential", "service", "footway", "tertiary" };

/* One edit from 6 bytes; RS_OK when the roads (or styles) changed. */
static rs_result edit(rs_ctx *ctx, rs_roads *roads, rs_styles *styles, const uint8_t *e)
{
    size_t n = rs_roads_count(roads), i = n ? e[1] % n : 0;
    switch (e[0] % 6) {
    case 0:
        return n ? rs_roads_remove(ctx, roads, i) : RS_ERR_INVALID_ARG;
    case 1: { /* moved by (-16..15.75 m), width 0.25..16 m */
        const double *p;
        size_t np;
        if (!n || rs_roads_get(roads, i, NULL, NULL, &p, &np)) return RS_ERR_INVALID_ARG;
        double *q = malloc(2 * np * sizeof *q);
        REQUIRE(q);
        for (size_t k = 0; k < np; k++)
            q[2 * k] = p[2 * k] + ((int)e[2] - 128) / 8.0, q[2 * k + 1] = p[2 * k + 1] + ((int)e[3] - 128) / 8.0;
        rs_result r = rs_roads_replace(ctx, roads, i, NULL, 0.25 + e[4] / 16.0, q, np);
        free(q);
        return r;
    }
    case 2: {
        char v[8];
        if (!n) return RS_ERR_INVALID_ARG;
        if (e[2] % 3 == 0) return rs_roads_set_attr(ctx, roads, i, "class", classes[e[3] % 6]);
        if (e[2] % 3 == 1) {
            snprintf(v, sizeof v, "%d", 1 + e[3] % 5);
            return rs_roads_set_attr(ctx, roads, i, "lanes", v);
        }
        if (e[3] & 2) { /* a level: layer -1, 0 or 1 (docs/network.md "Bridges and layers") */
            snprintf(v, sizeof v, "%d", (e[3] >> 2) % 3 - 1);
            return rs_roads_set_attr(ctx, roads, i, "layer", v);
        }
        return rs_roads_set_attr(ctx, roads, i, "oneway", e[3] & 1 ? "yes" : "no");
    }
    case 3: {
        const double *p;
        size_t np;
        if (!n || rs_roads_get(roads, i, NULL, NULL, &p, &np)) return RS_ERR_INVALID_ARG;
        return rs_roads_set_point_attr(ctx, roads, i, e[2] % np, "crossing", e[3] & 1 ? "zebra" : NULL);
    }
    case 4: { /* a road of 2 or 3 points in the map (75 x 55 m) */
        double xy[6];
        for (int k = 0; k < 3; k++) xy[2 * k] = (e[1 + k] % 80) - 2.5, xy[2 * k + 1] = ((e[1 + k] >> 4) * 61 + e[4]) % 60;
        rs_result r = rs_roads_add(ctx, roads, NULL, 1 + e[5] % 12, xy, 2 + (e[5] >> 7));
        if (r == RS_OK && (e[4] & 1)) r = rs_roads_set_attr(ctx, roads, n, "class", classes[e[5] % 6]);
        return r;
    }
    default: { /* redefine the style `s` (roads may name it: style=s) */
        char text[160];
        int len = snprintf(text, sizeof text, "style s\nfill #%02x4030\ncasing %.2f #303030\nline 0 %.2f #ffffff%s\nend\n",
                           e[2], e[3] / 128.0, 0.05 + e[4] / 256.0, e[5] & 1 ? " dash 3 3" : "");
        rs_styles *one = NULL;
        if (rs_styles_parse(ctx, text, (size_t)len, &one)) return RS_ERR_INVALID_ARG;
        rs_result r = rs_styles_count(one) ? rs_styles_replace(ctx, styles, rs_styles_get(one, 0)) : RS_ERR_INVALID_ARG;
        rs_styles_free(ctx, one);
        return r;
    }
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 2) return 0;
    const uint8_t flags = data[0];
    const uint8_t *text = data + 1, *end = memchr(text, 0, size - 1);
    size_t tlen = end ? (size_t)(end - text) : size - 1;
    const uint8_t *ops = end ? end + 1 : data + size;
    size_t nops = (size_t)(data + size - ops) / 6;
    if (nops > MAX_EDITS) nops = MAX_EDITS;

    rs_ctx *ctx = NULL;
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_points = 4096;        /* small and quick: a limit is not a finding */
    lim.max_field_work = 1 << 22;
    lim.max_line_length = 4096;
    if (flags & 8) lim.max_patches = 2;
    REQUIRE(rs_ctx_create(NULL, &lim, &ctx) == RS_OK);
    float z[BIG_W * BIG_H];
    const int big = (flags & 64) != 0, dw = big ? BIG_W : DW, dh = big ? BIG_H : DH;
    for (int k = 0; k < dw * dh; k++) z[k] = (float)((k * 37 % 23) + (k / dw) * 2);
    rs_dem *dem = NULL;
    rs_dem_frame fr = { 5, 0.05, 0, 0 };
    rs_roads *roads = NULL, *none = NULL;
    rs_styles *styles = NULL;
    rs_road_grid *g0 = NULL, *gt = NULL, *since = NULL;
    rs_roads *snap = NULL;
    int restyled = 0, lag = 0;
    image a = { 0 }, t = { 0 };
    REQUIRE(rs_dem_create(ctx, (uint32_t)dw, (uint32_t)dh, z, &dem) == RS_OK && rs_dem_set_frame(ctx, dem, &fr) == RS_OK);
    static const char base_style[] = "style s\nfill #a04030\nend\n";
    REQUIRE(rs_styles_parse(ctx, base_style, sizeof base_style - 1, &styles) == RS_OK);
    REQUIRE(rs_roads_create(ctx, &none) == RS_OK);
    if (rs_roads_parse(ctx, (const char *)text, tlen, &roads) != RS_OK) goto done;

    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = big ? 1 + (flags & 1) : 1 + (flags & 3);
    o.coverage.edges = flags & 4 ? RS_EDGES_ALPHAMAP : RS_EDGES_ANALYTIC;
    o.grid.edits = 1;
    o.style.styles = styles;
    if (rs_road_grid_build(ctx, dem, roads, &o, &g0) || render(ctx, dem, g0, &o, &a) ||
        rs_road_grid_build(ctx, dem, none, &o, &gt) || render(ctx, dem, gt, &o, &t))
        goto done;
    for (size_t k = 0; k < nops; k++) {
        rs_result r = edit(ctx, roads, styles, ops + 6 * k);
        REQUIRE(rs_strerror(r) != NULL);
        if (r) continue;
        restyled |= since && ops[6 * k] % 6 == 5; /* (flat's styles are then not the copy's: refused) */
        lag = 1; /* (the roads are ahead of g0 until an update) */
        if ((flags & 128) && k % 2 == 0 && k + 1 < nops) continue; /* (the next edit's update takes both) */
        rs_road_grid *g1 = NULL, *gf = NULL;
        image b = { 0 }, c = { 0 };
        r = rs_road_grid_update(ctx, dem, roads, &o, g0, &g1);
        REQUIRE(rs_strerror(r) != NULL && (r == RS_OK) == (g1 != NULL));
        int ok = r == RS_OK && render(ctx, dem, g1, &o, &b) == 0 && rs_road_grid_build(ctx, dem, roads, &o, &gf) == RS_OK &&
                 render(ctx, dem, gf, &o, &c) == 0;
        if (ok) check(g1, &a, &b, &c, &t);
        if (ok) REQUIRE(rs__grid_track_net_check(ctx, g1, roads) == 1);
        if (ok && (flags & 32) && !since) { /* (the copy at this grid, kept) */
            r = rs_roads_copy(ctx, roads, &snap);
            REQUIRE(r == RS_OK || r == RS_ERR_NOMEM);
            if (r == RS_OK) since = g1;
        }
        rs_road_grid_free(ctx, gf);
        image_free(&b);
        if (!ok) {
            rs_road_grid_free(ctx, g1);
            image_free(&c);
            break;
        }
        if (g0 != since) rs_road_grid_free(ctx, g0);
        g0 = g1;
        lag = 0;
        image_free(&a);
        a = c;
    }
    if (since && g0 && a.rgba) { /* the chain moved onto a whole build of the copy */
        rs_road_grid *flat = NULL, *rb = NULL;
        if (rs_road_grid_build(ctx, dem, snap, &o, &flat) == RS_OK) {
            rs_result r = rs_road_grid_rebase(ctx, g0, since, flat, &rb);
            REQUIRE(o.coverage.edges == RS_EDGES_ANALYTIC && !restyled ? r == RS_OK || r == RS_ERR_NOMEM
                                                                       : r == RS_OK || r == RS_ERR_INVALID_ARG);
            image b = { 0 };
            if (r == RS_OK && render(ctx, dem, rb, &o, &b) == 0) {
                REQUIRE(b.w == a.w && b.h == a.h && memcmp(b.rgba, a.rgba, (size_t)a.w * a.h * 4) == 0 &&
                        memcmp(b.wt, a.wt, (size_t)a.w * a.h * 2) == 0);
                REQUIRE(rs_road_grid_dirty(rb, NULL, 0) == 0);
                if (!lag) REQUIRE(rs__grid_track_net_check(ctx, rb, roads) == 1); /* (else g0 is of earlier roads) */
            }
            image_free(&b);
        }
        rs_road_grid_free(ctx, rb);
        rs_road_grid_free(ctx, flat);
    }
done:
    if (since != g0) rs_road_grid_free(ctx, since);
    rs_roads_free(ctx, snap);
    image_free(&a);
    image_free(&t);
    rs_road_grid_free(ctx, g0);
    rs_road_grid_free(ctx, gt);
    rs_roads_free(ctx, roads);
    rs_roads_free(ctx, none);
    rs_styles_free(ctx, styles);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    return 0;
}
