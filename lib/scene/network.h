/* The road network (issue 27, docs/network.md): nodes where road records
 * meet, their legs, and strokes (chains of records that continue each
 * other and share one arc length). The public queries are rs_network_* in
 * include/roadsplat.h; the drawing code reads the arrays below directly. */
#ifndef RS_NETWORK_H
#define RS_NETWORK_H
#include "internal.h"
#include <math.h>

struct rs_network {
    size_t nroads;
    double tol;
    size_t nnodes, nlegs;
    rs_network_node *node;  /* nnodes */
    uint32_t *leg_start;    /* nnodes + 1: legs of node i are leg[leg_start[i] .. leg_start[i+1]) */
    rs_network_leg *leg;
    /* strokes */
    size_t nstrokes;
    uint32_t *stroke_of;    /* per road */
    double *s_off;          /* per road: stroke arc length at its first point (reversed: the stroke's s
                               falls along the record: s_off - s) */
    double *length;         /* per road */
    double *s_len;          /* per road: its stroke's whole length (INFINITY: a ring), kept in a part
                               (rs__network_subset): how far a street runs on past a T (tee_ends.c) */
    uint32_t *prev, *next;  /* per road, UINT32_MAX: none (a ring's seam has none) */
    uint32_t *stroke_start; /* nstrokes + 1 */
    uint32_t *stroke_roads; /* nroads: the records of each stroke in order */
    uint8_t *closed;        /* per stroke */
    uint8_t *rev;           /* per road: drawn against its points (a two-way record pointing the other way) */
    uint32_t *link;         /* per road end (2 r: start, 2 r + 1: end): the road end it continues into
                               (2 q + f), NONE: none (a ring's seam is cut) */
    int any_short;          /* a record is short (two places at most twice the tolerance apart) */
    /* per node, for rs__network_update (NULL in a part: rs__network_subset) */
    uint64_t *node_key;     /* its lowest point, by which the nodes are numbered: record << 32 | point index */
    float *node_rad;        /* its points' greatest distance from its position, rounded up */
    uint8_t *node_surf;     /* 1: it holds a road's free end inside a street's surface (surface_tees) and
                               the street's two legs there */
    double *s_base;         /* per road, or NULL: the whole map's rs__stroke_bases, when this is a part
                               of its network (rs__network_subset; the line symbols otherwise sum
                               their own) */
    size_t bytes;
};

/* Default tolerance, metres (rs_network_options.tolerance = 0). */
#define RS__NETWORK_TOL 0.05

/* Class rank for priorities (motorway 9 .. path/footway/cycleway 1, none 0);
 * shared with the automatic markings. */
int rs__class_rank(rs_road_class c);
/* A road's priority at a junction: its class rank, + 10 for
 * priority_road=designated|yes_unposted, + 20 for junction=roundabout
 * (docs/network.md "Priorities"); shared with the automatic markings. */
int rs__road_priority(const rs_roads *roads, size_t r);
/* Road r's oneway= as the lanes, the default styles and the network take
 * it: where it is not given, one-way along the points for
 * junction=roundabout or circular (OSM: implied); still NONE otherwise,
 * which rs__lanes_oneway reads as two-way but for a motorway. in: its
 * info (rs_roads_get_info). */
rs_oneway rs__road_oneway(const rs_roads *roads, size_t r, const rs_road_info *in);
/* A road's level where roads cross (docs/network.md "Bridges and
 * layers"): its layer= (a whole number -100..100; others count as none),
 * else 1 for bridge= (any value but no), else 0. */
int rs__road_level(const rs_roads *roads, size_t r);
/* Where roads cross, which surface lies on top: RS__LEVEL_RANK * the
 * level + rs__road_priority (the level first, then the priority); the
 * level back from a rank (rs__rank_level, floor division). */
#define RS__LEVEL_RANK 64
int rs__road_rank(const rs_roads *roads, size_t r);
int rs__rank_level(int rank);
/* rs__road_rank of every road into *out (the caller's: rs__free), or
 * *out = NULL when all are equal (nothing to rank): the fills and the
 * line symbols' crossings read them. RS_ERR_NOMEM, RS_ERR_CANCELLED
 * (ticks per road). */
rs_result rs__road_priorities(rs_ctx *ctx, const rs_roads *roads, int **out);
/* Classes for feet and bikes (path, footway, cycleway): no car markings,
 * and their surfaces cut no car road's lines; shared with the automatic
 * markings, the line symbols and the GPU export. rs__road_non_car: road
 * r's class is one (0 when it has none). */
int rs__class_non_car(rs_road_class c);
int rs__road_non_car(const rs_roads *roads, size_t r);

size_t rs__network_bytes(const rs_network *net);
/* Per record of N (the roads of `roads`), into out: the stroke's arc
 * length where the record's travel starts, the records' lengths summed in
 * travel order in the local frame of a map with this origin and DEM cell
 * (lib/scene/road_local.h), as the line symbols sum a record's points.
 * With ids (n records of N), only the records of their strokes (the others
 * NaN). Polls ctx (may be NULL): RS_ERR_CANCELLED leaves out half made. */
rs_result rs__stroke_bases(rs_ctx *ctx, const rs_network *N, const rs_roads *roads, double origin_x, double origin_y,
                           double cell_size, const uint32_t *ids, size_t n, double *out);
/* The part of network N that the records ids[0..n) take part in (ascending
 * record ids of N), as the drawing code of a road set holding only those
 * records, in that order, reads it: their nodes (in N's order) with their
 * legs among them, their stroke arc lengths and directions from N, and
 * N's strokes cut into runs of kept records (a ring stays closed only when
 * kept whole), and s_base from `bases` (per record of N; NULL: N's own). At a node where N has other legs, the degree, kind and
 * major flags are of the kept legs. For a local build that takes the
 * whole map's strokes (docs/embedding.md). *out is the caller's
 * (rs_network_free). RS_ERR_INVALID_ARG when ids are not ascending or out of
 * range, RS_ERR_NOMEM. */
rs_result rs__network_subset(rs_ctx *ctx, const rs_network *N, const double *bases, const uint32_t *ids, size_t n,
                             rs_network **out);
/* The network of `roads` after an edit, as rs_network_build (default
 * options but N0's tolerance) would make it, from N0, the network of the
 * road set before: m_old[i] is old record i's record in `roads`
 * (UINT32_MAX: removed), m_new[j] new record j's old one (UINT32_MAX: new),
 * each record matched alike in everything the network reads; box: per
 * record of `roads`, its points' box; zone: the box of the removed and the
 * new records (empty: min above max); reach: half the widest record of
 * both sets. The nodes within reach of the zone are made anew from a
 * network of the roads near it (docs/network.md "After an edit"), the
 * others kept; the strokes are numbered anew, the free ends inside a
 * surface found again where a stroke changed. *out NULL (RS_OK) when it
 * cannot (a short record in either set, a node of points spread across
 * the zone's edge, most of the map near the edit): build it whole. N0 must
 * be a whole network (rs_network_build or this: node_key set).
 * RS_ERR_NOMEM, RS_ERR_CANCELLED. */
rs_result rs__network_update(rs_ctx *ctx, const rs_roads *roads, const rs_network *N0, const uint32_t *m_old,
                             const uint32_t *m_new, const double *box, const double *zone, double reach,
                             rs_network **out);
/* 1 when networks a and b are equal in every array (tests). */
int rs__network_equal(const rs_network *a, const rs_network *b);
/* Two record ends at a node going on within 30 degrees of straight (the
 * cosine of their angle below -cos 30 degrees) that do not make a stroke
 * (they do not draw alike) are the through road of a T when no stroke
 * passes there (lib/scene/tee_ends.c, the line symbols) */
#define RS__STRAIGHT_COS 0.8660254037844386
/* That pair among a node's d legs L (end legs of two records, their
 * directions' cosine below -RS__STRAIGHT_COS): 1 with *a, *b when there is
 * exactly one, else 0 (lib/scene/network.c). */
int rs__straight_pair(const rs_network_leg *L, uint32_t d, const rs_network_leg **a, const rs_network_leg **b);
/* The direction of a street passing a node on legs a and b: the unit
 * chord from b's direction to a's (a bent street's mean direction) into
 * *tx, *ty; 0 when a and b leave the same way (no direction). */
static inline int rs__through_dir(const rs_network_leg *a, const rs_network_leg *b, double *tx, double *ty)
{
    double x = cos(a->angle) - cos(b->angle), y = sin(a->angle) - sin(b->angle), n = hypot(x, y);
    if (!(n > 1e-6)) return 0;
    *tx = x / n, *ty = y / n;
    return 1;
}

/* How squarely a road end leaving its node in direction (wx, wy) meets a
 * street through it in direction (tx, ty): the sine of their angle. Where
 * several streets pass, the T end's trim (lib/scene/tee_ends.c) and its
 * line rule (lib/scene/linesym.c) both take the largest, the first of
 * equals, so they pick the same street. */
static inline double rs__meet_sine(double wx, double wy, double tx, double ty)
{
    return fabs(ty * wx - tx * wy);
}

/* Leg L is at a road's end (RS_LEG_START or RS_LEG_END). */
static inline int rs__is_end_leg(const rs_network_leg *L)
{
    return L->kind == RS_LEG_START || L->kind == RS_LEG_END;
}

/* The road end of an end leg: 2 r its start, 2 r + 1 its end (the index
 * of net->link). */
static inline uint32_t rs__leg_end(const rs_network_leg *L)
{
    return 2 * L->road + (L->kind == RS_LEG_END);
}

/* Leg L's street passes through its node: the road goes through it, or
 * the road ends there and its stroke goes on, or it is at a ring's seam
 * (the only record ends of a closed stroke without a link: number_strokes
 * opens the ring there, but the street goes on through it; until 6
 * December 2026 a side road ending on a roundabout's first point was no T,
 * and its surface cut the ring's far edge line). */
static inline int rs__leg_passes(const rs_network *net, const rs_network_leg *L)
{
    return !rs__is_end_leg(L) || net->link[rs__leg_end(L)] != UINT32_MAX ||
           (net->closed && net->closed[net->stroke_of[L->road]]);
}

#endif
