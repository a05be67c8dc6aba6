/* roadsplat: the command-line tool. `roadsplat [options] DEM ROADS OUT.png`
 * splats roads into a terrain texture; `roadsplat mesh ...` meshes a DEM. */
#include "bigalloc.h"
#include "png.h"
#include "gis.h"
#include "tiles.h"
#include "odr.h"

#include <errno.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

static const char usage_text[] =
    "Usage: roadsplat [options] DEM ROADS OUT.png|OUT.tif\n"
    "       roadsplat mesh [options] DEM OUT.obj|OUT.ply   (see roadsplat mesh --help)\n"
    "       roadsplat convert [options] ROADS_IN ROADS.txt (GIS roads to road text; needs GDAL)\n"
    "       roadsplat render [options] DEM ROADS OUT.png  (see roadsplat render --help; needs OSMesa)\n"
    "       roadsplat tiles [options] DEM ROADS OUTDIR  (tile pyramid; see roadsplat tiles --help)\n"
    "\n"
    "Burns the roads of ROADS (text, docs/road-format.md) into a terrain texture\n"
    "of the height map DEM (PGM, PNG or TIFF) and writes it to OUT.png: (W-1)*T x\n"
    "(H-1)*T pixels for a W x H DEM and T texels per cell.\n"
    "With GDAL (docs/gis.md): DEM may be any georeferenced raster (GeoTIFF, VRT,\n"
    "ASCII grid, .hgt, ...), whose cell size, origin, CRS and nodata are used;\n"
    "ROADS may be any OGR source (GeoJSON, GeoPackage, Shapefile, OSM, ...),\n"
    "reprojected to the DEM's CRS; OUT.tif is a georeferenced GeoTIFF.\n"
    "\n"
    "Options:\n"
    "  --cell-size M         DEM cell size in metres (default 1)\n"
    "  --z-scale S           metres per DEM unit (default 1)\n"
    "  --texels N            output texels per DEM cell side (default 8; 1 m pixels\n"
    "                        on cells over 8 m); or --pixel-size M\n"
    "  --edges MODE          road edges: 'analytic' (default; the exact area of each\n"
    "                        pixel inside the road buffers) or 'alphamap' (seed 000's\n"
    "                        table; the options marked * apply to it only)\n"
    "* --buffer MODE         road cells by 'distance' (default) or 'dilate' (the paper)\n"
    "* --road-cell M         road-grid cell size in metres (default: automatic)\n"
    "* --alpha-res N         alpha-map resolution (default 32)\n"
    "* --transition PX       transition band in alpha-map pixels (default 2, 0 = hard)\n"
    "* --jitter SEED         irregular road edges: seeded jitter in the band\n"
    "  --terrain-texture IMG tile IMG over the terrain (default: tint + hillshade)\n"
    "  --road-texture IMG    tile IMG over the roads (default: procedural asphalt)\n"
    "  --texture-scale M     metres per texture repeat (default 10)\n"
    "  --styles FILE         style blocks (docs/road-format.md) for style= and\n"
    "                        per-class overrides; the road file may hold some too\n"
    "  --profile rms|us      built-in road styles and lane widths: German RMS\n"
    "                        (default) or US MUTCD markings\n"
    "  --driving-side left|right  traffic side for roads without driving_side=\n"
    "                        (default right): lanes, arrows, stop lines mirrored\n"
    "  --aa exact|hermite    line anti-aliasing: exact pixel area (default) or the\n"
    "                        seed's Hermite smoothing\n"
    "  --no-styles           draw every road unstyled (no casings, fills or lines)\n"
    "  --atlas IMG --atlas-index FILE  road-marking atlas (RGBA image) and its index\n"
    "                        (docs/markings.md; default: the built-in atlas)\n"
    "  --no-auto-markings    only the road file's `mark` lines (no automatic\n"
    "                        stop lines, arrows, zebras)\n"
    "  --no-markings         no road markings at all\n"
    "  --max-field-work N    budget of the road index build for segments crowding\n"
    "                        one place (default 2^30 steps; docs/ROBUSTNESS.md)\n"
    "  --max-atlas-mb N      budget of the marking atlas's mip levels (default 256)\n"
    "  --origin X,Y          world coordinates of DEM sample (0,0); road points are\n"
    "                        in that world frame (e.g. UTM metres; default 0,0)\n"
    "  --window X,Y,W,H      render only that rectangle of the output (pixels)\n"
    "  --window-world XMIN,YMIN,XMAX,YMAX  the same in world units (y north), for\n"
    "                        a georeferenced DEM or world roads; snapped outwards\n"
    "                        to whole output pixels\n"
    "  --layer NAME          GIS roads: the layer to read (default: the first line\n"
    "                        layer; OSM: lines)\n"
    "  --where SQL           GIS roads: only features matching this filter\n"
    "  --strict              no road touching the map is an error (default: a warning)\n"
    "  --world-file          also write OUT's world file (.pgw, .tfw), .prj and\n"
    "                        (PNG) OUT.aux.xml\n";
/* two strings: C99 compilers need only take 4095 characters in one */
static const char usage_text2[] =
    "  --max-linesym-mb N    budget of all roads' line symbols (lines, dashes;\n"
    "                        default 4096)\n"    "  --gdal-trust          open DEM and ROADS with every GDAL driver (VRTs naming\n"
    "                        any file, URLs, network access); default: local files\n"
    "                        of an allow-list of formats only (docs/ROBUSTNESS.md)\n"
    "  --max-image-pixels N  decoded-image budget: the pixels all textures, the atlas\n"
    "                        and surface images may hold together (default 134217728\n"
    "                        = 512 MiB as RGBA; 0: no budget)\n"
    "  --cog                 OUT.tif as a Cloud Optimized GeoTIFF (with overviews)\n"
    "  --pixel-size M        metres per output pixel (sets --texels: the cell size / M,\n"
    "                        rounded); one image is at most 2^28 pixels: --window-world\n"
    "                        renders part of a finer virtual image\n"
    "  --color-relief FILE   terrain tint by absolute height: gdaldem color-relief's\n"
    "                        'HEIGHT R G B' lines, metres (default: a fixed ramp,\n"
    "                        0 m green to 3500 m white)\n"
    "  --threads N           worker threads (default: all cores; same output for any N)\n"
    "  --weight-out FILE     write the road weight R = 1 - alpha, 16-bit: .pgm (or no\n"
    "                        extension), .png or .tif (GeoTIFF)\n"
    "  --normal-out FILE.png write the tangent-space normal map of the same pixels\n"
    "                        (RGB8; docs/normals.md)\n"
    "  --normal-convention gl|dx  green = north/image up (gl, default) or down (dx)\n"
    "  --normal-strength S   road-texture relief: slope per luminance step (default 1)\n"
    "  --lighting            light the colour by the sun with the normal map (Lambert;\n"
    "                        replaces the terrain hillshade; flat ground unchanged;\n"
    "                        docs/surface.md)\n"
    "  --sun AZ,ALT          sun azimuth (compass degrees) and altitude for --lighting\n"
    "                        (default 315,45, the hillshade's)\n"
    "  --specular K          --lighting: wet-looking asphalt, a specular share 0..1\n"
    "                        on roads (default 0)\n"
    "  --rgba                OUT.png with an alpha channel even when every pixel is\n"
    "                        opaque (default: RGB then; RGBA with GIS nodata)\n"
    "  --png-level N         PNG compression, 0 (none) .. 12 (smallest, slowest);\n"
    "                        default 1, about 17 % larger than zlib's level 6\n"
    "  --stats FILE.json     write timings and counts as JSON\n"
    "  --quiet               no progress bar\n"
    "  --help                show this help and exit\n"
    "  --version             show the version and exit\n";

typedef struct args {
    cli_splat_args s;
    const char *dem, *roads, *out;
    const char *weight_out, *stats, *normal_out;
    rs_normal_options normal;
    int normal_given; /* --normal-convention or --normal-strength */
    int conv_given;   /* --normal-convention */
    int quiet, have_window, have_window_world, world_file, cog, rgba;
    uint32_t window[4];
    double window_world[4]; /* XMIN, YMIN, XMAX, YMAX */
} args;

/* Four comma-separated numbers into d: whole numbers below 2^32
 * (`whole`), else finite numbers within 1e12; `form` names them in the
 * message. */
static int parse_four(const char *name, const char *v, const char *form, int whole, double d[4])
{
    const char *p = v;
    for (int k = 0; k < 4; k++) {
        const char *e = strchr(p, ',');
        size_t len = k < 3 ? (e ? (size_t)(e - p) : 0) : strlen(p);
        char buf[64];
        if ((k < 3 && !e) || len == 0 || len >= sizeof buf) {
            cli_error("%s: '%s' is not %s", name, v, form);
            return 1;
        }
        memcpy(buf, p, len);
        buf[len] = '\0';
        if (whole) {
            uint32_t u;
            if (cli_parse_u32(name, buf, &u)) return 1;
            d[k] = u;
        } else {
            if (cli_parse_double(name, buf, &d[k])) return 1;
            if (!(d[k] >= -1e12 && d[k] <= 1e12)) {
                cli_error("%s: '%s' must be within 1e12 on each axis", name, v);
                return 1;
            }
        }
        p = e ? e + 1 : p + len;
    }
    return 0;
}

/* "X,Y,W,H": whole numbers, W and H >= 1, all below 2^32. */
static int parse_window(const char *name, const char *v, double d[4])
{
    if (parse_four(name, v, "X,Y,W,H", 1, d)) return 1;
    if (d[2] < 1 || d[3] < 1) {
        cli_error("%s: '%s': width and height must be >= 1", name, v);
        return 1;
    }
    return 0;
}

/* "XMIN,YMIN,XMAX,YMAX": four finite numbers. */
static int parse_box(const char *name, const char *v, double d[4])
{
    return parse_four(name, v, "XMIN,YMIN,XMAX,YMAX (world units, y north)", 0, d);
}

/* Returns 0 to run, 1 on a usage error, 2 when --help/--version was handled. */
static int parse_args(int argc, char **argv, args *a)
{
    const char *pos[3];
    int npos = 0, only_pos = 0;
    memset(a, 0, sizeof *a);
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (only_pos || arg[0] != '-' || arg[1] == '\0') {
            if (npos == 3) {
                cli_error("unexpected argument '%s' (see roadsplat --help)", arg);
                return 1;
            }
            pos[npos++] = arg;
            continue;
        }
        if (!strcmp(arg, "--")) { only_pos = 1; continue; }
        char name[CLI_OPT_NAME];
        const char *inl = cli_option_split(arg, name);
        if (!strcmp(name, "--help") || !strcmp(name, "-h")) {
            fputs(usage_text, stdout);
            fputs(usage_text2, stdout);
            return 2;
        } else if (!strcmp(name, "--version")) {
            printf("roadsplat %s\n", rs_version_string());
            return 2;
        } else if (!strcmp(name, "--quiet") || !strcmp(name, "-q")) {
            a->quiet = 1;
            continue;
        } else if (!strcmp(name, "--world-file") || !strcmp(name, "--cog") || !strcmp(name, "--rgba")) {
            if (inl) { cli_error("%s takes no value", name); return 1; }
            if (name[2] == 'w') a->world_file = 1;
            else if (name[2] == 'c') a->cog = 1;
            else a->rgba = 1;
            continue;
        }
        int sr = cli_splat_option(argc, argv, &i, name, inl, &a->s);
        if (sr < 0) sr = cli_lighting_option(argc, argv, &i, name, inl, &a->s);
        if (sr > 0) return 1;
        if (sr == 0) continue;
        if (!strcmp(name, "--weight-out")) {
            if (cli_option_value(argc, argv, &i, name, inl, &a->weight_out)) return 1;
        } else if (!strcmp(name, "--normal-out")) {
            if (cli_option_value(argc, argv, &i, name, inl, &a->normal_out) || cli_normal_png_check(a->normal_out))
                return 1;
        } else if (!strcmp(name, "--normal-convention")) {
            const char *v;
            if (cli_option_value(argc, argv, &i, name, inl, &v)) return 1;
            if (strcmp(v, "gl") && strcmp(v, "dx")) {
                cli_error("%s: '%s' is not gl or dx", name, v);
                return 1;
            }
            a->normal.directx = v[0] == 'd';
            a->normal_given = a->conv_given = 1;
        } else if (!strcmp(name, "--normal-strength")) {
            const char *v;
            if (cli_option_value(argc, argv, &i, name, inl, &v) || cli_parse_double(name, v, &a->normal.strength))
                return 1;
            if (!(a->normal.strength > 0 && a->normal.strength <= 1e6)) {
                cli_error("%s: '%s' must be in (0, 1e6]", name, v);
                return 1;
            }
            a->normal_given = 1;
        } else if (!strcmp(name, "--stats")) {
            if (cli_option_value(argc, argv, &i, name, inl, &a->stats)) return 1;
        } else if (!strcmp(name, "--window")) {
            const char *v;
            double d[4];
            if (cli_option_value(argc, argv, &i, name, inl, &v) || parse_window(name, v, d)) return 1;
            for (int k = 0; k < 4; k++) a->window[k] = (uint32_t)d[k];
            a->have_window = 1;
        } else if (!strcmp(name, "--window-world")) {
            const char *v;
            if (cli_option_value(argc, argv, &i, name, inl, &v) || parse_box(name, v, a->window_world)) return 1;
            a->have_window_world = 1;
        } else {
            cli_error("unknown option '%s' (see roadsplat --help)", arg);
            return 1;
        }
    }
    if (a->normal_given && !a->normal_out && (a->conv_given || !a->s.o.lighting.enable)) {
        cli_error("--normal-convention and --normal-strength need --normal-out (--normal-strength also serves "
                  "--lighting)");
        return 1;
    }
    if (cli_lighting_check(&a->s)) return 1;
    a->s.o.lighting.normal.strength = a->normal.strength;
    if (a->have_window && a->have_window_world) {
        cli_error("--window and --window-world are exclusive (output pixels or world units)");
        return 1;
    }
    if (npos != 3) {
        cli_error("expected DEM ROADS OUT.png, got %d argument%s (see roadsplat --help)", npos, npos == 1 ? "" : "s");
        return 1;
    }
    a->dem = pos[0];
    a->roads = pos[1];
    a->out = pos[2];
    return 0;
}

/* Outputs of one run (OUT, --weight-out, --stats): each is written into a
 * temporary sibling (cli_out_open, which also refuses a non-regular target)
 * opened before the work starts, and all are renamed over their targets
 * only once every one is complete. A failing side output therefore leaves
 * every old file untouched, and an unwritable target fails in milliseconds. */

/* Flush, check and close a temporary without renaming it. */
static int out_finish(cli_out *o) { return cli_out_finish(o); }

/* fsync in a second thread while the first re-reads the file. */
typedef struct sync_job {
    int fd, err;
} sync_job;

static void *sync_thread(void *arg)
{
    sync_job *j = arg;
    j->err = fsync(j->fd) != 0 && errno != EINVAL ? errno : 0;
    return NULL;
}

/* The PNG (written into o->f by cli_splat_png_run) is flushed, synced and
 * closed, and checked whole; the sync (waiting on the disk) and the check
 * (re-reading the page cache) run side by side. */
static int png_finish(cli_out *o)
{
    if (fflush(o->f) != 0 || ferror(o->f)) return out_finish(o); /* reports the error */
    sync_job j = { fileno(o->f), 0 };
    pthread_t t;
    int threaded = pthread_create(&t, NULL, sync_thread, &j) == 0;
    int whole = cli_png_file_complete(o->tmp);
    if (threaded) pthread_join(t, NULL);
    if (j.err) {
        cli_error("%s: write failed: %s", o->path, strerror(j.err));
        return 1;
    }
    if (out_finish(o)) return 1; /* fsyncs again when the thread could not start: cheap once synced */
    if (!whole) {
        cli_error("%s: write failed: the PNG did not reach the disk whole", o->path);
        return 1;
    }
    return 0;
}

static int weight_pgm_to_temp(cli_out *o, uint32_t w, uint32_t h, const uint16_t *wt)
{
    int ok = fprintf(o->f, "P5\n%u %u\n65535\n", w, h) > 0;
    uint8_t *row = malloc((size_t)w * 2);
    if (!row) ok = 0;
    for (uint32_t y = 0; ok && y < h; y++) {
        for (uint32_t x = 0; x < w; x++) {
            uint16_t v = wt[(size_t)y * w + x];
            row[2 * x] = (uint8_t)(v >> 8);
            row[2 * x + 1] = (uint8_t)(v & 0xFF);
        }
        ok = fwrite(row, 1, (size_t)w * 2, o->f) == (size_t)w * 2;
    }
    int e = errno;
    free(row);
    if (!ok) {
        cli_error("%s: write failed: %s", o->path, strerror(e ? e : EIO));
        return 1;
    }
    return out_finish(o);
}

typedef struct run_stats {
    double startup;              /* before the work began (cli_startup_ms) */
    double t[5];                 /* read, roads, splat, write, total (see splat_main) */
    cli_png_run_stats png;
    const rs_road_grid_stats *gs;
    const rs_splat_options *o;
    uint32_t w, h, x0, y0, full_w, full_h;
    const cli_splat_job *job;
    const cli_gdal_road_counts *src; /* a GIS road source's counts (src->set 0: road text) */
    double pixel_m;                  /* metres per output pixel */
} run_stats;

static int stats_to_temp(cli_out *o, const run_stats *rs)
{
    const double *t = rs->t;
    const rs_road_grid_stats *gs = rs->gs;
    const rs_splat_profile *pf = &rs->job->profile;
    char src[768] = "";
    if (rs->src && rs->src->set) {
        const cli_gdal_road_counts *c = rs->src;
        snprintf(src, sizeof src,
                 "  \"roads_source\": {\"features\": %zu, \"roads\": %zu, \"skipped_no_highway\": %zu, "
                 "\"skipped_not_road\": %zu, \"skipped_tunnel\": %zu, \"skipped_not_lines\": %zu, "
                 "\"skipped_not_reprojected\": %zu, "
                 "\"crossings\": {\"zebra_nodes\": %zu, \"zebra_points\": %zu, \"traffic_signals\": %zu, "
                 "\"unmarked\": %zu}},\n",
                 c->features, c->roads, c->no_highway, c->not_roads, c->tunnels, c->not_lines, c->not_reprojected,
                 c->zebra_nodes, c->zebra_points, c->signal_nodes, c->unmarked_nodes);
    }
    if (fprintf(o->f, "{\n%s  \"pixel_size_m\": %.9g,\n", src, rs->pixel_m) < 0) {
        cli_error("%s: write failed: %s", o->path, strerror(errno ? errno : EIO));
        return 1;
    }
    int ok = fprintf(o->f,
                     "  \"timings_ms\": {\"startup\": %.3f, \"read\": %.3f, \"roads\": %.3f, \"splat\": %.3f, "
                     "\"write\": %.3f, \"total\": %.3f},\n"
                     "  \"stages_ms\": {\"coverage\": %.3f, \"surface\": %.3f, \"overlays\": %.3f, "
                     "\"composite\": %.3f},\n"
                     "  \"splat_write_ms\": {\"wall\": %.3f, \"splat_cpu\": %.3f, \"png_cpu\": %.3f, \"file\": %.3f, "
                     "\"splat_done\": %.3f},\n"
                     "  \"png_pieces_joined\": {\"stored\": %llu, \"end_of_block\": %llu, \"inflate\": %llu, "
                     "\"isal_bands\": %llu},\n"
                     "  \"threads\": %u,\n"
                     "  \"edges\": \"%s\",\n  \"buffer\": \"%s\",\n  \"k\": %u,\n  \"road_cell_m\": %.9g,\n  \"texels\": %u,\n"
                     "  \"window\": {\"x\": %u, \"y\": %u, \"width\": %u, \"height\": %u},\n"
                     "  \"image\": {\"width\": %u, \"height\": %u},\n"
                     "  \"width\": %u,\n  \"height\": %u,\n  \"pixels\": %llu,\n  \"road_pixels\": %llu,\n"
                     "  \"segments\": %llu,\n"
                     "  \"markings\": {\"explicit\": %llu, \"auto\": %llu, \"tests\": %llu, \"pixels\": %llu},\n"
                     "  \"road_cells\": %llu,\n  \"interior_cells\": %llu,\n  \"boundary_cells\": %llu,\n"
                     "  \"boundary_by_type\": {\"edge\": %llu, \"inner_corner\": %llu, \"outer_corner\": %llu, "
                     "\"saddle\": %llu, \"too_thin\": %llu},\n"
                     "  \"grid_tiles\": %llu,\n  \"grid_bytes\": %llu\n}\n",
                     rs->startup, t[0], t[1], t[2], t[3], t[4], pf->coverage_ms, pf->surface_ms, pf->overlays_ms, pf->composite_ms,
                     rs->png.wall_ms, rs->png.splat_cpu_ms, rs->png.png_cpu_ms, rs->png.file_ms, rs->png.splat_done_ms,
                     (unsigned long long)rs->png.joins[0], (unsigned long long)rs->png.joins[1],
                     (unsigned long long)rs->png.joins[2], (unsigned long long)rs->png.joins[3],
                     rs->job->threads_used, rs->o->coverage.edges == RS_EDGES_ANALYTIC ? "analytic" : "alphamap",
                     rs->o->grid.buffer == RS_BUFFER_DILATE ? "dilate" : "distance", gs->k, gs->road_cell,
                     rs->o->texels ? rs->o->texels : 8, rs->x0, rs->y0, rs->w, rs->h, rs->full_w, rs->full_h, rs->w,
                     rs->h, (unsigned long long)rs->w * rs->h, (unsigned long long)pf->road_pixels,
                     (unsigned long long)gs->segments, (unsigned long long)gs->marks_explicit,
                     (unsigned long long)gs->marks_auto, (unsigned long long)pf->mark_tests,
                     (unsigned long long)pf->mark_pixels, (unsigned long long)gs->road_cells,
                     (unsigned long long)gs->interior_cells, (unsigned long long)gs->boundary_cells,
                     (unsigned long long)gs->by_type[RS_TILE_EDGE], (unsigned long long)gs->by_type[RS_TILE_INNER],
                     (unsigned long long)gs->by_type[RS_TILE_OUTER], (unsigned long long)gs->by_type[RS_TILE_SADDLE],
                     (unsigned long long)gs->by_type[RS_TILE_TERRAIN], (unsigned long long)gs->tiles_allocated,
                     (unsigned long long)gs->bytes) > 0;
    if (!ok) {
        cli_error("%s: write failed: %s", o->path, strerror(errno ? errno : EIO));
        return 1;
    }
    return out_finish(o);
}

static int splat_main(int argc, char **argv)
{
    args a;
    int pr = parse_args(argc, argv, &a);
    if (pr) return pr == 2 ? 0 : 1;
    a.s.auto_pixel = 1; /* 1 m pixels by default on coarse DEMs (docs/gis.md "Pixel size") */

    double t_start = cli_now_ms(), startup = cli_startup_ms();
    int rc = 1;
    rs_ctx *ctx = NULL;
    cli_splat_input in;
    rs_splatter *sp = NULL;
    rs_road_grid *grid = NULL;
    uint16_t *wt = NULL;
    rs_splat_options *o = &a.s.o;
    cli_out out_png, out_wt, out_stats, out_wf, out_prj, out_nm, out_aux;
    char *wf_path = NULL, *prj_path = NULL, *aux_path = NULL;
    uint8_t *rgba = NULL;
    run_stats st;
    cli_splat_job job;
    memset(&st, 0, sizeof st);
    memset(&job, 0, sizeof job);
    memset(&in, 0, sizeof in);
    memset(&out_png, 0, sizeof out_png);
    memset(&out_wt, 0, sizeof out_wt);
    memset(&out_stats, 0, sizeof out_stats);
    memset(&out_wf, 0, sizeof out_wf);
    memset(&out_prj, 0, sizeof out_prj);
    memset(&out_aux, 0, sizeof out_aux);
    memset(&out_nm, 0, sizeof out_nm);
    size_t ol = strlen(a.out);
    int tif_name = (ol > 4 && !strcasecmp(a.out + ol - 4, ".tif")) || (ol > 5 && !strcasecmp(a.out + ol - 5, ".tiff"));
    if (a.world_file) { /* OUT's name with .pgw / .tfw and .prj for its extension */
        size_t n = strlen(a.out), e = n;
        const char *slash = strrchr(a.out, '/'), *dot = strrchr(a.out, '.');
        if (dot && (!slash || dot > slash + 1) && dot != a.out) e = (size_t)(dot - a.out);
        wf_path = malloc(e + 5);
        prj_path = malloc(e + 5);
        aux_path = tif_name ? NULL : malloc(n + 9); /* GDAL reads a PNG's CRS from OUT.aux.xml, not the .prj */
        if (!wf_path || !prj_path || (!tif_name && !aux_path)) {
            free(wf_path);
            free(prj_path);
            free(aux_path);
            cli_error("out of memory");
            return 1;
        }
        memcpy(wf_path, a.out, e);
        memcpy(prj_path, a.out, e);
        strcpy(wf_path + e, tif_name ? ".tfw" : ".pgw");
        strcpy(prj_path + e, ".prj");
        if (aux_path) sprintf(aux_path, "%s.aux.xml", a.out);
    }
    /* Every output is checked and opened before any work. */
    const cli_file_role outs[7] = { { a.out, "OUT" }, { a.weight_out, "--weight-out" }, { a.stats, "--stats" },
                                    { wf_path, "the world file" }, { prj_path, "the .prj" },
                                    { a.normal_out, "--normal-out" }, { aux_path, "the .aux.xml" } };
    const cli_file_role ins[4] = { { a.dem, "DEM" }, { a.roads, "ROADS" }, { a.s.terrain_tex, "--terrain-texture" },
                                   { a.s.road_tex, "--road-texture" } };
    /* Output formats follow the extensions (docs/gis.md). */
    int fmt = 0, wfmt = 0;
    if (cli_check_outputs(outs, 7, ins, 4) || (fmt = cli_out_format(a.out, "OUT", 0)) < 0 ||
        (a.weight_out && (wfmt = cli_out_format(a.weight_out, "--weight-out", 1)) < 0) ||
        (a.cog && fmt != CLI_FMT_TIF && (cli_error("--cog: OUT %s is not a .tif", a.out), 1)) ||
        (!cli_gdal_available() && (fmt == CLI_FMT_TIF || wfmt == CLI_FMT_TIF) &&
         (cli_gdal_write_tiff(NULL, fmt == CLI_FMT_TIF ? a.out : a.weight_out, 0, 0, 0, 0, NULL, NULL, NULL, 0), 1))) {
        free(wf_path);
        free(prj_path);
        free(aux_path);
        return 1;
    }
    /* Huge pages for the DEM, its filled copy and the road index: their
     * first touch in 4 KiB pages was most of the read stage (cli/bigalloc.c) */
    cli_bigalloc *ba = cli_bigalloc_create(0);
    rs_allocator hook;
    memset(&hook, 0, sizeof hook);
    if (ba) hook = cli_bigalloc_hook(ba);
    /* no library limit on the virtual image: the limit is the window's
     * (CLI_MAX_IMAGE_PIXELS, below), so a close-up of a big map works */
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    cli_splat_limits(&a.s, &lim);
    lim.max_pixels = (uint64_t)1 << 52;
    rs_result r = rs_ctx_create(ba ? &hook : NULL, &lim, &ctx);
    if (r) { cli_bigalloc_destroy(ba); cli_error("%s", rs_strerror(r)); free(wf_path); free(prj_path); free(aux_path); return 1; }
    if (cli_out_open(&out_png, a.out) || (a.weight_out && cli_out_open(&out_wt, a.weight_out)) ||
        (a.stats && cli_out_open(&out_stats, a.stats)) || (wf_path && cli_out_open(&out_wf, wf_path)) ||
        (prj_path && cli_out_open(&out_prj, prj_path)) || (a.normal_out && cli_out_open(&out_nm, a.normal_out)) ||
        (aux_path && cli_out_open(&out_aux, aux_path)))
        goto done;
    if (cli_splat_input_load(ctx, a.dem, a.roads, &a.s, &in)) goto done;
    /* now every input is known (the styles' surface images, the atlas...):
     * no output may replace one (checked again at the renames) */
    for (size_t k = 0; k < 6; k++)
        if (cli_inputs_check_output(outs[k].path, outs[k].role)) goto done;
    if (a.world_file && !in.world) {
        cli_error("--world-file: %s", in.geo.georef ? "the roads are not in the DEM's world frame ('frame world' or GIS roads)"
                                                    : "the DEM has no georeference; give --origin X,Y with roads in "
                                                      "'frame world' (x east, y north)");
        goto done;
    }
    const rs_dem *dem = in.dem;
    st.t[0] = cli_now_ms() - t_start;

    uint32_t fw, fh;
    if ((r = rs_splat_size(ctx, dem, o, &fw, &fh))) {
        cli_error("%s: %s", a.dem, rs_ctx_message(ctx));
        goto done;
    }
    uint32_t x0 = 0, y0 = 0, w = fw, h = fh;
    if (a.have_window) {
        x0 = a.window[0], y0 = a.window[1], w = a.window[2], h = a.window[3];
        if (x0 >= fw || y0 >= fh || w > fw - x0 || h > fh - y0) {
            cli_error("--window: %u,%u,%u,%u is not inside the %u x %u output", x0, y0, w, h, fw, fh);
            goto done;
        }
    } else if (a.have_window_world) {
        uint32_t win[4];
        if (cli_geo_window(&in, a.dem, o->texels ? o->texels : 8, fw, fh, a.window_world, win)) goto done;
        x0 = win[0], y0 = win[1], w = win[2], h = win[3];
    }
    if ((uint64_t)w * h > CLI_MAX_IMAGE_PIXELS) {
        rs_dem_frame dfr;
        rs_dem_get_frame(dem, &dfr);
        cli_error("%s: the %s of %u x %u pixels of %.6g m exceeds the limit of %llu (2^28) pixels of one image: render a part "
                  "with --window-world XMIN,YMIN,XMAX,YMAX (or --window), choose coarser pixels with --pixel-size, "
                  "or write tiles of any size with 'roadsplat tiles'", a.dem, a.have_window || a.have_window_world ?
                  "window" : "output", w, h, dfr.cell_size / (o->texels ? o->texels : 8),
                  (unsigned long long)CLI_MAX_IMAGE_PIXELS);
        goto done;
    }
    if (a.s.pixel_note[0] && !a.quiet) fputs(a.s.pixel_note, stderr);
    if (!a.quiet) cli_geo_source_note(&in.source, a.roads);
    double t1 = cli_now_ms();
    if (cli_splatter_prepare(ctx, &in, a.roads, &a.s, a.quiet, &grid, &sp)) goto done;
    st.t[1] = cli_now_ms() - t1;

    /* The splat and the PNG run together (cli_splat_png_run): no image-sized
     * buffer, compression overlapping the splat. Their wall time is split
     * into "splat", the splat's time per thread (its CPU time summed over
     * the threads, divided by them: exact with one thread), and "write",
     * the rest: what writing OUT adds to the run, sync and check included. */
    t1 = cli_now_ms();
    if (a.weight_out && !(wt = malloc((size_t)w * h * sizeof *wt))) {
        cli_error("%s: out of memory for a %u x %u image", a.weight_out, w, h);
        goto done;
    }
    cli_splat_job_init(&job, sp, &a.s, a.quiet);
    job.x0 = x0, job.y0 = y0, job.w = w, job.h = h;
    job.weight = wt;
    job.nodata = in.nodata;
    job.alpha = a.rgba;
    job.dem_w = rs_dem_width(dem), job.dem_h = rs_dem_height(dem);
    double gt[6];
    int have_gt = !cli_geo_texture_gt(&in, job.texels, x0, y0, gt);
    if (!have_gt && a.world_file) cli_geo_world_gt(&in, job.texels, x0, y0, gt); /* PGM with --origin */
    if (fmt == CLI_FMT_TIF) {
        /* the whole image, then GDAL's GeoTIFF writer into OUT's temporary */
        if (!(rgba = malloc((size_t)w * h * 4))) {
            cli_error("%s: out of memory for a %u x %u image", a.out, w, h);
            goto done;
        }
        job.rgba = rgba;
        if (cli_splat_run(&job)) goto done;
        st.t[2] = cli_now_ms() - t1;
        fclose(out_png.f);
        out_png.f = NULL;
        if (cli_gdal_write_tiff(out_png.tmp, a.out, w, h, 4, 8, rgba, have_gt ? gt : NULL,
                                have_gt ? in.geo.crs : NULL, a.cog))
            goto done;
    } else {
        if (cli_splat_png_run(&job, out_png.f, a.out, a.s.png_level_given ? a.s.png_level : -1, &st.png) ||
            png_finish(&out_png))
            goto done;
        st.t[2] = st.png.splat_cpu_ms / (job.threads_used ? job.threads_used : 1);
    }
    if (wt) {
        if (wfmt == CLI_FMT_PGM) {
            if (weight_pgm_to_temp(&out_wt, w, h, wt)) goto done;
        } else if (wfmt == CLI_FMT_PNG) {
            cli_png_image img = { w, h, 1, 16, wt };
            if (cli_png_encode(out_wt.f, a.weight_out, &img, NULL) || out_finish(&out_wt)) goto done;
        } else {
            fclose(out_wt.f);
            out_wt.f = NULL;
            if (cli_gdal_write_tiff(out_wt.tmp, a.weight_out, w, h, 1, 16, wt, have_gt ? gt : NULL,
                                    have_gt ? in.geo.crs : NULL, 0))
                goto done;
        }
    }
    if (a.normal_out && (cli_normal_png(sp, &a.normal, x0, y0, w, h, job.threads, a.s.png_level_given ? a.s.png_level : -1,
                                        out_nm.f, a.normal_out) ||
                         out_finish(&out_nm)))
        goto done;
    if (wf_path) { /* the world file: pixel size, rotations, then the centre of the first pixel */
        if (fprintf(out_wf.f, "%.17g\n0\n0\n%.17g\n%.17g\n%.17g\n", gt[1], gt[5], gt[0] + gt[1] / 2,
                    gt[3] + gt[5] / 2) < 0 || out_finish(&out_wf)) {
            cli_error("%s: write failed: %s", wf_path, strerror(errno ? errno : EIO));
            goto done;
        }
        if (in.geo.crs) {
            char *prj = cli_gdal_prj_text(in.geo.crs, prj_path);
            if (!prj) goto done;
            int bad = fprintf(out_prj.f, "%s\n", prj) < 0 || out_finish(&out_prj);
            free(prj);
            if (bad) {
                cli_error("%s: write failed: %s", prj_path, strerror(errno ? errno : EIO));
                goto done;
            }
        } else {
            cli_out_abort(&out_prj); /* no CRS: no .prj */
            memset(&out_prj, 0, sizeof out_prj);
        }
        if (aux_path && in.geo.crs) { /* GDAL's sidecar: the CRS as given, XML-escaped, and the geotransform */
            int bad = fputs("<PAMDataset>\n  <SRS>", out_aux.f) < 0;
            for (const char *c = in.geo.crs; *c && !bad; c++)
                bad = (*c == '<' ? fputs("&lt;", out_aux.f) : *c == '>' ? fputs("&gt;", out_aux.f)
                       : *c == '&' ? fputs("&amp;", out_aux.f) : fputc(*c, out_aux.f)) < 0;
            bad = bad || fprintf(out_aux.f, "</SRS>\n  <GeoTransform>%.17g, %.17g, 0, %.17g, 0, %.17g</GeoTransform>\n"
                                 "</PAMDataset>\n", gt[0], gt[1], gt[3], gt[5]) < 0 || out_finish(&out_aux);
            if (bad) {
                cli_error("%s: write failed: %s", aux_path, strerror(errno ? errno : EIO));
                goto done;
            }
        } else if (aux_path) {
            cli_out_abort(&out_aux);
            memset(&out_aux, 0, sizeof out_aux);
        }
    }
    st.t[3] = cli_now_ms() - t1 - st.t[2];
    st.t[4] = cli_now_ms() - t_start;
    if (a.stats) {
        rs_road_grid_stats gs;
        rs_road_grid_get_stats(rs_splatter_grid(sp), &gs);
        st.startup = startup;
        st.gs = &gs;
        st.o = o;
        st.w = w, st.h = h, st.x0 = x0, st.y0 = y0, st.full_w = fw, st.full_h = fh;
        st.job = &job;
        st.src = &in.source;
        rs_dem_frame dfr;
        rs_dem_get_frame(dem, &dfr);
        st.pixel_m = dfr.cell_size / (o->texels ? o->texels : 8);
        if (stats_to_temp(&out_stats, &st)) goto done;
    }
    cli_out *const all[7] = { &out_png, &out_wt, &out_stats, &out_wf, &out_prj, &out_nm, &out_aux };
    if (cli_out_commit_all(all, 7)) goto done;
    rc = 0;
done:
    cli_out_abort(&out_png); /* no-ops once renamed */
    cli_out_abort(&out_wt);
    cli_out_abort(&out_stats);
    cli_out_abort(&out_wf);
    cli_out_abort(&out_prj);
    cli_out_abort(&out_aux);
    cli_out_abort(&out_nm);
    free(wf_path);
    free(prj_path);
    free(aux_path);
    free(rgba);
    free(wt);
    rs_splatter_free(ctx, sp);
    rs_road_grid_free(ctx, grid);
    cli_splat_input_free(ctx, &in);
    rs_ctx_free(ctx);
    cli_bigalloc_destroy(ba);
    cli_inputs_clear();
    return rc;
}

int main(int argc, char **argv)
{
    cli_signals_install();
    if (argc > 1 && !strcmp(argv[1], "mesh")) return cli_mesh_main(argc - 1, argv + 1);
    if (argc > 1 && !strcmp(argv[1], "render")) return cli_render_main(argc - 1, argv + 1);
    if (argc > 1 && !strcmp(argv[1], "convert"))
        return cli_odr_convert_wants(argc - 1, argv + 1) ? cli_odr_convert_main(argc - 1, argv + 1)
                                                         : cli_convert_main(argc - 1, argv + 1);
    if (argc > 1 && !strcmp(argv[1], "tiles")) return cli_tiles_main(argc - 1, argv + 1);
    return splat_main(argc, argv);
}
