#ifndef RS_TESTS_SEAMS_H
#define RS_TESTS_SEAMS_H
#include "roadgrid.h"
/* Max |alpha_A - alpha_B| (0..1) over all adjacent cell pairs of `g`, at the
 * res+1 alpha-map samples along each shared edge (res <= 64). */
double rs_test_seam_error(const rs_road_grid *g, uint32_t res);
#endif
