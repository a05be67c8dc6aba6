/* Composite stage (rgba and weight point at the piece's first pixel): C = a*T + (1-a)*S per pixel (seed 000, formula 4) with
 * a = 1 - R; pure terrain and pure road pixels take one colour, no blend. */
#include "splatter.h"

static uint8_t to_byte(double v)
{
    /* NaN, negative and large values all land in 0..255 */
    return (uint8_t)(v >= 0 ? (v >= 255 ? 255 : v + 0.5) : 0);
}

void rs__composite(const rs__piece *p, uint8_t *rgba, size_t rgba_stride, uint16_t *weight, size_t weight_stride)
{
    for (uint32_t r = 0; r < p->rows; r++) {
        const uint16_t *q = p->q + (size_t)r * p->w;
        const float *tc = p->tc + (size_t)r * p->w * 3, *sc = p->sc + (size_t)r * p->w * 3;
        uint8_t *out = rgba + (size_t)r * rgba_stride;
        for (uint32_t k = 0; k < p->w; k++) {
            uint32_t qq = q[k];
            double rr = qq / 65535.0;
            for (int ch = 0; ch < 3; ch++) {
                double v = qq == 0 ? tc[3 * k + ch]
                                   : (qq == 65535u ? sc[3 * k + ch] : (1 - rr) * tc[3 * k + ch] + rr * sc[3 * k + ch]);
                out[4 * k + ch] = to_byte(v);
            }
            out[4 * k + 3] = 255;
        }
        if (weight) {
            uint16_t *wrow = weight + (size_t)r * weight_stride;
            for (uint32_t k = 0; k < p->w; k++) wrow[k] = q[k];
        }
    }
}
