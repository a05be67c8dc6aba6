/* Surface stage: the terrain colour T (hypsometric tint times Horn's
 * hillshade, or a tiled texture) where a pixel has terrain, and the road
 * colour S (procedural asphalt or a tiled texture) where it has road. */
#include "splatter.h"
#include "dem.h"
#include "styling.h"

#include <math.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

static uint32_t hash2(uint32_t x, uint32_t y)
{
    uint32_t h = x * 0x8da6b343u ^ y * 0xd8163841u;
    h ^= h >> 15; h *= 0x2c1b3c6dU;
    h ^= h >> 12; h *= 0x297a2d39U;
    h ^= h >> 15;
    return h;
}

/* The palette: lowland green, olive, brown, grey rock, snow. Relative
 * tints place its stops at these fractions of the height range; the
 * absolute default ramp at fixed heights (docs/surface.md "Terrain
 * colour"), so a hill of 88 m is green wherever it stands. */
static const double palette[6][4] = {
    { 0.00, 74, 112, 62 }, { 0.25, 104, 138, 72 }, { 0.50, 158, 156, 96 },
    { 0.70, 160, 132, 96 }, { 0.88, 150, 140, 132 }, { 1.00, 236, 236, 236 },
};
static const double default_heights[6] = { 0, 300, 800, 1500, 2400, 3500 }; /* metres */

static void hypsometric(double t, float rgb[3])
{
    const double (*stops)[4] = palette;
    if (!(t > 0)) t = 0;
    if (t > 1) t = 1;
    int i = 0;
    while (i < 4 && t > stops[i + 1][0]) i++;
    double f = (t - stops[i][0]) / (stops[i + 1][0] - stops[i][0]);
    for (int c = 0; c < 3; c++) rgb[c] = (float)(stops[i][c + 1] + f * (stops[i + 1][c + 1] - stops[i][c + 1]));
}

/* The absolute tint of height zm (metres): the ramp's colour, linear
 * between stops, the end colours beyond them. */
static void absolute_tint(const rs_surface_options *f, double zm, float rgb[3])
{
    if (!f->ramp) {
        int i = 0;
        if (!(zm > default_heights[0])) zm = default_heights[0];
        if (zm > default_heights[5]) zm = default_heights[5];
        while (i < 4 && zm > default_heights[i + 1]) i++;
        double u = (zm - default_heights[i]) / (default_heights[i + 1] - default_heights[i]);
        for (int c = 0; c < 3; c++)
            rgb[c] = (float)(palette[i][c + 1] + u * (palette[i + 1][c + 1] - palette[i][c + 1]));
        return;
    }
    const rs_colour_stop *r = f->ramp;
    size_t n = f->ramp_count, i = 0;
    if (!(zm > r[0].height)) zm = r[0].height;
    if (zm > r[n - 1].height) zm = r[n - 1].height;
    while (i + 2 < n && zm > r[i + 1].height) i++;
    double u = (zm - r[i].height) / (r[i + 1].height - r[i].height);
    const rs_colour a = r[i].colour, b = r[i + 1].colour;
    rgb[0] = (float)(a.r + u * (b.r - a.r));
    rgb[1] = (float)(a.g + u * (b.g - a.g));
    rgb[2] = (float)(a.b + u * (b.b - a.b));
}

/* Hillshade factor by the trigonometric formula (gdaldem's): slope and
 * aspect angles, then the cosine of the angle to the light. */
static double shade_trig(const rs_splatter *s, double dzdx, double dzdy)
{
    double slope = atan(sqrt(dzdx * dzdx + dzdy * dzdy));
    double aspect = 0;
    if (dzdx != 0) {
        aspect = atan2(dzdy, -dzdx);
        if (aspect < 0) aspect += 2 * RS__PI;
    } else if (dzdy > 0) aspect = RS__PI / 2;
    else if (dzdy < 0) aspect = 1.5 * RS__PI;
    double hs = s->cos_zen * cos(slope) + s->sin_zen * sin(slope) * cos(s->sun_az - aspect);
    if (!(hs > 0)) hs = 0;
    return 0.3 + 0.7 * hs / s->cos_zen;
}

/* Terrain colour of one sample from its gradient: tint times the shade,
 * clamped to 255, as float. */
static void terrain_rgb(const float tint[3], double shade, float *out, size_t plane)
{
    for (int ch = 0; ch < 3; ch++) {
        double v = tint[ch] * shade;
        out[(size_t)ch * plane] = (float)(v > 255 ? 255 : v);
    }
}

/* The shade of one sample from its gradient, onto its tint in out (the
 * scalar path; terrain_row). The three channels lie `plane` floats apart. */
static void shade_one(const rs_splatter *s, const double light[2], double dzdx, double dzdy, float *out, size_t plane)
{
    const double lx = light[0], ly = light[1], cz = s->cos_zen;
    float tint[3] = { out[0], out[plane], out[2 * plane] };
    double g2 = dzdx * dzdx + dzdy * dzdy;
    double hs = (cz + lx * dzdx + ly * dzdy) / sqrt(1 + g2);
    if (!(hs > 0)) hs = 0;
    double shade = 0.3 + 0.7 * hs / cz;
    int tie = !(g2 < 1e200);
    for (int ch = 0; ch < 3; ch++) {
        double v = tint[ch] * shade;
        v = v > 255 ? 255 : v;
        tie |= (float)(v * (1 - 1e-12)) != (float)(v * (1 + 1e-12));
    }
    terrain_rgb(tint, tie ? shade_trig(s, dzdx, dzdy) : shade, out, plane);
}

#if defined(__SSE2__)
/* The lanes of a vector shade (shade_pair, shade_quad) into out: the
 * vector's colours r, or shade_one where bit l of tiebits says the
 * trigonometric formula must decide (dx, dy: the lane's gradient). */
static void shade_lanes(const rs_splatter *s, const double light[2], float (*r)[4], const double *dx,
                        const double *dy, int tiebits, int lanes, float *out, size_t plane)
{
    for (int l = 0; l < lanes; l++) {
        float *o = out + l;
        if (tiebits >> l & 1) shade_one(s, light, dx[l], dy[l], o, plane);
        else
            for (int ch = 0; ch < 3; ch++) o[(size_t)ch * plane] = r[ch][l];
    }
}

/* Two floats at p as doubles. */
static __m128d load2f(const float *p)
{
    return _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(const void *)p)));
}

/* shade_one for the two interior samples (i, j) and (i, j + 1), the same
 * operations in the same order in each lane of a register (so the same
 * doubles); a lane where the trigonometric formula must decide takes the
 * scalar path. */
static void shade_pair(const rs_splatter *s, const double light[2], const float *zrow, size_t W, double eight_cs,
                       float *out, size_t plane)
{
    const double zs = s->dem->frame.z_scale;
    const double lx = light[0], ly = light[1], cz = s->cos_zen;
    const float *up = zrow - W, *mid = zrow, *dn = zrow + W;
    const __m128d vzs = _mm_set1_pd(zs), two = _mm_set1_pd(2), v8 = _mm_set1_pd(eight_cs);
    __m128d a = _mm_mul_pd(load2f(up - 1), vzs), b = _mm_mul_pd(load2f(up), vzs), c = _mm_mul_pd(load2f(up + 1), vzs);
    __m128d d = _mm_mul_pd(load2f(mid - 1), vzs), f = _mm_mul_pd(load2f(mid + 1), vzs);
    __m128d g = _mm_mul_pd(load2f(dn - 1), vzs), h = _mm_mul_pd(load2f(dn), vzs), k = _mm_mul_pd(load2f(dn + 1), vzs);
    __m128d dzdx = _mm_div_pd(_mm_sub_pd(_mm_add_pd(_mm_add_pd(c, _mm_mul_pd(two, f)), k),
                                         _mm_add_pd(_mm_add_pd(a, _mm_mul_pd(two, d)), g)), v8);
    __m128d dzdy = _mm_div_pd(_mm_sub_pd(_mm_add_pd(_mm_add_pd(g, _mm_mul_pd(two, h)), k),
                                         _mm_add_pd(_mm_add_pd(a, _mm_mul_pd(two, b)), c)), v8);
    __m128d g2 = _mm_add_pd(_mm_mul_pd(dzdx, dzdx), _mm_mul_pd(dzdy, dzdy));
    __m128d hs = _mm_div_pd(_mm_add_pd(_mm_add_pd(_mm_set1_pd(cz), _mm_mul_pd(_mm_set1_pd(lx), dzdx)),
                                       _mm_mul_pd(_mm_set1_pd(ly), dzdy)),
                            _mm_sqrt_pd(_mm_add_pd(_mm_set1_pd(1), g2)));
    hs = _mm_and_pd(_mm_cmpgt_pd(hs, _mm_setzero_pd()), hs);
    __m128d shade = _mm_add_pd(_mm_set1_pd(0.3), _mm_div_pd(_mm_mul_pd(_mm_set1_pd(0.7), hs), _mm_set1_pd(cz)));
    __m128 tie = _mm_castpd_ps(_mm_cmpnlt_pd(g2, _mm_set1_pd(1e200)));
    int tiebits = _mm_movemask_pd(_mm_castps_pd(tie));
    const __m128d lo = _mm_set1_pd(1 - 1e-12), hi = _mm_set1_pd(1 + 1e-12), cap = _mm_set1_pd(255);
    __m128 res[3];
    for (int ch = 0; ch < 3; ch++) {
        __m128d v = _mm_mul_pd(load2f(out + (size_t)ch * plane), shade);
        __m128d over = _mm_cmpgt_pd(v, cap);
        v = _mm_or_pd(_mm_and_pd(over, cap), _mm_andnot_pd(over, v));
        res[ch] = _mm_cvtpd_ps(v);
        tiebits |= _mm_movemask_ps(_mm_cmpneq_ps(_mm_cvtpd_ps(_mm_mul_pd(v, lo)), _mm_cvtpd_ps(_mm_mul_pd(v, hi)))) & 3;
    }
    float r[3][4];
    for (int ch = 0; ch < 3; ch++) _mm_storeu_ps(r[ch], res[ch]);
    double dx[2], dy[2];
    _mm_storeu_pd(dx, dzdx);
    _mm_storeu_pd(dy, dzdy);
    shade_lanes(s, light, r, dx, dy, tiebits, 2, out, plane);
}
#endif

#ifdef RS_AVX2_DISPATCH
/* shade_pair for four interior samples (i, j .. j + 3) where the CPU has
 * AVX2 but not AVX-512: the same operations in the same order in each
 * lane (the divided gradient and the square root, so the same doubles);
 * a lane where the trigonometric formula must decide takes the scalar
 * path, as there. */
RS_AVX2 static void shade_quad(const rs_splatter *s, const double light[2], const float *zrow, size_t W,
                               double eight_cs, float *out, size_t plane)
{
    const double zs = s->dem->frame.z_scale;
    const double lx = light[0], ly = light[1], cz = s->cos_zen;
    const float *up = zrow - W, *mid = zrow, *dn = zrow + W;
    const __m256d vzs = _mm256_set1_pd(zs), two = _mm256_set1_pd(2), v8 = _mm256_set1_pd(eight_cs);
#define LOAD4F(p) _mm256_cvtps_pd(_mm_loadu_ps(p))
    __m256d a = _mm256_mul_pd(LOAD4F(up - 1), vzs), b = _mm256_mul_pd(LOAD4F(up), vzs),
            c = _mm256_mul_pd(LOAD4F(up + 1), vzs);
    __m256d d = _mm256_mul_pd(LOAD4F(mid - 1), vzs), f = _mm256_mul_pd(LOAD4F(mid + 1), vzs);
    __m256d g = _mm256_mul_pd(LOAD4F(dn - 1), vzs), h = _mm256_mul_pd(LOAD4F(dn), vzs),
            k = _mm256_mul_pd(LOAD4F(dn + 1), vzs);
    __m256d dzdx = _mm256_div_pd(_mm256_sub_pd(_mm256_add_pd(_mm256_add_pd(c, _mm256_mul_pd(two, f)), k),
                                               _mm256_add_pd(_mm256_add_pd(a, _mm256_mul_pd(two, d)), g)), v8);
    __m256d dzdy = _mm256_div_pd(_mm256_sub_pd(_mm256_add_pd(_mm256_add_pd(g, _mm256_mul_pd(two, h)), k),
                                               _mm256_add_pd(_mm256_add_pd(a, _mm256_mul_pd(two, b)), c)), v8);
    __m256d g2 = _mm256_add_pd(_mm256_mul_pd(dzdx, dzdx), _mm256_mul_pd(dzdy, dzdy));
    __m256d hs = _mm256_div_pd(_mm256_add_pd(_mm256_add_pd(_mm256_set1_pd(cz), _mm256_mul_pd(_mm256_set1_pd(lx), dzdx)),
                                             _mm256_mul_pd(_mm256_set1_pd(ly), dzdy)),
                               _mm256_sqrt_pd(_mm256_add_pd(_mm256_set1_pd(1), g2)));
    hs = _mm256_and_pd(_mm256_cmp_pd(hs, _mm256_setzero_pd(), _CMP_GT_OS), hs);
    __m256d shade =
        _mm256_add_pd(_mm256_set1_pd(0.3), _mm256_div_pd(_mm256_mul_pd(_mm256_set1_pd(0.7), hs), _mm256_set1_pd(cz)));
    int tiebits = _mm256_movemask_pd(_mm256_cmp_pd(g2, _mm256_set1_pd(1e200), _CMP_NLT_US));
    const __m256d lo = _mm256_set1_pd(1 - 1e-12), hi = _mm256_set1_pd(1 + 1e-12), cap = _mm256_set1_pd(255);
    __m128 res[3];
    for (int ch = 0; ch < 3; ch++) {
        __m256d v = _mm256_mul_pd(LOAD4F(out + (size_t)ch * plane), shade);
        v = _mm256_blendv_pd(v, cap, _mm256_cmp_pd(v, cap, _CMP_GT_OS));
        res[ch] = _mm256_cvtpd_ps(v);
        tiebits |= _mm_movemask_ps(
            _mm_cmpneq_ps(_mm256_cvtpd_ps(_mm256_mul_pd(v, lo)), _mm256_cvtpd_ps(_mm256_mul_pd(v, hi))));
    }
#undef LOAD4F
    if (!tiebits) {
        for (int ch = 0; ch < 3; ch++) _mm_storeu_ps(out + (size_t)ch * plane, res[ch]);
        return;
    }
    float r[3][4];
    for (int ch = 0; ch < 3; ch++) _mm_storeu_ps(r[ch], res[ch]);
    double dx[4], dy[4];
    _mm256_storeu_pd(dx, dzdx);
    _mm256_storeu_pd(dy, dzdy);
    shade_lanes(s, light, r, dx, dy, tiebits, 4, out, plane);
}
#endif

#ifdef RS_AVX512_DISPATCH
/* The tint of a sample as a piecewise linear ramp of x (the height, or
 * its fraction of the range): x clamped to [H[0], H[n-1]] (NaN to H[0]),
 * stop i = the number of H[1..n-2] below x, u = (x - H[i]) / (H[i+1] -
 * H[i]), colour C[i] + u (C[i+1] - C[i]): the operations of
 * hypsometric() and absolute_tint(), as tables, for the vector paths. */
typedef struct tint_ramp {
    int n;                       /* stops, 2..8 (0: no table; the scalar path) */
    int mode;                    /* x: 0 zc, 1 (zc - hmin) / (hmax - hmin), 2 (zc / zs - zmin) / zrange, 3 0.5 */
    double H[8], HD[8], C[3][8], CD[3][8];
} tint_ramp;

/* Samples j .. j + lanes - 1 of a row of n for the vector tints: the row
 * itself, or past its end a copy with the last sample repeated (in buf);
 * *m = the real ones. */
static const float *lane_samples(const float *zrow, uint32_t j, uint32_t n, uint32_t lanes, float *buf, uint32_t *m)
{
    *m = n - j < lanes ? n - j : lanes;
    if (*m == lanes) return zrow + j;
    for (uint32_t l = 0; l < lanes; l++) buf[l] = zrow[j + (l < *m ? l : *m - 1)];
    return buf;
}

static void tint_ramp_init(const rs_splatter *s, tint_ramp *t)
{
    const rs_surface_options *sf = &s->o.surface;
    memset(t, 0, sizeof *t);
    if (s->o.lighting.enable) return; /* the tint alone: the scalar path */
    if (sf->tint == RS_TINT_ABSOLUTE) {
        if (sf->ramp && sf->ramp_count > 8) return;
        t->mode = 0;
        if (!sf->ramp) {
            t->n = 6;
            for (int k = 0; k < 6; k++) {
                t->H[k] = default_heights[k];
                for (int c = 0; c < 3; c++) t->C[c][k] = palette[k][c + 1];
            }
        } else {
            t->n = (int)sf->ramp_count;
            for (int k = 0; k < t->n; k++) {
                const rs_colour col = sf->ramp[k].colour;
                t->H[k] = sf->ramp[k].height;
                t->C[0][k] = col.r, t->C[1][k] = col.g, t->C[2][k] = col.b;
            }
        }
    } else {
        t->mode = sf->height_min != 0 || sf->height_max != 0 ? 1 : s->zrange > 0 ? 2 : 3;
        t->n = 6;
        for (int k = 0; k < 6; k++) {
            t->H[k] = palette[k][0];
            for (int c = 0; c < 3; c++) t->C[c][k] = palette[k][c + 1];
        }
    }
    /* the differences as the scalar code forms them (for integer colours
     * the int difference converted: the same double) */
    for (int k = 0; k + 1 < t->n; k++) {
        t->HD[k] = t->H[k + 1] - t->H[k];
        for (int c = 0; c < 3; c++) t->CD[c][k] = t->C[c][k + 1] - t->C[c][k];
    }
}
#endif

#ifdef RS_AVX512_DISPATCH

/* Eight floats at p as doubles. */
RS_AVX512 static inline __m512d load8f(const float *p)
{
    return _mm512_cvtps_pd(_mm256_loadu_ps(p));
}

/* The tints of n samples of row zrow into the planes of out (8 a step,
 * the rest by the same lanes on a padded copy): tint_ramp's operations in
 * every lane, the same doubles as the scalar path. */
RS_AVX512 static void tint_row8(const rs_splatter *s, const tint_ramp *t, const float *zrow, uint32_t n, float *out,
                                size_t plane)
{
    const rs_surface_options *sf = &s->o.surface;
    const double zs = s->dem->frame.z_scale;
    const __m512d vzs = _mm512_set1_pd(zs), lo = _mm512_set1_pd(t->H[0]), hi = _mm512_set1_pd(t->H[t->n - 1]);
    const __m512d Hv = _mm512_loadu_pd(t->H), HDv = _mm512_loadu_pd(t->HD);
    const __m512i one = _mm512_set1_epi64(1);
    __m512d Cv[3], CDv[3];
    for (int c = 0; c < 3; c++) Cv[c] = _mm512_loadu_pd(t->C[c]), CDv[c] = _mm512_loadu_pd(t->CD[c]);
    const __m512d hmin = _mm512_set1_pd(sf->height_min), hrange = _mm512_set1_pd(sf->height_max - sf->height_min);
    const __m512d zmin = _mm512_set1_pd(s->zmin), zrange = _mm512_set1_pd(s->zrange);
    for (uint32_t j = 0; j < n; j += 8) {
        float zb[8];
        uint32_t m;
        const float *zp = lane_samples(zrow, j, n, 8, zb, &m);
        __m512d x = _mm512_mul_pd(load8f(zp), vzs);
        if (t->mode == 1) x = _mm512_div_pd(_mm512_sub_pd(x, hmin), hrange);
        else if (t->mode == 2) x = _mm512_div_pd(_mm512_sub_pd(_mm512_div_pd(x, vzs), zmin), zrange);
        else if (t->mode == 3) x = _mm512_set1_pd(0.5);
        x = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(x, lo, _CMP_GT_OQ), lo, x);
        x = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(x, hi, _CMP_GT_OQ), x, hi);
        __m512i idx = _mm512_setzero_si512();
        for (int k = 1; k + 1 < t->n; k++)
            idx = _mm512_mask_add_epi64(idx, _mm512_cmp_pd_mask(x, _mm512_set1_pd(t->H[k]), _CMP_GT_OQ), idx, one);
        __m512d u = _mm512_div_pd(_mm512_sub_pd(x, _mm512_permutexvar_pd(idx, Hv)), _mm512_permutexvar_pd(idx, HDv));
        for (int c = 0; c < 3; c++) {
            __m512d v = _mm512_add_pd(_mm512_permutexvar_pd(idx, Cv[c]), _mm512_mul_pd(u, _mm512_permutexvar_pd(idx, CDv[c])));
            __m256 f = _mm512_cvtpd_ps(v);
            float *o = out + (size_t)c * plane + j;
            if (m == 8) _mm256_storeu_ps(o, f);
            else {
                float fb[8];
                _mm256_storeu_ps(fb, f);
                memcpy(o, fb, m * sizeof *o);
            }
        }
    }
}

#ifdef RS_AVX2_DISPATCH
/* tint_row8 four samples a register where the CPU has AVX2 but not
 * AVX-512: the same operations lane by lane (the same doubles). A lane's
 * stop is the last k with x > H[k], taken by blends (the stops rise:
 * rs_surface_options' check), which is tint_row8's count of them. */
RS_AVX2 static void tint_row4(const rs_splatter *s, const tint_ramp *t, const float *zrow, uint32_t n, float *out,
                              size_t plane)
{
    const rs_surface_options *sf = &s->o.surface;
    const double zs = s->dem->frame.z_scale;
    const __m256d vzs = _mm256_set1_pd(zs), lo = _mm256_set1_pd(t->H[0]), hi = _mm256_set1_pd(t->H[t->n - 1]);
    const __m256d hmin = _mm256_set1_pd(sf->height_min), hrange = _mm256_set1_pd(sf->height_max - sf->height_min);
    const __m256d zmin = _mm256_set1_pd(s->zmin), zrange = _mm256_set1_pd(s->zrange);
    for (uint32_t j = 0; j < n; j += 4) {
        float zb[4];
        uint32_t m;
        const float *zp = lane_samples(zrow, j, n, 4, zb, &m);
        __m256d x = _mm256_mul_pd(_mm256_cvtps_pd(_mm_loadu_ps(zp)), vzs);
        if (t->mode == 1) x = _mm256_div_pd(_mm256_sub_pd(x, hmin), hrange);
        else if (t->mode == 2) x = _mm256_div_pd(_mm256_sub_pd(_mm256_div_pd(x, vzs), zmin), zrange);
        else if (t->mode == 3) x = _mm256_set1_pd(0.5);
        x = _mm256_blendv_pd(lo, x, _mm256_cmp_pd(x, lo, _CMP_GT_OQ)); /* (NaN: lo) */
        x = _mm256_blendv_pd(x, hi, _mm256_cmp_pd(x, hi, _CMP_GT_OQ));
        __m256d h = _mm256_set1_pd(t->H[0]), hd = _mm256_set1_pd(t->HD[0]), c[3], cd[3];
        for (int q = 0; q < 3; q++) c[q] = _mm256_set1_pd(t->C[q][0]), cd[q] = _mm256_set1_pd(t->CD[q][0]);
        for (int k = 1; k + 1 < t->n; k++) {
            const __m256d above = _mm256_cmp_pd(x, _mm256_set1_pd(t->H[k]), _CMP_GT_OQ);
            h = _mm256_blendv_pd(h, _mm256_set1_pd(t->H[k]), above);
            hd = _mm256_blendv_pd(hd, _mm256_set1_pd(t->HD[k]), above);
            for (int q = 0; q < 3; q++) {
                c[q] = _mm256_blendv_pd(c[q], _mm256_set1_pd(t->C[q][k]), above);
                cd[q] = _mm256_blendv_pd(cd[q], _mm256_set1_pd(t->CD[q][k]), above);
            }
        }
        const __m256d u = _mm256_div_pd(_mm256_sub_pd(x, h), hd);
        for (int q = 0; q < 3; q++) {
            __m128 f = _mm256_cvtpd_ps(_mm256_add_pd(c[q], _mm256_mul_pd(u, cd[q])));
            float *o = out + (size_t)q * plane + j;
            if (m == 4) _mm_storeu_ps(o, f);
            else {
                float fb[4];
                _mm_storeu_ps(fb, f);
                memcpy(o, fb, m * sizeof *o);
            }
        }
    }
}
#endif

/* shade_pair for the eight interior samples (i, j .. j + 7), without a
 * division: the gradient times 1 / (8 cs), 1 / sqrt(1 + g^2) from the
 * 14-bit estimate and two Newton steps, the shade's 0.7 / cos_zen as one
 * factor. The shade then differs from the divided one by a few units in
 * the last place (relative 1e-15), far inside the 1e-12 that decides a
 * tie, so every colour is the same float: a lane whose float is not
 * decided within 1e-12 takes the scalar path with the gradient divided as
 * before (rs__dem_horn), as shade_pair's ties do. */
RS_AVX512 static void shade8(const rs_splatter *s, const double light[2], const float *zrow, size_t W,
                             double inv_8cs, float *out, size_t plane, uint32_t i, uint32_t j)
{
    const double lx = light[0], ly = light[1], cz = s->cos_zen;
    const float *up = zrow - W, *mid = zrow, *dn = zrow + W;
    const __m512d vzs = _mm512_set1_pd(s->dem->frame.z_scale), two = _mm512_set1_pd(2), v8 = _mm512_set1_pd(inv_8cs);
    __m512d a = _mm512_mul_pd(load8f(up - 1), vzs), b = _mm512_mul_pd(load8f(up), vzs),
            c = _mm512_mul_pd(load8f(up + 1), vzs);
    __m512d d = _mm512_mul_pd(load8f(mid - 1), vzs), f = _mm512_mul_pd(load8f(mid + 1), vzs);
    __m512d g = _mm512_mul_pd(load8f(dn - 1), vzs), h = _mm512_mul_pd(load8f(dn), vzs),
            k = _mm512_mul_pd(load8f(dn + 1), vzs);
    __m512d dzdx = _mm512_mul_pd(_mm512_sub_pd(_mm512_add_pd(_mm512_add_pd(c, _mm512_mul_pd(two, f)), k),
                                               _mm512_add_pd(_mm512_add_pd(a, _mm512_mul_pd(two, d)), g)), v8);
    __m512d dzdy = _mm512_mul_pd(_mm512_sub_pd(_mm512_add_pd(_mm512_add_pd(g, _mm512_mul_pd(two, h)), k),
                                               _mm512_add_pd(_mm512_add_pd(a, _mm512_mul_pd(two, b)), c)), v8);
    __m512d g2 = _mm512_add_pd(_mm512_mul_pd(dzdx, dzdx), _mm512_mul_pd(dzdy, dzdy));
    __m512d x = _mm512_add_pd(_mm512_set1_pd(1), g2);
    /* y ~ 1/sqrt(x): 2^-14, then y (1.5 - x/2 y^2) twice (2^-28, 2^-52 and rounding) */
    const __m512d half = _mm512_set1_pd(0.5), th = _mm512_set1_pd(1.5);
    __m512d xh = _mm512_mul_pd(half, x), y = _mm512_rsqrt14_pd(x);
    y = _mm512_mul_pd(y, _mm512_sub_pd(th, _mm512_mul_pd(xh, _mm512_mul_pd(y, y))));
    y = _mm512_mul_pd(y, _mm512_sub_pd(th, _mm512_mul_pd(xh, _mm512_mul_pd(y, y))));
    __m512d hs = _mm512_mul_pd(_mm512_add_pd(_mm512_add_pd(_mm512_set1_pd(cz), _mm512_mul_pd(_mm512_set1_pd(lx), dzdx)),
                                             _mm512_mul_pd(_mm512_set1_pd(ly), dzdy)), y);
    hs = _mm512_maskz_mov_pd(_mm512_cmp_pd_mask(hs, _mm512_setzero_pd(), _CMP_GT_OQ), hs);
    __m512d shade = _mm512_add_pd(_mm512_set1_pd(0.3), _mm512_mul_pd(_mm512_set1_pd(0.7 / cz), hs));
    /* huge gradients (g2 >= 1e200, where x overflows the estimate's range)
     * and NaN take the scalar path */
    unsigned tiebits = _mm512_cmp_pd_mask(g2, _mm512_set1_pd(1e200), _CMP_NLT_UQ);
    const __m512d lo = _mm512_set1_pd(1 - 1e-12), hi = _mm512_set1_pd(1 + 1e-12), cap = _mm512_set1_pd(255);
    __m256 res[3];
    for (int ch = 0; ch < 3; ch++) {
        __m512d v = _mm512_mul_pd(load8f(out + (size_t)ch * plane), shade);
        v = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(v, cap, _CMP_GT_OQ), v, cap);
        res[ch] = _mm512_cvtpd_ps(v);
        tiebits |= _mm256_cmp_ps_mask(_mm512_cvtpd_ps(_mm512_mul_pd(v, lo)), _mm512_cvtpd_ps(_mm512_mul_pd(v, hi)),
                                      _CMP_NEQ_UQ);
    }
    if (!tiebits) {
        for (int ch = 0; ch < 3; ch++) _mm256_storeu_ps(out + (size_t)ch * plane, res[ch]);
        return;
    }
    float r[3][8];
    for (int ch = 0; ch < 3; ch++) _mm256_storeu_ps(r[ch], res[ch]);
    const rs_dem *dm = s->dem;
    for (int l = 0; l < 8; l++) {
        float *o = out + l;
        if (tiebits >> l & 1) {
            double dx, dy;
            rs__dem_horn(s->z, dm->width, dm->height, dm->frame.cell_size, dm->frame.z_scale, i, j + (uint32_t)l, &dx,
                         &dy);
            shade_one(s, light, dx, dy, o, plane);
        } else
            for (int ch = 0; ch < 3; ch++) o[(size_t)ch * plane] = r[ch][l];
    }
}

/* The interior shades of row i from column j on, 8 a step; the column reached. */
RS_AVX512 static uint32_t shade_row8(const rs_splatter *s, const double light[2], uint32_t i, uint32_t j,
                                     uint32_t c0, uint32_t n, float *rgb, size_t plane)
{
    const rs_dem *dm = s->dem;
    const uint32_t W = dm->width;
    const double inv_8cs = 1 / (8 * dm->frame.cell_size);
    for (; j + 8 <= c0 + n && j + 8 < W; j += 8)
        shade8(s, light, s->z + (size_t)i * W + j, W, inv_8cs, rgb + (j - c0), plane, i, j);
    return j;
}
#endif

#ifdef RS_AVX512_DISPATCH
/* rs__surface's bilinear terrain colours of piece p (every row) with
 * eight columns a register: per column the two horizontal interpolants
 * of the sample rows r0 and r1, then each pixel row's vertical step; the
 * operations and their order of the plain loops there, so the same
 * floats. A piece of one or two rows keeps the interpolants in registers;
 * taller ones store them (p->hx) and then go row by row, so that the
 * colour rows are written in order. T <= 64 (the lanes' columns and
 * weights from a table per offset in the cell). */
RS_AVX512 static void terrain_bilinear8(const rs__piece *p, uint32_t T, const float *r0, const float *r1,
                                        uint32_t wc0, size_t tplane, const double *fxt)
{
    const uint32_t w = p->w;
    /* for a group starting at offset o in its cell: lane l's column after
     * the group's first (o + l) / T and its weight fxt[(o + l) % T]; the
     * next group's offset and column step */
    int32_t rel[64][8];
    double fxg[64][8];
    uint32_t next[64], step[64];
    for (uint32_t o = 0; o < T; o++) {
        for (uint32_t l = 0; l < 8; l++) {
            rel[o][l] = (int32_t)((o + l) / T);
            fxg[o][l] = fxt[(o + l) % T];
        }
        next[o] = (o + 8) % T;
        step[o] = (o + 8) / T;
    }
    const int fused = p->rows <= 2;
    double *hx = p->hx;
    const __m512d one = _mm512_set1_pd(1);
    uint32_t ccol = p->x0 / T, off = p->x0 - ccol * T;
    if (T == 1 && p->rows == 1) {
        /* a texel a cell (a row a piece): the loop below without its lane
         * tables, its permutes or its stack copy of the six interpolants
         * (they stay in registers); the same products and sums */
        const double fy = (p->y0 - p->crow * T + 0.5) / T;
        const __m512d vf = _mm512_set1_pd(fxt[0]), vg = _mm512_sub_pd(one, vf);
        const __m512d vfy = _mm512_set1_pd(fy), vgy = _mm512_set1_pd(1 - fy);
        const size_t base0 = ccol - wc0;
        for (uint32_t k = 0; k < w; k += 8) {
            const uint32_t m = w - k < 8 ? w - k : 8;
            const size_t base = base0 + k;
            const uint32_t na = tplane - base >= 8 ? 8 : (uint32_t)(tplane - base);
            const uint32_t nb = tplane - base - 1 >= 8 ? 8 : (uint32_t)(tplane - base - 1);
            const __mmask8 ma = (__mmask8)((1u << na) - 1), mb = (__mmask8)((1u << nb) - 1);
            const __mmask8 ms = (__mmask8)((1u << m) - 1);
            /* (whole groups by plain loads and stores: masked ones cost
             * more on some CPUs, e.g. AMD Zen 4's stores) */
            const int whole = m == 8 && nb == 8;
            for (int ch = 0; ch < 3; ch++) {
                const float *a = r0 + base + (size_t)ch * tplane, *c = r1 + base + (size_t)ch * tplane;
                __m256 a0, a1, c0, c1;
                if (whole) {
                    a0 = _mm256_loadu_ps(a), a1 = _mm256_loadu_ps(a + 1);
                    c0 = _mm256_loadu_ps(c), c1 = _mm256_loadu_ps(c + 1);
                } else {
                    a0 = _mm256_maskz_loadu_ps(ma, a), a1 = _mm256_maskz_loadu_ps(mb, a + 1);
                    c0 = _mm256_maskz_loadu_ps(ma, c), c1 = _mm256_maskz_loadu_ps(mb, c + 1);
                }
                __m512d h0 = _mm512_add_pd(_mm512_mul_pd(_mm512_cvtps_pd(a0), vg), _mm512_mul_pd(_mm512_cvtps_pd(a1), vf));
                __m512d h1 = _mm512_add_pd(_mm512_mul_pd(_mm512_cvtps_pd(c0), vg), _mm512_mul_pd(_mm512_cvtps_pd(c1), vf));
                __m256 v = _mm512_cvtpd_ps(_mm512_add_pd(_mm512_mul_pd(h0, vgy), _mm512_mul_pd(h1, vfy)));
                if (whole) _mm256_storeu_ps(p->tc + (size_t)ch * w + k, v);
                else _mm256_mask_storeu_ps(p->tc + (size_t)ch * w + k, ms, v);
            }
        }
        return;
    }
    for (uint32_t k = 0; k < w; k += 8) {
        const uint32_t m = w - k < 8 ? w - k : 8;
        const size_t base = ccol - wc0;
        const uint32_t na = tplane - base >= 8 ? 8 : (uint32_t)(tplane - base);
        const uint32_t nb = tplane - base - 1 >= 8 ? 8 : (uint32_t)(tplane - base - 1);
        const __mmask8 ma = (__mmask8)((1u << na) - 1), mb = (__mmask8)((1u << nb) - 1);
        const __mmask8 ms = (__mmask8)((1u << m) - 1);
        const __m256i vrel = _mm256_loadu_si256((const __m256i *)(const void *)rel[off]);
        const __m512d vfx = _mm512_loadu_pd(fxg[off]), vgx = _mm512_sub_pd(one, vfx);
        __m512d h[2][3];
        /* (plain loads and stores for a whole group: see above) */
        const int whole_in = nb == 8, whole_out = m == 8;
        for (int row = 0; row < 2; row++) {
            const float *src = (row ? r1 : r0) + base;
            for (int ch = 0; ch < 3; ch++) {
                const float *pl = src + (size_t)ch * tplane;
                __m256 A = whole_in ? _mm256_loadu_ps(pl) : _mm256_maskz_loadu_ps(ma, pl);
                __m256 B = whole_in ? _mm256_loadu_ps(pl + 1) : _mm256_maskz_loadu_ps(mb, pl + 1);
                if (T > 1) A = _mm256_permutexvar_ps(vrel, A), B = _mm256_permutexvar_ps(vrel, B);
                h[row][ch] = _mm512_add_pd(_mm512_mul_pd(_mm512_cvtps_pd(A), vgx), _mm512_mul_pd(_mm512_cvtps_pd(B), vfx));
                if (fused) continue;
                if (whole_out) _mm512_storeu_pd(hx + (size_t)(3 * row + ch) * w + k, h[row][ch]);
                else _mm512_mask_storeu_pd(hx + (size_t)(3 * row + ch) * w + k, ms, h[row][ch]);
            }
        }
        if (fused)
            for (uint32_t r = 0; r < p->rows; r++) {
                uint32_t ty = p->y0 + r - p->crow * T;
                double fy = (ty + 0.5) / T, gy = 1 - fy;
                const __m512d vg = _mm512_set1_pd(gy), vf = _mm512_set1_pd(fy);
                for (int ch = 0; ch < 3; ch++) {
                    __m256 v = _mm512_cvtpd_ps(_mm512_add_pd(_mm512_mul_pd(h[0][ch], vg), _mm512_mul_pd(h[1][ch], vf)));
                    if (whole_out) _mm256_storeu_ps(p->tc + (size_t)r * w * 3 + (size_t)ch * w + k, v);
                    else _mm256_mask_storeu_ps(p->tc + (size_t)r * w * 3 + (size_t)ch * w + k, ms, v);
                }
            }
        ccol += step[off];
        off = next[off];
    }
    if (fused) return;
    for (uint32_t r = 0; r < p->rows; r++) {
        uint32_t ty = p->y0 + r - p->crow * T;
        double fy = (ty + 0.5) / T, gy = 1 - fy;
        const __m512d vg = _mm512_set1_pd(gy), vf = _mm512_set1_pd(fy);
        for (int ch = 0; ch < 3; ch++) {
            const double *h0 = hx + (size_t)ch * w, *h1 = hx + (size_t)(3 + ch) * w;
            float *tc = p->tc + (size_t)r * w * 3 + (size_t)ch * w;
            uint32_t k = 0;
            for (; k + 8 <= w; k += 8) { /* (plain loads and stores: see above) */
                __m512d v = _mm512_add_pd(_mm512_mul_pd(_mm512_loadu_pd(h0 + k), vg),
                                          _mm512_mul_pd(_mm512_loadu_pd(h1 + k), vf));
                _mm256_storeu_ps(tc + k, _mm512_cvtpd_ps(v));
            }
            if (k < w) {
                const __mmask8 ms = (__mmask8)((1u << (w - k)) - 1);
                __m512d v = _mm512_add_pd(_mm512_mul_pd(_mm512_maskz_loadu_pd(ms, h0 + k), vg),
                                          _mm512_mul_pd(_mm512_maskz_loadu_pd(ms, h1 + k), vf));
                _mm256_mask_storeu_ps(tc + k, ms, _mm512_cvtpd_ps(v));
            }
        }
    }
}
#endif

/* Terrain colour of DEM sample row i, columns [c0, c0 + n): tint times a
 * hillshade by Horn's gradient, light from azimuth 315, altitude 45
 * (gdaldem's defaults and formula), normalised so flat ground keeps its
 * tint. Planar: R of the n columns, then G, then B.
 *
 * Without trigonometry: with g = |grad|, cos(atan g) = 1/sqrt(1+g^2),
 * sin(atan g) = g/sqrt(1+g^2), and the aspect's unit vector is
 * (-dzdx, dzdy)/g, so the shade is (cos_zen - sin_zen cos(az) dzdx +
 * sin_zen sin(az) dzdy) / sqrt(1+g^2). It differs from the trigonometric
 * value in the last bits only (relative 1e-14); where either float that a
 * colour channel rounds to could depend on those bits (the value within
 * 1e-12 of a float rounding boundary), the trigonometric formula decides,
 * so the colours are the same floats as gdaldem's formula gives
 * (tests/tools/splat_identity.sh).
 *
 * Two passes: the tints of the row, then the shades, eight interior
 * samples per register (AVX-512, where the CPU has it), else two (SSE2),
 * and the border ones one by one. Every path gives the same floats: the
 * tints divide as the scalar code does, and the AVX-512 shades (shade8,
 * without divisions) stay within the tie test's 1e-12. The five
 * divisions and the square root of a sample were ~40 ns per sample in
 * one dependent chain (docs/speed.md). */
static void terrain_row(const rs_splatter *s, uint32_t i, uint32_t c0, uint32_t n, float *rgb)
{
    const rs_dem *d = s->dem;
    const double zs = d->frame.z_scale;
    const uint32_t W = d->width, H = d->height;
    const float *z = s->z;
    const rs_surface_options *sf = &s->o.surface;
    const size_t plane = n;
#ifdef RS_AVX512_DISPATCH
    const int wide = rs__avx512_ok();
#ifdef RS_AVX2_DISPATCH
    const int avx2 = !wide && rs__avx2_ok();
#else
    const int avx2 = 0;
#endif
    tint_ramp tr;
    tr.n = 0;
    if (wide || avx2) tint_ramp_init(s, &tr);
    if (wide && tr.n) tint_row8(s, &tr, z + (size_t)i * W + c0, n, rgb, plane);
#ifdef RS_AVX2_DISPATCH
    else if (avx2 && tr.n) tint_row4(s, &tr, z + (size_t)i * W + c0, n, rgb, plane);
#endif
    else
#endif
    for (uint32_t j = c0; j < c0 + n; j++) {
        double zc = z[(size_t)i * W + j] * zs;
        float tint[3];
        if (sf->tint == RS_TINT_ABSOLUTE) absolute_tint(sf, zc, tint);
        else if (sf->height_min != 0 || sf->height_max != 0)
            hypsometric((zc - sf->height_min) / (sf->height_max - sf->height_min), tint);
        else hypsometric(s->zrange > 0 ? (zc / zs - s->zmin) / s->zrange : 0.5, tint);
        /* lit output: the relief is shaded once, by the lighting */
        terrain_rgb(tint, 1.0, rgb + (j - c0), plane);
    }
    if (s->o.lighting.enable) return;
    /* the light's horizontal components, once per row */
    const double light[2] = { -s->sin_zen * cos(s->sun_az), s->sin_zen * sin(s->sun_az) };
    uint32_t j = c0;
#if defined(__SSE2__)
    const double eight_cs = 8 * d->frame.cell_size;
    if (i >= 1 && i + 1 < H) {
        if (j < 1 && j < c0 + n) {
            double dzdx, dzdy;
            rs__dem_horn(z, W, H, d->frame.cell_size, zs, i, j, &dzdx, &dzdy);
            shade_one(s, light, dzdx, dzdy, rgb + (j - c0), plane);
            j++;
        }
#ifdef RS_AVX512_DISPATCH
        if (wide) j = shade_row8(s, light, i, j, c0, n, rgb, plane);
#endif
#ifdef RS_AVX2_DISPATCH
        if (avx2)
            for (; j + 4 <= c0 + n && j + 4 < W; j += 4)
                shade_quad(s, light, z + (size_t)i * W + j, W, eight_cs, rgb + (j - c0), plane);
#endif
        for (; j + 2 <= c0 + n; j++) {
            if (j >= 1 && j + 2 < W) {
                shade_pair(s, light, z + (size_t)i * W + j, W, eight_cs, rgb + (j - c0), plane);
                j++;
                continue;
            }
            double dzdx, dzdy;
            rs__dem_horn(z, W, H, d->frame.cell_size, zs, i, j, &dzdx, &dzdy);
            shade_one(s, light, dzdx, dzdy, rgb + (j - c0), plane);
        }
    }
#endif
    for (; j < c0 + n; j++) {
        double dzdx, dzdy;
        rs__dem_horn(z, W, H, d->frame.cell_size, zs, i, j, &dzdx, &dzdy);
        shade_one(s, light, dzdx, dzdy, rgb + (j - c0), plane);
    }
}

rs_result rs__surface_colours(rs_ctx *ctx, rs_splatter *s)
{
    const uint64_t W = s->dem->width, H = s->dem->height;
    if (s->o.texels > RS__TCOL_TEXELS || s->o.surface.terrain_texture || W * H > RS__TCOL_SAMPLES) return RS_OK;
    float *t = rs__alloc_array(ctx, (size_t)(W * H), 3 * sizeof *t);
    if (!t) return RS_ERR_NOMEM;
    for (uint32_t i = 0; i < H; i++) {
        if (rs__tick(ctx, 0)) {
            rs__free(ctx, t);
            return RS_ERR_CANCELLED;
        }
        terrain_row(s, i, 0, (uint32_t)W, t + (size_t)i * 3 * W);
    }
    s->tcol = t;
    return RS_OK;
}

/* The window's terrain colours of sample rows i and i + 1 (lib/splat/splatter.h). */
static void terrain_rows(const rs_splatter *s, rs__terrain_cache *c, uint32_t i, const float **r0, const float **r1)
{
    for (uint32_t k = 0; k < 2; k++) {
        uint32_t want = i + k;
        int slot = c->row_of[0] == want ? 0 : (c->row_of[1] == want ? 1 : -1);
        if (slot < 0) {
            /* the slot not holding the other row wanted */
            slot = c->row_of[0] == i + 1 - k ? 1 : 0;
            terrain_row(s, want, c->c0, c->ncol, c->rgb[slot]);
            c->row_of[slot] = want;
        }
        if (k) *r1 = c->rgb[slot];
        else *r0 = c->rgb[slot];
    }
}

/* Texture coordinate tables along one axis: for n pixels starting at pixel
 * p0, the texel pair (i0[k], i1[k] = i0[n + k]) and the weights (1 - f in
 * wt[k], f in wt[n + k]) of the bilinear sample of an image of `size`
 * texels per repeat. */
static void texture_axis(int64_t p0, uint32_t n, double texel_m, double scale, uint32_t size, uint32_t *idx,
                         double *wt)
{
    const int64_t S = size;
    for (uint32_t k = 0; k < n; k++) {
        double u = ((double)(p0 + k) + 0.5) * texel_m / scale;
        u = (u - floor(u)) * S - 0.5;
        double fu = floor(u), au = u - fu;
        int64_t x0 = (int64_t)fu;
        int64_t a = x0 >= 0 && x0 < S ? x0 : ((x0 % S) + S) % S;
        idx[k] = (uint32_t)a;
        idx[n + k] = (uint32_t)(a + 1 == S ? 0 : a + 1);
        wt[k] = 1 - au;
        wt[n + k] = au;
    }
}

#if defined(__SSE2__)
static __m128i load32(const uint8_t *p)
{
    int32_t v;
    memcpy(&v, p, 4);
    return _mm_cvtsi32_si128(v);
}

/* Texel a (one pixel) and texel b (the next pixel) widened to 32 bits:
 * lo = R R' G G', hi = B B' A A'. */
static void texel_pair(const uint8_t *a, const uint8_t *b, __m128i *lo, __m128i *hi)
{
    const __m128i z = _mm_setzero_si128();
    __m128i x = _mm_unpacklo_epi8(_mm_unpacklo_epi8(load32(a), load32(b)), z);
    *lo = _mm_unpacklo_epi16(x, z);
    *hi = _mm_unpackhi_epi16(x, z);
}

/* One channel of two pixels: the bilinear sample as float, in the scalar
 * loop's order of operations; i selects the channel's 32-bit pair. */
#define TEX_CHANNEL(i00, i01, i10, i11)                                                                         \
    _mm_cvtpd_ps(_mm_add_pd(                                                                                   \
        _mm_mul_pd(_mm_add_pd(_mm_mul_pd(_mm_cvtepi32_pd(i00), vbu), _mm_mul_pd(_mm_cvtepi32_pd(i01), vau)), vbv), \
        _mm_mul_pd(_mm_add_pd(_mm_mul_pd(_mm_cvtepi32_pd(i10), vbu), _mm_mul_pd(_mm_cvtepi32_pd(i11), vau)), vav)))
#endif

#ifdef RS_AVX2_DISPATCH
/* Channel c (0, 1, 2: the texel's byte) of four texels as doubles. */
#define TEX_BYTE4(t, c) _mm256_cvtepi32_pd(_mm_and_si128(_mm_srli_epi32((t), 8 * (c)), ff))
/* One channel of four pixels, as TEX_CHANNEL: the scalar loop's doubles in
 * its order, rounded to float. */
#define TEX_CHANNEL4(c)                                                                                            \
    _mm256_cvtpd_ps(_mm256_add_pd(                                                                                 \
        _mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(TEX_BYTE4(t00, c), vbu), _mm256_mul_pd(TEX_BYTE4(t01, c), vau)), \
                      vbv),                                                                                        \
        _mm256_mul_pd(_mm256_add_pd(_mm256_mul_pd(TEX_BYTE4(t10, c), vbu), _mm256_mul_pd(TEX_BYTE4(t11, c), vau)), \
                      vav)))

/* Texels x and x + 1 of row r for four pixels (their x at cx[0..3]), as
 * t0 = the four texels x, t1 = the four texels x + 1: one 8-byte load a
 * pixel. */
RS_AVX2 static void texel_pairs4(const uint8_t *r, const uint32_t *cx, __m128i *t0, __m128i *t1)
{
    __m128 a = _mm_loadh_pi(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(const void *)(r + 4 * (size_t)cx[0]))),
                            (const __m64 *)(const void *)(r + 4 * (size_t)cx[1]));
    __m128 b = _mm_loadh_pi(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(const void *)(r + 4 * (size_t)cx[2]))),
                            (const __m64 *)(const void *)(r + 4 * (size_t)cx[3]));
    *t0 = _mm_castps_si128(_mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0)));
    *t1 = _mm_castps_si128(_mm_shuffle_ps(a, b, _MM_SHUFFLE(3, 1, 3, 1)));
}

/* texture_piece's row four pixels a register where the CPU has AVX2. A
 * pixel's two texels of a row are next to each other but where the
 * texture wraps (x + 1 = 0): one 8-byte load gives both; a group of four
 * with a wrap takes its texels by gathers (the columns are below 2^31:
 * the caller checks the width). Four pixels of no interest are skipped
 * together (a group with one such pixel gives it a colour the composite
 * never reads). Returns the pixels done, a multiple of 4. */
RS_AVX2 static size_t texture_row4(const uint8_t *ra, const uint8_t *rb, const uint32_t *cx, const uint32_t *cx1,
                                   const double *bu, const double *au, double bv, double av, const uint16_t *q,
                                   int32_t skip, size_t w, float *out)
{
    const __m128i ff = _mm_set1_epi32(0xFF), one = _mm_set1_epi32(1);
    const __m256d vbv = _mm256_set1_pd(bv), vav = _mm256_set1_pd(av);
    const int *a = (const int *)(const void *)ra, *b = (const int *)(const void *)rb;
    size_t k = 0;
    for (; k + 4 <= w; k += 4) {
        if ((q[k] == skip) & (q[k + 1] == skip) & (q[k + 2] == skip) & (q[k + 3] == skip)) continue;
        const __m128i i0 = _mm_loadu_si128((const __m128i *)(const void *)(cx + k));
        const __m128i i1 = _mm_loadu_si128((const __m128i *)(const void *)(cx1 + k));
        __m128i t00, t01, t10, t11;
        if (_mm_movemask_epi8(_mm_cmpeq_epi32(_mm_sub_epi32(i1, i0), one)) == 0xFFFF) {
            texel_pairs4(ra, cx + k, &t00, &t01);
            texel_pairs4(rb, cx + k, &t10, &t11);
        } else {
            t00 = _mm_i32gather_epi32(a, i0, 4), t01 = _mm_i32gather_epi32(a, i1, 4);
            t10 = _mm_i32gather_epi32(b, i0, 4), t11 = _mm_i32gather_epi32(b, i1, 4);
        }
        const __m256d vbu = _mm256_loadu_pd(bu + k), vau = _mm256_loadu_pd(au + k);
        _mm_storeu_ps(out + k, TEX_CHANNEL4(0));
        _mm_storeu_ps(out + w + k, TEX_CHANNEL4(1));
        _mm_storeu_ps(out + 2 * w + k, TEX_CHANNEL4(2));
    }
    return k;
}
#undef TEX_CHANNEL4
#undef TEX_BYTE4
#endif

/* A tiled texture into dst over the piece's pixels with terrain (road = 0)
 * or with road (road = 1); the other pixels may get colours too, which the
 * composite never reads. Column coordinates once per run of pieces with
 * the same columns, row coordinates per piece. */
static void texture_piece(const rs_splatter *s, rs__piece *p, const rs_image *img, int road, float *dst)
{
    const size_t w = p->w, ww = p->win_w, off = p->x0 - p->win_x0;
    uint32_t *ry = p->tiy;
    double *wy = p->twy;
    double scale = s->o.surface.texture_scale;
    if (!p->tx_ready[road]) {
        texture_axis(p->win_x0 + s->o.surface.texel_offset_x, p->win_w, s->texel_m, scale, img->width, p->tix[road],
                     p->twx[road]);
        p->tx_ready[road] = 1;
    }
    texture_axis(p->y0 + s->o.surface.texel_offset_y, p->rows, s->texel_m, scale, img->height, ry, wy);
    const uint32_t *cx = p->tix[road] + off, *cx1 = cx + ww;
    const double *bu = p->twx[road] + off, *au = bu + ww;
    /* pixels of no interest: pure road for the terrain, pure terrain for
     * the road; skipped two at a time (none for the layers: p->all) */
    const int32_t skip = p->all ? -1 : (road ? 0 : 65535);
    const size_t W4 = 4 * (size_t)img->width;
#ifdef RS_AVX2_DISPATCH
    const int avx2 = img->width <= (uint32_t)INT32_MAX && rs__avx2_ok();
#endif
    for (uint32_t r = 0; r < p->rows; r++) {
        const uint16_t *q = p->q + (size_t)r * w;
        float *out = dst + (size_t)r * w * 3;
        const uint8_t *ra = img->rgba + ry[r] * W4, *rb = img->rgba + ry[p->rows + r] * W4;
        const double bv = wy[r], av = wy[p->rows + r];
        size_t k = 0;
#ifdef RS_AVX2_DISPATCH
        if (avx2) k = texture_row4(ra, rb, cx, cx1, bu, au, bv, av, q, skip, w, out);
#endif
#if defined(__SSE2__)
        /* two pixels per channel in a register, the scalar arithmetic */
        const __m128d vbv = _mm_set1_pd(bv), vav = _mm_set1_pd(av);
        for (; k + 2 <= w; k += 2) {
            if (q[k] == skip && q[k + 1] == skip) continue;
            __m128i l00, h00, l01, h01, l10, h10, l11, h11;
            texel_pair(ra + 4 * (size_t)cx[k], ra + 4 * (size_t)cx[k + 1], &l00, &h00);
            texel_pair(ra + 4 * (size_t)cx1[k], ra + 4 * (size_t)cx1[k + 1], &l01, &h01);
            texel_pair(rb + 4 * (size_t)cx[k], rb + 4 * (size_t)cx[k + 1], &l10, &h10);
            texel_pair(rb + 4 * (size_t)cx1[k], rb + 4 * (size_t)cx1[k + 1], &l11, &h11);
            const __m128d vbu = _mm_loadu_pd(bu + k), vau = _mm_loadu_pd(au + k);
            __m128 fr = TEX_CHANNEL(l00, l01, l10, l11);
            __m128 fg = TEX_CHANNEL(_mm_srli_si128(l00, 8), _mm_srli_si128(l01, 8), _mm_srli_si128(l10, 8),
                                    _mm_srli_si128(l11, 8));
            __m128 fb = TEX_CHANNEL(h00, h01, h10, h11);
            _mm_storel_epi64((__m128i *)(void *)(out + k), _mm_castps_si128(fr));
            _mm_storel_epi64((__m128i *)(void *)(out + w + k), _mm_castps_si128(fg));
            _mm_storel_epi64((__m128i *)(void *)(out + 2 * w + k), _mm_castps_si128(fb));
        }
#endif
        for (; k < w; k++) {
            if (q[k] == skip) continue;
            const uint8_t *p00 = ra + 4 * (size_t)cx[k], *p01 = ra + 4 * (size_t)cx1[k];
            const uint8_t *p10 = rb + 4 * (size_t)cx[k], *p11 = rb + 4 * (size_t)cx1[k];
            for (int c = 0; c < 3; c++)
                out[c * w + k] = (float)((p00[c] * bu[k] + p01[c] * au[k]) * bv + (p10[c] * bu[k] + p11[c] * au[k]) * av);
        }
    }
}

/* Procedural asphalt: dark grey, fine grain per texel plus a soft mottle on
 * a 4-texel lattice; keyed to texel indices, so deterministic. One row of
 * n pixels from column px0 (wrapping as uint32), those with road (q > 0)
 * or all; the lattice's four hashes once per lattice column. */
static void asphalt_row(uint32_t px0, uint32_t py, const uint16_t *q, int all, int skip_whole, uint32_t n, float *rgb,
                        size_t plane)
{
    const uint32_t ly = py >> 2;
    const double fy = (py & 3) / 4.0;
    uint32_t at = 0;
    double n00 = 0, n01 = 0, n10 = 0, n11 = 0;
    int have = 0;
    for (uint32_t k = 0; k < n; k++) {
#if defined(__SSE2__)
        /* eight pixels that need no asphalt (terrain, or whole road under
         * an opaque fill) in one test: most of a row is one or the other */
        if (!all && (k & 7) == 0 && k + 8 <= n) {
            const __m128i v = _mm_loadu_si128((const __m128i *)(const void *)(q + k));
            __m128i none = _mm_cmpeq_epi16(v, _mm_setzero_si128());
            if (skip_whole) none = _mm_or_si128(none, _mm_cmpeq_epi16(v, _mm_set1_epi16(-1)));
            if (_mm_movemask_epi8(none) == 0xFFFF) {
                k += 7;
                continue;
            }
        }
#endif
        if (!all && (q[k] == 0 || (skip_whole && q[k] == 65535u))) continue;
        const uint32_t px = px0 + k, lx = px >> 2;
        if (!have || lx != at) {
            n00 = (hash2(lx, ly + 7919u) & 0xFF) / 255.0;
            n01 = (hash2(lx + 1, ly + 7919u) & 0xFF) / 255.0;
            n10 = (hash2(lx, ly + 7920u) & 0xFF) / 255.0;
            n11 = (hash2(lx + 1, ly + 7920u) & 0xFF) / 255.0;
            at = lx;
            have = 1;
        }
        double grain = (double)(hash2(px, py) & 0xFFFF) / 65535.0 - 0.5;
        double fx = (px & 3) / 4.0;
        double mottle = (n00 * (1 - fx) + n01 * fx) * (1 - fy) + (n10 * (1 - fx) + n11 * fx) * fy - 0.5;
        double v = 70 + 18 * grain + 10 * mottle;
        rgb[k] = (float)v;
        rgb[plane + k] = (float)v;
        rgb[2 * plane + k] = (float)(v + 3);
    }
}

#ifdef RS_AVX2_DISPATCH
/* terrain_bilinear's vertical step four pixels a register where the CPU
 * has AVX2 but not AVX-512 (the same products and sum); returns the pixels
 * done, a multiple of 4. */
RS_AVX2 static size_t lerp_row4(const double *h0, const double *h1, double gy, double fy, float *tc, size_t w)
{
    const __m256d vg = _mm256_set1_pd(gy), vf = _mm256_set1_pd(fy);
    size_t j = 0;
    for (; j + 4 <= w; j += 4)
        _mm_storeu_ps(tc + j, _mm256_cvtpd_ps(_mm256_add_pd(_mm256_mul_pd(_mm256_loadu_pd(h0 + j), vg),
                                                            _mm256_mul_pd(_mm256_loadu_pd(h1 + j), vf))));
    return j;
}

/* terrain_bilinear's one-texel row (T = 1, one pixel row) four pixels a
 * register where the CPU has AVX2 but not AVX-512 (the SSE2 loop's
 * products and sums); returns the pixels done, a multiple of 4. */
RS_AVX2 static size_t row1_4(const float *a, const float *c, double fx, double gy, double fy, float *tc, size_t w)
{
    const __m256d g = _mm256_set1_pd(1 - fx), f = _mm256_set1_pd(fx), vg = _mm256_set1_pd(gy),
                  vf = _mm256_set1_pd(fy);
    size_t j = 0;
    for (; j + 4 <= w; j += 4) {
        __m256d a0 = _mm256_cvtps_pd(_mm_loadu_ps(a + j)), a1 = _mm256_cvtps_pd(_mm_loadu_ps(a + j + 1));
        __m256d c0 = _mm256_cvtps_pd(_mm_loadu_ps(c + j)), c1 = _mm256_cvtps_pd(_mm_loadu_ps(c + j + 1));
        __m256d h0 = _mm256_add_pd(_mm256_mul_pd(a0, g), _mm256_mul_pd(a1, f));
        __m256d h1 = _mm256_add_pd(_mm256_mul_pd(c0, g), _mm256_mul_pd(c1, f));
        _mm_storeu_ps(tc + j, _mm256_cvtpd_ps(_mm256_add_pd(_mm256_mul_pd(h0, vg), _mm256_mul_pd(h1, vf))));
    }
    return j;
}

/* terrain_bilinear's whole cells of T >= 4 texels with four offsets a
 * register where the CPU has AVX2 but not AVX-512 (the same products and
 * sums as the two-offset loop there); a: the cell's first sample of the
 * plane, h: its first interpolant. */
RS_AVX2 static void cells4(const float *a, double *h, uint32_t ncell, uint32_t T, const double *fxt)
{
    for (uint32_t cc = 0; cc < ncell; cc++, a++, h += T) {
        const __m256d v0 = _mm256_set1_pd(a[0]), v1 = _mm256_set1_pd(a[1]);
        uint32_t o = 0;
        for (; o + 4 <= T; o += 4) {
            const __m256d f = _mm256_loadu_pd(fxt + o), g = _mm256_sub_pd(_mm256_set1_pd(1), f);
            _mm256_storeu_pd(h + o, _mm256_add_pd(_mm256_mul_pd(v0, g), _mm256_mul_pd(v1, f)));
        }
        for (; o < T; o++) h[o] = (double)a[0] * (1 - fxt[o]) + (double)a[1] * fxt[o];
    }
}
#endif

/* terrain_bilinear's two horizontal interpolants of pixels [k, k1) of
 * piece p (p->hx), pixel by pixel from column ccol at offset off in its
 * cell (off = T: the next cell's first). */
static void hx_pixels(const rs__piece *p, uint32_t T, const float *r0, const float *r1, uint32_t wc0, size_t tplane,
                      const double *fxt, uint32_t nt, uint32_t k, uint32_t k1, uint32_t ccol, uint32_t off)
{
    double *hx = p->hx;
    const size_t w = p->w;
    for (; k < k1; k++, off++) {
        if (off == T) { off = 0; ccol++; }
        double fx = off < nt ? fxt[off] : (off + 0.5) / T;
        const float *a = r0 + (ccol - wc0), *c = r1 + (ccol - wc0);
        for (int ch = 0; ch < 3; ch++) {
            hx[ch * w + k] = a[ch * tplane] * (1 - fx) + a[ch * tplane + 1] * fx;
            hx[(3 + ch) * w + k] = c[ch * tplane] * (1 - fx) + c[ch * tplane + 1] * fx;
        }
    }
}

/* rs__surface's bilinear terrain colours of piece p (every row): the two
 * horizontal interpolants per column once per piece (p->hx), then every
 * row of the piece (all pixels: a plain loop). The column and its offset
 * in the cell are counted along (no integer division per column); fxt
 * holds the weights of the first nt offsets. */
static void terrain_bilinear(const rs__piece *p, uint32_t T, const float *r0, const float *r1, uint32_t wc0,
                             size_t tplane, const double *fxt, uint32_t nt)
{
#ifdef RS_AVX2_DISPATCH
    const int avx2 = rs__avx2_ok();
#endif
    double *hx = p->hx;
    const size_t w = p->w;
    uint32_t ccol = p->x0 / T, off = p->x0 - ccol * T;
    uint32_t k = 0;
#if defined(__SSE2__)
    /* one or two texels a cell (where this is most of the splat): the
     * same products and sums two pixels at a time, channel by channel */
    if (T == 1 && p->rows == 1) {
        /* one row: both steps in registers, straight into the colours */
        const __m128d g = _mm_set1_pd(1 - fxt[0]), f = _mm_set1_pd(fxt[0]);
        const double fy = (p->y0 - p->crow * T + 0.5) / T, gy = 1 - fy;
        const __m128d vg = _mm_set1_pd(gy), vf = _mm_set1_pd(fy);
        for (int ch = 0; ch < 3; ch++) {
            const float *a = r0 + (size_t)ch * tplane + (ccol - wc0), *c = r1 + (size_t)ch * tplane + (ccol - wc0);
            float *tc = p->tc + (size_t)ch * w;
            size_t j = 0;
#ifdef RS_AVX2_DISPATCH
            if (avx2) j = row1_4(a, c, fxt[0], gy, fy, tc, w);
#endif
            for (; j + 2 <= w; j += 2) {
                __m128d a0 = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(const void *)(a + j))));
                __m128d a1 = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(const void *)(a + j + 1))));
                __m128d c0 = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(const void *)(c + j))));
                __m128d c1 = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(const void *)(c + j + 1))));
                __m128d h0 = _mm_add_pd(_mm_mul_pd(a0, g), _mm_mul_pd(a1, f));
                __m128d h1 = _mm_add_pd(_mm_mul_pd(c0, g), _mm_mul_pd(c1, f));
                __m128d v = _mm_add_pd(_mm_mul_pd(h0, vg), _mm_mul_pd(h1, vf));
                _mm_storel_epi64((__m128i *)(void *)(tc + j), _mm_castps_si128(_mm_cvtpd_ps(v)));
            }
            for (; j < w; j++) {
                double h0 = a[j] * (1 - fxt[0]) + a[j + 1] * fxt[0], h1 = c[j] * (1 - fxt[0]) + c[j + 1] * fxt[0];
                tc[j] = (float)(h0 * gy + h1 * fy);
            }
        }
        return;
    } else if (T == 2 && off == 0) {
        /* a pair of pixels in one cell: offsets 0 and 1 (a piece starting
         * at an odd column, a window's choice, takes hx_pixels) */
        const __m128d g = _mm_set_pd(1 - fxt[1], 1 - fxt[0]), f = _mm_set_pd(fxt[1], fxt[0]);
        for (int rw = 0; rw < 2; rw++)
            for (int ch = 0; ch < 3; ch++) {
                const float *a = (rw ? r1 : r0) + (size_t)ch * tplane + (ccol - wc0);
                double *h = hx + (size_t)(3 * rw + ch) * w;
                uint32_t kk = 0;
                for (; kk + 2 <= w; kk += 2, a++) {
                    __m128d v0 = _mm_set1_pd(a[0]), v1 = _mm_set1_pd(a[1]);
                    _mm_storeu_pd(h + kk, _mm_add_pd(_mm_mul_pd(v0, g), _mm_mul_pd(v1, f)));
                }
                k = kk;
            }
        ccol += k / 2;
    } else if (T >= 3 && T <= nt) {
        /* whole cells from the first cell boundary on: a cell's two samples
         * loaded once per plane, its offsets two a register (the same
         * products and sums as hx_pixels, whose per-pixel column and
         * weight steps were most of the stage at 4 texels without AVX-512);
         * the part before the boundary and after the last whole cell go
         * pixel by pixel */
        uint32_t k0 = off ? T - off : 0;
        if (k0 > w) k0 = (uint32_t)w;
        uint32_t ncell = (uint32_t)((w - k0) / T), c0 = ccol + (off ? 1 : 0);
        hx_pixels(p, T, r0, r1, wc0, tplane, fxt, nt, 0, k0, ccol, off);
        for (int rw = 0; rw < 2; rw++)
            for (int ch = 0; ch < 3; ch++) {
                const float *a = (rw ? r1 : r0) + (size_t)ch * tplane + (c0 - wc0);
                double *h = hx + (size_t)(3 * rw + ch) * w + k0;
#ifdef RS_AVX2_DISPATCH
                if (avx2 && T >= 4) {
                    cells4(a, h, ncell, T, fxt);
                    continue;
                }
#endif
                for (uint32_t cc = 0; cc < ncell; cc++, a++, h += T) {
                    const __m128d v0 = _mm_set1_pd(a[0]), v1 = _mm_set1_pd(a[1]);
                    uint32_t o = 0;
                    for (; o + 2 <= T; o += 2) {
                        const __m128d f = _mm_loadu_pd(fxt + o);
                        const __m128d g = _mm_sub_pd(_mm_set1_pd(1), f);
                        _mm_storeu_pd(h + o, _mm_add_pd(_mm_mul_pd(v0, g), _mm_mul_pd(v1, f)));
                    }
                    if (o < T) h[o] = (double)a[0] * (1 - fxt[o]) + (double)a[1] * fxt[o];
                }
            }
        k = k0 + ncell * T;
        ccol = c0 + ncell;
        off = 0;
    }
#endif
    hx_pixels(p, T, r0, r1, wc0, tplane, fxt, nt, k, p->w, ccol, off);
    for (uint32_t r = 0; r < p->rows; r++) {
        uint32_t ty = p->y0 + r - p->crow * T;
        double fy = (ty + 0.5) / T, gy = 1 - fy;
        for (size_t ch = 0; ch < 3; ch++) {
            const double *h0 = hx + ch * w, *h1 = hx + (3 + ch) * w;
            float *tc = p->tc + (size_t)r * w * 3 + ch * w;
            size_t j = 0;
#ifdef RS_AVX2_DISPATCH
            if (avx2) j = lerp_row4(h0, h1, gy, fy, tc, w);
#endif
#if defined(__SSE2__)
            const __m128d vg = _mm_set1_pd(gy), vf = _mm_set1_pd(fy);
            for (; j + 2 <= w; j += 2) {
                __m128d v = _mm_add_pd(_mm_mul_pd(_mm_loadu_pd(h0 + j), vg), _mm_mul_pd(_mm_loadu_pd(h1 + j), vf));
                _mm_storel_epi64((__m128i *)(void *)(tc + j), _mm_castps_si128(_mm_cvtpd_ps(v)));
            }
#endif
            for (; j < w; j++) tc[j] = (float)(h0[j] * gy + h1[j] * fy);
        }
    }
}

void rs__surface(const rs_splatter *s, rs__piece *p)
{
    const uint32_t T = s->o.texels;
    const rs_surface_options *f = &s->o.surface;
    const size_t n = (size_t)p->rows * p->w;
    int need_terrain = p->all, need_road = p->all || p->road_pixels != 0;
    for (size_t i = 0; i < n && !need_terrain; i++) need_terrain = p->q[i] < 65535u;
    if (need_terrain && f->terrain_texture) texture_piece(s, p, f->terrain_texture, 0, p->tc);
    else if (need_terrain) {
        /* Bilinear between the sample rows crow and crow + 1 */
        const float *r0 = NULL, *r1 = NULL;
        uint32_t wc0 = p->tcache->c0;
        size_t tplane = p->tcache->ncol;
        if (s->tcol) {
            /* (the rows as terrain_row makes them for columns 0 .. W - 1) */
            tplane = s->dem->width;
            wc0 = 0;
            r0 = s->tcol + (size_t)p->crow * 3 * tplane;
            r1 = r0 + 3 * tplane;
        } else terrain_rows(s, p->tcache, p->crow, &r0, &r1);
        /* the weight per offset in the cell from a table: the same doubles
         * as (offset + 0.5) / T */
        double fxt[64];
        const uint32_t nt = T < 64 ? T : 64;
        for (uint32_t t = 0; t < nt; t++) fxt[t] = (t + 0.5) / T;
#ifdef RS_AVX512_DISPATCH
        if (T <= 64 && rs__avx512_ok()) terrain_bilinear8(p, T, r0, r1, wc0, tplane, fxt);
        else
#endif
            terrain_bilinear(p, T, r0, r1, wc0, tplane, fxt, nt);
    }
    if (!need_road) return;
    if (f->road_texture) {
        texture_piece(s, p, f->road_texture, 1, p->sc);
        return;
    }
    /* the grain keyed to the map's pixel grid: (uint32) wraps the same in every tile */
    const uint32_t ox = (uint32_t)(uint64_t)f->texel_offset_x, oy = (uint32_t)(uint64_t)f->texel_offset_y;
    /* no asphalt under one opaque fill (rs__styling.fill_opaque; layers,
     * p->all, show the surface bare) */
    const rs__styling *st = s->grid ? s->grid->styling : NULL;
    const int skip_whole = st && st->fill_opaque;
    for (uint32_t r = 0; r < p->rows; r++)
        asphalt_row(p->x0 + ox, p->y0 + r + oy, p->q + (size_t)r * p->w, p->all, skip_whole, p->w,
                    p->sc + (size_t)r * p->w * 3, p->w);
}
