/* ROAM mesher against @mapbox/martini (RTIN, run with node) on the same
 * grids in the same run: triangles, true max / RMS vertical error (measured
 * by tests/roam_check.h for both), and build + extraction time (medians).
 * Usage: roam OUTDIR  -> OUTDIR/roam.md, OUTDIR/roam.csv, and the cold CLI
 * section (issue 18, target 4: `roadsplat mesh` processes against martini
 * warm, same run) in OUTDIR/roam_cold.md and .csv; `roam OUTDIR cold` runs
 * that section alone.
 * martini comes from the npm registry into $BUILD/npm (installed here when
 * missing); without node or npm the martini columns say so. */
#include "roadsplat.h"
#include "../roam_check.h"
#include "../scenes.h"

#include "timing.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#define RUNS 5

typedef struct run_result {
    uint32_t tris;
    double build_ms, refine_ms, total_ms, max_err, rms_err;
    int valid;
} run_result;

/* create + refine_error(E) + extract, RUNS times; mesh of the last run
 * checked. With `reuse`, the landscape is created once before the runs (like
 * martini's `new Martini(size)`) and each run re-targets it at the DEM with
 * rs_roam_set_dem (like martini's createTile), so build = set_dem. */
static int run_roam(rs_ctx *ctx, const rs_dem *dem, const float *z, uint32_t W, uint32_t H, double E,
                    int check, int reuse, run_result *out)
{
    double tb[RUNS], tr[RUNS], tt[RUNS];
    float *v = NULL;
    uint32_t *idx = NULL;
    size_t nv = 0, ni = 0;
    memset(out, 0, sizeof *out);
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    o.pool_nodes = 1u << 22;
    rs_roam *kept = NULL;
    if (reuse && rs_roam_create(ctx, dem, &o, &kept) != RS_OK) return -1;
    for (int r = 0; r < RUNS; r++) {
        double t0 = tm_now_ms();
        rs_roam *L = kept;
        if (reuse) {
            if (rs_roam_set_dem(ctx, L, dem) != RS_OK) { rs_roam_free(ctx, kept); return -1; }
        } else if (rs_roam_create(ctx, dem, &o, &L) != RS_OK) return -1;
        double t1 = tm_now_ms();
        rs_result rr = rs_roam_refine_error(ctx, L, E);
        if (rr != RS_OK) { fprintf(stderr, "roam bench: %s\n", rs_ctx_message(ctx)); rs_roam_free(ctx, L); return -1; }
        size_t mv, mi;
        rs_roam_mesh_bound(L, NULL, &mv, &mi);
        free(v); free(idx);
        v = malloc(mv * 5 * sizeof *v);
        idx = malloc(mi * sizeof *idx);
        if (!v || !idx || rs_roam_extract(ctx, L, NULL, v, NULL, mv, idx, mi, &nv, &ni) != RS_OK) {
            rs_roam_free(ctx, L); free(v); free(idx); return -1;
        }
        double t2 = tm_now_ms();
        tb[r] = t1 - t0; tr[r] = t2 - t1; tt[r] = t2 - t0;
        rs_roam_stats st;
        rs_roam_get_stats(L, &st);
        out->tris = st.triangles;
        if (!reuse) rs_roam_free(ctx, L);
    }
    rs_roam_free(ctx, kept);
    out->build_ms = tm_median(tb, RUNS);
    out->refine_ms = tm_median(tr, RUNS);
    out->total_ms = tm_median(tt, RUNS);
    if (check) {
        int32_t *gx = malloc(nv * sizeof *gx), *gy = malloc(nv * sizeof *gy);
        double *vz = malloc(nv * sizeof *vz);
        rc_result res;
        for (size_t k = 0; k < nv; k++) {
            gx[k] = (int32_t)lround(v[5 * k]); gy[k] = (int32_t)lround(v[5 * k + 1]); vz[k] = (double)z[(size_t)gy[k] * W + (size_t)gx[k]];
        }
        rc_check(W, H, z, 1.0, gx, gy, vz, nv, idx, ni / 3, &res);
        out->valid = rc_all_ok(&res);
        out->max_err = res.max_err;
        out->rms_err = res.rms_err;
        free(gx); free(gy); free(vz);
    }
    free(v); free(idx);
    return 0;
}

typedef struct mart {
    double E, ms, build_ms, init_ms, cold_ms, min_ms, max_err, rms_err;
    uint32_t tris;
    int covered;
} mart;

/* The martini package under $BUILD/npm, installed from the npm registry
 * when missing; 0 when there. */
static int martini_dir(char *mdir, size_t n)
{
    const char *b = getenv("BUILD");
    char npm[512], cmd[1200], probe[700];
    snprintf(npm, sizeof npm, "%s/npm", b && *b ? b : "build");
    snprintf(mdir, n, "%s/node_modules/@mapbox/martini", npm);
    struct stat st;
    snprintf(probe, sizeof probe, "%s/martini.js", mdir);
    if (stat(probe, &st) != 0) {
        snprintf(cmd, sizeof cmd, "npm install --prefix '%s' @mapbox/martini@0.2.0 --no-audit --no-fund >&2", npm);
        if (system(cmd) != 0 || stat(probe, &st) != 0) return -1;
    }
    return 0;
}

/* One node process running tests/bench/martini.js over f32 (S x S) at each
 * of Es[0..nE): fills m[0..nE) from its output lines (its meshes go to
 * PREFIX<k>.bin). 0, or -1 when node failed or printed fewer lines. */
static int martini_node(const char *mdir, const char *f32, uint32_t S, const double *Es, int nE, const char *prefix,
                        mart *m)
{
    char cmd[4096], errs[512] = "";
    for (int k = 0; k < nE; k++) {
        size_t l = strlen(errs);
        snprintf(errs + l, sizeof errs - l, "%s%g", k ? "," : "", Es[k]);
    }
    snprintf(cmd, sizeof cmd, "node tests/bench/martini.js '%s' '%s' %u %s '%s' %d", mdir, f32, S, errs, prefix, RUNS);
    FILE *p = popen(cmd, "r");
    if (!p) return -1;
    int n = 0;
    while (n < nE && fscanf(p, "%lf %lf %lf %u %lf %lf %lf", &m[n].E, &m[n].ms, &m[n].build_ms, &m[n].tris,
                            &m[n].init_ms, &m[n].cold_ms, &m[n].min_ms) == 7)
        n++;
    return pclose(p) != 0 || n != nE ? -1 : 0;
}

/* Run martini through node; fills m[0..n) and returns n, or -1. */
static int run_martini(const char *outdir, const char *name, const float *z, uint32_t S, const double *Es, int nE,
                       mart *m)
{
    char mdir[600], f32[600], prefix[600];
    if (martini_dir(mdir, sizeof mdir) != 0) return -1;
    snprintf(f32, sizeof f32, "%s/roam_%s.f32", outdir, name);
    snprintf(prefix, sizeof prefix, "%s/roam_martini_%s_", outdir, name);
    FILE *f = fopen(f32, "wb");
    if (!f) return -1;
    fwrite(z, sizeof(float), (size_t)S * S, f);
    fclose(f);
    if (martini_node(mdir, f32, S, Es, nE, prefix, m)) return -1;
    for (int k = 0; k < nE; k++) {
        char path[700];
        snprintf(path, sizeof path, "%s%d.bin", prefix, k);
        FILE *g = fopen(path, "rb");
        if (!g) return -1;
        uint32_t hdr[2];
        if (fread(hdr, 4, 2, g) != 2) { fclose(g); return -1; }
        uint16_t *xy = malloc((size_t)hdr[0] * 4 + 4);
        uint32_t *tri = malloc((size_t)hdr[1] * 12 + 4);
        int32_t *gx = malloc((size_t)hdr[0] * 4 + 4), *gy = malloc((size_t)hdr[0] * 4 + 4);
        double *vz = malloc((size_t)hdr[0] * 8 + 8);
        if (fread(xy, 4, hdr[0], g) != hdr[0] || fread(tri, 12, hdr[1], g) != hdr[1]) { fclose(g); return -1; }
        fclose(g);
        remove(path);
        for (uint32_t v = 0; v < hdr[0]; v++) {
            gx[v] = xy[2 * v]; gy[v] = xy[2 * v + 1];
            vz[v] = z[(size_t)gy[v] * S + (size_t)gx[v]];
        }
        rc_result res;
        rc_check(S, S, z, 1.0, gx, gy, vz, hdr[0], tri, hdr[1], &res);
        m[k].max_err = res.max_err;
        m[k].rms_err = res.rms_err;
        m[k].covered = res.ok_coverage && res.ok_area;
        free(xy); free(tri); free(gx); free(gy); free(vz);
    }
    remove(f32);
    return nE;
}

/* ---- cold `roadsplat mesh` against martini (issue 18, target 4) ---------- */

#define COLD_NE 4

static double json_num(const char *buf, const char *key)
{
    char pat[64];
    snprintf(pat, sizeof pat, "\"%s\": ", key);
    const char *p = strstr(buf, pat);
    return p ? strtod(p + strlen(pat), NULL) : -1.0;
}

typedef struct cold_run {
    double mesh, create, refine, extract, measured, faults;
    uint32_t tris;
} cold_run;

/* One `roadsplat mesh` process: the stats of its mesh stage; -1 on failure. */
static int run_cli_mesh(const char *bin, const char *outdir, const char *pgm, double zs, double E, cold_run *o)
{
    char cmd[4096], json[600], ply[600];
    snprintf(json, sizeof json, "%s/mesh_cold.json", outdir);
    snprintf(ply, sizeof ply, "%s/mesh_cold.ply", outdir);
    snprintf(cmd, sizeof cmd, "'%s' mesh --z-scale %.17g --max-error %g --stats '%s' '%s' '%s'", bin, zs, E, json, pgm,
             ply);
    if (system(cmd) != 0) return -1;
    FILE *f = fopen(json, "rb");
    if (!f) return -1;
    char buf[4096];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = 0;
    o->mesh = json_num(buf, "mesh");
    o->create = json_num(buf, "create");
    o->refine = json_num(buf, "refine");
    o->extract = json_num(buf, "extract");
    o->measured = json_num(buf, "max_error_measured");
    o->faults = json_num(buf, "mesh_page_faults");
    o->tris = (uint32_t)json_num(buf, "triangles");
    remove(json);
    remove(ply);
    return o->mesh >= 0 ? 0 : -1;
}

/* One node process: martini's warm createTile + getMesh at each E (after
 * its warm-up run): fastest and median of RUNS, triangles. */
static int run_martini_warm(const char *mdir, const char *outdir, const char *f32, uint32_t S, const double *Es,
                            mart *m)
{
    char prefix[600];
    snprintf(prefix, sizeof prefix, "%s/mesh_cold_martini_", outdir);
    int r = martini_node(mdir, f32, S, Es, COLD_NE, prefix, m);
    for (int k = 0; k < COLD_NE; k++) {
        char path[700];
        snprintf(path, sizeof path, "%s%d.bin", prefix, k);
        remove(path);
    }
    return r;
}

static double min_of(const double *v, int n)
{
    double m = v[0];
    for (int i = 1; i < n; i++) if (v[i] < m) m = v[i];
    return m;
}

/* The 1025^2 fractal quantised to a 16-bit PGM (the CLI's input) and the
 * same heights in metres as float32 (martini's). Rounds alternate which
 * runs first; each round is one cold CLI process per E and one node
 * process (warm-up, then RUNS warm runs per E). Writes roam_cold.md/.csv
 * and every run to roam_cold_runs.csv;
 * returns 1 when a mesh is invalid or a run failed. */
static int run_cold(const char *outdir)
{
    const uint32_t S = 1025;
    static const double Es[COLD_NE] = { 2, 5, 10, 20 };
    const char *b = getenv("BUILD"), *re = getenv("ROAM_COLD_ROUNDS");
    int rounds = re && atoi(re) > 0 ? atoi(re) : 7;
    if (rounds > 64) rounds = 64;
    char bin[600], pgm[600], f32[600], path[600], mdir[600];
    snprintf(bin, sizeof bin, "%s/roadsplat", b && *b ? b : "build");
    snprintf(pgm, sizeof pgm, "%s/mesh_cold.pgm", outdir);
    snprintf(f32, sizeof f32, "%s/mesh_cold.f32", outdir);
    snprintf(path, sizeof path, "%s/roam_cold.md", outdir);
    FILE *md = fopen(path, "w");
    snprintf(path, sizeof path, "%s/roam_cold.csv", outdir);
    FILE *csv = fopen(path, "w");
    float *z = malloc((size_t)S * S * sizeof *z);
    if (!md || !csv || !z) { fprintf(stderr, "roam bench: cannot write to %s\n", outdir); return 1; }
    rc_dem_fractal(z, S, S, 1234, 512.0, 400.0, 0.5);
    float lo = z[0], hi = z[0];
    for (size_t i = 0; i < (size_t)S * S; i++) {
        if (z[i] < lo) lo = z[i];
        if (z[i] > hi) hi = z[i];
    }
    double zs = ((double)hi - lo) / 65535.0;
    FILE *fp = fopen(pgm, "wb"), *ff = fopen(f32, "wb");
    if (!fp || !ff) { fprintf(stderr, "roam bench: cannot write to %s\n", outdir); return 1; }
    fprintf(fp, "P5\n%u %u\n65535\n", S, S);
    for (size_t i = 0; i < (size_t)S * S; i++) {
        long q = lround(((double)z[i] - lo) / zs);
        if (q < 0) q = 0;
        if (q > 65535) q = 65535;
        unsigned char be[2] = { (unsigned char)(q >> 8), (unsigned char)(q & 0xFF) };
        fwrite(be, 1, 2, fp);
        z[i] = (float)((double)q * zs); /* what the CLI meshes, in metres */
    }
    fwrite(z, sizeof(float), (size_t)S * S, ff);
    int bad = (fclose(fp) != 0) | (fclose(ff) != 0);
    int have_m = martini_dir(mdir, sizeof mdir) == 0;
    static cold_run cr[COLD_NE][64];
    static double cms[COLD_NE][64], mmin[COLD_NE][64], mmed[COLD_NE][64];
    uint32_t mtris[COLD_NE] = { 0 };
    for (int r = 0; r < rounds && !bad; r++)
        for (int half = 0; half < 2 && !bad; half++) {
            if ((half == 0) == (r % 2 == 0)) {
                if (!have_m) continue;
                mart m[COLD_NE];
                if (run_martini_warm(mdir, outdir, f32, S, Es, m) != 0) { have_m = 0; continue; }
                for (int k = 0; k < COLD_NE; k++) { mmin[k][r] = m[k].min_ms; mmed[k][r] = m[k].ms; mtris[k] = m[k].tris; }
            } else
                for (int k = 0; k < COLD_NE && !bad; k++) {
                    if (run_cli_mesh(bin, outdir, pgm, zs, Es[k], &cr[k][r]) != 0) { bad = 1; break; }
                    cms[k][r] = cr[k][r].mesh;
                    if (!(cr[k][r].measured <= Es[k] + 1e-9)) bad = 1;
                }
        }
    remove(pgm);
    remove(f32);
    snprintf(path, sizeof path, "%s/roam_cold_runs.csv", outdir);
    FILE *runs = fopen(path, "w");
    if (runs) {
        fprintf(runs, "round,E,cli_mesh_ms,create_ms,refine_ms,extract_ms,page_faults,martini_fastest_ms,martini_median_ms\n");
        for (int r = 0; r < rounds && !bad; r++)
            for (int k = 0; k < COLD_NE; k++)
                fprintf(runs, "%d,%g,%.3f,%.3f,%.3f,%.3f,%.0f,%.3f,%.3f\n", r, Es[k], cr[k][r].mesh, cr[k][r].create,
                        cr[k][r].refine, cr[k][r].extract, cr[k][r].faults, have_m ? mmin[k][r] : 0.0,
                        have_m ? mmed[k][r] : 0.0);
        fclose(runs);
    }
    fprintf(md, "## Cold `roadsplat mesh` vs @mapbox/martini (tests/bench/roam.c; issue 18, target 4)\n\n");
    if (bad) fprintf(md, "The run failed (a CLI run failed or a mesh exceeded its E).\n\n");
    fprintf(md, "The 1025x1025 fractal of the table above, quantised to a 16-bit PGM (z-scale %.6g m); martini\n"
                "meshes the same heights in metres (float32). roadsplat: one `roadsplat mesh --max-error E --stats`\n"
                "process per run, its `timings_ms.mesh` (`rs_roam_create` + refinement + mesh bound + output arrays\n"
                "+ `rs_roam_extract`, the DEM already read; every page the mesher touches is touched for the first\n"
                "time in that process). martini: warm `createTile + getMesh` (after a JIT warm-up run in the same\n"
                "node process, `new Martini(1025)` excluded). %d rounds, alternating which of the two goes first;\n"
                "per round one CLI process per E and one node process with %d warm runs per E. *Fastest* is the\n"
                "fastest CLI process against martini's fastest warm run, *median* the median CLI process against\n"
                "the median of martini's per-round medians. Target: fastest ratio <= 0.5.\n\n", zs, rounds, RUNS);
    fprintf(md, "| E (m) | roadsplat tris | martini tris | roadsplat cold mesh ms, fastest / median | of the fastest: create + refine + extract | its page faults | martini warm ms, fastest / median | ratio fastest | ratio median | <= 0.5 |\n");
    fprintf(md, "|---|---|---|---|---|---|---|---|---|---|\n");
    fprintf(csv, "E,roadsplat_tris,martini_tris,cli_fastest_ms,cli_median_ms,martini_fastest_ms,martini_median_ms,ratio_fastest,ratio_median\n");
    int met = 0;
    for (int k = 0; k < COLD_NE && !bad; k++) {
        int fr = 0;
        for (int r = 1; r < rounds; r++) if (cms[k][r] < cms[k][fr]) fr = r;
        double tmp[64];
        memcpy(tmp, cms[k], sizeof(double) * (size_t)rounds);
        double cfast = cms[k][fr], cmed = tm_median(tmp, rounds);
        const cold_run *c = &cr[k][fr];
        if (have_m) {
            double mfast = min_of(mmin[k], rounds);
            memcpy(tmp, mmed[k], sizeof(double) * (size_t)rounds);
            double mmedian = tm_median(tmp, rounds);
            double rf = cfast / mfast, rm = cmed / mmedian;
            met += rf <= 0.5;
            fprintf(md, "| %g | %u | %u | %.1f / %.1f | %.1f + %.1f + %.1f | %.0f | %.1f / %.1f | %.2f | %.2f | %s |\n", Es[k],
                    c->tris, mtris[k], cfast, cmed, c->create, c->refine, c->extract, c->faults, mfast, mmedian, rf, rm,
                    rf <= 0.5 ? "yes" : "**no**");
            fprintf(csv, "%g,%u,%u,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f\n", Es[k], c->tris, mtris[k], cfast, cmed, mfast,
                    mmedian, rf, rm);
        } else {
            fprintf(md, "| %g | %u | - | %.1f / %.1f | %.1f + %.1f + %.1f | %.0f | - | - | - | - |\n", Es[k], c->tris,
                    cfast, cmed, c->create, c->refine, c->extract, c->faults);
            fprintf(csv, "%g,%u,,%.3f,%.3f,,,,\n", Es[k], c->tris, cfast, cmed);
        }
    }
    if (!have_m) fprintf(md, "\nmartini could not be run (node/npm unavailable): roadsplat only.\n");
    else if (!bad) fprintf(md, "\nTarget 4 (cold CLI <= 0.5x martini warm at E = 2, 5, 10, 20): met at %d of %d E.\n", met, COLD_NE);
    fprintf(md, "\n");
    fclose(md);
    fclose(csv);
    free(z);
    if (bad) fprintf(stderr, "roam bench: a cold roadsplat mesh run failed or exceeded its E\n");
    return bad;
}


/* OUTDIR/NAME.md and OUTDIR/NAME.csv opened for writing; 1 on failure. */

/* ---- drive: frame-coherent updates against per-frame rebuilds (issue 31) ---- */

#define DRIVE_FRAMES 600

/* Thread CPU time in ms: the drive's frames are short, and on a shared
 * host wall time would mostly measure preemption. */
static double cpu_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}
#define DRIVE_TOL 2.0
#define DRIVE_FRACTAL_M 500.0 /* height range of the fractal drive DEM */

typedef struct drive_scene {
    const char *name;
    uint32_t W, H;
    float *z;           /* DEM units */
    double cs, zs;
    uint32_t target;    /* triangle target of the target-mode runs */
    uint32_t patch;     /* patch size (0: automatic) */
} drive_scene;

/* Height (metres) at map point (x, y) metres, bilinear, clamped to the map. */
static double drive_height(const drive_scene *s, double x, double y)
{
    double fx = x / s->cs, fy = y / s->cs;
    if (fx < 0) fx = 0;
    if (fy < 0) fy = 0;
    if (fx > s->W - 1.001) fx = s->W - 1.001;
    if (fy > s->H - 1.001) fy = s->H - 1.001;
    size_t i = (size_t)fx, j = (size_t)fy;
    double u = fx - (double)i, v = fy - (double)j;
    const float *r0 = s->z + j * s->W + i, *r1 = r0 + s->W;
    return ((r0[0] * (1 - u) + r0[1] * u) * (1 - v) + (r1[0] * (1 - u) + r1[1] * u) * v) * s->zs;
}

/* Frame f of the drive: 200 m along a gentle S-curve through the map's
 * middle at 1/3 m per frame (20 m/s at 60 fps), the eye 3 m above the
 * highest ground within 10 m, looking ahead and 6 degrees down. */
static void drive_view(const drive_scene *s, int f, rs_roam_view *v)
{
    double cx = 0.5 * (s->W - 1) * s->cs, cy = 0.5 * (s->H - 1) * s->cs;
    double t = (double)f / DRIVE_FRAMES;
    double x = cx - 100.0 + 200.0 * t, y = cy + 20.0 * sin(6.283185307179586 * t);
    double hx = 200.0, hy = 20.0 * 6.283185307179586 * cos(6.283185307179586 * t);
    double hl = sqrt(hx * hx + hy * hy);
    double h = drive_height(s, x, y);
    for (int k = 0; k < 8; k++) {
        double a = k * 0.7853981633974483, g = drive_height(s, x + 10 * cos(a), y + 10 * sin(a));
        if (g > h) h = g;
    }
    memset(v, 0, sizeof *v);
    v->eye[0] = x; v->eye[1] = y; v->eye[2] = h + 3.0;
    v->dir[0] = hx / hl; v->dir[1] = hy / hl; v->dir[2] = -0.105;
    v->fov_y = 60; v->width = 1280; v->height = 720;
    v->pixel_error = DRIVE_TOL;
}

typedef struct drive_frame {
    double upd_ms, reb_ms, tgt_ms, tgt_reb_ms, worst, upload, patch_upload;
    uint32_t upd_tris, reb_tris, tgt_tris, ops;
} drive_frame;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double pct(const double *sorted, int n, double q)
{
    int i = (int)ceil(q * n) - 1;
    return sorted[i < 0 ? 0 : i >= n ? n - 1 : i];
}

typedef struct drive_sum {
    double mean[4], p50[4], p99[4], max[4]; /* update, rebuild, target update, target rebuild */
    double steady;      /* update / rebuild over frames 1.. (frame 0 builds the first mesh) */
    double worst, max_tri_ratio, max_tgt_dev, mean_tris, max_upload, mean_upload, mean_patch_upload;
    int cracks, bad, unit_mismatch;
    uint32_t patch, unit;
} drive_sum;

static void drive_stats(const drive_frame *fr, int n, drive_sum *o)
{
    double *a = malloc((size_t)n * sizeof *a);
    for (int c = 0; c < 4; c++) {
        double sum = 0;
        for (int f = 0; f < n; f++) {
            a[f] = c == 0 ? fr[f].upd_ms : c == 1 ? fr[f].reb_ms : c == 2 ? fr[f].tgt_ms : fr[f].tgt_reb_ms;
            sum += a[f];
        }
        qsort(a, (size_t)n, sizeof *a, cmp_double);
        o->mean[c] = sum / n; o->p50[c] = pct(a, n, 0.5); o->p99[c] = pct(a, n, 0.99); o->max[c] = a[n - 1];
    }
    double su = 0, sr = 0;
    for (int f = 1; f < n; f++) { su += fr[f].upd_ms; sr += fr[f].reb_ms; }
    o->steady = sr > 0 ? su / sr : 0;
    free(a);
}

/* Extract the mesh of L into grid coordinates; returns the triangle count
 * or -1. */
static long drive_extract(rs_ctx *ctx, rs_roam *L, const drive_scene *s, int32_t **gx, int32_t **gy, double **vz,
                          uint32_t **idx, size_t *nv)
{
    size_t mv, mi, ni;
    rs_roam_mesh_bound(L, NULL, &mv, &mi);
    float *v = malloc(mv * 5 * sizeof *v);
    *idx = malloc(mi * sizeof **idx);
    if (!v || !*idx || rs_roam_extract(ctx, L, NULL, v, NULL, mv, *idx, mi, nv, &ni) != RS_OK) { free(v); return -1; }
    *gx = malloc(*nv * sizeof **gx); *gy = malloc(*nv * sizeof **gy); *vz = malloc(*nv * sizeof **vz);
    for (size_t k = 0; k < *nv; k++) {
        (*gx)[k] = (int32_t)lround(v[5 * k] / s->cs);
        (*gy)[k] = (int32_t)lround(v[5 * k + 1] / s->cs);
        (*vz)[k] = v[5 * k + 2];
    }
    free(v);
    return (long)(ni / 3);
}

/* One scene's drive: landscape A updated frame to frame (pixel tolerance),
 * B rebuilt every frame at the same view (rs_roam_frame), C updated with a
 * triangle target and D rebuilt with it. A's mesh is checked every frame
 * against the tolerance (rc_view_worst) and every 25th for cracks. */
static int drive_scene_run(rs_ctx *ctx, const drive_scene *s, FILE *csv, drive_sum *o)
{
    memset(o, 0, sizeof *o);
    rs_dem *dem = NULL;
    rs_dem_frame frm = { s->cs, s->zs, 0, 0 };
    if (rs_dem_create(ctx, s->W, s->H, s->z, &dem) != RS_OK || rs_dem_set_frame(ctx, dem, &frm) != RS_OK) return -1;
    rs_roam *L[4] = { NULL, NULL, NULL, NULL };
    rs_roam_options ro;
    memset(&ro, 0, sizeof ro);
    ro.patch_size = s->patch;
    for (int k = 0; k < 4; k++)
        if (rs_roam_create(ctx, dem, &ro, &L[k]) != RS_OK) { fprintf(stderr, "%s\n", rs_ctx_message(ctx)); return -1; }
    drive_frame *fr = calloc(DRIVE_FRAMES, sizeof *fr);
    float *zm = malloc((size_t)s->W * s->H * sizeof *zm);
    for (size_t i = 0; i < (size_t)s->W * s->H; i++) zm[i] = (float)((double)s->z[i] * s->zs);
    o->worst = 0; o->max_tri_ratio = 0;
    double tris_sum = 0, upload_sum = 0;
    rs_roam_stats st0;
    rs_roam_get_stats(L[0], &st0);
    uint32_t npatch = st0.patches_x * st0.patches_y;
    o->patch = st0.patch_size;
    uint32_t *gens = calloc(npatch, sizeof *gens);
    uint32_t nunit = st0.units;
    o->unit = st0.unit_size;
    uint32_t *ugens = calloc(nunit, sizeof *ugens);
    size_t *uverts = calloc(nunit, sizeof *uverts);
    double patch_upload_sum = 0;
    for (int f = 0; f < DRIVE_FRAMES; f++) {
        rs_roam_view v;
        drive_view(s, f, &v);
        rs_roam_view vt = v;
        vt.target_triangles = s->target;
        double t[5];
        rs_result rr[4];
        /* alternate which goes first */
        if (f & 1) {
            t[0] = cpu_ms(); rr[1] = rs_roam_frame(ctx, L[1], &v); t[1] = cpu_ms();
            rr[0] = rs_roam_update(ctx, L[0], &v, 0); t[2] = cpu_ms();
            fr[f].reb_ms = t[1] - t[0]; fr[f].upd_ms = t[2] - t[1];
        } else {
            t[0] = cpu_ms(); rr[0] = rs_roam_update(ctx, L[0], &v, 0); t[1] = cpu_ms();
            rr[1] = rs_roam_frame(ctx, L[1], &v); t[2] = cpu_ms();
            fr[f].upd_ms = t[1] - t[0]; fr[f].reb_ms = t[2] - t[1];
        }
        t[0] = cpu_ms(); rr[2] = rs_roam_update(ctx, L[2], &vt, 0); t[1] = cpu_ms();
        rr[3] = rs_roam_frame(ctx, L[3], &vt); t[2] = cpu_ms();
        fr[f].tgt_ms = t[1] - t[0]; fr[f].tgt_reb_ms = t[2] - t[1];
        for (int k = 0; k < 4; k++)
            if (rr[k] != RS_OK) { fprintf(stderr, "roam drive %s frame %d: %s\n", s->name, f, rs_ctx_message(ctx)); o->bad = 1; }
        rs_roam_stats st[4];
        for (int k = 0; k < 4; k++) rs_roam_get_stats(L[k], &st[k]);
        fr[f].upd_tris = st[0].triangles; fr[f].reb_tris = st[1].triangles; fr[f].tgt_tris = st[2].triangles;
        fr[f].ops = st[0].update_ops;
        tris_sum += st[1].triangles;
        double ratio = (double)st[0].triangles / st[1].triangles;
        if (ratio > o->max_tri_ratio) o->max_tri_ratio = ratio;
        double dev = fabs((double)st[2].triangles - s->target) / s->target;
        if (dev > o->max_tgt_dev) o->max_tgt_dev = dev;
        /* the tolerance on A's mesh, independently */
        int32_t *gx = NULL, *gy = NULL;
        double *vz = NULL;
        uint32_t *idx = NULL;
        size_t nv = 0;
        long nt = drive_extract(ctx, L[0], s, &gx, &gy, &vz, &idx, &nv);
        if (nt < 0) o->bad = 1;
        else {
            double k = 720.0 / (2.0 * tan(30.0 * 3.14159265358979323846 / 180.0));
            size_t nchk = 0;
            fr[f].worst = rc_view_worst(s->W, s->H, s->z, s->zs, s->cs, gx, gy, idx, (size_t)nt, v.eye, v.dir,
                                        29.0 * 3.14159265358979323846 / 180.0, k, DRIVE_TOL, 1e-3 * s->cs, &nchk);
            if (fr[f].worst > o->worst) o->worst = fr[f].worst;
            if (f % 25 == 0) {
                rc_result res;
                if (!rc_check(s->W, s->H, zm, 1.0, gx, gy, vz, nv, idx, (size_t)nt, &res) || !rc_all_ok(&res)) o->cracks++;
            }
        }
        free(gx); free(gy); free(vz); free(idx);
        /* re-upload: what a host keeping one buffer per unit (per patch)
         * sends, the vertices of the units (patches) whose generation
         * changed, against those of all units (patches) */
        {
            size_t mv, mi, nvp, nip, all = 0, changed = 0;
            rs_roam_mesh_bound(L[0], NULL, &mv, &mi);
            float *pv = malloc(mv * 5 * sizeof *pv);
            uint32_t *pi = malloc(mi * sizeof *pi);
            for (uint32_t p = 0; pv && pi && p < npatch; p++) {
                if (rs_roam_extract_patch(ctx, L[0], p, NULL, pv, NULL, mv, pi, mi, &nvp, &nip) != RS_OK) { o->bad = 1; break; }
                uint32_t g = rs_roam_patch_generation(L[0], p);
                all += nvp;
                if (g != gens[p]) changed += nvp;
                gens[p] = g;
            }
            fr[f].patch_upload = all ? (double)changed / (double)all : 0.0;
            /* units: the changed ones extracted (as the host would), the
             * others counted as at their last extraction; every 25th frame
             * all of them, checked against those counts and, together,
             * against the whole mesh's triangles */
            int every = f % 25 == 0;
            uint64_t *ukeys = NULL, *wkeys = NULL;
            size_t nuk = 0, nwk = 0;
            if (every) {
                size_t ni;
                if (rs_roam_extract(ctx, L[0], NULL, pv, NULL, mv, pi, mi, &nvp, &ni) != RS_OK) o->bad = 1;
                else wkeys = rc_tri_keys(pv, pi, nwk = ni / 3, s->W, s->cs);
                ukeys = malloc((mi / 3 + 1) * sizeof *ukeys);
            }
            all = changed = 0;
            for (uint32_t u = 0; pv && pi && u < nunit; u++) {
                uint32_t g = rs_roam_unit_generation(L[0], u);
                if (g != ugens[u] || every) {
                    if (rs_roam_extract_unit(ctx, L[0], u, NULL, pv, NULL, mv, pi, mi, &nvp, &nip) != RS_OK) { o->bad = 1; break; }
                    if (g == ugens[u] && nvp != uverts[u]) o->unit_mismatch++;
                    if (ukeys) {
                        size_t nk = nip / 3;
                        uint64_t *k = rc_tri_keys(pv, pi, nk, s->W, s->cs);
                        if (k && nuk + nk <= mi / 3) memcpy(ukeys + nuk, k, nk * sizeof *k);
                        nuk += nk;
                        free(k);
                    }
                    if (g != ugens[u]) changed += nvp;
                    uverts[u] = nvp;
                    ugens[u] = g;
                }
                all += uverts[u];
            }
            if (every) {
                if (ukeys) qsort(ukeys, nuk, sizeof *ukeys, rc_cmp_u64);
                if (!ukeys || !wkeys || nuk != nwk || memcmp(ukeys, wkeys, nuk * sizeof *ukeys)) o->unit_mismatch++;
            }
            free(ukeys); free(wkeys);
            free(pv); free(pi);
            fr[f].upload = all ? (double)changed / (double)all : 0.0;
            if (f > 0) {
                upload_sum += fr[f].upload;
                patch_upload_sum += fr[f].patch_upload;
                if (fr[f].upload > o->max_upload) o->max_upload = fr[f].upload;
            }
        }
        fprintf(csv, "%s,%d,%.4f,%.4f,%u,%u,%u,%.4f,%.4f,%u,%.5f,%.5f,%.5f\n", s->name, f, fr[f].upd_ms, fr[f].reb_ms,
                fr[f].upd_tris, fr[f].reb_tris, fr[f].ops, fr[f].tgt_ms, fr[f].tgt_reb_ms, fr[f].tgt_tris, fr[f].worst,
                fr[f].upload, fr[f].patch_upload);
    }
    drive_stats(fr, DRIVE_FRAMES, o);
    o->mean_tris = tris_sum / DRIVE_FRAMES;
    o->mean_upload = upload_sum / (DRIVE_FRAMES - 1);
    o->mean_patch_upload = patch_upload_sum / (DRIVE_FRAMES - 1);
    free(fr); free(zm); free(gens); free(ugens); free(uverts);
    for (int k = 0; k < 4; k++) rs_roam_free(ctx, L[k]);
    rs_dem_free(ctx, dem);
    return 0;
}

static int run_drive(const char *outdir)
{
    FILE *md, *csv;
    if (tm_open_section(outdir, "roam_drive", &md, &csv)) return 1;
    rs_ctx *ctx = NULL;
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    fprintf(csv, "scene,frame,update_ms,rebuild_ms,update_tris,rebuild_tris,update_ops,target_update_ms,"
                 "target_rebuild_ms,target_tris,worst_over_tol,upload_fraction,patch_upload_fraction\n");
    drive_scene sc[4];
    memset(sc, 0, sizeof sc);
    sc[0].name = "fractal"; sc[0].W = sc[0].H = 1025; sc[0].cs = 1.0; sc[0].zs = DRIVE_FRACTAL_M / 65535.0; sc[0].target = 100000;
    sc[0].z = malloc((size_t)1025 * 1025 * sizeof(float));
    sc_dem_fractal(sc[0].z, 1025, 1025, 5, 0.5);
    sc_scene city;
    if (sc_city_default(&city, 1)) return 1;
    sc[1].name = "city"; sc[1].W = city.w; sc[1].H = city.h; sc[1].cs = city.cell_size; sc[1].zs = 0.01; sc[1].z = city.z; sc[1].target = 20000;
    /* the same drives with 16-cell patches: finer upload units (and
     * height ranges) against more roots and per-patch work */
    sc[2] = sc[0]; sc[2].name = "fractal-p16"; sc[2].patch = 16;
    sc[3] = sc[1]; sc[3].name = "city-p16"; sc[3].patch = 16;
    fprintf(md, "## ROAM drive: frame-coherent updates against per-frame rebuilds (tests/bench/roam.c)\n\n"
                "%d frames at 1280x720 (60 degree vertical field of view), 1/3 m per frame (20 m/s at 60 fps) "
                "along a 200 m S-curve through the map's middle, the eye 3 m above the ground, one core, times in thread CPU time (on a shared host wall time mostly measures preemption). Per frame: `rs_roam_update` "
                "(split and merge queues, tolerance %.0f px, merge hysteresis 1.25 (the default), no budget) on one landscape and `rs_roam_frame` "
                "(from scratch) on another at the same view, alternating which goes first; then the same with "
                "a triangle target (100,000 on the fractal, 20,000 on the city). The updated mesh is checked every frame against the tolerance by "
                "`rc_view_worst` (true error over the distance to the nearest sample, triangles inside a 29 "
                "degree cone) and every 25th frame for cracks by `rc_check`.\n\n"
                "![per-frame mesh time over the drive](bench/roam_drive.png)\n\n"
                "Rows `-p16` use `patch_size` 16 (the automatic size is 64 on both maps). The steady ratio leaves out frame 0, "
                "where the update builds the first mesh from the base mesh. *Re-uploaded*: what a host that keeps one buffer "
                "per upload unit (`rs_roam_extract_unit`, the halves of `unit` x `unit` cell squares, the default) re-sends, "
                "the vertices of the units whose `rs_roam_unit_generation` changed over the vertices of all units (each "
                "unit's own count, so shared edge vertices count once per unit), frames 1..; every 25th frame all units are "
                "extracted and their triangles together compared with `rs_roam_extract`'s. *By patch*: the same with one "
                "buffer per patch.\n\n"
                "| scene | patch | mean tris (rebuild) | update ms mean / p50 / p99 / max | rebuild ms mean / p50 / p99 / max "
                "| update / rebuild (mean) | update / rebuild, frames 1.. | max tris update / rebuild | worst error / tolerance | cracked frames "
                "| target: update ms mean / p99 | target: rebuild ms mean / p99 | target: max deviation "
                "| unit | vertices re-uploaded per frame, mean / max | the same by patch, mean |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n", DRIVE_FRAMES, DRIVE_TOL);
    int fail = 0;
    /* ROAM_DRIVE_ONLY=NAME runs that scene alone (profiling) */
    const char *only = getenv("ROAM_DRIVE_ONLY");
    for (int k = 0; k < 4; k++) {
        drive_sum o;
        if (only && *only && strcmp(only, sc[k].name)) continue;
        if (drive_scene_run(ctx, &sc[k], csv, &o) != 0) { fail = 1; continue; }
        fprintf(md, "| %s %ux%u | %u | %.0f | %.3f / %.3f / %.3f / %.3f | %.3f / %.3f / %.3f / %.3f | %.2f | %.2f | %.4f | %.4f | %d "
                    "| %.3f / %.3f | %.3f / %.3f | %.2f %% | %u | %.1f %% / %.1f %% | %.1f %% |\n", sc[k].name, sc[k].W, sc[k].H, o.patch, o.mean_tris,
                o.mean[0], o.p50[0], o.p99[0], o.max[0], o.mean[1], o.p50[1], o.p99[1], o.max[1], o.mean[0] / o.mean[1], o.steady,
                o.max_tri_ratio, o.worst, o.cracks, o.mean[2], o.p99[2], o.mean[3], o.p99[3], 100 * o.max_tgt_dev,
                o.unit, 100 * o.mean_upload, 100 * o.max_upload, 100 * o.mean_patch_upload);
        fflush(md);
        if (o.unit_mismatch) fprintf(stderr, "roam bench: %s: upload units disagree with the whole mesh (%d)\n", sc[k].name, o.unit_mismatch);
        if (o.bad || o.cracks || o.unit_mismatch || o.worst > 1.0 + 1e-9 || o.max_tri_ratio > 1.05) fail = 1;
    }
    fprintf(md, "\n");
    free(sc[0].z);
    sc_scene_free(&city);
    fclose(md);
    fclose(csv);
    rs_ctx_free(ctx);
    if (fail) fprintf(stderr, "roam bench: a drive frame broke the tolerance, cracked or failed\n");
    return fail;
}

int main(int argc, char **argv)
{
    if (argc < 2) { fprintf(stderr, "usage: roam OUTDIR [cold]\n"); return 2; }
    const char *outdir = argv[1];
    if (argc > 2 && !strcmp(argv[2], "cold")) return run_cold(outdir); /* that section alone */
    if (argc > 2 && !strcmp(argv[2], "drive")) return run_drive(outdir);
    FILE *md, *csv;
    if (tm_open_section(outdir, "roam", &md, &csv)) return 1;
    rs_ctx *ctx = NULL;
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    fprintf(csv, "dem,mesher,requested_error,triangles,max_error,rms_error,build_ms,extract_ms,total_ms\n");
    fprintf(md, "## ROAM mesher vs @mapbox/martini (tests/bench/roam.c)\n\n");
    fprintf(md, "Same grid, same run. Errors are the true vertical errors over every DEM sample, measured by\n"
                "`tests/roam_check.h` for both meshers (heights in DEM units = metres here). roadsplat time =\n"
                "`rs_roam_create` + `rs_roam_refine_error` + `rs_roam_extract` (the exact error bounds\n"
                "are computed during refinement, for the nodes it tests), output buffers allocated per run;\n"
                "martini time = `createTile` + `getMesh`, warm (after a JIT warm-up run). Medians of %d runs.\n"
                "martini builds its `Martini(size)` object once per grid size and reuses it (its time is\n"
                "shown separately). The matching roadsplat model is a landscape created once and re-targeted\n"
                "at the DEM on each run with `rs_roam_set_dem` (the \"reused\" columns), keeping the node\n"
                "pool's pages, as a simulator streaming terrain tiles would. Both roadsplat models are shown.\n"
                "\"roadsplat @ martini's true error\" asks roadsplat for martini's measured max error.\n\n"
                "![ROAM vs martini: time and triangles against error](bench/roam.png)\n\n", RUNS);
    const uint32_t S = 1025;
    float *z = malloc((size_t)S * S * sizeof *z);
    static const double Es[] = { 0.5, 1, 2, 5, 10, 20 };
    const int nE = 6;
    int fail = 0;
    double worst_time_ratio = 0, worst_reuse_ratio = 0, worst_tri_ratio = 0, best_tri_ratio = 1e9;
    for (int d = 0; d < 2; d++) {
        const char *name = d == 0 ? "fractal" : "realistic";
        if (d == 0) rc_dem_fractal(z, S, S, 1234, 512.0, 400.0, 0.5);
        else rc_dem_realistic(z, S, S, 77);
        rs_dem *dem = NULL;
        if (rs_dem_create(ctx, S, S, z, &dem) != RS_OK) return 1;
        mart m[6];
        memset(m, 0, sizeof m);
        int have_m = run_martini(outdir, name, z, S, Es, nE, m) == nE;
        fprintf(md, "### %s DEM, %ux%u%s\n\n", name, S, S,
                d == 0 ? " (value-noise fBm, 400 m amplitude)" : " (ridged mountains, valley floor, flat lake, 0.1 m steps)");
        if (!have_m) fprintf(md, "martini could not be run (node/npm unavailable): roadsplat only.\n\n");
        else fprintf(md, "martini one-time `new Martini(%u)`: %.1f ms; first (cold JIT) createTile+getMesh: %.1f ms.\n\n", S,
                     m[0].init_ms, m[0].cold_ms);
        fprintf(md, "| requested E | martini tris | martini true max / RMS | martini ms | roadsplat tris | roadsplat true max / RMS | roadsplat ms, fresh (create + refine/extract) | roadsplat ms, reused (set_dem + refine/extract) | roadsplat tris @ martini's true max | tris ratio | time ratio fresh / reused |\n");
        fprintf(md, "|---|---|---|---|---|---|---|---|---|---|---|\n");
        for (int k = 0; k < nE; k++) {
            run_result a, b, c;
            if (run_roam(ctx, dem, z, S, S, Es[k], 1, 0, &a) != 0) { fail = 1; break; }
            if (run_roam(ctx, dem, z, S, S, Es[k], 1, 1, &c) != 0) { fail = 1; break; }
            if (!a.valid || a.max_err > Es[k] + 1e-9 * 1000) fail = 1;
            if (!c.valid || c.tris != a.tris || c.max_err != a.max_err) fail = 1;
            fprintf(csv, "%s,roadsplat,%g,%u,%.6f,%.6f,%.3f,%.3f,%.3f\n", name, Es[k], a.tris, a.max_err, a.rms_err,
                    a.build_ms, a.refine_ms, a.total_ms);
            fprintf(csv, "%s,roadsplat_reused,%g,%u,%.6f,%.6f,%.3f,%.3f,%.3f\n", name, Es[k], c.tris, c.max_err,
                    c.rms_err, c.build_ms, c.refine_ms, c.total_ms);
            if (have_m) {
                if (run_roam(ctx, dem, z, S, S, m[k].max_err, 1, 0, &b) != 0) { fail = 1; break; }
                double tri_ratio = (double)b.tris / m[k].tris, time_ratio = a.total_ms / m[k].ms;
                double reuse_ratio = c.total_ms / m[k].ms;
                if (tri_ratio > worst_tri_ratio) worst_tri_ratio = tri_ratio;
                if (tri_ratio < best_tri_ratio) best_tri_ratio = tri_ratio;
                if (time_ratio > worst_time_ratio) worst_time_ratio = time_ratio;
                if (reuse_ratio > worst_reuse_ratio) worst_reuse_ratio = reuse_ratio;
                fprintf(csv, "%s,martini,%g,%u,%.6f,%.6f,%.3f,%.3f,%.3f\n", name, Es[k], m[k].tris, m[k].max_err,
                        m[k].rms_err, m[k].build_ms, m[k].ms - m[k].build_ms, m[k].ms);
                fprintf(md, "| %g | %u | %.3f / %.3f%s | %.1f | %u | %.3f / %.3f%s | %.1f (%.1f + %.1f) | %.1f (%.1f + %.1f) | %u (max %.3f) | %.2f | %.2f / %.2f |\n",
                        Es[k], m[k].tris, m[k].max_err, m[k].rms_err, m[k].covered ? "" : " (gaps!)", m[k].ms, a.tris,
                        a.max_err, a.rms_err, a.valid ? "" : " (INVALID)", a.total_ms, a.build_ms, a.refine_ms,
                        c.total_ms, c.build_ms, c.refine_ms, b.tris, b.max_err, tri_ratio, time_ratio, reuse_ratio);
            } else {
                fprintf(md, "| %g | - | - | - | %u | %.3f / %.3f%s | %.1f (%.1f + %.1f) | %.1f (%.1f + %.1f) | - | - | - |\n",
                        Es[k], a.tris, a.max_err, a.rms_err, a.valid ? "" : " (INVALID)", a.total_ms, a.build_ms,
                        a.refine_ms, c.total_ms, c.build_ms, c.refine_ms);
            }
            fflush(md);
        }
        fprintf(md, "\n");
        rs_dem_free(ctx, dem);
    }
    if (worst_tri_ratio > 0)
        fprintf(md, "Summary: at martini's own true max error roadsplat needs %.2f-%.2fx martini's triangles; "
                    "roadsplat build+extract takes at most %.2fx martini's warm time at the same requested E "
                    "with a fresh landscape per run, at most %.2fx with a reused one (set_dem).\n\n",
                best_tri_ratio, worst_tri_ratio, worst_time_ratio, worst_reuse_ratio);
    /* a non-2^n+1 grid (SRTM 3-arc-second tile size), roadsplat only: martini needs 2^n+1 */
    {
        const uint32_t W2 = 1201;
        float *z2 = malloc((size_t)W2 * W2 * sizeof *z2);
        rc_dem_realistic(z2, W2, W2, 78);
        rs_dem *dem = NULL;
        if (rs_dem_create(ctx, W2, W2, z2, &dem) == RS_OK) {
            fprintf(md, "### realistic DEM, %ux%u (martini cannot mesh this size)\n\n| E | tris | true max / RMS | ms (build + refine/extract) |\n|---|---|---|---|\n", W2, W2);
            for (int k = 1; k < nE; k += 2) {
                run_result a;
                if (run_roam(ctx, dem, z2, W2, W2, Es[k], 1, 0, &a) != 0) { fail = 1; break; }
                if (!a.valid || a.max_err > Es[k] + 1e-6) fail = 1;
                fprintf(md, "| %g | %u | %.3f / %.3f%s | %.1f (%.1f + %.1f) |\n", Es[k], a.tris, a.max_err, a.rms_err,
                        a.valid ? "" : " (INVALID)", a.total_ms, a.build_ms, a.refine_ms);
                fprintf(csv, "realistic1201,roadsplat,%g,%u,%.6f,%.6f,%.3f,%.3f,%.3f\n", Es[k], a.tris, a.max_err, a.rms_err,
                        a.build_ms, a.refine_ms, a.total_ms);
            }
            fprintf(md, "\n");
            rs_dem_free(ctx, dem);
        }
        free(z2);
    }
    free(z);
    fclose(md);
    fclose(csv);
    rs_ctx_free(ctx);
    if (fail) fprintf(stderr, "roam bench: a roadsplat mesh was invalid or exceeded its bound\n");
    return run_cold(outdir) | run_drive(outdir) | fail;
}
