/* The GIS layer in the splat (issue 17, docs/gis.md): DEMs with their
 * georeference, OGR road sources, the north-up world frame, the check that
 * some road touches the map, nodata made transparent, outputs chosen by
 * extension, and `roadsplat convert`. GDAL itself is in the module
 * roadsplat-gdal.so (cli/gdal.c); this file only calls its entry points
 * (cli/module.c), so a run on a PGM and road text never loads it. */
#include "gis.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* ---- file names ------------------------------------------------------------------ */

/* The extension of the last path component, from its '.', or "". */
static const char *ext_of(const char *path)
{
    const char *slash = strrchr(path, '/'), *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    return dot && dot != base ? dot : "";
}

static int ext_is(const char *path, const char *ext)
{
    const char *e = ext_of(path);
    size_t n = strlen(ext);
    if (strlen(e) != n) return 0;
    for (size_t i = 0; i < n; i++) {
        char c = e[i];
        if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
        if (c != ext[i]) return 0;
    }
    return 1;
}

int cli_out_format(const char *path, const char *role, int pgm_ok)
{
    const char *e = ext_of(path);
    if (!e[0]) return pgm_ok ? CLI_FMT_PGM : CLI_FMT_PNG;
    if (ext_is(path, ".png")) return CLI_FMT_PNG;
    if (ext_is(path, ".tif") || ext_is(path, ".tiff")) return CLI_FMT_TIF;
    if (pgm_ok && ext_is(path, ".pgm")) return CLI_FMT_PGM;
    cli_error("%s: %s has the unknown extension '%s': roadsplat writes .png or .tif (GeoTIFF)%s", path, role, e,
              pgm_ok ? " or .pgm (16-bit)" : "");
    return -1;
}

int cli_roads_are_gis(const cli_input *in)
{
    static const char *const exts[] = { ".geojson", ".json", ".gpkg", ".shp", ".osm", ".pbf", ".fgb",
                                        ".gml", ".kml", ".sqlite", ".csv", ".geojsonl", ".gdb" };
    for (size_t i = 0; i < sizeof exts / sizeof exts[0]; i++)
        if (ext_is(in->path, exts[i])) return 1;
    if (in->fd < 0) return 0;
    if (S_ISDIR(in->st.st_mode)) return 1;
    const unsigned char *head = (const unsigned char *)in->head;
    size_t n = in->got, i = 0;
    if (n >= 3 && head[0] == 0xEF && head[1] == 0xBB && head[2] == 0xBF) i = 3;
    while (i < n && (head[i] == ' ' || head[i] == '\t' || head[i] == '\r' || head[i] == '\n')) i++;
    if (i < n && (head[i] == '{' || head[i] == '<')) return 1;
    return n >= 15 && !memcmp(head, "SQLite format 3", 15);
}

/* ---- inputs ---------------------------------------------------------------------- */

static int is_pgm(const cli_input *in)
{
    return ext_is(in->path, ".pgm") || (in->got >= 2 && in->head[0] == 'P' && (in->head[1] == '2' || in->head[1] == '5'));
}

rs_dem *cli_geo_load_dem(rs_ctx *ctx, const char *path, cli_geo *geo)
{
    memset(geo, 0, sizeof *geo);
    /* builds without GDAL: as before */
    if (!cli_gdal_available()) return cli_load_dem(ctx, path);
    /* opened once: every reader below (GDAL, the library, OpenImageIO)
     * reads this descriptor, which is what gets registered */
    cli_input in;
    if (cli_gdal_input_open(&in, path, 0)) return NULL;
    if (in.fd >= 0 && (is_pgm(&in) || !cli_gdal_loadable())) return cli_load_dem_input(ctx, &in);
    rs_limits lim = { 0 };
    rs_ctx_limits(ctx, &lim);
    uint32_t w = 0, h = 0;
    float *z = NULL;
    size_t nd = 0;
    int r = cli_gdal_read_dem_input(&in, "DEM", lim.max_dem_side, &w, &h, &z, &nd, geo);
    if (r == 2 && in.fd >= 0) return cli_load_dem_input(ctx, &in);
    cli_input_close(&in);
    if (r == 2) cli_error("%s: not a DEM GDAL can read", path);
    if (r) {
        free(z);
        cli_geo_free(geo);
        return NULL;
    }
    rs_dem *dem = NULL;
    rs_result rc = rs_dem_create(ctx, w, h, z, &dem);
    free(z);
    if (rc != RS_OK) {
        cli_error("%s: %s", path, rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(rc));
        cli_geo_free(geo);
        return NULL;
    }
    return dem;
}

int cli_geo_roads_text(const char *roads_path, const cli_splat_args *s, const cli_geo *geo, char **text,
                       size_t *size, cli_gdal_road_counts *counts)
{
    *text = NULL;
    *size = 0;
    cli_input in;
    if (cli_gdal_input_open(&in, roads_path, 1)) return 1;
    int rc = 1;
    if (!cli_roads_are_gis(&in)) {
        if (s->layer || s->where) {
            cli_error("%s: --layer and --where select from GIS road sources (GeoJSON, GeoPackage, Shapefile, OSM, "
                      "...), not from road text", roads_path);
        } else if (in.fd < 0) {
            cli_error("%s: not a local file", roads_path);
        } else {
            /* the default rs_limits.max_points (10^7) at 64 bytes a point */
            rc = cli_input_read_all(&in, (size_t)10000000 * 64 + (1u << 20), text, size) ||
                 cli_inputs_add(roads_path, "ROADS", in.fd, *text, *size);
            if (rc) {
                free(*text);
                *text = NULL;
                *size = 0;
            }
        }
        cli_input_close(&in);
        return rc;
    }
    cli_gdal_roads_opts o;
    memset(&o, 0, sizeof o);
    o.layer = s->layer;
    o.where = s->where;
    o.dst_crs = geo->crs;
    o.shown = roads_path;
    o.counts = counts;
    if (!cli_gdal_available()) {
        cli_gdal_roads_text_input(&in, NULL, &o, text, size); /* says why */
    } else if (!geo->georef || !geo->crs) {
        cli_error("%s: GIS roads are reprojected to the DEM's coordinate system, and the DEM has %s; use a "
                  "georeferenced DEM, or write the roads in a chosen CRS first: roadsplat convert --t-srs "
                  "EPSG:XXXX %s roads.txt", roads_path, geo->georef ? "no CRS" : "no georeference", roads_path);
    } else {
        rc = cli_gdal_roads_text_input(&in, "ROADS", &o, text, size);
    }
    cli_input_close(&in);
    return rc;
}

void cli_geo_source_note(const cli_gdal_road_counts *c, const char *roads_path)
{
    if (c->set && (c->no_highway || c->not_roads || c->tunnels)) {
        char tun[96] = "";
        if (c->tunnels) snprintf(tun, sizeof tun, ", and %zu in tunnels (under the ground)", c->tunnels);
        fprintf(stderr, "roadsplat: note: %s: %zu roads from %zu features; skipped %zu ways without highway=* "
                "(fences, rivers, railways, ...; --where selects features) and %zu whose highway= is not a road%s\n",
                roads_path, c->roads, c->features, c->no_highway, c->not_roads, tun);
    }
}

/* ---- the frame --------------------------------------------------------------------- */

int cli_geo_check_gt(const char *path, const double gt[6])
{
    for (int k = 0; k < 6; k++)
        if (!isfinite(gt[k])) {
            cli_error("%s: the geotransform is not finite (%g, %g, %g, %g, %g, %g)", path, gt[0], gt[1], gt[2], gt[3],
                      gt[4], gt[5]);
            return 1;
        }
    /* the limits of --origin and --cell-size, in the file's own terms (y north) */
    if (!(fabs(gt[0]) <= 1e12 && fabs(gt[3]) <= 1e12)) {
        cli_error("%s: the grid's corner x %.12g, y %.12g (y north) is not within 1e12 m", path, gt[0], gt[3]);
        return 1;
    }
    if (!(fabs(gt[1]) >= 1e-9 && fabs(gt[1]) <= 1e9 && fabs(gt[5]) >= 1e-9 && fabs(gt[5]) <= 1e9)) {
        cli_error("%s: the pixel size %.12g x %.12g is not in [1e-9, 1e9] m", path, gt[1], fabs(gt[5]));
        return 1;
    }
    return 0;
}

/* Some road's box, grown by half its width, meets the map's. Boxes in the
 * local frame (library coordinates: world - origin, y down). */
static int roads_touch(const rs_roads *roads, const rs_dem_frame *fr, double mw, double mh, double box[4])
{
    size_t n = rs_roads_count(roads);
    int touch = 0;
    box[0] = box[1] = INFINITY;
    box[2] = box[3] = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        const double *xy;
        size_t np;
        double w;
        if (rs_roads_get(roads, i, NULL, &w, &xy, &np) != RS_OK) continue;
        double b[4] = { INFINITY, INFINITY, -INFINITY, -INFINITY };
        for (size_t k = 0; k < np; k++) {
            double x = xy[2 * k] - fr->origin_x, y = xy[2 * k + 1] - fr->origin_y;
            if (x < b[0]) b[0] = x;
            if (y < b[1]) b[1] = y;
            if (x > b[2]) b[2] = x;
            if (y > b[3]) b[3] = y;
        }
        for (int k = 0; k < 2; k++) {
            if (b[k] < box[k]) box[k] = b[k];
            if (b[k + 2] > box[k + 2]) box[k + 2] = b[k + 2];
        }
        double r = w / 2;
        if (b[0] - r <= mw && b[2] + r >= 0 && b[1] - r <= mh && b[3] + r >= 0) touch = 1;
    }
    return touch;
}

static int cmp_double(const void *a, const void *b)
{
    double u = *(const double *)a, v = *(const double *)b;
    return u < v ? -1 : u > v;
}

/* The roads' median width (the lower one) is over 4 cells: a DEM whose
 * cell size was left at 1 m (issue 28: roads drawn 5 times too wide). */
static int roads_wide_for_cells(const rs_roads *roads, double cell)
{
    size_t n = rs_roads_count(roads);
    if (!n) return 0;
    double *w = malloc(n * sizeof *w);
    if (!w) return 0;
    for (size_t i = 0; i < n; i++) rs_roads_get(roads, i, NULL, &w[i], NULL, NULL);
    qsort(w, n, sizeof *w, cmp_double);
    int wide = w[(n - 1) / 2] > 4 * cell;
    free(w);
    return wide;
}

int cli_geo_frame(rs_ctx *ctx, cli_splat_input *in, cli_splat_args *s, const char *dem_path, const char *roads_path)
{
    rs_dem_frame fr = s->frame;
    const char *rcrs = NULL;
    rs_road_frame rf = rs_roads_frame(in->roads, &rcrs);
    const cli_geo *g = &in->geo;
    in->world = 0;
    if (g->georef) {
        if (s->cell_size_given || s->origin_given) {
            cli_error("%s: %s: the DEM is georeferenced, so its cell size (%.12g) and origin come from the file; "
                      "leave the option out", dem_path, s->cell_size_given ? "--cell-size" : "--origin", g->gt[1]);
            return 1;
        }
        fr.cell_size = g->gt[1];
        if (rf == RS_FRAME_WORLD) {
            if (rcrs && g->crs && strcmp(rcrs, g->crs)) {
                int same = cli_gdal_same_crs(rcrs, g->crs, roads_path);
                if (same < 0) return 1;
                if (!same) {
                    cli_error("%s: the roads are in %.60s but the DEM %s is in %.60s; convert the GIS source with "
                              "roadsplat convert --dem %s", roads_path, rcrs, dem_path, g->crs, dem_path);
                    return 1;
                }
            }
            in->world = 1;
            in->wx0 = g->gt[0] + g->gt[1] / 2;
            in->wy0 = g->gt[3] + g->gt[5] / 2;
        }
        /* local (or no frame line): relative to sample (0,0), y down, as before */
    } else if (rf == RS_FRAME_WORLD) {
        if (!s->origin_given) {
            cli_error("%s: the roads are in world coordinates ('frame world') but the DEM %s has no georeference; use "
                      "a georeferenced DEM (GeoTIFF, ...) or give --origin X,Y, the world point of sample (0,0) with y "
                      "growing north", roads_path, dem_path);
            return 1;
        }
        in->world = 1;
        in->wx0 = fr.origin_x;
        in->wy0 = fr.origin_y;
    }
    if (in->world) {
        if (rs_roads_negate_y(ctx, in->roads) != RS_OK) {
            cli_error("%s: %s", roads_path, rs_ctx_message(ctx));
            return 1;
        }
        fr.origin_x = in->wx0;
        fr.origin_y = -in->wy0;
    }
    if (rs_dem_set_frame(ctx, in->dem, &fr) != RS_OK) {
        cli_error("%s: %s", dem_path, rs_ctx_message(ctx));
        return 1;
    }
    if (!g->georef && !s->cell_size_given && roads_wide_for_cells(in->roads, fr.cell_size ? fr.cell_size : 1))
        fprintf(stderr, "roadsplat: warning: %s: no --cell-size, so the DEM's cells are 1 m apart and the roads "
                "(%s) are most of them over 4 cells wide; give --cell-size M, the metres between DEM samples\n",
                dem_path, roads_path);
    if (rs_roads_count(in->roads) == 0) return 0;
    rs_dem_frame got;
    rs_dem_get_frame(in->dem, &got);
    double mw = (rs_dem_width(in->dem) - 1) * got.cell_size, mh = (rs_dem_height(in->dem) - 1) * got.cell_size;
    double box[4];
    if (roads_touch(in->roads, &got, mw, mh, box)) return 0;
    /* both extents in the coordinates the user wrote */
    double rx0, rx1, ry0, ry1, mx0, mx1, my0, my1;
    if (in->world) {
        rx0 = box[0] + in->wx0, rx1 = box[2] + in->wx0, ry0 = in->wy0 - box[3], ry1 = in->wy0 - box[1];
        mx0 = in->wx0, mx1 = in->wx0 + mw, my0 = in->wy0 - mh, my1 = in->wy0;
    } else {
        rx0 = box[0] + got.origin_x, rx1 = box[2] + got.origin_x, ry0 = box[1] + got.origin_y,
        ry1 = box[3] + got.origin_y;
        mx0 = got.origin_x, mx1 = got.origin_x + mw, my0 = got.origin_y, my1 = got.origin_y + mh;
    }
    const char *hint = "";
    if (!in->world && g->georef)
        hint = "; roads in the DEM's world coordinates need the line 'frame world' at the top of the road file";
    else if (!in->world && !s->origin_given)
        hint = "; roads in world coordinates need --origin X,Y (the world point of sample (0,0))";
    char msg[700];
    int short_crs = in->world && g->crs && strlen(g->crs) < 24; /* an EPSG code, not a WKT */
    snprintf(msg, sizeof msg,
             "%s: no road touches the map: the roads span x %.10g..%.10g, y %.10g..%.10g; the map (%s) spans x "
             "%.10g..%.10g, y %.10g..%.10g (%s%s%s)%s",
             roads_path, rx0, rx1, ry0, ry1, dem_path, mx0, mx1, my0, my1, in->world ? "y north" : "y down",
             short_crs ? ", " : "", short_crs ? g->crs : "", hint);
    if (s->strict) {
        cli_error("%s", msg);
        return 1;
    }
    fprintf(stderr, "roadsplat: warning: %s\n", msg);
    return 0;
}

void cli_nodata_alpha(const uint8_t *mask, uint32_t dem_w, uint32_t dem_h, uint32_t texels, uint32_t x0, uint32_t y0,
                      uint32_t w, uint32_t rows, uint8_t *rgba, size_t stride)
{
    uint64_t T = texels ? texels : 1;
    for (uint32_t r = 0; r < rows; r++) {
        /* the nearest sample: pixel centre (p + 1/2) / T cells, rounded */
        uint64_t i = (2 * ((uint64_t)y0 + r) + 1 + T) / (2 * T);
        if (i >= dem_h) i = dem_h - 1;
        const uint8_t *m = mask + i * dem_w;
        uint8_t *row = rgba + r * stride;
        for (uint32_t x = 0; x < w; x++) {
            uint64_t j = (2 * ((uint64_t)x0 + x) + 1 + T) / (2 * T);
            if (j >= dem_w) j = dem_w - 1;
            if (m[j]) row[4 * (size_t)x + 3] = 0;
        }
    }
}

int cli_geo_texture_gt(const cli_splat_input *in, uint32_t texels, uint32_t x0, uint32_t y0, double gt[6])
{
    if (!in->geo.georef) return 1;
    return cli_geo_world_gt(in, texels, x0, y0, gt);
}

int cli_geo_world_gt(const cli_splat_input *in, uint32_t texels, uint32_t x0, uint32_t y0, double gt[6])
{
    if (!in->world) return 1; /* a georeferenced DEM, or a PGM with --origin and world roads */
    rs_dem_frame fr;
    rs_dem_get_frame(in->dem, &fr);
    double px = fr.cell_size / (texels ? texels : 1);
    /* sample (0,0) is the centre of the DEM's first pixel, the texture's
     * corner (SPEC "Frames and units") */
    gt[0] = in->wx0 + x0 * px;
    gt[1] = px;
    gt[2] = 0;
    gt[3] = in->wy0 - y0 * px;
    gt[4] = 0;
    gt[5] = -px;
    return 0;
}

int cli_geo_world_origin(const cli_splat_input *in, double *x, double *y)
{
    if (in->world) {
        *x = in->wx0;
        *y = in->wy0;
        return 1;
    }
    if (in->geo.georef) { /* the first pixel's centre */
        *x = in->geo.gt[0] + in->geo.gt[1] / 2;
        *y = in->geo.gt[3] + in->geo.gt[5] / 2;
        return 1;
    }
    return 0;
}

/* floor / ceil of v, a count of pixels, forgiving the rounding error of a
 * box edge given on a pixel edge (1e-6 px). */
static double floor_px(double v) { return floor(v + 1e-6); }
static double ceil_px(double v) { return ceil(v - 1e-6); }

int cli_geo_window(const cli_splat_input *in, const char *dem_path, uint32_t texels, uint32_t fw, uint32_t fh,
                   const double box[4], uint32_t win[4])
{
    double X0, Y0;
    if (!cli_geo_world_origin(in, &X0, &Y0)) {
        cli_error("--window-world: the DEM %s has no georeference and the roads are not in a world frame; give a "
                  "georeferenced DEM (GeoTIFF, ...), or --origin X,Y with 'frame world' roads, or use --window X,Y,W,H "
                  "in output pixels", dem_path);
        return 1;
    }
    if (!(box[0] < box[2]) || !(box[1] < box[3])) {
        cli_error("--window-world: %.12g,%.12g,%.12g,%.12g is not XMIN,YMIN,XMAX,YMAX with XMIN < XMAX and "
                  "YMIN < YMAX", box[0], box[1], box[2], box[3]);
        return 1;
    }
    rs_dem_frame fr;
    rs_dem_get_frame(in->dem, &fr);
    uint32_t T = texels ? texels : 1;
    double px = fr.cell_size / T;
    /* the texture spans x X0 .. X0 + fw px, y Y0 - fh px .. Y0 (y north) */
    double mx1 = X0 + fw * px, my0 = Y0 - fh * px;
    double a = floor_px((box[0] - X0) / px), b = ceil_px((box[2] - X0) / px);
    double c = floor_px((Y0 - box[3]) / px), d = ceil_px((Y0 - box[1]) / px);
    if (a < 0 || c < 0 || b > fw || d > fh) {
        cli_error("--window-world: %.12g,%.12g,%.12g,%.12g is not inside the map (%s): it spans x %.12g..%.12g, "
                  "y %.12g..%.12g (y north%s%s)", box[0], box[1], box[2], box[3], dem_path, X0, mx1, my0, Y0,
                  in->geo.crs && strlen(in->geo.crs) < 24 ? ", " : "",
                  in->geo.crs && strlen(in->geo.crs) < 24 ? in->geo.crs : "");
        return 1;
    }
    if (b <= a) b = a + 1; /* a box thinner than a pixel: the pixel it is in */
    if (d <= c) d = c + 1;
    if (b > fw) a = fw - 1, b = fw;
    if (d > fh) c = fh - 1, d = fh;
    win[0] = (uint32_t)a;
    win[1] = (uint32_t)c;
    win[2] = (uint32_t)(b - a);
    win[3] = (uint32_t)(d - c);
    return 0;
}

/* ---- roadsplat convert -------------------------------------------------------------- */

static const char convert_usage[] =
    "Usage: roadsplat convert [options] ROADS_IN ROADS_OUT.txt\n"
    "\n"
    "Reads LineString / MultiLineString features of any GDAL vector source (GeoJSON,\n"
    "GeoPackage, Shapefile, OSM .osm/.pbf, FlatGeobuf, ...) and writes them as road text\n"
    "(docs/road-format.md) with a 'frame world CRS' line, mapping highway, lanes, width,\n"
    "name, oneway and turn:lanes to road attributes, and OSM zebra crossing nodes\n"
    "(highway=crossing with crossing=zebra or crossing:markings=zebra) to\n"
    "'X Y crossing=zebra' points of the roads through them (docs/gis.md).\n"
    "\n"
    "Options:\n"
    "  --dem DEM        reproject to the DEM's coordinate system\n"
    "  --t-srs CRS      reproject to CRS (EPSG:32632, a WKT, a PROJ string)\n"
    "                   (default: the source's CRS; the UTM zone of the roads'\n"
    "                   centre when that is in degrees)\n"
    "  --layer NAME     the layer to read (default: the first line layer; OSM: lines)\n"
    "  --where SQL      only features matching this attribute filter\n"
    "  --gdal-trust     open ROADS_IN and --dem with every GDAL driver and network\n"
    "                   access (URLs, VRTs naming any file); default: local files\n"
    "                   of an allow-list of formats (docs/ROBUSTNESS.md)\n"
    "  --help           show this help and exit\n";

int cli_convert_main(int argc, char **argv)
{
    const char *pos[2], *dem = NULL, *tsrs = NULL;
    int npos = 0;
    cli_splat_args s;
    memset(&s, 0, sizeof s);
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (arg[0] != '-' || arg[1] == '\0') {
            if (npos == 2) {
                cli_error("convert: unexpected argument '%s' (see roadsplat convert --help)", arg);
                return 1;
            }
            pos[npos++] = arg;
            continue;
        }
        char name[CLI_OPT_NAME];
        const char *inl = cli_option_split(arg, name), *v;
        if (!strcmp(name, "--help") || !strcmp(name, "-h")) {
            fputs(convert_usage, stdout);
            return 0;
        }
        if (!strcmp(name, "--gdal-trust")) {
            if (inl) {
                cli_error("%s takes no value", name);
                return 1;
            }
            cli_gdal_set_trust(1);
            continue;
        }
        if (!strcmp(name, "--dem") || !strcmp(name, "--t-srs") || !strcmp(name, "--layer") ||
            !strcmp(name, "--where")) {
            if (cli_option_value(argc, argv, &i, name, inl, &v)) return 1;
            if (name[2] == 'd') dem = v;
            else if (name[2] == 't') tsrs = v;
            else if (name[2] == 'l') s.layer = v;
            else s.where = v;
        } else {
            cli_error("convert: unknown option '%s' (see roadsplat convert --help)", arg);
            return 1;
        }
    }
    if (npos != 2) {
        cli_error("convert: expected ROADS_IN ROADS_OUT.txt, got %d argument%s (see roadsplat convert --help)", npos,
                  npos == 1 ? "" : "s");
        return 1;
    }
    if (dem && tsrs) {
        cli_error("convert: give --dem or --t-srs, not both");
        return 1;
    }
    if (!cli_gdal_available()) { /* the stand-in says why */
        cli_gdal_roads_opts o0;
        char *t;
        size_t n;
        memset(&o0, 0, sizeof o0);
        o0.shown = pos[0];
        cli_gdal_roads_text(pos[0], &o0, &t, &n);
        return 1;
    }
    const cli_file_role outs[1] = { { pos[1], "ROADS_OUT" } };
    const cli_file_role ins[2] = { { pos[0], "ROADS_IN" }, { dem, "--dem" } };
    if (cli_check_outputs(outs, 1, ins, 2)) return 1;
    cli_geo geo;
    memset(&geo, 0, sizeof geo);
    if (dem) {
        uint32_t w, h;
        float *z = NULL;
        size_t nd;
        cli_input din;
        int r = cli_gdal_input_open(&din, dem, 0);
        if (!r) {
            r = cli_gdal_read_dem_input(&din, "--dem", 0, &w, &h, &z, &nd, &geo);
            cli_input_close(&din);
        }
        free(z);
        if (r == 2 || (r == 0 && !geo.crs)) {
            cli_error("%s: --dem: the DEM has no coordinate system", dem);
            cli_geo_free(&geo);
            return 1;
        }
        if (r) {
            cli_geo_free(&geo);
            return 1;
        }
        tsrs = geo.crs;
    }
    cli_gdal_roads_opts o;
    memset(&o, 0, sizeof o);
    o.layer = s.layer;
    o.where = s.where;
    o.dst_crs = tsrs;
    o.shown = pos[0];
    char *text = NULL;
    size_t size = 0;
    int rc = 1;
    cli_input rin;
    if (cli_gdal_input_open(&rin, pos[0], 1)) goto done;
    int rr = cli_gdal_roads_text_input(&rin, "ROADS_IN", &o, &text, &size);
    cli_input_close(&rin);
    if (rr) goto done;
    /* what was written reads back: a check of the converter, and of the CRS line */
    rs_ctx *ctx = NULL;
    rs_roads *roads = NULL;
    if (rs_ctx_create(NULL, NULL, &ctx) == RS_OK) {
        rs_result r = rs_roads_parse(ctx, text, size, &roads);
        if (r) cli_error("%s: the converted roads do not parse: %s", pos[0], rs_ctx_message(ctx));
        rs_roads_free(ctx, roads);
        rs_ctx_free(ctx);
        if (r) goto done;
    }
    if (cli_out_write_file(pos[1], text, size)) goto done;
    rc = 0;
done:
    free(text);
    cli_geo_free(&geo);
    return rc;
}
