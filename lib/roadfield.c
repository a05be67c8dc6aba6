/* Placeholder until the road-field branch lands. */
#include "roadfield.h"

rs_result rs__roadfield_build(rs_ctx *ctx, const rs_roads *roads, const rs__roadfield_params *p, rs__roadfield **out)
{
    (void)roads; (void)p;
    *out = NULL;
    return rs__fail(ctx, RS_ERR_UNSUPPORTED, "analytic edges are not built yet");
}
void rs__roadfield_free(rs_ctx *ctx, rs__roadfield *f) { (void)ctx; (void)f; }
size_t rs__roadfield_bytes(const rs__roadfield *f) { (void)f; return 0; }
int rs__roadfield_nearest(const rs__roadfield *f, double x, double y, double reach, rs__road_point *out)
{
    (void)f; (void)x; (void)y; (void)reach; (void)out;
    return 0;
}
void rs__roadfield_coverage(const rs__roadfield *f, uint32_t px0, uint32_t py0, uint32_t w, uint32_t h, double pix,
                            double *out, size_t stride)
{
    (void)f; (void)px0; (void)py0; (void)pix;
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) out[(size_t)y * stride + x] = 0;
}
