/* `roadsplat render`: splat the roads on the CPU, mesh the terrain with the
 * view-dependent ROAM mesher and draw both offscreen with OSMesa to a PNG
 * (cli/render_gl.c holds the GL). Without OSMesa this is a stub that says so.
 * Design notes: docs/render.md. */
#include "cli.h"

#ifndef RS_WITH_OSMESA

int cli_render_main(int argc, char **argv)
{
    (void)argc;
    (void)argv;
    cli_error("render: this build has no OSMesa support (install libosmesa6-dev and rebuild)");
    return 1;
}

#else
#include "render_gl.h"
#include "render_shader.h"
#include "gis.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define RENDER_PI 3.14159265358979323846
#define RENDER_MAX_COORD 1e9 /* metres: --camera / --look-at, local or world */

static const char render_usage[] =
    "Usage: roadsplat render [splat options] [render options] DEM ROADS OUT.png\n"
    "\n"
    "Meshes the terrain of DEM with view-dependent ROAM and renders it offscreen\n"
    "(OSMesa) to OUT.png, with ROADS drawn per screen pixel by a fragment shader\n"
    "(--roads shader) or as the CPU splat (`roadsplat`'s image) for a texture.\n"
    "Positions (--camera, --look-at) are world coordinates when the DEM is\n"
    "georeferenced or the roads are in a world frame ('frame world', GIS roads):\n"
    "X east, Y north (the DEM's CRS), Z height in metres; with --origin (roads not in\n"
    "a world frame) they are in the roads' frame: the origin plus metres, Y down the\n"
    "map. Otherwise they are local: metres from DEM sample (0,0), Y growing down the map.\n"
    "A camera below the terrain or a view that misses the map is a warning.\n"
    "\n"
    "Splat options (see roadsplat --help): --cell-size M, --z-scale S, --texels N,\n"
    "  --buffer distance|dilate, --road-cell M, --alpha-res N, --transition PX,\n"
    "  --jitter SEED, --terrain-texture IMG, --road-texture IMG, --texture-scale M,\n"
    "  --styles FILE, --profile rms|us, --aa exact|hermite, --no-styles,\n"
    "  --png-level N (OUT.png compression 0..12, default 1), --origin X,Y,\n"
    "  --edges MODE, --threads N, --pixel-size M, --color-relief FILE,\n"
    "  --atlas IMG, --atlas-index FILE, --no-auto-markings, --no-markings,\n"
    "  --layer NAME, --where SQL (GIS roads), --strict, --driving-side left|right,\n"
    "  --gdal-trust (every GDAL driver and the network for DEM and ROADS),\n"
    "  --max-image-pixels N, --max-field-work N, --max-atlas-mb N, --max-linesym-mb N\n"
    "  (budgets)\n"
    "Render options:\n"
    "  --path FILE         a flythrough along camera key frames with streamed texture tiles\n"
    "                      (docs/render.md \"Flythrough\"; its options: --path FILE --help)\n"
    "  --size WxH          image size (default 1280x960; with --ortho: the splat's size)\n"
    "  --camera X,Y,Z      eye position (default: oblique view of the whole map from the south)\n"
    "  --look-at X,Y,Z     point looked at (default: the map centre)\n"
    "  --fov DEG           vertical field of view (default 45)\n"
    "  --pixel-error P     ROAM screen-space tolerance in pixels (default 1)\n"
    "  --triangles N       hold the ROAM mesh near N triangles instead\n"
    "  --sun AZ,ALT        sun azimuth (compass, degrees) and altitude (default 315,45)\n"
    "  --lighting on|off   shade by the sun (default on; shader mode: per pixel from the\n"
    "                      normal map, on the terrain tint without the splat's hillshade)\n"
    "  --fog               linear distance fog towards the horizon colour\n"
    "  --ortho             top-down orthographic view of the whole map: at the splat's\n"
    "                      size one pixel is one texel (the CPU cross-check)\n"
    "  --roads MODE        shader: the fragment shader draws roads, styles and markings\n"
    "                      per screen pixel (OpenGL 3.3 core; default when available);\n"
    "                      texture: the CPU splat as the terrain texture\n"
    "  --frames N          render the view N times, for timing (default 1; 10 with --stats)\n"
    "  --anisotropy N      texture mode: anisotropic texture filtering with at most N taps\n"
    "                      (1: off; default: the GL's maximum, 16 on llvmpipe)\n"
    "  --tile-size N       texture mode: split the texture into tiles of at most N texels per side\n"
    "                      (default: only when it exceeds GL_MAX_TEXTURE_SIZE)\n"
    "  --stats FILE.json   fps, triangle count and timings as JSON\n"
    "  --quiet             no progress bar\n";

typedef struct render_args {
    cli_splat_args s;
    const char *dem, *roads, *out, *stats;
    uint32_t width, height, triangles, frames, tile_size;
    int have_size, have_camera, have_look, have_pixel_error;
    double camera[3], look[3], fov, pixel_error, sun_az, sun_alt, anisotropy;
    int lighting, fog, ortho, quiet;
    int roads_mode; /* 0: shader when the context supports it, 1: texture, 2: shader (asked for) */
} render_args;

/* 0 run, 1 usage error, 2 --help handled. */
static int parse_render_args(int argc, char **argv, render_args *a)
{
    const char *pos[3];
    int npos = 0, only_pos = 0;
    memset(a, 0, sizeof *a);
    a->width = 1280; a->height = 960;
    a->fov = 45; a->pixel_error = 1; a->sun_az = 315; a->sun_alt = 45; a->lighting = 1;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i], *v = NULL;
        if (only_pos || arg[0] != '-' || arg[1] == '\0') {
            if (npos == 3) { cli_error("render: unexpected argument '%s'", arg); return 1; }
            pos[npos++] = arg;
            continue;
        }
        if (!strcmp(arg, "--")) { only_pos = 1; continue; }
        char name[CLI_OPT_NAME];
        const char *inl = cli_option_split(arg, name);
        double d[3];
        if (!strcmp(name, "--help") || !strcmp(name, "-h")) { fputs(render_usage, stdout); return 2; }
        if (!strcmp(name, "--quiet") || !strcmp(name, "-q")) { a->quiet = 1; continue; }
        if (!strcmp(name, "--fog")) { a->fog = 1; continue; }
        if (!strcmp(name, "--ortho")) { a->ortho = 1; continue; }
        int sr = cli_splat_option(argc, argv, &i, name, inl, &a->s);
        if (sr > 0) return 1;
        if (sr == 0) continue;
        if (cli_option_value(argc, argv, &i, name, inl, &v)) return 1;
        /* every option below takes a value v */
        if (!strcmp(name, "--size")) {
            if (cli_parse_size(name, v, &a->width, &a->height)) return 1;
            if (a->width < 1 || a->height < 1 || a->width > 16384 || a->height > 16384) {
                cli_error("%s: '%s' must be 1..16384 on each side", name, v);
                return 1;
            }
            a->have_size = 1;
        } else if (!strcmp(name, "--camera") || !strcmp(name, "--look-at")) {
            double *p = !strcmp(name, "--camera") ? a->camera : a->look;
            if (cli_parse_vec(name, v, p, 3)) return 1;
            /* distances, squares and clip planes must stay finite */
            for (int k = 0; k < 3; k++)
                if (!(fabs(p[k]) <= RENDER_MAX_COORD)) {
                    cli_error("%s: '%s' must lie within +-%g m on each axis", name, v, RENDER_MAX_COORD);
                    return 1;
                }
            if (p == a->camera) a->have_camera = 1;
            else a->have_look = 1;
        } else if (!strcmp(name, "--fov")) {
            if (cli_parse_double(name, v, &a->fov)) return 1;
            if (!(a->fov >= 1 && a->fov <= 170)) { cli_error("%s: '%s' must be 1..170 degrees", name, v); return 1; }
        } else if (!strcmp(name, "--pixel-error")) {
            if (cli_parse_double(name, v, &a->pixel_error)) return 1;
            if (!(a->pixel_error > 0)) { cli_error("%s: '%s' must be > 0", name, v); return 1; }
            a->have_pixel_error = 1;
        } else if (!strcmp(name, "--triangles")) {
            if (cli_parse_u32(name, v, &a->triangles)) return 1;
            if (a->triangles < 2) { cli_error("%s: '%s' must be >= 2", name, v); return 1; }
        } else if (!strcmp(name, "--sun")) {
            if (cli_parse_vec(name, v, d, 2)) return 1;
            if (!(d[1] >= -90 && d[1] <= 90)) { cli_error("%s: altitude '%g' must be -90..90", name, d[1]); return 1; }
            a->sun_az = d[0];
            a->sun_alt = d[1];
        } else if (!strcmp(name, "--lighting")) {
            if (!strcmp(v, "on")) a->lighting = 1;
            else if (!strcmp(v, "off")) a->lighting = 0;
            else { cli_error("%s: '%s' is not 'on' or 'off'", name, v); return 1; }
        } else if (!strcmp(name, "--frames")) {
            if (cli_parse_u32(name, v, &a->frames)) return 1;
            if (a->frames < 1 || a->frames > 100000) { cli_error("%s: '%s' must be 1..100000", name, v); return 1; }
        } else if (!strcmp(name, "--anisotropy")) {
            if (cli_parse_double(name, v, &a->anisotropy)) return 1;
            if (!(a->anisotropy >= 1 && a->anisotropy <= 64)) {
                cli_error("%s: '%s' must be 1..64", name, v);
                return 1;
            }
        } else if (!strcmp(name, "--tile-size")) {
            if (cli_parse_u32(name, v, &a->tile_size)) return 1;
            if (a->tile_size < 16) { cli_error("%s: '%s' must be >= 16", name, v); return 1; }
        } else if (!strcmp(name, "--roads")) {
            if (!strcmp(v, "shader")) a->roads_mode = 2;
            else if (!strcmp(v, "texture")) a->roads_mode = 1;
            else { cli_error("%s: '%s' is not 'shader' or 'texture'", name, v); return 1; }
        } else if (!strcmp(name, "--stats")) a->stats = v;
        else { cli_error("render: unknown option '%s' (see roadsplat render --help)", arg); return 1; }
    }
    if (npos != 3) {
        cli_error("render: expected DEM ROADS OUT.png, got %d argument%s (see roadsplat render --help)", npos,
                  npos == 1 ? "" : "s");
        return 1;
    }
    if (a->s.frame.z_scale < 0) {
        cli_error("render: --z-scale must be > 0 for rendering");
        return 1;
    }
    if (a->have_pixel_error && a->triangles) {
        cli_error("render: --pixel-error and --triangles are exclusive");
        return 1;
    }
    if (a->have_camera && a->have_look && a->camera[0] == a->look[0] && a->camera[1] == a->look[1] &&
        a->camera[2] == a->look[2]) {
        cli_error("render: --camera and --look-at must differ");
        return 1;
    }
    if (!a->frames) a->frames = a->stats ? 10 : 1;
    a->dem = pos[0];
    a->roads = pos[1];
    a->out = pos[2];
    return 0;
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return a < b ? -1 : a > b;
}

static double median(double *v, size_t n)
{
    qsort(v, n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* Default camera: from the south, 20 degrees above the horizon, far enough
 * that the map's bounding sphere fits the narrower field of view. */
static void default_camera(const render_args *a, const rg_view *v, double *eye, double *look)
{
    double c[3] = { v->map_w / 2, v->map_h / 2, (v->zmin + v->zmax) / 2 };
    if (!a->have_look) memcpy(look, c, sizeof c);
    if (a->have_camera) return;
    double R = 0.5 * sqrt(v->map_w * v->map_w + v->map_h * v->map_h + (v->zmax - v->zmin) * (v->zmax - v->zmin));
    double fy = a->fov * RENDER_PI / 180, fx = 2 * atan(tan(fy / 2) * a->width / a->height);
    double d = 0.8 * R / sin(0.5 * (fx < fy ? fx : fy)), pitch = 20 * RENDER_PI / 180;
    eye[0] = look[0];
    eye[1] = look[1] + d * cos(pitch);
    eye[2] = look[2] + d * sin(pitch);
}

/* Near/far from the map's bounding box; near keeps depth precision when the
 * eye is outside it. */
static void clip_range(rg_view *v)
{
    double far2 = 0, dx, dy, dz;
    for (int k = 0; k < 8; k++) {
        dx = (k & 1 ? v->map_w : 0) - v->eye[0];
        dy = (k & 2 ? v->map_h : 0) - v->eye[1];
        dz = (k & 4 ? v->zmax : v->zmin) - v->eye[2];
        double d2 = dx * dx + dy * dy + dz * dz;
        if (d2 > far2) far2 = d2;
    }
    dx = v->eye[0] < 0 ? -v->eye[0] : v->eye[0] > v->map_w ? v->eye[0] - v->map_w : 0;
    dy = v->eye[1] < 0 ? -v->eye[1] : v->eye[1] > v->map_h ? v->eye[1] - v->map_h : 0;
    dz = v->eye[2] < v->zmin ? v->zmin - v->eye[2] : v->eye[2] > v->zmax ? v->eye[2] - v->zmax : 0;
    double dbox = sqrt(dx * dx + dy * dy + dz * dz);
    v->zfar = sqrt(far2) * 1.01 + 1.0;
    v->znear = fmax(v->zfar * 1e-4, 0.5 * dbox);
    double dl = sqrt((v->look[0] - v->eye[0]) * (v->look[0] - v->eye[0]) +
                     (v->look[1] - v->eye[1]) * (v->look[1] - v->eye[1]) +
                     (v->look[2] - v->eye[2]) * (v->look[2] - v->eye[2]));
    v->fog_start = 0.6 * dl;
    v->fog_end = fmax(v->zfar * 1.3, v->fog_start + 1.0);
}

/* A camera below the terrain, or a view that misses the map, gives an
 * empty or odd picture: say so, naming the problem (issue 15). */
static void view_warnings(const render_args *a, const rg_view *v, const rs_dem *dem, double cs, double zs, double fx0,
                          double fy0, double fys, const char *frame_name)
{
    const double *e = v->eye;
    uint32_t W = rs_dem_width(dem), H = rs_dem_height(dem);
    if (e[0] >= 0 && e[0] <= v->map_w && e[1] >= 0 && e[1] <= v->map_h) {
        /* the DEM's height under the eye, bilinear */
        const float *z = rs_dem_samples(dem);
        double gx = e[0] / cs, gy = e[1] / cs;
        uint32_t i = (uint32_t)fmin(floor(gy), H > 1 ? H - 2 : 0), j = (uint32_t)fmin(floor(gx), W > 1 ? W - 2 : 0);
        uint32_t i1 = H > 1 ? i + 1 : i, j1 = W > 1 ? j + 1 : j;
        double fy = gy - i, fx = gx - j;
        double z00 = z[(size_t)i * W + j], z01 = z[(size_t)i * W + j1], z10 = z[(size_t)i1 * W + j],
               z11 = z[(size_t)i1 * W + j1];
        double hz = ((z00 * (1 - fx) + z01 * fx) * (1 - fy) + (z10 * (1 - fx) + z11 * fx) * fy) * zs;
        if (hz == hz && e[2] < hz)
            fprintf(stderr, "roadsplat: warning: the camera %.10g,%.10g,%.10g (%s frame) is below the terrain, "
                    "which is %.6g m high there: the picture shows the terrain from below\n", fx0 + e[0],
                    fy0 + fys * e[1], e[2], frame_name, hz);
    }
    /* the map's box against the view frustum: all corners beyond one plane */
    double f[3] = { v->look[0] - e[0], v->look[1] - e[1], v->look[2] - e[2] };
    double fl = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    if (!(fl > 0)) return;
    for (int k = 0; k < 3; k++) f[k] /= fl;
    double sx[3] = { f[1], -f[0], 0 };
    double sl = sqrt(sx[0] * sx[0] + sx[1] * sx[1]);
    if (sl < 1e-9) { sx[0] = 1; sx[1] = 0; sl = 1; }
    for (int k = 0; k < 2; k++) sx[k] /= sl;
    double u[3] = { f[1] * sx[2] - f[2] * sx[1], f[2] * sx[0] - f[0] * sx[2], f[0] * sx[1] - f[1] * sx[0] };
    double ty = tan(v->fov_y * RENDER_PI / 360.0), tx = ty * a->width / a->height;
    int out[5] = { 1, 1, 1, 1, 1 };
    for (int c = 0; c < 8; c++) {
        double d[3] = { (c & 1 ? v->map_w : 0) - e[0], (c & 2 ? v->map_h : 0) - e[1], (c & 4 ? v->zmax : v->zmin) - e[2] };
        double zz = d[0] * f[0] + d[1] * f[1] + d[2] * f[2], xx = d[0] * sx[0] + d[1] * sx[1] + d[2] * sx[2],
               yy = d[0] * u[0] + d[1] * u[1] + d[2] * u[2];
        out[0] &= zz <= 0;
        out[1] &= xx < -zz * tx;
        out[2] &= xx > zz * tx;
        out[3] &= yy < -zz * ty;
        out[4] &= yy > zz * ty;
    }
    if (out[0] || out[1] || out[2] || out[3] || out[4])
        fprintf(stderr, "roadsplat: warning: the view from %.10g,%.10g,%.10g towards %.10g,%.10g,%.10g (%s frame) "
                "misses the map, which spans x %.10g..%.10g, y %.10g..%.10g: %s\n", fx0 + e[0], fy0 + fys * e[1],
                e[2], fx0 + v->look[0], fy0 + fys * v->look[1], v->look[2], frame_name, fx0,
                fx0 + v->map_w, fys > 0 ? fy0 : fy0 - v->map_h, fys > 0 ? fy0 + v->map_h : fy0,
                out[0] ? "the map is behind the camera" : "the map lies outside the field of view");
}

/* The shader mode's textures, from one pass of the splatter's layers
 * (rs_splat_layers_window, on the splat's threads): the terrain colour T
 * with no roads (lit by the renderer: the tint alone, unshaded, as a lit
 * splat's terrain), the road material S under no style (the shader draws
 * the styles) and, lit, the normal map (rs_normal_window's defaults, which
 * need the roads: their paint and surfaces). Unlit, T and S do not depend
 * on the roads: a splatter on none. The error is printed. */
static int bake_layers(rs_ctx *ctx, const cli_splat_input *in, const render_args *a, uint32_t tw, uint32_t th,
                       rs_road_grid **grid, rs_splatter **sp, uint8_t **terrain, uint8_t **road, uint8_t **nmap)
{
    cli_splat_args s = a->s;
    cli_splat_input on = *in;
    rs_roads *none = NULL;
    int rc = 1;
    s.o.lighting.enable = a->lighting;
    if (!a->lighting) {
        rs_result r = rs_roads_create(ctx, &none);
        if (r) { cli_error("render: %s", rs_strerror(r)); return 1; }
        on.roads = none;
        s.o.style.disable = 1;
        s.o.markings.disable = 1;
    }
    if (cli_splatter_prepare(ctx, &on, a->roads, &s, 1, grid, sp)) goto done;
    *terrain = malloc((size_t)tw * th * 4);
    *road = malloc((size_t)tw * th * 4);
    if (a->lighting) *nmap = malloc((size_t)tw * th * 3);
    if (!*terrain || !*road || (a->lighting && !*nmap)) {
        cli_error("%s: out of memory for the %u x %u terrain and road textures", a->out, tw, th);
        goto done;
    }
    static const rs_normal_options normal_defaults;
    rs_splat_layers L;
    memset(&L, 0, sizeof L);
    L.terrain = *terrain;
    L.terrain_stride = (size_t)tw * 4;
    L.surface = *road;
    L.surface_stride = (size_t)tw * 4;
    L.surface_unstyled = 1;
    L.normal = a->lighting ? *nmap : NULL;
    L.normal_stride = (size_t)tw * 3;
    L.normal_options = &normal_defaults;
    cli_splat_job job;
    cli_splat_job_init(&job, *sp, &a->s, 1);
    job.layers = &L;
    if (cli_splat_run(&job)) goto done;
    rc = 0;
done:
    rs_roads_free(ctx, none);
    return rc;
}

/* What the shader mode does not draw (docs/render.md "Shader mode",
 * "What is drawn how"): NULL when it draws everything the CPU splat would,
 * else the feature, for the note that sends the run to the texture mode. */
static const char *shader_missing(rs_ctx *ctx, const render_args *a, const rs_roads *roads, char *buf, size_t n)
{
    const rs_splat_options *o = &a->s.o;
    if (o->coverage.edges == RS_EDGES_ALPHAMAP) return "alpha-map road edges (--edges alphamap)";
    if (o->style.aa == RS_LINE_AA_HERMITE && !o->style.disable) return "Hermite line smoothing (--aa hermite)";
    for (size_t i = 0; !o->style.disable && i < rs_roads_count(roads); i++) {
        rs_style st;
        if (rs_road_style(ctx, roads, i, o->style.styles, o->style.profile, &st) != RS_OK) continue;
        if (st.surface_image[0]) {
            snprintf(buf, n, "surface images (style '%s': surface %s)", st.name, st.surface_image);
            return buf;
        }
    }
    return NULL;
}

int cli_render_main(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) /* the flythrough through the virtual texture (cli/render_vt.c) */
        if (!strcmp(argv[i], "--path") || !strncmp(argv[i], "--path=", 7)) return cli_render_path_main(argc, argv);
    render_args a;
    int pr = parse_render_args(argc, argv, &a);
    if (pr) return pr == 2 ? 0 : 1;

    double t_start = cli_now_ms();
    double t_read = 0, t_grid = 0, t_splat = 0, t_roam = 0, t_ctx = 0, t_upload = 0, t_readback = 0, t_write = 0;
    int rc = 1;
    rs_ctx *ctx = NULL;
    cli_splat_input in;
    rs_splatter *sp = NULL;
    rs_road_grid *grid = NULL;
    rs_roam *roam = NULL;
    rg_renderer *gl = NULL;
    rsh_renderer *sh = NULL;
    rs_gpu_scene *scene = NULL;
    uint8_t *tex_road = NULL, *nmap = NULL;
    char err[256], miss[RS_STYLE_NAME_MAX + RS_STYLE_IMAGE_MAX + 64];
    uint8_t *tex = NULL, *frame = NULL;
    cli_mesh_buf mesh;
    memset(&mesh, 0, sizeof mesh);
    double *frame_ms = NULL, *mesh_ms = NULL, *draw_ms = NULL, *mesh_seq = NULL;
    uint32_t *tris_seq = NULL;
    size_t nv = 0, ni = 0;
    rs_roam_stats rst;
    rg_tex_stats tst;
    int warned = 0;
    memset(&in, 0, sizeof in);
    /* Outputs: checked and opened (as temporaries) before any work, renamed
     * together at the end. */
    cli_out out, so;
    memset(&out, 0, sizeof out);
    memset(&so, 0, sizeof so);
    const cli_file_role outs[2] = { { a.out, "OUT" }, { a.stats, "--stats" } };
    const cli_file_role ins[4] = { { a.dem, "DEM" }, { a.roads, "ROADS" }, { a.s.terrain_tex, "--terrain-texture" },
                                   { a.s.road_tex, "--road-texture" } };
    if (cli_check_outputs(outs, 2, ins, 4)) return 1;
    rs_limits budgets;
    memset(&budgets, 0, sizeof budgets);
    cli_splat_limits(&a.s, &budgets);
    rs_result r = rs_ctx_create(NULL, &budgets, &ctx);
    if (r) { cli_error("%s", rs_strerror(r)); return 1; }
    double cs = a.s.frame.cell_size > 0 ? a.s.frame.cell_size : 1, zs = a.s.frame.z_scale > 0 ? a.s.frame.z_scale : 1;
    if (cli_out_open(&out, a.out) || (a.stats && cli_out_open(&so, a.stats))) goto done;

    if (cli_splat_input_load(ctx, a.dem, a.roads, &a.s, &in)) goto done;
    const rs_dem *dem = in.dem;
    t_read = cli_now_ms() - t_start;
    {
        /* the DEM's own frame: a georeferenced DEM brings its cell size */
        rs_dem_frame fr;
        rs_dem_get_frame(dem, &fr);
        cs = fr.cell_size;
    }
    /* World positions (docs/gis.md): x east, y north from the world point
     * of sample (0,0); the view works in the local frame (y down). */
    double wx0 = 0, wy0 = 0;
    int world = cli_geo_world_origin(&in, &wx0, &wy0);
    /* --origin with roads not in a 'frame world': the roads' points are
     * that frame (the local axes moved by the origin), and so are the
     * camera's (issue 15: a camera given as the roads are no longer lands
     * far off the map) */
    int orig = 0;
    if (!world && a.s.origin_given) {
        rs_dem_frame fr;
        rs_dem_get_frame(dem, &fr);
        wx0 = fr.origin_x;
        wy0 = fr.origin_y;
        orig = 1;
    }
    for (int k = 0; k < 2; k++) {
        double *p = k ? a.look : a.camera;
        if (!(k ? a.have_look : a.have_camera)) continue;
        if (world) {
            p[0] -= wx0;
            p[1] = wy0 - p[1];
        } else if (orig) {
            p[0] -= wx0;
            p[1] -= wy0;
        }
    }
    /* local -> the frame of --camera */
    double fx0 = world || orig ? wx0 : 0, fy0 = world || orig ? wy0 : 0, fys = world ? -1 : 1;
    const char *frame_name = world ? "world" : orig ? "origin" : "local";

    /* the texture: the CPU splat */
    uint32_t tw, th;
    if ((r = rs_splat_size(ctx, dem, &a.s.o, &tw, &th))) { cli_error("%s: %s", a.dem, rs_ctx_message(ctx)); goto done; }
    double t1;

    /* the mesh */
    t1 = cli_now_ms();
    rs_roam_options ro;
    memset(&ro, 0, sizeof ro);
    if ((r = rs_roam_create(ctx, dem, &ro, &roam))) { cli_error("%s: %s", a.dem, rs_ctx_message(ctx)); goto done; }
    t_roam = cli_now_ms() - t1;

    /* the view */
    rg_view view;
    memset(&view, 0, sizeof view);
    uint32_t W = rs_dem_width(dem), H = rs_dem_height(dem);
    view.map_w = (W - 1) * cs;
    view.map_h = (H - 1) * cs;
    {
        double lo, hi;
        rs_dem_height_range(dem, &lo, &hi, NULL);
        view.zmin = lo * zs;
        view.zmax = hi * zs;
    }
    for (int k = 0; k < 2; k++) { /* an eye or target far off the map: likely the wrong frame */
        const double *p = k ? a.look : a.camera;
        if (!(k ? a.have_look : a.have_camera)) continue;
        double span = fmax(fmax(view.map_w, view.map_h), 1.0), lim = k ? span : 10 * span; /* issue 28: 10, not 1000 */
        if (p[0] < -lim || p[0] > view.map_w + lim || p[1] < -lim || p[1] > view.map_h + lim) {
            double mx0 = fx0, mx1 = mx0 + view.map_w, my0 = world ? wy0 - view.map_h : fy0,
                   my1 = world ? wy0 : fy0 + view.map_h;
            fprintf(stderr, "roadsplat: warning: %s %.10g,%.10g is far off the map %s, which spans x %.10g..%.10g, "
                    "y %.10g..%.10g (%s)\n", k ? "--look-at" : "--camera", fx0 + p[0], fy0 + fys * p[1], a.dem, mx0,
                    mx1, my0, my1,
                    world  ? "world coordinates, y north"
                    : orig ? "the roads' frame: --origin plus metres, y down"
                           : "local metres from sample (0,0), y down");
        }
    }
    if (a.ortho && !a.have_size) { a.width = tw; a.height = th; }
    if (a.width > 16384 || a.height > 16384) {
        cli_error("render: the splat is %u x %u; give --size (at most 16384 a side)", tw, th);
        goto done;
    }
    view.ortho = a.ortho;
    view.fov_y = a.fov;
    view.lighting = a.lighting;
    view.fog = a.fog;
    view.anisotropy = a.anisotropy;
    double az = a.sun_az * RENDER_PI / 180, alt = a.sun_alt * RENDER_PI / 180;
    view.sun[0] = sin(az) * cos(alt);
    view.sun[1] = -cos(az) * cos(alt); /* north is -y */
    view.sun[2] = sin(alt);
    memcpy(view.eye, a.camera, sizeof view.eye);
    memcpy(view.look, a.look, sizeof view.look);
    default_camera(&a, &view, view.eye, view.look);
    if (a.have_camera && !a.have_look && view.eye[0] == view.look[0] && view.eye[1] == view.look[1] &&
        view.eye[2] == view.look[2])
        view.look[2] -= 1.0;
    clip_range(&view);
    if (!a.ortho) view_warnings(&a, &view, dem, cs, zs, fx0, fy0, fys, frame_name);

    /* the shader mode when the context supports it (docs/render.md "Shader mode") */
    t1 = cli_now_ms();
    memset(&tst, 0, sizeof tst);
    const char *missing = a.roads_mode != 1 ? shader_missing(ctx, &a, in.roads, miss, sizeof miss) : NULL;
    if (missing)
        fprintf(stderr, "roadsplat: note: render: the shader mode does not draw %s; drawing the roads as a texture "
                "(--roads texture)\n", missing);
    else if (a.roads_mode != 1) {
        if (!(sh = rsh_create(a.width, a.height, err, sizeof err)))
            fprintf(stderr, "roadsplat: note: render: %s; drawing the roads as a texture (--roads texture)\n", err);
        else if (tw > rsh_max_texture_size(sh) || th > rsh_max_texture_size(sh)) {
            fprintf(stderr, "roadsplat: note: render: the %u x %u texture exceeds GL_MAX_TEXTURE_SIZE %u of the "
                    "shader mode; drawing the roads as a texture (--roads texture)\n", tw, th, rsh_max_texture_size(sh));
            rsh_destroy(sh);
            sh = NULL;
        }
    }
    t_ctx = cli_now_ms() - t1;
    if (sh) {
        /* terrain colour T and road surface S baked on the CPU, the roads
         * exported for the fragment shader */
        t1 = cli_now_ms();
        if (bake_layers(ctx, &in, &a, tw, th, &grid, &sp, &tex, &tex_road, &nmap)) goto done;
        t_splat = cli_now_ms() - t1;
        t1 = cli_now_ms();
        if ((r = rs_gpu_scene_create(ctx, dem, in.roads, &a.s.o, NULL, &scene))) {
            cli_error("%s: %s", a.roads, rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(r));
            goto done;
        }
        t_grid = cli_now_ms() - t1;
        t1 = cli_now_ms();
        if (rsh_upload(sh, scene, tex, tex_road, nmap, tw, th, err, sizeof err)) { cli_error("render: %s", err); goto done; }
        t_upload = cli_now_ms() - t1;
    } else {
        t1 = cli_now_ms();
        if (cli_splatter_prepare(ctx, &in, a.roads, &a.s, a.quiet, &grid, &sp)) goto done;
        t_grid = cli_now_ms() - t1;
        t1 = cli_now_ms();
        tex = malloc((size_t)tw * th * 4);
        if (!tex) { cli_error("%s: out of memory for a %u x %u texture", a.out, tw, th); goto done; }
        {
            cli_splat_job job;
            cli_splat_job_init(&job, sp, &a.s, a.quiet);
            job.rgba = tex;
            if (cli_splat_run(&job)) goto done;
        }
        t_splat = cli_now_ms() - t1;
        t1 = cli_now_ms();
        if (!(gl = rg_create(a.width, a.height, err, sizeof err))) { cli_error("render: %s", err); goto done; }
        t_ctx += cli_now_ms() - t1;
        t1 = cli_now_ms();
        if (rg_upload_texture(gl, tex, tw, th, a.tile_size, &view, &tst, err, sizeof err)) {
            cli_error("render: %s", err);
            goto done;
        }
        t_upload = cli_now_ms() - t1;
    }
    free(tex);
    tex = NULL;
    free(tex_road);
    tex_road = NULL;
    free(nmap);
    nmap = NULL;

    frame_ms = malloc(a.frames * sizeof *frame_ms);
    mesh_ms = malloc(a.frames * sizeof *mesh_ms);
    draw_ms = malloc(a.frames * sizeof *draw_ms);
    mesh_seq = malloc(a.frames * sizeof *mesh_seq);
    tris_seq = malloc(a.frames * sizeof *tris_seq);
    if (!frame_ms || !mesh_ms || !draw_ms || !mesh_seq || !tris_seq) { cli_error("out of memory"); goto done; }
    rs_roam_view rv;
    memset(&rv, 0, sizeof rv);
    for (int k = 0; k < 3; k++) {
        rv.eye[k] = view.eye[k];
        rv.dir[k] = view.look[k] - view.eye[k];
    }
    rv.fov_y = a.fov;
    rv.width = a.width;
    rv.height = a.height;
    rv.pixel_error = a.pixel_error;
    rv.target_triangles = a.triangles;
    rv.far_dist = view.zfar;
    double ppm = fmin(a.width / view.map_w, a.height / view.map_h);
    for (uint32_t f = 0; f < a.frames; f++) {
        double f0 = cli_now_ms();
        if (a.ortho) /* heights do not move pixels top-down: the tolerance is in map metres */
            r = a.triangles ? rs_roam_refine_count(ctx, roam, a.triangles)
                            : rs_roam_refine_error(ctx, roam, a.pixel_error / ppm);
        else /* frame to frame: split and merge what the view changed */
            r = rs_roam_update(ctx, roam, &rv, 0);
        if (r == RS_ERR_POOL_EXHAUSTED || (a.ortho && r == RS_ERR_LIMIT)) {
            if (!warned) fprintf(stderr, "roadsplat: warning: %s\n", rs_ctx_message(ctx));
            warned = 1;
        } else if (r) {
            cli_error("%s: %s", a.dem, rs_ctx_message(ctx));
            goto done;
        }
        if (cli_mesh_extract(ctx, roam, a.dem, &mesh)) goto done;
        nv = mesh.nv;
        ni = mesh.ni;
        double f1 = cli_now_ms();
        if (sh ? rsh_draw(sh, &view, mesh.vtx, mesh.nrm, nv, mesh.idx, ni, err, sizeof err)
               : rg_draw(gl, &view, mesh.vtx, mesh.nrm, nv, mesh.idx, ni, err, sizeof err)) {
            cli_error("render: %s", err);
            goto done;
        }
        double f2 = cli_now_ms();
        mesh_ms[f] = mesh_seq[f] = f1 - f0;
        tris_seq[f] = (uint32_t)(ni / 3);
        draw_ms[f] = f2 - f1;
        frame_ms[f] = f2 - f0;
    }
    rs_roam_get_stats(roam, &rst);

    t1 = cli_now_ms();
    frame = malloc((size_t)a.width * a.height * 4);
    if (!frame) { cli_error("out of memory for a %u x %u image", a.width, a.height); goto done; }
    if (sh) rsh_read_rgba(sh, frame);
    else rg_read_rgba(gl, frame);
    for (size_t k = 0; k < (size_t)a.width * a.height; k++) /* RGBA -> RGB in place */
        memmove(frame + 3 * k, frame + 4 * k, 3);
    t_readback = cli_now_ms() - t1;
    t1 = cli_now_ms();
    {
        /* into OUT's temporary, opened before the work; renamed with --stats */
        cli_png_image img = { a.width, a.height, 3, 8, frame };
        cli_png_options po = { a.s.png_level_given ? a.s.png_level : -1, NULL, NULL, 0 };
        if (cli_png_encode(out.f, out.path, &img, &po) || cli_out_finish(&out)) goto done;
        if (!cli_png_file_complete(out.tmp)) {
            cli_error("%s: write failed: the PNG did not reach the disk whole", out.path);
            goto done;
        }
    }
    t_write = cli_now_ms() - t1;

    if (a.stats) {
        double fmin_ms = frame_ms[0], fmax_ms = frame_ms[0];
        for (uint32_t f = 1; f < a.frames; f++) {
            fmin_ms = fmin(fmin_ms, frame_ms[f]);
            fmax_ms = fmax(fmax_ms, frame_ms[f]);
        }
        double fm = median(frame_ms, a.frames), mm = median(mesh_ms, a.frames), dm = median(draw_ms, a.frames);
        char desc[256];
        if (sh) rsh_describe(sh, desc, sizeof desc);
        else rg_describe(gl, desc, sizeof desc);
        fprintf(so.f, "{\n  \"command\": \"render\",\n  \"gl\": \"%s\",\n", desc);
        fprintf(so.f, "  \"width\": %u,\n  \"height\": %u,\n  \"mode\": \"%s\",\n", a.width, a.height, a.ortho ? "ortho" : "perspective");
        /* in the frame of --camera / --look-at */
        fprintf(so.f, "  \"frame\": \"%s\",\n", frame_name);
        fprintf(so.f, "  \"camera\": [%.17g, %.17g, %.17g],\n  \"look_at\": [%.17g, %.17g, %.17g],\n  \"fov\": %.9g,\n",
                fx0 + view.eye[0], fy0 + fys * view.eye[1], view.eye[2], fx0 + view.look[0], fy0 + fys * view.look[1],
                view.look[2],
                a.fov);
        fprintf(so.f, "  \"lighting\": %s,\n  \"fog\": %s,\n", a.lighting ? "true" : "false", a.fog ? "true" : "false");
        fprintf(so.f, "  \"roads\": \"%s\",\n", sh ? "shader" : "texture");
        if (scene) {
            rs_gpu_scene_info si;
            rs_gpu_scene_get_info(scene, &si);
            fprintf(so.f, "  \"scene\": {\"segments\": %zu, \"index_cell\": %.9g, \"index_cells\": %zu, "
                          "\"index_entries\": %zu, \"bands\": %zu, \"markings\": %zu, \"bytes\": %zu},\n",
                    si.nseg, si.cell, (size_t)si.gw * si.gh, si.nseg_entries, si.nbands, si.nmarks, si.bytes);
        }
        if (a.triangles) fprintf(so.f, "  \"triangle_budget\": %u,\n", a.triangles);
        else fprintf(so.f, "  \"pixel_error\": %.9g,\n", a.pixel_error);
        fprintf(so.f, "  \"triangles\": %u,\n  \"vertices\": %zu,\n  \"roam_threshold\": %.9g,\n"
                      "  \"roam_frame_passes\": %u,\n  \"patches_culled\": %u,\n",
                rst.triangles, nv, rst.threshold, rst.frame_passes, rst.patches_culled);
        fprintf(so.f, "  \"texture\": {\"width\": %u, \"height\": %u, \"max_texture_size\": %u, \"tiles_x\": %u, "
                      "\"tiles_y\": %u, \"tile_core\": %u, \"base_level_min\": %u, \"base_level_max\": %u, "
                      "\"texels_uploaded\": %llu, \"texels_full_chain\": %llu",
                tw, th, tst.max_texture_size, tst.tiles_x, tst.tiles_y, tst.tile_core, tst.finest_level,
                tst.coarsest_base, (unsigned long long)tst.texels_uploaded, (unsigned long long)tst.texels_full);
        if (!sh) /* the texture mode's filter (the shader mode filters its own way) */
            fprintf(so.f, ", \"anisotropy\": %g, \"anisotropy_max\": %g", tst.anisotropy, tst.anisotropy_max);
        fprintf(so.f, "},\n");
        fprintf(so.f, "  \"frames\": %u,\n  \"fps\": %.3f,\n  \"fps_draw\": %.3f,\n", a.frames, 1000.0 / fm,
                1000.0 / dm);
        /* per frame: mesh time (update or refinement + extraction) and triangles */
        fprintf(so.f, "  \"per_frame\": {\"mesh_ms\": [");
        for (uint32_t f = 0; f < a.frames; f++) fprintf(so.f, "%s%.3f", f ? ", " : "", mesh_seq[f]);
        fprintf(so.f, "], \"mesh_triangles\": [");
        for (uint32_t f = 0; f < a.frames; f++) fprintf(so.f, "%s%u", f ? ", " : "", tris_seq[f]);
        fprintf(so.f, "]},\n");
        fprintf(so.f, "  \"timings_ms\": {\"read\": %.3f, \"roads\": %.3f, \"splat\": %.3f, \"roam_create\": %.3f, "
                      "\"context\": %.3f, \"upload\": %.3f, \"frame_median\": %.3f, \"frame_min\": %.3f, "
                      "\"frame_max\": %.3f, \"mesh_median\": %.3f, \"draw_median\": %.3f, \"readback\": %.3f, "
                      "\"write\": %.3f, \"total\": %.3f}\n}\n",
                t_read, t_grid, t_splat, t_roam, t_ctx, t_upload, fm, fmin_ms, fmax_ms, mm, dm, t_readback, t_write,
                cli_now_ms() - t_start);
        if (ferror(so.f)) { cli_error("%s: write failed", a.stats); goto done; }
    }
    cli_out *const all[2] = { &out, &so };
    if (cli_out_commit_all(all, 2)) goto done;
    rc = 0;
done:
    cli_out_abort(&out); /* no-ops once committed */
    cli_out_abort(&so);
    rg_destroy(gl);
    rsh_destroy(sh);
    rs_gpu_scene_free(ctx, scene);
    free(frame); free(tex); free(tex_road); free(nmap);
    cli_mesh_buf_free(&mesh);
    free(frame_ms); free(mesh_ms); free(draw_ms); free(mesh_seq); free(tris_seq);
    rs_roam_free(ctx, roam);
    rs_splatter_free(ctx, sp);
    rs_road_grid_free(ctx, grid);
    cli_splat_input_free(ctx, &in);
    rs_ctx_free(ctx);
    return rc;
}
#endif
