/* ROAM terrain mesher: the landscape's lifecycle (create, set_dem, free,
 * stats). The mesher's parts and where they live: lib/roam/roam.h and
 * docs/roam.md, "Source files". */
#include "roam.h"

#include <float.h>
#include <math.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#define MAX_PATCH_LOG 14          /* patch side <= 16384 cells: heap index < 2^30 */
/* The automatic patch side is at most 64 cells: patches are the unit of
 * frustum culling, of the height range behind the view priorities and of
 * rs_roam_extract_patch; error-mode meshes do not depend on it (docs/roam.md). */
#define AUTO_PATCH_LOG 6
#define MAX_SIDE 32768u           /* node coordinates are uint16 */
#define AUTO_POOL_CAP (1u << 21)
/* Upload units: halves of 8-cell squares (128 per 64-cell patch; on the
 * drives 1-3 % of the vertices change per frame on average, at most a
 * tenth; with 16-cell squares up to a quarter: docs/roam.md) */
#define DEFAULT_UNIT_SIZE 8u

size_t rs_roam_node_bytes(void) { return sizeof(roam_node); }

/* ---- nodata ---------------------------------------------------------------- */

/* The DEM module's nodata policy (lib/dem.c), into an owned copy. */
static rs_result fill_nodata(rs_ctx *ctx, rs_roam *L, const rs_dem *dem)
{
    float *z;
    rs_result r = rs__dem_fill_nodata(ctx, dem, &z);
    if (r != RS_OK) return r;
    L->zown = z;
    L->z = z;
    return RS_OK;
}

/* ---- heights -------------------------------------------------------------------- */

/* Largest |z| over the finite samples of z[0..n), and whether there are
 * others (NaN or infinite: nodata). */
static float abs_max_finite(const float *z, size_t n, int *bad)
{
    size_t i = 0;
    float zmax = 0.0f;
    *bad = 0;
#if defined(__SSE2__)
    /* The usual DEM, all finite, in four lanes: max of |z| and a NaN flag;
     * an infinity shows in the max. Anything non-finite takes the scalar
     * loop below from the start, which skips it exactly. */
    {
        const __m128 absmask = _mm_castsi128_ps(_mm_set1_epi32(0x7FFFFFFF));
        __m128 m = _mm_setzero_ps(), nan = _mm_setzero_ps();
        for (; i + 4 <= n; i += 4) {
            __m128 a = _mm_and_ps(_mm_loadu_ps(z + i), absmask);
            nan = _mm_or_ps(nan, _mm_cmpunord_ps(a, a));
            m = _mm_max_ps(a, m); /* NaN lanes keep m */
        }
        float lane[4];
        _mm_storeu_ps(lane, m);
        zmax = lane[0];
        for (int k = 1; k < 4; k++) if (lane[k] > zmax) zmax = lane[k];
        if (_mm_movemask_ps(nan) || !(zmax <= FLT_MAX)) { i = 0; zmax = 0.0f; }
    }
#endif
    for (; i < n; i++) {
        float a = fabsf(z[i]);
        if (!(a <= FLT_MAX)) *bad = 1; /* NaN or inf */
        else if (a > zmax) zmax = a;
    }
    return zmax;
}

/* Heights must stay finite through the error arithmetic (checked over the
 * valid samples: filled nodata copies one of them). One pass, which also
 * tells whether there is nodata to fill. */
static rs_result check_heights(rs_ctx *ctx, const rs_roam *L, const rs_dem *dem, int *has_nodata, float *zabs)
{
    int bad;
    float zmax = abs_max_finite(dem->z, (size_t)L->w * L->hgt, &bad);
    *has_nodata = bad;
    *zabs = zmax;
    /* In float, where they are kept: error bounds (differences of up to
     * four heights' worth) and the vertices' z = height * z_scale. An
     * infinite bound would split every triangle at any max error. */
    if (!(zmax <= FLT_MAX / 4) || !((double)zmax * L->zs <= FLT_MAX))
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "ROAM: heights up to %g times z_scale %g leave the float range (at most %g, and %g "
                        "before scaling)", zmax, L->zs, (double)FLT_MAX, (double)(FLT_MAX / 4));
    return RS_OK;
}

/* Point the landscape at dem's heights (nodata filled into an owned copy),
 * forget every cached error bound and recompute the per-patch height
 * ranges. On failure the landscape keeps its previous heights. */
static rs_result load_heights(rs_ctx *ctx, rs_roam *L, const rs_dem *dem, int has_nodata)
{
    float *old = L->zown;
    if (has_nodata) {
        L->zown = NULL;
        rs_result r = fill_nodata(ctx, L, dem);
        if (r != RS_OK) { L->zown = old; return r; }
    } else {
        L->zown = NULL;
        L->z = dem->z;
    }
    rs__free(ctx, old);
    /* all NaN (computed on first use): no chunk initialised */
    memset(L->eready, 0, (L->nerr + ERR_CHUNK - 1) / ERR_CHUNK);
    L->err_empty = 1;
    L->zrange_ok = 0; /* rs__roam_patch_ranges, when a view frame needs them */
    return RS_OK;
}

void rs__roam_patch_ranges(rs_roam *L)
{
    if (L->zrange_ok) return;
    size_t W = L->w;
    uint32_t P = L->P;
    for (uint32_t py = 0; py < L->npy; py++)
        for (uint32_t px = 0; px < L->npx; px++) {
            uint32_t p = py * L->npx + px, x0 = px * P, y0 = py * P;
            float lo = INFINITY, hi = -INFINITY;
            uint32_t xe = x0 + P < L->cw ? x0 + P : L->cw, ye = y0 + P < L->ch ? y0 + P : L->ch;
            for (uint32_t y = y0; y <= ye; y++)
                for (uint32_t x = x0; x <= xe; x++) {
                    float v = L->z[(size_t)y * W + x];
                    if (v < lo) lo = v;
                    if (v > hi) hi = v;
                }
            L->pzmin[p] = lo; L->pzmax[p] = hi;
        }
    L->zrange_ok = 1;
}

rs_result rs_roam_set_dem(rs_ctx *ctx, rs_roam *L, const rs_dem *dem)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!L || !dem) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_set_dem: roam and dem must not be NULL");
    if (dem->width != L->w || dem->height != L->hgt)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_set_dem: DEM is %ux%u, the landscape %ux%u",
                        dem->width, dem->height, L->w, L->hgt);
    if (dem->frame.cell_size != L->cs || dem->frame.z_scale != L->zs)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_roam_set_dem: DEM frame (cell size %g, z-scale %g) differs from the landscape's (%g, %g)",
                        dem->frame.cell_size, dem->frame.z_scale, L->cs, L->zs);
    int has_nodata;
    float zabs;
    /* progress: one call, once the new DEM is checked (a stop there keeps
     * the previous DEM; the load after it takes a few ms) */
    rs__progress pg;
    rs__progress_begin(ctx, &pg, NULL, NULL, 1, 1);
    rs_result r = check_heights(ctx, L, dem, &has_nodata, &zabs);
    if (r == RS_OK && rs__report(ctx, 1)) r = RS_ERR_CANCELLED;
    if (r == RS_OK) r = load_heights(ctx, L, dem, has_nodata);
    if (r != RS_OK) return rs__progress_end(ctx, &pg, r);
    L->zabs = zabs;
    rs__roam_reset_mesh(L);
    L->threshold = INFINITY;
    L->tol = 0.0;
    L->frame_passes = 0;
    L->culled = 0;
    if ((r = rs__progress_end(ctx, &pg, r)) != RS_OK) return r; /* (never: the one call said done) */
    rs__ok(ctx);
    return RS_OK;
}

/* ---- progress ---------------------------------------------------------------- */

void rs__roam_progress_begin(rs_ctx *ctx, rs_roam *L, rs__progress *pg, uint64_t total, rs_ctx **saved)
{
    rs__progress_begin(ctx, pg, NULL, NULL, total, total / 1024 + 1);
    *saved = L->pctx;
    L->pctx = ctx;
    if (!*saved) L->cancelled = 0;
    L->polled_used = L->used;
}

rs_result rs__roam_progress_end(rs_ctx *ctx, rs_roam *L, rs__progress *pg, rs_result r, rs_ctx *saved)
{
    L->pctx = saved;
    if (L->cancelled && (r == RS_OK || r == RS_ERR_POOL_EXHAUSTED)) r = RS_ERR_CANCELLED;
    if (!saved) L->cancelled = 0; /* the outermost call is over */
    return rs__progress_end(ctx, pg, r);
}

int rs__roam_poll(rs_roam *L)
{
    if (!L->pctx || L->cancelled) return L->cancelled;
    uint32_t u = L->used, d = u > L->polled_used ? u - L->polled_used : 0;
    L->polled_used = u;
    if (rs__report(L->pctx, d)) L->cancelled = 1;
    return L->cancelled;
}

/* ---- creation --------------------------------------------------------------- */

static uint32_t choose_patch_log(uint32_t cw, uint32_t ch)
{
    /* Cost: two roots per patch plus the border splits when the map edge cuts
     * through patches (about four triangles per cell of edge). */
    uint32_t best = 0;
    double best_cost = -1.0;
    uint32_t big = cw > ch ? cw : ch;
    for (uint32_t lg = 0; lg <= AUTO_PATCH_LOG; lg++) {
        uint32_t P = 1u << lg;
        if (lg > 0 && (P >> 1) >= big) break;
        double nx = (double)((cw + P - 1) / P), ny = (double)((ch + P - 1) / P);
        double cost = 2.0 * nx * ny + ((cw % P) ? 4.0 * ch : 0.0) + ((ch % P) ? 4.0 * cw : 0.0);
        if (best_cost < 0 || cost <= best_cost) { best_cost = cost; best = lg; }
    }
    return best;
}

static int node_inside(const rs_roam *L, const roam_node *n)
{
    int cx, cy;
    node_corner(n, &cx, &cy);
    return inside_xy(L, n->ax, n->ay, n->bx, n->by, cx, cy);
}

static void init_roots(rs_roam *L)
{
    roam_node *n = L->nodes;
    uint32_t P = L->P;
    for (uint32_t py = 0; py < L->npy; py++)
        for (uint32_t px = 0; px < L->npx; px++) {
            uint32_t p = py * L->npx + px, r0 = 2 * p, r1 = 2 * p + 1;
            uint32_t x0 = px * P, y0 = py * P;
            roam_node *a = &n[r0], *b = &n[r1];
            a->lc = a->rc = b->lc = b->rc = NIL;
            /* P = 1: the roots are already cell halves */
            a->e = L->plog ? (uint32_t)(p * L->epp + 2) : NIL;
            b->e = L->plog ? (uint32_t)(p * L->epp + 3) : NIL;
            /* root 0: apex top-left, left corner top-right; root 1 mirrors it */
            a->ax = (uint16_t)x0; a->ay = (uint16_t)y0; a->bx = (uint16_t)(x0 + P); a->by = (uint16_t)y0;
            b->ax = (uint16_t)(x0 + P); b->ay = (uint16_t)(y0 + P); b->bx = (uint16_t)x0; b->by = (uint16_t)(y0 + P);
            a->base = r1; b->base = r0;
            a->left = py > 0 ? 2 * (p - L->npx) + 1 : NIL;          /* top edge */
            a->right = px > 0 ? 2 * (p - 1) + 1 : NIL;              /* left edge */
            b->left = py + 1 < L->npy ? 2 * (p + L->npx) : NIL;     /* bottom edge */
            b->right = px + 1 < L->npx ? 2 * (p + 1) : NIL;         /* right edge */
        }
    L->used = 2 * L->npx * L->npy;
    L->tris = 0;
    for (uint32_t i = 0; i < L->used; i++) L->tris += (uint32_t)node_inside(L, &n[i]);
}

void rs_roam_free(rs_ctx *ctx, rs_roam *L)
{
    if (!ctx || !L) return;
    rs__free(ctx, L->zown);
    rs__free(ctx, L->err);
    rs__free(ctx, L->eready);
    rs__free(ctx, L->pzmin);
    rs__free(ctx, L->pzmax);
    rs__free(ctx, L->pin);
    rs__free(ctx, L->pgen);
    rs__free(ctx, L->ugen);
    rs__free(ctx, L->nodes);
    rs__free(ctx, L->base_copy);
    rs__free(ctx, L->stack);
    rs__free(ctx, L->vrank);
    rs__free(ctx, L->ucol);
    rs__free(ctx, L->vrow);
    rs__free(ctx, L->vbits);
    rs__free(ctx, L->vsum);
    rs__free(ctx, L->smap);
    rs__roam_update_free(ctx, L);
    rs__free(ctx, L);
}

/* The landscape's dimensions, worked out from the DEM and the options
 * before anything is allocated. */
typedef struct roam_size {
    double cs, zs;                  /* the DEM's frame */
    uint32_t W, H;                  /* samples */
    uint32_t plog, P, npx, npy;     /* patch side 2^plog cells, patches per row and column */
    uint32_t dq;                    /* implicit levels below a block node */
    uint32_t usize, udepth;         /* upload unit: square side (cells), depth below the roots */
    uint64_t npatch, epp, nerr;     /* patches, heap indices per patch, all of them */
    uint64_t pool;                  /* pool nodes */
} roam_size;

/* Check the DEM's size and frame and the options against the limits, and
 * size the landscape: patches, error entries, implicit levels, pool. */
static rs_result size_landscape(rs_ctx *ctx, const rs_dem *dem, const rs_roam_options *opts, roam_size *s)
{
    rs_roam_options o;
    rs_result rc = RS__OPTS_IN(ctx, opts, &o, rs_roam_options);
    if (rc) return rc;
    double cs = dem->frame.cell_size, zs = dem->frame.z_scale;
    if (!(zs > 0.0))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM: the DEM's z-scale %g must be > 0 (z is up)", zs);
    uint32_t W = dem->width, H = dem->height;
    if (W < 2 || H < 2)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM: DEM is %ux%u, need at least 2x2 samples", W, H);
    /* Vertices are floats (j*cs, i*cs): every one a normal float, so they
     * stay distinct and exact to float precision, and the map fits. */
    double side = (double)(W > H ? W : H) - 1.0;
    if (cs < FLT_MIN || side * cs > FLT_MAX)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "ROAM: cell_size %g is outside the float range of the vertices (%g .. %g for a %ux%u DEM)",
                        cs, (double)FLT_MIN, FLT_MAX / side, W, H);
    uint32_t side_lim = ctx->limits.max_dem_side < MAX_SIDE ? ctx->limits.max_dem_side : MAX_SIDE;
    if (W > side_lim || H > side_lim)
        return rs__fail(ctx, RS_ERR_LIMIT, "ROAM: DEM %ux%u exceeds the side limit %u", W, H, side_lim);
    uint32_t plog;
    if (o.patch_size) {
        if (o.patch_size & (o.patch_size - 1) || o.patch_size > (1u << MAX_PATCH_LOG))
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM: patch_size %u must be a power of two <= %u",
                            o.patch_size, 1u << MAX_PATCH_LOG);
        for (plog = 0; (1u << plog) < o.patch_size; plog++) {}
    } else plog = choose_patch_log(W - 1, H - 1);
    uint32_t P = 1u << plog;
    uint32_t npx = (W - 1 + P - 1) / P, npy = (H - 1 + P - 1) / P;
    if ((uint64_t)npx * P > 65535u || (uint64_t)npy * P > 65535u)
        return rs__fail(ctx, RS_ERR_LIMIT, "ROAM: patch size %u too large for a %ux%u DEM", P, W, H);
    /* upload units: halves of usize-cell squares, from the block level
     * (units hold whole blocks) to the patch */
    uint32_t usize = o.unit_size ? o.unit_size : DEFAULT_UNIT_SIZE;
    if (usize & (usize - 1))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM: unit_size %u must be a power of two", o.unit_size);
    uint32_t dq0 = 2 * plog < IMPL_DEPTH ? 2 * plog : IMPL_DEPTH, ublock = 1u << (dq0 / 2);
    if (usize > P) usize = P;
    if (usize < ublock) usize = ublock;
    uint32_t ulog = 0;
    while ((1u << ulog) < usize) ulog++;
    uint64_t npatch = (uint64_t)npx * npy;
    uint64_t epp = (uint64_t)P * P; /* heap indices down to the R level: < P^2 */
    uint64_t nerr;
    if (!rs__mul_u64(npatch, epp, &nerr) || nerr >= ((uint64_t)1 << 32) || 2 * npatch > 0x7FFFFFFFull)
        return rs__fail(ctx, RS_ERR_LIMIT, "ROAM: %llu patches of %u cells need too many error entries",
                        (unsigned long long)npatch, P);
    /* Full refinement: every patch tree down to the block level (the dq
     * finer levels are implicit): 2 + 4 + ... + 2^(2 plog - dq + 1) nodes. */
    uint32_t dq = 2 * plog < IMPL_DEPTH ? 2 * plog : IMPL_DEPTH;
    uint64_t full_nodes = npatch * (((uint64_t)1 << (2 * plog - dq + 2)) - 2);
    uint64_t pool;
    if (o.pool_nodes) pool = o.pool_nodes;
    else if (o.pool_bytes) pool = o.pool_bytes / sizeof(roam_node);
    else {
        pool = full_nodes;
        if (pool > AUTO_POOL_CAP) pool = AUTO_POOL_CAP;
        if (pool > ctx->limits.max_pool_nodes) pool = ctx->limits.max_pool_nodes;
    }
    if (pool > ctx->limits.max_pool_nodes)
        return rs__fail(ctx, RS_ERR_LIMIT, "ROAM: pool of %llu nodes exceeds max_pool_nodes %u",
                        (unsigned long long)pool, ctx->limits.max_pool_nodes);
    s->cs = cs; s->zs = zs; s->W = W; s->H = H;
    s->plog = plog; s->P = P; s->npx = npx; s->npy = npy; s->dq = dq;
    s->usize = usize; s->udepth = 2 * (plog - ulog);
    s->npatch = npatch; s->epp = epp; s->nerr = nerr; s->pool = pool;
    return RS_OK;
}

/* A landscape of size s with its partner table, no tables or nodes yet
 * (NULL when out of memory). */
static rs_roam *new_landscape(rs_ctx *ctx, const roam_size *s)
{
    rs_roam *L = rs__calloc(ctx, 1, sizeof *L);
    if (!L) return NULL;
    L->w = s->W; L->hgt = s->H; L->cw = s->W - 1; L->ch = s->H - 1;
    L->cs = s->cs; L->zs = s->zs;
    L->plog = s->plog; L->P = s->P; L->npx = s->npx; L->npy = s->npy; L->epp = (size_t)s->epp;
    L->elog = 2 * s->plog;
    L->dq = s->dq; L->ncut = 1u << s->dq;
    L->usize = s->usize; L->udepth = s->udepth; L->upp = 2u << s->udepth;
    L->scan = NIL;
    L->free_head = NIL;
    rs__roam_build_partner_table(L);
    return L;
}

/* The per-patch tables (error cache, height ranges, on-map flags) and
 * extraction's (vertex set, texture coordinates, skirt map), initialised
 * except for what the heights fill in (load_heights). */
static rs_result alloc_tables(rs_ctx *ctx, rs_roam *L, const roam_size *s)
{
    uint32_t W = s->W, H = s->H, P = s->P;
    size_t npatch = (size_t)s->npatch;
    uint64_t nerr = (s->nerr + 1) / 2; /* cached above the R level only (err_slot) */
    L->nerr = (size_t)nerr;
    L->err = rs__alloc_array(ctx, (size_t)nerr, sizeof(float));
    L->eready = rs__alloc_array(ctx, ((size_t)nerr + ERR_CHUNK - 1) / ERR_CHUNK, 1);
    L->pzmin = rs__alloc_array(ctx, npatch, sizeof(float));
    L->pzmax = rs__alloc_array(ctx, npatch, sizeof(float));
    L->pin = rs__alloc_array(ctx, npatch, 1);
    L->pgen = rs__alloc_array(ctx, npatch, sizeof(uint32_t));
    L->ugen = rs__alloc_array(ctx, npatch * L->upp, sizeof(uint32_t));
    L->wpr = (W + 63) / 64;
    L->nwords = (size_t)L->wpr * H;
    L->nsum = (L->nwords + 63) / 64;
    L->vbits = rs__alloc_array(ctx, L->nwords, sizeof(uint64_t));
    L->vsum = rs__alloc_array(ctx, L->nsum, sizeof(uint64_t));
    L->vrank = rs__alloc_array(ctx, L->nwords, sizeof(uint32_t));
    L->ucol = rs__alloc_array(ctx, W, sizeof(float));
    L->vrow = rs__alloc_array(ctx, H, sizeof(float));
    L->smap = rs__alloc_array(ctx, 2 * ((size_t)W + H), sizeof(uint32_t));
    if (!L->err || !L->eready || !L->pzmin || !L->pzmax || !L->pin || !L->pgen || !L->ugen || !L->vbits || !L->vsum || !L->vrank || !L->smap || !L->ucol || !L->vrow)
        return rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory for the error tree (%llu entries)",
                        (unsigned long long)nerr);
    memset(L->vbits, 0, L->nwords * sizeof(uint64_t));
    memset(L->vsum, 0, L->nsum * sizeof(uint64_t));
    for (uint32_t x = 0; x < W; x++) L->ucol[x] = (float)((double)x / L->cw);
    for (uint32_t y = 0; y < H; y++) L->vrow[y] = (float)((double)y / L->ch);
    memset(L->smap, 0xFF, 2 * ((size_t)W + H) * sizeof(uint32_t));
    L->gen = 1;
    for (size_t p = 0; p < npatch; p++) L->pgen[p] = 1;
    for (size_t u = 0; u < npatch * L->upp; u++) L->ugen[u] = 1;
    for (uint32_t py = 0; py < s->npy; py++)
        for (uint32_t px = 0; px < s->npx; px++)
            L->pin[py * s->npx + px] = (unsigned char)(px * P + P <= L->cw && py * P + P <= L->ch);
    return RS_OK;
}

/* Base mesh: roots plus the splits that stop triangles straddling the map
 * edge. Sized by trial, doubling, before the pool exists. */
static rs_result build_base_mesh(rs_ctx *ctx, rs_roam *L, const roam_size *s)
{
    uint64_t roots = 2 * s->npatch;
    uint64_t bcap = roots + 64;
    refine_params rp = { INFINITY, 1, NULL, NULL, 0 };
    for (;;) {
        if (bcap + s->pool > 0x7FFFFFF0ull) /* node indices below TAG */
            return rs__fail(ctx, RS_ERR_LIMIT, "ROAM: base mesh plus pool exceed 2^32 nodes");
        roam_node *nn = rs__realloc(ctx, L->nodes, (size_t)bcap * sizeof(roam_node));
        if (!nn) return rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory for %llu base nodes", (unsigned long long)bcap);
        L->nodes = nn;
        uint32_t *ns = rs__realloc(ctx, L->stack, 2 * (size_t)bcap * sizeof(uint32_t));
        if (!ns) return rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory for %llu base nodes", (unsigned long long)bcap);
        L->stack = ns;
        L->cap = (uint32_t)bcap;
        init_roots(L);
        L->exhausted = 0;
        rs__roam_refine(L, &rp);
        if (!L->exhausted) break;
        bcap *= 2;
    }
    L->base_count = L->used;
    L->base_tris = L->tris;
    return RS_OK;
}

/* Grow the node array and the stack to the base mesh plus `pool` nodes,
 * and keep the copy of the base mesh that every refinement starts from. */
static rs_result alloc_pool(rs_ctx *ctx, rs_roam *L, uint64_t pool)
{
    size_t total;
    if (!rs__mul_size((size_t)L->base_count + (size_t)pool, sizeof(roam_node), &total))
        return rs__fail(ctx, RS_ERR_LIMIT, "ROAM: pool too large");
    roam_node *nn = rs__realloc(ctx, L->nodes, total);
    if (nn) L->nodes = nn;
    uint32_t *ns = nn ? rs__realloc(ctx, L->stack, 2 * (total / sizeof(roam_node)) * sizeof(uint32_t)) : NULL;
    if (ns) L->stack = ns;
    L->base_copy = rs__alloc_array(ctx, L->base_count, sizeof(roam_node));
    if (!nn || !ns || !L->base_copy)
        return rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory for a pool of %llu nodes", (unsigned long long)pool);
    for (uint32_t i = 0; i < L->base_count; i++) /* keep the split bits only */
        if (L->nodes[i].lc == IMPL) L->nodes[i].rc &= SPLIT_BIT(L->ncut) - 1u;
    memcpy(L->base_copy, L->nodes, (size_t)L->base_count * sizeof(roam_node));
    L->cap = L->base_count + (uint32_t)pool;
    return RS_OK;
}

/* Memory held by a newly created landscape (rs_roam_stats.bytes). */
static uint64_t landscape_bytes(const rs_roam *L)
{
    uint64_t W = L->w, H = L->hgt, npatch = (uint64_t)L->npx * L->npy;
    return sizeof *L + (uint64_t)L->nerr * sizeof(float) + (L->nerr + ERR_CHUNK - 1) / ERR_CHUNK + npatch * (2 * sizeof(float) + 1 + sizeof(uint32_t) + L->upp * sizeof(uint32_t))
           + W * H * sizeof(float) * (L->zown ? 1 : 0)
           + (uint64_t)L->nwords * (sizeof(uint64_t) + sizeof(uint32_t)) + (uint64_t)L->nsum * sizeof(uint64_t)
           + 2 * (W + H) * sizeof(uint32_t)
           + ((uint64_t)L->cap + L->base_count) * sizeof(roam_node)
           + 2 * (uint64_t)L->cap * sizeof(uint32_t) + (W + H) * sizeof(float);
}

/* A stage of rs_roam_create done: RS_ERR_CANCELLED when the callback says stop. */
static rs_result create_poll(rs_ctx *ctx)
{
    return rs__report(ctx, 1) ? RS_ERR_CANCELLED : RS_OK;
}

rs_result rs_roam_create(rs_ctx *ctx, const rs_dem *dem, const rs_roam_options *opts, rs_roam **out)
{
    if (out) *out = NULL;
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!dem || !out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_create: dem and out must not be NULL");
    roam_size s;
    memset(&s, 0, sizeof s);
    rs_result r = size_landscape(ctx, dem, opts, &s);
    if (r != RS_OK) return r;
    rs_roam *L = new_landscape(ctx, &s);
    if (!L) return rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory");
    /* progress: a unit per stage, polls between them (the base mesh's
     * refinement polls within) */
    rs__progress pg;
    rs__progress_begin(ctx, &pg, NULL, NULL, 5, 1);
    L->pctx = ctx;
    int has_nodata;
    if ((r = check_heights(ctx, L, dem, &has_nodata, &L->zabs)) != RS_OK || (r = create_poll(ctx)) != RS_OK
        || (r = alloc_tables(ctx, L, &s)) != RS_OK || (r = create_poll(ctx)) != RS_OK
        || (r = load_heights(ctx, L, dem, has_nodata)) != RS_OK || (r = create_poll(ctx)) != RS_OK
        || (r = build_base_mesh(ctx, L, &s)) != RS_OK || (r = L->cancelled ? RS_ERR_CANCELLED : create_poll(ctx)) != RS_OK
        || (r = alloc_pool(ctx, L, s.pool)) != RS_OK) {
        L->pctx = NULL;
        rs_roam_free(ctx, L);
        return rs__progress_end(ctx, &pg, r);
    }
    L->pctx = NULL;
    if ((r = rs__progress_end(ctx, &pg, RS_OK)) != RS_OK) {
        rs_roam_free(ctx, L);
        return r;
    }
    L->bytes = landscape_bytes(L);
    L->threshold = INFINITY;
    rs__ok(ctx);
    *out = L;
    return RS_OK;
}

/* ---- stats --------------------------------------------------------------------- */

void rs_roam_get_stats(const rs_roam *L, rs_roam_stats *o)
{
    if (!o) return;
    memset(o, 0, sizeof *o);
    if (!L) return;
    o->width = L->w; o->height = L->hgt;
    o->patch_size = L->P; o->patches_x = L->npx; o->patches_y = L->npy;
    o->unit_size = L->usize; o->units = L->npx * L->npy * L->upp;
    o->base_nodes = L->base_count;
    o->pool_nodes = L->cap - L->base_count;
    o->pool_used = L->used - L->base_count - L->nfree;
    o->pool_exhausted = L->exhausted;
    o->triangles = L->tris;
    o->threshold = L->threshold;
    o->max_error_bound = rs__roam_leaves_max_bound(L);
    o->frame_passes = L->frame_passes;
    o->patches_culled = L->culled;
    o->update_ops = L->update_ops;
    o->update_done = L->update_done;
    o->bytes = L->bytes;
}

