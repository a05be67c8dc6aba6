/* Private: the DEM module (lib/dem.c). */
#ifndef RS_DEM_H
#define RS_DEM_H
#include "internal.h"

/* A DEM with the default frame and width*height uninitialised samples. */
rs_result rs__dem_alloc(rs_ctx *ctx, uint32_t w, uint32_t h, rs_dem **out);

/* The nodata policy: a copy of the samples where every NaN (or infinite)
 * sample takes the lowest valid 8-neighbour height, layer by layer inwards
 * (all nodata -> 0). *out is the caller's, freed with rs__free. */
rs_result rs__dem_fill_nodata(rs_ctx *ctx, const rs_dem *dem, float **out);

/* Horn's gradient (gdaldem's, in metres per metre: x right, y down) of the
 * heights z (width x height, no NaN) at sample (i, j). Outside the map the
 * surface continues linearly from the two nearest samples. The hillshade
 * and the mesher's normals both use it. */
void rs__dem_horn(const float *z, uint32_t width, uint32_t height, double cell_size, double z_scale, uint32_t i,
                  uint32_t j, double *dzdx, double *dzdy);
#endif
