/* Progress and cancel of every long call (issue 30 target 4: cancel returns
 * within 50 ms from every long call). For each call on a big input, with
 * the context's progress callback (rs_ctx_set_progress): the longest time
 * between two progress calls (counting from the call's start and to its
 * return), and the time from a callback that asks to stop to the call's
 * return, for stops spread over the call (the largest of them). Inputs: the
 * generated city (tests/scenes.c sc_city on the 400 x 350 DEM of 5 m cells)
 * with 10^4 and 10^5 roads, classed (lines, casings, automatic markings);
 * its whole 8-texel image (3192 x 2792) as one window; the virtual texture
 * over it; the 1025^2 fractal DEM for ROAM. Wall clock, one thread. A
 * call's time ends at its return: freeing what it made (rs_road_grid_free
 * of a 615 MB grid: ~0.14 s of page unmapping) is the host's next call.
 * Usage: cancel OUTDIR [ONLY] (writes OUTDIR/cancel.md and cancel.csv; ONLY:
 * just the calls whose name holds that text). */
#include "roadsplat.h"
#include "roam_check.h"
#include "scenes.h"
#include "timing.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct watch {
    int armed;
    double last, gap, stop_time;
    uint64_t calls, stop_at;
} watch;

static int on_progress(void *user, uint64_t done, uint64_t total)
{
    watch *w = user;
    (void)done;
    (void)total;
    if (!w->armed) return 0;
    double now = tm_now_ms();
    if (now - w->last > w->gap) w->gap = now - w->last;
    w->last = now;
    w->calls++;
    if (w->stop_at && w->calls == w->stop_at) {
        w->stop_time = now;
        return 1;
    }
    return 0;
}

/* What the calls work on. */
typedef struct bench {
    rs_ctx *ctx;
    watch *w;
    rs_dem *dem, *fractal;
    rs_roads *roads;     /* the city of this round */
    rs_splatter *sp;     /* its 8-texel styled splatter (10^4 roads) */
    rs_vt *vt;
    rs_vt_workspace *vws;
    uint8_t *px;         /* a whole image */
    rs_roam *roam;
    uint32_t W, H;
    char *text;          /* the city's roads as a road file */
    size_t text_len;
    char *pgm[2];        /* a 2049^2 P2 and an 8193^2 16-bit P5 DEM */
    size_t pgm_len[2];
    rs_image atlas;      /* a 4096 x 2048 atlas image of one sprite */
    float *mesh;         /* rs_roam_extract's buffers */
    uint32_t *mesh_ix;
    size_t mesh_v, mesh_i;
    double ret;          /* when the measured call returned (before what it made is freed), or 0 */
} bench;

enum {
    C_GRID, C_GRID_PLAIN, C_NETWORK, C_GPU, C_WINDOW, C_NORMALS, C_VT_CREATE, C_VT_TILE,
    C_ROAM_CREATE, C_ROAM_SETDEM, C_ROAM_ERROR, C_ROAM_COUNT, C_ROAM_FRAME, C_ROAM_UPDATE, C_PARSE_ROADS,
    C_PARSE_P2, C_PARSE_P5, C_ROAM_EXTRACT, C_ATLAS, C_COUNT
};
static const char *const call_name[C_COUNT] = {
    "rs_road_grid_build (classes)", "rs_road_grid_build (no styles)", "rs_network_build", "rs_gpu_scene_create",
    "rs_splat_window (whole image)", "rs_normal_window (whole image)", "rs_vt_create (with roads)",
    "rs_vt_make_tile (coarsest level)", "rs_roam_create", "rs_roam_set_dem", "rs_roam_refine_error (0.05 m)",
    "rs_roam_refine_count (10^6)", "rs_roam_frame (target 10^5)", "rs_roam_update (from the base mesh)",
    "rs_roads_parse", "rs_dem_parse_pgm (P2)", "rs_dem_parse_pgm (P5)", "rs_roam_extract (with normals)",
    "rs_atlas_create"
};

static rs_roam_view view(void)
{
    rs_roam_view v;
    memset(&v, 0, sizeof v);
    v.eye[0] = 200; v.eye[1] = 200; v.eye[2] = 600;
    v.dir[0] = 1; v.dir[1] = 1; v.dir[2] = -0.6;
    return v;
}

/* Before the measured call, unmeasured: what it needs. */
static rs_result prepare(bench *b, int c)
{
    /* (a frame with a target starts from the last one's tolerance) */
    if ((c == C_ROAM_UPDATE || c == C_ROAM_FRAME) && b->roam) rs_roam_free(b->ctx, b->roam), b->roam = NULL;
    if ((c == C_ROAM_SETDEM || c == C_ROAM_ERROR || c == C_ROAM_COUNT || c == C_ROAM_FRAME || c == C_ROAM_UPDATE ||
         c == C_ROAM_EXTRACT) &&
        !b->roam) {
        rs_roam_options o;
        memset(&o, 0, sizeof o);
        o.pool_nodes = 1u << 21;
        rs_result r = rs_roam_create(b->ctx, b->fractal, &o, &b->roam);
        if (r) return r;
    }
    if (c == C_ROAM_EXTRACT && !b->mesh) {
        /* the mesh of refine_count(10^6), without the progress callback */
        rs_ctx *quiet = NULL;
        rs_result r = rs_ctx_create(NULL, NULL, &quiet);
        if (!r) r = rs_roam_refine_count(quiet, b->roam, 1000000);
        rs_ctx_free(quiet);
        if (r && r != RS_ERR_POOL_EXHAUSTED) return r;
        rs_roam_mesh_options mo;
        memset(&mo, 0, sizeof mo);
        mo.normals = 1;
        rs_roam_mesh_bound(b->roam, &mo, &b->mesh_v, &b->mesh_i);
        b->mesh = malloc(b->mesh_v * 8 * sizeof *b->mesh);
        b->mesh_ix = malloc(b->mesh_i * sizeof *b->mesh_ix);
        if (!b->mesh || !b->mesh_ix) return RS_ERR_NOMEM;
    }
    return RS_OK;
}

/* The measured call; what it made is freed at once. */
static rs_result run(bench *b, int c)
{
    rs_ctx *ctx = b->ctx;
    rs_result r = RS_OK;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    switch (c) {
    case C_GRID:
    case C_GRID_PLAIN: {
        o.style.disable = o.markings.disable = c == C_GRID_PLAIN;
        rs_road_grid *g = NULL;
        r = rs_road_grid_build(ctx, b->dem, b->roads, &o, &g);
        b->ret = tm_now_ms();
        rs_road_grid_free(ctx, g);
        break;
    }
    case C_NETWORK: {
        rs_network *n = NULL;
        r = rs_network_build(ctx, b->roads, NULL, &n);
        b->ret = tm_now_ms();
        rs_network_free(ctx, n);
        break;
    }
    case C_GPU: {
        rs_gpu_scene *g = NULL;
        r = rs_gpu_scene_create(ctx, b->dem, b->roads, &o, NULL, &g);
        b->ret = tm_now_ms();
        rs_gpu_scene_free(ctx, g);
        break;
    }
    case C_WINDOW:
        r = rs_splat_window(ctx, b->sp, 0, 0, b->W, b->H, b->px, (size_t)b->W * 4, NULL, 0, NULL);
        break;
    case C_NORMALS:
        r = rs_normal_window(ctx, b->sp, 0, 0, b->W, b->H, b->px, (size_t)b->W * 3, NULL);
        break;
    case C_VT_CREATE: {
        rs_vt_options vo;
        memset(&vo, 0, sizeof vo);
        vo.roads = b->roads;
        rs_vt *vt = NULL;
        r = rs_vt_create(ctx, b->sp, &vo, &vt);
        b->ret = tm_now_ms();
        rs_vt_free(ctx, vt);
        break;
    }
    case C_VT_TILE: {
        rs_vt_info in;
        rs_vt_get_info(b->vt, &in);
        r = rs_vt_make_tile(ctx, b->vt, b->vws, in.levels - 1, 0, 0, b->px, (size_t)in.tile_side * 4);
        break;
    }
    case C_ROAM_CREATE: {
        rs_roam *L = NULL;
        r = rs_roam_create(ctx, b->fractal, NULL, &L);
        b->ret = tm_now_ms();
        rs_roam_free(ctx, L);
        break;
    }
    case C_ROAM_SETDEM: r = rs_roam_set_dem(ctx, b->roam, b->fractal); break;
    case C_ROAM_ERROR: r = rs_roam_refine_error(ctx, b->roam, 0.05); break;
    case C_ROAM_COUNT: r = rs_roam_refine_count(ctx, b->roam, 1000000); break;
    case C_ROAM_FRAME: {
        rs_roam_view v = view();
        v.target_triangles = 100000;
        r = rs_roam_frame(ctx, b->roam, &v);
        break;
    }
    case C_ROAM_UPDATE: {
        rs_roam_view v = view();
        v.pixel_error = 0.5;
        r = rs_roam_update(ctx, b->roam, &v, 0);
        break;
    }
    case C_ROAM_EXTRACT: {
        rs_roam_mesh_options mo;
        memset(&mo, 0, sizeof mo);
        mo.normals = 1;
        size_t nv, ni;
        r = rs_roam_extract(ctx, b->roam, &mo, b->mesh, b->mesh + 5 * b->mesh_v, b->mesh_v, b->mesh_ix, b->mesh_i, &nv,
                            &ni);
        break;
    }
    case C_ATLAS: {
        static const char index[] = "big 0 0 4096 2048 2 1\n";
        rs_atlas *a = NULL;
        r = rs_atlas_create(ctx, &b->atlas, index, sizeof index - 1, &a);
        b->ret = tm_now_ms();
        rs_atlas_free(ctx, a);
        break;
    }
    case C_PARSE_ROADS: {
        rs_roads *R = NULL;
        r = rs_roads_parse(ctx, b->text, b->text_len, &R);
        b->ret = tm_now_ms();
        rs_roads_free(ctx, R);
        break;
    }
    case C_PARSE_P2:
    case C_PARSE_P5: {
        rs_dem *d = NULL;
        r = rs_dem_parse_pgm(ctx, b->pgm[c == C_PARSE_P5], b->pgm_len[c == C_PARSE_P5], &d);
        b->ret = tm_now_ms();
        rs_dem_free(ctx, d);
        break;
    }
    }
    return r == RS_ERR_POOL_EXHAUSTED ? RS_OK : r;
}

typedef struct result {
    double ms, gap_ms, cancel_ms;
    uint64_t calls;
} result;

static int measure(bench *b, int c, int stops, result *out)
{
    watch *w = b->w;
    memset(out, 0, sizeof *out);
    if (prepare(b, c)) return 1;
    memset(w, 0, sizeof *w);
    w->armed = 1;
    double t0 = tm_now_ms();
    w->last = t0;
    b->ret = 0;
    rs_result r = run(b, c);
    double t1 = b->ret ? b->ret : tm_now_ms();
    w->armed = 0;
    if (r) {
        fprintf(stderr, "cancel: %s: %s (%s)\n", call_name[c], rs_strerror(r), rs_ctx_message(b->ctx));
        return 1;
    }
    out->ms = t1 - t0;
    out->gap_ms = w->gap > t1 - w->last ? w->gap : t1 - w->last;
    out->calls = w->calls;
    uint64_t calls = w->calls;
    for (int k = 1; k <= stops && calls > 0; k++) {
        if (prepare(b, c)) return 1;
        memset(w, 0, sizeof *w);
        w->stop_at = calls * (uint64_t)k / (uint64_t)(stops + 1) + 1;
        w->armed = 1;
        w->last = tm_now_ms();
        b->ret = 0;
        r = run(b, c);
        double t = b->ret ? b->ret : tm_now_ms();
        w->armed = 0;
        if (r != RS_ERR_CANCELLED) {
            fprintf(stderr, "cancel: %s did not stop at call %llu of %llu: %s\n", call_name[c],
                    (unsigned long long)w->stop_at, (unsigned long long)calls, rs_strerror(r));
            return 1;
        }
        if (t - w->stop_time > out->cancel_ms) out->cancel_ms = t - w->stop_time;
    }
    return 0;
}

static int city(rs_ctx *ctx, size_t n, rs_dem **dem, rs_roads **roads)
{
    sc_scene sc;
    if (sc_city(&sc, 400, 350, 5.0, n, 1) || rs_dem_create(ctx, sc.w, sc.h, sc.z, dem) ||
        rs_roads_create(ctx, roads))
        return 1;
    for (size_t i = 0; i < sc.nroads; i++) {
        const sc_road *r = &sc.roads[i];
        if (rs_roads_add(ctx, *roads, NULL, r->width, r->xy, r->n) ||
            rs_roads_set_attr(ctx, *roads, i, "class", sc_city_class(r->width)) ||
            rs_roads_set_attr(ctx, *roads, i, "lanes", "2"))
            return 1;
    }
    rs_dem_frame fc = { sc.cell_size, 0.01, 0, 0 };
    int bad = rs_dem_set_frame(ctx, *dem, &fc) != RS_OK;
    sc_scene_free(&sc);
    return bad;
}

/* Roads as the road file format (%.17g: the same doubles back). */
static char *roads_text(const rs_roads *roads, size_t *len)
{
    size_t n = rs_roads_count(roads), cap = 64;
    for (size_t i = 0; i < n; i++) {
        size_t np = 0;
        rs_roads_get(roads, i, NULL, NULL, NULL, &np);
        cap += 96 + 52 * np;
    }
    char *t = malloc(cap);
    size_t at = 0;
    for (size_t i = 0; t && i < n; i++) {
        const double *xy = NULL;
        double w = 0;
        size_t np = 0;
        rs_roads_get(roads, i, NULL, &w, &xy, &np);
        at += (size_t)snprintf(t + at, cap - at, "road r%zu width %.17g class=%s lanes=2\n", i, w,
                               rs_roads_get_attr(roads, i, "class"));
        for (size_t k = 0; k < np; k++)
            at += (size_t)snprintf(t + at, cap - at, "%.17g %.17g\n", xy[2 * k], xy[2 * k + 1]);
        at += (size_t)snprintf(t + at, cap - at, "end\n");
    }
    *len = at;
    return t;
}

/* A side x side PGM of pseudo-random heights 0..4000: P2 text or 16-bit P5. */
static char *pgm_file(uint32_t side, int binary, size_t *len)
{
    size_t n = (size_t)side * side;
    char *p = malloc(32 + (binary ? 2 : 6) * n);
    if (!p) return NULL;
    size_t at = (size_t)sprintf(p, "%s\n%u %u\n4000\n", binary ? "P5" : "P2", side, side);
    for (size_t i = 0; i < n; i++) {
        unsigned v = (unsigned)((i * 2654435761u) % 4001u);
        if (binary) {
            p[at++] = (char)(v >> 8);
            p[at++] = (char)(v & 255);
        } else {
            at += (size_t)sprintf(p + at, "%u\n", v);
        }
    }
    *len = at;
    return p;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "build/bench";
    rs_ctx *ctx;
    if (rs_ctx_create(NULL, NULL, &ctx)) return 1;
    watch w;
    memset(&w, 0, sizeof w);
    rs_ctx_set_progress(ctx, on_progress, &w);
    bench b;
    memset(&b, 0, sizeof b);
    b.ctx = ctx;
    b.w = &w;
    /* the fractal of tests/bench/roam.c (1 m cells, 400 m of relief) */
    const uint32_t S = 1025;
    float *z = malloc((size_t)S * S * sizeof *z);
    if (!z) return 1;
    rc_dem_fractal(z, S, S, 1234, 512.0, 400.0, 0.5);
    rs_dem_frame ff = { 1.0, 1.0, 0, 0 };
    if (rs_dem_create(ctx, S, S, z, &b.fractal) || rs_dem_set_frame(ctx, b.fractal, &ff)) return 1;
    free(z);

    if (!(b.pgm[0] = pgm_file(2049, 0, &b.pgm_len[0])) || !(b.pgm[1] = pgm_file(8193, 1, &b.pgm_len[1]))) return 1;
    b.atlas.width = 4096;
    b.atlas.height = 2048;
    uint8_t *apx = malloc((size_t)4096 * 2048 * 4);
    if (!apx) return 1;
    for (size_t i = 0; i < (size_t)4096 * 2048 * 4; i++) apx[i] = (uint8_t)(i * 2654435761u >> 24);
    b.atlas.rgba = apx;

    FILE *md, *csv;
    if (tm_open_section(dir, "cancel", &md, &csv)) return 1;
    fprintf(md, "## Progress and cancel of the long calls (tests/bench/cancel.c)\n\n"
                "Each long call on a big input with the context's progress callback (`rs_ctx_set_progress`): the "
                "longest time between two progress calls (from the call's start, and from the last call to its "
                "return), and then calls stopped by the callback at call points spread over the run (7; 3 for "
                "the slowest): the largest time from the stopping call to the return. The city: `sc_city`, 400 x "
                "350 samples of 5 m, default class styles (lines, casings, automatic markings), grids at 4 "
                "texels; the window, normal map and virtual texture on its 8-texel splatter (10^4 roads, a "
                "3192 x 2792 image); ROAM on the 1025^2 fractal (1 m cells, 400 m relief, pool 2^21 nodes); the "
                "parsers on the city's roads as a road file and on PGM files of pseudo-random heights (a 2049^2 "
                "P2, an 8193^2 16-bit P5 with maxval 4000, which is checked sample by sample); the extraction "
                "(with normals) of the fractal's refine_count(10^6) mesh; an atlas of one 4096 x 2048 sprite. "
                "Wall clock, one thread; a call's time ends at its return (freeing what it made is the host's "
                "next call: rs_road_grid_free of the 10^5-road grid, 615 MB, takes ~0.14 s of page unmapping, "
                "which until 2 December 2026 was counted here). Issue 30 target 4: cancel returns within 50 ms.\n\n"
                "| call | input | ms | progress calls | longest gap ms | stop to return ms (max) |\n"
                "|---|---|---|---|---|---|\n");
    fprintf(csv, "call,input,ms,calls,gap_ms,cancel_ms\n");
    double worst = 0;
    const char *worst_call = "";
    static const size_t counts[2] = { 10000, 100000 };
    for (int ci = 0; ci < 2; ci++) {
        if (city(ctx, counts[ci], &b.dem, &b.roads)) return 1;
        char input[64];
        snprintf(input, sizeof input, "city, %zu roads", counts[ci]);
        int calls[C_COUNT], nc = 0;
        calls[nc++] = C_GRID;
        calls[nc++] = C_GRID_PLAIN;
        calls[nc++] = C_NETWORK;
        calls[nc++] = C_GPU;
        if (!(b.text = roads_text(b.roads, &b.text_len))) return 1;
        calls[nc++] = C_PARSE_ROADS;
        if (ci == 0) {
            rs_splat_options o;
            memset(&o, 0, sizeof o);
            o.texels = 8;
            if (rs_splatter_create(ctx, b.dem, b.roads, NULL, &o, &b.sp)) return 1;
            rs_splatter_size(b.sp, &b.W, &b.H);
            rs_vt_options vo;
            memset(&vo, 0, sizeof vo);
            vo.roads = b.roads;
            if (!(b.px = malloc((size_t)b.W * b.H * 4)) || rs_vt_create(ctx, b.sp, &vo, &b.vt) ||
                rs_vt_workspace_create(ctx, b.vt, &b.vws))
                return 1;
            calls[nc++] = C_WINDOW;
            calls[nc++] = C_NORMALS;
            calls[nc++] = C_VT_CREATE;
            calls[nc++] = C_VT_TILE;
            calls[nc++] = C_ROAM_CREATE;
            calls[nc++] = C_ROAM_SETDEM;
            calls[nc++] = C_ROAM_ERROR;
            calls[nc++] = C_ROAM_COUNT;
            calls[nc++] = C_ROAM_FRAME;
            calls[nc++] = C_ROAM_UPDATE;
            calls[nc++] = C_ROAM_EXTRACT;
            calls[nc++] = C_PARSE_P2;
            calls[nc++] = C_PARSE_P5;
            calls[nc++] = C_ATLAS;
        }
        for (int k = 0; k < nc; k++) {
            int c = calls[k];
            if (argc > 2 && !strstr(call_name[c], argv[2])) continue;
            result r;
            int roam = c >= C_ROAM_CREATE && c <= C_ROAM_UPDATE;
            if (measure(&b, c, ci || c == C_VT_CREATE ? 3 : 7, &r)) return 1;
            const char *in = roam ? "fractal 1025^2" : c == C_WINDOW || c == C_NORMALS ? "city 10^4, 3192 x 2792 px"
                           : c == C_VT_CREATE || c == C_VT_TILE ? "city 10^4, 8 texels"
                           : c == C_PARSE_P2 ? "PGM 2049^2, text" : c == C_PARSE_P5 ? "PGM 8193^2, 16-bit"
                           : c == C_ROAM_EXTRACT ? "fractal 1025^2, refine_count(10^6)"
                           : c == C_ATLAS ? "one 4096 x 2048 sprite" : input;
            double m = r.gap_ms > r.cancel_ms ? r.gap_ms : r.cancel_ms;
            if (m > worst) worst = m, worst_call = call_name[c];
            fprintf(md, "| %s | %s | %.0f | %llu | %.1f | %.1f |\n", call_name[c], in, r.ms,
                    (unsigned long long)r.calls, r.gap_ms, r.cancel_ms);
            fprintf(csv, "\"%s\",\"%s\",%.3f,%llu,%.3f,%.3f\n", call_name[c], in, r.ms, (unsigned long long)r.calls,
                    r.gap_ms, r.cancel_ms);
            printf("cancel: %s, %s: %.0f ms, %llu calls, longest gap %.1f ms, stop to return %.1f ms\n", call_name[c],
                   in, r.ms, (unsigned long long)r.calls, r.gap_ms, r.cancel_ms);
            fflush(stdout);
        }
        rs_vt_workspace_free(ctx, b.vws);
        rs_vt_free(ctx, b.vt);
        rs_splatter_free(ctx, b.sp);
        b.vws = NULL, b.vt = NULL, b.sp = NULL;
        rs_roads_free(ctx, b.roads);
        rs_dem_free(ctx, b.dem);
        free(b.text);
        b.text = NULL;
    }
    fprintf(md, "\n| target (issue 30, 4) | measured | |\n|---|---|---|\n"
                "| every call above: cancel within 50 ms (longest gap, stop to return) | %.1f ms (%s) | %s |\n",
            worst, worst_call, worst <= 50 ? "met" : "**missed**");
    fclose(md);
    fclose(csv);
    free(b.px);
    free(b.pgm[0]);
    free(b.pgm[1]);
    free(apx);
    free(b.mesh);
    free(b.mesh_ix);
    rs_roam_free(ctx, b.roam);
    rs_dem_free(ctx, b.fractal);
    rs_ctx_free(ctx);
    return 0;
}
