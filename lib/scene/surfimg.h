/* Private: road-aligned surface images (issue 16; docs/surface.md). A
 * style's `surface IMG [length L]` strip is mipmapped once when the grid is
 * built (premultiplied RGBA8 per level, each level the exact area average
 * of the one above: repeats along the image's rows stay seamless) and
 * sampled per pixel by (t, s) with trilinear filtering. */
#ifndef RS_SURFIMG_H
#define RS_SURFIMG_H
#include "internal.h"

#define RS__SURFIMG_MAX_SIDE 65536u
#define RS__SURFIMG_LEVELS 17

typedef struct rs__surfimg {
    uint32_t levels;
    uint32_t w[RS__SURFIMG_LEVELS], h[RS__SURFIMG_LEVELS];
    uint8_t *px[RS__SURFIMG_LEVELS]; /* premultiplied RGBA8, rows tightly packed */
    size_t bytes;
} rs__surfimg;

/* Mipmap a copy of `img` (checked: 1..RS__SURFIMG_MAX_SIDE a side, at most
 * the context's max_texture_pixels). `what` names the image in messages. */
rs_result rs__surfimg_build(rs_ctx *ctx, const rs_image *img, const char *what, rs__surfimg **out);
void rs__surfimg_free(rs_ctx *ctx, rs__surfimg *m);

/* Level of detail for a footprint of `texels` level-0 texels per output
 * pixel: lev = the finer level, f = the weight of the next coarser one. */
void rs__surfimg_lod(const rs__surfimg *m, double texels, uint32_t *lev, double *f);

/* Trilinear sample at u across (0 = the image's left edge, 1 = its right
 * edge; clamped) and v along (in image heights; wraps), levels lev and
 * lev + 1 mixed by f. Premultiplied: rgb 0..255, a 0..1. */
void rs__surfimg_sample(const rs__surfimg *m, double u, double v, uint32_t lev, double f, double out[4]);
#endif
