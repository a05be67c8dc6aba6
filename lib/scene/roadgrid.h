/* Private: the road grid (lib/scene/roadgrid.c), read by the coverage stages
 * and the splatter. */
#ifndef RS_ROADGRID_H
#define RS_ROADGRID_H
#include "internal.h"

/* Cells are bytes in square blocks of RS__TILE x RS__TILE, allocated only
 * where a road touches, so memory follows road area, not map area. */
#define RS__TILE_SHIFT 6
#define RS__TILE (1u << RS__TILE_SHIFT)
#define RS__CELL_ROAD 0x80u    /* the cell is road */
#define RS__CELL_PATTERN 0x0Fu /* corner pattern (lib/splat/mask.c) once classified */

struct rs_road_grid {
    /* What it was built for: a splatter checks these against its own. */
    uint32_t dem_w, dem_h;   /* DEM size */
    rs_dem_frame frame;      /* DEM frame */
    uint32_t texels;
    rs_grid_options opts;    /* as given (road_cell 0 = automatic) */
    rs_edge_mode edges;
    /* Alpha-map edges: the cell grid (tiles NULL otherwise). */
    uint32_t k;              /* road cells per DEM cell side */
    double c;                /* road cell, metres (frame.cell_size / k) */
    uint32_t gw, gh;         /* grid size in road cells */
    uint32_t tw, th;         /* grid size in tiles */
    uint8_t **tiles;         /* tw*th, NULL where there is no road */
    /* Analytic edges (or overlays): the road field, else NULL. */
    struct rs__roadfield *field;
    /* Road styles (lib/scene/styling.c), NULL when no road is styled; and the
     * style options they were resolved with. */
    struct rs__styling *styling;
    rs_style_options style;
    /* Markings (lib/scene/markings.c), NULL when there are none; the marking
     * options they were placed with. */
    struct rs__markings *markings;
    rs_marking_options marks;
    /* What rs_road_grid_update compares (lib/scene/grid_edit.h). */
    struct rs__grid_edit *edit;
    rs_road_grid_stats stats;
    /* Sharing (rs_road_grid_update, docs/embedding.md "Patches"): a whole
     * grid's structures above stay while `refs` holders have it (itself
     * and the patched grids made on it). A patched grid borrows every
     * structure above from `base` (a whole grid) and draws its patches'
     * grids inside their rectangles, the later over the earlier. */
    long refs;
    struct rs_road_grid *base;
    size_t npatch;
    struct rs__grid_patch *patch;
    rs_pixel_rect *dirty;       /* a patched grid's dirty rectangles (a whole grid's are in edit) */
    size_t ndirty;
    struct rs__grid_track *track; /* what the next proportional update reads (NULL: none) */
    struct rs_road_grid *atlas_hold; /* a patch's grid: the base whose built-in marking atlas its
                                        markings point into, held (NULL: none) */
};

/* A patch: the grid of some roads (a whole grid of its own, shared) that
 * decides the output pixels of `rect`; ids[i] is its road i's index in the
 * patched grid's road set. */
typedef struct rs__grid_patch {
    rs_pixel_rect rect;
    struct rs_road_grid *grid;
    uint32_t *ids;
    size_t n;
} rs__grid_patch;

/* Add d to a holder count, atomically (holders of one grid or track may
 * free it from several threads); the count after. */
static inline long rs__refs_add(long *refs, long d)
{
#if defined(__GNUC__)
    return __atomic_add_fetch(refs, d, __ATOMIC_ACQ_REL);
#else
    return *refs += d;
#endif
}
/* Hold / release a whole grid's structures (a patched grid releases its
 * base and its patches' grids). */
void rs__grid_hold(struct rs_road_grid *g);
/* The grid deciding output pixel (x, y) of g: a patch's, else g itself;
 * *patch the patch (NULL: none). */
const struct rs_road_grid *rs__grid_at(const struct rs_road_grid *g, uint32_t x, uint32_t y,
                                       const rs__grid_patch **patch);

static inline const uint8_t *rs__grid_tile(const rs_road_grid *g, uint32_t tx, uint32_t ty)
{
    return g->tiles[(size_t)ty * g->tw + tx];
}
/* For tests and tools, so they never read the storage: the grid's size in
 * road cells (0 x 0 without a cell grid), and cell (x, y) of it: 0 for a
 * terrain cell, else 1 with its corner pattern (lib/splat/mask.h). */
void rs__grid_size(const rs_road_grid *g, uint32_t *gw, uint32_t *gh);
int rs__grid_cell(const rs_road_grid *g, uint32_t x, uint32_t y, unsigned *pattern);
#endif
