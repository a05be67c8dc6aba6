/* `roadsplat tiles --tiling mercator` (cli/mercator.c; docs/tiles.md
 * "Tiling"): XYZ tiles in EPSG:3857, tile (z, x, y) the standard Web
 * Mercator square, y from the north. Each finest tile is resampled from a
 * window of the splat in the DEM's CRS; cli/tiles.c builds the coarser
 * levels and writes everything as for the raster grid. The coordinate
 * transformation lives in the GDAL module (cli/mercator_gdal.c). */
#ifndef RS_CLI_MERCATOR_H
#define RS_CLI_MERCATOR_H
#include "cli.h"

#include <stdio.h>

/* Half the side of the Web Mercator square, metres (pi * 6378137). */
#define CLI_MERC_HALF 20037508.342789244

typedef struct cli_merc_grid {
    uint32_t zmin, zmax, zd; /* levels written; the coarsest whose pixel is no larger than a DEM cell */
    uint64_t fx0, fy0, nx, ny; /* the finest level's tiles that meet the DEM: [fx0, fx0+nx) x [fy0, fy0+ny) */
    uint32_t texels;         /* texels per DEM cell of the splat the tiles are resampled from */
    double m[4];             /* the DEM's footprint in EPSG:3857: xmin, ymin, xmax, ymax */
    double ll[4];            /* the same in longitude, latitude (WGS84 degrees): west, south, east, north */
    double centre[2];        /* the footprint's centre, longitude and latitude */
    double pixel_m;          /* a finest tile pixel on the ground at the centre, metres */
} cli_merc_grid;

typedef struct cli_merc cli_merc;

/* The grid for a loaded input (before the splatter is made): the DEM
 * must be georeferenced with a CRS. user_texels: the texels per cell the
 * options ask for (the target pixel size); zoom_min/zoom_max: --zoom, -1
 * when not given. 0, or 1 after one line naming dem_path. */
int cli_merc_open(const cli_splat_input *in, const char *dem_path, uint32_t tile, uint32_t user_texels,
                  int zoom_min, int zoom_max, cli_merc **out, cli_merc_grid *grid);
/* Finest tile (x, y) (zoom grid->zmax) into rgba (tile x tile x 4), from
 * sp (the splat at grid->texels): bilinear, alpha-weighted; transparent
 * outside the DEM. *has_road: some output pixel samples a road pixel.
 * 0, or 1 after a message. */
int cli_merc_tile(cli_merc *m, const rs_splatter *sp, const cli_splat_args *s, uint64_t x, uint64_t y,
                  uint8_t *rgba, int *has_road);
void cli_merc_close(cli_merc *m);

/* MBTiles 1.3 metadata values: "west,south,east,north" and "lon,lat,zoom". */
void cli_merc_bounds_text(const cli_merc_grid *g, char *buf, size_t cap);
void cli_merc_center_text(const cli_merc_grid *g, char *buf, size_t cap);

/* A GDAL WMS description (TMS minidriver) of a folder of tiles, so that
 * gdalinfo/QGIS open the pyramid in place: OUTDIR/tiles.xml. ul/px: the
 * top-left corner and pixel size of level zmax, whose tile (0, 0) starts
 * at ul; the raster GDAL sees is the level-0 tile's square (tile << zmax
 * pixels a side: GDAL's TMS minidriver knows no partial grid), transparent
 * beyond the tiles; crs: a CRS text. 0, or 1 after a message. */
int cli_tiles_gdal_xml(const char *outdir, const double ul[2], double px, uint32_t zmax,
                       uint32_t tile, int tms, const char *crs);
#endif
