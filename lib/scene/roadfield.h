/* Road field (SPEC "Road field", seed 003): an index grid over the map that
 * lists, per cell, the road segments whose capsule reaches the cell; nearest
 * centreline queries (road, segment, s, t) and exact-where-it-matters box
 * coverage of output pixels. Private to the library; docs/roadfield.md. */
#ifndef RS_ROADFIELD_H
#define RS_ROADFIELD_H
#include "internal.h"

typedef struct rs__roadfield rs__roadfield; /* immutable after build; safe to query from many threads */

typedef struct rs__roadfield_params {
    double origin_x, origin_y; /* world coords of DEM sample (0,0) */
    double cell_size;          /* DEM cell, metres (for rs__local_quantum) */
    double width_m, height_m;  /* map extent in local metres: [0,width_m] x [0,height_m] */
    double reach_extra;        /* metres beyond each road's half width that queries must still find; >= 0 */
    double index_cell;         /* index grid cell size in metres; 0 -> automatic (docs/roadfield.md) */
    double pixel;              /* largest output pixel the coverage will be asked for, metres;
                                  0 -> cell_size. Larger pixels still work, only slower. */
    uint32_t relation_scan;    /* holder search (docs/roadfield.md): cell lists up to this long are
                                  scanned, longer ones use the box tree; 0 -> 64. Same result either
                                  way (tests force each: 1 = always the tree, UINT32_MAX = never) */
    /* window_on: only the pixels inside window (local metres x0, y0, x1,
     * y1) and nearest queries there within window_reach metres will be
     * asked (a patch's local build). The segments that cannot reach them
     * stay in the field, with their ids, joints and T's, but are listed in
     * no cell: those pixels and queries come out as without the window. */
    int window_on;
    double window[4], window_reach;
} rs__roadfield_params;

/* Parameters of a road field over the whole map of `dem` for output pixels
 * of cell_size / texels (the road grid's field, the styles' fields). */
rs__roadfield_params rs__roadfield_params_for_dem(const rs_dem *dem, uint32_t texels);

rs_result rs__roadfield_build(rs_ctx *ctx, const rs_roads *roads, const rs__roadfield_params *p,
                              rs__roadfield **out);
void rs__roadfield_free(rs_ctx *ctx, rs__roadfield *f);
/* The index cell rs__roadfield_build takes for these roads and p (p's, or
 * the automatic one). */
double rs__roadfield_cell_for(const rs_roads *roads, const rs__roadfield_params *p);
/* The largest automatic index cell (p->index_cell 0) of any roads no wider
 * than `widest` metres over p's map. */
double rs__roadfield_cell_most(const rs__roadfield_params *p, double widest);
/* A record's end segment (end 0: its first, 1: its last) of points xy[0..np):
 * past repeated points at that end; SIZE_MAX when it has none (the T
 * trimming's rule, rs__roadfield_set_tees). */
size_t rs__end_segment(const double *xy, size_t np, int end);

/* Cut segment A-B, if it reaches beyond `far` from the w x h map, to the
 * disc around the map that a capsule of reach `pad` can touch from it
 * (full precision however far A and B are); *along = the new A's distance
 * from the old one. Returns 0 when nothing can reach the map. */
int rs__clip_far(double *ax, double *ay, double *bx, double *by, double w, double h, double pad, double far,
                 double *along);

/* A field of the same segments as src (the same ids, grid and pixel), each
 * road's half width grown by extra[road] (nroads entries, each 0..the
 * index cell: rs__roadfield_cell): what rs__roadfield_coverage2 computes
 * beside src in one pass (casings). */
rs_result rs__roadfield_widen(rs_ctx *ctx, const rs__roadfield *src, const double *extra, size_t nroads,
                              rs__roadfield **out);
/* A field of src's segments (the same ids and grid) whose one-cell paths
 * hold for pixels up to `pixel` metres: a splatter drawing coarser pixels
 * than src was built for (rs__roadfield_coverage falls back to a search of
 * the cells around every pixel otherwise). The same field as one built
 * from the roads for that pixel. */
rs_result rs__roadfield_repixel(rs_ctx *ctx, const rs__roadfield *src, double pixel, rs__roadfield **out);
/* A record end at a T (docs/network.md "Ends at a T"): it ends on road
 * `through`, which passes through the node; (nx, ny) is the through road's
 * unit normal there, pointing from the leg across it (road set frame). */
typedef struct rs__tee_end {
    uint32_t road;
    int end;           /* 0: the record's first point, 1: its last */
    uint32_t through;
    double nx, ny;
    double far;        /* the far edge line is n . p = n . E + far (E: the end point): the
                          through road's half width, less how far E lies past its centre
                          line along n (an end inside its surface, docs/network.md "Ends
                          inside a surface"; a T within the tolerance: E on it) */
    double grow;       /* how far the through road's shape in the field given the
                          ends reaches past its surface edge (its casing's width
                          in a casing field; 0 when it does not) */
} rs__tee_end;
/* The T ends of a network of `roads` (lib/scene/tee_ends.c): one through road
 * passing once through a junction node, every other record ending there
 * free (not continued by its stroke) at a sine above 0.2 with it. *out is
 * the caller's (rs__free), NULL with *n = 0 when there are none. */
rs_result rs__tee_ends(rs_ctx *ctx, const rs_roads *roads, const rs_network *net, rs__tee_end **out, size_t *n);
/* rs__tee_ends, or a copy of T's when T is given (the same network and
 * roads: a grid build works them out once). */
rs_result rs__tee_ends_from(rs_ctx *ctx, const rs__tees *T, const rs_roads *roads, const rs_network *net,
                            rs__tee_end **out, size_t *n);
/* rs__tee_ends at the nodes d with nodes[d] != 0 only (NULL: all). roads
 * NULL: from the network alone (a network whose roads are gone: an old
 * one after an edit), far then -INFINITY (unknown), the rest as with them. */
rs_result rs__tee_ends_at(rs_ctx *ctx, const rs_roads *roads, const rs_network *net, const uint8_t *nodes,
                          rs__tee_end **out, size_t *n);
/* How far road r's end (end 0: its first point, 1: its last) lies past
 * the centre line of the road of through leg tl along the unit normal
 * (nx, ny) (negative: short of it), metres: the end point against the
 * nearest point of tl's segment. 0 for an end within tol of it (a T found
 * there: the end is taken to be on the centre line) and where the through
 * road passes by points (a shared point or a joint of its records). */
double rs__tee_offset(const rs_roads *roads, uint32_t r, int end, const rs_network_leg *tl, double nx, double ny,
                      double tol);
/* Trims the round caps of the T ends of f's roads: such an end is a flat
 * strip up to the through road's far edge line (n . p = n . E + far, E
 * the end point), clipped
 * there; the coverage and the nearest query use that shape (a widened
 * field, rs__roadfield_widen, keeps the same lines: a casing stops at the
 * through road's surface edge). Part of building f (before any query). */
rs_result rs__roadfield_set_tees(rs_ctx *ctx, rs__roadfield *f, const rs_roads *roads, const rs__tee_end *tees,
                                 size_t n);
/* The index cell of f, metres. */
double rs__roadfield_cell(const rs__roadfield *f);
/* The largest pixel its one-cell coverage paths hold for, metres. */
double rs__roadfield_pixel(const rs__roadfield *f);
size_t rs__roadfield_bytes(const rs__roadfield *f);
/* The bounds (x0, x1, y0, y1, local metres) of every shape of f, T strips
 * included; x0 = +inf when f holds none. */
void rs__roadfield_bounds(const rs__roadfield *f, double box[4]);
/* 0 when no shape of f can reach the rows of local y in [y0, y1] (no
 * segment and no T strip listed in the index rows they meet): their
 * coverage is 0 there. */
int rs__roadfield_rows_have(const rs__roadfield *f, double y0, double y1);

typedef struct rs__road_point {
    uint32_t road;     /* index in rs_roads */
    uint32_t seg;      /* segment index within that road (points seg..seg+1) */
    double s;          /* arc length from the road's first point to the nearest point q, metres */
    double t;          /* signed lateral offset, + = left of travel; |t| = dist */
    double dist;       /* |p - q| */
    double half_width;
} rs__road_point;

/* Nearest road centreline to local point (x, y) among segments with
 * dist - half_width <= reach. Returns 1 and fills *out, or 0 when none or
 * (x, y) is more than one index cell outside the map. O(1) for an empty
 * cell; reach <= reach_extra + pixel*sqrt(2)/2 needs one cell's list, larger
 * reach scans the cells around. Ties: lowest road, then lowest segment. */
int rs__roadfield_nearest(const rs__roadfield *f, double x, double y, double reach, rs__road_point *out);
/* The same with priorities (per road, NULL: as rs__roadfield_nearest):
 * among the segments whose surface holds (x, y) the highest priority
 * wins, then the nearest; a point on no surface takes the nearest. The
 * fill of a crossing is the higher road's (issue 27 problem 6). */
int rs__roadfield_nearest_ranked(const rs__roadfield *f, double x, double y, double reach, const int *prio,
                                 rs__road_point *out);
/* rs__roadfield_nearest among the roads with only[road] > 0 (the casing
 * colour's road: one with a casing, never an uncased road beside it). */
int rs__roadfield_nearest_of(const rs__roadfield *f, double x, double y, double reach, const double *only,
                             rs__road_point *out);
/* 1 when some segment whose surface holds (x, y) (the fill lookups'
 * test: the capsule, or a trimmed T end's strip) belongs to a road q with
 * lv[q] > level and stroke[q] != st, else 0: a lower road's marking under
 * a bridge's deck (lib/scene/markings.c, docs/network.md "Bridges and
 * layers"). */
int rs__roadfield_held_above(const rs__roadfield *f, double x, double y, const int32_t *lv, const uint32_t *stroke,
                             int32_t level, uint32_t st);
/* 1 when rs__roadfield_nearest(f, x, y, reach) would find a road, else 0
 * (stops at the first: for fills that are the same on every road). */
int rs__roadfield_any_near(const rs__roadfield *f, double x, double y, double reach);
/* The same, trying segment *hint first (UINT32_MAX: none) and leaving in
 * *hint the one a scan found: neighbouring pixels mostly find the same
 * road. */
int rs__roadfield_any_near_hint(const rs__roadfield *f, double x, double y, double reach, uint32_t *hint);

/* Coverage of pixels [px0, px0+w) x [py0, py0+h), pixel side `pix` metres:
 * out[(py-py0)*stride + (px-px0)] = area fraction of the pixel inside the
 * union of the roads (round caps and joins). A pixel's value depends only on
 * (px, py, pix) and the field, never on the block. */
void rs__roadfield_coverage(const rs__roadfield *f, uint32_t px0, uint32_t py0, uint32_t w, uint32_t h,
                            double pix, double *out, size_t stride);

/* rs__roadfield_coverage of f into out and of g into outg (same stride),
 * in one pass: g must be rs__roadfield_widen of f (or NULL: f alone).
 * out equals f's own rs__roadfield_coverage; outg equals g's, except that
 * a pixel whose cover by f is within 2^-10 of 1 and is not one straight
 * edge may get f's cover (g is for casings: what they add to such a pixel
 * cannot show in 8 bits). */
void rs__roadfield_coverage2(const rs__roadfield *f, const rs__roadfield *g, uint32_t px0, uint32_t py0,
                             uint32_t w, uint32_t h, double pix, double *out, double *outg, size_t stride);

/* Index statistics (tests, benchmarks, docs). */
typedef struct rs__roadfield_stats {
    double index_cell;     /* cell size actually used, metres */
    uint32_t gw, gh;       /* grid cells (the map plus one cell on every side) */
    size_t segments;       /* segments that reach the grid */
    size_t entries;        /* (cell, segment) pairs */
    size_t nonempty_cells, full_cells;
    size_t max_list;       /* longest cell list */
    size_t redundant;      /* segments whose capsule lies within another one */
    uint64_t relation_work; /* work units of the segment relations (list entries scanned, holder-tree
                               nodes and items visited): near-linear in the segments, capped by
                               rs_limits.max_field_work */
    size_t tees;           /* T entries (road ends trimmed at a T, rs__roadfield_set_tees) */
} rs__roadfield_stats;
void rs__roadfield_get_stats(const rs__roadfield *f, rs__roadfield_stats *out);
#endif
