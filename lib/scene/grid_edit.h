/* Private: what a road grid keeps for edits (issue 30, lib/scene/grid_edit.c):
 * a fingerprint and a paint region per piece of what the grid draws, so
 * that rs_road_grid_update can tell which pixels an edit may change and
 * rs_road_grid_rect_has_roads which pixels no road reaches. */
#ifndef RS_GRID_EDIT_H
#define RS_GRID_EDIT_H
#include "internal.h"

#include <string.h>

/* Fingerprint mixing (64 bits): a value into a running hash (one multiply
 * and a rotation; rs__fp_final mixes a finished fingerprint well). */
static inline uint64_t rs__fp_mix(uint64_t h, uint64_t v)
{
    h = (h ^ v) * 0x9e3779b97f4a7c15ull;
    return (h << 27) | (h >> 37);
}

static inline uint64_t rs__fp_final(uint64_t h)
{
    h ^= h >> 31;
    h *= 0xbf58476d1ce4e5b9ull;
    h ^= h >> 29;
    h *= 0x94d049bb133111ebull;
    return h ^ (h >> 32);
}

static inline uint64_t rs__fp_mixd(uint64_t h, double d)
{
    uint64_t v;
    if (d == 0) d = 0; /* -0 draws as 0 */
    memcpy(&v, &d, sizeof v);
    return rs__fp_mix(h, v);
}

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

typedef struct rs__grid_edit {
    rs__edit_item *it;
    size_t n, cap;
    int fills; /* some road has a fill, gradient or surface image: which road is on top shows */
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
 * network, NULL when it built none) is at hand. Sets g->edit. */
rs_result rs__grid_edit_build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                              const rs_network *net, struct rs_road_grid *g);
void rs__grid_edit_free(rs_ctx *ctx, rs__grid_edit *e);
#endif
