/* Road markings (issue 14, docs/markings.md): sprites of the atlas placed
 * in road coordinates and drawn per pixel through a grid index over their
 * extents, after seed 001 (atlas + per-marking parametric record, one pass
 * for all markings, c = (1 - a) c1 + a c2) but with the marking bent along
 * its road instead of a rigid box, and the atlas sampled trilinearly for
 * the pixel's footprint. */
#include "markings.h"
#include "splatter.h"

#include <float.h>
#include <stdio.h>
#include <math.h>
#include <string.h>

#define MAX_INDEX_ENTRIES (1u << 26)
#define MAX_INDEX_CELLS (1u << 22)

void rs__road_local_free(rs_ctx *ctx, rs__road_local *r)
{
    rs__free(ctx, r->x);
    rs__free(ctx, r->y);
    rs__free(ctx, r->s);
    memset(r, 0, sizeof *r);
}

rs_result rs__road_local_get(rs_ctx *ctx, const rs_roads *roads, size_t ri, const rs_dem *dem, rs__road_local *out)
{
    const double *xy = NULL;
    size_t n = 0;
    memset(out, 0, sizeof *out);
    rs_roads_get(roads, ri, NULL, NULL, &xy, &n);
    double per_unit = rs__local_quantum(dem->frame.cell_size);
    out->x = rs__alloc_array(ctx, n ? n : 1, sizeof(double));
    out->y = rs__alloc_array(ctx, n ? n : 1, sizeof(double));
    out->s = rs__alloc_array(ctx, n ? n : 1, sizeof(double));
    if (!out->x || !out->y || !out->s) {
        rs__road_local_free(ctx, out);
        return RS_ERR_NOMEM;
    }
    size_t m = 0;
    double s = 0;
    for (size_t k = 0; k < n; k++) {
        double x = rs__local_coord(xy[2 * k], dem->frame.origin_x, per_unit);
        double y = rs__local_coord(xy[2 * k + 1], dem->frame.origin_y, per_unit);
        if (m > 0) {
            if (x == out->x[m - 1] && y == out->y[m - 1]) continue;
            s += 2 * hypot(0.5 * x - 0.5 * out->x[m - 1], 0.5 * y - 0.5 * out->y[m - 1]);
            if (!(s <= DBL_MAX)) s = DBL_MAX;
        }
        out->x[m] = x;
        out->y[m] = y;
        out->s[m] = s;
        m++;
    }
    out->n = m;
    return RS_OK;
}

rs_result rs__placement_push(rs_ctx *ctx, rs__placement **pl, size_t *n, size_t *cap, const rs__placement *p)
{
    if (*n == *cap) {
        size_t nc = *cap ? 2 * *cap : 64;
        rs__placement *q = rs__realloc(ctx, *pl, nc * sizeof *q);
        if (!q) return RS_ERR_NOMEM;
        *pl = q;
        *cap = nc;
    }
    (*pl)[(*n)++] = *p;
    return RS_OK;
}

void rs__markings_free(rs_ctx *ctx, rs__markings *mk)
{
    if (!mk) return;
    rs_atlas_free(ctx, mk->atlas_own);
    rs__free(ctx, mk->m);
    rs__free(ctx, mk->pts);
    rs__free(ctx, mk->start);
    rs__free(ctx, mk->list);
    rs__free(ctx, mk);
}

/* The road coordinates of local point (x, y) on a marking's stretch of
 * road: the nearest point of its segments (the first and last extended
 * beyond their ends, so that pixels past the stretch never clamp onto it),
 * s there and t = the signed distance (+ left of travel), so a marking
 * bends with the road as its buffer does. */
static void road_coords(const double *pts, size_t npt, double x, double y, double *s_out, double *t_out)
{
    if (npt == 2) { /* one segment, extended both ways: the line's own coordinates */
        double len = pts[5] - pts[2];
        double ux = (pts[3] - pts[0]) / len, uy = (pts[4] - pts[1]) / len, px = x - pts[0], py = y - pts[1];
        *s_out = pts[2] + px * ux + py * uy;
        *t_out = px * uy - py * ux;
        return;
    }
    double best = INFINITY, bs = 0, bt = 0;
    for (size_t k = 0; k + 1 < npt; k++) {
        const double *a = pts + 3 * k, *b = a + 3;
        double dx = b[0] - a[0], dy = b[1] - a[1], len = b[2] - a[2];
        if (!(len > 0)) continue;
        double ux = dx / len, uy = dy / len;
        double px = x - a[0], py = y - a[1];
        double u = px * ux + py * uy;
        if (k > 0 && u < 0) u = 0;
        if (k + 2 < npt && u > len) u = len;
        double ex = px - u * ux, ey = py - u * uy, d2 = ex * ex + ey * ey;
        if (d2 < best) {
            best = d2;
            bs = a[2] + u;
            double side = ex * uy - ey * ux; /* (p - q) . (dy, -dx) */
            double d = sqrt(d2);
            bt = side < 0 ? -d : d;
        }
    }
    *s_out = bs;
    *t_out = bt;
}

/* Geometry of one placement: its stretch of road, bounding box, filter
 * reach. Returns 0 when it lies wholly off its road. */
static int place(const rs__placement *pl, const rs__road_local *r, const rs__atlas_type *ty, double pix, rs__mk *m,
                 double **pts, size_t *npts, size_t *cap, rs_ctx *ctx, rs_result *err)
{
    memset(m, 0, sizeof *m);
    m->ty = ty;
    m->flip = pl->flip;
    m->s0 = pl->s;
    m->t0 = pl->t;
    m->hl = 0.5 * pl->length;
    m->hw = 0.5 * pl->width;
    m->kx = ty->lev[0].w / pl->width;
    m->ky = ty->lev[0].h / pl->length;
    double rho = pix * (m->kx > m->ky ? m->kx : m->ky);
    m->lod = rho > 1 ? log2(rho) : 0;
    double top = ceil(m->lod);
    if (top > ty->nlev - 1) top = ty->nlev - 1;
    double reach = 0.5 * ldexp(1.0, (int)top); /* level-0 texels past the edge */
    m->ms = reach / m->ky;
    m->mt = reach / m->kx;
    if (r->n < 2) return 0;
    double total = r->s[r->n - 1];
    double lo = m->s0 - m->hl - m->ms, hi = m->s0 + m->hl + m->ms;
    if (hi < 0 || lo > total) return 0;
    /* segments [a, b] overlapping [lo, hi] */
    size_t a = 0, b = r->n - 2;
    {
        size_t l = 0, h = r->n - 1; /* last k with s[k] <= lo */
        while (l + 1 < h) {
            size_t mid = (l + h) / 2;
            if (r->s[mid] <= lo) l = mid; else h = mid;
        }
        a = l;
        l = 0;
        h = r->n - 1; /* first k with s[k] >= hi */
        while (l + 1 < h) {
            size_t mid = (l + h) / 2;
            if (r->s[mid] >= hi) h = mid; else l = mid;
        }
        b = h > 0 ? h - 1 : 0;
        if (b < a) b = a;
    }
    size_t np = b - a + 2;
    if (*npts + np > *cap) {
        size_t nc = *cap ? *cap : 256;
        while (nc < *npts + np) nc *= 2;
        double *q = rs__realloc(ctx, *pts, nc * 3 * sizeof(double));
        if (!q) {
            *err = RS_ERR_NOMEM;
            return 0;
        }
        *pts = q;
        *cap = nc;
    }
    m->first = *npts;
    m->npt = np;
    for (size_t k = 0; k < np; k++) {
        double *o = *pts + 3 * (*npts + k);
        o[0] = r->x[a + k];
        o[1] = r->y[a + k];
        o[2] = r->s[a + k];
    }
    /* the box: the offset rectangle's corners where [lo, hi] starts and
     * ends (on the end segments' lines, extended past the stretch as the
     * lookup extends them), and around every vertex inside [lo, hi] the
     * square of the farthest offset (an outer bend's arc stays in it) */
    const double *c0 = *pts + 3 * *npts;
    double tin = m->t0 - m->hw - m->mt, tout = m->t0 + m->hw + m->mt;
    double far = fabs(tin) > fabs(tout) ? fabs(tin) : fabs(tout);
    m->bx0 = m->by0 = INFINITY;
    m->bx1 = m->by1 = -INFINITY;
    for (int end = 0; end < 2; end++) {
        double sv = end ? hi : lo;
        /* the segment of the chain that holds sv (end segments extended) */
        size_t k = 0;
        while (k + 2 < np && c0[3 * (k + 1) + 2] <= sv) k++;
        const double *A = c0 + 3 * k, *B = A + 3;
        double len = B[2] - A[2], ux = len > 0 ? (B[0] - A[0]) / len : 1, uy = len > 0 ? (B[1] - A[1]) / len : 0;
        double px = A[0] + (sv - A[2]) * ux, py = A[1] + (sv - A[2]) * uy;
        for (int side = 0; side < 2; side++) {
            double tt = side ? tout : tin, x = px + tt * uy, y = py - tt * ux; /* left normal (dy, -dx) */
            if (x < m->bx0) m->bx0 = x;
            if (x > m->bx1) m->bx1 = x;
            if (y < m->by0) m->by0 = y;
            if (y > m->by1) m->by1 = y;
        }
    }
    for (size_t k = 1; k + 1 < np; k++) {
        const double *V = c0 + 3 * k;
        if (!(V[2] > lo && V[2] < hi)) continue;
        if (V[0] - far < m->bx0) m->bx0 = V[0] - far;
        if (V[0] + far > m->bx1) m->bx1 = V[0] + far;
        if (V[1] - far < m->by0) m->by0 = V[1] - far;
        if (V[1] + far > m->by1) m->by1 = V[1] + far;
    }
    *npts += np;
    return 1;
}

static rs_result build_index(rs_ctx *ctx, rs__markings *mk, double map_w, double map_h)
{
    double cell = 2.0;
    if (cell < 4 * mk->pix) cell = 4 * mk->pix;
    while ((map_w / cell + 1) * (map_h / cell + 1) > MAX_INDEX_CELLS) cell *= 2;
    mk->cell = cell;
    mk->gw = (uint32_t)(map_w / cell) + 1;
    mk->gh = (uint32_t)(map_h / cell) + 1;
    size_t ncell = (size_t)mk->gw * mk->gh;
    mk->start = rs__calloc(ctx, ncell + 1, sizeof *mk->start);
    if (!mk->start) return RS_ERR_NOMEM;
    uint64_t total = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (size_t i = 0; i < mk->n; i++) {
            const rs__mk *m = &mk->m[i];
            double cx0 = floor(m->bx0 / cell), cx1 = floor(m->bx1 / cell);
            double cy0 = floor(m->by0 / cell), cy1 = floor(m->by1 / cell);
            if (cx1 < 0 || cy1 < 0 || cx0 >= mk->gw || cy0 >= mk->gh) continue;
            uint32_t x0 = cx0 < 0 ? 0 : (uint32_t)cx0, y0 = cy0 < 0 ? 0 : (uint32_t)cy0;
            uint32_t x1 = cx1 >= mk->gw ? mk->gw - 1 : (uint32_t)cx1, y1 = cy1 >= mk->gh ? mk->gh - 1 : (uint32_t)cy1;
            if (pass == 0) {
                total += (uint64_t)(x1 - x0 + 1) * (y1 - y0 + 1);
                if (total > MAX_INDEX_ENTRIES)
                    return rs__fail(ctx, RS_ERR_LIMIT, "markings cover more than %u index cells in all (too large?)",
                                    MAX_INDEX_ENTRIES);
                for (uint32_t y = y0; y <= y1; y++)
                    for (uint32_t x = x0; x <= x1; x++) mk->start[(size_t)y * mk->gw + x + 1]++;
            } else {
                for (uint32_t y = y0; y <= y1; y++)
                    for (uint32_t x = x0; x <= x1; x++) {
                        rs__mk_ref *e = &mk->list[mk->start[(size_t)y * mk->gw + x]++];
                        e->x0 = nextafterf((float)m->bx0, -INFINITY);
                        e->y0 = nextafterf((float)m->by0, -INFINITY);
                        e->x1 = nextafterf((float)m->bx1, INFINITY);
                        e->y1 = nextafterf((float)m->by1, INFINITY);
                        e->i = (uint32_t)i;
                    }
            }
        }
        if (pass == 0) {
            for (size_t c = 0; c < ncell; c++) mk->start[c + 1] += mk->start[c];
            mk->list = rs__alloc_array(ctx, total ? (size_t)total : 1, sizeof *mk->list);
            if (!mk->list) return RS_ERR_NOMEM;
        } else {
            /* the fill advanced each start to the next cell's: shift back */
            for (size_t c = ncell; c > 0; c--) mk->start[c] = mk->start[c - 1];
            mk->start[0] = 0;
        }
    }
    mk->bytes += (ncell + 1) * sizeof *mk->start + (size_t)total * sizeof *mk->list;
    return RS_OK;
}

rs_result rs__markings_build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                             rs__markings **out)
{
    *out = NULL;
    if (o->markings.disable) return RS_OK;
    size_t nexp = rs_roads_mark_count(roads);
    if (nexp == 0 && o->markings.no_auto) return RS_OK;
    rs__markings *mk = rs__calloc(ctx, 1, sizeof *mk);
    if (!mk) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
    rs_result r = RS_OK;
    const rs_atlas *atlas = o->markings.atlas;
    if (!atlas) {
        r = rs_atlas_default(ctx, &mk->atlas_own);
        atlas = mk->atlas_own;
    }
    rs__placement *pl = NULL;
    size_t npl = 0, cap = 0;
    for (size_t i = 0; i < nexp && !r; i++) {
        rs_mark m;
        rs_roads_get_mark(roads, i, &m);
        long ti = rs_atlas_find(atlas, m.type);
        if (ti < 0) {
            char where[48];
            if (m.line) snprintf(where, sizeof where, "line %llu: ", (unsigned long long)m.line);
            else snprintf(where, sizeof where, "mark %zu: ", i);
            r = rs__fail(ctx, RS_ERR_INVALID_ARG, "%smark: the atlas has no type '%s'", where, m.type);
            break;
        }
        rs__placement p;
        memset(&p, 0, sizeof p);
        p.type = (uint32_t)ti;
        p.road = m.road;
        p.s = m.s;
        p.t = m.t;
        p.length = m.length > 0 ? m.length : atlas->t[ti].length;
        p.width = m.width > 0 ? m.width : atlas->t[ti].width;
        p.flip = m.flip;
        p.line = m.line;
        if (rs__placement_push(ctx, &pl, &npl, &cap, &p)) r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
    }
    size_t n_explicit = npl;
    if (!r && !o->markings.no_auto) r = rs__markings_auto(ctx, dem, roads, atlas, &pl, &npl, &cap);
    if (!r && npl) {
        mk->pix = dem->frame.cell_size / o->texels;
        mk->m = rs__alloc_array(ctx, npl, sizeof *mk->m);
        if (!mk->m) r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
        size_t pcap = 0, npts = 0;
        rs__road_local rl;
        memset(&rl, 0, sizeof rl);
        size_t have_road = SIZE_MAX;
        for (size_t i = 0; i < npl && !r; i++) {
            if (pl[i].road != have_road) {
                rs__road_local_free(ctx, &rl);
                have_road = SIZE_MAX;
                if (rs__road_local_get(ctx, roads, pl[i].road, dem, &rl)) {
                    r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
                    break;
                }
                have_road = pl[i].road;
            }
            rs_result e = RS_OK;
            if (place(&pl[i], &rl, &atlas->t[pl[i].type], mk->pix, &mk->m[mk->n], &mk->pts, &npts, &pcap, ctx, &e)) {
                mk->n++;
                if (i < n_explicit) mk->n_explicit++;
                else mk->n_auto++;
            }
            if (e) r = rs__fail(ctx, RS_ERR_NOMEM, "out of memory for markings");
        }
        rs__road_local_free(ctx, &rl);
        mk->bytes = sizeof *mk + npl * sizeof *mk->m + pcap * 3 * sizeof(double);
        if (!r && mk->n) {
            double map_w = (double)(dem->width - 1) * dem->frame.cell_size;
            double map_h = (double)(dem->height - 1) * dem->frame.cell_size;
            r = build_index(ctx, mk, map_w, map_h);
            if (r == RS_ERR_NOMEM) rs__fail(ctx, r, "out of memory for the markings index");
        }
    }
    rs__free(ctx, pl);
    if (r || mk->n == 0) {
        rs__markings_free(ctx, mk);
        return r;
    }
    *out = mk;
    return RS_OK;
}

void rs__markings_paint(const rs__markings *mk, rs__piece *p)
{
    const size_t w = p->w;
    const double pix = mk->pix, cell = mk->cell;
    uint64_t tests = 0, painted = 0;
    for (uint32_t r = 0; r < p->rows; r++) {
        float *sc = p->sc + (size_t)r * w * 3;
        const uint16_t *q = p->q + (size_t)r * w;
        double y = ((double)p->y0 + (double)r + 0.5) * pix;
        double cy = floor(y / cell);
        if (cy < 0 || cy >= mk->gh) continue;
        size_t row = (size_t)cy * mk->gw;
        for (size_t k = 0; k < w; k++) {
            if (q[k] == 0) continue;
            double x = ((double)p->x0 + (double)k + 0.5) * pix;
            double cx = floor(x / cell);
            if (cx < 0 || cx >= mk->gw) continue;
            size_t c = row + (size_t)cx;
            uint32_t a = mk->start[c], b = mk->start[c + 1];
            int any = 0;
            const float fx = (float)x, fy = (float)y;
            for (uint32_t i = a; i < b; i++) {
                const rs__mk_ref *e = &mk->list[i];
                if (fx < e->x0 || fx > e->x1 || fy < e->y0 || fy > e->y1) continue;
                const rs__mk *m = &mk->m[e->i];
                tests++;
                double s, t;
                road_coords(mk->pts + 3 * m->first, m->npt, x, y, &s, &t);
                double ds = s - m->s0, dt = t - m->t0;
                if (fabs(ds) > m->hl + m->ms || fabs(dt) > m->hw + m->mt) continue;
                if (m->flip) {
                    ds = -ds;
                    dt = -dt;
                }
                float c4[4];
                rs__atlas_sample(m->ty, (m->hw - dt) * m->kx, (m->hl - ds) * m->ky, m->lod, c4);
                if (!(c4[3] > 0)) continue;
                any = 1;
                float keep = 1.0f - c4[3];
                for (int ch = 0; ch < 3; ch++) {
                    float *v = sc + (size_t)ch * w + k;
                    *v = *v * keep + c4[ch];
                }
            }
            painted += (uint64_t)any;
        }
    }
    p->mark_tests += tests;
    p->mark_pixels += painted;
}
