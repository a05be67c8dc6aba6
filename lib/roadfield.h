/* Private: the road field (lib/roadfield.c). Placeholder interface until the
 * road-field branch lands. */
#ifndef RS_ROADFIELD_H
#define RS_ROADFIELD_H
#include "internal.h"
typedef struct rs__roadfield rs__roadfield;

typedef struct rs__roadfield_params {
    double origin_x, origin_y;
    double cell_size;
    double width_m, height_m;
    double reach_extra;
    double index_cell;
} rs__roadfield_params;

rs_result rs__roadfield_build(rs_ctx *ctx, const rs_roads *roads, const rs__roadfield_params *p, rs__roadfield **out);
void rs__roadfield_free(rs_ctx *ctx, rs__roadfield *f);
size_t rs__roadfield_bytes(const rs__roadfield *f);

typedef struct rs__road_point {
    uint32_t road;
    uint32_t seg;
    double s;
    double t;
    double dist;
    double half_width;
} rs__road_point;
int rs__roadfield_nearest(const rs__roadfield *f, double x, double y, double reach, rs__road_point *out);
void rs__roadfield_coverage(const rs__roadfield *f, uint32_t px0, uint32_t py0, uint32_t w, uint32_t h, double pix,
                            double *out, size_t stride);
#endif
