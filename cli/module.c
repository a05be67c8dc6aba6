/* Optional modules, loaded on first use (dlopen), so that the executable
 * itself links only libc, libm and libdeflate: `roadsplat --version` or a
 * mesh of a PGM start in about a millisecond, and never map OpenImageIO
 * (and its ~100 libraries) or OSMesa (which pulls in LLVM).
 *
 * - roadsplat-image.so: cli/imageio.cpp (OpenImageIO readers);
 * - roadsplat-render.so: cli/render.c + cli/render_gl.c (`roadsplat render`);
 * - roadsplat-gdal.so: cli/gdal.c (GDAL: georeferenced DEMs, OGR roads,
 *   GeoTIFF output; cli/gis.h);
 * - roadsplat-mbtiles.so: cli/mbtiles.c (SQLite: `tiles --format mbtiles`);
 * - roadsplat-gltf.so: cli/gltf.c (meshoptimizer: `mesh OUT.glb`);
 * - roadsplat-odr.so: cli/odr.c (expat: OpenDRIVE road sources).
 *
 * Search order: the folder of the running executable (/proc/self/exe: the
 * build folder, or a relocated install), then RS_MODULEDIR, the
 * $(LIBDIR)/roadsplat chosen at build time. The modules call back into the
 * executable (cli_* helpers, the library), which is linked with
 * --export-dynamic for that. Also here: the stand-ins of the module entry
 * points, and the start-up clock. */
#include "gis.h"
#include "gltf.h"

#include <dlfcn.h>
#include <sys/stat.h>
#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#ifndef RS_MODULEDIR
#define RS_MODULEDIR "/usr/local/lib/roadsplat"
#endif

typedef struct module {
    const char *name; /* "image" */
    const char *needs; /* what it wraps, for messages */
    void *handle;
    int failed;       /* tried and failed: do not retry (or repeat messages) */
    char why[800];
} module;

static module modules[] = {
    { "image", "OpenImageIO", NULL, 0, { 0 } },
    { "render", "OSMesa", NULL, 0, { 0 } },
    { "gdal", "GDAL", NULL, 0, { 0 } },
    { "mbtiles", "SQLite", NULL, 0, { 0 } },
    { "gltf", "meshoptimizer", NULL, 0, { 0 } },
    { "odr", "expat", NULL, 0, { 0 } },
};

/* Folder of the executable, with a trailing '/'; "" when unknown. */
static void exe_dir(char *out, size_t n)
{
    char buf[PATH_MAX];
    ssize_t k = readlink("/proc/self/exe", buf, sizeof buf - 1);
    out[0] = '\0';
    if (k <= 0) return;
    buf[k] = '\0';
    char *slash = strrchr(buf, '/');
    if (!slash) return;
    slash[1] = '\0';
    if (strlen(buf) < n) memcpy(out, buf, strlen(buf) + 1);
}

static void module_open(module *m)
{
    char dir[PATH_MAX], path[PATH_MAX + 64];
    const char *dirs[2];
    exe_dir(dir, sizeof dir);
    dirs[0] = dir;
    dirs[1] = RS_MODULEDIR "/";
    for (int i = 0; i < 2; i++) {
        if (!dirs[i][0]) continue;
        snprintf(path, sizeof path, "%sroadsplat-%s.so", dirs[i], m->name);
        if (access(path, F_OK) != 0) continue;
        m->handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
        if (m->handle) return;
        const char *e = dlerror();
        /* dlerror names the missing library ("libOpenImageIO.so.2.4: cannot open ...") */
        snprintf(m->why, sizeof m->why, "cannot load the %s module: %.480s", m->needs, e ? e : path);
        m->failed = 1;
        return;
    }
    snprintf(m->why, sizeof m->why, "the %s module roadsplat-%s.so is in neither %.256s nor %.256s/ (not built or not installed)",
             m->needs, m->name, dir[0] ? dir : "the executable's folder", RS_MODULEDIR);
    m->failed = 1;
}

void *cli_module_symbol(const char *name, const char *symbol, const char *what)
{
    module *m = NULL;
    for (size_t i = 0; i < sizeof modules / sizeof modules[0]; i++)
        if (!strcmp(modules[i].name, name)) m = &modules[i];
    if (!m) return NULL;
    if (!m->handle && !m->failed) module_open(m);
    void *sym = m->handle ? dlsym(m->handle, symbol) : NULL;
    if (m->handle && !sym) {
        snprintf(m->why, sizeof m->why, "roadsplat-%s.so has no %s (a module of another version?)", name, symbol);
        m->failed = 1;
    }
    if (!sym) cli_error("%s: %s", what, m->why);
    return sym;
}

/* ---- stand-ins for the module entry points -------------------------------- */

typedef int (*read_gray_fn)(const char *, const char *, uint32_t, uint32_t *, uint32_t *, float **);
typedef int (*read_rgba_fn)(const char *, const char *, uint64_t, uint32_t *, uint32_t *, uint8_t **);
typedef int (*main_fn)(int, char **);

int cli_image_read_gray_float(const char *path, const char *shown, uint32_t max_side, uint32_t *w, uint32_t *h,
                              float **data)
{
    void *s = cli_module_symbol("image", "cli_image_read_gray_float", shown);
    read_gray_fn f;
    *data = NULL;
    if (!s) return 1;
    memcpy(&f, &s, sizeof f); /* object to function pointer, as POSIX dlsym allows */
    return f(path, shown, max_side, w, h, data);
}

int cli_image_read_rgba8(const char *path, const char *shown, uint64_t max_pixels, uint32_t *w, uint32_t *h,
                         uint8_t **data)
{
    void *s = cli_module_symbol("image", "cli_image_read_rgba8", shown);
    read_rgba_fn f;
    *data = NULL;
    if (!s) return 1;
    memcpy(&f, &s, sizeof f);
    return f(path, shown, max_pixels, w, h, data);
}

int cli_render_main(int argc, char **argv)
{
#ifndef RS_WITH_OSMESA
    (void)argc; (void)argv;
    cli_error("render: this build has no OSMesa support (install libosmesa6-dev and rebuild)");
    return 1;
#else
    void *s = cli_module_symbol("render", "cli_render_main", "render");
    main_fn f;
    if (!s) return 1;
    memcpy(&f, &s, sizeof f);
    return f(argc, argv);
#endif
}

/* ---- the GDAL module (cli/gis.h) ------------------------------------------------ */

#ifdef RS_WITH_GDAL
/* The symbol, or NULL after the module's message naming `what`. */
static void *gdal_symbol(const char *symbol, const char *what)
{
    return cli_module_symbol("gdal", symbol, what);
}
#define GDAL_FN(type, var, symbol, what, fail)         \
    type var;                                          \
    do {                                               \
        void *s_ = gdal_symbol(symbol, what);          \
        if (!s_) return fail;                          \
        memcpy(&var, &s_, sizeof var);                 \
    } while (0)
#endif

int cli_gdal_available(void)
{
#ifdef RS_WITH_GDAL
    return 1;
#else
    return 0;
#endif
}

int cli_gdal_loadable(void)
{
#ifdef RS_WITH_GDAL
    module *m = &modules[2];
    if (!m->handle && !m->failed) module_open(m);
    return m->handle != NULL;
#else
    return 0;
#endif
}

#ifndef RS_WITH_GDAL
static int no_gdal(const char *what)
{
    cli_error("%s: this build has no GDAL support (install libgdal-dev, or run 'make deps', and rebuild)", what);
    return 1;
}
#endif

typedef int (*gdal_dem_fn)(cli_input *, const char *, uint32_t, uint32_t *, uint32_t *, float **, size_t *, cli_geo *);
typedef int (*gdal_roads_fn)(cli_input *, const char *, const cli_gdal_roads_opts *, char **, size_t *);
typedef int (*gdal_tiff_fn)(const char *, const char *, uint32_t, uint32_t, int, int, const void *, const double *,
                            const char *, int);
typedef int (*gdal_same_fn)(const char *, const char *, const char *);
typedef char *(*gdal_prj_fn)(const char *, const char *);

int cli_gdal_read_dem_input(cli_input *in, const char *role, uint32_t max_side, uint32_t *w, uint32_t *h, float **z,
                            size_t *nodata, cli_geo *geo)
{
    memset(geo, 0, sizeof *geo);
    *z = NULL;
    *nodata = 0;
#ifdef RS_WITH_GDAL
    GDAL_FN(gdal_dem_fn, f, "cli_gdal_read_dem_input", in->path, 1);
    return f(in, role, max_side, w, h, z, nodata, geo);
#else
    (void)in; (void)role; (void)max_side; (void)w; (void)h;
    return 2;
#endif
}

int cli_gdal_read_dem(const char *path, uint32_t max_side, uint32_t *w, uint32_t *h, float **z, size_t *nodata,
                      cli_geo *geo)
{
    cli_input in;
    memset(geo, 0, sizeof *geo);
    *z = NULL;
    *nodata = 0;
    if (cli_gdal_input_open(&in, path, 0)) return 1;
    int r = cli_gdal_read_dem_input(&in, NULL, max_side, w, h, z, nodata, geo);
    cli_input_close(&in);
    return r;
}

int cli_gdal_roads_text_input(cli_input *in, const char *role, const cli_gdal_roads_opts *o, char **text,
                              size_t *size)
{
    *text = NULL;
    *size = 0;
#ifdef RS_WITH_GDAL
    GDAL_FN(gdal_roads_fn, f, "cli_gdal_roads_text_input", o->shown ? o->shown : in->path, 1);
    return f(in, role, o, text, size);
#else
    (void)role;
    return no_gdal(o->shown ? o->shown : in->path);
#endif
}

int cli_gdal_roads_text(const char *path, const cli_gdal_roads_opts *o, char **text, size_t *size)
{
    cli_input in;
    *text = NULL;
    *size = 0;
#ifndef RS_WITH_GDAL
    (void)in;
    return no_gdal(o->shown ? o->shown : path);
#else
    if (cli_gdal_input_open(&in, path, 1)) return 1;
    int r = cli_gdal_roads_text_input(&in, NULL, o, text, size);
    cli_input_close(&in);
    return r;
#endif
}

int cli_gdal_write_tiff(const char *path, const char *shown, uint32_t w, uint32_t h, int channels, int bits,
                        const void *data, const double gt[6], const char *crs, int cog)
{
#ifdef RS_WITH_GDAL
    GDAL_FN(gdal_tiff_fn, f, "cli_gdal_write_tiff", shown, 1);
    return f(path, shown, w, h, channels, bits, data, gt, crs, cog);
#else
    (void)path; (void)w; (void)h; (void)channels; (void)bits; (void)data; (void)gt; (void)crs; (void)cog;
    return no_gdal(shown);
#endif
}

int cli_gdal_same_crs(const char *a, const char *b, const char *shown)
{
#ifdef RS_WITH_GDAL
    GDAL_FN(gdal_same_fn, f, "cli_gdal_same_crs", shown, -1);
    return f(a, b, shown);
#else
    (void)a; (void)b;
    no_gdal(shown);
    return -1;
#endif
}

char *cli_gdal_prj_text(const char *crs, const char *shown)
{
#ifdef RS_WITH_GDAL
    GDAL_FN(gdal_prj_fn, f, "cli_gdal_prj_text", shown, NULL);
    return f(crs, shown);
#else
    (void)crs;
    no_gdal(shown);
    return NULL;
#endif
}

static int gdal_trust;

void cli_gdal_set_trust(int on) { gdal_trust = on != 0; }

int cli_gdal_trusted(void) { return gdal_trust; }

int cli_gdal_path_check(const char *path)
{
    if (gdal_trust) return 0;
    struct stat st;
    const char *why = NULL;
    if (!strncmp(path, "/vsi", 4)) why = "a GDAL virtual file system path";
    else if (strstr(path, "://")) why = "a URL";
    else if (stat(path, &st) != 0) why = "not an existing file or folder (a connection string?)";
    if (!why) return 0;
    cli_error("%s: %s; roadsplat reads only local files unless --gdal-trust is given (docs/ROBUSTNESS.md)", path, why);
    return 1;
}

int cli_gdal_input_open(cli_input *in, const char *path, int folder_ok)
{
    struct stat st;
    int local = strncmp(path, "/vsi", 4) && !strstr(path, "://") && stat(path, &st) == 0;
    memset(in, 0, sizeof *in);
    in->path = path;
    in->fd = -1;
    if (!local && gdal_trust) return 0; /* GDAL reads the name: a URL, a /vsi path, a connection string */
    if (!local && (!strncmp(path, "/vsi", 4) || strstr(path, "://"))) return cli_gdal_path_check(path);
    return cli_input_open(in, path, folder_ok);
}

void cli_geo_free(cli_geo *g)
{
    free(g->crs);
    memset(g, 0, sizeof *g);
}

/* ---- start-up clock ----------------------------------------------------------- */

static double cpu_before_main_ms, main_wall_ms;

/* Runs after the dynamic loader, just before main(). */
__attribute__((constructor)) static void startup_mark(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) == 0)
        cpu_before_main_ms = (double)ts.tv_sec * 1000.0 + (double)ts.tv_nsec / 1e6;
    main_wall_ms = cli_now_ms();
}

double cli_startup_ms(void)
{
    return cpu_before_main_ms + (cli_now_ms() - main_wall_ms);
}

/* ---- the glTF module (cli/gltf.h) ------------------------------------------------ */
typedef int (*gltf_write_fn)(FILE *, const char *, const cli_gltf_mesh *, cli_gltf_stats *);
int cli_gltf_write(FILE *f, const char *shown, const cli_gltf_mesh *m, cli_gltf_stats *st)
{
    memset(st, 0, sizeof *st);
#ifdef RS_WITH_MESHOPT
    void *s = cli_module_symbol("gltf", "cli_gltf_write", shown);
    gltf_write_fn fn;
    if (!s) return 1;
    memcpy(&fn, &s, sizeof fn);
    return fn(f, shown, m, st);
#else
    (void)f; (void)m;
    cli_error("%s: this build has no glTF support (install libmeshoptimizer-dev, or run 'make deps', and rebuild)", shown);
    return 1;
#endif
}
