/* `roadsplat render --path FILE [options] DEM ROADS OUT.png`: a flythrough
 * through the virtual texture (issue 30; include/roadsplat.h "Virtual
 * texture", docs/render.md "Flythrough"). The camera moves linearly
 * between the key frames of FILE; each frame the view-dependent ROAM mesh
 * is updated, rs_vt_update lists the tiles to make (made on 2 threads) and
 * they go into GL textures, one per rs_vt slot, and the mesh is drawn tile
 * by tile (cli/render_gl.c, rg_draw_vt). OUT.png is the last frame; the
 * per-frame milliseconds (p50, p99, max) of the texture work and of the
 * whole frame, the tiles made per frame and the resident texture memory go
 * to stdout and --stats. */
#include "cli.h"

#ifdef RS_WITH_OSMESA
#include "render_gl.h"
#include "gis.h"

#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#define PATH_PI 3.14159265358979323846
#define PATH_MAX_KEYS 100000

static const char path_usage[] =
    "Usage: roadsplat render --path FILE [splat options] [options] DEM ROADS OUT.png\n"
    "\n"
    "Flies the camera through the key frames of FILE (one per line: eye X Y Z and\n"
    "look-at X Y Z, in the frame --camera uses; '#' comments), linearly in between,\n"
    "and draws every frame with the roads from the virtual texture: tiles of the\n"
    "splat made as the view needs them (rs_vt), not one baked texture. OUT.png is\n"
    "the last frame. Prints the per-frame milliseconds of the texture work (update,\n"
    "making tiles on 2 threads, upload) and of the whole frame (p50, p99, max), the\n"
    "tiles made per frame and the resident texture memory.\n"
    "\n"
    "Splat options as for `roadsplat render` (--texels N sets the finest pixel).\n"
    "Options:\n"
    "  --frames N          frames over the whole path (default 600)\n"
    "  --size WxH          image size (default 1280x720)\n"
    "  --fov DEG           vertical field of view (default 60)\n"
    "  --pixel-error P     ROAM screen-space tolerance in pixels (default 1)\n"
    "  --tile-size N       virtual texture tile side, pixels (default 256)\n"
    "  --budget-mb MB      resident tiles at most this many MiB (default 256)\n"
    "  --max-make N        at most N tiles made a frame (default: all the view needs)\n"
    "  --lighting on|off   shade by the sun (default on)\n"
    "  --fog               linear distance fog\n"
    "  --stats FILE.json   the numbers as JSON, with per-frame arrays\n"
    "  --quiet             no summary line\n";

typedef struct path_args {
    cli_splat_args s;
    const char *dem, *roads, *out, *path, *stats;
    uint32_t width, height, frames, tile_size, max_make;
    double fov, budget_mb, pixel_error;
    int lighting, fog, quiet;
} path_args;

/* 0 run, 1 usage error, 2 --help handled. */
static int parse_path_args(int argc, char **argv, path_args *a)
{
    const char *pos[3];
    int npos = 0;
    memset(a, 0, sizeof *a);
    a->width = 1280;
    a->height = 720;
    a->frames = 600;
    a->fov = 60;
    a->pixel_error = 1;
    a->tile_size = 256;
    a->budget_mb = 256;
    a->lighting = 1;
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i], *v = NULL;
        if (arg[0] != '-' || arg[1] == '\0') {
            if (npos == 3) { cli_error("render: unexpected argument '%s'", arg); return 1; }
            pos[npos++] = arg;
            continue;
        }
        char name[CLI_OPT_NAME];
        const char *inl = cli_option_split(arg, name);
        if (!strcmp(name, "--help") || !strcmp(name, "-h")) { fputs(path_usage, stdout); return 2; }
        if (!strcmp(name, "--quiet") || !strcmp(name, "-q")) { a->quiet = 1; continue; }
        if (!strcmp(name, "--fog")) { a->fog = 1; continue; }
        int sr = cli_splat_option(argc, argv, &i, name, inl, &a->s);
        if (sr > 0) return 1;
        if (sr == 0) continue;
        if (cli_option_value(argc, argv, &i, name, inl, &v)) return 1;
        if (!strcmp(name, "--path")) a->path = v;
        else if (!strcmp(name, "--stats")) a->stats = v;
        else if (!strcmp(name, "--size")) {
            if (cli_parse_size(name, v, &a->width, &a->height)) return 1;
            if (a->width < 1 || a->height < 1 || a->width > 16384 || a->height > 16384) {
                cli_error("%s: '%s' must be 1..16384 on each side", name, v);
                return 1;
            }
        } else if (!strcmp(name, "--frames") || !strcmp(name, "--tile-size") || !strcmp(name, "--max-make")) {
            uint32_t *p = !strcmp(name, "--frames") ? &a->frames : !strcmp(name, "--tile-size") ? &a->tile_size
                                                                                                 : &a->max_make;
            if (cli_parse_u32(name, v, p)) return 1;
            if ((p == &a->frames && (*p < 1 || *p > 1000000)) || (p == &a->tile_size && (*p < 8 || *p > 8192))) {
                cli_error("%s: '%s' must be %s", name, v, p == &a->frames ? "1..1000000" : "8..8192");
                return 1;
            }
        } else if (!strcmp(name, "--fov") || !strcmp(name, "--budget-mb") || !strcmp(name, "--pixel-error")) {
            double *p = !strcmp(name, "--fov") ? &a->fov : !strcmp(name, "--budget-mb") ? &a->budget_mb
                                                                                         : &a->pixel_error;
            if (cli_parse_double(name, v, p)) return 1;
            if ((p == &a->fov && !(*p > 0 && *p < 179)) || (p == &a->budget_mb && !(*p > 0 && *p <= 1048576)) ||
                (p == &a->pixel_error && !(*p > 0 && *p <= 1e6))) {
                cli_error("%s: '%s' must be %s", name, v,
                          p == &a->fov ? "in (0, 179) degrees" : p == &a->budget_mb ? "in (0, 1048576]" : "in (0, 1e6]");
                return 1;
            }
        } else if (!strcmp(name, "--lighting")) {
            if (strcmp(v, "on") && strcmp(v, "off")) { cli_error("%s: '%s' must be on or off", name, v); return 1; }
            a->lighting = !strcmp(v, "on");
        } else {
            cli_error("render: unknown option '%s' with --path (see roadsplat render --path FILE --help)", arg);
            return 1;
        }
    }
    if (npos != 3) {
        cli_error("render: need DEM ROADS OUT.png (see roadsplat render --path FILE --help)");
        return 1;
    }
    if (!a->path) { cli_error("render: --path FILE is required here"); return 1; }
    a->dem = pos[0];
    a->roads = pos[1];
    a->out = pos[2];
    return 0;
}

/* The key frames: 6 numbers a line (eye, look-at). */
static int read_path(const char *file, double **keys, size_t *nkeys)
{
    char *text = NULL;
    size_t size = 0;
    if (cli_read_input(file, "--path", 64u << 20, &text, &size)) return 1;
    size_t cap = 16, n = 0, line = 0;
    double *k = malloc(cap * 6 * sizeof *k);
    int bad = !k;
    if (!k) cli_error("%s: out of memory", file);
    char *save = NULL;
    for (char *ln = text; !bad && ln && *ln;) {
        char *nl = strchr(ln, '\n');
        if (nl) *nl = '\0';
        line++;
        char *hash = strchr(ln, '#');
        if (hash) *hash = '\0';
        double v[6];
        int got = 0;
        char where[1100]; /* cli_parse_double's message names it: "FILE line N: 'x' is not a number" */
        snprintf(where, sizeof where, "%.1000s line %zu", file, line);
        for (char *tok = strtok_r(ln, " \t\r", &save); tok && !bad; tok = strtok_r(NULL, " \t\r", &save)) {
            if (got == 6) {
                cli_error("%s line %zu: more than 6 numbers (eye X Y Z, look-at X Y Z)", file, line);
                bad = 1;
            } else if (cli_parse_double(where, tok, &v[got])) {
                bad = 1;
            } else if (fabs(v[got]) > 1e9) {
                cli_error("%s line %zu: %s is beyond 1e9 metres", file, line, tok);
                bad = 1;
            } else got++;
        }
        if (!bad && got && got != 6) {
            cli_error("%s line %zu: %d numbers, need 6 (eye X Y Z, look-at X Y Z)", file, line, got);
            bad = 1;
        }
        if (!bad && got == 6) {
            if (v[0] == v[3] && v[1] == v[4] && v[2] == v[5]) {
                cli_error("%s line %zu: the eye is the point looked at", file, line);
                bad = 1;
            } else if (n == PATH_MAX_KEYS) {
                cli_error("%s line %zu: more than %d key frames", file, line, PATH_MAX_KEYS);
                bad = 1;
            } else {
                if (n == cap) {
                    double *q = realloc(k, cap * 2 * 6 * sizeof *k);
                    if (!q) { cli_error("%s: out of memory", file); bad = 1; break; }
                    k = q;
                    cap *= 2;
                }
                memcpy(k + 6 * n++, v, sizeof v);
            }
        }
        ln = nl ? nl + 1 : NULL;
    }
    free(text);
    if (!bad && n < 2) {
        cli_error("%s: %zu key frames, need at least 2 (one a line: eye X Y Z look-at X Y Z)", file, n);
        bad = 1;
    }
    if (bad) { free(k); return 1; }
    *keys = k;
    *nkeys = n;
    return 0;
}

typedef struct maker {
    const rs_vt *vt;
    const rs_vt_tile *tiles;
    size_t n, next;
    uint8_t *stage;
    size_t tile_bytes;
    uint32_t side;
    pthread_mutex_t mu;
    int bad;
    char msg[256];
} maker;

typedef struct maker_thread {
    maker *m;
    rs_ctx *ctx;
    rs_vt_workspace *ws;
} maker_thread;

static void make_tiles(maker_thread *t)
{
    maker *m = t->m;
    for (;;) {
        pthread_mutex_lock(&m->mu);
        size_t i = m->next++;
        pthread_mutex_unlock(&m->mu);
        if (i >= m->n) break;
        const rs_vt_tile *tl = &m->tiles[i];
        if (rs_vt_make_tile(t->ctx, m->vt, t->ws, tl->level, tl->x, tl->y, m->stage + i * m->tile_bytes,
                            (size_t)m->side * 4)) {
            pthread_mutex_lock(&m->mu);
            if (!m->bad) snprintf(m->msg, sizeof m->msg, "%s", rs_ctx_message(t->ctx));
            m->bad = 1;
            pthread_mutex_unlock(&m->mu);
        }
    }
}

static void *make_thread_main(void *arg)
{
    make_tiles(arg);
    return NULL;
}

/* The frame's camera for the virtual texture and for the mesher: the same
 * eye, direction, field of view, viewport and far distance. */
static void cameras(const path_args *a, const rg_view *v, rs_vt_view *vv, rs_roam_view *rv)
{
    memset(vv, 0, sizeof *vv);
    memset(rv, 0, sizeof *rv);
    memcpy(vv->eye, v->eye, sizeof vv->eye);
    memcpy(rv->eye, v->eye, sizeof rv->eye);
    for (int k = 0; k < 3; k++) vv->dir[k] = rv->dir[k] = v->look[k] - v->eye[k];
    vv->fov_y = rv->fov_y = a->fov;
    vv->width = rv->width = a->width;
    vv->height = rv->height = a->height;
    vv->far_dist = rv->far_dist = v->zfar;
    vv->max_make = a->max_make;
    vv->anisotropy = 1; /* the tiles' GL sampler: trilinear, no anisotropic taps */
    rv->pixel_error = a->pixel_error;
}

static int cmp_dbl(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return a < b ? -1 : a > b;
}

/* p50, p99, max of n values (sorted in place). */
static void percentiles(double *v, size_t n, double out[3])
{
    qsort(v, n, sizeof *v, cmp_dbl);
    out[0] = v[n / 2];
    out[1] = v[(size_t)ceil(0.99 * (double)n) - 1];
    out[2] = v[n - 1];
}

int cli_render_path_main(int argc, char **argv)
{
    path_args a;
    int pr = parse_path_args(argc, argv, &a);
    if (pr) return pr == 2 ? 0 : 1;
    int rc = 1;
    rs_ctx *ctx = NULL, *ctx2 = NULL;
    cli_splat_input in;
    memset(&in, 0, sizeof in);
    rs_road_grid *grid = NULL;
    rs_splatter *sp = NULL;
    rs_vt *vt = NULL;
    rs_vt_workspace *ws[2] = { NULL, NULL };
    rs_roam *roam = NULL;
    rg_renderer *gl = NULL;
    double *keys = NULL, *tex_ms = NULL, *frame_ms = NULL;
    uint32_t *made_seq = NULL;
    uint8_t *stage = NULL, *frame = NULL;
    size_t stage_cap = 0;
    cli_mesh_buf mesh;
    memset(&mesh, 0, sizeof mesh);
    rg_vt_draw_tile *dt = NULL;
    size_t nkeys = 0;
    char err[256];
    maker mk;
    memset(&mk, 0, sizeof mk);
    pthread_mutex_init(&mk.mu, NULL);
    cli_out out, so;
    memset(&out, 0, sizeof out);
    memset(&so, 0, sizeof so);
    const cli_file_role outs[2] = { { a.out, "OUT" }, { a.stats, "--stats" } };
    const cli_file_role ins[5] = { { a.dem, "DEM" }, { a.roads, "ROADS" }, { a.s.terrain_tex, "--terrain-texture" },
                                   { a.s.road_tex, "--road-texture" }, { a.path, "--path" } };
    if (cli_check_outputs(outs, 2, ins, 5)) goto done;
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    cli_splat_limits(&a.s, &lim);
    /* the virtual image is never held whole: only its tiles */
    if (lim.max_pixels < ((uint64_t)1 << 42)) lim.max_pixels = (uint64_t)1 << 42;
    if (rs_ctx_create(NULL, &lim, &ctx) || rs_ctx_create(NULL, &lim, &ctx2)) { cli_error("out of memory"); goto done; }
    if (read_path(a.path, &keys, &nkeys)) goto done;
    if (cli_out_open(&out, a.out) || (a.stats && cli_out_open(&so, a.stats))) goto done;
    if (cli_splat_input_load(ctx, a.dem, a.roads, &a.s, &in)) goto done;
    const rs_dem *dem = in.dem;
    rs_dem_frame fr;
    rs_dem_get_frame(dem, &fr);
    /* key frames in the frame of --camera (cli/render.c): world, the roads' origin, or local */
    double wx0 = 0, wy0 = 0;
    int world = cli_geo_world_origin(&in, &wx0, &wy0), orig = !world && a.s.origin_given;
    if (orig) { wx0 = fr.origin_x; wy0 = fr.origin_y; }
    for (size_t k = 0; k < 2 * nkeys; k++) {
        double *p = keys + 3 * k;
        if (world) { p[0] -= wx0; p[1] = wy0 - p[1]; }
        else if (orig) { p[0] -= wx0; p[1] -= wy0; }
    }
    if (cli_splatter_prepare(ctx, &in, a.roads, &a.s, 1, &grid, &sp)) goto done;
    uint32_t tw, th;
    rs_splatter_size(sp, &tw, &th);
    rs_vt_options vo;
    memset(&vo, 0, sizeof vo);
    vo.tile_size = a.tile_size;
    vo.budget_bytes = (uint64_t)(a.budget_mb * 1048576.0);
    vo.roads = in.roads; /* coarser levels of a styled grid build their own grids */
    rs_result r;
    if ((r = rs_vt_create(ctx, sp, &vo, &vt)) || (r = rs_vt_workspace_create(ctx, vt, &ws[0])) ||
        (r = rs_vt_workspace_create(ctx2, vt, &ws[1]))) {
        cli_error("%s: virtual texture: %s", a.roads, rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(r));
        goto done;
    }
    rs_vt_info vi;
    rs_vt_get_info(vt, &vi);
    rs_roam_options ro;
    memset(&ro, 0, sizeof ro);
    if ((r = rs_roam_create(ctx, dem, &ro, &roam))) { cli_error("%s: %s", a.dem, rs_ctx_message(ctx)); goto done; }
    if (!(gl = rg_create(a.width, a.height, err, sizeof err)) || rg_vt_slots(gl, vi.slots, vi.tile_side, err, sizeof err)) {
        cli_error("render: %s", err);
        goto done;
    }
    tex_ms = malloc(a.frames * sizeof *tex_ms);
    frame_ms = malloc(a.frames * sizeof *frame_ms);
    made_seq = malloc(a.frames * sizeof *made_seq);
    dt = malloc(vi.slots * sizeof *dt);
    if (!tex_ms || !frame_ms || !made_seq || !dt) { cli_error("out of memory"); goto done; }

    rg_view view;
    memset(&view, 0, sizeof view);
    view.map_w = (rs_dem_width(dem) - 1) * fr.cell_size;
    view.map_h = (rs_dem_height(dem) - 1) * fr.cell_size;
    double zlo, zhi;
    rs_dem_height_range(dem, &zlo, &zhi, NULL);
    view.zmin = fmin(zlo * fr.z_scale, zhi * fr.z_scale);
    view.zmax = fmax(zlo * fr.z_scale, zhi * fr.z_scale);
    view.fov_y = a.fov;
    view.lighting = a.lighting;
    view.fog = a.fog;
    view.sun[0] = sin(315 * PATH_PI / 180) * cos(PATH_PI / 4);
    view.sun[1] = -cos(315 * PATH_PI / 180) * cos(PATH_PI / 4);
    view.sun[2] = sin(PATH_PI / 4);
    double diag = sqrt(view.map_w * view.map_w + view.map_h * view.map_h + (view.zmax - view.zmin) * (view.zmax - view.zmin));
    uint64_t made_total = 0;
    uint32_t made_max = 0;
    double resident_max = 0;
    for (uint32_t f = 0; f < a.frames; f++) {
        double f0 = cli_now_ms();
        double s = a.frames > 1 ? (double)f * (double)(nkeys - 1) / (a.frames - 1) : 0;
        size_t seg = (size_t)s < nkeys - 1 ? (size_t)s : nkeys - 2;
        double t = s - (double)seg;
        double kv[6];
        for (int k = 0; k < 6; k++) kv[k] = keys[6 * seg + k] + t * (keys[6 * (seg + 1) + k] - keys[6 * seg + k]);
        memcpy(view.eye, kv, sizeof view.eye);
        memcpy(view.look, kv + 3, sizeof view.look);
        /* clip range: the nearest and farthest the map can be */
        double far = 0;
        for (int c = 0; c < 4; c++) {
            double dx = (c & 1 ? view.map_w : 0) - view.eye[0], dy = (c & 2 ? view.map_h : 0) - view.eye[1];
            double dz = fmax(fabs(view.zmin - view.eye[2]), fabs(view.zmax - view.eye[2]));
            far = fmax(far, sqrt(dx * dx + dy * dy + dz * dz));
        }
        view.zfar = fmax(far, diag) * 1.01 + 1;
        view.znear = fmax(view.zfar * 1e-5, 0.01);
        view.fog_start = 0.3 * view.zfar;
        view.fog_end = view.zfar;
        rs_vt_view vv;
        rs_roam_view rv;
        cameras(&a, &view, &vv, &rv);
        /* the texture work: the cut, the tiles made on 2 threads, their upload */
        if ((r = rs_vt_update(ctx, vt, &vv))) { cli_error("render: %s", rs_ctx_message(ctx)); goto done; }
        size_t nm, nn;
        mk.tiles = rs_vt_to_make(vt, &nm);
        if (nm * vi.tile_bytes > stage_cap) {
            free(stage);
            stage_cap = nm * vi.tile_bytes;
            stage = malloc(stage_cap);
            if (!stage) { cli_error("out of memory for %zu tiles", nm); goto done; }
        }
        mk.vt = vt;
        mk.n = nm;
        mk.next = 0;
        mk.stage = stage;
        mk.tile_bytes = vi.tile_bytes;
        mk.side = vi.tile_side;
        maker_thread t0 = { &mk, ctx, ws[0] }, t1 = { &mk, ctx2, ws[1] };
        pthread_t th2;
        int threaded = nm > 1 && pthread_create(&th2, NULL, make_thread_main, &t1) == 0;
        make_tiles(&t0);
        if (threaded) pthread_join(th2, NULL);
        if (mk.bad) { cli_error("render: making a tile: %s", mk.msg); goto done; }
        for (size_t i = 0; i < nm; i++)
            if (rg_vt_upload(gl, mk.tiles[i].slot, stage + i * vi.tile_bytes, err, sizeof err)) {
                cli_error("render: %s", err);
                goto done;
            }
        double f1 = cli_now_ms();
        /* the mesh */
        r = rs_roam_update(ctx, roam, &rv, 0);
        if (r && r != RS_ERR_POOL_EXHAUSTED) { cli_error("%s: %s", a.dem, rs_ctx_message(ctx)); goto done; }
        if (cli_mesh_extract(ctx, roam, a.dem, &mesh)) goto done;
        /* each needed tile, or while a capped make is pending its nearest resident ancestor */
        const rs_vt_tile *need = rs_vt_needed(vt, &nn);
        size_t nd = 0;
        for (size_t i = 0; i < nn; i++) {
            rs_vt_tile use = need[i];
            if (use.slot == UINT32_MAX && !rs_vt_lookup(vt, need[i].level, need[i].x, need[i].y, &use)) continue;
            double sc = ldexp(1.0, (int)need[i].level), S = vi.tile_size;
            rg_vt_draw_tile *d = &dt[nd++];
            d->slot = use.slot;
            d->x0 = need[i].x * S * sc;
            d->y0 = need[i].y * S * sc;
            d->x1 = fmin((need[i].x + 1) * S * sc, tw);
            d->y1 = fmin((need[i].y + 1) * S * sc, th);
            d->scale = ldexp(1.0, (int)use.level);
            d->ox = use.x * S - vi.border;
            d->oy = use.y * S - vi.border;
        }
        if (rg_draw_vt(gl, &view, mesh.vtx, mesh.nrm, mesh.nv, mesh.idx, mesh.ni, tw, th, dt, nd, err, sizeof err)) {
            cli_error("render: %s", err);
            goto done;
        }
        double f2 = cli_now_ms();
        tex_ms[f] = f1 - f0;
        frame_ms[f] = f2 - f0;
        rs_vt_stats st;
        rs_vt_get_stats(vt, &st);
        made_seq[f] = st.made;
        made_total += st.made;
        if (st.made > made_max) made_max = st.made;
        if (st.resident_bytes / 1048576.0 > resident_max) resident_max = st.resident_bytes / 1048576.0;
    }
    frame = malloc((size_t)a.width * a.height * 4);
    if (!frame) { cli_error("out of memory for a %u x %u image", a.width, a.height); goto done; }
    rg_read_rgba(gl, frame);
    for (size_t k = 0; k < (size_t)a.width * a.height; k++) memmove(frame + 3 * k, frame + 4 * k, 3);
    {
        cli_png_image img = { a.width, a.height, 3, 8, frame };
        cli_png_options po = { a.s.png_level_given ? a.s.png_level : -1, NULL, NULL, 0 };
        if (cli_png_encode(out.f, out.path, &img, &po) || cli_out_finish(&out)) goto done;
    }
    double tp[3], fp[3];
    if (a.stats) {
        fprintf(so.f, "{\n  \"command\": \"render --path\",\n  \"frames\": %u,\n  \"width\": %u,\n  \"height\": %u,\n",
                a.frames, a.width, a.height);
        fprintf(so.f, "  \"virtual_texture\": {\"width\": %u, \"height\": %u, \"levels\": %u, \"tile_size\": %u, "
                      "\"border\": %u, \"slots\": %u, \"budget_bytes\": %llu},\n",
                tw, th, vi.levels, vi.tile_size, vi.border, vi.slots, (unsigned long long)vi.budget_bytes);
        fprintf(so.f, "  \"per_frame\": {\"texture_ms\": [");
        for (uint32_t f = 0; f < a.frames; f++) fprintf(so.f, "%s%.3f", f ? ", " : "", tex_ms[f]);
        fprintf(so.f, "], \"frame_ms\": [");
        for (uint32_t f = 0; f < a.frames; f++) fprintf(so.f, "%s%.3f", f ? ", " : "", frame_ms[f]);
        fprintf(so.f, "], \"tiles_made\": [");
        for (uint32_t f = 0; f < a.frames; f++) fprintf(so.f, "%s%u", f ? ", " : "", made_seq[f]);
        fprintf(so.f, "]},\n");
    }
    percentiles(tex_ms, a.frames, tp);
    percentiles(frame_ms, a.frames, fp);
    if (a.stats) {
        fprintf(so.f, "  \"texture_ms\": {\"p50\": %.3f, \"p99\": %.3f, \"max\": %.3f},\n", tp[0], tp[1], tp[2]);
        fprintf(so.f, "  \"frame_ms\": {\"p50\": %.3f, \"p99\": %.3f, \"max\": %.3f},\n", fp[0], fp[1], fp[2]);
        fprintf(so.f, "  \"tiles_made\": {\"mean\": %.3f, \"max\": %u},\n  \"resident_mb_max\": %.3f\n}\n",
                (double)made_total / a.frames, made_max, resident_max);
        if (ferror(so.f)) { cli_error("%s: write failed", a.stats); goto done; }
    }
    cli_out *const all[2] = { &out, &so };
    if (cli_out_commit_all(all, 2)) goto done;
    if (!a.quiet)
        printf("render --path: %u frames, texture work p50 %.2f p99 %.2f max %.2f ms, frame p50 %.2f p99 %.2f max "
               "%.2f ms, %.2f tiles made a frame (max %u), %.1f MB resident (max)\n",
               a.frames, tp[0], tp[1], tp[2], fp[0], fp[1], fp[2], (double)made_total / a.frames, made_max,
               resident_max);
    rc = 0;
done:
    cli_out_abort(&out);
    cli_out_abort(&so);
    rg_destroy(gl);
    free(frame); free(stage); free(dt);
    cli_mesh_buf_free(&mesh);
    free(tex_ms); free(frame_ms); free(made_seq); free(keys);
    pthread_mutex_destroy(&mk.mu);
    rs_roam_free(ctx, roam);
    rs_vt_workspace_free(ctx, ws[0]);
    rs_vt_workspace_free(ctx2, ws[1]);
    rs_vt_free(ctx, vt);
    rs_splatter_free(ctx, sp);
    rs_road_grid_free(ctx, grid);
    cli_splat_input_free(ctx, &in);
    rs_ctx_free(ctx2);
    rs_ctx_free(ctx);
    return rc;
}
#else
/* Without OSMesa nothing here is compiled (cli/render.c prints why). */
typedef int rs_render_vt_no_osmesa;
#endif
