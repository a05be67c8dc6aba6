/* `roadsplat mesh`: ROAM-mesh a DEM to OBJ, PLY or binary glTF (atomic
 * write), with an optional stats JSON. Axes: y up; sample (row i, column j)
 * is written as (j*cs, height, i*cs); faces counter-clockwise seen from
 * above. */
#define _POSIX_C_SOURCE 200809L /* getrusage */
#include "bigalloc.h"
#include "gis.h"
#include "gltf.h"
#include "numfmt.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

static const char *mesh_usage =
    "usage: roadsplat mesh [--cell-size M] [--z-scale S] [--max-error E | --triangles N]\n"
    "                      [--pool N] [--normals] [--skirt DEPTH] [--stats FILE.json]\n"
    "                      [--texture IMG] [--gdal-trust] [--quiet]\n"
    "                      DEM OUT.obj|OUT.ply|OUT.glb\n"
    "  --max-error E   max vertical error in metres over every DEM sample (default 1)\n"
    "  --triangles N   finest mesh with at most N triangles (instead of --max-error)\n"
    "  --pool N        ROAM node pool size (default: what the finest mesh needs, <= 2^26)\n"
    "  --quiet, -q     no progress bars (otherwise drawn on a terminal for a refinement\n"
    "                  or a file write of over a second)\n"
    "  --texture IMG   OUT.obj: also write OUT.mtl with IMG as the diffuse texture;\n"
    "                  OUT.glb: embed IMG (PNG or JPEG) as the base colour texture\n"
    "OUT.glb is binary glTF 2.0 with normals, texture coordinates and the vertex\n"
    "order optimised by meshoptimizer (docs/gltf.md).\n"
    "  --gdal-trust    open the DEM with every GDAL driver and network access (a VRT\n"
    "                  naming any file, URLs); default: local files, an allow-list\n"
    "                  of formats (docs/ROBUSTNESS.md)\n"
    "A georeferenced DEM (GDAL, docs/gis.md) brings its cell size; vertices stay\n"
    "relative to sample (0,0), whose world point the header records.\n";

/* Page faults of this process so far (the mesh stage reports its own). */
static long minor_faults(void)
{
    struct rusage u;
    return getrusage(RUSAGE_SELF, &u) == 0 ? (long)u.ru_minflt : 0;
}

static int ends_with(const char *s, const char *suf)
{
    size_t a = strlen(s), b = strlen(suf);
    if (a < b) return 0;
    for (size_t k = 0; k < b; k++) {
        char c = s[a - b + k];
        if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
        if (c != suf[k]) return 0;
    }
    return 1;
}

/* Exact DEM height (metres) of vertex k; nodata samples keep the mesher's
 * filled value. The sample comes from the library's per-vertex sample
 * index, never from the float position. */
static double vertex_height(const float *z, double zs, const float *v, const uint32_t *smp, size_t k)
{
    float s = z[smp[k]];
    return isnan(s) ? (double)v[5 * k + 2] : (double)s * zs;
}

/* Max |mesh - DEM| over every valid sample, rasterizing each triangle. */
static double measure_error(const float *z, uint32_t W, double zs, const float *v, const uint32_t *smp,
                            const uint32_t *idx, size_t ntri)
{
    double mx = 0.0;
    for (size_t t = 0; t < ntri; t++) {
        long x[3], y[3];
        double h[3];
        for (int c = 0; c < 3; c++) {
            size_t k = idx[3 * t + (size_t)c];
            x[c] = (long)(smp[k] % W); y[c] = (long)(smp[k] / W);
            h[c] = vertex_height(z, zs, v, smp, k);
        }
        long cr = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
        if (cr == 0) continue;
        long x0 = x[0], x1 = x[0], y0 = y[0], y1 = y[0];
        for (int c = 1; c < 3; c++) {
            if (x[c] < x0) x0 = x[c];
            if (x[c] > x1) x1 = x[c];
            if (y[c] < y0) y0 = y[c];
            if (y[c] > y1) y1 = y[c];
        }
        for (long py = y0; py <= y1; py++)
            for (long px = x0; px <= x1; px++) {
                long w0 = (x[2] - x[1]) * (py - y[1]) - (y[2] - y[1]) * (px - x[1]);
                long w1 = (x[0] - x[2]) * (py - y[2]) - (y[0] - y[2]) * (px - x[2]);
                long w2 = (x[1] - x[0]) * (py - y[0]) - (y[1] - y[0]) * (px - x[0]);
                if (cr < 0) { w0 = -w0; w1 = -w1; w2 = -w2; }
                if (w0 < 0 || w1 < 0 || w2 < 0) continue;
                float s = z[(size_t)py * W + (size_t)px];
                if (isnan(s)) continue;
                double zi = (w0 * h[0] + w1 * h[1] + w2 * h[2]) / (double)(w0 + w1 + w2);
                double e = fabs(zi - (double)s * zs);
                if (e > mx) mx = e;
            }
    }
    return mx;
}

static void put_f32(unsigned char *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    b[0] = (unsigned char)u; b[1] = (unsigned char)(u >> 8); b[2] = (unsigned char)(u >> 16); b[3] = (unsigned char)(u >> 24);
}

static void put_u32(unsigned char *b, uint32_t u)
{
    b[0] = (unsigned char)u; b[1] = (unsigned char)(u >> 8); b[2] = (unsigned char)(u >> 16); b[3] = (unsigned char)(u >> 24);
}

/* The bar every 65536 lines or records of the file (a fine OBJ is
 * hundreds of MB of text: most of a mesh run). */
static void wrote(cli_progress *prog, size_t k, size_t base, size_t total)
{
    if ((k & 0xFFFF) == 0) cli_progress_cb(prog, base + k, total);
}

/* OBJ text a buffer at a time, its numbers by cli/numfmt.c (printf's
 * bytes: most of a fine mesh's run was printf). A line fits in the
 * OBJ_LINE_MAX bytes obj_room leaves. */
#define OBJ_LINE_MAX 256
typedef struct obj_text {
    FILE *f;
    size_t n;
    char b[1 << 16];
} obj_text;

static void obj_flush(obj_text *o)
{
    if (o->n) fwrite(o->b, 1, o->n, o->f); /* (a short write sets the stream's error, checked at the end) */
    o->n = 0;
}

/* Where the next line goes (room for OBJ_LINE_MAX bytes); obj_end takes
 * the line, written up to c. */
static char *obj_room(obj_text *o)
{
    if (o->n > sizeof o->b - OBJ_LINE_MAX) obj_flush(o);
    return o->b + o->n;
}

static void obj_end(obj_text *o, char *c)
{
    *c++ = '\n';
    o->n = (size_t)(c - o->b);
}

/* " " and printf's "%.*g" of v at c; past it. */
static char *obj_num(char *c, double v, int prec)
{
    *c++ = ' ';
    return c + cli_fmt_g(c, v, prec);
}

/* `world`: comment lines on the world frame (or ""); mtl: the .mtl's file
 * name for OBJ (or NULL); prog: the write's progress bar. */
static int write_mesh(FILE *f, int ply, const float *z, double zs, const float *v, const uint32_t *smp,
                      const float *n, size_t nv, const uint32_t *idx, size_t ni, size_t ntop, const char *world,
                      const char *mtl, cli_progress *prog)
{
    const size_t nt = ni / 3, total = ply ? nv + nt : (n ? 3 : 2) * nv + nt;
    if (!ply) {
        fprintf(f, "# roadsplat mesh: y up, v = (column*cs, height, row*cs) metres\n%s", world);
        if (mtl) fprintf(f, "mtllib %s\nusemtl roadsplat\n", mtl);
        obj_text o;
        o.f = f, o.n = 0;
        for (size_t k = 0; k < nv; k++) {
            const float *p = v + 5 * k;
            double h = k < ntop ? vertex_height(z, zs, v, smp, k) : (double)p[2];
            char *c = obj_room(&o);
            *c++ = 'v';
            c = obj_num(c, (double)p[0], 9);
            c = obj_num(c, h, 10);
            obj_end(&o, obj_num(c, (double)p[1], 9));
            wrote(prog, k, 0, total);
        }
        for (size_t k = 0; k < nv; k++) {
            char *c = obj_room(&o);
            *c++ = 'v';
            *c++ = 't';
            c = obj_num(c, (double)v[5 * k + 3], 9);
            obj_end(&o, obj_num(c, 1.0 - (double)v[5 * k + 4], 9));
            wrote(prog, k, nv, total);
        }
        if (n)
            for (size_t k = 0; k < nv; k++) {
                char *c = obj_room(&o);
                *c++ = 'v';
                *c++ = 'n';
                c = obj_num(c, (double)n[3 * k], 7); /* (nx, nz, ny: y up) */
                c = obj_num(c, (double)n[3 * k + 2], 7);
                obj_end(&o, obj_num(c, (double)n[3 * k + 1], 7));
                wrote(prog, k, 2 * nv, total);
            }
        for (size_t t = 0; t < ni; t += 3) {
            wrote(prog, t / 3, total - nt, total);
            char *c = obj_room(&o);
            *c++ = 'f';
            for (int i = 0; i < 3; i++) { /* (a/a/a with normals, else a/a) */
                *c++ = ' ';
                size_t k = cli_fmt_u(c, idx[t + (size_t)i] + 1ul);
                c += k;
                for (int r = n ? 2 : 1; r > 0; r--) {
                    *c++ = '/';
                    memmove(c, c - k - 1, k);
                    c += k;
                }
            }
            obj_end(&o, c);
        }
        obj_flush(&o);
    } else {
        fprintf(f, "ply\nformat binary_little_endian 1.0\ncomment roadsplat mesh: y up, (column*cs, height, row*cs) metres\n");
        for (const char *l = world; *l;) { /* the world lines as PLY comments */
            const char *e = strchr(l, '\n');
            size_t len = e ? (size_t)(e - l) : strlen(l);
            fprintf(f, "comment%.*s\n", (int)(len > 1 ? len - 1 : 0), l + 1);
            l += len + (e ? 1 : 0);
        }
        fprintf(f, ""
                   "element vertex %zu\nproperty float x\nproperty float y\nproperty float z\n"
                   "property float s\nproperty float t\n", nv);
        if (n) fprintf(f, "property float nx\nproperty float ny\nproperty float nz\n");
        fprintf(f, "element face %zu\nproperty list uchar uint vertex_indices\nend_header\n", ni / 3);
        unsigned char b[32];
        for (size_t k = 0; k < nv; k++) {
            const float *p = v + 5 * k;
            double h = k < ntop ? vertex_height(z, zs, v, smp, k) : (double)p[2];
            put_f32(b, p[0]); put_f32(b + 4, (float)h); put_f32(b + 8, p[1]);
            put_f32(b + 12, p[3]); put_f32(b + 16, 1.0f - p[4]);
            size_t len = 20;
            if (n) { put_f32(b + 20, n[3 * k]); put_f32(b + 24, n[3 * k + 2]); put_f32(b + 28, n[3 * k + 1]); len = 32; }
            if (fwrite(b, 1, len, f) != len) return -1;
            wrote(prog, k, 0, total);
        }
        for (size_t t = 0; t < ni; t += 3) {
            wrote(prog, t / 3, nv, total);
            b[0] = 3;
            put_u32(b + 1, idx[t]); put_u32(b + 5, idx[t + 1]); put_u32(b + 9, idx[t + 2]);
            if (fwrite(b, 1, 13, f) != 13) return -1;
        }
    }
    return ferror(f) ? -1 : 0;
}

/* JSON string body of s (quotes, backslashes and control characters
 * escaped) into out; 1 when it did not fit. */
static int json_escape(const char *s, char *out, size_t n)
{
    size_t k = 0;
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        char e[8];
        int len = c == '"' || c == '\\' ? snprintf(e, sizeof e, "\\%c", c)
                  : c < 0x20              ? snprintf(e, sizeof e, "\\u%04x", c)
                                          : snprintf(e, sizeof e, "%c", c);
        if (k + (size_t)len + 1 > n) return 1;
        memcpy(out + k, e, (size_t)len);
        k += (size_t)len;
    }
    out[k] = '\0';
    return 0;
}

/* OUT.glb: the same vertices (exact heights), texture coordinates and
 * normals as OUT.obj, through the glTF module; the texture file embedded;
 * the world frame of a georeferenced DEM in the scene's extras. */
static int write_glb(FILE *f, const char *outp, const float *z, double zs, const float *v, const uint32_t *smp,
                     const float *n, size_t nv, const uint32_t *idx, size_t ni, size_t ntop, const cli_geo *geo,
                     const char *texture, cli_gltf_stats *gs)
{
    int rc = 1;
    float *pos = malloc((nv ? nv : 1) * 3 * sizeof *pos), *uv = malloc((nv ? nv : 1) * 2 * sizeof *uv);
    float *nn = n ? malloc((nv ? nv : 1) * 3 * sizeof *nn) : NULL;
    char *img = NULL, *extras = NULL, *crs = NULL;
    size_t img_len = 0;
    cli_gltf_mesh m;
    memset(&m, 0, sizeof m);
    if (!pos || !uv || (n && !nn)) { cli_error("%s: out of memory for %zu vertices", outp, nv); goto out; }
    for (size_t k = 0; k < nv; k++) {
        const float *p = v + 5 * k;
        double h = k < ntop ? vertex_height(z, zs, v, smp, k) : (double)p[2];
        pos[3 * k] = p[0];
        pos[3 * k + 1] = (float)h;
        pos[3 * k + 2] = p[1];
        uv[2 * k] = p[3];
        uv[2 * k + 1] = p[4]; /* glTF's v runs down the image, as the library's does */
        if (n) {
            nn[3 * k] = n[3 * k];
            nn[3 * k + 1] = n[3 * k + 2];
            nn[3 * k + 2] = n[3 * k + 1];
        }
    }
    m.nv = nv;
    m.ni = ni;
    m.pos = pos;
    m.uv = uv;
    m.nrm = nn;
    m.idx = idx;
    if (texture) {
        /* embedded as it is: glTF's core images are PNG and JPEG */
        if (cli_read_file(texture, (size_t)1 << 30, &img, &img_len)) goto out;
        const unsigned char *b = (const unsigned char *)img;
        if (img_len >= 8 && !memcmp(b, "\x89PNG\r\n\x1a\n", 8)) m.image_mime = "image/png";
        else if (img_len >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) m.image_mime = "image/jpeg";
        else {
            cli_error("--texture: %s is neither PNG nor JPEG, the two image formats a .glb can embed", texture);
            goto out;
        }
        m.image = b;
        m.image_len = img_len;
    }
    if (geo->georef) {
        size_t cap = 2 * (geo->crs ? strlen(geo->crs) : 0) * 3 + 1;
        extras = malloc(cap + 512);
        crs = malloc(cap);
        if (!extras || !crs || json_escape(geo->crs ? geo->crs : "", crs, cap)) {
            cli_error("%s: out of memory for the world frame", outp);
            goto out;
        }
        snprintf(extras, cap + 512,
                 "{\"roadsplat\":{\"world_origin\":[%.17g,%.17g],\"crs\":\"%s\",\"frame\":\"a vertex (vx, vy, vz) is "
                 "at world x0 + vx (east), y0 - vz (north), height vy\"}}",
                 geo->gt[0] + geo->gt[1] / 2, geo->gt[3] + geo->gt[5] / 2, crs);
        m.extras = extras;
    }
    rc = cli_gltf_write(f, outp, &m, gs);
out:
    free(pos);
    free(uv);
    free(nn);
    free(img);
    free(extras);
    free(crs);
    return rc;
}

int cli_mesh_main(int argc, char **argv)
{
    double t_start = cli_now_ms();
    double cs = 1.0, zs = 1.0, max_error = 1.0, skirt = 0.0;
    uint32_t tris = 0, pool = 0;
    int have_err = 0, normals = 0, quiet = 0;
    const char *stats_path = NULL, *in = NULL, *outp = NULL, *texture = NULL;
    int cs_given = 0;
    for (int a = 1; a < argc; a++) {
        const char *s = argv[a];
        int more = a + 1 < argc;
        if (!strcmp(s, "--help") || !strcmp(s, "-h")) { fputs(mesh_usage, stdout); return 0; }
        else if (!strcmp(s, "--normals")) normals = 1;
        else if (!strcmp(s, "--quiet") || !strcmp(s, "-q")) quiet = 1;
        else if (!strcmp(s, "--gdal-trust")) cli_gdal_set_trust(1);
        else if (s[0] == '-' && s[1] == '-' && !more) { cli_error("%s needs a value", s); return 1; }
        else if (!strcmp(s, "--cell-size")) { if (cli_parse_double(s, argv[++a], &cs)) return 1; cs_given = 1; }
        else if (!strcmp(s, "--texture")) texture = argv[++a];
        else if (!strcmp(s, "--z-scale")) { if (cli_parse_double(s, argv[++a], &zs)) return 1; }
        else if (!strcmp(s, "--max-error")) { if (cli_parse_double(s, argv[++a], &max_error)) return 1; have_err = 1; }
        else if (!strcmp(s, "--triangles")) {
            if (cli_parse_u32(s, argv[++a], &tris)) return 1;
            if (tris == 0) { cli_error("--triangles: '%s' must be >= 1", argv[a]); return 1; }
        }
        else if (!strcmp(s, "--pool")) { if (cli_parse_u32(s, argv[++a], &pool)) return 1; }
        else if (!strcmp(s, "--skirt")) { if (cli_parse_double(s, argv[++a], &skirt)) return 1; }
        else if (!strcmp(s, "--stats")) stats_path = argv[++a];
        else if (s[0] == '-' && s[1] != '\0') { cli_error("mesh: unknown option '%s'\n%s", s, mesh_usage); return 1; }
        else if (!in) in = s;
        else if (!outp) outp = s;
        else { cli_error("mesh: unexpected argument '%s'", s); return 1; }
    }
    if (!in || !outp) { cli_error("mesh: need DEM and OUT.obj|OUT.ply|OUT.glb\n%s", mesh_usage); return 1; }
    const int glb = ends_with(outp, ".glb");
    /* a .glb reads the texture (embeds it); OBJ only names it */
    const cli_file_role outs[2] = { { outp, "OUT" }, { stats_path, "--stats" } },
                        ins[2] = { { in, "DEM" }, { glb ? texture : NULL, "--texture" } };
    if (cli_check_outputs(outs, 2, ins, 2)) return 1;
    if (have_err && tris) { cli_error("mesh: --max-error and --triangles are exclusive"); return 1; }
    if (!(cs > 0)) { cli_error("--cell-size: '%g' must be > 0", cs); return 1; }
    if (!(zs > 0)) { cli_error("--z-scale: '%g' must be > 0", zs); return 1; }
    /* Vertices are floats: a cell size below the smallest normal float
     * would collapse them (and their sample positions with them). */
    if (cs < FLT_MIN) { cli_error("--cell-size: '%g' is below %g, the smallest cell size a float vertex holds", cs, (double)FLT_MIN); return 1; }
    if (cs > FLT_MAX) { cli_error("--cell-size: '%g' is beyond the float range of the output (%g)", cs, (double)FLT_MAX); return 1; }
    if (skirt > FLT_MAX) { cli_error("--skirt: '%g' is beyond the float range of the output (%g)", skirt, (double)FLT_MAX); return 1; }
    if (!(max_error >= 0)) { cli_error("--max-error: '%g' must be >= 0", max_error); return 1; }
    if (!(skirt >= 0)) { cli_error("--skirt: '%g' must be >= 0", skirt); return 1; }
    if (have_err == 0 && tris == 0) have_err = 1;
    int ply = ends_with(outp, ".ply");
    if (!ply && !glb && !ends_with(outp, ".obj")) { cli_error("%s: output must end in .obj, .ply or .glb", outp); return 1; }
    if (texture && ply) { cli_error("--texture: %s is a PLY; the material file goes with OUT.obj", outp); return 1; }
    if (glb) normals = 1; /* engines light a .glb: always with normals */
    /* OUT.mtl beside OUT.obj, named in its mtllib line */
    char *mtl_path = NULL;
    const char *mtl_name = NULL;
    if (texture && !glb) {
        size_t n = strlen(outp);
        if (!(mtl_path = malloc(n + 1))) { cli_error("out of memory"); return 1; }
        memcpy(mtl_path, outp, n - 4);
        strcpy(mtl_path + n - 4, ".mtl");
        const char *slash = strrchr(mtl_path, '/');
        mtl_name = slash ? slash + 1 : mtl_path;
        const cli_file_role o2[3] = { { outp, "OUT" }, { stats_path, "--stats" }, { mtl_path, "OUT.mtl" } },
                            i2[1] = { { in, "DEM" } };
        if (cli_check_outputs(o2, 3, i2, 1)) { free(mtl_path); return 1; }
    }

    /* Huge pages for the bulk of the landscape, the DEM and the output
     * buffers: their first touch in 4 KiB pages was most of a cold mesh
     * (docs/roam.md, "Cold roadsplat mesh"). */
    cli_bigalloc *ba = cli_bigalloc_create(0);
    rs_allocator hook;
    memset(&hook, 0, sizeof hook);
    if (ba) hook = cli_bigalloc_hook(ba);
    rs_ctx *ctx = NULL;
    if (!ba || rs_ctx_create(&hook, NULL, &ctx) != RS_OK) {
        cli_bigalloc_destroy(ba);
        free(mtl_path);
        cli_error("out of memory");
        return 1;
    }
    int rc = 1;
    rs_roam *L = NULL;
    float *v = NULL, *nrm = NULL;
    uint32_t *idx = NULL;
    /* OUT and the stats go to temporaries opened before the work (an
     * unwritable target fails at once) and are renamed only when both are
     * written, so a failing stats file leaves the old OUT alone too. */
    cli_out out, so, mo_out;
    memset(&out, 0, sizeof out);
    memset(&so, 0, sizeof so);
    memset(&mo_out, 0, sizeof mo_out);
    uint32_t *smp = NULL;
    rs_dem *dem = NULL;
    cli_geo geo;
    memset(&geo, 0, sizeof geo);
    char world[400] = "";
    if (cli_out_open(&out, outp) || (stats_path && cli_out_open(&so, stats_path)) ||
        (mtl_path && cli_out_open(&mo_out, mtl_path)))
        goto done;
    dem = cli_geo_load_dem(ctx, in, &geo);
    if (!dem) goto done;
    if (geo.georef) { /* the DEM's cell size; the world point of sample (0,0) in the header */
        if (cs_given) {
            cli_error("%s: --cell-size: the DEM is georeferenced, so its cell size (%.12g) comes from the file; leave "
                      "the option out", in, geo.gt[1]);
            goto done;
        }
        cs = geo.gt[1];
        snprintf(world, sizeof world,
                 "# world: sample (0,0) at x %.17g, y %.17g (north up%s%.60s); a vertex (vx, vy, vz) is at x + vx "
                 "(east), y - vz (north), height vy\n",
                 geo.gt[0] + geo.gt[1] / 2, geo.gt[3] + geo.gt[5] / 2, geo.crs && strlen(geo.crs) < 60 ? ", " : "",
                 geo.crs && strlen(geo.crs) < 60 ? geo.crs : "");
    }
    double read_ms = cli_now_ms() - t_start;
    /* Every value that reaches the float output must fit, checked before
     * the work with the option that decides it named. */
    {
        uint32_t W = rs_dem_width(dem), H = rs_dem_height(dem);
        double side = (double)(W > H ? W : H) - 1.0, zabs = 0;
        const float *z = rs_dem_samples(dem);
        for (size_t k = 0; k < (size_t)W * H; k++)
            if (fabs((double)z[k]) > zabs) zabs = fabs((double)z[k]); /* NaN (nodata) compares false */
        if (side * cs > FLT_MAX) {
            cli_error("--cell-size: '%g' puts the map edge at %g m, beyond the float range of the output (%g)", cs,
                      side * cs, (double)FLT_MAX);
            goto done;
        }
        if (zabs * zs > FLT_MAX || zabs > FLT_MAX / 4) {
            cli_error("--z-scale: '%g' makes heights of %g m, beyond the float range of the output (%g)", zs,
                      zabs * zs, (double)FLT_MAX);
            goto done;
        }
        if (zabs * zs + skirt > FLT_MAX) {
            cli_error("--skirt: '%g' below heights down to %g m is beyond the float range of the output (%g)", skirt,
                      -zabs * zs, (double)FLT_MAX);
            goto done;
        }
    }
    {
        rs_dem_frame frame;
        memset(&frame, 0, sizeof frame);
        frame.cell_size = cs;
        frame.z_scale = zs;
        if (rs_dem_set_frame(ctx, dem, &frame) != RS_OK) {
            cli_error("%s: %s", cs < 1e-9 || cs > 1e9 ? "--cell-size" : "--z-scale", rs_ctx_message(ctx));
            goto done;
        }
    }
    /* timings_ms.mesh: everything between the DEM in memory and the mesh in
     * the output arrays: rs_roam_create, the refinement, the mesh bound,
     * allocating the output arrays and rs_roam_extract (docs/roam.md) */
    long flt0 = minor_faults();
    double t_mesh = cli_now_ms();
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    if (pool) o.pool_nodes = pool;
    else {
        /* the CLI defaults to a pool that holds the finest mesh (within the
         * limit): about one node per four cells, doubled for patch padding */
        uint64_t full = (uint64_t)rs_dem_width(dem) * rs_dem_height(dem) / 2 + 64;
        o.pool_nodes = (uint32_t)(full < (1u << 26) ? full : (1u << 26));
    }
    rs_result r = rs_roam_create(ctx, dem, &o, &L);
    if (r != RS_OK) { cli_error("%s: %s", in, rs_ctx_message(ctx)); goto done; }
    double t_refine = cli_now_ms();
    cli_progress prog;
    cli_progress_init(&prog, "mesh", quiet);
    rs_ctx_set_progress(ctx, cli_progress_cb, &prog);
    r = tris ? rs_roam_refine_count(ctx, L, tris) : rs_roam_refine_error(ctx, L, max_error);
    rs_ctx_set_progress(ctx, NULL, NULL);
    cli_progress_done(&prog);
    if (r == RS_ERR_POOL_EXHAUSTED) fprintf(stderr, "roadsplat: warning: %s\n", rs_ctx_message(ctx));
    else if (r != RS_OK) { cli_error("%s: %s", in, rs_ctx_message(ctx)); goto done; }
    double t_extract = cli_now_ms();
    rs_roam_mesh_options mo;
    memset(&mo, 0, sizeof mo);
    mo.normals = normals;
    mo.skirt_depth = skirt;
    size_t mv, mi, nv, ni;
    rs_roam_mesh_bound(L, &mo, &mv, &mi);
    v = cli_big_malloc(ba, (mv ? mv : 1) * 5 * sizeof *v);
    nrm = normals ? cli_big_malloc(ba, (mv ? mv : 1) * 3 * sizeof *nrm) : NULL;
    idx = cli_big_malloc(ba, (mi ? mi : 1) * sizeof *idx);
    smp = cli_big_malloc(ba, (mv ? mv : 1) * sizeof *smp);
    mo.samples = smp;
    if (!v || !idx || !smp || (normals && !nrm)) { cli_error("out of memory for a mesh of %zu vertices", mv); goto done; }
    if (rs_roam_extract(ctx, L, &mo, v, nrm, mv, idx, mi, &nv, &ni) != RS_OK) {
        cli_error("%s: %s", in, rs_ctx_message(ctx));
        goto done;
    }
    double t_mesh_end = cli_now_ms(), mesh_ms = t_mesh_end - t_mesh;
    long mesh_faults = minor_faults() - flt0;
    rs_roam_stats st;
    rs_roam_get_stats(L, &st);
    size_t ntop = 0;
    for (size_t k = 0; k < 3 * (size_t)st.triangles; k++) if (idx[k] + (size_t)1 > ntop) ntop = idx[k] + (size_t)1;
    if (mtl_path) { /* the texture covers the DEM's cells as the mesh's UVs do */
        if (fprintf(mo_out.f, "# roadsplat mesh material\n%snewmtl roadsplat\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nillum 1\n"
                              "map_Kd %s\n", world, texture) < 0) {
            cli_error("%s: write failed: %s", mtl_path, strerror(errno ? errno : EIO));
            goto done;
        }
    }
    cli_gltf_stats gs;
    memset(&gs, 0, sizeof gs);
    if (glb) {
        if (write_glb(out.f, outp, rs_dem_samples(dem), zs, v, smp, nrm, nv, idx, ni, ntop, &geo, texture, &gs))
            goto done;
    } else {
        cli_progress wprog;
        cli_progress_init(&wprog, "write", quiet);
        int bad = write_mesh(out.f, ply, rs_dem_samples(dem), zs, v, smp, nrm, nv, idx, ni, ntop, world, mtl_name, &wprog);
        cli_progress_done(&wprog);
        if (bad) {
            cli_error("%s: write failed: %s", outp, strerror(errno ? errno : EIO));
            goto done;
        }
    }
    double write_ms = cli_now_ms() - t_mesh_end;
    if (stats_path) {
        double measured = measure_error(rs_dem_samples(dem), rs_dem_width(dem), zs, v, smp, idx, st.triangles);
        fprintf(so.f, "{\n  \"command\": \"mesh\",\n  \"dem\": {\"width\": %u, \"height\": %u, \"cell_size\": %.9g, \"z_scale\": %.9g},\n",
                st.width, st.height, cs, zs);
        fprintf(so.f, "  \"mode\": \"%s\",\n", tris ? "triangles" : "max_error");
        if (tris) fprintf(so.f, "  \"triangle_budget\": %u,\n", tris);
        fprintf(so.f, "  \"max_error_requested\": %.9g,\n  \"max_error_measured\": %.9g,\n  \"max_error_bound\": %.9g,\n",
                tris ? st.threshold : max_error, measured, st.max_error_bound);
        fprintf(so.f, "  \"triangles\": %u,\n  \"vertices\": %zu,\n  \"indices\": %zu,\n", st.triangles, nv, ni);
        if (glb)
            fprintf(so.f, "  \"glb\": {\"vertices\": %zu, \"triangles\": %zu, \"acmr_before\": %.4f, \"acmr_after\": %.4f, "
                          "\"bytes\": %zu},\n",
                    gs.vertices, gs.triangles, gs.acmr_before, gs.acmr_after, gs.bytes);
        fprintf(so.f, "  \"patch_size\": %u,\n  \"pool\": {\"nodes\": %u, \"used\": %u, \"base_nodes\": %u, \"exhausted\": %s, \"bytes\": %llu},\n",
                st.patch_size, st.pool_nodes, st.pool_used, st.base_nodes, st.pool_exhausted ? "true" : "false",
                (unsigned long long)st.bytes);
        cli_bigalloc_stats bs;
        cli_bigalloc_get_stats(ba, &bs);
        fprintf(so.f, "  \"memory\": {\"mesh_page_faults\": %ld, \"mapped_blocks\": %zu, \"mapped_bytes\": %zu},\n",
                mesh_faults, bs.mapped_blocks, bs.mapped_bytes);
        fprintf(so.f, "  \"timings_ms\": {\"read\": %.3f, \"mesh\": %.3f, \"create\": %.3f, \"refine\": %.3f, "
                      "\"extract\": %.3f, \"write\": %.3f, \"total\": %.3f}\n}\n",
                read_ms, mesh_ms, t_refine - t_mesh, t_extract - t_refine, t_mesh_end - t_extract, write_ms,
                cli_now_ms() - t_start);
        if (fflush(so.f) != 0 || ferror(so.f)) {
            cli_error("%s: write failed: %s", stats_path, strerror(errno ? errno : EIO));
            goto done;
        }
    }
    if (fflush(out.f) != 0 || ferror(out.f)) {
        cli_error("%s: write failed: %s", outp, strerror(errno ? errno : EIO));
        goto done;
    }
    cli_out *const all[3] = { &out, &so, &mo_out };
    if (cli_out_commit_all(all, 3)) goto done;
    rc = 0;
done:
    cli_out_abort(&out); /* no-ops once committed */
    cli_out_abort(&so);
    cli_out_abort(&mo_out);
    free(mtl_path);
    cli_geo_free(&geo);
    cli_big_free(ba, v); cli_big_free(ba, nrm); cli_big_free(ba, idx); cli_big_free(ba, smp);
    rs_roam_free(ctx, L);
    if (dem) rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    cli_bigalloc_destroy(ba);
    return rc;
}

int cli_mesh_extract(rs_ctx *ctx, rs_roam *roam, const char *shown, cli_mesh_buf *m)
{
    rs_roam_mesh_options mo;
    memset(&mo, 0, sizeof mo);
    mo.normals = 1;
    size_t mv, mi;
    rs_roam_mesh_bound(roam, &mo, &mv, &mi);
    if (mv > m->cap_v) {
        free(m->vtx);
        free(m->nrm);
        m->vtx = malloc(mv * 5 * sizeof *m->vtx);
        m->nrm = malloc(mv * 3 * sizeof *m->nrm);
        m->cap_v = m->vtx && m->nrm ? mv : 0;
        if (!m->cap_v) { cli_error("out of memory for a mesh of %zu vertices", mv); return 1; }
    }
    if (mi > m->cap_i) {
        free(m->idx);
        m->idx = malloc(mi * sizeof *m->idx);
        m->cap_i = m->idx ? mi : 0;
        if (!m->idx) { cli_error("out of memory for a mesh of %zu indices", mi); return 1; }
    }
    if (rs_roam_extract(ctx, roam, &mo, m->vtx, m->nrm, m->cap_v, m->idx, m->cap_i, &m->nv, &m->ni)) {
        cli_error("%s: %s", shown, rs_ctx_message(ctx));
        return 1;
    }
    return 0;
}

void cli_mesh_buf_free(cli_mesh_buf *m)
{
    free(m->vtx);
    free(m->nrm);
    free(m->idx);
    memset(m, 0, sizeof *m);
}
