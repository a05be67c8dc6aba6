/* Road styles: the style-block parser, named style sets and the built-in
 * default styles per road class (docs/road-format.md has the grammar, the
 * tables and their sources).
 *
 * A style is plain data (rs_style: fixed arrays, the name inline), so a
 * set is one array plus a hash index over the names. The block parser
 * reads lines handed over by the text parser in lib/input/roads.c. */
#include "style.h"
#include "lanes.h"
#include "network.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define MAX_STYLES 65536
/* Value bounds (metres), documented on rs_style and in docs/road-format.md. */
#define MIN_WIDTH 0.001
#define MAX_WIDTH 1000.0
#define MAX_OFFSET 1000.0
#define MIN_DASH 0.001
#define MAX_DASH 1e6
#define MAX_PHASE 1e9
#define MIN_SURF_LEN 0.001
#define MAX_SURF_LEN 1e6

struct rs_styles {
    rs_style *v;
    size_t count, cap;
    uint32_t *index; /* open addressing: style index + 1, 0 = empty */
    size_t index_cap; /* a power of two >= 2 * count, or 0 */
};

static uint64_t name_hash(const char *s)
{
    uint64_t h = 1469598103934665603ull;
    for (; *s; s++) {
        h ^= (unsigned char)*s;
        h *= 1099511628211ull;
    }
    return h;
}

static void index_insert(rs_styles *S, size_t i)
{
    size_t mask = S->index_cap - 1, k = (size_t)name_hash(S->v[i].name) & mask;
    while (S->index[k]) k = (k + 1) & mask;
    S->index[k] = (uint32_t)(i + 1);
}

/* Rebuild the index for `count` styles (capacity grows as needed). */
static int index_rebuild(rs_ctx *ctx, rs_styles *S, size_t count)
{
    size_t cap = S->index_cap ? S->index_cap : 16;
    while (cap < 2 * count) cap *= 2;
    if (cap != S->index_cap) {
        uint32_t *ix = rs__alloc_array(ctx, cap, sizeof *ix);
        if (!ix) return 0;
        rs__free(ctx, S->index);
        S->index = ix;
        S->index_cap = cap;
    }
    memset(S->index, 0, S->index_cap * sizeof *S->index);
    for (size_t i = 0; i < count; i++) index_insert(S, i);
    return 1;
}

rs_result rs_styles_create(rs_ctx *ctx, rs_styles **out)
{
    if (!out) return ctx ? rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_styles_create: out is NULL") : RS_ERR_INVALID_ARG;
    *out = NULL;
    if (!ctx) return RS_ERR_INVALID_ARG;
    rs_styles *S = rs__calloc(ctx, 1, sizeof *S);
    if (!S) return rs__fail(ctx, RS_ERR_NOMEM, "out of memory creating a style set");
    *out = S;
    rs__ok(ctx);
    return RS_OK;
}

void rs_styles_free(rs_ctx *ctx, rs_styles *styles)
{
    if (!ctx || !styles) return;
    rs__free(ctx, styles->v);
    rs__free(ctx, styles->index);
    rs__free(ctx, styles);
}

size_t rs_styles_count(const rs_styles *styles) { return styles ? styles->count : 0; }

const rs_style *rs_styles_get(const rs_styles *styles, size_t i)
{
    return styles && i < styles->count ? &styles->v[i] : NULL;
}

const rs_style *rs_styles_find(const rs_styles *styles, const char *name)
{
    if (!styles || !name || !styles->count) return NULL;
    size_t mask = styles->index_cap - 1, k = (size_t)name_hash(name) & mask;
    for (uint32_t e; (e = styles->index[k]) != 0; k = (k + 1) & mask)
        if (strcmp(styles->v[e - 1].name, name) == 0) return &styles->v[e - 1];
    return NULL;
}

void rs__styles_truncate(rs_styles *styles, size_t count)
{
    if (!styles || count >= styles->count) return;
    styles->count = count;
    /* deleting from open addressing: rebuild in place (the capacity fits) */
    if (styles->index_cap) {
        memset(styles->index, 0, styles->index_cap * sizeof *styles->index);
        for (size_t i = 0; i < count; i++) index_insert(styles, i);
    }
}

/* The checks of rs_styles_add, shared with the parser's `end`. Returns 1,
 * or 0 with the reason in why. */
static int style_ok(const rs_style *s, char *why, size_t cap)
{
    const char *nul = memchr(s->name, '\0', sizeof s->name);
    size_t n = nul ? (size_t)(nul - s->name) : sizeof s->name;
    if (n == 0 || n > RS_STYLE_NAME_MAX) {
        snprintf(why, cap, "the name must be 1..%d bytes", RS_STYLE_NAME_MAX);
        return 0;
    }
    for (size_t i = 0; i < n;) {
        unsigned char c = (unsigned char)s->name[i];
        if (c >= 0x80) {
            size_t k = rs__utf8_len((const unsigned char *)s->name + i, n - i);
            if (!k) { snprintf(why, cap, "the name is not valid UTF-8"); return 0; }
            i += k;
        } else if (c < 0x20 || c == 0x7F) {
            snprintf(why, cap, "the name has a control character");
            return 0;
        } else i++;
    }
    if ((unsigned)s->surface > RS_SURFACE_GRADIENT) {
        snprintf(why, cap, "surface %d is not an rs_surface", (int)s->surface);
        return 0;
    }
    {
        const char *inul = memchr(s->surface_image, '\0', sizeof s->surface_image);
        if (!inul) {
            snprintf(why, cap, "the surface image name is longer than %d bytes", RS_STYLE_IMAGE_MAX);
            return 0;
        }
        size_t ni = (size_t)(inul - s->surface_image);
        for (size_t i = 0; i < ni;) {
            unsigned char c = (unsigned char)s->surface_image[i];
            if (c >= 0x80) {
                size_t k = rs__utf8_len((const unsigned char *)s->surface_image + i, ni - i);
                if (!k) { snprintf(why, cap, "the surface image name is not valid UTF-8"); return 0; }
                i += k;
            } else if (c < 0x20 || c == 0x7F) {
                snprintf(why, cap, "the surface image name has a control character");
                return 0;
            } else i++;
        }
        if (s->surface_length != 0 && !(ni > 0 && s->surface_length >= MIN_SURF_LEN && s->surface_length <= MAX_SURF_LEN)) {
            snprintf(why, cap, "surface length %g must be 0 (the image's aspect) or %g..%g metres, with an image",
                     s->surface_length, MIN_SURF_LEN, MAX_SURF_LEN);
            return 0;
        }
    }
    if (s->casing_width != 0 && !(s->casing_width >= MIN_WIDTH && s->casing_width <= MAX_WIDTH)) {
        snprintf(why, cap, "casing width %g must be 0 (none) or %g..%g metres", s->casing_width, MIN_WIDTH, MAX_WIDTH);
        return 0;
    }
    if (s->line_count > RS_STYLE_MAX_LINES) {
        snprintf(why, cap, "%u lines; at most %d", s->line_count, RS_STYLE_MAX_LINES);
        return 0;
    }
    for (uint32_t i = 0; i < s->line_count; i++) {
        const rs_style_line *l = &s->line[i];
        if (!(l->offset >= -MAX_OFFSET && l->offset <= MAX_OFFSET)) {
            snprintf(why, cap, "line %u: offset %g must be -%g..%g metres", i, l->offset, MAX_OFFSET, MAX_OFFSET);
            return 0;
        }
        if (!(l->width >= MIN_WIDTH && l->width <= MAX_WIDTH)) {
            snprintf(why, cap, "line %u: width %g must be %g..%g metres", i, l->width, MIN_WIDTH, MAX_WIDTH);
            return 0;
        }
        if (l->dash_count > RS_STYLE_MAX_DASH || (l->dash_count & 1)) {
            snprintf(why, cap, "line %u: %u dash lengths; an even count up to %d", i, l->dash_count, RS_STYLE_MAX_DASH);
            return 0;
        }
        for (uint32_t k = 0; k < l->dash_count; k++)
            if (!(l->dash[k] >= MIN_DASH && l->dash[k] <= MAX_DASH)) {
                snprintf(why, cap, "line %u: dash length %g must be %g..%g metres", i, l->dash[k], MIN_DASH, MAX_DASH);
                return 0;
            }
        if (!(l->phase >= -MAX_PHASE && l->phase <= MAX_PHASE) || (l->dash_count == 0 && l->phase != 0)) {
            snprintf(why, cap, "line %u: phase %g must be 0 for a solid line, else -%g..%g metres", i, l->phase,
                     MAX_PHASE, MAX_PHASE);
            return 0;
        }
    }
    return 1;
}

/* Append a checked style; 0 on no memory or the count limit (message set). */
static rs_result append(rs_ctx *ctx, rs_styles *S, const rs_style *s, const char *who, unsigned long long line)
{
    char q[64];
    if (rs_styles_find(S, s->name)) {
        if (line)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: style %s is already defined", line,
                            rs__quote(q, sizeof q, s->name, strlen(s->name)));
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "%s: style %s is already defined", who,
                        rs__quote(q, sizeof q, s->name, strlen(s->name)));
    }
    if (S->count >= MAX_STYLES) {
        if (line) return rs__fail(ctx, RS_ERR_LIMIT, "line %llu: more than %d styles", line, MAX_STYLES);
        return rs__fail(ctx, RS_ERR_LIMIT, "%s: more than %d styles", who, MAX_STYLES);
    }
    if (S->count == S->cap) {
        size_t nc = S->cap ? 2 * S->cap : 8;
        rs_style *v = rs__alloc_array(ctx, nc, sizeof *v);
        if (!v) goto nomem;
        if (S->count) memcpy(v, S->v, S->count * sizeof *v);
        rs__free(ctx, S->v);
        S->v = v;
        S->cap = nc;
    }
    if (2 * (S->count + 1) > S->index_cap && !index_rebuild(ctx, S, S->count)) goto nomem;
    S->v[S->count] = *s;
    /* the name is NUL-terminated within the array, whatever the caller's bytes past it */
    S->v[S->count].name[RS_STYLE_NAME_MAX] = '\0';
    index_insert(S, S->count);
    S->count++;
    rs__ok(ctx);
    return RS_OK;
nomem:
    if (line) return rs__fail(ctx, RS_ERR_NOMEM, "line %llu: out of memory", line);
    return rs__fail(ctx, RS_ERR_NOMEM, "%s: out of memory", who);
}

/* The arguments of rs_styles_add / _replace (`who`) checked. */
static rs_result style_args(rs_ctx *ctx, const rs_styles *styles, const rs_style *style, const char *who)
{
    char why[200];
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!styles || !style) return rs__fail(ctx, RS_ERR_INVALID_ARG, "%s: styles or style is NULL", who);
    if (!style_ok(style, why, sizeof why)) return rs__fail(ctx, RS_ERR_INVALID_ARG, "%s: %s", who, why);
    return RS_OK;
}

rs_result rs_styles_add(rs_ctx *ctx, rs_styles *styles, const rs_style *style)
{
    rs_result r = style_args(ctx, styles, style, "rs_styles_add");
    return r ? r : append(ctx, styles, style, "rs_styles_add", 0);
}

rs_result rs_styles_replace(rs_ctx *ctx, rs_styles *styles, const rs_style *style)
{
    rs_result r = style_args(ctx, styles, style, "rs_styles_replace");
    if (r) return r;
    rs_style *have = (rs_style *)rs_styles_find(styles, style->name);
    if (!have) return append(ctx, styles, style, "rs_styles_replace", 0);
    *have = *style; /* same name: same place, the index stays */
    have->name[RS_STYLE_NAME_MAX] = '\0';
    rs__ok(ctx);
    return RS_OK;
}

rs_result rs_styles_add_text(rs_ctx *ctx, rs_styles *styles, const char *text, size_t size)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    if (!styles) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_styles_add_text: styles is NULL");
    if (!text && size) return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_styles_add_text: text is NULL");
    rs_result rc = rs__text_parse(ctx, text, size, RS_PROFILE_RMS, NULL, styles);
    if (rc == RS_OK) rs__ok(ctx);
    return rc;
}

rs_result rs_styles_parse(rs_ctx *ctx, const char *text, size_t size, rs_styles **out)
{
    if (!out) return ctx ? rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_styles_parse: out is NULL") : RS_ERR_INVALID_ARG;
    *out = NULL;
    if (!ctx) return RS_ERR_INVALID_ARG;
    rs_styles *S;
    rs_result rc = rs_styles_create(ctx, &S);
    if (rc != RS_OK) return rc;
    if ((rc = rs_styles_add_text(ctx, S, text, size)) != RS_OK) {
        rs_styles_free(ctx, S);
        return rc;
    }
    *out = S;
    return RS_OK;
}

/* ------------------------------------------------------------------------
 * Style blocks
 * ---------------------------------------------------------------------- */

static int hexval(char c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    return c - 'A' + 10;
}

static const char *block_name(char *q, size_t cap, const rs__style_block *b)
{
    return rs__quote(q, cap, b->st.name, strlen(b->st.name));
}

/* Read a colour argument of `what`. */
static rs_result colour(rs_ctx *ctx, unsigned long long line, rs__lex *L, const char *what, rs_colour *out)
{
    char q[64];
    rs__tok t;
    int k = rs__lex_next(L, RS__LEX_COLOUR, &t);
    if (k == 0) {
        /* "#fff" or "#12345g" started a comment: name it as the bad colour */
        if (L->comment && L->comment + 1 < L->s + L->n && L->comment[1] != ' ' && L->comment[1] != '\t' &&
            L->comment[1] != '#') {
            size_t n = 1;
            while (L->comment + n < L->s + L->n && L->comment[n] != ' ' && L->comment[n] != '\t') n++;
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: %s colour %s must be #RRGGBB or #RRGGBBAA", line, what,
                            rs__quote(q, sizeof q, L->comment, n));
        }
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: %s needs a colour #RRGGBB or #RRGGBBAA", line, what);
    }
    if (t.s[0] != '#')
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: %s colour %s must be #RRGGBB or #RRGGBBAA", line, what,
                        rs__quote(q, sizeof q, t.s, t.n));
    uint8_t v[4] = { 0, 0, 0, 255 };
    for (size_t i = 0; i + 1 < t.n; i += 2) v[i / 2] = (uint8_t)(hexval(t.s[1 + i]) * 16 + hexval(t.s[2 + i]));
    out->r = v[0];
    out->g = v[1];
    out->b = v[2];
    out->a = v[3];
    return RS_OK;
}

/* Read a number argument in [lo, hi]. */
static rs_result number(rs_ctx *ctx, unsigned long long line, rs__lex *L, const char *what, const char *usage,
                        double lo, double hi, double *out)
{
    char q[64];
    rs__tok t;
    if (rs__lex_next(L, RS__LEX_PLAIN, &t) == 0)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: %s is missing: %s", line, what, usage);
    rs_result rc = rs__number(ctx, line, &t, what, out);
    if (rc != RS_OK) return rc;
    if (!(*out >= lo && *out <= hi))
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: %s %s must be %g..%g (metres)", line, what,
                        rs__quote(q, sizeof q, t.s, t.n), lo, hi);
    return RS_OK;
}

static rs_result no_more(rs_ctx *ctx, unsigned long long line, rs__lex *L, const char *after)
{
    char q[64];
    rs__tok t;
    if (rs__lex_next(L, RS__LEX_PLAIN, &t) == 0) return RS_OK;
    return rs__fail(ctx, RS_ERR_PARSE, "line %llu: extra token %s after %s", line, rs__quote(q, sizeof q, t.s, t.n),
                    after);
}

rs_result rs__style_begin(rs_ctx *ctx, rs__style_block *b, unsigned long long line, rs__lex *L)
{
    char q[64];
    rs__tok t;
    memset(b, 0, sizeof *b);
    b->line = line;
    int k = rs__lex_next(L, RS__LEX_NAME, &t);
    if (k < 0) return rs__lex_fail(ctx, line, L);
    if (k == 0) return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'style' needs a name: style NAME", line);
    if (t.n > RS_STYLE_NAME_MAX + 2 || (!t.quoted && t.n > RS_STYLE_NAME_MAX))
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: style name %s is longer than %d bytes", line,
                        rs__quote(q, sizeof q, t.s, t.n), RS_STYLE_NAME_MAX);
    char name[RS_STYLE_NAME_MAX + 3];
    size_t n = rs__tok_text(&t, name);
    if (n == 0 || n > RS_STYLE_NAME_MAX)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: style name %s must be 1..%d bytes", line,
                        rs__quote(q, sizeof q, t.s, t.n), RS_STYLE_NAME_MAX);
    for (size_t i = 0; i < n; i++)
        if (name[i] == '\t')
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: style name %s has a tab", line,
                            rs__quote(q, sizeof q, t.s, t.n));
    memcpy(b->st.name, name, n);
    b->st.name[n] = '\0';
    return no_more(ctx, line, L, "the style name");
}

#define LINE_USAGE "line T W #RRGGBB [dash ON OFF ...] [phase P]"

static rs_result style_lineword(rs_ctx *ctx, rs__style_block *b, unsigned long long line, rs__lex *L)
{
    char q[64];
    rs_result rc;
    if (b->st.line_count >= RS_STYLE_MAX_LINES)
        return rs__fail(ctx, RS_ERR_LIMIT, "line %llu: style %s has more than %d lines", line,
                        block_name(q, sizeof q, b), RS_STYLE_MAX_LINES);
    rs_style_line ln;
    memset(&ln, 0, sizeof ln);
    if ((rc = number(ctx, line, L, "line offset", LINE_USAGE, -MAX_OFFSET, MAX_OFFSET, &ln.offset)) != RS_OK ||
        (rc = number(ctx, line, L, "line width", LINE_USAGE, MIN_WIDTH, MAX_WIDTH, &ln.width)) != RS_OK ||
        (rc = colour(ctx, line, L, "line", &ln.colour)) != RS_OK)
        return rc;
    int have_dash = 0, have_phase = 0;
    rs__tok t;
    int k = rs__lex_next(L, RS__LEX_PLAIN, &t);
    while (k == 1) {
        if (rs__tok_is(&t, "dash") && !have_dash) {
            have_dash = 1;
            while ((k = rs__lex_next(L, RS__LEX_PLAIN, &t)) == 1 && !rs__tok_is(&t, "phase") &&
                   !rs__tok_is(&t, "dash")) {
                if (ln.dash_count >= RS_STYLE_MAX_DASH)
                    return rs__fail(ctx, RS_ERR_LIMIT, "line %llu: dash pattern has more than %d lengths", line,
                                    RS_STYLE_MAX_DASH);
                double d;
                if ((rc = rs__number(ctx, line, &t, "dash length", &d)) != RS_OK) return rc;
                if (!(d >= MIN_DASH && d <= MAX_DASH))
                    return rs__fail(ctx, RS_ERR_PARSE, "line %llu: dash length %s must be %g..%g (metres)", line,
                                    rs__quote(q, sizeof q, t.s, t.n), MIN_DASH, MAX_DASH);
                ln.dash[ln.dash_count++] = d;
            }
            if (ln.dash_count == 0)
                return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'dash' needs lengths: dash ON OFF ...", line);
            if (ln.dash_count & 1)
                return rs__fail(ctx, RS_ERR_PARSE,
                                "line %llu: dash pattern has %u lengths; it needs ON OFF pairs (an even count)", line,
                                ln.dash_count);
            continue; /* t is 'phase' or the line ended */
        }
        if (rs__tok_is(&t, "phase") && !have_phase) {
            have_phase = 1;
            if ((rc = number(ctx, line, L, "dash phase", LINE_USAGE, -MAX_PHASE, MAX_PHASE, &ln.phase)) != RS_OK)
                return rc;
            k = rs__lex_next(L, RS__LEX_PLAIN, &t);
            continue;
        }
        if (rs__tok_is(&t, "dash") || rs__tok_is(&t, "phase"))
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: %s given twice", line, rs__quote(q, sizeof q, t.s, t.n));
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: unexpected %s after the line colour (expected 'dash' or 'phase')",
                        line, rs__quote(q, sizeof q, t.s, t.n));
    }
    if (have_phase && !have_dash)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'phase' needs a 'dash' pattern", line);
    b->st.line[b->st.line_count++] = ln;
    return RS_OK;
}

#define SURFACE_USAGE "surface IMG [length L]"

/* `surface IMG [length L]`: the image's name (a path, quoted when it has
 * blanks) is kept as written; the caller decodes the image. */
static rs_result style_surface(rs_ctx *ctx, rs__style_block *b, unsigned long long line, rs__lex *L)
{
    char q[64];
    rs__tok t;
    rs_result rc;
    if (b->st.surface_image[0])
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: style %s: 'surface' given twice", line,
                        block_name(q, sizeof q, b));
    int k = rs__lex_next(L, RS__LEX_NAME, &t);
    if (k < 0) return rs__lex_fail(ctx, line, L);
    if (k == 0) return rs__fail(ctx, RS_ERR_PARSE, "line %llu: 'surface' needs an image: " SURFACE_USAGE, line);
    if (t.n > RS_STYLE_IMAGE_MAX + 2 || (!t.quoted && t.n > RS_STYLE_IMAGE_MAX))
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: surface image %s is longer than %d bytes", line,
                        rs__quote(q, sizeof q, t.s, t.n), RS_STYLE_IMAGE_MAX);
    char name[RS_STYLE_IMAGE_MAX + 3];
    size_t n = rs__tok_text(&t, name);
    if (n == 0 || n > RS_STYLE_IMAGE_MAX)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: surface image %s must be 1..%d bytes", line,
                        rs__quote(q, sizeof q, t.s, t.n), RS_STYLE_IMAGE_MAX);
    for (size_t i = 0; i < n; i++)
        if ((unsigned char)name[i] < 0x20 || name[i] == 0x7F)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: surface image %s has a control character", line,
                            rs__quote(q, sizeof q, t.s, t.n));
    memcpy(b->st.surface_image, name, n);
    b->st.surface_image[n] = '\0';
    b->st.surface_line = line;
    k = rs__lex_next(L, RS__LEX_PLAIN, &t);
    if (k == 1 && rs__tok_is(&t, "length")) {
        if ((rc = number(ctx, line, L, "surface length", SURFACE_USAGE, MIN_SURF_LEN, MAX_SURF_LEN,
                         &b->st.surface_length)) != RS_OK)
            return rc;
        return no_more(ctx, line, L, "the surface length");
    }
    if (k == 1)
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: unexpected %s after the surface image (expected 'length L')",
                        line, rs__quote(q, sizeof q, t.s, t.n));
    return RS_OK;
}

rs_result rs__style_line(rs_ctx *ctx, rs__style_block *b, unsigned long long line, const rs__tok *first,
                         rs__lex *L)
{
    char q[64], q2[64];
    rs_result rc;
    if (rs__tok_is(first, "fill") || rs__tok_is(first, "gradient")) {
        int fill = first->s[0] == 'f';
        if (b->st.surface != RS_SURFACE_DEFAULT)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: style %s: the surface is set twice ('fill' or 'gradient')",
                            line, block_name(q, sizeof q, b));
        if (fill) {
            if ((rc = colour(ctx, line, L, "fill", &b->st.fill)) != RS_OK) return rc;
            b->st.surface = RS_SURFACE_FILL;
        } else {
            if ((rc = colour(ctx, line, L, "gradient centre", &b->st.gradient_centre)) != RS_OK ||
                (rc = colour(ctx, line, L, "gradient edge", &b->st.gradient_edge)) != RS_OK)
                return rc;
            b->st.surface = RS_SURFACE_GRADIENT;
        }
        return no_more(ctx, line, L, "the colour");
    }
    if (rs__tok_is(first, "casing")) {
        if (b->have_casing)
            return rs__fail(ctx, RS_ERR_PARSE, "line %llu: style %s: 'casing' given twice", line,
                            block_name(q, sizeof q, b));
        if ((rc = number(ctx, line, L, "casing width", "casing W #RRGGBB", MIN_WIDTH, MAX_WIDTH,
                         &b->st.casing_width)) != RS_OK ||
            (rc = colour(ctx, line, L, "casing", &b->st.casing)) != RS_OK)
            return rc;
        b->have_casing = 1;
        return no_more(ctx, line, L, "the colour");
    }
    if (rs__tok_is(first, "line")) return style_lineword(ctx, b, line, L);
    if (rs__tok_is(first, "surface")) return style_surface(ctx, b, line, L);
    return rs__fail(ctx, RS_ERR_PARSE,
                    "line %llu: unknown keyword %s in style %s (expected fill, gradient, surface, casing, line or end)",
                    line,
                    rs__quote(q, sizeof q, first->s, first->n), block_name(q2, sizeof q2, b));
}

rs_result rs__style_end(rs_ctx *ctx, rs_styles *styles, rs__style_block *b, unsigned long long line, rs__lex *L)
{
    char why[200];
    rs_result rc = no_more(ctx, line, L, "'end'");
    if (rc != RS_OK) return rc;
    if (!style_ok(&b->st, why, sizeof why)) /* not expected: the parser checked each value */
        return rs__fail(ctx, RS_ERR_PARSE, "line %llu: %s", line, why);
    return append(ctx, styles, &b->st, NULL, line);
}

/* ------------------------------------------------------------------------
 * Built-in defaults (tables and sources: docs/road-format.md)
 * ---------------------------------------------------------------------- */

#define FT 0.3048
#define IN 0.0254

/* Cross-section of one class: default lane count, lane width, paved strip
 * beyond the outer lanes (two-way: each side; one-way: left and right of
 * the travel direction). */
typedef struct section {
    uint8_t lanes;
    double lane, strip_left, strip_right;
} section;

static const section sections[2][RS_CLASS_COUNT] = {
    { /* RMS profile: RAS-Q 1996 / RAA 2008 / RAL 2012, ERA 2010, EFA 2002 */
      { 0, 3.25, 0, 0 },       /* none: RAS-Q group C lane */
      { 2, 3.75, 0.75, 2.50 }, /* motorway carriageway: left strip, hard shoulder */
      { 2, 3.50, 0.50, 0.50 }, /* trunk */
      { 2, 3.50, 0.25, 0.25 }, /* primary: RQ 10.5, 7.50 m paved */
      { 2, 3.00, 0.25, 0.25 }, /* secondary: RQ 9.5, 6.50 m paved */
      { 2, 2.75, 0, 0 },       /* tertiary: RQ 7.5, 5.50 m paved */
      { 2, 2.75, 0, 0 },       /* residential: RAS-Q group E */
      { 1, 3.00, 0, 0 },       /* service */
      { 1, 3.00, 0, 0 },       /* track */
      { 1, 2.50, 0, 0 },       /* path */
      { 1, 2.50, 0, 0 },       /* footway */
      { 1, 2.00, 0, 0 } },     /* cycleway */
    { /* MUTCD profile: AASHTO Green Book lane and shoulder widths, feet */
      { 0, 12 * FT, 0, 0 },
      { 2, 12 * FT, 4 * FT, 10 * FT }, /* Interstate: 4 ft left, 10 ft right shoulder */
      { 2, 12 * FT, 8 * FT, 8 * FT },
      { 2, 12 * FT, 4 * FT, 4 * FT },
      { 2, 11 * FT, 2 * FT, 2 * FT },
      { 2, 11 * FT, 0, 0 },
      { 2, 10 * FT, 0, 0 },
      { 1, 12 * FT, 0, 0 },
      { 1, 10 * FT, 0, 0 },
      { 1, 10 * FT, 0, 0 },
      { 1, 5 * FT, 0, 0 },
      { 1, 10 * FT, 0, 0 } }
};

/* Marking rules of one class and area. */
typedef struct marking {
    double lane_w;   /* lane and centre line width, 0: no lines at all */
    double edge_w;   /* edge line width, 0: none */
    double dash_on, dash_off;
    int kerb;        /* casing = kerb */
} marking;

static int class_urban(rs_road_class c)
{
    return c >= RS_CLASS_TERTIARY;
}

static marking rms_marking(rs_road_class c, int urban)
{
    marking m = { 0.12, 0, 6.0, 12.0, 0 };
    if (c == RS_CLASS_MOTORWAY) {
        m.lane_w = 0.15; /* Autobahn: Schmalstrich 0.15, Breitstrich 0.30 */
        m.edge_w = 0.30;
        return m;
    }
    if (c > RS_CLASS_TERTIARY || c == RS_CLASS_NONE) {
        m.lane_w = 0; /* residential and smaller: unmarked */
        m.kerb = urban && c <= RS_CLASS_SERVICE && c != RS_CLASS_NONE;
        return m;
    }
    if (urban) {
        m.dash_on = 3.0; /* innerorts Leitlinie 3 m / 6 m */
        m.dash_off = 6.0;
        m.kerb = 1;
    } else if (c != RS_CLASS_TERTIARY) {
        m.edge_w = 0.25; /* Breitstrich */
    }
    return m;
}

static marking mutcd_marking(rs_road_class c, int urban)
{
    marking m = { 4 * IN, 4 * IN, 10 * FT, 30 * FT, 0 };
    if (c == RS_CLASS_MOTORWAY) {
        m.lane_w = m.edge_w = 6 * IN;
        return m;
    }
    if (c > RS_CLASS_TERTIARY || c == RS_CLASS_NONE) {
        m.lane_w = m.edge_w = 0;
        m.kerb = urban && c <= RS_CLASS_SERVICE && c != RS_CLASS_NONE;
        return m;
    }
    if (c == RS_CLASS_TERTIARY) m.edge_w = 0;
    m.kerb = urban;
    return m;
}

static const rs_colour rms_white = { 0xF4, 0xF4, 0xF0, 0xFF };
static const rs_colour us_white = { 0xF4, 0xF4, 0xF4, 0xFF };
static const rs_colour us_yellow = { 0xF2, 0xB7, 0x05, 0xFF };
static const rs_colour kerb_grey = { 0xB4, 0xB0, 0xA8, 0xFF };
#define KERB_W 0.15

static const rs_colour class_fill[RS_CLASS_COUNT] = {
    { 0, 0, 0, 0 }, { 0, 0, 0, 0 }, { 0, 0, 0, 0 }, { 0, 0, 0, 0 }, { 0, 0, 0, 0 }, { 0, 0, 0, 0 },
    { 0, 0, 0, 0 }, { 0, 0, 0, 0 },
    { 0x9C, 0x8A, 0x6C, 0xFF }, /* track: gravel */
    { 0xB8, 0xA8, 0x8A, 0xFF }, /* path: compacted earth */
    { 0xC0, 0xBA, 0xB0, 0xFF }, /* footway: paving */
    { 0xB0, 0x50, 0x40, 0xFF }  /* cycleway: red surfacing */
};

static int request_ok(const rs_style_request *req)
{
    return req && (unsigned)req->road_class < RS_CLASS_COUNT && req->lanes <= 16 &&
           (unsigned)req->oneway <= RS_ONEWAY_REVERSE && (unsigned)req->area <= RS_AREA_RURAL &&
           (unsigned)req->profile <= RS_PROFILE_MUTCD && req->width >= 0 && req->width <= 2 * MAX_OFFSET &&
           req->lanes_forward <= 16 && req->lanes_backward <= 16 && (unsigned)req->driving_side <= RS_DRIVING_LEFT;
}

void rs__section(rs_profile p, rs_road_class c, uint32_t *lanes, double *lane, double *strip_left,
                 double *strip_right)
{
    const section *s = &sections[p == RS_PROFILE_MUTCD][(unsigned)c < RS_CLASS_COUNT ? c : RS_CLASS_NONE];
    *lanes = s->lanes;
    *lane = s->lane;
    *strip_left = s->strip_left;
    *strip_right = s->strip_right;
}

static uint32_t lanes_of(const rs_style_request *req)
{
    const section *s = &sections[req->profile][req->road_class];
    if (req->lanes) return req->lanes;
    return s->lanes ? s->lanes : 1;
}

/* Nominal width and its parts. */
static double nominal(const rs_style_request *req, double *left, double *lane, double *right)
{
    const section *s = &sections[req->profile][req->road_class];
    uint32_t n = lanes_of(req);
    if (rs__lanes_oneway(req->road_class, req->oneway)) {
        *left = s->strip_left;
        *right = s->strip_right;
    } else {
        *left = *right = s->strip_right; /* two-way: the outer strip on both sides */
    }
    *lane = s->lane;
    return *left + n * *lane + *right;
}

/* The host's request in this header's layout (the ABI rule; no context:
 * no message), RS_ERR_INVALID_ARG when NULL or out of range. */
static rs_result request_in(const rs_style_request *req_in, rs_style_request *rq)
{
    if (!req_in) return RS_ERR_INVALID_ARG;
    rs_result r = RS__OPTS_IN(NULL, req_in, rq, rs_style_request);
    if (r) return r;
    return request_ok(rq) ? RS_OK : RS_ERR_INVALID_ARG;
}

rs_result rs_style_default_width(const rs_style_request *req_in, double *width)
{
    rs_style_request rq;
    rs_result r = request_in(req_in, &rq);
    if (r || !width) return r ? r : RS_ERR_INVALID_ARG;
    double l, ln, rt;
    *width = nominal(&rq, &l, &ln, &rt);
    return RS_OK;
}

static void add_line(rs_style *st, double t, double w, rs_colour c, double on, double off)
{
    if (st->line_count >= RS_STYLE_MAX_LINES) return; /* not reached: 32 lanes need 33 + 2 */
    rs_style_line *l = &st->line[st->line_count++];
    memset(l, 0, sizeof *l);
    l->offset = t;
    l->width = w;
    l->colour = c;
    if (on > 0) {
        l->dash_count = 2;
        l->dash[0] = on;
        l->dash[1] = off;
    }
}

/* The default style of req's class, its lines on the lanes of `in`. */
static void default_style(const rs_style_request *req, const rs__lanes_in *in, rs_style *out)
{
    memset(out, 0, sizeof *out);
    rs_road_class c = req->road_class;
    memcpy(out->name, rs_road_class_name(c), strlen(rs_road_class_name(c)) + 1);
    if (c == RS_CLASS_NONE) return;
    if (class_fill[c].a) {
        out->surface = RS_SURFACE_FILL;
        out->fill = class_fill[c];
    }
    int urban = req->area == RS_AREA_AUTO ? class_urban(c) : req->area == RS_AREA_URBAN;
    int us = req->profile == RS_PROFILE_MUTCD;
    marking m = us ? mutcd_marking(c, urban) : rms_marking(c, urban);
    if (m.kerb) {
        out->casing_width = KERB_W;
        out->casing = kerb_grey;
    }
    if (m.lane_w == 0) return;

    /* Lines on the lane boundaries (lib/scene/lanes.c), listed from the left of
     * the main direction of travel, t = + left of the points. */
    rs_road_lanes L;
    double strip[2];
    rs__lanes_layout(in, &L, strip);
    uint32_t n = L.count;
    int ow = rs__lanes_oneway(c, req->oneway), left = L.side == RS_DRIVING_LEFT;
    double dir = ow < 0 ? -1.0 : 1.0, hw = L.width / 2;
    rs_colour white = us ? us_white : rms_white;
    for (uint32_t b = 1; b < n; b++) {
        uint32_t k = dir > 0 ? b : n - b; /* the boundary between lanes k - 1 and k */
        double t = L.lane[k].t_left;
        if (L.lane[k - 1].direction * L.lane[k].direction < 0) { /* between the directions */
            if (us && n >= 4) { /* two-direction no-passing: double solid yellow */
                double d = m.lane_w / 2 + 2 * IN;
                add_line(out, t + dir * d, m.lane_w, us_yellow, 0, 0);
                add_line(out, t - dir * d, m.lane_w, us_yellow, 0, 0);
            } else if (us) {
                add_line(out, t, m.lane_w, us_yellow, m.dash_on, m.dash_off);
            } else if (n >= 4) {
                add_line(out, t, m.lane_w, white, 0, 0); /* Fahrstreifenbegrenzung */
            } else {
                add_line(out, t, m.lane_w, white, m.dash_on, m.dash_off);
            }
        } else {
            add_line(out, t, m.lane_w, white, m.dash_on, m.dash_off);
        }
    }
    if (m.edge_w > 0) {
        /* inside the paved strip when it is wide enough, else flush with the road edge */
        double e = m.edge_w;
        double tl = strip[0] >= e ? L.lane[0].t_left + e / 2 : hw - e / 2;
        double tr = strip[1] >= e ? L.lane[n - 1].t_right - e / 2 : -hw + e / 2;
        /* the left edge of travel first; a one-way road's edge on the side
         * of opposing traffic (left of travel, right in left-hand traffic)
         * is yellow in the US */
        double first = dir > 0 ? tl : tr, second = dir > 0 ? tr : tl;
        add_line(out, first, e, us && ow && !left ? us_yellow : white, 0, 0);
        add_line(out, second, e, us && ow && left ? us_yellow : white, 0, 0);
    }
    /* many lanes of one direction in a narrow road put the centre line's
     * double yellow near an edge: keep every line inside the road */
    for (uint32_t k = 0; k < out->line_count; k++) {
        rs_style_line *l = &out->line[k];
        double lim = hw - l->width / 2;
        if (lim < 0) lim = 0;
        if (l->offset > lim) l->offset = lim;
        if (l->offset < -lim) l->offset = -lim;
    }
}

static void request_input(const rs_style_request *req, rs__lanes_in *in)
{
    memset(in, 0, sizeof *in);
    in->road_class = req->road_class;
    in->profile = req->profile;
    in->oneway = req->oneway;
    in->side = req->driving_side;
    in->lanes = req->lanes;
    in->forward = req->lanes_forward;
    in->backward = req->lanes_backward;
    in->width = req->width;
}

rs_result rs_style_default(const rs_style_request *req_in, rs_style *out)
{
    rs_style_request rq;
    rs_result r = request_in(req_in, &rq);
    if (r || !out) return r ? r : RS_ERR_INVALID_ARG;
    rs__lanes_in in;
    request_input(&rq, &in);
    default_style(&rq, &in, out);
    return RS_OK;
}

static rs_result road_style(rs_ctx *ctx, const rs_roads *roads, size_t i, const rs_styles *styles,
                            rs_profile profile, rs_driving_side side, rs_style *out)
{
    char q[64], q2[64];
    if (!ctx) return RS_ERR_INVALID_ARG;
    rs_road_info info;
    const char *name;
    rs_style_request req;
    memset(&req, 0, sizeof req);
    if (!out || rs_roads_get(roads, i, &name, &req.width, NULL, NULL) != RS_OK ||
        rs_roads_get_info(roads, i, &info) != RS_OK)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_road_style: no road %zu, or out is NULL", i);
    if ((unsigned)profile > RS_PROFILE_MUTCD)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_road_style: unknown profile %d", (int)profile);
    req.road_class = info.road_class;
    req.lanes = info.lanes;
    req.oneway = rs__road_oneway(roads, i, &info);
    req.area = info.area;
    req.profile = profile;
    /* line offsets are bounded (MAX_OFFSET): a road wider than 2 km gets
     * the lines of a 2 km road, about its centre */
    if (req.width > 2 * MAX_OFFSET) req.width = 2 * MAX_OFFSET;
    const rs_style *s;
    if (info.style) {
        if ((s = rs_styles_find(styles, info.style)) != NULL) {
            *out = *s;
            rs__ok(ctx);
            return RS_OK;
        }
        rs_road_class c = rs_road_class_from_name(info.style, NULL);
        if (c == RS_CLASS_NONE)
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "road %zu (%s): style %s is not defined", i,
                            rs__quote(q, sizeof q, name, strlen(name)),
                            rs__quote(q2, sizeof q2, info.style, strlen(info.style)));
        req.road_class = c;
    } else if (info.road_class != RS_CLASS_NONE &&
               (s = rs_styles_find(styles, rs_road_class_name(info.road_class))) != NULL) {
        *out = *s;
        rs__ok(ctx);
        return RS_OK;
    }
    /* the lanes of the road itself (lanes per direction, width:lanes,
     * turn:lanes, driving_side: lib/scene/lanes.c) */
    rs__lanes_in in;
    rs__lanes_input(roads, i, profile, side, &in);
    in.road_class = req.road_class;
    in.width = req.width;
    req.driving_side = in.side;
    default_style(&req, &in, out);
    rs__ok(ctx);
    return RS_OK;
}

rs_result rs_road_style(rs_ctx *ctx, const rs_roads *roads, size_t i, const rs_styles *styles, rs_profile profile,
                        rs_style *out)
{
    return road_style(ctx, roads, i, styles, profile, RS_DRIVING_RIGHT, out);
}

rs_result rs_road_style_ex(rs_ctx *ctx, const rs_roads *roads, size_t i, const rs_style_options *opts_in,
                           rs_style *out)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    rs_style_options so;
    rs_result r = RS__OPTS_IN(ctx, opts_in, &so, rs_style_options);
    if (r) return r;
    const rs_style_options *opts = &so;
    if ((unsigned)opts->driving_side > RS_DRIVING_LEFT) {
        if (!ctx) return RS_ERR_INVALID_ARG;
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "rs_road_style_ex: unknown driving side %d",
                        (int)opts->driving_side);
    }
    return road_style(ctx, roads, i, opts->styles, opts->profile, opts->driving_side, out);
}
