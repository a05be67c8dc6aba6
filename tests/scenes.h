/* Synthetic scenes for tests and benchmarks: DEMs, roads, and writers for the
 * PGM and road-text formats. Independent of the library on purpose: the
 * ground truth (groundtruth.h) measures the library against these plain
 * descriptions, so they must not share code with what they measure.
 *
 * Frames follow SPEC.md: sample (row i, column j) at world (j*cs, i*cs),
 * x right, y down, metres. Every generator is deterministic (seeded
 * splitmix64, never rand()). Functions returning int give 0 on success and
 * -1 on allocation or I/O failure. */
#ifndef RS_TESTS_SCENES_H
#define RS_TESTS_SCENES_H
#include <stddef.h>
#include <stdint.h>

typedef struct sc_road {
    double width; /* metres */
    double *xy;   /* n points, x0 y0 x1 y1 ... (metres, SPEC frame); owned */
    size_t n;
} sc_road;

typedef struct sc_scene {
    uint32_t w, h;    /* DEM samples */
    float *z;         /* w*h heights, row-major; owned */
    double cell_size; /* metres between samples */
    sc_road *roads;   /* owned */
    size_t nroads;
    size_t cap;       /* capacity of roads */
} sc_scene;

/* --- deterministic PRNG (splitmix64) --- */
typedef struct sc_rng { uint64_t s; } sc_rng;
void sc_rng_seed(sc_rng *r, uint64_t seed);
uint64_t sc_rng_u64(sc_rng *r);
double sc_rng_unit(sc_rng *r);                       /* [0, 1), 53 bits */
double sc_rng_range(sc_rng *r, double lo, double hi); /* [lo, hi) */

/* --- scene --- */
/* Zero heights, no roads. */
int sc_scene_init(sc_scene *s, uint32_t w, uint32_t h, double cell_size);
void sc_scene_free(sc_scene *s);
/* Copies n points (2n doubles). */
int sc_add_road(sc_scene *s, double width, const double *xy, size_t n);
/* Map extent in metres: (w-1)*cs by (h-1)*cs. */
double sc_extent_x(const sc_scene *s);
double sc_extent_y(const sc_scene *s);

/* --- DEM generators: fill z[w*h], values within 0..65535 --- */
void sc_dem_constant(float *z, uint32_t w, uint32_t h, float value);
/* All `base`, sample (row, col) = peak. */
void sc_dem_spike(float *z, uint32_t w, uint32_t h, float base, float peak, uint32_t row, uint32_t col);
/* 0 / 65535 squares of `period` samples (1 = every sample alternates). */
void sc_dem_checker(float *z, uint32_t w, uint32_t h, uint32_t period);
/* Tent-shaped ridge through the grid centre along direction `angle` (radians,
 * from +x towards +y), `halfwidth` samples wide on each side, from 0 to peak. */
void sc_dem_ridge(float *z, uint32_t w, uint32_t h, double angle, double halfwidth, float peak);
/* Fractal noise (sum of value-noise octaves, gain `roughness`, e.g. 0.5),
 * any size, normalised to exactly 0..65535. */
void sc_dem_fractal(float *z, uint32_t w, uint32_t h, uint64_t seed, double roughness);
/* Real-looking terrain in centimetres (use z-scale 0.01): roughly 50..140 m,
 * fractal detail + smooth hills and valleys + a river valley running roughly
 * west to east. cs = cell size in metres (the features are sized in metres). */
void sc_dem_terrain(float *z, uint32_t w, uint32_t h, double cs, uint64_t seed);
/* The river's centreline y (metres) at x, for the same (w, h, cs, seed). */
double sc_river_y(uint32_t w, uint32_t h, double cs, uint64_t seed, double x);

/* --- road generators (append to s->roads; coordinates in metres) --- */
/* Straight road of `length` centred on the map centre at angle theta
 * (radians, from +x towards +y). A length longer than the map's diagonal
 * makes a road leaving the map at both ends. */
int sc_road_straight(sc_scene *s, double theta, double length, double width);
/* Circular arc centred (cx, cy), radius, from angle a0 to a1, npts >= 2 points. */
int sc_road_arc(sc_scene *s, double cx, double cy, double radius, double a0, double a1,
                double width, size_t npts);
/* nx streets along y (vertical) and ny along x (horizontal), evenly spaced
 * inside the map with `margin` metres kept free on every side; each street is
 * one road spanning between the margins, so they cross in X junctions. */
int sc_road_grid(sc_scene *s, unsigned nx, unsigned ny, double width, double margin);
/* A road from the map centre leaving through the map edge at angle theta,
 * continuing `beyond` metres along the road past the map edge; it bends
 * 20 degrees halfway. */
int sc_road_leaving(sc_scene *s, double theta, double width, double beyond);
/* A crowded road (issue 26): n >= 2 points evenly spread along the x axis
 * from (x0, y) over `length` metres, so thousands of tiny segments share
 * every index cell (10^6 points on 100 m: 0.1 mm segments). */
int sc_road_crowded(sc_scene *s, double x0, double y, double length, size_t n, double width);

/* Realistic city: sc_dem_terrain DEM plus an OSM-like network of about
 * target_roads roads 4-14 m wide: curvy arterials (12-14 m, leaving the
 * map), rotated and warped street grids per district (6-10 m, T and X
 * junctions), winding residential lanes ending in cul-de-sacs (4-6 m); no
 * streets in the river channel except arterial bridges. Widths are multiples
 * of 0.5 m and coordinates multiples of 1 mm. Deterministic in all arguments. */
int sc_city(sc_scene *s, uint32_t w, uint32_t h, double cs, size_t target_roads, uint64_t seed);
/* The benchmark scene: 400 x 350 samples, 5 m cells, ~1000 roads. */
int sc_city_default(sc_scene *s, uint64_t seed);
/* The OSM class the benchmarks give a city road of this width: arterials
 * (12 m and wider) primary, streets (6 m and wider) residential, lanes
 * service. */
const char *sc_city_class(double width);

/* --- writers --- */
/* P5, maxval 65535, big-endian; values rounded and clamped to 0..65535. */
int sc_write_pgm16(const char *path, uint32_t w, uint32_t h, const float *z);
/* Road text format: optional `# ...` header lines (header may be NULL or
 * contain newlines; each line is prefixed with "# "), then per road
 * `road NAME width W`, one `X Y` per line, `end`. Numbers in the shortest
 * form that reads back to the same double. Names: arterialN (>= 12 m),
 * streetN (>= 6 m) or laneN, N = road index. */
int sc_write_roads(const char *path, const sc_scene *s, const char *header);
/* The scene for the Cairo scripts (roadfield_cairo.py, styles_cairo.py): "W H cell",
 * then one road per line "width n x0 y0 x1 y1 ..." (%.17g). 0 or -1. */
int sc_write_plain(const char *path, const sc_scene *s);
#endif
