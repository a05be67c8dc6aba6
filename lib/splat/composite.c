/* Composite stage (rgba and weight point at the piece's first pixel): C = a*T + (1-a)*S per pixel (seed 000, formula 4) with
 * a = 1 - R; pure terrain and pure road pixels take one colour, no blend.
 *
 * Casings of one colour (p->cas, lib/splat/overlays.c) are blended into T here
 * first: T' = T + (K - T) b with b = alpha_K min(1, (min(C, 1) - R) / (1 - R))
 * where the casing field's coverage C exceeds R < 1 (else b = 0): the
 * composite then shows T' over 1 - R of the pixel, so the casing takes
 * C - R of it (docs/linesym.md, "Casings").
 *
 * T and S are planar per piece row (lib/splat/splatter.h). With SSE2 four pixels
 * at a time without branches: the blend for every pixel, then the pure
 * colours selected by mask, the same double arithmetic and rounding as the
 * scalar loop (which does the rest of a row and all of it without SSE2);
 * four pure pixels in a row skip the blend. */
#include "splatter.h"

#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

static uint8_t to_byte(double v)
{
    /* NaN, negative and large values all land in 0..255 */
    return (uint8_t)(v >= 0 ? (v >= 255 ? 255 : v + 0.5) : 0);
}

#if defined(__SSE2__)
/* Four pixels of the planar colour at src (planes w apart) as RGBA8 with
 * A = 255: in float, four at a time, the same bytes as to_byte in double
 * (checked over all 2^32 floats): from 0.5 up, v + 0.5 is exact or rounds
 * within its integer part, above 255 both clamp; below 0.5 (and NaN) the
 * byte is 0, taken as v = 0 (the float sum would round 0.49999997 + 0.5 up
 * to 1). */
static __m128i pack4(const float *src, size_t w)
{
    const __m128 halff = _mm_set1_ps(0.5f), zerof = _mm_setzero_ps(), topf = _mm_set1_ps(255.0f);
    __m128i px = _mm_set1_epi32((int)0xFF000000u);
    for (int ch = 0; ch < 3; ch++) {
        __m128 v = _mm_loadu_ps(src + ch * w);
        v = _mm_and_ps(_mm_cmpge_ps(v, halff), v);
        v = _mm_min_ps(_mm_max_ps(_mm_add_ps(v, halff), zerof), topf);
        px = _mm_or_si128(px, _mm_slli_epi32(_mm_cvttps_epi32(v), 8 * ch));
    }
    return px;
}
#endif

/* A row of w pixels of planar colour (3 planes of w floats) as RGBA8, A = 255. */
static void row_bytes(const float *src, size_t w, uint8_t *out)
{
    size_t k = 0;
#if defined(__SSE2__)
    for (; k + 4 <= w; k += 4) _mm_storeu_si128((__m128i *)(void *)(out + 4 * k), pack4(src + k, w));
#endif
    for (; k < w; k++) {
        for (size_t ch = 0; ch < 3; ch++) out[4 * k + ch] = to_byte(src[ch * w + k]);
        out[4 * k + 3] = 255;
    }
}

#ifdef RS_AVX512_DISPATCH
/* pack4 for eight pixels */
RS_AVX512 static __m256i pack8(const float *src, size_t w)
{
    const __m256 halff = _mm256_set1_ps(0.5f), zerof = _mm256_setzero_ps(), topf = _mm256_set1_ps(255.0f);
    __m256i px = _mm256_set1_epi32((int)0xFF000000u);
    for (int ch = 0; ch < 3; ch++) {
        __m256 v = _mm256_loadu_ps(src + ch * w);
        v = _mm256_and_ps(_mm256_cmp_ps(v, halff, _CMP_GE_OS), v);
        v = _mm256_min_ps(_mm256_max_ps(_mm256_add_ps(v, halff), zerof), topf);
        px = _mm256_or_si256(px, _mm256_slli_epi32(_mm256_cvttps_epi32(v), 8 * ch));
    }
    return px;
}

/* The composite of one row's pixels [0, k) eight at a time where the CPU
 * has AVX-512 (splatter.h), as the SSE2 loop does them four at a time (the
 * same operations on each pixel, so the same bytes); returns k, a multiple
 * of 8. */
RS_AVX512 static size_t composite_row8(const rs__piece *p, const uint16_t *q, const float *tc, const float *sc,
                                       const double *cas, const double *cov, uint8_t *out)
{
    const size_t w = p->w;
    const __m512d one = _mm512_set1_pd(1.0), half = _mm512_set1_pd(0.5), zero = _mm512_setzero_pd(),
                  top = _mm512_set1_pd(255.0), full = _mm512_set1_pd(65535.0), ka = _mm512_set1_pd(p->cas_rgba[3]);
    size_t k = 0;
    for (; k + 8 <= w; k += 8) {
        __m128i q8 = _mm_loadu_si128((const __m128i *)(const void *)(q + k));
        const int allroad = _mm_movemask_epi8(_mm_cmpeq_epi16(q8, _mm_set1_epi16(-1))) == 0xFFFF;
        const int allterr = _mm_movemask_epi8(_mm_cmpeq_epi16(q8, _mm_setzero_si128())) == 0xFFFF;
        /* casing shares b (zero without casings and where C <= R or R = 1) */
        __m512d cb = zero;
        __mmask8 mc = 0;
        if (cas && !allroad) {
            __m512d c = _mm512_loadu_pd(cas + k), rw = _mm512_loadu_pd(cov + k);
            mc = _mm512_cmp_pd_mask(c, rw, _CMP_GT_OS) & _mm512_cmp_pd_mask(rw, one, _CMP_LT_OS);
            if (mc) {
                __m512d b = _mm512_div_pd(_mm512_sub_pd(_mm512_min_pd(c, one), rw), _mm512_sub_pd(one, rw));
                cb = _mm512_maskz_mov_pd(mc, _mm512_mul_pd(_mm512_min_pd(b, one), ka));
            }
        }
        if (!mc && (allterr || allroad)) {
            /* eight pure terrain or eight pure road pixels: one colour */
            _mm256_storeu_si256((__m256i *)(void *)(out + 4 * k), pack8((allroad ? sc : tc) + k, w));
            continue;
        }
        __m512d qv = _mm512_cvtepi32_pd(_mm256_cvtepu16_epi32(q8));
        __m512d rr = _mm512_div_pd(qv, full), ir = _mm512_sub_pd(one, rr);
        __mmask8 m0 = _mm512_cmp_pd_mask(qv, zero, _CMP_EQ_OQ), m1 = _mm512_cmp_pd_mask(qv, full, _CMP_EQ_OQ);
        __m256i px = _mm256_set1_epi32((int)0xFF000000u);
        for (int ch = 0; ch < 3; ch++) {
            __m512d t = _mm512_cvtps_pd(_mm256_loadu_ps(tc + ch * w + k));
            __m512d s = _mm512_cvtps_pd(_mm256_loadu_ps(sc + ch * w + k));
            if (mc) t = _mm512_add_pd(t, _mm512_mul_pd(_mm512_sub_pd(_mm512_set1_pd(p->cas_rgba[ch]), t), cb));
            __m512d v = _mm512_add_pd(_mm512_mul_pd(ir, t), _mm512_mul_pd(rr, s));
            v = _mm512_mask_mov_pd(v, m0, t);
            v = _mm512_mask_mov_pd(v, m1, s);
            /* to_byte: max returns its second operand (0) for NaN */
            v = _mm512_min_pd(_mm512_max_pd(_mm512_add_pd(v, half), zero), top);
            px = _mm256_or_si256(px, _mm256_slli_epi32(_mm512_cvttpd_epi32(v), 8 * ch));
        }
        _mm256_storeu_si256((__m256i *)(void *)(out + 4 * k), px);
    }
    return k;
}
#endif

#ifdef RS_AVX2_DISPATCH
/* composite_row8's four-lane form where the CPU has AVX2 but not AVX-512
 * (the SSE2 loop's operations on each pixel, so the same bytes; pure
 * groups by pack4, as there); returns k, a multiple of 4. */
RS_AVX2 static size_t composite_row4(const rs__piece *p, const uint16_t *q, const float *tc, const float *sc,
                                     const double *cas, const double *cov, uint8_t *out)
{
    const size_t w = p->w;
    const __m256d one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5), zero = _mm256_setzero_pd(),
                  top = _mm256_set1_pd(255.0), full = _mm256_set1_pd(65535.0), ka = _mm256_set1_pd(p->cas_rgba[3]);
    size_t k = 0;
    for (; k + 4 <= w; k += 4) {
        uint64_t q4;
        memcpy(&q4, q + k, sizeof q4);
        /* casing shares b (zero without casings and where C <= R or R = 1) */
        __m256d cb = zero;
        int mc = 0;
        if (cas && q4 != UINT64_MAX) {
            __m256d c = _mm256_loadu_pd(cas + k), rw = _mm256_loadu_pd(cov + k);
            __m256d m = _mm256_and_pd(_mm256_cmp_pd(c, rw, _CMP_GT_OS), _mm256_cmp_pd(rw, one, _CMP_LT_OS));
            mc = _mm256_movemask_pd(m);
            if (mc) {
                /* lanes outside m may divide by zero: masked off */
                __m256d b = _mm256_div_pd(_mm256_sub_pd(_mm256_min_pd(c, one), rw), _mm256_sub_pd(one, rw));
                cb = _mm256_and_pd(m, _mm256_mul_pd(_mm256_min_pd(b, one), ka));
            }
        }
        if (!mc && (q4 == 0 || q4 == UINT64_MAX)) {
            /* four pure terrain or four pure road pixels: one colour */
            _mm_storeu_si128((__m128i *)(void *)(out + 4 * k), pack4((q4 ? sc : tc) + k, w));
            continue;
        }
        __m256d qv = _mm256_cvtepi32_pd(_mm_cvtepu16_epi32(_mm_loadl_epi64((const __m128i *)(const void *)(q + k))));
        __m256d rr = _mm256_div_pd(qv, full), ir = _mm256_sub_pd(one, rr);
        __m256d m0 = _mm256_cmp_pd(qv, zero, _CMP_EQ_OQ), m1 = _mm256_cmp_pd(qv, full, _CMP_EQ_OQ);
        __m128i px = _mm_set1_epi32((int)0xFF000000u);
        for (int ch = 0; ch < 3; ch++) {
            __m256d t = _mm256_cvtps_pd(_mm_loadu_ps(tc + ch * w + k));
            __m256d s = _mm256_cvtps_pd(_mm_loadu_ps(sc + ch * w + k));
            if (mc) t = _mm256_add_pd(t, _mm256_mul_pd(_mm256_sub_pd(_mm256_set1_pd(p->cas_rgba[ch]), t), cb));
            __m256d v = _mm256_add_pd(_mm256_mul_pd(ir, t), _mm256_mul_pd(rr, s));
            v = _mm256_blendv_pd(v, t, m0);
            v = _mm256_blendv_pd(v, s, m1);
            /* to_byte: max returns its second operand (0) for NaN */
            v = _mm256_min_pd(_mm256_max_pd(_mm256_add_pd(v, half), zero), top);
            px = _mm_or_si128(px, _mm_slli_epi32(_mm256_cvttpd_epi32(v), 8 * ch));
        }
        _mm_storeu_si128((__m128i *)(void *)(out + 4 * k), px);
    }
    return k;
}
#endif

/* The casing share b of one pixel (scalar; see above). */
static double casing_share(double c, double r, double alpha)
{
    if (!(c > r && r < 1)) return 0;
    double b = ((c > 1 ? 1 : c) - r) / (1 - r);
    return (b > 1 ? 1 : b) * alpha;
}

void rs__composite(const rs__piece *p, uint8_t *rgba, size_t rgba_stride, uint16_t *weight, size_t weight_stride)
{
    const size_t w = p->w;
#ifdef RS_AVX512_DISPATCH
    const int wide = rs__avx512_ok();
#endif
#ifdef RS_AVX2_DISPATCH
    const int wide4 = !wide && rs__avx2_ok();
#endif
    for (uint32_t r = 0; r < p->rows; r++) {
        const uint16_t *q = p->q + (size_t)r * w;
        const float *tc = p->tc + (size_t)r * w * 3, *sc = p->sc + (size_t)r * w * 3;
        const double *cas = p->cas ? p->cas + (size_t)r * w : NULL, *cov = p->cov + (size_t)r * w;
        uint8_t *out = rgba + (size_t)r * rgba_stride;
        size_t k = 0;
#ifdef RS_AVX512_DISPATCH
        if (wide) k = composite_row8(p, q, tc, sc, cas, cov, out);
#endif
#ifdef RS_AVX2_DISPATCH
        if (wide4) k = composite_row4(p, q, tc, sc, cas, cov, out);
#endif
#if defined(__SSE2__)
        const __m128d one = _mm_set1_pd(1.0), half = _mm_set1_pd(0.5), zero = _mm_setzero_pd(),
                      top = _mm_set1_pd(255.0), full = _mm_set1_pd(65535.0), ka = _mm_set1_pd(p->cas_rgba[3]);
        for (; k + 4 <= w; k += 4) {
            uint64_t q4;
            memcpy(&q4, q + k, sizeof q4);
            /* casing shares b (zero without casings) */
            __m128d cb[2] = { zero, zero };
            int anyc = 0;
            __m128d c4[2];
            if (cas && q4 != UINT64_MAX &&
                (c4[0] = _mm_loadu_pd(cas + k), c4[1] = _mm_loadu_pd(cas + k + 2),
                 _mm_movemask_pd(_mm_cmpneq_pd(_mm_or_pd(c4[0], c4[1]), zero)))) {
                /* some C != 0 (most pixels have none) */
                for (int h = 0; h < 2; h++) {
                    __m128d c = c4[h], rw = _mm_loadu_pd(cov + k + 2 * h);
                    __m128d m = _mm_and_pd(_mm_cmpgt_pd(c, rw), _mm_cmplt_pd(rw, one));
                    /* lanes outside m may divide by zero: masked off (b = 0
                     * leaves T as it is: T + (K - T) 0 = T) */
                    __m128d b = _mm_div_pd(_mm_sub_pd(_mm_min_pd(c, one), rw), _mm_sub_pd(one, rw));
                    cb[h] = _mm_and_pd(m, _mm_mul_pd(_mm_min_pd(b, one), ka));
                }
                anyc = 1;
            }
            if ((q4 == 0 && !anyc) || q4 == UINT64_MAX) {
                /* four pure terrain or four pure road pixels: one colour */
                _mm_storeu_si128((__m128i *)(void *)(out + 4 * k), pack4((q4 ? sc : tc) + k, w));
                continue;
            }
            __m128d qv[2] = { _mm_set_pd(q[k + 1], q[k]), _mm_set_pd(q[k + 3], q[k + 2]) };
            __m128d rr[2], ir[2], m0[2], m1[2];
            for (int h = 0; h < 2; h++) {
                rr[h] = _mm_div_pd(qv[h], full);
                ir[h] = _mm_sub_pd(one, rr[h]);
                m0[h] = _mm_cmpeq_pd(qv[h], zero);
                m1[h] = _mm_cmpeq_pd(qv[h], full);
            }
            __m128i px = _mm_set1_epi32((int)0xFF000000u);
            for (int ch = 0; ch < 3; ch++) {
                __m128i c[2];
                const __m128d kc = _mm_set1_pd(p->cas_rgba[ch]);
                for (int h = 0; h < 2; h++) {
                    const float *tp = tc + ch * w + k + 2 * h, *sp = sc + ch * w + k + 2 * h;
                    __m128d t = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(const void *)tp)));
                    __m128d s = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64((const __m128i *)(const void *)sp)));
                    if (anyc) t = _mm_add_pd(t, _mm_mul_pd(_mm_sub_pd(kc, t), cb[h]));
                    __m128d v = _mm_add_pd(_mm_mul_pd(ir[h], t), _mm_mul_pd(rr[h], s));
                    v = _mm_or_pd(_mm_and_pd(m0[h], t), _mm_andnot_pd(m0[h], v));
                    v = _mm_or_pd(_mm_and_pd(m1[h], s), _mm_andnot_pd(m1[h], v));
                    /* to_byte: max returns its second operand (0) for NaN */
                    v = _mm_min_pd(_mm_max_pd(_mm_add_pd(v, half), zero), top);
                    c[h] = _mm_cvttpd_epi32(v);
                }
                px = _mm_or_si128(px, _mm_slli_epi32(_mm_unpacklo_epi64(c[0], c[1]), 8 * ch));
            }
            _mm_storeu_si128((__m128i *)(void *)(out + 4 * k), px);
        }
#endif
        for (; k < w; k++) {
            uint32_t qq = q[k];
            double rr = qq / 65535.0, b = cas && qq != 65535u ? casing_share(cas[k], cov[k], p->cas_rgba[3]) : 0;
            for (size_t ch = 0; ch < 3; ch++) {
                double t = tc[ch * w + k], s = sc[ch * w + k];
                if (b > 0) t += (p->cas_rgba[ch] - t) * b;
                double v = qq == 0 ? t : (qq == 65535u ? s : (1 - rr) * t + rr * s);
                out[4 * k + ch] = to_byte(v);
            }
            out[4 * k + 3] = 255;
        }
        if (weight) memcpy(weight + (size_t)r * weight_stride, q, w * sizeof *q);
    }
}

/* Layers (rs_splat_layers_window; docs/embedding.md "Layers"). A layer's
 * bytes are rounded as the composite rounds (to_byte); the premultiplied
 * planes over another (casing over terrain, paint over surface) take up
 * that plane's rounding: alpha a8 first, then the colour byte that brings
 * under * (1 - a8/255) + colour nearest to the true blend, so each blend
 * recomposes within half a level plus the alpha's clamp (docs). */
static uint8_t premul_byte(double truth, double under8, uint8_t a8)
{
    double v = truth - under8 * (1 - a8 / 255.0);
    uint8_t c = to_byte(v);
    return c > a8 ? a8 : c;
}

static uint8_t *plane_at(uint8_t *base, size_t stride, size_t bpp, uint32_t r, uint32_t ax, uint32_t ay)
{
    return base + (size_t)(ay + r) * stride + (size_t)ax * bpp;
}

void rs__layers_surface(const rs__piece *p, const rs_splat_layers *L, uint32_t ax, uint32_t ay)
{
    const size_t w = p->w;
    for (uint32_t r = 0; r < p->rows; r++) {
        row_bytes(p->sc + (size_t)r * w * 3, w, plane_at(L->surface, L->surface_stride, 4, r, ax, ay));
    }
}

void rs__layers_ground(const rs__piece *p, const rs_splat_layers *L, uint32_t ax, uint32_t ay)
{
    const size_t w = p->w;
    if (L->surface && !L->surface_unstyled) rs__layers_surface(p, L, ax, ay);
    for (uint32_t r = 0; r < p->rows; r++) {
        const uint16_t *q = p->q + (size_t)r * w;
        const float *tc = p->tc + (size_t)r * w * 3;
        if (L->coverage) memcpy(L->coverage + (size_t)(ay + r) * L->coverage_stride + ax, q, w * sizeof *q);
        if (L->terrain) row_bytes(tc, w, plane_at(L->terrain, L->terrain_stride, 4, r, ax, ay));
        if (!L->casing) continue;
        uint8_t *o = plane_at(L->casing, L->casing_stride, 4, r, ax, ay);
        const double *cas = p->cas ? p->cas + (size_t)r * w : NULL, *cov = p->cov + (size_t)r * w;
        const float *lc = p->lcas ? p->lcas + (size_t)r * w * 4 : NULL;
        if (!cas && !lc) {
            memset(o, 0, w * 4);
            continue;
        }
        for (size_t k = 0; k < w; k++) {
            /* the casing's alpha and the ground T' the composite shows
             * (none under a whole road pixel, as the composite) */
            double a = 0, g[3];
            if (q[k] != 65535u && cas) {
                a = casing_share(cas[k], cov[k], p->cas_rgba[3]);
                for (size_t ch = 0; ch < 3; ch++) {
                    double t = tc[ch * w + k];
                    g[ch] = t + (p->cas_rgba[ch] - t) * a;
                }
            } else if (q[k] != 65535u && lc && lc[3 * w + k] > 0) {
                a = lc[3 * w + k];
                for (size_t ch = 0; ch < 3; ch++) g[ch] = tc[ch * w + k] * (1.0f - lc[3 * w + k]) + lc[ch * w + k];
            }
            uint8_t a8 = to_byte(a * 255);
            if (!(a > 0)) {
                memset(o + 4 * k, 0, 4);
                continue;
            }
            for (size_t ch = 0; ch < 3; ch++) o[4 * k + ch] = premul_byte(g[ch], to_byte(tc[ch * w + k]), a8);
            o[4 * k + 3] = a8;
        }
    }
}

void rs__layers_paint(const rs__piece *p, const rs_splat_layers *L, uint32_t ax, uint32_t ay, const float *p0,
                      const float *p1)
{
    const size_t w = p->w;
    for (uint32_t r = 0; r < p->rows; r++) {
        const uint16_t *q = p->q + (size_t)r * w;
        const float *sc = p->sc + (size_t)r * w * 3, *z = p0 + (size_t)r * w * 3, *o1 = p1 + (size_t)r * w * 3;
        uint8_t *o = plane_at(L->paint, L->paint_stride, 4, r, ax, ay);
        for (size_t k = 0; k < w; k++) {
            /* painted over 0: the premultiplied colour; over 1: plus the
             * transmittance (one per pixel: each layer blends all channels
             * by one alpha; the mean of the three roundings) */
            double tr = 0;
            if (q[k] != 0)
                for (size_t ch = 0; ch < 3; ch++) tr += (double)o1[ch * w + k] - z[ch * w + k];
            tr /= 3;
            double a = 1 - tr;
            if (q[k] == 0 || !(a > 0)) {
                memset(o + 4 * k, 0, 4);
                continue;
            }
            uint8_t a8 = to_byte(a * 255);
            for (size_t ch = 0; ch < 3; ch++) {
                double s = sc[ch * w + k];
                o[4 * k + ch] = premul_byte(s * tr + z[ch * w + k], to_byte(s), a8);
            }
            o[4 * k + 3] = a8;
        }
    }
}
