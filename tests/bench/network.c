/* The road network (issue 27), one thread, same run:
 *  1. its cost in the prepared scene: rs_network_build against the whole
 *     road grid build (rs_road_grid_build, which builds the network) of the
 *     city with the default class styles, the city as given and with every
 *     road split into records of two segments (target: the network adds
 *     <= 10 %; process CPU time, wall time beside it);
 *  2. near-linear: rs_network_build on a street lattice of 10^4 and 10^5
 *     records (streets split every two blocks, T ends, crossings at shared
 *     points; target: 100k within 12x of 10k in process CPU time, wall
 *     time beside it).
 * Times: fastest of RUNS, cases interleaved (11 runs since the network's
 * dense cells: 7 before; the city's share in CPU time since then, in wall
 * time before).
 * Usage: network OUTDIR   (writes OUTDIR/network.md and network.csv);
 *        network --one N REPS [city|default|default_split] (a lattice of N
 *        records, the generated city of N roads on the index bench's map,
 *        or the bench's city as given or split (N unused): REPS builds, the
 *        fastest in thread CPU time; for profilers and A/B runs);
 *        network --one N REPS warm (a lattice, after one build of the 10^5
 *        lattice: the heap as warm as in the bench's runs, no page faults);
 *        network --pair REPS (the bench's two lattices by turns, fastest of
 *        REPS each in process CPU time, and their ratio: for A/B runs);
 *        network --dump (an FNV-1a hash of every node, leg and stroke of
 *        lattices and cities of 100 to 10^5 records, plain and split, at
 *        three tolerances: to compare two builds with diff). */
#include "roadsplat.h"
#include "scenes.h"
#include "timing.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define RUNS 11

/* The city's roads with classes; split: every two segments a new record. */
static int city_roads(rs_ctx *ctx, const sc_scene *sc, int split, rs_roads **out)
{
    *out = NULL;
    if (rs_roads_create(ctx, out)) return 1;
    for (size_t i = 0; i < sc->nroads; i++) {
        const sc_road *r = &sc->roads[i];
        for (size_t a = 0; a + 1 < r->n;) {
            size_t b = split ? (a + 2 < r->n ? a + 2 : r->n - 1) : r->n - 1;
            if (rs_roads_add(ctx, *out, NULL, r->width, r->xy + 2 * a, b - a + 1)) return 1;
            size_t k = rs_roads_count(*out) - 1;
            if (rs_roads_set_attr(ctx, *out, k, "class", sc_city_class(r->width)) ||
                rs_roads_set_attr(ctx, *out, k, "lanes", "2"))
                return 1;
            a = b;
        }
    }
    return 0;
}

/* A street lattice of about `target` records: streets every 50 m both ways,
 * a point every 25 m, one record per two blocks; every fourth street ends
 * 10 m short (a dead end), every seventh starts on the previous street's
 * centre line between points (a T). */
static int lattice(rs_ctx *ctx, size_t target, rs_roads **out)
{
    if (rs_roads_create(ctx, out)) return 1;
    size_t side = 2;
    while (2 * side * (side / 4 + 1) < target) side++;
    double xy[2 * 5];
    for (int dir = 0; dir < 2; dir++)
        for (size_t j = 0; j < side; j++)
            for (size_t b = 0; b + 1 < side && rs_roads_count(*out) < target; b += 4) {
                size_t np = 0;
                for (size_t k = 0; k <= 4; k++) {
                    double along = 50.0 * (double)b + 25.0 * (double)k * 2, across = 50.0 * (double)j;
                    if (k == 4 && j % 4 == 3) along -= 10;
                    if (k == 0 && j % 7 == 6) along += 12.5;
                    xy[2 * np] = dir ? across : along;
                    xy[2 * np + 1] = dir ? along : across;
                    np++;
                }
                if (rs_roads_add(ctx, *out, NULL, 7, xy, np)) return 1;
                if (rs_roads_set_attr(ctx, *out, rs_roads_count(*out) - 1, "class", "residential")) return 1;
            }
    return 0;
}

/* This process's CPU time, ms: on a loaded machine a long run is
 * descheduled more often than a short one, which wall time counts. */
static double cpu_ms(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec * 1e3 + (double)t.tv_nsec * 1e-6;
}

static double time_network(rs_ctx *ctx, const rs_roads *roads, double *cpu)
{
    rs_network *net = NULL;
    double t0 = tm_now_ms(), c0 = cpu_ms();
    if (rs_network_build(ctx, roads, NULL, &net)) return -1;
    double t = tm_now_ms() - t0;
    *cpu = cpu_ms() - c0;
    rs_network_free(ctx, net);
    return t;
}

static uint64_t fnv(uint64_t h, const void *p, size_t n)
{
    const unsigned char *c = p;
    for (size_t i = 0; i < n; i++) h = (h ^ c[i]) * 1099511628211ull;
    return h;
}

/* Everything the network says, hashed field by field. */
static uint64_t network_hash(const rs_network *N)
{
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < rs_network_node_count(N); i++) {
        rs_network_node d;
        rs_network_get_node(N, i, &d);
        int kind = (int)d.kind;
        h = fnv(fnv(fnv(fnv(fnv(h, &d.x, 8), &d.y, 8), &d.degree, 4), &kind, sizeof kind), &d.control, 4);
        for (size_t k = 0; k < d.degree; k++) {
            rs_network_leg L;
            rs_network_get_leg(N, i, k, &L);
            int lk = (int)L.kind;
            h = fnv(fnv(fnv(fnv(h, &L.road, 4), &lk, sizeof lk), &L.segment, 4), &L.s, 8);
            h = fnv(fnv(fnv(h, &L.angle, 8), &L.priority, sizeof L.priority), &L.major, sizeof L.major);
        }
    }
    for (size_t r = 0; r < rs_network_road_count(N); r++) {
        rs_road_stroke st;
        rs_network_road_stroke(N, r, &st);
        h = fnv(fnv(fnv(fnv(h, &st.stroke, 4), &st.s_offset, 8), &st.length, 8), &st.prev, 4);
        h = fnv(fnv(fnv(h, &st.next, 4), &st.closed, sizeof st.closed), &st.reversed, sizeof st.reversed);
    }
    for (size_t k = 0; k < rs_network_stroke_count(N); k++) {
        uint32_t buf[256];
        size_t c = rs_network_stroke_roads(N, k, buf, 256);
        h = fnv(fnv(h, &c, sizeof c), buf, (c < 256 ? c : 256) * sizeof *buf);
    }
    return h;
}

/* The road set of --one and --dump: a lattice of n records, or the city
 * generator's n roads on the index bench's 400 x 350 map of 5 m cells. */
static int scene_roads(rs_ctx *ctx, size_t n, int city, int split, rs_roads **out)
{
    if (!city) return lattice(ctx, n, out);
    sc_scene sc;
    if (sc_city(&sc, 400, 350, 5.0, n, 1)) return 1;
    int r = city_roads(ctx, &sc, split, out);
    sc_scene_free(&sc);
    return r;
}

static int one(rs_ctx *ctx, int argc, char **argv)
{
    size_t n = (size_t)atol(argv[2]);
    int reps = argc > 3 ? atoi(argv[3]) : 1, city = argc > 4 && strcmp(argv[4], "city") == 0;
    rs_roads *R = NULL;
    if (argc > 4 && strncmp(argv[4], "default", 7) == 0) { /* the bench's city, [split] */
        sc_scene sc;
        if (sc_city_default(&sc, 1) || city_roads(ctx, &sc, strcmp(argv[4], "default_split") == 0, &R)) return 1;
        sc_scene_free(&sc);
        city = 1;
    } else if (scene_roads(ctx, n, city, 0, &R)) return 1;
    if (argc > 4 && strcmp(argv[4], "warm") == 0) { /* (the heap grown as in the bench's runs) */
        rs_roads *W = NULL;
        double c;
        if (lattice(ctx, 100000, &W) || time_network(ctx, W, &c) < 0) return 1;
        rs_roads_free(ctx, W);
    }
    double best = -1;
    for (int i = 0; i < reps; i++) {
        rs_network *net = NULL;
        double t0 = tm_thread_cpu_ms();
        if (rs_network_build(ctx, R, NULL, &net)) return 1;
        double ms = tm_thread_cpu_ms() - t0;
        rs_network_free(ctx, net);
        best = best < 0 || ms < best ? ms : best;
    }
    printf("network: %s of %zu records: %.3f ms (thread CPU, fastest of %d)\n", city ? "city" : "lattice",
           rs_roads_count(R), best, reps);
    rs_roads_free(ctx, R);
    return 0;
}

static int pair(rs_ctx *ctx, int reps)
{
    rs_roads *lat[2];
    double best[2] = { 1e300, 1e300 };
    if (lattice(ctx, 10000, &lat[0]) || lattice(ctx, 100000, &lat[1])) return 1;
    for (int run = 0; run < reps; run++)
        for (int i = 0; i < 2; i++) {
            double c;
            if (time_network(ctx, lat[i], &c) < 0) return 1;
            best[i] = c < best[i] ? c : best[i];
        }
    printf("network: lattice %zu / %zu records: %.3f / %.3f ms (process CPU, fastest of %d): %.2fx, %.2fx per record\n",
           rs_roads_count(lat[0]), rs_roads_count(lat[1]), best[0], best[1], reps, best[1] / best[0],
           best[1] / best[0] * (double)rs_roads_count(lat[0]) / (double)rs_roads_count(lat[1]));
    for (int i = 0; i < 2; i++) rs_roads_free(ctx, lat[i]);
    return 0;
}

static int dump(rs_ctx *ctx)
{
    const double tols[3] = { 0, 0.5, 3 };
    for (int kind = 0; kind < 3; kind++)
        for (size_t n = 100; n <= 100000; n *= 10) {
            rs_roads *R = NULL;
            if (scene_roads(ctx, n, kind > 0, kind == 2, &R)) return 1;
            for (int t = 0; t < (kind && n >= 100000 ? 2 : 3); t++) { /* (3 m on the dense city: huge nodes) */
                rs_network_options o;
                memset(&o, 0, sizeof o);
                o.tolerance = tols[t];
                rs_network *net = NULL;
                if (rs_network_build(ctx, R, &o, &net)) return 1;
                printf("%s %zu records, tolerance %g: %zu nodes, %zu strokes, hash %016llx\n",
                       kind == 0 ? "lattice" : kind == 1 ? "city" : "split city", rs_roads_count(R), o.tolerance,
                       rs_network_node_count(net), rs_network_stroke_count(net),
                       (unsigned long long)network_hash(net));
                rs_network_free(ctx, net);
            }
            rs_roads_free(ctx, R);
        }
    return 0;
}

static double time_grid(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o, double *cpu)
{
    rs_road_grid *g = NULL;
    double t0 = tm_now_ms(), c0 = cpu_ms();
    if (rs_road_grid_build(ctx, dem, roads, o, &g)) return -1;
    double t = tm_now_ms() - t0;
    *cpu = cpu_ms() - c0;
    rs_road_grid_free(ctx, g);
    return t;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "build/bench";
    rs_ctx *ctx;
    if (rs_ctx_create(NULL, NULL, &ctx)) return 1;
    if (argc > 2 && strcmp(argv[1], "--one") == 0) {
        int r = one(ctx, argc, argv);
        rs_ctx_free(ctx);
        return r;
    }
    if (argc > 2 && strcmp(argv[1], "--pair") == 0) {
        int r = pair(ctx, atoi(argv[2]));
        rs_ctx_free(ctx);
        return r;
    }
    if (argc > 1 && strcmp(argv[1], "--dump") == 0) {
        int r = dump(ctx);
        rs_ctx_free(ctx);
        return r;
    }
    sc_scene sc;
    rs_dem *dem;
    rs_roads *city[2], *lat[2];
    if (sc_city_default(&sc, 1) || rs_dem_create(ctx, sc.w, sc.h, sc.z, &dem) || city_roads(ctx, &sc, 0, &city[0]) ||
        city_roads(ctx, &sc, 1, &city[1]) || lattice(ctx, 10000, &lat[0]) || lattice(ctx, 100000, &lat[1]))
        return 1;
    rs_dem_frame fc = { sc.cell_size, 0.01, 0, 0 };
    if (rs_dem_set_frame(ctx, dem, &fc)) return 1;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    double net_ms[2] = { 1e300, 1e300 }, grid_ms[2] = { 1e300, 1e300 }, lat_ms[2] = { 1e300, 1e300 };
    double lat_cpu[2] = { 1e300, 1e300 }, net_cpu[2] = { 1e300, 1e300 }, grid_cpu[2] = { 1e300, 1e300 };
    for (int run = 0; run < RUNS; run++)
        for (int i = 0; i < 2; i++) {
            double ca, cb, cc;
            double a = time_network(ctx, city[i], &ca), b = time_grid(ctx, dem, city[i], &o, &cb),
                   c = time_network(ctx, lat[i], &cc);
            if (a < 0 || b < 0 || c < 0) {
                fprintf(stderr, "network: %s\n", rs_ctx_message(ctx));
                return 1;
            }
            net_ms[i] = a < net_ms[i] ? a : net_ms[i];
            net_cpu[i] = ca < net_cpu[i] ? ca : net_cpu[i];
            grid_cpu[i] = cb < grid_cpu[i] ? cb : grid_cpu[i];
            grid_ms[i] = b < grid_ms[i] ? b : grid_ms[i];
            lat_ms[i] = c < lat_ms[i] ? c : lat_ms[i];
            lat_cpu[i] = cc < lat_cpu[i] ? cc : lat_cpu[i];
        }
    double add[2], add_wall[2], scale = lat_cpu[1] / lat_cpu[0], scale_wall = lat_ms[1] / lat_ms[0];
    for (int i = 0; i < 2; i++) {
        add[i] = net_cpu[i] / (grid_cpu[i] - net_cpu[i]);
        add_wall[i] = net_ms[i] / (grid_ms[i] - net_ms[i]);
    }
    size_t nodes[2];
    for (int i = 0; i < 2; i++) {
        rs_network *net = NULL;
        if (rs_network_build(ctx, lat[i], NULL, &net)) return 1;
        nodes[i] = rs_network_node_count(net);
        rs_network_free(ctx, net);
    }
    FILE *md, *csv;
    if (tm_open_section(dir, "network", &md, &csv)) return 1;
    fprintf(md,
            "## Road network (tests/bench/network.c)\n\n"
            "`rs_network_build` (topology and strokes, docs/network.md) against the road grid build that "
            "contains it: city scene `sc_city_default(1)` with the default class styles at 4 texels, as given "
            "and with every road split into records of two segments; one thread, fastest of %d in process CPU "
            "time, wall time beside it (until the network's dense cells: fastest of 7 in wall time).\n\n"
            "| scene | records | network ms (CPU) | grid build ms (CPU) | network / rest of the build (CPU) | "
            "network ms (wall) | grid build ms (wall) | (wall) |\n| --- | --- | --- | --- | --- | --- | --- | --- |\n",
            RUNS);
    for (int i = 0; i < 2; i++)
        fprintf(md, "| city%s | %zu | %.2f | %.1f | %.1f %% | %.2f | %.1f | %.1f %% |\n", i ? ", split" : "",
                rs_roads_count(city[i]), net_cpu[i], grid_cpu[i], 100 * add[i], net_ms[i], grid_ms[i],
                100 * add_wall[i]);
    fprintf(md,
            "\nStreet lattice (50 m blocks, records of two blocks, dead ends, T ends between points); "
            "process CPU time beside wall time (fastest of %d each), since on a loaded machine a long run is "
            "descheduled more often than a short one:\n\n"
            "| records | nodes | network ms (wall) | network ms (CPU) |\n| --- | --- | --- | --- |\n"
            "| %zu | %zu | %.2f | %.2f |\n| %zu | %zu | %.2f | %.2f |\n\n"
            "| target | measured | |\n| --- | --- | --- |\n"
            "| the network adds <= 10 %% to the styled city's grid build (CPU time) | %.1f %% (split: %.1f %%) | %s |\n"
            "| 10^5 records within 12x of 10^4 (CPU time) | %.2fx (wall: %.2fx) | %s |\n\n",
            RUNS, rs_roads_count(lat[0]), nodes[0], lat_ms[0], lat_cpu[0], rs_roads_count(lat[1]), nodes[1],
            lat_ms[1], lat_cpu[1], 100 * add[0], 100 * add[1], add[0] <= 0.10 && add[1] <= 0.10 ? "met" : "**missed**",
            scale, scale_wall, scale <= 12 ? "met" : "**missed**");
    fprintf(csv, "case,records,network_ms,grid_ms,network_cpu_ms,grid_cpu_ms\n");
    for (int i = 0; i < 2; i++)
        fprintf(csv, "city%s,%zu,%.3f,%.3f,%.3f,%.3f\n", i ? "_split" : "", rs_roads_count(city[i]), net_ms[i],
                grid_ms[i], net_cpu[i], grid_cpu[i]);
    for (int i = 0; i < 2; i++) fprintf(csv, "lattice,%zu,%.3f,,%.3f,\n", rs_roads_count(lat[i]), lat_ms[i], lat_cpu[i]);
    fclose(md);
    fclose(csv);
    printf("network: adds %.1f %% (split city %.1f %%) to the grid build in CPU time (wall: %.1f %%, %.1f %%); "
           "100k/10k records %.2fx CPU (%.2fx wall)\n",
           100 * add[0], 100 * add[1], 100 * add_wall[0], 100 * add_wall[1], scale, scale_wall);
    for (int i = 0; i < 2; i++) {
        rs_roads_free(ctx, city[i]);
        rs_roads_free(ctx, lat[i]);
    }
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    rs_ctx_free(ctx);
    return 0;
}
