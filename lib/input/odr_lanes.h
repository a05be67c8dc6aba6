/* Private: an OpenDRIVE document as plain data, and its conversion to road
 * text (issue 32, docs/opendrive.md).
 *
 * The XML is read outside the library (cli/odr.c, with expat), which fills
 * an rs__odr_doc; the library turns it into road text that draws the
 * lanes' surfaces and road marks exactly (rs__odr_to_text), so the core
 * keeps depending on libc and libm only. Every s below is the road's own
 * arc length (absolute, not relative to a lane section). Arrays are owned
 * by whoever filled the document and are never NULL (also when empty). */
#ifndef RS_ODR_LANES_H
#define RS_ODR_LANES_H
#include "odr_geom.h"

/* A cubic a + b ds + c ds^2 + d ds^3 with ds = s - s0. */
typedef struct rs__odr_poly {
    double s0, a, b, c, d;
} rs__odr_poly;

/* Road-mark types (ASAM names in docs/opendrive.md). */
typedef enum rs__odr_mark_type {
    RS__ODR_MARK_NONE = 0,
    RS__ODR_MARK_SOLID,
    RS__ODR_MARK_BROKEN,
    RS__ODR_MARK_SOLID_SOLID,
    RS__ODR_MARK_SOLID_BROKEN,
    RS__ODR_MARK_BROKEN_SOLID,
    RS__ODR_MARK_BROKEN_BROKEN,
    RS__ODR_MARK_BOTTS_DOTS,
    RS__ODR_MARK_CURB,
    RS__ODR_MARK_EDGE,
    RS__ODR_MARK_GRASS,
    RS__ODR_MARK_CUSTOM
} rs__odr_mark_type;

/* One line of an explicit <type><line> pattern. */
typedef struct rs__odr_mark_line {
    double length, space, t_offset, s_offset, width; /* width <= 0: the mark's */
    uint32_t rgba;                                   /* 0: the mark's colour */
} rs__odr_mark_line;

typedef struct rs__odr_mark {
    double s;            /* where it starts (section s + sOffset) */
    rs__odr_mark_type type;
    double width;        /* <= 0: the default of the type and weight */
    uint32_t rgba;       /* 0xRRGGBBAA */
    int bold;            /* weight="bold" */
    const char *lane_change; /* as written, or NULL */
    size_t line0, nline; /* explicit lines in doc->lines */
    unsigned long xml_line;
} rs__odr_mark;

/* What a lane's surface is drawn as. */
typedef enum rs__odr_surface {
    RS__ODR_SURF_NONE = 0,   /* not drawn: none, border, curb, median, rail, tram, ... */
    RS__ODR_SURF_ROAD,       /* the carriageway: driving, shoulder, parking, ... */
    RS__ODR_SURF_SIDEWALK,
    RS__ODR_SURF_BIKE
} rs__odr_surface;

typedef struct rs__odr_lane {
    int id;                  /* > 0 left, 0 centre, < 0 right */
    rs__odr_surface surface;
    size_t width0, nwidth;   /* width polynomials in doc->polys, by s0 */
    size_t mark0, nmark;     /* road marks in doc->marks, by s */
    unsigned long xml_line;
} rs__odr_lane;

typedef struct rs__odr_section {
    double s;
    size_t lane0, nlane;     /* lanes in doc->lanes, ids from the highest down (left to right) */
    unsigned long xml_line;
} rs__odr_section;

typedef enum rs__odr_object_kind {
    RS__ODR_OBJ_CROSSWALK = 1,
    RS__ODR_OBJ_STOP_LINE
} rs__odr_object_kind;

/* A marking object: its extent as a box in (s, t) of its road. */
typedef struct rs__odr_object {
    rs__odr_object_kind kind;
    double s0, s1, t0, t1;
    int side;            /* a stop line from a signal: across the lanes on this side (+1 left, -1 right) at s0 */
    unsigned long xml_line;
} rs__odr_object;

typedef struct rs__odr_road {
    const char *id;
    double length;
    int in_junction;         /* junction != -1: a connecting road */
    size_t geom0, ngeom;     /* planView records in doc->geoms, by s */
    size_t off0, noff;       /* laneOffset polynomials in doc->polys */
    size_t sec0, nsec;       /* lane sections in doc->sections, by s */
    size_t obj0, nobj;
    unsigned long xml_line;
} rs__odr_road;

typedef struct rs__odr_doc {
    const char *name;        /* the file, for messages */
    const char *geo_reference; /* PROJ string, or NULL */
    double off_x, off_y, off_hdg; /* header <offset>: local to georeferenced */
    rs__odr_road *roads;
    size_t nroads;
    rs__odr_geom *geoms;
    size_t ngeoms;
    rs__odr_poly *polys;
    size_t npolys;
    rs__odr_section *sections;
    size_t nsections;
    rs__odr_lane *lanes;
    size_t nlanes;
    rs__odr_mark *marks;
    size_t nmarks;
    rs__odr_mark_line *lines;
    size_t nlines;
    rs__odr_object *objects;
    size_t nobjects;
    size_t njunctions;
} rs__odr_doc;

/* Conversion tolerance: how far (metres) a drawn lane boundary or surface
 * edge may lie from its exact position. */
#define RS__ODR_TOL 0.01

/* The road text of `doc` (frame line, styles, roads; docs/opendrive.md):
 * *text is NUL-terminated, rs__alloc'd on ctx (rs__free). Errors name the
 * road and the line of the file. At most max_points points (0: 10^7). */
rs_result rs__odr_to_text(rs_ctx *ctx, const rs__odr_doc *doc, size_t max_points, char **text, size_t *size);

/* Lateral offset of the outer boundary of lane `lane_id` (0: the centre
 * lane's line, laneOffset) of section `sec` of road `road` at s: exposed
 * for the tests. */
double rs__odr_boundary_t(const rs__odr_doc *doc, const rs__odr_road *road, const rs__odr_section *sec, int lane_id,
                          double s);
/* Value of the polynomial among p[0..n) in effect at s (0 when none). */
double rs__odr_poly_at(const rs__odr_poly *p, size_t n, double s);
/* The default dash pattern of a broken mark (metres). */
#define RS__ODR_DASH_ON 3.0
#define RS__ODR_DASH_OFF 6.0
#endif
