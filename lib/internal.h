/* Private declarations shared by the library's files (prefix rs__). */
#ifndef RS_INTERNAL_H
#define RS_INTERNAL_H
#include "roadsplat.h"
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h> /* (memcpy: rs__fp_mixd) */

#if defined(__GNUC__)
#define RS__PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define RS__PRINTF(a, b)
#endif

/* The progress of the call running on a context (rs__tick): set by a long
 * call for its duration, so that its inner loops can report and be cancelled
 * without a parameter through every function. A context serves one thread
 * at a time, so this is the call's own state, not shared. */
typedef struct rs__progress {
    rs_progress_fn fn;
    void *user;
    uint64_t done, total, next; /* units done, expected, when to call fn next */
    uint64_t step;              /* units between calls */
    uint64_t said;              /* `done` of the last call (UINT64_MAX: none yet) */
    uint32_t polls;             /* rs__tick calls since the last callback */
    int cancelled;
    int nested;                 /* begun inside another call's progress: reports to it */
    struct rs__progress *outer; /* ctx->pg before this call */
} rs__progress;

struct rs_ctx {
    rs_allocator alloc;
    rs_limits limits;
    char message[256];
    rs__progress *pg; /* the running call's progress, or NULL */
    rs_progress_fn progress; /* rs_ctx_set_progress */
    void *progress_user;
};

/* A long call's progress (docs/embedding.md "Progress and cancel"): begin
 * puts `pg` on the context for the call's duration, with `fn` (the call's
 * own callback: an options' field; NULL: the context's, rs_ctx_set_progress)
 * and `total` units, a callback every `step` units. A call begun while
 * another runs on the context (a grid build inside rs_splatter_create,
 * a splat window inside rs_vt_make_tile) reports to that one instead: its
 * ticks add to the outer call's units, and a cancel there stops it. end
 * takes the call's result: makes the last call (done == total) when the
 * call succeeded and no call said total yet, returns RS_ERR_CANCELLED
 * ("cancelled") once a callback asked to stop, and takes pg off the
 * context. */
void rs__progress_begin(rs_ctx *ctx, rs__progress *pg, rs_progress_fn fn, void *user, uint64_t total,
                        uint64_t step);
rs_result rs__progress_end(rs_ctx *ctx, rs__progress *pg, rs_result r);

/* `units` more of the running call's work done: calls its progress
 * callback every pg->step units (with done clamped to total), and every
 * RS__TICK_POLLS calls however few units they add, so that a loop whose
 * iterations are no units of their own (ticking 0) can still be
 * cancelled. Returns 1 once the callback asked to stop (the caller then
 * returns RS_ERR_CANCELLED), else 0; 0 when no call reports. */
#define RS__TICK_POLLS 256u
int rs__tick(rs_ctx *ctx, uint64_t units);
/* rs__tick(ctx, 0) that always calls the callback: between the stages of
 * a long call. */
int rs__poll(rs_ctx *ctx);
/* rs__tick(ctx, units) that always calls the callback: from loops that
 * count their own time (every few thousand items). */
int rs__report(rs_ctx *ctx, uint64_t units);
/* Sort n elements of `size` bytes at base by cmp, stably (equal elements
 * keep their order: the same result on every C library), polling for
 * cancel (lib/sort.c). Scratch: 8 n bytes plus one element. Returns
 * RS_OK; RS_ERR_NOMEM or RS_ERR_CANCELLED (base unchanged: the elements
 * move only after the last poll that stops); RS_ERR_LIMIT for n >= 2^32.
 * No message set. */
rs_result rs__sort(rs_ctx *ctx, void *base, size_t n, size_t size, int (*cmp)(const void *, const void *));
/* The same, ordered by key[i] for element i (ascending; equal keys keep
 * their order): for large elements whose order is a number (rs__sort_recs
 * on (key, index) records, then each element moved once). key is read
 * only. Scratch: 32 n bytes plus one element. */
rs_result rs__sort_keyed(rs_ctx *ctx, void *base, size_t n, size_t size, const uint64_t *key);
/* A 64-bit key and 8 bytes of the caller's (indices): what rs__sort_recs
 * sorts (the pieces' fingerprints of an edit, the elements of
 * rs__sort_keyed). */
typedef struct rs__keyed {
    uint64_t h;
    uint32_t i, pos;
} rs__keyed;
/* r[0..n) by h ascending, equal ones in their order (LSD radix, a byte a
 * pass; insertion below 64), polling for cancel between passes. Scratch:
 * 16 n bytes. RS_OK; RS_ERR_NOMEM (r unchanged); RS_ERR_CANCELLED (r holds
 * its records in some order). No message set. */
rs_result rs__sort_recs(rs_ctx *ctx, rs__keyed *r, size_t n);
/* A grid build's T ends (lib/scene/tee_ends.c), worked out once and read
 * by its parts (the road field, the styles' fields and lines, the edit
 * pieces, the track): rs__tee_ends_from copies them. */
struct rs__tee_end;
typedef struct rs__tees {
    const struct rs__tee_end *t;
    size_t n;
} rs__tees;
/* qsort's comparison of two uint32_t, ascending. */
int rs__cmp_u32(const void *pa, const void *pb);

struct rs_dem {
    uint32_t width, height;
    float *z;           /* width*height, row-major, NaN = nodata */
    rs_dem_frame frame; /* defaults filled in (lib/dem.c) */
    /* the samples' range, kept as they go in (rs__dem_seal_range): the
     * samples never change after, and every update's dirty render made
     * two splatters that scanned them all */
    int nodata;
    float zlo, zhi;
};

/* Allocation through the context's allocator. rs__alloc_array checks
 * count*size for overflow and returns NULL on it. None of these set a
 * message; callers return rs__fail(ctx, RS_ERR_NOMEM, ...). */
void *rs__malloc(rs_ctx *ctx, size_t size);
void *rs__calloc(rs_ctx *ctx, size_t count, size_t size);
void *rs__alloc_array(rs_ctx *ctx, size_t count, size_t size);
void *rs__realloc(rs_ctx *ctx, void *ptr, size_t size);
void rs__free(rs_ctx *ctx, void *ptr);
/* Room for one more element in a growing array: when n == *cap, the
 * array *arr of `size`-byte elements doubles (first capacity `first`).
 * A block of a few MB may sit in the C library's heap, where realloc
 * copies it into fresh pages in one call (50-90 ms for 30 MB on the test
 * host, with no poll: issue 30's cancel target); such blocks are copied
 * here in 1 MB pieces with a poll between them. Returns RS_OK,
 * RS_ERR_NOMEM, RS_ERR_LIMIT (capacity past `max` elements) or
 * RS_ERR_CANCELLED; on failure *arr and *cap are unchanged. No message. */
rs_result rs__grow(rs_ctx *ctx, void **arr, size_t n, size_t *cap, size_t size, size_t first, size_t max);
/* The block *arr of `old` bytes resized to `bytes` (its first min(old,
 * bytes) kept), copied in polled pieces as rs__grow does. RS_OK,
 * RS_ERR_NOMEM or RS_ERR_CANCELLED (then *arr unchanged). No message. */
rs_result rs__resize(rs_ctx *ctx, void **arr, size_t old, size_t bytes);

/* Record a failure detail on ctx (printf-style) and return `code`. */
rs_result rs__fail(rs_ctx *ctx, rs_result code, const char *fmt, ...) RS__PRINTF(3, 4);
/* Clear the message (on success paths). */
void rs__ok(rs_ctx *ctx);

/* Checked size arithmetic: return 0 on overflow, else 1 and *out. */
int rs__mul_size(size_t a, size_t b, size_t *out);
int rs__mul_u64(uint64_t a, uint64_t b, uint64_t *out);

/* Locale-independent decimal number parsing ("2.5", "-1e3"; never "2,5",
 * never hex, inf or nan). Parses [s, end); *stop receives the first byte not
 * consumed. Returns 0 when no number was read or it overflowed (|x| huge). */
int rs__parse_double(const char *s, const char *end, double *out, const char **stop);

/* World coordinates to the local frame (lib/core.c). rs__local_coord gives
 * world - origin rounded to 1/per_unit metres, so a scene translated by up
 * to ~10^7 m gives the same local coordinates, hence the same bytes;
 * rs__local_quantum(cell_size) is that per_unit: 10^6 per metre, or a
 * millionth of the power of ten at or below the cell size when cells are
 * smaller than 1 m (docs/stability.md). Every part that turns road points
 * into local coordinates must use these two. */
double rs__local_quantum(double cell_size);
double rs__local_coord(double world, double origin, double per_unit);

#define RS__PI 3.14159265358979323846

/* The ABI rule for option structs (include/roadsplat.h "ABI"): copy the
 * host's struct `in` (NULL: all defaults) of type `name` into `out`, this
 * header's layout of `full` bytes, by its first member `size_t size`: 0 is
 * this layout; a smaller size (a host built against an older header) has
 * its first `size` bytes read and the rest zero (defaults); a larger one
 * (a newer header) is refused with RS_ERR_UNSUPPORTED unless the bytes
 * beyond `full` are all zero. out->size is then `full`. ctx may be NULL
 * (no message). */
rs_result rs__opts_in(rs_ctx *ctx, const void *in, void *out, size_t full, const char *name);
#define RS__OPTS_IN(ctx, in, out, type) rs__opts_in((ctx), (in), (out), sizeof(type), #type)
/* The other way, for getters of such a struct (rs_ctx_limits,
 * ...): write `full` bytes of `src` into `out` up to out->size (0: all of
 * them); out->size becomes the bytes written. */
void rs__opts_out(const void *src, void *out, size_t full);

/* Validate splat options and fill in defaults (lib/options.c). */
rs_result rs__splat_defaults(rs_ctx *ctx, const rs_splat_options *in, rs_splat_options *out);
/* The roads ids[0..n) of a road set (ascending indices; ids NULL: the
 * first n, n at most the count) as a road set of their own, in that order: geometry, names, attributes, their markings
 * and point attributes (renumbered), the frame line (lib/input/roads_edit.c).
 * *out is the caller's (rs_roads_free). RS_ERR_INVALID_ARG, RS_ERR_NOMEM. */
rs_result rs__roads_subset(rs_ctx *ctx, const rs_roads *roads, const uint32_t *ids, size_t n, rs_roads **out);
/* What a whole map's roads decide for every pixel, beyond the roads near
 * it: a local build of some of them takes these from the whole map
 * (rs__road_grid_build_subset). */
typedef struct rs__grid_facts {
    double index_cell;            /* the road field's index cell, metres (0: none) */
    int styled;                   /* some road is styled */
    int any_surface, fill_uniform; /* rs__styling's switches of those names, and their colours */
    float fill_rgba[4];
    int casing_uniform;
    float casing_rgba[4];
    double widest_casing;         /* the widest casing, metres (0: none) */
    int ranked;                   /* the roads' priorities differ and some road has a surface: a fill
                                     lookup prefers the surfaces that hold a pixel (rs__styling's prio) */
    /* window_on: only the pixels inside window (local metres x0, y0, x1,
     * y1), and queries there up to window_reach metres, will be asked of
     * this part (a patch): its road fields list only the segments that can
     * reach them (rs__roadfield_params) */
    int window_on;
    double window[4], window_reach;
} rs__grid_facts;
/* The facts of grid g (a whole build: rs_road_grid_build) into *out. */
void rs__grid_facts_of(const rs_road_grid *g, rs__grid_facts *out);
/* rs_road_grid_build of the roads ids[0..n) of `roads` (ascending) with the
 * strokes and nodes of `net`, the network of all of `roads` (rs__network_subset),
 * instead of a network of their own, and the whole map's `facts`: inside a
 * region no farther than the stated reach from every road it leaves out,
 * the grid splats as the whole road set's does (lib/scene/roadgrid.c;
 * docs/embedding.md). */
rs_result rs__road_grid_build_subset(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads,
                                     const rs_splat_options *opts, const rs_network *net,
                                     const rs__grid_facts *facts, const uint32_t *ids, size_t n,
                                     rs_road_grid **out);

/* Fingerprint mixing (64 bits): a value into a running hash (one multiply
 * and a rotation; rs__fp_final mixes a finished fingerprint well). Shared
 * by the road set's per-road prints (lib/input/roads.c) and the edits'
 * pieces (lib/scene/grid_edit.h). */
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

/* A string (NULL: none) into a running hash, by its FNV-1a. */
static inline uint64_t rs__fp_mixs(uint64_t h, const char *s)
{
    uint64_t f = 1469598103934665603ull;
    for (; s && *s; s++) f = (f ^ (unsigned char)*s) * 1099511628211ull;
    return rs__fp_mix(h, f);
}

static inline uint64_t rs__fp_mixd(uint64_t h, double d)
{
    uint64_t v;
    if (d == 0) d = 0; /* -0 draws as 0 */
    memcpy(&v, &d, sizeof v);
    return rs__fp_mix(h, v);
}

/* Road i's print (name, width, points and attributes, not yet
 * rs__fp_final-mixed; point attributes and markings not in it), its width
 * and its points' box (x0, y0, x1, y1): kept by the road set as edits
 * make them (lib/input/roads.c), so an update does not hash every road. */
void rs__roads_road_print(const rs_roads *roads, size_t i, uint64_t *print, double *width, const double **box);

#endif
