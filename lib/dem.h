/* Private: the DEM module (lib/dem.c). */
#ifndef RS_DEM_H
#define RS_DEM_H
#include "internal.h"

/* A DEM with the default frame and width*height uninitialised samples;
 * the caller fills them, then calls rs__dem_seal_range. */
rs_result rs__dem_alloc(rs_ctx *ctx, uint32_t w, uint32_t h, rs_dem **out);
/* The samples are in: their range as the caller found it while filling
 * them (lo, hi: the least and greatest valid sample; nodata: some sample
 * is NaN), kept for rs_dem_height_range. */
void rs__dem_seal_range(rs_dem *dem, float lo, float hi, int nodata);

/* The nodata policy: a copy of the samples where every NaN (or infinite)
 * sample takes the lowest valid 8-neighbour height, layer by layer inwards
 * (all nodata -> 0). *out is the caller's, freed with rs__free. */
rs_result rs__dem_fill_nodata(rs_ctx *ctx, const rs_dem *dem, float **out);

/* Horn's gradient (gdaldem's, in metres per metre: x right, y down) of the
 * heights z (width x height, no NaN) at sample (i, j). Outside the map the
 * surface continues linearly from the two nearest samples. The hillshade
 * and the mesher's normals both use it. Inline: the hillshade calls it per
 * sample, and inside the map it needs no edge handling. */
void rs__dem_horn_border(const float *z, uint32_t width, uint32_t height, double cell_size, double z_scale,
                         uint32_t i, uint32_t j, double *dzdx, double *dzdy);
static inline void rs__dem_horn(const float *z, uint32_t width, uint32_t height, double cell_size, double z_scale,
                                uint32_t i, uint32_t j, double *dzdx, double *dzdy)
{
    if (i >= 1 && i + 1 < height && j >= 1 && j + 1 < width) {
        /* the terms and their order of rs__dem_horn_border, which gives the
         * same doubles here */
        const float *up = z + (size_t)(i - 1) * width + j, *mid = up + width, *dn = mid + width;
        double zs = z_scale;
        double a = up[-1] * zs, b = up[0] * zs, c = up[1] * zs, d = mid[-1] * zs, f = mid[1] * zs;
        double g = dn[-1] * zs, h = dn[0] * zs, k = dn[1] * zs;
        *dzdx = ((c + 2 * f + k) - (a + 2 * d + g)) / (8 * cell_size);
        *dzdy = ((g + 2 * h + k) - (a + 2 * b + c)) / (8 * cell_size);
    } else rs__dem_horn_border(z, width, height, cell_size, z_scale, i, j, dzdx, dzdy);
}
#endif
