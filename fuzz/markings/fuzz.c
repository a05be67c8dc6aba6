/* libFuzzer target: the marking atlas index (rs_atlas_create over a fixed
 * 64 x 64 image) and road text with `mark` lines and point attributes
 * (rs_roads_parse), then markings placed on a small DEM. The input is the
 * index, a line "---", then the road text (no such line: all road text,
 * the built-in atlas). Errors must be clean: a "line N:" message (or
 * "atlas index line N:") and no object. */
#include "roadsplat.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static const char *find_sep(const char *s, size_t n)
{
    for (size_t i = 0; i + 4 <= n; i++)
        if ((i == 0 || s[i - 1] == '\n') && memcmp(s + i, "---\n", 4) == 0) return s + i;
    return NULL;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    rs_limits lim = { 0 };
    lim.max_points = 10000;
    lim.max_line_length = 4096;
    rs_ctx *ctx = NULL;
    if (rs_ctx_create(NULL, &lim, &ctx) != RS_OK) return 0;
    const char *text = (const char *)data, *sep = find_sep(text, size);
    rs_atlas *atlas = NULL;
    static uint8_t px[64 * 64 * 4];
    for (size_t i = 0; i < sizeof px; i++) px[i] = (uint8_t)(i * 131u);
    if (sep) {
        rs_image img = { 64, 64, px };
        rs_result r = rs_atlas_create(ctx, &img, text, (size_t)(sep - text), &atlas);
        if (r != RS_OK) {
            if (atlas) abort();
            if (r == RS_ERR_PARSE && strncmp(rs_ctx_message(ctx), "atlas index line ", 17) != 0) abort();
            rs_ctx_free(ctx);
            return 0;
        }
        if (rs_atlas_count(atlas) == 0) abort();
        size -= (size_t)(sep + 4 - text);
        text = sep + 4;
    }
    rs_roads *roads = NULL;
    rs_result r = rs_roads_parse(ctx, text, size, &roads);
    if (r != RS_OK) {
        if (roads) abort();
        if (r == RS_ERR_PARSE && strncmp(rs_ctx_message(ctx), "line ", 5) != 0) abort();
    } else {
        for (size_t i = 0; i < rs_roads_mark_count(roads); i++) {
            rs_mark m;
            if (rs_roads_get_mark(roads, i, &m) != RS_OK || m.road >= rs_roads_count(roads) || !m.type[0]) abort();
        }
        static float z[33 * 33];
        rs_dem *dem = NULL;
        if (rs_dem_create(ctx, 33, 33, z, &dem) == RS_OK) {
            rs_splat_options o;
            memset(&o, 0, sizeof o);
            o.texels = 2;
            o.markings.atlas = atlas;
            rs_splatter *sp = NULL;
            if (rs_splatter_create(ctx, dem, roads, NULL, &o, &sp) == RS_OK) {
                static uint8_t out[64 * 64 * 4];
                if (rs_splat_window(ctx, sp, 0, 0, 64, 64, out, 64 * 4, NULL, 0, NULL) != RS_OK) abort();
                rs_splatter_free(ctx, sp);
            }
            rs_dem_free(ctx, dem);
        }
        rs_roads_free(ctx, roads);
    }
    rs_atlas_free(ctx, atlas);
    rs_ctx_free(ctx);
    return 0;
}
