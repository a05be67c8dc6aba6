/* Road sets and the road text format (docs/road-format.md).
 *
 * All points of all roads live in one growable array of doubles; a road is
 * a slice of it plus a width, a name and its attributes. Names, attribute
 * keys and values are NUL-terminated strings in one growable character
 * pool; a road's attributes are a slice of one (key, value) array. The
 * parser appends points of the open road straight to the shared array and
 * records the road when its `end` arrives, so parsing costs one pass and
 * amortised O(1) allocations per point.
 *
 * The text parser (rs__text_parse) also reads style blocks, handing their
 * lines to lib/input/style.c, so that road files may carry their styles. */
#include "style.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "roads_impl.h"

/* Make room for `need` (>= 1) elements of `elem` bytes: capacity doubles
 * (at least 16), every product checked. Returns the (possibly moved)
 * buffer, or NULL on overflow or no memory with `buf` still valid. */
static void *grow(rs_ctx *ctx, void *buf, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return buf;
    size_t nc = *cap < 16 ? 16 : *cap;
    while (nc < need) {
        if (nc > SIZE_MAX / 2) { nc = need; break; }
        nc *= 2;
    }
    size_t bytes;
    if (!rs__mul_size(nc, elem, &bytes)) return NULL;
    void *p = rs__realloc(ctx, buf, bytes);
    if (p) *cap = nc;
    return p;
}

rs_result rs_roads_create(rs_ctx *ctx, rs_roads **out)
{
    if (!out) return ctx ? rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_create: out is NULL") : RS_ERR_INVALID_ARG;
    *out = NULL;
    if (!ctx) return RS_ERR_INVALID_ARG;
    rs_roads *r = rs__calloc(ctx, 1, sizeof *r);
    if (!r) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory creating a road set");
    r->frame_crs = SIZE_MAX;
    *out = r;
    rs__ok(ctx);
    return RS_OK;
}

void rs_roads_free(rs_ctx *ctx, rs_roads *roads)
{
    if (!ctx || !roads) return;
    rs__free(ctx, roads->roads);
    rs__free(ctx, roads->xy);
    rs__free(ctx, roads->names);
    rs__free(ctx, roads->attrs);
    rs__free(ctx, roads->marks);
    rs__free(ctx, roads->pattrs);
    rs__free(ctx, roads);
}

size_t rs_roads_count(const rs_roads *roads) { return roads ? roads->count : 0; }

rs_road_frame rs_roads_frame(const rs_roads *roads, const char **crs)
{
    if (crs) *crs = roads && roads->frame_crs != SIZE_MAX ? roads->names + roads->frame_crs : NULL;
    return roads ? (rs_road_frame)roads->frame : RS_FRAME_NONE;
}

rs_result rs_roads_negate_y(rs_ctx *ctx, rs_roads *roads)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!roads) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_negate_y: roads is NULL");
    for (size_t k = 0; k < roads->points; k++) roads->xy[2 * k + 1] = -roads->xy[2 * k + 1];
    for (size_t i = 0; i < roads->count; i++) rs__roads_reprint(roads, i);
    rs__ok(ctx);
    return RS_OK;
}

rs_result rs_roads_get(const rs_roads *roads, size_t i, const char **name, double *width,
                       const double **xy, size_t *n)
{
    if (!roads || i >= roads->count) return RS_ERR_INVALID_ARG;
    const rs_road_rec *rec = &roads->roads[i];
    if (name) *name = roads->names + rec->name;
    if (width) *width = rec->width;
    if (xy) *xy = roads->xy + 2 * rec->first;
    if (n) *n = rec->n;
    return RS_OK;
}

rs_result rs_roads_get_info(const rs_roads *roads, size_t i, rs_road_info *out)
{
    if (!roads || i >= roads->count || !out) return RS_ERR_INVALID_ARG;
    const rs_road_rec *rec = &roads->roads[i];
    memset(out, 0, sizeof *out);
    out->road_class = (rs_road_class)rec->road_class;
    out->link = rec->link;
    out->lanes = rec->lanes;
    out->oneway = (rs_oneway)rec->oneway;
    out->area = (rs_area)rec->area;
    out->style = rec->style == SIZE_MAX ? NULL : roads->names + rec->style;
    out->width_given = rec->width_given;
    return RS_OK;
}

size_t rs_roads_attr_count(const rs_roads *roads, size_t i)
{
    return roads && i < roads->count ? roads->roads[i].attr_count : 0;
}

rs_result rs_roads_attr_at(const rs_roads *roads, size_t i, size_t k, const char **key, const char **value)
{
    if (!roads || i >= roads->count || k >= roads->roads[i].attr_count) return RS_ERR_INVALID_ARG;
    const rs_attr *a = &roads->attrs[roads->roads[i].attr_first + k];
    if (key) *key = roads->names + a->key;
    if (value) *value = roads->names + a->value;
    return RS_OK;
}

/* Index of `key` among road i's attributes, or SIZE_MAX. */
static size_t find_attr(const rs_roads *roads, const rs_road_rec *rec, const char *key, size_t kn)
{
    for (uint32_t k = 0; k < rec->attr_count; k++) {
        const char *have = roads->names + roads->attrs[rec->attr_first + k].key;
        /* (the first byte settles most keys without a call) */
        if ((kn == 0 || have[0] == key[0]) && strncmp(have, key, kn) == 0 && have[kn] == '\0') return rec->attr_first + k;
    }
    return SIZE_MAX;
}

const char *rs_roads_get_attr(const rs_roads *roads, size_t i, const char *key)
{
    if (!roads || i >= roads->count || !key) return NULL;
    size_t a = find_attr(roads, &roads->roads[i], key, strlen(key));
    return a == SIZE_MAX ? NULL : roads->names + roads->attrs[a].value;
}

/* Element offset of p inside [base, base + count) of `elem`-byte
 * elements, or SIZE_MAX: callers may pass pointers from rs_roads_get(),
 * which a realloc would invalidate. */
static size_t inside(const void *base, size_t count, const void *p, size_t elem)
{
    uintptr_t b = (uintptr_t)base, q = (uintptr_t)p;
    if (!base || !p || q < b || q >= b + count * elem) return SIZE_MAX;
    return (size_t)(q - b) / elem;
}

/* Room for `n` more bytes and a NUL in the string pool: the write
 * position, or NULL (no memory) with the pool unchanged. */
static char *pool_reserve(rs_ctx *ctx, rs_roads *roads, size_t n)
{
    if (n > SIZE_MAX - 1 - roads->names_len) return NULL;
    char *names = grow(ctx, roads->names, &roads->names_cap, roads->names_len + n + 1, 1);
    if (!names) return NULL;
    roads->names = names;
    return names + roads->names_len;
}

/* Close a string of `n` bytes written at pool_reserve's position; returns
 * its offset. */
static size_t pool_commit(rs_roads *roads, size_t n)
{
    size_t off = roads->names_len;
    roads->names[off + n] = '\0';
    roads->names_len = off + n + 1;
    return off;
}

/* Copy s[0, n) into the pool (s may point into the pool). SIZE_MAX: no memory. */
static size_t pool_add(rs_ctx *ctx, rs_roads *roads, const char *s, size_t n)
{
    size_t s_off = inside(roads->names, roads->names_len, s, 1);
    char *w = pool_reserve(ctx, roads, n);
    if (!w) return SIZE_MAX;
    if (s_off != SIZE_MAX) s = roads->names + s_off; /* the text came from this pool */
    if (n) memmove(w, s, n);
    return pool_commit(roads, n);
}

void rs__roads_reprint(rs_roads *roads, size_t i)
{
    rs_road_rec *rec = &roads->roads[i];
    const double *xy = roads->xy + 2 * rec->first;
    uint64_t h = rs__fp_mixs(rs__fp_mixd(0x7e57, rec->width), roads->names + rec->name);
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY, y1 = -INFINITY;
    /* (the x and the y in two chains, joined at the end: half the
     * dependent multiplies of one chain) */
    uint64_t hy = rs__fp_mix(h, 0x79);
    for (size_t k = 0; k < rec->n; k++) {
        double x = xy[2 * k], y = xy[2 * k + 1];
        h = rs__fp_mixd(h, x), hy = rs__fp_mixd(hy, y);
        x0 = x < x0 ? x : x0, y0 = y < y0 ? y : y0, x1 = x > x1 ? x : x1, y1 = y > y1 ? y : y1;
    }
    h = rs__fp_mix(rs__fp_mix(h, hy), rec->n);
    for (uint32_t k = 0; k < rec->attr_count; k++) {
        const rs_attr *a = &roads->attrs[rec->attr_first + k];
        h = rs__fp_mixs(rs__fp_mixs(h, roads->names + a->key), roads->names + a->value);
    }
    rec->print = h;
    rec->box[0] = x0, rec->box[1] = y0, rec->box[2] = x1, rec->box[3] = y1;
}

void rs__roads_road_print(const rs_roads *roads, size_t i, uint64_t *print, double *width, const double **box)
{
    const rs_road_rec *rec = &roads->roads[i];
    *print = rec->print;
    *width = rec->width;
    *box = rec->box;
}

/* Record a road whose points are already the last `n` of roads->xy;
 * `rec` holds everything else. */
static int commit_road(rs_ctx *ctx, rs_roads *roads, const rs_road_rec *rec, size_t n)
{
    rs_road_rec *recs = grow(ctx, roads->roads, &roads->cap, roads->count + 1, sizeof(rs_road_rec));
    if (!recs) return 0;
    roads->roads = recs;
    rs_road_rec *r = &roads->roads[roads->count++];
    *r = *rec;
    r->first = roads->points - n;
    r->n = n;
    return 1;
}

rs_result rs__roads_check_geometry(rs_ctx *ctx, const char *fn, double width, const double *xy, size_t n)
{
    if (!(width > 0) || !isfinite(width))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "%s: width %g must be finite and > 0", fn, width);
    if (n < 2) return rs__fail(ctx, RS_ERR_INVALID_ARG, "%s: %zu points; a road needs at least 2", fn, n);
    if (!xy) return rs__fail(ctx, RS_ERR_INVALID_ARG, "%s: xy is NULL", fn);
    for (size_t i = 0; i < 2 * n; i++)
        if (!isfinite(xy[i]))
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "%s: point %zu has a non-finite %c", fn, i / 2,
                            (i & 1) ? 'y' : 'x');
    return RS_OK;
}

rs_result rs_roads_add(rs_ctx *ctx, rs_roads *roads, const char *name, double width,
                       const double *xy, size_t n)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!roads) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_add: roads is NULL");
    rs_result g = rs__roads_check_geometry(ctx, "rs_roads_add", width, xy, n);
    if (g) return g;
    if (n > ctx->limits.max_points || roads->points > ctx->limits.max_points - n)
        return rs__fail(ctx, RS_ERR_LIMIT, "rs_roads_add: more than %llu road points in total",
                        (unsigned long long)ctx->limits.max_points);
    size_t name_len = name ? strlen(name) : 0;
    size_t xy_off = inside(roads->xy, 2 * roads->points, xy, sizeof(double));
    double *pts = roads->points > SIZE_MAX - n ? NULL
                  : grow(ctx, roads->xy, &roads->points_cap, roads->points + n, 2 * sizeof(double));
    if (!pts) return rs__fail(ctx, RS_ERR_NOMEM, "rs_roads_add: out of memory for %zu points", n);
    roads->xy = pts;
    if (xy_off != SIZE_MAX) xy = pts + xy_off; /* copying one of our own roads */
    size_t names_len = roads->names_len;
    rs_road_rec rec;
    memset(&rec, 0, sizeof rec);
    rec.width = width;
    rec.width_given = 1;
    rec.style = SIZE_MAX;
    rec.attr_first = roads->attrs_len;
    rec.name = pool_add(ctx, roads, name ? name : "", name_len);
    if (rec.name == SIZE_MAX) return rs__fail(ctx, RS_ERR_NOMEM, "rs_roads_add: out of memory");
    memcpy(roads->xy + 2 * roads->points, xy, n * 2 * sizeof(double));
    roads->points += n;
    if (!commit_road(ctx, roads, &rec, n)) {
        roads->points -= n;
        roads->names_len = names_len;
        return rs__fail(ctx, RS_ERR_NOMEM, "rs_roads_add: out of memory");
    }
    rs__roads_reprint(roads, roads->count - 1);
    rs__ok(ctx);
    return RS_OK;
}

/* ------------------------------------------------------------------------
 * Markings and point attributes (issue 14)
 * ---------------------------------------------------------------------- */

static int mark_type_ok(const char *s, size_t n)
{
    if (n == 0 || n > RS_MARK_TYPE_MAX) return 0;
    for (size_t i = 0; i < n; i++) {
        char c = s[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '-'))
            return 0;
    }
    return 1;
}

static int mark_size_ok(double v) { return v >= 0 && v <= 1e6; }

/* Append a marking record; the type text is copied into the pool. */
static int push_mark(rs_ctx *ctx, rs_roads *roads, const rs_mark_rec *rec, const char *type, size_t tn)
{
    size_t names_len = roads->names_len;
    size_t off = pool_add(ctx, roads, type, tn);
    if (off == SIZE_MAX) return 0;
    rs_mark_rec *m = grow(ctx, roads->marks, &roads->marks_cap, roads->marks_len + 1, sizeof *m);
    if (!m) {
        roads->names_len = names_len;
        return 0;
    }
    roads->marks = m;
    m[roads->marks_len] = *rec;
    m[roads->marks_len].type = off;
    roads->marks_len++;
    return 1;
}

rs_result rs_roads_add_mark(rs_ctx *ctx, rs_roads *roads, const rs_mark *mark)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!roads || !mark || !mark->type) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_add_mark: NULL argument");
    size_t tn = strlen(mark->type);
    if (!mark_type_ok(mark->type, tn))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_add_mark: type must be 1..%d characters of A-Z a-z 0-9 _ -",
                        RS_MARK_TYPE_MAX);
    if (mark->road >= roads->count)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_add_mark: road %zu of %zu", mark->road, roads->count);
    if (!isfinite(mark->s) || !isfinite(mark->t) || fabs(mark->s) > 1e12 || fabs(mark->t) > 1e6)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_add_mark: s and t must be finite (|s| <= 1e12, |t| <= 1e6)");
    if (!mark_size_ok(mark->length) || !mark_size_ok(mark->width))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_add_mark: length and width must be 0..1e6 (0: the atlas size)");
    rs_mark_rec rec;
    memset(&rec, 0, sizeof rec);
    rec.road = mark->road;
    rec.s = mark->s;
    rec.t = mark->t;
    rec.length = mark->length;
    rec.width = mark->width;
    rec.flip = mark->flip != 0;
    rec.line = mark->line;
    if (!push_mark(ctx, roads, &rec, mark->type, tn)) return rs__fail(ctx, RS_ERR_NOMEM, "rs_roads_add_mark: out of memory");
    rs__ok(ctx);
    return RS_OK;
}

size_t rs_roads_mark_count(const rs_roads *roads) { return roads ? roads->marks_len : 0; }

rs_result rs_roads_get_mark(const rs_roads *roads, size_t i, rs_mark *out)
{
    if (!roads || !out || i >= roads->marks_len) return RS_ERR_INVALID_ARG;
    const rs_mark_rec *m = &roads->marks[i];
    memset(out, 0, sizeof *out);
    out->type = roads->names + m->type;
    out->road = m->road;
    out->s = m->s;
    out->t = m->t;
    out->length = m->length;
    out->width = m->width;
    out->flip = m->flip;
    out->line = m->line;
    return RS_OK;
}

size_t rs_roads_point_attr_count(const rs_roads *roads) { return roads ? roads->pattrs_len : 0; }

rs_result rs_roads_point_attr_at(const rs_roads *roads, size_t k, size_t *road, size_t *point, const char **key,
                                 const char **value)
{
    if (!roads || k >= roads->pattrs_len) return RS_ERR_INVALID_ARG;
    const rs_point_attr *a = &roads->pattrs[k];
    if (road) *road = a->road;
    if (point) *point = a->point;
    if (key) *key = roads->names + a->key;
    if (value) *value = roads->names + a->value;
    return RS_OK;
}

/* ------------------------------------------------------------------------
 * Attributes
 * ---------------------------------------------------------------------- */

static const char *const class_names[RS_CLASS_COUNT] = {
    "", "motorway", "trunk", "primary", "secondary", "tertiary", "residential",
    "service", "track", "path", "footway", "cycleway"
};

const char *rs_road_class_name(rs_road_class c)
{
    return (unsigned)c < RS_CLASS_COUNT ? class_names[c] : "";
}

/* Class of s[0, n): the names above, or one of the first five + "_link". */
static rs_road_class class_of(const char *s, size_t n, int *link)
{
    int lk = 0;
    if (n > 5 && memcmp(s + n - 5, "_link", 5) == 0) { lk = 1; n -= 5; }
    for (int c = 1; c < RS_CLASS_COUNT; c++)
        if (strlen(class_names[c]) == n && memcmp(class_names[c], s, n) == 0) {
            if (lk && c > RS_CLASS_TERTIARY) break;
            if (link) *link = lk;
            return (rs_road_class)c;
        }
    if (link) *link = 0;
    return RS_CLASS_NONE;
}

rs_road_class rs_road_class_from_name(const char *name, int *link)
{
    if (link) *link = 0;
    return name ? class_of(name, strlen(name), link) : RS_CLASS_NONE;
}

static int word_is(const char *s, size_t n, const char *w) { return strlen(w) == n && memcmp(s, w, n) == 0; }

/* Check a key: 1..MAX_KEY of A-Z a-z 0-9 _ : . - */
static int key_ok(const char *k, size_t n)
{
    if (n == 0 || n > MAX_KEY) return 0;
    for (size_t i = 0; i < n; i++) {
        char c = k[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
              c == ':' || c == '.' || c == '-'))
            return 0;
    }
    return 1;
}

/* Check the value of a known key and record it in rec; unknown keys pass.
 * `value_off` is the value's pool offset (for style=). Returns 1, or 0 with
 * the reason in why. */
static int apply_known(rs_road_rec *rec, const char *key, size_t kn, const char *v, size_t vn, size_t value_off,
                       char *why, size_t cap)
{
    char q[64];
    if (word_is(key, kn, "class")) {
        int link;
        rs_road_class c = class_of(v, vn, &link);
        if (c == RS_CLASS_NONE) {
            snprintf(why, cap, "class %s is not a road class (motorway, trunk, primary, secondary, tertiary, "
                     "residential, service, track, path, footway, cycleway, or one of the first five + '_link')",
                     rs__quote(q, sizeof q, v, vn));
            return 0;
        }
        rec->road_class = (uint8_t)c;
        rec->link = (uint8_t)link;
    } else if (word_is(key, kn, "lanes")) {
        uint32_t l = 0;
        size_t i = 0;
        for (; i < vn && i < 3 && v[i] >= '0' && v[i] <= '9'; i++) l = l * 10 + (uint32_t)(v[i] - '0');
        if (vn == 0 || i != vn || l < 1 || l > MAX_LANES) {
            snprintf(why, cap, "lanes %s must be a whole number 1..%d", rs__quote(q, sizeof q, v, vn), MAX_LANES);
            return 0;
        }
        rec->lanes = l;
    } else if (word_is(key, kn, "oneway")) {
        if (word_is(v, vn, "yes") || word_is(v, vn, "1") || word_is(v, vn, "true")) rec->oneway = RS_ONEWAY_YES;
        else if (word_is(v, vn, "no") || word_is(v, vn, "0") || word_is(v, vn, "false")) rec->oneway = RS_ONEWAY_NO;
        else if (word_is(v, vn, "-1")) rec->oneway = RS_ONEWAY_REVERSE;
        else {
            snprintf(why, cap, "oneway %s must be yes, no or -1", rs__quote(q, sizeof q, v, vn));
            return 0;
        }
    } else if (word_is(key, kn, "area")) {
        if (word_is(v, vn, "urban")) rec->area = RS_AREA_URBAN;
        else if (word_is(v, vn, "rural")) rec->area = RS_AREA_RURAL;
        else {
            snprintf(why, cap, "area %s must be urban or rural", rs__quote(q, sizeof q, v, vn));
            return 0;
        }
    } else if (word_is(key, kn, "style")) {
        if (vn == 0 || vn > RS_STYLE_NAME_MAX) {
            snprintf(why, cap, "style name %s must be 1..%d bytes", rs__quote(q, sizeof q, v, vn), RS_STYLE_NAME_MAX);
            return 0;
        }
        rec->style = value_off;
    } else if (word_is(key, kn, "width")) {
        snprintf(why, cap, "write the width as 'width W', not as an attribute");
        return 0;
    }
    return 1;
}

/* Make room for one more attribute at the end of road `rec`'s slice: when
 * the slice is not at the end of the array, it moves there. */
static int attr_slot(rs_ctx *ctx, rs_roads *roads, rs_road_rec *rec)
{
    int at_end = rec->attr_first + rec->attr_count == roads->attrs_len;
    size_t extra = at_end ? 1 : (size_t)rec->attr_count + 1;
    if (extra > SIZE_MAX - roads->attrs_len) return 0;
    rs_attr *a = grow(ctx, roads->attrs, &roads->attrs_cap, roads->attrs_len + extra, sizeof(rs_attr));
    if (!a) return 0;
    roads->attrs = a;
    if (!at_end) {
        if (rec->attr_count)
            memcpy(a + roads->attrs_len, a + rec->attr_first, rec->attr_count * sizeof *a);
        rec->attr_first = roads->attrs_len;
        roads->attrs_len += rec->attr_count;
    }
    return 1;
}

/* An attribute value: valid UTF-8 without control characters (tab allowed). */
rs_result rs__roads_value_check(rs_ctx *ctx, const char *fn, const char *value, size_t vn)
{
    for (size_t k = 0; k < vn;) {
        unsigned char c = (unsigned char)value[k];
        if (c < 0x80) {
            if ((c < 0x20 && c != '\t') || c == 0x7F)
                return rs__fail(ctx, RS_ERR_INVALID_ARG, "%s: value has control character 0x%02x", fn, c);
            k++;
            continue;
        }
        size_t len = rs__utf8_len((const unsigned char *)value + k, vn - k);
        if (!len) return rs__fail(ctx, RS_ERR_INVALID_ARG, "%s: value is not valid UTF-8", fn);
        k += len;
    }
    return RS_OK;
}

rs_result rs_roads_set_attr(rs_ctx *ctx, rs_roads *roads, size_t i, const char *key, const char *value)
{
    char why[200], q[64];
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!roads || i >= roads->count || !key || !value)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_set_attr: no road %zu, or key/value NULL", i);
    size_t kn = strlen(key), vn = strlen(value);
    if (!key_ok(key, kn))
        return rs__fail(ctx, RS_ERR_INVALID_ARG,
                        "rs_roads_set_attr: key %s must be 1..%d characters of A-Z a-z 0-9 _ : . -",
                        rs__quote(q, sizeof q, key, kn), MAX_KEY);
    rs_result vr = rs__roads_value_check(ctx, "rs_roads_set_attr", value, vn);
    if (vr) return vr;
    rs_road_rec *rec = &roads->roads[i];
    rs_road_rec next = *rec;
    if (!apply_known(&next, key, kn, value, vn, roads->names_len, why, sizeof why))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_set_attr: %s", why);
    size_t names_len = roads->names_len;
    size_t voff = pool_add(ctx, roads, value, vn);
    if (voff == SIZE_MAX) return rs__fail(ctx, RS_ERR_NOMEM, "rs_roads_set_attr: out of memory");
    size_t have = find_attr(roads, rec, key, kn);
    if (have != SIZE_MAX) {
        roads->attrs[have].value = voff;
    } else {
        if (rec->attr_count >= MAX_ATTRS) {
            roads->names_len = names_len;
            return rs__fail(ctx, RS_ERR_LIMIT, "rs_roads_set_attr: road %zu has %d attributes already", i, MAX_ATTRS);
        }
        size_t koff = pool_add(ctx, roads, key, kn);
        if (koff == SIZE_MAX || !attr_slot(ctx, roads, &next)) {
            roads->names_len = names_len;
            return rs__fail(ctx, RS_ERR_NOMEM, "rs_roads_set_attr: out of memory");
        }
        roads->attrs[roads->attrs_len].key = koff;
        roads->attrs[roads->attrs_len].value = voff;
        roads->attrs_len++;
        next.attr_count++;
    }
    *rec = next;
    rs__roads_reprint(roads, i);
    rs__ok(ctx);
    return RS_OK;
}

/* ------------------------------------------------------------------------
 * Lexer
 * ---------------------------------------------------------------------- */

const char *rs__quote(char *buf, size_t cap, const char *s, size_t n)
{
    const size_t max = 40;
    size_t k = n > max ? max : n;
    if (k + 6 > cap) k = cap - 6;
    while (k > 0 && k < n && ((unsigned char)s[k] & 0xC0) == 0x80) k--; /* whole UTF-8 characters */
    buf[0] = '\'';
    memcpy(buf + 1, s, k);
    size_t o = 1 + k;
    if (k < n) { memcpy(buf + o, "...", 3); o += 3; }
    buf[o++] = '\'';
    buf[o] = '\0';
    return buf;
}

int rs__tok_is(const rs__tok *t, const char *word)
{
    return !t->quoted && word_is(t->s, t->n, word);
}

static int blank(char c) { return c == ' ' || c == '\t'; }
static int hexdigit(char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f') || (c >= 'A' && c <= 'F'); }

/* Scan a quoted part opening at s[q] == '"'. Returns the index after the
 * closing quote, or 0 with L->err set. */
static size_t scan_quoted(rs__lex *L, size_t q)
{
    size_t j = q + 1;
    while (j < L->n) {
        char c = L->s[j];
        if (c == '\\') {
            if (j + 1 < L->n && (L->s[j + 1] == '"' || L->s[j + 1] == '\\')) { j += 2; continue; }
            L->err = RS__LEX_ERR_ESCAPE;
            L->err_at = L->s + j;
            return 0;
        }
        if (c == '"') {
            j++;
            if (j < L->n && !blank(L->s[j]) && L->s[j] != '#') {
                L->err = RS__LEX_ERR_AFTER_QUOTE;
                L->err_at = L->s + j;
                return 0;
            }
            return j;
        }
        j++;
    }
    L->err = RS__LEX_ERR_UNTERMINATED;
    L->err_at = L->s + q;
    return 0;
}

/* The token [b, end of the quoted string starting at q): 1, or -1 when the
 * quoted part is malformed (scan_quoted set L->err). */
static int quoted_token(rs__lex *L, rs__tok *t, size_t b, size_t q)
{
    size_t e = scan_quoted(L, q);
    if (!e) return -1;
    t->s = L->s + b;
    t->n = e - b;
    t->quoted = 1;
    L->i = e;
    return 1;
}

/* rs__lex_next in PLAIN mode, inline for the point lines (most of a file). */
static inline int lex_plain(rs__lex *L, rs__tok *t)
{
    const char *s = L->s;
    size_t i = L->i, n = L->n;
    while (i < n && (s[i] == ' ' || s[i] == '\t')) i++;
    if (i == n || s[i] == '#' || L->comment) {
        if (i < n && !L->comment) L->comment = s + i;
        L->i = n;
        return 0;
    }
    size_t b = i;
    while (i < n && s[i] != ' ' && s[i] != '\t' && s[i] != '#') i++;
    t->s = s + b;
    t->n = i - b;
    t->quoted = 0;
    L->tok_at = s + b;
    L->i = i;
    return 1;
}

int rs__lex_next(rs__lex *L, int mode, rs__tok *t)
{
    if (mode == RS__LEX_PLAIN) return lex_plain(L, t);
    size_t i = L->i;
    while (i < L->n && blank(L->s[i])) i++;
    L->i = i;
    if (i == L->n || L->comment) return 0;
    size_t b = i;
    t->quoted = 0;
    L->tok_at = L->s + b;
    if (L->s[b] == '#') {
        if (mode == RS__LEX_COLOUR) {
            size_t h = b + 1;
            while (h < L->n && hexdigit(L->s[h])) h++;
            if ((h - b - 1 == 6 || h - b - 1 == 8) && (h == L->n || blank(L->s[h]))) {
                t->s = L->s + b;
                t->n = h - b;
                L->i = h;
                return 1;
            }
        }
        L->comment = L->s + b;
        L->i = L->n;
        return 0;
    }
    if (L->s[b] == '"' && (mode == RS__LEX_NAME || mode == RS__LEX_ATTR)) return quoted_token(L, t, b, b);
    int seen_eq = 0;
    while (i < L->n && !blank(L->s[i]) && L->s[i] != '#') {
        if (mode == RS__LEX_ATTR && !seen_eq && L->s[i] == '=') {
            seen_eq = 1;
            if (i + 1 < L->n && L->s[i + 1] == '"') return quoted_token(L, t, b, i + 1);
        }
        i++;
    }
    t->s = L->s + b;
    t->n = i - b;
    L->i = i;
    return 1;
}

rs_result rs__lex_fail(rs_ctx *ctx, unsigned long long line, const rs__lex *L)
{
    char q[64];
    size_t col = (size_t)(L->err_at - L->s) + 1;
    const char *tok = L->tok_at ? L->tok_at : L->err_at;
    size_t tn = (size_t)(L->s + L->n - tok);
    if (L->err == RS__LEX_ERR_ESCAPE)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: unknown escape %s at column %zu (only \\\" and \\\\ in quotes)",
                        line, rs__quote(q, sizeof q, L->err_at, L->err_at + 1 < L->s + L->n ? 2 : 1), col);
    if (L->err == RS__LEX_ERR_AFTER_QUOTE)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: text after the closing quote at column %zu in %s", line, col,
                        rs__quote(q, sizeof q, tok, tn));
    return rs__fail(ctx, RS_ERR_PARSE, "line %llu: the quote at column %zu is not closed on this line", line, col);
}

size_t rs__tok_text(const rs__tok *t, char *out)
{
    size_t o = 0, i = 0;
    int in_q = 0;
    while (i < t->n) {
        char c = t->s[i];
        if (t->quoted && c == '"') { in_q = !in_q; i++; continue; }
        if (in_q && c == '\\') { out[o++] = t->s[i + 1]; i += 2; continue; }
        out[o++] = c;
        i++;
    }
    return o;
}

rs_result rs__number(rs_ctx *ctx, unsigned long long line, const rs__tok *t, const char *what, double *out)
{
    char q[64];
    const char *stop;
    int ok = rs__parse_double(t->s, t->s + t->n, out, &stop);
    if (ok && stop == t->s + t->n) return RS_OK;
    rs__quote(q, sizeof q, t->s, t->n);
    if (!ok && stop > t->s && stop == t->s + t->n)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: %s %s is out of range", line, what, q);
    if (memchr(t->s, ',', t->n))
        return rs__fail(ctx, RS_ERR_PARSE,
                        "line %llu: %s %s is not a number (use '.' as the decimal point and spaces between values)",
                        line, what, q);
    return rs__fail(ctx, RS_ERR_PARSE, "line %llu: %s %s is not a number", line, what, q);
}

size_t rs__utf8_len(const unsigned char *s, size_t avail)
{
    unsigned char c = s[0];
    size_t len;
    unsigned char lo = 0x80, hi = 0xBF; /* allowed range of the second byte */
    if (c >= 0xC2 && c <= 0xDF) len = 2;
    else if (c >= 0xE0 && c <= 0xEF) {
        len = 3;
        if (c == 0xE0) lo = 0xA0;
        if (c == 0xED) hi = 0x9F;
    } else if (c >= 0xF0 && c <= 0xF4) {
        len = 4;
        if (c == 0xF0) lo = 0x90;
        if (c == 0xF4) hi = 0x8F;
    } else return 0;
    if (avail < len) return 0;
    if (s[1] < lo || s[1] > hi) return 0;
    for (size_t i = 2; i < len; i++)
        if (s[i] < 0x80 || s[i] > 0xBF) return 0;
    return len;
}

/* ------------------------------------------------------------------------
 * Parser
 * ---------------------------------------------------------------------- */

#define MAX_TOKENS 5 /* "X Y" or "end" + extras, for the messages */

typedef struct text_parser {
    rs_ctx *ctx;
    rs_roads *roads;
    int keep_points; /* 0: count points only (styles-only parse) */
    rs_styles *styles;
    rs_profile profile;
    unsigned long long line;
    int in_road;
    unsigned long long road_line;
    const char *road_name; /* the raw name token, for messages */
    size_t road_name_len;
    rs_road_rec rec;       /* the open road: name, width, attributes */
    size_t road_first;     /* index of the open road's first point */
    int in_style;
    rs__style_block style;
    int seen_block;                /* a road, style or mark line came before */
    unsigned long long frame_line; /* line of the `frame` line, 0: none */
} text_parser;

/* One key=value word of a road header. `eq` points at its '='. */
static rs_result road_attr(text_parser *P, const rs__tok *t, const char *eq)
{
    char q[64], q2[64], why[200];
    rs_ctx *ctx = P->ctx;
    rs_roads *R = P->roads;
    size_t kn = (size_t)(eq - t->s);
    const char *rn = rs__quote(q2, sizeof q2, P->road_name, P->road_name_len);
    if (!key_ok(t->s, kn))
        return rs__fail(ctx, RS_ERR_PARSE,
                        "line %llu: road %s: attribute key %s must be 1..%d characters of A-Z a-z 0-9 _ : . -",
                        P->line, rn, rs__quote(q, sizeof q, t->s, kn), MAX_KEY);
    if (eq + 1 == t->s + t->n)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s: attribute %s has no value (write key=\"\" for an empty one)",
                        P->line, rn, rs__quote(q, sizeof q, t->s, t->n));
    if (find_attr(R, &P->rec, t->s, kn) != SIZE_MAX)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s: attribute %s given twice", P->line, rn,
                        rs__quote(q, sizeof q, t->s, kn));
    if (P->rec.attr_count >= MAX_ATTRS)
        return rs__fail(ctx, RS_ERR_LIMIT, "line %llu: road %s: more than %d attributes", P->line, rn, MAX_ATTRS);
    size_t names_len = R->names_len;
    size_t koff = pool_add(ctx, R, t->s, kn);
    rs__tok v = { eq + 1, (size_t)(t->s + t->n - (eq + 1)), t->quoted };
    char *w = koff == SIZE_MAX ? NULL : pool_reserve(ctx, R, v.n);
    if (!w || !attr_slot(ctx, R, &P->rec)) {
        R->names_len = names_len;
        return rs__fail(ctx, RS_ERR_NOMEM, "line %llu: out of memory", P->line);
    }
    size_t vn = rs__tok_text(&v, w);
    size_t voff = pool_commit(R, vn);
    if (!apply_known(&P->rec, R->names + koff, kn, R->names + voff, vn, voff, why, sizeof why))
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s: %s", P->line, rn, why);
    R->attrs[R->attrs_len].key = koff;
    R->attrs[R->attrs_len].value = voff;
    R->attrs_len++;
    P->rec.attr_count++;
    return RS_OK;
}

/* `road NAME [width W] [key=value ...]`; L is after `road`. */
static rs_result road_header(text_parser *P, rs__lex *L)
{
    char q[64], q2[64];
    rs_ctx *ctx = P->ctx;
    rs_roads *R = P->roads;
    if (P->in_road)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'road' inside road %s (line %llu); missing 'end'?",
                        P->line, rs__quote(q, sizeof q, P->road_name, P->road_name_len), P->road_line);
    rs__tok name, t;
    int k = rs__lex_next(L, RS__LEX_NAME, &name);
    if (k < 0) return rs__lex_fail(ctx, P->line, L);
    if (k == 0)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'road' needs a name and a width: road NAME width W", P->line);
    P->road_name = name.s;
    P->road_name_len = name.n;
    const char *rn = rs__quote(q2, sizeof q2, name.s, name.n);
    memset(&P->rec, 0, sizeof P->rec);
    P->rec.style = SIZE_MAX;
    P->rec.attr_first = R->attrs_len;
    char *w = pool_reserve(ctx, R, name.n);
    if (!w) return rs__fail(ctx, RS_ERR_NOMEM, "line %llu: out of memory", P->line);
    P->rec.name = pool_commit(R, rs__tok_text(&name, w));
    int have_width = 0;
    while ((k = rs__lex_next(L, RS__LEX_ATTR, &t)) != 0) {
        if (k < 0) return rs__lex_fail(ctx, P->line, L);
        if (rs__tok_is(&t, "width")) {
            if (have_width)
                return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s: 'width' given twice", P->line, rn);
            rs__tok v;
            if (rs__lex_next(L, RS__LEX_PLAIN, &v) == 0)
                return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s: the width value is missing", P->line, rn);
            /* A word after the width that is no attribute was reported
             * before the width's value was checked; keep that order. */
            rs__lex peek = *L;
            rs__tok x;
            if (P->rec.attr_count == 0 && rs__lex_next(&peek, RS__LEX_ATTR, &x) == 1 &&
                !rs__tok_is(&x, "width") && (x.s[0] == '"' || !memchr(x.s, '=', x.n)))
                return rs__fail(ctx, RS_ERR_PARSE, "line %llu: extra token %s after the width", P->line,
                                rs__quote(q, sizeof q, x.s, x.n));
            double wd;
            rs_result rc = rs__number(ctx, P->line, &v, "width", &wd);
            if (rc != RS_OK) return rc;
            if (!(wd > 0))
                return rs__fail(ctx, RS_ERR_PARSE, "line %llu: width %s must be > 0", P->line,
                                rs__quote(q, sizeof q, v.s, v.n));
            P->rec.width = wd;
            have_width = 1;
            continue;
        }
        const char *eq = t.s[0] == '"' ? NULL : memchr(t.s, '=', t.n);
        if (!eq) {
            if (!have_width && P->rec.attr_count == 0)
                return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s: expected 'width', got %s", P->line, rn,
                                rs__quote(q, sizeof q, t.s, t.n));
            if (P->rec.attr_count == 0)
                return rs__fail(ctx, RS_ERR_PARSE, "line %llu: extra token %s after the width", P->line,
                                rs__quote(q, sizeof q, t.s, t.n));
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s: %s is not an attribute (write key=value)", P->line,
                            rn, rs__quote(q, sizeof q, t.s, t.n));
        }
        rs_result rc = road_attr(P, &t, eq);
        if (rc != RS_OK) return rc;
    }
    P->rec.width_given = (uint8_t)have_width;
    if (!have_width) {
        if (P->rec.road_class == RS_CLASS_NONE && P->rec.lanes == 0)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s: missing 'width W' (or class= / lanes= to derive it)",
                            P->line, rn);
        rs_style_request req;
        memset(&req, 0, sizeof req);
        req.road_class = (rs_road_class)P->rec.road_class;
        req.lanes = P->rec.lanes;
        req.oneway = (rs_oneway)P->rec.oneway;
        req.area = (rs_area)P->rec.area;
        req.profile = P->profile;
        if (rs_style_default_width(&req, &P->rec.width) != RS_OK || !(P->rec.width > 0))
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s: no width for these attributes", P->line, rn);
    }
    P->in_road = 1;
    P->road_line = P->line;
    P->road_first = R->points;
    return RS_OK;
}

/* `key=value` words after a point's X Y (t: those already read). */
static rs_result point_attr(text_parser *P, const rs__tok *t)
{
    char q[64];
    rs_ctx *ctx = P->ctx;
    rs_roads *R = P->roads;
    const char *eq = memchr(t->s, '=', t->n);
    if (!eq)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: extra token %s after the point",
                        P->line, rs__quote(q, sizeof q, t->s, t->n));
    size_t kn = (size_t)(eq - t->s), vn = t->n - kn - 1;
    if (!key_ok(t->s, kn))
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: point attribute key %s must be 1..%d characters of A-Z a-z 0-9 _ : . -",
                        P->line, rs__quote(q, sizeof q, t->s, kn), MAX_KEY);
    if (vn == 0)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: point attribute %s has no value", P->line,
                        rs__quote(q, sizeof q, t->s, t->n));
    if (!P->keep_points) return RS_OK;
    size_t names_len = R->names_len;
    size_t k = pool_add(ctx, R, t->s, kn), v = k == SIZE_MAX ? SIZE_MAX : pool_add(ctx, R, eq + 1, vn);
    rs_point_attr *a = v == SIZE_MAX ? NULL : grow(ctx, R->pattrs, &R->pattrs_cap, R->pattrs_len + 1, sizeof *a);
    if (!a) {
        R->names_len = names_len;
        return rs__fail(ctx, RS_ERR_NOMEM, "line %llu: out of memory", P->line);
    }
    R->pattrs = a;
    a[R->pattrs_len].road = R->count;
    a[R->pattrs_len].point = R->points - P->road_first;
    a[R->pattrs_len].key = k;
    a[R->pattrs_len].value = v;
    R->pattrs_len++;
    return RS_OK;
}

static rs_result point_attrs(text_parser *P, const rs__tok *t, size_t n, rs__lex *L)
{
    for (size_t i = 0; i < n; i++) {
        rs_result rc = point_attr(P, &t[i]);
        if (rc != RS_OK) return rc;
    }
    rs__tok x;
    int k;
    while ((k = rs__lex_next(L, RS__LEX_PLAIN, &x)) == 1) {
        rs_result rc = point_attr(P, &x);
        if (rc != RS_OK) return rc;
    }
    return k < 0 ? rs__lex_fail(P->ctx, P->line, L) : RS_OK;
}

/* `mark TYPE road=NAME s=S t=T [length=L] [width=W] [flip]`; L after `mark`. */
static rs_result mark_line(text_parser *P, rs__lex *L)
{
    char q[64];
    rs_ctx *ctx = P->ctx;
    rs_roads *R = P->roads;
    if (P->in_road)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'mark' inside road %s (line %llu); missing 'end'?", P->line,
                        rs__quote(q, sizeof q, P->road_name, P->road_name_len), P->road_line);
    rs__tok type, t;
    int k = rs__lex_next(L, RS__LEX_PLAIN, &type);
    if (k == 0)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'mark' needs a type: mark TYPE road=NAME s=S t=T", P->line);
    if (!mark_type_ok(type.s, type.n))
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: mark type %s must be 1..%d characters of A-Z a-z 0-9 _ -", P->line,
                        rs__quote(q, sizeof q, type.s, type.n), RS_MARK_TYPE_MAX);
    rs_mark_rec rec;
    memset(&rec, 0, sizeof rec);
    rec.road = SIZE_MAX;
    rec.line = P->line;
    rs__tok road;
    int have[6] = { 0 }; /* road s t length width flip */
    static const char *const keys[6] = { "road", "s", "t", "length", "width", "flip" };
    while ((k = rs__lex_next(L, RS__LEX_ATTR, &t)) != 0) {
        if (k < 0) return rs__lex_fail(ctx, P->line, L);
        const char *eq = t.s[0] == '"' ? NULL : memchr(t.s, '=', t.n);
        size_t kn = eq ? (size_t)(eq - t.s) : t.n;
        int which = -1;
        for (int i = 0; i < 6; i++)
            if (strlen(keys[i]) == kn && memcmp(t.s, keys[i], kn) == 0) which = i;
        if (which < 0 || (which == 5) != (eq == NULL))
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: mark: unexpected %s (expected road=, s=, t=, length=, width= or flip)",
                            P->line, rs__quote(q, sizeof q, t.s, t.n));
        if (have[which])
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: mark: '%s' given twice", P->line, keys[which]);
        have[which] = 1;
        if (which == 5) {
            rec.flip = 1;
            continue;
        }
        rs__tok v = { eq + 1, (size_t)(t.s + t.n - (eq + 1)), t.quoted };
        if (v.n == 0) return rs__fail(ctx, RS_ERR_PARSE, "line %llu: mark: '%s' has no value", P->line, keys[which]);
        if (which == 0) {
            road = v;
            continue;
        }
        double d;
        rs_result rc = rs__number(ctx, P->line, &v, keys[which], &d);
        if (rc != RS_OK) return rc;
        if (which == 1 && !(fabs(d) <= 1e12))
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: mark: s must be within +-1e12", P->line);
        if (which == 2 && !(fabs(d) <= 1e6))
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: mark: t must be within +-1e6", P->line);
        if (which >= 3 && !(d > 0 && d <= 1e6))
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: mark: %s must be > 0 and <= 1e6", P->line, keys[which]);
        if (which == 1) rec.s = d;
        else if (which == 2) rec.t = d;
        else if (which == 3) rec.length = d;
        else rec.width = d;
    }
    for (int i = 0; i < 3; i++)
        if (!have[i])
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: mark: missing %s= (mark TYPE road=NAME s=S t=T)", P->line,
                            keys[i]);
    if (!P->keep_points) return RS_OK;
    size_t names_len = R->names_len;
    char *w = pool_reserve(ctx, R, road.n);
    if (w) rec.road_name = pool_commit(R, rs__tok_text(&road, w));
    if (!w || !push_mark(ctx, R, &rec, type.s, type.n)) {
        R->names_len = names_len;
        return rs__fail(ctx, RS_ERR_NOMEM, "line %llu: out of memory", P->line);
    }
    return RS_OK;
}

/* Road names to indices for the parsed marks (first road of a name). */
static int by_name_cmp(const void *a, const void *b, const rs_roads *R)
{
    size_t i = *(const size_t *)a, j = *(const size_t *)b;
    int c = strcmp(R->names + R->roads[i].name, R->names + R->roads[j].name);
    return c ? c : (i < j ? -1 : i > j);
}

static void sort_names(size_t *ix, size_t n, const rs_roads *R)
{
    /* heap sort: no qsort context pointer in C99 */
    for (size_t start = n / 2; start-- > 0;) {
        for (size_t root = start;;) {
            size_t c = 2 * root + 1;
            if (c >= n) break;
            if (c + 1 < n && by_name_cmp(&ix[c], &ix[c + 1], R) < 0) c++;
            if (by_name_cmp(&ix[root], &ix[c], R) >= 0) break;
            size_t tmp = ix[root]; ix[root] = ix[c]; ix[c] = tmp;
            root = c;
        }
    }
    for (size_t end = n; end-- > 1;) {
        size_t tmp = ix[0]; ix[0] = ix[end]; ix[end] = tmp;
        for (size_t root = 0;;) {
            size_t c = 2 * root + 1;
            if (c >= end) break;
            if (c + 1 < end && by_name_cmp(&ix[c], &ix[c + 1], R) < 0) c++;
            if (by_name_cmp(&ix[root], &ix[c], R) >= 0) break;
            size_t t2 = ix[root]; ix[root] = ix[c]; ix[c] = t2;
            root = c;
        }
    }
}

static rs_result resolve_marks(rs_ctx *ctx, rs_roads *R, size_t first)
{
    if (first >= R->marks_len) return RS_OK;
    size_t *ix = rs__alloc_array(ctx, R->count ? R->count : 1, sizeof *ix);
    if (!ix) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory resolving marks");
    for (size_t i = 0; i < R->count; i++) ix[i] = i;
    sort_names(ix, R->count, R);
    rs_result rc = RS_OK;
    for (size_t m = first; m < R->marks_len && rc == RS_OK; m++) {
        rs_mark_rec *mk = &R->marks[m];
        if (mk->road != SIZE_MAX) continue;
        const char *want = R->names + mk->road_name;
        size_t lo = 0, hi = R->count;
        while (lo < hi) {
            size_t mid = lo + (hi - lo) / 2;
            if (strcmp(R->names + R->roads[ix[mid]].name, want) < 0) lo = mid + 1;
            else hi = mid;
        }
        if (lo < R->count && strcmp(R->names + R->roads[ix[lo]].name, want) == 0) mk->road = ix[lo];
        else {
            char q[64];
            rc = rs__fail(ctx, RS_ERR_PARSE, "line %llu: mark: no road named %s", (unsigned long long)mk->line,
                          rs__quote(q, sizeof q, want, strlen(want)));
        }
    }
    rs__free(ctx, ix);
    return rc;
}

/* `end`, a point, or an unknown keyword (the road format before styles). */
static rs_result road_line(text_parser *P, const rs__tok *t, size_t nt, rs__lex *L)
{
    char q[64];
    rs_ctx *ctx = P->ctx;
    if (rs__tok_is(&t[0], "end")) {
        if (nt > 1)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: extra token %s after 'end'", P->line,
                            rs__quote(q, sizeof q, t[1].s, t[1].n));
        if (!P->in_road)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'end' without a matching 'road'", P->line);
        size_t n = P->roads->points - P->road_first;
        if (n < 2)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s (line %llu) has %zu point%s; a road needs at least 2",
                            P->line, rs__quote(q, sizeof q, P->road_name, P->road_name_len), P->road_line, n,
                            n == 1 ? "" : "s");
        if (!commit_road(ctx, P->roads, &P->rec, n))
            return rs__fail(ctx, RS_ERR_NOMEM, "line %llu: out of memory", P->line);
        if (P->keep_points) rs__roads_reprint(P->roads, P->roads->count - 1);
        P->in_road = 0;
        return RS_OK;
    }
    char c = t[0].s[0];
    /* A point line: starts like a number, or is two tokens inside a road
     * (so "nan 5" is reported as a bad number, not as a keyword). */
    if ((c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || (P->in_road && nt == 2)) {
        if (!P->in_road)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: point %s outside a road block (add 'road NAME width W' first)",
                            P->line, rs__quote(q, sizeof q, t[0].s, t[0].n));
        double x, y;
        rs_result rc = rs__number(ctx, P->line, &t[0], "x", &x);
        if (rc != RS_OK) return rc;
        if (nt < 2)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: point needs 'X Y', got only %s", P->line,
                            rs__quote(q, sizeof q, t[0].s, t[0].n));
        if ((rc = rs__number(ctx, P->line, &t[1], "y", &y)) != RS_OK) return rc;
        rs_roads *R = P->roads;
        if (nt > 2 && (rc = point_attrs(P, t + 2, nt - 2, L)) != RS_OK) return rc;
        if (R->points >= ctx->limits.max_points)
            return rs__fail(ctx, RS_ERR_LIMIT, "line %llu: more than %llu road points in total", P->line,
                            (unsigned long long)ctx->limits.max_points);
        if (P->keep_points) {
            double *pts = grow(ctx, R->xy, &R->points_cap, R->points + 1, 2 * sizeof(double));
            if (!pts) return rs__fail(ctx, RS_ERR_NOMEM, "line %llu: out of memory for road points", P->line);
            R->xy = pts;
            R->xy[2 * R->points] = x;
            R->xy[2 * R->points + 1] = y;
        }
        R->points++;
        return RS_OK;
    }
    return rs__fail(ctx, RS_ERR_PARSE, "line %llu: unknown keyword %s (expected 'road', 'end' or a point 'X Y')",
                    P->line, rs__quote(q, sizeof q, t[0].s, t[0].n));
}

/* Check one line's bytes: no NUL, no control characters, valid UTF-8. */
static rs_result check_bytes(text_parser *P, const unsigned char *s, size_t n)
{
    for (size_t i = 0; i < n;) {
        unsigned char c = s[i];
        if (c >= 0x20 && c < 0x7F) { i++; continue; }
        if (c == '\t') { i++; continue; }
        if (c == 0)
            return rs__fail(P->ctx, RS_ERR_PARSE, "line %llu: NUL byte at column %zu (binary file?)", P->line, i + 1);
        if (c < 0x80)
            return rs__fail(P->ctx, RS_ERR_PARSE, "line %llu: control character 0x%02x at column %zu", P->line, c, i + 1);
        size_t k = rs__utf8_len(s + i, n - i);
        if (!k)
            return rs__fail(P->ctx, RS_ERR_PARSE, "line %llu: invalid UTF-8 byte 0x%02x at column %zu (binary file?)",
                            P->line, c, i + 1);
        i += k;
    }
    return RS_OK;
}

/* `frame local` or `frame world [CRS]`: once, before any road, style or
 * mark line. The CRS is one word or a quoted string (EPSG:32632, a WKT). */
static rs_result frame_line(text_parser *P, rs__lex *L)
{
    char q[64];
    rs_ctx *ctx = P->ctx;
    rs_roads *R = P->roads;
    if (P->frame_line)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'frame' given twice (first on line %llu)", P->line,
                        P->frame_line);
    if (P->seen_block || P->in_road)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'frame' must come before the first road, style or mark",
                        P->line);
    rs__tok kind, crs, extra;
    int k = rs__lex_next(L, RS__LEX_PLAIN, &kind);
    if (k <= 0 || !(rs__tok_is(&kind, "local") || rs__tok_is(&kind, "world")))
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: frame %s must be 'local' or 'world [CRS]' (e.g. frame world EPSG:32632)",
                        P->line, k > 0 ? rs__quote(q, sizeof q, kind.s, kind.n) : "''");
    int world = kind.s[0] == 'w';
    k = rs__lex_next(L, RS__LEX_NAME, &crs);
    if (k < 0) return rs__lex_fail(ctx, P->line, L);
    if (k > 0 && !world)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: extra token %s after 'frame local'", P->line,
                        rs__quote(q, sizeof q, crs.s, crs.n));
    if (k > 0) {
        int k2 = rs__lex_next(L, RS__LEX_NAME, &extra);
        if (k2 < 0) return rs__lex_fail(ctx, P->line, L);
        if (k2 > 0)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: extra token %s after the CRS (quote a CRS with blanks)",
                            P->line, rs__quote(q, sizeof q, extra.s, extra.n));
        if (R) {
            char *w = pool_reserve(ctx, R, crs.n);
            if (!w) return rs__fail(ctx, RS_ERR_NOMEM, "line %llu: out of memory", P->line);
            size_t len = rs__tok_text(&crs, w);
            if (len == 0) return rs__fail(ctx, RS_ERR_PARSE, "line %llu: the CRS is empty", P->line);
            R->frame_crs = pool_commit(R, len);
        }
    }
    if (R) R->frame = world ? RS_FRAME_WORLD : RS_FRAME_LOCAL;
    P->frame_line = P->line;
    return RS_OK;
}

/* One meaningful line: L is after its first token t0. */
static rs_result text_line(text_parser *P, rs__lex *L, const rs__tok *t0)
{
    char q[64];
    rs_ctx *ctx = P->ctx;
    if (P->in_style) {
        if (rs__tok_is(t0, "end")) {
            P->in_style = 0;
            return rs__style_end(ctx, P->styles, &P->style, P->line, L);
        }
        if (rs__tok_is(t0, "road") || rs__tok_is(t0, "style"))
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: '%s' inside style %s (line %llu); missing 'end'?", P->line,
                            t0->s[0] == 'r' ? "road" : "style",
                            rs__quote(q, sizeof q, P->style.st.name, strlen(P->style.st.name)), P->style.line);
        return rs__style_line(ctx, &P->style, P->line, t0, L);
    }
    if (rs__tok_is(t0, "style")) {
        if (P->in_road)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'style' inside road %s (line %llu); missing 'end'?",
                            P->line, rs__quote(q, sizeof q, P->road_name, P->road_name_len), P->road_line);
        P->in_style = 1;
        P->seen_block = 1;
        return rs__style_begin(ctx, &P->style, P->line, L);
    }
    if (rs__tok_is(t0, "frame")) return frame_line(P, L);
    if (rs__tok_is(t0, "road")) { P->seen_block = 1; return road_header(P, L); }
    if (rs__tok_is(t0, "mark")) { P->seen_block = 1; return mark_line(P, L); }
    rs__tok t[MAX_TOKENS];
    size_t nt = 1;
    t[0] = *t0;
    while (nt < MAX_TOKENS && lex_plain(L, &t[nt]) == 1) nt++;
    return road_line(P, t, nt, L);
}

rs_result rs__text_parse(rs_ctx *ctx, const char *text, size_t size, rs_profile profile, rs_roads *roads,
                         rs_styles *styles)
{
    text_parser P;
    memset(&P, 0, sizeof P);
    P.ctx = ctx;
    P.profile = profile;
    P.roads = roads;
    P.keep_points = roads != NULL;
    P.styles = styles;
    rs_result rc = RS_OK;
    if (!roads && (rc = rs_roads_create(ctx, &P.roads)) != RS_OK) return rc;
    if (!styles && (rc = rs_styles_create(ctx, &P.styles)) != RS_OK) {
        if (!roads) rs_roads_free(ctx, P.roads);
        return rc;
    }
    size_t styles_before = rs_styles_count(P.styles);
    size_t marks_before = P.roads->marks_len;

    size_t pos = 0;
    /* A UTF-8 byte order mark, as some editors write, is not content. */
    if (size >= 3 && (unsigned char)text[0] == 0xEF && (unsigned char)text[1] == 0xBB && (unsigned char)text[2] == 0xBF)
        pos = 3;
    while (pos < size) {
        P.line++;
        const char *ls = text + pos;
        const char *nl = memchr(ls, '\n', size - pos);
        size_t len = nl ? (size_t)(nl - ls) : size - pos;
        pos += len + (nl ? 1 : 0);
        if (len && ls[len - 1] == '\r') len--; /* CRLF */
        if (len > ctx->limits.max_line_length) {
            rc = rs__fail(ctx, RS_ERR_LIMIT, "line %llu: longer than %u bytes", P.line, ctx->limits.max_line_length);
            goto done;
        }
        if ((rc = check_bytes(&P, (const unsigned char *)ls, len)) != RS_OK) goto done;
        /* progress of rs_roads_parse(_ex): bytes read */
        if (rs__tick(ctx, len + 1)) {
            rc = RS_ERR_CANCELLED;
            goto done;
        }
        rs__lex L;
        memset(&L, 0, sizeof L);
        L.s = ls;
        L.n = len;
        rs__tok t0;
        if (lex_plain(&L, &t0) == 0) continue;
        char c = t0.s[0];
        if (!P.in_style && ((c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.')) {
            /* a point line (or an error road_line names): skip the keyword checks */
            rs__tok t[MAX_TOKENS];
            size_t nt = 1;
            t[0] = t0;
            while (nt < MAX_TOKENS && lex_plain(&L, &t[nt]) == 1) nt++;
            rc = road_line(&P, t, nt, &L);
        } else {
            rc = text_line(&P, &L, &t0);
        }
        if (rc != RS_OK) goto done;
    }
    if (P.in_road) {
        char q[64];
        rc = rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s (started on line %llu) has no 'end'", P.line,
                      rs__quote(q, sizeof q, P.road_name, P.road_name_len), P.road_line);
    } else if (P.in_style) {
        char q[64];
        rc = rs__fail(ctx, RS_ERR_PARSE, "line %llu: style %s (started on line %llu) has no 'end'", P.line,
                      rs__quote(q, sizeof q, P.style.st.name, strlen(P.style.st.name)), P.style.line);
    } else if (roads) {
        rc = resolve_marks(ctx, P.roads, marks_before);
    }
done:
    if (rc != RS_OK) rs__styles_truncate(P.styles, styles_before);
    if (!roads) rs_roads_free(ctx, P.roads);
    if (!styles) rs_styles_free(ctx, P.styles);
    return rc;
}

rs_result rs_roads_parse_ex(rs_ctx *ctx, const char *text, size_t size, const rs_road_parse_options *opts,
                            rs_roads **out)
{
    if (!out) return ctx ? rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_parse: out is NULL") : RS_ERR_INVALID_ARG;
    *out = NULL;
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!text && size) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_parse: text is NULL");
    rs_road_parse_options po;
    rs_result rc = RS__OPTS_IN(ctx, opts, &po, rs_road_parse_options);
    if (rc) return rc;
    rs_profile profile = po.profile;
    if (profile != RS_PROFILE_RMS && profile != RS_PROFILE_MUTCD)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_parse_ex: unknown profile %d", (int)profile);
    rs_roads *roads;
    rc = rs_roads_create(ctx, &roads);
    if (rc != RS_OK) return rc;
    /* progress: the context's callback (rs_ctx_set_progress), bytes of the text */
    rs__progress pg;
    rs__progress_begin(ctx, &pg, NULL, NULL, size ? size : 1, (uint64_t)1 << 20);
    rc = rs__progress_end(ctx, &pg, rs__text_parse(ctx, text, size, profile, roads, po.styles));
    if (rc != RS_OK) {
        rs_roads_free(ctx, roads);
        return rc;
    }
    *out = roads;
    rs__ok(ctx);
    return RS_OK;
}

rs_result rs_roads_parse(rs_ctx *ctx, const char *text, size_t size, rs_roads **out)
{
    return rs_roads_parse_ex(ctx, text, size, NULL, out);
}

/* For lib/input/roads_edit.c (lib/input/roads_impl.h). */
void *rs__roads_grow(rs_ctx *ctx, void *buf, size_t *cap, size_t need, size_t elem)
{
    return grow(ctx, buf, cap, need, elem);
}

size_t rs__roads_pool_add(rs_ctx *ctx, rs_roads *roads, const char *s, size_t n)
{
    return pool_add(ctx, roads, s, n);
}

int rs__roads_key_ok(const char *k, size_t n) { return key_ok(k, n); }
