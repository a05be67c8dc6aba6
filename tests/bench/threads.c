/* Threads: the splat of the city scene with 1 and 2 worker threads on one
 * shared splatter, each thread with its own context, bands of rows taken in
 * turn (as the CLI's --threads does). Reports the speed-up measured in the
 * same run and checks the bytes are the same. */
#include "roadsplat.h"
#include "scene_splat.h"
#include "scenes.h"
#include "timing.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct pool {
    const rs_splatter *s;
    uint8_t *px;
    uint32_t w, h, band, next;
    pthread_mutex_t mu;
    int bad;
} pool;

static void *worker(void *arg)
{
    pool *p = arg;
    rs_ctx *c = NULL;
    if (rs_ctx_create(NULL, NULL, &c)) { p->bad = 1; return NULL; }
    for (;;) {
        pthread_mutex_lock(&p->mu);
        uint32_t y = p->next;
        p->next += p->band;
        pthread_mutex_unlock(&p->mu);
        if (y >= p->h) break;
        uint32_t hh = p->h - y < p->band ? p->h - y : p->band;
        if (rs_splat_window(c, p->s, 0, y, p->w, hh, p->px + (size_t)y * p->w * 4, (size_t)p->w * 4, NULL, 0, NULL))
            p->bad = 1;
    }
    rs_ctx_free(c);
    return NULL;
}

static double run(const rs_splatter *s, uint32_t w, uint32_t h, uint32_t T, int n, uint8_t *px)
{
    pool p;
    memset(&p, 0, sizeof p);
    p.s = s; p.px = px; p.w = w; p.h = h;
    p.band = T * ((32 + T - 1) / T);
    pthread_mutex_init(&p.mu, NULL);
    pthread_t t[8];
    double t0 = tm_now_ms();
    for (int i = 1; i < n; i++) pthread_create(&t[i], NULL, worker, &p);
    worker(&p);
    for (int i = 1; i < n; i++) pthread_join(t[i], NULL);
    double ms = tm_now_ms() - t0;
    pthread_mutex_destroy(&p.mu);
    return p.bad ? -1 : ms;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "build/bench";
    char path[1024];
    rs_ctx *ctx;
    sc_scene sc;
    if (rs_ctx_create(NULL, NULL, &ctx) || sc_city_default(&sc, 1)) return 1;
    rs_dem *dem;
    rs_roads *roads = ss_roads(ctx, &sc);
    rs_dem_frame fr = { sc.cell_size, 0.01, 0, 0 };
    if (!roads || rs_dem_create(ctx, sc.w, sc.h, sc.z, &dem) || rs_dem_set_frame(ctx, dem, &fr)) return 1;
    snprintf(path, sizeof path, "%s/threads.md", dir);
    FILE *md = fopen(path, "w");
    if (!md) return 1;
    fprintf(md, "## Threads (tests/bench/threads.c)\n\n"
                "City scene (`sc_city_default(1)`, 400 x 350 DEM, 5 m cells, %zu roads). One splatter shared by the "
                "worker threads, each with its own context, taking bands of at least 32 rows in turn (what "
                "`--threads N` does). Time = the splat of the whole image (splatter already built), median of 5; "
                "speed-up = 1-thread time / N-thread time, same run. Output bytes compared across thread counts.\n\n"
                "| edges | texels | pixels | 1 thread ms | 2 threads ms | speed-up | same bytes |\n|---|---|---|---|---|---|---|\n",
            sc.nroads);
    const uint32_t Ts[] = { 4, 8 };
    for (int mode = 0; mode < 2; mode++)
        for (int k = 0; k < 2; k++) {
            rs_splat_options o;
            memset(&o, 0, sizeof o);
            o.texels = Ts[k];
            o.coverage.edges = mode ? RS_EDGES_ANALYTIC : RS_EDGES_ALPHAMAP;
            rs_splatter *s;
            if (rs_splatter_create(ctx, dem, roads, NULL, &o, &s)) {
                fprintf(stderr, "threads: %s\n", rs_ctx_message(ctx));
                return 1;
            }
            uint32_t w, h;
            rs_splatter_size(s, &w, &h);
            uint8_t *a = malloc((size_t)w * h * 4), *b = malloc((size_t)w * h * 4);
            if (!a || !b) return 1;
            double t1[5], t2[5];
            for (int r = 0; r < 5; r++) {
                t1[r] = run(s, w, h, Ts[k], 1, a);
                t2[r] = run(s, w, h, Ts[k], 2, b);
                if (t1[r] < 0 || t2[r] < 0) return 1;
            }
            double m1 = tm_median(t1, 5), m2 = tm_median(t2, 5);
            int same = memcmp(a, b, (size_t)w * h * 4) == 0;
            fprintf(md, "| %s | %u | %u x %u | %.1f | %.1f | %.2f | %s |\n", mode ? "analytic" : "alphamap", Ts[k], w,
                    h, m1, m2, m1 / m2, same ? "yes" : "NO");
            printf("threads: %s T=%u: 1 thread %.1f ms, 2 threads %.1f ms (x%.2f)%s\n", mode ? "analytic" : "alphamap",
                   Ts[k], m1, m2, m1 / m2, same ? "" : " BYTES DIFFER");
            free(a);
            free(b);
            rs_splatter_free(ctx, s);
            if (!same) return 1;
        }
    fprintf(md, "\nThe machine has 2 cores; a speed-up below 2 is the share of the work that memory bandwidth and the "
                "other processes on this host leave to the second core.\n");
    fclose(md);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    rs_ctx_free(ctx);
    return 0;
}
