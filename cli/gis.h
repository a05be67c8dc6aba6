/* Georeferenced input and output (issue 17). The GDAL module
 * roadsplat-gdal.so (cli/gdal.c, loaded on first use by cli/module.c) reads
 * rasters and OGR vector sources and writes GeoTIFFs; cli/geo.c puts them
 * into the splat (world frame, nodata, outputs by extension). Every
 * function that fails prints one line, "roadsplat: FILE: problem". */
#ifndef RS_CLI_GIS_H
#define RS_CLI_GIS_H
#include "cli.h"

#ifdef __cplusplus
extern "C" {
#endif

void cli_geo_free(cli_geo *g);
/* 1 when this build has the GDAL module (it may still fail to load). */
int cli_gdal_available(void);
/* 1 when the GDAL module loads (quietly tried): DEMs fall back to the
 * image module without it. */
int cli_gdal_loadable(void);

/* A DEM through GDAL. 0: read (*z malloc'd, w*h floats, NaN where the
 * file's nodata value or a NaN stood; *nodata counts them); 1: error
 * printed; 2: not for GDAL (not opened by it, or a PNG/TIFF without any
 * georeference: the caller reads it as before, through OpenImageIO).
 * Refused with one line each: rotated or south-up geotransforms,
 * non-square pixels, geographic degrees (with the gdalwarp command to
 * use), CRS units other than metres, more than one band. */
int cli_gdal_read_dem(const char *path, uint32_t max_side, uint32_t *w, uint32_t *h, float **z, size_t *nodata,
                      cli_geo *geo);
/* The same from an input opened once (cli_gdal_input_open): GDAL reads
 * what that descriptor holds (docs/ROBUSTNESS.md, "trust model"); on
 * success the input and the sidecar files read with it are registered
 * under role (NULL: not). On 2 a pipe's bytes stay with the input, for the
 * next reader. The caller closes it. */
int cli_gdal_read_dem_input(cli_input *in, const char *role, uint32_t max_side, uint32_t *w, uint32_t *h, float **z,
                            size_t *nodata, cli_geo *geo);

/* An OGR vector source as road text (docs/road-format.md), malloc'd and
 * NUL-terminated, starting with `frame world CRS`. dst_crs: the CRS to
 * reproject to (EPSG:X, WKT, anything OSRSetFromUserInput reads); NULL:
 * the source's CRS, or the UTM zone of the roads' centre when that is in
 * degrees. */
typedef struct cli_gdal_roads_opts {
    const char *layer; /* --layer NAME, or NULL */
    const char *where; /* --where SQL, or NULL */
    const char *dst_crs;
    const char *shown; /* the name messages give */
    struct cli_gdal_road_counts *counts; /* filled when not NULL */
} cli_gdal_roads_opts;
int cli_gdal_roads_text(const char *path, const cli_gdal_roads_opts *o, char **text, size_t *size);
/* The same from an input opened once, registered under role on success. */
int cli_gdal_roads_text_input(cli_input *in, const char *role, const cli_gdal_roads_opts *o, char **text,
                              size_t *size);
/* Open a GIS input once: cli_input_open (a folder too when folder_ok),
 * after cli_gdal_path_check; with --gdal-trust a name that is no local
 * file (a URL, a /vsi path) is left for GDAL to read (in->fd -1, not
 * registered). 0, or 1 after a message. */
int cli_gdal_input_open(cli_input *in, const char *path, int folder_ok);

/* A GeoTIFF of w x h pixels, channels 1..4 (4: RGBA, alpha unassociated),
 * bits 8 or 16, tiled 256 x 256, deflate; cog: Cloud Optimized GeoTIFF
 * layout with overviews. Written to `path` (the caller's temporary);
 * messages name `shown`. gt and crs may be NULL (no georeference). */
int cli_gdal_write_tiff(const char *path, const char *shown, uint32_t w, uint32_t h, int channels, int bits,
                        const void *data, const double gt[6], const char *crs, int cog);

/* 1 when the two CRS texts name the same CRS, 0 when not, -1 (message
 * printed, naming `shown`) when one cannot be read. */
int cli_gdal_same_crs(const char *a, const char *b, const char *shown);

/* The CRS as ESRI WKT for a .prj (malloc'd), or NULL after a message. */
char *cli_gdal_prj_text(const char *crs, const char *shown);

/* --gdal-trust (docs/ROBUSTNESS.md, "trust model"): off, DEMs and roads
 * are opened only with an allow-list of file drivers, a VRT only when
 * every source it names is a file beside it, and GDAL makes no network
 * request. cli/module.c keeps the flag; the GDAL module reads it. */
void cli_gdal_set_trust(int on);
int cli_gdal_trusted(void);
/* Untrusted: refuse a name GDAL would not read as a local file (a URL,
 * /vsicurl/ and other /vsi paths, a connection string, a name that is not
 * an existing file or folder). 0, or 1 after a message. */
int cli_gdal_path_check(const char *path);

/* 1 when the input should be read as an OGR source rather than road text:
 * a known GIS extension (.geojson .json .gpkg .shp .osm .pbf .fgb .gml
 * .kml .sqlite .csv), a folder, or content that starts like JSON, XML or
 * SQLite (its first bytes, read once: a pipe too). */
int cli_roads_are_gis(const cli_input *in);

/* ---- cli/geo.c: the GIS layer in the splat ---------------------------------- */

/* A DEM with its georeference: PGM through the library; other files
 * through GDAL when it has a georeference for them, else OpenImageIO as
 * before. NULL after a message. */
rs_dem *cli_geo_load_dem(rs_ctx *ctx, const char *path, cli_geo *geo);
/* The one frame check of every command, on a DEM's geotransform (GDAL's
 * order, y north): finite, the corner within 1e12 m, the pixel size in
 * [1e-9, 1e9] m (the limits of --origin and --cell-size). 0, or 1 after a
 * message naming path. */
int cli_geo_check_gt(const char *path, const double gt[6]);
/* The road text of ROADS: the file, or an OGR source converted to the
 * DEM's CRS (s->layer, s->where), its counts in *counts. 0, or 1 after a
 * message. */
int cli_geo_roads_text(const char *roads_path, const cli_splat_args *s, const cli_geo *geo, char **text,
                       size_t *size, cli_gdal_road_counts *counts);
/* One stderr line on what OSM semantics skipped (none when nothing was). */
void cli_geo_source_note(const cli_gdal_road_counts *c, const char *roads_path);
/* The DEM's frame from its georeference and the road file's `frame` line
 * (rs_roads_negate_y for world roads), then the check that some road
 * touches the map (a warning; an error with --strict). 0, or 1 after a
 * message. */
int cli_geo_frame(rs_ctx *ctx, cli_splat_input *in, cli_splat_args *s, const char *dem_path, const char *roads_path);
/* Alpha 0 where the DEM sample nearest to the pixel centre is nodata. */
void cli_nodata_alpha(const uint8_t *mask, uint32_t dem_w, uint32_t dem_h, uint32_t texels, uint32_t x0, uint32_t y0,
                      uint32_t w, uint32_t rows, uint8_t *rgba, size_t stride);

/* Output formats by extension. */
enum { CLI_FMT_PNG = 1, CLI_FMT_TIF, CLI_FMT_PGM };
/* OUT (pgm_ok 0): .png or none -> PNG, .tif/.tiff -> GeoTIFF; --weight-out
 * (pgm_ok 1): .pgm or none -> PGM, .png, .tif. -1 after a message naming
 * the formats. */
int cli_out_format(const char *path, const char *role, int pgm_ok);
/* The texture's geotransform for a window at (x0, y0) of T texels per
 * cell (docs/gis.md): 0, or 1 when the input has no georeference. */
int cli_geo_texture_gt(const cli_splat_input *in, uint32_t texels, uint32_t x0, uint32_t y0, double gt[6]);
/* The same for a world frame without georeference too (a PGM with --origin
 * and roads in 'frame world'): the world file's geotransform. */
int cli_geo_world_gt(const cli_splat_input *in, uint32_t texels, uint32_t x0, uint32_t y0, double gt[6]);
/* The world point (x east, y north) of DEM sample (0,0), the texture's
 * corner: 1 when the run has a world frame (world roads, or a
 * georeferenced DEM), else 0. */
int cli_geo_world_origin(const cli_splat_input *in, double *x, double *y);
/* --window-world XMIN,YMIN,XMAX,YMAX (world units, y north) as an output
 * pixel window: snapped outwards to whole pixels of T texels per cell;
 * win = x0, y0, w, h inside the fw x fh output. 0, or 1 after a message
 * (no world frame, a box not inside the map). */
int cli_geo_window(const cli_splat_input *in, const char *dem_path, uint32_t texels, uint32_t fw, uint32_t fh,
                   const double box[4], uint32_t win[4]);
/* `roadsplat convert` (cli/geo.c). */
int cli_convert_main(int argc, char **argv);

#ifdef __cplusplus
}
#endif
#endif
