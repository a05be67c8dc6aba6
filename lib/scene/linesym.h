/* Line symbols (seed 003; SPEC "Road field"): bands of a road at a lateral
 * offset, solid or dashed along the arc length s, painted with the exact
 * box-filtered area of each pixel inside the band (or the seed's Hermite
 * smoothing, for comparison). Private to the library; docs/linesym.md.
 *
 * A band of road r is {p : t(p) in [T - W/2, T + W/2], s(p) "on"}, with
 * (s, t) from the nearest point of the road's centreline. Near one vertex
 * that set splits into convex pieces: one per segment (the segment's slab
 * cut by the angle bisectors at its ends: mitred on the inner side of a
 * bend) and an annular sector at each vertex on the outer side (the round
 * join, where the nearest point is the vertex itself and s is constant).
 * The pieces of one band never overlap and leave no gap, so a pixel's band
 * coverage is the sum of the pieces' areas in it. */
#ifndef RS_LINESYM_H
#define RS_LINESYM_H
#include "internal.h"

typedef struct rs__band {
    double t, w;        /* centre lateral offset (+ = left of travel) and width, metres; w > 0 */
    float rgba[4];      /* colour 0..1; rgba[3] = opacity */
    const double *dash; /* on, off, on, off, ... lengths in metres (copied by build); NULL: solid */
    uint32_t ndash;     /* even, 0 for solid */
    double phase;       /* s at which the first "on" starts; the pattern repeats both ways */
} rs__band;

typedef enum rs__band_aa {
    RS__AA_EXACT = 0,   /* area of the pixel inside the band */
    RS__AA_HERMITE = 1  /* seed 003: smoothstep of the pixel centre's distance to each band edge */
} rs__band_aa;

/* A road end at a T on a through road with the right of way
 * (docs/network.md "The through road at a T"): the through stroke
 * (RS__NO_STROKE: none), the depth into it the end's surface keeps cutting
 * (lines within `keep` of its centre line run on), and the through road's
 * direction there. */
#define RS__NO_STROKE UINT32_MAX
typedef struct rs__tee {
    uint32_t stroke;
    uint32_t stroke2; /* a through road of two strokes (two record ends going straight on that
                         do not draw alike), else RS__NO_STROKE */
    double keep, dx, dy;  /* (dx, dy): its direction from both legs (a bent street's chord) */
    double lx[2], ly[2];  /* the through road's two legs' directions from the node */
    double off; /* how far the end lies past the through road's centre line (negative:
                   short of it; rs__tee_offset): the cut stops keep + off before the end */
} rs__tee;
/* Per road two entries (start, end) into *out (the caller's, rs__free);
 * *out NULL without a network or when it is not of these roads. The GPU
 * export applies the same rule (lib/gpu/gpu_export.c). RS_ERR_NOMEM,
 * RS_ERR_CANCELLED (polls every 4096 nodes). */
rs_result rs__network_tees(rs_ctx *ctx, const rs_roads *roads, const rs_network *net, rs__tee **out);

typedef struct rs__linesym_params {
    double origin_x, origin_y; /* world coords of DEM sample (0,0) */
    double cell_size;          /* DEM cell, metres (for rs__local_quantum) */
    uint32_t out_w, out_h;     /* output pixels */
    double pixel;              /* pixel side, metres (the only size rs__linesym_paint accepts) */
    rs__band_aa aa;
    const rs_network *net;     /* NULL: every road alone. Else the roads' network: each stroke is drawn
                                  as one polyline with the bands of its first record (every record of a
                                  stroke draws alike), so a road split into records draws as one */
    const struct rs__line_cut *cuts; /* where a road's lane and centre lines stop (lib/scene/lanes.h: stop lines,
                                        zebras); read while building */
    size_t ncuts;
    int prio_given;            /* 1: prio holds the roads' priorities (rs__road_priorities; NULL: all
                                  equal), read while building; 0: worked out here */
    const int *prio;
    const rs__tees *tees;      /* the T ends of roads and net, worked out once by the caller (NULL: here) */
    int window_on;             /* 1: only the pieces whose box meets window (local metres: x0, y0, x1,
                                  y1) are made (a patch's grid: its pixels and edit pieces lie there) */
    double window[4];
} rs__linesym_params;

typedef struct rs__linesym rs__linesym; /* immutable after build; safe to read from many threads */

/* Bands of road i are bands[band_start[i] .. band_start[i+1]); band_start
 * has rs_roads_count(roads) + 1 entries. Painting order: road by road (with
 * p->net: stroke by stroke, in stroke order), band by band. */
rs_result rs__linesym_build(rs_ctx *ctx, const rs_roads *roads, const rs__linesym_params *p,
                            const uint32_t *band_start, const rs__band *bands, rs__linesym **out);
void rs__linesym_free(rs_ctx *ctx, rs__linesym *L);
size_t rs__linesym_bytes(const rs__linesym *L);
/* Doubles of scratch rs__linesym_paint needs for a window w pixels wide. */
size_t rs__linesym_scratch_len(uint32_t w);

/* Composite every band over the planar colour rows of the pixels
 * [px0, px0+w) x [py0, py0+h): rgb + y*row_stride holds w R, w G, w B floats.
 * c = c (1 - a cov) + colour a cov, band by band in painting order.
 * scratch: rs__linesym_scratch_len(w) doubles. A pixel's result depends only on its own
 * coordinates, never on the block. pix must equal the build's pixel. */
void rs__linesym_paint(const rs__linesym *L, uint32_t px0, uint32_t py0, uint32_t w, uint32_t h, float *rgb,
                       size_t row_stride, double *scratch);

/* For edits (lib/scene/grid_edit.c): the pieces the build made (after
 * every cut), and piece k as an edit compares it. A slab (a band along a
 * segment, in its frame: u along (ux, uy) from (ox, oy), v to the left)
 * paints the pixels whose centre has u in [ru0, ru1] and v in [rv0, rv1]
 * (ru0 > ru1: none); a pixel there depends on the fingerprint h (band,
 * colour, dashes, arc length, frame, v limits) and on the half-planes
 * c0 + cu u + cv v >= 0 (hp: c0, cu, cv and the pixel's half extent
 * along the normal, sup, per half-plane; nhp of them) whose value at its
 * centre is below sup: a half-plane at least sup everywhere in a stretch
 * of u cuts no pixel of it. A wedge (a round join) has h of everything
 * and the region reg = (ax, ay, bx, by, -1), the box [ax, bx] x [ay, by]
 * (ax > bx: empty); local metres. */
typedef struct rs__linesym_piece_view {
    int slab;
    uint64_t h;
    double ox, oy, ux, uy, ru0, ru1, rv0, rv1;
    const double *hp;
    uint32_t nhp;
    double reg[5];
} rs__linesym_piece_view;
size_t rs__linesym_piece_count(const rs__linesym *L);
void rs__linesym_piece_get(const rs__linesym *L, size_t k, rs__linesym_piece_view *out);

/* Tests: coverage of band number `band` (global index into the build's
 * bands array) alone, in [0,1], into out[y*stride + x]. */
void rs__linesym_coverage(const rs__linesym *L, uint32_t band, uint32_t px0, uint32_t py0, uint32_t w, uint32_t h,
                          double *out, size_t stride);
#endif
