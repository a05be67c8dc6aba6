/* The virtual texture (include/roadsplat.h, "Virtual texture"; docs/
 * embedding.md "Streaming"): a quadtree of tiles over the splat image, the
 * per-frame cut by projected texel size (seed 002's Cline formula), an LRU
 * resident set within a byte budget, and tiles made on the host's threads.
 *
 * Every tile is rendered from the road grid on its own (never from other
 * tiles): a level whose pixel is the splat at an integer texel count is
 * that splat's window; any other level is the splat at the next finer
 * integer texel count, area-averaged onto the level's pixels with exact
 * integer box weights. Lengths in the averaging are counted in units of
 * 1/(T t) DEM cells: a source pixel (t texels a cell) is T units, a level-k
 * pixel t 2^k units (T: the finest texels a cell). */
#include "splatter.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define VT_MAX_LEVELS 32
#define VT_BASE_TILES (1u << 22) /* height ranges kept per tile for at most this many tiles a level */
#define VT_BAND_UNITS 32         /* a resampled band covers about this many source rows */

typedef struct vt_level {
    uint32_t w, h;     /* level image, pixels */
    uint32_t tx, ty;   /* tiles per row and column */
    double pixel_m;    /* pixel size, metres */
    uint32_t src;      /* splatter index */
    uint64_t D;        /* pixel length in units (T t 2^k / T = t 2^k); == T: direct */
    float *zr;         /* tx*ty (lo, hi) height ranges, metres; NULL below the base level */
} vt_level;

/* A drop candidate: when it was last needed, its key, its record. */
typedef struct lru_item {
    uint64_t last, key;
    uint32_t index;
} lru_item;

typedef struct vt_res {
    uint64_t key;
    uint64_t last; /* frame last needed */
    uint32_t slot;
} vt_res;

struct rs_vt {
    const rs_splatter *sp[VT_MAX_LEVELS + 1];
    rs_splatter *own[VT_MAX_LEVELS + 1];
    uint32_t sp_tex[VT_MAX_LEVELS + 1];
    uint32_t nsp;
    uint32_t T, S, B, n, nlev, zbase;
    double cs, map_w, map_h, zlo, zhi; /* map extent metres; DEM height range metres */
    vt_level lv[VT_MAX_LEVELS];
    uint64_t budget;
    uint32_t slots;
    size_t tile_bytes, bytes;
    /* resident set: res[0..nres), hash (index + 1, 0 empty) rebuilt after changes */
    vt_res *res;
    uint32_t nres;
    uint32_t *ht, hmask;
    uint32_t *free_slots, nfree;
    /* the last update's lists and scratch */
    rs_vt_tile *need, *make, *drop;
    uint32_t nneed, nmake, ndrop;
    lru_item *lru;
    rs_vt_stats st;
};

struct rs_vt_workspace {
    const rs_vt *vt;
    rs_splat_workspace *sw[VT_MAX_LEVELS + 1];
    uint8_t *src;  /* a band of source pixels */
    double *hsum;  /* a band's rows, averaged across: n columns x 4 sums */
    size_t span;   /* source pixels one level pixel can overlap along an axis, at most */
    double *cw;    /* per level column: its source columns' overlaps (span each), then one row's */
    int64_t *cja;  /* per level column: its first source column */
    uint32_t *cnq; /* per level column: how many */
    size_t bytes;
};

static uint64_t tile_key(uint32_t k, uint32_t x, uint32_t y) { return (uint64_t)k << 58 | (uint64_t)x << 29 | y; }
static uint32_t key_level(uint64_t key) { return (uint32_t)(key >> 58); }
static uint32_t key_x(uint64_t key) { return (uint32_t)(key >> 29) & 0x1FFFFFFFu; }
static uint32_t key_y(uint64_t key) { return (uint32_t)key & 0x1FFFFFFFu; }

static int64_t floordiv(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

static void vt_free_parts(rs_ctx *ctx, rs_vt *vt)
{
    for (uint32_t i = 0; i < VT_MAX_LEVELS + 1; i++) rs_splatter_free(ctx, vt->own[i]);
    for (uint32_t k = 0; k < VT_MAX_LEVELS; k++) rs__free(ctx, vt->lv[k].zr);
    rs__free(ctx, vt->res);
    rs__free(ctx, vt->ht);
    rs__free(ctx, vt->free_slots);
    rs__free(ctx, vt->need);
    rs__free(ctx, vt->make);
    rs__free(ctx, vt->drop);
    rs__free(ctx, vt->lru);
}

void rs_vt_free(rs_ctx *ctx, rs_vt *vt)
{
    if (!ctx || !vt) return;
    vt_free_parts(ctx, vt);
    rs__free(ctx, vt);
}

/* The splatter rendering texel count t (made once per count): on s's grid,
 * or with styles or markings on a grid of its own from roads (NULL: an
 * error). */
static rs_result splatter_for(rs_ctx *ctx, rs_vt *vt, const rs_splatter *s, const rs_roads *roads, uint32_t t,
                              uint32_t *index)
{
    for (uint32_t i = 0; i < vt->nsp; i++)
        if (vt->sp_tex[i] == t) {
            *index = i;
            return RS_OK;
        }
    rs_splat_options o = s->o;
    o.texels = t;
    o.progress = NULL;
    o.progress_user = NULL;
    /* the grain and tiled textures are indexed by output pixel: scale the offset to t */
    o.surface.texel_offset_x = (int64_t)floor((double)s->o.surface.texel_offset_x * t / vt->T);
    o.surface.texel_offset_y = (int64_t)floor((double)s->o.surface.texel_offset_y * t / vt->T);
    /* line symbols, casings and markings are laid out in the grid's pixels */
    int own_grid = (s->grid->styling || s->grid->markings) && t != vt->T;
    if (own_grid && !roads)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "virtual texture: the splatter's grid has styles or markings, so its %u-texel level needs "
                        "a grid of its own: give rs_vt_options.roads",
                        t);
    if (!own_grid) { /* read only while the grid was built (the host may have freed them since) */
        o.style.styles = NULL;
        o.style.surface_images = NULL;
        o.style.surface_image_count = 0;
    }
    rs_result r = rs_splatter_create(ctx, s->dem, own_grid ? roads : NULL, own_grid ? NULL : s->grid, &o,
                                     &vt->own[vt->nsp]);
    if (r) return r;
    vt->sp[vt->nsp] = vt->own[vt->nsp];
    vt->sp_tex[vt->nsp] = t;
    *index = vt->nsp++;
    return RS_OK;
}

/* Height ranges: per tile of the base level (the finest with at most
 * VT_BASE_TILES tiles) the DEM samples under its core, then each coarser
 * level from its children. Finer levels use their base-level ancestor's. */
static rs_result height_ranges(rs_ctx *ctx, rs_vt *vt, const rs_splatter *s)
{
    const rs_dem *dem = s->dem;
    const double zs = dem->frame.z_scale;
    uint32_t b = 0;
    while (b + 1 < vt->nlev && (uint64_t)vt->lv[b].tx * vt->lv[b].ty > VT_BASE_TILES) b++;
    vt->zbase = b;
    vt->zlo = INFINITY;
    vt->zhi = -INFINITY;
    for (uint32_t k = b; k < vt->nlev; k++) {
        vt_level *L = &vt->lv[k];
        L->zr = rs__alloc_array(ctx, (size_t)L->tx * L->ty * 2, sizeof *L->zr);
        if (!L->zr) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the virtual texture's height ranges");
    }
    vt_level *L = &vt->lv[b];
    double tile_m = vt->S * L->pixel_m;
    for (uint32_t ty = 0; ty < L->ty; ty++) {
        uint32_t r0 = (uint32_t)floor(ty * tile_m / vt->cs), r1 = (uint32_t)ceil((ty + 1) * tile_m / vt->cs);
        if (r1 > dem->height - 1) r1 = dem->height - 1;
        if (r0 > r1) r0 = r1;
        for (uint32_t tx = 0; tx < L->tx; tx++) {
            uint32_t c0 = (uint32_t)floor(tx * tile_m / vt->cs), c1 = (uint32_t)ceil((tx + 1) * tile_m / vt->cs);
            if (c1 > dem->width - 1) c1 = dem->width - 1;
            if (c0 > c1) c0 = c1;
            float lo = INFINITY, hi = -INFINITY;
            for (uint32_t r = r0; r <= r1; r++) {
                const float *row = s->z + (size_t)r * dem->width;
                for (uint32_t c = c0; c <= c1; c++) {
                    if (row[c] < lo) lo = row[c];
                    if (row[c] > hi) hi = row[c];
                }
            }
            double a = lo * zs, bb = hi * zs;
            float *o = L->zr + 2 * ((size_t)ty * L->tx + tx);
            o[0] = (float)(a < bb ? a : bb);
            o[1] = (float)(a < bb ? bb : a);
            /* float rounding must not shrink the range */
            if (o[0] > (a < bb ? a : bb)) o[0] = nextafterf(o[0], -INFINITY);
            if (o[1] < (a < bb ? bb : a)) o[1] = nextafterf(o[1], INFINITY);
            if (o[0] < vt->zlo) vt->zlo = o[0];
            if (o[1] > vt->zhi) vt->zhi = o[1];
        }
    }
    for (uint32_t k = b + 1; k < vt->nlev; k++) {
        vt_level *P = &vt->lv[k], *C = &vt->lv[k - 1];
        for (uint32_t ty = 0; ty < P->ty; ty++)
            for (uint32_t tx = 0; tx < P->tx; tx++) {
                float lo = INFINITY, hi = -INFINITY;
                for (uint32_t q = 0; q < 4; q++) {
                    uint32_t cx = 2 * tx + (q & 1), cy = 2 * ty + (q >> 1);
                    if (cx >= C->tx || cy >= C->ty) continue;
                    const float *c = C->zr + 2 * ((size_t)cy * C->tx + cx);
                    if (c[0] < lo) lo = c[0];
                    if (c[1] > hi) hi = c[1];
                }
                P->zr[2 * ((size_t)ty * P->tx + tx)] = lo;
                P->zr[2 * ((size_t)ty * P->tx + tx) + 1] = hi;
            }
    }
    return RS_OK;
}

rs_result rs_vt_create(rs_ctx *ctx, const rs_splatter *s, const rs_vt_options *opts, rs_vt **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_vt_create: out is NULL");
    *out = NULL;
    if (!s) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_vt_create: NULL splatter");
    rs_vt_options o;
    rs_result rc = RS__OPTS_IN(ctx, opts, &o, rs_vt_options);
    if (rc) return rc;
    uint32_t S = o.tile_size ? o.tile_size : 256;
    if (S < 8 || S > 8192) return rs__fail(ctx, RS_ERR_INVALID_ARG, "virtual texture: tile_size %u must be 8..8192", S);
    if (o.border < -1 || o.border > (int32_t)(S / 2))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "virtual texture: border %d must be -1, 0 or 1..%u", (int)o.border, S / 2);
    uint32_t B = o.border == 0 ? 4 : o.border < 0 ? 0 : (uint32_t)o.border;
    if (B > S / 2) B = S / 2;
    if (s->o.coverage.edges != RS_EDGES_ANALYTIC)
        return rs__fail(ctx, RS_ERR_UNSUPPORTED,
                        "virtual texture: needs analytic edges (its coarser levels re-render the road grid)");
    rs_vt *vt = rs__calloc(ctx, 1, sizeof *vt);
    if (!vt) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the virtual texture");
    vt->T = s->o.texels;
    vt->S = S;
    vt->B = B;
    vt->n = S + 2 * B;
    vt->cs = s->dem->frame.cell_size;
    vt->map_w = (double)(s->dem->width - 1) * vt->cs;
    vt->map_h = (double)(s->dem->height - 1) * vt->cs;
    vt->tile_bytes = (size_t)vt->n * vt->n * 4;
    vt->budget = o.budget_bytes ? o.budget_bytes : (uint64_t)256 << 20;
    uint64_t slots = vt->budget / vt->tile_bytes;
    if (slots > (1u << 24)) slots = 1u << 24;
    vt->slots = (uint32_t)slots;
    /* levels: until the coarsest fits one tile */
    uint32_t full = 1;
    while (full < VT_MAX_LEVELS && (((uint64_t)s->out_w + ((uint64_t)1 << (full - 1)) - 1) >> (full - 1) > S ||
                                    ((uint64_t)s->out_h + ((uint64_t)1 << (full - 1)) - 1) >> (full - 1) > S))
        full++;
    rs_result r = RS_OK;
    if (o.levels > full) r = rs__fail(ctx, RS_ERR_INVALID_ARG, "virtual texture: levels %u must be 1..%u", o.levels, full);
    vt->nlev = o.levels ? o.levels : full;
    vt->sp[0] = s;
    vt->sp_tex[0] = vt->T;
    vt->nsp = 1;
    /* progress (the context's callback): the grid builds and splatters of
     * the levels report as parts of this call (a road per unit in each of
     * a build's five stages), a unit per level, polls between levels */
    rs__progress pg;
    size_t nroads = o.roads ? rs_roads_count(o.roads) : 0;
    rs__progress_begin(ctx, &pg, NULL, NULL, (uint64_t)vt->nlev * (5 * (uint64_t)nroads + 3) + 1, 64);
    for (uint32_t k = 0; !r && k < vt->nlev; k++) {
        vt_level *L = &vt->lv[k];
        uint64_t m = (uint64_t)1 << k;
        L->w = (uint32_t)((s->out_w + m - 1) >> k);
        L->h = (uint32_t)((s->out_h + m - 1) >> k);
        L->tx = (L->w + S - 1) / S;
        L->ty = (L->h + S - 1) / S;
        L->pixel_m = vt->cs * (double)m / vt->T;
        uint32_t t = vt->T % m == 0 ? (uint32_t)(vt->T / m) : (uint32_t)((vt->T + m - 1) / m);
        if (t < 1) t = 1;
        L->D = (uint64_t)t * m;
        r = splatter_for(ctx, vt, s, o.roads, t, &L->src);
        if (!r && rs__report(ctx, 1)) r = RS_ERR_CANCELLED;
    }
    const vt_level *top = &vt->lv[vt->nlev - 1];
    if (!r && (uint64_t)top->tx * top->ty > vt->slots)
        r = rs__fail(ctx, RS_ERR_INVALID_ARG,
                     "virtual texture: a budget of %llu bytes holds %u tiles of %zu bytes, fewer than the %u tiles of the "
                     "coarsest level",
                     (unsigned long long)vt->budget, vt->slots, vt->tile_bytes, top->tx * top->ty);
    if (!r) r = height_ranges(ctx, vt, s);
    if (!r && rs__report(ctx, 1)) r = RS_ERR_CANCELLED;
    if (!r) {
        uint32_t hcap = 1;
        while (hcap < 2 * vt->slots) hcap <<= 1;
        vt->hmask = hcap - 1;
        vt->res = rs__alloc_array(ctx, vt->slots, sizeof *vt->res);
        vt->ht = rs__calloc(ctx, hcap, sizeof *vt->ht);
        vt->free_slots = rs__alloc_array(ctx, vt->slots, sizeof *vt->free_slots);
        vt->need = rs__alloc_array(ctx, vt->slots, sizeof *vt->need);
        vt->make = rs__alloc_array(ctx, vt->slots, sizeof *vt->make);
        vt->drop = rs__alloc_array(ctx, vt->slots, sizeof *vt->drop);
        vt->lru = rs__alloc_array(ctx, vt->slots, sizeof *vt->lru);
        if (!vt->res || !vt->ht || !vt->free_slots || !vt->need || !vt->make || !vt->drop || !vt->lru)
            r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the virtual texture's tables (%u slots)", vt->slots);
        else {
            /* popped from the end: slot 0 first */
            for (uint32_t i = 0; i < vt->slots; i++) vt->free_slots[i] = vt->slots - 1 - i;
            vt->nfree = vt->slots;
            vt->bytes = sizeof *vt + (size_t)hcap * sizeof *vt->ht +
                        (size_t)vt->slots * (sizeof *vt->res + sizeof *vt->free_slots + 3 * sizeof *vt->need +
                                             sizeof *vt->lru);
            for (uint32_t k = vt->zbase; k < vt->nlev; k++)
                vt->bytes += (size_t)vt->lv[k].tx * vt->lv[k].ty * 2 * sizeof(float);
        }
    }
    r = rs__progress_end(ctx, &pg, r);
    if (r) {
        rs_vt_free(ctx, vt);
        return r;
    }
    *out = vt;
    rs__ok(ctx);
    return RS_OK;
}

void rs_vt_get_info(const rs_vt *vt, rs_vt_info *out)
{
    if (!out) return;
    memset(out, 0, sizeof *out);
    if (!vt) return;
    out->levels = vt->nlev;
    out->tile_size = vt->S;
    out->border = vt->B;
    out->tile_side = vt->n;
    out->tile_bytes = vt->tile_bytes;
    out->slots = vt->slots;
    out->budget_bytes = vt->budget;
    out->bytes = vt->bytes;
}

rs_result rs_vt_level_size(const rs_vt *vt, uint32_t level, uint32_t *width, uint32_t *height, double *pixel_m)
{
    if (!vt || level >= vt->nlev) return RS_ERR_INVALID_ARG;
    if (width) *width = vt->lv[level].w;
    if (height) *height = vt->lv[level].h;
    if (pixel_m) *pixel_m = vt->lv[level].pixel_m;
    return RS_OK;
}

void rs_vt_get_stats(const rs_vt *vt, rs_vt_stats *out)
{
    if (!out) return;
    if (vt) *out = vt->st;
    else memset(out, 0, sizeof *out);
}

/* ---- the cut ------------------------------------------------------------------- */

typedef struct vt_cam {
    double eye[3], f[3], rt[3], up[3];
    double tx, ty;    /* tan of the half angles */
    double k;         /* screen pixels per radian near the axis: height / (2 tan(fov/2)) */
    double far_dist, tp, aniso;
    uint32_t bias;
} vt_cam;

static rs_result make_cam(rs_ctx *ctx, const rs_vt_view *v_in, vt_cam *c)
{
    memset(c, 0, sizeof *c);
    rs_vt_view vv;
    rs_result rc = RS__OPTS_IN(ctx, v_in, &vv, rs_vt_view);
    if (rc) return rc;
    const rs_vt_view *v = &vv;
    double fov = v->fov_y == 0.0 ? 60.0 : v->fov_y;
    double wpx = v->width ? v->width : 1280, hpx = v->height ? v->height : 720;
    for (int i = 0; i < 3; i++)
        if (!isfinite(v->eye[i]) || !isfinite(v->dir[i]))
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "virtual texture view: eye and dir must be finite");
    if (!(fov > 0.0 && fov < 179.0))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "virtual texture view: fov_y %g must be in (0, 179) degrees", fov);
    if (!(v->far_dist >= 0.0) || !(v->texel_pixels >= 0.0) || !isfinite(v->texel_pixels))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "virtual texture view: far_dist and texel_pixels must be >= 0");
    if (!(v->anisotropy == 0.0 || (v->anisotropy >= 1.0 && v->anisotropy <= 64.0)))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "virtual texture view: anisotropy %g must be 0 or 1..64", v->anisotropy);
    double len = sqrt(v->dir[0] * v->dir[0] + v->dir[1] * v->dir[1] + v->dir[2] * v->dir[2]);
    if (!(len > 0.0) || !isfinite(len)) return rs__fail(ctx, RS_ERR_INVALID_ARG, "virtual texture view: dir must not be 0");
    for (int i = 0; i < 3; i++) {
        c->eye[i] = v->eye[i];
        c->f[i] = v->dir[i] / len;
    }
    /* right-handed camera with z up; looking straight down, x is right */
    double h = sqrt(c->f[0] * c->f[0] + c->f[1] * c->f[1]);
    if (h < 1e-9) {
        c->rt[0] = 1;
    } else {
        c->rt[0] = c->f[1] / h;
        c->rt[1] = -c->f[0] / h;
    }
    c->up[0] = c->rt[1] * c->f[2] - c->rt[2] * c->f[1];
    c->up[1] = c->rt[2] * c->f[0] - c->rt[0] * c->f[2];
    c->up[2] = c->rt[0] * c->f[1] - c->rt[1] * c->f[0];
    c->ty = tan(fov * RS__PI / 360.0);
    if (!(c->ty >= 1e-9)) return rs__fail(ctx, RS_ERR_INVALID_ARG, "virtual texture view: fov_y %g is too small", fov);
    c->tx = c->ty * wpx / hpx;
    c->k = hpx / (2.0 * c->ty);
    c->far_dist = v->far_dist;
    c->tp = v->texel_pixels > 0 ? v->texel_pixels : 1.0;
    c->aniso = v->anisotropy; /* 0: no limit */
    return RS_OK;
}

/* 1 when the box [lo, hi] lies wholly outside one side of the frustum
 * (its 8 corners in camera coordinates: right r, up u, forward d). */
static int box_culled(const vt_cam *c, const double lo[3], const double hi[3])
{
    int out_l = 1, out_r = 1, out_b = 1, out_t = 1, out_n = 1;
    for (int q = 0; q < 8; q++) {
        double p[3] = { (q & 1 ? hi : lo)[0] - c->eye[0], (q & 2 ? hi : lo)[1] - c->eye[1],
                        (q & 4 ? hi : lo)[2] - c->eye[2] };
        double r = p[0] * c->rt[0] + p[1] * c->rt[1] + p[2] * c->rt[2];
        double u = p[0] * c->up[0] + p[1] * c->up[1] + p[2] * c->up[2];
        double d = p[0] * c->f[0] + p[1] * c->f[1] + p[2] * c->f[2];
        out_l &= r < -c->tx * d;
        out_r &= r > c->tx * d;
        out_b &= u < -c->ty * d;
        out_t &= u > c->ty * d;
        out_n &= d < 0;
    }
    return out_l | out_r | out_b | out_t | out_n;
}

typedef struct vt_walk {
    rs_vt *vt;
    const vt_cam *c;
    uint32_t count, visited;
    int overflow;
} vt_walk;

/* The level asked for by a box at nearest distance d with largest height
 * difference dz (rs_vt_update's formula). */
static uint32_t wanted_level(const rs_vt *vt, const vt_cam *c, double d, double dz)
{
    if (!(d > 1e-9)) return 0;
    double P = vt->lv[0].pixel_m * c->k / d;
    double cosb = dz / d < 1 ? dz / d : 1;
    /* the GPU's footprint: P across the view, P cosb along it, N = min(1/cosb, A) taps */
    double rho = c->aniso > 0 && cosb * c->aniso < 1 ? P * cosb * c->aniso : P;
    double L = floor(log2(c->tp / rho)) + c->bias;
    if (!(L > 0)) return 0;
    return L >= vt->nlev - 1 ? vt->nlev - 1 : (uint32_t)L;
}

static void tile_box(const rs_vt *vt, uint32_t k, uint32_t x, uint32_t y, double lo[3], double hi[3])
{
    const vt_level *L = &vt->lv[k];
    double tm = vt->S * L->pixel_m;
    lo[0] = x * tm;
    lo[1] = y * tm;
    hi[0] = (x + 1) * tm < vt->map_w ? (x + 1) * tm : vt->map_w;
    hi[1] = (y + 1) * tm < vt->map_h ? (y + 1) * tm : vt->map_h;
    uint32_t b = vt->zbase;
    const vt_level *Z = &vt->lv[k > b ? k : b];
    uint32_t sh = k < b ? b - k : 0;
    const float *z = Z->zr + 2 * ((size_t)(y >> sh) * Z->tx + (x >> sh));
    lo[2] = z[0];
    hi[2] = z[1];
}

static void walk(vt_walk *w, uint32_t k, uint32_t x, uint32_t y)
{
    rs_vt *vt = w->vt;
    const vt_cam *c = w->c;
    if (w->overflow) return;
    w->visited++;
    double lo[3], hi[3];
    tile_box(vt, k, x, y, lo, hi);
    if (box_culled(c, lo, hi)) return;
    double d2 = 0, dz = 0;
    for (int i = 0; i < 3; i++) {
        double e = c->eye[i], g = e < lo[i] ? lo[i] - e : e > hi[i] ? e - hi[i] : 0;
        d2 += g * g;
    }
    double d = sqrt(d2);
    if (c->far_dist > 0 && d > c->far_dist) return;
    dz = fabs(c->eye[2] - lo[2]) > fabs(c->eye[2] - hi[2]) ? fabs(c->eye[2] - lo[2]) : fabs(c->eye[2] - hi[2]);
    if (k == 0 || wanted_level(vt, c, d, dz) >= k) {
        if (w->count >= vt->slots) {
            w->overflow = 1;
            return;
        }
        rs_vt_tile *t = &vt->need[w->count++];
        t->level = k;
        t->x = x;
        t->y = y;
        t->slot = UINT32_MAX;
        t->x0 = lo[0];
        t->y0 = lo[1];
        t->x1 = hi[0];
        t->y1 = hi[1];
        t->dist = d;
        return;
    }
    const vt_level *C = &vt->lv[k - 1];
    for (uint32_t q = 0; q < 4; q++) {
        uint32_t cx = 2 * x + (q & 1), cy = 2 * y + (q >> 1);
        if (cx < C->tx && cy < C->ty) walk(w, k - 1, cx, cy);
    }
}

/* ---- the resident set ---------------------------------------------------------- */

static uint32_t hash_slot(const rs_vt *vt, uint64_t key)
{
    uint64_t h = key * 0x9E3779B97F4A7C15ull;
    return (uint32_t)(h >> 32) & vt->hmask;
}

static void rehash(rs_vt *vt)
{
    memset(vt->ht, 0, ((size_t)vt->hmask + 1) * sizeof *vt->ht);
    for (uint32_t i = 0; i < vt->nres; i++) {
        uint32_t h = hash_slot(vt, vt->res[i].key);
        while (vt->ht[h]) h = (h + 1) & vt->hmask;
        vt->ht[h] = i + 1;
    }
}

static vt_res *find_res(const rs_vt *vt, uint64_t key)
{
    uint32_t h = hash_slot(vt, key);
    while (vt->ht[h]) {
        vt_res *r = &vt->res[vt->ht[h] - 1];
        if (r->key == key) return r;
        h = (h + 1) & vt->hmask;
    }
    return NULL;
}

static uint64_t tkey(const rs_vt_tile *t) { return tile_key(t->level, t->x, t->y); }

/* Make order: nearest first, then coarser, then by key (a total order). */
static int cmp_make(const void *a, const void *b)
{
    const rs_vt_tile *p = a, *q = b;
    if (p->dist != q->dist) return p->dist < q->dist ? -1 : 1;
    if (p->level != q->level) return p->level > q->level ? -1 : 1;
    uint64_t kp = tkey(p), kq = tkey(q);
    return kp < kq ? -1 : kp > kq;
}


static int cmp_lru(const void *a, const void *b)
{
    const lru_item *p = a, *q = b;
    if (p->last != q->last) return p->last < q->last ? -1 : 1;
    return p->key < q->key ? -1 : p->key > q->key;
}

static void fill_tile(const rs_vt *vt, uint64_t key, uint32_t slot, rs_vt_tile *t)
{
    double lo[3], hi[3];
    t->level = key_level(key);
    t->x = key_x(key);
    t->y = key_y(key);
    tile_box(vt, t->level, t->x, t->y, lo, hi);
    t->x0 = lo[0];
    t->y0 = lo[1];
    t->x1 = hi[0];
    t->y1 = hi[1];
    t->dist = 0;
    t->slot = slot;
}

rs_result rs_vt_update(rs_ctx *ctx, rs_vt *vt, const rs_vt_view *view)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!vt || !view) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_vt_update");
    vt_cam c;
    rs_result r = make_cam(ctx, view, &c);
    if (r) return r;
    vt->st.frame++;
    const uint64_t frame = vt->st.frame;
    const vt_level *top = &vt->lv[vt->nlev - 1];
    vt_walk w;
    uint32_t visited = 0;
    for (c.bias = 0;; c.bias++) {
        memset(&w, 0, sizeof w);
        w.vt = vt;
        w.c = &c;
        for (uint32_t y = 0; y < top->ty; y++)
            for (uint32_t x = 0; x < top->tx; x++) walk(&w, vt->nlev - 1, x, y);
        visited += w.visited;
        /* at bias >= levels every box asks for the top level, whose tiles fit */
        if (!w.overflow) break;
    }
    vt->nneed = w.count;
    vt->st.bias = c.bias;
    vt->st.visited = visited;
    /* needed and resident: touch; needed and not: to make */
    vt->nmake = 0;
    for (uint32_t i = 0; i < vt->nneed; i++) {
        vt_res *e = find_res(vt, tkey(&vt->need[i]));
        if (e) {
            e->last = frame;
            vt->need[i].slot = e->slot;
        } else vt->make[vt->nmake++] = vt->need[i];
    }
    if (vt->nmake > 1) qsort(vt->make, vt->nmake, sizeof *vt->make, cmp_make);
    if (view->max_make && vt->nmake > view->max_make) vt->nmake = view->max_make;
    /* room: drop the least recently needed tiles not needed now */
    vt->ndrop = 0;
    if (vt->nmake > vt->nfree) {
        uint32_t want = vt->nmake - vt->nfree, nc = 0;
        lru_item *items = vt->lru;
        for (uint32_t i = 0; i < vt->nres; i++)
            if (vt->res[i].last != frame) {
                items[nc].last = vt->res[i].last;
                items[nc].key = vt->res[i].key;
                items[nc].index = i;
                nc++;
            }
        if (nc > 1) qsort(items, nc, sizeof *items, cmp_lru);
        /* nc >= want: the needed tiles fit the slots */
        uint32_t nd = want < nc ? want : nc;
        for (uint32_t i = 0; i < nd; i++) {
            vt_res *e = &vt->res[items[i].index];
            fill_tile(vt, e->key, e->slot, &vt->drop[vt->ndrop++]);
            vt->free_slots[vt->nfree++] = e->slot;
            e->last = UINT64_MAX; /* marked: removed below */
        }
        uint32_t j = 0;
        for (uint32_t i = 0; i < vt->nres; i++)
            if (vt->res[i].last != UINT64_MAX) vt->res[j++] = vt->res[i];
        vt->nres = j;
    }
    for (uint32_t i = 0; i < vt->nmake; i++) {
        uint32_t slot = vt->free_slots[--vt->nfree];
        vt->make[i].slot = slot;
        vt->res[vt->nres].key = tkey(&vt->make[i]);
        vt->res[vt->nres].last = frame;
        vt->res[vt->nres].slot = slot;
        vt->nres++;
    }
    rehash(vt);
    for (uint32_t i = 0; i < vt->nneed; i++)
        if (vt->need[i].slot == UINT32_MAX) {
            const vt_res *e = find_res(vt, tkey(&vt->need[i]));
            if (e) vt->need[i].slot = e->slot;
        }
    vt->st.needed = vt->nneed;
    vt->st.made = vt->nmake;
    vt->st.dropped = vt->ndrop;
    vt->st.resident = vt->nres;
    vt->st.resident_bytes = (uint64_t)vt->nres * vt->tile_bytes;
    rs__ok(ctx);
    return RS_OK;
}

const rs_vt_tile *rs_vt_needed(const rs_vt *vt, size_t *count)
{
    if (count) *count = vt ? vt->nneed : 0;
    return vt ? vt->need : NULL;
}

const rs_vt_tile *rs_vt_to_make(const rs_vt *vt, size_t *count)
{
    if (count) *count = vt ? vt->nmake : 0;
    return vt ? vt->make : NULL;
}

const rs_vt_tile *rs_vt_to_drop(const rs_vt *vt, size_t *count)
{
    if (count) *count = vt ? vt->ndrop : 0;
    return vt ? vt->drop : NULL;
}

int rs_vt_lookup(const rs_vt *vt, uint32_t level, uint32_t x, uint32_t y, rs_vt_tile *out)
{
    if (!vt || level >= vt->nlev || x >= vt->lv[level].tx || y >= vt->lv[level].ty) return 0;
    for (uint32_t k = level; k < vt->nlev; k++, x >>= 1, y >>= 1) {
        const vt_res *e = find_res(vt, tile_key(k, x, y));
        if (e) {
            if (out) fill_tile(vt, e->key, e->slot, out);
            return 1;
        }
    }
    return 0;
}

rs_result rs_vt_discard(rs_ctx *ctx, rs_vt *vt, uint32_t level, uint32_t x, uint32_t y)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!vt) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_vt_discard");
    vt_res *e = level < vt->nlev ? find_res(vt, tile_key(level, x, y)) : NULL;
    if (!e) return rs__fail(ctx, RS_ERR_INVALID_ARG, "tile %u/%u/%u is not resident", level, x, y);
    vt->free_slots[vt->nfree++] = e->slot;
    *e = vt->res[--vt->nres];
    rehash(vt);
    vt->st.resident = vt->nres;
    vt->st.resident_bytes = (uint64_t)vt->nres * vt->tile_bytes;
    rs__ok(ctx);
    return RS_OK;
}

/* ---- making tiles ---------------------------------------------------------------- */

/* Source pixels a resampled band of level L may need: columns and rows. */
static void band_extent(const rs_vt *vt, const vt_level *L, uint32_t *cols, uint32_t *rows, uint32_t *band)
{
    uint64_t T = vt->T;
    uint32_t b = (uint32_t)(VT_BAND_UNITS * T / L->D);
    if (b < 1) b = 1;
    if (b > vt->n) b = vt->n;
    *band = b;
    *cols = (uint32_t)(((uint64_t)vt->n * L->D + T - 1) / T + 2);
    *rows = (uint32_t)(((uint64_t)b * L->D + T - 1) / T + 2);
}

void rs_vt_workspace_free(rs_ctx *ctx, rs_vt_workspace *ws)
{
    if (!ctx || !ws) return;
    for (uint32_t i = 0; i < VT_MAX_LEVELS + 1; i++) rs_splat_workspace_free(ctx, ws->sw[i]);
    rs__free(ctx, ws->src);
    rs__free(ctx, ws->cw);
    rs__free(ctx, ws->cja);
    rs__free(ctx, ws->cnq);
    rs__free(ctx, ws->hsum);
    rs__free(ctx, ws);
}

size_t rs_vt_workspace_bytes(const rs_vt_workspace *ws) { return ws ? ws->bytes : 0; }

rs_result rs_vt_workspace_create(rs_ctx *ctx, const rs_vt *vt, rs_vt_workspace **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_vt_workspace_create: out is NULL");
    *out = NULL;
    if (!vt) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_vt_workspace_create: NULL virtual texture");
    rs_vt_workspace *ws = rs__calloc(ctx, 1, sizeof *ws);
    if (!ws) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for a virtual texture workspace");
    ws->vt = vt;
    uint32_t width[VT_MAX_LEVELS + 1] = { 0 };
    size_t src_px = 0, hrows = 0, span = 0;
    for (uint32_t k = 0; k < vt->nlev; k++) {
        const vt_level *L = &vt->lv[k];
        uint32_t wk = vt->n;
        if (L->D != vt->T) {
            uint32_t cols, rows, band;
            band_extent(vt, L, &cols, &rows, &band);
            wk = cols;
            if ((size_t)cols * rows > src_px) src_px = (size_t)cols * rows;
            if (rows > hrows) hrows = rows;
            size_t sk = (size_t)((L->D + vt->T - 1) / vt->T) + 1;
            if (sk > span) span = sk;
        }
        if (wk > width[L->src]) width[L->src] = wk;
    }
    rs_result r = RS_OK;
    ws->bytes = sizeof *ws;
    for (uint32_t i = 0; !r && i < vt->nsp; i++) {
        if (!width[i]) continue;
        uint32_t iw;
        rs_splatter_size(vt->sp[i], &iw, NULL);
        r = rs_splat_workspace_create(ctx, vt->sp[i], width[i] < iw ? width[i] : iw, &ws->sw[i]);
        if (!r) ws->bytes += rs_splat_workspace_bytes(ws->sw[i]);
    }
    if (!r && src_px) {
        ws->src = rs__alloc_array(ctx, src_px, 4);
        ws->hsum = rs__alloc_array(ctx, hrows * vt->n * 4, sizeof *ws->hsum);
        ws->span = span;
        ws->cw = rs__alloc_array(ctx, (vt->n + 1) * span, sizeof *ws->cw);
        ws->cja = rs__alloc_array(ctx, vt->n, sizeof *ws->cja);
        ws->cnq = rs__alloc_array(ctx, vt->n, sizeof *ws->cnq);
        if (!ws->src || !ws->hsum || !ws->cw || !ws->cja || !ws->cnq)
            r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for a virtual texture workspace");
        ws->bytes += src_px * 4 + hrows * vt->n * 4 * sizeof *ws->hsum +
                     vt->n * (span * sizeof *ws->cw + sizeof *ws->cja + sizeof *ws->cnq) + span * sizeof *ws->cw;
    }
    if (r) {
        rs_vt_workspace_free(ctx, ws);
        return r;
    }
    *out = ws;
    rs__ok(ctx);
    return RS_OK;
}

/* Level k's pixels [X0, X0+n) x [Y0, Y0+n) averaged from its source
 * splatter's image, band by band of rows: each source row summed across
 * into the level's columns (hsum), then the band's source rows summed
 * down. Weights are the exact overlaps in units; colour is alpha-weighted;
 * beyond the source image is transparent. */
/* The source pixels [first, first + count) that level pixel [u0, u0 + D)
 * (in units; a source pixel is T units) overlaps within [lo, hi], and
 * each one's overlap in units into w. */
static uint32_t box_weights(int64_t u0, int64_t D, int64_t T, int64_t lo, int64_t hi, int64_t *first, double *w)
{
    int64_t u1 = u0 + D, ja = floordiv(u0, T), jb = floordiv(u1 - 1, T);
    if (ja < lo) ja = lo;
    if (jb > hi) jb = hi;
    for (int64_t q = ja; q <= jb; q++) {
        int64_t a = q * T > u0 ? q * T : u0, b = (q + 1) * T < u1 ? (q + 1) * T : u1;
        w[q - ja] = (double)(b - a);
    }
    *first = ja;
    return jb >= ja ? (uint32_t)(jb - ja + 1) : 0;
}

static rs_result resample(rs_ctx *ctx, const rs_vt *vt, rs_vt_workspace *ws, const vt_level *L, int64_t X0, int64_t Y0,
                          uint8_t *rgba, size_t stride)
{
    const int64_t T = vt->T, D = (int64_t)L->D, n = vt->n;
    const rs_splatter *sp = vt->sp[L->src];
    uint32_t Ws, Hs, cols, rows, band;
    rs_splatter_size(sp, &Ws, &Hs);
    band_extent(vt, L, &cols, &rows, &band);
    int64_t sa = floordiv(X0 * D, T), sb = floordiv((X0 + n) * D - 1, T);
    if (sa < 0) sa = 0;
    if (sb > (int64_t)Ws - 1) sb = (int64_t)Ws - 1;
    const double area = (double)D * (double)D;
    /* each level column's source columns and overlaps, the same for every
     * source row (the weights as the sums below take them) */
    const size_t span = ws->span;
    double *cw = ws->cw, *rw = ws->cw + (size_t)n * span;
    for (int64_t i = 0; i < n; i++) ws->cnq[i] = box_weights((X0 + i) * D, D, T, sa, sb, &ws->cja[i], cw + (size_t)i * span);
    for (int64_t r0 = 0; r0 < n; r0 += band) {
        int64_t r1 = r0 + band < n ? r0 + band : n;
        int64_t ya = floordiv((Y0 + r0) * D, T), yb = floordiv((Y0 + r1) * D - 1, T);
        if (ya < 0) ya = 0;
        if (yb > (int64_t)Hs - 1) yb = (int64_t)Hs - 1;
        if (sa > sb || ya > yb) {
            for (int64_t i = r0; i < r1; i++) memset(rgba + (size_t)i * stride, 0, (size_t)n * 4);
            continue;
        }
        uint32_t sw = (uint32_t)(sb - sa + 1), sh = (uint32_t)(yb - ya + 1);
        rs_result r = rs_splat_window_ws(ctx, sp, ws->sw[L->src], (uint32_t)sa, (uint32_t)ya, sw, sh, ws->src,
                                         (size_t)sw * 4, NULL, 0, NULL);
        if (!r && rs__poll(ctx)) r = RS_ERR_CANCELLED; /* (the sums below: a few ms at most) */
        if (r) return r;
        for (uint32_t j = 0; j < sh; j++) {
            const uint8_t *row = ws->src + (size_t)j * sw * 4;
            double *hs = ws->hsum + (size_t)j * n * 4;
            for (int64_t i = 0; i < n; i++) {
                const uint8_t *p = row + (size_t)(ws->cja[i] - sa) * 4;
                const double *w = cw + (size_t)i * span;
                double acc[4] = { 0, 0, 0, 0 };
                for (uint32_t m = 0; m < ws->cnq[i]; m++, p += 4) {
                    double wa = w[m] * p[3];
                    acc[0] += wa * p[0];
                    acc[1] += wa * p[1];
                    acc[2] += wa * p[2];
                    acc[3] += wa;
                }
                memcpy(hs + i * 4, acc, sizeof acc);
            }
        }
        for (int64_t i = r0; i < r1; i++) {
            int64_t ja;
            uint32_t nq = box_weights((Y0 + i) * D, D, T, ya, yb, &ja, rw);
            uint8_t *o = rgba + (size_t)i * stride;
            for (int64_t x = 0; x < n; x++) {
                double acc[4] = { 0, 0, 0, 0 };
                for (uint32_t m = 0; m < nq; m++) {
                    const double *h = ws->hsum + ((size_t)(ja + m - ya) * n + x) * 4;
                    double wv = rw[m];
                    acc[0] += wv * h[0];
                    acc[1] += wv * h[1];
                    acc[2] += wv * h[2];
                    acc[3] += wv * h[3];
                }
                uint8_t *p = o + x * 4;
                if (!(acc[3] > 0)) {
                    memset(p, 0, 4);
                    continue;
                }
                for (int k = 0; k < 3; k++) {
                    double v = floor(acc[k] / acc[3] + 0.5);
                    p[k] = (uint8_t)(v > 255 ? 255 : v);
                }
                double a = floor(acc[3] / area + 0.5);
                if (a < 1) { /* rounds to transparent */
                    memset(p, 0, 4);
                    continue;
                }
                p[3] = (uint8_t)(a > 255 ? 255 : a);
            }
        }
    }
    return RS_OK;
}

static rs_result make_tile(rs_ctx *ctx, const rs_vt *vt, rs_vt_workspace *ws, uint32_t level, uint32_t x, uint32_t y,
                           uint8_t *rgba, size_t stride);

/* Progress: the level-0 splatter's callback, else the context's; the
 * source rows its windows render (about tile_side * 2^k / T of them at
 * level k), polls between a resampled tile's bands. */
rs_result rs_vt_make_tile(rs_ctx *ctx, const rs_vt *vt, rs_vt_workspace *ws, uint32_t level, uint32_t x, uint32_t y,
                          uint8_t *rgba, size_t stride)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!vt || level >= vt->nlev) return make_tile(ctx, vt, ws, level, x, y, rgba, stride);
    const rs_splatter *s = vt->sp[0];
    uint64_t rows = ((uint64_t)vt->n * vt->lv[level].D + vt->T - 1) / vt->T + 1;
    rs__progress pg;
    rs__progress_begin(ctx, &pg, s->o.progress, s->o.progress_user, rows, 1);
    return rs__progress_end(ctx, &pg, make_tile(ctx, vt, ws, level, x, y, rgba, stride));
}

static rs_result make_tile(rs_ctx *ctx, const rs_vt *vt, rs_vt_workspace *ws, uint32_t level, uint32_t x, uint32_t y,
                           uint8_t *rgba, size_t stride)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!vt || !ws || !rgba) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_vt_make_tile");
    if (ws->vt != vt) return rs__fail(ctx, RS_ERR_INVALID_ARG, "the workspace was made for another virtual texture");
    if (level >= vt->nlev || x >= vt->lv[level].tx || y >= vt->lv[level].ty)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "tile %u/%u/%u is outside the quadtree", level, x, y);
    const size_t n = vt->n;
    if (stride / 4 < n) return rs__fail(ctx, RS_ERR_INVALID_ARG, "tile row stride %zu bytes, need %zu", stride, n * 4);
    const vt_level *L = &vt->lv[level];
    int64_t X0 = (int64_t)x * vt->S - vt->B, Y0 = (int64_t)y * vt->S - vt->B;
    if (L->D != vt->T) return resample(ctx, vt, ws, L, X0, Y0, rgba, stride);
    for (size_t j = 0; j < n; j++) memset(rgba + j * stride, 0, n * 4);
    int64_t x0 = X0 < 0 ? 0 : X0, y0 = Y0 < 0 ? 0 : Y0;
    int64_t x1 = X0 + (int64_t)n < (int64_t)L->w ? X0 + (int64_t)n : L->w;
    int64_t y1 = Y0 + (int64_t)n < (int64_t)L->h ? Y0 + (int64_t)n : L->h;
    if (x0 >= x1 || y0 >= y1) return RS_OK;
    return rs_splat_window_ws(ctx, vt->sp[L->src], ws->sw[L->src], (uint32_t)x0, (uint32_t)y0, (uint32_t)(x1 - x0),
                              (uint32_t)(y1 - y0), rgba + (size_t)(y0 - Y0) * stride + (size_t)(x0 - X0) * 4, stride,
                              NULL, 0, NULL);
}
