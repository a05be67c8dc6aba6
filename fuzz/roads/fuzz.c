/* libFuzzer target: rs_roads_parse on arbitrary bytes. Success must give
 * roads with >= 2 finite points and a finite positive width; a parse error
 * must come with a "line N:" message and no object. */
#include "roadsplat.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    rs_limits lim = { 0 };
    lim.max_points = 100000;
    lim.max_line_length = 4096;
    rs_ctx *ctx = NULL;
    if (rs_ctx_create(NULL, &lim, &ctx) != RS_OK) return 0;
    rs_roads *roads = NULL;
    rs_result rc = rs_roads_parse(ctx, (const char *)data, size, &roads);
    if (rc == RS_OK) {
        size_t total = 0;
        for (size_t i = 0; i < rs_roads_count(roads); i++) {
            const char *name;
            double w;
            const double *xy;
            size_t n;
            if (rs_roads_get(roads, i, &name, &w, &xy, &n) != RS_OK) abort();
            if (!name || !(w > 0) || !isfinite(w) || n < 2) abort();
            for (size_t k = 0; k < 2 * n; k++)
                if (!isfinite(xy[k])) abort();
            total += n;
        }
        if (total > lim.max_points) abort();
        rs_roads_free(ctx, roads);
    } else {
        if (roads) abort();
        if ((rc == RS_ERR_PARSE || rc == RS_ERR_LIMIT) && strncmp(rs_ctx_message(ctx), "line ", 5) != 0) abort();
    }
    rs_ctx_free(ctx);
    return 0;
}
