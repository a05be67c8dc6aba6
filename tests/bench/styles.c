/* Road styles and line symbols (issue 13), one thread, same run:
 *  1. the city scene with the default class styles against the same scene
 *     unstyled (splat time; target <= 1.5x);
 *  2. a dashed line's cost against a solid one (the same lines with and
 *     without dashes; overlays stage and whole splat; target <= 1.2x);
 *  3. exact against Hermite anti-aliasing: error against a supersampled
 *     reference (lib/scene/linesym.c coverage, straight and curved lines of real
 *     marking widths at two pixel sizes) and the overlays time on the city.
 * Times: fastest of RUNS whole-image rs_splat_window calls on a prepared
 * splatter, the cases interleaved run by run.
 * Usage: styles OUTDIR   (writes OUTDIR/styles.md and styles.csv)
 *        styles --t1 REPS  (issue 29 target 1 alone, REPS style builds each
 *                           with 3 splats, no Cairo: for profiling)
 *        styles --cases [I] (the cases' splats alone, with the fastest run's
 *                           stages; case I alone 4 times as often: for profiling) */
#include "roadsplat.h"
#include "bandref.h"
#include "linesym.h"
#include "scenes.h"
#include "timing.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RUNS 15
#define REF_N 64

static double clock_ms(void *user)
{
    (void)user;
    return tm_now_ms();
}

typedef struct scase {
    const char *name;
    rs_splatter *s;
    double ms, ov_ms;
    rs_splat_profile prof; /* the fastest run's (styles --cases) */
} scase;

static int run_once(rs_ctx *ctx, scase *k, uint8_t *rgba, uint32_t w, uint32_t h)
{
    rs_splat_profile pf;
    memset(&pf, 0, sizeof pf);
    pf.clock_ms = clock_ms;
    double t0 = tm_now_ms();
    if (rs_splat_window(ctx, k->s, 0, 0, w, h, rgba, (size_t)w * 4, NULL, 0, &pf)) return -1;
    double t = tm_now_ms() - t0;
    if (t < k->ms) k->ms = t, k->prof = pf;
    if (pf.overlays_ms < k->ov_ms) k->ov_ms = pf.overlays_ms;
    return 0;
}

/* --- accuracy of exact vs Hermite line coverage --------------------------- */
typedef struct acc {
    double sum, max;
    size_t n;
} acc;

static int accuracy(rs_ctx *ctx, rs__band_aa aa, double pix, acc *out)
{
    /* a gentle curve and a straight road at 23 degrees, 0.12-0.30 m lines */
    enum { N = 25 };
    double cx[N], cy[N], sx[2] = { -5, 70 }, sy[2] = { 4, 4 + 75 * tan(0.4) };
    for (int k = 0; k < N; k++) {
        double a = 0.2 + 1.2 * k / (N - 1);
        cx[k] = 2 + 30 * cos(a);
        cy[k] = 2 + 30 * sin(a);
    }
    static const double dash[2] = { 3, 6 };
    rs__band b[3] = { { 0, 0.12, { 255, 255, 255, 1 }, NULL, 0, 0 },
                      { 1.75, 0.3, { 255, 255, 255, 1 }, NULL, 0, 0 },
                      { -1.75, 0.15, { 255, 255, 255, 1 }, dash, 2, 1 } };
    uint32_t W = (uint32_t)(34 / pix), H = W;
    memset(out, 0, sizeof *out);
    for (int scene = 0; scene < 2; scene++) {
        const double *x = scene ? sx : cx, *y = scene ? sy : cy;
        size_t n = scene ? 2 : N;
        bandref_line rl;
        bandref_init(&rl, x, y, n);
        rs_roads *roads;
        double xy[2 * N];
        for (size_t k = 0; k < n; k++) xy[2 * k] = x[k], xy[2 * k + 1] = y[k];
        if (rs_roads_create(ctx, &roads) || rs_roads_add(ctx, roads, NULL, 7, xy, n)) return -1;
        uint32_t bs[2] = { 0, 3 };
        rs__linesym_params p;
        memset(&p, 0, sizeof p);
        p.cell_size = 1;
        p.out_w = W;
        p.out_h = H;
        p.pixel = pix;
        p.aa = aa;
        rs__linesym *L;
        if (rs__linesym_build(ctx, roads, &p, bs, b, &L)) return -1;
        double *cov = malloc(sizeof(double) * W * H);
        if (!cov) return -1;
        for (uint32_t bi = 0; bi < 3; bi++) {
            rs__linesym_coverage(L, bi, 0, 0, W, H, cov, W);
            double reach = fabs(b[bi].t) + 0.5 * b[bi].w + pix, inner = fabs(b[bi].t) - 0.5 * b[bi].w - pix;
            for (uint32_t py = 0; py < H; py++)
                for (uint32_t px = 0; px < W; px++) {
                    double c = cov[(size_t)py * W + px];
                    double dmin = bandref_dist(&rl, (px + 0.5) * pix, (py + 0.5) * pix);
                    if (dmin > reach || dmin < inner) continue;
                    double g = bandref_cover(&rl, &b[bi], pix, px, py, REF_N), e = fabs(c - g);
                    if (!((c > 0 && c < 1) || (g > 0 && g < 1))) continue;
                    out->sum += e;
                    out->n++;
                    if (e > out->max) out->max = e;
                }
        }
        free(cov);
        rs__linesym_free(ctx, L);
        rs_roads_free(ctx, roads);
    }
    return 0;
}

/* --- issue 29 target 1: styled city against Cairo ------------------------ */

/* The target's styling on every road: a 0.5 m casing, solid edge lines
 * 0.12 m wide 0.25 m inside the road edges, a dashed centre line (0.15 m,
 * 6/12 m) and a flat asphalt fill; one style per distinct width (the edge
 * lines' offsets follow the width). tests/bench/styles_cairo.py draws the
 * same with Cairo: keep the constants equal. */
#define T1_CASING 0.5
#define T1_EDGE_IN 0.25
#define T1_EDGE_W 0.12

/* Rounds of ours then Cairo's, alternating (make bench): a burst of load
 * on this shared machine then slows one round of both, not one side. */
#define T1_ROUNDS 5

typedef struct t1_result {
    double build_ms, splat_ms, cairo_ms;
    int nround;                  /* rounds run (0 without Cairo) */
    double round_ratio[T1_ROUNDS]; /* per round: (its fastest build + splat) / its Cairo */
    size_t nstyles;
    rs_splat_profile prof; /* the fastest splat's stages (styles --t1 only) */
    uint64_t hash;         /* FNV-1a of the last splat's bytes: two builds' outputs compared */
} t1_result;

/* The fastest of N Cairo drawings (the script prints it), or < 0 when
 * python3-cairo is missing. */
static double t1_cairo_ms(const char *roads_path)
{
    char args[2048];
    snprintf(args, sizeof args, "tests/bench/styles_cairo.py '%s' 4 10", roads_path);
    return tm_python_ms(args);
}

static int t1_run(rs_ctx *ctx, const char *dir, const sc_scene *sc, const rs_dem *dem, const rs_splat_options *base,
                  int reps, t1_result *out)
{
    size_t cap = 1 << 16, len = 0, nst = 0;
    char *text = malloc(cap);
    double *wid = malloc(sc->nroads * sizeof *wid);
    rs_roads *roads = NULL;
    rs_styles *styles = NULL;
    uint8_t *rgba = NULL;
    int rc = -1;
    if (!text || !wid || rs_roads_create(ctx, &roads)) goto done;
    for (size_t i = 0; i < sc->nroads; i++) {
        const sc_road *r = &sc->roads[i];
        size_t k = 0;
        while (k < nst && wid[k] != r->width) k++;
        if (k == nst) {
            double x = r->width / 2 - T1_EDGE_IN;
            if (len + 512 > cap) {
                char *t = realloc(text, cap *= 2);
                if (!t) goto done;
                text = t;
            }
            len += (size_t)snprintf(text + len, cap - len,
                                    "style w%zu\n fill #383838\n casing %.17g #A0A0A0\n"
                                    " line 0 0.15 #FFFFFF dash 6 12\n line %.17g %.17g #FFFFFF\n"
                                    " line %.17g %.17g #FFFFFF\nend\n",
                                    k, T1_CASING, x, T1_EDGE_W, -x, T1_EDGE_W);
            wid[nst++] = r->width;
        }
        char name[32];
        snprintf(name, sizeof name, "w%zu", k);
        if (rs_roads_add(ctx, roads, NULL, r->width, r->xy, r->n) ||
            rs_roads_set_attr(ctx, roads, i, "style", name))
            goto done;
    }
    if (rs_styles_parse(ctx, text, len, &styles)) goto done;
    rs_splat_options o = *base;
    o.style.styles = styles;
    out->build_ms = out->splat_ms = 1e300;
    out->nstyles = nst;
    uint32_t w = 0, h = 0;
    char path[1024];
    out->cairo_ms = -1;
    out->nround = 0;
    if (dir) {
        snprintf(path, sizeof path, "%s/styles_roads.txt", dir);
        if (sc_write_plain(path, sc)) goto done;
    }
    for (int round = 0; round < (dir ? T1_ROUNDS : 1); round++) {
        double rb = 1e300, rs = 1e300; /* this round's fastest build and splat */
        for (int run = 0; run < reps; run++) {
            rs_splatter *s = NULL;
            double t0 = tm_now_ms();
            if (rs_splatter_create(ctx, dem, roads, NULL, &o, &s)) goto done;
            double b = tm_now_ms() - t0;
            out->build_ms = b < out->build_ms ? b : out->build_ms;
            rb = b < rb ? b : rb;
            rs_splatter_size(s, &w, &h);
            if (!rgba && !(rgba = malloc((size_t)w * h * 4))) {
                rs_splatter_free(ctx, s);
                goto done;
            }
            for (int k = 0; k < 3; k++) {
                rs_splat_profile pf;
                memset(&pf, 0, sizeof pf);
                pf.clock_ms = clock_ms;
                t0 = tm_now_ms();
                if (rs_splat_window(ctx, s, 0, 0, w, h, rgba, (size_t)w * 4, NULL, 0, dir ? NULL : &pf)) {
                    rs_splatter_free(ctx, s);
                    goto done;
                }
                double t = tm_now_ms() - t0;
                if (t < out->splat_ms) out->prof = pf;
                out->splat_ms = t < out->splat_ms ? t : out->splat_ms;
                rs = t < rs ? t : rs;
            }
            rs_splatter_free(ctx, s);
        }
        if (dir) {
            double c = t1_cairo_ms(path);
            if (c > 0) {
                out->cairo_ms = out->cairo_ms > 0 && out->cairo_ms < c ? out->cairo_ms : c;
                out->round_ratio[out->nround++] = (rb + rs) / c;
            }
        }
    }
    out->hash = 1469598103934665603ull;
    for (size_t i = 0; rgba && i < (size_t)w * h * 4; i++) out->hash = (out->hash ^ rgba[i]) * 1099511628211ull;
    rc = 0;
done:
    if (rc) fprintf(stderr, "styles: target 1: %s\n", rs_ctx_message(ctx));
    free(rgba);
    rs_styles_free(ctx, styles);
    rs_roads_free(ctx, roads);
    free(wid);
    free(text);
    return rc;
}

/* --- scenes ------------------------------------------------------------------ */

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "build/bench";
    int t1_only = argc == 3 && strcmp(argv[1], "--t1") == 0, t1_reps = t1_only ? atoi(argv[2]) : 0;
    int cases_only = argc >= 2 && strcmp(argv[1], "--cases") == 0;
    int only = cases_only && argc == 3 ? atoi(argv[2]) : -1; /* styles --cases I: that case alone (0 .. NC - 1) */
    if (t1_only && t1_reps < 1) { fprintf(stderr, "usage: styles --t1 REPS (REPS >= 1)\n"); return 2; }
    rs_ctx *ctx;
    if (rs_ctx_create(NULL, NULL, &ctx)) return 1;
    sc_scene sc;
    rs_dem *dem;
    rs_roads *plain, *classed, *lined;
    if (sc_city_default(&sc, 1) || rs_dem_create(ctx, sc.w, sc.h, sc.z, &dem) || rs_roads_create(ctx, &plain) ||
        rs_roads_create(ctx, &classed) || rs_roads_create(ctx, &lined))
        return 1;
    size_t nprim = 0, nres = 0, nsrv = 0;
    for (size_t i = 0; i < sc.nroads; i++) {
        const sc_road *r = &sc.roads[i];
        if (rs_roads_add(ctx, plain, NULL, r->width, r->xy, r->n) ||
            rs_roads_add(ctx, classed, NULL, r->width, r->xy, r->n) ||
            rs_roads_add(ctx, lined, NULL, r->width, r->xy, r->n))
            return 1;
        const char *c = sc_city_class(r->width);
        nprim += c[0] == 'p';
        nres += c[0] == 'r';
        nsrv += c[0] == 's';
        if (rs_roads_set_attr(ctx, classed, i, "class", c) || rs_roads_set_attr(ctx, classed, i, "lanes", "2") ||
            rs_roads_set_attr(ctx, lined, i, "style", "lines"))
            return 1;
    }
    rs_dem_frame fc = { sc.cell_size, 0.01, 0, 0 };
    if (rs_dem_set_frame(ctx, dem, &fc)) return 1;
    /* the same three lines solid and dashed (German RMS widths and a 6/12 m dash) */
    static const char solid_text[] = "style lines\n line 0 0.15 #FFFFFF\n line 1.6 0.12 #FFFFFF\n"
                                     " line -1.6 0.12 #FFFFFF\nend\n";
    static const char dashed_text[] = "style lines\n line 0 0.15 #FFFFFF dash 6 12\n"
                                      " line 1.6 0.12 #FFFFFF dash 6 12 phase 3\n"
                                      " line -1.6 0.12 #FFFFFF dash 6 12 phase 9\nend\n";
    rs_styles *solid, *dashed;
    if (rs_styles_parse(ctx, solid_text, sizeof solid_text - 1, &solid) ||
        rs_styles_parse(ctx, dashed_text, sizeof dashed_text - 1, &dashed))
        return 1;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 4;
    if (t1_only) {
        t1_result t;
        if (t1_run(ctx, NULL, &sc, dem, &o, t1_reps, &t)) return 1;
        printf("target 1: style build %.2f ms, splat %.2f ms (fastest; its coverage %.2f, surface %.2f, overlays %.2f, "
               "composite %.2f ms); bytes %016llx\n",
               t.build_ms, t.splat_ms, t.prof.coverage_ms, t.prof.surface_ms, t.prof.overlays_ms, t.prof.composite_ms,
               (unsigned long long)t.hash);
        return 0;
    }
    enum { C_PLAIN, C_CLASSED, C_HERMITE, C_MARKED, C_SOLID, C_DASHED, NC };
    scase k[NC] = { { "unstyled", NULL, 1e300, 1e300, { 0 } },
                    { "default class styles (RMS), exact lines", NULL, 1e300, 1e300, { 0 } },
                    { "default class styles (RMS), Hermite lines", NULL, 1e300, 1e300, { 0 } },
                    { "default class styles (RMS), exact lines, and automatic markings", NULL, 1e300, 1e300, { 0 } },
                    { "three solid lines on every road", NULL, 1e300, 1e300, { 0 } },
                    { "the same lines dashed 6/12 m", NULL, 1e300, 1e300, { 0 } } };
    rs_splat_options oc[NC];
    for (int i = 0; i < NC; i++) oc[i] = o;
    oc[C_HERMITE].style.aa = RS_LINE_AA_HERMITE;
    /* the styles alone: the classes also bring automatic markings (give-way
     * lines where a lower class meets a higher one; issue 14, its own
     * benchmark tests/bench/markings.c), shown in their own row */
    oc[C_CLASSED].markings.no_auto = 1;
    oc[C_HERMITE].markings.no_auto = 1;
    oc[C_SOLID].style.styles = solid;
    oc[C_DASHED].style.styles = dashed;
    const rs_roads *rr[NC] = { plain, classed, classed, classed, lined, lined };
    double build_ms[NC];
    for (int i = 0; i < NC; i++) {
        double t0 = tm_now_ms();
        if (rs_splatter_create(ctx, dem, rr[i], NULL, &oc[i], &k[i].s)) {
            fprintf(stderr, "styles: %s\n", rs_ctx_message(ctx));
            return 1;
        }
        build_ms[i] = tm_now_ms() - t0;
    }
    uint32_t w, h;
    rs_splatter_size(k[0].s, &w, &h);
    uint8_t *rgba = malloc((size_t)w * h * 4);
    if (!rgba) return 1;
    if (only >= NC) only = -1;
    for (int run = 0; run < (only >= 0 ? 4 * RUNS : RUNS); run++)
        for (int i = 0; i < NC; i++)
            if ((only < 0 || i == only) && run_once(ctx, &k[i], rgba, w, h)) return 1;
    if (cases_only) {
        for (int i = 0; i < NC; i++) {
            if (only >= 0 && i != only) continue;
            printf("%-70s %6.2f ms (coverage %.2f, surface %.2f, overlays %.2f, composite %.2f)", k[i].name, k[i].ms,
                   k[i].prof.coverage_ms, k[i].prof.surface_ms, k[i].prof.overlays_ms, k[i].prof.composite_ms);
            if (only < 0) printf(" / unstyled %.3f", k[i].ms / k[0].ms);
            printf("\n");
        }
        return 0;
    }

    acc ex[2], he[2];
    const double pixes[2] = { 1.25, 0.1 };
    for (int i = 0; i < 2; i++)
        if (accuracy(ctx, RS__AA_EXACT, pixes[i], &ex[i]) || accuracy(ctx, RS__AA_HERMITE, pixes[i], &he[i])) return 1;

    t1_result t1;
    if (t1_run(ctx, dir, &sc, dem, &o, 5, &t1)) return 1;

    FILE *md, *csv;
    if (tm_open_section(dir, "styles", &md, &csv)) return 1;
    double ratio_city = k[C_CLASSED].ms / k[C_PLAIN].ms, ratio_dash_ov = k[C_DASHED].ov_ms / k[C_SOLID].ov_ms,
           ratio_dash = k[C_DASHED].ms / k[C_SOLID].ms;
    fprintf(md,
            "## Road styles and line symbols (tests/bench/styles.c)\n\n"
            "City scene `sc_city_default(1)` (%zu roads, z-scale 0.01) at 4 texels: %u x %u pixels of 1.25 m. "
            "`rs_splat_window` over the whole image on a prepared splatter, one thread, fastest of %d runs, the "
            "cases interleaved run by run; overlays = the stage that draws casings (whose coverage the analytic "
            "coverage stage computes beside the road's: see coverage in the splat time), fills, lines and markings "
            "(rs_splat_profile). Classes by width for the styled case: >= 12 m `primary` (%zu roads: dashed centre "
            "line, edge lines), >= 6 m `residential` (%zu: kerb casing), else `service` (%zu: kerb), all "
            "`lanes=2`. The classes also place automatic markings (give-way lines where a lower class ends on a "
            "higher one; issue 14, benchmarked in tests/bench/markings.c): the style rows leave them out "
            "(`markings.no_auto`), the row \"and automatic markings\" has them.\n\n"
            "| case | splat ms | overlays ms | / unstyled | grid + styles build ms |\n|---|---|---|---|---|\n",
            sc.nroads, w, h, RUNS, nprim, nres, nsrv);
    fprintf(csv, "case,splat_ms,overlays_ms,build_ms\n");
    for (int i = 0; i < NC; i++) {
        fprintf(md, "| %s | %.1f | %.1f | %.2f | %.1f |\n", k[i].name, k[i].ms, k[i].ov_ms, k[i].ms / k[0].ms,
                build_ms[i]);
        fprintf(csv, "%s,%.3f,%.3f,%.3f\n", k[i].name, k[i].ms, k[i].ov_ms, build_ms[i]);
    }
    fprintf(md,
            "\nLine anti-aliasing against a supersampled reference (%d x %d point samples per pixel of the SPEC "
            "band; lib/scene/linesym.c coverage of three lines 0.12-0.30 m wide, one dashed 3/6 m, on a curve and a "
            "straight road at 23 degrees); errors over the pixels where either value is strictly between 0 and 1 "
            "(the reference's own error is up to 1/%d):\n\n"
            "| pixel | exact: mean / max error | Hermite: mean / max error | pixels |\n|---|---|---|---|\n",
            REF_N, REF_N, 2 * REF_N);
    for (int i = 0; i < 2; i++)
        fprintf(md, "| %.2f m | %.4f / %.4f | %.4f / %.4f | %zu |\n", pixes[i], ex[i].sum / (double)ex[i].n,
                ex[i].max, he[i].sum / (double)he[i].n, he[i].max, ex[i].n);
    fprintf(md,
            "\nOverlays time with Hermite / exact lines on the city (same run): %.2f.\n\n"
            "| target (issue 13) | measured | |\n|---|---|---|\n"
            "| city, default class styles / unstyled splat <= 1.5x | %.2fx | %s |\n"
            "| dashed / solid line cost <= 1.2x (overlays stage) | %.2fx (whole splat %.2fx) | %s |\n"
            "| exact line error, mean <= 1/255, max <= 2/255 (vs the 16x16 reference; here %dx%d) | %.4f / %.4f | %s |\n",
            k[C_HERMITE].ov_ms / k[C_CLASSED].ov_ms, ratio_city, ratio_city <= 1.5 ? "met" : "**missed**",
            ratio_dash_ov, ratio_dash, ratio_dash_ov <= 1.2 ? "met" : "**missed**", REF_N, REF_N,
            fmax(ex[0].sum / (double)ex[0].n, ex[1].sum / (double)ex[1].n), fmax(ex[0].max, ex[1].max),
            fmax(ex[0].sum / (double)ex[0].n, ex[1].sum / (double)ex[1].n) <= 1.0 / 255 &&
                    fmax(ex[0].max, ex[1].max) <= 2.0 / 255
                ? "met"
                : "**missed**");
    double t1_ours = t1.build_ms + t1.splat_ms, t1_ratio = t1.cairo_ms > 0 ? t1_ours / t1.cairo_ms : -1;
    char cairo_cell[64], measured[160], rounds[160];
    double rmed = -1, rlo = 1e300, rhi = 0;
    size_t rl = 0;
    rounds[0] = 0;
    for (int i = 0; i < t1.nround; i++) {
        rlo = fmin(rlo, t1.round_ratio[i]), rhi = fmax(rhi, t1.round_ratio[i]);
        rl += (size_t)snprintf(rounds + rl, sizeof rounds - rl, "%s%.2f", i ? ", " : "", t1.round_ratio[i]);
        if (rl >= sizeof rounds) rl = sizeof rounds - 1;
    }
    if (t1.nround) {
        double tmp[T1_ROUNDS];
        memcpy(tmp, t1.round_ratio, sizeof tmp);
        rmed = tm_median(tmp, t1.nround);
    }
    if (t1_ratio < 0) {
        snprintf(cairo_cell, sizeof cairo_cell, "not run (no python3-cairo)");
        snprintf(measured, sizeof measured, "-");
    } else {
        snprintf(cairo_cell, sizeof cairo_cell, "%.1f", t1.cairo_ms);
        snprintf(measured, sizeof measured, "%.1f / %.1f ms = %.2fx; rounds' median %.2fx (%.2f-%.2f)", t1_ours,
                 t1.cairo_ms, t1_ratio, rmed, rlo, rhi);
    }
    fprintf(md,
            "\nIssue 29 target 1, the styled city against Cairo: every road gets a %.2g m casing, solid edge lines "
            "%.2g m wide %.2g m inside its edges, a dashed centre line (0.15 m, 6/12 m) and a flat fill (%zu styles, "
            "one per road width). roadsplat: style build (`rs_splatter_create`, fastest of 5 a round) + "
            "`rs_splat_window` of the whole texture, terrain included (fastest of 15 a round), one thread. "
            "Cairo (python3-cairo, tests/bench/styles_cairo.py): the same roads and styling into an ARGB32 "
            "image of the same pixels, strokes only (casings, surfaces, edge lines as a white and an asphalt "
            "stroke, dashed centre lines; layer by layer over all roads), fastest of 10 a round. The two "
            "alternate in %d rounds (ours, then Cairo's); "
            "the times are the fastest over all rounds, and each round's own ratio is given too (%s): one "
            "Cairo reading during a burst of load read up to 1.3x slower than the others here, so the target is "
            "met only when both the fastest times and the rounds' median are within it.\n\n"
            "| | ms |\n|---|---|\n| roadsplat style build | %.1f |\n| roadsplat splat | %.1f |\n"
            "| roadsplat build + splat | %.1f |\n| Cairo | %s |\n\n"
            "| target (issue 29) | measured | |\n|---|---|---|\n"
            "| 1. styled city, style build + splat, 1 thread <= 1.0x Cairo | %s | %s |\n",
            T1_CASING, T1_EDGE_W, T1_EDGE_IN, t1.nstyles, T1_ROUNDS, t1.nround ? rounds : "none", t1.build_ms,
            t1.splat_ms, t1_ours, cairo_cell, measured,
            t1_ratio < 0 ? "not measured" : t1_ratio <= 1.0 && rmed <= 1.0 ? "met" : "**missed**");
    fclose(md);
    fclose(csv);
    for (int i = 0; i < NC; i++) rs_splatter_free(ctx, k[i].s);
    free(rgba);
    rs_styles_free(ctx, solid);
    rs_styles_free(ctx, dashed);
    rs_roads_free(ctx, plain);
    rs_roads_free(ctx, classed);
    rs_roads_free(ctx, lined);
    rs_dem_free(ctx, dem);
    sc_scene_free(&sc);
    rs_ctx_free(ctx);
    printf("styles: city styled/unstyled %.2f, dashed/solid overlays %.2f (splat %.2f); target 1 styled city %s\n",
           ratio_city, ratio_dash_ov, ratio_dash, measured);
    return 0;
}
