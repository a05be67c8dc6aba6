/* roadsplat: experimental and test-only functions (issue 30).
 *
 * Exported by the same library as include/roadsplat.h, but with no promise
 * of a stable API or ABI across minor versions: the 8-neighbour mask
 * classification table and its alpha-maps (docs/design.md, SPEC "mask bit
 * order"), which the unit tests, the fuzzers and renderers that do their own
 * blending use. Include roadsplat.h's rules: the rs_ prefix, rs_result codes,
 * no printing. */
#ifndef ROADSPLAT_EXPERIMENTAL_H
#define ROADSPLAT_EXPERIMENTAL_H

#include "roadsplat.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------------------
 * The classification table (exposed for tests and for renderers that want
 * to do their own blending with the same alpha-maps).
 * ------------------------------------------------------------------------- */
/* (rs_tile_type, the tile types these return, is in roadsplat.h: the grid
 * statistics count cells by it.) */

/* Mask bit order (SPEC): bit0 N, bit1 NE, bit2 E, bit3 SE, bit4 S, bit5 SW,
 * bit6 W, bit7 NW; set = road. Returns the tile type and its rotation in
 * 90-degree clockwise turns of the canonical tile (0..3). */
RS_API void rs_mask_classify(uint8_t mask, rs_tile_type *type, int *rotation);

/* Alpha (terrain weight, 0..1) of the tile for `mask` at cell-local point
 * (u, v) in [0,1]^2, u right, v down, for a transition band
 * `transition_cells` wide (a fraction of the cell, not alpha-map pixels;
 * 0 = hard edge). Exact, not sampled from a raster. */
RS_API double rs_tile_alpha(uint8_t mask, double u, double v, double transition_cells);

/* Alpha-map rasters: (res+1) x (res+1) vertex-centred samples of the
 * canonical tile of `type` (EDGE, INNER or OUTER), as bytes 0..255, with a
 * transition band `transition_px` alpha-map pixels wide (0 = hard edge; at
 * most res/2) and, when jitter_amount > 0 (at most 1), jitter seeded by
 * jitter_seed (any value). `out` holds (res+1)^2 bytes. */
RS_API rs_result rs_alpha_map(rs_tile_type type, uint32_t res, double transition_px,
                              uint32_t jitter_seed, double jitter_amount,
                              uint8_t *out, size_t out_size);

#ifdef __cplusplus
}
#endif

#endif
