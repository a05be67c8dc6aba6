/* Road attributes, quoting, style blocks, style sets and the built-in
 * default styles (docs/road-format.md): every keyword, every error with
 * its line number, the limits, the default tables, allocation failures. */
#include "harness.h"
#include "fail_alloc.h"
#include "roadsplat.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static int contains(const char *hay, const char *needle) { return strstr(hay, needle) != NULL; }

static rs_result roads_s(rs_ctx *ctx, const char *s, rs_roads **out) { return rs_roads_parse(ctx, s, strlen(s), out); }

/* A text that must fail with `want`, a message starting with "line N:" and
 * holding a and b; rs_roads_parse and rs_styles_parse must agree. */
static void bad(rs_ctx *ctx, const char *s, rs_result want, const char *a, const char *b)
{
    rs_roads *r = (rs_roads *)1;
    rs_result rc = rs_roads_parse(ctx, s, strlen(s), &r);
    char m[256];
    snprintf(m, sizeof m, "%s", rs_ctx_message(ctx));
    CHECKF(rc == want && r == NULL, "%s: got %d want %d (%s)", s, rc, want, m);
    CHECKF(strncmp(m, "line ", 5) == 0 && (!a || contains(m, a)) && (!b || contains(m, b)),
           "%s: message '%s' lacks 'line' / '%s' / '%s'", s, m, a ? a : "", b ? b : "");
    rs_styles *st = (rs_styles *)1;
    rc = rs_styles_parse(ctx, s, strlen(s), &st);
    CHECKF(rc == want && st == NULL && strcmp(m, rs_ctx_message(ctx)) == 0, "%s: styles parse gave %d '%s'", s, rc,
           rs_ctx_message(ctx));
}

/* ---- road attributes ------------------------------------------------------ */
static void test_attributes(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_roads *r = NULL;
    rs_road_info info;
    const char *name, *k, *v;
    double w;
    const char *text = "road a width 7 class=residential lanes=2 style=town oneway=yes area=urban surface=asphalt "
                       "maxspeed=30 # comment\n0 0\n10 0\nend\n"
                       "road b width 3.5\n0 0\n1 1\nend\n"
                       "road c class=motorway_link oneway=-1 lanes=1\n0 0\n5 5\nend\n"
                       "road d width 4 oneway=no class=track\n0 0\n5 5\nend\n";
    CHECK(roads_s(ctx, text, &r) == RS_OK);
    CHECK_EQ_INT(rs_roads_count(r), 4);
    CHECK(rs_roads_get_info(r, 0, &info) == RS_OK);
    CHECK(info.road_class == RS_CLASS_RESIDENTIAL && !info.link && info.lanes == 2 && info.oneway == RS_ONEWAY_YES &&
          info.area == RS_AREA_URBAN && info.style && strcmp(info.style, "town") == 0 && info.width_given);
    CHECK_EQ_INT(rs_roads_attr_count(r, 0), 7);
    CHECK(rs_roads_attr_at(r, 0, 0, &k, &v) == RS_OK && strcmp(k, "class") == 0 && strcmp(v, "residential") == 0);
    CHECK(rs_roads_attr_at(r, 0, 5, &k, &v) == RS_OK && strcmp(k, "surface") == 0 && strcmp(v, "asphalt") == 0);
    CHECK(rs_roads_attr_at(r, 0, 6, &k, &v) == RS_OK && strcmp(k, "maxspeed") == 0 && strcmp(v, "30") == 0);
    CHECK(rs_roads_attr_at(r, 0, 7, &k, &v) == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_get_attr(r, 0, "maxspeed") && strcmp(rs_roads_get_attr(r, 0, "maxspeed"), "30") == 0);
    CHECK(rs_roads_get_attr(r, 0, "maxspee") == NULL && rs_roads_get_attr(r, 0, "name") == NULL);
    CHECK(rs_roads_get_attr(r, 1, "class") == NULL && rs_roads_attr_count(r, 1) == 0);
    CHECK(rs_roads_get_info(r, 1, &info) == RS_OK && info.road_class == RS_CLASS_NONE && info.lanes == 0 &&
          info.style == NULL && info.oneway == RS_ONEWAY_NONE && info.width_given);
    CHECK(rs_roads_get_info(r, 2, &info) == RS_OK && info.road_class == RS_CLASS_MOTORWAY && info.link &&
          info.oneway == RS_ONEWAY_REVERSE && info.lanes == 1 && !info.width_given);
    rs_roads_get(r, 2, &name, &w, NULL, NULL);
    CHECK_NEAR(w, 0.75 + 3.75 + 2.50, 1e-12); /* RMS motorway carriageway, one lane */
    CHECK(rs_roads_get_info(r, 3, &info) == RS_OK && info.road_class == RS_CLASS_TRACK && info.oneway == RS_ONEWAY_NO);
    CHECK(rs_roads_get_info(r, 4, &info) == RS_ERR_INVALID_ARG && rs_roads_get_info(r, 0, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_get_attr(r, 9, "class") == NULL && rs_roads_attr_count(r, 9) == 0);
    rs_roads_free(ctx, r);

    /* oneway spellings */
    const char *ow[][2] = { { "yes", "2" }, { "1", "2" }, { "true", "2" }, { "no", "1" }, { "0", "1" },
                            { "false", "1" }, { "-1", "3" } };
    for (size_t i = 0; i < sizeof ow / sizeof ow[0]; i++) {
        char buf[128];
        snprintf(buf, sizeof buf, "road a width 3 oneway=%s\n0 0\n1 0\nend\n", ow[i][0]);
        CHECK(roads_s(ctx, buf, &r) == RS_OK && rs_roads_get_info(r, 0, &info) == RS_OK &&
              (int)info.oneway == atoi(ow[i][1]));
        rs_roads_free(ctx, r);
    }
    /* every class name and its _link */
    for (int c = 1; c < RS_CLASS_COUNT; c++) {
        char buf[128];
        int link = -1;
        CHECK((int)rs_road_class_from_name(rs_road_class_name((rs_road_class)c), &link) == c && link == 0);
        snprintf(buf, sizeof buf, "%s_link", rs_road_class_name((rs_road_class)c));
        CHECK((int)rs_road_class_from_name(buf, &link) == (c <= RS_CLASS_TERTIARY ? c : 0));
        CHECK(link == (c <= RS_CLASS_TERTIARY));
        snprintf(buf, sizeof buf, "road x class=%s\n0 0\n1 0\nend\n", rs_road_class_name((rs_road_class)c));
        CHECK(roads_s(ctx, buf, &r) == RS_OK && rs_roads_get(r, 0, NULL, &w, NULL, NULL) == RS_OK && w > 1 && w < 20);
        rs_roads_free(ctx, r);
    }
    CHECK(rs_road_class_from_name("Motorway", NULL) == RS_CLASS_NONE && rs_road_class_from_name(NULL, NULL) == 0);
    CHECK(rs_road_class_from_name("_link", NULL) == RS_CLASS_NONE && strcmp(rs_road_class_name(RS_CLASS_COUNT), "") == 0);

    /* width from the lane table: class, lanes, both; the parse profile */
    CHECK(roads_s(ctx, "road p class=primary\n0 0\n1 0\nend\nroad q lanes=3\n0 0\n1 0\nend\n"
                       "road s class=secondary lanes=4 oneway=yes\n0 0\n1 0\nend\n", &r) == RS_OK);
    rs_roads_get(r, 0, NULL, &w, NULL, NULL);
    CHECK_NEAR(w, 7.50, 1e-12); /* RQ 10.5 */
    rs_roads_get(r, 1, NULL, &w, NULL, NULL);
    CHECK_NEAR(w, 3 * 3.25, 1e-12);
    rs_roads_get(r, 2, NULL, &w, NULL, NULL);
    CHECK_NEAR(w, 4 * 3.00 + 0.5, 1e-12);
    rs_roads_free(ctx, r);
    {
        rs_road_parse_options po;
        memset(&po, 0, sizeof po);
        po.profile = RS_PROFILE_MUTCD;
        const char *t = "road i class=motorway lanes=3\n0 0\n1 0\nend\nroad j width 9 class=motorway\n0 0\n1 0\nend\n";
        CHECK(rs_roads_parse_ex(ctx, t, strlen(t), &po, &r) == RS_OK);
        rs_roads_get(r, 0, NULL, &w, NULL, NULL);
        CHECK_NEAR(w, (4 + 36 + 10) * 0.3048, 1e-12); /* Interstate: 4 ft + 3 x 12 ft + 10 ft */
        rs_roads_get(r, 1, NULL, &w, NULL, NULL);
        CHECK(w == 9); /* a given width wins */
        rs_roads_free(ctx, r);
        po.profile = (rs_profile)7;
        CHECK(rs_roads_parse_ex(ctx, t, strlen(t), &po, &r) == RS_ERR_INVALID_ARG && r == NULL);
        CHECK(rs_roads_parse_ex(ctx, t, strlen(t), &po, NULL) == RS_ERR_INVALID_ARG);
    }
    /* width may come anywhere after the name */
    CHECK(roads_s(ctx, "road a class=primary width 6 lanes=2\n0 0\n1 0\nend\n", &r) == RS_OK &&
          rs_roads_get(r, 0, NULL, &w, NULL, NULL) == RS_OK && w == 6 && rs_roads_attr_count(r, 0) == 2);
    rs_roads_free(ctx, r);

    /* errors, each naming its line */
    bad(ctx, "road a width 2\n0 0\n1 1\nend\nroad b class=highway\n", RS_ERR_PARSE, "line 5: road 'b'",
        "class 'highway' is not a road class");
    bad(ctx, "road a class=service_link\n", RS_ERR_PARSE, "line 1", "'service_link'");
    bad(ctx, "\nroad a lanes=0\n", RS_ERR_PARSE, "line 2: road 'a': lanes '0' must be a whole number 1..16", NULL);
    bad(ctx, "road a lanes=17\n", RS_ERR_PARSE, "lanes '17'", NULL);
    bad(ctx, "road a lanes=2.0\n", RS_ERR_PARSE, "lanes '2.0'", NULL);
    bad(ctx, "road a lanes=0002\n", RS_ERR_PARSE, "lanes '0002'", NULL);
    bad(ctx, "road a lanes=+2\n", RS_ERR_PARSE, "lanes '+2'", NULL);
    bad(ctx, "road a width 2 oneway=maybe\n", RS_ERR_PARSE, "line 1", "oneway 'maybe' must be yes, no or -1");
    bad(ctx, "road a width 2 area=suburb\n", RS_ERR_PARSE, "area 'suburb' must be urban or rural", NULL);
    bad(ctx, "road a width 2 style=\"\"\n", RS_ERR_PARSE, "style name ''", "1..63");
    bad(ctx, "road a width 2 style=0123456789012345678901234567890123456789012345678901234567890123\n", RS_ERR_PARSE,
        "style name", "1..63");
    bad(ctx, "road a width=2\n", RS_ERR_PARSE, "line 1: road 'a': write the width as 'width W'", NULL);
    bad(ctx, "road a width 2 a/b=c\n", RS_ERR_PARSE, "attribute key 'a/b'", NULL);
    bad(ctx, "road a width 2 =c\n", RS_ERR_PARSE, "attribute key ''", NULL);
    bad(ctx, "road a width 2 "
             "k12345678901234567890123456789012345678901234567890123456789012345=1\n",
        RS_ERR_PARSE, "attribute key", "1..64");
    bad(ctx, "road a width 2 maxspeed=\n", RS_ERR_PARSE, "attribute 'maxspeed=' has no value", NULL);
    bad(ctx, "road a width 2 x=1 y=2 x=3\n", RS_ERR_PARSE, "line 1: road 'a': attribute 'x' given twice", NULL);
    bad(ctx, "road a width 2 width 3\n", RS_ERR_PARSE, "'width' given twice", NULL);
    bad(ctx, "road a width\n", RS_ERR_PARSE, "the width value is missing", NULL);
    bad(ctx, "road a x=1\n", RS_ERR_PARSE, "line 1: road 'a': missing 'width W'", "class=");
    bad(ctx, "road a x=1 junk\n", RS_ERR_PARSE, "road 'a': 'junk' is not an attribute (write key=value)", NULL);
    bad(ctx, "road a width 2 x=1 junk\n", RS_ERR_PARSE, "'junk' is not an attribute", NULL);
    /* the messages of the format before attributes are unchanged */
    bad(ctx, "road a width 4 lanes 2\n", RS_ERR_PARSE, "line 1: extra token 'lanes' after the width", NULL);
    bad(ctx, "road a wid\n", RS_ERR_PARSE, "line 1: road 'a': expected 'width', got 'wid'", NULL);
    bad(ctx, "road a width x y\n", RS_ERR_PARSE, "extra token 'y' after the width", NULL);
    {
        char buf[2048];
        size_t o = (size_t)snprintf(buf, sizeof buf, "road a width 2");
        for (int i = 0; i < 64; i++) o += (size_t)snprintf(buf + o, sizeof buf - o, " k%d=%d", i, i);
        snprintf(buf + o, sizeof buf - o, "\n0 0\n1 1\nend\n");
        CHECK(roads_s(ctx, buf, &r) == RS_OK && rs_roads_attr_count(r, 0) == 64 &&
              strcmp(rs_roads_get_attr(r, 0, "k63"), "63") == 0);
        rs_roads_free(ctx, r);
        snprintf(buf + o, sizeof buf - o, " k64=1\n0 0\n1 1\nend\n");
        bad(ctx, buf, RS_ERR_LIMIT, "line 1", "more than 64 attributes");
    }
    rs_ctx_free(ctx);
}

/* ---- quoting ---------------------------------------------------------------- */
static void test_quoting(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_roads *r = NULL;
    const char *name;
    const char *text = "road \"Main Street\" width 7 name=\"Hauptstra\xC3\x9F" "e 1\" note=\"a # is no comment\"\n"
                       "0 0\n1 0\nend\n"
                       "road \"say \\\"hi\\\" \\\\ bye\"\twidth 3#comment\n0 0\n1 0\nend\n"
                       "road \"\" width 2 empty=\"\" tab=\"a\tb\"\n0 0\n1 0\nend\n"
                       "road a\"b width 2 k=v\"w\n0 0\n1 0\nend\n" /* quotes inside a word are plain */
                       "road \"#\" width 2 k=\"\"#c\n0 0\n1 0\nend\n";
    CHECKF(roads_s(ctx, text, &r) == RS_OK, "%s", rs_ctx_message(ctx));
    CHECK_EQ_INT(rs_roads_count(r), 5);
    if (rs_roads_count(r) == 5) {
        rs_roads_get(r, 0, &name, NULL, NULL, NULL);
        CHECK(strcmp(name, "Main Street") == 0);
        CHECK(strcmp(rs_roads_get_attr(r, 0, "name"), "Hauptstra\xC3\x9F" "e 1") == 0);
        CHECK(strcmp(rs_roads_get_attr(r, 0, "note"), "a # is no comment") == 0);
        rs_roads_get(r, 1, &name, NULL, NULL, NULL);
        CHECK(strcmp(name, "say \"hi\" \\ bye") == 0);
        rs_roads_get(r, 2, &name, NULL, NULL, NULL);
        CHECK(strcmp(name, "") == 0 && strcmp(rs_roads_get_attr(r, 2, "empty"), "") == 0 &&
              strcmp(rs_roads_get_attr(r, 2, "tab"), "a\tb") == 0);
        rs_roads_get(r, 3, &name, NULL, NULL, NULL);
        CHECK(strcmp(name, "a\"b") == 0 && strcmp(rs_roads_get_attr(r, 3, "k"), "v\"w") == 0);
        rs_roads_get(r, 4, &name, NULL, NULL, NULL);
        CHECK(strcmp(name, "#") == 0 && strcmp(rs_roads_get_attr(r, 4, "k"), "") == 0);
    }
    rs_roads_free(ctx, r);
    bad(ctx, "road \"Main Street width 7\n", RS_ERR_PARSE, "line 1: the quote at column 6 is not closed", NULL);
    bad(ctx, "\n\nroad \"a\\tb\" width 7\n", RS_ERR_PARSE, "line 3: unknown escape '\\t' at column 8", NULL);
    bad(ctx, "road \"a\"b width 7\n", RS_ERR_PARSE, "line 1: text after the closing quote at column 9", NULL);
    bad(ctx, "road a width 7 k=\"v\n", RS_ERR_PARSE, "line 1: the quote at column 18 is not closed", NULL);
    bad(ctx, "road a width 7 k=\"v\"x\n", RS_ERR_PARSE, "text after the closing quote", NULL);
    bad(ctx, "road a width 7 \"k\"=v\n", RS_ERR_PARSE, "text after the closing quote", NULL);
    bad(ctx, "road a width 7 \"k=v\"\n", RS_ERR_PARSE, "extra token '\"k=v\"' after the width", NULL);
    bad(ctx, "road a width \"7\"\n", RS_ERR_PARSE, "width '\"7\"' is not a number", NULL);
    bad(ctx, "road a width 7\n\"1\" 2\nend\n", RS_ERR_PARSE, "line 2: x '\"1\"' is not a number", NULL);
    rs_ctx_free(ctx);
}

/* ---- style blocks --------------------------------------------------------- */
static const char *styles_text =
    "# styles and roads in one file\n"
    "style town\n"
    "  fill #808080          # plain grey\n"
    "  casing 0.5 #FFffFF80\n"
    "  line 0 0.12 #fafafa dash 3 6 phase 1.5   # centre\n"
    "  line -3.1 0.25 #ffffff\n"
    "  line 2.5 0.1 #FFD700 dash 1 2 3 4\n"
    "end\n"
    "road a width 7 style=town\n0 0\n10 0\nend\n"
    "style \"big road\"\n"
    "  gradient #202020 #404040c0\n"
    "  line 0.2 0.1 #ffffff phase 2 dash 5 5\n"
    "end # done\n"
    "style empty\nend\n";

static void test_style_blocks(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_styles *S = NULL;
    CHECKF(rs_styles_parse(ctx, styles_text, strlen(styles_text), &S) == RS_OK, "%s", rs_ctx_message(ctx));
    CHECK_EQ_INT(rs_styles_count(S), 3);
    const rs_style *s = rs_styles_find(S, "town");
    CHECK(s && s == rs_styles_get(S, 0));
    if (s) {
        CHECK(strcmp(s->name, "town") == 0 && s->surface == RS_SURFACE_FILL);
        CHECK(s->fill.r == 0x80 && s->fill.g == 0x80 && s->fill.b == 0x80 && s->fill.a == 0xFF);
        CHECK(s->casing_width == 0.5 && s->casing.r == 255 && s->casing.a == 0x80);
        CHECK_EQ_INT(s->line_count, 3);
        CHECK(s->line[0].offset == 0 && s->line[0].width == 0.12 && s->line[0].colour.r == 0xfa);
        CHECK(s->line[0].dash_count == 2 && s->line[0].dash[0] == 3 && s->line[0].dash[1] == 6 && s->line[0].phase == 1.5);
        CHECK(s->line[1].offset == -3.1 && s->line[1].width == 0.25 && s->line[1].dash_count == 0 && s->line[1].phase == 0);
        CHECK(s->line[2].dash_count == 4 && s->line[2].dash[3] == 4 && s->line[2].colour.g == 0xD7);
    }
    s = rs_styles_find(S, "big road");
    CHECK(s && s->surface == RS_SURFACE_GRADIENT && s->gradient_centre.r == 0x20 && s->gradient_edge.g == 0x40 &&
          s->gradient_edge.a == 0xc0 && s->casing_width == 0);
    CHECK(s && s->line_count == 1 && s->line[0].phase == 2 && s->line[0].dash_count == 2 && s->line[0].dash[0] == 5);
    s = rs_styles_find(S, "empty");
    CHECK(s && s->surface == RS_SURFACE_DEFAULT && s->line_count == 0 && s->casing_width == 0);
    CHECK(rs_styles_find(S, "nope") == NULL && rs_styles_find(S, "Town") == NULL && rs_styles_get(S, 3) == NULL);
    CHECK(rs_styles_find(NULL, "town") == NULL && rs_styles_count(NULL) == 0);

    /* the same text for rs_roads_parse: styles checked and dropped, or kept */
    rs_roads *r = NULL;
    CHECK(roads_s(ctx, styles_text, &r) == RS_OK && rs_roads_count(r) == 1);
    rs_roads_free(ctx, r);
    rs_styles *S2;
    rs_styles_create(ctx, &S2);
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.styles = S2;
    CHECK(rs_roads_parse_ex(ctx, styles_text, strlen(styles_text), &po, &r) == RS_OK && rs_roads_count(r) == 1 &&
          rs_styles_count(S2) == 3);
    rs_roads_free(ctx, r);
    /* a second time: the names exist, nothing is added, the roads are refused too */
    CHECK(rs_roads_parse_ex(ctx, styles_text, strlen(styles_text), &po, &r) == RS_ERR_PARSE && r == NULL);
    CHECK(contains(rs_ctx_message(ctx), "line 8: style 'town' is already defined"));
    CHECK_EQ_INT(rs_styles_count(S2), 3);
    /* add_text is atomic: a failure late in the text adds nothing */
    const char *more = "style m1\nend\nstyle m2\nline 0 1 #000000\nend\nstyle m3\nfill #00\nend\n";
    CHECK(rs_styles_add_text(ctx, S2, more, strlen(more)) == RS_ERR_PARSE && rs_styles_count(S2) == 3);
    CHECK(rs_styles_find(S2, "m1") == NULL && rs_styles_find(S2, "town") != NULL);
    CHECK(rs_styles_add_text(ctx, S2, more, strlen(more) - 22) == RS_OK && rs_styles_count(S2) == 5 && rs_styles_find(S2, "m2"));
    CHECK(rs_styles_add_text(ctx, NULL, more, 4) == RS_ERR_INVALID_ARG);
    CHECK(rs_styles_add_text(ctx, S2, NULL, 4) == RS_ERR_INVALID_ARG);
    CHECK(rs_styles_add_text(ctx, S2, NULL, 0) == RS_OK);
    rs_styles_free(ctx, S2);
    rs_styles_free(ctx, S);
    CHECK(rs_styles_parse(ctx, "x", 1, NULL) == RS_ERR_INVALID_ARG && rs_styles_parse(NULL, "x", 1, &S) == RS_ERR_INVALID_ARG);

    /* limits that pass: 32 lines, 8 dash lengths, the bounds */
    {
        char buf[8192];
        size_t o = (size_t)snprintf(buf, sizeof buf, "style lim\n casing 1000 #000000\n");
        for (int i = 0; i < 32; i++)
            o += (size_t)snprintf(buf + o, sizeof buf - o, " line %d 0.001 #010203 dash 0.001 1e6 1 2 3 4 5 6 phase -1e9\n",
                                  i % 2 ? 1000 : -1000);
        snprintf(buf + o, sizeof buf - o, "end\n");
        CHECK(rs_styles_parse(ctx, buf, strlen(buf), &S) == RS_OK);
        s = rs_styles_find(S, "lim");
        CHECK(s && s->line_count == 32 && s->line[31].dash_count == 8 && s->line[0].offset == -1000 &&
              s->line[5].phase == -1e9 && s->casing_width == 1000);
        rs_styles_free(ctx, S);
        snprintf(buf + o, sizeof buf - o, " line 0 1 #000000\nend\n");
        bad(ctx, buf, RS_ERR_LIMIT, "line 35: style 'lim' has more than 32 lines", NULL);
    }

    /* errors, each with its line */
    bad(ctx, "style\n", RS_ERR_PARSE, "line 1: 'style' needs a name", NULL);
    bad(ctx, "style a b\nend\n", RS_ERR_PARSE, "line 1: extra token 'b' after the style name", NULL);
    bad(ctx, "style \"\"\nend\n", RS_ERR_PARSE, "style name '\"\"' must be 1..63 bytes", NULL);
    bad(ctx, "style \"a\tb\"\nend\n", RS_ERR_PARSE, "has a tab", NULL);
    bad(ctx, "style 0123456789012345678901234567890123456789012345678901234567890123\nend\n", RS_ERR_PARSE,
        "longer than 63 bytes", NULL);
    bad(ctx, "style a\nfill #000000\n", RS_ERR_PARSE, "line 2: style 'a' (started on line 1) has no 'end'", NULL);
    bad(ctx, "style a\nroad b width 2\n", RS_ERR_PARSE, "line 2: 'road' inside style 'a' (line 1); missing 'end'?", NULL);
    bad(ctx, "style a\nstyle b\n", RS_ERR_PARSE, "line 2: 'style' inside style 'a' (line 1)", NULL);
    bad(ctx, "road b width 2\nstyle a\n", RS_ERR_PARSE, "line 2: 'style' inside road 'b' (line 1); missing 'end'?", NULL);
    bad(ctx, "style a\n0 0\nend\n", RS_ERR_PARSE, "line 2: unknown keyword '0' in style 'a' (expected fill", NULL);
    bad(ctx, "style a\nFill #000000\nend\n", RS_ERR_PARSE, "unknown keyword 'Fill'", NULL);
    bad(ctx, "style a\nfill\nend\n", RS_ERR_PARSE, "line 2: fill needs a colour #RRGGBB or #RRGGBBAA", NULL);
    bad(ctx, "style a\nfill # comment\nend\n", RS_ERR_PARSE, "line 2: fill needs a colour", NULL);
    bad(ctx, "style a\nfill #fff\nend\n", RS_ERR_PARSE, "line 2: fill colour '#fff' must be #RRGGBB or #RRGGBBAA", NULL);
    bad(ctx, "style a\nfill #12345g\nend\n", RS_ERR_PARSE, "colour '#12345g'", NULL);
    bad(ctx, "style a\nfill #1234567\nend\n", RS_ERR_PARSE, "colour '#1234567'", NULL);
    bad(ctx, "style a\nfill #123456#x\nend\n", RS_ERR_PARSE, "colour '#123456#x'", NULL);
    bad(ctx, "style a\nfill red\nend\n", RS_ERR_PARSE, "fill colour 'red' must be", NULL);
    /* after the arguments a '#' starts a comment, even one that looks like a colour */
    CHECK(rs_styles_parse(ctx, "style a\nfill #000000 #ffffff\nend\n", 33, &S) == RS_OK &&
          rs_styles_get(S, 0)->fill.r == 0);
    rs_styles_free(ctx, S);
    bad(ctx, "style a\nfill #000000 x\nend\n", RS_ERR_PARSE, "extra token 'x' after the colour", NULL);
    bad(ctx, "style a\nfill #000000\ngradient #000000 #111111\nend\n", RS_ERR_PARSE, "line 3: style 'a': the surface is set twice",
        NULL);
    bad(ctx, "style a\nfill #000000\nfill #000000\nend\n", RS_ERR_PARSE, "line 3", "surface is set twice");
    bad(ctx, "style a\ngradient #000000\nend\n", RS_ERR_PARSE, "line 2: gradient edge needs a colour", NULL);
    bad(ctx, "style a\ncasing #000000\nend\n", RS_ERR_PARSE, "line 2: casing width is missing", NULL);
    bad(ctx, "style a\ncasing\nend\n", RS_ERR_PARSE, "line 2: casing width is missing: casing W #RRGGBB", NULL);
    bad(ctx, "style a\ncasing 0 #000000\nend\n", RS_ERR_PARSE, "casing width '0' must be 0.001..1000", NULL);
    bad(ctx, "style a\ncasing 1001 #000000\nend\n", RS_ERR_PARSE, "casing width '1001'", NULL);
    bad(ctx, "style a\ncasing nan #000000\nend\n", RS_ERR_PARSE, "casing width 'nan' is not a number", NULL);
    bad(ctx, "style a\ncasing 1e999 #000000\nend\n", RS_ERR_PARSE, "casing width '1e999' is out of range", NULL);
    bad(ctx, "style a\ncasing 1 #000000\ncasing 1 #000000\nend\n", RS_ERR_PARSE, "line 3: style 'a': 'casing' given twice",
        NULL);
    bad(ctx, "style a\ncasing 1\nend\n", RS_ERR_PARSE, "casing needs a colour", NULL);
    bad(ctx, "style a\nline\nend\n", RS_ERR_PARSE, "line 2: line offset is missing: line T W #RRGGBB", NULL);
    bad(ctx, "style a\nline 0\nend\n", RS_ERR_PARSE, "line width is missing", NULL);
    bad(ctx, "style a\nline 0 1\nend\n", RS_ERR_PARSE, "line needs a colour", NULL);
    bad(ctx, "style a\nline 1001 1 #000000\nend\n", RS_ERR_PARSE, "line offset '1001' must be -1000..1000", NULL);
    bad(ctx, "style a\nline -inf 1 #000000\nend\n", RS_ERR_PARSE, "line offset '-inf' is not a number", NULL);
    bad(ctx, "style a\nline 0 0.0009 #000000\nend\n", RS_ERR_PARSE, "line width '0.0009' must be 0.001..1000", NULL);
    bad(ctx, "style a\nline 0 -1 #000000\nend\n", RS_ERR_PARSE, "line width '-1'", NULL);
    bad(ctx, "style a\nline 0 1,5 #000000\nend\n", RS_ERR_PARSE, "'1,5' is not a number (use '.'", NULL);
    bad(ctx, "style a\nline 0 1 #000000 dash\nend\n", RS_ERR_PARSE, "line 2: 'dash' needs lengths", NULL);
    bad(ctx, "style a\nline 0 1 #000000 dash 1 2 3\nend\n", RS_ERR_PARSE, "dash pattern has 3 lengths; it needs ON OFF pairs",
        NULL);
    bad(ctx, "style a\nline 0 1 #000000 dash 1 2 3 4 5 6 7 8 9 10\nend\n", RS_ERR_LIMIT, "more than 8 lengths", NULL);
    bad(ctx, "style a\nline 0 1 #000000 dash 1 0\nend\n", RS_ERR_PARSE, "dash length '0' must be 0.001..1e+06", NULL);
    bad(ctx, "style a\nline 0 1 #000000 dash 1 2e6\nend\n", RS_ERR_PARSE, "dash length '2e6'", NULL);
    bad(ctx, "style a\nline 0 1 #000000 dash 1 x\nend\n", RS_ERR_PARSE, "dash length 'x' is not a number", NULL);
    bad(ctx, "style a\nline 0 1 #000000 dash 1 1 dash 2 2\nend\n", RS_ERR_PARSE, "'dash' given twice", NULL);
    bad(ctx, "style a\nline 0 1 #000000 phase 1\nend\n", RS_ERR_PARSE, "line 2: 'phase' needs a 'dash' pattern", NULL);
    bad(ctx, "style a\nline 0 1 #000000 dash 1 1 phase\nend\n", RS_ERR_PARSE, "dash phase is missing", NULL);
    bad(ctx, "style a\nline 0 1 #000000 dash 1 1 phase 2e9\nend\n", RS_ERR_PARSE, "dash phase '2e9' must be", NULL);
    bad(ctx, "style a\nline 0 1 #000000 dash 1 1 phase 1 phase 2\nend\n", RS_ERR_PARSE, "'phase' given twice", NULL);
    bad(ctx, "style a\nline 0 1 #000000 phase 1 dash 1 1 dash 1 1\nend\n", RS_ERR_PARSE, "'dash' given twice", NULL);
    bad(ctx, "style a\nline 0 1 #000000 solid\nend\n", RS_ERR_PARSE, "unexpected 'solid' after the line colour", NULL);
    bad(ctx, "style a\nend x\n", RS_ERR_PARSE, "line 2: extra token 'x' after 'end'", NULL);
    bad(ctx, "style a\nend\nstyle a\nend\n", RS_ERR_PARSE, "line 4: style 'a' is already defined", NULL);
    bad(ctx, "style a\nend\nroad b width 1\n0 0\nend\n", RS_ERR_PARSE, "line 5: road 'b' (line 3) has 1 point", NULL);
    rs_ctx_free(ctx);
}

/* ---- rs_styles_add and many styles -------------------------------------------------- */
static void test_styles_add(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_styles *S;
    CHECK(rs_styles_create(ctx, &S) == RS_OK);
    rs_style st;
    memset(&st, 0, sizeof st);
    strcpy(st.name, "s");
    st.line_count = 1;
    st.line[0].width = 0.5;
    CHECK(rs_styles_add(ctx, S, &st) == RS_OK);
    CHECK(rs_styles_add(ctx, S, &st) == RS_ERR_INVALID_ARG && contains(rs_ctx_message(ctx), "already defined"));
    struct { const char *field; void (*set)(rs_style *); } cases[8];
    (void)cases;
    rs_style b = st;
    strcpy(b.name, "b");
    b.line[0].width = 0; CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG && contains(rs_ctx_message(ctx), "width"));
    b.line[0].width = NAN; CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG);
    b.line[0].width = 1; b.line[0].offset = INFINITY; CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG);
    b.line[0].offset = 0; b.line[0].dash_count = 3; CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG);
    b.line[0].dash_count = 10; CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG);
    b.line[0].dash_count = 2; b.line[0].dash[0] = 1; b.line[0].dash[1] = 0; CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG);
    b.line[0].dash[1] = 1; b.line[0].phase = NAN; CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG);
    b.line[0].phase = 3; CHECK(rs_styles_add(ctx, S, &b) == RS_OK);
    strcpy(b.name, "c");
    b.line[0].dash_count = 0; CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG && contains(rs_ctx_message(ctx), "phase"));
    b.line[0].phase = 0; b.casing_width = -1; CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG);
    b.casing_width = 1e-4; CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG);
    b.casing_width = 0; b.surface = (rs_surface)3; CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG);
    b.surface = RS_SURFACE_GRADIENT; b.line_count = 33; CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG);
    b.line_count = 0; b.name[0] = 0; CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG);
    strcpy(b.name, "a\tb"); CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG);
    strcpy(b.name, "\xC3("); CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG);
    memset(b.name, 'x', sizeof b.name); CHECK(rs_styles_add(ctx, S, &b) == RS_ERR_INVALID_ARG); /* no NUL */
    strcpy(b.name, "Stra\xC3\x9F" "e"); CHECK(rs_styles_add(ctx, S, &b) == RS_OK);
    CHECK(rs_styles_add(ctx, S, NULL) == RS_ERR_INVALID_ARG && rs_styles_add(NULL, S, &b) == RS_ERR_INVALID_ARG);
    CHECK_EQ_INT(rs_styles_count(S), 3);
    /* many names: every one found through the index, none invented */
    int found = 1;
    for (int i = 0; i < 3000; i++) {
        snprintf(b.name, sizeof b.name, "n%d", i);
        if (rs_styles_add(ctx, S, &b) != RS_OK) found = 0;
    }
    for (int i = 0; i < 3000; i++) {
        char nm[32];
        snprintf(nm, sizeof nm, "n%d", i);
        const rs_style *f = rs_styles_find(S, nm);
        if (!f || strcmp(f->name, nm) != 0 || f != rs_styles_get(S, 3 + (size_t)i)) found = 0;
    }
    CHECK(found && rs_styles_find(S, "n3000") == NULL && rs_styles_find(S, "s") == rs_styles_get(S, 0));
    rs_styles_free(ctx, S);
    rs_ctx_free(ctx);
}

/* ---- default styles ----------------------------------------------------------- */
static const rs_style_line *find_line(const rs_style *s, double t)
{
    for (uint32_t i = 0; i < s->line_count; i++)
        if (fabs(s->line[i].offset - t) < 1e-9) return &s->line[i];
    return NULL;
}

static void test_defaults(void)
{
    rs_style_request q;
    rs_style s;
    double w;
    memset(&q, 0, sizeof q);

    /* RMS motorway, two lanes: 0.75 + 2 x 3.75 + 2.50 = 10.75 m; lane line
     * 0.15 m 6/12 dashed at the lane boundary; 0.30 m edge lines in the strips */
    q.road_class = RS_CLASS_MOTORWAY;
    CHECK(rs_style_default_width(&q, &w) == RS_OK);
    CHECK_NEAR(w, 10.75, 1e-12);
    CHECK(rs_style_default(&q, &s) == RS_OK && strcmp(s.name, "motorway") == 0 && s.surface == RS_SURFACE_DEFAULT);
    CHECK_EQ_INT(s.line_count, 3);
    const rs_style_line *l = find_line(&s, 10.75 / 2 - 0.75 - 3.75);
    CHECK(l && l->width == 0.15 && l->dash_count == 2 && l->dash[0] == 6 && l->dash[1] == 12 && l->phase == 0);
    l = find_line(&s, 10.75 / 2 - 0.75 + 0.15);
    CHECK(l && l->width == 0.30 && l->dash_count == 0);
    l = find_line(&s, -10.75 / 2 + 2.50 - 0.15);
    CHECK(l && l->width == 0.30 && l->dash_count == 0 && l->colour.r == 0xF4);
    /* against the travel direction: mirrored */
    q.oneway = RS_ONEWAY_REVERSE;
    CHECK(rs_style_default(&q, &s) == RS_OK && find_line(&s, -(10.75 / 2 - 0.75 + 0.15)) != NULL);
    q.oneway = RS_ONEWAY_NONE;

    /* RMS rural primary two-way (RQ 10.5): dashed centre line 6/12 at t = 0, edge lines */
    q.road_class = RS_CLASS_PRIMARY;
    CHECK(rs_style_default_width(&q, &w) == RS_OK && fabs(w - 7.5) < 1e-12);
    CHECK(rs_style_default(&q, &s) == RS_OK && s.line_count == 3);
    l = find_line(&s, 0);
    CHECK(l && l->width == 0.12 && l->dash_count == 2 && l->dash[0] == 6 && l->dash[1] == 12);
    CHECK(s.casing_width == 0);
    /* in town: 3/6 dashes, kerb casing, no edge lines */
    q.area = RS_AREA_URBAN;
    CHECK(rs_style_default(&q, &s) == RS_OK && s.line_count == 1 && s.line[0].dash[0] == 3 && s.line[0].dash[1] == 6);
    CHECK(s.casing_width == 0.15);
    q.area = RS_AREA_AUTO;
    /* tertiary is urban by default */
    q.road_class = RS_CLASS_TERTIARY;
    CHECK(rs_style_default(&q, &s) == RS_OK && s.line_count == 1 && s.line[0].dash[0] == 3 && s.casing_width > 0);
    /* four lanes two-way: solid centre line, dashed lane lines */
    q.road_class = RS_CLASS_TRUNK;
    q.lanes = 4;
    CHECK(rs_style_default(&q, &s) == RS_OK && s.line_count == 5);
    l = find_line(&s, 0);
    CHECK(l && l->dash_count == 0 && l->width == 0.12);
    CHECK(find_line(&s, 3.5) && find_line(&s, 3.5)->dash_count == 2);
    q.lanes = 0;
    /* residential and below: no lines; track, path, footway, cycleway: coloured fill */
    q.road_class = RS_CLASS_RESIDENTIAL;
    CHECK(rs_style_default(&q, &s) == RS_OK && s.line_count == 0 && s.surface == RS_SURFACE_DEFAULT && s.casing_width > 0);
    q.road_class = RS_CLASS_CYCLEWAY;
    CHECK(rs_style_default(&q, &s) == RS_OK && s.line_count == 0 && s.surface == RS_SURFACE_FILL);
    CHECK(rs_style_default_width(&q, &w) == RS_OK && w == 2.0);
    q.road_class = RS_CLASS_NONE;
    CHECK(rs_style_default(&q, &s) == RS_OK && s.line_count == 0 && s.name[0] == 0 && s.casing_width == 0);

    /* MUTCD: 10 ft / 30 ft dashes, 4-6 in lines, yellow centre and left edge lines */
    q.profile = RS_PROFILE_MUTCD;
    q.road_class = RS_CLASS_MOTORWAY;
    CHECK(rs_style_default_width(&q, &w) == RS_OK);
    CHECK_NEAR(w, (4 + 24 + 10) * 0.3048, 1e-12);
    CHECK(rs_style_default(&q, &s) == RS_OK && s.line_count == 3);
    l = find_line(&s, w / 2 - 4 * 0.3048 - 12 * 0.3048);
    CHECK(l && fabs(l->width - 6 * 0.0254) < 1e-12 && l->dash_count == 2 && fabs(l->dash[0] - 3.048) < 1e-12 &&
          fabs(l->dash[1] - 9.144) < 1e-12 && l->colour.b == 0xF4);
    l = find_line(&s, w / 2 - 4 * 0.3048 + 3 * 0.0254);
    CHECK(l && l->colour.r == 0xF2 && l->colour.b == 0x05); /* left edge: yellow */
    q.road_class = RS_CLASS_SECONDARY;
    CHECK(rs_style_default(&q, &s) == RS_OK);
    l = find_line(&s, 0);
    CHECK(l && l->colour.b == 0x05 && l->dash_count == 2 && fabs(l->width - 0.1016) < 1e-12);
    q.lanes = 4; /* undivided four lanes: double solid yellow, 4 in apart */
    CHECK(rs_style_default(&q, &s) == RS_OK);
    CHECK(find_line(&s, 0.1016) && find_line(&s, -0.1016) && find_line(&s, 0.1016)->dash_count == 0 &&
          find_line(&s, 0.1016)->colour.b == 0x05);
    q.lanes = 0;
    q.road_class = RS_CLASS_PATH;
    CHECK(rs_style_default_width(&q, &w) == RS_OK && fabs(w - 10 * 0.3048) < 1e-12);

    /* a given width: the layout scales into it */
    q.road_class = RS_CLASS_PRIMARY;
    q.profile = RS_PROFILE_RMS;
    q.width = 15;
    CHECK(rs_style_default(&q, &s) == RS_OK && find_line(&s, 0) != NULL);
    CHECK(find_line(&s, 7.5 - 0.5 + 0.125) != NULL); /* strip 0.25 x 2 = 0.5 */
    q.width = 0;

    /* every class, profile, area, oneway and lane count: lines inside the road,
     * the style passes rs_styles_add's checks, output deterministic */
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_styles *S;
    rs_styles_create(ctx, &S);
    int inside = 1, valid = 1, same = 1;
    for (int p = 0; p < 2; p++)
        for (int c = 0; c < RS_CLASS_COUNT; c++)
            for (int a = 0; a < 3; a++)
                for (int o = 0; o < 4; o++)
                    for (uint32_t n = 0; n <= 16; n++)
                        for (int wi = 0; wi < 3; wi++) {
                            rs_style_request rq;
                            memset(&rq, 0, sizeof rq);
                            rq.profile = (rs_profile)p;
                            rq.road_class = (rs_road_class)c;
                            rq.area = (rs_area)a;
                            rq.oneway = (rs_oneway)o;
                            rq.lanes = n;
                            rq.width = wi == 0 ? 0 : wi == 1 ? 2.0 : 40.0;
                            rs_style s1, s2;
                            memset(&s2, 0xAB, sizeof s2);
                            if (rs_style_default(&rq, &s1) != RS_OK || rs_style_default(&rq, &s2) != RS_OK ||
                                rs_style_default_width(&rq, &w) != RS_OK) {
                                valid = 0;
                                continue;
                            }
                            same &= memcmp(&s1, &s2, sizeof s1) == 0;
                            double half = (rq.width > 0 ? rq.width : w) / 2;
                            for (uint32_t i = 0; i < s1.line_count; i++)
                                inside &= fabs(s1.line[i].offset) + s1.line[i].width / 2 <= half + 1e-9 ||
                                          rq.width == 2.0; /* 2 m cannot hold a motorway's lines */
                            if (c == 0) continue;
                            snprintf(s1.name, sizeof s1.name, "d%d_%d_%d_%d_%u_%d", p, c, a, o, n, wi);
                            valid &= rs_styles_add(ctx, S, &s1) == RS_OK;
                        }
    CHECK(inside);
    CHECK(valid);
    CHECK(same);
    rs_styles_free(ctx, S);
    rs_ctx_free(ctx);

    /* bad requests */
    q.road_class = RS_CLASS_COUNT;
    CHECK(rs_style_default(&q, &s) == RS_ERR_INVALID_ARG && rs_style_default_width(&q, &w) == RS_ERR_INVALID_ARG);
    q.road_class = RS_CLASS_PRIMARY;
    q.lanes = 17;
    CHECK(rs_style_default(&q, &s) == RS_ERR_INVALID_ARG);
    q.lanes = 0;
    q.width = NAN;
    CHECK(rs_style_default(&q, &s) == RS_ERR_INVALID_ARG);
    q.width = -1;
    CHECK(rs_style_default(&q, &s) == RS_ERR_INVALID_ARG);
    q.width = 2001;
    CHECK(rs_style_default(&q, &s) == RS_ERR_INVALID_ARG);
    q.width = 2000;
    CHECK(rs_style_default(&q, &s) == RS_OK);
    q.width = 0;
    q.profile = (rs_profile)2;
    CHECK(rs_style_default(&q, &s) == RS_ERR_INVALID_ARG);
    CHECK(rs_style_default(NULL, &s) == RS_ERR_INVALID_ARG && rs_style_default(&q, NULL) == RS_ERR_INVALID_ARG);
}

/* ---- which style a road gets ------------------------------------------------- */
static void test_road_style(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    const char *text = "style mine\nfill #ff0000\nend\n"
                       "style residential\nfill #00ff00\nend\n"
                       "road a width 5 style=mine class=primary\n0 0\n1 0\nend\n"
                       "road b width 5 class=residential\n0 0\n1 0\nend\n"
                       "road c width 8 class=primary\n0 0\n1 0\nend\n"
                       "road d width 8 style=secondary lanes=4\n0 0\n1 0\nend\n"
                       "road e width 3\n0 0\n1 0\nend\n"
                       "road f width 3 style=nowhere\n0 0\n1 0\nend\n"
                       "road g width 1e6 class=primary lanes=4\n0 0\n1 0\nend\n";
    rs_styles *S;
    rs_roads *r;
    rs_styles_create(ctx, &S);
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.styles = S;
    CHECK(rs_roads_parse_ex(ctx, text, strlen(text), &po, &r) == RS_OK);
    rs_style s, d;
    rs_style_request q;
    memset(&q, 0, sizeof q);
    CHECK(rs_road_style(ctx, r, 0, S, RS_PROFILE_RMS, &s) == RS_OK && strcmp(s.name, "mine") == 0 && s.fill.r == 255);
    CHECK(rs_road_style(ctx, r, 1, S, RS_PROFILE_RMS, &s) == RS_OK && strcmp(s.name, "residential") == 0 &&
          s.surface == RS_SURFACE_FILL && s.fill.g == 255);
    CHECK(rs_road_style(ctx, r, 1, NULL, RS_PROFILE_RMS, &s) == RS_OK && s.surface == RS_SURFACE_DEFAULT);
    q.road_class = RS_CLASS_PRIMARY;
    q.width = 8;
    CHECK(rs_road_style(ctx, r, 2, S, RS_PROFILE_RMS, &s) == RS_OK && rs_style_default(&q, &d) == RS_OK &&
          memcmp(&s, &d, sizeof s) == 0);
    q.profile = RS_PROFILE_MUTCD;
    CHECK(rs_road_style(ctx, r, 2, S, RS_PROFILE_MUTCD, &s) == RS_OK && rs_style_default(&q, &d) == RS_OK &&
          memcmp(&s, &d, sizeof s) == 0);
    q.profile = RS_PROFILE_RMS;
    q.road_class = RS_CLASS_SECONDARY; /* a built-in by name, with the road's lanes */
    q.lanes = 4;
    CHECK(rs_road_style(ctx, r, 3, S, RS_PROFILE_RMS, &s) == RS_OK && rs_style_default(&q, &d) == RS_OK &&
          memcmp(&s, &d, sizeof s) == 0 && s.line_count == 5);
    CHECK(rs_road_style(ctx, r, 4, S, RS_PROFILE_RMS, &s) == RS_OK && s.line_count == 0 && s.name[0] == 0);
    CHECK(rs_road_style(ctx, r, 5, S, RS_PROFILE_RMS, &s) == RS_ERR_INVALID_ARG);
    CHECK(contains(rs_ctx_message(ctx), "road 5 ('f'): style 'nowhere' is not defined"));
    /* a road wider than 2 km: the lines of a 2 km road, within the offset bound */
    q.road_class = RS_CLASS_PRIMARY;
    q.width = 2000;
    CHECK(rs_road_style(ctx, r, 6, S, RS_PROFILE_RMS, &s) == RS_OK && rs_style_default(&q, &d) == RS_OK &&
          memcmp(&s, &d, sizeof s) == 0 && s.line_count == 5 && fabs(s.line[4].offset) <= 1000);
    CHECK(rs_road_style(ctx, r, 7, S, RS_PROFILE_RMS, &s) == RS_ERR_INVALID_ARG);
    CHECK(rs_road_style(ctx, r, 0, S, (rs_profile)9, &s) == RS_ERR_INVALID_ARG);
    CHECK(rs_road_style(ctx, r, 0, S, RS_PROFILE_RMS, NULL) == RS_ERR_INVALID_ARG);
    CHECK(rs_road_style(NULL, r, 0, S, RS_PROFILE_RMS, &s) == RS_ERR_INVALID_ARG);
    rs_roads_free(ctx, r);
    rs_styles_free(ctx, S);
    rs_ctx_free(ctx);
}

/* ---- rs_roads_set_attr ------------------------------------------------------- */
static void test_set_attr(void)
{
    rs_ctx *ctx;
    rs_ctx_create(NULL, NULL, &ctx);
    rs_roads *r;
    rs_road_info info;
    double pts[4] = { 0, 0, 1, 1 };
    const char *k, *v;
    rs_roads_create(ctx, &r);
    rs_roads_add(ctx, r, "a", 3, pts, 2);
    rs_roads_add(ctx, r, "b", 4, pts, 2);
    CHECK(rs_roads_set_attr(ctx, r, 0, "class", "primary") == RS_OK);
    CHECK(rs_roads_set_attr(ctx, r, 1, "surface", "gravel") == RS_OK);
    CHECK(rs_roads_set_attr(ctx, r, 0, "lanes", "3") == RS_OK); /* road 0's slice moves to the end */
    CHECK(rs_roads_set_attr(ctx, r, 1, "lanes", "1") == RS_OK);
    CHECK(rs_roads_set_attr(ctx, r, 0, "class", "track") == RS_OK); /* replaced in place */
    CHECK(rs_roads_set_attr(ctx, r, 0, "style", "s1") == RS_OK);
    CHECK(rs_roads_get_info(r, 0, &info) == RS_OK && info.road_class == RS_CLASS_TRACK && info.lanes == 3 &&
          strcmp(info.style, "s1") == 0 && info.width_given);
    CHECK_EQ_INT(rs_roads_attr_count(r, 0), 3);
    CHECK(rs_roads_attr_at(r, 0, 0, &k, &v) == RS_OK && strcmp(k, "class") == 0 && strcmp(v, "track") == 0);
    CHECK(rs_roads_attr_at(r, 0, 1, &k, &v) == RS_OK && strcmp(k, "lanes") == 0 && strcmp(v, "3") == 0);
    CHECK(rs_roads_attr_count(r, 1) == 2 && strcmp(rs_roads_get_attr(r, 1, "surface"), "gravel") == 0 &&
          strcmp(rs_roads_get_attr(r, 1, "lanes"), "1") == 0);
    double w;
    rs_roads_get(r, 0, NULL, &w, NULL, NULL);
    CHECK(w == 3); /* attributes never change the width */
    CHECK(rs_roads_set_attr(ctx, r, 0, "lanes", "99") == RS_ERR_INVALID_ARG && contains(rs_ctx_message(ctx), "1..16"));
    CHECK(rs_roads_set_attr(ctx, r, 0, "width", "3") == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_set_attr(ctx, r, 0, "bad key", "3") == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_set_attr(ctx, r, 0, "", "3") == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_set_attr(ctx, r, 0, "k", "a\nb") == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_set_attr(ctx, r, 0, "k", "\xff") == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_set_attr(ctx, r, 0, "k", "a\tb \xC3\xA9") == RS_OK);
    CHECK(rs_roads_set_attr(ctx, r, 2, "k", "v") == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_set_attr(ctx, r, 0, NULL, "v") == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_set_attr(NULL, r, 0, "k", "v") == RS_ERR_INVALID_ARG);
    CHECK(rs_roads_get_info(r, 0, &info) == RS_OK && info.lanes == 3 && info.road_class == RS_CLASS_TRACK);
    int ok = 1;
    for (int i = 0; i < 60; i++) {
        char key[16];
        snprintf(key, sizeof key, "x%d", i);
        ok &= rs_roads_set_attr(ctx, r, 1, key, key) == (i < 62 ? RS_OK : RS_ERR_LIMIT);
    }
    CHECK(ok && rs_roads_attr_count(r, 1) == 62);
    CHECK(rs_roads_set_attr(ctx, r, 1, "y1", "1") == RS_OK && rs_roads_set_attr(ctx, r, 1, "y2", "1") == RS_OK);
    CHECK(rs_roads_set_attr(ctx, r, 1, "y3", "1") == RS_ERR_LIMIT && rs_roads_attr_count(r, 1) == 64);
    CHECK(rs_roads_set_attr(ctx, r, 1, "y1", "2") == RS_OK); /* replacing is fine at the limit */
    /* copying a road keeps working after attributes grew the pool */
    const char *name;
    const double *xy;
    size_t n;
    rs_roads_get(r, 0, &name, &w, &xy, &n);
    CHECK(rs_roads_add(ctx, r, name, w, xy, n) == RS_OK && rs_roads_attr_count(r, 2) == 0);
    rs_roads_get(r, 2, &name, NULL, NULL, NULL);
    CHECK(strcmp(name, "a") == 0);
    rs_roads_free(ctx, r);
    rs_ctx_free(ctx);
}

/* ---- allocation failures ------------------------------------------------------- */
static rs_result alloc_case(rs_ctx *ctx, const char *text, size_t n)
{
    rs_styles *S = NULL;
    rs_roads *r = NULL;
    rs_result rc = rs_styles_create(ctx, &S);
    rs_road_parse_options po;
    memset(&po, 0, sizeof po);
    po.styles = S;
    if (rc == RS_OK) rc = rs_roads_parse_ex(ctx, text, n, &po, &r);
    if (rc == RS_OK) rc = rs_roads_set_attr(ctx, r, 0, "late", "value");
    if (rc == RS_OK) rc = rs_roads_set_attr(ctx, r, 1, "later", "value");
    if (rc == RS_OK) {
        rs_style s;
        rc = rs_road_style(ctx, r, 0, S, RS_PROFILE_RMS, &s);
        if (rc == RS_OK) {
            strcpy(s.name, "copy");
            rc = rs_styles_add(ctx, S, &s);
        }
    }
    if (rc == RS_OK) {
        rs_styles *S2 = NULL;
        rc = rs_styles_parse(ctx, text, n, &S2);
        rs_styles_free(ctx, S2);
    }
    rs_roads_free(ctx, r);
    rs_styles_free(ctx, S);
    return rc;
}

static void test_alloc_failures(void)
{
    char *buf = malloc(1 << 16);
    if (!buf) { CHECK(0); return; }
    size_t o = 0;
    for (int i = 0; i < 30; i++) {
        o += (size_t)snprintf(buf + o, 400, "style s%d\n fill #10203040\n casing 0.5 #000000\n line 0 0.1 #ffffff dash 3 6\nend\n", i);
        o += (size_t)snprintf(buf + o, 400, "road \"road %d\" class=%s lanes=%d style=s%d k%d=\"v %d\"\n0 0\n%d 1\nend\n", i,
                              i % 2 ? "primary" : "residential", 1 + i % 4, i, i, i, i + 1);
    }
    /* count the allocations of a clean run, then fail each in turn */
    long total;
    {
        fail_alloc fa = { 1000000000L, 0 };
        rs_allocator al = fail_alloc_hook(&fa);
        rs_ctx *ctx;
        rs_ctx_create(&al, NULL, &ctx);
        CHECK(alloc_case(ctx, buf, o) == RS_OK);
        rs_ctx_free(ctx);
        total = 1000000000L - fa.countdown;
        CHECK_EQ_INT(fa.live, 0);
    }
    int all_nomem = 1, no_leak = 1;
    for (long N = 1; N < total; N++) { /* N = 0 would fail the context itself */
        fail_alloc fa = { N, 0 };
        rs_allocator al = fail_alloc_hook(&fa);
        rs_ctx *ctx;
        if (rs_ctx_create(&al, NULL, &ctx) != RS_OK) { all_nomem = 0; continue; }
        rs_result rc = alloc_case(ctx, buf, o);
        rs_ctx_free(ctx);
        if (fa.live != 0) no_leak = 0;
        if (rc != RS_ERR_NOMEM) { all_nomem = 0; fprintf(stderr, "N=%ld rc=%d\n", N, rc); }
    }
    CHECKF(total > 20, "%ld allocations", total);
    CHECK(all_nomem);
    CHECK(no_leak);
    free(buf);
}

int main(void)
{
    test_attributes();
    test_quoting();
    test_style_blocks();
    test_styles_add();
    test_defaults();
    test_road_style();
    test_set_attr();
    test_alloc_failures();
    return th_finish("test_style");
}
