/* Private: road markings on the splat (issue 14, docs/markings.md). The
 * road grid prepares them (rs__markings_build) and the overlays stage
 * paints them onto the road colour S after the line symbols. */
#ifndef RS_MARKINGS_H
#define RS_MARKINGS_H
#include "internal.h"
#include "atlas.h"
#include "road_local.h"

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


/* Paint-time table of a type (issue 25): the summed-area table S of its
 * level-0 texels (S(j, i) = the sum over texels [0, i) x [0, j)), so that
 * the integral of the sprite (each texel a square of constant colour)
 * over [0, u] x [0, v] is the bilinear interpolation of S. Alpha-only
 * types (one colour): 255 x alpha, whole numbers, stored as doubles
 * (exact; read two columns at a time without converting), (h + 2) x (w +
 * 2) corners, the last row and column repeated. Types of
 * several colours: per r g b a plane and corner (j, i), j in [0, h], i in
 * [0, w], the doubles S, R = S(j, i + 1) - S(j, i), D = S(j + 1, i) -
 * S(j, i), X = the texel (j, i) (0 past the last column or row). */
typedef struct rs__mk_tex {
    uint32_t w, h;             /* level-0 texels; w == 0: not built (type unused) */
    uint32_t nch;              /* 1: alpha only, colour = col x alpha; 4: r g b a */
    float col[3];              /* premultiplied colour per unit alpha (nch 1) */
    double *isat;              /* nch 1: (h + 2) x (w + 2), 255 x alpha */
    double *sat;               /* nch 4: 4 planes of (h + 1) x (w + 1) x 4 */
    int32_t ax0, ay0, ax1, ay1; /* texels with alpha > 0 (ax0 > ax1: none) */
} rs__mk_tex;

/* The pixel's footprint in texel coordinates, its two slanted sides each
 * replaced by a staircase (docs/markings.md): on the left, for V - Vc in
 * [dv[k], dv[k + 1]], the boundary is at U - Uc = du[k]; the right side is
 * the left one turned by 180 degrees about the centre (Uc, Vc). Each
 * parallelogram edge is cut into equal parts with a step at each part's
 * middle, so the staircases of neighbouring pixels fit together and the
 * footprints still tile the plane. Kept as pairs for both sides at once:
 * pv[k] = (dv[k], -dv[k]), pu[k] = (du[k], -du[k]). */
#define RS__MK_STEPS 6
typedef struct rs__mk_fp {
    int n;
    double ia; /* 1 / the staircase polygon's area */
    double hu, hv; /* the polygon's reach from the centre in U and in V */
    double pv[RS__MK_STEPS + 1][2], pu[RS__MK_STEPS][2];
} rs__mk_fp;

typedef struct rs__mk {
    /* what the paint reads, first (the records are scattered over a
     * piece's markings: few cache lines each) */
    const rs__mk_tex *tex;     /* the type's summed-area table */
    rs__mk_fp fp;              /* one-segment stretch: the pixel's footprint */
    int flat;                  /* one segment, and bu or bv is 0 */
    size_t first, npt;         /* its stretch of the road: points first..first+npt-1 of pts */
    size_t part, nparts;       /* curved: its span parts, parts[part..part+nparts-1] */
    size_t fpi;                /* curved: its segments' footprints, fps[fpi..fpi+npt-2] */
    double by0, by1;           /* rows of the box */
    /* its blends made in the build (mk->pre[pre0 .. pre0 + npre), by row,
     * then column); pre0 == SIZE_MAX: painted per piece */
    size_t pre0, npre;
    /* level-0 texel coordinates U (across), V (along), texel i covering
     * [i, i + 1): the sample is transparent outside [ulo, uhi) x [vlo, vhi) */
    double ulo, uhi, vlo, vhi;
    /* one-segment stretch: U, V affine in the pixel centre (x, y) =
     * ((gx + 1/2) pix, y): U = au + buy y + bu (gx + 1/2), V = av + bvy y
     * + bv (gx + 1/2); ibu, ibv = 1 / bu, 1 / bv (0 when bu, bv are 0);
     * ua, ub = ulo, uhi in the order of ibu's sign (va, vb: ibv) */
    double au, buy, bu, ibu, av, bvy, bv, ibv;
    double ua, ub, va, vb;
    /* a point (ds, dt) from the centre: U = cu + su dt, V = cv + sv ds */
    double cu, su, cv, sv;
    double s0, t0;             /* centre (road coordinates) */
    /* the rest */
    const rs__atlas_type *ty;
    double slo, shi, tlo, thi; /* the support in road coordinates (s, t) */
    int flip;
    double hl, hw;             /* half length and width (metres) */
    double kx, ky;             /* level-0 texels per metre across (x) and along (y) */
    double bx0, bx1;           /* columns of the box (metres) */
    uint32_t rec;              /* its place in record order (mk->at[rec] is this record) */
    uint32_t road;             /* its placement's road */
    /* under a higher road's deck in places (rs__markings_set_levels): the
     * paint leaves out the pixels whose centre a surface of a higher level
     * and another stroke holds */
    int under;
    uint64_t deck;             /* under: a print of the roads over it (the road set's prints), for the edits' pieces */
} rs__mk;

/* One pixel of a small marking, as the paint blends it (o = o (1 - a) +
 * c): made once in the build, so a splat of many windows or tiles does
 * not integrate the sprite again for each (docs/markings.md "Small
 * markings"). */
typedef struct rs__mk_pre {
    uint32_t x, y;             /* pixel of the whole image */
    float c[4];                /* premultiplied colour, alpha */
} rs__mk_pre;

typedef struct rs__mk_ref {
    float x0, y0, x1, y1; /* the marking's box, rounded outwards */
    uint32_t i;
    uint32_t cx, cy;      /* its first index cell (the box's x0, y0) */
    uint32_t lx;          /* the column of the cell whose list holds this entry */
} rs__mk_ref;

/* Per stretch point: x, y, s and the segment to the next point: unit
 * direction ux, uy, its arc length (0 after the last point) and the range
 * the nearest-point lookup clamps u to (-inf / +inf at the stretch's
 * ends, else 0 / length), 1 / (ux pix) and 1 / (uy pix) (0 for 0). */
#define RS__MK_PT 10

/* A part of a curved marking's row spans (a segment's rectangle, or the
 * wedge at a vertex), as bounds on K = column + 1/2 (absolute) linear in
 * the row centre y: K in [max(a0 + b0 y, a2 + b2 y), min(a1 + b1 y, a3 +
 * b3 y)] for y in [ylo, yhi], and (wedge) within r metres of (vx, vy):
 * a0 b0 a1 b1 a2 b2 a3 b3 ylo yhi vx vy r (r < 0: no disc). */
#define RS__MK_PART 13

typedef struct rs__markings {
    rs_atlas *atlas_own;       /* the built-in atlas when none was given */
    rs__mk_tex *tex;           /* per atlas type, built for the types placed */
    size_t ntex;
    /* the records kept, stored by the top of their box (so the markings a
     * piece paints, and the next piece, lie close together in memory, as
     * do their stretches' points, span parts and footprints); at[i]: the
     * record of the i-th marking in record order. The index and the
     * paint keep record order. */
    rs__mk *m;
    size_t n;
    uint32_t *at;
    double *pts;               /* RS__MK_PT doubles per point */
    double *parts;             /* RS__MK_PART doubles per span part of a curved marking */
    rs__mk_fp *fps;            /* per segment of a curved marking's stretch: the footprint of its direction */
    rs__mk_pre *pre;           /* the small markings' blends (rs__mk.pre0) */
    size_t npre;
    uint32_t img_w, img_h;     /* the whole image, pixels */
    double pix;                /* output pixel, metres */
    double cell;               /* index cell, metres */
    uint32_t ox, oy;           /* the index's first cell in the map's cells (a window's: a patch's grid) */
    uint32_t gw, gh;           /* its cells; a box or point beyond them is in the nearest (cell_of) */
    uint32_t *start;           /* gw*gh + 1 offsets into list */
    struct rs__mk_ref *list;   /* per cell, ascending marking index: the index and its box */
    uint64_t n_explicit, n_auto;
    /* Every placement as placed (record order: explicit, then automatic),
     * also those drawing nothing here: what the GPU export reads
     * (rs_gpu_scene_from_grid, lib/gpu/gpu_export.c). */
    rs__placement *pl;
    size_t npl;
    size_t bytes;
    /* Levels (rs__markings_set_levels; NULL when every road is on one
     * level): the grid's road field (borrowed; lv_own when the markings
     * made it, alpha-map edges) and per road its level and stroke (owned). */
    const struct rs__roadfield *lv_field;
    struct rs__roadfield *lv_own;
    int32_t *lv;
    uint32_t *lv_stroke;
} rs__markings;

/* Place the road set's `mark` records and (unless o->markings.no_auto) the
 * automatic ones. *out stays NULL when there is nothing to draw or
 * o->markings.disable. `net`: the network of these roads
 * (rs_network_build with default options) when the caller has it, else NULL
 * (built here when needed). */
rs_result rs__markings_build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                             const rs_network *net, rs__markings **out);
/* The same with the automatic placements already made (rs__auto_plan_make
 * with the same roads and options; NULL: made here). Takes the plan's
 * atlas; the plan is left for rs__auto_plan_free. `window` (x0, y0, x1, y1
 * in local metres, or NULL: the map): the pixels that will be painted (a
 * patch's rectangle); the index covers its cells only, every marking in
 * the nearest (a paint anywhere is still right, slower away from it). */
struct rs__auto_plan;
rs_result rs__markings_build_planned(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads,
                                     const rs_splat_options *o, const rs_network *net, struct rs__auto_plan *plan,
                                     const double *window, rs__markings **out);
void rs__markings_free(rs_ctx *ctx, rs__markings *mk);
/* Roads on different levels (a bridge, layer=; docs/network.md "Bridges
 * and layers"): a marking is not painted where the surface of a road of a
 * higher level and another stroke holds the pixel's centre, the rule the
 * fill and the shader follow. Marks the markings whose box meets such a
 * road's (they are then painted per piece, not from the build's blends)
 * and keeps `field` (a field of these roads with the build's T ends: the
 * grid's, or its styles' fill lookup field; it must outlive mk) to ask.
 * field NULL (alpha-map edges without fills: no such field): when a marking lies
 * under a deck, a road field of the roads over the map at `texels` with
 * the T ends `tees` is made for the question and kept in mk. Nothing when
 * every road is on one level. */
struct rs__roadfield;
rs_result rs__markings_set_levels(rs_ctx *ctx, rs__markings *mk, const rs_dem *dem, const rs_roads *roads,
                                  const rs_network *net, const struct rs__roadfield *field, const rs__tees *tees,
                                  uint32_t texels);

/* Whether the automatic rules can place anything on these roads (a road
 * with a class, turn:lanes or a crossing=zebra point). */
int rs__markings_auto_possible(const rs_roads *roads);

/* Automatic placement (lib/scene/markings_auto.c): appends to *pl (capacity
 * *cap, count *n). `so`: the style options (profile, default driving
 * side; NULL: defaults). `net`: the network of these roads
 * (rs_network_build with default options) when the caller has it, else NULL
 * (built here when needed). */
rs_result rs__markings_auto(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_atlas *atlas,
                            const rs_style_options *so, const rs_network *net, rs__placement **pl, size_t *n,
                            size_t *cap);
rs_result rs__placement_push(rs_ctx *ctx, rs__placement **pl, size_t *n, size_t *cap, const rs__placement *p);
/* The road file's `mark` records as placements (appended to *pl; atlas
 * sizes where a record gives none); a type missing from the atlas is an
 * error naming the record's line. */
rs_result rs__markings_explicit(rs_ctx *ctx, const rs_roads *roads, const rs_atlas *atlas, rs__placement **pl,
                                size_t *npl, size_t *cap);

/* The overlays stage's last layer: blend every marking over S on the
 * piece's road pixels, marking by marking in index order (so each pixel
 * sees its markings in record order, whatever the piece), each over the
 * pixels of its support's row spans. */
void rs__markings_paint(const rs__markings *mk, struct rs__piece *p);
#endif
