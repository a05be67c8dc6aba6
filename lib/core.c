/* Context, allocator, limits, errors and version. */
#include "internal.h"

#include <math.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RS__STR2(x) #x
#define RS__STR(x) RS__STR2(x)

const char *rs_version_string(void)
{
    return RS__STR(RS_VERSION_MAJOR) "." RS__STR(RS_VERSION_MINOR) "." RS__STR(RS_VERSION_PATCH);
}

uint32_t rs_version_number(void)
{
    return (uint32_t)RS_VERSION;
}

const char *rs_strerror(rs_result r)
{
    switch (r) {
    case RS_OK: return "success";
    case RS_ERR_INVALID_ARG: return "invalid argument";
    case RS_ERR_NOMEM: return "out of memory";
    case RS_ERR_PARSE: return "malformed input";
    case RS_ERR_LIMIT: return "input exceeds a configured limit";
    case RS_ERR_BUFFER_TOO_SMALL: return "output buffer too small";
    case RS_ERR_POOL_EXHAUSTED: return "ROAM node pool exhausted";
    case RS_ERR_UNSUPPORTED: return "unsupported";
    case RS_ERR_CANCELLED: return "cancelled";
    }
    return "unknown error";
}

static void *default_malloc(void *user, size_t size) { (void)user; return malloc(size); }
static void *default_realloc(void *user, void *p, size_t size) { (void)user; return realloc(p, size); }
static void default_free(void *user, void *p) { (void)user; free(p); }

static void fill_limits(rs_limits *l)
{
    if (!l->max_dem_side) l->max_dem_side = 16384;
    if (!l->max_pixels) l->max_pixels = (uint64_t)1 << 28;
    if (!l->max_points) l->max_points = 10000000u;
    if (!l->max_line_length) l->max_line_length = 65536;
    if (!l->max_road_cells) l->max_road_cells = (uint64_t)1 << 32;
    if (!l->max_pool_nodes) l->max_pool_nodes = (uint32_t)1 << 26;
    if (!l->max_texture_pixels) l->max_texture_pixels = (uint64_t)1 << 26;
    if (!l->max_field_work) l->max_field_work = (uint64_t)1 << 30;
    if (!l->max_atlas_bytes) l->max_atlas_bytes = (uint64_t)1 << 28;
    if (!l->max_linesym_bytes) l->max_linesym_bytes = (uint64_t)1 << 32;
    if (!l->max_dirty_compare) l->max_dirty_compare = (uint64_t)1 << 20;
    if (!l->max_patches) l->max_patches = 16;
}

rs_result rs_ctx_create(const rs_allocator *alloc, const rs_limits *limits, rs_ctx **out)
{
    if (!out) return RS_ERR_INVALID_ARG;
    *out = NULL;
    rs_allocator a = { default_malloc, default_realloc, default_free, NULL };
    if (alloc) {
        if (!alloc->malloc_fn || !alloc->realloc_fn || !alloc->free_fn) return RS_ERR_INVALID_ARG;
        a = *alloc;
    }
    rs_limits lim;
    if (RS__OPTS_IN(NULL, limits, &lim, rs_limits)) return limits->size < sizeof(size_t) ? RS_ERR_INVALID_ARG : RS_ERR_UNSUPPORTED;
    rs_ctx *ctx = a.malloc_fn(a.user, sizeof *ctx);
    if (!ctx) return RS_ERR_NOMEM;
    memset(ctx, 0, sizeof *ctx);
    ctx->alloc = a;
    ctx->limits = lim;
    fill_limits(&ctx->limits);
    *out = ctx;
    return RS_OK;
}

void rs_ctx_free(rs_ctx *ctx)
{
    if (ctx) ctx->alloc.free_fn(ctx->alloc.user, ctx);
}

void rs_ctx_limits(const rs_ctx *ctx, rs_limits *out)
{
    if (ctx && out) rs__opts_out(&ctx->limits, out, sizeof *out);
}

const char *rs_ctx_message(const rs_ctx *ctx)
{
    return ctx ? ctx->message : "";
}

void *rs__malloc(rs_ctx *ctx, size_t size)
{
    return ctx->alloc.malloc_fn(ctx->alloc.user, size ? size : 1);
}

void *rs__alloc_array(rs_ctx *ctx, size_t count, size_t size)
{
    size_t total;
    if (!rs__mul_size(count, size, &total)) return NULL;
    return rs__malloc(ctx, total);
}

void *rs__calloc(rs_ctx *ctx, size_t count, size_t size)
{
    size_t total;
    if (!rs__mul_size(count, size, &total)) return NULL;
    void *p = rs__malloc(ctx, total);
    if (p) memset(p, 0, total);
    return p;
}

void *rs__realloc(rs_ctx *ctx, void *ptr, size_t size)
{
    return ctx->alloc.realloc_fn(ctx->alloc.user, ptr, size ? size : 1);
}

void rs__free(rs_ctx *ctx, void *ptr)
{
    if (ptr) ctx->alloc.free_fn(ctx->alloc.user, ptr);
}

/* Copied in pieces between these sizes; below, a copy is short; from 32 MB
 * up glibc serves blocks with mmap and grows them with mremap (no copy). */
#define GROW_PIECE ((size_t)1 << 20)
#define GROW_PIECES_BELOW ((size_t)32 << 20)

rs_result rs__resize(rs_ctx *ctx, void **arr, size_t old, size_t bytes)
{
    void *q;
    if (old < 2 * GROW_PIECE || old >= GROW_PIECES_BELOW || bytes < old) {
        q = rs__realloc(ctx, *arr, bytes);
        if (!q) return RS_ERR_NOMEM;
    } else {
        q = rs__malloc(ctx, bytes);
        if (!q) return RS_ERR_NOMEM;
        const unsigned char *from = *arr;
        for (size_t at = 0; at < old; at += GROW_PIECE) {
            if (rs__report(ctx, 0)) {
                rs__free(ctx, q);
                return RS_ERR_CANCELLED;
            }
            memcpy((unsigned char *)q + at, from + at, old - at < GROW_PIECE ? old - at : GROW_PIECE);
        }
        rs__free(ctx, *arr);
    }
    *arr = q;
    return RS_OK;
}

rs_result rs__grow(rs_ctx *ctx, void **arr, size_t n, size_t *cap, size_t size, size_t first, size_t max)
{
    if (n < *cap) return RS_OK;
    size_t nc = *cap ? 2 * *cap : first, bytes;
    if (nc > max) nc = max;
    if (nc <= n) return RS_ERR_LIMIT;
    if (!rs__mul_size(nc, size, &bytes)) return RS_ERR_NOMEM;
    rs_result r = rs__resize(ctx, arr, *cap * size, bytes);
    if (!r) *cap = nc;
    return r;
}

rs_result rs__fail(rs_ctx *ctx, rs_result code, const char *fmt, ...)
{
    if (ctx) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(ctx->message, sizeof ctx->message, fmt, ap);
        va_end(ap);
    }
    return code;
}

rs_result rs__opts_in(rs_ctx *ctx, const void *in, void *out, size_t full, const char *name)
{
    size_t size = 0;
    memset(out, 0, full);
    if (!in) {
        memcpy(out, &full, sizeof full);
        return RS_OK;
    }
    memcpy(&size, in, sizeof size);
    if (size == 0) size = full;
    if (size < sizeof size)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "%s.size %zu is smaller than the size field itself", name, size);
    if (size > full) {
        const unsigned char *tail = (const unsigned char *)in + full;
        for (size_t k = 0; k < size - full; k++)
            if (tail[k])
                return rs__fail(ctx, RS_ERR_UNSUPPORTED,
                                "%s.size %zu: byte %zu is set, but this roadsplat %s knows only %zu bytes "
                                "(options of a newer header)",
                                name, size, full + k, rs_version_string(), full);
        size = full;
    }
    memcpy(out, in, size);
    memcpy(out, &full, sizeof full);
    return RS_OK;
}

void rs__opts_out(const void *src, void *out, size_t full)
{
    size_t size;
    memcpy(&size, out, sizeof size);
    if (size == 0 || size > full) size = full;
    if (size < sizeof size) return; /* nothing but part of the size field: leave it */
    memcpy(out, src, size);
    memcpy(out, &size, sizeof size);
}

void rs_ctx_set_progress(rs_ctx *ctx, rs_progress_fn fn, void *user)
{
    if (!ctx) return;
    ctx->progress = fn;
    ctx->progress_user = fn ? user : NULL;
}

int rs__tick(rs_ctx *ctx, uint64_t units)
{
    rs__progress *p = ctx ? ctx->pg : NULL;
    if (!p || !p->fn) return 0;
    if (p->cancelled) return 1;
    p->done += units;
    if (p->done < p->next && ++p->polls < RS__TICK_POLLS) return 0;
    p->polls = 0;
    p->next = p->done + (p->step ? p->step : 1);
    p->said = p->done < p->total ? p->done : p->total;
    if (p->fn(p->user, p->said, p->total)) p->cancelled = 1;
    return p->cancelled;
}

int rs__report(rs_ctx *ctx, uint64_t units)
{
    if (ctx && ctx->pg) ctx->pg->polls = RS__TICK_POLLS;
    return rs__tick(ctx, units);
}

int rs__poll(rs_ctx *ctx)
{
    return rs__report(ctx, 0);
}

void rs__progress_begin(rs_ctx *ctx, rs__progress *pg, rs_progress_fn fn, void *user, uint64_t total,
                        uint64_t step)
{
    memset(pg, 0, sizeof *pg);
    pg->outer = ctx->pg;
    pg->said = UINT64_MAX;
    if (!fn) {
        fn = ctx->progress;
        user = ctx->progress_user;
    }
    /* inside a call that reports, or nothing to report to: ticks go to
     * ctx->pg as it is */
    if ((ctx->pg && ctx->pg->fn) || !fn) {
        pg->nested = 1;
        return;
    }
    pg->fn = fn;
    pg->user = user;
    pg->total = total;
    pg->step = step ? step : 1;
    pg->next = pg->step;
    ctx->pg = pg;
}

rs_result rs__progress_end(rs_ctx *ctx, rs__progress *pg, rs_result r)
{
    if (pg->nested) return r; /* the outer call ends it (and names a cancel) */
    ctx->pg = pg->outer;
    if (!r && pg->fn && !pg->cancelled && pg->said != pg->total) {
        pg->said = pg->total;
        if (pg->fn(pg->user, pg->total, pg->total)) pg->cancelled = 1;
    }
    if (!r && pg->cancelled) r = RS_ERR_CANCELLED;
    if (r == RS_ERR_CANCELLED) return rs__fail(ctx, r, "cancelled");
    return r;
}

void rs__ok(rs_ctx *ctx)
{
    if (ctx) ctx->message[0] = '\0';
}

int rs__mul_size(size_t a, size_t b, size_t *out)
{
    if (a && b > SIZE_MAX / a) return 0;
    *out = a * b;
    return 1;
}

int rs__mul_u64(uint64_t a, uint64_t b, uint64_t *out)
{
    if (a && b > UINT64_MAX / a) return 0;
    *out = a * b;
    return 1;
}

/* The rounding removes the last bits lost when large world coordinates were
 * read; scaling cell size and roads by a power of ten scales the quantum
 * with them. */
double rs__local_quantum(double cell_size)
{
    return cell_size < 1 ? pow(10.0, 6.0 - floor(log10(cell_size))) : 1e6;
}

double rs__local_coord(double world, double origin, double per_unit)
{
    double d = world - origin;
    if (!(fabs(d) * per_unit < 1e18)) return d; /* far away: precision is moot, keep it finite */
    return floor(d * per_unit + 0.5) / per_unit;
}
