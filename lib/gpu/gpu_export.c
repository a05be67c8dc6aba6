/* GPU export (include/roadsplat.h "GPU export", docs/render.md "Shader
 * mode"): the roads as segments with their arc length, an index grid of
 * cells -> segments, the resolved styles, the markings in road coordinates
 * and the marking atlas's mip chains, as flat arrays for buffer textures.
 * Pure C; the library never sees GL. */
#include "internal.h"
#include "atlas.h"
#include "linesym.h"
#include "markings.h"
#include "lanes.h"
#include "roadfield.h"
#include "network.h"
#include "roadgrid.h"
#include "grid_edit.h"
#include "styling.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define GE_COS30 0.866
#define GE_MAX_CELLS ((double)(1u << 22))

/* The scene (include/roadsplat.h "GPU export"; opaque to hosts, who read
 * it through rs_gpu_scene_get_info and rs_gpu_scene_array). */
struct rs_gpu_scene {
    double cell, x0, y0, reach;
    uint32_t gw, gh;
    double map_w, map_h;           /* map extent, metres */
    size_t nseg, nroads, nbands, nmarks, ntypes, nlevels;
    size_t nseg_entries, nmark_entries, atlas_texels;
    float *seg, *road, *band, *mark;
    uint32_t *cell_start, *cell_seg;   /* gw*gh + 1, nseg_entries */
    uint32_t *mark_start, *mark_ids;   /* gw*gh + 1, nmark_entries */
    uint32_t *types, *levels;          /* ntypes * RS_GPU_TYPE_INTS, nlevels * RS_GPU_LEVEL_INTS */
    float *atlas_px;                   /* atlas_texels * 4 */
    size_t bytes;
    size_t ncuts;                      /* line cuts (issue 27) */
    float *cut;                        /* 4 * max(nroads, 1) + ncuts * RS_GPU_CUT_FLOATS */
    /* the markings' summed-area tables the shader samples (ge_mark_tables) */
    uint32_t *mark_levels;             /* nlevels * RS_GPU_LEVEL_INTS */
    int32_t *mark_sat;                 /* sat_corners * 4 */
    size_t sat_corners;
};

/* Where the export takes the styles, line cuts and placements from: the
 * road grid prepared for these roads (rs_gpu_scene_from_grid), or NULL:
 * worked out from the roads (rs_gpu_scene_create). */
typedef struct ge_src {
    const rs_road_grid *grid;
} ge_src;

static void colour_of(rs_colour *c, const float *f)
{
    c->r = (uint8_t)f[0];
    c->g = (uint8_t)f[1];
    c->b = (uint8_t)f[2];
    c->a = (uint8_t)lrintf(f[3] * 255.0f);
}

/* Road i's style as the export reads it (surface, colours, casing, lines):
 * resolved from the roads, or rebuilt from what the grid's styling kept
 * (the colours as put_colour stored them: r, g, b whole, a / 255, both
 * exact both ways). A grid with no styled road kept none: its roads are
 * drawn unstyled, and their colours (not read by the shader) are what the
 * style options without the named table give, else 0. */
static rs_result ge_style(rs_ctx *ctx, const ge_src *src, const rs_roads *roads, size_t i, const rs_style_options *so,
                          rs_style *sty)
{
    if (!src->grid) return rs_road_style_ex(ctx, roads, i, so, sty);
    const rs__styling *st = src->grid->styling;
    memset(sty, 0, sizeof *sty);
    if (!st) {
        if (rs_road_style_ex(ctx, roads, i, so, sty) != RS_OK) memset(sty, 0, sizeof *sty);
        sty->surface = RS_SURFACE_DEFAULT;
        sty->casing_width = 0;
        sty->line_count = 0;
        rs__ok(ctx);
        return RS_OK;
    }
    const float *c = st->colour + 16 * i;
    sty->surface = (rs_surface)st->surface[i];
    colour_of(&sty->fill, c);
    colour_of(&sty->gradient_centre, c + 4);
    colour_of(&sty->gradient_edge, c + 8);
    colour_of(&sty->casing, c + 12);
    sty->casing_width = st->casing_width ? st->casing_width[i] : 0;
    uint32_t b0 = st->band_start ? st->band_start[i] : 0, b1 = st->band_start ? st->band_start[i + 1] : 0;
    sty->line_count = b1 - b0;
    for (uint32_t j = 0; j < sty->line_count; j++) {
        const rs__band *b = &st->bands[b0 + j];
        rs_style_line *ln = &sty->line[j];
        ln->offset = b->t;
        ln->width = b->w;
        colour_of(&ln->colour, b->rgba);
        ln->dash_count = b->ndash;
        if (b->ndash) memcpy(ln->dash, b->dash, b->ndash * sizeof *b->dash);
        ln->phase = b->phase;
    }
    return RS_OK;
}

typedef struct ge_end {
    double x, y, dx, dy; /* end point and the direction the road leaves it */
    uint32_t road;
    int end;             /* 0 start, 1 end */
} ge_end;

static int ge_end_cmp(const void *a, const void *b)
{
    const ge_end *p = a, *q = b;
    if (p->x != q->x) return p->x < q->x ? -1 : 1;
    if (p->y != q->y) return p->y < q->y ? -1 : 1;
    if (p->road != q->road) return p->road < q->road ? -1 : 1;
    return p->end - q->end;
}

/* A double as a finite float: saturated to +-FLT_MAX (a NaN as 0). */
static float ge_float(double v)
{
    return v >= -FLT_MAX ? (v <= FLT_MAX ? (float)v : FLT_MAX) : (v < 0 ? -FLT_MAX : 0.0f);
}

/* The lines look the same drawn either way: each has its mirror image
 * (offset -t, all else equal) among them (lib/scene/linesym.c's rule on its
 * quantised offsets: a centre line at 1e-15 m is at 0). */
static int ge_lines_mirror(const rs_style *st)
{
    for (uint32_t i = 0; i < st->line_count; i++) {
        const rs_style_line *a = &st->line[i];
        int found = 0;
        for (uint32_t j = 0; j < st->line_count && !found; j++) {
            const rs_style_line *b = &st->line[j];
            found = fabs(b->offset + a->offset) <= 1e-9 && b->width == a->width && !memcmp(&b->colour, &a->colour, sizeof a->colour) &&
                    b->dash_count == a->dash_count && b->phase == a->phase &&
                    (a->dash_count == 0 || !memcmp(b->dash, a->dash, a->dash_count * sizeof *a->dash));
        }
        if (!found) return 0;
    }
    return 1;
}

/* Where the CPU draws a stroke's records as one polyline (lib/scene/linesym.c,
 * docs/network.md "Drawing by strokes"), the export gives their segments
 * the stroke's arc length, and a record drawn against the stroke its
 * points last to first: dashes then run on across the splits in the
 * shader as on the CPU. soff[i] < 0: the record keeps its own s. */
static rs_result ge_strokes(rs_ctx *ctx, const ge_src *src, const rs_roads *roads, const rs_network *net,
                            const rs_splat_options *o, rs_style *sty, double *soff, unsigned char *srev)
{
    size_t n = rs_roads_count(roads);
    for (size_t i = 0; i < n; i++) soff[i] = -1, srev[i] = 0;
    if (!net || n < 2) return RS_OK;
    uint32_t *recs = rs__alloc_array(ctx, n, sizeof *recs);
    if (!recs) return RS_ERR_NOMEM;
    rs_result r = RS_OK;
    size_t nk = rs_network_stroke_count(net);
    for (size_t k = 0; k < nk; k++) {
        size_t nrec = rs_network_stroke_roads(net, k, recs, n);
        if (nrec < 2 || nrec > n) continue;
        rs_road_stroke h, q;
        rs_network_road_stroke(net, recs[0], &h);
        int mixed = 0;
        for (size_t j = 1; j < nrec && !mixed; j++) {
            rs_network_road_stroke(net, recs[j], &q);
            mixed = q.reversed != h.reversed;
        }
        if (mixed) { /* every record drawn against another needs lines that look the same both ways */
            if ((r = ge_style(ctx, src, roads, recs[0], &o->style, sty)) != RS_OK) break;
            int alone = !ge_lines_mirror(sty);
            for (size_t j = 1; j < nrec && !alone && !r; j++) {
                rs_network_road_stroke(net, recs[j], &q);
                if (q.reversed == h.reversed) continue;
                if ((r = ge_style(ctx, src, roads, recs[j], &o->style, sty)) != RS_OK) break;
                alone = !ge_lines_mirror(sty);
            }
            if (r) break;
            if (alone) continue; /* drawn record by record */
        }
        for (size_t j = 0; j < nrec; j++) {
            rs_network_road_stroke(net, recs[j], &q);
            soff[recs[j]] = q.s_offset;
            srev[recs[j]] = (unsigned char)(q.reversed != 0);
        }
    }
    rs__free(ctx, recs);
    return r;
}

/* Joints the CPU draws as one line (lib/scene/linesym.c: a stroke's run of
 * records whose lines are alike is one polyline): record A's end meets
 * record C's start (both in their stroke's terms) at the same point, each
 * the other's continuation (road floats 5, 6), with equal bands. Their
 * segments there get RS_GPU_SEG_JOIN_LAST and RS_GPU_SEG_JOIN_FIRST: the
 * shader then cuts the lines at the joint's bisector and joins them round
 * outside, as at a vertex of one road, where it ended both square (a
 * wedge out of the outer lines, a spur of the inner ones past the mitre).
 * The partner's end segment is found through road float 39 (each road's
 * first segment), exact below 2^24 segments (the caller's condition). */
static void ge_joints(rs_gpu_scene *g, const ge_end *ends, size_t nends, const double *soff)
{
    for (size_t a = 0; a < nends; a++)
        for (size_t c = a + 1; c < nends && ends[c].x == ends[a].x && ends[c].y == ends[a].y; c++) {
            if (ends[a].end == ends[c].end || ends[a].road == ends[c].road) continue;
            const ge_end *A = ends[a].end ? &ends[a] : &ends[c], *C = ends[a].end ? &ends[c] : &ends[a];
            const float *ra = g->road + RS_GPU_ROAD_FLOATS * A->road, *rc = g->road + RS_GPU_ROAD_FLOATS * C->road;
            if (soff[A->road] < 0 || soff[C->road] < 0 || ra[6] != (float)C->road || rc[5] != (float)A->road ||
                ra[24] != rc[24] || ra[4] != rc[4] ||
                memcmp(g->band + RS_GPU_BAND_FLOATS * (size_t)ra[3], g->band + RS_GPU_BAND_FLOATS * (size_t)rc[3],
                       (size_t)ra[4] * RS_GPU_BAND_FLOATS * sizeof(float)))
                continue;
            size_t ka = (A->road + 1 < g->nroads ? (size_t)ra[RS_GPU_ROAD_FLOATS + 39] : g->nseg), kc = (size_t)rc[39];
            size_t kc_end = C->road + 1 < g->nroads ? (size_t)rc[RS_GPU_ROAD_FLOATS + 39] : g->nseg;
            if (ka == (size_t)ra[39] || kc == kc_end) continue; /* no segment on the map */
            float *sa = g->seg + RS_GPU_SEG_FLOATS * (ka - 1), *sc = g->seg + RS_GPU_SEG_FLOATS * kc;
            /* both ends where the records meet (not cut off far from the map) */
            if (!((uint32_t)sa[7] & RS_GPU_SEG_LAST) || !((uint32_t)sc[7] & RS_GPU_SEG_FIRST) || sa[2] != sc[0] ||
                sa[3] != sc[1])
                continue;
            /* the bisector's normal (the shader's sum): none at a reversal */
            float mx = sa[10] + sc[10], my = sa[11] + sc[11];
            if (!(mx * mx + my * my > 1e-6f)) continue;
            sa[7] = (float)((uint32_t)sa[7] | RS_GPU_SEG_JOIN_LAST);
            sc[7] = (float)((uint32_t)sc[7] | RS_GPU_SEG_JOIN_FIRST);
        }
}

/* The T rule of lib/scene/linesym.c for the shader (docs/render.md): per road its
 * stroke, the through stroke each end meets at a T and how deep its end
 * keeps cutting there, and whether some road end meets its own stroke so. */
static rs_result ge_tees(rs_ctx *ctx, const rs_roads *roads, const rs_network *net, rs_gpu_scene *g,
                         const unsigned char *srev)
{
    size_t n = g->nroads;
    for (size_t i = 0; i < n; i++) {
        float *rd = g->road + RS_GPU_ROAD_FLOATS * i;
        rd[24] = rd[25] = rd[26] = -1;
        rd[27] = rd[28] = rd[29] = 0;
    }
    if (!net) return RS_OK;
    rs__tee *T = NULL;
    rs_result r = rs__network_tees(ctx, roads, net, &T);
    if (r || !T) return r;
    size_t nk = rs_network_stroke_count(net);
    unsigned char *met = rs__calloc(ctx, nk ? nk : 1, 1); /* per stroke: some road end meets it at a T */
    if (!met) { rs__free(ctx, T); return RS_ERR_NOMEM; }
    for (size_t i = 0; i < n; i++) {
        rs_road_stroke k;
        rs_network_road_stroke(net, i, &k);
        g->road[RS_GPU_ROAD_FLOATS * i + 24] = (float)k.stroke;
    }
    for (size_t i = 0; i < n; i++)
        for (int e = 0; e < 2; e++) {
            const rs__tee *t = &T[2 * i + e];
            if (t->stroke == RS__NO_STROKE) continue;
            /* the exported start is the record's end when it runs against its stroke */
            int ge = srev[i] ? !e : e;
            float *rd = g->road + RS_GPU_ROAD_FLOATS * i;
            rd[25 + ge] = (float)t->stroke;
            rd[27 + ge] = ge_float(t->keep + t->off); /* (the depth the cut stops short of the end: the T rule) */
            if (t->stroke < nk) met[t->stroke] = 1;
        }
    for (size_t i = 0; i < n; i++) {
        float *rd = g->road + RS_GPU_ROAD_FLOATS * i;
        if (rd[24] >= 0 && (size_t)rd[24] < nk && met[(size_t)rd[24]]) rd[29] = 1;
    }
    rs__free(ctx, met);
    rs__free(ctx, T);
    return RS_OK;
}

/* The clip lines of a record's trimmed T ends (lib/scene/roadfield.c, the same
 * rule): per exported end (the record's last point first when it runs
 * against its stroke) n and c of n.p <= c, the end point's n plus the
 * through road's half width, in floats 32..37; float 38: how far the
 * trimmed strip (and casing) reaches beyond the capsule, for the index. */
static void ge_tee_clips(float *rd, const rs__road_local *rl, const rs__tee_end *tees, const size_t *tix, double hw,
                         double casing, int rev)
{
    size_t m = rl->n;
    if (m < 2 || !(hw > 0)) return;
    for (int e = 0; e < 2; e++) {
        if (tix[e] == SIZE_MAX) continue;
        const rs__tee_end *t = &tees[tix[e]];
        size_t a = e ? m - 1 : 0, b = e ? m - 2 : 1;
        double dx = rl->x[a] - rl->x[b], dy = rl->y[a] - rl->y[b], l = hypot(dx, dy);
        double sn = (t->nx * dx + t->ny * dy) / l, cs = fabs(t->nx * dy - t->ny * dx) / l;
        if (!(sn > 0.1)) continue;
        /* a record whose capsules (casing included) all stay short of the
         * line keeps its round cap, as the CPU's field does
         * (tee_end_unchanged): where the through street bends, the flat
         * strip run on to the line (parallel to the street's chord) reached
         * up to 1.2 m past its far edge on the outer side */
        double cl = t->nx * rl->x[a] + t->ny * rl->y[a] + t->far, reach = -INFINITY;
        for (size_t k = 0; k < m; k++) reach = fmax(reach, t->nx * rl->x[k] + t->ny * rl->y[k]);
        if (reach + hw + casing <= cl) continue;
        int ge = rev ? !e : e;
        rd[32 + 3 * ge] = (float)t->nx;
        rd[33 + 3 * ge] = (float)t->ny;
        rd[34 + 3 * ge] = ge_float(cl);
        for (int k = 0; k < 2; k++) {
            double r = hw + (k ? casing : 0), ub = (t->far + r * cs) / sn;
            rd[38] = fmaxf(rd[38], ge_float(hypot(ub, r) - r));
        }
    }
}

/* A record's local points in the stroke's terms (see ge_strokes). */
static void ge_local_to_stroke(rs__road_local *rl, double off, int rev)
{
    size_t m = rl->n;
    for (size_t j = 0; rev && j < m / 2; j++) {
        double t;
        t = rl->x[j], rl->x[j] = rl->x[m - 1 - j], rl->x[m - 1 - j] = t;
        t = rl->y[j], rl->y[j] = rl->y[m - 1 - j], rl->y[m - 1 - j] = t;
        t = rl->s[j], rl->s[j] = rl->s[m - 1 - j], rl->s[m - 1 - j] = t;
    }
    for (size_t j = 0; j < m; j++) rl->s[j] = rev ? off - rl->s[j] : off + rl->s[j];
}

void rs_gpu_scene_free(rs_ctx *ctx, rs_gpu_scene *g)
{
    if (!g) return;
    rs__free(ctx, g->seg);
    rs__free(ctx, g->road);
    rs__free(ctx, g->band);
    rs__free(ctx, g->mark);
    rs__free(ctx, g->cell_start);
    rs__free(ctx, g->cell_seg);
    rs__free(ctx, g->mark_start);
    rs__free(ctx, g->mark_ids);
    rs__free(ctx, g->types);
    rs__free(ctx, g->levels);
    rs__free(ctx, g->atlas_px);
    rs__free(ctx, g->cut);
    rs__free(ctx, g->mark_levels);
    rs__free(ctx, g->mark_sat);
    rs__free(ctx, g);
}

static void put_colour(float *dst, rs_colour c)
{
    dst[0] = c.r;
    dst[1] = c.g;
    dst[2] = c.b;
    dst[3] = (float)c.a / 255.0f;
}

/* Cells [i0, i1] x [j0, j1] of the grid touched by a box, clamped (a NaN
 * or infinite bound clamps to the grid's edge). */
static void box_cells(const rs_gpu_scene *g, double xa, double ya, double xb, double yb, uint32_t *i0, uint32_t *j0,
                      uint32_t *i1, uint32_t *j1)
{
    double v[4] = { floor((xa - g->x0) / g->cell), floor((ya - g->y0) / g->cell), floor((xb - g->x0) / g->cell),
                    floor((yb - g->y0) / g->cell) };
    uint32_t u[4];
    for (int k = 0; k < 4; k++) {
        double hi = (k & 1) ? g->gh - 1 : g->gw - 1;
        u[k] = v[k] >= 0 ? (v[k] <= hi ? (uint32_t)v[k] : (uint32_t)hi) : 0;
    }
    *i0 = u[0]; *j0 = u[1]; *i1 = u[2]; *j1 = u[3];
}

/* Whether point (x, y) is within r of segment a-b: hypot(e) <= r for e
 * from the point to its nearest point of the segment. The squares decide
 * unless they are within a 1e-9 fraction of each other (far more than
 * their rounding), where hypot decides: the same answers as hypot alone,
 * at a fraction of its cost (the index fill asks this of every cell near
 * every segment: it was two thirds of the export). */
static int seg_within(double ax, double ay, double bx, double by, double x, double y, double r)
{
    double dx = bx - ax, dy = by - ay, l2 = dx * dx + dy * dy, u = 0;
    if (l2 > 0) {
        u = ((x - ax) * dx + (y - ay) * dy) / l2;
        u = u < 0 ? 0 : u > 1 ? 1 : u;
    }
    double ex = x - ax - u * dx, ey = y - ay - u * dy, e2 = ex * ex + ey * ey, r2 = r * r;
    if (e2 < r2 * (1 - 1e-9)) return 1;
    if (e2 > r2 * (1 + 1e-9)) return 0;
    return hypot(ex, ey) <= r;
}

/* The items an index grid lists: segments (listed in every cell whose
 * square comes within R of the stored float segment: centre distance <=
 * R + half diagonal) or markings' support boxes (every cell the box
 * touches). The count and the fill pass ask these two functions, with the
 * same stored numbers, so they cannot disagree on a cell. */
typedef struct ge_items {
    const float *seg;   /* segments, or NULL */
    const double *box;  /* or boxes: x0, y0, x1, y1 per item */
    size_t n;
} ge_items;

static double item_reach(const rs_gpu_scene *g, const float *s)
{
    const float *rd = g->road + RS_GPU_ROAD_FLOATS * (size_t)s[6];
    return (double)s[4] + rd[2] + rd[38] + g->reach;
}

static void item_cells(const rs_gpu_scene *g, const ge_items *it, size_t k, uint32_t b[4])
{
    if (it->seg) {
        const float *s = it->seg + RS_GPU_SEG_FLOATS * k;
        double R = item_reach(g, s);
        box_cells(g, fmin(s[0], s[2]) - R, fmin(s[1], s[3]) - R, fmax(s[0], s[2]) + R, fmax(s[1], s[3]) + R, &b[0],
                  &b[1], &b[2], &b[3]);
    } else {
        const double *bb = it->box + 4 * k;
        box_cells(g, bb[0], bb[1], bb[2], bb[3], &b[0], &b[1], &b[2], &b[3]);
    }
}

static int item_in_cell(const rs_gpu_scene *g, const ge_items *it, size_t k, uint32_t i, uint32_t j)
{
    if (!it->seg) return 1;
    const float *s = it->seg + RS_GPU_SEG_FLOATS * k;
    double cx = g->x0 + (i + 0.5) * g->cell, cy = g->y0 + (j + 0.5) * g->cell;
    return seg_within(s[0], s[1], s[2], s[3], cx, cy, item_reach(g, s) + g->cell * 0.70710678118654752440);
}

#define GE_MAX_ENTRIES ((size_t)1 << 28)

/* An index grid over the items: *start (gw*gh + 1 offsets) and *ids (the
 * items per cell, ascending). Counted, then filled, by the same two
 * functions; a fill that would leave its cell's range is not written, and
 * the ranges must come out exactly full. */
static rs_result index_build(rs_ctx *ctx, const rs_gpu_scene *g, const ge_items *it, const char *what,
                             uint32_t **start_out, uint32_t **ids_out, size_t *nentries)
{
    const size_t ncell = (size_t)g->gw * g->gh;
    uint32_t *start = rs__calloc(ctx, ncell + 1, sizeof *start), *ids = NULL, *pos = NULL;
    if (!start) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the GPU export");
    size_t total = 0;
    for (size_t k = 0; k < it->n; k++) {
        if ((k & 1023) == 1023 && rs__poll(ctx)) {
            rs__free(ctx, start);
            return RS_ERR_CANCELLED;
        }
        uint32_t b[4];
        item_cells(g, it, k, b);
        for (uint32_t j = b[1]; j <= b[3]; j++)
            for (uint32_t i = b[0]; i <= b[2]; i++)
                if (item_in_cell(g, it, k, i, j)) {
                    start[(size_t)j * g->gw + i + 1]++;
                    if (++total > GE_MAX_ENTRIES) {
                        rs__free(ctx, start);
                        return rs__fail(ctx, RS_ERR_LIMIT, "GPU export: the %s index needs more than 2^28 entries",
                                        what);
                    }
                }
    }
    for (size_t c = 0; c < ncell; c++) start[c + 1] += start[c];
    ids = rs__alloc_array(ctx, total ? total : 1, sizeof *ids);
    pos = rs__alloc_array(ctx, ncell, sizeof *pos);
    if (!ids || !pos) {
        rs__free(ctx, start);
        rs__free(ctx, ids);
        rs__free(ctx, pos);
        return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the GPU export");
    }
    memcpy(pos, start, ncell * sizeof *pos);
    int full = 1;
    for (size_t k = 0; k < it->n; k++) {
        if ((k & 1023) == 1023 && rs__poll(ctx)) {
            rs__free(ctx, start);
            rs__free(ctx, ids);
            rs__free(ctx, pos);
            return RS_ERR_CANCELLED;
        }
        uint32_t b[4];
        item_cells(g, it, k, b);
        for (uint32_t j = b[1]; j <= b[3]; j++)
            for (uint32_t i = b[0]; i <= b[2]; i++) {
                size_t c = (size_t)j * g->gw + i;
                if (!item_in_cell(g, it, k, i, j)) continue;
                if (pos[c] < start[c + 1]) ids[pos[c]++] = (uint32_t)k;
                else full = 0;
            }
    }
    for (size_t c = 0; c < ncell; c++) full &= pos[c] == start[c + 1];
    rs__free(ctx, pos);
    if (!full) { /* cannot happen: both passes ask the same functions */
        rs__free(ctx, start);
        rs__free(ctx, ids);
        return rs__fail(ctx, RS_ERR_LIMIT, "GPU export: the %s index came out inconsistent", what);
    }
    *start_out = start;
    *ids_out = ids;
    *nentries = total;
    return RS_OK;
}

/* The segments of road i as the GPU draws them, appended to g->seg: one per
 * pair of consecutive points of the road in the local frame once repeated
 * points are dropped in double precision (the points the lines and the
 * markings use, rs__road_local_get), so whether a segment exists never
 * depends on what float makes of its ends; a road of one point is one
 * segment of length 0. Lengths, directions and s come from the doubles.
 * A segment reaching beyond a map size (plus its reach `pad`) from the map
 * is cut to the disc around the map it can touch (rs__clip_far, as the
 * road field cuts), or left out when it cannot reach the map, so every
 * stored coordinate is a float near the map; the flags stay those of the
 * road's ends. */
static rs_result road_segments(rs_ctx *ctx, rs_gpu_scene *g, const rs__road_local *rl, size_t i, double hw,
                               double casing, double pad, size_t *cap)
{
    size_t m = rl->n;
    for (size_t p = 0; p + 1 < m || (m == 1 && p == 0); p++) {
        size_t q = p + 1 < m ? p + 1 : p;
        double ax = rl->x[p], ay = rl->y[p], bx = rl->x[q], by = rl->y[q], along = 0;
        if (!rs__clip_far(&ax, &ay, &bx, &by, g->map_w, g->map_h, pad, g->map_w + g->map_h + 2 * pad, &along))
            continue;
        if (g->nseg == *cap) {
            size_t nc = *cap ? 2 * *cap : 64, bytes;
            if (!rs__mul_size(nc, RS_GPU_SEG_FLOATS * sizeof(float), &bytes)) return RS_ERR_NOMEM;
            float *ns = rs__realloc(ctx, g->seg, bytes);
            if (!ns) return RS_ERR_NOMEM;
            g->seg = ns;
            *cap = nc;
        }
        float *sg = g->seg + RS_GPU_SEG_FLOATS * g->nseg++;
        double len = hypot(bx - ax, by - ay);
        sg[0] = ge_float(ax); sg[1] = ge_float(ay); sg[2] = ge_float(bx); sg[3] = ge_float(by);
        sg[4] = ge_float(hw);
        sg[5] = ge_float(rl->s[p] + along);
        sg[6] = (float)i;
        sg[7] = (float)((p == 0 ? RS_GPU_SEG_FIRST : 0) | (q + 1 >= m ? RS_GPU_SEG_LAST : 0));
        sg[8] = ge_float(casing);
        sg[9] = ge_float(len);
        sg[10] = len > 0 ? (float)((bx - ax) / len) : 1.0f;
        sg[11] = len > 0 ? (float)((by - ay) / len) : 0.0f;
    }
    return RS_OK;
}

/* Placements as the road grid makes them (lib/scene/markings.c): the explicit
 * records, then the automatic rules. */
/* cuts: where also the line cuts are wanted (*cuts NULL, *have 0 when the
 * rules did not run: rs__markings_line_cuts then finds none or runs them) */
static rs_result placements(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                            const rs_atlas *atlas, const rs_network *net, rs__placement **pl, size_t *npl,
                            rs__line_cut **cuts, size_t *ncut, int *have)
{
    size_t cap = 0;
    *pl = NULL;
    *npl = 0;
    rs_result r = rs__markings_explicit(ctx, roads, atlas, pl, npl, &cap);
    if (r) return r;
    if (o->markings.no_auto || !rs__markings_auto_possible(roads)) return RS_OK;
    if (!cuts) return rs__markings_auto(ctx, dem, roads, atlas, &o->style, net, pl, npl, &cap);
    r = rs__markings_auto_cuts(ctx, dem, roads, atlas, &o->style, net, pl, npl, &cap, cuts, ncut);
    *have = r == RS_OK;
    return r;
}

static rs_result ge_mark_tables(rs_ctx *ctx, rs_gpu_scene *g);

/* The export of either entry point: o are the options the styles and
 * markings follow (the grid's own with src.grid). */
static rs_result ge_export(rs_ctx *ctx, ge_src src, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *opts,
                           const rs_gpu_options *gopts, rs_gpu_scene **out)
{
    rs_splat_options o;
    rs_result ro = RS__OPTS_IN(ctx, opts, &o, rs_splat_options);
    if (ro) return ro;
    rs_gpu_options go;
    if ((ro = RS__OPTS_IN(ctx, gopts, &go, rs_gpu_options)) != RS_OK) return ro;
    if (!(go.cell >= 0 && go.cell <= 1e9) || !(go.reach >= 0 && go.reach <= 1e9))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_gpu_options: cell and reach must be 0..1e9 metres");

    rs_gpu_scene *g = rs__calloc(ctx, 1, sizeof *g);
    if (!g) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the GPU export");
    rs_result r = RS_OK;
    rs_style *sty = NULL;
    rs_atlas *atlas_own = NULL;
    rs__placement *pl = NULL;
    rs__line_cut *auto_cuts = NULL; /* the line cuts of the placements' run of the rules (have_cuts) */
    size_t auto_ncut = 0;
    int have_cuts = 0;
    ge_end *ends = NULL;
    double *soff = NULL;
    unsigned char *srev = NULL;
    rs_network *net = NULL;
    rs__tee_end *tees = NULL;
    size_t ntees = 0, *tee_of = NULL;
    const double cs = dem->frame.cell_size;
    g->map_w = (double)(dem->width - 1) * cs;
    g->map_h = (double)(dem->height - 1) * cs;
    double cell = go.cell > 0 ? go.cell : cs;
    {
        double ext_w = g->map_w + 2 * cell, ext_h = g->map_h + 2 * cell;
        while ((ext_w / cell + 1) * (ext_h / cell + 1) > GE_MAX_CELLS) {
            cell *= 1.5;
            ext_w = g->map_w + 2 * cell;
            ext_h = g->map_h + 2 * cell;
        }
    }
    g->cell = cell;
    g->reach = go.reach > 0 ? go.reach : 0.5 * cell;
    g->x0 = -cell;
    g->y0 = -cell;
    g->gw = (uint32_t)ceil(g->map_w / cell) + 2;
    g->gh = (uint32_t)ceil(g->map_h / cell) + 2;
    const size_t ncell = (size_t)g->gw * g->gh;

    /* roads: styles and segments */
    const size_t n = rs_roads_count(roads);
    if (n >= ((size_t)1 << 24)) { /* road indices travel as floats */
        r = rs__fail(ctx, RS_ERR_LIMIT, "GPU export: %zu roads (at most 2^24 - 1)", n);
        goto fail_msg;
    }
    g->nroads = n;
    sty = rs__malloc(ctx, sizeof *sty);
    g->road = rs__calloc(ctx, n ? n : 1, RS_GPU_ROAD_FLOATS * sizeof(float));
    if (!sty || !g->road) { r = RS_ERR_NOMEM; goto fail; }
    size_t nbands = 0, segcap = 0, nseg = 0;
    for (size_t i = 0; i < n; i++) {
        if (o.style.disable) continue;
        if ((i & 63) == 63 && rs__poll(ctx)) { r = RS_ERR_CANCELLED; goto fail_msg; }
        if ((r = ge_style(ctx, &src, roads, i, &o.style, sty)) != RS_OK) goto fail_msg;
        nbands += sty->line_count;
    }
    g->band = rs__calloc(ctx, nbands ? nbands : 1, RS_GPU_BAND_FLOATS * sizeof(float));
    ends = rs__alloc_array(ctx, 2 * (n ? n : 1), sizeof *ends);
    soff = rs__alloc_array(ctx, n ? n : 1, sizeof *soff);
    srev = rs__alloc_array(ctx, n ? n : 1, sizeof *srev);
    if (!g->band || !ends || !soff || !srev) { r = RS_ERR_NOMEM; goto fail; }
    if (!o.style.disable && n > 0 && (r = rs_network_build(ctx, roads, NULL, &net)) != RS_OK) goto fail_msg;
    if ((r = ge_strokes(ctx, &src, roads, net, &o, sty, soff, srev)) != RS_OK) goto fail_msg;
    /* record ends at a T: trimmed as the road field trims them */
    if ((r = rs__tee_ends(ctx, roads, net, &tees, &ntees)) != RS_OK) goto fail;
    if (ntees && !(tee_of = rs__alloc_array(ctx, 2 * n, sizeof *tee_of))) { r = RS_ERR_NOMEM; goto fail; }
    for (size_t i = 0; tee_of && i < 2 * n; i++) tee_of[i] = SIZE_MAX;
    for (size_t i = 0; i < ntees; i++) tee_of[2 * (size_t)tees[i].road + (tees[i].end != 0)] = i;
    size_t nends = 0;
    for (size_t i = 0, b = 0; i < n; i++) {
        if ((i & 63) == 63 && rs__poll(ctx)) { r = RS_ERR_CANCELLED; goto fail_msg; }
        float *rd = g->road + RS_GPU_ROAD_FLOATS * i;
        double w = 0;
        rs_roads_get(roads, i, NULL, &w, NULL, NULL);
        /* wider than 2e15 m covers any map; the cap keeps it a float */
        double hw = fmin(0.5 * w, 1e15);
        memset(sty, 0, sizeof *sty);
        if (!o.style.disable && (r = ge_style(ctx, &src, roads, i, &o.style, sty)) != RS_OK)
            goto fail_msg;
        rd[0] = (float)sty->surface;
        rd[1] = ge_float(hw);
        rd[2] = ge_float(sty->casing_width);
        rd[3] = (float)b;
        rd[4] = (float)sty->line_count;
        rd[5] = rd[6] = -1;
        put_colour(rd + 8, sty->surface == RS_SURFACE_GRADIENT ? sty->gradient_centre : sty->fill);
        put_colour(rd + 12, sty->gradient_centre);
        put_colour(rd + 16, sty->gradient_edge);
        put_colour(rd + 20, sty->casing);
        double lines_reach = 0;
        for (uint32_t j = 0; j < sty->line_count; j++, b++) {
            const rs_style_line *ln = &sty->line[j];
            float *bd = g->band + RS_GPU_BAND_FLOATS * b;
            double period = 0;
            for (uint32_t d = 0; d < ln->dash_count; d++) period += ln->dash[d];
            bd[0] = (float)ln->offset;
            bd[1] = (float)ln->width;
            bd[2] = (float)ln->phase;
            bd[3] = (float)period;
            put_colour(bd + 4, ln->colour);
            lines_reach = fmax(lines_reach, fabs(ln->offset) + 0.5 * ln->width);
            bd[8] = (float)ln->dash_count;
            for (uint32_t d = 0; d < ln->dash_count && d < 8; d++) bd[12 + d] = (float)ln->dash[d];
        }
        rd[7] = ge_float(lines_reach);
        /* the fill's rank, level then priority (lib/scene/styling.c: -1e9 for all when all are equal) */
        rd[30] = (float)rs__road_rank(roads, i);
        /* a car road: a path, footway or cycleway cuts none of its lines (lib/scene/linesym.c) */
        rd[31] = rs__road_non_car(roads, i) ? 0.0f : 1.0f;
        rs__road_local rl;
        if (rs__road_local_get(ctx, roads, i, dem, &rl)) { r = RS_ERR_NOMEM; goto fail; }
        if (tee_of) ge_tee_clips(rd, &rl, tees, tee_of + 2 * i, hw, sty->casing_width, srev[i]);
        if (soff[i] >= 0) ge_local_to_stroke(&rl, soff[i], srev[i]);
        double pad = 2 * (hw + sty->casing_width + lines_reach + g->reach) + g->cell;
        size_t seg0 = g->nseg;
        rd[39] = (float)seg0; /* exact below 2^24 segments (the joints below need it) */
        r = road_segments(ctx, g, &rl, i, hw, sty->casing_width, pad, &segcap);
        /* a ring of one record (its stroke closed, its last point its
         * first): its lines do not end at its seam, as the CPU's line
         * symbols join it there (lib/scene/linesym.c road_band_pieces);
         * the shader's nearest segment of the road then joins it as at any
         * vertex (round outside, mitred inside). Rings of several records
         * keep their square ends at the seam and at their joints here. */
        if (!r && net && rs_network_road_count(net) == n && rl.n >= 4 && rl.x[0] == rl.x[rl.n - 1] &&
            rl.y[0] == rl.y[rl.n - 1] && net->closed[net->stroke_of[i]] &&
            net->stroke_start[net->stroke_of[i] + 1] - net->stroke_start[net->stroke_of[i]] == 1)
            for (size_t k = seg0; k < g->nseg; k++) {
                float *sg = g->seg + RS_GPU_SEG_FLOATS * k;
                sg[7] = (float)((uint32_t)sg[7] & ~(RS_GPU_SEG_FIRST | RS_GPU_SEG_LAST));
            }
        /* a segment reaching past a trimmed end's line is clipped by it (the road field's rule) */
        for (size_t k = seg0; !r && k < g->nseg; k++)
            for (int e = 0; e < 2; e++) {
                float *sg = g->seg + RS_GPU_SEG_FLOATS * k;
                const float *c = rd + 32 + 3 * e;
                if (c[0] == 0 && c[1] == 0) continue;
                double fa = (double)c[0] * sg[0] + (double)c[1] * sg[1], fb = (double)c[0] * sg[2] + (double)c[1] * sg[3];
                if (fmax(fa, fb) + hw + sty->casing_width > c[2]) sg[7] = (float)((uint32_t)sg[7] | RS_GPU_SEG_CLIP);
            }
        size_t m = rl.n;
        if (!r && m >= 2) {
            for (int e = 0; e < 2; e++) {
                size_t a = e ? m - 1 : 0, c = e ? m - 2 : 1;
                double dx = rl.x[c] - rl.x[a], dy = rl.y[c] - rl.y[a], l = hypot(dx, dy);
                ge_end *E = &ends[nends++];
                E->x = rl.x[a]; E->y = rl.y[a];
                E->dx = dx / l; E->dy = dy / l;
                E->road = (uint32_t)i;
                E->end = e;
            }
        }
        rs__road_local_free(ctx, &rl);
        if (r) goto fail;
    }
    {
        /* equal priorities: the fill takes the nearest road, as the CPU's
         * lookups without priorities */
        int differ = 0;
        for (size_t i = 1; i < n && !differ; i++) differ = g->road[RS_GPU_ROAD_FLOATS * i + 30] != g->road[30];
        for (size_t i = 0; i < n && !differ; i++) g->road[RS_GPU_ROAD_FLOATS * i + 30] = -1e9f;
    }
    if (!g->seg && !(g->seg = rs__calloc(ctx, 1, RS_GPU_SEG_FLOATS * sizeof(float)))) { r = RS_ERR_NOMEM; goto fail; }
    nseg = g->nseg;
    g->nbands = nbands;
    if (rs__poll(ctx)) { r = RS_ERR_CANCELLED; goto fail_msg; }
    if ((r = ge_tees(ctx, roads, net, g, srev)) != RS_OK) goto fail;
    if (rs__poll(ctx)) { r = RS_ERR_CANCELLED; goto fail_msg; }
    /* continuations: equal end points, leaving within 30 degrees of opposite */
    if ((r = rs__sort(ctx, ends, nends, sizeof *ends, ge_end_cmp)) != RS_OK) goto fail;
    for (size_t a = 0; a < nends; a++)
        for (size_t c = a + 1; c < nends && ends[c].x == ends[a].x && ends[c].y == ends[a].y; c++) {
            const ge_end *A = &ends[a], *C = &ends[c];
            if (A->road == C->road || A->dx * C->dx + A->dy * C->dy >= -GE_COS30) continue;
            float *ra = g->road + RS_GPU_ROAD_FLOATS * A->road + 5 + A->end;
            float *rc = g->road + RS_GPU_ROAD_FLOATS * C->road + 5 + C->end;
            if (*ra < 0) *ra = (float)C->road;
            if (*rc < 0) *rc = (float)A->road;
        }
    if (nseg < ((size_t)1 << 24)) ge_joints(g, ends, nends, soff);

    /* the segment index */
    {
        ge_items it = { g->seg, NULL, nseg };
        if ((r = index_build(ctx, g, &it, "segment", &g->cell_start, &g->cell_seg, &g->nseg_entries)) != RS_OK)
            goto fail_msg;
    }

    /* markings and the atlas */
    if (!o.markings.disable &&
        (rs_roads_mark_count(roads) || (!o.markings.no_auto && rs__markings_auto_possible(roads)))) {
        const rs_atlas *atlas = o.markings.atlas;
        const rs__markings *kept = src.grid ? src.grid->markings : NULL;
        if (!atlas && kept) atlas = kept->atlas_own;
        if (!atlas) {
            if ((r = rs_atlas_default(ctx, &atlas_own)) != RS_OK) goto fail_msg;
            atlas = atlas_own;
        }
        size_t npl = 0;
        if (kept) { /* the grid's placements (a copy: turned into the strokes' terms below) */
            npl = kept->npl;
            if (!(pl = rs__alloc_array(ctx, npl ? npl : 1, sizeof *pl))) { r = RS_ERR_NOMEM; goto fail; }
            if (npl) memcpy(pl, kept->pl, npl * sizeof *pl);
        } else {
            /* the line cuts from the same run of the rules when the styles
             * take them below (one run instead of two: ~2 s at 10^5 roads) */
            int cuts_below = !o.style.disable && !(src.grid && src.grid->styling && src.grid->styling->lines);
            if ((r = placements(ctx, dem, roads, &o, atlas, net, &pl, &npl, cuts_below ? &auto_cuts : NULL,
                                &auto_ncut, &have_cuts)) != RS_OK)
                goto fail_msg;
        }
        g->mark = rs__calloc(ctx, npl ? npl : 1, RS_GPU_MARK_FLOATS * sizeof(float));
        g->ntypes = atlas->n;
        g->types = rs__calloc(ctx, atlas->n ? atlas->n : 1, RS_GPU_TYPE_INTS * sizeof(uint32_t));
        if (!g->mark || !g->types) { r = RS_ERR_NOMEM; goto fail; }
        size_t nlev = 0, ntex = 0;
        for (size_t t = 0; t < atlas->n; t++) {
            if (atlas->t[t].shared) continue; /* the same rectangle as an earlier type: its levels */
            nlev += atlas->t[t].nlev;
            for (uint32_t l = 0; l < atlas->t[t].nlev; l++) ntex += (size_t)atlas->t[t].lev[l].w * atlas->t[t].lev[l].h;
        }
        g->levels = rs__calloc(ctx, nlev ? nlev : 1, RS_GPU_LEVEL_INTS * sizeof(uint32_t));
        g->atlas_px = rs__alloc_array(ctx, ntex ? ntex : 1, 4 * sizeof(float));
        if (!g->levels || !g->atlas_px) { r = RS_ERR_NOMEM; goto fail; }
        for (size_t t = 0, li = 0, tx = 0; t < atlas->n; t++) {
            const rs__atlas_type *ty = &atlas->t[t];
            if (ty->shared) {
                size_t own = 0;
                while (atlas->t[own].shared || atlas->t[own].lev[0].px != ty->lev[0].px) own++;
                memcpy(g->types + RS_GPU_TYPE_INTS * t, g->types + RS_GPU_TYPE_INTS * own,
                       RS_GPU_TYPE_INTS * sizeof *g->types);
                continue;
            }
            g->types[RS_GPU_TYPE_INTS * t] = (uint32_t)li;
            g->types[RS_GPU_TYPE_INTS * t + 1] = ty->nlev;
            for (uint32_t l = 0; l < ty->nlev; l++, li++) {
                size_t cnt = (size_t)ty->lev[l].w * ty->lev[l].h;
                uint32_t *L = g->levels + RS_GPU_LEVEL_INTS * li;
                L[0] = (uint32_t)tx; L[1] = ty->lev[l].w; L[2] = ty->lev[l].h;
                memcpy(g->atlas_px + 4 * tx, ty->lev[l].px, cnt * 4 * sizeof(float));
                tx += cnt;
            }
        }
        g->nlevels = nlev;
        g->atlas_texels = ntex;
        /* records; support boxes from the road's segments over the s range */
        size_t *first_seg = rs__alloc_array(ctx, n + 1, sizeof *first_seg);
        if (!first_seg) { r = RS_ERR_NOMEM; goto fail; }
        for (size_t k = 0, i = 0; i <= n; i++) {
            while (k < nseg && (size_t)g->seg[RS_GPU_SEG_FLOATS * k + 6] < i) k++;
            first_seg[i] = k;
        }
        double *box = rs__alloc_array(ctx, npl ? npl : 1, 4 * sizeof *box);
        if (!box) { rs__free(ctx, first_seg); r = RS_ERR_NOMEM; goto fail; }
        uint32_t net_one;
        size_t nm = 0;
        for (size_t i = 0; i < npl; i++) { /* in the segments' terms (ge_strokes) */
            if ((i & 1023) == 1023 && rs__poll(ctx)) { /* (each walks its stroke's segments) */
                rs__free(ctx, first_seg);
                rs__free(ctx, box);
                r = RS_ERR_CANCELLED;
                goto fail_msg;
            }
            rs__placement *p = &pl[i];
            if (soff[p->road] >= 0) {
                int rev = srev[p->road];
                p->s = rev ? soff[p->road] - p->s : soff[p->road] + p->s;
                if (rev) p->t = -p->t, p->flip = !p->flip;
            }
            const rs__atlas_type *ty = &atlas->t[p->type];
            float *mk = g->mark + RS_GPU_MARK_FLOATS * nm;
            double hl = 0.5 * p->length, hw = 0.5 * p->width, kx = ty->lev[0].w / p->width, ky = ty->lev[0].h / p->length;
            /* the filter reaches half a coarse texel past the rectangle: at a
             * footprint up to `reach`, at most reach + a level-0 texel */
            double pad = 2.0 * g->reach + 2.0 / fmin(kx, ky);
            double slo = p->s - hl - pad, shi = p->s + hl + pad, grow = fabs(p->t) + hw + pad;
            double bx0 = HUGE_VAL, by0 = HUGE_VAL, bx1 = -HUGE_VAL, by1 = -HUGE_VAL;
            /* a record in its stroke's terms: the marking follows the
             * stroke's segments past the record's ends, as the CPU paints it
             * along the records that go on there (lib/scene/markings.c) */
            const uint32_t *recs = &net_one;
            size_t nrec = 1;
            int stroke = -1;
            net_one = (uint32_t)p->road;
            if (soff[p->road] >= 0 && net) {
                uint32_t k = net->stroke_of[p->road];
                recs = net->stroke_roads + net->stroke_start[k];
                nrec = net->stroke_start[k + 1] - net->stroke_start[k];
                stroke = (int)k;
            }
            for (size_t q = 0; q < nrec; q++)
            for (size_t k = first_seg[recs[q]]; k < first_seg[recs[q] + 1]; k++) {
                const float *s = g->seg + RS_GPU_SEG_FLOATS * k;
                double len = hypot((double)s[2] - s[0], (double)s[3] - s[1]);
                int firstseg = q == 0 && k == first_seg[recs[q]], lastseg = q + 1 == nrec && k + 1 == first_seg[recs[q] + 1];
                if (stroke >= 0 && net->closed[stroke]) firstseg = lastseg = 0;
                if (!((s[5] + len >= slo || lastseg) && (s[5] <= shi || firstseg))) continue;
                bx0 = fmin(bx0, fmin(s[0], s[2])); bx1 = fmax(bx1, fmax(s[0], s[2]));
                by0 = fmin(by0, fmin(s[1], s[3])); by1 = fmax(by1, fmax(s[1], s[3]));
                /* the first and last segments extend past the road's ends */
                if ((firstseg && slo < s[5]) || (lastseg && shi > s[5] + len)) {
                    double ux = len > 0 ? (s[2] - s[0]) / len : 0, uy = len > 0 ? (s[3] - s[1]) / len : 0;
                    double ex = firstseg && slo < s[5] ? s[0] + ux * (slo - s[5]) : s[2] + ux * (shi - s[5] - len);
                    double ey = firstseg && slo < s[5] ? s[1] + uy * (slo - s[5]) : s[3] + uy * (shi - s[5] - len);
                    bx0 = fmin(bx0, ex); bx1 = fmax(bx1, ex); by0 = fmin(by0, ey); by1 = fmax(by1, ey);
                }
            }
            if (!(bx0 <= bx1)) continue; /* no road there */
            double *bb = box + 4 * nm;
            bb[0] = bx0 - grow; bb[1] = by0 - grow; bb[2] = bx1 + grow; bb[3] = by1 + grow;
            mk[0] = (float)p->road; mk[1] = (float)p->type;
            mk[2] = ge_float(p->s); mk[3] = ge_float(p->t);
            mk[4] = ge_float(hl); mk[5] = ge_float(hw);
            mk[6] = p->flip ? 1.0f : 0.0f;
            mk[7] = ge_float(kx); mk[8] = ge_float(ky);
            mk[9] = (float)stroke;
            nm++;
        }
        rs__free(ctx, first_seg);
        g->nmarks = nm;
        ge_items it = { NULL, box, nm };
        r = index_build(ctx, g, &it, "marking", &g->mark_start, &g->mark_ids, &g->nmark_entries);
        rs__free(ctx, box);
        if (r) goto fail_msg;
    } else {
        g->mark_start = rs__calloc(ctx, ncell + 1, sizeof *g->mark_start);
        g->mark_ids = rs__alloc_array(ctx, 1, sizeof *g->mark_ids);
        if (!g->mark_start || !g->mark_ids) { r = RS_ERR_NOMEM; goto fail; }
    }
    /* the lines' cuts at stop lines and zebras, as the CPU's line symbols
     * take them (lib/scene/styling.c) */
    if (!o.style.disable) {
        rs__line_cut *cuts = NULL;
        size_t nc = 0;
        const rs__styling *st = src.grid ? src.grid->styling : NULL;
        if (st && st->lines) { /* the grid's (kept where some road has lines) */
            nc = st->ncuts;
            if (!(cuts = rs__alloc_array(ctx, nc ? nc : 1, sizeof *cuts))) { r = RS_ERR_NOMEM; goto fail; }
            if (nc) memcpy(cuts, st->cuts, nc * sizeof *cuts);
        } else if (have_cuts) { /* the placements' run */
            cuts = auto_cuts, nc = auto_ncut;
            auto_cuts = NULL;
        } else if ((r = rs__markings_line_cuts(ctx, dem, roads, &o, net, &cuts, &nc)) != RS_OK) {
            goto fail_msg;
        }
        g->cut = rs__calloc(ctx, 4 * (n ? n : 1) + RS_GPU_CUT_FLOATS * nc, sizeof(float));
        if (!g->cut) {
            rs__free(ctx, cuts);
            r = RS_ERR_NOMEM;
            goto fail;
        }
        g->ncuts = nc;
        /* road by road (a counting sort on the road's cut count) */
        for (size_t k = 0; k < nc; k++) g->cut[4 * cuts[k].road + 1] += 1;
        size_t at = 0;
        for (size_t i = 0; nc && i < n; i++) {
            g->cut[4 * i] = (float)at;
            at += (size_t)g->cut[4 * i + 1];
            g->cut[4 * i + 1] = 0;
        }
        for (size_t k = 0; k < nc; k++) {
            float *rc = g->cut + 4 * cuts[k].road;
            float *c = g->cut + 4 * n + RS_GPU_CUT_FLOATS * ((size_t)rc[0] + (size_t)rc[1]);
            rc[1] += 1;
            const rs__line_cut *q = &cuts[k];
            c[0] = (float)q->ax, c[1] = (float)q->ay, c[2] = (float)q->ux, c[3] = (float)q->uy;
            c[4] = ge_float(q->u0), c[5] = ge_float(q->u1), c[6] = ge_float(q->r), c[7] = 0;
        }
        rs__free(ctx, cuts);
    }
    if (!g->cut) g->cut = rs__calloc(ctx, 4 * (n ? n : 1), sizeof(float));
    if (!g->cut) { r = RS_ERR_NOMEM; goto fail; }
    if (!g->mark) g->mark = rs__calloc(ctx, 1, RS_GPU_MARK_FLOATS * sizeof(float));
    if (!g->types) g->types = rs__calloc(ctx, 1, RS_GPU_TYPE_INTS * sizeof(uint32_t));
    if (!g->levels) g->levels = rs__calloc(ctx, 1, RS_GPU_LEVEL_INTS * sizeof(uint32_t));
    if (!g->atlas_px) g->atlas_px = rs__calloc(ctx, 1, 4 * sizeof(float));
    if (!g->mark || !g->types || !g->levels || !g->atlas_px) { r = RS_ERR_NOMEM; goto fail; }
    g->bytes = sizeof *g + (g->nseg * RS_GPU_SEG_FLOATS + g->nroads * RS_GPU_ROAD_FLOATS +
                            g->nbands * RS_GPU_BAND_FLOATS + g->nmarks * RS_GPU_MARK_FLOATS + g->atlas_texels * 4 +
                            4 * (n ? n : 1) + RS_GPU_CUT_FLOATS * g->ncuts) *
                               sizeof(float) +
               (2 * (ncell + 1) + g->nseg_entries + g->nmark_entries + g->ntypes * RS_GPU_TYPE_INTS +
                g->nlevels * RS_GPU_LEVEL_INTS) * sizeof(uint32_t);
    if ((r = ge_mark_tables(ctx, g)) != RS_OK) goto fail_msg;
    g->bytes += (g->nlevels * RS_GPU_LEVEL_INTS + g->sat_corners * 4) * sizeof(uint32_t);
    rs__free(ctx, pl);
    rs__free(ctx, ends);
    rs__free(ctx, soff);
    rs__free(ctx, srev);
    rs__free(ctx, tees);
    rs__free(ctx, tee_of);
    rs__free(ctx, auto_cuts);
    rs_network_free(ctx, net);
    rs__free(ctx, sty);
    rs_atlas_free(ctx, atlas_own);
    *out = g;
    rs__ok(ctx);
    return RS_OK;
fail: /* out of memory, or a stage's cancel (rs__progress_end says "cancelled") */
    if (r != RS_ERR_CANCELLED) r = rs__fail(ctx, r ? r : RS_ERR_NOMEM, "out of memory for the GPU export");
fail_msg:
    rs__free(ctx, pl);
    rs__free(ctx, ends);
    rs__free(ctx, soff);
    rs__free(ctx, srev);
    rs__free(ctx, tees);
    rs__free(ctx, tee_of);
    rs__free(ctx, auto_cuts);
    rs_network_free(ctx, net);
    rs__free(ctx, sty);
    rs_atlas_free(ctx, atlas_own);
    rs_gpu_scene_free(ctx, g);
    return r;
}


/* Progress (both entry points): the context's callback (the options'
 * progress is the grid build's); polls in the network, markings and
 * per-road passes. */
rs_result rs_gpu_scene_create(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *opts,
                              const rs_gpu_options *gopts, rs_gpu_scene **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!dem || !roads || !out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_gpu_scene_create: NULL argument");
    *out = NULL;
    ge_src src = { NULL };
    rs__progress pg;
    rs__progress_begin(ctx, &pg, NULL, NULL, 1, 1);
    return rs__progress_end(ctx, &pg, ge_export(ctx, src, dem, roads, opts, gopts, out));
}

rs_result rs_gpu_scene_from_grid(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_road_grid *grid,
                                 const rs_gpu_options *gopts, rs_gpu_scene **out)
{
    if (out) *out = NULL;
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!dem || !roads || !grid || !out)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_gpu_scene_from_grid: NULL argument");
    if (grid->dem_w != dem->width || grid->dem_h != dem->height ||
        memcmp(&grid->frame, &dem->frame, sizeof grid->frame) != 0)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_gpu_scene_from_grid: the grid was built for another DEM");
    /* the grid's per-road tables must be of these roads */
    const size_t n = rs_roads_count(roads);
    int other = grid->npatch ? grid->track && grid->track->n != n : grid->styling && grid->styling->nroads != n;
    for (size_t k = 0; !grid->npatch && grid->markings && k < grid->markings->npl && !other; k++)
        other = grid->markings->pl[k].road >= n;
    if (other)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_gpu_scene_from_grid: the grid was built from other roads");
    /* the options the grid was built with, as far as the export reads them */
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = grid->texels;
    o.style = grid->style;
    o.markings = grid->marks;
    /* a patched grid (rs_road_grid_update) holds its styles in pieces:
     * the export works them out from the roads, as rs_gpu_scene_create */
    ge_src src = { grid->npatch ? NULL : grid };
    rs__progress pg;
    rs__progress_begin(ctx, &pg, NULL, NULL, 1, 1);
    return rs__progress_end(ctx, &pg, ge_export(ctx, src, dem, roads, &o, gopts, out));
}

/* Type t has levels and is the first with its level 0 (a type sharing an
 * earlier type's rectangle shares its table). */
static int ge_table_of(const rs_gpu_scene *g, size_t t)
{
    const uint32_t *ty = g->types + RS_GPU_TYPE_INTS * t;
    if (!ty[1]) return 0;
    for (size_t u = 0; u < t; u++)
        if (g->types[RS_GPU_TYPE_INTS * u + 1] && g->types[RS_GPU_TYPE_INTS * u] == ty[0]) return 0;
    return 1;
}

/* The markings' summed-area tables (issue 25, docs/markings.md) from each
 * type's level 0: per type (h + 1) x (w + 1) corners of the sums of
 * round(255 x premultiplied r g b) and round(255 x alpha) (whole numbers,
 * so the shader's differences are exact), and a copy of the level records
 * whose level-0 fourth int is the type's first corner. Types sharing a
 * rectangle (the same first level) share their table. */
static rs_result ge_mark_tables(rs_ctx *ctx, rs_gpu_scene *g)
{
    size_t n = 0;
    for (size_t t = 0; t < g->ntypes; t++) {
        if (!ge_table_of(g, t)) continue;
        const uint32_t *L = g->levels + RS_GPU_LEVEL_INTS * g->types[RS_GPU_TYPE_INTS * t];
        n += (size_t)(L[1] + 1) * (L[2] + 1);
    }
    g->mark_sat = rs__calloc(ctx, n ? n : 1, 4 * sizeof *g->mark_sat);
    g->mark_levels = rs__calloc(ctx, g->nlevels ? g->nlevels : 1, RS_GPU_LEVEL_INTS * sizeof *g->mark_levels);
    if (!g->mark_sat || !g->mark_levels) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for the GPU export");
    if (g->nlevels) memcpy(g->mark_levels, g->levels, g->nlevels * RS_GPU_LEVEL_INTS * sizeof *g->mark_levels);
    size_t off = 0;
    for (size_t t = 0; t < g->ntypes; t++) {
        if (!ge_table_of(g, t)) continue;
        uint32_t *L = g->mark_levels + RS_GPU_LEVEL_INTS * g->types[RS_GPU_TYPE_INTS * t];
        const size_t w = L[1], h = L[2], w1 = w + 1;
        const float *px = g->atlas_px + 4 * (size_t)L[0];
        int32_t *S = g->mark_sat + 4 * off;
        L[3] = (uint32_t)off;
        for (size_t j = 0; j < h; j++) {
            int64_t row[4] = { 0, 0, 0, 0 };
            for (size_t i = 0; i < w; i++)
                for (int c = 0; c < 4; c++) {
                    row[c] += (int64_t)lrintf(px[4 * (j * w + i) + (size_t)c] * 255.0f);
                    int64_t v = S[4 * (j * w1 + i + 1) + (size_t)c] + row[c];
                    if (v > INT32_MAX)
                        return rs__fail(ctx, RS_ERR_LIMIT, "GPU export: marking type %zu (%zu x %zu texels) is too "
                                        "large for the shader's summed-area table", t, w, h);
                    S[4 * ((j + 1) * w1 + i + 1) + (size_t)c] = (int32_t)v;
                }
        }
        off += w1 * (h + 1);
    }
    g->sat_corners = n;
    return RS_OK;
}

void rs_gpu_scene_get_info(const rs_gpu_scene *g, rs_gpu_scene_info *out)
{
    if (!out) return;
    memset(out, 0, sizeof *out);
    if (!g) return;
    out->cell = g->cell;
    out->x0 = g->x0;
    out->y0 = g->y0;
    out->reach = g->reach;
    out->gw = g->gw;
    out->gh = g->gh;
    out->map_w = g->map_w;
    out->map_h = g->map_h;
    out->nseg = g->nseg;
    out->nroads = g->nroads;
    out->nbands = g->nbands;
    out->nmarks = g->nmarks;
    out->ntypes = g->ntypes;
    out->nlevels = g->nlevels;
    out->ncuts = g->ncuts;
    out->nseg_entries = g->nseg_entries;
    out->nmark_entries = g->nmark_entries;
    out->atlas_texels = g->atlas_texels;
    out->sat_corners = g->sat_corners;
    out->bytes = g->bytes;
}

const void *rs_gpu_scene_array(const rs_gpu_scene *g, rs_gpu_array which, size_t *count)
{
    size_t n = 0;
    const void *p = NULL;
    const size_t ncell1 = g ? (size_t)g->gw * g->gh + 1 : 0;
    if (g) switch (which) {
    case RS_GPU_ARRAY_SEG: p = g->seg, n = g->nseg * RS_GPU_SEG_FLOATS; break;
    case RS_GPU_ARRAY_CELL_START: p = g->cell_start, n = ncell1; break;
    case RS_GPU_ARRAY_CELL_SEG: p = g->cell_seg, n = g->nseg_entries; break;
    case RS_GPU_ARRAY_ROAD: p = g->road, n = g->nroads * RS_GPU_ROAD_FLOATS; break;
    case RS_GPU_ARRAY_BAND: p = g->band, n = g->nbands * RS_GPU_BAND_FLOATS; break;
    case RS_GPU_ARRAY_MARK: p = g->mark, n = g->nmarks * RS_GPU_MARK_FLOATS; break;
    case RS_GPU_ARRAY_MARK_START: p = g->mark_start, n = ncell1; break;
    case RS_GPU_ARRAY_MARK_IDS: p = g->mark_ids, n = g->nmark_entries; break;
    case RS_GPU_ARRAY_TYPES: p = g->types, n = g->ntypes * RS_GPU_TYPE_INTS; break;
    case RS_GPU_ARRAY_MARK_LEVELS: p = g->mark_levels, n = g->nlevels * RS_GPU_LEVEL_INTS; break;
    case RS_GPU_ARRAY_MARK_SAT: p = g->mark_sat, n = g->sat_corners * 4; break;
    case RS_GPU_ARRAY_CUT: p = g->cut, n = 4 * (g->nroads ? g->nroads : 1) + RS_GPU_CUT_FLOATS * g->ncuts; break;
    case RS_GPU_ARRAY_LEVELS: p = g->levels, n = g->nlevels * RS_GPU_LEVEL_INTS; break;
    case RS_GPU_ARRAY_ATLAS_PX: p = g->atlas_px, n = g->atlas_texels * 4; break;
    default: break;
    }
    if (count) *count = p ? n : 0;
    return p;
}

const char *rs_gpu_array_sampler(rs_gpu_array which, uint32_t *channels, uint32_t *kind)
{
    /* in rs_gpu_array order; kind 0 float, 1 uint32, 2 int32 */
    static const struct { const char *name; uint32_t ch, kind; } tab[RS_GPU_ARRAY_COUNT] = {
        { "u_seg", 4, 0 },   { "u_cstart", 1, 1 }, { "u_cseg", 1, 1 },  { "u_roadt", 4, 0 },
        { "u_band", 4, 0 },  { "u_mark", 4, 0 },   { "u_mstart", 1, 1 }, { "u_mids", 1, 1 },
        { "u_types", 1, 1 }, { "u_levels", 4, 1 }, { "u_atlas", 4, 2 }, { "u_cut", 4, 0 },
        { NULL, 1, 1 },      { NULL, 4, 0 },
    };
    if ((unsigned)which >= RS_GPU_ARRAY_COUNT) {
        if (channels) *channels = 0;
        if (kind) *kind = 0;
        return NULL;
    }
    if (channels) *channels = tab[which].ch;
    if (kind) *kind = tab[which].kind;
    return tab[which].name;
}
