/* Road sets and the road text format (docs/road-format.md).
 *
 * All points of all roads live in one growable array of doubles; a road is
 * a slice of it plus a width and a name (NUL-terminated, in one growable
 * character pool). The parser appends points of the open road straight to
 * the shared array and records the road when its `end` arrives, so parsing
 * costs one pass and amortised O(1) allocations per point. */
#include "internal.h"

#include <math.h>
#include <string.h>

typedef struct rs_road_rec {
    size_t name;  /* offset into names */
    double width;
    size_t first; /* index of the first point */
    size_t n;     /* point count */
} rs_road_rec;

struct rs_roads {
    rs_road_rec *roads;
    size_t count, cap;
    double *xy; /* x0 y0 x1 y1 ... */
    size_t points, points_cap;
    char *names;
    size_t names_len, names_cap;
};

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
    rs__free(ctx, roads);
}

size_t rs_roads_count(const rs_roads *roads) { return roads ? roads->count : 0; }

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

/* Element offset of p inside [base, base + count) of `elem`-byte
 * elements, or SIZE_MAX: callers may pass pointers from rs_roads_get(),
 * which a realloc would invalidate. */
static size_t inside(const void *base, size_t count, const void *p, size_t elem)
{
    uintptr_t b = (uintptr_t)base, q = (uintptr_t)p;
    if (!base || !p || q < b || q >= b + count * elem) return SIZE_MAX;
    return (size_t)(q - b) / elem;
}

/* Record a road whose points are already the last `n` of roads->xy. */
static int commit_road(rs_ctx *ctx, rs_roads *roads, const char *name, size_t name_len, double width, size_t n)
{
    size_t need_names, name_off = inside(roads->names, roads->names_len, name, 1);
    if (name_len > SIZE_MAX - 1 - roads->names_len) return 0;
    need_names = roads->names_len + name_len + 1;
    char *names = grow(ctx, roads->names, &roads->names_cap, need_names, 1);
    if (!names) return 0;
    roads->names = names;
    if (name_off != SIZE_MAX) name = names + name_off; /* the name came from this pool */
    rs_road_rec *recs = grow(ctx, roads->roads, &roads->cap, roads->count + 1, sizeof(rs_road_rec));
    if (!recs) return 0;
    roads->roads = recs;
    if (name_len) memcpy(roads->names + roads->names_len, name, name_len);
    roads->names[roads->names_len + name_len] = '\0';
    rs_road_rec *rec = &roads->roads[roads->count++];
    rec->name = roads->names_len;
    rec->width = width;
    rec->first = roads->points - n;
    rec->n = n;
    roads->names_len = need_names;
    return 1;
}

rs_result rs_roads_add(rs_ctx *ctx, rs_roads *roads, const char *name, double width,
                       const double *xy, size_t n)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!roads) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_add: roads is NULL");
    if (!(width > 0) || !isfinite(width))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_add: width %g must be finite and > 0", width);
    if (n < 2) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_add: %zu points; a road needs at least 2", n);
    if (!xy) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_add: xy is NULL");
    for (size_t i = 0; i < 2 * n; i++)
        if (!isfinite(xy[i]))
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_add: point %zu has a non-finite %c", i / 2,
                            (i & 1) ? 'y' : 'x');
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
    memcpy(roads->xy + 2 * roads->points, xy, n * 2 * sizeof(double));
    roads->points += n;
    if (!commit_road(ctx, roads, name, name_len, width, n)) {
        roads->points -= n;
        return rs__fail(ctx, RS_ERR_NOMEM, "rs_roads_add: out of memory");
    }
    rs__ok(ctx);
    return RS_OK;
}

/* ------------------------------------------------------------------------
 * Parser
 * ---------------------------------------------------------------------- */

#define MAX_TOKENS 5 /* "road NAME width W" + one to detect extras */

typedef struct token {
    const char *s;
    size_t n;
} token;

/* Quote a token for a message, shortened to keep messages one line. */
static const char *quote(char *buf, size_t cap, const char *s, size_t n)
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

static int tok_is(const token *t, const char *word)
{
    size_t n = strlen(word);
    return t->n == n && memcmp(t->s, word, n) == 0;
}

/* Length of a well-formed UTF-8 sequence at s (lead byte >= 0x80), 0 if
 * malformed (overlong, surrogate, > U+10FFFF, truncated). */
static size_t utf8_len(const unsigned char *s, size_t avail)
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

typedef struct road_parser {
    rs_ctx *ctx;
    rs_roads *roads;
    unsigned long long line;
    int in_road;
    unsigned long long road_line;
    const char *road_name;
    size_t road_name_len;
    double road_width;
    size_t road_first; /* index of the open road's first point */
} road_parser;

/* Parse a whole token as a number. Returns RS_OK or a message naming it. */
static rs_result number_token(road_parser *P, const token *t, const char *what, double *out)
{
    char q[64];
    const char *stop;
    int ok = rs__parse_double(t->s, t->s + t->n, out, &stop);
    if (ok && stop == t->s + t->n) return RS_OK;
    quote(q, sizeof q, t->s, t->n);
    if (!ok && stop > t->s && stop == t->s + t->n)
        return rs__fail(P->ctx, RS_ERR_PARSE, "line %llu: %s %s is out of range", P->line, what, q);
    if (memchr(t->s, ',', t->n))
        return rs__fail(P->ctx, RS_ERR_PARSE,
                        "line %llu: %s %s is not a number (use '.' as the decimal point and spaces between values)",
                        P->line, what, q);
    return rs__fail(P->ctx, RS_ERR_PARSE, "line %llu: %s %s is not a number", P->line, what, q);
}

static rs_result road_line(road_parser *P, const token *t, size_t nt)
{
    char q[64], q2[64];
    rs_ctx *ctx = P->ctx;
    if (tok_is(&t[0], "road")) {
        if (P->in_road)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'road' inside road %s (line %llu); missing 'end'?",
                            P->line, quote(q, sizeof q, P->road_name, P->road_name_len), P->road_line);
        if (nt < 2)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'road' needs a name and a width: road NAME width W", P->line);
        if (nt < 3)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s: missing 'width W'", P->line,
                            quote(q, sizeof q, t[1].s, t[1].n));
        if (!tok_is(&t[2], "width"))
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s: expected 'width', got %s", P->line,
                            quote(q, sizeof q, t[1].s, t[1].n), quote(q2, sizeof q2, t[2].s, t[2].n));
        if (nt < 4)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s: the width value is missing", P->line,
                            quote(q, sizeof q, t[1].s, t[1].n));
        if (nt > 4)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: extra token %s after the width", P->line,
                            quote(q, sizeof q, t[4].s, t[4].n));
        double w;
        rs_result rc = number_token(P, &t[3], "width", &w);
        if (rc != RS_OK) return rc;
        if (!(w > 0))
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: width %s must be > 0", P->line,
                            quote(q, sizeof q, t[3].s, t[3].n));
        P->in_road = 1;
        P->road_line = P->line;
        P->road_name = t[1].s;
        P->road_name_len = t[1].n;
        P->road_width = w;
        P->road_first = P->roads->points;
        return RS_OK;
    }
    if (tok_is(&t[0], "end")) {
        if (nt > 1)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: extra token %s after 'end'", P->line,
                            quote(q, sizeof q, t[1].s, t[1].n));
        if (!P->in_road)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'end' without a matching 'road'", P->line);
        size_t n = P->roads->points - P->road_first;
        if (n < 2)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s (line %llu) has %zu point%s; a road needs at least 2",
                            P->line, quote(q, sizeof q, P->road_name, P->road_name_len), P->road_line, n,
                            n == 1 ? "" : "s");
        if (!commit_road(ctx, P->roads, P->road_name, P->road_name_len, P->road_width, n))
            return rs__fail(ctx, RS_ERR_NOMEM, "line %llu: out of memory", P->line);
        P->in_road = 0;
        return RS_OK;
    }
    char c = t[0].s[0];
    /* A point line: starts like a number, or is two tokens inside a road
     * (so "nan 5" is reported as a bad number, not as a keyword). */
    if ((c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || (P->in_road && nt == 2)) {
        if (!P->in_road)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: point %s outside a road block (add 'road NAME width W' first)",
                            P->line, quote(q, sizeof q, t[0].s, t[0].n));
        double x, y;
        rs_result rc = number_token(P, &t[0], "x", &x);
        if (rc != RS_OK) return rc;
        if (nt < 2)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: point needs 'X Y', got only %s", P->line,
                            quote(q, sizeof q, t[0].s, t[0].n));
        if ((rc = number_token(P, &t[1], "y", &y)) != RS_OK) return rc;
        if (nt > 2)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: extra token %s after the point", P->line,
                            quote(q, sizeof q, t[2].s, t[2].n));
        rs_roads *R = P->roads;
        if (R->points >= ctx->limits.max_points)
            return rs__fail(ctx, RS_ERR_LIMIT, "line %llu: more than %llu road points in total", P->line,
                            (unsigned long long)ctx->limits.max_points);
        double *pts = grow(ctx, R->xy, &R->points_cap, R->points + 1, 2 * sizeof(double));
        if (!pts) return rs__fail(ctx, RS_ERR_NOMEM, "line %llu: out of memory for road points", P->line);
        R->xy = pts;
        R->xy[2 * R->points] = x;
        R->xy[2 * R->points + 1] = y;
        R->points++;
        return RS_OK;
    }
    return rs__fail(ctx, RS_ERR_PARSE, "line %llu: unknown keyword %s (expected 'road', 'end' or a point 'X Y')",
                    P->line, quote(q, sizeof q, t[0].s, t[0].n));
}

/* Check one line's bytes: no NUL, no control characters, valid UTF-8. */
static rs_result check_bytes(road_parser *P, const unsigned char *s, size_t n)
{
    for (size_t i = 0; i < n;) {
        unsigned char c = s[i];
        if (c >= 0x20 && c < 0x7F) { i++; continue; }
        if (c == '\t') { i++; continue; }
        if (c == 0)
            return rs__fail(P->ctx, RS_ERR_PARSE, "line %llu: NUL byte at column %zu (binary file?)", P->line, i + 1);
        if (c < 0x80)
            return rs__fail(P->ctx, RS_ERR_PARSE, "line %llu: control character 0x%02x at column %zu", P->line, c, i + 1);
        size_t k = utf8_len(s + i, n - i);
        if (!k)
            return rs__fail(P->ctx, RS_ERR_PARSE, "line %llu: invalid UTF-8 byte 0x%02x at column %zu (binary file?)",
                            P->line, c, i + 1);
        i += k;
    }
    return RS_OK;
}

rs_result rs_roads_parse(rs_ctx *ctx, const char *text, size_t size, rs_roads **out)
{
    if (!out) return ctx ? rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_parse: out is NULL") : RS_ERR_INVALID_ARG;
    *out = NULL;
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!text && size) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_roads_parse: text is NULL");

    road_parser P;
    memset(&P, 0, sizeof P);
    P.ctx = ctx;
    rs_result rc = rs_roads_create(ctx, &P.roads);
    if (rc != RS_OK) return rc;

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
            goto fail;
        }
        if ((rc = check_bytes(&P, (const unsigned char *)ls, len)) != RS_OK) goto fail;
        const char *hash = memchr(ls, '#', len);
        if (hash) len = (size_t)(hash - ls);
        token t[MAX_TOKENS];
        size_t nt = 0;
        for (size_t i = 0; i < len && nt < MAX_TOKENS;) {
            while (i < len && (ls[i] == ' ' || ls[i] == '\t')) i++;
            if (i == len) break;
            size_t b = i;
            while (i < len && ls[i] != ' ' && ls[i] != '\t') i++;
            t[nt].s = ls + b;
            t[nt].n = i - b;
            nt++;
        }
        if (nt == 0) continue;
        if ((rc = road_line(&P, t, nt)) != RS_OK) goto fail;
    }
    if (P.in_road) {
        char q[64];
        rc = rs__fail(ctx, RS_ERR_PARSE, "line %llu: road %s (started on line %llu) has no 'end'", P.line,
                      quote(q, sizeof q, P.road_name, P.road_name_len), P.road_line);
        goto fail;
    }
    *out = P.roads;
    rs__ok(ctx);
    return RS_OK;
fail:
    rs_roads_free(ctx, P.roads);
    return rc;
}
