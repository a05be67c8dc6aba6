/* Coverage stage, analytic edges: the exact fraction of each pixel inside
 * the union of the road buffers, from the road field (lib/roadfield.c). */
#include "splatter.h"
#include "roadfield.h"
#include "styling.h"

void rs__coverage_analytic(const rs_splatter *s, rs__piece *p)
{
    /* casings from the grid's field widened: their coverage C into ov in
     * the same pass (the overlays stage reads it there) */
    const rs__styling *st = s->grid->styling;
    const rs__roadfield *g = st && st->casing_merged ? st->casing : NULL;
    rs__roadfield_coverage2(s->grid->field, g, p->x0, p->y0, p->w, p->rows, s->texel_m, p->cov, p->ov, p->w);
}

/* Shared end of both coverage modes: R to 16 bits, the value the weight
 * output holds and the later stages test (0: no road work, 65535: no
 * terrain work). */
void rs__coverage_quantise(rs__piece *p)
{
    size_t n = (size_t)p->rows * p->w;
    uint64_t road = 0;
    for (size_t i = 0; i < n; i++) {
        double rw = p->cov[i];
        uint32_t q = rw <= 0 ? 0 : (rw >= 1 ? 65535u : (uint32_t)(rw * 65535.0 + 0.5));
        p->q[i] = (uint16_t)q;
        road += q != 0;
    }
    p->road_pixels = road;
}
