/* Lanes per direction (issue 27, docs/road-format.md "Lanes"): the
 * cross-section of one road record, shared by the default styles
 * (lib/input/style.c), the automatic markings (lib/scene/markings_auto.c) and the
 * public queries rs_road_lanes_get / rs_network_lanes_at. */
#ifndef RS_LANES_H
#define RS_LANES_H
#include "internal.h"

/* What a cross-section is made from: the decoded attributes (strings may
 * be NULL: absent). */
typedef struct rs__lanes_in {
    rs_road_class road_class;
    rs_profile profile;
    rs_oneway oneway;
    rs_driving_side side;
    uint32_t lanes, forward, backward; /* 0: absent */
    double width;                      /* 0: the nominal width */
    const char *turn, *turn_forward, *turn_backward, *width_lanes;
} rs__lanes_in;

/* Lay out the lanes (never fails: bad attributes fall back to defaults).
 * strip (may be NULL): the paved strips beyond the outer lanes, [0] on
 * the +t side, [1] on the -t side, metres. */
void rs__lanes_layout(const rs__lanes_in *in, rs_road_lanes *out, double strip[2]);
/* The attributes of road i into *in (profile and default side given). */
void rs__lanes_input(const rs_roads *roads, size_t i, rs_profile profile, rs_driving_side side_default,
                     rs__lanes_in *in);
/* 1: the road runs one way (-1: against its points), 0: two-way. */
int rs__lanes_oneway(rs_road_class c, rs_oneway o);
/* The class cross-section of a profile (lib/input/style.c's table): default
 * lanes (0: none given), lane width, strips left and right of travel. */
void rs__section(rs_profile p, rs_road_class c, uint32_t *lanes, double *lane, double *strip_left,
                 double *strip_right);
/* `driving_side=` of road i, or the default. */
rs_driving_side rs__driving_side(const rs_roads *roads, size_t i, rs_driving_side side_default);

/* Where the automatic markings interrupt their road's lane and centre
 * lines (lib/scene/markings_auto.c): between a stop or give-way line and the
 * junction, and across a zebra. A rectangle in the local frame of the
 * road field: u in [u0, u1] along (ux, uy) from (ax, ay), |v| <= r. */
typedef struct rs__line_cut {
    uint32_t road;
    double ax, ay, ux, uy, u0, u1, r;
} rs__line_cut;
/* The cuts of the automatic markings the splat options place (none when
 * they place none); *out is the caller's (rs__free). `net`: the network of these roads
 * (rs_network_build with default options) when the caller has it, else NULL
 * (built here when needed). */
rs_result rs__markings_line_cuts(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                                 const rs_network *net, rs__line_cut **out, size_t *n);
/* rs__markings_auto (lib/scene/markings.h) that also returns the line cuts
 * (*cuts the caller's, rs__free; NULL on failure): the placements and the
 * cuts of one run of the rules, for the GPU export, which needs both (the
 * cuts depend on the atlas's sizes alone, the same for the built-in
 * atlas and the sizes rs__markings_line_cuts uses without one). */
struct rs__placement;
rs_result rs__markings_auto_cuts(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_atlas *atlas,
                                 const rs_style_options *so, const rs_network *net, struct rs__placement **pl,
                                 size_t *n, size_t *cap, rs__line_cut **cuts, size_t *ncut);
/* The automatic markings of one grid build, placed once for their two
 * readers: the placements (rs__markings_build) and the line cuts
 * (rs__styling_build: lane and centre lines stop there). Empty (all zero)
 * when the splat options place no automatic markings on these roads. */
struct rs__placement;
typedef struct rs__auto_plan {
    rs_atlas *atlas;            /* the built-in atlas when the options give none; taken by the markings */
    struct rs__placement *pl;   /* the automatic placements, in rule order */
    size_t npl, cap;
    rs__line_cut *cuts;
    size_t ncuts;
} rs__auto_plan;
/* Fill *plan (zeroed first). `net`: the network of these roads
 * (rs_network_build with default options) when the caller has it, else
 * NULL (built here when needed). Ticks the context's progress by one unit
 * per road for each of its two readers. */
rs_result rs__auto_plan_make(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                             const rs_network *net, rs__auto_plan *plan);
void rs__auto_plan_free(rs_ctx *ctx, rs__auto_plan *plan);
#endif
