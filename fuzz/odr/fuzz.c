/* Fuzz target: the OpenDRIVE reader (cli/odr.c with expat) and the
 * conversion to road text (lib/input/odr_lanes.c). Every input either fails with
 * one message line naming the input, or gives road text that the road
 * parser reads back with its styles. */
#include "../../cli/odr.h"
#include "roadsplat.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = NULL, err[800];
    size_t n = 0;
    err[0] = '\0';
    /* a small point budget keeps each run fast; the limit's path is fuzzed too */
    int r = cli_odr_text((const char *)data, size, "in.xodr", 20000, &text, &n, err, sizeof err);
    if (r) {
        if (strncmp(err, "in.xodr", 7) || strchr(err, '\n')) abort(); /* one line naming the file */
        return 0;
    }
    rs_ctx *ctx = NULL;
    rs_styles *styles = NULL;
    rs_roads *roads = NULL;
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) abort();
    if (rs_styles_create(ctx, &styles) != RS_OK) abort();
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.styles = styles;
    if (rs_roads_parse_ex(ctx, text, n, &po, &roads) != RS_OK) abort(); /* the converter wrote bad road text */
    rs_roads_free(ctx, roads);
    rs_styles_free(ctx, styles);
    rs_ctx_free(ctx);
    free(text);
    return 0;
}
