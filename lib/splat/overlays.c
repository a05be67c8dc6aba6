/* Overlays stage: road styles drawn between the surface and the composite
 * (issue 13; docs/linesym.md "In the splat"), in layer order: casings onto
 * the terrain colour T (under every road surface, so the composite's road
 * weight covers them wherever a road is), fill and gradient surfaces onto
 * the road colour S, then the line symbols onto S. Markings (issue 14)
 * come next, onto S (SPEC: markings are composited onto S). */
#include "splatter.h"
#include "linesym.h"
#include "roadfield.h"
#include "styling.h"
#include "markings.h"

#include <math.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#define HALF_SQRT2 0.70710678118654752440

/* Casing colour into terrain pixel k of row r (share of the pixel > 0),
 * casings of several colours (one colour: the composite blends it). */
static void casing_pixel(const rs__styling *st, double pix, const rs__piece *p, uint32_t r, size_t k, double c,
                         double R)
{
    /* The composite shows T' over 1 - R of the pixel; the casing's own
     * share of the pixel is C - R (the casing field holds the roads), so
     * T' takes (C - R) / (1 - R) of casing colour. */
    double share = ((c > 1 ? 1 : c) - R) / (1 - R);
    if (!(share > 0)) return;
    /* the colour of the nearest road with a casing: C - R > 0 is its band
     * (with alpha-map edges the field holds the cased roads alone). Until
     * 3 December 2026 the nearest road of any kind: where an uncased road's
     * end met a cased one, the pixel lost the casing the one-colour blend
     * gives it (fuzz/edits) */
    rs__road_point rp;
    double x = ((double)p->x0 + (double)k + 0.5) * pix, y = ((double)p->y0 + (double)r + 0.5) * pix;
    if (!(st->casing_road ? rs__roadfield_nearest(st->casing, x, y, pix * HALF_SQRT2, &rp)
                          : rs__roadfield_nearest_of(st->casing, x, y, pix * HALF_SQRT2, st->casing_width, &rp)))
        return;
    const float *col = st->colour + 16 * (size_t)(st->casing_road ? st->casing_road[rp.road] : rp.road) + 12;
    float a = (float)(share > 1 ? 1 : share) * col[3], *tc = p->tc + (size_t)r * p->w * 3;
    if (p->lcas) {
        /* layers: premultiplied, T left bare (T' = T (1 - a) + col a) */
        float *lc = p->lcas + (size_t)r * p->w * 4 + k;
        for (int ch = 0; ch < 3; ch++) lc[(size_t)ch * p->w] = col[ch] * a;
        lc[3 * (size_t)p->w] = a;
        return;
    }
    for (int ch = 0; ch < 3; ch++) {
        float *v = tc + (size_t)ch * p->w + k;
        *v = *v * (1.0f - a) + col[ch] * a;
    }
}

static void casings(const rs_splatter *s, const rs__styling *st, double pix, rs__piece *p)
{
    const size_t w = p->w;
    /* the analytic coverage stage has C in ov already when merged */
    if (!(st->casing_merged && s->o.coverage.edges == RS_EDGES_ANALYTIC))
        rs__roadfield_coverage(st->casing, p->x0, p->y0, p->w, p->rows, pix, p->ov, w);
    if (st->casing_uniform) {
        /* one colour: the composite blends it (lib/splat/composite.c) */
        p->cas = p->ov;
        memcpy(p->cas_rgba, st->casing_rgba, sizeof p->cas_rgba);
        return;
    }
    for (uint32_t r = 0; r < p->rows; r++) {
        const double *cr = p->ov + (size_t)r * w, *rr = p->cov + (size_t)r * w;
        size_t k = 0;
        /* casing pixels are few: C > R and R < 1 (a whole road pixel shows
         * no terrain, hence no casing); two at a time to skip the rest */
#if defined(__SSE2__)
        const __m128d one = _mm_set1_pd(1);
        for (; k + 1 < w; k += 2) {
            __m128d c = _mm_loadu_pd(cr + k), R = _mm_loadu_pd(rr + k);
            int m = _mm_movemask_pd(_mm_and_pd(_mm_cmpgt_pd(c, R), _mm_cmplt_pd(R, one)));
            if (!m) continue;
            if (m & 1) casing_pixel(st, pix, p, r, k, cr[k], rr[k]);
            if (m & 2) casing_pixel(st, pix, p, r, k + 1, cr[k + 1], rr[k + 1]);
        }
#endif
        for (; k < w; k++)
            if (cr[k] > rr[k] && rr[k] < 1) casing_pixel(st, pix, p, r, k, cr[k], rr[k]);
    }
}

/* surfaces() for one fill on every road where q > 0 means a road is near
 * (q_means_near): every road pixel takes the fill, the same floats as the
 * pixel loop below (the blend, or the fill itself on a whole road pixel
 * when it is opaque), four pixels a step with SSE2. */
static void fill_uniform_rows(const rs__styling *st, rs__piece *p)
{
    const size_t w = p->w;
    const float *c = st->fill_rgba;
    const float a = c[3], ka = 1.0f - a;
    for (uint32_t r = 0; r < p->rows; r++) {
        float *sc = p->sc + (size_t)r * w * 3;
        const uint16_t *q = p->q + (size_t)r * w;
        size_t k = 0;
#if defined(__SSE2__)
        const __m128i zero = _mm_setzero_si128(), all = _mm_set1_epi32(65535);
        const __m128 va = _mm_set1_ps(a), vka = _mm_set1_ps(ka);
        for (; k + 4 <= w; k += 4) {
            __m128i q4 = _mm_unpacklo_epi16(_mm_loadl_epi64((const __m128i *)(const void *)(q + k)), zero);
            __m128 road = _mm_castsi128_ps(_mm_cmpgt_epi32(q4, zero)); /* q > 0 */
            if (!_mm_movemask_ps(road)) continue;
            __m128 whole = st->fill_opaque ? _mm_castsi128_ps(_mm_cmpeq_epi32(q4, all)) : _mm_setzero_ps();
            for (int ch = 0; ch < 3; ch++) {
                float *v = sc + (size_t)ch * w + k;
                __m128 old = _mm_loadu_ps(v), col = _mm_set1_ps(c[ch]);
                __m128 blend = _mm_add_ps(_mm_mul_ps(old, vka), _mm_mul_ps(col, va));
                __m128 nv = _mm_or_ps(_mm_and_ps(whole, col), _mm_andnot_ps(whole, blend));
                _mm_storeu_ps(v, _mm_or_ps(_mm_and_ps(road, nv), _mm_andnot_ps(road, old)));
            }
        }
#endif
        for (; k < w; k++) {
            if (q[k] == 0) continue;
            for (int ch = 0; ch < 3; ch++) {
                float *v = sc + (size_t)ch * w + k;
                *v = q[k] == 65535 && st->fill_opaque ? c[ch] : *v * ka + c[ch] * a;
            }
        }
    }
}

/* q_means_near: R is the analytic coverage of st->near's own roads (the
 * grid's field, or the same field indexed for these pixels), so a pixel
 * with q > 0 has a road surface within its half diagonal: it takes 0.5 /
 * 65535 of its area or more from a road shape only if that shape reaches
 * into its square (by far more than the roundings; docs/linesym.md,
 * tests/test_roadfield.c test_weight_implies_near). */
static void surfaces(const rs__styling *st, double pix, rs__piece *p, int q_means_near)
{
    const size_t w = p->w;
    if (st->fill_uniform && q_means_near) {
        fill_uniform_rows(st, p);
        return;
    }
    uint32_t hint = UINT32_MAX; /* the segment the last lookup found */
    for (uint32_t r = 0; r < p->rows; r++) {
        float *sc = p->sc + (size_t)r * w * 3;
        for (size_t k = 0; k < w; k++) {
            uint16_t q = p->q[(size_t)r * w + k];
            if (q == 0) continue;
            if (q == 65535 && st->fill_opaque) {
                /* its colour (what the blend below gives over any finite
                 * colour): rs__surface made no asphalt there (but for the
                 * layers, p->all) */
                for (int ch = 0; ch < 3; ch++) sc[(size_t)ch * w + k] = st->fill_rgba[ch];
                continue;
            }
            double x = ((double)p->x0 + (double)k + 0.5) * pix, y = ((double)p->y0 + (double)r + 0.5) * pix;
            float c[4];
            if (st->fill_uniform) {
                /* every road has this fill: which road the lookup below
                 * finds does not matter, only whether it finds one (it
                 * does on a whole road pixel; with q_means_near on every
                 * road pixel: fill_uniform_rows) */
                if (q != 65535 && !rs__roadfield_any_near_hint(st->near, x, y, pix * HALF_SQRT2, &hint)) continue;
                memcpy(c, st->fill_rgba, sizeof c);
            } else {
                rs__road_point rp;
                if (!rs__roadfield_nearest_ranked(st->near, x, y, pix * HALF_SQRT2, st->prio, &rp)) continue;
                /* the surface image replaces the base surface, blended by its
                 * alpha (premultiplied); fill or gradient go on top */
                double im[4];
                if (rs__styling_image(st, rp.road, rp.s, rp.t, im))
                    for (int ch = 0; ch < 3; ch++) {
                        float *v = sc + (size_t)ch * w + k;
                        *v = (float)(*v * (1 - im[3]) + im[ch]);
                    }
                uint8_t kind = st->surface[rp.road];
                if (kind == RS_SURFACE_DEFAULT) continue;
                const float *col = st->colour + 16 * (size_t)rp.road;
                if (kind == RS_SURFACE_GRADIENT) {
                    double hw = st->half_width[rp.road], f = hw > 0 ? fabs(rp.t) / hw : 1;
                    float g = (float)(f > 1 ? 1 : f);
                    for (int ch = 0; ch < 4; ch++) c[ch] = col[4 + ch] + (col[8 + ch] - col[4 + ch]) * g;
                } else {
                    for (int ch = 0; ch < 4; ch++) c[ch] = col[ch];
                }
            }
            for (int ch = 0; ch < 3; ch++) {
                float *v = sc + (size_t)ch * w + k;
                *v = *v * (1.0f - c[3]) + c[ch] * c[3];
            }
        }
    }
}

/* Bridges' casings over the roads below them (rs__deck; docs/network.md
 * "Bridges and layers"). In a pixel the deck's casing band is C - H (its
 * widened shapes less the surfaces of its level and above) and the roads
 * below hold R - H. The band's part over them, min(C - H, R - H), goes
 * onto the road colour S, which the composite shows over R of the pixel,
 * where a road below is near and the nearest is not of the casing's
 * stroke; after the lines and markings (they lie under the deck's edge).
 * Over terrain the casing is casings()'s, as for any road. Rows and
 * columns near each deck's shapes only; C and H into the line symbols'
 * scratch (free once they are painted). */
static void decks(const rs__styling *st, double pix, const rs__piece *p, float *rgb)
{
    const size_t w = p->w;
    double *C = p->ls, *H = p->ls + w; /* (rs__linesym_scratch_len(w) >= 2 w) */
    for (size_t d = 0; d < st->ndeck; d++) {
        const rs__deck *D = &st->deck[d];
        /* the piece's pixels whose squares can meet the deck's shapes */
        double ka = floor(D->box[0] / pix) - 1 - (double)p->x0, kb = floor(D->box[1] / pix) + 2 - (double)p->x0;
        double ra = floor(D->box[2] / pix) - 1 - (double)p->y0, rb = floor(D->box[3] / pix) + 2 - (double)p->y0;
        ka = ka > 0 ? ka : 0, ra = ra > 0 ? ra : 0;
        kb = kb < (double)w ? kb : (double)w, rb = rb < (double)p->rows ? rb : (double)p->rows;
        if (!(ka < kb && ra < rb)) continue; /* (NaN: no shapes) */
        const uint32_t k0 = (uint32_t)ka, k1 = (uint32_t)kb, n = k1 - k0;
        for (uint32_t r = (uint32_t)ra; r < (uint32_t)rb; r++) {
            const double *R = p->cov + (size_t)r * w;
            float *r0 = rgb + (size_t)r * w * 3, *r1 = r0 + w, *r2 = r1 + w;
            uint32_t k = k0;
            while (k < k1 && !(R[k] > 0)) k++;
            if (k == k1) continue; /* no road on this row here */
            /* (no casing of the deck's reaches this row: bridges scattered
             * over a map make its box the map's) */
            const double yr = ((double)p->y0 + (double)r) * pix;
            if (!rs__roadfield_rows_have(D->casing, yr - pix, yr + 2 * pix)) continue;
            rs__roadfield_coverage(D->casing, p->x0 + k0, p->y0 + r, n, 1, pix, C, n);
            rs__roadfield_coverage(D->hide, p->x0 + k0, p->y0 + r, n, 1, pix, H, n);
            for (; k < k1; k++) {
                double c = C[k - k0] < 1 ? C[k - k0] : 1, h = H[k - k0] < 1 ? H[k - k0] : 1, band = c - h,
                       below = R[k] - h, over = band < below ? band : below;
                if (!(over > 0 && R[k] > 0)) continue;
                rs__road_point rp, under;
                double x = ((double)p->x0 + (double)k + 0.5) * pix, y = ((double)p->y0 + (double)r + 0.5) * pix;
                if (!rs__roadfield_nearest(D->casing, x, y, pix * HALF_SQRT2, &rp)) continue;
                /* only over a road below, and not one of its own stroke
                 * (its casing's cap over the record it continues) */
                int found = D->below_of ? rs__roadfield_nearest_of(D->look, x, y, pix * HALF_SQRT2, D->below_of, &under)
                                        : rs__roadfield_nearest(D->look, x, y, pix * HALF_SQRT2, &under);
                if (!found || D->lstroke[under.road] == D->cstroke[rp.road]) continue;
                const float *col = st->colour + 16 * (size_t)D->road[rp.road] + 12;
                double share = over / R[k];
                float a = (float)(share < 1 ? share : 1) * col[3], ka1 = 1.0f - a;
                r0[k] = r0[k] * ka1 + col[0] * a;
                r1[k] = r1[k] * ka1 + col[1] * a;
                r2[k] = r2[k] * ka1 + col[2] * a;
            }
        }
    }
}

void rs__overlays_casings(const rs_splatter *s, rs__piece *p)
{
    const rs__styling *st = s->grid->styling;
    p->cas = NULL;
    if (p->w == 0 || p->rows == 0) return;
    if (st && st->casing) casings(s, st, s->texel_m, p);
}

void rs__overlays_surfaces(const rs_splatter *s, rs__piece *p)
{
    const rs__styling *st = s->grid->styling;
    if (st && st->any_surface && p->road_pixels && p->w && p->rows)
        surfaces(st, s->texel_m, p, s->o.coverage.edges == RS_EDGES_ANALYTIC && st->near == s->grid->field);
}

void rs__overlays_paint(const rs_splatter *s, rs__piece *p, float *rgb)
{
    const rs__styling *st = s->grid->styling;
    if (!p->road_pixels || p->w == 0 || p->rows == 0) return;
    if (st && st->lines) rs__linesym_paint(st->lines, p->x0, p->y0, p->w, p->rows, rgb, (size_t)p->w * 3, p->ls);
    if (s->grid->markings) {
        /* the markings paint p->sc */
        float *sc = p->sc;
        p->sc = rgb;
        rs__markings_paint(s->grid->markings, p);
        p->sc = sc;
    }
    if (st && st->ndeck) decks(st, s->texel_m, p, rgb);
}

void rs__overlays(const rs_splatter *s, rs__piece *p)
{
    rs__overlays_casings(s, p);
    rs__overlays_surfaces(s, p);
    rs__overlays_paint(s, p, p->sc);
}
