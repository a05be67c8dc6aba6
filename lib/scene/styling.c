/* Road styles on the splat: per-road style resolution, the casing field,
 * the surface lookup field and the line symbols (lib/scene/styling.h). */
#include "styling.h"
#include "linesym.h"
#include "roadfield.h"
#include "surfimg.h"
#include "style.h"
#include "lanes.h"
#include "network.h"

#include <math.h>
#include <string.h>

void rs__styling_free(rs_ctx *ctx, rs__styling *st)
{
    if (!st) return;
    rs__linesym_free(ctx, st->lines);
    rs__roadfield_free(ctx, st->casing);
    rs__roadfield_free(ctx, st->near_own);
    for (size_t k = 0; k < st->ndeck; k++) {
        rs__roadfield_free(ctx, st->deck[k].casing);
        rs__roadfield_free(ctx, st->deck[k].hide);
        rs__roadfield_free(ctx, st->deck[k].below);
        rs__free(ctx, st->deck[k].below_of);
        rs__free(ctx, st->deck[k].road);
        rs__free(ctx, st->deck[k].cstroke);
        rs__free(ctx, st->deck[k].lstroke);
    }
    rs__free(ctx, st->deck);
    rs__free(ctx, st->prio);
    rs__free(ctx, st->surface);
    rs__free(ctx, st->colour);
    rs__free(ctx, st->half_width);
    rs__free(ctx, st->img_of);
    rs__free(ctx, st->img_len);
    rs__free(ctx, st->img_lev);
    rs__free(ctx, st->img_f);
    rs__free(ctx, st->img_s0);
    rs__free(ctx, st->img_rev);
    rs__free(ctx, st->band_start);
    rs__free(ctx, st->bands);
    rs__free(ctx, st->dash);
    rs__free(ctx, st->casing_width);
    rs__free(ctx, st->casing_road);
    rs__free(ctx, st->cuts);
    if (st->imgs)
        for (size_t i = 0; i < st->nimgs; i++) rs__surfimg_free(ctx, st->imgs[i]);
    rs__free(ctx, st->imgs);
    rs__free(ctx, st);
}

int rs__styling_image(const rs__styling *st, uint32_t road, double s, double t, double out[4])
{
    if (!st->img_of || st->img_of[road] < 0) return 0;
    const rs__surfimg *m = st->imgs[st->img_of[road]];
    double hw = st->half_width[road];
    /* along the stroke (a record drawn against its points: s and t turn) */
    if (st->img_s0 && st->img_rev[road]) s = st->img_s0[road] - s, t = -t;
    else if (st->img_s0) s += st->img_s0[road];
    /* the image's left edge at t = +hw (left of travel), right edge at -hw */
    double u = hw > 0 ? (hw - t) / (2 * hw) : 0.5;
    rs__surfimg_sample(m, u, s / st->img_len[road], st->img_lev[road], st->img_f[road], out);
    return 1;
}

/* Road i's surface image: find its name in the options' table, mipmap it
 * once, and the road's length per image height and level of detail. */
static rs_result road_image(rs_ctx *ctx, rs__styling *st, const rs_style *sty, size_t i, const rs_roads *roads,
                            const rs_splat_options *o, double pix)
{
    char q[64], q2[64], q3[64];
    const rs_style_options *so = &o->style;
    size_t k = 0;
    while (k < so->surface_image_count &&
           !(so->surface_images[k].name && strcmp(so->surface_images[k].name, sty->surface_image) == 0))
        k++;
    if (k == so->surface_image_count) {
        const char *name = NULL;
        rs_roads_get(roads, i, &name, NULL, NULL, NULL);
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "road %zu (%s): style %s: surface image %s was not given", i,
                        rs__quote(q, sizeof q, name, strlen(name)),
                        rs__quote(q2, sizeof q2, sty->name, strlen(sty->name)),
                        rs__quote(q3, sizeof q3, sty->surface_image, strlen(sty->surface_image)));
    }
    if (!st->imgs) {
        st->imgs = rs__calloc(ctx, so->surface_image_count, sizeof *st->imgs);
        st->img_of = rs__alloc_array(ctx, rs_roads_count(roads), sizeof *st->img_of);
        st->img_len = rs__calloc(ctx, rs_roads_count(roads), sizeof *st->img_len);
        st->img_lev = rs__calloc(ctx, rs_roads_count(roads), sizeof *st->img_lev);
        st->img_f = rs__calloc(ctx, rs_roads_count(roads), sizeof *st->img_f);
        if (!st->imgs || !st->img_of || !st->img_len || !st->img_lev || !st->img_f)
            return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for road styles");
        st->nimgs = so->surface_image_count;
        for (size_t r = 0; r < rs_roads_count(roads); r++) st->img_of[r] = -1;
    }
    if (!st->imgs[k]) {
        /* every image the styles use is copied and mipmapped: their pixels
         * together stay within the texture limit, as one texture's do */
        const rs_image *im = &so->surface_images[k].image;
        uint64_t px = (uint64_t)im->width * im->height;
        if (px > ctx->limits.max_texture_pixels - st->img_pixels)
            return rs__fail(ctx, RS_ERR_LIMIT,
                            "style %s: surface image %s (%u x %u) brings the surface images in use to %llu pixels, "
                            "over the limit of %llu for all of them together (rs_limits.max_texture_pixels)",
                            rs__quote(q2, sizeof q2, sty->name, strlen(sty->name)),
                            rs__quote(q3, sizeof q3, sty->surface_image, strlen(sty->surface_image)), im->width,
                            im->height, (unsigned long long)(st->img_pixels + px),
                            (unsigned long long)ctx->limits.max_texture_pixels);
        rs_result r = rs__surfimg_build(ctx, &so->surface_images[k].image,
                                        rs__quote(q, sizeof q, sty->surface_image, strlen(sty->surface_image)),
                                        &st->imgs[k]);
        if (r) return r;
        st->bytes += st->imgs[k]->bytes;
        st->img_pixels += px;
    }
    const rs__surfimg *m = st->imgs[k];
    double w = 2 * st->half_width[i];
    double len = sty->surface_length > 0 ? sty->surface_length : w * m->h[0] / m->w[0];
    if (!(len >= 1e-9)) len = 1e-9; /* a road of width ~0 */
    st->img_of[i] = (int32_t)k;
    st->img_len[i] = len;
    /* footprint of one output pixel in level-0 texels, the larger axis */
    double across = w > 0 ? pix * m->w[0] / w : 0, along = pix * m->h[0] / len;
    rs__surfimg_lod(m, across > along ? across : along, &st->img_lev[i], &st->img_f[i]);
    return RS_OK;
}

void rs__put_colour(float *dst, rs_colour c)
{
    dst[0] = c.r;
    dst[1] = c.g;
    dst[2] = c.b;
    dst[3] = (float)c.a / 255.0f;
}

/* A field of the styles gets the road grid's T ends (docs/network.md
 * "Ends at a T"); extra: the roads' widening in f (a casing field), or
 * NULL. */
static rs_result field_tees(rs_ctx *ctx, const rs_roads *roads, const rs_network *net, const rs__tees *T,
                            rs__roadfield *f, const double *extra, const rs_roads *froads, const uint32_t *sub)
{
    rs__tee_end *tees = NULL;
    size_t ntees = 0, m = 0;
    rs_result r = rs__tee_ends_from(ctx, T, roads, net, &tees, &ntees);
    for (size_t i = 0; !r && extra && i < ntees; i++) tees[i].grow = extra[tees[i].through];
    /* a field of some of the roads (sub: an id there or UINT32_MAX): the
     * ends of its roads, by its ids */
    for (size_t i = 0; !r && i < ntees; i++) {
        rs__tee_end t = tees[i];
        if (sub) {
            if (sub[t.road] == UINT32_MAX) continue;
            t.road = sub[t.road];
            t.through = sub[t.through];
        }
        tees[m++] = t;
    }
    if (!r) r = rs__roadfield_set_tees(ctx, f, froads, tees, m);
    rs__free(ctx, tees);
    return r;
}

/* The field of the roads i with pick[i] (widened by 2 extra[i] when extra
 * is not NULL), their T ends as the styles' fields have them; *ids the
 * rs_roads id of each of its roads (the caller's). */
static rs_result subset_field(rs_ctx *ctx, const rs_roads *roads, const rs_network *net, const rs__tees *tees,
                              const double *extra, const uint8_t *pick, const rs__roadfield_params *fp,
                              rs__roadfield **out, uint32_t **ids)
{
    size_t n = rs_roads_count(roads), m = 0;
    rs_roads *sub_roads = NULL;
    uint32_t *sub = rs__alloc_array(ctx, n, sizeof *sub), *id = NULL;
    for (size_t i = 0; sub && i < n; i++) m += pick[i] != 0;
    if (sub) id = rs__alloc_array(ctx, m ? m : 1, sizeof *id);
    rs_result r = sub && id ? rs_roads_create(ctx, &sub_roads) : RS_ERR_NOMEM;
    m = 0;
    for (size_t i = 0; i < n && !r; i++) {
        sub[i] = UINT32_MAX;
        if (!pick[i]) continue;
        const char *name = NULL;
        const double *xy = NULL;
        size_t np = 0;
        double w = 0;
        rs_roads_get(roads, i, &name, &w, &xy, &np);
        sub[i] = (uint32_t)m;
        id[m++] = (uint32_t)i;
        r = rs_roads_add(ctx, sub_roads, name, w + (extra ? 2 * extra[i] : 0), xy, np);
    }
    if (!r) r = rs__roadfield_build(ctx, sub_roads, fp, out);
    if (!r) r = field_tees(ctx, roads, net, tees, *out, extra, sub_roads, sub);
    rs_roads_free(ctx, sub_roads);
    rs__free(ctx, sub);
    if (r == RS_OK && ids) *ids = id;
    else rs__free(ctx, id);
    return r;
}

/* Road ids of a subset field (ids[k]: its road k; NULL: every road, k
 * itself) to their strokes (each road alone without a network); *out the
 * caller's. */
static rs_result stroke_ids(rs_ctx *ctx, const rs_network *net, size_t n, const uint32_t *ids, size_t m, uint32_t **out)
{
    uint32_t *o = rs__alloc_array(ctx, m ? m : 1, sizeof *o);
    if (!o) return RS_ERR_NOMEM;
    const int strokes = net && rs_network_road_count(net) == n;
    for (size_t k = 0; k < m; k++) {
        uint32_t i = ids ? ids[k] : (uint32_t)k;
        o[k] = strokes ? net->stroke_of[i] : i;
    }
    *out = o;
    return RS_OK;
}

/* st->deck: per level above the lowest that has cased roads, the fields
 * the overlays draw those casings over the roads below with (rs__deck). */
static rs_result decks_build(rs_ctx *ctx, const rs_roads *roads, const rs__roadfield *field, const rs_network *net,
                             const rs__tees *tees, const double *extra, const rs__roadfield_params *fp,
                             rs__styling *st)
{
    size_t n = rs_roads_count(roads);
    int32_t lo = INT32_MAX, *lv = rs__alloc_array(ctx, n, sizeof *lv);
    uint8_t *pick = rs__alloc_array(ctx, n, 1);
    uint32_t *bids = NULL, *cl = NULL;
    double *box = NULL, widest = 0, widest_casing = 0;
    rs_result r = lv && pick ? RS_OK : RS_ERR_NOMEM;
    for (size_t i = 0; i < n && !r; i++) {
        lv[i] = rs__road_level(roads, i);
        lo = lv[i] < lo ? lv[i] : lo;
    }
    /* without the grid's field: per road its points' box grown by its
     * half width (map metres), for the roads below that can lie near a
     * deck's casing */
    if (!r && !field && !(box = rs__alloc_array(ctx, n, 4 * sizeof *box))) r = RS_ERR_NOMEM;
    for (size_t i = 0; i < n && !r && !field; i++) {
        uint64_t print;
        double w = 0, *b = box + 4 * i;
        const double *pb; /* (the road set's box of its points: x0, y0, x1, y1) */
        rs__roads_road_print(roads, i, &print, &w, &pb);
        b[0] = pb[0] - 0.5 * w, b[1] = pb[2] + 0.5 * w, b[2] = pb[1] - 0.5 * w, b[3] = pb[3] + 0.5 * w;
        widest = fmax(widest, w), widest_casing = fmax(widest_casing, extra[i]);
    }
    /* a road below matters where a pixel in a casing band has it within
     * the lookup's reach; its T strips may reach a through road's width
     * past its box: twice the widest road, the casing and two pixels */
    const double near_m = 2 * widest + widest_casing + 2 * fp->pixel + 1;
    for (int32_t L = lo; !r;) {
        /* the next level above L with a cased road */
        int32_t next = INT32_MAX;
        for (size_t i = 0; i < n; i++)
            if (extra[i] > 0 && lv[i] > L && lv[i] < next) next = lv[i];
        if (next == INT32_MAX) break;
        L = next;
        rs__deck *d = rs__realloc(ctx, st->deck, (st->ndeck + 1) * sizeof *st->deck);
        if (!d) { r = RS_ERR_NOMEM; break; }
        st->deck = d;
        d = &st->deck[st->ndeck++];
        memset(d, 0, sizeof *d);
        d->level = L;
        size_t nc = 0, nb = 0;
        for (size_t i = 0; i < n; i++) nc += pick[i] = extra[i] > 0 && lv[i] == L;
        r = subset_field(ctx, roads, net, tees, extra, pick, fp, &d->casing, &d->road);
        if (!r) r = stroke_ids(ctx, net, n, d->road, nc, &d->cstroke);
        for (size_t i = 0; i < n; i++) pick[i] = lv[i] >= L;
        if (!r) r = subset_field(ctx, roads, net, tees, NULL, pick, fp, &d->hide, NULL);
        if (field) {
            /* the roads below in the grid's field */
            d->look = field;
            if (!r && !(d->below_of = rs__alloc_array(ctx, n, sizeof *d->below_of))) r = RS_ERR_NOMEM;
            for (size_t i = 0; !r && i < n; i++) d->below_of[i] = lv[i] < L;
            if (!r) r = stroke_ids(ctx, net, n, NULL, n, &d->lstroke);
            nb = n;
        } else {
            /* else a field of the roads below whose box comes near a cased
             * road's of this level (all of them when that would take long) */
            if (!r && !(cl = rs__realloc(ctx, cl, (nc ? nc : 1) * sizeof *cl))) r = RS_ERR_NOMEM;
            for (size_t i = 0, m = 0; !r && i < n; i++)
                if (extra[i] > 0 && lv[i] == L) cl[m++] = (uint32_t)i;
            const int prune = (double)nc * (double)n <= 2e7;
            for (size_t i = 0; !r && i < n; i++) {
                pick[i] = lv[i] < L;
                if (!pick[i] || !prune) continue;
                const double *a = box + 4 * i;
                int near = 0;
                for (size_t m = 0; m < nc && !near; m++) {
                    const double *c = box + 4 * cl[m], g = extra[cl[m]] + near_m;
                    /* (NaN and infinite boxes count as near) */
                    near = !(a[1] < c[0] - g || a[0] > c[1] + g || a[3] < c[2] - g || a[2] > c[3] + g);
                }
                pick[i] = (uint8_t)near;
            }
            for (size_t i = 0; i < n; i++) nb += pick[i];
            if (!r) r = subset_field(ctx, roads, net, tees, NULL, pick, fp, &d->below, &bids);
            d->look = d->below;
            if (!r) r = stroke_ids(ctx, net, n, bids, nb, &d->lstroke);
        }
        rs__free(ctx, bids);
        bids = NULL;
        if (!r) rs__roadfield_bounds(d->casing, d->box);
        if (!r)
            st->bytes += rs__roadfield_bytes(d->casing) + rs__roadfield_bytes(d->hide) + rs__roadfield_bytes(d->below) +
                         (2 * nc + nb) * sizeof(uint32_t) + (d->below_of ? n * sizeof(double) : 0);
    }
    rs__free(ctx, lv);
    rs__free(ctx, pick);
    rs__free(ctx, box);
    rs__free(ctx, cl);
    return r;
}

rs_result rs__styling_build(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_splat_options *o,
                            const rs__roadfield *field, const rs_network *net, const rs__tees *tees,
                            const rs__line_cut *cuts, size_t ncuts, const rs__grid_facts *facts, rs__styling **out)
{
    *out = NULL;
    if (o->style.disable) return RS_OK;
    size_t n = rs_roads_count(roads);
    if (n == 0) return RS_OK;
    rs_result r = RS_OK;
    rs__styling *st = rs__calloc(ctx, 1, sizeof *st);
    rs_style *sty = NULL;
    uint32_t *band_start = NULL;
    rs__band *bands = NULL;
    double *extra = NULL;
    if (!st) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory for road styles");
    st->surface = rs__calloc(ctx, n, 1);
    st->colour = rs__alloc_array(ctx, n, 16 * sizeof *st->colour);
    st->half_width = rs__alloc_array(ctx, n, sizeof *st->half_width);
    band_start = rs__alloc_array(ctx, n + 1, sizeof *band_start);
    sty = rs__malloc(ctx, sizeof *sty);
    if (!st->surface || !st->colour || !st->half_width || !band_start || !sty) { r = RS_ERR_NOMEM; goto fail; }
    /* pass 1: styles, counts */
    size_t nbands = 0, ncasing = 0;
    int styled = 0;
    for (size_t i = 0; i < n; i++) {
        if (rs__tick(ctx, 0)) { r = RS_ERR_CANCELLED; goto fail_msg; }
        if ((r = rs_road_style_ex(ctx, roads, i, &o->style, sty)) != RS_OK) goto fail_msg;
        double w = 0;
        rs_roads_get(roads, i, NULL, &w, NULL, NULL);
        st->half_width[i] = 0.5 * w;
        st->surface[i] = (uint8_t)sty->surface;
        float *c = st->colour + 16 * i;
        rs__put_colour(c, sty->surface == RS_SURFACE_GRADIENT ? sty->gradient_centre : sty->fill);
        rs__put_colour(c + 4, sty->gradient_centre);
        rs__put_colour(c + 8, sty->gradient_edge);
        rs__put_colour(c + 12, sty->casing);
        if (sty->surface != RS_SURFACE_DEFAULT) st->any_surface = 1;
        if (i == 0) {
            st->fill_uniform = sty->surface == RS_SURFACE_FILL;
            memcpy(st->fill_rgba, c, sizeof st->fill_rgba);
        } else if (sty->surface != RS_SURFACE_FILL || memcmp(st->fill_rgba, c, sizeof st->fill_rgba)) {
            st->fill_uniform = 0;
        }
        if (sty->surface_image[0]) {
            st->fill_uniform = 0;
            if ((r = road_image(ctx, st, sty, i, roads, o, dem->frame.cell_size / o->texels)) != RS_OK) goto fail_msg;
            st->any_surface = 1;
        }
        band_start[i] = (uint32_t)nbands;
        nbands += sty->line_count;
        if (sty->casing_width > 0) ncasing++;
        styled |= sty->surface != RS_SURFACE_DEFAULT || sty->line_count || sty->casing_width > 0 ||
                  sty->surface_image[0];
    }
    band_start[n] = (uint32_t)nbands;
    if (facts) { /* a part of a map: its switches are the whole map's */
        st->any_surface = facts->any_surface;
        st->fill_uniform = facts->fill_uniform;
        memcpy(st->fill_rgba, facts->fill_rgba, sizeof st->fill_rgba);
        styled = facts->styled;
    }
    st->fill_opaque = st->fill_uniform && st->fill_rgba[3] == 1.0f;
    if (!styled) {
        rs__free(ctx, sty);
        rs__free(ctx, band_start);
        rs__styling_free(ctx, st);
        rs__ok(ctx);
        return RS_OK;
    }
    rs__roadfield_params fp = rs__roadfield_params_for_dem(dem, o->texels);
    if (facts && facts->window_on) { /* (a patch: its window) */
        fp.window_on = 1;
        memcpy(fp.window, facts->window, sizeof fp.window);
        fp.window_reach = facts->window_reach;
    }
    /* pass 2: bands and casing roads (styles resolved again: each is small) */
    /* every road's lines with room for their dashes: part of the line
     * symbols' total (rs_limits.max_linesym_bytes; the pieces add to it) */
    if (nbands && ctx->limits.max_linesym_bytes &&
        (uint64_t)nbands > ctx->limits.max_linesym_bytes / (sizeof *bands + RS_STYLE_MAX_DASH * sizeof(double))) {
        r = rs__fail(ctx, RS_ERR_LIMIT,
                     "line symbols: the roads' %llu styled lines take more than %llu bytes together (many "
                     "styled lines; the budget is rs_limits.max_linesym_bytes)",
                     (unsigned long long)nbands, (unsigned long long)ctx->limits.max_linesym_bytes);
        goto fail_msg;
    }
    if (nbands) {
        bands = rs__alloc_array(ctx, nbands, sizeof *bands);
        if (!bands) { r = RS_ERR_NOMEM; goto fail; }
    }
    /* dash arrays must outlive the build: one style per road is too many
     * to keep, so copy the dashes into one array */
    double *dash = NULL;
    size_t ndash = 0;
    if (nbands) {
        dash = rs__alloc_array(ctx, nbands, RS_STYLE_MAX_DASH * sizeof *dash);
        if (!dash) { r = RS_ERR_NOMEM; goto fail; }
    }
    /* (a part of a map with casings has the casing field even when none of its roads has one) */
    int casings = ncasing || (facts && facts->widest_casing > 0);
    if (casings) {
        extra = rs__calloc(ctx, n, sizeof *extra);
        if (!extra) { r = RS_ERR_NOMEM; goto fail_dash; }
    }
    for (size_t i = 0, k = 0, cr = 0; i < n; i++) {
        if (rs__tick(ctx, 0)) { r = RS_ERR_CANCELLED; goto fail_dash; } /* (10^5 styles: ~35 ms) */
        if ((r = rs_road_style_ex(ctx, roads, i, &o->style, sty)) != RS_OK) goto fail_dash;
        for (uint32_t j = 0; j < sty->line_count; j++, k++) {
            const rs_style_line *ln = &sty->line[j];
            rs__band *b = &bands[k];
            b->t = ln->offset;
            b->w = ln->width;
            rs__put_colour(b->rgba, ln->colour);
            b->ndash = ln->dash_count;
            b->dash = dash + ndash;
            memcpy(dash + ndash, ln->dash, ln->dash_count * sizeof *dash);
            ndash += ln->dash_count;
            b->phase = ln->phase;
        }
        if (sty->casing_width > 0) {
            extra[i] = sty->casing_width;
            const float *c = st->colour + 16 * i + 12;
            if (cr == 0) {
                memcpy(st->casing_rgba, c, sizeof st->casing_rgba);
                st->casing_uniform = 1;
            } else if (memcmp(st->casing_rgba, c, sizeof st->casing_rgba)) {
                st->casing_uniform = 0;
            }
            cr++;
        }
    }
    if (facts) {
        st->casing_uniform = facts->casing_uniform;
        memcpy(st->casing_rgba, facts->casing_rgba, sizeof st->casing_rgba);
    }
    /* the roads' priorities (NULL: all equal): the line symbols' crossings
     * read them, and the fill lookups keep them (below) */
    if ((nbands || st->any_surface || st->img_of) && (r = rs__road_priorities(ctx, roads, &st->prio)) != RS_OK)
        goto fail_dash;
    if (facts && facts->ranked && !st->prio && (st->any_surface || st->img_of)) {
        /* a part of a map whose roads all rank alike where the map's do
         * not: its fills are looked up as the whole map's are (a pixel
         * takes a surface that holds it before a nearer centre line) */
        if (!(st->prio = rs__alloc_array(ctx, n ? n : 1, sizeof *st->prio))) { r = RS_ERR_NOMEM; goto fail_dash; }
        for (size_t i = 0; i < n; i++) st->prio[i] = rs__road_rank(roads, i);
    }
    if (nbands) {
        rs__linesym_params lp;
        memset(&lp, 0, sizeof lp);
        lp.origin_x = dem->frame.origin_x;
        lp.origin_y = dem->frame.origin_y;
        lp.cell_size = dem->frame.cell_size;
        lp.out_w = (dem->width - 1) * o->texels;
        lp.out_h = (dem->height - 1) * o->texels;
        lp.pixel = fp.pixel;
        lp.aa = o->style.aa == RS_LINE_AA_HERMITE ? RS__AA_HERMITE : RS__AA_EXACT;
        lp.net = net;
        lp.tees = tees;
        /* lane and centre lines stop at the automatic stop lines and zebras */
        lp.cuts = cuts;
        lp.ncuts = ncuts;
        lp.prio_given = 1;
        lp.prio = st->prio;
        if (facts && facts->window_on) {
            /* a patch: its pixels, and its edit pieces (lib/scene/grid_edit.c:
             * those meeting its window grown by a grid's pad, 4 pixels and 4
             * m), lie within this */
            double m = 4.5 * fp.pixel + 8 + (o->coverage.edges == RS_EDGES_ANALYTIC ? 0 : 4 * dem->frame.cell_size);
            lp.window_on = 1;
            lp.window[0] = facts->window[0] - m, lp.window[1] = facts->window[1] - m;
            lp.window[2] = facts->window[2] + m, lp.window[3] = facts->window[3] + m;
        }
        r = rs__linesym_build(ctx, roads, &lp, band_start, bands, &st->lines);
        if (r == RS_OK && ncuts) { /* kept for the GPU export (the plan's are freed after the build) */
            st->cuts = rs__alloc_array(ctx, ncuts, sizeof *st->cuts);
            if (!st->cuts) r = RS_ERR_NOMEM;
            else {
                memcpy(st->cuts, cuts, ncuts * sizeof *cuts);
                st->ncuts = ncuts;
            }
        }
        if (r != RS_OK) goto fail_dash;
        st->bytes += rs__linesym_bytes(st->lines);
    }
    if (casings) {
        /* The casing field: every road, those with a casing widened by it
         * (C holds R). From the grid's field when the casings are at most
         * an index cell wide: the same segments, so the coverage stage
         * computes C beside R in one pass (docs/linesym.md). */
        double widest = 0;
        for (size_t i = 0; i < n; i++) widest = fmax(widest, extra[i]);
        if (facts) widest = facts->widest_casing;
        st->widest_casing = widest;
        if (field && widest <= rs__roadfield_cell(field)) {
            if ((r = rs__roadfield_widen(ctx, field, extra, n, &st->casing)) != RS_OK) goto fail_dash;
            st->casing_merged = 1;
        } else {
            /* With alpha-map edges R is the alpha map's coverage, not the
             * analytic one an uncased road's part of C holds: where the
             * two differ (its edge pixels) C > R gave every road without a
             * casing a tint of casing colour (up to 11/255) once any road
             * had one. There C holds the cased roads alone. */
            const int alone = o->coverage.edges == RS_EDGES_ALPHAMAP;
            uint8_t *pick = rs__alloc_array(ctx, n, 1);
            if (!pick) { r = RS_ERR_NOMEM; goto fail_dash; }
            for (size_t i = 0; i < n; i++) pick[i] = !alone || extra[i] > 0;
            r = subset_field(ctx, roads, net, tees, extra, pick, &fp, &st->casing, alone ? &st->casing_road : NULL);
            rs__free(ctx, pick);
            if (r != RS_OK) goto fail_dash;
        }
        st->bytes += rs__roadfield_bytes(st->casing);
        /* bridges' casings over the roads below them */
        if ((r = decks_build(ctx, roads, field, net, tees, extra, &fp, st)) != RS_OK) goto fail_dash;
    }
    if (st->img_of && net && rs_network_road_count(net) == n) {
        st->img_s0 = rs__alloc_array(ctx, n, sizeof *st->img_s0);
        st->img_rev = rs__alloc_array(ctx, n, 1);
        if (!st->img_s0 || !st->img_rev) { r = RS_ERR_NOMEM; goto fail_dash; }
        for (size_t i = 0; i < n; i++) {
            rs_road_stroke k;
            rs_network_road_stroke(net, i, &k);
            st->img_s0[i] = k.s_offset;
            st->img_rev[i] = (uint8_t)k.reversed;
        }
    }
    if (st->prio && !(st->any_surface || st->img_of)) { /* the fill lookups need none */
        rs__free(ctx, st->prio);
        st->prio = NULL;
    }
    if (st->prio) st->bytes += n * sizeof *st->prio;
    if (st->any_surface) {
        st->near = field;
        if (!field) {
            if ((r = rs__roadfield_build(ctx, roads, &fp, &st->near_own)) != RS_OK) goto fail_dash;
            if ((r = field_tees(ctx, roads, net, tees, st->near_own, NULL, roads, NULL)) != RS_OK) goto fail_dash;
            st->near = st->near_own;
            st->bytes += rs__roadfield_bytes(st->near_own);
        }
    }
    st->bytes += sizeof *st + n * (1 + 16 * sizeof(float) + sizeof(double));
    if (st->img_of) st->bytes += n * (sizeof *st->img_of + sizeof *st->img_len + sizeof *st->img_lev + sizeof *st->img_f);
    if (st->img_s0) st->bytes += n * (sizeof *st->img_s0 + 1);
    /* what the GPU export reads (rs_gpu_scene_from_grid): kept, not freed */
    st->nroads = n;
    st->band_start = band_start;
    st->bands = bands;
    st->dash = dash;
    st->casing_width = extra;
    st->bytes += (n + 1) * sizeof *band_start + nbands * (sizeof *bands + RS_STYLE_MAX_DASH * sizeof *dash) +
                 (extra ? n * sizeof *extra : 0) + st->ncuts * sizeof *st->cuts;
    rs__free(ctx, sty);
    *out = st;
    rs__ok(ctx);
    return RS_OK;
fail_dash:
    rs__free(ctx, dash);
    rs__free(ctx, extra);
fail:
    if (r == RS_ERR_NOMEM) rs__fail(ctx, r, "out of memory for road styles");
fail_msg:
    rs__free(ctx, bands);
    rs__free(ctx, band_start);
    rs__free(ctx, sty);
    rs__styling_free(ctx, st);
    return r;
}
