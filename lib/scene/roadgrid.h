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
};

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
