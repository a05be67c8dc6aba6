/* The coordinate transformation of `tiles --tiling mercator` (cli/mercator.c):
 * part of the GDAL module roadsplat-gdal.so, so that the executable never
 * links PROJ. One transformer between the DEM's CRS and EPSG:3857, both in
 * the traditional GIS axis order (x east, y north). */
#include "mercator.h"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <ogr_srs_api.h>

#include <math.h>
#include <stdlib.h>

typedef struct merc_proj {
    OGRCoordinateTransformationH fwd, inv; /* DEM CRS -> EPSG:3857, and back */
} merc_proj;

static OGRSpatialReferenceH srs(const char *text)
{
    OGRSpatialReferenceH s = OSRNewSpatialReference(NULL);
    if (!s) return NULL;
    if (OSRSetFromUserInput(s, text) != OGRERR_NONE) {
        OSRDestroySpatialReference(s);
        return NULL;
    }
    OSRSetAxisMappingStrategy(s, OAMS_TRADITIONAL_GIS_ORDER);
    return s;
}

#if defined(__GNUC__)
__attribute__((visibility("default")))
#endif
void *cli_merc_proj_open(const char *crs, const char *shown);
void *cli_merc_proj_open(const char *crs, const char *shown)
{
    CPLSetErrorHandler(CPLQuietErrorHandler);
    OGRSpatialReferenceH a = srs(crs), b = srs("EPSG:3857");
    merc_proj *p = calloc(1, sizeof *p);
    if (a && b && p) {
        p->fwd = OCTNewCoordinateTransformation(a, b);
        p->inv = OCTNewCoordinateTransformation(b, a);
    }
    if (a) OSRDestroySpatialReference(a);
    if (b) OSRDestroySpatialReference(b);
    if (!p || !p->fwd || !p->inv) {
        const char *m = CPLGetLastErrorMsg();
        cli_error("%s: --tiling mercator: no transformation from the DEM's CRS to EPSG:3857%s%s", shown,
                  m && m[0] ? ": " : "", m ? m : "");
        if (p) {
            if (p->fwd) OCTDestroyCoordinateTransformation(p->fwd);
            if (p->inv) OCTDestroyCoordinateTransformation(p->inv);
        }
        free(p);
        return NULL;
    }
    return p;
}

/* n points in place: to EPSG:3857 (inverse 0) or back to the DEM's CRS
 * (inverse 1). A point PROJ cannot transform becomes NaN. */
#if defined(__GNUC__)
__attribute__((visibility("default")))
#endif
void cli_merc_proj_transform(void *h, int inverse, size_t n, double *x, double *y);
void cli_merc_proj_transform(void *h, int inverse, size_t n, double *x, double *y)
{
    merc_proj *p = h;
    enum { B = 4096 };
    int ok[B];
    for (size_t i = 0; i < n; i += B) {
        int m = (int)(n - i < B ? n - i : B);
        if (!OCTTransformEx(inverse ? p->inv : p->fwd, m, x + i, y + i, NULL, ok)) {
            for (int k = 0; k < m; k++) x[i + k] = y[i + k] = NAN;
            continue;
        }
        for (int k = 0; k < m; k++)
            if (!ok[k] || !isfinite(x[i + k]) || !isfinite(y[i + k])) x[i + k] = y[i + k] = NAN;
    }
}

#if defined(__GNUC__)
__attribute__((visibility("default")))
#endif
void cli_merc_proj_close(void *h);
void cli_merc_proj_close(void *h)
{
    merc_proj *p = h;
    if (!p) return;
    OCTDestroyCoordinateTransformation(p->fwd);
    OCTDestroyCoordinateTransformation(p->inv);
    free(p);
}
