/* Private: the mask table internals shared by lib/splat/mask.c, lib/scene/roadgrid.c and
 * lib/splat.c. */
#ifndef RS_MASK_H
#define RS_MASK_H
#include "roadsplat_experimental.h"

#define RS__MAX_ALPHA_RES 1024u

/* 4-bit corner pattern of a mask: bit0 NE, bit1 SE, bit2 SW, bit3 NW set
 * when that corner touches terrain. */
unsigned rs__mask_corners(unsigned mask);
void rs__pattern_classify(unsigned pattern, rs_tile_type *type, int *rotation);
/* Exact signed offset field of a pattern's tile at (u,v) in [0,1]^2. */
double rs__pattern_phi(unsigned pattern, double u, double v);
double rs__phi_to_alpha(double phi, double w);
/* The whole table, built once per call by the rule above (no global state):
 * corners[mask] and, per corner pattern, type and rotation. */
typedef struct rs__mask_table {
    uint8_t corners[256];
    uint8_t type[16];
    uint8_t rot[16];
} rs__mask_table;
void rs__mask_table_build(rs__mask_table *t);
int rs__alpha_args_ok(rs_tile_type type, uint32_t res, double transition_px, double jitter_amount);
/* (res+1)^2 floats of the canonical tile, quantised to 1/255. */
void rs__alpha_map_float(rs_tile_type type, uint32_t res, double transition_px, uint32_t seed,
                         double amount, float *out);
#endif
