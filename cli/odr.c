/* The OpenDRIVE reader (module roadsplat-odr.so, issue 32,
 * docs/opendrive.md): expat's streaming parser fills the library's plain
 * document (lib/input/odr_lanes.h), which the library turns into road text.
 *
 * Expat rather than libxml2: a small, streaming (SAX) parser with line
 * numbers for every element, no DOM of a 100 MB network in memory, and
 * protection against entity expansion attacks (expat >= 2.4, Debian 12 has
 * 2.5) and no external entity loading by default.
 *
 * Self-contained (no cli_* helpers): the fuzz target links this file with
 * the library and expat alone. */
#include "odr.h"
#include "../lib/input/odr_lanes.h"

#include <expat.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_ITEMS 1000000 /* of each kind of element: roads, lanes, marks, ... */
#define MAX_ID 256
#define MAX_GEOREF 4096
#define MAX_DEPTH 64

typedef enum el {
    E_OTHER = 0, E_ROOT, E_HEADER, E_GEOREF, E_OFFSET, E_ROAD, E_PLANVIEW, E_GEOMETRY, E_LANES, E_LANEOFFSET,
    E_SECTION, E_SIDE, E_LANE, E_WIDTH, E_ROADMARK, E_MARKTYPE, E_MARKLINE, E_OBJECTS, E_OBJECT, E_OUTLINE,
    E_CORNER, E_SIGNALS, E_SIGNAL, E_JUNCTION
} el;

typedef struct rd {
    XML_Parser xp;
    const char *shown;
    char *err;
    size_t nerr;
    int failed;
    el stack[MAX_DEPTH];
    int depth, skip; /* skip: depth beyond MAX_DEPTH (ignored elements) */
    rs__odr_doc doc;
    size_t capr, capg, capp, caps, capl, capm, capml, capo;
    char *georef;
    size_t ngeoref;
    int in_georef;
    /* the current object's outline box */
    double ob[4];
    int obn;
} rd;

static void fail(rd *R, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static void fail(rd *R, const char *fmt, ...)
{
    if (R->failed) return;
    R->failed = 1;
    char msg[600];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    snprintf(R->err, R->nerr, "%s line %lu: %s", R->shown, (unsigned long)XML_GetCurrentLineNumber(R->xp), msg);
    XML_StopParser(R->xp, XML_FALSE);
}

static unsigned long line_now(rd *R)
{
    return (unsigned long)XML_GetCurrentLineNumber(R->xp);
}

/* Room for one more item in *arr (count n, capacity *cap); NULL after a message. */
static void *grow(rd *R, void **arr, size_t n, size_t *cap, size_t size, const char *what)
{
    if (n >= MAX_ITEMS) {
        fail(R, "more than %d <%s> elements", MAX_ITEMS, what);
        return NULL;
    }
    if (n == *cap) {
        size_t c = *cap ? 2 * *cap : 16;
        void *p = realloc(*arr, c * size);
        if (!p) {
            fail(R, "out of memory reading <%s>", what);
            return NULL;
        }
        *arr = p;
        *cap = c;
    }
    return (char *)*arr + n * size;
}

static const char *attr(const char **a, const char *name)
{
    for (; a[0]; a += 2)
        if (!strcmp(a[0], name)) return a[1];
    return NULL;
}

/* A required (or, with opt, optional: *v = def) finite number. */
static int num(rd *R, const char **a, const char *el_name, const char *name, int opt, double def, double *v)
{
    const char *s = attr(a, name);
    if (!s) {
        if (opt) {
            *v = def;
            return 0;
        }
        fail(R, "<%s> needs the attribute %s", el_name, name);
        return 1;
    }
    const char *b = s, *e = s + strlen(s), *stop = NULL;
    while (b < e && (*b == ' ' || *b == '\t' || *b == '\n' || *b == '\r')) b++;
    while (e > b && (e[-1] == ' ' || e[-1] == '\t' || e[-1] == '\n' || e[-1] == '\r')) e--;
    if (b == e || !rs__parse_double(b, e, v, &stop) || stop != e || !isfinite(*v)) {
        fail(R, "<%s> %s='%.60s' is not a number", el_name, name, s);
        return 1;
    }
    return 0;
}

static el el_of(const char *n, el parent)
{
    switch (parent) {
    case E_OTHER: return strcmp(n, "OpenDRIVE") ? E_OTHER : E_ROOT;
    case E_ROOT:
        if (!strcmp(n, "header")) return E_HEADER;
        if (!strcmp(n, "road")) return E_ROAD;
        if (!strcmp(n, "junction")) return E_JUNCTION;
        return E_OTHER;
    case E_HEADER:
        if (!strcmp(n, "geoReference")) return E_GEOREF;
        if (!strcmp(n, "offset")) return E_OFFSET;
        return E_OTHER;
    case E_ROAD:
        if (!strcmp(n, "planView")) return E_PLANVIEW;
        if (!strcmp(n, "lanes")) return E_LANES;
        if (!strcmp(n, "objects")) return E_OBJECTS;
        if (!strcmp(n, "signals")) return E_SIGNALS;
        return E_OTHER;
    case E_PLANVIEW: return strcmp(n, "geometry") ? E_OTHER : E_GEOMETRY;
    case E_LANES:
        if (!strcmp(n, "laneOffset")) return E_LANEOFFSET;
        if (!strcmp(n, "laneSection")) return E_SECTION;
        return E_OTHER;
    case E_SECTION:
        return !strcmp(n, "left") || !strcmp(n, "center") || !strcmp(n, "right") ? E_SIDE : E_OTHER;
    case E_SIDE: return strcmp(n, "lane") ? E_OTHER : E_LANE;
    case E_LANE:
        if (!strcmp(n, "width")) return E_WIDTH;
        if (!strcmp(n, "roadMark")) return E_ROADMARK;
        return E_OTHER;
    case E_ROADMARK: return strcmp(n, "type") ? E_OTHER : E_MARKTYPE;
    case E_MARKTYPE: return strcmp(n, "line") ? E_OTHER : E_MARKLINE;
    case E_OBJECTS: return strcmp(n, "object") ? E_OTHER : E_OBJECT;
    case E_OBJECT: return strcmp(n, "outline") ? E_OTHER : E_OUTLINE;
    case E_OUTLINE: return !strcmp(n, "cornerRoad") || !strcmp(n, "cornerLocal") ? E_CORNER : E_OTHER;
    case E_SIGNALS: return strcmp(n, "signal") ? E_OTHER : E_SIGNAL;
    default: return E_OTHER;
    }
}

/* ---- element handlers ------------------------------------------------------------ */

static uint32_t colour_of(rd *R, const char *c)
{
    static const struct { const char *name; uint32_t rgba; } tab[] = {
        { "standard", 0xF4F4F0FFu }, { "white", 0xF4F4F0FFu }, { "yellow", 0xF2B705FFu }, { "red", 0xC8281EFFu },
        { "blue", 0x1E50C8FFu }, { "green", 0x2E8B3AFFu }, { "orange", 0xF08020FFu }, { "black", 0x141414FFu },
        { "violet", 0x8040A0FFu },
    };
    if (!c) return 0xF4F4F0FFu;
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (!strcmp(c, tab[i].name)) return tab[i].rgba;
    fail(R, "roadMark color '%.40s' is not an OpenDRIVE colour (standard, white, yellow, red, blue, green, orange, "
         "black, violet)", c);
    return 0;
}

static rs__odr_road *cur_road(rd *R)
{
    return &R->doc.roads[R->doc.nroads - 1];
}

static void start_road(rd *R, const char **a)
{
    rs__odr_road *r = grow(R, (void **)&R->doc.roads, R->doc.nroads, &R->capr, sizeof *r, "road");
    if (!r) return;
    memset(r, 0, sizeof *r);
    const char *id = attr(a, "id"), *j = attr(a, "junction");
    if (!id) {
        fail(R, "<road> needs the attribute id");
        return;
    }
    if (strlen(id) > MAX_ID) {
        fail(R, "<road> id is longer than %d bytes", MAX_ID);
        return;
    }
    char *copy = malloc(strlen(id) + 1);
    if (!copy) {
        fail(R, "out of memory");
        return;
    }
    strcpy(copy, id);
    r->id = copy;
    R->doc.nroads++;
    if (num(R, a, "road", "length", 0, 0, &r->length)) return;
    r->in_junction = j && strcmp(j, "-1") != 0;
    r->geom0 = R->doc.ngeoms;
    r->off0 = R->doc.npolys;
    r->sec0 = R->doc.nsections;
    r->obj0 = R->doc.nobjects;
    r->xml_line = line_now(R);
}

static void start_geometry(rd *R, const char **a)
{
    rs__odr_geom *g = grow(R, (void **)&R->doc.geoms, R->doc.ngeoms, &R->capg, sizeof *g, "geometry");
    if (!g) return;
    memset(g, 0, sizeof *g);
    g->kind = (rs__odr_kind)-1;
    if (num(R, a, "geometry", "s", 0, 0, &g->s) || num(R, a, "geometry", "x", 0, 0, &g->x) ||
        num(R, a, "geometry", "y", 0, 0, &g->y) || num(R, a, "geometry", "hdg", 0, 0, &g->hdg) ||
        num(R, a, "geometry", "length", 0, 0, &g->length))
        return;
    R->doc.ngeoms++;
    cur_road(R)->ngeom++;
}

static void geometry_kind(rd *R, const char *n, const char **a)
{
    rs__odr_geom *g = &R->doc.geoms[R->doc.ngeoms - 1];
    if ((int)g->kind != -1) {
        fail(R, "<geometry> has more than one of line, arc, spiral, poly3, paramPoly3");
        return;
    }
    if (!strcmp(n, "line")) g->kind = RS__ODR_LINE;
    else if (!strcmp(n, "arc")) {
        g->kind = RS__ODR_ARC;
        num(R, a, "arc", "curvature", 0, 0, &g->curv);
    } else if (!strcmp(n, "spiral")) {
        g->kind = RS__ODR_SPIRAL;
        if (!num(R, a, "spiral", "curvStart", 0, 0, &g->curv_start)) num(R, a, "spiral", "curvEnd", 0, 0, &g->curv_end);
    } else if (!strcmp(n, "poly3")) {
        g->kind = RS__ODR_POLY3;
        if (!num(R, a, n, "a", 0, 0, &g->a) && !num(R, a, n, "b", 0, 0, &g->b) && !num(R, a, n, "c", 0, 0, &g->c))
            num(R, a, n, "d", 0, 0, &g->d);
    } else if (!strcmp(n, "paramPoly3")) {
        g->kind = RS__ODR_PARAMPOLY3;
        double *v[8] = { &g->au, &g->bu, &g->cu, &g->du, &g->av, &g->bv, &g->cv, &g->dv };
        static const char *const names[8] = { "aU", "bU", "cU", "dU", "aV", "bV", "cV", "dV" };
        for (int k = 0; k < 8; k++)
            if (num(R, a, n, names[k], 0, 0, v[k])) return;
        const char *pr = attr(a, "pRange");
        if (!pr || !strcmp(pr, "normalized")) g->normalized = 1;
        else if (!strcmp(pr, "arcLength")) g->normalized = 0;
        else fail(R, "<paramPoly3> pRange='%.40s' must be arcLength or normalized", pr);
    } else {
        fail(R, "<geometry> holds an unknown <%.40s> (expected line, arc, spiral, poly3 or paramPoly3)", n);
    }
}

static rs__odr_poly *new_poly(rd *R, const char *what)
{
    return grow(R, (void **)&R->doc.polys, R->doc.npolys, &R->capp, sizeof(rs__odr_poly), what);
}

static int poly_attrs(rd *R, const char **a, const char *what, const char *sname, double base, rs__odr_poly *p)
{
    double s;
    if (num(R, a, what, sname, 0, 0, &s) || num(R, a, what, "a", 0, 0, &p->a) || num(R, a, what, "b", 0, 0, &p->b) ||
        num(R, a, what, "c", 0, 0, &p->c) || num(R, a, what, "d", 0, 0, &p->d))
        return 1;
    p->s0 = base + s;
    return 0;
}

/* Appends a polynomial to the run *first, *count (a road's laneOffsets, a
 * lane's widths), which must stand together in doc.polys. */
static void add_poly(rd *R, const char **a, const char *what, const char *sname, double base, size_t *first,
                     size_t *count)
{
    if (*count && *first + *count != R->doc.npolys) {
        fail(R, "<%s> records must stand together (laneOffsets before the laneSections, a lane's widths in a row)",
             what);
        return;
    }
    rs__odr_poly *p = new_poly(R, what);
    if (!p || poly_attrs(R, a, what, sname, base, p)) return;
    if (!*count) *first = R->doc.npolys;
    R->doc.npolys++;
    (*count)++;
}

static void start_laneoffset(rd *R, const char **a)
{
    rs__odr_road *r = cur_road(R);
    add_poly(R, a, "laneOffset", "s", 0, &r->off0, &r->noff);
}

static void start_section(rd *R, const char **a)
{
    rs__odr_section *S = grow(R, (void **)&R->doc.sections, R->doc.nsections, &R->caps, sizeof *S, "laneSection");
    if (!S) return;
    memset(S, 0, sizeof *S);
    if (num(R, a, "laneSection", "s", 0, 0, &S->s)) return;
    S->lane0 = R->doc.nlanes;
    S->xml_line = line_now(R);
    R->doc.nsections++;
    cur_road(R)->nsec++;
}

static rs__odr_surface surface_of(const char *t)
{
    static const char *const none[] = { "none", "border", "curb", "median", "rail", "tram", "special1", "special2",
                                        "special3" };
    for (size_t i = 0; i < sizeof none / sizeof none[0]; i++)
        if (!strcmp(t, none[i])) return RS__ODR_SURF_NONE;
    if (!strcmp(t, "sidewalk") || !strcmp(t, "walking")) return RS__ODR_SURF_SIDEWALK;
    if (!strcmp(t, "biking")) return RS__ODR_SURF_BIKE;
    return RS__ODR_SURF_ROAD;
}

static void start_lane(rd *R, const char **a)
{
    rs__odr_lane *l = grow(R, (void **)&R->doc.lanes, R->doc.nlanes, &R->capl, sizeof *l, "lane");
    if (!l) return;
    memset(l, 0, sizeof *l);
    double id;
    if (num(R, a, "lane", "id", 0, 0, &id)) return;
    if (id != floor(id) || fabs(id) > 1000) {
        fail(R, "<lane> id='%.40s' must be a whole number in -1000..1000", attr(a, "id"));
        return;
    }
    const char *t = attr(a, "type");
    if (!t) {
        fail(R, "<lane> needs the attribute type");
        return;
    }
    rs__odr_section *S = &R->doc.sections[R->doc.nsections - 1];
    for (size_t k = S->lane0; k < R->doc.nlanes; k++)
        if (R->doc.lanes[k].id == (int)id) {
            fail(R, "lane %d given twice in this laneSection", (int)id);
            return;
        }
    l->id = (int)id;
    l->surface = l->id ? surface_of(t) : RS__ODR_SURF_NONE;
    l->width0 = R->doc.npolys;
    l->mark0 = R->doc.nmarks;
    l->xml_line = line_now(R);
    R->doc.nlanes++;
    S->nlane++;
}

static rs__odr_lane *cur_lane(rd *R)
{
    return &R->doc.lanes[R->doc.nlanes - 1];
}

static void start_width(rd *R, const char **a)
{
    rs__odr_lane *l = cur_lane(R);
    add_poly(R, a, "width", "sOffset", R->doc.sections[R->doc.nsections - 1].s, &l->width0, &l->nwidth);
}

static void start_roadmark(rd *R, const char **a)
{
    static const struct { const char *name; rs__odr_mark_type t; } types[] = {
        { "none", RS__ODR_MARK_NONE }, { "solid", RS__ODR_MARK_SOLID }, { "broken", RS__ODR_MARK_BROKEN },
        { "solid solid", RS__ODR_MARK_SOLID_SOLID }, { "solid broken", RS__ODR_MARK_SOLID_BROKEN },
        { "broken solid", RS__ODR_MARK_BROKEN_SOLID }, { "broken broken", RS__ODR_MARK_BROKEN_BROKEN },
        { "botts dots", RS__ODR_MARK_BOTTS_DOTS }, { "grass", RS__ODR_MARK_GRASS }, { "curb", RS__ODR_MARK_CURB },
        { "custom", RS__ODR_MARK_CUSTOM }, { "edge", RS__ODR_MARK_EDGE },
    };
    static const char *const changes[] = { "increase", "decrease", "both", "none" };
    rs__odr_lane *l = cur_lane(R);
    if (l->nmark && l->mark0 + l->nmark != R->doc.nmarks) {
        fail(R, "<roadMark> records of a lane must stand together");
        return;
    }
    rs__odr_mark *m = grow(R, (void **)&R->doc.marks, R->doc.nmarks, &R->capm, sizeof *m, "roadMark");
    if (!m) return;
    memset(m, 0, sizeof *m);
    double so;
    if (num(R, a, "roadMark", "sOffset", 0, 0, &so)) return;
    m->s = R->doc.sections[R->doc.nsections - 1].s + so;
    const char *t = attr(a, "type");
    if (!t) {
        fail(R, "<roadMark> needs the attribute type");
        return;
    }
    size_t k = 0;
    while (k < sizeof types / sizeof types[0] && strcmp(types[k].name, t)) k++;
    if (k == sizeof types / sizeof types[0]) {
        fail(R, "roadMark type '%.40s' is not an OpenDRIVE road-mark type (solid, broken, solid solid, ...)", t);
        return;
    }
    m->type = types[k].t;
    const char *w = attr(a, "weight");
    if (w && strcmp(w, "standard") && strcmp(w, "bold")) {
        fail(R, "roadMark weight '%.40s' must be standard or bold", w);
        return;
    }
    m->bold = w && !strcmp(w, "bold");
    m->rgba = colour_of(R, attr(a, "color"));
    if (R->failed || num(R, a, "roadMark", "width", 1, 0, &m->width)) return;
    if (!(m->width >= 0 && m->width <= 10)) {
        fail(R, "roadMark width %.17g must be 0..10 m", m->width);
        return;
    }
    const char *lc = attr(a, "laneChange");
    for (size_t i = 0; lc && i < 4; i++)
        if (!strcmp(lc, changes[i])) m->lane_change = changes[i];
    m->line0 = R->doc.nlines;
    m->xml_line = line_now(R);
    if (!l->nmark) l->mark0 = R->doc.nmarks;
    R->doc.nmarks++;
    l->nmark++;
}

static void start_markline(rd *R, const char **a)
{
    rs__odr_mark *m = &R->doc.marks[R->doc.nmarks - 1];
    rs__odr_mark_line *l = grow(R, (void **)&R->doc.lines, R->doc.nlines, &R->capml, sizeof *l, "line");
    if (!l) return;
    memset(l, 0, sizeof *l);
    if (num(R, a, "line", "length", 0, 0, &l->length) || num(R, a, "line", "space", 0, 0, &l->space) ||
        num(R, a, "line", "tOffset", 0, 0, &l->t_offset) || num(R, a, "line", "sOffset", 0, 0, &l->s_offset) ||
        num(R, a, "line", "width", 1, 0, &l->width))
        return;
    if (!(l->length >= 0 && l->length <= 1e6 && l->space >= 0 && l->space <= 1e6 && fabs(l->t_offset) <= 100 &&
          fabs(l->s_offset) <= 1e7 && l->width >= 0 && l->width <= 10)) {
        fail(R, "<line> length and space must be 0..1e6 m, |tOffset| <= 100 m, |sOffset| <= 1e7 m, width 0..10 m");
        return;
    }
    const char *c = attr(a, "color");
    l->rgba = c ? colour_of(R, c) : 0;
    if (R->failed) return;
    if (m->nline >= 16) {
        fail(R, "more than 16 <line>s in one roadMark");
        return;
    }
    R->doc.nlines++;
    m->nline++;
}

static void start_object(rd *R, const char **a, int signal)
{
    const char *type = attr(a, "type"), *sub = attr(a, "subtype"), *name = attr(a, "name");
    rs__odr_object_kind kind = 0;
    if (signal) {
        if (type && !strcmp(type, "294")) kind = RS__ODR_OBJ_STOP_LINE; /* StVO 294, Haltlinie */
    } else if (type && !strcmp(type, "crosswalk")) {
        kind = RS__ODR_OBJ_CROSSWALK;
    } else if (type && (!strcmp(type, "stopLine") ||
                        (!strcmp(type, "roadMark") && ((sub && strstr(sub, "top")) || (name && strstr(name, "top")))))) {
        kind = RS__ODR_OBJ_STOP_LINE; /* "stopLine", "StopLine" */
    }
    R->obn = -1;
    if (!kind) return;
    const char *el_name = signal ? "signal" : "object";
    rs__odr_object *o = grow(R, (void **)&R->doc.objects, R->doc.nobjects, &R->capo, sizeof *o, el_name);
    if (!o) return;
    memset(o, 0, sizeof *o);
    double s, t, len, wid, hdg;
    if (num(R, a, el_name, "s", 0, 0, &s) || num(R, a, el_name, "t", 0, 0, &t) ||
        num(R, a, el_name, "length", 1, 0, &len) || num(R, a, el_name, "width", 1, 0, &wid) ||
        num(R, a, el_name, "hdg", 1, 0, &hdg))
        return;
    o->kind = kind;
    o->xml_line = line_now(R);
    if (signal) {
        /* the stop line across the lanes the sign faces: '+' the right, '-' the left */
        const char *ori = attr(a, "orientation");
        o->s0 = o->s1 = s;
        o->t0 = o->t1 = 0;
        o->side = ori && !strcmp(ori, "-") ? 1 : -1;
    } else {
        /* the box of length (along u) x width (along v) turned by hdg */
        double c = fabs(cos(hdg)), sn = fabs(sin(hdg));
        double hs = 0.5 * (len * c + wid * sn), ht = 0.5 * (len * sn + wid * c);
        o->s0 = s - hs, o->s1 = s + hs, o->t0 = t - ht, o->t1 = t + ht;
    }
    R->ob[0] = s, R->ob[1] = t;
    R->obn = 0;
    R->doc.nobjects++;
    cur_road(R)->nobj++;
}

static void corner(rd *R, const char *n, const char **a)
{
    if (R->obn < 0) return;
    rs__odr_object *o = &R->doc.objects[R->doc.nobjects - 1];
    double s, t;
    if (!strcmp(n, "cornerRoad")) {
        if (num(R, a, n, "s", 0, 0, &s) || num(R, a, n, "t", 0, 0, &t)) return;
    } else {
        double u, v;
        if (num(R, a, n, "u", 0, 0, &u) || num(R, a, n, "v", 0, 0, &v)) return;
        s = R->ob[0] + u, t = R->ob[1] + v; /* local axes along the road (hdg ignored) */
    }
    if (R->obn == 0) o->s0 = o->s1 = s, o->t0 = o->t1 = t;
    o->s0 = fmin(o->s0, s), o->s1 = fmax(o->s1, s), o->t0 = fmin(o->t0, t), o->t1 = fmax(o->t1, t);
    R->obn++;
}

static void XMLCALL on_start(void *user, const XML_Char *n, const XML_Char **a)
{
    rd *R = user;
    if (R->failed) return;
    if (R->depth >= MAX_DEPTH) {
        R->skip++;
        return;
    }
    el parent = R->depth ? R->stack[R->depth - 1] : E_OTHER;
    el e = R->depth == 0 ? el_of(n, E_OTHER) : parent == E_OTHER ? E_OTHER : el_of(n, parent);
    if (R->depth == 0 && e != E_ROOT) {
        fail(R, "the root element is <%.40s>, not <OpenDRIVE>", n);
        return;
    }
    R->stack[R->depth++] = e;
    switch (e) {
    case E_GEOREF: R->in_georef = 1; R->ngeoref = 0; break;
    case E_OFFSET:
        if (!num(R, a, "offset", "x", 1, 0, &R->doc.off_x) && !num(R, a, "offset", "y", 1, 0, &R->doc.off_y))
            num(R, a, "offset", "hdg", 1, 0, &R->doc.off_hdg);
        break;
    case E_ROAD: start_road(R, a); break;
    case E_GEOMETRY: start_geometry(R, a); break;
    case E_LANEOFFSET: start_laneoffset(R, a); break;
    case E_SECTION: start_section(R, a); break;
    case E_LANE: start_lane(R, a); break;
    case E_WIDTH: start_width(R, a); break;
    case E_ROADMARK: start_roadmark(R, a); break;
    case E_MARKLINE: start_markline(R, a); break;
    case E_OBJECT: start_object(R, a, 0); break;
    case E_SIGNAL: start_object(R, a, 1); break;
    case E_CORNER: corner(R, n, a); break;
    case E_JUNCTION: R->doc.njunctions++; break;
    case E_OTHER:
        if (parent == E_GEOMETRY) geometry_kind(R, n, a);
        break;
    default: break;
    }
}

static int cmp_lane_desc(const void *a, const void *b)
{
    int x = ((const rs__odr_lane *)a)->id, y = ((const rs__odr_lane *)b)->id;
    return x > y ? -1 : x < y;
}

static void XMLCALL on_end(void *user, const XML_Char *n)
{
    rd *R = user;
    (void)n;
    if (R->failed) return;
    if (R->skip) {
        R->skip--;
        return;
    }
    el e = R->stack[--R->depth];
    if (e == E_GEOREF) R->in_georef = 0;
    if (e == E_GEOMETRY && (int)R->doc.geoms[R->doc.ngeoms - 1].kind == -1)
        fail(R, "<geometry> has none of line, arc, spiral, poly3, paramPoly3");
    if (e == E_SECTION) { /* lanes left to right */
        rs__odr_section *S = &R->doc.sections[R->doc.nsections - 1];
        if (S->nlane > 1) qsort(R->doc.lanes + S->lane0, S->nlane, sizeof *R->doc.lanes, cmp_lane_desc);
    }
}

static void XMLCALL on_text(void *user, const XML_Char *s, int len)
{
    rd *R = user;
    if (R->failed || !R->in_georef || R->skip || R->stack[R->depth - 1] != E_GEOREF) return;
    if (R->ngeoref + (size_t)len > MAX_GEOREF) {
        fail(R, "the geoReference is longer than %d bytes", MAX_GEOREF);
        return;
    }
    if (!R->georef && !(R->georef = malloc(MAX_GEOREF + 1))) {
        fail(R, "out of memory");
        return;
    }
    memcpy(R->georef + R->ngeoref, s, (size_t)len);
    R->ngeoref += (size_t)len;
    R->georef[R->ngeoref] = '\0';
}

/* The PROJ string with blanks and line breaks made single spaces. */
static const char *clean_georef(char *g)
{
    if (!g) return NULL;
    size_t o = 0;
    for (size_t i = 0; g[i]; i++) {
        char c = g[i];
        int blank = c == ' ' || c == '\t' || c == '\n' || c == '\r';
        if (blank && (o == 0 || g[o - 1] == ' ')) continue;
        g[o++] = blank ? ' ' : c;
    }
    while (o && g[o - 1] == ' ') o--;
    g[o] = '\0';
    return o ? g : NULL;
}

static void doc_free(rd *R)
{
    for (size_t i = 0; i < R->doc.nroads; i++) free((void *)R->doc.roads[i].id);
    free(R->doc.roads);
    free(R->doc.geoms);
    free(R->doc.polys);
    free(R->doc.sections);
    free(R->doc.lanes);
    free(R->doc.marks);
    free(R->doc.lines);
    free(R->doc.objects);
    free(R->georef);
}

int cli_odr_text(const char *data, size_t n, const char *shown, size_t max_points, char **text, size_t *size,
                 char *err, size_t nerr)
{
    *text = NULL;
    *size = 0;
    rd R;
    memset(&R, 0, sizeof R);
    R.shown = shown;
    R.err = err;
    R.nerr = nerr;
    R.doc.name = shown;
    R.xp = XML_ParserCreate(NULL);
    if (!R.xp) {
        snprintf(err, nerr, "%s: out of memory for the XML parser", shown);
        return 1;
    }
    XML_SetUserData(R.xp, &R);
    XML_SetElementHandler(R.xp, on_start, on_end);
    XML_SetCharacterDataHandler(R.xp, on_text);
    int rc = 1;
    /* in pieces below INT_MAX (expat's length is an int) */
    size_t off = 0;
    do {
        size_t k = n - off > (1u << 30) ? (1u << 30) : n - off;
        int last = off + k == n;
        if (XML_Parse(R.xp, data + off, (int)k, last) == XML_STATUS_ERROR) {
            if (!R.failed)
                snprintf(err, nerr, "%s line %lu: XML: %s", shown, (unsigned long)XML_GetCurrentLineNumber(R.xp),
                         XML_ErrorString(XML_GetErrorCode(R.xp)));
            R.failed = 1;
            break;
        }
        off += k;
    } while (off < n);
    if (!R.failed && R.doc.nroads == 0) {
        snprintf(err, nerr, "%s: no <road> in this OpenDRIVE file", shown);
        R.failed = 1;
    }
    /* the library indexes every array (a NULL one, even by 0, is undefined) */
    void **arrs[] = { (void **)&R.doc.roads, (void **)&R.doc.geoms, (void **)&R.doc.polys, (void **)&R.doc.sections,
                      (void **)&R.doc.lanes, (void **)&R.doc.marks, (void **)&R.doc.lines, (void **)&R.doc.objects };
    for (size_t k = 0; k < sizeof arrs / sizeof arrs[0] && !R.failed; k++)
        if (!*arrs[k] && !(*arrs[k] = malloc(64))) {
            snprintf(err, nerr, "%s: out of memory", shown);
            R.failed = 1;
        }
    if (!R.failed) {
        R.doc.geo_reference = clean_georef(R.georef);
        rs_ctx *ctx = NULL;
        char *t = NULL;
        size_t ts = 0;
        if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) {
            snprintf(err, nerr, "%s: out of memory", shown);
        } else {
            rs_result r = rs__odr_to_text(ctx, &R.doc, max_points, &t, &ts);
            if (r) {
                snprintf(err, nerr, "%s", rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(r));
            } else if (!(*text = malloc(ts + 1))) {
                snprintf(err, nerr, "%s: out of memory for the road text", shown);
            } else {
                memcpy(*text, t, ts + 1);
                *size = ts;
                rc = 0;
            }
            rs__free(ctx, t);
            rs_ctx_free(ctx);
        }
    }
    XML_ParserFree(R.xp);
    doc_free(&R);
    return rc;
}
