/* Private: the road set's storage (lib/input/roads.c), shared with its
 * edits (lib/input/roads_edit.c). */
#ifndef RS_ROADS_IMPL_H
#define RS_ROADS_IMPL_H
#include "internal.h"

#define MAX_ATTRS 64   /* attributes per road */
#define MAX_KEY 64     /* bytes of an attribute key */
#define MAX_LANES 16

typedef struct rs_road_rec {
    size_t name;  /* offset into names */
    double width;
    size_t first; /* index of the first point */
    size_t n;     /* point count */
    size_t attr_first;   /* index into attrs */
    uint32_t attr_count;
    uint32_t lanes;      /* 0: not given */
    size_t style;        /* offset into names of the style= value; SIZE_MAX: none */
    uint8_t road_class;  /* rs_road_class */
    uint8_t link, oneway, area, width_given;
    uint64_t print;      /* rs__roads_road_print: set by rs__roads_reprint whenever the above change */
    double box[4];
} rs_road_rec;

typedef struct rs_attr {
    size_t key, value; /* offsets into names */
} rs_attr;

/* An explicit marking (issue 14): a `mark` line or rs_roads_add_mark. */
typedef struct rs_mark_rec {
    size_t type;      /* offset into names */
    size_t road;      /* road index; SIZE_MAX while the parser resolves road_name */
    size_t road_name; /* offset into names (parser) */
    double s, t, length, width;
    int flip;
    uint64_t line;
} rs_mark_rec;

/* A point attribute (`X Y crossing=zebra`). */
typedef struct rs_point_attr {
    size_t road, point; /* road index, point index within it */
    size_t key, value;  /* offsets into names */
} rs_point_attr;

struct rs_roads {
    rs_road_rec *roads;
    size_t count, cap;
    double *xy; /* x0 y0 x1 y1 ... */
    size_t points, points_cap;
    char *names; /* string pool: names, attribute keys and values */
    size_t names_len, names_cap;
    rs_attr *attrs;
    size_t attrs_len, attrs_cap;
    rs_mark_rec *marks;
    size_t marks_len, marks_cap;
    rs_point_attr *pattrs;
    size_t pattrs_len, pattrs_cap;
    int frame;        /* rs_road_frame: the `frame` header line (RS_FRAME_NONE: none) */
    size_t frame_crs; /* offset into names of its CRS; SIZE_MAX: none */
};

/* Road i's print and box (rs__roads_road_print) from its name, width,
 * points and attributes: after every change of those. */
void rs__roads_reprint(rs_roads *roads, size_t i);
/* roads.c's helpers for roads_edit.c: grow an array to `need` elements
 * (NULL: no memory, buf still valid), copy a string into the pool
 * (SIZE_MAX: no memory), check an attribute key. */
void *rs__roads_grow(rs_ctx *ctx, void *buf, size_t *cap, size_t need, size_t elem);
size_t rs__roads_pool_add(rs_ctx *ctx, rs_roads *roads, const char *s, size_t n);
int rs__roads_key_ok(const char *k, size_t n);
/* An attribute value of vn bytes: valid UTF-8 without control characters
 * (tab allowed); else RS_ERR_INVALID_ARG, the message starting with fn. */
rs_result rs__roads_value_check(rs_ctx *ctx, const char *fn, const char *value, size_t vn);
/* A road's width (> 0, finite), n >= 2 points, xy not NULL and finite;
 * else RS_ERR_INVALID_ARG naming the value, the message starting with fn. */
rs_result rs__roads_check_geometry(rs_ctx *ctx, const char *fn, double width, const double *xy, size_t n);
#endif
