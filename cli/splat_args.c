/* Splat options and inputs shared by `roadsplat` and `roadsplat render`. */
#include "gis.h"
#include "odr.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

void cli_splat_limits(const cli_splat_args *s, rs_limits *lim)
{
    lim->max_field_work = s->max_field_work;
    lim->max_atlas_bytes = s->max_atlas_bytes;
    lim->max_linesym_bytes = s->max_linesym_bytes;
}

const char *cli_lib_message(const rs_ctx *ctx, rs_result r, char *buf, size_t cap)
{
    static const char *const budget[3][2] = { { "rs_limits.max_field_work", "--max-field-work N" },
                                             { "rs_limits.max_atlas_bytes", "--max-atlas-mb N" },
                                             { "rs_limits.max_linesym_bytes", "--max-linesym-mb N" } };
    const char *m = rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(r);
    for (int i = 0; i < 3; i++)
        if (strstr(m, budget[i][0])) {
            snprintf(buf, cap, "%s; %s raises it", m, budget[i][1]);
            return buf;
        }
    snprintf(buf, cap, "%s", m);
    return buf;
}

const char *cli_option_split(const char *arg, char name[CLI_OPT_NAME])
{
    const char *eq = strchr(arg, '=');
    size_t len = eq ? (size_t)(eq - arg) : strlen(arg);
    if (len >= CLI_OPT_NAME) len = CLI_OPT_NAME - 1;
    memcpy(name, arg, len);
    name[len] = '\0';
    return eq ? eq + 1 : NULL;
}

int cli_option_value(int argc, char **argv, int *i, const char *name, const char *inl, const char **val)
{
    if (inl) { *val = inl; return 0; }
    if (*i + 1 >= argc) {
        cli_error("option %s needs a value (see --help)", name);
        return 1;
    }
    *val = argv[++*i];
    return 0;
}

static int positive(const char *name, const char *v, double x)
{
    if (x > 0) return 0;
    cli_error("%s: '%s' must be > 0", name, v);
    return 1;
}

int cli_splat_option(int argc, char **argv, int *i, const char *name, const char *inl, cli_splat_args *s)
{
    static const char *const known[] = { "--cell-size", "--z-scale", "--texels", "--buffer", "--road-cell",
                                         "--alpha-res", "--transition", "--jitter", "--terrain-texture",
                                         "--road-texture", "--texture-scale", "--origin", "--edges", "--threads",
                                         "--png-level", "--styles", "--profile", "--aa", "--no-styles", "--atlas",
                                         "--atlas-index", "--no-auto-markings", "--no-markings", "--layer", "--where",
                                         "--strict", "--pixel-size", "--color-relief", "--max-field-work",
                                         "--max-atlas-mb", "--gdal-trust", "--max-image-pixels", "--driving-side",
                                         "--max-linesym-mb" };
    size_t k, n = sizeof known / sizeof known[0];
    for (k = 0; k < n && strcmp(name, known[k]); k++) {}
    if (k == n) return -1;
    rs_splat_options *o = &s->o;
    if (!strcmp(name, "--strict") || !strcmp(name, "--gdal-trust")) {
        if (inl) { cli_error("%s takes no value", name); return 1; }
        if (name[2] == 's') s->strict = 1;
        else cli_gdal_set_trust(1);
        return 0;
    }
    if (!strcmp(name, "--no-styles") || !strcmp(name, "--no-auto-markings") || !strcmp(name, "--no-markings")) {
        if (inl) { cli_error("%s takes no value", name); return 1; }
        if (name[5] == 's') o->style.disable = 1;
        else if (name[5] == 'a') o->markings.no_auto = 1;
        else o->markings.disable = 1;
        return 0;
    }
    const char *v;
    if (cli_option_value(argc, argv, i, name, inl, &v)) return 1;
    rs_dem_frame *fr = &s->frame;
    double d, xy[2];
    uint32_t u;
    if (!strcmp(name, "--max-field-work") || !strcmp(name, "--max-atlas-mb") || !strcmp(name, "--max-linesym-mb")) {
        /* budgets (docs/ROBUSTNESS.md, issue 26): whole numbers >= 1 */
        if (cli_parse_double(name, v, &d)) return 1;
        int mb = name[6] == 'a' || name[6] == 'l';
        double top = mb ? 1048576.0 : 1e15;
        if (!(d >= 1 && d <= top && d == floor(d))) {
            cli_error("%s: '%s' must be a whole number in [1, %.0f]", name, v, top);
            return 1;
        }
        if (name[6] == 'a') s->max_atlas_bytes = (uint64_t)d << 20;
        else if (name[6] == 'l') s->max_linesym_bytes = (uint64_t)d << 20;
        else s->max_field_work = (uint64_t)d;
    } else if (!strcmp(name, "--max-image-pixels")) {
        if (cli_parse_u32(name, v, &u)) return 1;
        cli_image_budget_set(u);
    } else if (!strcmp(name, "--layer")) {
        s->layer = v;
    } else if (!strcmp(name, "--where")) {
        s->where = v;
    } else if (!strcmp(name, "--cell-size")) {
        s->cell_size_given = 1;
        if (cli_parse_double(name, v, &fr->cell_size) || positive(name, v, fr->cell_size)) return 1;
        if (!(fr->cell_size >= 1e-9 && fr->cell_size <= 1e9)) {
            cli_error("%s: '%s' must be in [1e-9, 1e9] metres", name, v);
            return 1;
        }
    } else if (!strcmp(name, "--z-scale")) {
        if (cli_parse_double(name, v, &fr->z_scale)) return 1;
        if (!(fabs(fr->z_scale) >= 1e-12 && fabs(fr->z_scale) <= 1e12)) {
            cli_error("%s: '%s' must be in [1e-12, 1e12] in magnitude", name, v);
            return 1;
        }
    } else if (!strcmp(name, "--threads")) {
        if (cli_parse_u32(name, v, &u)) return 1;
        if (u < 1 || u > 256) { cli_error("%s: '%s' must be 1..256", name, v); return 1; }
        s->threads = u;
    } else if (!strcmp(name, "--edges")) {
        if (!strcmp(v, "alphamap")) o->coverage.edges = RS_EDGES_ALPHAMAP;
        else if (!strcmp(v, "analytic")) o->coverage.edges = RS_EDGES_ANALYTIC;
        else { cli_error("%s: '%s' is not 'alphamap' or 'analytic'", name, v); return 1; }
    } else if (!strcmp(name, "--pixel-size")) {
        if (cli_parse_double(name, v, &s->pixel_size) || positive(name, v, s->pixel_size)) return 1;
        if (!(s->pixel_size >= 1e-6 && s->pixel_size <= 1e9)) {
            cli_error("%s: '%s' must be in [1e-6, 1e9] metres", name, v);
            return 1;
        }
    } else if (!strcmp(name, "--color-relief")) {
        s->color_relief = v;
    } else if (!strcmp(name, "--texels")) {
        if (cli_parse_u32(name, v, &o->texels)) return 1;
        if (o->texels < 1 || o->texels > 1024) { cli_error("%s: '%s' must be 1..1024", name, v); return 1; }
    } else if (!strcmp(name, "--buffer")) {
        if (!strcmp(v, "distance")) o->grid.buffer = RS_BUFFER_DISTANCE;
        else if (!strcmp(v, "dilate")) o->grid.buffer = RS_BUFFER_DILATE;
        else { cli_error("%s: '%s' is not 'distance' or 'dilate'", name, v); return 1; }
    } else if (!strcmp(name, "--road-cell")) {
        if (cli_parse_double(name, v, &o->grid.road_cell) || positive(name, v, o->grid.road_cell)) return 1;
        if (o->grid.road_cell > 1e9) { cli_error("%s: '%s' must be at most 1e9 metres", name, v); return 1; }
    } else if (!strcmp(name, "--alpha-res")) {
        if (cli_parse_u32(name, v, &o->coverage.alpha_res)) return 1;
        if (o->coverage.alpha_res < 2 || o->coverage.alpha_res > 1024) { cli_error("%s: '%s' must be 2..1024", name, v); return 1; }
    } else if (!strcmp(name, "--transition")) {
        if (cli_parse_double(name, v, &d)) return 1;
        if (!(d >= 0 && d <= 512)) { cli_error("%s: '%s' must be in [0, 512]", name, v); return 1; }
        if (d == 0) o->coverage.hard_edge = 1;
        else o->coverage.transition_px = d;
    } else if (!strcmp(name, "--jitter")) {
        if (cli_parse_u32(name, v, &u)) return 1;
        o->coverage.jitter = 1;
        o->coverage.jitter_seed = u;
    } else if (!strcmp(name, "--terrain-texture")) {
        s->terrain_tex = v;
    } else if (!strcmp(name, "--road-texture")) {
        s->road_tex = v;
    } else if (!strcmp(name, "--texture-scale")) {
        if (cli_parse_double(name, v, &o->surface.texture_scale) || positive(name, v, o->surface.texture_scale)) return 1;
        if (!(o->surface.texture_scale >= 1e-6 && o->surface.texture_scale <= 1e9)) {
            cli_error("%s: '%s' must be in [1e-6, 1e9] metres", name, v);
            return 1;
        }
    } else if (!strcmp(name, "--styles")) {
        s->styles_path = v;
    } else if (!strcmp(name, "--atlas")) {
        s->atlas_path = v;
    } else if (!strcmp(name, "--atlas-index")) {
        s->atlas_index_path = v;
    } else if (!strcmp(name, "--profile")) {
        if (!strcmp(v, "rms") || !strcmp(v, "de")) o->style.profile = RS_PROFILE_RMS;
        else if (!strcmp(v, "us") || !strcmp(v, "mutcd")) o->style.profile = RS_PROFILE_MUTCD;
        else { cli_error("%s: '%s' is not 'rms' (Germany) or 'us' (MUTCD)", name, v); return 1; }
    } else if (!strcmp(name, "--driving-side")) {
        if (!strcmp(v, "right")) o->style.driving_side = RS_DRIVING_RIGHT;
        else if (!strcmp(v, "left")) o->style.driving_side = RS_DRIVING_LEFT;
        else { cli_error("%s: '%s' is not 'left' or 'right'", name, v); return 1; }
    } else if (!strcmp(name, "--aa")) {
        if (!strcmp(v, "exact")) o->style.aa = RS_LINE_AA_EXACT;
        else if (!strcmp(v, "hermite")) o->style.aa = RS_LINE_AA_HERMITE;
        else { cli_error("%s: '%s' is not 'exact' or 'hermite'", name, v); return 1; }
    } else if (!strcmp(name, "--png-level")) {
        if (cli_parse_png_level(name, v, &s->png_level)) return 1;
        s->png_level_given = 1;
    } else { /* --origin */
        if (cli_parse_vec(name, v, xy, 2)) return 1;
        if (!(fabs(xy[0]) <= 1e12 && fabs(xy[1]) <= 1e12)) {
            cli_error("%s: '%s' must be within 1e12 metres", name, v);
            return 1;
        }
        fr->origin_x = xy[0];
        fr->origin_y = xy[1];
        s->origin_given = 1;
    }
    return 0;
}

static int load_texture(const char *path, const char *role, rs_image *img, uint8_t **data)
{
    if (!path) return 0;
    if (cli_load_texture(path, role, &img->width, &img->height, data)) return 1;
    img->rgba = *data;
    return 0;
}

/* `name` of a style's `surface` relative to the folder of `file`, the
 * file it was written in (an absolute name, or a file without a folder:
 * as it is). Malloc'd. */
static char *beside(const char *file, const char *name)
{
    const char *slash = file ? strrchr(file, '/') : NULL;
    size_t d = name[0] == '/' || !slash ? 0 : (size_t)(slash - file) + 1, n = strlen(name);
    char *p = malloc(d + n + 1);
    if (!p) return NULL;
    memcpy(p, file, d);
    memcpy(p + d, name, n + 1);
    return p;
}

/* The surface image names of the styles some road is drawn with, each
 * once: *names malloc'd (pointers into `styles`' copies), *n of them. */
static int used_surfaces(rs_ctx *ctx, const cli_splat_input *in, const cli_splat_args *s, char (**names)[RS_STYLE_IMAGE_MAX + 1],
                         size_t *n)
{
    *names = NULL;
    *n = 0;
    if (s->o.style.disable) return 0;
    size_t cap = 0;
    rs_style st;
    for (size_t i = 0, nr = rs_roads_count(in->roads); i < nr; i++) {
        if (rs_road_style(ctx, in->roads, i, in->styles, s->o.style.profile, &st) != RS_OK || !st.surface_image[0])
            continue;
        size_t k = 0;
        while (k < *n && strcmp((*names)[k], st.surface_image)) k++;
        if (k < *n) continue;
        if (*n == cap) {
            cap = cap ? 2 * cap : 8;
            char(*p)[RS_STYLE_IMAGE_MAX + 1] = realloc(*names, cap * sizeof *p);
            if (!p) {
                free(*names);
                *names = NULL;
                cli_error("out of memory for surface images");
                return 1;
            }
            *names = p;
        }
        memcpy((*names)[(*n)++], st.surface_image, sizeof st.surface_image);
    }
    return 0;
}

static int load_used_surfaces(cli_splat_args *s, const char *roads_path, size_t nfile, cli_splat_input *in, size_t m,
                              const char (*used)[RS_STYLE_IMAGE_MAX + 1], size_t nused);

/* Decode the image of every style with `surface IMG` that some road is
 * drawn with (an unused style costs nothing), each file once (two names of
 * one file share its pixels): styles [0, nfile) came from --styles FILE,
 * the rest from the road file. */
static int load_surface_images(rs_ctx *ctx, cli_splat_args *s, const char *roads_path, size_t nfile,
                               cli_splat_input *in)
{
    size_t n = rs_styles_count(in->styles), m = 0;
    for (size_t i = 0; i < n; i++) m += rs_styles_get(in->styles, i)->surface_image[0] != 0;
    if (!m) return 0;
    char(*used)[RS_STYLE_IMAGE_MAX + 1];
    size_t nused;
    if (used_surfaces(ctx, in, s, &used, &nused)) return 1;
    int rc = load_used_surfaces(s, roads_path, nfile, in, m, (const char(*)[RS_STYLE_IMAGE_MAX + 1])used, nused);
    free(used);
    return rc;
}

/* load_surface_images for the m styles with a surface image, of which the
 * names `used` are drawn. */
static int load_used_surfaces(cli_splat_args *s, const char *roads_path, size_t nfile, cli_splat_input *in, size_t m,
                              const char (*used)[RS_STYLE_IMAGE_MAX + 1], size_t nused)
{
    size_t n = rs_styles_count(in->styles);
    in->surf = calloc(m, sizeof *in->surf);
    in->surf_path = calloc(m, sizeof *in->surf_path);
    in->surf_px = calloc(m, sizeof *in->surf_px);
    if (!in->surf || !in->surf_path || !in->surf_px) {
        cli_error("out of memory for surface images");
        return 1;
    }
    for (size_t i = 0; i < n; i++) {
        const rs_style *st = rs_styles_get(in->styles, i);
        if (!st->surface_image[0]) continue;
        const char *file = i < nfile ? s->styles_path : roads_path;
        char *path = beside(file, st->surface_image);
        if (!path) {
            cli_error("out of memory for surface images");
            return 1;
        }
        size_t k = 0;
        while (k < in->nsurf && strcmp(in->surf[k].name, st->surface_image)) k++;
        if (k < in->nsurf) {
            int same = !strcmp(in->surf_path[k], path);
            if (!same)
                cli_error("%s line %llu: surface image '%s' is %s here but %s in an earlier style; give one of them "
                          "another name", file, (unsigned long long)st->surface_line, st->surface_image, path,
                          in->surf_path[k]);
            free(path);
            if (!same) return 1;
            continue;
        }
        size_t u = 0;
        while (u < nused && strcmp(used[u], st->surface_image)) u++;
        if (u == nused) { /* no road is drawn with it: not read at all */
            free(path);
            continue;
        }
        /* the same file under another name: its pixels again, not a second decode */
        struct stat sb;
        const uint8_t *shared = NULL;
        uint32_t w = 0, h = 0;
        if (stat(path, &sb) == 0 && S_ISREG(sb.st_mode))
            for (size_t j = 0; j < in->nsurf && !shared; j++) {
                struct stat sj;
                if (stat(in->surf_path[j], &sj) == 0 && sj.st_dev == sb.st_dev && sj.st_ino == sb.st_ino) {
                    shared = in->surf[j].image.rgba;
                    w = in->surf[j].image.width;
                    h = in->surf[j].image.height;
                }
            }
        uint8_t *px = NULL;
        if (!shared) {
            char where[512];
            snprintf(where, sizeof where, "%s line %llu: surface image", file, (unsigned long long)st->surface_line);
            cli_error_context(where);
            int bad = cli_load_texture(path, "surface image", &w, &h, &px);
            cli_error_context(NULL);
            if (bad) {
                free(path);
                return 1;
            }
        }
        in->surf[k].name = st->surface_image;
        in->surf[k].image.width = w;
        in->surf[k].image.height = h;
        in->surf[k].image.rgba = shared ? shared : px;
        in->surf_px[k] = px; /* NULL when shared: freed once, by its first name */
        in->surf_path[k] = path;
        in->nsurf++;
    }
    s->o.style.surface_images = in->surf;
    s->o.style.surface_image_count = in->nsurf;
    return 0;
}

/* A custom atlas without a type the automatic markings place
 * (lib/scene/markings_auto.c) silently loses those markings: say which. */
static void warn_atlas_types(const cli_splat_args *s, const rs_atlas *atlas)
{
    static const char *const auto_types[] = { "stop_line", "give_way_line", "zebra", "arrow_left", "arrow_right",
                                              "arrow_straight", "arrow_straight_left", "arrow_straight_right",
                                              "arrow_uturn" };
    if (s->o.markings.disable || s->o.markings.no_auto) return;
    char missing[300] = "";
    size_t nm = 0;
    for (size_t i = 0; i < sizeof auto_types / sizeof auto_types[0]; i++)
        if (rs_atlas_find(atlas, auto_types[i]) < 0) {
            size_t l = strlen(missing);
            snprintf(missing + l, sizeof missing - l, "%s%s", nm ? ", " : "", auto_types[i]);
            nm++;
        }
    if (nm)
        fprintf(stderr, "roadsplat: warning: %s: the atlas has no %s; automatic markings of %s are not drawn "
                        "(--no-auto-markings: none are wanted)\n", s->atlas_index_path, missing,
                nm > 1 ? "these types" : "this type");
}

int cli_lighting_option(int argc, char **argv, int *i, const char *name, const char *inl, cli_splat_args *s)
{
    rs_lighting_options *l = &s->o.lighting;
    const char *v;
    if (!strcmp(name, "--lighting")) {
        if (inl) {
            cli_error("%s takes no value", name);
            return 1;
        }
        l->enable = 1;
    } else if (!strcmp(name, "--sun")) {
        double d[2];
        if (cli_option_value(argc, argv, i, name, inl, &v) || cli_parse_vec(name, v, d, 2)) return 1;
        if (!(d[0] >= -360 && d[0] <= 360 && d[1] > 0 && d[1] <= 90)) {
            cli_error("%s: '%s': azimuth must be -360..360 and altitude in (0, 90] degrees", name, v);
            return 1;
        }
        l->sun_given = 1;
        l->sun_azimuth = d[0];
        l->sun_altitude = d[1];
        s->light_given = 1;
    } else if (!strcmp(name, "--specular")) {
        if (cli_option_value(argc, argv, i, name, inl, &v) || cli_parse_double(name, v, &l->specular)) return 1;
        if (!(l->specular >= 0 && l->specular <= 1)) {
            cli_error("%s: '%s' must be in [0, 1]", name, v);
            return 1;
        }
        s->light_given = 1;
    } else
        return -1;
    return 0;
}

int cli_lighting_check(const cli_splat_args *s)
{
    if (s->light_given && !s->o.lighting.enable) {
        cli_error("--sun and --specular need --lighting");
        return 1;
    }
    return 0;
}

/* o.texels from --pixel-size, or, in the main command (s->auto_pixel), the
 * default when neither it nor --texels is given: 8 texels per cell, or 1 m
 * pixels on cells over 8 m, fewer
 * when the whole map would pass CLI_MAX_IMAGE_PIXELS; said in a note
 * (s->pixel_note) on a georeferenced DEM or when it is not 8, or when
 * --pixel-size is rounded (docs/gis.md "Pixel size"). */
static int resolve_texels(cli_splat_args *s, const cli_splat_input *in, const char *dem_path)
{
    rs_dem_frame fr;
    rs_dem_get_frame(in->dem, &fr);
    const double cell = fr.cell_size;
    if (s->pixel_size) {
        if (s->o.texels) {
            cli_error("--pixel-size and --texels both set the pixel size; give one");
            return 1;
        }
        double q = cell / s->pixel_size;
        if (!(q >= 0.5)) {
            cli_error("--pixel-size %g: coarser than the DEM's %g m cells (%s); the texture has at least one pixel "
                      "per cell: --pixel-size %g", s->pixel_size, cell, dem_path, cell);
            return 1;
        }
        if (!(q < 1024.5)) {
            cli_error("--pixel-size %g: the DEM's %g m cells (%s) would need %.0f pixels per cell; at most 1024: "
                      "--pixel-size %g or coarser", s->pixel_size, cell, dem_path, q, cell / 1024);
            return 1;
        }
        uint32_t T = (uint32_t)floor(q + 0.5);
        if (T < 1) T = 1;
        if (fabs(cell / T - s->pixel_size) > 1e-6 * s->pixel_size)
            snprintf(s->pixel_note, sizeof s->pixel_note, "roadsplat: note: --pixel-size %g: pixels are %.9g m "
                     "(%u per %g m DEM cell; a size that divides the cell size is exact)\n", s->pixel_size, cell / T,
                     T, cell);
        s->o.texels = T;
        return 0;
    }
    if (s->o.texels || !s->auto_pixel) return 0;
    uint32_t T = 8;
    if (cell > 8) T = cell >= 1024 ? 1024 : (uint32_t)ceil(cell - 1e-9);
    double cells = (double)(rs_dem_width(in->dem) - 1) * (rs_dem_height(in->dem) - 1);
    int fitted = 0;
    if (cells * T * T > (double)CLI_MAX_IMAGE_PIXELS) {
        uint32_t f = (uint32_t)floor(sqrt((double)CLI_MAX_IMAGE_PIXELS / cells));
        if (f < 1) f = 1;
        if (f < T) T = f, fitted = 1;
    }
    if (in->geo.georef || T != 8)
        snprintf(s->pixel_note, sizeof s->pixel_note, "roadsplat: note: %s: %.6g m pixels (%u per %g m DEM cell%s); "
                 "choose with --pixel-size M\n", dem_path, cell / T, T, cell,
                 fitted ? ", the most that keep the whole map within 2^28 pixels" : "");
    s->o.texels = T;
    return 0;
}

/* --color-relief FILE: gdaldem color-relief's text format, one stop a
 * line, "HEIGHT R G B [A]" (blanks, tabs or commas between), heights in
 * metres in any order; `nv` (nodata) lines are skipped (nodata is
 * transparent anyway), `#` starts a comment. Percentages and colour
 * names are refused: a ramp relative to each DEM is what the absolute
 * tint avoids. */
static int read_color_relief(cli_splat_args *s, cli_splat_input *in)
{
    char *text = NULL;
    size_t size = 0;
    const char *path = s->color_relief;
    if (cli_read_file(path, (size_t)1 << 20, &text, &size)) return 1;
    rs_colour_stop *st = calloc(RS_RAMP_MAX_STOPS, sizeof *st);
    size_t n = 0, line = 0;
    int rc = 1;
    if (!st) {
        cli_error("%s: out of memory", path);
        goto out;
    }
    for (char *p = text, *end = text + size; p < end;) {
        char *nl = memchr(p, '\n', (size_t)(end - p));
        char *e = nl ? nl : end;
        line++;
        char buf[256];
        size_t len = (size_t)(e - p) < sizeof buf - 1 ? (size_t)(e - p) : sizeof buf - 1;
        memcpy(buf, p, len);
        buf[len] = '\0';
        p = nl ? nl + 1 : end;
        char *hash = strchr(buf, '#');
        if (hash) *hash = '\0';
        char *tok[6];
        int nt = 0;
        for (char *t = strtok(buf, " \t,\r"); t && nt < 6; t = strtok(NULL, " \t,\r")) tok[nt++] = t;
        if (nt == 0) continue;
        if (!strcmp(tok[0], "nv")) continue;
        if (nt < 4 || nt > 5) {
            cli_error("%s line %zu: expected 'HEIGHT R G B [A]' (gdaldem color-relief), got %d value%s", path, line,
                      nt, nt == 1 ? "" : "s");
            goto out;
        }
        if (strchr(tok[0], '%')) {
            cli_error("%s line %zu: '%s' is a percentage of each DEM's range; give heights in metres (the tint is "
                      "absolute)", path, line, tok[0]);
            goto out;
        }
        double hgt, c[3];
        char *q;
        hgt = strtod(tok[0], &q);
        if (*q || q == tok[0] || !(fabs(hgt) <= 1e9)) {
            cli_error("%s line %zu: height '%s' is not a number", path, line, tok[0]);
            goto out;
        }
        for (int k = 0; k < 3; k++) {
            c[k] = strtod(tok[1 + k], &q);
            if (*q || q == tok[1 + k] || !(c[k] >= 0 && c[k] <= 255) || c[k] != floor(c[k])) {
                cli_error("%s line %zu: colour value '%s' must be a whole number 0..255 (colour names are not read)",
                          path, line, tok[1 + k]);
                goto out;
            }
        }
        if (n == RS_RAMP_MAX_STOPS) {
            cli_error("%s line %zu: more than %d stops", path, line, RS_RAMP_MAX_STOPS);
            goto out;
        }
        for (size_t k = 0; k < n; k++)
            if (st[k].height == hgt) {
                cli_error("%s line %zu: height %g is given twice", path, line, hgt);
                goto out;
            }
        st[n].height = hgt;
        st[n].colour.r = (uint8_t)c[0];
        st[n].colour.g = (uint8_t)c[1];
        st[n].colour.b = (uint8_t)c[2];
        st[n].colour.a = 255;
        n++;
    }
    if (n < 2) {
        cli_error("%s: a colour ramp needs at least 2 heights, found %zu", path, n);
        goto out;
    }
    for (size_t i = 1; i < n; i++) /* by height: a few stops, insertion sort */
        for (size_t k = i; k > 0 && st[k].height < st[k - 1].height; k--) {
            rs_colour_stop t = st[k];
            st[k] = st[k - 1];
            st[k - 1] = t;
        }
    in->relief = st;
    s->o.surface.ramp = st;
    s->o.surface.ramp_count = n;
    st = NULL;
    rc = 0;
out:
    free(st);
    free(text);
    return rc;
}

int cli_splat_input_load(rs_ctx *ctx, const char *dem_path, const char *roads_path, cli_splat_args *s,
                         cli_splat_input *in)
{
    char *text = NULL;
    size_t size = 0;
    memset(in, 0, sizeof *in);
    if (!(in->dem = cli_geo_load_dem(ctx, dem_path, &in->geo))) return 1;
    /* nodata (NaN) samples: the library fills them; the colour output
     * makes them transparent (cli_nodata_alpha) */
    {
        uint32_t W = rs_dem_width(in->dem), H = rs_dem_height(in->dem);
        const float *z = rs_dem_samples(in->dem);
        size_t n = (size_t)W * H, k = 0;
        while (k < n && z[k] == z[k]) k++;
        if (k < n) {
            if (!(in->nodata = malloc(n))) {
                cli_error("%s: out of memory for the nodata mask", dem_path);
                return 1;
            }
            for (size_t i = 0; i < n; i++) in->nodata[i] = z[i] != z[i];
        }
    }
    if (rs_styles_create(ctx, &in->styles) != RS_OK) {
        cli_error("%s", rs_ctx_message(ctx));
        return 1;
    }
    /* --styles first: a road file's own style block of the same name is then an error naming its line */
    if (s->styles_path) {
        if (cli_read_input(s->styles_path, "--styles", (size_t)16 << 20, &text, &size)) return 1;
        rs_result r = rs_styles_add_text(ctx, in->styles, text, size);
        free(text);
        text = NULL;
        if (r) {
            cli_error("%s: %s", s->styles_path, rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(r));
            return 1;
        }
    }
    size_t nfile = rs_styles_count(in->styles);
    if (cli_roads_are_odr(roads_path) ? cli_odr_roads_text(roads_path, &text, &size)
                                      : cli_geo_roads_text(roads_path, s, &in->geo, &text, &size, &in->source))
        return 1;
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.profile = s->o.style.profile;
    po.styles = in->styles;
    rs_result r = rs_roads_parse_ex(ctx, text, size, &po, &in->roads);
    free(text);
    if (r) {
        cli_error("%s: %s", roads_path, rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(r));
        return 1;
    }
    /* the frame: the DEM's georeference, the road file's frame line */
    if (cli_geo_frame(ctx, in, s, dem_path, roads_path)) return 1;
    if (resolve_texels(s, in, dem_path)) return 1;
    if (in->geo.georef) { /* textures and asphalt on the world's pixel grid: DEM tiles of a map agree */
        /* texels 0 is the library's default of 8 (render and mesh leave it unset) */
        double px = in->geo.gt[1] / (s->o.texels ? s->o.texels : 8), x = (in->geo.gt[0] + in->geo.gt[1] / 2) / px,
               y = -(in->geo.gt[3] + in->geo.gt[5] / 2) / px;
        if (fabs(x) < 1e15 && fabs(y) < 1e15) {
            s->o.surface.texel_offset_x = (int64_t)floor(x + 0.5);
            s->o.surface.texel_offset_y = (int64_t)floor(y + 0.5);
        }
    }
    if (s->color_relief && read_color_relief(s, in)) return 1;
    s->o.style.styles = in->styles;
    if (load_surface_images(ctx, s, roads_path, nfile, in)) return 1;
    if (load_texture(s->terrain_tex, "--terrain-texture", &in->terrain, &in->terrain_px) ||
        load_texture(s->road_tex, "--road-texture", &in->road, &in->road_px))
        return 1;
    if (in->terrain_px) s->o.surface.terrain_texture = &in->terrain;
    if (in->road_px) s->o.surface.road_texture = &in->road;
    if ((s->atlas_path != NULL) != (s->atlas_index_path != NULL)) {
        cli_error("--atlas and --atlas-index go together (an RGBA image and its index file)");
        return 1;
    }
    if (s->atlas_path) {
        rs_image img;
        if (load_texture(s->atlas_path, "--atlas", &img, &in->atlas_px)) return 1;
        if (cli_read_input(s->atlas_index_path, "--atlas-index", (size_t)16 << 20, &text, &size)) return 1;
        r = rs_atlas_create(ctx, &img, text, size, &in->atlas);
        free(text);
        if (r) {
            char m[512];
            cli_error("%s: %s", r == RS_ERR_PARSE || r == RS_ERR_LIMIT ? s->atlas_index_path : s->atlas_path,
                      cli_lib_message(ctx, r, m, sizeof m));
            return 1;
        }
        s->o.markings.atlas = in->atlas;
        warn_atlas_types(s, in->atlas);
    }
    return 0;
}

void cli_splat_input_free(rs_ctx *ctx, cli_splat_input *in)
{
    rs_roads_free(ctx, in->roads);
    rs_styles_free(ctx, in->styles);
    free(in->relief);
    rs_dem_free(ctx, in->dem);
    free(in->terrain_px);
    free(in->road_px);
    rs_atlas_free(ctx, in->atlas);
    free(in->atlas_px);
    for (size_t i = 0; i < in->nsurf; i++) {
        free(in->surf_px[i]);
        free(in->surf_path[i]);
    }
    free(in->surf);
    free(in->surf_px);
    free(in->surf_path);
    cli_geo_free(&in->geo);
    free(in->nodata);
    memset(in, 0, sizeof *in);
}
