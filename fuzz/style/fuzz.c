/* libFuzzer target: road files with attributes and style blocks.
 * rs_roads_parse_ex (keeping the styles) and rs_styles_parse on the same
 * bytes must agree (result and message); a parse error comes with a
 * "line N:" message and no object. On success every style passes
 * rs_styles_add's checks and is found by its name, every road's attributes
 * are consistent (unique keys, get_attr = attr_at, known keys decoded),
 * and rs_road_style gives a valid style under both profiles (or refuses a
 * style= name that is defined nowhere). */
#include "roadsplat.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void check_style(rs_ctx *ctx, rs_styles *scratch, const rs_style *s, unsigned serial)
{
    rs_style c = *s;
    /* rs_styles_add wants a unique, non-empty name */
    c.name[0] = '#';
    c.name[1] = (char)('0' + serial % 10);
    c.name[2] = (char)('0' + serial / 10 % 10);
    c.name[3] = (char)('0' + serial / 100 % 10);
    c.name[4] = (char)('0' + serial / 1000 % 10);
    c.name[5] = '\0';
    if (rs_styles_add(ctx, scratch, &c) != RS_OK) abort();
    for (uint32_t i = 0; i < s->line_count; i++)
        if (!isfinite(s->line[i].offset) || !(s->line[i].width > 0)) abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    rs_limits lim = { 0 };
    lim.max_points = 100000;
    lim.max_line_length = 4096;
    rs_ctx *ctx = NULL;
    if (rs_ctx_create(NULL, &lim, &ctx) != RS_OK) return 0;
    rs_styles *kept = NULL, *alone = NULL, *scratch = NULL;
    rs_roads *roads = NULL;
    if (rs_styles_create(ctx, &kept) != RS_OK || rs_styles_create(ctx, &scratch) != RS_OK) abort();
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.styles = kept;
    po.profile = size && (data[0] & 1) ? RS_PROFILE_MUTCD : RS_PROFILE_RMS;
    rs_result rc = rs_roads_parse_ex(ctx, (const char *)data, size, &po, &roads);
    char msg[256];
    strncpy(msg, rs_ctx_message(ctx), sizeof msg - 1);
    msg[sizeof msg - 1] = '\0';
    rs_result rc2 = rs_styles_parse(ctx, (const char *)data, size, &alone);
    if (rc != rc2 || strcmp(msg, rs_ctx_message(ctx)) != 0) abort();
    if (rc != RS_OK) {
        if (roads || alone || rs_styles_count(kept) != 0) abort();
        if ((rc == RS_ERR_PARSE || rc == RS_ERR_LIMIT) && strncmp(msg, "line ", 5) != 0) abort();
    } else {
        unsigned serial = 0;
        if (rs_styles_count(kept) != rs_styles_count(alone)) abort();
        for (size_t i = 0; i < rs_styles_count(kept); i++) {
            const rs_style *s = rs_styles_get(kept, i), *t = rs_styles_get(alone, i);
            if (!s || !t || memcmp(s, t, sizeof *s) != 0 || rs_styles_find(kept, s->name) != s) abort();
            check_style(ctx, scratch, s, serial++);
        }
        for (size_t i = 0; i < rs_roads_count(roads); i++) {
            rs_road_info info;
            const char *name;
            double w;
            size_t n;
            if (rs_roads_get(roads, i, &name, &w, NULL, &n) != RS_OK || rs_roads_get_info(roads, i, &info) != RS_OK)
                abort();
            if (!name || !(w > 0) || !isfinite(w) || n < 2) abort();
            if ((unsigned)info.road_class >= RS_CLASS_COUNT || info.lanes > 16 || (unsigned)info.oneway > 3 ||
                (unsigned)info.area > 2)
                abort();
            size_t na = rs_roads_attr_count(roads, i);
            if (na > 64) abort();
            for (size_t k = 0; k < na; k++) {
                const char *key, *val;
                if (rs_roads_attr_at(roads, i, k, &key, &val) != RS_OK || !key || !val || !*key) abort();
                if (rs_roads_get_attr(roads, i, key) != val) abort(); /* keys are unique */
            }
            if ((info.style != NULL) != (rs_roads_get_attr(roads, i, "style") != NULL)) abort();
            for (int p = 0; p < 2; p++) {
                rs_style s;
                rs_result r = rs_road_style(ctx, roads, i, kept, (rs_profile)p, &s);
                if (r == RS_OK) check_style(ctx, scratch, &s, serial++);
                else if (r != RS_ERR_INVALID_ARG || !info.style || rs_styles_find(kept, info.style)) abort();
            }
        }
    }
    rs_roads_free(ctx, roads);
    rs_styles_free(ctx, alone);
    rs_styles_free(ctx, kept);
    rs_styles_free(ctx, scratch);
    rs_ctx_free(ctx);
    return 0;
}
