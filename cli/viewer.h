/* `roadsplat tiles --viewer` (cli/viewer.c): an index.html that shows the
 * pyramid on a Leaflet map, with Leaflet copied beside it. */
#ifndef RS_CLI_VIEWER_H
#define RS_CLI_VIEWER_H
#include <stdint.h>

typedef struct cli_viewer_info {
    uint32_t tile;          /* tile side, pixels */
    uint32_t width, height; /* the finest level's image, pixels */
    uint32_t zmax, zdense;  /* finest level; finest complete level */
    int tms;                /* file names count y up */
    const char *title;
    const char *attribution; /* plain text for the map's attribution line */
    int mercator;            /* --tiling mercator: EPSG:3857 XYZ tiles, Leaflet's default CRS */
    uint32_t zmin;           /* mercator: the first level written */
    double bounds[4];        /* mercator: west, south, east, north (degrees) */
} cli_viewer_info;

/* Writes OUTDIR/index.html and OUTDIR/leaflet/ (from libjs-leaflet). 0, or
 * 1 after a message (Leaflet missing names the package). */
int cli_tiles_viewer(const char *outdir, const cli_viewer_info *v);
#endif
