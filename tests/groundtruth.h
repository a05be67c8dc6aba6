/* Exact ground truth and the SPEC "Error measures" (see docs/error-measures.md).
 * Independent of the library: it reads only an sc_scene.
 *
 * Images are (W-1)*T x (H-1)*T floats, row-major; pixel (px, py) covers
 * [px*p, (px+1)*p) x [py*p, (py+1)*p) metres with p = cell_size / T.
 * A road is the set of points within width/2 of its centreline polyline
 * (round caps and joins); several roads combine by union. Functions returning
 * int give 0 on success, -1 on allocation failure or bad arguments. */
#ifndef RS_TESTS_GROUNDTRUTH_H
#define RS_TESTS_GROUNDTRUTH_H
#include "scenes.h"

/* G(px) = fraction of the pixel's area inside the union of roads. Pixels
 * whose centre is farther than half the pixel diagonal from every road
 * outline are exactly 0 or 1; the others are integrated exactly across x and
 * by Gauss-Legendre in y between every y where a boundary piece starts, ends
 * or crosses the pixel's sides (error ~1e-6 of a pixel, see the doc). */
int gt_coverage(const sc_scene *s, unsigned T, float *G);

/* Length (metres) of the boundary of the union of roads inside the image
 * rectangle [0, (W-1)*cs] x [0, (H-1)*cs]. Does not depend on T. Returns a
 * negative value on allocation failure. */
double gt_outline_length(const sc_scene *s, unsigned T);

typedef struct gt_result {
    double edge_error;     /* sum |R-G| * A_px / L, metres (SPEC) */
    double abs_area;       /* sum |R-G| * A_px, m^2 */
    double outline;        /* L, metres */
    double max_disp;       /* max |signed distance| over contour points, metres */
    double mean_disp;      /* mean of the same */
    size_t contour_points; /* R = 0.5 crossings between 4-adjacent pixel centres */
} gt_result;

/* Edge error of road weight R against the scene. Computes G itself. */
int gt_edge_error(const sc_scene *s, unsigned T, const float *R, gt_result *out);
/* The same with a precomputed G from gt_coverage (many R, one scene), and an
 * outline length L from gt_outline_length (pass L < 0 to compute it). */
int gt_edge_error_g(const sc_scene *s, unsigned T, const float *G, double L, const float *R, gt_result *out);

/* References: R = 1 where the pixel centre is within a road, else 0. */
int gt_hard_raster(const sc_scene *s, unsigned T, float *R);
/* "Traditional road buffer": a whole DEM cell is road (all its T x T pixels
 * 1) iff the cell's centre is within a road. */
int gt_cell_buffer(const sc_scene *s, unsigned T, float *R);
/* The same per-cell mask, bilinearly interpolated between DEM cell centres
 * to the pixel centres (clamped at the map border): the "blurred buffer"
 * of multi-texture blending. */
int gt_cell_buffer_bilinear(const sc_scene *s, unsigned T, float *R);

/* Signed distance to the union outline as the SPEC ruler defines it:
 * min over roads of (distance to centreline - width/2). Exact outside the
 * roads; inside it is minus the depth in the deepest single road. */
typedef struct gt_index gt_index;
/* margin: extra reach of the per-cell segment lists (metres, >= 0). */
gt_index *gt_index_new(const sc_scene *s, double margin);
void gt_index_free(gt_index *ix);
double gt_signed_distance(const gt_index *ix, double x, double y);
#endif
