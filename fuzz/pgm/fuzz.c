/* libFuzzer target: rs_dem_parse_pgm on arbitrary bytes, under tight limits
 * so that huge headers are rejected quickly. Checks the invariants a
 * caller relies on: success gives a DEM of the header's size with finite
 * samples; failure gives no DEM and a message. */
#include "roadsplat.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    rs_limits lim = { 0 };
    lim.max_dem_side = 4096;
    rs_ctx *ctx = NULL;
    if (rs_ctx_create(NULL, &lim, &ctx) != RS_OK) return 0;
    rs_dem *dem = NULL;
    rs_result rc = rs_dem_parse_pgm(ctx, data, size, &dem);
    if (rc == RS_OK) {
        uint32_t w = rs_dem_width(dem), h = rs_dem_height(dem);
        const float *z = rs_dem_samples(dem);
        if (w < 2 || h < 2 || !z) abort();
        for (size_t i = 0; i < (size_t)w * h; i++)
            if (!isfinite(z[i]) || z[i] < 0 || z[i] > 65535) abort();
        rs_dem_free(ctx, dem);
    } else {
        if (dem || rs_ctx_message(ctx)[0] == '\0') abort();
    }
    rs_ctx_free(ctx);
    return 0;
}
