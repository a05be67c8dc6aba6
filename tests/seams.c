/* Seam error of a built road grid (SPEC "Error measures"): the largest
 * difference of alpha across any shared cell edge, read from each cell's own
 * alpha-map raster (saddles as two inner corners), terrain cells as 1. */
#include "seams.h"
#include "mask.h"

#include <stdlib.h>

/* Seam error over every pair of adjacent road cells of a real scene: the
 * alpha-map samples along each shared edge, read from both cells. */
double rs_test_seam_error(const rs_road_grid *g, uint32_t res)
{
    uint8_t maps[3][(64 + 1) * (64 + 1)];
    rs_tile_type ts[3] = { RS_TILE_EDGE, RS_TILE_INNER, RS_TILE_OUTER };
    for (int i = 0; i < 3; i++) rs_alpha_map(ts[i], res, 2, 0, 0, maps[i], sizeof maps[i]);
    int worst = 0;
    uint32_t gw, gh;
    rs__grid_size(g, &gw, &gh);
    for (uint32_t y = 0; y < gh; y++)
        for (uint32_t x = 0; x < gw; x++) {
            unsigned pa = 0, pb = 0;
            int ra = rs__grid_cell(g, x, y, &pa);
            for (int dir = 0; dir < 2; dir++) {
                uint32_t x2 = x + (dir == 0), y2 = y + (dir == 1);
                if (x2 >= gw || y2 >= gh) continue;
                int rb = rs__grid_cell(g, x2, y2, &pb);
                if (!ra && !rb) continue;
                for (uint32_t k = 0; k <= res; k++) {
                    int va = 255, vb = 255;
                    int road[2] = { ra, rb };
                    unsigned pats[2] = { pa, pb };
                    int *vals[2] = { &va, &vb };
                    for (int s = 0; s < 2; s++) {
                        if (!road[s]) continue;
                        rs_tile_type ty;
                        int rot;
                        rs__pattern_classify(pats[s], &ty, &rot);
                        /* point on the shared edge, in this cell's local frame */
                        double u = dir == 0 ? (s == 0 ? 1.0 : 0.0) : (double)k / res;
                        double v = dir == 0 ? (double)k / res : (s == 0 ? 1.0 : 0.0);
                        int reps = ty == RS_TILE_SADDLE ? 2 : 1, acc = 0;
                        for (int q = 0; q < reps; q++) {
                            int r = rot + 2 * q;
                            double cu = u, cv = v;
                            for (int z = 0; z < (r & 3); z++) { double nu = cv, nv = 1 - cu; cu = nu; cv = nv; }
                            int i = (int)(cv * res + 0.5), j = (int)(cu * res + 0.5);
                            int a;
                            if (ty == RS_TILE_INTERIOR) a = 0;
                            else if (ty == RS_TILE_TERRAIN) a = 255;
                            else a = maps[ty == RS_TILE_EDGE ? 0 : (ty == RS_TILE_OUTER ? 2 : 1)][i * (res + 1) + j];
                            acc += a;
                        }
                        *vals[s] = acc > 255 ? 255 : acc;
                    }
                    if (abs(va - vb) > worst) worst = abs(va - vb);
                }
            }
        }
    return worst / 255.0;
}

