/* Private declarations shared by the library's files (prefix rs__). */
#ifndef RS_INTERNAL_H
#define RS_INTERNAL_H
#include "roadsplat.h"
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#if defined(__GNUC__)
#define RS__PRINTF(a, b) __attribute__((format(printf, a, b)))
#else
#define RS__PRINTF(a, b)
#endif

struct rs_ctx {
    rs_allocator alloc;
    rs_limits limits;
    char message[256];
};

struct rs_dem {
    uint32_t width, height;
    float *z;           /* width*height, row-major, NaN = nodata */
    rs_dem_frame frame; /* defaults filled in (lib/dem.c) */
};

/* Allocation through the context's allocator. rs__alloc_array checks
 * count*size for overflow and returns NULL on it. None of these set a
 * message; callers return rs__fail(ctx, RS_ERR_NOMEM, ...). */
void *rs__malloc(rs_ctx *ctx, size_t size);
void *rs__calloc(rs_ctx *ctx, size_t count, size_t size);
void *rs__alloc_array(rs_ctx *ctx, size_t count, size_t size);
void *rs__realloc(rs_ctx *ctx, void *ptr, size_t size);
void rs__free(rs_ctx *ctx, void *ptr);

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

/* Validate splat options and fill in defaults (lib/options.c). */
rs_result rs__splat_defaults(rs_ctx *ctx, const rs_splat_options *in, rs_splat_options *out);
#endif
