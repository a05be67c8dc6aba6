/* Synthetic scenes: see scenes.h. */
#include "scenes.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define SC_PI 3.14159265358979323846

/* --- PRNG -------------------------------------------------------------- */
static uint64_t sc_mix(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

void sc_rng_seed(sc_rng *r, uint64_t seed) { r->s = seed; }

uint64_t sc_rng_u64(sc_rng *r)
{
    r->s += 0x9e3779b97f4a7c15ULL;
    return sc_mix(r->s);
}

double sc_rng_unit(sc_rng *r) { return (double)(sc_rng_u64(r) >> 11) * (1.0 / 9007199254740992.0); }

double sc_rng_range(sc_rng *r, double lo, double hi) { return lo + (hi - lo) * sc_rng_unit(r); }

/* --- scene --------------------------------------------------------------- */
int sc_scene_init(sc_scene *s, uint32_t w, uint32_t h, double cell_size)
{
    memset(s, 0, sizeof *s);
    s->w = w;
    s->h = h;
    s->cell_size = cell_size;
    s->z = calloc((size_t)w * h > 0 ? (size_t)w * h : 1, sizeof *s->z);
    return s->z ? 0 : -1;
}

void sc_scene_free(sc_scene *s)
{
    size_t i;
    if (!s) return;
    for (i = 0; i < s->nroads; i++) free(s->roads[i].xy);
    free(s->roads);
    free(s->z);
    memset(s, 0, sizeof *s);
}

int sc_add_road(sc_scene *s, double width, const double *xy, size_t n)
{
    sc_road *r;
    if (n == 0) return -1;
    if (s->nroads == s->cap) {
        size_t nc = s->cap ? s->cap * 2 : 16;
        sc_road *nr = realloc(s->roads, nc * sizeof *nr);
        if (!nr) return -1;
        s->roads = nr;
        s->cap = nc;
    }
    r = &s->roads[s->nroads];
    r->xy = malloc(2 * n * sizeof *r->xy);
    if (!r->xy) return -1;
    memcpy(r->xy, xy, 2 * n * sizeof *r->xy);
    r->n = n;
    r->width = width;
    s->nroads++;
    return 0;
}

double sc_extent_x(const sc_scene *s) { return (s->w > 0 ? s->w - 1 : 0) * s->cell_size; }
double sc_extent_y(const sc_scene *s) { return (s->h > 0 ? s->h - 1 : 0) * s->cell_size; }

/* --- DEMs -------------------------------------------------------------------- */
void sc_dem_constant(float *z, uint32_t w, uint32_t h, float value)
{
    size_t i, n = (size_t)w * h;
    for (i = 0; i < n; i++) z[i] = value;
}

void sc_dem_spike(float *z, uint32_t w, uint32_t h, float base, float peak, uint32_t row, uint32_t col)
{
    sc_dem_constant(z, w, h, base);
    if (row < h && col < w) z[(size_t)row * w + col] = peak;
}

void sc_dem_checker(float *z, uint32_t w, uint32_t h, uint32_t period)
{
    uint32_t i, j;
    if (period == 0) period = 1;
    for (i = 0; i < h; i++)
        for (j = 0; j < w; j++) z[(size_t)i * w + j] = ((i / period + j / period) & 1) ? 65535.0f : 0.0f;
}

void sc_dem_ridge(float *z, uint32_t w, uint32_t h, double angle, double halfwidth, float peak)
{
    double cx = (w - 1) * 0.5, cy = (h - 1) * 0.5, nx = -sin(angle), ny = cos(angle);
    uint32_t i, j;
    for (i = 0; i < h; i++)
        for (j = 0; j < w; j++) {
            double d = fabs((j - cx) * nx + (i - cy) * ny);
            double t = halfwidth > 0 ? 1.0 - d / halfwidth : (d == 0 ? 1.0 : 0.0);
            z[(size_t)i * w + j] = (float)(peak * (t > 0 ? t : 0));
        }
}

/* Value noise: hashed lattice values in [-1, 1], quintic interpolation. */
static double sc_lattice(uint64_t seed, int64_t ix, int64_t iy, unsigned oct)
{
    uint64_t k = sc_mix(seed ^ ((uint64_t)ix * 0x9e3779b97f4a7c15ULL) ^ ((uint64_t)iy * 0xc2b2ae3d27d4eb4fULL) ^
                        ((uint64_t)oct * 0x165667b19e3779f9ULL));
    return (double)(k >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

static double sc_fade(double t) { return t * t * t * (t * (t * 6 - 15) + 10); }

static double sc_value_noise(uint64_t seed, double x, double y, unsigned oct)
{
    double fx = floor(x), fy = floor(y), tx = sc_fade(x - fx), ty = sc_fade(y - fy);
    int64_t ix = (int64_t)fx, iy = (int64_t)fy;
    double a = sc_lattice(seed, ix, iy, oct), b = sc_lattice(seed, ix + 1, iy, oct);
    double c = sc_lattice(seed, ix, iy + 1, oct), d = sc_lattice(seed, ix + 1, iy + 1, oct);
    double top = a + (b - a) * tx, bot = c + (d - c) * tx;
    return top + (bot - top) * ty;
}

/* fBm in roughly [-1, 1]; `period` = size of the largest feature in the
 * coordinate units, octaves down to `finest`. */
static double sc_fbm(uint64_t seed, double x, double y, double period, double finest, double gain)
{
    double sum = 0, amp = 1, norm = 0;
    unsigned oct = 0;
    while (period >= finest && oct < 24) {
        sum += amp * sc_value_noise(seed, x / period, y / period, oct);
        norm += amp;
        amp *= gain;
        period *= 0.5;
        oct++;
    }
    return norm > 0 ? sum / norm : 0;
}

void sc_dem_fractal(float *z, uint32_t w, uint32_t h, uint64_t seed, double roughness)
{
    size_t i, n = (size_t)w * h;
    uint32_t r, c;
    double period = (w > h ? w : h) * 0.5, lo = HUGE_VAL, hi = -HUGE_VAL;
    if (period < 2) period = 2;
    for (r = 0; r < h; r++)
        for (c = 0; c < w; c++) {
            double v = sc_fbm(seed, c, r, period, 1.0, roughness);
            z[(size_t)r * w + c] = (float)v;
            if (v < lo) lo = v;
            if (v > hi) hi = v;
        }
    for (i = 0; i < n; i++) z[i] = hi > lo ? (float)floor((z[i] - lo) / (hi - lo) * 65535.0 + 0.5) : 0.0f;
}

/* Parameters of the terrain's smooth features, all derived from the seed. */
typedef struct sc_terrain_params {
    double ext_x, ext_y;
    double river_y0, river_a1, river_l1, river_p1, river_a2, river_l2, river_p2;
    int nhills;
    double hx[6], hy[6], hr[6], hh[6];
} sc_terrain_params;

static void sc_terrain_setup(sc_terrain_params *p, uint32_t w, uint32_t h, double cs, uint64_t seed)
{
    sc_rng g;
    int k;
    sc_rng_seed(&g, seed ^ 0x7465727261696eULL);
    p->ext_x = (w > 1 ? w - 1 : 1) * cs;
    p->ext_y = (h > 1 ? h - 1 : 1) * cs;
    p->river_y0 = p->ext_y * sc_rng_range(&g, 0.35, 0.65);
    p->river_a1 = p->ext_y * sc_rng_range(&g, 0.06, 0.12);
    p->river_l1 = p->ext_x * sc_rng_range(&g, 0.7, 1.3);
    p->river_p1 = sc_rng_range(&g, 0, 2 * SC_PI);
    p->river_a2 = p->ext_y * sc_rng_range(&g, 0.015, 0.03);
    p->river_l2 = p->ext_x * sc_rng_range(&g, 0.2, 0.35);
    p->river_p2 = sc_rng_range(&g, 0, 2 * SC_PI);
    p->nhills = 4 + (int)(sc_rng_u64(&g) % 3);
    for (k = 0; k < p->nhills; k++) {
        p->hx[k] = sc_rng_range(&g, 0, p->ext_x);
        p->hy[k] = sc_rng_range(&g, 0, p->ext_y);
        p->hr[k] = sc_rng_range(&g, 0.12, 0.3) * (p->ext_x < p->ext_y ? p->ext_x : p->ext_y) + 50;
        p->hh[k] = sc_rng_range(&g, -15, 30);
    }
}

static double sc_river_at(const sc_terrain_params *p, double x)
{
    return p->river_y0 + p->river_a1 * sin(2 * SC_PI * x / p->river_l1 + p->river_p1) +
           p->river_a2 * sin(2 * SC_PI * x / p->river_l2 + p->river_p2);
}

/* Approximate distance from (x, y) to the river centreline. */
static double sc_river_dist(const sc_terrain_params *p, double x, double y)
{
    double e = 1.0, slope = (sc_river_at(p, x + e) - sc_river_at(p, x - e)) / (2 * e);
    return fabs(y - sc_river_at(p, x)) / sqrt(1 + slope * slope);
}

double sc_river_y(uint32_t w, uint32_t h, double cs, uint64_t seed, double x)
{
    sc_terrain_params p;
    sc_terrain_setup(&p, w, h, cs, seed);
    return sc_river_at(&p, x);
}

void sc_dem_terrain(float *z, uint32_t w, uint32_t h, double cs, uint64_t seed)
{
    sc_terrain_params p;
    uint32_t r, c;
    int k;
    sc_terrain_setup(&p, w, h, cs, seed);
    for (r = 0; r < h; r++)
        for (c = 0; c < w; c++) {
            double x = c * cs, y = r * cs, m, d, v;
            m = 90 + 22 * sc_fbm(seed, x, y, 700, 2 * cs, 0.5);      /* rolling base */
            m += 1.5 * sc_fbm(seed ^ 0x5a5a, x, y, 40, cs, 0.55);    /* fine roughness */
            for (k = 0; k < p.nhills; k++) {
                double dx = x - p.hx[k], dy = y - p.hy[k];
                m += p.hh[k] * exp(-(dx * dx + dy * dy) / (p.hr[k] * p.hr[k]));
            }
            d = sc_river_dist(&p, x, y);
            v = 1 - exp(-(d * d) / (160.0 * 160.0)); /* valley: 0 at the river, 1 far away */
            m = 45 + (m - 45) * (0.35 + 0.65 * v);
            if (d < 15) m -= 2.5 * (1 - d / 15); /* channel */
            if (m < 1) m = 1;
            if (m > 650) m = 650;
            z[(size_t)r * w + c] = (float)floor(m * 100 + 0.5);
        }
}

/* --- roads ---------------------------------------------------------------------- */
int sc_road_straight(sc_scene *s, double theta, double length, double width)
{
    double cx = sc_extent_x(s) * 0.5, cy = sc_extent_y(s) * 0.5, ux = cos(theta), uy = sin(theta);
    double xy[4];
    xy[0] = cx - ux * length * 0.5;
    xy[1] = cy - uy * length * 0.5;
    xy[2] = cx + ux * length * 0.5;
    xy[3] = cy + uy * length * 0.5;
    return sc_add_road(s, width, xy, 2);
}

int sc_road_arc(sc_scene *s, double cx, double cy, double radius, double a0, double a1, double width,
                size_t npts)
{
    double *xy;
    size_t i;
    int rc;
    if (npts < 2) npts = 2;
    xy = malloc(2 * npts * sizeof *xy);
    if (!xy) return -1;
    for (i = 0; i < npts; i++) {
        double a = a0 + (a1 - a0) * (double)i / (double)(npts - 1);
        xy[2 * i] = cx + radius * cos(a);
        xy[2 * i + 1] = cy + radius * sin(a);
    }
    rc = sc_add_road(s, width, xy, npts);
    free(xy);
    return rc;
}

int sc_road_grid(sc_scene *s, unsigned nx, unsigned ny, double width, double margin)
{
    double ex = sc_extent_x(s), ey = sc_extent_y(s), xy[4];
    unsigned k;
    for (k = 0; k < nx; k++) {
        double x = margin + (ex - 2 * margin) * (k + 0.5) / nx;
        xy[0] = x; xy[1] = margin; xy[2] = x; xy[3] = ey - margin;
        if (sc_add_road(s, width, xy, 2)) return -1;
    }
    for (k = 0; k < ny; k++) {
        double y = margin + (ey - 2 * margin) * (k + 0.5) / ny;
        xy[0] = margin; xy[1] = y; xy[2] = ex - margin; xy[3] = y;
        if (sc_add_road(s, width, xy, 2)) return -1;
    }
    return 0;
}

int sc_road_leaving(sc_scene *s, double theta, double width, double beyond)
{
    double ex = sc_extent_x(s), ey = sc_extent_y(s), cx = ex * 0.5, cy = ey * 0.5;
    double ux = cos(theta), uy = sin(theta), t = HUGE_VAL, xy[6];
    /* distance from the centre to the map edge along theta */
    if (ux > 1e-12) t = fmin(t, (ex - cx) / ux);
    if (ux < -1e-12) t = fmin(t, -cx / ux);
    if (uy > 1e-12) t = fmin(t, (ey - cy) / uy);
    if (uy < -1e-12) t = fmin(t, -cy / uy);
    xy[0] = cx;
    xy[1] = cy;
    /* bend 20 degrees halfway */
    xy[2] = cx + ux * t * 0.5;
    xy[3] = cy + uy * t * 0.5;
    {
        double b = theta + 20 * SC_PI / 180, vx = cos(b), vy = sin(b), t2 = HUGE_VAL;
        double px = xy[2], py = xy[3];
        if (vx > 1e-12) t2 = fmin(t2, (ex - px) / vx);
        if (vx < -1e-12) t2 = fmin(t2, -px / vx);
        if (vy > 1e-12) t2 = fmin(t2, (ey - py) / vy);
        if (vy < -1e-12) t2 = fmin(t2, -py / vy);
        xy[4] = px + vx * (t2 + beyond);
        xy[5] = py + vy * (t2 + beyond);
    }
    return sc_add_road(s, width, xy, 3);
}

int sc_road_crowded(sc_scene *s, double x0, double y, double length, size_t n, double width)
{
    if (n < 2) return -1;
    double *xy = malloc(2 * n * sizeof *xy);
    if (!xy) return -1;
    for (size_t k = 0; k < n; k++) {
        xy[2 * k] = x0 + length * (double)k / (double)(n - 1);
        xy[2 * k + 1] = y;
    }
    int r = sc_add_road(s, width, xy, n);
    free(xy);
    return r;
}

/* --- city ---------------------------------------------------------------------- */
typedef struct sc_pts { double *xy; size_t n, cap; } sc_pts;

static int sc_pts_push(sc_pts *p, double x, double y)
{
    if (p->n == p->cap) {
        size_t nc = p->cap ? p->cap * 2 : 32;
        double *nx = realloc(p->xy, 2 * nc * sizeof *nx);
        if (!nx) return -1;
        p->xy = nx;
        p->cap = nc;
    }
    /* millimetre grid: exact round trip through the text format */
    p->xy[2 * p->n] = floor(x * 1000 + 0.5) / 1000;
    p->xy[2 * p->n + 1] = floor(y * 1000 + 0.5) / 1000;
    p->n++;
    return 0;
}

static double sc_half_metres(double w) { return floor(w * 2 + 0.5) / 2; }

typedef struct sc_district {
    double sx, sy;         /* seed point */
    double ang, s1, s2;    /* grid rotation, spacings along u and v */
    double ox, oy;         /* grid origin */
    double w1, w2;         /* street widths of the two families */
    double wa, wl, wp;     /* warp amplitude, wavelength, phase */
} sc_district;

static void sc_district_warp(const sc_district *d, double *x, double *y)
{
    double px = *x, py = *y;
    *x = px + d->wa * sin(2 * SC_PI * py / d->wl + d->wp);
    *y = py + d->wa * sin(2 * SC_PI * px / d->wl + 1.7 * d->wp);
}

static void sc_district_point(const sc_district *d, double i, double j, double *x, double *y)
{
    double ux = cos(d->ang), uy = sin(d->ang);
    *x = d->ox + i * d->s1 * ux - j * d->s2 * uy;
    *y = d->oy + i * d->s1 * uy + j * d->s2 * ux;
    sc_district_warp(d, x, y);
}

static size_t sc_nearest_district(const sc_district *ds, size_t nd, double x, double y)
{
    size_t k, best = 0;
    double bd = HUGE_VAL;
    for (k = 0; k < nd; k++) {
        double dx = x - ds[k].sx, dy = y - ds[k].sy, d = dx * dx + dy * dy;
        if (d < bd) { bd = d; best = k; }
    }
    return best;
}

/* Emits a polyline from lattice (i0,j0) stepping `edges` lattice edges along
 * family `fam` (0: along i, 1: along j), densified 4 points per edge. */
static int sc_emit_street(sc_scene *s, const sc_district *d, int fam, long i0, long j0, long edges, double width)
{
    sc_pts p = {0, 0, 0};
    long e;
    int q, rc;
    for (e = 0; e < edges; e++)
        for (q = 0; q < 4; q++) {
            double i = (double)i0 + (fam == 0 ? e + q * 0.25 : 0), j = (double)j0 + (fam == 1 ? e + q * 0.25 : 0), x, y;
            sc_district_point(d, i, j, &x, &y);
            if (sc_pts_push(&p, x, y)) { free(p.xy); return -1; }
        }
    {
        double x, y;
        sc_district_point(d, (double)i0 + (fam == 0 ? edges : 0), (double)j0 + (fam == 1 ? edges : 0), &x, &y);
        if (sc_pts_push(&p, x, y)) { free(p.xy); return -1; }
    }
    rc = sc_add_road(s, width, p.xy, p.n);
    free(p.xy);
    return rc;
}

/* A winding polyline from (x, y) with heading `a`, a point every `step`
 * metres: used for arterials and lanes. Stops after `len` metres or, when
 * `leave` (arterials: steered back towards target_a), once it has been
 * inside the map and is 30 m outside again. */
static int sc_wander(sc_scene *s, sc_rng *g, double x, double y, double a, double step, double len,
                     double wander, double width, int leave, double target_a)
{
    sc_pts p = {0, 0, 0};
    double ex = sc_extent_x(s), ey = sc_extent_y(s), t = 0, ph1 = sc_rng_range(g, 0, 6.3),
           ph2 = sc_rng_range(g, 0, 6.3), l1 = sc_rng_range(g, 150, 400), l2 = sc_rng_range(g, 60, 140);
    int was_inside = 0, rc;
    if (sc_pts_push(&p, x, y)) return -1;
    while (t < len) {
        double turn = wander * (sin(2 * SC_PI * t / l1 + ph1) + 0.5 * sin(2 * SC_PI * t / l2 + ph2));
        double h = a + turn, inside;
        if (leave) { /* steer back towards the overall direction */
            double da = remainder(target_a - a, 2 * SC_PI);
            a += 0.05 * da;
        } else
            a += sc_rng_range(g, -0.12, 0.12);
        x += step * cos(h);
        y += step * sin(h);
        t += step;
        if (sc_pts_push(&p, x, y)) { free(p.xy); return -1; }
        inside = x >= 0 && x <= ex && y >= 0 && y <= ey;
        if (inside) was_inside = 1;
        if (leave && was_inside && (x < -30 || y < -30 || x > ex + 30 || y > ey + 30)) break;
    }
    rc = p.n >= 2 ? sc_add_road(s, width, p.xy, p.n) : 0;
    free(p.xy);
    return rc;
}

int sc_city(sc_scene *s, uint32_t w, uint32_t h, double cs, size_t target_roads, uint64_t seed)
{
    sc_rng g;
    sc_terrain_params tp;
    sc_district *ds = NULL;
    size_t nd, k, ndx, ndy, first_street, nstreet;
    double ex, ey, area, spacing, dsize;
    int nart, a;

    if (sc_scene_init(s, w, h, cs)) return -1;
    sc_dem_terrain(s->z, w, h, cs, seed);
    sc_terrain_setup(&tp, w, h, cs, seed);
    sc_rng_seed(&g, seed);
    ex = sc_extent_x(s);
    ey = sc_extent_y(s);
    area = ex * ey;

    /* 1. arterials: cross the map edge to edge, split into pieces like OSM ways */
    nart = (int)floor(area / 700000.0 + 0.5) + 2;
    for (a = 0; a < nart; a++) {
        double x, y, dir;
        size_t before = s->nroads;
        int side = (int)(sc_rng_u64(&g) % 4);
        if (side == 0) { x = -30; y = sc_rng_range(&g, 0.1, 0.9) * ey; dir = 0; }
        else if (side == 1) { x = ex + 30; y = sc_rng_range(&g, 0.1, 0.9) * ey; dir = SC_PI; }
        else if (side == 2) { x = sc_rng_range(&g, 0.1, 0.9) * ex; y = -30; dir = SC_PI / 2; }
        else { x = sc_rng_range(&g, 0.1, 0.9) * ex; y = ey + 30; dir = -SC_PI / 2; }
        dir += sc_rng_range(&g, -0.35, 0.35);
        if (sc_wander(s, &g, x, y, dir, 10, 4 * (ex + ey), 0.3, sc_half_metres(sc_rng_range(&g, 12, 14.49)), 1, dir))
            goto fail;
        /* split the new road into pieces of 20-40 points sharing endpoints */
        if (s->nroads > before) {
            sc_road r = s->roads[--s->nroads];
            size_t i0 = 0;
            while (i0 + 1 < r.n) {
                size_t cnt = 20 + (size_t)(sc_rng_u64(&g) % 21), i1 = i0 + cnt;
                if (i1 >= r.n || r.n - i1 < 5) i1 = r.n - 1;
                if (sc_add_road(s, r.width, r.xy + 2 * i0, i1 - i0 + 1)) { free(r.xy); goto fail; }
                i0 = i1;
            }
            free(r.xy);
        }
    }

    /* 2. districts: Voronoi cells around jittered seeds, each its own grid.
     * Spacing so that streets make about 3/4 of the target count. */
    dsize = 480;
    ndx = (size_t)ceil(ex / dsize);
    ndy = (size_t)ceil(ey / dsize);
    if (ndx < 1) ndx = 1;
    if (ndy < 1) ndy = 1;
    nd = ndx * ndy;
    ds = calloc(nd, sizeof *ds);
    if (!ds) goto fail;
    spacing = sqrt(area / (0.55 * (double)(target_roads ? target_roads : 1)));
    for (k = 0; k < nd; k++) {
        sc_district *d = &ds[k];
        d->sx = (k % ndx + sc_rng_range(&g, 0.2, 0.8)) * ex / ndx;
        d->sy = (k / ndx + sc_rng_range(&g, 0.2, 0.8)) * ey / ndy;
        d->ang = sc_rng_range(&g, -0.6, 0.6);
        d->s1 = spacing * sc_rng_range(&g, 0.8, 1.3);
        d->s2 = spacing * sc_rng_range(&g, 0.7, 1.1);
        d->ox = d->sx + sc_rng_range(&g, -0.5, 0.5) * d->s1;
        d->oy = d->sy + sc_rng_range(&g, -0.5, 0.5) * d->s2;
        d->w1 = sc_half_metres(sc_rng_range(&g, 7, 10.49));
        d->w2 = sc_half_metres(sc_rng_range(&g, 6, 8.49));
        d->wa = sc_rng_range(&g, 2, 9);
        d->wl = sc_rng_range(&g, 250, 600);
        d->wp = sc_rng_range(&g, 0, 2 * SC_PI);
    }
    first_street = s->nroads;
    for (k = 0; k < nd; k++) {
        const sc_district *d = &ds[k];
        long lim = (long)ceil(2.0 * (ex + ey) / (d->s1 < d->s2 ? d->s1 : d->s2)) + 2;
        int fam;
        for (fam = 0; fam < 2; fam++) {
            long line, pos;
            for (line = -lim; line <= lim; line++) {
                long run_start = 0, run_len = 0, want = 0;
                for (pos = -lim; pos <= lim + 1; pos++) {
                    int ok = pos <= lim;
                    if (ok) { /* is the lattice edge (pos -> pos+1) on this line ours? */
                        double x0, y0, x1, y1, mx, my;
                        long i0 = fam == 0 ? pos : line, j0 = fam == 0 ? line : pos;
                        sc_district_point(d, (double)i0, (double)j0, &x0, &y0);
                        sc_district_point(d, (double)(i0 + (fam == 0)), (double)(j0 + (fam == 1)), &x1, &y1);
                        mx = 0.5 * (x0 + x1);
                        my = 0.5 * (y0 + y1);
                        ok = mx > -20 && my > -20 && mx < ex + 20 && my < ey + 20 &&
                             sc_nearest_district(ds, nd, mx, my) == k && /* edges cross district borders a little */
                             sc_river_dist(&tp, x0, y0) > 35 && sc_river_dist(&tp, x1, y1) > 35 &&
                             sc_rng_unit(&g) > 0.08; /* dropped edges make T junctions */
                    }
                    if (ok) {
                        if (run_len == 0) { run_start = pos; want = 1 + (long)(sc_rng_u64(&g) % 3); }
                        run_len++;
                    }
                    if (run_len > 0 && (!ok || run_len == want)) {
                        long i0 = fam == 0 ? run_start : line, j0 = fam == 0 ? line : run_start;
                        if (sc_emit_street(s, d, fam, i0, j0, run_len, fam == 0 ? d->w1 : d->w2)) goto fail;
                        run_len = 0;
                    }
                }
            }
        }
    }
    nstreet = s->nroads - first_street;

    /* 3. residential lanes: leave a random street sideways, wind, dead-end */
    {
        size_t nlanes = target_roads > s->nroads ? target_roads - s->nroads : 0, made = 0, tries = 0;
        while (made < nlanes && nstreet > 0 && tries < 20 * nlanes) {
            const sc_road *r = &s->roads[first_street + (size_t)(sc_rng_u64(&g) % nstreet)];
            size_t i = (size_t)(sc_rng_u64(&g) % (r->n - 1));
            double x = 0.5 * (r->xy[2 * i] + r->xy[2 * i + 2]), y = 0.5 * (r->xy[2 * i + 1] + r->xy[2 * i + 3]);
            double dx = r->xy[2 * i + 2] - r->xy[2 * i], dy = r->xy[2 * i + 3] - r->xy[2 * i + 1];
            double side = (sc_rng_u64(&g) & 1) ? 1 : -1, a0 = atan2(dy, dx) + side * SC_PI / 2;
            double len = sc_rng_range(&g, 30, 110), ex2, ey2;
            tries++;
            /* the lane's far end must stay on land and inside the map */
            ex2 = x + len * 0.7 * cos(a0);
            ey2 = y + len * 0.7 * sin(a0);
            if (ex2 < 0 || ey2 < 0 || ex2 > ex || ey2 > ey || sc_river_dist(&tp, ex2, ey2) < 40) continue;
            if (sc_wander(s, &g, x, y, a0, 6, len, 0.25, sc_half_metres(sc_rng_range(&g, 4, 6.49)), 0, a0)) goto fail;
            made++;
        }
    }
    free(ds);
    return 0;
fail:
    free(ds);
    sc_scene_free(s);
    return -1;
}

int sc_city_default(sc_scene *s, uint64_t seed) { return sc_city(s, 400, 350, 5.0, 1000, seed); }

const char *sc_city_class(double width)
{
    return width >= 12 ? "primary" : (width >= 6 ? "residential" : "service");
}

/* --- writers ---------------------------------------------------------------------- */
int sc_write_pgm16(const char *path, uint32_t w, uint32_t h, const float *z)
{
    FILE *f = fopen(path, "wb");
    size_t i, n = (size_t)w * h;
    int ok;
    if (!f) return -1;
    ok = fprintf(f, "P5\n%lu %lu\n65535\n", (unsigned long)w, (unsigned long)h) > 0;
    for (i = 0; ok && i < n; i++) {
        double v = z[i] != z[i] ? 0 : floor((double)z[i] + 0.5);
        unsigned u = v < 0 ? 0u : v > 65535 ? 65535u : (unsigned)v;
        ok = putc((int)(u >> 8), f) != EOF && putc((int)(u & 255), f) != EOF;
    }
    if (fclose(f) != 0) ok = 0;
    return ok ? 0 : -1;
}

/* Shortest %.*g that reads back to the same double. */
static void sc_fmt(char *buf, size_t size, double v)
{
    int p;
    for (p = 1; p <= 17; p++) {
        snprintf(buf, size, "%.*g", p, v);
        if (strtod(buf, NULL) == v) return;
    }
}

int sc_write_roads(const char *path, const sc_scene *s, const char *header)
{
    FILE *f = fopen(path, "w");
    size_t i, k;
    int ok = 1;
    char a[40], b[40];
    if (!f) return -1;
    if (header) {
        const char *p = header;
        while (*p && ok) {
            const char *e = strchr(p, '\n');
            size_t len = e ? (size_t)(e - p) : strlen(p);
            ok = fprintf(f, "# %.*s\n", (int)len, p) > 0;
            p += len + (e ? 1 : 0);
        }
    }
    for (i = 0; ok && i < s->nroads; i++) {
        const sc_road *r = &s->roads[i];
        const char *kind = r->width >= 12 ? "arterial" : r->width >= 6 ? "street" : "lane";
        sc_fmt(a, sizeof a, r->width);
        ok = fprintf(f, "road %s%lu width %s\n", kind, (unsigned long)i, a) > 0;
        for (k = 0; ok && k < r->n; k++) {
            sc_fmt(a, sizeof a, r->xy[2 * k]);
            sc_fmt(b, sizeof b, r->xy[2 * k + 1]);
            ok = fprintf(f, "%s %s\n", a, b) > 0;
        }
        if (ok) ok = fprintf(f, "end\n") > 0;
    }
    if (fclose(f) != 0) ok = 0;
    return ok ? 0 : -1;
}

int sc_write_plain(const char *path, const sc_scene *s)
{
    FILE *f = fopen(path, "w");
    if (!f) return -1;
    fprintf(f, "%u %u %.17g\n", s->w, s->h, s->cell_size);
    for (size_t i = 0; i < s->nroads; i++) {
        fprintf(f, "%.17g %zu", s->roads[i].width, s->roads[i].n);
        for (size_t k = 0; k < 2 * s->roads[i].n; k++) fprintf(f, " %.17g", s->roads[i].xy[k]);
        fputc('\n', f);
    }
    return fclose(f) ? -1 : 0;
}
