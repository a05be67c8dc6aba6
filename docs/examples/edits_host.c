/* An editing host in C99 (docs/embedding.md "Long chains"): it links the
 * installed roadsplat only and keeps every edit on its own thread in
 * proportion to the edit, while a worker thread builds the grid whole now
 * and then.
 *
 *   cc -std=c99 edits_host.c $(pkg-config --cflags --libs roadsplat) -lpthread -o edits_host
 *   ./edits_host dem.pgm roads.txt 5 4 40
 *
 * Steps: load a DEM (its cell size and texels from the arguments) and
 * roads; build the grid for edits; then N edits (each road in turn moved
 * 2 m east), each an rs_road_grid_update whose dirty rectangles say what
 * to draw again. When the grid holds 8 patches, the roads are copied and a
 * worker thread builds them whole; when it is done, rs_road_grid_rebase
 * moves the chain onto that grid. At the end the grid's splat is compared
 * with a fresh build's: exit 1 when a byte differs, 2 when a step fails. */
#include <roadsplat.h>

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct worker {
    const rs_dem *dem;
    rs_roads *roads; /* the copy, the worker's */
    const rs_splat_options *o;
    rs_road_grid *flat;
    rs_result r;
} worker;

static void *build_whole(void *arg)
{
    worker *w = arg;
    rs_ctx *c = NULL; /* a context per thread */
    w->r = rs_ctx_create(NULL, NULL, &c);
    if (!w->r) w->r = rs_road_grid_build(c, w->dem, w->roads, w->o, &w->flat);
    rs_ctx_free(c);
    return NULL;
}

static char *read_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    char *buf = NULL;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (buf = malloc((size_t)n + 1)) != NULL && fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
    }
    if (buf) *size = (size_t)n;
    fclose(f);
    return buf;
}

/* The grid's whole splat (RGBA and weight), or NULL */
static uint8_t *splat(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *g, const rs_splat_options *o, size_t *bytes)
{
    rs_splatter *sp = NULL;
    uint32_t w, h;
    uint8_t *px = NULL;
    if (rs_splatter_create(ctx, dem, NULL, g, o, &sp)) return NULL;
    rs_splatter_size(sp, &w, &h);
    *bytes = (size_t)w * h * 6;
    if ((px = malloc(*bytes)) != NULL &&
        rs_splat_window(ctx, sp, 0, 0, w, h, px, (size_t)w * 4, (uint16_t *)(void *)(px + (size_t)w * h * 4), w, NULL)) {
        free(px);
        px = NULL;
    }
    rs_splatter_free(ctx, sp);
    return px;
}

static int fail(rs_ctx *ctx, const char *step, rs_result r)
{
    fprintf(stderr, "edits_host: %s: %s (%s)\n", step, rs_strerror(r), rs_ctx_message(ctx));
    return 2;
}

int main(int argc, char **argv)
{
    const char *dem_path = argc > 1 ? argv[1] : "dem.pgm", *roads_path = argc > 2 ? argv[2] : "roads.txt";
    int edits = argc > 5 ? atoi(argv[5]) : 40, e, running = 0, rebases = 0, most = 0, differ;
    rs_ctx *ctx = NULL;
    rs_limits lim;
    rs_splat_options o;
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    rs_road_grid *grid = NULL, *since = NULL, *fresh = NULL;
    rs_dem_frame fr;
    rs_result r;
    pthread_t th;
    worker wk;
    size_t size = 0, nb = 0, nf = 0, dirty = 0;
    char *text;
    uint8_t *a, *b;

    memset(&lim, 0, sizeof lim);
    lim.size = sizeof lim;
    lim.max_patches = 32; /* room while the worker builds */
    if (rs_ctx_create(NULL, &lim, &ctx) != RS_OK) return 2;
    memset(&o, 0, sizeof o);
    o.size = sizeof o;
    o.texels = argc > 4 ? (uint32_t)atoi(argv[4]) : 4;
    o.grid.edits = 1; /* the grid keeps what an update reads */
    if (!(text = read_file(dem_path, &size))) { perror(dem_path); return 2; }
    r = rs_dem_parse_pgm(ctx, text, size, &dem);
    free(text);
    if (r) return fail(ctx, dem_path, r);
    rs_dem_get_frame(dem, &fr);
    fr.cell_size = argc > 3 ? atof(argv[3]) : 5;
    fr.z_scale = 0.01;
    if ((r = rs_dem_set_frame(ctx, dem, &fr))) return fail(ctx, "frame", r);
    if (!(text = read_file(roads_path, &size))) { perror(roads_path); return 2; }
    r = rs_roads_parse(ctx, text, size, &roads);
    free(text);
    if (r) return fail(ctx, roads_path, r);
    if ((r = rs_road_grid_build(ctx, dem, roads, &o, &grid))) return fail(ctx, "road grid", r);

    memset(&wk, 0, sizeof wk);
    for (e = 0; e < edits && rs_roads_count(roads); e++) {
        size_t i = (size_t)e % rs_roads_count(roads), np, k;
        const double *xy;
        double width, *moved;
        rs_road_grid *next = NULL;
        /* the edit: road i 2 m east */
        rs_roads_get(roads, i, NULL, &width, &xy, &np);
        if (!(moved = malloc(2 * np * sizeof *moved))) return 2;
        for (k = 0; k < np; k++) moved[2 * k] = xy[2 * k] + 2, moved[2 * k + 1] = xy[2 * k + 1];
        r = rs_roads_replace(ctx, roads, i, NULL, width, moved, np);
        free(moved);
        if (r) return fail(ctx, "edit", r);
        if ((r = rs_road_grid_update(ctx, dem, roads, &o, grid, &next))) return fail(ctx, "update", r);
        dirty += rs_road_grid_dirty(next, NULL, 0); /* a host draws these again */
        if (grid != since) rs_road_grid_free(ctx, grid);
        grid = next;
        if ((int)rs_road_grid_patch_count(grid) > most) most = (int)rs_road_grid_patch_count(grid);
        if (running && e % 4 == 3) { /* (a host would poll a flag; this one joins now and then) */
            rs_road_grid *moved_grid = NULL;
            pthread_join(th, NULL);
            running = 0;
            if (wk.r) return fail(ctx, "worker's build", wk.r);
            if ((r = rs_road_grid_rebase(ctx, grid, since, wk.flat, &moved_grid))) return fail(ctx, "rebase", r);
            rs_road_grid_free(ctx, grid);
            rs_road_grid_free(ctx, since);
            rs_road_grid_free(ctx, wk.flat);
            rs_roads_free(ctx, wk.roads);
            grid = moved_grid, since = NULL, rebases++;
        } else if (!running && rs_road_grid_patch_count(grid) >= 8) {
            memset(&wk, 0, sizeof wk);
            wk.dem = dem, wk.o = &o;
            if ((r = rs_roads_copy(ctx, roads, &wk.roads))) return fail(ctx, "copy", r);
            since = grid; /* kept until the rebase */
            if (pthread_create(&th, NULL, build_whole, &wk)) return 2;
            running = 1;
        }
    }
    if (running) {
        pthread_join(th, NULL);
        rs_road_grid_free(ctx, wk.flat);
        rs_roads_free(ctx, wk.roads);
        if (since != grid) rs_road_grid_free(ctx, since);
    }

    /* the chain's grid against a fresh build */
    if ((r = rs_road_grid_build(ctx, dem, roads, &o, &fresh))) return fail(ctx, "fresh build", r);
    a = splat(ctx, dem, grid, &o, &nb);
    b = splat(ctx, dem, fresh, &o, &nf);
    if (!a || !b) return fail(ctx, "splat", RS_ERR_NOMEM);
    differ = nb != nf || memcmp(a, b, nb) != 0;
    printf("edits_host: %d edits, %zu dirty rectangles, at most %d patches, %d rebases; the grid %s a fresh build's\n",
           e, dirty, most, rebases, differ ? "differs from" : "splats as");
    free(a);
    free(b);
    rs_road_grid_free(ctx, fresh);
    rs_road_grid_free(ctx, grid);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    return differ ? 1 : 0;
}
