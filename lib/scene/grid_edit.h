/* Private: what a road grid keeps for edits (issue 30, lib/scene/grid_edit.c):
 * a fingerprint and a paint region per piece of what the grid draws, so
 * that rs_road_grid_update can tell which pixels an edit may change and
 * rs_road_grid_rect_has_roads which pixels no road reaches. */
#ifndef RS_GRID_EDIT_H
#define RS_GRID_EDIT_H
#include "internal.h" /* (the fingerprint mixing, rs__fp_*, with its string.h) */

/* One piece: a chunk of a road (about 10 m of it, or the disc around one
 * of its vertices), a line cut, a marking. Its region holds every pixel
 * centre its paint can reach, before the grid's pad (rs__grid_edit_pad):
 * the capsule of segment (ax, ay)-(bx, by) with radius r, or (r < 0) the
 * box [ax, bx] x [ay, by]; local metres. `h` hashes everything the build
 * made that decides how the piece is drawn (never a road index: roads
 * renumbered by a removal keep their fingerprints). */
enum {
    RS__EI_CORE,    /* a road's core: its pixels are wholly road */
    RS__EI_SURFACE, /* the rest of a road's surface and casing */
    RS__EI_PAINT,   /* line symbols and markings, painted over the surfaces */
    RS__EI_PAINT_AT /* paint whose region holds the pixel centres it reaches, not the pixel squares
                       (the line symbols' straight pieces: their u and v ranges are grown by the
                       square's extent already) */
};
typedef struct rs__edit_item {
    uint64_t h;
    double ax, ay, bx, by, r;
    float dev;     /* a core: the centre line strays this far from the segment (rounded up) */
    uint32_t kind; /* RS__EI_* */
} rs__edit_item;

/* The pieces' multisets are rs__keyed records (lib/internal.h): a
 * fingerprint and its index, sorted by fingerprint, then index (given in
 * index order to the stable rs__sort_recs). pos: where a list of some
 * pieces had it before the sort (rs__patch_candidates' counts). */

typedef struct rs__grid_edit {
    rs__edit_item *it;
    size_t n, cap;
    int fills; /* some road has a fill, gradient or surface image, or a bridge's casing lies over
                  roads below: which road is on top shows */
    int over;  /* more pieces than the budget: none kept (updates dirty the whole image) */
    /* the items by bins of `bin` metres over the map (bw x bh; an item
     * listed in every bin its box meets), for rect_has_roads */
    double bin;
    uint32_t bw, bh;
    uint32_t *bstart; /* bw * bh + 1 */
    uint32_t *bitem;
    /* the dirty rectangles against the grid this one was updated from */
    rs_pixel_rect *dirty;
    size_t ndirty;
    size_t bytes;
} rs__grid_edit;

struct rs_road_grid;
/* The pieces of grid g, built by rs_road_grid_build from `roads` with
 * options o (when o->grid.edits is set), after its styles and markings and while `net` (the grid's
 * network, NULL when it built none) is at hand. Sets g->edit. window
 * (local metres x0, y0, x1, y1; NULL: the map): a patch's rectangle, the
 * pieces far from it left out (no update reads them). T: net's T ends,
 * worked out by the build (NULL: here). */
rs_result rs__grid_edit_build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                              const rs_network *net, const rs__tees *T, const double *window,
                              struct rs_road_grid *g);
void rs__grid_edit_free(rs_ctx *ctx, rs__grid_edit *e);

/* What the whole map's facts read of one road's resolved style. */
typedef struct rs__road_sum {
    float fill[4], casing[4]; /* its fill (a gradient's centre) and casing colour */
    double casing_width;
    double reach;             /* its paint's reach from the centre line */
    uint8_t fill_surface, image, any_surface, styled;
    uint8_t lines;            /* it draws lines (their dashes are laid along its stroke) */
    int prio;                 /* rs__road_priority */
} rs__road_sum;

/* What a proportional update reads from the grid it updates (lib/scene/grid_patch.c):
 * per road of the grid's road set a fingerprint of everything about it
 * that can change a pixel (geometry, width, name, attributes, point
 * attributes, markings; never its index), its resolved style's
 * fingerprint and sum, and its box in world metres (x0, y0, x1, y1); the
 * network of the whole set, and the whole map's facts. */
/* Boxes along each road (lib/scene/grid_patch.c path_boxes, not grown):
 * road i's are v[4 start[i]] .. v[4 start[i + 1]], none when its box is
 * at most the chunk's width across (its box is then its one). */
typedef struct rs__road_chunks {
    uint32_t *start; /* n + 1 */
    double *v;
    size_t bytes;
} rs__road_chunks;

typedef struct rs__grid_track {
    long refs;        /* grids holding it (a rebased grid shares its chain's: rs_road_grid_rebase) */
    size_t n;
    uint64_t *print;  /* per road: its own (raw_prints in lib/scene/grid_patch.c) */
    uint64_t *sprint; /* per road: its resolved style's */
    rs__road_sum *sum;
    uint64_t sctx;    /* the named styles, profile and side the styles were resolved with */
    double *box;
    rs__road_chunks chunks; /* boxes along the wider roads (an edit's changed area) */
    rs_network *net;
    rs__grid_facts facts;
    double max_width; /* the widest road's width (NaN: one is not finite) */
    double *tfar;     /* per road end (2 i + end): its T line's rs__tee_end.far, NaN when it is no T end
                       * (NULL: no network) */
    double *tstrip;   /* per road end: its T strip, 7 doubles (lib/scene/grid_patch.c strip_params: end
                       * point, direction, far / sin, cos / sin, half width; NaN: none), so that an update
                       * knows where a changed or removed road's strip was (NULL: no network) */
    size_t bytes;
} rs__grid_track;
/* The track of whole grid g built from `roads` with options o; takes `net`
 * (the grid's network: freed with the track, also on failure). T: net's T
 * ends, worked out by the build (NULL: here). */
rs_result rs__grid_track_build(rs_ctx *ctx, const rs_roads *roads, const rs_splat_options *o, rs_network *net,
                               const rs__tees *T, struct rs_road_grid *g);
/* Release a holder of t (freed with the last). */
void rs__grid_track_free(rs_ctx *ctx, rs__grid_track *t);
/* Tests: 1 when the network grid g keeps for its next update equals one
 * rs_network_build makes of `roads` (or it keeps none), and so do the T
 * lines and strips it keeps per road end and the prints, boxes and chunks
 * per road; 0 when not, -1 when that build failed. */
int rs__grid_track_net_check(rs_ctx *ctx, const struct rs_road_grid *g, const rs_roads *roads);
/* The candidate rectangles *rects (*nrects of them, the caller's:
 * rs__free) rendered under grids a and b (splatters on them for dem and
 * opts, lighting off) and replaced by the exact rectangles of the pixels
 * whose colour or weight differ, when the candidates hold at most
 * rs_limits.max_dirty_compare pixels; else, or on a failure other than a
 * cancel, left as they are (a superset). Ticks 2 units a pixel. */
rs_result rs__dirty_render(rs_ctx *ctx, const rs_dem *dem, const rs_splat_options *opts, const struct rs_road_grid *a,
                           const struct rs_road_grid *b, rs_pixel_rect **rects, size_t *nrects);
/* Whether the capsule of segment (ax, ay)-(bx, by) with radius r >= 0
 * meets the box [x0, x1] x [y0, y1] (closed). */
int rs__capsule_meets_box(double ax, double ay, double bx, double by, double r, double x0, double y0, double x1,
                          double y1);
/* The pieces that differ between what grid old draws inside `rect` (its
 * base, and inside its patches their grids) and what `local` draws there:
 * candidate rectangles within rect (*out the caller's: rs__free). */
rs_result rs__patch_candidates(rs_ctx *ctx, const struct rs_road_grid *old, const struct rs_road_grid *local,
                               rs_pixel_rect rect, rs_pixel_rect **out, size_t *nout);
/* The proportional update (docs/embedding.md "Patches"): *out a patched
 * grid on old's base, or NULL with RS_OK when this edit needs the whole
 * build (the caller then builds). */
rs_result rs__grid_update_patched(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                                  const struct rs_road_grid *old, struct rs_road_grid **out);
#endif
