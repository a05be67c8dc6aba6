/* Lanes per direction and left-hand traffic (issue 27 targets 4 and 5;
 * docs/road-format.md "Lanes"). Property tests on images at 0.1 m per
 * pixel, measured from the pixels alone: paint alpha = (C - C_plain) /
 * (white - C_plain) against the same scene drawn without lines and
 * markings, over a plain grey road texture.
 *
 * - arrows: each painted arrow's centroid within 0.1 m of the centre of a
 *   lane, the lanes measured from the painted lane, centre and edge lines;
 * - stop lines: from the painted centre line (+-0.1 m) to the kerb (the
 *   road edge, +-0.1 m), on the side of the arrows;
 * - give-way blocks (RMS 0.5 x 0.5 m, 0.25 m gaps) and zebra bars (0.5 m,
 *   0.5 m gaps) keep their size on roads of any width (+-0.02 m);
 * - mirror: a left-hand scene equals the mirrored right-hand scene;
 * - the lane queries (rs_road_lanes_get, rs_network_lanes_at).
 *
 * The property tests use only the API of main 449fdfd (driving_side as a
 * road attribute), so they build there and fail; the queries are new. */
#include "roadsplat.h"
#include "harness.h"
#include "gpu_scene_view.h"
#include "scene_splat.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static rs_ctx *ctx;

#define TEX 10   /* texels per 1 m cell: 0.1 m pixels */
#define PIX 0.1
#define WHITE 244.0 /* the green of the built-in markings and RMS lines */

typedef struct img {
    uint32_t w, h;
    uint8_t *rgba;
} img;

static const uint8_t grey_px[4] = { 60, 60, 60, 255 };

/* Render `text` over a flat dw x dh DEM (1 m cells): with lines and
 * markings (`paint`) or without either. */
static const rs_atlas *render_atlas; /* NULL: the built-in one */

/* the line anti-aliasing of render() (test_many_crossings sets Hermite for a while) */
static rs_line_aa render_aa = RS_LINE_AA_EXACT;
static rs_edge_mode render_edges = RS_EDGES_ANALYTIC;
static const rs_styles *render_styles; /* NULL: none but the classes' */

static int render(const char *text, uint32_t dw, uint32_t dh, rs_profile profile, int paint, int no_auto, img *im)
{
    float *z = calloc((size_t)dw * dh, sizeof *z);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    rs_image tex = { 1, 1, grey_px };
    int ok = z && rs_dem_create(ctx, dw, dh, z, &dem) == RS_OK &&
             rs_roads_parse(ctx, text, strlen(text), &roads) == RS_OK;
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = TEX;
    o.surface.road_texture = &tex;
    o.style.profile = profile;
    o.style.aa = render_aa;
    o.coverage.edges = render_edges;
    o.style.styles = render_styles;
    o.style.disable = !paint;
    o.markings.disable = !paint;
    o.markings.no_auto = no_auto;
    o.markings.atlas = render_atlas;
    memset(im, 0, sizeof *im);
    if (ok) ok = ss_splat_window(ctx, dem, roads, &o, &im->w, &im->h, &im->rgba) == RS_OK;
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
    free(z);
    return ok;
}

/* The largest difference of an RGB channel between a and b (the same size)
 * over columns [x0, x1) and rows [y0, y1). */
static int max_diff(const img *a, const img *b, uint32_t x0, uint32_t x1, uint32_t y0, uint32_t y1)
{
    int worst = 0;
    for (uint32_t y = y0; y < y1; y++)
        for (uint32_t x = x0; x < x1; x++)
            for (int c = 0; c < 3; c++) {
                size_t i = ((size_t)y * a->w + x) * 4 + c;
                int d = abs((int)a->rgba[i] - (int)b->rgba[i]);
                if (d > worst) worst = d;
            }
    return worst;
}

/* Paint alpha per pixel: `a` drawn with paint, `b` without. */
static double *paint_alpha(const img *a, const img *b)
{
    size_t n = (size_t)a->w * a->h;
    double *al = calloc(n ? n : 1, sizeof *al);
    for (size_t i = 0; al && i < n; i++) {
        double c = a->rgba[4 * i + 1], c0 = b->rgba[4 * i + 1];
        al[i] = WHITE - c0 > 20 ? (c - c0) / (WHITE - c0) : 0;
        if (al[i] < 0) al[i] = 0;
        if (al[i] > 1) al[i] = 1;
    }
    return al;
}

/* The paint of a scene: alpha with everything, with lines only (no
 * automatic markings: `lines`), both may be NULL. */
static int scene_paint(const char *text, uint32_t dw, uint32_t dh, rs_profile profile, double **all, double **lines,
                       uint32_t *w, uint32_t *h)
{
    img plain, full, nomark;
    int ok = render(text, dw, dh, profile, 0, 0, &plain) && render(text, dw, dh, profile, 1, 0, &full) &&
             render(text, dw, dh, profile, 1, 1, &nomark);
    if (ok) {
        *w = plain.w;
        *h = plain.h;
        if (all) *all = paint_alpha(&full, &plain);
        if (lines) *lines = paint_alpha(&nomark, &plain);
    }
    free(plain.rgba);
    free(full.rgba);
    free(nomark.rgba);
    return ok;
}

/* Runs of alpha > 0.01 along a row (dx = 1) or a column of `a`, within
 * pixel indices [i0, i1): each run's extent (the partial end pixels
 * counted by their alpha), painted width (sum of alpha x pixel) and
 * centroid, in metres. */
typedef struct run {
    double lo, hi, width, centre;
} run;

static int runs(const double *a, uint32_t w, int along_row, uint32_t fixed, uint32_t i0, uint32_t i1, run *out,
                int cap)
{
    int n = 0;
    uint32_t i = i0;
    while (i < i1) {
#define AT(k) (along_row ? a[(size_t)fixed * w + (k)] : a[(size_t)(k) * w + fixed])
        if (AT(i) <= 0.01) { i++; continue; }
        uint32_t j = i;
        double sum = 0, mom = 0;
        while (j < i1 && AT(j) > 0.01) {
            sum += AT(j);
            mom += AT(j) * (j + 0.5) * PIX;
            j++;
        }
        if (n < cap) {
            out[n].lo = (i + 1 - AT(i)) * PIX;
            out[n].hi = (j - 1 + AT(j - 1)) * PIX;
            out[n].width = sum * PIX;
            out[n].centre = mom / sum;
        }
        n++;
        i = j;
#undef AT
    }
    return n;
}

/* A secondary road of 3 lanes (2 towards the junction) meeting a primary
 * road at a T; its lines, arrows and stop line. DEM 61 x 41: the side road
 * runs north from (30, 40) to the main road's centre line at y = 20. */
/* The row (by_row) or column of `a` (w wide) in [i0, i1) with the most
 * paint over columns (rows) [j0, j1), and that paint (*sum). */
static uint32_t most_paint(const double *a, uint32_t w, int by_row, uint32_t i0, uint32_t i1, uint32_t j0, uint32_t j1,
                           double *sum)
{
    uint32_t best = i0;
    double bs = 0;
    for (uint32_t i = i0; i < i1; i++) {
        double t = 0;
        for (uint32_t j = j0; j < j1; j++) t += by_row ? a[(size_t)i * w + j] : a[(size_t)j * w + i];
        if (t > bs) bs = t, best = i;
    }
    if (sum) *sum = bs;
    return best;
}

static const char lanes_scene[] =
    "road main width 8 class=primary area=rural\n0 20\n60 20\nend\n"
    "road side width 10.5 class=secondary area=rural lanes=3 lanes:forward=2 turn:lanes=through|through "
    "control=stop\n30 40\n30 20\nend\n";

static void test_arrows_and_stop_line(void)
{
    double *all = NULL, *lines = NULL;
    uint32_t w = 0, h = 0;
    CHECK(scene_paint(lanes_scene, 61, 41, RS_PROFILE_RMS, &all, &lines, &w, &h));
    if (!all || !lines) return;
    /* the lines across the side road at y = 38 m (no markings there) */
    run L[8];
    int nl = runs(lines, w, 1, 380, 240, 360, L, 8);
    CHECK_EQ_INT(nl, 4); /* edge, two lane/centre lines, edge */
    if (nl != 4) goto done;
    /* lane boundaries: the inner edges of the edge lines, the centres of the others */
    double b[4] = { L[0].centre + L[0].width / 2, L[1].centre, L[2].centre, L[3].centre - L[3].width / 2 };
    for (int k = 0; k < 3; k++) CHECKF(b[k + 1] - b[k] > 3.0, "lane %d is %.3f m wide", k, b[k + 1] - b[k]);
    /* markings = all paint minus the lines */
    size_t n = (size_t)w * h;
    double *mk = malloc(n * sizeof *mk);
    for (size_t i = 0; i < n; i++) mk[i] = all[i] - lines[i] > 0.01 ? all[i] - lines[i] : 0;
    /* arrows: between y = 28 and 37 m; centroid per lane */
    double sx[3] = { 0, 0, 0 }, sa[3] = { 0, 0, 0 };
    for (uint32_t y = 280; y < 370; y++)
        for (uint32_t x = 240; x < 360; x++) {
            double a = mk[(size_t)y * w + x], xc = (x + 0.5) * PIX;
            for (int k = 0; k < 3; k++)
                if (xc > b[k] && xc < b[k + 1]) sx[k] += a * xc, sa[k] += a;
        }
    int arrows = 0, bare = -1;
    for (int k = 0; k < 3; k++) {
        if (sa[k] * PIX * PIX < 0.5) { bare = k; continue; } /* an arrow paints about 1.3 m^2 */
        arrows++;
        double c = sx[k] / sa[k], want = (b[k] + b[k + 1]) / 2;
        CHECKF(fabs(c - want) <= 0.1, "arrow in lane %d: centroid x %.3f m, lane centre %.3f m", k, c, want);
        printf("arrow in lane %d: centroid %.4f m from the lane centre\n", k, c - want);
    }
    CHECK_EQ_INT(arrows, 2);
    CHECK(bare == 0 || bare == 2); /* the lane without an arrow is the outer one of the other direction */
    /* the stop line: the marking row with the most paint between y = 20 and 28 m */
    uint32_t best = most_paint(mk, w, 1, 200, 280, 240, 360, NULL);
    /* all paint on that row: the stop line with the lines it crosses, one
     * run (a stop line short of the centre line leaves a gap); the widest */
    run S[8];
    int ns = runs(all, w, 1, best, 240, 360, S, 8), wi = 0;
    for (int i = 1; i < ns && i < 8; i++)
        if (S[i].width > S[wi].width) wi = i;
    CHECK(ns >= 1 && S[wi].width > 3);
    if (ns >= 1 && bare >= 0) {
        /* from the centre line to the kerb on the arrows' side */
        double centre = bare == 0 ? L[1].centre : L[2].centre;
        double kerb = bare == 0 ? 30 + 5.25 : 30 - 5.25;
        double near = bare == 0 ? S[wi].lo : S[wi].hi, far = bare == 0 ? S[wi].hi : S[wi].lo;
        CHECKF(fabs(near - centre) <= 0.1, "stop line starts at %.3f m, the centre line is at %.3f m", near, centre);
        CHECKF(fabs(far - kerb) <= 0.1, "stop line ends at %.3f m, the kerb is at %.3f m", far, kerb);
        printf("stop line: %.3f .. %.3f m; centre line %.3f, kerb %.3f\n", S[wi].lo, S[wi].hi, centre, kerb);
    }
    free(mk);
done:
    free(all);
    free(lines);
}

/* Give-way blocks on side roads of four widths, zebra bars on main roads of
 * three: each element 0.5 m (+-0.02) across, gaps 0.25 / 0.5 m. */
static void test_standard_sizes(void)
{
    static const double widths[] = { 5.5, 7, 9, 11 };
    for (int k = 0; k < 4; k++) {
        char text[512];
        snprintf(text, sizeof text,
                 "road main width 10 class=primary area=rural\n0 20\n60 20\nend\n"
                 "road side width %g class=residential\n30 40\n30 20\nend\n",
                 widths[k]);
        double *all = NULL, *lines = NULL;
        uint32_t w = 0, h = 0;
        CHECK(scene_paint(text, 61, 41, RS_PROFILE_RMS, &all, &lines, &w, &h));
        if (!all || !lines) continue;
        /* the markings alone (the kerbs are lines' business); the block row:
         * the row with the most marking paint (y 25 .. 35 m) */
        for (size_t i = 0; i < (size_t)w * h; i++) all[i] = all[i] - lines[i] > 0.01 ? all[i] - lines[i] : 0;
        uint32_t best = most_paint(all, w, 1, 250, 350, 200, 400, NULL);
        run B[32];
        int nb = runs(all, w, 1, best, 200, 400, B, 32);
        CHECKF(nb >= 2 && nb <= 32, "width %g: %d blocks", widths[k], nb);
        for (int i = 0; i < nb && i < 32; i++) {
            CHECKF(fabs(B[i].width - 0.5) <= 0.02, "width %g: block %d is %.3f m across", widths[k], i, B[i].width);
            if (i) CHECKF(fabs(B[i].lo - B[i - 1].hi - 0.25) <= 0.02, "width %g: gap %.3f m", widths[k],
                          B[i].lo - B[i - 1].hi);
            /* along the road: 0.5 m */
            run A[4];
            uint32_t col = (uint32_t)(B[i].centre / PIX);
            int na = runs(all, w, 0, col, best - 20, best + 20, A, 4);
            CHECKF(na == 1 && fabs(A[0].width - 0.5) <= 0.02, "width %g: block %d is %.3f m along", widths[k], i,
                   na ? A[0].width : 0);
        }
        free(all);
        free(lines);
    }
    static const double zw[] = { 6, 8, 10.5 };
    for (int k = 0; k < 3; k++) {
        char text[256];
        snprintf(text, sizeof text, "road main width %g class=residential\n0 20\n30 20 crossing=zebra\n60 20\nend\n",
                 zw[k]);
        double *all = NULL, *lines = NULL;
        uint32_t w = 0, h = 0;
        CHECK(scene_paint(text, 61, 41, RS_PROFILE_RMS, &all, &lines, &w, &h));
        if (!all || !lines) continue;
        for (size_t i = 0; i < (size_t)w * h; i++) all[i] = all[i] - lines[i] > 0.01 ? all[i] - lines[i] : 0;
        run Z[32];
        int nz = runs(all, w, 0, 300, 100, 300, Z, 32);
        int want = (int)floor((zw[k] - 0.4 + 0.5) / 1.0);
        CHECKF(nz == want, "zebra on %g m: %d bars, want %d", zw[k], nz, want);
        for (int i = 0; i < nz && i < 32; i++) {
            CHECKF(fabs(Z[i].width - 0.5) <= 0.02, "zebra on %g m: bar %d is %.3f m", zw[k], i, Z[i].width);
            if (i) CHECKF(fabs(Z[i].lo - Z[i - 1].hi - 0.5) <= 0.02, "zebra on %g m: gap %.3f", zw[k],
                          Z[i].lo - Z[i - 1].hi);
        }
        free(all);
        free(lines);
    }
}

/* Lane lines end at the stop line and are interrupted at a zebra. The
 * lines are measured with the markings drawn from an atlas of the same
 * sizes whose sprites are transparent (so the automatic markings are
 * placed, and cut the lines, but paint nothing); the stop line's edge
 * from the built-in atlas. */
static const char line_ends_one[] =
    "road main width 12 class=primary area=rural lanes=4\n0 20\n10 20 crossing=zebra\n60 20\nend\n"
    "road side width 12 class=secondary area=rural lanes=4 control=stop\n30 40\n30 20\nend\n";
/* the main road in two records meeting in a straight line (one stroke,
 * drawn as one polyline without the joint): the zebra's cut still applies */
static const char line_ends_split[] =
    "road main width 12 class=primary area=rural lanes=4\n0 20\n10 20 crossing=zebra\n45 20\nend\n"
    "road main width 12 class=primary area=rural lanes=4\n45 20\n60 20\nend\n"
    "road side width 12 class=secondary area=rural lanes=4 control=stop\n30 40\n30 20\nend\n";

static void test_line_ends(const char *text)
{
    static uint8_t clear[8 * 8 * 4];
    static const char index[] = "stop_line 0 0 8 8 0.5 3.5\ngive_way_line 0 0 8 8 0.5 3.5\n"
                                "give_way_block 0 0 8 8 0.5 0.5\nzebra_bar 0 0 8 8 4 0.5\n";
    rs_image im = { 8, 8, clear };
    rs_atlas *atlas = NULL;
    CHECK(rs_atlas_create(ctx, &im, index, sizeof index - 1, &atlas) == RS_OK);
    double *real = NULL, *lines = NULL, *cut = NULL;
    uint32_t w = 0, h = 0;
    CHECK(scene_paint(text, 61, 41, RS_PROFILE_RMS, &real, &lines, &w, &h));
    render_atlas = atlas;
    CHECK(scene_paint(text, 61, 41, RS_PROFILE_RMS, &cut, NULL, &w, &h));
    render_atlas = NULL;
    if (!real || !lines || !cut) goto done;
    {
        /* the side road's solid centre line (4 lanes) at x = 30 m: where it
         * ends towards the junction */
        run C[8];
        int nc = runs(cut, w, 0, 300, 205, 400, C, 8);
        CHECK(nc >= 1);
        /* the stop line's edge towards the drivers: the stop line alone
         * (real minus the lines) in the middle of the outer approach lane */
        size_t n = (size_t)w * h;
        double *mk = malloc(n * sizeof *mk);
        for (size_t i = 0; i < n; i++) mk[i] = real[i] - lines[i] > 0.01 ? real[i] - lines[i] : 0;
        run S[8];
        int ns = runs(mk, w, 0, 300 + 45, 205, 300, S, 8); /* x = 34.5 m: the outer forward lane (t < 0) */
        CHECK(ns >= 1);
        if (nc >= 1 && ns >= 1) {
            double end = C[0].lo, edge = S[ns - 1].hi;
            CHECKF(fabs(end - edge) <= 0.1, "the centre line ends at y = %.3f m, the stop line's edge is at %.3f m",
                   end, edge);
            printf("line end: centre line ends at y = %.3f m, stop line edge %.3f m\n", end, edge);
        }
        free(mk);
        /* the main road's centre line at y = 20 m: a gap over the zebra
         * (x = 8 .. 12 m) and none elsewhere before the junction; the edge
         * lines run on */
        run Z[8];
        int nz = runs(cut, w, 1, 200, 0, 230, Z, 8);
        CHECKF(nz == 2, "%d runs of the centre line", nz);
        if (nz == 2) {
            CHECKF(fabs(Z[0].hi - 8) <= 0.1 && fabs(Z[1].lo - 12) <= 0.1, "centre line gap %.3f .. %.3f m", Z[0].hi,
                   Z[1].lo);
            printf("zebra: centre line gap %.3f .. %.3f m (the zebra: 8 .. 12 m)\n", Z[0].hi, Z[1].lo);
        }
        for (uint32_t y = 140; y < 260; y++) {
            int edge_row = 0;
            for (uint32_t x = 0; x < 230; x++) edge_row += lines[(size_t)y * w + x] > 0.9;
            if (edge_row < 225) continue; /* a solid line the whole way in the lines alone: an edge or centre line */
            int cut_row = 0;
            for (uint32_t x = 0; x < 230; x++) cut_row += cut[(size_t)y * w + x] > 0.9;
            if (y > 150 && y < 250 && (y < 195 || y > 205)) CHECKF(cut_row >= 225, "edge line row %u cut (%d px)", y, cut_row);
        }
    }
done:
    free(real);
    free(lines);
    free(cut);
    rs_atlas_free(ctx, atlas);
}

/* Markings across a split (issue 27 target 1): the side road of
 * lanes_scene split into two records before the junction, at 7 m (its
 * arrows wholly on the record before the short one that reaches the
 * junction) and at 13 m from the main road's centre line (the arrows
 * across the split), and in three records; every pixel within 8/255 of
 * the unsplit road; and a side road on a 20 m arc split at 13.6 m from
 * its end (the arrow across the split, on the bend; then with the first
 * record pointing the other way). Before, the arrows vanished (the
 * automatic rules dropped a placement past its record's end); then, on
 * the bend, they ran on along the record's end tangent. */
static void test_markings_split(void)
{
    static const char *const split[] = {
        "road main width 8 class=primary area=rural\n0 20\n60 20\nend\n"
        "road side width 10.5 class=secondary area=rural lanes=3 lanes:forward=2 turn:lanes=through|through "
        "control=stop\n30 40\n30 27\nend\n"
        "road side width 10.5 class=secondary area=rural lanes=3 lanes:forward=2 turn:lanes=through|through "
        "control=stop\n30 27\n30 20\nend\n",
        "road main width 8 class=primary area=rural\n0 20\n60 20\nend\n"
        "road side width 10.5 class=secondary area=rural lanes=3 lanes:forward=2 turn:lanes=through|through "
        "control=stop\n30 40\n30 33\nend\n"
        "road side width 10.5 class=secondary area=rural lanes=3 lanes:forward=2 turn:lanes=through|through "
        "control=stop\n30 33\n30 20\nend\n",
        /* three records of a two-way street with one lane each way, the
         * middle one pointing the other way (its forward is the street's
         * backward), the arrow across the short one */
        "road main width 8 class=primary area=rural\n0 20\n60 20\nend\n"
        "road side width 7 class=secondary area=rural lanes=2 turn:lanes:forward=through;right "
        "control=stop\n30 40\n30 32\nend\n"
        "road side width 7 class=secondary area=rural lanes=2 turn:lanes:backward=through;right "
        "control=stop\n30 29\n30 32\nend\n"
        "road side width 7 class=secondary area=rural lanes=2 turn:lanes:forward=through;right "
        "control=stop\n30 29\n30 20\nend\n",
    };
    static const char curved_whole[] = "road main width 8 class=primary area=rural\n0 20\n60 20\nend\nroad side width 7 class=secondary area=rural lanes=2 turn:lanes:forward=through;right control=stop\n10.000000 40.000000\n11.046719 39.972591\n12.090569 39.890438\n13.128689 39.753767\n14.158234 39.562952\n15.176381 39.318517\n16.180340 39.021130\n17.167359 38.671609\n18.134733 38.270909\n19.079810 37.820130\n20.000000 37.320508\n20.892781 36.773411\n21.755705 36.180340\n22.586408 35.542919\n23.382612 34.862897\n24.142136 34.142136\n24.862897 33.382612\n25.542919 32.586408\n26.180340 31.755705\n26.773411 30.892781\n27.320508 30.000000\n27.820130 29.079810\n28.270909 28.134733\n28.671609 27.167359\n29.021130 26.180340\n29.318517 25.176381\n29.562952 24.158234\n29.753767 23.128689\n29.890438 22.090569\n29.972591 21.046719\n30.000000 20.000000\nend\n";
    static const char *const curved[] = { "road main width 8 class=primary area=rural\n0 20\n60 20\nend\nroad side width 7 class=secondary area=rural lanes=2 turn:lanes:forward=through;right control=stop\n10.000000 40.000000\n11.046719 39.972591\n12.090569 39.890438\n13.128689 39.753767\n14.158234 39.562952\n15.176381 39.318517\n16.180340 39.021130\n17.167359 38.671609\n18.134733 38.270909\n19.079810 37.820130\n20.000000 37.320508\n20.892781 36.773411\n21.755705 36.180340\n22.586408 35.542919\n23.382612 34.862897\n24.142136 34.142136\n24.862897 33.382612\n25.542919 32.586408\nend\nroad side width 7 class=secondary area=rural lanes=2 turn:lanes:forward=through;right control=stop\n25.542919 32.586408\n26.180340 31.755705\n26.773411 30.892781\n27.320508 30.000000\n27.820130 29.079810\n28.270909 28.134733\n28.671609 27.167359\n29.021130 26.180340\n29.318517 25.176381\n29.562952 24.158234\n29.753767 23.128689\n29.890438 22.090569\n29.972591 21.046719\n30.000000 20.000000\nend\n", "road main width 8 class=primary area=rural\n0 20\n60 20\nend\nroad side width 7 class=secondary area=rural lanes=2 turn:lanes:backward=through;right control=stop\n25.542919 32.586408\n24.862897 33.382612\n24.142136 34.142136\n23.382612 34.862897\n22.586408 35.542919\n21.755705 36.180340\n20.892781 36.773411\n20.000000 37.320508\n19.079810 37.820130\n18.134733 38.270909\n17.167359 38.671609\n16.180340 39.021130\n15.176381 39.318517\n14.158234 39.562952\n13.128689 39.753767\n12.090569 39.890438\n11.046719 39.972591\n10.000000 40.000000\nend\nroad side width 7 class=secondary area=rural lanes=2 turn:lanes:forward=through;right control=stop\n25.542919 32.586408\n26.180340 31.755705\n26.773411 30.892781\n27.320508 30.000000\n27.820130 29.079810\n28.270909 28.134733\n28.671609 27.167359\n29.021130 26.180340\n29.318517 25.176381\n29.562952 24.158234\n29.753767 23.128689\n29.890438 22.090569\n29.972591 21.046719\n30.000000 20.000000\nend\n" };
    static const char two_way[] = "road main width 8 class=primary area=rural\n0 20\n60 20\nend\n"
                                  "road side width 7 class=secondary area=rural lanes=2 "
                                  "turn:lanes:forward=through;right control=stop\n30 40\n30 20\nend\n";
    const size_t nsplit = sizeof split / sizeof *split, ncase = nsplit + sizeof curved / sizeof *curved;
    for (size_t c = 0; c < ncase; c++) {
        const char *ref = c < 2 ? lanes_scene : c < nsplit ? two_way : curved_whole;
        const char *text = c < nsplit ? split[c] : curved[c - nsplit];
        img one, none, sp;
        CHECK(render(ref, 61, 41, RS_PROFILE_RMS, 1, 0, &one));
        CHECK(render(ref, 61, 41, RS_PROFILE_RMS, 1, 1, &none));
        /* the unsplit scene has its arrows: the automatic markings change pixels */
        size_t differ = 0;
        for (size_t i = 0; one.rgba && none.rgba && i < (size_t)one.w * one.h * 4; i++)
            differ += one.rgba[i] != none.rgba[i];
        CHECK(differ > 1000);
        free(none.rgba);
        CHECK(render(text, 61, 41, RS_PROFILE_RMS, 1, 0, &sp));
        if (!one.rgba || !sp.rgba || sp.w != one.w || sp.h != one.h) {
            free(sp.rgba);
            free(one.rgba);
            continue;
        }
        int worst = 0;
        size_t at = 0;
        for (size_t i = 0; i < (size_t)one.w * one.h * 4; i++) {
            int d = abs((int)one.rgba[i] - (int)sp.rgba[i]);
            if (d > worst) worst = d, at = i / 4;
        }
        CHECKF(worst <= 8, "split %zu: %d/255 at x %.1f y %.1f m", c, worst, (at % one.w + 0.5) * PIX,
               (at / one.w + 0.5) * PIX);
        printf("markings across a split %zu: max %d/255 against the unsplit road\n", c, worst);
        free(sp.rgba);
        free(one.rgba);
    }
}

/* Lanes that change along a street split into records (issue 27): each
 * record's lines are its own lane model's, the arc length running on. A
 * 4-lane US road with 3 lanes forward, then 1 (the yellow centre line
 * moves from t = +3.5 to -3.5 m at x = 30 m): left of the joint the
 * picture is the first record's road drawn whole, right of it the second's
 * (within 8/255, 1 m from the joint). Before, the stroke drew every record
 * with its first record's lines (the yellow line ran on at +3.5 m). */
static void test_lanes_change(void)
{
    static const char split[] = "road a width 14 class=secondary area=rural lanes=4 lanes:forward=3\n0 20\n30 20\nend\n"
                                "road a width 14 class=secondary area=rural lanes=4 lanes:forward=1\n30 20\n60 20\nend\n";
    static const char whole1[] = "road a width 14 class=secondary area=rural lanes=4 lanes:forward=3\n0 20\n60 20\nend\n";
    static const char whole2[] = "road a width 14 class=secondary area=rural lanes=4 lanes:forward=1\n0 20\n60 20\nend\n";
    img S, A, B;
    CHECK(render(split, 61, 41, RS_PROFILE_MUTCD, 1, 0, &S));
    CHECK(render(whole1, 61, 41, RS_PROFILE_MUTCD, 1, 0, &A));
    CHECK(render(whole2, 61, 41, RS_PROFILE_MUTCD, 1, 0, &B));
    if (S.rgba && A.rgba && B.rgba) {
        int worst[2] = { 0, 0 }, differ = 0;
        for (uint32_t y = 0; y < S.h; y++)
            for (uint32_t x = 0; x < S.w; x++) {
                double xm = (x + 0.5) * PIX;
                if (fabs(xm - 30) < 1) continue;
                const img *R = xm < 30 ? &A : &B;
                for (int c = 0; c < 3; c++) {
                    size_t i = ((size_t)y * S.w + x) * 4 + c;
                    int d = abs((int)S.rgba[i] - (int)R->rgba[i]);
                    if (d > worst[xm > 30]) worst[xm > 30] = d;
                    differ += A.rgba[i] != B.rgba[i];
                }
            }
        CHECK(differ > 1000); /* the two lane models draw differently */
        CHECKF(worst[0] <= 8 && worst[1] <= 8, "before the joint %d/255, after %d/255", worst[0], worst[1]);
        printf("lanes changing along a street: %d/255 before the joint, %d/255 after it\n", worst[0], worst[1]);
    }
    free(S.rgba);
    free(A.rgba);
    free(B.rgba);
    /* a two-way record (two lanes each way: its lines the same both ways)
     * going on as a record pointing the other way with 3 of its 4 lanes
     * backward (one stroke: the same lane total): the second's lines are its own, not mirrored (each drawn
     * alone when the records pointing the other way have lines that are
     * not the same both ways) */
    static const char rsplit[] = "road a width 14 class=secondary area=rural lanes=4\n0 20\n20 20\nend\n"
                                 "road a width 14 class=secondary area=rural lanes=4 lanes:backward=3\n40 20\n20 20\nend\n";
    static const char rwhole[] = "road a width 14 class=secondary area=rural lanes=4 lanes:backward=3\n40 20\n-20 20\nend\n";
    CHECK(render(rsplit, 61, 41, RS_PROFILE_MUTCD, 1, 0, &S));
    CHECK(render(rwhole, 61, 41, RS_PROFILE_MUTCD, 1, 0, &B));
    if (S.rgba && B.rgba) {
        int worst = max_diff(&S, &B, 210, 390, 0, S.h); /* x 21 .. 39 m: the second record */
        CHECKF(worst <= 8, "the reversed record's lines %d/255 from its road drawn whole", worst);
        printf("a reversed record after a two-way one: %d/255 from its road drawn whole\n", worst);
    }
    free(S.rgba);
    free(B.rgba);
}

/* A footway crossing a road (issue 27 problem 6): the road's edge and
 * centre lines run on over it (a path, footway or cycleway cuts no car
 * road's lines), and the crossing takes the road's surface (the fill of
 * the highest priority among the surfaces holding a pixel). Every pixel
 * the road's lines paint white without the footway is still white with
 * it, and inside the road nothing changes. Before, the lines stopped at
 * the footway's surface (a 3 m gap in each) and each pixel took the fill
 * of the nearest centre line (a jagged X of the two fills). */
static void test_footway_crossing(void)
{
    static const char alone[] = "road main width 8 class=primary area=rural\n0 20\n60 20\nend\n";
    static const char crossed[] = "road main width 8 class=primary area=rural\n0 20\n60 20\nend\n"
                                  "road walk width 3 class=footway\n25 0\n35 40\nend\n";
    img A, B;
    CHECK(render(alone, 61, 41, RS_PROFILE_RMS, 1, 0, &A));
    CHECK(render(crossed, 61, 41, RS_PROFILE_RMS, 1, 0, &B));
    if (A.rgba && B.rgba) {
        int white = 0, lost = 0;
        for (uint32_t y = 0; y < A.h; y++)
            for (uint32_t x = 250; x < 350; x++) { /* the crossing's columns */
                const uint8_t *a = A.rgba + ((size_t)y * A.w + x) * 4, *b = B.rgba + ((size_t)y * B.w + x) * 4;
                if (a[0] < 230 || a[1] < 230 || a[2] < 230) continue;
                white++;
                lost += b[0] < 230 || b[1] < 230 || b[2] < 230;
            }
        CHECK(white >= 150); /* two edge lines over 10 m */
        CHECKF(lost == 0, "%d of %d line pixels lost over the footway", lost, white);
        printf("footway crossing: %d of %d line pixels lost\n", lost, white);
        /* the crossing takes the road's surface: inside the road (|y - 20|
         * <= 3.9 m) every pixel as without the footway (no X split of the
         * two fills) */
        int worst = max_diff(&A, &B, 200, 400, 161, 239);
        CHECKF(worst <= 8, "inside the road %d/255 from the road alone", worst);
        printf("footway crossing: inside the road max %d/255 from the road alone\n", worst);
    }
    free(A.rgba);
    free(B.rgba);
}

/* Line paint at pixel (x, y): every channel >= 110 (the road is grey 60,
 * the grass below 110 in red and blue; a 0.12 m line covers about half
 * of the pixels it touches). */
static int is_paint(const img *m, uint32_t x, uint32_t y)
{
    const uint8_t *p = m->rgba + ((size_t)y * m->w + x) * 4;
    return p[0] >= 110 && p[1] >= 110 && p[2] >= 110;
}

/* A secondary road crossing a rural primary (issue 27 problem 6), with a
 * shared vertex and without one: the primary keeps its centre line through
 * the crossing (as drawn alone), its edge lines stop at the two mouths,
 * and the secondary's centre line stops at the primary's edge. */
static void test_class_crossing(void)
{
    static const char alone[] = "road main width 8 class=primary area=rural\n0 20\n60 20\nend\n";
    static const char *const crossed[2] = {
        "road main width 8 class=primary area=rural\n0 20\n39 20\n60 20\nend\n"
        "road side width 6 class=secondary area=rural\n39 0\n39 20\n39 40\nend\n",
        "road main width 8 class=primary area=rural\n0 20\n60 20\nend\n"
        "road side width 6 class=secondary area=rural\n39 0\n39 40\nend\n",
    };
    img A;
    CHECK(render(alone, 61, 41, RS_PROFILE_RMS, 1, 1, &A));
    for (int v = 0; v < 2 && A.rgba; v++) {
        img B;
        CHECK(render(crossed[v], 61, 41, RS_PROFILE_RMS, 1, 1, &B));
        if (!B.rgba) continue;
        /* the primary's centre line over the crossing (x 36..42 m: a dash) */
        int white = 0, lost = 0, worst = max_diff(&A, &B, 360, 420, 194, 207);
        for (uint32_t y = 194; y < 207; y++)
            for (uint32_t x = 360; x < 420; x++)
                if (is_paint(&A, x, y)) white++, lost += !is_paint(&B, x, y);
        CHECKF(white >= 80, "variant %d: the centre line alone has %d white pixels in the crossing", v, white);
        CHECKF(lost == 0 && worst <= 8, "variant %d: centre line %d of %d pixels lost, max %d/255 from alone", v, lost,
               white, worst);
        /* the primary's edge lines (|y - 20| in 3.6..4 m) within the mouths
         * (|x - 39| <= 2.5 m), and the secondary's centre line inside the
         * primary off its centre line (0.6 <= |y - 20| <= 3.4 m) */
        int mouth = 0, side = 0, side_out = 0;
        for (uint32_t x = 365; x < 415; x++)
            for (uint32_t y = 160; y < 240; y++) {
                double dy = fabs(((double)y + 0.5) / 10 - 20);
                if (dy >= 3.6 && is_paint(&B, x, y)) mouth++;
                if (dy >= 0.6 && dy <= 3.4 && is_paint(&B, x, y)) side++;
            }
        for (uint32_t y = 0; y < 150; y++)
            for (uint32_t x = 380; x < 400; x++) side_out += is_paint(&B, x, y);
        CHECKF(mouth == 0, "variant %d: %d edge-line pixels across the mouths", v, mouth);
        CHECKF(side == 0, "variant %d: %d pixels of the secondary's lines inside the primary", v, side);
        CHECKF(side_out > 30, "variant %d: the secondary's centre line is drawn outside (%d pixels)", v, side_out);
        printf("class crossing %d: centre line %d/%d kept (max %d/255 from alone), mouths %d, side lines inside %d\n", v,
               white - lost, white, worst, mouth, side);
        free(B.rgba);
    }
    free(A.rgba);
}

/* Another road's lines stop at the outside of a bend where its surface
 * does: the surface rectangles run past a vertex only as far as the
 * round join needs (hw tan(turn / 2)), not the half width (which stopped
 * them up to (sqrt 2 - 1) half widths early: here 0.68 m). A 10 m road
 * bends 20 degrees at (30, 30); a 6 m road of equal rank crosses it at
 * the vertex: its east edge line, beside the vertex on the outside, meets
 * the bend's second segment 4.32 m from the vertex's line. */
static void test_bend_outside_cut(void)
{
    static const char *const text[2] = {
        "road a width 10 class=secondary area=rural\n0 30\n30 30\n60 19.0809\nend\n"
        "road b width 6 class=secondary area=rural\n30 60\n30 0\nend\n",
        /* split at the bend into two records (their end rectangles ran on by
         * the half width there until 6 December 2026: joints_reach) */
        "road a width 10 class=secondary area=rural\n0 30\n30 30\nend\n"
        "road a width 10 class=secondary area=rural\n30 30\n60 19.0809\nend\n"
        "road b width 6 class=secondary area=rural\n30 60\n30 0\nend\n",
    };
    for (int v = 0; v < 2; v++) {
    double *al = NULL;
    uint32_t w = 0, h = 0;
    CHECK(scene_paint(text[v], 61, 61, RS_PROFILE_RMS, NULL, &al, &w, &h));
    if (!al || w != 600 || h != 600) {
        free(al);
        continue;
    }
    /* the east edge line's column: the most paint at y 40..50 m, x 31..34 m */
    double best = 0;
    uint32_t col = most_paint(al, w, 0, 310, 340, 400, 500, &best);
    /* its paint from y = 40 m towards road a, against the exact edge of a's
     * second segment at the column's centre (n = (sin 20, cos 20)) */
    double xc = (col + 0.5) * PIX, len = 0;
    for (uint32_t y = 330; y < 400; y++) len += al[(size_t)y * w + col] * PIX;
    double edge = 30 + (5 - 0.34202014 * (xc - 30)) / 0.93969262;
    CHECKF(best > 5 && fabs(len - (40 - edge)) <= 0.1,
           "%s: the crossing road's edge line (x %.2f m) runs %.2f m from y = 40 m, to the bend's edge %.2f m",
           v ? "two records" : "one record", xc, len, 40 - edge);
    printf("bend outside (%s): the crossing's edge line at x %.2f m stops %.3f m from a's edge\n",
           v ? "two records" : "one record", xc, len - (40 - edge));
    free(al);
    }
}

/* The lines of a 61 x 61 m scene and of its one road alone (each w = 600
 * pixels of 0.1 m a side); 0 when either failed (checked). */
static int paint_and_alone(const char *text, const char *alone, double **al, double **al0)
{
    uint32_t w = 0, h = 0, w0 = 0, h0 = 0;
    CHECK(scene_paint(text, 61, 61, RS_PROFILE_RMS, NULL, al, &w, &h));
    CHECK(scene_paint(alone, 61, 61, RS_PROFILE_RMS, NULL, al0, &w0, &h0));
    return *al && *al0 && w == 600 && h == 600 && w0 == 600 && h0 == 600;
}

/* A free road end's round cap cuts another road's line only where the
 * cap lies over it: a street ending 2 m short of a primary's edge reaches
 * over the primary's edge line with its cap (r = 3 m), whose chord there is
 * about 3.3 m wide. Until 6 December 2026 the cut ran to the square end's
 * corners (6 m: the line stopped up to (sqrt 2 - 1) r short of the cap,
 * 184/255 against the shader on docs/examples/network_spike.txt). */
static void test_cap_cut(void)
{
    static const char text[] = "road main width 10 class=primary area=rural\n0 30\n60 30\nend\n"
                               "road stub width 6 class=secondary area=rural\n30 55\n30 37\nend\n";
    static const char alone[] = "road main width 10 class=primary area=rural\n0 30\n60 30\nend\n";
    double *al = NULL, *al0 = NULL;
    const uint32_t w = 600;
    if (paint_and_alone(text, alone, &al, &al0)) {
        /* the rows of the primary's upper edge line alone (whole at x = 10 m) */
        int rows = 0, bad = 0, cut = 0, kept = 0;
        for (uint32_t y = 300; y < 350; y++) {
            if (!(al0[(size_t)y * w + 100] > 0.99)) continue;
            rows++;
            double dy = 37 - (y + 0.5) * PIX, half = sqrt(9 - dy * dy);
            for (uint32_t x = 150; x < 450; x++) {
                double d = fabs((x + 0.5) * PIX - 30), a = al[(size_t)y * w + x], a0 = al0[(size_t)y * w + x];
                if (d < half - PIX) bad += !(a < 0.01), cut++;
                else if (d > half + PIX) bad += !(fabs(a - a0) < 0.01), kept++;
            }
        }
        CHECKF(rows >= 1 && cut > 0 && kept > 0 && bad == 0,
               "%d edge-line rows: %d of %d pixels under the cap and %d beside it differ from the cap's cut", rows, bad,
               cut + kept, kept);
        printf("round cap cut: %d rows, %d pixels under the cap cut, %d beside it kept, %d wrong\n", rows, cut, kept,
               bad);
    }
    free(al);
    free(al0);
}

/* A bridge over a road (docs/network.md "Bridges and layers"): the upper
 * road's lines run on over the lower one, whatever their classes, and
 * the lower road's lines stop under the upper surface; a street ending
 * under the bridge gets no give-way line. On one level the crossing cuts
 * as before (the secondary's edge lines stop at the primary). */
static void test_bridge_lines(void)
{
    /* one level; a secondary bridge; a tertiary one (of lower rank than
     * the primary: on one level the primary cuts its lines and its own
     * centre line runs on over it) */
    /* and (v 3) a bridge record joined to ground records at both ends, as
     * OSM maps a bridge: until 7 December 2026 the stroke's polyline left
     * out the straight joints, the merged segment took the last record's
     * level and the primary cut the bridge's lines (the shader drew them) */
    static const char *const lvl[4] = { "secondary", "secondary layer=1", "tertiary bridge=yes", "secondary, ramps" };
    static const char prim[] = "road p width 9 class=primary area=rural\n0 30\n60 30\nend\n";
    char bridge[512], text[1024];
    for (int v = 0; v < 4; v++) {
        if (v < 3)
            snprintf(bridge, sizeof bridge, "road b width 7 class=%s area=rural\n39 2\n39 58\nend\n", lvl[v]);
        else
            snprintf(bridge, sizeof bridge,
                     "road r1 width 7 class=secondary area=rural\n39 2\n39 15\nend\n"
                     "road b width 7 class=secondary area=rural bridge=yes layer=1\n39 15\n39 50\nend\n"
                     "road r2 width 7 class=secondary area=rural\n39 50\n39 58\nend\n");
        snprintf(text, sizeof text, "%s%sroad u width 6 class=residential\n58 45\n41 45\nend\n", prim, bridge);
        double *al = NULL, *ln = NULL, *ab = NULL, *ap = NULL;
        uint32_t w = 0, h = 0;
        CHECK(scene_paint(text, 61, 61, RS_PROFILE_RMS, &al, &ln, &w, &h));
        CHECK(scene_paint(bridge, 61, 61, RS_PROFILE_RMS, NULL, &ab, &w, &h));
        CHECK(scene_paint(prim, 61, 61, RS_PROFILE_RMS, NULL, &ap, &w, &h));
        if (al && ln && ab && ap && w == 600 && h == 600) {
            /* the bridge's lines over the primary (x 35.5..42.5 m, y 26..34 m) */
            double diff_b = 0, alone_b = 0, under_p = 0, alone_p = 0, giveway = 0;
            for (uint32_t y = 260; y < 340; y++)
                for (uint32_t x = 355; x < 425; x++) diff_b += fabs(ln[(size_t)y * w + x] - ab[(size_t)y * w + x]),
                                                   alone_b += ab[(size_t)y * w + x];
            /* the primary's lines under the bridge (the paint beyond the
             * bridge's own; its centre line has a dash at 36..42 m), and
             * alone there */
            for (uint32_t y = 255; y < 345; y++)
                for (uint32_t x = 358; x < 422; x++)
                    under_p += fmax(ln[(size_t)y * w + x] - ab[(size_t)y * w + x], 0), alone_p += ap[(size_t)y * w + x];
            /* markings near the street's end under the bridge (x 42..45 m, y 42..48 m) */
            for (uint32_t y = 420; y < 480; y++)
                for (uint32_t x = 420; x < 450; x++) giveway += al[(size_t)y * w + x] - ln[(size_t)y * w + x];
            if (v) {
                /* (a rural tertiary has no lines of its own) */
                CHECKF((v == 2 || alone_b > 50) && diff_b < 1 && under_p < 1 && alone_p > 300 && giveway < 1,
                       "%s: its lines over the primary differ from alone by %.1f px (%.1f alone), the primary's "
                       "under it paint %.1f px (%.1f alone), markings at the end under it %.1f px",
                       lvl[v], diff_b, alone_b, under_p, alone_p, giveway);
            } else {
                /* one level: the primary cuts the secondary's lines, and the
                 * street meets the secondary at a T */
                CHECKF(diff_b > 20 && giveway > 5, "one level: the secondary's lines differ from alone by %.1f px, "
                       "markings at the street's end %.1f px", diff_b, giveway);
            }
            printf("bridge lines (%s): %.1f px of the bridge's lines differ over the primary, %.1f of the primary's "
                   "under it (%.1f alone), markings at the end under it %.1f px\n", lvl[v], diff_b, under_p, alone_p,
                   giveway);
        }
        free(al);
        free(ln);
        free(ab);
        free(ap);
    }
}

/* A bridge's casing over the road below it (docs/network.md "Bridges and
 * layers"): a secondary whose middle record is a bridge over a primary,
 * both with casings of their own colours. The bridge's casing runs on over
 * the primary (until 7 December 2026 the primary's asphalt showed there, as
 * the casing lay under every road surface); it is drawn neither across the
 * ground records the bridge continues (its casing's round caps at the
 * joints) nor with every road on one level. Both edge modes. */
static void test_deck_casing(void)
{
    static const char styles[] = "style deck\n  casing 0.5 #C03030\nend\nstyle main\n  casing 0.5 #3030C0\nend\n";
    static const char *const layer[2] = { " bridge=yes layer=1", "" };
    static const rs_edge_mode modes[2] = { RS_EDGES_ANALYTIC, RS_EDGES_ALPHAMAP };
    rs_styles *S = NULL;
    CHECK(rs_styles_parse(ctx, styles, sizeof styles - 1, &S) == RS_OK);
    for (int e = 0; e < 2 && S; e++)
        for (int v = 0; v < 2; v++) {
            char text[1024];
            snprintf(text, sizeof text,
                     "road p width 9 style=main\n0 30\n60 30\nend\n"
                     "road r1 width 7 style=deck\n39 2\n39 15\nend\n"
                     "road b width 7 style=deck%s\n39 15\n39 50\nend\n"
                     "road r2 width 7 style=deck\n39 50\n39 58\nend\n",
                     layer[v]);
            img A;
            render_edges = modes[e];
            render_styles = S;
            int ok = render(text, 61, 61, RS_PROFILE_RMS, 1, 1, &A);
            render_edges = RS_EDGES_ANALYTIC;
            render_styles = NULL;
            CHECK(ok && A.w == 600 && A.h == 600);
            if (!(ok && A.w == 600 && A.h == 600)) {
                free(A.rgba);
                continue;
            }
            /* casing colour: within 24 of #C03030 on every channel */
#define RED_AT(x, y)                                                                                               \
    (abs((int)A.rgba[((size_t)(y) * A.w + (x)) * 4] - 0xC0) <= 24 &&                                             \
     abs((int)A.rgba[((size_t)(y) * A.w + (x)) * 4 + 1] - 0x30) <= 24 &&                                         \
     abs((int)A.rgba[((size_t)(y) * A.w + (x)) * 4 + 2] - 0x30) <= 24)
            /* the band's middle (x 35.25 and 42.75 m) over the primary (y 26..34 m) */
            int band = 0, joints = 0;
            for (uint32_t y = 260; y < 340; y++) band += RED_AT(352, y) + RED_AT(427, y);
            /* the ramps' surfaces (x 36..42 m) where the bridge record's
             * casing cap would lie on them: 3.5 to 4 m from each joint
             * (y 15 and 50 m), within 11 m..joint and joint..54 m */
            for (uint32_t y = 105; y < 150; y++)
                for (uint32_t x = 360; x < 420; x++) joints += RED_AT(x, y) + RED_AT(x, y + 395);
#undef RED_AT
            if (v == 0)
                CHECKF(band == 160 && joints == 0,
                       "%s edges: a bridge's casing over the primary: %d of 160 band pixels in its colour, %d casing "
                       "pixels on the ramps at the joints", modes[e] == RS_EDGES_ALPHAMAP ? "alpha-map" : "analytic", band,
                       joints);
            else
                CHECKF(band == 0 && joints == 0, "one level: %d casing pixels over the primary, %d at the joints", band,
                       joints);
            printf("deck casing (%s edges, %s): %d of 160 band pixels over the primary in its colour, %d at the "
                   "joints\n", modes[e] == RS_EDGES_ALPHAMAP ? "alpha-map" : "analytic", v ? "one level" : "bridge",
                   band, joints);
            free(A.rgba);
        }
    rs_styles_free(ctx, S);
}

/* A lower road's markings under a bridge's deck (docs/network.md "Bridges
 * and layers"): left out where the deck's surface holds the pixel, painted
 * where they come out from under it; a marking running on from a record to
 * the bridge record of its own stroke stays whole. Until 6 December 2026
 * the primary's words were painted on the bridge's deck. */
static void test_marks_under_bridge(void)
{
    static const char prim[] = "road p width 9 class=primary area=rural\n0 30\n60 30\nend\n";
    static const char bridge[] = "road b width 7 class=secondary area=rural layer=1\n39 2\n39 58\nend\n";
    /* BUS wholly under the deck (x 36..42 m, the deck 35.5..42.5), SLOW at x 29..35 (out from under it) */
    static const char marks[] = "mark word_bus road=p s=39 t=-2.2 length=6 width=2\n"
                                "mark word_slow road=p s=32 t=2.2 length=6 width=2 flip\n";
    char a_txt[1024], b_txt[1024], c_txt[1024];
    snprintf(a_txt, sizeof a_txt, "%s%s%s", prim, bridge, marks);
    snprintf(b_txt, sizeof b_txt, "%s%s", prim, bridge);
    snprintf(c_txt, sizeof c_txt, "%s%s", prim, marks);
    /* both edge modes: alpha-map grids have no road field of their own, and
     * painted both words on the deck until 7 December 2026 */
    static const rs_edge_mode modes[2] = { RS_EDGES_ANALYTIC, RS_EDGES_ALPHAMAP };
    static const char *const mode_name[2] = { "analytic", "alpha-map" };
    for (int e = 0; e < 2; e++) {
        img A, B, C;
        render_edges = modes[e];
        int ok = render(a_txt, 61, 61, RS_PROFILE_RMS, 1, 1, &A) & render(b_txt, 61, 61, RS_PROFILE_RMS, 1, 1, &B) &
                 render(c_txt, 61, 61, RS_PROFILE_RMS, 1, 1, &C);
        render_edges = RS_EDGES_ANALYTIC;
        CHECK(ok && A.w == 600 && A.h == 600 && B.w == 600 && C.w == 600);
        if (ok && A.w == 600 && B.w == 600 && C.w == 600) {
            /* on the deck over the primary: as without the marks */
            int deck = max_diff(&A, &B, 360, 420, 255, 345);
            /* the part of SLOW out from under the deck (x 29.5..34.5 m): as
             * without the bridge, and painted */
            int out_c = max_diff(&A, &C, 295, 345, 255, 345), out_b = max_diff(&A, &B, 295, 345, 255, 345);
            /* and without the bridge BUS is there */
            int bus = max_diff(&C, &B, 360, 420, 255, 300);
            CHECKF(deck == 0 && out_c == 0 && out_b > 100 && bus > 100,
                   "marks under a deck (%s edges): %d/255 on the deck from the marks, %d out from under it against "
                   "no bridge, %d against no marks, %d where BUS lies without the bridge",
                   mode_name[e], deck, out_c, out_b, bus);
            printf("marks under a bridge (%s edges): deck %d/255, out from under it %d (no bridge) and %d (no marks), "
                   "BUS alone %d\n", mode_name[e], deck, out_c, out_b, bus);
        }
        free(A.rgba);
        free(B.rgba);
        free(C.rgba);
    }
    /* the same stroke: a primary whose second record is a bridge (over
     * nothing); a word across the joint draws as on one level */
    static const char *const lay[2] = { "", " layer=1" };
    img S[2];
    for (int v = 0; v < 2; v++) {
        char t[1024];
        snprintf(t, sizeof t,
                 "road p1 width 9 class=primary area=rural\n0 30\n30 30\nend\n"
                 "road p2 width 9 class=primary area=rural%s\n30 30\n60 30\nend\n"
                 "mark word_bus road=p1 s=29 t=-2.2 length=6 width=2\n",
                 lay[v]);
        int ok = render(t, 61, 61, RS_PROFILE_RMS, 1, 1, &S[v]);
        CHECK(ok);
    }
    if (S[0].rgba && S[1].rgba && S[0].w == S[1].w && S[0].h == S[1].h) {
        int d = max_diff(&S[0], &S[1], 0, S[0].w, 0, S[0].h);
        CHECKF(d == 0, "a word across a record's joint with its bridge record: %d/255 from one level", d);
    }
    free(S[0].rgba);
    free(S[1].rgba);
}

/* A roundabout is one-way along its points (OSM: junction=roundabout and
 * circular imply oneway=yes): drawn as with oneway=yes written, without
 * the centre line of a two-way road it drew until 6 December 2026 (the
 * OSM reader passes junction= since then, and real roundabouts rarely
 * say oneway=yes); oneway=no still makes it two-way. */
static void test_roundabout_oneway(void)
{
    static const char *const tags[4] = { " junction=roundabout oneway=yes", " junction=roundabout",
                                         " junction=circular", " junction=roundabout oneway=no" };
    img im[4];
    int ok = 1;
    for (int v = 0; v < 4; v++) {
        char text[2048];
        size_t at = (size_t)snprintf(text, sizeof text, "road ring width 7 class=secondary area=rural%s\n", tags[v]);
        for (int k = 0; k <= 24; k++)
            at += (size_t)snprintf(text + at, sizeof text - at, "%.6f %.6f\n", 30 + 18 * cos(k % 24 * 0.26179938779914943),
                                   30 + 18 * sin(k % 24 * 0.26179938779914943));
        snprintf(text + at, sizeof text - at, "end\n");
        /* (US rules: a yellow centre line between the directions, white lane lines) */
        memset(&im[v], 0, sizeof im[v]);
        ok &= render(text, 61, 61, RS_PROFILE_MUTCD, 1, 0, &im[v]);
    }
    CHECK(ok);
    if (ok) {
        int d1 = max_diff(&im[1], &im[0], 0, im[0].w, 0, im[0].h), d2 = max_diff(&im[2], &im[0], 0, im[0].w, 0, im[0].h);
        int d3 = max_diff(&im[3], &im[0], 0, im[0].w, 0, im[0].h);
        CHECKF(d1 == 0 && d2 == 0 && d3 > 100, "roundabout against oneway=yes: max %d/255 (roundabout), %d/255 "
               "(circular), %d/255 (oneway=no: a centre line)", d1, d2, d3);
        printf("roundabout one-way: max %d/255 and %d/255 from oneway=yes; oneway=no %d/255\n", d1, d2, d3);
    }
    for (int v = 0; v < 4; v++) free(im[v].rgba);
}

/* A line under several surfaces in a row is cut by each: a service road
 * of five segments runs along a primary's edge over its edge line, which
 * stops under it (a lower road cuts a higher one's edge lines, issue 27).
 * Until 6 December 2026 each cut cost a piece three half-planes and the
 * third left it whole: the edge line showed as dashes under the service
 * road (docs/examples/roads.txt, 181/255 against the shader). */
static void test_line_under_road(void)
{
    static const char text[] = "road main width 13 class=primary area=rural\n0 30\n60 30\nend\n"
                               "road lane width 5 class=service\n6 37.4\n14 37.5\n22 37.3\n30 37.5\n38 37.4\n46 37.5\nend\n";
    static const char alone[] = "road main width 13 class=primary area=rural\n0 30\n60 30\nend\n";
    double *al = NULL, *al0 = NULL;
    const uint32_t w = 600;
    if (paint_and_alone(text, alone, &al, &al0)) {
        /* the main road's lower edge line (rows 360..363: 6.0..6.4 m off
         * its centre line), x 12..40 m, under the lane (2.5 m each side of
         * 37.3..37.5 m) */
        double under = 0, alone_paint = 0;
        for (uint32_t y = 356; y < 368; y++)
            for (uint32_t x = 120; x < 400; x++) under += al[(size_t)y * w + x], alone_paint += al0[(size_t)y * w + x];
        CHECKF(alone_paint > 100 && under < 1, "the edge line under the lane paints %.1f pixels (alone %.1f)", under,
               alone_paint);
        printf("line under a road: the edge line paints %.1f pixels under the lane (%.1f alone)\n", under, alone_paint);
    }
    free(al);
    free(al0);
}

/* A line crossed by many roads in a row is cut at every crossing: a rural
 * primary of one segment crossed by eleven secondaries (118 m), and by
 * thirty (308 m); its edge lines stop at every mouth. Until 6 December
 * 2026 the far piece took a half-plane per crossing and stayed whole from
 * about the sixth crossing on (docs/render.md, the dense scene with one
 * segment per street), and until session 44 the line's pieces were at
 * most QMAX (16): past about the eighth crossing of one segment the edge
 * lines ran on across the mouths (now the piece is halved along its
 * length and each half cut alone; docs/linesym.md "Junctions"). */
static void test_many_crossings(void)
{
    /* exact lines, then Hermite lines (which keep every cut's half-planes
     * and ran out of them from about the ninth crossing on until session
     * 44: there a piece is halved as well when earlier cuts took two or
     * more of its half-planes) */
    static const int nx[3] = { 11, 30, 30 };
    for (int v = 0; v < 3; v++) {
        const int n = nx[v], len = 10 * n + 8;
        render_aa = v == 2 ? RS_LINE_AA_HERMITE : RS_LINE_AA_EXACT;
        char text[4096];
        size_t at = (size_t)snprintf(text, sizeof text, "road main width 8 class=primary area=rural\n1 30\n%d 30\nend\n",
                                     len + 1);
        for (int k = 0; k < n; k++)
            at += (size_t)snprintf(text + at, sizeof text - at, "road x%d width 6 class=secondary\n%d 2\n%d 58\nend\n", k,
                                   10 + 10 * k, 10 + 10 * k);
        double *al = NULL;
        uint32_t w = 0, h = 0;
        CHECK(scene_paint(text, (uint32_t)len + 3, 61, RS_PROFILE_RMS, NULL, &al, &w, &h));
        if (al && w == 10 * ((uint32_t)len + 2) && h == 600) {
            /* the edge lines (3.3..3.9 m off the centre line) inside each
             * crossing's surface, 0.2 m clear of its edges */
            int worst = -1, bad = 0;
            double worst_paint = 0, between = 0;
            for (int k = 0; k < n; k++) {
                double paint = 0;
                for (uint32_t y = 0; y < h; y++) {
                    double dy = fabs(((double)y + 0.5) * PIX - 30);
                    if (dy < 3.3 || dy > 3.9) continue;
                    for (uint32_t x = (uint32_t)(10 * (10 + 10 * k) - 28); x < (uint32_t)(10 * (10 + 10 * k) + 28); x++)
                        paint += al[(size_t)y * w + x];
                    /* and between this crossing and the next, where they run */
                    if (k < n - 1)
                        for (uint32_t x = (uint32_t)(10 * (10 + 10 * k) + 40); x < (uint32_t)(10 * (20 + 10 * k) - 40); x++)
                            between += al[(size_t)y * w + x];
                }
                bad += paint >= 1;
                if (paint > worst_paint) worst_paint = paint, worst = k;
            }
            CHECKF(worst_paint < 1 && between > 50.0 * (n - 1),
                   "%d crossings (%s): edge-line paint %.1f pixels inside crossing %d (%d crossings painted); %.1f "
                   "between them", n, v == 2 ? "Hermite" : "exact", worst_paint, worst, bad, between);
            printf("many crossings (%d, %s): the edge lines paint at most %.1f pixels inside a crossing (%d painted), "
                   "%.1f between them\n", n, v == 2 ? "Hermite" : "exact", worst_paint, bad, between);
        }
        free(al);
    }
    render_aa = RS_LINE_AA_EXACT;
}

/* A side road of one segment (two points) ending on a through road at a
 * T draws the through road's far half the same whichever way its points
 * run, and as the through road drawn alone (its far edge line, centre
 * line). Until 6 December 2026 a two-point side road drawn from the T
 * outwards cut the through road's far edge line across its mouth (and,
 * of equal rank, its centre line): the T was looked up at the segment's
 * end only. Secondary through roads with a secondary and a residential
 * side road, rural (edge lines). */
static void test_tee_side_direction(void)
{
    static const char alone[] = "road main width 7 class=secondary area=rural\n0 20\n60 20\nend\n";
    static const char *const side[2] = { "secondary", "residential" };
    img A;
    CHECK(render(alone, 61, 41, RS_PROFILE_RMS, 1, 1, &A));
    for (int k = 0; k < 2 && A.rgba; k++) {
        char text[2][512];
        img B[2];
        for (int dir = 0; dir < 2; dir++) {
            snprintf(text[dir], sizeof text[dir],
                     "road main width 7 class=secondary area=rural\n0 20\n60 20\nend\n"
                     "road side width 8 class=%s area=rural\n%s\nend\n",
                     side[k], dir ? "30 20\n30 0" : "30 0\n30 20");
            CHECK(render(text[dir], 61, 41, RS_PROFILE_RMS, 1, 1, &B[dir]));
        }
        if (B[0].rgba && B[1].rgba) {
            /* the far half: y 20 .. 24 m (the side road comes from y < 16.5) */
            int both = max_diff(&B[0], &B[1], 0, 600, 200, 240), far0 = max_diff(&A, &B[0], 0, 600, 200, 240),
                far1 = max_diff(&A, &B[1], 0, 600, 200, 240);
            CHECKF(both == 0, "%s side road: the through road's far half differs by %d/255 between the two directions",
                   side[k], both);
            CHECKF(far0 <= 8 && far1 <= 8, "%s side road: the far half differs from the road alone by %d and %d/255",
                   side[k], far0, far1);
            printf("T with a one-segment %s side road: far half, the two directions %d/255 apart, from alone %d and %d\n",
                   side[k], both, far0, far1);
        }
        free(B[0].rgba);
        free(B[1].rgba);
    }
    free(A.rgba);
}

/* A ring (one closed record, a 24-gon of 18 m radius round (30, 30) m)
 * draws its edge lines across its seam (its first point) as across any
 * other vertex: the lines near the seam equal those near the vertex a
 * quarter turn on, turned back (the ring is symmetric under it, up to the
 * road file's millimetres). Until 6 December 2026 both ends stopped
 * square at the seam and the outer edge line had a 0.9 m gap there. The
 * same ring in three records (an OSM roundabout is often split) too. */
static void test_ring_seam(void)
{
    char text[4096];
    for (int split = 0; split < 2; split++) {
        size_t at = 0;
        int nrec = split ? 3 : 1, per = 24 / nrec;
        for (int q = 0; q < nrec; q++) {
            at += (size_t)snprintf(text + at, sizeof text - at, "road r%d width 7 class=secondary area=rural\n", q);
            for (int k = q * per; k <= (q + 1) * per; k++) {
                double a = 2 * 3.14159265358979323846 * (k % 24) / 24;
                at += (size_t)snprintf(text + at, sizeof text - at, "%.4f %.4f\n", 30 + 18 * cos(a), 30 + 18 * sin(a));
            }
            at += (size_t)snprintf(text + at, sizeof text - at, "end\n");
        }
        double *al = NULL;
        uint32_t w = 0, h = 0;
        CHECK(scene_paint(text, 61, 61, RS_PROFILE_RMS, NULL, &al, &w, &h));
        if (!al || w != 600 || h != 600) {
            free(al);
            continue;
        }
        /* the edge lines (more than 2 m off the ring's centre line) within
         * 5 m of the seam (48, 30) m, against the quarter turn: pixel (x, y)
         * goes to (599 - y, x) */
        double worst = 0, painted = 0;
        for (uint32_t y = 250; y < 350; y++)
            for (uint32_t x = 430; x < 530; x++) {
                double dx = (x + 0.5) / 10 - 30, dy = (y + 0.5) / 10 - 30;
                if (fabs(hypot(dx, dy) - 18) < 2) continue;
                double a = al[(size_t)y * w + x], b = al[(size_t)x * w + (599 - y)];
                painted += a;
                if (fabs(a - b) > worst) worst = fabs(a - b);
            }
        CHECKF(painted > 50, "ring %d: the edge lines near the seam paint %.1f pixels", split, painted);
        CHECKF(worst <= 0.05, "ring %d: the edge lines at the seam differ by %.3f from a quarter turn on", split, worst);
        printf("ring seam (%s): edge lines %.1f pixels near the seam, max %.3f from the quarter turn\n",
               split ? "three records" : "one record", painted, worst);
        free(al);
    }
}

/* A roundabout drawn as one closed way with a side road at its first point
 * (OSM's roundabouts often start where an arm joins): the way is still a
 * ring (a closed stroke: its own two ends pair at the junction), the side
 * road ends on it at a T, and the ring's lines are those of the same ring
 * whose first point lies three vertices on (no automatic markings: the
 * give-way line is not the point here). Until 6 December 2026 a record's
 * own ends paired only at a node of two legs: with the arm there the ring
 * had free ends at its first point, the arm was no T, and the ring's far
 * (inner) edge line was cut across the mouth. */
static void test_ring_arm_at_seam(void)
{
    char text[2][4096];
    for (int v = 0; v < 2; v++) {
        size_t at = (size_t)snprintf(text[v], sizeof text[v],
                                     "road ring width 7 class=secondary junction=roundabout oneway=yes lanes=1\n");
        for (int k = 0; k <= 24; k++) {
            double a = 2 * 3.14159265358979323846 * ((k + 3 * v) % 24) / 24;
            at += (size_t)snprintf(text[v] + at, sizeof text[v] - at, "%.4f %.4f\n", 30 + 18 * cos(a), 30 + 18 * sin(a));
        }
        snprintf(text[v] + at, sizeof text[v] - at, "end\nroad east width 7 class=secondary lanes=2\n48 30\n60 30\nend\n");
    }
    rs_roads *R = NULL;
    rs_network *N = NULL;
    rs_road_stroke st;
    memset(&st, 0, sizeof st);
    CHECK(rs_roads_parse(ctx, text[0], strlen(text[0]), &R) == RS_OK && rs_network_build(ctx, R, NULL, &N) == RS_OK &&
          rs_network_road_stroke(N, 0, &st) == RS_OK);
    CHECKF(st.closed == 1, "the ring with an arm at its first point: closed %d", st.closed);
    rs_network_free(ctx, N);
    rs_roads_free(ctx, R);
    /* without and with the automatic markings: the arm's give-way line
     * lies where it does at any vertex of the ring (markings_auto.c
     * dir_at: the street's direction at a vertex is its two segments'
     * mean; the first segment found put it 0.5 m nearer the ring at the
     * first point until 6 December 2026) */
    for (int marks = 0; marks < 2; marks++) {
        img A, B;
        CHECK(render(text[0], 61, 61, RS_PROFILE_RMS, 1, !marks, &A));
        CHECK(render(text[1], 61, 61, RS_PROFILE_RMS, 1, !marks, &B));
        if (A.rgba && B.rgba) {
            int worst = max_diff(&A, &B, 0, A.w, 0, A.h);
            CHECKF(worst <= 8, "the ring with the arm at its first point differs by %d/255 from the ring started elsewhere%s",
                   worst, marks ? " (automatic markings)" : "");
            printf("ring with an arm at its first point%s: closed %d, %d/255 from the ring started three vertices on\n",
                   marks ? " (automatic markings)" : "", st.closed, worst);
        }
        free(A.rgba);
        free(B.rgba);
    }
}

/* One `turn:lanes` list mirrored: lanes in the other order, left <-> right. */
static void mirror_turns(const char *in, char *out, size_t cap)
{
    char tmp[256];
    size_t n = 0;
    const char *end = in + strlen(in);
    /* entries from the last to the first */
    while (end > in && n + 1 < sizeof tmp) {
        const char *bar = end;
        while (bar > in && bar[-1] != '|') bar--;
        for (const char *c = bar; c < end; c++) {
            if (!strncmp(c, "left", 4)) { memcpy(tmp + n, "right", 5); n += 5; c += 3; }
            else if (!strncmp(c, "right", 5)) { memcpy(tmp + n, "left", 4); n += 4; c += 4; }
            else tmp[n++] = *c;
        }
        end = bar > in ? bar - 1 : in;
        if (bar > in) tmp[n++] = '|';
    }
    tmp[n] = '\0';
    snprintf(out, cap, "%s", tmp);
}

/* A junction scene, right-hand, and its mirror image x -> 60 - x with
 * driving_side=left and mirrored turn lists: the paint (lines and
 * markings) is the mirrored paint. */
static void test_mirror(rs_profile profile)
{
    static const char *const fmt =
        "road main width 10.5 class=primary area=rural lanes=3 lanes:forward=2 turn:lanes=%s%s\n"
        "%g 20\n%g 20 crossing=zebra\n%g 20\nend\n"
        "road side width 9 class=secondary area=rural lanes=3 lanes:backward=1 turn:lanes=%s control=stop%s\n"
        "%g 40\n%g 20\nend\n"
        "road north width 7 class=residential turn:lanes:forward=%s%s\n%g 0\n%g 20\nend\n"
        "road oneway width 8 class=secondary area=rural oneway=yes lanes=2 turn:lanes=%s%s\n%g 40\n%g 20\nend\n";
    const char *t_main = "through|through;right", *t_side = "left|through", *t_north = "reverse", *t_one = "left|right";
    char m_main[256], m_side[256], m_north[256], m_one[256];
    mirror_turns(t_main, m_main, sizeof m_main);
    mirror_turns(t_side, m_side, sizeof m_side);
    mirror_turns(t_north, m_north, sizeof m_north);
    mirror_turns(t_one, m_one, sizeof m_one);
    CHECK(!strcmp(m_main, "through;left|through") && !strcmp(m_side, "through|right"));
    char right[2048], left[2048];
    const char *L = " driving_side=left";
    snprintf(right, sizeof right, fmt, t_main, "", 0.0, 12.0, 60.0, t_side, "", 30.0, 30.0, t_north, "", 27.0, 27.0,
             t_one, "", 50.0, 50.0);
    snprintf(left, sizeof left, fmt, m_main, L, 60.0, 48.0, 0.0, m_side, L, 30.0, 30.0, m_north, L, 33.0, 33.0, m_one,
             L, 10.0, 10.0);
    double *ar = NULL, *al = NULL;
    uint32_t w = 0, h = 0, w2 = 0, h2 = 0;
    CHECK(scene_paint(right, 61, 41, profile, &ar, NULL, &w, &h));
    CHECK(scene_paint(left, 61, 41, profile, &al, NULL, &w2, &h2));
    if (!ar || !al || w != w2 || h != h2) {
        free(ar);
        free(al);
        return;
    }
    double worst = 0, sum = 0, painted = 0;
    uint32_t wx = 0, wy = 0;
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++) {
            double a = ar[(size_t)y * w + x], b = al[(size_t)y * w + (w - 1 - x)], d = fabs(a - b);
            sum += d;
            painted += a;
            if (d > worst) worst = d, wx = x, wy = y;
        }
    CHECKF(worst <= 0.02, "profile %d: mirrored paint differs by %.3f at (%u, %u) (right %.3f, left %.3f)",
           (int)profile, worst, wx, wy, ar[(size_t)wy * w + wx], al[(size_t)wy * w + (w - 1 - wx)]);
    CHECK(painted * PIX * PIX > 20); /* the scene has paint: lines, arrows, lines across */
    printf("mirror (profile %d): worst %.4f, mean %.2g over %u x %u pixels, %.1f m^2 of paint\n", (int)profile, worst,
           sum / ((double)w * h), w, h, painted * PIX * PIX);
    free(ar);
    free(al);
}

#ifdef RS_LANES_MAX
/* The lane queries: counts, widths, directions, arrows, sides. */
static void test_lane_queries(void)
{
    static const char text[] =
        "road a width 12 class=primary lanes=3 lanes:forward=2 turn:lanes=left|through\n0 0\n100 0\nend\n"
        "road b width 12 class=primary lanes=3 lanes:forward=2 turn:lanes=left|through driving_side=left\n"
        "0 10\n100 10\nend\n"
        "road c width 9 class=secondary oneway=-1 lanes=2 width:lanes=3|4 turn:lanes=left|right\n0 20\n100 20\nend\n"
        "road d width 5.5 class=service\n0 30\n100 30\nend\n"
        "road e1 width 7 class=residential turn:lanes:backward=reverse\n0 40\n50 40\nend\n"
        "road e2 width 7 class=residential turn:lanes:backward=reverse\n100 40\n50 40\nend\n";
    rs_roads *roads = NULL;
    CHECK(rs_roads_parse(ctx, text, sizeof text - 1, &roads) == RS_OK);
    if (!roads) return;
    rs_road_lanes L;
    /* a: right-hand: the backward lane on the left (+t), then forward lanes
     * from the driver's left: left, through */
    CHECK(rs_road_lanes_get(roads, 0, NULL, &L) == RS_OK);
    CHECK_EQ_INT(L.count, 3);
    CHECK_EQ_INT(L.forward, 2);
    CHECK_EQ_INT(L.backward, 1);
    CHECK(L.lane[0].direction == -1 && L.lane[1].direction == 1 && L.lane[2].direction == 1);
    CHECK(L.lane[1].turn == RS_TURN_LEFT && L.lane[2].turn == RS_TURN_THROUGH && L.lane[0].turn == 0);
    CHECK_NEAR(L.centre, L.lane[0].t_right, 1e-12);
    CHECK(L.lane[0].t_left <= 6 && L.lane[2].t_right >= -6);
    for (uint32_t k = 0; k + 1 < L.count; k++) CHECK_NEAR(L.lane[k].t_right, L.lane[k + 1].t_left, 1e-12);
    rs_road_lanes M;
    /* b: the same road in left-hand traffic is its mirror */
    CHECK(rs_road_lanes_get(roads, 1, NULL, &M) == RS_OK);
    CHECK(M.side == RS_DRIVING_LEFT && M.count == 3);
    for (uint32_t k = 0; k < 3; k++) {
        const rs_lane *p = &L.lane[k], *q = &M.lane[2 - k];
        CHECK_NEAR(q->t_left, -p->t_right, 1e-12);
        CHECK_NEAR(q->t_right, -p->t_left, 1e-12);
        CHECK(q->direction == p->direction);
    }
    /* forward lanes from the driver's left (+t): left on the outside in left-hand traffic */
    CHECK(M.lane[0].turn == RS_TURN_LEFT && M.lane[1].turn == RS_TURN_THROUGH);
    CHECK_NEAR(M.centre, -L.centre, 1e-12);
    /* the default in the options: road a in left-hand traffic is road b */
    rs_style_options so;
    memset(&so, 0, sizeof so);
    so.driving_side = RS_DRIVING_LEFT;
    CHECK(rs_road_lanes_get(roads, 0, &so, &L) == RS_OK);
    CHECK(memcmp(&L, &M, sizeof L) == 0);
    /* c: one-way against its points, width:lanes along travel: 3 m then 4 m
     * from the driver's left (-t), the strips share the rest */
    CHECK(rs_road_lanes_get(roads, 2, NULL, &L) == RS_OK);
    CHECK(L.count == 2 && L.backward == 2 && L.forward == 0);
    CHECK_NEAR(L.lane[1].t_left - L.lane[1].t_right, 3, 1e-12); /* the driver's left lane: at -t */
    CHECK_NEAR(L.lane[0].t_left - L.lane[0].t_right, 4, 1e-12);
    CHECK(L.lane[1].turn == RS_TURN_LEFT && L.lane[0].turn == RS_TURN_RIGHT);
    /* d: a service road: one lane both ways */
    CHECK(rs_road_lanes_get(roads, 3, NULL, &L) == RS_OK);
    CHECK(L.count == 1 && L.lane[0].direction == 0 && L.centre == 0);
    CHECK_NEAR(L.lane[0].t_left, 2.75, 1e-12);
    /* defaults per class: a residential road has one lane each way */
    CHECK(rs_road_lanes_get(roads, 4, NULL, &L) == RS_OK);
    CHECK(L.count == 2 && L.forward == 1 && L.backward == 1 && L.lane[0].turn == RS_TURN_REVERSE);
    /* bad arguments */
    CHECK(rs_road_lanes_get(roads, 6, NULL, &L) == RS_ERR_INVALID_ARG);
    CHECK(rs_road_lanes_get(roads, 0, NULL, NULL) == RS_ERR_INVALID_ARG);
    /* along a stroke: e1 and e2 point at each other (two-way: one stroke);
     * the record drawn against the stroke has its lanes turned */
    rs_network *net = NULL;
    CHECK(rs_network_build(ctx, roads, NULL, &net) == RS_OK);
    rs_road_stroke st;
    CHECK(rs_network_road_stroke(net, 4, &st) == RS_OK);
    size_t road = 99;
    rs_road_lanes A, B;
    CHECK(rs_network_lanes_at(net, roads, st.stroke, 10, NULL, &road, &A) == RS_OK);
    CHECK(rs_network_lanes_at(net, roads, st.stroke, 90, NULL, &road, &B) == RS_OK);
    uint32_t rs2[2];
    CHECK_EQ_INT(rs_network_stroke_roads(net, st.stroke, rs2, 2), 2);
    CHECK_EQ_INT(road, rs2[1]);
    /* the backward lane (its U-turn arrow) is on the stroke's left for the
     * record along it, and the same lane is the stroke's forward... */
    CHECK(A.count == 2 && B.count == 2);
    CHECK(A.lane[0].direction == -1 && B.lane[0].direction == -1);
    CHECK(A.lane[0].turn == RS_TURN_REVERSE || B.lane[1].turn == RS_TURN_REVERSE);
    CHECK(rs_network_lanes_at(net, roads, 99, 0, NULL, NULL, &A) == RS_ERR_INVALID_ARG);
    rs_network_free(ctx, net);
    /* the default styles on the lanes: a left-hand two-way primary's lines
     * are the right-hand ones mirrored */
    rs_style_request rq;
    memset(&rq, 0, sizeof rq);
    rq.road_class = RS_CLASS_PRIMARY;
    rq.lanes = 3;
    rs_style sr, sl;
    CHECK(rs_style_default(&rq, &sr) == RS_OK);
    rq.driving_side = RS_DRIVING_LEFT;
    CHECK(rs_style_default(&rq, &sl) == RS_OK);
    CHECK_EQ_INT(sl.line_count, sr.line_count);
    for (uint32_t k = 0; k < sr.line_count; k++) {
        int found = 0;
        for (uint32_t j = 0; j < sl.line_count; j++)
            found |= fabs(sl.line[j].offset + sr.line[k].offset) < 1e-12 && sl.line[j].width == sr.line[k].width &&
                     sl.line[j].dash_count == sr.line[k].dash_count;
        CHECK(found);
    }
    /* the built-in sizes the line cuts assume (lib/scene/markings_auto.c
     * default_sizes) are the built-in atlas's */
    rs_atlas *at = NULL;
    CHECK(rs_atlas_default(ctx, &at) == RS_OK);
    static const struct {
        const char *name;
        double length, width;
    } sz[] = { { "stop_line", 0.5, 3.5 },         { "give_way_line", 0.5, 3.5 }, { "give_way_block", 0.5, 0.5 },
               { "yield_tooth", 0.6858, 0.4572 }, { "zebra_bar", 4.0, 0.5 },     { "zebra", 4.0, 6.0 },
               { "arrow_uturn_right", 5.0, 1.6 } };
    for (size_t k = 0; k < sizeof sz / sizeof sz[0]; k++) {
        long ti = rs_atlas_find(at, sz[k].name);
        double len = 0, wid = 0;
        CHECKF(ti >= 0 && rs_atlas_get(at, (size_t)ti, NULL, &len, &wid, NULL, NULL) == RS_OK &&
                   len == sz[k].length && wid == sz[k].width,
               "atlas type %s", sz[k].name);
    }
    rs_atlas_free(ctx, at);
    rq.driving_side = (rs_driving_side)2;
    CHECK(rs_style_default(&rq, &sl) == RS_ERR_INVALID_ARG);
    rs_roads_free(ctx, roads);
}

/* The GPU export carries the line cuts: per road its range, per cut a
 * unit direction and a positive range; the stop line's road has them, the
 * through road only its zebra's. */
static void test_gpu_cuts(void)
{
    static const char text[] =
        "road main width 12 class=primary area=rural lanes=4\n0 20\n10 20 crossing=zebra\n60 20\nend\n"
        "road side width 12 class=secondary area=rural lanes=4 control=stop\n30 40\n30 20\nend\n";
    float z[61 * 41];
    memset(z, 0, sizeof z);
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    rs_gpu_scene *g = NULL;
    CHECK(rs_dem_create(ctx, 61, 41, z, &dem) == RS_OK);
    CHECK(rs_roads_parse(ctx, text, sizeof text - 1, &roads) == RS_OK);
    CHECK(rs_gpu_scene_create(ctx, dem, roads, NULL, NULL, &g) == RS_OK);
    if (g) {
        CHECK(gsv_of(g).ncuts >= 2 && gsv_of(g).cut);
        size_t total = 0;
        for (size_t r = 0; r < gsv_of(g).nroads; r++) {
            size_t first = (size_t)gsv_of(g).cut[4 * r], n = (size_t)gsv_of(g).cut[4 * r + 1];
            CHECK(n == 0 || first == total);
            total += n;
            CHECK(n >= 1); /* main: the zebra; side: the stop line */
            for (size_t k = first; k < first + n && k < gsv_of(g).ncuts; k++) {
                const float *c = gsv_of(g).cut + 4 * gsv_of(g).nroads + RS_GPU_CUT_FLOATS * k;
                CHECK(fabs(hypot(c[2], c[3]) - 1) < 1e-5 && c[5] > c[4] && c[6] > 0);
            }
        }
        CHECK_EQ_INT(total, gsv_of(g).ncuts);
    }
    rs_gpu_scene_free(ctx, g);
    rs_roads_free(ctx, roads);
    rs_dem_free(ctx, dem);
}

/* Random lane attributes (valid and not): the model always holds its
 * invariants, left-hand traffic is the exact mirror of right-hand, and the
 * default style's lines stay inside the road. */
static uint32_t rnd_state = 12345;
static uint32_t rnd(uint32_t n)
{
    rnd_state = rnd_state * 1664525u + 1013904223u;
    return (rnd_state >> 8) % n;
}

static void test_random_lanes(void)
{
    static const char *const classes[] = { "motorway", "trunk", "primary", "secondary", "tertiary",
                                           "residential", "service", "track", "path", "footway", "cycleway" };
    static const char *const ow[] = { NULL, "yes", "no", "-1" };
    static const char *const counts[] = { NULL, "1", "2", "3", "4", "7", "16", "17", "0", "x", "08" };
    static const char *const turns[] = { NULL, "left", "left|through", "through;right|right", "reverse|left|through",
                                         "|", "none|none|none|none", "left|left|left|left|left|left|left|left|left" };
    static const char *const widths[] = { NULL, "3", "3|3.5", "2.75|3|3.25", "3,5|3", "1e3|2", "3|", "0.5|0.5|0.5|0.5" };
    int bad = 0;
    for (int it = 0; it < 3000; it++) {
        rs_roads *roads = NULL;
        double xy[4] = { 0, 0, 50, 0 };
        double w = 2 + rnd(200) / 10.0;
        if (rs_roads_create(ctx, &roads) != RS_OK) return;
        rs_roads_add(ctx, roads, "r", w, xy, 2);
        rs_roads_set_attr(ctx, roads, 0, "class", classes[rnd(11)]);
        const char *v;
        if ((v = ow[rnd(4)])) rs_roads_set_attr(ctx, roads, 0, "oneway", v);
        if ((v = counts[rnd(8)])) rs_roads_set_attr(ctx, roads, 0, "lanes", v);
        if ((v = counts[rnd(11)])) rs_roads_set_attr(ctx, roads, 0, "lanes:forward", v);
        if ((v = counts[rnd(11)])) rs_roads_set_attr(ctx, roads, 0, "lanes:backward", v);
        if ((v = turns[rnd(8)])) rs_roads_set_attr(ctx, roads, 0, "turn:lanes", v);
        if ((v = turns[rnd(8)])) rs_roads_set_attr(ctx, roads, 0, "turn:lanes:backward", v);
        /* lists (turn:, width:lanes) read from the driver's left on either
         * side: only the rest is a mirror */
        int listed = (v = widths[rnd(8)]) != NULL;
        if (listed) rs_roads_set_attr(ctx, roads, 0, "width:lanes", v);
        rs_style_options so;
        memset(&so, 0, sizeof so);
        so.profile = rnd(2) ? RS_PROFILE_MUTCD : RS_PROFILE_RMS;
        rs_road_lanes R, L;
        CHECK(rs_road_lanes_get(roads, 0, &so, &R) == RS_OK);
        so.driving_side = RS_DRIVING_LEFT;
        CHECK(rs_road_lanes_get(roads, 0, &so, &L) == RS_OK);
        int ok = R.count >= 1 && R.count <= RS_LANES_MAX && L.count == R.count && R.width == w &&
                 R.forward + R.backward <= R.count && fabs(R.lane[0].t_left) <= w / 2 + 1e-9 &&
                 fabs(R.lane[R.count - 1].t_right) <= w / 2 + 1e-9;
        for (uint32_t k = 0; ok && k < R.count; k++) {
            const rs_lane *a = &R.lane[k], *b = &L.lane[R.count - 1 - k];
            ok = a->t_left > a->t_right && (k == 0 || a->t_left == R.lane[k - 1].t_right) &&
                 b->direction == a->direction &&
                 (listed || (fabs(b->t_left + a->t_right) < 1e-9 && fabs(b->t_right + a->t_left) < 1e-9));
        }
        rs_style st;
        so.driving_side = (rs_driving_side)rnd(2);
        ok = ok && rs_road_style_ex(ctx, roads, 0, &so, &st) == RS_OK;
        for (uint32_t k = 0; ok && k < st.line_count; k++)
            ok = fabs(st.line[k].offset) + st.line[k].width / 2 <= w / 2 + 1e-9;
        if (!ok && bad++ < 5) {
            fprintf(stderr, "    random lanes case %d (width %g):", it, w);
            for (size_t k = 0; k < rs_roads_attr_count(roads, 0); k++) {
                const char *key, *val;
                rs_roads_attr_at(roads, 0, k, &key, &val);
                fprintf(stderr, " %s=%s", key, val);
            }
            fprintf(stderr, "\n");
        }
        CHECK(ok);
        rs_roads_free(ctx, roads);
    }
}

#endif

int main(void)
{
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 1;
    test_arrows_and_stop_line();
    test_standard_sizes();
    test_line_ends(line_ends_one);
    test_line_ends(line_ends_split);
    test_markings_split();
    test_lanes_change();
    test_footway_crossing();
    test_class_crossing();
    test_ring_seam();
    test_tee_side_direction();
    test_bend_outside_cut();
    test_cap_cut();
    test_bridge_lines();
    test_marks_under_bridge();
    test_deck_casing();
    test_roundabout_oneway();
    test_line_under_road();
    test_many_crossings();
    test_ring_arm_at_seam();
    test_mirror(RS_PROFILE_RMS);
    test_mirror(RS_PROFILE_MUTCD);
#ifdef RS_LANES_MAX
    test_lane_queries();
    test_random_lanes();
    test_gpu_cuts();
#endif
    rs_ctx_free(ctx);
    return th_finish("test_lanes");
}
