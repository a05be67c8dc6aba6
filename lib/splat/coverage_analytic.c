/* Coverage stage, analytic edges: the exact fraction of each pixel inside
 * the union of the road buffers, from the road field (lib/scene/roadfield.c). */
#include "splatter.h"
#include "roadfield.h"
#include "styling.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

void rs__coverage_analytic(const rs_splatter *s, rs__piece *p)
{
    /* casings from the grid's field widened: their coverage C into ov in
     * the same pass (the overlays stage reads it there) */
    const rs__styling *st = s->grid->styling;
    const rs__roadfield *g = st && st->casing_merged ? st->casing : NULL;
    rs__roadfield_coverage2(s->field, g, p->x0, p->y0, p->w, p->rows, s->texel_m, p->cov, p->ov, p->w);
}

/* Shared end of both coverage modes: R to 16 bits, the value the weight
 * output holds and the later stages test (0: no road work, 65535: no
 * terrain work). Branch-free: R is clamped to [0, 1] (NaN to 0) and
 * rounded, which gives the bytes of the three-way test it replaces
 * (below 0.5/65535 rounds to 0, 1 to 65535) without its mispredicted
 * branches along every road edge. */
void rs__coverage_quantise(rs__piece *p)
{
    const size_t n = (size_t)p->rows * p->w;
    const double *cov = p->cov;
    uint16_t *q = p->q;
    uint64_t road = 0;
    size_t i = 0;
#if defined(__SSE2__)
    const __m128d zero = _mm_setzero_pd(), one = _mm_set1_pd(1.0), scale = _mm_set1_pd(65535.0),
                  half = _mm_set1_pd(0.5);
    const __m128i zi = _mm_setzero_si128();
    for (; i + 4 <= n; i += 4) {
        /* max(x, 0) returns 0 for NaN (its second operand) */
        __m128d a = _mm_min_pd(_mm_max_pd(_mm_loadu_pd(cov + i), zero), one);
        __m128d b = _mm_min_pd(_mm_max_pd(_mm_loadu_pd(cov + i + 2), zero), one);
        __m128i ia = _mm_cvttpd_epi32(_mm_add_pd(_mm_mul_pd(a, scale), half));
        __m128i ib = _mm_cvttpd_epi32(_mm_add_pd(_mm_mul_pd(b, scale), half));
        __m128i v = _mm_unpacklo_epi64(ia, ib); /* four int32 in 0..65535 */
        /* to uint16: shift into int16's range, pack (exact there), shift back */
        const __m128i bias = _mm_set1_epi32(32768);
        __m128i pk = _mm_xor_si128(_mm_packs_epi32(_mm_sub_epi32(v, bias), zi), _mm_set1_epi16((short)0x8000));
        _mm_storel_epi64((__m128i *)(void *)(q + i), pk);
        /* count of the four that are non-zero: a 4-bit mask's popcount */
        unsigned m = (unsigned)_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(v, zi)));
        road += (0x4332322132212110ull >> (4 * m)) & 0xF;
    }
#endif
    for (; i < n; i++) {
        double rw = cov[i];
        rw = rw > 0 ? rw : 0;
        rw = rw < 1 ? rw : 1;
        uint32_t v = (uint32_t)(rw * 65535.0 + 0.5);
        q[i] = (uint16_t)v;
        road += v != 0;
    }
    p->road_pixels = road;
}
