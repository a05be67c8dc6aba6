/* Road styles on the splat (issue 13; docs/linesym.md "In the splat"):
 * casings under every road surface, fill and gradient surfaces, and line
 * symbols, prepared with the road grid and drawn by the overlays stage. */
#ifndef RS_STYLING_H
#define RS_STYLING_H
#include "internal.h"

struct rs__roadfield;
struct rs__linesym;
struct rs__band;
struct rs__line_cut;

/* A bridge deck's casing over the roads below it (docs/network.md
 * "Bridges and layers"), for one level L that has cased roads and roads
 * below it: `casing` holds the cased roads of level L, widened by their
 * casings (road[k]: the rs_roads id of its road k, cstroke[k] its
 * stroke); `hide` the roads of level L or higher, whose surfaces hide that
 * casing. The roads below are looked up in `look`: the grid's field with
 * below_of[i] = 1 for a road under L (analytic edges), else `below`, a
 * field of the roads under L whose boxes come near a cased one's (below_of
 * NULL); lstroke: the stroke of each road of look. A casing is not drawn
 * over a road of its own stroke (a bridge record's casing never crosses the
 * record it continues). box: the bounds of casing's shapes (local metres). */
typedef struct rs__deck {
    int32_t level;
    struct rs__roadfield *casing, *hide, *below;
    const struct rs__roadfield *look;
    double *below_of;
    uint32_t *road, *cstroke, *lstroke;
    double box[4];
} rs__deck;

typedef struct rs__styling {
    struct rs__linesym *lines;        /* NULL: no road has lines */
    struct rs__roadfield *casing;     /* every road, those with a casing widened by it on both sides (road
                                         ids as in rs_roads); with alpha-map edges the cased roads
                                         alone (casing_road); NULL: no casing */
    uint32_t *casing_road;            /* the rs_roads id of each road of casing (NULL: the same ids) */
    int casing_merged;                /* casing is rs__roadfield_widen of the grid's field: the analytic
                                         coverage stage computes its coverage into rs__piece.ov */
    int casing_uniform;               /* every casing has one colour: casing_rgba (no lookups) */
    float casing_rgba[4];
    double widest_casing;             /* the widest casing (0: none) */
    rs__deck *deck;                   /* ndeck, by rising level (NULL: every cased road on the lowest level) */
    size_t ndeck;
    const struct rs__roadfield *near; /* field for fill / gradient lookups: the grid's, else near_own */
    struct rs__roadfield *near_own;
    int *prio;                        /* per road: rs__road_priority, for the fill lookups (the higher road's fill
                                         at a crossing); NULL: all equal */
    uint8_t *surface;                 /* per road: rs_surface */
    float *colour;                    /* per road: fill rgba, gradient centre rgba, edge rgba, casing rgba (16 floats;
                                         rgb 0..255, a 0..1) */
    double *half_width;               /* per road */
    int any_surface;                  /* some road has a fill, gradient or surface image */
    int fill_uniform;                 /* every road has a fill, all of one colour (fill_rgba), and no road a
                                         surface image: a whole road pixel needs no lookup */
    float fill_rgba[4];
    int fill_opaque;                  /* fill_uniform with alpha 1: the overlays set a whole road pixel to it
                                         whatever lies under it, so the surface stage makes no asphalt there */
    /* Surface images (`surface IMG`, lib/scene/surfimg.h): per road the image
     * (index into imgs, -1: none), its metres per image height, width and
     * level of detail; NULL when no road has one. */
    int32_t *img_of;
    double *img_len;
    uint32_t *img_lev;
    double *img_f;
    double *img_s0;                   /* per road: the stroke arc length at its first point (images run on
                                         along a stroke); NULL: 0 */
    uint8_t *img_rev;                 /* per road: drawn against its points in its stroke (s and t turn) */
    struct rs__surfimg **imgs;        /* one per rs_style_options.surface_images entry in use (NULL: unused) */
    size_t nimgs;
    uint64_t img_pixels; /* pixels of the surface images in imgs[], all together */
    /* The resolved lines and casings as the GPU export reads them
     * (rs_gpu_scene_from_grid, lib/gpu/gpu_export.c): road i's lines are
     * bands[band_start[i] .. band_start[i + 1]) (dashes in `dash`), its
     * casing width casing_width[i] (NULL: no casing anywhere), and the
     * lines' cuts at stop lines and zebras (NULL when no road has lines). */
    size_t nroads;                    /* the roads the per-road tables hold */
    uint32_t *band_start;
    struct rs__band *bands;
    double *dash;
    double *casing_width;
    struct rs__line_cut *cuts;
    size_t ncuts;
    size_t bytes;
} rs__styling;

/* Resolve every road's style (rs_road_style with o->style) and prepare what
 * the overlays stage draws. `field` is the grid's road field of the same
 * roads (borrowed; it must outlive the styling) or NULL: then one is built
 * when a fill or gradient needs it. `net` (NULL: every road alone) is the
 * roads' network, read during the build only: a stroke's records share
 * one arc length for dashes and surface images (docs/network.md). `cuts`
 * (ncuts, borrowed for the call): where the automatic markings stop lane
 * and centre lines (rs__auto_plan). `facts` (NULL: from these roads): the
 * whole map's switches, when these roads are part of it (a local build).
 * *out stays NULL when no road is styled (or o->style.disable): the splat is
 * then the unstyled one. */
struct rs__line_cut;
rs_result rs__styling_build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                            const struct rs__roadfield *field, const rs_network *net, const rs__tees *tees,
                            const struct rs__line_cut *cuts, size_t ncuts, const rs__grid_facts *facts,
                            rs__styling **out);
void rs__styling_free(rs_ctx *ctx, rs__styling *st);
/* A style colour as the styling keeps it: r, g, b 0..255, alpha 0..1. */
void rs__put_colour(float *dst, rs_colour c);

/* The surface image colour of road `road` at (s, t) (s of the road, as
 * the road field gives it), premultiplied (rgb
 * 0..255, a 0..1); 0 when the road has no surface image. */
int rs__styling_image(const rs__styling *st, uint32_t road, double s, double t, double out[4]);
#endif
