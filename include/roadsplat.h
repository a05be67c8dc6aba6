/*
 * roadsplat - burn roads into terrain textures, mesh terrain with ROAM.
 *
 * One public header. Everything is prefixed rs_. The library never prints,
 * exits or aborts: every fallible call returns an rs_result, and
 * rs_ctx_message() gives a human-readable detail (file line, value) for the
 * last failure on that context.
 *
 * Threads: there is no global mutable state. A context and the objects made
 * with it must be used by one thread at a time; two contexts in two threads
 * are independent. Read-only objects (rs_dem, rs_roads after parsing) may be
 * shared between threads if nobody modifies them.
 *
 * Ownership: objects returned through an `**out` parameter belong to the
 * caller and are released with the matching *_free() function, passing the
 * same context that created them. Output pixel/vertex buffers are always
 * caller-provided; the *_bound() and *_size() functions say how large they must be.
 *
 * Coordinates (see docs/design.md and SPEC): DEM sample (row i, column j)
 * is at world (x, y) = (j*cs, i*cs) metres; x grows right, y grows down.
 */
#ifndef ROADSPLAT_H
#define ROADSPLAT_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(_WIN32) && defined(RS_BUILDING_SHARED)
#define RS_API __declspec(dllexport)
#elif defined(__GNUC__) && __GNUC__ >= 4
#define RS_API __attribute__((visibility("default")))
#else
#define RS_API
#endif

#define RS_VERSION_MAJOR 0
#define RS_VERSION_MINOR 1
#define RS_VERSION_PATCH 0
#define RS_VERSION ((RS_VERSION_MAJOR << 16) | (RS_VERSION_MINOR << 8) | RS_VERSION_PATCH)

/* "MAJOR.MINOR.PATCH" of the library actually linked. Static storage. */
RS_API const char *rs_version_string(void);
/* RS_VERSION of the library actually linked: a host built against one
 * header can compare it at run time with the shared library it loaded
 * (same major: compatible; docs/embedding.md). */
RS_API uint32_t rs_version_number(void);

/* ---------------------------------------------------------------------------
 * ABI of the option structs (docs/embedding.md "ABI")
 *
 * Every option struct the library reads through a pointer (rs_limits,
 * rs_road_parse_options, rs_style_request, rs_style_options,
 * rs_normal_options, rs_network_options, rs_splat_options, rs_gpu_options,
 * rs_roam_options, rs_roam_view, rs_roam_mesh_options, rs_vt_options,
 * rs_vt_view, and the plane set rs_splat_layers) starts with `size_t size`, and all-zero still means
 * defaults:
 * - size 0: the layout of this header; right when the host was built
 *   against the header of the library it runs with (rs_version_number);
 * - size = sizeof the struct (`o.size = sizeof o;`): safe with any later
 *   library of the same major version. A library whose struct is larger
 *   reads the host's first `size` bytes and takes the rest as zero (the
 *   defaults of the fields the host did not know);
 * - a size larger than the library's struct (a host built against a newer
 *   header) is accepted when the extra bytes are all zero (the host left
 *   the new fields at their defaults) and refused otherwise with
 *   RS_ERR_UNSUPPORTED, rs_ctx_message naming the struct and the byte;
 *   a size below sizeof(size_t) is RS_ERR_INVALID_ARG.
 * rs_roam_mesh_bound, which returns nothing, says what it does with a
 * refused struct. Getters that fill one
 * (rs_ctx_limits) write at most out->size bytes (0: all) and set out->size
 * to what they wrote, so zero the struct or set its size before the call.
 * Structs held by value inside another (rs_splat_options' grid, coverage,
 * surface, style, markings and lighting; the lighting's normal) are
 * covered by the outer struct's size: their own `size`, where they have
 * one, is ignored there.
 * Rules for the library (how a struct may change without a new major
 * version): members are only appended, at offsets at or beyond the old
 * sizeof (an old host's tail padding is not read as a new field), zero
 * keeps meaning "default", and a struct nested by value never grows
 * (new settings of a nested struct go at the end of the outer one).
 * Plain data records (rs_dem_frame, rs_style, rs_style_line, rs_mark,
 * rs_image, rs_colour, rs_colour_stop, rs_surface_image, rs_allocator) and
 * the structs the library fills for the host (statistics, info, network
 * nodes, lanes, tiles) carry no size: their layout is fixed for a minor
 * version before 1.0 and a major one after.
 * ------------------------------------------------------------------------- */

/* ---------------------------------------------------------------------------
 * Results
 * ------------------------------------------------------------------------- */
typedef enum rs_result {
    RS_OK = 0,
    RS_ERR_INVALID_ARG = 1,  /* NULL pointer, option out of range, bad size */
    RS_ERR_NOMEM = 2,        /* an allocation failed; nothing leaked */
    RS_ERR_PARSE = 3,        /* malformed input (PGM, road file) */
    RS_ERR_LIMIT = 4,        /* input exceeds an rs_limits bound */
    RS_ERR_BUFFER_TOO_SMALL = 5, /* caller buffer smaller than *_bound() */
    RS_ERR_POOL_EXHAUSTED = 6,   /* ROAM node pool ran out (mesh still valid) */
    RS_ERR_UNSUPPORTED = 7,  /* feature not compiled in / not implemented */
    RS_ERR_CANCELLED = 8     /* the progress callback asked to stop */
} rs_result;

/* Static English description of a result code; never NULL. */
RS_API const char *rs_strerror(rs_result r);

/* ---------------------------------------------------------------------------
 * Context, allocator, limits
 * ------------------------------------------------------------------------- */

/* Allocator hook. All three functions are required when one is given.
 * realloc_fn(user, NULL, n) must behave as malloc; free_fn(user, NULL) is
 * never called. Allocation failure is reported by returning NULL. */
typedef struct rs_allocator {
    void *(*malloc_fn)(void *user, size_t size);
    void *(*realloc_fn)(void *user, void *ptr, size_t size);
    void (*free_fn)(void *user, void *ptr);
    void *user;
} rs_allocator;

/* Input limits, checked before anything is allocated. A zero field means
 * the default shown. Callers may tighten them (or loosen, at their risk). */
typedef struct rs_limits {
    size_t size;            /* 0, or sizeof (rs_limits) of the host's header: "ABI" above */
    uint32_t max_dem_side;     /* 16384: max DEM width or height (samples)  */
    uint64_t max_pixels;       /* 2^28: max output pixels (splat texture)   */
    uint64_t max_points;       /* 10^7: max road points over all roads; also
                                  the most markings (explicit and automatic)
                                  and road points their stretches copy, all
                                  together                                 */
    uint32_t max_line_length;  /* 65536: max bytes in one road-file line    */
    uint64_t max_road_cells;   /* 2^32: max road-grid cells (W*K x H*K)     */
    uint32_t max_pool_nodes;   /* 2^26: max ROAM node pool size             */
    uint64_t max_texture_pixels; /* 2^26: max pixels of a terrain or road
                                    texture (8192 x 8192; 256 MiB as RGBA8) */
    uint64_t max_field_work;   /* 2^30: steps the grid build may spend comparing
                                  road segments that share index cells, for the
                                  road field and for the line symbols' junction
                                  cuts each (docs/roadfield.md; the benchmark
                                  city takes 4x10^4, 10^6 points on one 100 m
                                  road 4.4x10^7); RS_ERR_LIMIT beyond */
    uint64_t max_atlas_bytes;  /* 2^28: bytes of a marking atlas's mip levels,
                                  all types together (16 bytes a texel, ~4/3
                                  of the types' rectangles; types with the
                                  same rectangle share them) */
    uint64_t max_linesym_bytes; /* 2^32: bytes of the line symbols (a road
                                  style's lines and dashes) while they are
                                  built, all roads together: ~470 bytes a
                                  piece (a segment, dash or join wedge of one
                                  line) with its half-planes, and the index
                                  entries over the pieces (docs/ROBUSTNESS.md);
                                  RS_ERR_LIMIT beyond */
    uint64_t max_dirty_compare; /* 2^20: candidate pixels rs_road_grid_update
                                  renders under the old and the new grid to
                                  report only those that change (~0.25 s at
                                  most); beyond, it reports the candidates,
                                  a superset (docs/embedding.md) */
    uint32_t max_patches;      /* 16: patches (local builds, each drawing in
                                  one or more rectangles) a grid made by
                                  rs_road_grid_update holds (one per edit,
                                  fewer where a patch covers earlier ones);
                                  the update that would
                                  pass it builds the grid whole instead, at a
                                  build's cost. A host that flattens on a
                                  worker (docs/embedding.md "Long chains")
                                  raises it; each patch adds its memory and a
                                  little to every window */
} rs_limits;

typedef struct rs_ctx rs_ctx;

/* Create a context. `alloc` and `limits` may be NULL (malloc, defaults);
 * both are copied. On success *out owns a context; free with rs_ctx_free. */
RS_API rs_result rs_ctx_create(const rs_allocator *alloc, const rs_limits *limits, rs_ctx **out);
RS_API void rs_ctx_free(rs_ctx *ctx);

/* Effective limits (defaults filled in): at most out->size bytes of them
 * (0: the whole struct; "ABI" above), so zero *out or set its size first. */
RS_API void rs_ctx_limits(const rs_ctx *ctx, rs_limits *out);

/* Detail of the last failure on this context ("line 12: width must be > 0"),
 * or "" after success. Owned by ctx; valid until the next call on ctx. */
RS_API const char *rs_ctx_message(const rs_ctx *ctx);

/* Progress callback: `done` of `total` work units. Return non-zero to cancel
 * (the call then returns RS_ERR_CANCELLED). Called from the calling thread. */
typedef int (*rs_progress_fn)(void *user, uint64_t done, uint64_t total);

/* Progress and cancel of the long calls made with this context
 * (docs/embedding.md "Progress and cancel"): rs_road_grid_build,
 * rs_splatter_create, rs_splat_window(_ws), rs_splat, rs_normal_window,
 * rs_network_build, rs_gpu_scene_create, rs_roam_create, rs_roam_set_dem,
 * rs_roam_refine_error, rs_roam_refine_count, rs_roam_frame,
 * rs_roam_update, rs_vt_create and rs_vt_make_tile call `fn` from the
 * calling thread at least every few milliseconds of work (the longest
 * gaps measured are in docs/embedding.md), with `done` of `total` units
 * (per call, below; done never goes back, the last call of a completed
 * call has done == total). A call whose options carry their own callback
 * (rs_splat_options.progress: the grid build, the splatter, its windows)
 * calls that one instead. A call made inside another (the grid build of
 * rs_splatter_create, the windows of rs_vt_make_tile) reports as part of
 * the outer one. Non-zero from `fn` stops the call: it returns
 * RS_ERR_CANCELLED ("cancelled"), frees what it made, and leaves its
 * objects usable (what each call leaves is documented with it). `fn` NULL:
 * none (the default). A callback changes no output byte. The context
 * keeps the pointers; one thread uses a context at a time. */
RS_API void rs_ctx_set_progress(rs_ctx *ctx, rs_progress_fn fn, void *user);

/* ---------------------------------------------------------------------------
 * DEM (lib/dem.c): W x H height samples at grid vertices, row-major, stored
 * as float in file units (metres = value * z_scale). NaN marks nodata. The
 * DEM carries its frame - cell size, z-scale and world origin - which the
 * splatter, the road grid and the mesher all read from it.
 *
 * Nodata policy (one for splat, mesh and render): a nodata sample takes the
 * lowest valid 8-neighbour height, spreading inwards layer by layer (an
 * all-nodata DEM reads as 0 everywhere). Its colour in a splat and its
 * vertex in a mesh come from that filled height.
 * ------------------------------------------------------------------------- */
typedef struct rs_dem rs_dem;

/* Parse a PGM (P2 ASCII or P5 binary, maxval 1..65535, 16-bit samples big
 * endian, '#' comments wherever whitespace is allowed) from memory.
 * `data` is not retained. Width and height must be >= 2. The frame is the
 * default one (cell size 1, z-scale 1, origin 0,0). Progress: the
 * context's callback (rs_ctx_set_progress), bytes of samples read of
 * `size`; a cancel makes nothing. */
RS_API rs_result rs_dem_parse_pgm(rs_ctx *ctx, const void *data, size_t size, rs_dem **out);

/* Make a DEM from `width*height` floats (row-major, copied). NaN = nodata;
 * infinities are rejected. Default frame. */
RS_API rs_result rs_dem_create(rs_ctx *ctx, uint32_t width, uint32_t height,
                               const float *samples, rs_dem **out);
RS_API void rs_dem_free(rs_ctx *ctx, rs_dem *dem);
RS_API uint32_t rs_dem_width(const rs_dem *dem);
RS_API uint32_t rs_dem_height(const rs_dem *dem);
/* Pointer to width*height samples, owned by dem. */
RS_API const float *rs_dem_samples(const rs_dem *dem);

/* The DEM's frame. All-zero means defaults. */
typedef struct rs_dem_frame {
    double cell_size; /* metres between samples; 0 -> 1; else 1e-9..1e9 */
    double z_scale;   /* metres per DEM unit; 0 -> 1; else 1e-12 <= |z_scale| <= 1e12 */
    double origin_x;  /* world coordinates of sample (0,0): road points are */
    double origin_y;  /* given in that world frame (e.g. UTM); |origin| <= 1e12 */
} rs_dem_frame;

/* Set the frame (copied; defaults filled in). Out-of-range values give
 * RS_ERR_INVALID_ARG naming the field, and leave the DEM unchanged. The map
 * extent (W-1)*cell_size must be at most 1e12 m. Set the frame before
 * sharing the DEM between threads. */
RS_API rs_result rs_dem_set_frame(rs_ctx *ctx, rs_dem *dem, const rs_dem_frame *frame);
/* The frame in use, defaults filled in. */
RS_API void rs_dem_get_frame(const rs_dem *dem, rs_dem_frame *out);
/* Lowest and highest valid sample (DEM units; both 0 when every sample is
 * nodata) and whether any sample is nodata. Computed once at creation. */
RS_API void rs_dem_height_range(const rs_dem *dem, double *zmin, double *zmax, int *has_nodata);

/* ---------------------------------------------------------------------------
 * Roads: named centreline polylines with a width, in metres, in the DEM
 * frame. Text format: docs/road-format.md.
 * ------------------------------------------------------------------------- */
typedef struct rs_roads rs_roads;

/* Parse the road text format from memory (need not be NUL-terminated).
 * On RS_ERR_PARSE, rs_ctx_message() names the line and the problem.
 * Progress (this and rs_roads_parse_ex): the context's callback
 * (rs_ctx_set_progress), bytes read of `size`; a cancel makes nothing. */
RS_API rs_result rs_roads_parse(rs_ctx *ctx, const char *text, size_t size, rs_roads **out);
/* Empty road set, to fill with rs_roads_add(). */
RS_API rs_result rs_roads_create(rs_ctx *ctx, rs_roads **out);
/* Append a road: `name` (copied, may be NULL), width > 0 metres, `n` >= 2
 * points as x0,y0,x1,y1,... (copied). Points must be finite. */
RS_API rs_result rs_roads_add(rs_ctx *ctx, rs_roads *roads, const char *name, double width,
                              const double *xy, size_t n);
RS_API void rs_roads_free(rs_ctx *ctx, rs_roads *roads);
RS_API size_t rs_roads_count(const rs_roads *roads);
/* The road file's `frame` header line (docs/road-format.md): NONE when the
 * file has none (the local frame, as before it existed), LOCAL for `frame
 * local`, WORLD for `frame world [CRS]`: points in a georeferenced CRS
 * with y growing north. *crs (may be NULL) gets the CRS text or NULL. The
 * library itself always works in the local frame (y down); the CLI maps
 * world roads into it with rs_roads_negate_y and a DEM origin of
 * (X, -Y) for the world point (X, Y) of sample (0,0). */
typedef enum rs_road_frame {
    RS_FRAME_NONE = 0,
    RS_FRAME_LOCAL = 1,
    RS_FRAME_WORLD = 2
} rs_road_frame;
RS_API rs_road_frame rs_roads_frame(const rs_roads *roads, const char **crs);
/* y -> -y for every point (north-up world coordinates to the y-down local
 * frame; s and t of markings are unchanged, since the map picture is). */
RS_API rs_result rs_roads_negate_y(rs_ctx *ctx, rs_roads *roads);
/* Road i: name (never NULL), width, points (owned by roads), point count.
 * Any output pointer may be NULL. The name and points stay valid until the
 * next rs_roads_add() on this set or rs_roads_free(). */
RS_API rs_result rs_roads_get(const rs_roads *roads, size_t i, const char **name, double *width,
                              const double **xy, size_t *n);

/* A copy of the whole set (roads, names, attributes, markings, point
 * attributes, the frame line), *out the caller's (rs_roads_free): a
 * snapshot a worker thread can build from while the host goes on editing
 * the original (docs/embedding.md "Long chains"). RS_ERR_INVALID_ARG for
 * NULL, RS_ERR_NOMEM; *out NULL on error. Cost: one copy of the set's
 * memory. */
RS_API rs_result rs_roads_copy(rs_ctx *ctx, const rs_roads *roads, rs_roads **out);

/* Edits (issue 30; docs/embedding.md "Edits and dirty rectangles"). Each
 * invalidates the pointers from rs_roads_get* (like rs_roads_add) and
 * leaves the set unchanged when it fails; errors are RS_ERR_INVALID_ARG
 * naming the bad value (index, width, point), RS_ERR_LIMIT past
 * rs_limits.max_points, RS_ERR_NOMEM. A set is edited by one thread, and
 * not while a call reads it (a grid build, a network build).
 *
 * rs_roads_remove: road i goes, with its explicit markings (rs_roads_add_mark,
 * `mark` lines) and its point attributes; the roads after it move down by
 * one, and so do the road indices of their markings and point attributes
 * (road j > i becomes j - 1 everywhere). */
RS_API rs_result rs_roads_remove(rs_ctx *ctx, rs_roads *roads, size_t i);
/* Road i gets new points (n >= 2 finite x,y pairs, copied; xy may point
 * into this set), width (> 0, finite; the width counts as given) and name
 * (copied; NULL keeps the name). Its attributes, explicit markings (their
 * s now measured along the new points) and index stay; its point
 * attributes stay on the same point indices, those at index n or later are
 * dropped. */
RS_API rs_result rs_roads_replace(rs_ctx *ctx, rs_roads *roads, size_t i, const char *name, double width,
                                  const double *xy, size_t n);
/* Set (or replace) point attribute `key` of point `point` of road i
 * (`X Y key=value` in the road text; crossing=zebra places a zebra),
 * with the parser's rules: key 1..64 characters of A-Z a-z 0-9 _ : . -,
 * value non-empty, valid UTF-8 without control characters. Copied. A
 * new attribute goes last in rs_roads_point_attr_at's order. value NULL
 * removes the attribute (nothing to remove is not an error). */
RS_API rs_result rs_roads_set_point_attr(rs_ctx *ctx, rs_roads *roads, size_t i, size_t point, const char *key,
                                         const char *value);

/* ---------------------------------------------------------------------------
 * Road attributes (docs/road-format.md): `key=value` words on a road's
 * header line, `road NAME width W class=residential lanes=2 style=NAME
 * oneway=yes`. Every attribute is kept as text (unknown keys too); the
 * known keys below are checked when parsed and also decoded into
 * rs_road_info. `width` may be left out when `class` or `lanes` is given:
 * the width then comes from the lane-width table of the parse profile.
 * ------------------------------------------------------------------------- */

/* OpenStreetMap highway classes with built-in default styles. */
typedef enum rs_road_class {
    RS_CLASS_NONE = 0, /* no class given: an unstyled road */
    RS_CLASS_MOTORWAY,
    RS_CLASS_TRUNK,
    RS_CLASS_PRIMARY,
    RS_CLASS_SECONDARY,
    RS_CLASS_TERTIARY,
    RS_CLASS_RESIDENTIAL,
    RS_CLASS_SERVICE,
    RS_CLASS_TRACK,
    RS_CLASS_PATH,
    RS_CLASS_FOOTWAY,
    RS_CLASS_CYCLEWAY,
    RS_CLASS_COUNT
} rs_road_class;

/* `oneway=`: yes (or 1, true), no (or 0, false), -1 (one way against the
 * direction of the points). NONE: not given, which is two-way except for
 * motorways (one carriageway each, as OpenStreetMap maps them). */
typedef enum rs_oneway {
    RS_ONEWAY_NONE = 0,
    RS_ONEWAY_NO = 1,
    RS_ONEWAY_YES = 2,
    RS_ONEWAY_REVERSE = 3
} rs_oneway;

/* `area=urban|rural`: which marking rules apply (German RMS: dashes 3/6 m
 * in towns, 6/12 m outside). AUTO: decided by the class (docs/road-format.md). */
typedef enum rs_area {
    RS_AREA_AUTO = 0,
    RS_AREA_URBAN = 1,
    RS_AREA_RURAL = 2
} rs_area;

/* Marking and lane-width standards. All-zero (RMS) is the default. */
typedef enum rs_profile {
    RS_PROFILE_RMS = 0,  /* Germany: RMS markings, RAS-Q/RAA lane widths */
    RS_PROFILE_MUTCD = 1 /* United States: MUTCD 2009 markings, AASHTO lane widths */
} rs_profile;

/* The decoded known attributes of one road. */
typedef struct rs_road_info {
    rs_road_class road_class; /* class= (RS_CLASS_NONE if absent) */
    int link;                 /* class= was a *_link value (motorway_link ...) */
    uint32_t lanes;           /* lanes= (1..16), 0 if absent */
    rs_oneway oneway;         /* oneway= */
    rs_area area;             /* area= */
    const char *style;        /* style= (owned by the road set), NULL if absent */
    int width_given;          /* 1: `width W` was given; 0: derived from class/lanes */
} rs_road_info;

/* A set of named styles (below; names unique within a set). */
typedef struct rs_styles rs_styles;

/* Options of rs_roads_parse_ex. All-zero means defaults. */
typedef struct rs_road_parse_options {
    size_t size;            /* 0, or sizeof (rs_road_parse_options) of the host's header: "ABI" above */
    rs_profile profile;  /* lane widths for roads without `width` */
    rs_styles *styles;   /* non-NULL: the text's style blocks are added to this
                            set (nothing is added when parsing fails) */
} rs_road_parse_options;

/* rs_roads_parse with options (`opts` may be NULL). Style blocks in the text
 * are always checked; they are kept only when opts->styles is given. */
RS_API rs_result rs_roads_parse_ex(rs_ctx *ctx, const char *text, size_t size,
                                   const rs_road_parse_options *opts, rs_roads **out);
/* Road i's known attributes. The style pointer stays valid as the name does
 * (rs_roads_get). RS_ERR_INVALID_ARG if i is out of range. */
RS_API rs_result rs_roads_get_info(const rs_roads *roads, size_t i, rs_road_info *out);
/* Value of attribute `key` of road i (NUL-terminated, owned by roads, valid
 * as the name is), or NULL if the road has no such attribute. */
RS_API const char *rs_roads_get_attr(const rs_roads *roads, size_t i, const char *key);
/* Number of attributes of road i (0 if i is out of range), and the k-th of
 * them in file order (either output may be NULL). */
RS_API size_t rs_roads_attr_count(const rs_roads *roads, size_t i);
RS_API rs_result rs_roads_attr_at(const rs_roads *roads, size_t i, size_t k, const char **key,
                                  const char **value);
/* Set (or replace) attribute `key` of road i, with the parser's rules: key
 * 1..64 characters of A-Z a-z 0-9 _ : . -, value valid UTF-8 without
 * control characters, known keys checked (class, lanes, oneway, area,
 * style; `width` is refused). Copied. Does not change the road's width.
 * Invalidates the pointers from rs_roads_get*, like rs_roads_add. */
RS_API rs_result rs_roads_set_attr(rs_ctx *ctx, rs_roads *roads, size_t i, const char *key,
                                   const char *value);
/* Name of a class as written in road files ("motorway"; "" for NONE), and
 * the class of a name (RS_CLASS_NONE if unknown; *link set for *_link
 * names when link is not NULL). Static strings. */
RS_API const char *rs_road_class_name(rs_road_class c);
RS_API rs_road_class rs_road_class_from_name(const char *name, int *link);

/* ---------------------------------------------------------------------------
 * Road styles (docs/road-format.md, seed 003 line symbols): what the
 * renderer paints on and beside a road as functions of the arc length s and
 * the signed lateral offset t (+ to the left of the direction of travel).
 * A style is plain data (no pointers): copy it freely.
 * ------------------------------------------------------------------------- */
#define RS_STYLE_NAME_MAX 63 /* bytes of a style name, NUL excluded */
#define RS_STYLE_MAX_LINES 32
#define RS_STYLE_MAX_DASH 8  /* on/off lengths of one dash pattern (even count) */
#define RS_STYLE_IMAGE_MAX 255 /* bytes of a style's surface image name (a path), NUL excluded */

/* Colours are straight (not premultiplied) sRGB bytes with alpha. */
typedef struct rs_colour {
    uint8_t r, g, b, a;
} rs_colour;

typedef enum rs_surface {
    RS_SURFACE_DEFAULT = 0,  /* the renderer's road surface (procedural asphalt or road texture) */
    RS_SURFACE_FILL = 1,     /* one colour: fill */
    RS_SURFACE_GRADIENT = 2  /* colour by |t|: gradient_centre at t = 0 to gradient_edge at the road edge */
} rs_surface;

/* `line T W #RRGGBB [dash ON OFF ...] [phase P]`: a band W metres wide
 * centred at lateral offset T, solid or dashed along s. The dash pattern
 * starts "on" at s = phase and repeats with period sum(dash). */
typedef struct rs_style_line {
    double offset;       /* T, metres, + left of the travel direction; |T| <= 1000 */
    double width;        /* W, metres, 0.001..1000 */
    rs_colour colour;
    uint32_t dash_count; /* 0: solid; else even, 2..RS_STYLE_MAX_DASH */
    double dash[RS_STYLE_MAX_DASH]; /* on, off, on, off ... metres, each 0.001..1e6 */
    double phase;        /* metres, |phase| <= 1e9; 0 when solid */
} rs_style_line;

typedef struct rs_style {
    char name[RS_STYLE_NAME_MAX + 1]; /* NUL-terminated, valid UTF-8 */
    rs_surface surface;
    rs_colour fill;                   /* RS_SURFACE_FILL */
    rs_colour gradient_centre, gradient_edge; /* RS_SURFACE_GRADIENT */
    double casing_width;              /* 0: no casing; else 0.001..1000 metres outside both road edges */
    rs_colour casing;
    uint32_t line_count;              /* 0..RS_STYLE_MAX_LINES, in paint order */
    rs_style_line line[RS_STYLE_MAX_LINES];
    /* `surface IMG [length L]` (docs/surface.md): a road-aligned image of
     * the road surface, mapped by (t, s): the image's left edge at t =
     * +half width (left of travel), its right edge at t = -half width,
     * its rows down the road in the travel direction, repeating along s
     * every `surface_length` metres and clamped across. It replaces the
     * procedural asphalt (or road texture) of the road, blended by its
     * alpha; fill / gradient, lines and markings go on top, the casing
     * stays under. The name (the path as written in the style text) is
     * matched against rs_style_options.surface_images when the grid is
     * built. */
    char surface_image[RS_STYLE_IMAGE_MAX + 1]; /* "" none; else 1..RS_STYLE_IMAGE_MAX bytes, UTF-8, no control characters */
    double surface_length;            /* metres of road per image height; 0 -> the image's aspect
                                         with the road width; else 0.001..1e6 */
    uint64_t surface_line;            /* text line of the `surface` keyword (0: added through the API) */
} rs_style;

RS_API rs_result rs_styles_create(rs_ctx *ctx, rs_styles **out);
/* Parse the style blocks of a text (a road file or a styles-only file; road
 * blocks in it are checked as rs_roads_parse checks them, then dropped).
 * Errors as rs_roads_parse: rs_ctx_message() starts with "line N:". */
RS_API rs_result rs_styles_parse(rs_ctx *ctx, const char *text, size_t size, rs_styles **out);
/* Add the style blocks of a text to `styles`; on failure the set is unchanged.
 * A name already in the set is an error. */
RS_API rs_result rs_styles_add_text(rs_ctx *ctx, rs_styles *styles, const char *text, size_t size);
/* Add one style (copied), checked against the limits documented on
 * rs_style; RS_ERR_INVALID_ARG naming the field otherwise. */
RS_API rs_result rs_styles_add(rs_ctx *ctx, rs_styles *styles, const rs_style *style);
/* Redefine the style of style->name (checked as rs_styles_add checks it,
 * copied): it takes the old one's place (rs_styles_get index), or is added
 * when the set has no style of that name. Roads naming it draw with the
 * new one in grids built (or updated: rs_road_grid_update) afterwards. */
RS_API rs_result rs_styles_replace(rs_ctx *ctx, rs_styles *styles, const rs_style *style);
RS_API void rs_styles_free(rs_ctx *ctx, rs_styles *styles);
RS_API size_t rs_styles_count(const rs_styles *styles);
/* Style i in the order added, or NULL. Owned by the set; valid until the
 * next add or replace on it, or rs_styles_free. */
RS_API const rs_style *rs_styles_get(const rs_styles *styles, size_t i);
/* The style called `name`, or NULL. Same lifetime as rs_styles_get. */
RS_API const rs_style *rs_styles_find(const rs_styles *styles, const char *name);

/* Which side of the road traffic keeps to (issue 27). The road attribute
 * `driving_side=left|right` wins over the default given in the options
 * (rs_style_options.driving_side, all-zero = right). */
typedef enum rs_driving_side {
    RS_DRIVING_RIGHT = 0, /* right-hand traffic (continental Europe, the Americas) */
    RS_DRIVING_LEFT = 1   /* left-hand traffic (UK, Japan, Australia, ...): everything side-dependent mirrored */
} rs_driving_side;

/* What a built-in default style is made for. All-zero fields take the
 * defaults shown. */
typedef struct rs_style_request {
    size_t size;            /* 0, or sizeof (rs_style_request) of the host's header: "ABI" above */
    rs_road_class road_class; /* NONE: the unstyled road (no lines) */
    uint32_t lanes;           /* 0 -> the class's default; else 1..16 */
    rs_oneway oneway;         /* NONE -> the class's default */
    rs_area area;             /* AUTO -> by class */
    rs_profile profile;
    double width;             /* road width, metres, 0..2000: the lanes are laid out
                                 in it (scaled to fit); 0 -> rs_style_default_width */
    /* Lanes per direction (two-way roads; `lanes:forward`, `lanes:backward`):
     * 0 -> from `lanes` (half, rounded down, against the points), else 1..16 each;
     * when both are given they override `lanes`. */
    uint32_t lanes_forward, lanes_backward;
    rs_driving_side driving_side;
} rs_style_request;

/* Built-in default style for `req` (tables and sources in
 * docs/road-format.md). The name is the class name ("" for NONE). */
RS_API rs_result rs_style_default(const rs_style_request *req, rs_style *out);
/* Road width the lane-width table gives for `req` (req->width is ignored). */
RS_API rs_result rs_style_default_width(const rs_style_request *req, double *width);

/* The style road i is drawn with: its `style=` name looked up in `styles`
 * (may be NULL), then among the built-in class names; else, for a road
 * with a class, a style in `styles` named after the class, else the
 * built-in default for its class, lanes, oneway, area and width under
 * `profile` (a road wider than 2000 m is laid out as a 2000 m one); else
 * the unstyled road (RS_SURFACE_DEFAULT, no lines). A
 * `style=` name found nowhere gives RS_ERR_INVALID_ARG naming the road. */
RS_API rs_result rs_road_style(rs_ctx *ctx, const rs_roads *roads, size_t i, const rs_styles *styles,
                               rs_profile profile, rs_style *out);
struct rs_style_options;
/* rs_road_style with all style options (NULL: defaults): also takes the
 * default driving side (opts->driving_side) for roads without a
 * `driving_side=` attribute. rs_road_style uses right-hand traffic for
 * those. */
RS_API rs_result rs_road_style_ex(rs_ctx *ctx, const rs_roads *roads, size_t i,
                                  const struct rs_style_options *opts, rs_style *out);

/* ---------------------------------------------------------------------------
 * Splatting (docs/design.md): a prepared, immutable splatter renders any
 * window of the output texture in four stages per window - coverage (how
 * much road is in each pixel), surface (terrain and road colours), overlays
 * (line symbols, markings: empty for now) and composite (C = a*T + (1-a)*S,
 * SPEC). Any tiling of the image into windows gives the same bytes as the
 * whole image.
 *
 * The output covers the DEM's cells: (W-1)*T x (H-1)*T pixels for T texels
 * per cell; pixel (px, py) covers [px*cs/T, (px+1)*cs/T) x [py*cs/T, ...).
 * ------------------------------------------------------------------------- */
typedef enum rs_buffer_mode {
    RS_BUFFER_DISTANCE = 0, /* cell centre within half-width (+ half a cell) of the centreline */
    RS_BUFFER_DILATE = 1    /* paper: 8-connected centreline raster + 8-connected dilation */
} rs_buffer_mode;

/* The default is analytic: on the benchmark scenes it is faster than the
 * alpha-map table and its edge error is two orders of magnitude smaller
 * (docs/design.md, "Which edges by default"). */
typedef enum rs_edge_mode {
    RS_EDGES_ANALYTIC = 0, /* exact area of the pixel inside the union of the
                              road buffers (round caps and joins), box-filtered */
    RS_EDGES_ALPHAMAP = 1  /* seed 000: road grid + 256-mask alpha-map table */
} rs_edge_mode;

/* An RGBA8 image, rows tightly packed (stride = 4*width). Not owned. */
typedef struct rs_image {
    uint32_t width, height;
    const uint8_t *rgba;
} rs_image;

/* Road grid (alpha-map edges only). All-zero means defaults. */
typedef struct rs_grid_options {
    rs_buffer_mode buffer; /* how road cells are chosen */
    double road_cell;      /* road-grid cell size, metres; 0 -> automatic
                              (narrowest road >= 4 cells, cell <= half a texel) */
    int edits;             /* non-zero: the grid keeps the pieces rs_road_grid_update compares
                              and rs_road_grid_rect_has_roads reads (about a tenth more build
                              time and memory); 0: it keeps none */
} rs_grid_options;

/* Coverage stage. All-zero means defaults. */
typedef struct rs_coverage_options {
    rs_edge_mode edges;    /* analytic (default) or alpha-map */
    uint32_t alpha_res;    /* alpha-map resolution (intervals per side); 0 -> 32, else 2..1024 */
    int hard_edge;         /* non-zero: no transition band (alpha-map tiles are 0/1) */
    double transition_px;  /* transition band, alpha-map pixels; 0 -> 2; at most alpha_res/2 */
    int jitter;            /* non-zero: seeded jitter in the band (seed 000 section 3) */
    uint32_t jitter_seed;  /* any value, 0 included */
    double jitter_amount;  /* amplitude in (0,1]; 0 -> 0.5 */
} rs_coverage_options;

/* One stop of a terrain colour ramp: a height in metres (the DEM's value
 * times z_scale) and its colour (a ignored: the terrain is opaque). */
typedef struct rs_colour_stop {
    double height;
    rs_colour colour;
} rs_colour_stop;

#define RS_RAMP_MAX_STOPS 256

/* How the terrain tint follows the height (docs/surface.md "Terrain colour"). */
typedef enum rs_tint_mode {
    RS_TINT_ABSOLUTE = 0, /* a function of the absolute height: `ramp`, else the built-in ramp
                             (0 m green .. 3000 m white); the same height has the same colour in
                             every DEM, crop and tile */
    RS_TINT_RELATIVE = 1  /* the built-in palette stretched over [height_min, height_max] metres, or
                             over the DEM's own height range when both are 0 (the behaviour before
                             issue 28: it depends on each DEM's range) */
} rs_tint_mode;

/* Surface stage. All-zero means defaults. */
typedef struct rs_surface_options {
    const rs_image *terrain_texture; /* NULL -> hypsometric tint + hillshade */
    const rs_image *road_texture;    /* NULL -> procedural asphalt */
    double texture_scale;            /* metres per texture repeat; 0 -> 10; else 1e-6..1e9 */
    rs_tint_mode tint;               /* default RS_TINT_ABSOLUTE */
    /* RS_TINT_ABSOLUTE: ramp_count stops (2..RS_RAMP_MAX_STOPS, finite heights strictly
     * increasing; below the first and above the last the end colours hold), linear in
     * between; NULL/0 -> the built-in ramp. Copied by rs_splatter_create (the caller's
     * array may go after it). */
    const rs_colour_stop *ramp;
    size_t ramp_count;
    double height_min, height_max;   /* RS_TINT_RELATIVE: metres, finite, min < max; both 0 -> the DEM's range */
    /* Added to the output pixel indices of the procedural asphalt's grain and of the tiled
     * textures: give each DEM tile of a map its offset in the map's pixel grid (the CLI:
     * the world position of sample (0,0) in pixels) and tiles rendered apart agree with
     * the whole map; 0 -> none, |offset| <= 2^52. */
    int64_t texel_offset_x, texel_offset_y;
} rs_surface_options;

/* Line-symbol anti-aliasing (docs/linesym.md). */
typedef enum rs_line_aa {
    RS_LINE_AA_EXACT = 0,  /* the exact area of each pixel inside each band (box filter) */
    RS_LINE_AA_HERMITE = 1 /* seed 003: smoothstep of the pixel centre's distance to each band edge */
} rs_line_aa;

/* Road styles (issue 13; docs/road-format.md, docs/linesym.md): every road is
 * drawn with rs_road_style(roads, i, styles, profile): casings under every
 * road surface, fill or gradient surfaces, then its lines, by the overlays
 * stage. Roads without class= or style= are unstyled, as before. All-zero
 * means defaults. The grid build resolves the styles; a splatter checks
 * that its grid was built with the same style options. */
typedef struct rs_style_options {
    size_t size;            /* 0, or sizeof (rs_style_options) of the host's header: "ABI" above */
    const rs_styles *styles; /* named styles for style= and per-class overrides (borrowed while
                                the grid is built); NULL -> built-in styles only */
    rs_profile profile;      /* built-in styles' standard: RS_PROFILE_RMS (0) or RS_PROFILE_MUTCD */
    rs_line_aa aa;           /* line anti-aliasing */
    int disable;             /* non-zero: every road unstyled (no casing, fill or line) */
    rs_driving_side driving_side; /* default for roads without `driving_side=`: lanes, centre
                                     and edge lines, stop and give-way lines and arrows
                                     (docs/road-format.md "Lanes") */
    /* The decoded images of the styles' `surface IMG` (docs/surface.md):
     * one entry per name, matched byte for byte against
     * rs_style.surface_image. Copied when the grid is built (mipmaps in
     * the grid), so the caller may free them afterwards. A style in use
     * whose image is not in the table fails the build (RS_ERR_INVALID_ARG
     * naming the style and the image). */
    const struct rs_surface_image *surface_images;
    size_t surface_image_count;
} rs_style_options;

/* A named RGBA8 image for rs_style_options.surface_images. */
typedef struct rs_surface_image {
    const char *name; /* NUL-terminated: the style's surface_image text */
    rs_image image;   /* 1..65536 pixels a side, at most the context's max_texture_pixels */
} rs_surface_image;

/* Normal-map options (rs_normal_window, below; docs/normals.md). */
typedef struct rs_normal_options {
    size_t size;            /* 0, or sizeof (rs_normal_options) of the host's header: "ABI" above */
    int directx;          /* non-zero: G = -Y, south / image down (DirectX engines) */
    double strength;      /* road-texture and surface-image relief: slope per unit of luminance change per pixel;
                             0 -> 1, else (0, 1e6] */
    double paint_height;  /* raised paint, metres; 0 -> 0.003, else (0, 1] */
    int no_paint;         /* non-zero: paint adds no relief */
} rs_normal_options;

/* Lit output (docs/surface.md, `--lighting`): the colour of every pixel
 * times a Lambert factor from the normal map (rs_normal_window's normals,
 * before encoding) and a sun: f = ambient + (1 - ambient) * max(0, N.L) /
 * L.z, so flat ground keeps its colour (f = 1) and ground facing away from
 * the sun gets `ambient`. The terrain's own hillshade is then left out
 * (the tint alone), so relief is shaded once. An optional specular term
 * (Blinn-Phong, viewer straight above) adds specular * R * max(0, N.H)^40
 * of white on road pixels (R = road weight): wet-looking asphalt. All-zero
 * means off. */
typedef struct rs_lighting_options {
    int enable;               /* non-zero: light the colour output */
    double sun_azimuth;       /* degrees clockwise from north (image up); used when sun_given */
    double sun_altitude;      /* degrees above the horizon, (0, 90]; used when sun_given */
    int sun_given;            /* 0 -> azimuth 315, altitude 45 (the hillshade's sun) */
    double ambient;           /* share of light in full shadow; 0 -> 0.3 (the hillshade's), else (0, 1] */
    double specular;          /* 0: none; else (0, 1] */
    rs_normal_options normal; /* the normals' strength and paint (directx is ignored) */
} rs_lighting_options;


/* ---------------------------------------------------------------------------
 * Road markings (issue 14, docs/markings.md): sprites of a marking atlas
 * placed in road coordinates. A marking's centre sits at arc length s (from
 * the road's first point) and lateral offset t (+ left of travel); it spans
 * `length` metres along the road and `width` across it and bends with the
 * road. The road file's `mark TYPE road=NAME s=S t=T [length=L] [width=W]
 * [flip]` lines add explicit markings; the type name is checked against the
 * atlas when the road grid is built (an unknown type fails there, naming the
 * mark's line).
 * ------------------------------------------------------------------------- */
#define RS_MARK_TYPE_MAX 31 /* bytes of a marking type name, NUL excluded */

typedef struct rs_mark {
    const char *type; /* atlas type name: 1..RS_MARK_TYPE_MAX of A-Z a-z 0-9 _ - */
    size_t road;      /* road index */
    double s, t;      /* centre: arc length and lateral offset, metres */
    double length;    /* along the road, metres; 0 -> the atlas type's LENGTH */
    double width;     /* across the road, metres; 0 -> the atlas type's WIDTH */
    int flip;         /* non-zero: turned 180 degrees (facing against the road's direction) */
    uint64_t line;    /* road-file line (0: added through the API) */
} rs_mark;

/* Append an explicit marking (the type name is copied). RS_ERR_INVALID_ARG
 * for a bad name, a road out of range, non-finite s or t, or a negative or
 * non-finite length or width. */
RS_API rs_result rs_roads_add_mark(rs_ctx *ctx, rs_roads *roads, const rs_mark *mark);
RS_API size_t rs_roads_mark_count(const rs_roads *roads);
/* Marking i; out->type is owned by the road set (valid as road names are). */
RS_API rs_result rs_roads_get_mark(const rs_roads *roads, size_t i, rs_mark *out);

/* Point attributes: `X Y key=value ...` on a point line of a road block
 * (`crossing=zebra` places a zebra crossing there, docs/markings.md). All
 * of them in file order: road index, point index within the road, key and
 * value (owned by the road set, valid as road names are). */
RS_API size_t rs_roads_point_attr_count(const rs_roads *roads);
RS_API rs_result rs_roads_point_attr_at(const rs_roads *roads, size_t k, size_t *road, size_t *point,
                                        const char **key, const char **value);

/* The road network (docs/network.md): where road records meet (nodes, each
 * with its legs) and which records continue each other (strokes: chains of
 * records that share one arc length s, so a road split into several
 * records is drawn as one). Built from a road set alone; the road grid
 * builds its own with default options for drawing. Immutable after the
 * build: the queries may run from several threads at once. */
typedef struct rs_network rs_network;

/* Options of rs_network_build. All-zero means defaults. */
typedef struct rs_network_options {
    size_t size;            /* 0, or sizeof (rs_network_options) of the host's header: "ABI" above */
    double tolerance; /* metres: points closer than this are one node, an end point
                         this near another road's centreline is a T; 0 -> 0.05,
                         else 1e-9 .. 1000 */
} rs_network_options;

typedef enum rs_node_kind {
    RS_NODE_END = 0,          /* degree 1: a road ends here and meets nothing */
    RS_NODE_CONTINUATION = 1, /* degree 2: two road ends meet (a split) or a road touches itself */
    RS_NODE_JUNCTION = 2      /* degree 3 or more */
} rs_node_kind;

/* rs_network_node.control: flags from the node's point attributes and roads */
#define RS_NODE_STOP 1u        /* highway=stop on a point of the node */
#define RS_NODE_GIVE_WAY 2u    /* highway=give_way */
#define RS_NODE_SIGNALS 4u     /* highway=traffic_signals */
#define RS_NODE_CROSSING 8u    /* crossing=<any value> */
#define RS_NODE_ROUNDABOUT 16u /* a leg's road has junction=roundabout */

typedef struct rs_network_node {
    double x, y;        /* position in the road set's frame (a point of one of its roads) */
    uint32_t degree;    /* number of legs */
    rs_node_kind kind;
    uint32_t control;   /* RS_NODE_* flags */
} rs_network_node;

typedef enum rs_leg_kind {
    RS_LEG_START = 0,   /* the road's first point is at the node; the leg leaves along the road */
    RS_LEG_END = 1,     /* the road's last point; the leg runs back along the road */
    RS_LEG_FORWARD = 2, /* the road passes through the node (a shared interior point, a T on a
                           segment, or an end inside its surface: docs/network.md): the part
                           after it ... */
    RS_LEG_BACKWARD = 3 /* ... and the part before it */
} rs_leg_kind;

typedef struct rs_network_leg {
    uint32_t road;     /* road index in the road set */
    rs_leg_kind kind;
    uint32_t segment;  /* the road's point index at the node (START: 0, END: last), or for a T
                          on a segment, the segment (points segment, segment+1) */
    double s;          /* the road's arc length at the node, metres from its first point */
    double angle;      /* direction of the leg away from the node, radians (atan2 of dy, dx in
                          the road set's frame), -pi .. pi */
    int priority;      /* class rank (motorway 9 .. path/footway/cycleway 1, none 0), + 10 for
                          priority_road=designated|yes_unposted, + 20 for junction=roundabout */
    int major;         /* 1: the highest priority at this node (the road with right of way) */
} rs_network_leg;

/* A record's place in its stroke. */
typedef struct rs_road_stroke {
    uint32_t stroke;   /* stroke index, 0 .. rs_network_stroke_count - 1 (strokes are numbered by
                          their first record, in road order) */
    double s_offset;   /* stroke arc length at the record's first point, metres (reversed: at its
                          last point it is s_offset - length) */
    double length;     /* the record's length, metres */
    uint32_t prev, next; /* the records before and after it in the stroke; UINT32_MAX at the stroke's
                            ends (a closed stroke's last record has next UINT32_MAX: its seam) */
    int closed;        /* the stroke is a ring (its last record ends where its first begins) */
    int reversed;      /* the record runs against the stroke (a two-way record pointing the other
                          way): the stroke's arc length at the record's own s is s_offset - s */
} rs_road_stroke;

/* Build the network of `roads` (opts may be NULL). RS_ERR_INVALID_ARG for
 * a bad tolerance, RS_ERR_NOMEM; *out is the caller's (rs_network_free).
 * Cost: near-linear in the number of points (spatial hashing). Progress
 * (the context's callback): polls between and within the stages, done 0
 * of 1 until the end; a cancel makes nothing. */
RS_API rs_result rs_network_build(rs_ctx *ctx, const rs_roads *roads, const rs_network_options *opts,
                                  rs_network **out);
RS_API void rs_network_free(rs_ctx *ctx, rs_network *net);
/* Number of road records the network was built from. */
RS_API size_t rs_network_road_count(const rs_network *net);
RS_API size_t rs_network_node_count(const rs_network *net);
/* Node i (0 .. count-1; nodes are numbered by their first point in road order). */
RS_API rs_result rs_network_get_node(const rs_network *net, size_t i, rs_network_node *out);
/* Leg k (0 .. degree-1) of node i, legs sorted by angle (then road, kind). */
RS_API rs_result rs_network_get_leg(const rs_network *net, size_t node, size_t k, rs_network_leg *out);
RS_API size_t rs_network_stroke_count(const rs_network *net);
/* The stroke of road record `road`. */
RS_API rs_result rs_network_road_stroke(const rs_network *net, size_t road, rs_road_stroke *out);
/* The records of stroke k in order along it: writes up to `cap` road
 * indices into `roads` (may be NULL when cap is 0) and returns the
 * stroke's record count (0 for k out of range). */
RS_API size_t rs_network_stroke_roads(const rs_network *net, size_t k, uint32_t *roads, size_t cap);

/* The junction area of node `node` (docs/network.md "Junction areas"):
 * the polygon where its legs' surfaces meet, as osm2streets draws an
 * intersection. Each leg's road (half its width each side) is cut square
 * at its trim: the farthest point along the leg where its left edge meets
 * the next leg's right edge, or its right edge the previous leg's left
 * edge (legs counter-clockwise; neighbours at 180 degrees or more apart
 * add nothing), at most as far as the record runs from the node. The
 * polygon is the cut ends' corners, right then left of each leg in the
 * legs' order: counter-clockwise, x y pairs in the road set's frame,
 * corners of neighbouring legs that coincide given once. Writes up to
 * `cap` points into xy (2 cap doubles; may be NULL when cap is 0) and
 * each leg's trim (metres from the node) into trim[0 .. degree-1] (may be
 * NULL); returns the polygon's point count, at most 2 x degree (0: a node
 * of degree below 3, node out of range, or roads not the network's). No
 * allocation; safe from several threads. */
RS_API size_t rs_network_junction_area(const rs_network *net, const rs_roads *roads, size_t node, double *xy,
                                       size_t cap, double *trim);

/* Lanes (issue 27; docs/road-format.md "Lanes"): the cross-section of a
 * road record from `lanes`, `lanes:forward`, `lanes:backward`, `oneway`,
 * `turn:lanes(:forward|:backward)`, `width:lanes(:forward|:backward)`,
 * `driving_side` and the class defaults of the profile. Lanes are listed
 * across the road from its left edge (t = +width/2, left of the direction
 * of its points) to its right edge; t as everywhere (SPEC). */
#define RS_LANES_MAX 32
/* rs_lane.turn: arrows of one `turn:lanes` entry */
#define RS_TURN_THROUGH 1u
#define RS_TURN_LEFT 2u    /* left, slight_left, sharp_left */
#define RS_TURN_RIGHT 4u   /* right, slight_right, sharp_right */
#define RS_TURN_REVERSE 8u

typedef struct rs_lane {
    double t_left, t_right; /* the lane's edges, metres from the centreline (t_left > t_right) */
    int direction;          /* +1: traffic along the points, -1: against them, 0: both ways
                               (the one lane of a single-lane two-way road) */
    uint32_t turn;          /* RS_TURN_* flags, 0: none given */
} rs_lane;

typedef struct rs_road_lanes {
    uint32_t count;             /* lanes, 1 .. RS_LANES_MAX */
    uint32_t forward, backward; /* lanes with direction +1 and -1 */
    rs_driving_side side;       /* the side in effect (attribute or default) */
    double width;               /* the road's width, metres */
    double centre;              /* t of the boundary between the two directions (two-way roads
                                   with lanes both ways), else 0 */
    rs_lane lane[RS_LANES_MAX]; /* lane[0 .. count-1] from the left edge to the right */
} rs_road_lanes;

/* The lanes of road i (opts: profile and default driving side; NULL:
 * defaults). Filled into the caller's *out (no allocation); malformed
 * lane attributes are ignored (class defaults instead), as documented.
 * RS_ERR_INVALID_ARG if i is out of range or out is NULL. */
RS_API rs_result rs_road_lanes_get(const rs_roads *roads, size_t i, const struct rs_style_options *opts,
                                   rs_road_lanes *out);
/* The lanes at arc length s along stroke k of net (built from `roads`):
 * the record there (*road, may be NULL) and its lanes seen in the
 * stroke's direction (a record drawn against its points has its lanes
 * mirrored and directions negated, so +1 is along the stroke). s is
 * clamped to the stroke. RS_ERR_INVALID_ARG for k out of range, roads not
 * the network's or out NULL. */
RS_API rs_result rs_network_lanes_at(const rs_network *net, const rs_roads *roads, size_t k, double s,
                                     const struct rs_style_options *opts, size_t *road, rs_road_lanes *out);

/* A marking atlas: an RGBA image and its index (one line per type, `NAME X
 * Y W H LENGTH WIDTH`: the type's pixel rectangle and its size in metres
 * along x across the road; atlas row 0 points the way the road runs),
 * mipmapped per type with premultiplied alpha. Immutable once made; share
 * it between threads freely. */
typedef struct rs_atlas rs_atlas;
#define RS_ATLAS_MAX_TYPES 1024

/* From an image and an index text (need not be NUL-terminated). Errors in
 * the index are RS_ERR_PARSE with "atlas index line N: ..." messages. The
 * image is copied (only the types' rectangles). */
RS_API rs_result rs_atlas_create(rs_ctx *ctx, const rs_image *image, const char *index, size_t size,
                                 rs_atlas **out);
/* The built-in atlas (arrows, stop and give-way lines, zebra, cycle, BUS,
 * STOP, SLOW; docs/markings.md lists the types). */
RS_API rs_result rs_atlas_default(rs_ctx *ctx, rs_atlas **out);
RS_API void rs_atlas_free(rs_ctx *ctx, rs_atlas *atlas);
RS_API size_t rs_atlas_count(const rs_atlas *atlas);
/* Type i: name (owned by the atlas), LENGTH and WIDTH in metres, pixel
 * size. Any output may be NULL. */
RS_API rs_result rs_atlas_get(const rs_atlas *atlas, size_t i, const char **name, double *length,
                              double *width, uint32_t *w, uint32_t *h);
/* Index of the type called `name`, or -1. */
RS_API long rs_atlas_find(const rs_atlas *atlas, const char *name);

/* Markings (issue 14, docs/markings.md). All-zero means defaults: the
 * built-in atlas, explicit and automatic markings. */
typedef struct rs_marking_options {
    const rs_atlas *atlas; /* NULL -> the built-in atlas; else borrowed: it must outlive the grid */
    int no_auto;           /* non-zero: only the road set's explicit markings */
    int disable;           /* non-zero: no markings at all */
} rs_marking_options;

/* All-zero means defaults. The frame (cell size, z-scale, origin) is the DEM's. */
typedef struct rs_splat_options {
    size_t size;            /* 0, or sizeof (rs_splat_options) of the host's header: "ABI" above */
    uint32_t texels;                /* output texels per DEM cell side; 0 -> 8, else 1..1024 */
    rs_grid_options grid;
    rs_coverage_options coverage;
    rs_surface_options surface;
    rs_style_options style;
    rs_marking_options markings;
    rs_progress_fn progress;        /* may be NULL; see rs_splat_window */
    void *progress_user;
    rs_lighting_options lighting;   /* lit output (off by default) */
} rs_splat_options;

/* The road grid: the roads prepared for one DEM and one set of options -
 * road cells (DEM cells split K x K) classified by their 8-neighbour mask
 * for alpha-map edges, the road field (per-pixel road coordinates, index
 * grid over the segments) for analytic edges. Built once, splatted any
 * number of times, read-only afterwards. */
typedef struct rs_road_grid rs_road_grid;

typedef struct rs_road_grid_stats {
    uint32_t k;                 /* road cells per DEM cell side (0: no cell grid) */
    double road_cell;           /* road cell size, metres */
    uint64_t road_cells;        /* all road cells */
    uint64_t interior_cells;    /* road cells with all 8 neighbours road */
    uint64_t boundary_cells;    /* road cells with a terrain neighbour */
    uint64_t by_type[6];        /* boundary cells by tile type (RS_TILE_*) */
    uint64_t tiles_allocated;   /* sparse storage blocks in use */
    uint64_t segments;          /* road segments in the road field (0: none built) */
    uint64_t marks_explicit;    /* markings placed from the road set's records */
    uint64_t marks_auto;        /* markings placed by the automatic rules */
    uint64_t bytes;             /* memory held by the grid (its edit pieces included: rs_road_grid_update) */
} rs_road_grid_stats;

/* Prepare `roads` over `dem` (its frame included). `opts` may be NULL. Reads
 * texels, grid, coverage.edges, style and progress. The grid keeps no pointer to
 * dem or roads. */
RS_API rs_result rs_road_grid_build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads,
                                    const rs_splat_options *opts, rs_road_grid **out);
RS_API void rs_road_grid_free(rs_ctx *ctx, rs_road_grid *grid);
RS_API void rs_road_grid_get_stats(const rs_road_grid *grid, rs_road_grid_stats *out);

/* Edits with dirty rectangles (issue 30; docs/embedding.md "Edits and
 * dirty rectangles"). A rectangle of output pixels: columns [x0, x1),
 * rows [y0, y1), in the pixels of the grid's texels (the splatter's image). */
typedef struct rs_pixel_rect {
    uint32_t x0, y0, x1, y1;
} rs_pixel_rect;

/* The grid of the edited `roads`, and which pixels the edit may change.
 * `old` is a grid rs_road_grid_build (or this call) made for the same
 * `dem` and `opts` from the roads before the edit (any number of edits:
 * rs_roads_add, _remove, _replace, _set_attr, _set_point_attr,
 * _add_mark, rs_styles_replace on the opts' style table); it is only read
 * and stays the caller's (splatters on it may go on rendering from other
 * threads meanwhile). *out is a new grid (the caller's: rs_road_grid_free),
 * splatting to the same bytes
 * as rs_road_grid_build(ctx, dem, roads, opts) would, that also holds the
 * dirty rectangles (rs_road_grid_dirty): their union covers every pixel
 * whose colour or weight (rs_splat_window) may differ between splats of
 * `old` and of *out (the normal map and lit output read one pixel around:
 * grow them by one pixel; rs_splat_layers_window's planes are not
 * covered). The rectangles do not overlap, are sorted by rows and then
 * columns. They hold exactly the pixels whose unlit colour or weight
 * differ when the pieces that changed reach at most
 * rs_limits.max_dirty_compare pixels (2^20): those candidates are rendered
 * under both grids and compared; beyond, the rectangles are the candidates
 * (for one road moved, added or removed on the 10k-road city 1.9 to 2.4
 * times the pixels that change, docs/embedding.md). The roads are matched by what
 * they draw, not by index: a removal's renumbering dirties nothing else.
 * `old` must have been built with opts->grid.edits set (else
 * RS_ERR_INVALID_ARG): only such a grid keeps the pieces this compares
 * (counted in its stats' bytes; about a tenth of rs_road_grid_build's
 * time); *out keeps them too, whatever opts->grid.edits says. A grid for
 * other DEM dimensions, frame, texels, edge or buffer mode than `opts`
 * give is RS_ERR_INVALID_ARG naming the value; when the edit changes the
 * alpha-map road cell (the narrowest road decides it) the whole image is
 * the candidate. Cost (docs/embedding.md "Patches"): with analytic edges
 * and the whole map's style switches unchanged (one casing colour, one
 * fill), the roads near the edit are built alone and *out shares old's
 * structures, drawing the new parts in patch rectangles, its network
 * updated in place (on the 10k-road city medians of 0.031 to 0.048 of a
 * build per kind of edit; over 200 roads moved one at a time the 90th
 * percentile 0.056, a record of a long stroke up to about 0.55); when it would
 * pass rs_limits.max_patches (16), or the edit changes a
 * quarter of the image or a style switch, or with alpha-map edges, a full
 * rs_road_grid_build plus the comparison. Grids sharing structures count
 * their holders atomically: any of them may be freed, from any thread,
 * while the others are in use. Progress and cancel: rs_road_grid_build's,
 * then the renders' (2 units a candidate pixel). Errors leave *out NULL. */
RS_API rs_result rs_road_grid_update(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads,
                                     const rs_splat_options *opts, const rs_road_grid *old, rs_road_grid **out);
/* Patches the grid holds (0 for a grid from rs_road_grid_build): each
 * rs_road_grid_update adds at most one (a local build of the roads near
 * the edit, drawing in the rectangles along the changed area), and builds
 * the grid whole instead of passing rs_limits.max_patches. A host that keeps edits off its frame
 * thread's budget flattens the grid on a worker before that
 * (docs/embedding.md "Long chains"). Read-only: any thread. */
RS_API size_t rs_road_grid_patch_count(const rs_road_grid *grid);
/* Long chains of edits without a whole build on the caller's thread
 * (docs/embedding.md "Long chains"). `flat` is a whole grid a worker built
 * (rs_road_grid_build, opts.grid.edits, analytic edges) from a copy of the
 * roads (rs_roads_copy) taken while `since` was the chain's latest grid;
 * `current` is a later grid of the same chain (rs_road_grid_update from
 * since, any number of times). *out draws exactly what current draws (no
 * dirty rectangles) with flat's structures and only the patches current
 * made after since, so the chain goes on from it far from
 * rs_limits.max_patches. When a whole build came between since and
 * current, or the edits since changed a map-wide switch (a casing colour,
 * one fill everywhere), *out is current's patches on current's base (the
 * same pixels; patch count unchanged). All three are only read and stay
 * the caller's; *out is the caller's (rs_road_grid_free) and shares their
 * structures. RS_ERR_INVALID_ARG naming what does not fit: a grid not made
 * for edits, flat patched or for another DEM, frame, texels or edge mode,
 * or built from other roads or styles than since (their fingerprints);
 * RS_ERR_NOMEM. Cost: a copy of current's patch list (no build, no
 * render). */
RS_API rs_result rs_road_grid_rebase(rs_ctx *ctx, const rs_road_grid *current, const rs_road_grid *since,
                                     const rs_road_grid *flat, rs_road_grid **out);
/* The grid's dirty rectangles (none for a grid from rs_road_grid_build):
 * returns their count and copies the first min(count, cap) into rects
 * (NULL with cap 0: the count alone). Read-only: any thread. */
RS_API size_t rs_road_grid_dirty(const rs_road_grid *grid, rs_pixel_rect *rects, size_t cap);
/* 0 when no road paint of the grid (surface, casing, lines, markings, and
 * the anti-aliased pixel around them) can reach output pixels [x0, x1) x
 * [y0, y1), so a host may skip that tile and draw the terrain alone; 1
 * when some may (conservative: a 1 may still find no road pixel; never 0
 * where a road pixel is). An empty rectangle gives 0. It reads the pieces
 * of a grid built with opts->grid.edits: without them the answer is 1. O(pieces near the
 * rectangle); read-only: any thread. */
RS_API int rs_road_grid_rect_has_roads(const rs_road_grid *grid, uint32_t x0, uint32_t y0, uint32_t x1,
                                       uint32_t y1);

/* Output size for `dem` and `opts`: (W-1)*T x (H-1)*T. Fails with
 * RS_ERR_LIMIT when it exceeds the context's max_pixels. */
RS_API rs_result rs_splat_size(rs_ctx *ctx, const rs_dem *dem, const rs_splat_options *opts,
                               uint32_t *width, uint32_t *height);

typedef struct rs_splatter rs_splatter;

/* Prepare a splatter: validate once, build the alpha-map integral tables,
 * the DEM's nodata-filled heights, height range and light vector once; at
 * 1 or 2 texels a cell on a DEM of at most 2^22 samples without a terrain
 * texture also every sample's terrain colour (12 bytes a sample, held by
 * the splatter), which windows otherwise compute for their own samples.
 * Give exactly one of `roads` (the splatter builds and owns its grid) and
 * `grid` (from rs_road_grid_build with the same dem and options; borrowed:
 * it must outlive the splatter). An analytic grid without styles and
 * markings may have been built for more texels (the splatter indexes its
 * road field for its own pixels: the same bytes as a grid built for them);
 * one with styles or markings must match the texels (RS_ERR_INVALID_ARG:
 * they are laid out in its pixels). `dem` and the option textures are
 * borrowed too. The splatter is immutable: rs_splat_window may be called on
 * it from several threads at once, each with its own context. Progress:
 * opts->progress (else the context's), the grid build's units and one
 * more (analytic edges; alpha-map edges report only their grid's sweep);
 * a cancel makes nothing. */
RS_API rs_result rs_splatter_create(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads,
                                    const rs_road_grid *grid, const rs_splat_options *opts,
                                    rs_splatter **out);
RS_API void rs_splatter_free(rs_ctx *ctx, rs_splatter *s);
/* Size of the whole output image in pixels. */
RS_API void rs_splatter_size(const rs_splatter *s, uint32_t *width, uint32_t *height);
/* The grid in use (owned by the splatter or borrowed). */
RS_API const rs_road_grid *rs_splatter_grid(const rs_splatter *s);

/* Optional per-call profile: stage times from the caller's clock (the
 * library itself reads no clock) and counts, ADDED to the fields. */
typedef struct rs_splat_profile {
    double (*clock_ms)(void *user); /* NULL: no timings */
    void *clock_user;
    double coverage_ms, surface_ms, overlays_ms, composite_ms;
    uint64_t pixels;       /* pixels rendered */
    uint64_t road_pixels;  /* pixels with some road (weight > 0) */
    uint64_t mark_tests;   /* road pixels inside the markings' row spans (pixel, marking pairs examined);
                              for a small marking whose blends the grid made (docs/markings.md): its
                              blends on road pixels */
    uint64_t mark_pixels;  /* blends: a pixel under two markings counts twice */
} rs_splat_profile;

/* Render the window [x0, x0+w) x [y0, y0+h) of the output image: RGBA8 into
 * `rgba` (row r of the window at rgba + r*rgba_stride bytes; rgba_stride >=
 * 4*w) and, when `weight` is not NULL, the road weight R = 1 - alpha as
 * uint16 0..65535 (row r at weight + r*weight_stride values). The window
 * must lie inside the image (RS_ERR_INVALID_ARG). Scratch memory (a few
 * rows of the window) comes from ctx's allocator. Progress: the splatter's
 * progress callback (else the context's) gets (rows done, h) from this
 * thread after each band of rows and, within a band, after each piece of
 * 2^18 pixels; with several threads the splatter's must be thread-safe. A
 * cancel leaves the window's rows partly written. `profile` may be NULL. With
 * opts->lighting.enable, each band of rows is lit by its normals as soon as
 * it is splatted (scratch as rs_normal_window's; docs/surface.md). */
RS_API rs_result rs_splat_window(rs_ctx *ctx, const rs_splatter *s, uint32_t x0, uint32_t y0,
                                 uint32_t w, uint32_t h, uint8_t *rgba, size_t rgba_stride,
                                 uint16_t *weight, size_t weight_stride, rs_splat_profile *profile);

/* A reusable workspace: the scratch of rs_splat_window for every window at
 * most `max_width` pixels wide (any height) of splatter `s`, allocated once
 * from ctx's allocator (about 10 MB at most, whatever the window;
 * rs_splat_workspace_bytes tells). rs_splat_window_ws then renders a window
 * with no allocation at all and the same bytes as rs_splat_window (with
 * opts->lighting.enable, or a normal plane of rs_splat_layers_window, the
 * first such call adds the normal map's scratch to the workspace, as
 * rs_normal_window's for max_width columns; the first rs_splat_layers_window
 * of a splatter with styles or markings adds the layers' two planes, 16
 * bytes a pixel of a piece: later calls allocate nothing). A workspace belongs to one splatter and serves one call
 * at a time: give each thread its own. max_width: 1..image width
 * (RS_ERR_INVALID_ARG otherwise). Free it before the splatter. */
typedef struct rs_splat_workspace rs_splat_workspace;
RS_API rs_result rs_splat_workspace_create(rs_ctx *ctx, const rs_splatter *s, uint32_t max_width,
                                           rs_splat_workspace **out);
RS_API void rs_splat_workspace_free(rs_ctx *ctx, rs_splat_workspace *ws);
RS_API size_t rs_splat_workspace_bytes(const rs_splat_workspace *ws);
/* rs_splat_window through `ws` (made for `s`; the window at most its width,
 * else RS_ERR_INVALID_ARG). */
RS_API rs_result rs_splat_window_ws(rs_ctx *ctx, const rs_splatter *s, rs_splat_workspace *ws, uint32_t x0,
                                    uint32_t y0, uint32_t w, uint32_t h, uint8_t *rgba, size_t rgba_stride,
                                    uint16_t *weight, size_t weight_stride, rs_splat_profile *profile);

/* Layers (docs/embedding.md "Layers"): the parts rs_splat_window blends,
 * as separate planes, for a host that lights or blends itself. Each plane
 * is optional (NULL: not written); row r of the window at plane + r*stride
 * (strides in bytes for the 8-bit planes, in values for coverage; at least
 * 4*w, 3*w or w). The caller owns every plane; nothing is kept.
 *
 *   terrain   RGBA8, A = 255: the terrain colour with no roads at every
 *             pixel (tint times hillshade, or the terrain texture; with
 *             opts->lighting.enable the tint alone, unshaded: the lighting
 *             shades the relief)
 *   casing    RGBA8 premultiplied: road casings (styles' borders, drawn
 *             on the ground beside a road) over the terrain; 0 elsewhere
 *   surface   RGBA8, A = 255: the road colour before paint at every pixel:
 *             the material (procedural asphalt or the road texture),
 *             under roads with their styles' fills, gradients and surface
 *             images (surface_unstyled: the material alone, what
 *             rs_gpu_scene's shader reads as its road texture)
 *   coverage  uint16: the road weight R, 0..65535, rs_splat_window's weight
 *   paint     RGBA8 premultiplied: line symbols and markings as painted on
 *             the road surface, 0 where R = 0
 *   normal    RGB8: rs_normal_window's bytes with normal_options (NULL:
 *             the splatter's opts->lighting.normal; all zero: defaults)
 *
 * With t = terrain/255, c = casing/255, s = surface/255, p = paint/255
 * (premultiplied: ca, pa their alphas) and R = coverage/65535, per channel:
 *
 *   ground = t (1 - ca) + c        road = s (1 - pa) + p
 *   colour = ground (1 - R) + road R
 *
 * which is rs_splat_window's colour (before lighting: a lit splatter's
 * output is this colour lit as rs_lighting_options says, with the
 * unrounded normals) within
 * 1/255 per channel: 255 * colour rounds to the output byte or a
 * neighbour (the layers are rounded to bytes; the casing and paint colours
 * take up the rounding of the planes under them). Exact where R = 0 with no
 * casing, and where R = 65535 with no paint.
 *
 * The planes of one call come from one pass over the window (one coverage
 * and surface per piece; the paint is painted twice, over black and over
 * white, for its colour and alpha; the normal plane, rs_normal_window's
 * code band by band, computes coverage and paint again over its one-pixel
 * halo). Any window gives the bytes of the same pixels of the whole image.
 * All-zero (no plane) is RS_ERR_INVALID_ARG. */
typedef struct rs_splat_layers {
    size_t size;            /* 0, or sizeof (rs_splat_layers) of the host's header: "ABI" above */
    uint8_t *terrain;
    size_t terrain_stride;
    uint8_t *casing;
    size_t casing_stride;
    uint8_t *surface;
    size_t surface_stride;
    uint16_t *coverage;
    size_t coverage_stride; /* values */
    uint8_t *paint;
    size_t paint_stride;
    uint8_t *normal;
    size_t normal_stride;
    const rs_normal_options *normal_options; /* NULL: the splatter's opts->lighting.normal */
    int surface_unstyled;                    /* non-zero: the surface plane without the styles' surfaces */
} rs_splat_layers;

/* The layers of the window [x0, x0+w) x [y0, y0+h) (inside the image,
 * RS_ERR_INVALID_ARG otherwise, as for no plane, bad normal_options or
 * another splatter's workspace; a short stride: RS_ERR_BUFFER_TOO_SMALL).
 * `ws` may be NULL (scratch from ctx's
 * allocator, as rs_splat_window) or a workspace of `s` at least w wide:
 * then nothing is allocated (but by the workspace's first call with
 * normals or with layers, as above; rs_splat_workspace_bytes counts them).
 * Progress and profile as rs_splat_window (the layer writing counts as
 * composite time). */
RS_API rs_result rs_splat_layers_window(rs_ctx *ctx, const rs_splatter *s, rs_splat_workspace *ws, uint32_t x0,
                                        uint32_t y0, uint32_t w, uint32_t h, const rs_splat_layers *layers,
                                        rs_splat_profile *profile);

/* Whole-image convenience: a splatter on `grid` (built with the same dem
 * and opts), one window covering the image, tightly packed buffers:
 * width*height*4 bytes of RGBA (rgba_size available) and, when `weight` is
 * not NULL, width*height uint16. */
RS_API rs_result rs_splat(rs_ctx *ctx, const rs_dem *dem, const rs_road_grid *grid,
                          const rs_splat_options *opts, uint8_t *rgba, size_t rgba_size,
                          uint16_t *weight, size_t weight_count);

/* Normal maps (docs/normals.md): a tangent-space normal per pixel of the
 * same grid as rs_splat_window's colour output. Terrain: Horn's gradient
 * at the DEM samples (the hillshade's), interpolated bilinearly per pixel
 * as the terrain colour is. Road pixels add, weighted by the road weight
 * R, the relief of the road surface: the road texture's or the style's
 * surface image's luminance as a height (Sobel gradient per output pixel,
 * times `strength`; only with one of them) and raised paint (lines and markings, `paint_height`
 * metres high). Encoding: byte = round((n * 0.5 + 0.5) * 255) per
 * component, R = X east (image right), G = Y north (image up: OpenGL),
 * B = Z up; flat ground is (128, 128, 255). All-zero means defaults. */
/* (rs_normal_options is defined above, with the lighting options.) */

/* Write the normal map of the window [x0, x0+w) x [y0, y0+h) as RGB8 into
 * `rgb` (row r at rgb + r*rgb_stride bytes; rgb_stride >= 3*w). The window
 * must lie inside the image (RS_ERR_INVALID_ARG), options as documented
 * (RS_ERR_INVALID_ARG naming the field). Any window gives the bytes of the
 * same pixels of the whole image; the splatter may be shared by several
 * threads as for rs_splat_window. Scratch (about 60 bytes per pixel of a
 * piece of at most 1026 x (texels + 2) pixels) comes from ctx's
 * allocator. Progress: the context's callback (rs_ctx_set_progress), rows
 * done of h. `opts` may be NULL. */
RS_API rs_result rs_normal_window(rs_ctx *ctx, const rs_splatter *s, uint32_t x0, uint32_t y0, uint32_t w,
                                  uint32_t h, uint8_t *rgb, size_t rgb_stride, const rs_normal_options *opts);

/* Road field query (needs a grid built with analytic edges, or any grid
 * from rs_splatter_create when the splatter needed the field): the nearest
 * road centreline to local point (x, y) metres within `reach` metres of a
 * road's edge. Returns 1 and fills the fields, 0 when no road is that near
 * (or the grid has no road field). s = arc length from the road's first
 * point (metres), t = signed lateral offset, + to the left of the direction
 * of travel (SPEC "Road field"). On a grid from rs_road_grid_update that
 * holds patches, a point drawn by a patch gets the whole build's answer for
 * reach up to 20 m; beyond that a road more than 20 m away may be missed
 * (the patch indexes its roads for its own pixels: docs/embedding.md). */
typedef struct rs_road_point {
    uint32_t road;     /* index in the rs_roads the grid was built from */
    uint32_t segment;  /* segment (points segment, segment+1) */
    double s, t;       /* metres */
    double distance;   /* |t| away from the segment ends; to the nearest point */
} rs_road_point;
RS_API int rs_road_grid_query(const rs_road_grid *grid, double x, double y, double reach,
                              rs_road_point *out);

/* ---------------------------------------------------------------------------
 * GPU export (lib/gpu/gpu_export.c, docs/render.md "Shader mode"): everything a
 * fragment shader needs to evaluate the roads, their styles and markings per
 * screen pixel, as flat arrays in the local frame (SPEC: metres from DEM
 * sample (0,0), y down), float32 where a GPU reads them. No GL in here: a
 * renderer copies the arrays into buffer textures as they are.
 *
 * - seg: RS_GPU_SEG_FLOATS per segment, roads in order, points in order:
 *   ax, ay, bx, by (end points), half width, s at a (arc length from the
 *   road's first point, summed in double as the road field sums it; for a
 *   record the CPU draws as part of a stroke, docs/network.md, the
 *   stroke's arc length, and a record running against its stroke has its
 *   points last to first, its t and markings mirrored to match), road
 *   index, flags (RS_GPU_SEG_FIRST: the road's first segment, its start is
 *   a flat road end; RS_GPU_SEG_LAST: its last; RS_GPU_SEG_CLIP: it reaches past
 *   a line of its road's trimmed ends at a T, which clip it; RS_GPU_SEG_JOIN_FIRST,
 *   RS_GPU_SEG_JOIN_LAST: that end is a joint, below); the road's casing width,
 *   the segment's length and unit direction (1, 0 for length 0), so a
 *   shader needs neither a division nor a second lookup. A road of one
 *   point is one segment of length 0. Ascending segment index = ascending
 *   road. Segments join the road's points once repeated points are
 *   dropped (in double precision, as the CPU's lines and markings do); a
 *   segment reaching beyond a map size from the map is cut to the part
 *   that can touch it, and one that cannot is left out, so every float is
 *   finite and near the map (half widths above 1e15 m are 1e15 m, s
 *   saturates at FLT_MAX). RS_ERR_LIMIT for 2^24 roads or more (indices
 *   travel as floats) or an index of more than 2^28 entries.
 * - the index grid: cell (i, j) spans [x0 + i cell, x0 + (i+1) cell) x
 *   [y0 + j cell, ...); cell_start has gw*gh + 1 offsets into cell_seg, which
 *   lists per cell, ascending, the segments whose capsule grown by the road's
 *   casing width plus `reach` touches the cell. Per-pixel work follows the
 *   roads near the pixel, not the number of roads.
 * - road: RS_GPU_ROAD_FLOATS per road: surface (rs_surface), half width,
 *   casing width (0: none), first band, band count, the road continuing
 *   this one at its start and at its end (-1: none; SPEC junction rule of
 *   docs/linesym.md: shared end point, within 30 degrees of straight), the
 *   lines' reach (the largest |offset| + width/2 of its bands, 0: none);
 *   fill rgba, gradient centre rgba, gradient edge rgba, casing rgba (rgb
 *   0..255, a 0..1, as the CPU styling holds them); the T rule of
 *   docs/network.md: the road's stroke (-1: no network), the through
 *   stroke its start and its end meet at a T (-1: none), how far from
 *   that stroke's centre line each of those ends keeps cutting its lines
 *   (metres), 1 when some road end meets this road's stroke at a T, the
 *   road's rank for the fill (docs/network.md "Crossings": among the
 *   surfaces holding a pixel the highest wins, then the nearest; -1e9 for
 *   every road when all are equal): 64 x its level (layer=, bridge=:
 *   docs/network.md "Bridges and layers"; floor(rank / 64) gives it back)
 *   + its priority, 1 for a car road (0: path, footway,
 *   cycleway: its surface cuts no car road's lines);
 *   its trimmed ends at a T (docs/network.md "Ends at a T": no round cap,
 *   the strip runs on to the through road's far edge line n.p = c and
 *   stops there, casing too): nx, ny, c for its start, then for its end
 *   (0, 0, 0: a round cap, also where every capsule of the road, casing
 *   included, stays short of the line, as in the CPU splat), and how far
 *   such a strip reaches beyond the
 *   road's capsule (the index lists the road that much further), the
 *   index of the road's first segment (the segments of the roads before
 *   it; exact below 2^24 segments).
 * - joints: where the CPU draws two records of a stroke as one line (their
 *   lines alike, docs/linesym.md), the first record's LAST segment gets
 *   RS_GPU_SEG_JOIN_LAST and the next one's FIRST segment
 *   RS_GPU_SEG_JOIN_FIRST; each is the other's continuing road (road floats
 *   5, 6), and the partner's segment there is its last (the next road's
 *   first segment index - 1) or its first. Their lines do not end there:
 *   each record paints the side of the joint's bisector it lies on
 *   (normal: the sum of the two segments' directions, through the shared
 *   point), beyond its end as around a vertex (t the distance to the
 *   point), as the CPU mitres and round-joins a bend. Not set from 2^24
 *   segments on, where the lines then end square at the joint.
 * - band: RS_GPU_BAND_FLOATS per line of a style (paint order): offset T,
 *   width W, phase, period (0: solid); r, g, b (0..255), a (0..1); dash
 *   count, 0, 0, 0; dash[0..7] (on, off, ... metres).
 * - mark: RS_GPU_MARK_FLOATS per marking (record order: explicit, then
 *   automatic): road, atlas type, s, t (centre), half length, half width,
 *   flip (0/1), kx, ky (level-0 texels per metre across and along), the
 *   stroke whose segments it follows (its road is in the stroke's terms:
 *   s, t and flip are then the stroke's; -1: its road's segments only), 0, 0;
 *   and the same grid's cells listing the markings whose support box
 *   touches them (mark_start, mark_ids).
 * - atlas: per type RS_GPU_TYPE_INTS: first level record, level count;
 *   per level RS_GPU_LEVEL_INTS: first texel in atlas_px, w, h, 0;
 *   atlas_px: RGBA floats, rgb premultiplied 0..255, a 0..1, row-major,
 *   row 0 = the sprite's top (the way the road runs), exactly the CPU's mip
 *   chains (sampled trilinearly, transparent outside each level).
 * - cut (issue 27): where a road's lane and centre lines stop (between an
 *   automatic stop or give-way line and the junction, across a zebra):
 *   first 4 floats per road, the index of its first cut record (in
 *   RS_GPU_CUT_FLOATS units after the road part) and its cut count, 0, 0;
 *   then RS_GPU_CUT_FLOATS per cut, road by road: ax, ay, ux, uy (a
 *   segment's start and unit direction), u0, u1 (the cut along it), r (its
 *   lines within |t| <= r are cut), 0. A band's part inside |t| <= r loses
 *   the pixel's share of u0 <= (p - a).u <= u1. */
#define RS_GPU_SEG_FLOATS 12
#define RS_GPU_SEG_FIRST 1u
#define RS_GPU_SEG_LAST 2u
#define RS_GPU_SEG_CLIP 4u /* clipped by its road's trimmed T end lines (road floats 32..37) */
#define RS_GPU_SEG_JOIN_FIRST 8u /* its FIRST end joins the road continuing it: see "joints" above */
#define RS_GPU_SEG_JOIN_LAST 16u /* its LAST end joins the road continuing it */
#define RS_GPU_ROAD_FLOATS 40
#define RS_GPU_BAND_FLOATS 20
#define RS_GPU_MARK_FLOATS 12
#define RS_GPU_TYPE_INTS 2
#define RS_GPU_LEVEL_INTS 4
#define RS_GPU_CUT_FLOATS 8

typedef struct rs_gpu_options {
    size_t size;            /* 0, or sizeof (rs_gpu_options) of the host's header: "ABI" above */
    double cell;   /* index cell, metres; 0 -> automatic (the DEM cell, grown to at most 2^22 cells) */
    double reach;  /* metres beyond each capsule (and casing) a cell still lists it: the widest
                      anti-aliasing footprint served exactly; 0 -> half the index cell */
} rs_gpu_options;

/* The exported scene: opaque (read it through rs_gpu_scene_get_info and
 * rs_gpu_scene_array); immutable after creation, so any number of threads
 * may read one scene. */
typedef struct rs_gpu_scene rs_gpu_scene;

/* Export `roads` over `dem` with the styles and markings that the splat
 * with `opts` (may be NULL) draws: opts->style and opts->markings are read
 * as rs_road_grid_build reads them (the styles, network, line cuts and
 * markings are worked out again here; rs_gpu_scene_from_grid reads them
 * from a grid that has them). *out belongs to the caller: free it with
 * rs_gpu_scene_free and the same context. `gopts` may be NULL.
 * RS_ERR_LIMIT also for a marking sprite whose summed-area table
 * (RS_GPU_ARRAY_MARK_SAT) would pass 2^31 - 1. Progress (this and
 * rs_gpu_scene_from_grid): the context's callback (rs_ctx_set_progress;
 * not opts->progress), polls in every stage; a cancel makes nothing. */
RS_API rs_result rs_gpu_scene_create(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads,
                                     const rs_splat_options *opts, const rs_gpu_options *gopts,
                                     rs_gpu_scene **out);
/* The same export from a prepared road grid: `grid` from rs_road_grid_build
 * of `roads` over `dem` (the same roads, unchanged since: the grid keeps
 * no pointer to them). The styles, the lines' cuts and the markings'
 * placements are read from the grid, as resolved when it was built with
 * its options (the named style table need not be alive any more); the
 * marking atlas is the grid's (the options' atlas must still be valid, as
 * for the grid itself). The arrays are byte for byte those of
 * rs_gpu_scene_create with the options the grid was built with
 * (tests/test_gpu_export.c, fuzz/gpu_export), but for the colour floats of
 * a road drawn unstyled when no road of the grid is styled (not read by the
 * shader; docs/embedding.md). RS_ERR_INVALID_ARG for a grid of another DEM,
 * with styles of another number of roads or a marking on a road `roads`
 * lacks. Ownership as
 * rs_gpu_scene_create; the grid is only read during the call. */
RS_API rs_result rs_gpu_scene_from_grid(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads,
                                        const rs_road_grid *grid, const rs_gpu_options *gopts,
                                        rs_gpu_scene **out);
RS_API void rs_gpu_scene_free(rs_ctx *ctx, rs_gpu_scene *scene);

/* The scene's scalars: the index grid (cell (i, j) spans [x0 + i cell,
 * x0 + (i+1) cell) x [y0 + j cell, ...), gw x gh cells), the map extent and
 * the item counts. What a shader takes as uniforms (the fragment source's
 * u_grid = (x0, y0, 1 / cell, reach), u_gdim = (gw, gh), u_map = (map_w,
 * map_h)). */
typedef struct rs_gpu_scene_info {
    double cell, x0, y0;   /* index cell and origin, metres */
    double reach;          /* metres beyond each capsule a cell still lists it */
    uint32_t gw, gh;       /* index cells */
    double map_w, map_h;   /* map extent, metres */
    size_t nseg, nroads, nbands, nmarks, ntypes, nlevels, ncuts;
    size_t nseg_entries, nmark_entries; /* index list entries */
    size_t atlas_texels;   /* level texels of every type's mip chain */
    size_t sat_corners;    /* summed-area corners (RS_GPU_ARRAY_MARK_SAT: 4 ints each) */
    size_t bytes;          /* memory the scene holds */
} rs_gpu_scene_info;
RS_API void rs_gpu_scene_get_info(const rs_gpu_scene *scene, rs_gpu_scene_info *out);

/* The scene's arrays, each a buffer texture of the fragment shader. */
typedef enum rs_gpu_array {
    RS_GPU_ARRAY_SEG = 0,        /* u_seg    float  RGBA32F  nseg * RS_GPU_SEG_FLOATS */
    RS_GPU_ARRAY_CELL_START = 1, /* u_cstart uint32 R32UI    gw * gh + 1 */
    RS_GPU_ARRAY_CELL_SEG = 2,   /* u_cseg   uint32 R32UI    nseg_entries */
    RS_GPU_ARRAY_ROAD = 3,       /* u_roadt  float  RGBA32F  nroads * RS_GPU_ROAD_FLOATS */
    RS_GPU_ARRAY_BAND = 4,       /* u_band   float  RGBA32F  nbands * RS_GPU_BAND_FLOATS */
    RS_GPU_ARRAY_MARK = 5,       /* u_mark   float  RGBA32F  nmarks * RS_GPU_MARK_FLOATS */
    RS_GPU_ARRAY_MARK_START = 6, /* u_mstart uint32 R32UI    gw * gh + 1 */
    RS_GPU_ARRAY_MARK_IDS = 7,   /* u_mids   uint32 R32UI    nmark_entries */
    RS_GPU_ARRAY_TYPES = 8,      /* u_types  uint32 R32UI    ntypes * RS_GPU_TYPE_INTS */
    RS_GPU_ARRAY_MARK_LEVELS = 9, /* u_levels uint32 RGBA32UI nlevels * RS_GPU_LEVEL_INTS: LEVELS with
                                    each type's first summed-area corner in its level 0's fourth int */
    RS_GPU_ARRAY_MARK_SAT = 10,  /* u_atlas  int32  RGBA32I  sat_corners * 4: per type (types of
                                    one rectangle share one), from the corner its MARK_LEVELS
                                    level 0 names, (h + 1) x (w + 1) corners (row-major, row 0
                                    the sprite's top): at (j, i) the sums over its level-0 texels
                                    [0, i) x [0, j) of round(255 x premultiplied r, g, b, a) */
    RS_GPU_ARRAY_CUT = 11,       /* u_cut    float  RGBA32F  4 * max(nroads, 1) + ncuts * RS_GPU_CUT_FLOATS */
    RS_GPU_ARRAY_LEVELS = 12,    /* (not a sampler) uint32  nlevels * RS_GPU_LEVEL_INTS: the mip levels */
    RS_GPU_ARRAY_ATLAS_PX = 13,  /* (not a sampler) float   atlas_texels * 4: the mip chains' texels */
    RS_GPU_ARRAY_COUNT = 14
} rs_gpu_array;
/* Array `which` of the scene: its first value, and in *count (may be NULL)
 * how many 32-bit values it holds (the sizes above). The pointer is never
 * NULL for a scene and a valid `which` (NULL with *count 0 otherwise), also
 * when *count is 0: a GL host then uploads one zero texel instead, as
 * buffer textures cannot be empty. Owned by the scene: valid until
 * rs_gpu_scene_free. The shader reads the samplers 0 ..
 * RS_GPU_ARRAY_CUT; rs_gpu_array_sampler names them. */
RS_API const void *rs_gpu_scene_array(const rs_gpu_scene *scene, rs_gpu_array which, size_t *count);
/* The fragment shader's sampler of `which` ("u_seg", ...; NULL for
 * RS_GPU_ARRAY_LEVELS, RS_GPU_ARRAY_ATLAS_PX and values out of range), with
 * its texel format: *channels 1 or 4 values a texel, *kind 0 float, 1
 * uint32, 2 int32 (either pointer may be NULL). Static strings. */
RS_API const char *rs_gpu_array_sampler(rs_gpu_array which, uint32_t *channels, uint32_t *kind);

/* GLSL sources that draw an rs_gpu_scene (docs/embedding.md "The GPU
 * side", docs/render.md "Shader mode"): the terrain vertex shader (attributes
 * a_pos at location 0: map frame x east, y down the map, z up, metres; a_nrm
 * at 1; uniforms u_mvp, u_eye), the terrain fragment shader (the roads per
 * screen pixel from the scene's arrays bound as buffer textures u_seg,
 * u_cstart, u_cseg, u_roadt, u_band, u_mark, u_mstart, u_mids, u_types,
 * u_levels, u_atlas, u_cut; terrain and road colour images u_terrain,
 * u_road; the uniforms listed at the top of the source), and a sky pair for
 * perspective views. cli/render_shader.c is a complete host. */
typedef enum rs_gpu_shader {
    RS_GPU_SHADER_TERRAIN_VERTEX = 0,
    RS_GPU_SHADER_TERRAIN_FRAGMENT = 1,
    RS_GPU_SHADER_SKY_VERTEX = 2,
    RS_GPU_SHADER_SKY_FRAGMENT = 3
} rs_gpu_shader;
/* The source of `which` for GLSL `version` (330: "#version 330 core", the
 * only one so far) as *count strings, to hand to glShaderSource as they are
 * (count, strings, NULL lengths: each is NUL-terminated); C compilers need
 * not take longer literals. Returns NULL with *count = 0 for another
 * version or shader. Static storage owned by the library: never free it;
 * safe from any thread. `count` may be NULL. */
RS_API const char *const *rs_gpu_glsl(uint32_t version, rs_gpu_shader which, size_t *count);

/* The tile types of the 8-neighbour mask classification (seed 000's alpha-map
 * types; the grid statistics count cells by them). The classification table
 * itself (rs_mask_classify, rs_tile_alpha, rs_alpha_map: for tests and for
 * renderers that do their own blending with the same alpha-maps) is declared
 * in roadsplat_experimental.h. */
typedef enum rs_tile_type {
    RS_TILE_INTERIOR = 0, /* all road (alpha 0) */
    RS_TILE_EDGE = 1,     /* paper type 1: terrain along one side */
    RS_TILE_INNER = 2,    /* paper type 2: inner corner, one corner terrain */
    RS_TILE_OUTER = 3,    /* paper type 3: outer corner, road towards one corner */
    RS_TILE_SADDLE = 4,   /* two opposite inner corners (type 2 at rot r and r+2) */
    RS_TILE_TERRAIN = 5   /* road cell too thin to show: all terrain (alpha 1) */
} rs_tile_type;

/* == ROAM mesher (lib/roam/roam.c) ============================================ */
/*
 * A Landscape of square patches (two root triangles each) covers any W x H
 * DEM; bintree nodes come from a fixed pool sized by the caller and are
 * linked by 32-bit indices (left/right child, base/left/right neighbour).
 * Each node's error is a true bound (in DEM units, float) on the vertical
 * error of every DEM sample under its triangle, so a requested max error is
 * never exceeded. Splits force-split as in ROAM and reserve the worst case
 * first: running out of pool stops refining with a valid, crack-free mesh.
 * Design notes: docs/roam.md. Frame: x = column * cell_size, y = row *
 * cell_size (metres, y grows down the map), z = height in metres (up).
 */
typedef struct rs_roam rs_roam;

/* All-zero means defaults. Cell size and z-scale are the DEM's frame
 * (rs_dem_set_frame); the mesher needs z_scale > 0. */
typedef struct rs_roam_options {
    size_t size;            /* 0, or sizeof (rs_roam_options) of the host's header: "ABI" above */
    uint32_t pool_nodes;  /* node pool size; 0 -> pool_bytes, else automatic */
    uint64_t pool_bytes;  /* pool size in bytes (used when pool_nodes is 0) */
    uint32_t patch_size;  /* patch side in cells, a power of two; 0 -> automatic */
    uint32_t unit_size;   /* upload units (rs_roam_extract_unit) are the two halves of
                             squares of this many cells, a power of two; 0 -> 8;
                             clamped to [4, patch side] (to the patch for patches
                             of 2 cells or less) */
} rs_roam_options;

/* Bytes of one pool node (for sizing pool_bytes). */
RS_API size_t rs_roam_node_bytes(void);

/* Build the landscape: the patch roots, the base mesh, the node pool and a
 * cache for the error bounds (half a float per padded DEM cell; each bound
 * is computed the first time refinement needs it). The finest mesh needs
 * about one pool node per four DEM cells (the four finest bintree levels
 * are kept as bits in their parent node, docs/roam.md). The automatic
 * pool holds the finest mesh, capped at 2^21 nodes and at the context's
 * max_pool_nodes (RS_ERR_LIMIT if a requested pool exceeds that). `dem` is
 * copied where it holds nodata, otherwise referenced: it must outlive *out.
 * Nodata (NaN) samples get the lowest valid 8-neighbour height, spreading
 * inwards (all-nodata -> 0); they never produce NaN vertices. Progress: a
 * unit per stage (5); a cancel makes nothing. */
RS_API rs_result rs_roam_create(rs_ctx *ctx, const rs_dem *dem, const rs_roam_options *opts,
                                rs_roam **out);
RS_API void rs_roam_free(rs_ctx *ctx, rs_roam *roam);

/* Re-target a landscape at another DEM of the same size (the next terrain
 * tile of a simulator, a new elevation model), keeping its node pool,
 * caches and options: no allocation unless the new DEM holds nodata. The
 * cached error bounds are dropped and the mesh is reset to the base mesh.
 * `dem` must outlive the landscape's use of it, as for rs_roam_create. On
 * failure (size or frame mismatch: the cell size and z-scale must be the
 * landscape's, RS_ERR_INVALID_ARG; RS_ERR_NOMEM; a cancel at its one
 * progress call, once the new DEM is checked) the landscape keeps its
 * previous DEM. */
RS_API rs_result rs_roam_set_dem(rs_ctx *ctx, rs_roam *roam, const rs_dem *dem);

/* Error-bounded mode. Reset to the base mesh, then split (depth first,
 * in a fixed order) every triangle whose error bound exceeds `max_error`
 * metres: the result is the coarsest crack-free bintree mesh whose max
 * vertical error over all DEM samples is <= max_error. Returns
 * RS_ERR_POOL_EXHAUSTED when the pool ran out: the mesh is then still valid,
 * crack-free and complete, only coarser (and a larger pool never gives a
 * coarser mesh). Progress (rs_ctx_set_progress): pool nodes taken of the
 * pool; a cancel leaves the mesh refined so far, valid and crack-free as
 * when the pool runs out. */
RS_API rs_result rs_roam_refine_error(rs_ctx *ctx, rs_roam *roam, double max_error);

/* The finest mesh of the error-bounded family with at most `max_triangles`
 * triangles (binary search on the error; stats.threshold tells the error
 * reached). If even the base mesh has more, the base mesh is kept and
 * RS_ERR_LIMIT returned. Progress: the pool nodes of each search pass (of
 * at most 33); a cancel leaves the base mesh. */
RS_API rs_result rs_roam_refine_count(rs_ctx *ctx, rs_roam *roam, uint32_t max_triangles);

/* View-dependent mode: one frame. All-zero fields take the default shown. */
typedef struct rs_roam_view {
    size_t size;            /* 0, or sizeof (rs_roam_view) of the host's header: "ABI" above */
    double eye[3];        /* camera position, metres (x, y map frame, z up) */
    double dir[3];        /* view direction (need not be unit); must not be 0 */
    double fov_y;         /* vertical field of view, degrees; 0 -> 60 */
    uint32_t width, height; /* viewport pixels; 0 -> 1280 x 720 */
    double pixel_error;   /* tolerance in pixels (start value with a target); 0 -> 1 */
    uint32_t target_triangles; /* 0: fixed pixel_error; else feedback on the
                                  tolerance (gFrameVariance) holds the count near it */
    double far_dist;      /* far plane, metres; 0 -> none */
    double merge_hysteresis; /* rs_roam_update with a fixed pixel_error: merge a
                                diamond only when both parents are within
                                pixel_error / this (>= 1; 0 -> 1.25; 1: none) */
} rs_roam_view;

/* Per-frame reset and split-only re-tessellation (rs_roam_update keeps
 * the mesh between frames instead; docs/roam.md). A triangle splits when its error bound,
 * projected at its nearest distance to the eye, exceeds the tolerance;
 * triangles outside the view frustum are not refined. With
 * target_triangles, the tolerance is carried from frame to frame and
 * corrected within the frame (a few re-tessellations at most) so the count
 * lands within +-5 % whenever the target is reachable. Progress: the pool
 * nodes of each pass; a cancel leaves the mesh of the pass under way (valid,
 * crack-free, coarser) and the target's tolerance as it was. */
RS_API rs_result rs_roam_frame(rs_ctx *ctx, rs_roam *roam, const rs_roam_view *view);

/* Frame-coherent view mode (seed 004's split and merge queues): start
 * from the current mesh (the previous update's, or whatever the last call
 * left) and adapt it to `view`. Leaves whose priority (error bound
 * projected at their nearest distance to the eye, pixels) rose above the
 * tolerance split, highest first, with their forced splits; diamonds whose
 * two parents' priorities are both within pixel_error / merge_hysteresis
 * merge, lowest first. With a fixed pixel_error, when the update completes
 * every leaf is within the tolerance (the bound rs_roam_frame gives) and
 * the mesh is crack-free, with at least rs_roam_frame's triangles and a
 * few more where the hysteresis kept splits (0.8 % on the drive of
 * docs/roam.md; none beyond the bounds' own slack with merge_hysteresis 1). With target_triangles it starts at the tolerance the last
 * update ended at and, when the count is off by more than 1.5 %, runs the
 * seed's loop over all leaves and diamonds (merge while above, split while
 * below, trade the highest split for the lowest merge): one update lands
 * within 1.5 % of the target whenever the pool and budget allow
 * (stats.threshold: the tolerance reached), or beside that band when one
 * split or merge (with its forced splits) changes the count by more than
 * the band, as on a mesh of a hundred triangles. Past the target the loop
 * makes at most 1024 operations or a sixteenth of the triangles, then
 * stops at the next count within 1 % (at most as many again). `budget` caps the split and
 * merge operations of this call (a split counts once with its forced
 * splits; 0: no cap); when it runs out the mesh is valid and crack-free but
 * not yet at the tolerance (stats.update_done = 0), and the next update
 * goes on. Cost: what changed, plus a walk that skips every subtree whose
 * items cannot have crossed the tolerance since their last look (the eye
 * has not moved far enough, nothing in it changed). The first call
 * allocates 13 bytes per pool node (parent links, the walk's cache) and the
 * queues, which grow with the mesh (RS_ERR_NOMEM: the mesh stays valid).
 * Like every rs_roam call it mutates the landscape: one thread per
 * landscape at a time; landscapes are independent. RS_ERR_POOL_EXHAUSTED
 * as for rs_roam_frame. Progress: pool nodes taken; a cancel stops the
 * update as a spent budget does (mesh valid and crack-free, update_done
 * 0, the next update goes on). */
RS_API rs_result rs_roam_update(rs_ctx *ctx, rs_roam *roam, const rs_roam_view *view, uint32_t budget);

typedef struct rs_roam_stats {
    uint32_t width, height;     /* DEM samples */
    uint32_t patch_size;        /* cells per patch side */
    uint32_t patches_x, patches_y;
    uint32_t base_nodes;        /* roots + splits forced by the map border */
    uint32_t pool_nodes;        /* pool capacity (nodes) */
    uint32_t pool_used;         /* pool nodes in use by the current mesh */
    int pool_exhausted;         /* the last refinement stopped for lack of nodes */
    uint32_t triangles;         /* triangles of the current mesh (inside the map) */
    double threshold;           /* error (metres) or tolerance (pixels) last used */
    double max_error_bound;     /* largest node error bound of the mesh, metres */
    uint32_t frame_passes;      /* tessellation passes of the last frame */
    uint32_t patches_culled;    /* patches outside the frustum in the last frame */
    uint32_t update_ops;        /* split/merge operations of the last rs_roam_update */
    int update_done;            /* the last rs_roam_update reached its goal (budget not hit) */
    uint64_t bytes;             /* memory held by the landscape */
    uint32_t unit_size;         /* side of an upload unit's square, cells (rs_roam_options) */
    uint32_t units;             /* upload units of the landscape (rs_roam_extract_unit) */
} rs_roam_stats;
RS_API void rs_roam_get_stats(const rs_roam *roam, rs_roam_stats *out);

/* Mesh extraction. All-zero means: no normals, no skirts. */
typedef struct rs_roam_mesh_options {
    size_t size;            /* 0, or sizeof (rs_roam_mesh_options) of the host's header: "ABI" above */
    int normals;          /* non-zero: write unit normals (Horn's gradient, as the hillshade) */
    double skirt_depth;   /* > 0: add a skirt this many metres deep on the map border */
    uint32_t *samples;    /* NULL, or vertex_capacity entries: the DEM sample of each vertex,
                             row * width + column (a skirt vertex: the sample above it) */
} rs_roam_mesh_options;

/* Upper bounds on the vertex and index counts of rs_roam_extract for the
 * current mesh and `opts` (may be NULL; one the ABI rule refuses is bounded
 * as with a skirt, and rs_roam_extract then refuses it). */
RS_API void rs_roam_mesh_bound(const rs_roam *roam, const rs_roam_mesh_options *opts,
                               size_t *max_vertices, size_t *max_indices);

/* Write the current mesh. `vertices` holds 5 floats per vertex (x, y, z
 * metres, u = x / map width, v = y / map height), `normals` 3 floats per
 * vertex (only when opts->normals; else may be NULL), `indices` 3 per
 * triangle, counter-clockwise seen from above (z up). A vertex at sample
 * (i, j) has exactly (j*cs, i*cs, z[i][j]*z_scale). Capacities are counted
 * in vertices and indices; RS_ERR_BUFFER_TOO_SMALL if they are below what
 * is needed. Output is deterministic (same order every run). Every value
 * written is finite: rs_roam_create refuses a cell_size or heights whose
 * vertices leave the float range (or whose cell_size is below FLT_MIN), and
 * this call a skirt_depth that would. */
RS_API rs_result rs_roam_extract(rs_ctx *ctx, rs_roam *roam, const rs_roam_mesh_options *opts,
                                 float *vertices, float *normals, size_t vertex_capacity,
                                 uint32_t *indices, size_t index_capacity,
                                 size_t *vertex_count, size_t *index_count);
/* Per-patch output, for hosts that keep one GPU buffer per patch and
 * re-upload only what changed. Patch p = py * patches_x + px covers cells
 * [px P, px P + P) x [py P, py P + P) of the map (P = stats.patch_size;
 * clipped at the map's edge). The automatic patch size is at most 64
 * cells, so patches can be culled (docs/roam.md). */
/* Generation of patch p's triangles: changes whenever they may have
 * changed (an rs_roam_update split or merge in it; any other mode
 * changes every patch's). Compare with the value at the last upload. 0
 * for a patch out of range. */
RS_API uint32_t rs_roam_patch_generation(const rs_roam *roam, uint32_t patch);
/* rs_roam_extract for the triangles of one patch: its own vertex numbering
 * (vertices on a patch edge appear in both patches' buffers, at the same
 * sample), the same options, order rules and errors; rs_roam_mesh_bound's
 * counts hold for any patch. RS_ERR_INVALID_ARG for a patch out of range. */
RS_API rs_result rs_roam_extract_patch(rs_ctx *ctx, rs_roam *roam, uint32_t patch,
                                       const rs_roam_mesh_options *opts, float *vertices, float *normals,
                                       size_t vertex_capacity, uint32_t *indices, size_t index_capacity,
                                       size_t *vertex_count, size_t *index_count);
/* Upload units: a finer unit than the patch for hosts that re-upload what
 * changed (the patch stays the unit of meshing and culling). A patch of P
 * cells is cut into squares of U = stats.unit_size cells; each square's two
 * halves (the bintree's triangles at depth 2 log2(P / U) below the patch's
 * roots) are units, 2 (P / U)^2 per patch, stats.units in all, numbered
 * patch by patch (unit / (2 (P / U)^2) is its patch). A unit holds the
 * triangles inside its half square, and each triangle larger than a unit
 * belongs to exactly one unit (the one holding its first corner in the
 * bintree's order: its leftmost descendant at the units' depth), so the
 * units' triangles together are exactly rs_roam_extract's; many units are
 * empty on a coarse mesh. Generation of unit u's triangles: as
 * rs_roam_patch_generation (a split or merge of a leaf in it changes it;
 * rs_roam_frame, rs_roam_refine_* and rs_roam_set_dem change every unit's);
 * 0 for a unit out of range. */
RS_API uint32_t rs_roam_unit_generation(const rs_roam *roam, uint32_t unit);
/* rs_roam_extract for the triangles of one unit: its own vertex numbering
 * (vertices on a unit's edge appear in the buffers of every unit that has
 * them), the same options, order rules and errors; rs_roam_mesh_bound's
 * counts hold for any unit. RS_ERR_INVALID_ARG for a unit out of range.
 * The buffers are the caller's, written only up to the returned counts. */
RS_API rs_result rs_roam_extract_unit(rs_ctx *ctx, rs_roam *roam, uint32_t unit,
                                      const rs_roam_mesh_options *opts, float *vertices, float *normals,
                                      size_t vertex_capacity, uint32_t *indices, size_t index_capacity,
                                      size_t *vertex_count, size_t *index_count);
/* Seams between DEM tiles. Two landscapes on tiles that share an edge
 * row or column (the same samples on both sides, e.g. columns 0..1024 and
 * 1024..2048 of a larger map) mesh it independently, so their vertices on
 * it differ (T-junctions across the seam). rs_roam_stitch splits border
 * leaves of each (with their forced splits) until both have the union of
 * the two vertex sets on the shared edge: the meshes then meet vertex to
 * vertex, no skirts needed. The edges are named as seen in each tile's own
 * frame and run the same way (by increasing column or row); they must have
 * the same length, the landscapes the same patch size, and a right or
 * bottom edge must lie on the patch grid (cells across a multiple of the
 * patch size). The host calls it after every update of either landscape
 * (an update may merge the extra splits again); it allocates 4 bytes per
 * edge sample for the call. RS_ERR_POOL_EXHAUSTED when a pool ran short
 * (both meshes valid, the seam not closed). */
enum { RS_ROAM_EDGE_TOP = 0, RS_ROAM_EDGE_BOTTOM = 1, RS_ROAM_EDGE_LEFT = 2, RS_ROAM_EDGE_RIGHT = 3 };
RS_API rs_result rs_roam_stitch(rs_ctx *ctx, rs_roam *a, int edge_a, rs_roam *b, int edge_b);
/* == end ROAM mesher ===================================================== */

/* == Virtual texture: streamed tiles around a moving camera (lib/splat/vt.c) ===== */
/*
 * A quadtree of texture tiles over the whole splat image of a prepared
 * splatter (issue 30, seed 002; docs/embedding.md "Streaming"). Level 0
 * is the splatter's own image (T texels per DEM cell); level k has pixels
 * 2^k times larger, (ceil(W/2^k) x ceil(H/2^k)) pixels for a W x H splat;
 * its tile (x, y) is the level image's window [xS - B, (x+1)S + B) x
 * [yS - B, (y+1)S + B) for tile size S and border B (pixels beyond the
 * image transparent, 0,0,0,0). Tile (k, x, y) covers the same ground as
 * tiles (k-1, 2x..2x+1, 2y..2y+1). Every tile is rendered on its own from
 * the road grid, never from other tiles, so any tile can be made at any
 * time, on any thread, in any order, with the same bytes:
 * - level k where 2^k divides T: the splat at T / 2^k texels (a splatter
 *   sharing the grid): byte-identical to rs_splat_window at those texels;
 *   at level 0 to the splatter's own windows;
 * - other levels: the splat at t = ceil(T / 2^k) texels (at least 1), area-
 *   averaged onto the level's pixels (exact box weights, alpha-weighted
 *   colour, rounded). Levels coarser than a DEM cell render t = 1 and
 *   average ceil(2^k / T)^2 or so pixels each.
 * Rendering coarse levels from their children instead would need every
 * finest tile under them (the whole 4e10-pixel map for a far view).
 * Needs analytic edges (RS_EDGES_ANALYTIC, the default): the other levels
 * re-render the splatter's road grid at other texel counts, which an
 * alpha-map grid does not allow (RS_ERR_UNSUPPORTED).
 *
 * Frame: as rs_roam_view: x = column * cell_size, y = row * cell_size
 * metres from DEM sample (0,0) (y down the map), z = height in metres (the
 * DEM's value times z_scale), z up.
 *
 * Threads: the library starts no threads. rs_vt_update, rs_vt_discard and
 * the list and lookup calls use the rs_vt's mutable state: one thread at a
 * time. rs_vt_make_tile reads only what rs_vt_create fixed (levels,
 * splatters), so any number of host threads may make tiles at once, each
 * with its own context and its own rs_vt_workspace, also while another
 * thread runs rs_vt_update. The splatter (and its grid and DEM) must
 * outlive the rs_vt.
 */
typedef struct rs_vt rs_vt;

/* All-zero means defaults. */
typedef struct rs_vt_options {
    size_t size;            /* 0, or sizeof (rs_vt_options) of the host's header: "ABI" above */
    uint32_t tile_size;    /* S: core pixels per tile side; 0 -> 256, else 8..8192 */
    int32_t border;        /* B: pixels of the level image around the core on each side
                              (for bilinear/anisotropic filtering across tile edges);
                              0 -> 4, -1 -> none, else 1..S/2 */
    uint64_t budget_bytes; /* resident tiles at most this many bytes ((S+2B)^2 * 4 each);
                              0 -> 256 MiB; must hold every tile of the coarsest level */
    uint32_t levels;       /* 0 -> until the coarsest level fits one tile; else 1..that,
                              at most 32 */
    const rs_roads *roads; /* the roads s was made from: needed when s's grid has styles or
                              markings (line symbols, casings and markings are laid out in the
                              grid's pixels, so each coarser texel count gets a grid of its own,
                              built from these with s's options; s's styles, surface images and
                              marking atlas must then still be valid). Borrowed during
                              rs_vt_create only.
                              NULL: share s's grid (without styles and markings only) */
} rs_vt_options;

/* One frame's camera. All-zero fields take the default shown. */
typedef struct rs_vt_view {
    size_t size;            /* 0, or sizeof (rs_vt_view) of the host's header: "ABI" above */
    double eye[3];        /* camera position, metres (frame above) */
    double dir[3];        /* view direction (need not be unit), not 0; up is +z */
    double fov_y;         /* vertical field of view, degrees; 0 -> 60, else (0, 179) */
    uint32_t width, height; /* viewport pixels; 0 -> 1280 x 720 */
    double far_dist;      /* metres: tiles farther than this are not needed; 0 -> none */
    double texel_pixels;  /* a level is fine enough where its texel projects to at most this
                             many screen pixels; 0 -> 1; larger: coarser, less memory */
    double anisotropy;    /* the host sampler's max anisotropy A (1: isotropic), 1..64; 0: no
                             limit (the view angle never coarsens the level: right for any
                             sampler, the most tiles) */
    uint32_t max_make;    /* at most this many tiles to make per update (the nearest first);
                             0 -> no cap */
} rs_vt_view;

/* A tile and where it lives. `slot` (0 .. rs_vt_info.slots - 1) is the
 * tile's place in the host's cache or texture atlas while it is resident:
 * given when the tile enters the make list, free again when it is dropped. */
typedef struct rs_vt_tile {
    uint32_t level, x, y;
    uint32_t slot;           /* UINT32_MAX in the needed list: not resident (max_make cut it) */
    double x0, y0, x1, y1;   /* the core's ground rectangle, metres (clipped to the map) */
    double dist;             /* nearest distance from the eye to the tile's box, metres */
} rs_vt_tile;

typedef struct rs_vt_info {
    uint32_t levels;       /* level count (0 finest) */
    uint32_t tile_size;    /* S */
    uint32_t border;       /* B */
    uint32_t tile_side;    /* S + 2B: pixels per side of a made tile */
    size_t tile_bytes;     /* (S + 2B)^2 * 4 */
    uint32_t slots;        /* most tiles resident at once: budget_bytes / tile_bytes */
    uint64_t budget_bytes; /* in use (default filled in) */
    size_t bytes;          /* memory the rs_vt itself holds (tables, splatters' own memory excluded) */
} rs_vt_info;

/* Per-update counts (the last rs_vt_update). */
typedef struct rs_vt_stats {
    uint64_t frame;        /* updates so far */
    uint32_t needed;       /* tiles of the view's cut (the needed list) */
    uint32_t made;         /* tiles in the make list */
    uint32_t dropped;      /* tiles in the drop list */
    uint32_t resident;     /* resident tiles after the update */
    uint64_t resident_bytes; /* resident * tile_bytes, <= budget_bytes */
    uint32_t bias;         /* levels the whole cut was coarsened by to fit the budget (0: none) */
    uint32_t visited;      /* quadtree nodes visited */
} rs_vt_stats;

/* Build the quadtree over the splatter's image: the levels, a splatter per
 * texel count the levels need (sharing s's grid, or with styles or markings
 * a grid of its own from opts->roads; s's options; their grid builds report
 * as parts of this call to the context's callback, rs_ctx_set_progress),
 * the height range of every tile (from the DEM) and the bookkeeping for
 * rs_vt_info.slots tiles, all allocated here (rs_vt_update then allocates
 * nothing). The coarser splatters are checked against ctx's limits as any
 * splatter is. RS_ERR_INVALID_ARG for bad options, a budget below the
 * coarsest level's tiles, or a grid with styles or markings and no
 * opts->roads; RS_ERR_UNSUPPORTED for alpha-map edges, RS_ERR_NOMEM. *out
 * is the caller's (rs_vt_free, same context). */
RS_API rs_result rs_vt_create(rs_ctx *ctx, const rs_splatter *s, const rs_vt_options *opts, rs_vt **out);
RS_API void rs_vt_free(rs_ctx *ctx, rs_vt *vt);
RS_API void rs_vt_get_info(const rs_vt *vt, rs_vt_info *out);
/* Level k's image size in pixels and its pixel size in metres. RS_ERR_INVALID_ARG
 * for k out of range. */
RS_API rs_result rs_vt_level_size(const rs_vt *vt, uint32_t level, uint32_t *width, uint32_t *height,
                                  double *pixel_m);

/* One frame. Finds the view's cut of the quadtree: starting from the
 * coarsest level, a tile outside the view frustum (or beyond far_dist) is
 * not needed; a tile at level k is needed when k <= L, the level its box
 * asks for, else its children are examined. L for a box (ground rectangle
 * times the DEM's height range there) is, with d the nearest distance from
 * the eye to the box, dz the largest height difference between the eye and
 * the box, f = height / (2 tan(fov_y / 2)) and p0 the finest pixel size
 * (Cline and Egbert's projected size, seed 002 formula 1):
 *     P = p0 f / d                 screen pixels of a level-0 texel seen face on
 *     c = min(1, dz / d)           bound on the cosine of the view angle to the ground
 *     rho = P min(1, c A)          the footprint the sampler picks its mip level by
 *                                  (A: anisotropy; A = 0 means no limit: rho = P)
 *     L = floor(log2(texel_pixels / rho)), clamped to 0 .. levels-1
 * (all bounds taken towards finer levels: the chosen level is never coarser
 * than the mip level a GPU picks for any texel of the tile, the
 * EXT_texture_filter_anisotropic rule: with N = min(1/c, A) taps along the
 * foreshortened axis, the level of its footprint divided by N). L never decreases when the box
 * moves away. Every visible point of the map is then under exactly one
 * needed tile, of a level at least as fine as its own L. When the cut's
 * tiles exceed the budget, L is raised by 1 everywhere until they fit
 * (stats.bias).
 * Lists (rs_vt_needed, rs_vt_to_make, rs_vt_to_drop; valid until the next
 * update): tiles to make (needed and not resident: they are resident from
 * now on, in the slot given; nearest first, at most max_make) and tiles to
 * drop (resident tiles not needed now, least recently needed first, only as
 * many as the new ones need room: the resident set never exceeds
 * rs_vt_info.slots tiles). The host drops, then makes, then draws the
 * needed tiles. Deterministic: the same views in the same order give the
 * same lists. Takes nothing from the allocator (rs_vt_create sized
 * everything). */
RS_API rs_result rs_vt_update(rs_ctx *ctx, rs_vt *vt, const rs_vt_view *view);
RS_API const rs_vt_tile *rs_vt_needed(const rs_vt *vt, size_t *count);
RS_API const rs_vt_tile *rs_vt_to_make(const rs_vt *vt, size_t *count);
RS_API const rs_vt_tile *rs_vt_to_drop(const rs_vt *vt, size_t *count);
RS_API void rs_vt_get_stats(const rs_vt *vt, rs_vt_stats *out);
/* The resident tile that holds ground point of tile (level, x, y): that tile
 * or its nearest resident ancestor (a host draws with it while a finer one
 * is on its way). Returns 1 and fills *out, or 0 when none is resident. */
RS_API int rs_vt_lookup(const rs_vt *vt, uint32_t level, uint32_t x, uint32_t y, rs_vt_tile *out);
/* Forget a resident tile (the host could not make it, or wants the slot):
 * its slot is free again and a later update lists it to make again.
 * RS_ERR_INVALID_ARG when it is not resident. */
RS_API rs_result rs_vt_discard(rs_ctx *ctx, rs_vt *vt, uint32_t level, uint32_t x, uint32_t y);

/* Per-thread scratch of rs_vt_make_tile: a splat workspace per texel
 * count and the averaging buffers, allocated once (rs_vt_workspace_bytes
 * tells). Belongs to one rs_vt and serves one call at a time. */
typedef struct rs_vt_workspace rs_vt_workspace;
RS_API rs_result rs_vt_workspace_create(rs_ctx *ctx, const rs_vt *vt, rs_vt_workspace **out);
RS_API void rs_vt_workspace_free(rs_ctx *ctx, rs_vt_workspace *ws);
RS_API size_t rs_vt_workspace_bytes(const rs_vt_workspace *ws);

/* Render tile (level, x, y) into the caller's `rgba`: tile_side rows of
 * tile_side RGBA8 pixels, row r at rgba + r * stride bytes (stride >=
 * 4 * tile_side). Any tile of the quadtree may be made, resident or not.
 * Allocates nothing (with the splatter's lighting on, the first tile of
 * each texel count adds the normal scratch to the workspace: see
 * rs_splat_workspace_create). Level 0 renders through `s`
 * itself: its progress callback, if any, is called from the making thread
 * as rs_splat_window_ws calls it (the vt's own splatters have none), else
 * the context's: source rows rendered (polls between the bands of a
 * resampled tile); a cancel leaves the tile's bytes unspecified. Thread
 * rules above.
 * RS_ERR_INVALID_ARG for a tile out of range, another vt's workspace or a
 * short stride. */
RS_API rs_result rs_vt_make_tile(rs_ctx *ctx, const rs_vt *vt, rs_vt_workspace *ws, uint32_t level, uint32_t x,
                                 uint32_t y, uint8_t *rgba, size_t stride);
/* == end virtual texture ================================================== */

#ifdef __cplusplus
}
#endif
#endif /* ROADSPLAT_H */
