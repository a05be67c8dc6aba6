/* Road edits in proportion to the edit (issue 30 target 3, docs/embedding.md
 * "Patches"): a grid keeps a fingerprint and a box per road, its network
 * and the whole map's facts (rs__grid_track); an update finds the roads
 * that changed by their fingerprints, the records whose strokes changed by
 * the new network, builds the roads around them alone with the whole
 * map's network and facts (rs__road_grid_build_subset), and makes a grid
 * that shares the old one's structures and draws the new part inside one
 * rectangle (a patch). */
#include "roadgrid.h"
#include "grid_edit.h"
#include "network.h"
#include "styling.h"
#include "roadfield.h"
#include "markings.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define mix rs__fp_mix
#define mixd rs__fp_mixd
#define mixs rs__fp_mixs

/* Metres beyond twice the widest paint reach that an edit may change
 * pixels at (a give-way line's setback, a junction's surface) and, beyond
 * the changed area, the roads a local build takes (35 m sufficed on the
 * 10k-road city: tests/tools/edit_locality.c). */
#define CHANGE_PAD 15.0
#define CONTEXT_PAD 60.0
/* A patch's roads are indexed for its rectangle's pixels and for queries
 * there (rs_road_grid_query) up to this reach: beyond it a query may miss
 * a road the whole build finds. */
#define PATCH_QUERY_REACH 20.0
/* doubles per road end of a track's T strips (strip_params) */
#define TS 7

static uint64_t mix_colour(uint64_t h, rs_colour c)
{
    return mix(h, (uint64_t)c.r | (uint64_t)c.g << 8 | (uint64_t)c.b << 16 | (uint64_t)c.a << 24);
}

static uint64_t style_print(uint64_t h, const rs_style *y)
{
    h = mixs(mix(h, (uint64_t)y->surface), y->surface_image);
    h = mix_colour(mix_colour(mix_colour(h, y->fill), y->gradient_centre), y->gradient_edge);
    h = mix_colour(mixd(h, y->casing_width), y->casing);
    h = mixd(h, y->surface_length);
    h = mix(h, y->line_count);
    for (uint32_t k = 0; k < y->line_count && k < RS_STYLE_MAX_LINES; k++) {
        const rs_style_line *l = &y->line[k];
        h = mix_colour(mixd(mixd(h, l->offset), l->width), l->colour);
        h = mixd(mix(h, l->dash_count), l->phase);
        for (uint32_t d = 0; d < l->dash_count && d < RS_STYLE_MAX_DASH; d++) h = mixd(h, l->dash[d]);
    }
    return h;
}

/* The larger of two widths, NaN when either is (a width that is not a
 * number makes the widest one unknown). */
static double widest(double a, double b)
{
    return a != a || b != b ? NAN : a > b ? a : b;
}

static void box_add(double *acc, const double *b, double grow)
{
    acc[0] = fmin(acc[0], b[0] - grow), acc[1] = fmin(acc[1], b[1] - grow);
    acc[2] = fmax(acc[2], b[2] + grow), acc[3] = fmax(acc[3], b[3] + grow);
}

/* The changed area as boxes (each grown as it is added): along a road,
 * and for edits far apart, rectangles of their own instead of one over the
 * map between them. */
typedef struct boxes {
    rs_ctx *ctx;
    double *v; /* 4 a box */
    size_t n, cap;
    int nomem;
} boxes;

/* Room for `more` boxes past B's n (B->nomem when there is none). */
static void boxes_room(boxes *B, size_t more)
{
    if (B->nomem || B->cap - B->n >= more) return;
    size_t nc = B->cap ? 2 * B->cap : 16;
    if (nc - B->n < more) nc = B->n + more;
    double *v = nc <= SIZE_MAX / (4 * sizeof *v) ? rs__realloc(B->ctx, B->v, nc * 4 * sizeof *v) : NULL;
    if (!v) {
        B->nomem = 1;
        return;
    }
    B->v = v, B->cap = nc;
}

static void boxes_add(boxes *B, const double *b, double grow)
{
    boxes_room(B, 1);
    if (B->n == B->cap) return; /* (B->nomem) */
    double *d = B->v + 4 * B->n++;
    d[0] = b[0] - grow, d[1] = b[1] - grow, d[2] = b[2] + grow, d[3] = b[3] + grow;
}

/* Metres of road one changed box covers at most across: a box per run of
 * a road's points this wide (a longer segment in pieces), so a long or
 * winding road's change is the strip along it, not its whole bounding box
 * (a diagonal avenue's box is most of the map). */
#define CHUNK_M 32.0

static void box_point(double *b, double x, double y)
{
    b[0] = fmin(b[0], x), b[1] = fmin(b[1], y), b[2] = fmax(b[2], x), b[3] = fmax(b[3], y);
}

/* Boxes of the polyline's points a..b, each at most CHUNK_M across (the
 * last point of one is the first of the next: every piece of the line lies
 * in a box), grown by grow, into B. A segment too long or not finite stays
 * one box (a NaN box makes the update build whole). */
static void path_boxes(boxes *B, const double *xy, size_t a, size_t b, double grow)
{
    double bx[4] = { INFINITY, INFINITY, -INFINITY, -INFINITY };
    double px = xy[2 * a], py = xy[2 * a + 1];
    int pts = 1; /* (in bx) */
    box_point(bx, px, py);
    for (size_t i = a; i < b; i++) {
        const double *q = xy + 2 * i + 2;
        double dx = q[0] - xy[2 * i], dy = q[1] - xy[2 * i + 1], ext = fmax(fabs(dx), fabs(dy));
        size_t np = ext > CHUNK_M && ext < 1e6 * CHUNK_M ? (size_t)ceil(ext / CHUNK_M) : 1;
        for (size_t k = 1; k <= np; k++) {
            double x = k == np ? q[0] : xy[2 * i] + dx * ((double)k / (double)np);
            double y = k == np ? q[1] : xy[2 * i + 1] + dy * ((double)k / (double)np);
            if (pts > 1 && fmax(fmax(bx[2], x) - fmin(bx[0], x), fmax(bx[3], y) - fmin(bx[1], y)) > CHUNK_M) {
                boxes_add(B, bx, grow);
                bx[0] = bx[2] = px, bx[1] = bx[3] = py;
                pts = 1;
            }
            box_point(bx, x, y);
            pts++;
            px = x, py = y;
        }
    }
    boxes_add(B, bx, grow);
}

static void chunks_free(rs_ctx *ctx, rs__road_chunks *c)
{
    rs__free(ctx, c->start);
    rs__free(ctx, c->v);
    memset(c, 0, sizeof *c);
}

/* Road i's changed area: its boxes along it (or its box) grown by grow. */
static void road_boxes(boxes *B, const double *box, const rs__road_chunks *c, size_t i, double grow)
{
    if (c->start && c->start[i + 1] > c->start[i])
        for (uint32_t k = c->start[i]; k < c->start[i + 1]; k++) boxes_add(B, c->v + 4 * (size_t)k, grow);
    else
        boxes_add(B, box + 4 * i, grow);
}

/* The end of the run of roads from j matched in order to the old ones
 * (m_new[j .. end) = m_new[j], m_new[j] + 1, ...; m_new[j] matched): their
 * per-road data is copied in one piece. */
static size_t matched_run(const uint32_t *m_new, size_t n, size_t j)
{
    size_t e = j + 1;
    while (e < n && m_new[e] == m_new[j] + (e - j)) e++;
    return e;
}

/* The boxes along every road of `roads` (boxes B) wider than CHUNK_M:
 * a new road's (m_new[j] UINT32_MAX, or no old ones) from its points, a
 * kept one's copied from old's (its points are the same). */
static rs_result chunks_make(rs_ctx *ctx, const rs_roads *roads, const double *B, const uint32_t *m_new,
                             const rs__road_chunks *old, rs__road_chunks *ch)
{
    size_t n = rs_roads_count(roads);
    boxes acc;
    memset(&acc, 0, sizeof acc);
    acc.ctx = ctx;
    memset(ch, 0, sizeof *ch);
    if (n >= UINT32_MAX || !(ch->start = rs__alloc_array(ctx, n + 1, sizeof *ch->start))) return RS_ERR_NOMEM;
    ch->start[0] = 0;
    /* (the old chunks of a run of roads matched in order, as many as the
     * old set has: room made once for all of them, one copy a run; a new
     * road's boxes between two runs take room of their own, so each copy
     * makes sure of its room: fuzz/edits) */
    if (m_new && old->start && old->v && n) {
        size_t cap = 16;
        for (size_t j = 0; j < n; j++)
            if (m_new[j] != UINT32_MAX) cap += old->start[m_new[j] + 1] - old->start[m_new[j]];
        if (!(acc.v = rs__alloc_array(ctx, cap, 4 * sizeof *acc.v))) acc.nomem = 1;
        else acc.cap = cap;
    }
    for (size_t j = 0; j < n && !acc.nomem; j++) {
        const double *b = B + 4 * j;
        uint32_t i = m_new && old->start ? m_new[j] : UINT32_MAX;
        if (i != UINT32_MAX) {
            size_t q = matched_run(m_new, n, j);
            size_t k0 = old->start[i], k1 = old->start[i + (q - j)];
            if (k1 > k0) boxes_room(&acc, k1 - k0);
            if (k1 > k0 && !acc.nomem) {
                memcpy(acc.v + 4 * acc.n, old->v + 4 * k0, (k1 - k0) * 4 * sizeof *acc.v);
                acc.n += k1 - k0;
            }
            for (size_t t = j; t < q; t++) ch->start[t + 1] = (uint32_t)(acc.n - (k1 - old->start[i + (t - j) + 1]));
            if (acc.n >= UINT32_MAX) acc.nomem = 1;
            j = q - 1;
            continue;
        } else if (b[2] - b[0] > CHUNK_M || b[3] - b[1] > CHUNK_M) {
            const double *xy = NULL;
            size_t np = 0;
            rs_roads_get(roads, j, NULL, NULL, &xy, &np);
            if (np) path_boxes(&acc, xy, 0, np - 1, 0);
        }
        if (acc.n >= UINT32_MAX) acc.nomem = 1;
        ch->start[j + 1] = (uint32_t)acc.n;
    }
    if (acc.nomem) {
        rs__free(ctx, acc.v);
        chunks_free(ctx, ch);
        return RS_ERR_NOMEM;
    }
    ch->v = acc.v;
    ch->bytes = (n + 1) * sizeof *ch->start + acc.n * 4 * sizeof *acc.v;
    return RS_OK;
}

/* The raw prints (geometry, width, name, attributes, point attributes,
 * markings), boxes and widest road of every road, and the reach of the
 * widest marking. */
static rs_result raw_prints(rs_ctx *ctx, const rs_roads *roads, uint64_t **print, double **box, double *max_width,
                            double *mark_reach)
{
    size_t n = rs_roads_count(roads);
    uint64_t *P = rs__alloc_array(ctx, n ? n : 1, sizeof *P);
    double *B = rs__alloc_array(ctx, n ? n : 1, 4 * sizeof *B);
    if (!P || !B) {
        rs__free(ctx, P);
        rs__free(ctx, B);
        return RS_ERR_NOMEM;
    }
    *max_width = 0;
    *mark_reach = 0;
    /* (each road's print and box kept by the road set: rs__roads_road_print) */
    for (size_t i = 0; i < n; i++) {
        double w = 0;
        const double *b = NULL;
        rs__roads_road_print(roads, i, &P[i], &w, &b);
        *max_width = widest(*max_width, w);
        memcpy(B + 4 * i, b, 4 * sizeof *B);
    }
    /* point attributes and markings, in their order, into their roads' prints */
    for (size_t k = 0; k < rs_roads_point_attr_count(roads); k++) {
        size_t road = 0, point = 0;
        const char *key = NULL, *val = NULL;
        rs_roads_point_attr_at(roads, k, &road, &point, &key, &val);
        if (road < n) P[road] = mixs(mixs(mix(P[road], point), key), val);
    }
    for (size_t k = 0; k < rs_roads_mark_count(roads); k++) {
        rs_mark m;
        if (rs_roads_get_mark(roads, k, &m) != RS_OK || m.road >= n) continue;
        uint64_t h = mixd(mixd(mixd(mixd(mixs(P[m.road], m.type), m.s), m.t), m.length), m.width);
        P[m.road] = mix(h, (uint64_t)(m.flip != 0));
        /* (a marking lies |t| across, up to its extent; 0 takes its type's: 10 m is more than any) */
        double ext = fmax(m.length > 0 ? m.length : 10, m.width > 0 ? m.width : 10);
        if (fabs(m.t) + ext > *mark_reach) *mark_reach = fabs(m.t) + ext;
    }
    for (size_t i = 0; i < n; i++) P[i] = rs__fp_final(P[i]);
    *print = P;
    *box = B;
    return RS_OK;
}

/* What the styles the roads resolve to depend on besides the roads: the
 * named styles, the profile and the driving side. */
static uint64_t styles_print(const rs_splat_options *o)
{
    uint64_t h = mix(mix(mix(0x5717e5, (uint64_t)o->style.disable), (uint64_t)o->style.profile),
                     (uint64_t)o->style.driving_side);
    size_t n = rs_styles_count(o->style.styles);
    h = mix(h, n);
    for (size_t k = 0; k < n; k++) {
        const rs_style *y = rs_styles_get(o->style.styles, k);
        h = style_print(mixs(h, y->name), y);
    }
    return rs__fp_final(h);
}

/* Road i's resolved style: its print and what the whole map's facts read
 * of it (with the styles off: its half width alone). */
static rs_result road_sum(rs_ctx *ctx, const rs_roads *roads, size_t i, const rs_splat_options *o, rs_style *y,
                          uint64_t *sprint, rs__road_sum *S)
{
    double w = 0;
    rs_roads_get(roads, i, NULL, &w, NULL, NULL);
    memset(S, 0, sizeof *S);
    S->reach = 0.5 * w;
    *sprint = 0;
    S->prio = rs__road_rank(roads, i);
    if (o->style.disable) return RS_OK;
    rs_result r = rs_road_style_ex(ctx, roads, i, &o->style, y);
    if (r) return r;
    *sprint = rs__fp_final(style_print(0x5717e, y));
    rs__put_colour(S->fill, y->surface == RS_SURFACE_GRADIENT ? y->gradient_centre : y->fill);
    S->fill_surface = y->surface == RS_SURFACE_FILL;
    S->image = y->surface_image[0] != 0;
    S->any_surface = y->surface != RS_SURFACE_DEFAULT || S->image;
    S->styled = y->surface != RS_SURFACE_DEFAULT || y->line_count || y->casing_width > 0 || S->image;
    S->lines = y->line_count > 0;
    if (y->casing_width > 0) {
        rs__put_colour(S->casing, y->casing);
        S->casing_width = y->casing_width;
        S->reach += y->casing_width;
    }
    for (uint32_t k = 0; k < y->line_count && k < RS_STYLE_MAX_LINES; k++)
        S->reach = fmax(S->reach, fabs(y->line[k].offset) + 0.5 * y->line[k].width);
    return RS_OK;
}

/* The whole map's facts (index cell left 0) and widest paint reach from
 * the roads' sums, in road order. */
static void facts_of(const rs__road_sum *S, size_t n, int disable, double mark_reach, rs__grid_facts *facts,
                     double *reach)
{
    memset(facts, 0, sizeof *facts);
    *reach = 0;
    int casings = 0;
    for (size_t i = 0; i < n; i++) {
        const rs__road_sum *y = &S[i];
        if (!disable) {
            if (y->any_surface) facts->any_surface = 1;
            if (i == 0) {
                facts->fill_uniform = y->fill_surface;
                memcpy(facts->fill_rgba, y->fill, sizeof y->fill);
            } else if (!y->fill_surface || memcmp(facts->fill_rgba, y->fill, sizeof y->fill)) {
                facts->fill_uniform = 0;
            }
            if (y->image) facts->fill_uniform = 0;
            facts->styled |= y->styled;
            if (y->casing_width > 0) {
                if (!casings++) {
                    memcpy(facts->casing_rgba, y->casing, sizeof y->casing);
                    facts->casing_uniform = 1;
                } else if (memcmp(facts->casing_rgba, y->casing, sizeof y->casing)) {
                    facts->casing_uniform = 0;
                }
                facts->widest_casing = fmax(facts->widest_casing, y->casing_width);
            }
        }
        *reach = fmax(*reach, y->reach);
    }
    /* (as rs__styling keeps its priorities: they differ, and a fill looks them up) */
    for (size_t i = 1; i < n && !disable && facts->any_surface && !facts->ranked; i++)
        facts->ranked = S[i].prio != S[0].prio;
    if (!facts->styled) memset(facts, 0, sizeof *facts); /* (no styling: the whole build keeps no switches) */
    if (mark_reach > *reach) *reach = mark_reach;
}

/* The memory track t holds (its network included). */
static size_t track_bytes(const rs__grid_track *t)
{
    return sizeof *t + t->n * (sizeof *t->print + sizeof *t->sprint + sizeof *t->sum + 4 * sizeof *t->box) +
           (t->tfar ? 2 * t->n * sizeof *t->tfar : 0) + (t->tstrip ? 2 * TS * t->n * sizeof *t->tstrip : 0) +
           (t->net ? rs__network_bytes(t->net) : 0) + t->chunks.bytes;
}

/* A T end's strip (rs__roadfield_set_tees: its end segment a..a+2 runs on
 * to the clip line n.p = n.E + far; at a slant one edge of a strip of half
 * width R reaches (far + R cos) / sin past E, 40 m on the edits fuzz
 * target's hairpin), kept as TS doubles: E, the unit direction u towards
 * the end, far / sin, cos / sin and the road's half width r; NaN when the
 * strip is not made (sin <= 0.1). */
static void strip_none(double *p)
{
    for (int c = 0; c < TS; c++) p[c] = NAN;
}

static void strip_params(const double *a, const double *E, int end, double nx, double ny, double far, double r,
                         double *p)
{
    double dx = a[2] - a[0], dy = a[3] - a[1], len = hypot(dx, dy);
    strip_none(p);
    if (!(len > 0)) return;
    double ux = end ? dx / len : -dx / len, uy = end ? dy / len : -dy / len;
    double sn = nx * ux + ny * uy, cs = fabs(nx * uy - ny * ux);
    if (!(sn > 0.1)) return;
    p[0] = E[0], p[1] = E[1], p[2] = ux, p[3] = uy, p[4] = far / sn, p[5] = cs / sn, p[6] = r;
}

/* The box of strip p (strip_params) at half width r + wider into bx; 0
 * when there is no strip. */
static int strip_box(const double *p, double wider, double *bx)
{
    if (isnan(p[0])) return 0;
    double R = p[6] + wider, ub = fmax(p[4] + R * p[5], 0), fx = p[0] + ub * p[2], fy = p[1] + ub * p[3];
    bx[0] = fmin(p[0], fx) - R, bx[1] = fmin(p[1], fy) - R, bx[2] = fmax(p[0], fx) + R, bx[3] = fmax(p[1], fy) + R;
    return 1;
}

/* Strip p's box at half width r + wider into acc, grown by grow. */
static void strip_add(boxes *acc, const double *p, double wider, double grow)
{
    double bx[4];
    if (strip_box(p, wider, bx)) boxes_add(acc, bx, grow); /* (not finite: the update builds whole) */
}

/* The strips of the T ends te[0..n) of `roads` into ts (TS per road end;
 * the other ends left). */
static void tee_strips(double *ts, const rs__tee_end *te, size_t n, const rs_roads *roads)
{
    for (size_t k = 0; k < n; k++) {
        const double *xy;
        size_t np;
        double w = 0;
        double *p = ts + TS * (2 * (size_t)te[k].road + (te[k].end ? 1 : 0));
        strip_none(p);
        if (rs_roads_get(roads, te[k].road, NULL, &w, &xy, &np) || !np) continue;
        size_t ke = rs__end_segment(xy, np, te[k].end);
        if (ke != SIZE_MAX)
            strip_params(xy + 2 * ke, xy + 2 * (te[k].end ? np - 1 : 0), te[k].end, te[k].nx, te[k].ny, te[k].far,
                         0.5 * w, p);
    }
}

/* far of the T ends te[0..n) into tfar (per road end, the rest left) */
static void tee_fars(double *tfar, const rs__tee_end *te, size_t n)
{
    for (size_t k = 0; k < n; k++) tfar[2 * (size_t)te[k].road + (te[k].end ? 1 : 0)] = te[k].far;
}

/* Every road end's T line and strip (NaN where it is no T end) of the n
 * roads of `roads` with network net into *tfar (2 n) and *tstrip (2 TS
 * n), the caller's (rs__free, also on failure). T: net's T ends given (NULL:
 * worked out here). */
static rs_result tee_lines(rs_ctx *ctx, const rs_roads *roads, const rs_network *net, const rs__tees *T, size_t n,
                           double **tfar, double **tstrip)
{
    rs__tee_end *te = NULL;
    size_t nte = 0;
    *tfar = rs__alloc_array(ctx, 2 * (n ? n : 1), sizeof **tfar);
    *tstrip = rs__alloc_array(ctx, 2 * TS * (n ? n : 1), sizeof **tstrip);
    rs_result r = *tfar && *tstrip ? rs__tee_ends_from(ctx, T, roads, net, &te, &nte) : RS_ERR_NOMEM;
    for (size_t k = 0; !r && k < 2 * n; k++) (*tfar)[k] = NAN;
    for (size_t k = 0; !r && k < 2 * TS * n; k++) (*tstrip)[k] = NAN;
    if (!r) tee_fars(*tfar, te, nte), tee_strips(*tstrip, te, nte, roads);
    rs__free(ctx, te);
    return r;
}

void rs__grid_track_free(rs_ctx *ctx, rs__grid_track *t)
{
    if (!t || rs__refs_add(&t->refs, -1) > 0) return;
    rs__free(ctx, t->print);
    rs__free(ctx, t->sprint);
    rs__free(ctx, t->sum);
    rs__free(ctx, t->box);
    chunks_free(ctx, &t->chunks);
    rs__free(ctx, t->tfar);
    rs__free(ctx, t->tstrip);
    rs_network_free(ctx, t->net);
    rs__free(ctx, t);
}

rs_result rs__grid_track_build(rs_ctx *ctx, const rs_roads *roads, const rs_splat_options *o, rs_network *net,
                               const rs__tees *T, rs_road_grid *g)
{
    rs__grid_track *t = rs__calloc(ctx, 1, sizeof *t);
    if (!t) {
        rs_network_free(ctx, net);
        return RS_ERR_NOMEM;
    }
    t->refs = 1;
    t->net = net;
    t->n = rs_roads_count(roads);
    double mark_reach;
    rs_style *y = rs__malloc(ctx, sizeof *y);
    t->sprint = rs__alloc_array(ctx, t->n ? t->n : 1, sizeof *t->sprint);
    t->sum = rs__alloc_array(ctx, t->n ? t->n : 1, sizeof *t->sum);
    rs_result r = y && t->sprint && t->sum ? RS_OK : RS_ERR_NOMEM;
    if (!r) r = raw_prints(ctx, roads, &t->print, &t->box, &t->max_width, &mark_reach);
    if (!r) r = chunks_make(ctx, roads, t->box, NULL, NULL, &t->chunks);
    for (size_t i = 0; i < t->n && !r; i++) r = road_sum(ctx, roads, i, o, y, &t->sprint[i], &t->sum[i]);
    rs__free(ctx, y);
    if (r) {
        rs__grid_track_free(ctx, t);
        return r;
    }
    if (net) { /* (every end's T line, for the next update's clip walks) */
        r = tee_lines(ctx, roads, net, T, t->n, &t->tfar, &t->tstrip);
        if (r) {
            rs__grid_track_free(ctx, t);
            return r;
        }
    }
    t->sctx = styles_print(o);
    rs__grid_facts_of(g, &t->facts);
    t->bytes = track_bytes(t);
    g->track = t;
    return RS_OK;
}

/* ---- matching the roads by their prints ---------------------------------- */

/* new road j's old road (UINT32_MAX: none) in *m_new, old i's new one in
 * *m_old: for each new road in order, the first old road after the last
 * match with an equal print (a road whose print also changed order is no
 * match). Mostly the next old road; else the old ones after it are read
 * in order (a few misses: a move, an added road), and past a budget of
 * reads a table of the old prints, each print's roads ascending, made
 * once, answers (the same first later one). */
static rs_result match_roads(rs_ctx *ctx, const uint64_t *po, size_t no, const uint64_t *pn, size_t nn,
                             uint32_t *m_old, uint32_t *m_new)
{
    typedef struct slot { uint64_t h; uint32_t head; } slot;
    slot *tab = NULL;
    uint32_t *next = NULL;
    size_t mask = 0, read = 0;
    int64_t last = -1;
    for (size_t i = 0; i < no; i++) m_old[i] = UINT32_MAX;
    for (size_t j = 0; j < nn; j++) {
        m_new[j] = UINT32_MAX;
        size_t i = (size_t)(last + 1);
        if (!(i < no && po[i] == pn[j]) && !tab && read + (no - i) <= 4 * (uint64_t)no + 64) {
            read += no - i;
            while (i < no && po[i] != pn[j]) i++;
            if (i == no) continue;
        } else if (!(i < no && po[i] == pn[j])) {
            if (!tab) {
                size_t cap = 16;
                while (cap < 2 * no) cap *= 2;
                tab = rs__alloc_array(ctx, cap, sizeof *tab);
                next = rs__alloc_array(ctx, no ? no : 1, sizeof *next);
                if (!tab || !next) {
                    rs__free(ctx, tab);
                    rs__free(ctx, next);
                    return RS_ERR_NOMEM;
                }
                mask = cap - 1;
                for (size_t k = 0; k < cap; k++) tab[k].head = UINT32_MAX;
                for (size_t k = no; k-- > 0;) { /* (from the last: each list ascends) */
                    size_t at = (size_t)rs__fp_final(po[k]) & mask;
                    while (tab[at].head != UINT32_MAX && tab[at].h != po[k]) at = (at + 1) & mask;
                    next[k] = tab[at].head;
                    tab[at].h = po[k];
                    tab[at].head = (uint32_t)k;
                }
            }
            size_t at = (size_t)rs__fp_final(pn[j]) & mask;
            while (tab[at].head != UINT32_MAX && tab[at].h != pn[j]) at = (at + 1) & mask;
            /* (roads up to the last match are no match again: dropped) */
            uint32_t k = tab[at].head;
            while (k != UINT32_MAX && (int64_t)k <= last) k = next[k];
            if (tab[at].head != UINT32_MAX) tab[at].head = k;
            if (k == UINT32_MAX) continue;
            i = k;
        }
        m_new[j] = (uint32_t)i;
        m_old[i] = (uint32_t)j;
        last = (int64_t)i;
    }
    rs__free(ctx, tab);
    rs__free(ctx, next);
    return RS_OK;
}

/* How old record i and new record j (a match) sit in their strokes: 0
 * alike; 1 only their arc length along the stroke or their direction in
 * it differ (the stroke changed beyond their neighbours: its start moved,
 * a record gone further along); 2 their neighbours, length or ring
 * differ. */
static int place_change(const rs_network *A, const rs_network *B, uint32_t i, uint32_t j, const uint32_t *m_old)
{
    if (A->length[i] != B->length[j] || A->closed[A->stroke_of[i]] != B->closed[B->stroke_of[j]]) return 2;
    /* (a neighbour gone is a change: m_old of a removed record is UINT32_MAX, as no neighbour is) */
    const uint32_t pa = A->prev[i], na = A->next[i];
    if (pa == UINT32_MAX ? B->prev[j] != UINT32_MAX : m_old[pa] == UINT32_MAX || m_old[pa] != B->prev[j]) return 2;
    if (na == UINT32_MAX ? B->next[j] != UINT32_MAX : m_old[na] == UINT32_MAX || m_old[na] != B->next[j]) return 2;
    for (int e = 0; e < 2; e++) {
        uint32_t la = A->link[2 * i + e], lb = B->link[2 * j + e];
        if (la == UINT32_MAX ? lb != UINT32_MAX : m_old[la / 2] == UINT32_MAX || 2 * m_old[la / 2] + la % 2 != lb)
            return 2;
    }
    return A->s_off[i] != B->s_off[j] || A->rev[i] != B->rev[j];
}

/* ---- records whose stroke changed far away ----------------------------------
 * A record that only moved along its stroke (place_change 1) draws the
 * same when it has no lines (dashes take their phase from the stroke) and
 * no image (laid along s), and its stroke is no ring: its surface and
 * casing never read the stroke, and the automatic markings read it only
 * near junctions (lib/scene/markings_auto.c measures along the street from
 * the record, and its areas from the record's own start). What can still
 * change there is where the markings compare streets: a street that
 * passes close to itself (two of its records near one point: a junction
 * with itself, one street met twice), the stroke's ends near a changed
 * record, and a free end of the street that another road joins (the
 * junctions at the street's linked ends on that road). Those places get a
 * zone each; the rest of such a record stays out of the changed area.
 * docs/embedding.md "Records moved along their stroke". */

/* Squared distance between segments (a0, a1) and (b0, b1). */
static double seg_seg_d2(const double *a0, const double *a1, const double *b0, const double *b1)
{
    const double *P[4] = { a0, a1, b0, b1 }, *S0[4] = { b0, b0, a0, a0 }, *S1[4] = { b1, b1, a1, a1 };
    /* proper crossing: 0 */
    double d1 = (a1[0] - a0[0]) * (b0[1] - a0[1]) - (a1[1] - a0[1]) * (b0[0] - a0[0]);
    double d2 = (a1[0] - a0[0]) * (b1[1] - a0[1]) - (a1[1] - a0[1]) * (b1[0] - a0[0]);
    double d3 = (b1[0] - b0[0]) * (a0[1] - b0[1]) - (b1[1] - b0[1]) * (a0[0] - b0[0]);
    double d4 = (b1[0] - b0[0]) * (a1[1] - b0[1]) - (b1[1] - b0[1]) * (a1[0] - b0[0]);
    if (((d1 < 0 && d2 > 0) || (d1 > 0 && d2 < 0)) && ((d3 < 0 && d4 > 0) || (d3 > 0 && d4 < 0))) return 0;
    double best = INFINITY;
    for (int k = 0; k < 4; k++) {
        double ux = S1[k][0] - S0[k][0], uy = S1[k][1] - S0[k][1], l2 = ux * ux + uy * uy;
        double t = l2 > 0 ? ((P[k][0] - S0[k][0]) * ux + (P[k][1] - S0[k][1]) * uy) / l2 : 0;
        t = t < 0 ? 0 : t > 1 ? 1 : t;
        double dx = P[k][0] - (S0[k][0] + t * ux), dy = P[k][1] - (S0[k][1] + t * uy), d = dx * dx + dy * dy;
        if (d < best) best = d;
    }
    return best;
}

/* Do roads a and b (points of `roads`) come within d of each other? NaN: yes. */
static int roads_within(const rs_roads *roads, size_t a, size_t b, double d)
{
    const double *pa, *pb;
    size_t na, nb;
    rs_roads_get(roads, a, NULL, NULL, &pa, &na);
    rs_roads_get(roads, b, NULL, NULL, &pb, &nb);
    double d2 = d * d;
    for (size_t u = 0; u < na; u++) {
        const double *a0 = pa + 2 * u, *a1 = pa + 2 * (u + 1 < na ? u + 1 : u);
        for (size_t v = 0; v < nb; v++) {
            const double *b0 = pb + 2 * v, *b1 = pb + 2 * (v + 1 < nb ? v + 1 : v);
            double e = seg_seg_d2(a0, a1, b0, b1);
            if (!(e > d2)) return 1;
        }
    }
    return 0;
}

static void point_zone(boxes *B, double x, double y, double z)
{
    const double b[4] = { x, y, x, y };
    boxes_add(B, b, z);
}

/* Road j's end e's point (0: first, 1: last), 0 when it has none. */
static int road_end(const rs_roads *roads, size_t j, int e, double *x, double *y)
{
    const double *p;
    size_t n;
    rs_roads_get(roads, j, NULL, NULL, &p, &n);
    if (!n) return 0;
    *x = p[e ? 2 * (n - 1) : 0], *y = p[e ? 2 * (n - 1) + 1 : 1];
    return 1;
}

static int road_near(const rs_roads *roads, size_t i, const double *rb, const double *bx, double d);

/* Strokes bigger than this are not searched for places where they pass
 * close to themselves: their records that moved along them stay changed
 * whole. */
#define SELF_MAX 256
/* Updates moving records of more strokes along them than this take those
 * records whole (each stroke's free ends scan every road). */
#define ZONE_STROKES 64

/* The zones of stroke k of network N (the old or the new one; M the
 * other, toM: N's record to M's, UINT32_MAX where it has none): where two
 * of its records come within d of each other with a link between them
 * that M does not have (before and after the edit they are one street in
 * one network only: a junction of the street with itself, a street met
 * twice), and the linked ends of its records near a road that one of its
 * free ends lies on (that road joins the street there, which decides the
 * junctions at those ends), but where that end is free in M too and the
 * linked end is one street with it in both. toRoad: N's record to a road of `roads`
 * (UINT32_MAX: none, then its box in ob, N's records' boxes; NULL: the
 * same); bn: the roads' boxes. Returns 0, or 1 when the stroke has more
 * than SELF_MAX records (its moved records are then taken whole). */
static int stroke_zones(boxes *B, const rs_network *N, size_t k, const rs_network *M, const uint32_t *toM,
                        const uint32_t *toRoad, const double *ob, const rs_roads *roads, const double *bn, size_t nn,
                        double d, double z, uint32_t *recs, uint32_t *nbrk)
{
    uint32_t m = N->stroke_start[k + 1] - N->stroke_start[k];
    if (m > SELF_MAX) return 1;
    const uint32_t *sr = N->stroke_roads + N->stroke_start[k];
    for (uint32_t a = 0; a < m; a++) recs[a] = toRoad ? toRoad[sr[a]] : sr[a];
    /* nbrk[a]: links before position a along the stroke that M lacks */
    nbrk[0] = 0;
    for (uint32_t a = 0; a + 1 < m; a++) {
        uint32_t x = toM[sr[a]], y = toM[sr[a + 1]];
        int kept = x != UINT32_MAX && y != UINT32_MAX && (M->next[x] == y || M->next[y] == x);
        nbrk[a + 1] = nbrk[a] + !kept;
    }
    for (uint32_t a = 0; a < m; a++)
        for (uint32_t b = a + 1; b < m; b++) {
            if (nbrk[b] == nbrk[a]) continue; /* (one street in both: they compare alike) */
            const double *ba = recs[a] != UINT32_MAX ? bn + 4 * (size_t)recs[a] : ob + 4 * (size_t)sr[a];
            const double *bb = recs[b] != UINT32_MAX ? bn + 4 * (size_t)recs[b] : ob + 4 * (size_t)sr[b];
            if (ba[0] - d > bb[2] || bb[0] - d > ba[2] || ba[1] - d > bb[3] || bb[1] - d > ba[3]) continue;
            if (recs[a] != UINT32_MAX && recs[b] != UINT32_MAX && !roads_within(roads, recs[a], recs[b], d)) continue;
            const double zb[4] = { fmax(ba[0], bb[0]) - d, fmax(ba[1], bb[1]) - d, fmin(ba[2], bb[2]) + d,
                                   fmin(ba[3], bb[3]) + d };
            boxes_add(B, zb, z);
        }
    if (N->closed[k] || !m) return 0;
    /* the free ends: the first record's start and the last's end, along the stroke */
    for (int side = 0; side < 2; side++) {
        uint32_t pe = side ? m - 1 : 0, rr = sr[pe], road = recs[pe];
        int ee = (side != 0) != (N->rev[rr] != 0); /* (rr's end there: 0 its first point) */
        /* an end free in M too: a linked end one street with it in both
         * networks has it among its street's free ends in both */
        uint32_t xm = toM[rr];
        int free_m = xm != UINT32_MAX && M->link[2 * (size_t)xm + (size_t)ee] == UINT32_MAX &&
                     !M->closed[M->stroke_of[xm]];
        double fb[4];
        if (road == UINT32_MAX) {
            memcpy(fb, ob + 4 * (size_t)rr, sizeof fb);
        } else {
            double x, y;
            if (!road_end(roads, road, ee, &x, &y)) continue;
            fb[0] = fb[2] = x, fb[1] = fb[3] = y;
        }
        for (size_t j = 0; j < nn; j++) {
            const double *bj = bn + 4 * j;
            /* (reach below is at most d: most roads fail this first) */
            if (bj[0] - d > fb[2] || fb[0] - d > bj[2] || bj[1] - d > fb[3] || fb[1] - d > bj[3]) continue;
            double w = 0;
            rs_roads_get(roads, j, NULL, &w, NULL, NULL);
            double reach = 0.5 * w + 1.0; /* (the markings' 0.5 m, and as much again for the frames' rounding) */
            if (!(reach < 1e300)) reach = INFINITY;
            if (bj[0] - reach > fb[2] || fb[0] - reach > bj[2] || bj[1] - reach > fb[3] || fb[1] - reach > bj[3])
                continue;
            int own = 0; /* (the street's own records: no junction) */
            for (uint32_t a = 0; a < m && !own; a++) own = recs[a] == j;
            if (own || (fb[0] == fb[2] && fb[1] == fb[3] && !road_near(roads, j, bj, fb, reach))) continue;
            /* road j holds a free end of the street: the street's linked ends on j */
            for (uint32_t a = 0; a < m; a++)
                for (int e = 0; e < 2; e++) {
                    if (N->link[2 * (size_t)sr[a] + (size_t)e] == UINT32_MAX) continue;
                    if (free_m && nbrk[a] == nbrk[pe]) continue; /* (the same in both) */
                    if (recs[a] == UINT32_MAX) {
                        boxes_add(B, ob + 4 * (size_t)sr[a], z);
                        continue;
                    }
                    double x, y;
                    if (!road_end(roads, recs[a], e, &x, &y)) continue;
                    const double pt[4] = { x, y, x, y };
                    if (road_near(roads, j, bj, pt, reach)) point_zone(B, x, y, z);
                }
        }
    }
    return 0;
}

static uint64_t rect_area(rs_pixel_rect r) { return (uint64_t)(r.x1 - r.x0) * (r.y1 - r.y0); }

static int rects_meet(rs_pixel_rect a, rs_pixel_rect b)
{
    return a.x0 < b.x1 && b.x0 < a.x1 && a.y0 < b.y1 && b.y0 < a.y1;
}

static rs_pixel_rect rect_union(rs_pixel_rect a, rs_pixel_rect b)
{
    rs_pixel_rect u = { a.x0 < b.x0 ? a.x0 : b.x0, a.y0 < b.y0 ? a.y0 : b.y0, a.x1 > b.x1 ? a.x1 : b.x1,
                        a.y1 > b.y1 ? a.y1 : b.y1 };
    return u;
}

/* Rectangles in rows, then columns (the patch rectangles; their candidates) */
static int cmp_rect(const void *pa, const void *pb)
{
    const rs_pixel_rect *a = pa, *b = pb;
    if (a->y0 != b->y0) return a->y0 < b->y0 ? -1 : 1;
    return (a->x0 > b->x0) - (a->x0 < b->x0);
}

static void sort_rects(rs_pixel_rect *r, size_t n)
{
    if (n > 1) qsort(r, n, sizeof *r, cmp_rect);
}

/* Most rectangles one update draws in (its local build serves them all):
 * the changed area's disjoint rectangles, the pairs whose union adds least
 * merged down to this many */
#define MAX_RECTS 8
/* Two rectangles whose union adds at most this much are made one: each
 * rectangle costs its own candidates pass (80 m x 80 m; a small edit's
 * boxes then give one rectangle) */
#define RECT_WASTE_M2 6400.0
/* More boxes or disjoint rectangles than these (an edit all over the
 * map): their bounding box */
#define MAX_BOXES 4096
#define MAX_PIECES 256

static int cmp_x0(const void *pa, const void *pb)
{
    const rs_pixel_rect *a = pa, *b = pb;
    return (a->x0 > b->x0) - (a->x0 < b->x0);
}

/* The union of R[0..n) as disjoint rectangles into *out (the caller's):
 * between each two consecutive y edges, the x runs the rectangles cover;
 * a run the same as one of the slab above extends that one. Their count,
 * or SIZE_MAX out of memory or past MAX_PIECES. */
static size_t disjoint_rects(rs_ctx *ctx, const rs_pixel_rect *R, size_t n, rs_pixel_rect **out)
{
    uint32_t *ys = rs__alloc_array(ctx, 2 * n, sizeof *ys);
    rs_pixel_rect *iv = rs__alloc_array(ctx, n, sizeof *iv), *D = rs__alloc_array(ctx, MAX_PIECES, sizeof *D);
    size_t *above = rs__alloc_array(ctx, 2 * MAX_PIECES, sizeof *above), *here = above ? above + MAX_PIECES : NULL;
    size_t nd = SIZE_MAX, na = 0;
    if (!ys || !iv || !D || !above) goto done;
    for (size_t i = 0; i < n; i++) ys[2 * i] = R[i].y0, ys[2 * i + 1] = R[i].y1;
    qsort(ys, 2 * n, sizeof *ys, rs__cmp_u32);
    size_t ny = 0;
    for (size_t i = 0; i < 2 * n; i++)
        if (!ny || ys[i] != ys[ny - 1]) ys[ny++] = ys[i];
    nd = 0;
    for (size_t k = 0; k + 1 < ny; k++) {
        uint32_t y0 = ys[k], y1 = ys[k + 1];
        size_t m = 0, nh = 0;
        for (size_t i = 0; i < n; i++)
            if (R[i].y0 <= y0 && R[i].y1 >= y1) iv[m++] = R[i];
        if (m > 1) qsort(iv, m, sizeof *iv, cmp_x0);
        for (size_t i = 0; i < m;) {
            uint32_t x0 = iv[i].x0, x1 = iv[i].x1;
            for (i++; i < m && iv[i].x0 <= x1; i++) x1 = iv[i].x1 > x1 ? iv[i].x1 : x1;
            size_t j = 0;
            while (j < na && !(D[above[j]].x0 == x0 && D[above[j]].x1 == x1)) j++;
            if (j < na) {
                D[above[j]].y1 = y1;
                here[nh++] = above[j];
                continue;
            }
            if (nd == MAX_PIECES) { nd = SIZE_MAX; goto done; }
            rs_pixel_rect e = { x0, y0, x1, y1 };
            here[nh++] = nd;
            D[nd++] = e;
        }
        memcpy(above, here, nh * sizeof *above);
        na = nh;
    }
done:
    rs__free(ctx, ys);
    rs__free(ctx, iv);
    rs__free(ctx, above);
    if (nd == SIZE_MAX) rs__free(ctx, D);
    else *out = D;
    return nd;
}

/* The patch rectangles of the changed boxes: each box's pixels in whole
 * DEM cells (pieces never straddle a patch's rows) within the W x H image,
 * their union as disjoint rectangles (a long or winding road's strip, not
 * its bounding box), the pair whose union adds least merged while there
 * are more than MAX_RECTS, and an older patch of `old` that one overlaps
 * taken into it (gone[k] = 1) while that takes no more pixels than the two
 * and at most doubles it (a road dragged, or edits near each other, keep
 * one patch instead of a patch each: the whole build at max_patches comes
 * later). The rectangles end disjoint and in row order. *out the
 * caller's; -1 when a box is not a number, -2 out of memory. */
static int change_rects(rs_ctx *ctx, const boxes *B, const rs_dem *dem, double pix, uint32_t W, uint32_t H,
                        uint32_t Tx, const rs_road_grid *old, uint8_t *gone, rs_pixel_rect **out, size_t *nout)
{
    *out = NULL;
    *nout = 0;
    rs_pixel_rect *R = rs__alloc_array(ctx, B->n ? B->n : 1, sizeof *R);
    if (!R) return -2;
    size_t n = 0;
    for (size_t k = 0; k < B->n; k++) {
        const double *b = B->v + 4 * k;
        double fx0 = floor((b[0] - dem->frame.origin_x) / pix), fy0 = floor((b[1] - dem->frame.origin_y) / pix);
        double fx1 = ceil((b[2] - dem->frame.origin_x) / pix), fy1 = ceil((b[3] - dem->frame.origin_y) / pix);
        if (!(fx0 == fx0 && fy0 == fy0 && fx1 == fx1 && fy1 == fy1)) {
            rs__free(ctx, R);
            return -1;
        }
        fx0 = fmax(fx0, 0), fy0 = fmax(fy0, 0), fx1 = fmin(fx1, W), fy1 = fmin(fy1, H);
        if (!(fx0 < fx1 && fy0 < fy1)) continue;
        rs_pixel_rect r;
        r.x0 = (uint32_t)fx0 / Tx * Tx, r.y0 = (uint32_t)fy0 / Tx * Tx;
        r.x1 = ((uint32_t)fx1 + Tx - 1) / Tx * Tx, r.y1 = ((uint32_t)fy1 + Tx - 1) / Tx * Tx;
        r.x1 = r.x1 < W ? r.x1 : W, r.y1 = r.y1 < H ? r.y1 : H;
        R[n++] = r;
    }
    const double wf = RECT_WASTE_M2 / (pix * pix);
    const uint64_t rect_waste = wf < 1e15 ? (uint64_t)wf : (uint64_t)1e15;
    rs_pixel_rect *D = NULL;
    size_t nd = n > 1 && n <= MAX_BOXES ? disjoint_rects(ctx, R, n, &D) : SIZE_MAX;
    if (nd != SIZE_MAX) {
        rs__free(ctx, R);
        R = D;
        n = nd;
    } else if (n > 1) { /* (one box, or too many: their bounding box) */
        for (size_t k = 1; k < n; k++) R[0] = rect_union(R[0], R[k]);
        n = 1;
    }
    for (int again = 1; again;) {
        again = 0;
        for (size_t i = 0; i < n; i++) /* (a union below may meet a third) */
            for (size_t j = i + 1; j < n; j++)
                if (rects_meet(R[i], R[j])) {
                    R[i] = rect_union(R[i], R[j]);
                    R[j] = R[--n];
                    j = i; /* (R[i] grew: from its next again) */
                    again = 1;
                }
        if (n > 1) {
            size_t bi = 0, bj = 1;
            uint64_t best = UINT64_MAX;
            for (size_t i = 0; i < n; i++)
                for (size_t j = i + 1; j < n; j++) {
                    uint64_t add = rect_area(rect_union(R[i], R[j])) - rect_area(R[i]) - rect_area(R[j]);
                    if (add < best) best = add, bi = i, bj = j;
                }
            if (n > MAX_RECTS || best <= rect_waste) {
                R[bi] = rect_union(R[bi], R[bj]);
                R[bj] = R[--n];
                again = 1;
                continue;
            }
        }
        for (size_t i = 0; i < n; i++)
            for (size_t k = 0; k < old->npatch; k++) {
                rs_pixel_rect q = old->patch[k].rect, u = rect_union(R[i], q);
                if (gone[k] || !rects_meet(R[i], q)) continue;
                uint64_t au = rect_area(u), an = rect_area(R[i]);
                if (au > an + rect_area(q) || au > 2 * an || au * 4 > (uint64_t)W * H) continue;
                R[i] = u, gone[k] = 1, again = 1;
            }
    }
    sort_rects(R, n); /* (the dirty rectangles come out in that order) */
    *out = R;
    *nout = n;
    return 0;
}

/* One pass over the nodes of N: those where a road marked in m has a leg
 * into *on (the caller's, rs__free; NULL with no nodes), their count
 * returned; per road end the node holding it into *at (2 per road,
 * UINT32_MAX: none, a short record's); with moved (per road, or NULL),
 * the nodes not in *on where a moved road passes (its stroke's length or
 * arc lengths changed: a T end there may come or go, run_flips) into *rn
 * (NULL when none). SIZE_MAX when out of memory. */
static size_t scan_nodes(rs_ctx *ctx, const rs_network *N, const uint8_t *m, const uint8_t *moved, uint8_t **on,
                         uint32_t **at, uint8_t **rn)
{
    *on = NULL, *at = NULL, *rn = NULL;
    if (!N || !N->nnodes) return 0;
    size_t nr = rs_network_road_count(N);
    *on = rs__calloc(ctx, N->nnodes, 1);
    *at = rs__alloc_array(ctx, 2 * (nr ? nr : 1), sizeof **at);
    if (!*on || !*at) return SIZE_MAX;
    for (size_t k = 0; k < 2 * nr; k++) (*at)[k] = UINT32_MAX;
    size_t n = 0;
    for (size_t d = 0; d < N->nnodes; d++) {
        int mk = 0, mv = 0;
        for (uint32_t l = N->leg_start[d]; l < N->leg_start[d + 1]; l++) {
            const rs_network_leg *L = &N->leg[l];
            mk |= m[L->road];
            if (rs__is_end_leg(L)) (*at)[rs__leg_end(L)] = (uint32_t)d;
            if (moved && moved[L->road] && rs__leg_passes(N, L)) mv = 1;
        }
        (*on)[d] = (uint8_t)mk;
        n += mk != 0;
        if (mv && !mk) {
            if (!*rn && !(*rn = rs__calloc(ctx, N->nnodes, 1))) return SIZE_MAX;
            (*rn)[d] = 1;
        }
    }
    return n;
}

/* The nodes of B that hold the same end of a road as a node of A in onA
 * (1: marked there; map: A's road to B's, UINT32_MAX: none; atB: B's
 * road ends' nodes, scan_nodes) marked in onB too (2), *nb counting
 * them. A node can change without a changed road of its own there: a new
 * road ending on an old T end's point makes that end no longer free, and
 * its T (and the strip running from it) goes (fuzz/edits); every node
 * holds a road end or two roads' points, and where only passing roads
 * meet there is no T end. */
static void mark_across(const rs_network *A, const uint8_t *onA, const uint32_t *atB, uint8_t *onB, const uint32_t *map,
                        size_t *nb)
{
    if (!A || !onA || !onB || !atB) return;
    for (size_t d = 0; d < A->nnodes; d++) {
        if (onA[d] != 1) continue; /* (2: marked from the other network) */
        for (uint32_t l = A->leg_start[d]; l < A->leg_start[d + 1]; l++) {
            const rs_network_leg *L = &A->leg[l];
            uint32_t i = rs__is_end_leg(L) ? map[L->road] : UINT32_MAX;
            uint32_t db = i == UINT32_MAX ? UINT32_MAX : atB[2 * (size_t)i + (L->kind == RS_LEG_END)];
            if (db != UINT32_MAX && !onB[db]) onB[db] = 2, (*nb)++;
        }
    }
}

/* The nodes rn of N, the new network (scan_nodes: where a kept road
 * passes whose stroke's length or arc lengths changed elsewhere, a record
 * of it moved, split or joined; mark_across: the ends that stood where
 * it passed in the old network), where a kept road's end became a T or
 * stopped being one: the street now runs on past the T far enough for
 * the end's strip, or no longer does (tee_ends.c strip_on_street). Marked
 * in `on`, *non counting them; m_new: N's road to the old one's; tfar:
 * the old ends' T lines (NaN: no T). RS_OK, RS_ERR_NOMEM or
 * RS_ERR_CANCELLED. */
static rs_result run_flips(rs_ctx *ctx, const rs_network *N, const rs_roads *roads, const uint8_t *rn, const uint32_t *m_new,
                     const double *tfar, uint8_t *on, size_t *non)
{
    if (!rn || !tfar) return RS_OK;
    rs__tee_end *te = NULL;
    uint8_t *isT = NULL;
    size_t nte = 0, nr = rs_network_road_count(N);
    rs_result r = rs__tee_ends_at(ctx, roads, N, rn, &te, &nte);
    if (!r && !(isT = rs__calloc(ctx, 2 * (nr ? nr : 1), 1))) r = RS_ERR_NOMEM;
    for (size_t k = 0; !r && k < nte; k++) isT[2 * (size_t)te[k].road + (te[k].end ? 1 : 0)] = 1;
    for (size_t d = 0; !r && d < N->nnodes; d++)
        for (uint32_t l = N->leg_start[d]; rn[d] && !on[d] && l < N->leg_start[d + 1]; l++) {
            const rs_network_leg *L = &N->leg[l];
            if (!rs__is_end_leg(L)) continue;
            uint32_t i = m_new[L->road];
            int e = L->kind == RS_LEG_END, was = i != UINT32_MAX && !isnan(tfar[2 * (size_t)i + (size_t)e]);
            if (was != isT[rs__leg_end(L)]) on[d] = 1, (*non)++;
        }
    rs__free(ctx, te);
    rs__free(ctx, isT);
    return r;
}

/* At every node of N in `on` (scan_nodes of m), the other legs'
 * segments there (the leg's segment or point and the segments on either
 * side: a T or a junction on a segment changes how that capsule is drawn
 * all along it) into the boxes acc, grown by `grow`; map: N's road to a road of
 * `roads` (UINT32_MAX: none, then the road is marked itself). */
static void neighbour_segments(const rs_network *N, const uint8_t *on, const uint8_t *m, const uint32_t *map,
                               const rs_roads *roads, boxes *acc, double grow)
{
    for (size_t d = 0; on && d < N->nnodes; d++) {
        if (!on[d]) continue;
        for (uint32_t l = N->leg_start[d]; l < N->leg_start[d + 1]; l++) {
            const rs_network_leg *L = &N->leg[l];
            uint32_t q = map ? map[L->road] : L->road;
            if (m[L->road] || q == UINT32_MAX) continue;
            const double *xy;
            size_t np;
            rs_roads_get(roads, q, NULL, NULL, &xy, &np);
            if (!np) continue;
            size_t a = L->segment > 0 ? L->segment - 1 : 0, b = L->segment + 2 < np ? L->segment + 2 : np - 1;
            if (L->kind == RS_LEG_END) a = np >= 2 ? np - 2 : 0, b = np - 1;
            if (a > b) a = b;
            path_boxes(acc, xy, a, b, grow);
        }
    }
}

/* The T ends at the nodes of N in `on` (scan_nodes of m: `non` of
 * them), of records not marked (map: N's road to a road of `roads`, UINT32_MAX:
 * gone): the segments inward from the end segment that its T line clips
 * (rs__roadfield_set_tees: each while it reaches past the line; a record
 * that turns back across the through road loses all of itself beyond the
 * line there, however far from the T) into the boxes acc, grown by `grow`. The
 * new network's ends (map NULL) with their lines from the roads, written
 * into tfar and their strips into tstrip (the ends at those nodes: NaN
 * when no T); an old one's from the network alone (its roads are gone),
 * their lines' far from tfar and their strips from tstrip (the track's:
 * a changed or removed road's strip where it was). The capsules are taken
 * wider by `extra` (a casing and a field's index cell at most): a superset
 * of what a build clips. Each T end's strip too (strip_params; its half
 * width wider by `wider`, the casing at most). *known = 0 when an old
 * end's line or strip is not in tfar and tstrip. */
static rs_result tee_clips(rs_ctx *ctx, const rs_network *N, const uint8_t *on, size_t non, const uint8_t *m,
                           const uint32_t *map, const rs_roads *roads, boxes *acc, double grow, double extra,
                           double wider, double *tfar, double *tstrip, int *known)
{
    rs__tee_end *te = NULL;
    size_t nte = 0;
    rs_result r = non ? rs__tee_ends_at(ctx, map ? NULL : roads, N, on, &te, &nte) : RS_OK;
    if (!r && !map && tfar && tstrip) {
        for (size_t d = 0; d < N->nnodes; d++)
            for (uint32_t l = N->leg_start[d]; on[d] && l < N->leg_start[d + 1]; l++)
                if (rs__is_end_leg(&N->leg[l])) {
                    size_t e = rs__leg_end(&N->leg[l]);
                    tfar[e] = NAN;
                    strip_none(tstrip + TS * e);
                }
        tee_fars(tfar, te, nte);
        tee_strips(tstrip, te, nte, roads);
    }
    for (size_t k = 0; !r && k < nte; k++) {
        const rs__tee_end *t = &te[k];
        uint32_t q = map ? map[t->road] : t->road;
        size_t e = 2 * (size_t)t->road + (t->end ? 1 : 0);
        double far = !map ? t->far : tfar ? tfar[e] : NAN;
        if (map) { /* (an old end: its strip where it was, its road changed or gone) */
            /* (NaN: the build made no T there, its street running on too
             * short a way: tee_ends.c strip_on_street) */
            if (!(far > -INFINITY && far < INFINITY)) continue;
            if (!tstrip) {
                *known = 0;
                continue;
            }
            strip_add(acc, tstrip + TS * e, wider, grow);
        }
        if (q == UINT32_MAX) continue; /* (a road gone: its boxes are in) */
        const double *xy;
        size_t np;
        double w = 0;
        rs_roads_get(roads, q, NULL, &w, &xy, &np);
        size_t ke = rs__end_segment(xy, np, t->end); /* (none: a build has no T there) */
        if (ke == SIZE_MAX) continue;
        double margin = 0.5 * w + extra;
        if (!(margin < INFINITY && far > -INFINITY && far < INFINITY)) { /* (NaN: an old end not known as a T) */
            if (!m[t->road]) *known = 0;
            continue;
        }
        const double *E = xy + 2 * (t->end ? np - 1 : 0);
        if (!map && tstrip) strip_add(acc, tstrip + TS * e, wider, grow); /* (tee_strips' above) */
        /* (a marked road's boxes are in; a road of two points has no
         * segment inward: neighbour_segments took its end segment) */
        if (m[t->road] || np < 3) continue;
        double line = t->nx * E[0] + t->ny * E[1] + far - margin;
        /* (the other end's segment, and its strip when that end is a T:
         * the segment's trimmed shape there reaches as far as the strip,
         * and a clip takes the strip with it; the seed 2f282ac0's
         * neighbour b0e8f047: a hairpin's start became a T whose line
         * clipped its far end, strip and all, 28 m away) */
        size_t ko = rs__end_segment(xy, np, !t->end);
        const double *so = tstrip && ko != SIZE_MAX ? tstrip + TS * (2 * (size_t)t->road + (t->end ? 0 : 1)) : NULL;
        double ob[4];
        int has_o = so && strip_box(so, wider, ob);
        size_t lo = SIZE_MAX, hi = 0; /* (the segments clipped: points lo..hi) */
        for (size_t step = 1;; step++) {
            if (t->end ? ke < step : ke + step + 1 >= np) break;
            size_t i = t->end ? ke - step : ke + step;
            const double *a = xy + 2 * i, *b = a + 2;
            double reach = fmax(t->nx * a[0] + t->ny * a[1], t->nx * b[0] + t->ny * b[1]);
            if (i == ko && has_o) /* (the strip box's far corner along n) */
                reach = fmax(reach, t->nx * (t->nx > 0 ? ob[2] : ob[0]) + t->ny * (t->ny > 0 ? ob[3] : ob[1]));
            if (!(reach > line)) break;
            lo = i < lo ? i : lo, hi = i + 1 > hi ? i + 1 : hi;
            if (i == ko && has_o) boxes_add(acc, ob, grow);
        }
        if (lo < hi) path_boxes(acc, xy, lo, hi, grow);
    }
    rs__free(ctx, te);
    return r;
}

/* Whether local grid q draws in one of g's patches already (one update's
 * rectangles share one: its memory is counted once). */
static int grid_held(const rs_road_grid *g, const rs_road_grid *q)
{
    for (size_t k = 0; k < g->npatch; k++)
        if (g->patch[k].grid == q) return 1;
    return 0;
}

/* g's next patch (its entry filled) counted in: its grid's memory once
 * (one update's rectangles share one), its roads' ids each. */
static void patch_counted(rs_road_grid *g)
{
    const rs__grid_patch *d = &g->patch[g->npatch];
    g->stats.bytes += (grid_held(g, d->grid) ? 0 : d->grid->stats.bytes) + d->n * sizeof *d->ids;
    g->npatch++;
}

/* Patch q of another grid, shared (its grid held), appended to g's
 * patches (room made by the caller); map: q's road ids to g's (NULL: the
 * same, nmap unused). 0, or -1 out of memory. */
static int patch_take(rs_ctx *ctx, rs_road_grid *g, const rs__grid_patch *q, const uint32_t *map, size_t nmap)
{
    rs__grid_patch *d = &g->patch[g->npatch];
    if (!(d->ids = rs__alloc_array(ctx, q->n ? q->n : 1, sizeof *d->ids))) return -1;
    for (size_t i = 0; i < q->n; i++) d->ids[i] = !map ? q->ids[i] : q->ids[i] < nmap ? map[q->ids[i]] : UINT32_MAX;
    d->n = q->n;
    d->rect = q->rect;
    d->grid = q->grid;
    rs__grid_hold(d->grid);
    patch_counted(g);
    return 0;
}

/* Whether two sets of map-wide facts draw alike: the same style
 * switches (styled, a surface image, one fill everywhere and its colour,
 * one casing colour and it, any casing at all) and the same casing field
 * form in a road field of this index cell (the casings within a cell:
 * merged into the road field's, else a field of their own). */
static int same_switches(const rs__grid_facts *a, const rs__grid_facts *b, double cell)
{
    return a->styled == b->styled && a->any_surface == b->any_surface && a->fill_uniform == b->fill_uniform &&
           (!a->fill_uniform || !memcmp(a->fill_rgba, b->fill_rgba, sizeof a->fill_rgba)) &&
           a->casing_uniform == b->casing_uniform &&
           (!a->casing_uniform || !memcmp(a->casing_rgba, b->casing_rgba, sizeof a->casing_rgba)) &&
           (a->widest_casing > 0) == (b->widest_casing > 0) && (a->widest_casing <= cell) == (b->widest_casing <= cell) &&
           a->ranked == b->ranked;
}

/* ---- the patched grid ------------------------------------------------------ */

static int road_near(const rs_roads *roads, size_t i, const double *rb, const double *bx, double d)
{
    if (rb[0] > bx[2] + d || rb[2] < bx[0] - d || rb[1] > bx[3] + d || rb[3] < bx[1] - d) return 0;
    const double *xy;
    size_t np;
    rs_roads_get(roads, i, NULL, NULL, &xy, &np);
    for (size_t k = 0; k + 1 < np || (np == 1 && k == 0); k++) {
        const double *a = xy + 2 * k, *b = xy + 2 * (np == 1 ? k : k + 1);
        if (rs__capsule_meets_box(a[0], a[1], b[0], b[1], d, bx[0], bx[1], bx[2], bx[3])) return 1;
    }
    return 0;
}

rs_result rs__grid_update_patched(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                                  const rs_road_grid *old, rs_road_grid **out)
{
    *out = NULL;
    const rs_road_grid *base = old->base ? old->base : old;
    const rs__grid_track *T = old->track;
    if (!T || o->coverage.edges != RS_EDGES_ANALYTIC || !base->field) return RS_OK;
    size_t nn = rs_roads_count(roads), no = T->n;
    uint64_t *pn = NULL, *sp = NULL;
    rs__road_sum *sm = NULL;
    rs_style *ys = NULL;
    double *bn = NULL, reach = 0, max_width = 0, *tf = NULL, *ts = NULL;
    rs__grid_facts facts;
    rs_network *net = NULL;
    uint32_t *m_old = rs__alloc_array(ctx, no ? no : 1, sizeof *m_old);
    uint32_t *m_new = rs__alloc_array(ctx, nn ? nn : 1, sizeof *m_new);
    rs_road_grid *g = NULL;
    rs_pixel_rect *dirty = NULL;
    size_t ndirty = 0, nrect = 0;
    rs__grid_patch *fresh = NULL; /* the new patches (nrect), theirs until the grid takes them */
    uint8_t *gone = NULL; /* old patches inside a new one */
    rs__grid_track *nt = NULL;
    rs__road_chunks ch; /* the new roads' boxes along them */
    memset(&ch, 0, sizeof ch);
    rs_result r = m_old && m_new ? RS_OK : RS_ERR_NOMEM;
    double mark_reach = 0;
    if (!r) r = raw_prints(ctx, roads, &pn, &bn, &max_width, &mark_reach);
    if (!r) r = match_roads(ctx, T->print, no, pn, nn, m_old, m_new);
    if (!r) r = chunks_make(ctx, roads, bn, m_new, &T->chunks, &ch);
    /* the roads' styles: an unchanged road's kept while the named styles,
     * profile and side are the same; else resolved again, and a road whose
     * style changed no match */
    if (!r && (!(sp = rs__alloc_array(ctx, nn ? nn : 1, sizeof *sp)) || !(sm = rs__alloc_array(ctx, nn ? nn : 1, sizeof *sm)) ||
               !(ys = rs__malloc(ctx, sizeof *ys))))
        r = RS_ERR_NOMEM;
    const uint64_t sctx = styles_print(o);
    for (size_t j = 0; j < nn && !r; j++) {
        uint32_t i = m_new[j];
        if (i != UINT32_MAX && sctx == T->sctx) {
            /* (a run of roads matched in order in one copy: a sum's struct
             * copy was a string move) */
            size_t e = matched_run(m_new, nn, j);
            memcpy(sp + j, T->sprint + i, (e - j) * sizeof *sp);
            memcpy(sm + j, T->sum + i, (e - j) * sizeof *sm);
            j = e - 1;
            continue;
        }
        if ((r = road_sum(ctx, roads, j, o, ys, &sp[j], &sm[j])) != RS_OK) break;
        if (i != UINT32_MAX && sp[j] != T->sprint[i]) m_new[j] = UINT32_MAX, m_old[i] = UINT32_MAX;
    }
    if (!r) facts_of(sm, nn, o->style.disable, mark_reach, &facts, &reach);
    if (r) goto done;
    /* the whole map's switches must stand (a casing colour, a fill: the
     * whole map draws otherwise). The index cell stays the base's (a
     * pixel does not depend on it), but the casing field's form does: the
     * casings within a cell of the base's field, and of the field a whole
     * build of these roads would index. */
    /* (the base's: a rebased grid's base was built from other roads than
     * its track's, rs_road_grid_rebase) */
    const double base_cell = rs__roadfield_cell(base->field);
    facts.index_cell = base_cell;
    {
        rs__roadfield_params fp = rs__roadfield_params_for_dem(dem, o->texels);
        double cell_new = rs__roadfield_cell_for(roads, &fp);
        if (!same_switches(&T->facts, &facts, base_cell) ||
            (facts.widest_casing <= base_cell) != (facts.widest_casing <= cell_new))
            goto done;
    }
    if (!o->style.disable && nn > 0) {
        /* the old network where the edit left it, else built whole */
        double zone[4] = { INFINITY, INFINITY, -INFINITY, -INFINITY };
        for (size_t i = 0; i < no; i++)
            if (m_old[i] == UINT32_MAX) box_add(zone, T->box + 4 * i, 0);
        for (size_t j = 0; j < nn; j++)
            if (m_new[j] == UINT32_MAX) box_add(zone, bn + 4 * j, 0);
        if (T->net && T->net->node_key &&
            (r = rs__network_update(ctx, roads, T->net, m_old, m_new, bn, zone, 0.5 * widest(T->max_width, max_width),
                                    &net)) != RS_OK)
            goto done;
        if (!net && (r = rs_network_build(ctx, roads, NULL, &net)) != RS_OK) goto done;
    }
    /* the changed area: roads gone or new, and records whose place in
     * their stroke changed (their dashes move) */
    boxes chg;
    memset(&chg, 0, sizeof chg);
    chg.ctx = ctx;
    const double grow = 2 * reach + CHANGE_PAD;
    uint8_t *cn = rs__calloc(ctx, nn ? nn : 1, 1), *co = rs__calloc(ctx, no ? no : 1, 1);
    if (!cn || !co) {
        rs__free(ctx, cn);
        rs__free(ctx, co);
        r = RS_ERR_NOMEM;
        goto done;
    }
    for (size_t i = 0; i < no; i++) co[i] = m_old[i] == UINT32_MAX;
    /* arc: records that only moved along their stroke and draw the same
     * there (lines, image, ring: changed whole) */
    uint8_t *arc = NULL;
    size_t narc = 0;
    for (size_t j = 0; j < nn; j++) {
        uint32_t i = m_new[j];
        int pc = i == UINT32_MAX || (!net) != (!T->net) ? 2
                 : net && T->net                          ? place_change(T->net, net, i, (uint32_t)j, m_old)
                                                          : 0;
        if (pc == 1 && !sm[j].lines && !sm[j].image && (arc || (arc = rs__calloc(ctx, nn, 1)))) {
            arc[j] = 1;
            narc++;
            continue;
        }
        cn[j] = pc != 0;
    }
    for (size_t i = 0; i < no; i++)
        if (co[i]) road_boxes(&chg, T->box, &T->chunks, i, grow);
    if (narc) {
        /* their zones (place_change's comment); a zone's reach: a junction's
         * area on both streets (half the widest road and 0.5 m each), the
         * give-way line or arrow before it (6 m and the arrow) and a road's
         * half width across, beyond the changed boxes' own growth */
        const double wmax = widest(T->max_width, max_width), d = wmax + 2;
        const double zone = fmax(grow, 1.5 * wmax + 13 + mark_reach);
        int whole = !(zone < 1e300);
        /* a moved record whose end lies within a street's junction reach
         * (half the widest road and 0.5 m) of a changed one along the
         * stroke: the street's end may have come or gone there, which
         * decides whether it passes a junction that near (markings_auto's
         * street_passes); a zone at that end, as far again */
        const double hb = 0.5 * wmax + 1.5;
        for (size_t j = 0; j < nn && !whole; j++) {
            if (!arc[j]) continue;
            for (int e = 0; e < 2; e++) {
                /* along the stroke from end e: before j at its start unless reversed */
                int back = (e == 0) != (net->rev[j] != 0), near = 0;
                uint32_t lk = net->link[2 * j + (size_t)e];
                near = lk != UINT32_MAX && cn[lk / 2];
                double run = 0;
                size_t steps = 0;
                for (uint32_t q = back ? net->prev[j] : net->next[j];
                     !near && q != UINT32_MAX && run <= hb && steps <= nn; q = back ? net->prev[q] : net->next[q], steps++) {
                    near = cn[q];
                    run += net->length[q];
                }
                double x, y;
                if (near && road_end(roads, j, e, &x, &y)) point_zone(&chg, x, y, zone + hb);
            }
        }
        /* the strokes holding one, before and after */
        uint8_t *sn = rs__calloc(ctx, net->nstrokes ? net->nstrokes : 1, 1);
        uint8_t *so = rs__calloc(ctx, T->net->nstrokes ? T->net->nstrokes : 1, 1);
        uint32_t *recs = rs__alloc_array(ctx, 2 * SELF_MAX, sizeof *recs);
        if (!sn || !so || !recs) whole = 1, chg.nomem = 1;
        size_t nst = 0;
        for (size_t j = 0; j < nn && !whole; j++)
            if (arc[j]) {
                nst += !sn[net->stroke_of[j]] + !so[T->net->stroke_of[m_new[j]]];
                sn[net->stroke_of[j]] = so[T->net->stroke_of[m_new[j]]] = 1;
            }
        whole |= nst > ZONE_STROKES; /* (each stroke's free ends scan every road) */
        uint32_t *nbrk = recs ? recs + SELF_MAX : NULL;
        for (size_t k = 0; k < net->nstrokes && !whole; k++)
            if (sn[k]) whole |= stroke_zones(&chg, net, k, T->net, m_new, NULL, bn, roads, bn, nn, d, zone, recs, nbrk);
        for (size_t k = 0; k < T->net->nstrokes && !whole; k++)
            if (so[k])
                whole |= stroke_zones(&chg, T->net, k, net, m_old, m_old, T->box, roads, bn, nn, d, zone, recs, nbrk);
        rs__free(ctx, sn);
        rs__free(ctx, so);
        rs__free(ctx, recs);
        if (whole) /* (too many, or too big: taken whole) */
            for (size_t j = 0; j < nn; j++) cn[j] |= arc[j];
    }
    rs__free(ctx, arc);
    for (size_t j = 0; j < nn; j++)
        if (cn[j]) road_boxes(&chg, bn, &ch, j, grow);
    /* the segments of the roads meeting a changed one, in the new network
     * and the old (old roads by their new index: the unmatched are changed) */
    /* (the nodes of both networks where a changed road has a leg) */
    uint8_t *on_n = NULL, *on_o = NULL, *rn = NULL, *rn_o = NULL, *moved = NULL;
    uint32_t *at_n = NULL, *at_o = NULL;
    /* (kept roads whose stroke's length or arc lengths changed: run_flips) */
    int look = net && T->net && T->tfar && nn;
    if (look && (moved = rs__calloc(ctx, nn, 1)))
        for (size_t j = 0; j < nn; j++) {
            uint32_t i = m_new[j];
            moved[j] = i != UINT32_MAX && (net->s_len[j] != T->net->s_len[i] || net->s_off[j] != T->net->s_off[i] ||
                                           net->rev[j] != T->net->rev[i]);
        }
    /* (the same roads by their old index: the old network's nodes where they pass) */
    uint8_t *moved_o = moved ? rs__calloc(ctx, rs_network_road_count(T->net) ? rs_network_road_count(T->net) : 1, 1)
                             : NULL;
    for (size_t j = 0; moved_o && j < nn; j++)
        if (moved[j]) moved_o[m_new[j]] = 1;
    size_t non_n = scan_nodes(ctx, net, cn, moved, &on_n, &at_n, &rn);
    size_t non_o = scan_nodes(ctx, T->net, co, moved_o, &on_o, &at_o, &rn_o);
    int known = non_n != SIZE_MAX && non_o != SIZE_MAX && (moved_o || !look); /* (0: the whole build) */
    /* (and the ends that stood where one passed in the old network: an end
     * inside a street's surface has the street's legs at its node only
     * while it is a T there, so when the street's run changes, the new
     * network may hold it alone, where no moved road passes: fuzz/edits) */
    if (known && rn_o) {
        size_t nf = 0;
        if (!rn && !(rn = rs__calloc(ctx, net->nnodes ? net->nnodes : 1, 1))) known = 0;
        else mark_across(T->net, rn_o, at_n, rn, m_old, &nf);
    }
    rs__free(ctx, moved_o);
    /* (a street's run past a T changed: its strip came or went) */
    if (known && (r = run_flips(ctx, net, roads, rn, m_new, T->tfar, on_n, &non_n)) != RS_OK) known = 0;
    if (known) { /* (each network's nodes where the other's changed: their T ends) */
        mark_across(net, on_n, at_o, on_o, m_new, &non_o);
        mark_across(T->net, on_o, at_n, on_n, m_old, &non_n);
    }
    rs__free(ctx, moved);
    rs__free(ctx, rn);
    rs__free(ctx, rn_o);
    rs__free(ctx, at_n);
    rs__free(ctx, at_o);
    if (!known && !r) r = RS_ERR_NOMEM;
    if (known) {
        neighbour_segments(net, on_n, cn, NULL, roads, &chg, grow);
        neighbour_segments(T->net, on_o, co, m_old, roads, &chg, grow);
        /* the T lines of the ends at those nodes, before and after (a record
         * that turns back across the road it ends on is clipped far along:
         * fuzz/edits) */
        double wmax = widest(T->max_width, max_width), cas = fmax(T->facts.widest_casing, facts.widest_casing);
        double cell = base_cell;
        if (!(cas <= cell)) { /* (casings in a field of their own: its cell at most) */
            rs__roadfield_params fp = rs__roadfield_params_for_dem(dem, o->texels);
            cell = fmax(cell, rs__roadfield_cell_most(&fp, wmax + 2 * cas));
        } else cas = 0; /* (the casing field widens the road field's: its T's are those) */
        /* the capsule beyond the half width: a casing and an index cell, and
         * a slack above the roundings */
        double extra = cas + cell + 0.01;
        /* the new track's T lines and strips: the old ones' where the
         * nodes stand (a kept road's points are the same) */
        if (net && T->tfar && T->tstrip && (tf = rs__alloc_array(ctx, 2 * (nn ? nn : 1), sizeof *tf)) &&
            (ts = rs__alloc_array(ctx, 2 * TS * (nn ? nn : 1), sizeof *ts)))
            for (size_t j = 0; j < nn; j++) {
                if (m_new[j] == UINT32_MAX) {
                    for (int e = 0; e < 2; e++) {
                        tf[2 * j + e] = NAN;
                        strip_none(ts + TS * (2 * j + (size_t)e));
                    }
                    continue;
                }
                /* (a run of roads matched in order in one copy) */
                size_t i = m_new[j], q = matched_run(m_new, nn, j);
                memcpy(tf + 2 * j, T->tfar + 2 * i, 2 * (q - j) * sizeof *tf);
                memcpy(ts + TS * 2 * j, T->tstrip + TS * 2 * i, TS * 2 * (q - j) * sizeof *ts);
                j = q - 1;
            }
        known = extra < INFINITY && (!net || (tf && ts));
        const double wider = fmax(T->facts.widest_casing, facts.widest_casing) + 0.01; /* (the strip's: a casing) */
        if (known && !r) r = tee_clips(ctx, net, on_n, non_n, cn, NULL, roads, &chg, grow, extra, wider, tf, ts, &known);
        if (known && !r)
            r = tee_clips(ctx, T->net, on_o, non_o, co, m_old, roads, &chg, grow, extra, wider, T->tfar, T->tstrip,
                          &known);
    }
    rs__free(ctx, on_n);
    rs__free(ctx, on_o);
    rs__free(ctx, cn);
    rs__free(ctx, co);
    if (!r && chg.nomem) r = RS_ERR_NOMEM;
    if (r || !known) {
        rs__free(ctx, chg.v);
        goto done;
    }
    /* the patch rectangles: the changed boxes' pixels, those near each
     * other made one, the older patches they mostly cover taken in */
    const double pix = dem->frame.cell_size / o->texels;
    const uint32_t W = (dem->width - 1) * o->texels, H = (dem->height - 1) * o->texels, Tx = o->texels;
    const double ctx_d = CONTEXT_PAD + 2 * reach;
    if (!(gone = rs__calloc(ctx, old->npatch ? old->npatch : 1, 1))) r = RS_ERR_NOMEM;
    {
        rs_pixel_rect *rv = NULL;
        size_t nr = 0;
        int cr = r ? 0 : change_rects(ctx, &chg, dem, pix, W, H, Tx, old, gone, &rv, &nr);
        rs__free(ctx, chg.v);
        if (cr == -2) r = RS_ERR_NOMEM;
        uint64_t area = 0;
        for (size_t k = 0; k < nr; k++) area += rect_area(rv[k]);
        int whole = r || cr || area * 4 > (uint64_t)W * H; /* (a large part of the map: the whole build is as cheap) */
        if (!whole && nr && !(fresh = rs__calloc(ctx, nr, sizeof *fresh))) r = RS_ERR_NOMEM, whole = 1;
        for (size_t k = 0; !whole && k < nr; k++) fresh[k].rect = rv[k];
        nrect = whole ? 0 : nr;
        rs__free(ctx, rv);
        if (whole) goto done;
    }
    /* one local build serves every rectangle: the roads that can reach a
     * pixel of one, indexed over their bounding box */
    if (nrect) {
        rs_pixel_rect hull = fresh[0].rect;
        for (size_t pk = 1; pk < nrect; pk++) hull = rect_union(hull, fresh[pk].rect);
        size_t m = 0;
        uint32_t *ids = rs__alloc_array(ctx, nn ? nn : 1, sizeof *ids);
        if (!ids) { r = RS_ERR_NOMEM; goto done; }
        fresh[0].ids = ids;
        uint8_t *in = rs__calloc(ctx, nn ? nn : 1, 1);
        if (!in) { r = RS_ERR_NOMEM; goto done; }
        for (size_t pk = 0; pk < nrect; pk++) {
            const rs_pixel_rect rect = fresh[pk].rect;
            double bx[4] = { dem->frame.origin_x + rect.x0 * pix, dem->frame.origin_y + rect.y0 * pix,
                             dem->frame.origin_x + rect.x1 * pix, dem->frame.origin_y + rect.y1 * pix };
            for (size_t j = 0; j < nn; j++)
                if (!in[j]) in[j] = (uint8_t)road_near(roads, j, bn + 4 * j, bx, ctx_d);
        }
        /* a stroke drawn both ways may be drawn record by record, which
         * its records decide together, and a ring's lines join at its seam
         * only when it is kept whole (rs__network_subset; the line symbols'
         * road_band_pieces): such a stroke is taken whole */
        for (size_t k = 0; net && k < net->nstrokes; k++) {
            uint32_t a = net->stroke_start[k], b = net->stroke_start[k + 1];
            int whole = net->closed && net->closed[k] && b - a > 1, any = 0; /* (a ring, or mixed below) */
            for (uint32_t e = a; e < b; e++) {
                whole |= net->rev[net->stroke_roads[e]] != net->rev[net->stroke_roads[a]];
                any |= in[net->stroke_roads[e]];
            }
            if (whole && any)
                for (uint32_t e = a; e < b; e++) in[net->stroke_roads[e]] = 1;
        }
        for (size_t j = 0; j < nn; j++)
            if (in[j]) ids[m++] = (uint32_t)j;
        rs__free(ctx, in);
        rs_splat_options lo = *o;
        lo.grid.edits = 1;
        /* (the base's built-in atlas, not one decoded again: the patch's
         * markings point into it, and every grid holding the patch holds
         * the base) */
        if (!lo.markings.atlas && base->markings && base->markings->atlas_own) lo.markings.atlas = base->markings->atlas_own;
        lo.progress = NULL;
        lo.progress_user = NULL;
        /* (its fields list only what its pixels and queries can read) */
        facts.window_on = 1;
        facts.window[0] = hull.x0 * pix, facts.window[1] = hull.y0 * pix;
        facts.window[2] = hull.x1 * pix, facts.window[3] = hull.y1 * pix;
        facts.window_reach = PATCH_QUERY_REACH;
        r = rs__road_grid_build_subset(ctx, dem, roads, &lo, net, &facts, ids, m, &fresh[0].grid);
        facts.window_on = 0; /* (the track keeps the whole map's facts) */
        if (r != RS_OK) goto done;
        if (lo.markings.atlas && !o->markings.atlas) { /* (the base's atlas: held while the patch lives) */
            fresh[0].grid->atlas_hold = (rs_road_grid *)base;
            rs__grid_hold(fresh[0].grid->atlas_hold);
        }
        fresh[0].n = m;
        for (size_t pk = 1; pk < nrect; pk++) { /* (each rectangle a patch of its own on the one grid) */
            if (!(fresh[pk].ids = rs__alloc_array(ctx, m ? m : 1, sizeof *ids))) { r = RS_ERR_NOMEM; goto done; }
            memcpy(fresh[pk].ids, ids, m * sizeof *ids);
            fresh[pk].n = m;
            fresh[pk].grid = fresh[0].grid;
            rs__grid_hold(fresh[pk].grid);
        }
    }
    /* the grid: the base's structures, the old patches (their roads
     * renumbered) but those taken into a new one, the new ones over them */
    g = rs__calloc(ctx, 1, sizeof *g);
    nt = rs__calloc(ctx, 1, sizeof *nt);
    size_t np = old->npatch + nrect;
    rs__grid_patch *P = rs__calloc(ctx, np ? np : 1, sizeof *P);
    if (!g || !nt || !P) {
        rs__free(ctx, P);
        r = RS_ERR_NOMEM;
        goto done;
    }
    *g = *base;
    g->refs = 1;
    g->base = (rs_road_grid *)base;
    g->patch = P;
    g->npatch = 0;
    g->dirty = NULL;
    g->ndirty = 0;
    g->track = NULL;
    rs__grid_hold(g->base);
    for (size_t k = 0; k < old->npatch; k++)
        if (!gone[k] && patch_take(ctx, g, &old->patch[k], m_old, no)) { /* (but those inside a new patch) */
            r = RS_ERR_NOMEM;
            goto done;
        }
    for (size_t pk = 0; pk < nrect; pk++) {
        P[g->npatch] = fresh[pk];
        memset(&fresh[pk], 0, sizeof fresh[pk]);
        patch_counted(g);
    }
    /* for the next update */
    nt->refs = 1;
    nt->n = nn;
    nt->print = pn;
    nt->sprint = sp;
    nt->sum = sm;
    nt->sctx = sctx;
    sp = NULL, sm = NULL;
    nt->box = bn;
    nt->chunks = ch;
    memset(&ch, 0, sizeof ch);
    nt->net = net;
    nt->facts = facts;
    nt->max_width = max_width;
    nt->tfar = tf;
    nt->tstrip = ts;
    tf = NULL, ts = NULL;
    nt->bytes = track_bytes(nt);
    pn = NULL, bn = NULL, net = NULL;
    g->track = nt;
    nt = NULL;
    g->stats.bytes += g->track->bytes - (base->track ? base->track->bytes : 0);
    /* the rectangles' pixels that change (the old grid drew them, the new
     * one draws them; nothing changes outside them): the pieces that
     * differ in each (a superset, mostly 2 to 6 times the changed pixels;
     * the rectangles are apart and in row order, so are their candidates),
     * then those pixels rendered under both grids and compared (when they
     * are few enough) */
    for (size_t pk = 0; pk < nrect; pk++) {
        rs_pixel_rect *c = NULL;
        size_t nc = 0;
        if ((r = rs__patch_candidates(ctx, old, g->patch[g->npatch - nrect + pk].grid, g->patch[g->npatch - nrect + pk].rect, &c,
                                         &nc)) != RS_OK)
            goto done;
        rs_pixel_rect *all = nc ? rs__realloc(ctx, dirty, (ndirty + nc) * sizeof *all) : dirty;
        if (nc && !all) {
            rs__free(ctx, c);
            r = RS_ERR_NOMEM;
            goto done;
        }
        if (nc) memcpy(all + ndirty, c, nc * sizeof *c);
        dirty = all;
        ndirty += nc;
        rs__free(ctx, c);
    }
    if (nrect > 1) sort_rects(dirty, ndirty);
    if (nrect && (r = rs__dirty_render(ctx, dem, o, old, g, &dirty, &ndirty)) != RS_OK) goto done;
    if (rs_road_grid_patch_count(g) > ctx->limits.max_patches) {
        /* too many patches: the whole grid, with this edit's exact
         * rectangles (the patched grid drew the same pixels) */
        rs_road_grid *w = NULL;
        rs_splat_options wo = *o;
        wo.grid.edits = 1;
        if ((r = rs_road_grid_build(ctx, dem, roads, &wo, &w)) != RS_OK) goto done;
        rs__free(ctx, w->edit->dirty);
        w->edit->dirty = dirty;
        w->edit->ndirty = ndirty;
        w->edit->bytes += ndirty * sizeof *dirty;
        w->stats.bytes += ndirty * sizeof *dirty;
        dirty = NULL;
        *out = w;
        goto done;
    }
    g->dirty = dirty;
    g->ndirty = ndirty;
    g->stats.bytes += ndirty * sizeof *dirty;
    dirty = NULL;
    *out = g;
    g = NULL;
done:
    rs__free(ctx, m_old);
    rs__free(ctx, m_new);
    rs__free(ctx, pn);
    rs__free(ctx, sp);
    rs__free(ctx, sm);
    rs__free(ctx, ys);
    rs__free(ctx, bn);
    chunks_free(ctx, &ch);
    rs__free(ctx, tf);
    rs__free(ctx, ts);
    for (size_t k = 0; k < nrect; k++) {
        rs_road_grid_free(ctx, fresh[k].grid);
        rs__free(ctx, fresh[k].ids);
    }
    rs__free(ctx, fresh);
    rs__free(ctx, gone);
    rs_network_free(ctx, net);
    rs__free(ctx, dirty);
    rs__grid_track_free(ctx, nt);
    rs_road_grid_free(ctx, g);
    return r;
}

int rs__grid_track_net_check(rs_ctx *ctx, const rs_road_grid *g, const rs_roads *roads)
{
    const rs__grid_track *t = g->track ? g->track : g->base ? g->base->track : NULL;
    if (!t || !t->net) return 1;
    rs_network *n = NULL;
    if (rs_network_build(ctx, roads, NULL, &n) != RS_OK) return -1;
    int eq = rs__network_equal(t->net, n);
    /* and its T lines and strips, as a build of `roads` finds them */
    size_t nr = rs_roads_count(roads);
    if (eq && t->tfar && t->tstrip && t->n == nr) {
        double *tf = NULL, *ts = NULL;
        if (tee_lines(ctx, roads, n, NULL, nr, &tf, &ts) != RS_OK) eq = -1;
        for (size_t k = 0; eq == 1 && k < 2 * nr; k++) eq = isnan(tf[k]) ? isnan(t->tfar[k]) : tf[k] == t->tfar[k];
        for (size_t k = 0; eq == 1 && k < 2 * TS * nr; k++)
            eq = isnan(ts[k]) ? isnan(t->tstrip[k]) : ts[k] == t->tstrip[k];
        rs__free(ctx, tf);
        rs__free(ctx, ts);
    }
    /* and the prints, boxes and chunks it keeps per road, as a track of
     * `roads` makes them (an update copies the kept roads' in runs) */
    if (eq == 1 && t->print && t->box && t->n == nr) {
        uint64_t *p = NULL;
        double *b = NULL, mw = 0, mr = 0;
        rs__road_chunks c;
        memset(&c, 0, sizeof c);
        if (raw_prints(ctx, roads, &p, &b, &mw, &mr) != RS_OK || chunks_make(ctx, roads, b, NULL, NULL, &c) != RS_OK)
            eq = -1;
        else
            eq = !memcmp(p, t->print, nr * sizeof *p) && !memcmp(b, t->box, 4 * nr * sizeof *b) && t->chunks.start &&
                 !memcmp(c.start, t->chunks.start, (nr + 1) * sizeof *c.start) &&
                 (!c.start[nr] || !memcmp(c.v, t->chunks.v, 4 * (size_t)c.start[nr] * sizeof *c.v));
        rs__free(ctx, p);
        rs__free(ctx, b);
        chunks_free(ctx, &c);
    }
    rs_network_free(ctx, n);
    return eq;
}

/* ---- a chain moved onto a grid built whole on a worker --------------------- */

rs_result rs_road_grid_rebase(rs_ctx *ctx, const rs_road_grid *current, const rs_road_grid *since,
                              const rs_road_grid *flat, rs_road_grid **out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (out) *out = NULL;
    if (!current || !since || !flat || !out) return rs__fail(ctx, RS_ERR_INVALID_ARG, "NULL argument to rs_road_grid_rebase");
    const rs_road_grid *cb = current->base ? current->base : current, *sb = since->base ? since->base : since;
    if (!current->track || !since->track)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_road_grid_rebase: %s was not made for edits (opts.grid.edits, analytic edges)",
                        current->track ? "since" : "current");
    if (flat->base || !flat->track)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_road_grid_rebase: flat is not a whole grid made for edits (rs_road_grid_build with "
                        "opts.grid.edits, analytic edges)");
    if (flat->dem_w != cb->dem_w || flat->dem_h != cb->dem_h || memcmp(&flat->frame, &cb->frame, sizeof flat->frame) ||
        flat->texels != cb->texels || flat->edges != cb->edges)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_road_grid_rebase: flat was built for another DEM, frame, texels or edge mode than current");
    /* flat must hold the roads `since` was made for: the same prints */
    const rs__grid_track *F = flat->track, *S = since->track, *C = current->track;
    if (F->n != S->n || (F->n && (memcmp(F->print, S->print, F->n * sizeof *F->print) ||
                                  memcmp(F->sprint, S->sprint, F->n * sizeof *F->sprint))) ||
        F->sctx != S->sctx)
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_road_grid_rebase: flat was not built from the roads and styles `since` was made for "
                        "(%zu roads against %zu, or other points, attributes or styles)",
                        F->n, S->n);
    /* the patches made after `since`, on flat; when a whole build came
     * between (current is on another base) or flat's map-wide switches
     * are not the chain's, on current's base as they are */
    const rs_road_grid *nb = cb != sb || !same_switches(&F->facts, &C->facts, rs__roadfield_cell(flat->field)) ? cb : flat;
    size_t keep = 0;
    uint8_t *carry = rs__calloc(ctx, current->npatch ? current->npatch : 1, 1);
    if (!carry) return rs__fail(ctx, RS_ERR_NOMEM, "rs_road_grid_rebase: out of memory");
    for (size_t k = 0; k < current->npatch; k++) {
        int before = 0; /* (the patch is since's: flat draws its roads) */
        for (size_t j = 0; nb == flat && j < since->npatch && !before; j++) before = since->patch[j].grid == current->patch[k].grid;
        carry[k] = !before;
        keep += carry[k];
    }
    rs_road_grid *g = rs__calloc(ctx, 1, sizeof *g);
    rs__grid_patch *P = rs__calloc(ctx, keep ? keep : 1, sizeof *P);
    if (!g || !P) {
        rs__free(ctx, g);
        rs__free(ctx, P);
        rs__free(ctx, carry);
        return rs__fail(ctx, RS_ERR_NOMEM, "rs_road_grid_rebase: out of memory");
    }
    *g = *nb;
    g->refs = 1;
    g->base = (rs_road_grid *)nb;
    rs__grid_hold(g->base);
    g->patch = P;
    g->npatch = 0;
    g->dirty = NULL;
    g->ndirty = 0;
    g->atlas_hold = NULL;
    g->track = (rs__grid_track *)C; /* (shared: tracks are read only) */
    rs__refs_add(&g->track->refs, 1);
    g->stats.bytes += C->bytes - (nb->track ? nb->track->bytes : 0);
    rs_result r = RS_OK;
    for (size_t k = 0; k < current->npatch && !r; k++)
        if (carry[k] && patch_take(ctx, g, &current->patch[k], NULL, 0)) r = RS_ERR_NOMEM;
    rs__free(ctx, carry);
    if (r) {
        rs_road_grid_free(ctx, g);
        return rs__fail(ctx, r, "rs_road_grid_rebase: out of memory");
    }
    *out = g;
    rs__ok(ctx);
    return RS_OK;
}
