/* Independent checker for terrain meshes over a W x H grid (used by
 * tests/test_roam.c, tests/bench/roam.c and fuzz/roam, for roadsplat's meshes and for
 * martini's alike). Vertices are given as grid coordinates plus a height;
 * everything is recomputed here in double, nothing is taken from the mesher. */
#ifndef RS_ROAM_CHECK_H
#define RS_ROAM_CHECK_H
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef struct rc_result {
    int ok_grid;        /* every vertex on a grid sample, height finite */
    int ok_heights;     /* vertex height == DEM height (valid samples) */
    int ok_winding;     /* every triangle non-degenerate and counter-clockwise seen from above */
    int ok_area;        /* triangle areas add up to the map area */
    int ok_edges;       /* each directed edge once; interior edges paired; others on the border */
    int ok_tjunction;   /* no vertex strictly inside any triangle edge */
    int ok_coverage;    /* every DEM sample lies in some triangle */
    double max_err, rms_err; /* over valid DEM samples, in height units of z * zs */
    size_t samples;
} rc_result;

static inline int rc_cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* n triangles (indices into vertices of 5 floats, x and y in metres, cells
 * of cs metres, a map W samples wide) as sorted keys of their corner
 * samples, each rotated to start at the smallest so the winding is kept
 * (21 bits per sample); NULL when out of memory. The caller frees it. */
static inline uint64_t *rc_tri_keys(const float *v, const uint32_t *idx, size_t n, uint32_t W, double cs)
{
    uint64_t *k = (uint64_t *)malloc((n + 1) * sizeof *k);
    for (size_t t = 0; k && t < n; t++) {
        uint64_t q[3];
        for (int c = 0; c < 3; c++) {
            const float *p = v + 5 * (size_t)idx[3 * t + (size_t)c];
            q[c] = (uint64_t)lround(p[1] / cs) * W + (uint64_t)lround(p[0] / cs);
        }
        int m = q[0] < q[1] ? (q[0] < q[2] ? 0 : 2) : (q[1] < q[2] ? 1 : 2);
        k[t] = q[m] << 42 | q[(m + 1) % 3] << 21 | q[(m + 2) % 3];
    }
    if (k) qsort(k, n, sizeof *k, rc_cmp_u64);
    return k;
}

/* Bounding box of a triangle's three lattice corners. */
static inline void rc_bbox(const int64_t x[3], const int64_t y[3], int64_t *x0, int64_t *x1, int64_t *y0, int64_t *y1)
{
    *x0 = *x1 = x[0];
    *y0 = *y1 = y[0];
    for (int c = 1; c < 3; c++) {
        if (x[c] < *x0) *x0 = x[c];
        if (x[c] > *x1) *x1 = x[c];
        if (y[c] < *y0) *y0 = y[c];
        if (y[c] > *y1) *y1 = y[c];
    }
}

/* Barycentric weights (times twice the area) of lattice point (px, py) in
 * the triangle of corners x, y with cross product cr; 0 when outside. */
static inline int rc_bary(const int64_t x[3], const int64_t y[3], int64_t cr, int64_t px, int64_t py, int64_t w[3])
{
    w[0] = (x[2] - x[1]) * (py - y[1]) - (y[2] - y[1]) * (px - x[1]);
    w[1] = (x[0] - x[2]) * (py - y[2]) - (y[0] - y[2]) * (px - x[2]);
    w[2] = (x[1] - x[0]) * (py - y[0]) - (y[1] - y[0]) * (px - x[0]);
    if (cr < 0) { w[0] = -w[0]; w[1] = -w[1]; w[2] = -w[2]; }
    return w[0] >= 0 && w[1] >= 0 && w[2] >= 0;
}

/* gx, gy: grid column and row per vertex; vz: height per vertex (metres);
 * z: DEM (DEM units, NaN = nodata), heights in metres = z * zs;
 * tri: 3 indices per triangle, `nt` triangles. Returns 0 if out of memory. */
static inline int rc_check(uint32_t W, uint32_t H, const float *z, double zs, const int32_t *gx,
                    const int32_t *gy, const double *vz, size_t nv, const uint32_t *tri, size_t nt,
                    rc_result *r)
{
    memset(r, 0, sizeof *r);
    r->ok_grid = r->ok_heights = r->ok_winding = r->ok_area = r->ok_edges = 1;
    r->ok_tjunction = r->ok_coverage = 1;
    size_t n = (size_t)W * H;
    unsigned char *isv = calloc(n, 1);
    double *err = malloc(n * sizeof *err);
    uint64_t *edges = malloc((nt * 3 + 1) * sizeof *edges);
    if (!isv || !err || !edges) { free(isv); free(err); free(edges); return 0; }
    for (size_t i = 0; i < n; i++) err[i] = -1.0;
    for (size_t v = 0; v < nv; v++) {
        if (gx[v] < 0 || gy[v] < 0 || gx[v] >= (int32_t)W || gy[v] >= (int32_t)H || !isfinite(vz[v])) {
            r->ok_grid = 0;
            continue;
        }
        size_t id = (size_t)gy[v] * W + (size_t)gx[v];
        isv[id] = 1;
        if (!isnan(z[id]) && vz[v] != (double)z[id] * zs) r->ok_heights = 0;
    }
    if (!r->ok_grid) { free(isv); free(err); free(edges); return 1; }
    double area2 = 0.0;
    for (size_t t = 0; t < nt; t++) {
        uint32_t k[3] = { tri[3 * t], tri[3 * t + 1], tri[3 * t + 2] };
        if (k[0] >= nv || k[1] >= nv || k[2] >= nv) { r->ok_grid = 0; continue; }
        int64_t x[3], y[3];
        for (int c = 0; c < 3; c++) { x[c] = gx[k[c]]; y[c] = gy[k[c]]; }
        int64_t cr = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
        /* x right, y down the map, z up: counter-clockwise from above is a
         * negative cross product in (column, row) coordinates */
        if (cr >= 0) r->ok_winding = 0;
        area2 += (double)(cr < 0 ? -cr : cr);
        for (int c = 0; c < 3; c++) {
            int d = (c + 1) % 3;
            uint64_t a = (uint64_t)((size_t)y[c] * W + (size_t)x[c]), b = (uint64_t)((size_t)y[d] * W + (size_t)x[d]);
            edges[3 * t + (size_t)c] = (a << 32) | b;
            /* T-junction: lattice points strictly inside the edge */
            int64_t ex = x[d] - x[c], ey = y[d] - y[c];
            int64_t g = ex < 0 ? -ex : ex, gg = ey < 0 ? -ey : ey;
            while (gg) { int64_t tmp = g % gg; g = gg; gg = tmp; }
            for (int64_t s = 1; s < g; s++) {
                int64_t px = x[c] + ex / g * s, py = y[c] + ey / g * s;
                if (isv[(size_t)py * W + (size_t)px]) r->ok_tjunction = 0;
            }
        }
        /* rasterize the samples of the triangle */
        int64_t x0, x1, y0, y1;
        rc_bbox(x, y, &x0, &x1, &y0, &y1);
        if (cr == 0) continue;
        for (int64_t py = y0; py <= y1; py++)
            for (int64_t px = x0; px <= x1; px++) {
                int64_t w[3];
                if (!rc_bary(x, y, cr, px, py, w)) continue;
                double den = (double)(w[0] + w[1] + w[2]);
                double zi = (w[0] * vz[k[0]] + w[1] * vz[k[1]] + w[2] * vz[k[2]]) / den;
                size_t id = (size_t)py * W + (size_t)px;
                double e = isnan(z[id]) ? 0.0 : fabs(zi - (double)z[id] * zs);
                if (e > err[id]) err[id] = e;
            }
    }
    if (fabs(area2 - 2.0 * (double)(W - 1) * (double)(H - 1)) > 0.5) r->ok_area = 0;
    qsort(edges, nt * 3, sizeof *edges, rc_cmp_u64);
    for (size_t i = 0; i < nt * 3; i++) {
        if (i + 1 < nt * 3 && edges[i] == edges[i + 1]) r->ok_edges = 0;
        uint64_t rev = (edges[i] << 32) | (edges[i] >> 32);
        if (!bsearch(&rev, edges, nt * 3, sizeof *edges, rc_cmp_u64)) {
            /* unpaired: must lie on the map border */
            size_t a = (size_t)(edges[i] >> 32), b = (size_t)(edges[i] & 0xFFFFFFFFu);
            size_t ax = a % W, ay = a / W, bx = b % W, by = b / W;
            int border = (ax == bx && (ax == 0 || ax == W - 1)) || (ay == by && (ay == 0 || ay == H - 1));
            if (!border) r->ok_edges = 0;
        }
    }
    double sum2 = 0.0;
    size_t cnt = 0;
    for (size_t i = 0; i < n; i++) {
        if (err[i] < 0) { r->ok_coverage = 0; continue; }
        if (isnan(z[i])) continue;
        if (err[i] > r->max_err) r->max_err = err[i];
        sum2 += err[i] * err[i];
        cnt++;
    }
    r->samples = cnt;
    r->rms_err = cnt ? sqrt(sum2 / (double)cnt) : 0.0;
    free(isv); free(err); free(edges);
    return 1;
}

static inline int rc_all_ok(const rc_result *r)
{
    return r->ok_grid && r->ok_heights && r->ok_winding && r->ok_area && r->ok_edges && r->ok_tjunction
           && r->ok_coverage;
}

/* A view-dependent mesh against its tolerance, independently of the
 * mesher: for every triangle whose DEM samples (with their heights) all
 * lie inside the cone of half-angle `half` (radians) about `dir` from
 * `eye` (take it inside the view frustum), its true max vertical error
 * times k (pixels per metre at distance 1) over the distance from the eye
 * to its nearest sample (at least `floor_d`) must be <= tol: the mesher's
 * bounding-sphere distance is never larger, and its error bound never
 * smaller. Grid coordinates gx, gy per vertex, heights z * zs, cell size cs.
 * Returns the largest ratio (projected error / tol) over the checked
 * triangles (*nchecked of them). */
static inline double rc_view_worst(uint32_t W, uint32_t H, const float *z, double zs, double cs,
                                   const int32_t *gx, const int32_t *gy, const uint32_t *tri, size_t nt,
                                   const double eye[3], const double dir[3], double half, double k,
                                   double tol, double floor_d, size_t *nchecked)
{
    double dl = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]), ch = cos(half);
    double worst = 0.0;
    size_t checked = 0;
    (void)H;
    for (size_t t = 0; t < nt; t++) {
        int64_t x[3], y[3];
        double vz[3];
        for (int c = 0; c < 3; c++) {
            uint32_t v = tri[3 * t + (size_t)c];
            x[c] = gx[v]; y[c] = gy[v];
            vz[c] = (double)z[(size_t)y[c] * W + (size_t)x[c]] * zs;
        }
        int64_t cr = (x[1] - x[0]) * (y[2] - y[0]) - (x[2] - x[0]) * (y[1] - y[0]);
        if (cr == 0) continue;
        int64_t x0, x1, y0, y1;
        rc_bbox(x, y, &x0, &x1, &y0, &y1);
        double emax = 0.0, dmin = INFINITY;
        int inside = 1;
        for (int64_t py = y0; py <= y1 && inside; py++)
            for (int64_t px = x0; px <= x1; px++) {
                int64_t w[3];
                if (!rc_bary(x, y, cr, px, py, w)) continue;
                double zi = (w[0] * vz[0] + w[1] * vz[1] + w[2] * vz[2]) / (double)(w[0] + w[1] + w[2]);
                double zs_ = (double)z[(size_t)py * W + (size_t)px] * zs;
                double e = fabs(zi - zs_);
                if (e > emax) emax = e;
                double d[3] = { px * cs - eye[0], py * cs - eye[1], zs_ - eye[2] };
                double dd = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                if (dd < dmin) dmin = dd;
                if (d[0] * dir[0] + d[1] * dir[1] + d[2] * dir[2] < ch * dd * dl) { inside = 0; break; }
            }
        if (!inside) continue;
        checked++;
        double r = emax * k / (dmin > floor_d ? dmin : floor_d) / tol;
        if (r > worst) worst = r;
    }
    if (nchecked) *nchecked = checked;
    return worst;
}

/* ---- deterministic synthetic DEMs (any size) ---- */
static inline uint64_t rc_hash(uint64_t x)
{
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

/* lattice value in [-1, 1) */
static inline double rc_lattice(uint64_t seed, int64_t i, int64_t j)
{
    uint64_t h = rc_hash(seed ^ rc_hash((uint64_t)i * 0x1000193ull ^ rc_hash((uint64_t)j)));
    return (double)(h >> 11) / 4503599627370496.0 - 1.0;
}

static inline double rc_value_noise(uint64_t seed, double x, double y)
{
    double fx = floor(x), fy = floor(y);
    int64_t i = (int64_t)fx, j = (int64_t)fy;
    double u = x - fx, v = y - fy;
    u = u * u * (3 - 2 * u);
    v = v * v * (3 - 2 * v);
    double a = rc_lattice(seed, i, j), b = rc_lattice(seed, i + 1, j);
    double c = rc_lattice(seed, i, j + 1), d = rc_lattice(seed, i + 1, j + 1);
    return (a * (1 - u) + b * u) * (1 - v) + (c * (1 - u) + d * u) * v;
}

/* fBm: octaves from `period` samples down to 2, amplitude * gain^k. */
static inline void rc_dem_fractal(float *z, uint32_t W, uint32_t H, uint64_t seed, double period,
                                  double amplitude, double gain)
{
    for (size_t i = 0; i < (size_t)W * H; i++) z[i] = 0.0f;
    double amp = amplitude;
    int oct = 0;
    for (double p = period; p >= 2.0; p *= 0.5, amp *= gain, oct++)
        for (uint32_t y = 0; y < H; y++)
            for (uint32_t x = 0; x < W; x++)
                z[(size_t)y * W + x] += (float)(amp * rc_value_noise(seed + (uint64_t)oct, x / p, y / p));
}

/* Real-looking: ridged mountains, a valley floor, a flat lake, quantised to
 * 0.1 units like an integer DEM. */
static inline void rc_dem_realistic(float *z, uint32_t W, uint32_t H, uint64_t seed)
{
    for (uint32_t y = 0; y < H; y++)
        for (uint32_t x = 0; x < W; x++) {
            double h = 0.0, amp = 1.0, wgt = 1.0;
            int oct = 0;
            for (double p = 256.0; p >= 2.0; p *= 0.5, amp *= 0.5, oct++) {
                double n = 1.0 - fabs(rc_value_noise(seed + (uint64_t)oct, x / p, y / p));
                n = n * n * wgt;
                wgt = n * 2 > 1 ? 1 : n * 2;
                h += n * amp;
            }
            double valley = fabs(rc_value_noise(seed + 99, x / 400.0, y / 400.0));
            h = 900.0 * h * (0.25 + valley) + 300.0;
            if (h < 420.0) h = 420.0 - (420.0 - h) * 0.05; /* broad valley floor */
            if (h < 415.0) h = 415.0;                       /* the lake */
            z[(size_t)y * W + x] = (float)(floor(h * 10.0 + 0.5) / 10.0);
        }
}
#endif
