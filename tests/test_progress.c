/* Progress and cancel of the road grid build (issue 30): the default
 * (analytic) build of a styled scene reports through the options' progress
 * callback, done never goes back and ends at total, a callback that asks
 * to stop at its k-th call makes the build return RS_ERR_CANCELLED
 * ("cancelled", no grid, nothing leaked: the sanitizer build checks that)
 * at every stage, and a callback changes nothing in the output. */
#include "roadsplat.h"
#include "scenes.h"
#include "harness.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct watch {
    uint64_t calls, last_done, last_total, stop_at;
    int went_back, over;
} watch;

static int on_progress(void *user, uint64_t done, uint64_t total)
{
    watch *w = user;
    w->calls++;
    if (w->calls > 1 && done < w->last_done) w->went_back = 1;
    if (done > total) w->over = 1;
    w->last_done = done;
    w->last_total = total;
    return w->stop_at && w->calls >= w->stop_at;
}

static uint64_t hash_rgba(const uint8_t *p, size_t n)
{
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < n; i++) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

/* The grid of `roads` with `w` as its callback (NULL: none), splatted
 * whole; *hash: the image's hash. */
static rs_result build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, watch *w, uint64_t *hash)
{
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 2;
    o.progress = w ? on_progress : NULL;
    o.progress_user = w;
    rs_road_grid *g = NULL;
    rs_result r = rs_road_grid_build(ctx, dem, roads, &o, &g);
    if (r) {
        CHECK(g == NULL);
        return r;
    }
    o.progress = NULL;
    rs_splatter *s = NULL;
    if (hash && !rs_splatter_create(ctx, dem, NULL, g, &o, &s)) {
        uint32_t W, H;
        rs_splatter_size(s, &W, &H);
        uint8_t *px = malloc((size_t)W * H * 4);
        if (px && !rs_splat_window(ctx, s, 0, 0, W, H, px, (size_t)W * 4, NULL, 0, NULL))
            *hash = hash_rgba(px, (size_t)W * H * 4);
        free(px);
        rs_splatter_free(ctx, s);
    }
    rs_road_grid_free(ctx, g);
    return r;
}

int main(void)
{
    rs_ctx *ctx;
    if (rs_ctx_create(NULL, NULL, &ctx)) return 1;
    sc_scene sc;
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    /* a styled city: classes give lines, casings and automatic markings */
    CHECK(sc_city(&sc, 120, 100, 5.0, 300, 3) == 0);
    CHECK(rs_dem_create(ctx, sc.w, sc.h, sc.z, &dem) == RS_OK && rs_roads_create(ctx, &roads) == RS_OK);
    for (size_t i = 0; roads && i < sc.nroads; i++) {
        CHECK(rs_roads_add(ctx, roads, NULL, sc.roads[i].width, sc.roads[i].xy, sc.roads[i].n) == RS_OK);
        CHECK(rs_roads_set_attr(ctx, roads, i, "class", sc_city_class(sc.roads[i].width)) == RS_OK);
        CHECK(rs_roads_set_attr(ctx, roads, i, "lanes", "2") == RS_OK);
    }
    rs_dem_frame fc = { sc.cell_size, 0.01, 0, 0 };
    CHECK(rs_dem_set_frame(ctx, dem, &fc) == RS_OK);

    uint64_t h0 = 0, h1 = 1;
    watch w;
    memset(&w, 0, sizeof w);
    CHECK(build(ctx, dem, roads, NULL, &h0) == RS_OK);
    CHECK(build(ctx, dem, roads, &w, &h1) == RS_OK);
    CHECKF(h0 == h1, "a progress callback changed the image");
    /* 5b1f6e8's default build never called it */
    CHECKF(w.calls >= 5, "%llu progress calls", (unsigned long long)w.calls);
    CHECK(!w.went_back && !w.over && w.last_total > 0 && w.last_done == w.last_total);
    printf("grid build: %llu progress calls, total %llu\n", (unsigned long long)w.calls,
           (unsigned long long)w.last_total);

    /* stop at every call of the build: every stage cancels cleanly */
    uint64_t all = w.calls, cancelled = 0;
    for (uint64_t k = 1; k <= all; k++) {
        watch c;
        memset(&c, 0, sizeof c);
        c.stop_at = k;
        rs_result r = build(ctx, dem, roads, &c, NULL);
        CHECKF(r == RS_ERR_CANCELLED, "stop at call %llu of %llu: %s", (unsigned long long)k,
               (unsigned long long)all, rs_strerror(r));
        CHECKF(c.calls == k, "stop at call %llu: the build called on %llu times", (unsigned long long)k,
               (unsigned long long)c.calls);
        CHECK(strcmp(rs_ctx_message(ctx), "cancelled") == 0);
        cancelled += r == RS_ERR_CANCELLED;
    }
    printf("grid build: cancelled at %llu call points\n", (unsigned long long)cancelled);
    /* the context works on after a cancel */
    memset(&w, 0, sizeof w);
    h1 = 1;
    CHECK(build(ctx, dem, roads, &w, &h1) == RS_OK && h1 == h0);

    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    rs_ctx_free(ctx);
    return th_finish("test_progress");
}
