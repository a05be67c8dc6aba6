/* ROAM mesh extraction: mesh bound, leaves to sample keys, the vertex set
 * numbered in row-major order, normals and skirts (docs/roam.md, "Output"). */
#include "roam.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* Bits set in v. Bit arithmetic, not __builtin_popcountll: without a
 * popcnt target flag that builtin is a table-driven library call. */
static unsigned popcount64(uint64_t v)
{
    v = v - ((v >> 1) & 0x5555555555555555ull);
    v = (v & 0x3333333333333333ull) + ((v >> 2) & 0x3333333333333333ull);
    v = (v + (v >> 4)) & 0x0F0F0F0F0F0F0F0Full;
    return (unsigned)((v * 0x0101010101010101ull) >> 56);
}

static unsigned lowest_bit(uint64_t v) /* v != 0 */
{
#if defined(__GNUC__)
    return (unsigned)__builtin_ctzll(v);
#else
    unsigned n = 0;
    while (!(v & 1u)) { v >>= 1; n++; }
    return n;
#endif
}

void rs_roam_mesh_bound(const rs_roam *L, const rs_roam_mesh_options *opts, size_t *max_vertices,
                        size_t *max_indices)
{
    size_t v = 0, i = 0;
    if (L) {
        size_t t = L->tris;
        v = t + 2;
        if (v > (size_t)L->w * L->hgt) v = (size_t)L->w * L->hgt;
        i = 3 * t;
        /* a struct the ABI rule refuses is bounded as with a skirt (the
         * extraction then refuses it) */
        rs_roam_mesh_options o;
        if (RS__OPTS_IN(NULL, opts, &o, rs_roam_mesh_options) || o.skirt_depth > 0.0) {
            size_t border = 2 * ((size_t)L->cw + L->ch);
            v += border;
            i += 6 * border;
        }
    }
    if (max_vertices) *max_vertices = v;
    if (max_indices) *max_indices = i;
}

/* Horn's gradient, the same the splat's hillshade uses (lib/dem.c). */
static void vertex_normal(const rs_roam *L, int x, int y, float *out)
{
    double dzx, dzy;
    rs__dem_horn(L->z, L->w, L->hgt, L->cs, L->zs, (uint32_t)y, (uint32_t)x, &dzx, &dzy);
    double nx = -dzx, ny = -dzy, nz = 1.0, l = sqrt(nx * nx + ny * ny + nz * nz);
    out[0] = (float)(nx / l); out[1] = (float)(ny / l); out[2] = (float)(nz / l);
}

typedef struct extract_state {
    rs_roam *L;
    float *vtx, *nrm;
    int normals;
    size_t vcap, icap, nv, ni;
    uint32_t *idx;
    uint32_t *samples;  /* optional: sample (row * width + column) of each vertex */
    int overflow;
    rs_ctx *ctx;        /* progress (rs_ctx_set_progress): polls in the long passes */
    int cancelled;      /* a poll said stop (overflow is set too: the passes stop) */
} extract_state;

/* Items (nodes, vertex words, indices) between two polls of a pass (65536
 * left 21 ms between two of them on the refine_count(10^6) mesh) */
#define EXTRACT_POLL 16384u

/* A poll: 1 (and the state stopped) when the host's callback said stop. */
static int extract_stop(extract_state *s)
{
    if (!rs__poll(s->ctx)) return 0;
    s->cancelled = s->overflow = 1;
    return 1;
}

/* Pass 1 of extraction: a corner by its padded sample index (row * 64 wpr +
 * column), recorded in the vertex set. Indices are written as these keys
 * and renumbered once the set is complete (number_indices). */
static uint32_t mark_key(const extract_state *s, uint32_t p)
{
    rs_roam *L = s->L;
    L->vbits[p >> 6] |= (uint64_t)1 << (p & 63u);
    L->vsum[p >> 12] |= (uint64_t)1 << ((p >> 6) & 63u);
    return p;
}

static uint32_t mark(const extract_state *s, int x, int y)
{
    return mark_key(s, (uint32_t)y * (s->L->wpr * 64u) + (uint32_t)x);
}

/* One leaf triangle, when it lies on the map; 1 on overflow. */
static int emit_tri(extract_state *s, const tri *t)
{
    if (!tri_inside(s->L, t)) return 0;
    if (s->ni + 3 > s->icap) { s->overflow = 1; return 1; }
    /* apex, right corner, left corner: counter-clockwise seen from above */
    s->idx[s->ni++] = mark(s, t->ax, t->ay);
    s->idx[s->ni++] = mark(s, t->cx, t->cy);
    s->idx[s->ni++] = mark(s, t->bx, t->by);
    return 0;
}

/* The leaves of block nd's implicit subtree below position pos (triangle t). */
static int emit_imp(extract_state *s, const roam_node *nd, uint32_t pos, const tri *t)
{
    for (int k = 0; k < 2; k++) {
        uint32_t c = 2 * pos + (uint32_t)k;
        tri u;
        child_tri(t, k, &u);
        if (c < s->L->ncut && (nd->rc & SPLIT_BIT(c))) {
            if (emit_imp(s, nd, c, &u)) return 1;
        } else if (emit_tri(s, &u)) return 1;
    }
    return 0;
}

/* The same for a block on the map: every corner of a leaf is a
 * corner of the block or the hypotenuse midpoint of a split position, so
 * those are marked once each, and the leaves write their sample keys,
 * affine in the reference geometry pgeo, in the order of emit_imp. */
static int emit_block_on(extract_state *s, const roam_node *nd, const tri *t)
{
    const rs_roam *L = s->L;
    const uint32_t row = L->wpr * 64u;
    const int unit = 1 << (L->dq / 2);
    const uint32_t k0 = (uint32_t)t->ay * row + (uint32_t)t->ax;
    /* key steps along the legs' unit vectors (wrapping arithmetic) */
    const uint32_t kb = (uint32_t)((t->by - t->ay) / unit) * row + (uint32_t)((t->bx - t->ax) / unit);
    const uint32_t kc = (uint32_t)((t->cy - t->ay) / unit) * row + (uint32_t)((t->cx - t->ax) / unit);
#define KEY(u, v) (k0 + (uint32_t)(u) * kb + (uint32_t)(v) * kc)
    const uint32_t split = nd->rc & (SPLIT_BIT(L->ncut) - 1u);
    (void)mark_key(s, KEY(L->pgeo[1][0], L->pgeo[1][1]));
    (void)mark_key(s, KEY(L->pgeo[1][2], L->pgeo[1][3]));
    (void)mark_key(s, KEY(L->pgeo[1][4], L->pgeo[1][5]));
    (void)mark_key(s, KEY(L->pgeo[1][6], L->pgeo[1][7]));
    for (uint32_t m = split; m; m &= m - 1u) {
        const unsigned char *g = L->pgeo[lowest_bit(m) + 2u];
        (void)mark_key(s, KEY(g[6], g[7]));
    }
    uint32_t pos = 2;
    for (;;) {
        if (pos < L->ncut && (split & SPLIT_BIT(pos))) { pos *= 2; continue; }
        if (s->ni + 3 > s->icap) { s->overflow = 1; return 1; }
        const unsigned char *g = L->pgeo[pos];
        uint32_t *o = s->idx + s->ni;
        /* apex, right corner, left corner: counter-clockwise seen from above */
        o[0] = KEY(g[0], g[1]); o[1] = KEY(g[4], g[5]); o[2] = KEY(g[2], g[3]);
        s->ni += 3;
        while ((pos & 1u) && pos > 1) pos >>= 1;
        if (pos == 1) break;
        pos++;
    }
#undef KEY
    return 0;
}

/* The leaves at node nd (itself, or its implicit ones); 1 on overflow. */
static int emit_node(extract_state *s, const roam_node *nd)
{
    tri r;
    node_tri(s->L, nd, &r);
    if (nd->lc == NIL) return emit_tri(s, &r);
    if (r.on) return emit_block_on(s, nd, &r);
    return emit_imp(s, nd, 1, &r);
}

/* Leaves in allocation order (the implicit ones with their block node):
 * one linear pass over the node array (cache friendly; the order is
 * deterministic). */
static void emit_leaves(extract_state *s)
{
    rs_roam *L = s->L;
    const roam_node *nodes = L->nodes;
    size_t at = 0; /* (the indices at the last poll: a block node writes up to 2^ncut leaves) */
    for (uint32_t t = 0; t < L->used; t++) {
        if ((t & (EXTRACT_POLL - 1)) == EXTRACT_POLL - 1 || s->ni - at >= 3 * (size_t)EXTRACT_POLL) {
            at = s->ni;
            if (extract_stop(s)) return;
        }
        uint32_t lc = nodes[t].lc;
        if (lc != NIL && lc != IMPL) continue; /* inner node or free */
        if (emit_node(s, &nodes[t])) return;
    }
}

/* The leaves under roots[0..n), depth first, left child first (the order
 * is deterministic); the refinement stack is free between calls. */
static void emit_subtree_leaves(extract_state *s, const uint32_t *roots, int n)
{
    rs_roam *L = s->L;
    const roam_node *nodes = L->nodes;
    uint32_t *st = L->stack, sp = 0;
    while (n > 0) st[sp++] = roots[--n];
    while (sp) {
        const roam_node *nd = &nodes[st[--sp]];
        if (nd->lc != NIL && nd->lc != IMPL) {
            st[sp++] = nd->rc;
            st[sp++] = nd->lc;
        } else if (emit_node(s, nd)) return;
    }
}

/* The leaves of one patch. */
static void emit_patch_leaves(extract_state *s, uint32_t patch)
{
    uint32_t roots[2] = { 2 * patch, 2 * patch + 1 };
    emit_subtree_leaves(s, roots, 2);
}

/* The leaves of upload unit `unit` (docs/roam.md, "Upload units"): the
 * subtree at heap index h (depth udepth below the patch's roots), found by
 * walking down h's bits; a leaf met above that depth belongs to the unit of
 * its leftmost descendant (h's remaining bits all 0). *y0, *y1: the rows
 * the unit's triangle spans (its vertices lie there). */
static void emit_unit_leaves(extract_state *s, uint32_t unit, int *y0, int *y1)
{
    rs_roam *L = s->L;
    const roam_node *nodes = L->nodes;
    uint32_t patch = unit >> (L->udepth + 1u), h = L->upp + (unit & (L->upp - 1u));
    uint32_t i = 2 * patch + ((h >> L->udepth) - 2u);
    tri t;
    node_tri(L, &nodes[i], &t);
    uint32_t at = NIL; /* the subtree root, or the coarser leaf */
    for (uint32_t k = L->udepth; k-- > 0;) {
        tri c;
        child_tri(&t, (int)((h >> k) & 1u), &c);
        t = c;
        if (at == NIL) {
            const roam_node *nd = &nodes[i];
            if (nd->lc == NIL || nd->lc == IMPL) at = (h & ((2u << k) - 1u)) ? NIL - 1u : i;
            else i = (h >> k) & 1u ? nd->rc : nd->lc;
        }
    }
    int lo = t.ay < t.by ? t.ay : t.by, hi = t.ay > t.by ? t.ay : t.by;
    if (t.cy < lo) lo = t.cy;
    if (t.cy > hi) hi = t.cy;
    if (at == NIL - 1u) { *y0 = 0; *y1 = -1; return; } /* a coarser leaf in another unit */
    if (at != NIL) {
        /* a leaf coarser than the unit: its rows, not the unit's */
        node_tri(L, &nodes[at], &t);
        lo = t.ay < t.by ? t.ay : t.by; hi = t.ay > t.by ? t.ay : t.by;
        if (t.cy < lo) lo = t.cy;
        if (t.cy > hi) hi = t.cy;
        i = at;
    }
    *y0 = lo < 0 ? 0 : lo;
    *y1 = hi > (int)L->ch ? (int)L->ch : hi;
    emit_subtree_leaves(s, &i, 1);
}

/* Pass 2: number the vertex set in row-major order (the rank of each word)
 * and write the vertices, reading the DEM in order. Only words flagged in
 * the summary are visited, so a sparse mesh on a huge map stays cheap.
 * Returns the vertex count; writes nothing when it exceeds vcap. */
static size_t emit_vertices(extract_state *s, size_t g0, size_t g1)
{
    rs_roam *L = s->L;
    size_t n = 0;
    for (size_t g = g0; g < g1; g++) {
        if (((g - g0) & (EXTRACT_POLL / 64 - 1)) == EXTRACT_POLL / 64 - 1 && extract_stop(s)) return 0;
        for (uint64_t sm = L->vsum[g]; sm; sm &= sm - 1) {
            size_t k = g * 64 + lowest_bit(sm);
            L->vrank[k] = (uint32_t)n;
            n += popcount64(L->vbits[k]);
        }
    }
    if (n > s->vcap) return n;
    size_t v = 0;
    for (size_t g = g0; g < g1; g++) {
        if (((g - g0) & (EXTRACT_POLL / 64 - 1)) == EXTRACT_POLL / 64 - 1 && extract_stop(s)) return 0;
        for (uint64_t sm = L->vsum[g]; sm; sm &= sm - 1) {
            size_t k = g * 64 + lowest_bit(sm);
            int y = (int)(k / L->wpr), x0 = (int)(k % L->wpr) * 64;
            const float *zr = L->z + (size_t)y * L->w;
            const double py = y * L->cs;
            for (uint64_t b = L->vbits[k]; b; b &= b - 1, v++) {
                int x = x0 + (int)lowest_bit(b);
                float *o = s->vtx + 5 * v;
                o[0] = (float)(x * L->cs);
                o[1] = (float)py;
                o[2] = (float)((double)zr[x] * L->zs);
                o[3] = L->ucol[x];
                o[4] = L->vrow[y];
                if (s->samples) s->samples[v] = (uint32_t)y * L->w + (uint32_t)x;
                if (s->normals) vertex_normal(L, x, y, s->nrm + 3 * v);
            }
        }
    }
    return n;
}

/* Vertex number of sample key p (the vertex set complete and ranked). */
static uint32_t key_vertex(const rs_roam *L, uint32_t p)
{
    uint64_t below = ((uint64_t)1 << (p & 63u)) - 1u;
    return L->vrank[p >> 6] + popcount64(L->vbits[p >> 6] & below);
}

#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__)) && !defined(__POPCNT__)
/* The same with the popcnt instruction, on the CPUs that have it (all
 * x86-64 made since about 2009; the baseline target does not assume it):
 * one instruction instead of twelve per index, a third of the pass. */
#define RS_POPCNT_DISPATCH 1
__attribute__((target("popcnt"))) static void number_indices_popcnt(const extract_state *s, size_t i0, size_t n)
{
    const rs_roam *L = s->L;
    uint32_t *ix = s->idx;
    for (size_t i = i0; i < n; i++) {
        uint32_t p = ix[i];
        uint64_t below = ((uint64_t)1 << (p & 63u)) - 1u;
        ix[i] = L->vrank[p >> 6] + (uint32_t)__builtin_popcountll(L->vbits[p >> 6] & below);
    }
}
#endif

/* Pass 3: sample keys in entries i0..n of the index buffer -> vertex numbers. */
static void number_range(const extract_state *s, size_t i0, size_t n)
{
#ifdef RS_POPCNT_DISPATCH
    if (__builtin_cpu_supports("popcnt")) {
        number_indices_popcnt(s, i0, n);
        return;
    }
#endif
    uint32_t *ix = s->idx;
    for (size_t i = i0; i < n; i++) ix[i] = key_vertex(s->L, ix[i]);
}

/* Pass 3 over the first n entries, a poll every EXTRACT_POLL of them. */
static void number_indices(extract_state *s, size_t n)
{
    for (size_t i0 = 0; i0 < n; i0 += EXTRACT_POLL) {
        if (i0 && extract_stop(s)) return;
        number_range(s, i0, n - i0 < EXTRACT_POLL ? n : i0 + EXTRACT_POLL);
    }
}

/* Empty the vertex set for the next extraction: only the flagged words
 * (of the summary words g0..g1, which hold every set bit). */
static void clear_vertex_set(rs_roam *L, size_t g0, size_t g1)
{
    for (size_t g = g0; g < g1; g++) {
        for (uint64_t sm = L->vsum[g]; sm; sm &= sm - 1) L->vbits[g * 64 + lowest_bit(sm)] = 0;
        L->vsum[g] = 0;
    }
}

/* Border sample -> slot in smap: top row, bottom row, left column, right column. */
static size_t border_slot(const rs_roam *L, int x, int y)
{
    if (y == 0) return (size_t)x;
    if (y == (int)L->ch) return L->w + (size_t)x;
    if (x == 0) return 2 * (size_t)L->w + (size_t)y;
    return 2 * (size_t)L->w + L->hgt + (size_t)y;
}

/* Both keys on the same map border: their sample positions, from the keys
 * (never from the float vertices). */
static int on_same_border(const rs_roam *L, uint32_t kp, uint32_t kq, int *px, int *py, int *qx, int *qy)
{
    uint32_t row = L->wpr * 64u;
    *px = (int)(kp % row); *py = (int)(kp / row);
    *qx = (int)(kq % row); *qy = (int)(kq / row);
    if (*px == *qx && (*px == 0 || *px == (int)L->cw)) return 1;
    if (*py == *qy && (*py == 0 || *py == (int)L->ch)) return 1;
    return 0;
}

static uint32_t skirt_vertex(extract_state *s, uint32_t top, int x, int y, double depth)
{
    rs_roam *L = s->L;
    size_t slot = border_slot(L, x, y);
    if (L->smap[slot] != NIL) return L->smap[slot];
    if (s->nv >= s->vcap) { s->overflow = 1; return 0; }
    float *v = s->vtx + 5 * s->nv;
    memcpy(v, s->vtx + 5 * (size_t)top, 5 * sizeof(float));
    v[2] = (float)((double)v[2] - depth);
    if (s->normals) memcpy(s->nrm + 3 * s->nv, s->nrm + 3 * (size_t)top, 3 * sizeof(float));
    if (s->samples) s->samples[s->nv] = s->samples[top];
    L->smap[slot] = (uint32_t)s->nv;
    return (uint32_t)s->nv++;
}

/* What extract_mesh writes: the whole mesh, one patch or one upload unit. */
enum { EXTRACT_ALL, EXTRACT_PATCH, EXTRACT_UNIT };

/* rs_roam_extract, rs_roam_extract_patch (part = the patch) and
 * rs_roam_extract_unit (part = the unit). */
static rs_result extract_mesh(rs_ctx *ctx, rs_roam *L, int what, uint32_t part, const rs_roam_mesh_options *opts,
                              float *vertices, float *normals, size_t vertex_capacity, uint32_t *indices,
                              size_t index_capacity, size_t *vertex_count, size_t *index_count)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (vertex_count) *vertex_count = 0;
    if (index_count) *index_count = 0;
    if (!L || (!vertices && vertex_capacity) || (!indices && index_capacity))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_extract: roam and buffers must not be NULL");
    if (what == EXTRACT_PATCH && part >= L->npx * L->npy)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_extract_patch: patch %u of %u", part, L->npx * L->npy);
    if (what == EXTRACT_UNIT && part / L->upp >= L->npx * L->npy)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_extract_unit: unit %u of %llu", part,
                        (unsigned long long)L->npx * L->npy * L->upp);
    rs_roam_mesh_options o;
    rs_result rc = RS__OPTS_IN(ctx, opts, &o, rs_roam_mesh_options);
    if (rc) return rc;
    if (o.normals && !normals)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_extract: normals requested but buffer is NULL");
    if (!(o.skirt_depth >= 0.0) || !isfinite(o.skirt_depth))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roam_extract: skirt_depth %g must be >= 0", o.skirt_depth);
    if (!((double)L->zabs * L->zs + o.skirt_depth <= FLT_MAX))
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_roam_extract: skirt_depth %g below heights down to -%g leaves the float range (%g)",
                        o.skirt_depth, (double)L->zabs * L->zs, (double)FLT_MAX);
    extract_state s;
    memset(&s, 0, sizeof s);
    s.L = L; s.vtx = vertices; s.nrm = normals; s.normals = o.normals != 0;
    s.vcap = vertex_capacity; s.icap = index_capacity; s.idx = indices;
    s.samples = o.samples;
    s.ctx = ctx;
    /* the rows that can hold vertices, as summary words */
    int y0 = 0, y1 = (int)L->ch;
    if (what == EXTRACT_ALL) emit_leaves(&s);
    else if (what == EXTRACT_PATCH) {
        emit_patch_leaves(&s, part);
        y0 = (int)((part / L->npx) * L->P);
        if (y0 + (int)L->P < y1) y1 = y0 + (int)L->P;
    } else emit_unit_leaves(&s, part, &y0, &y1);
    size_t g0 = 0, g1 = 0;
    if (y1 >= y0) {
        g0 = ((size_t)y0 * L->wpr) >> 6;
        g1 = ((((size_t)y1 + 1) * L->wpr - 1) >> 6) + 1;
    }
    if (!s.overflow) {
        s.nv = emit_vertices(&s, g0, g1);
        if (s.nv > s.vcap) s.overflow = 1;
    }
    size_t top_indices = s.ni;
    int top_ok = !s.overflow;
    if (!s.overflow && o.skirt_depth > 0.0) {
        /* the top indices are still sample keys here: the border test reads
         * sample positions from them */
        for (size_t t = 0; t < top_indices && !s.overflow; t += 3)
            for (int e = 0; e < 3 && !s.overflow; e++) {
                uint32_t kp = indices[t + (size_t)e], kq = indices[t + (size_t)(e + 1) % 3];
                int px, py, qx, qy;
                if (!on_same_border(L, kp, kq, &px, &py, &qx, &qy)) continue;
                uint32_t p = key_vertex(L, kp), q = key_vertex(L, kq);
                uint32_t ps = skirt_vertex(&s, p, px, py, o.skirt_depth);
                uint32_t qs = skirt_vertex(&s, q, qx, qy, o.skirt_depth);
                if (s.overflow) break;
                if (s.ni + 6 > s.icap) { s.overflow = 1; break; }
                indices[s.ni++] = p; indices[s.ni++] = ps; indices[s.ni++] = q;
                indices[s.ni++] = q; indices[s.ni++] = ps; indices[s.ni++] = qs;
            }
        memset(L->smap, 0xFF, 2 * ((size_t)L->w + L->hgt) * sizeof(uint32_t));
    }
    if (top_ok) number_indices(&s, top_indices); /* as before skirts existed, even when they overflowed */
    clear_vertex_set(L, g0, g1);
    if (s.cancelled) return RS_ERR_CANCELLED; /* (the message: rs__progress_end) */
    if (s.overflow) {
        size_t mv, mi;
        rs_roam_mesh_bound(L, &o, &mv, &mi);
        return rs__fail(ctx, RS_ERR_BUFFER_TOO_SMALL,
                        "rs_roam_extract: buffers of %zu vertices / %zu indices too small (bound %zu / %zu)",
                        vertex_capacity, index_capacity, mv, mi);
    }
    if (vertex_count) *vertex_count = s.nv;
    if (index_count) *index_count = s.ni;
    rs__ok(ctx);
    return RS_OK;
}

/* Progress: the context's callback (rs_ctx_set_progress), polls in the
 * passes; a cancel writes no counts (the buffers' contents are then
 * undefined) and leaves the landscape as it was. */
static rs_result extract_run(rs_ctx *ctx, rs_roam *L, int what, uint32_t part, const rs_roam_mesh_options *opts,
                             float *vertices, float *normals, size_t vertex_capacity, uint32_t *indices,
                             size_t index_capacity, size_t *vertex_count, size_t *index_count)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    rs__progress pg;
    rs__progress_begin(ctx, &pg, NULL, NULL, 1, 1);
    return rs__progress_end(ctx, &pg, extract_mesh(ctx, L, what, part, opts, vertices, normals, vertex_capacity,
                                                   indices, index_capacity, vertex_count, index_count));
}

rs_result rs_roam_extract(rs_ctx *ctx, rs_roam *L, const rs_roam_mesh_options *opts, float *vertices,
                          float *normals, size_t vertex_capacity, uint32_t *indices, size_t index_capacity,
                          size_t *vertex_count, size_t *index_count)
{
    return extract_run(ctx, L, EXTRACT_ALL, 0, opts, vertices, normals, vertex_capacity, indices, index_capacity,
                        vertex_count, index_count);
}

rs_result rs_roam_extract_patch(rs_ctx *ctx, rs_roam *L, uint32_t patch, const rs_roam_mesh_options *opts,
                                float *vertices, float *normals, size_t vertex_capacity, uint32_t *indices,
                                size_t index_capacity, size_t *vertex_count, size_t *index_count)
{
    return extract_run(ctx, L, EXTRACT_PATCH, patch, opts, vertices, normals, vertex_capacity, indices,
                        index_capacity, vertex_count, index_count);
}

rs_result rs_roam_extract_unit(rs_ctx *ctx, rs_roam *L, uint32_t unit, const rs_roam_mesh_options *opts,
                               float *vertices, float *normals, size_t vertex_capacity, uint32_t *indices,
                               size_t index_capacity, size_t *vertex_count, size_t *index_count)
{
    return extract_run(ctx, L, EXTRACT_UNIT, unit, opts, vertices, normals, vertex_capacity, indices,
                        index_capacity, vertex_count, index_count);
}

uint32_t rs_roam_unit_generation(const rs_roam *L, uint32_t unit)
{
    if (!L || unit / L->upp >= L->npx * L->npy) return 0;
    return L->ugen[unit];
}

uint32_t rs_roam_patch_generation(const rs_roam *L, uint32_t patch)
{
    if (!L || patch >= L->npx * L->npy) return 0;
    return L->pgen[patch];
}
