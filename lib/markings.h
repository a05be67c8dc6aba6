/* Private: road markings on the splat (issue 14, docs/markings.md). The
 * road grid prepares them (rs__markings_build) and the overlays stage
 * paints them onto the road colour S after the line symbols. */
#ifndef RS_MARKINGS_H
#define RS_MARKINGS_H
#include "internal.h"
#include "atlas.h"

struct rs__piece;

/* One marking to place: what a `mark` record or an automatic rule asks for. */
typedef struct rs__placement {
    uint32_t type;         /* atlas type */
    size_t road;
    double s, t;           /* centre */
    double length, width;  /* metres, > 0 */
    int flip;
    uint64_t line;         /* road-file line, 0: none */
} rs__placement;

/* One road in local coordinates: distinct consecutive points and their arc
 * lengths (s summed in double as the road field sums it). */
typedef struct rs__road_local {
    double *x, *y, *s;
    size_t n;
} rs__road_local;
rs_result rs__road_local_get(rs_ctx *ctx, const rs_roads *roads, size_t ri, const rs_dem *dem, rs__road_local *out);
void rs__road_local_free(rs_ctx *ctx, rs__road_local *r);

typedef struct rs__mk {
    const rs__atlas_type *ty;
    int flip;
    double s0, t0, hl, hw;     /* centre, half length and width (metres) */
    double kx, ky;             /* level-0 texels per metre across (x) and along (y) */
    double lod;                /* log2 of level-0 texels per output pixel */
    double ms, mt;             /* how far past its rectangle the filtered sprite reaches */
    size_t first, npt;         /* its stretch of the road: points first..first+npt-1 of pts */
    double bx0, by0, bx1, by1; /* local bounding box (metres) */
} rs__mk;

typedef struct rs__mk_ref {
    float x0, y0, x1, y1; /* the marking's box, rounded outwards */
    uint32_t i;
} rs__mk_ref;

typedef struct rs__markings {
    rs_atlas *atlas_own;       /* the built-in atlas when none was given */
    rs__mk *m;
    size_t n;
    double *pts;               /* x, y, s per point */
    double pix;                /* output pixel, metres */
    double cell;               /* index cell, metres */
    uint32_t gw, gh;
    uint32_t *start;           /* gw*gh + 1 offsets into list */
    struct rs__mk_ref *list;   /* per cell, ascending marking index: the index and its box */
    uint64_t n_explicit, n_auto;
    size_t bytes;
} rs__markings;

/* Place the road set's `mark` records and (unless o->markings.no_auto) the
 * automatic ones. *out stays NULL when there is nothing to draw or
 * o->markings.disable. */
rs_result rs__markings_build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                             rs__markings **out);
void rs__markings_free(rs_ctx *ctx, rs__markings *mk);

/* Automatic placement (lib/markings_auto.c): appends to *pl (capacity
 * *cap, count *n). */
rs_result rs__markings_auto(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_atlas *atlas,
                            rs__placement **pl, size_t *n, size_t *cap);
rs_result rs__placement_push(rs_ctx *ctx, rs__placement **pl, size_t *n, size_t *cap, const rs__placement *p);

/* The overlays stage's last layer: blend every marking over S on the
 * piece's road pixels. */
void rs__markings_paint(const rs__markings *mk, struct rs__piece *p);
#endif
