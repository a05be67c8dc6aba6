/* The classification table: paper masks, D4 equivariance, seams, monotonicity,
 * for both the exact tile function and the alpha-map rasters the splat uses. */
#include "harness.h"
#include "roadsplat_experimental.h"

#include <stdint.h>
#include <stdlib.h>

#define RES 32

static unsigned rotl8(unsigned m, int r) { return ((m << r) | (m >> (8 - r))) & 0xFFu; }

/* Mirror left<->right: E<->W, NE<->NW, SE<->SW. */
static unsigned mirror_mask(unsigned m)
{
    static const int to[8] = { 0, 7, 6, 5, 4, 3, 2, 1 };
    unsigned r = 0;
    for (int b = 0; b < 8; b++)
        if (m & (1u << b)) r |= 1u << to[b];
    return r;
}

/* Alpha-map rasters for one (transition, jitter) setting. */
typedef struct maps {
    uint8_t a[3][(RES + 1) * (RES + 1)];
} maps;

static void make_maps(maps *m, double transition, uint32_t seed)
{
    rs_tile_type t[3] = { RS_TILE_EDGE, RS_TILE_INNER, RS_TILE_OUTER };
    for (int i = 0; i < 3; i++)
        CHECK(rs_alpha_map(t[i], RES, transition, seed, 0.6, m->a[i], sizeof m->a[i]) == RS_OK);
}

/* Canonical raster sample (i row, j col) of a type. */
static int canon(const maps *m, rs_tile_type t, int i, int j)
{
    switch (t) {
    case RS_TILE_INTERIOR: return 0;
    case RS_TILE_TERRAIN: return 255;
    case RS_TILE_EDGE: return m->a[0][i * (RES + 1) + j];
    case RS_TILE_INNER: return m->a[1][i * (RES + 1) + j];
    case RS_TILE_OUTER: return m->a[2][i * (RES + 1) + j];
    default: return -1;
    }
}

/* Sample (i, j) of the canonical tile turned r quarter turns clockwise:
 * the turned tile at (u,v) is the canonical one at (v, 1-u). */
static int turned(const maps *m, rs_tile_type t, int r, int i, int j)
{
    for (int k = 0; k < (r & 3); k++) {
        int ni = RES - j, nj = i; /* (u,v)=(j,i) -> (v, 1-u) = (i, RES-j) as (col,row) */
        i = ni;
        j = nj;
    }
    return canon(m, t, i, j);
}

/* Raster tile of a mask, as the splat reads it (saddle = sum of 2 inner corners). */
static int raster_alpha(const maps *m, unsigned mask, int i, int j)
{
    rs_tile_type t;
    int r;
    rs_mask_classify((uint8_t)mask, &t, &r);
    if (t == RS_TILE_SADDLE) {
        int a = turned(m, RS_TILE_INNER, r, i, j) + turned(m, RS_TILE_INNER, r + 2, i, j);
        return a > 255 ? 255 : a;
    }
    return turned(m, t, r, i, j);
}

static void test_paper_table(void)
{
    struct { unsigned mask; rs_tile_type type; int rot; } rows[] = {
        { 0x7C, RS_TILE_EDGE, 0 }, { 0xF1, RS_TILE_EDGE, 1 }, { 0xC7, RS_TILE_EDGE, 2 }, { 0x1F, RS_TILE_EDGE, 3 },
        { 0xFD, RS_TILE_INNER, 0 }, { 0xF7, RS_TILE_INNER, 1 }, { 0xDF, RS_TILE_INNER, 2 }, { 0x7F, RS_TILE_INNER, 3 },
        { 0x1C, RS_TILE_OUTER, 0 }, { 0x3C, RS_TILE_OUTER, 0 }, { 0x1E, RS_TILE_OUTER, 0 },
        { 0x70, RS_TILE_OUTER, 1 }, { 0x78, RS_TILE_OUTER, 1 }, { 0xF0, RS_TILE_OUTER, 1 },
        { 0xC1, RS_TILE_OUTER, 2 }, { 0xC3, RS_TILE_OUTER, 2 }, { 0xE1, RS_TILE_OUTER, 2 },
        { 0x07, RS_TILE_OUTER, 3 }, { 0x0F, RS_TILE_OUTER, 3 }, { 0x87, RS_TILE_OUTER, 3 },
        { 0xFF, RS_TILE_INTERIOR, 0 },
    };
    for (size_t i = 0; i < sizeof rows / sizeof rows[0]; i++) {
        rs_tile_type t;
        int r;
        rs_mask_classify((uint8_t)rows[i].mask, &t, &r);
        CHECKF(t == rows[i].type && r == rows[i].rot, "mask 0x%02X: type %d rot %d, expected %d rot %d",
               rows[i].mask, t, r, rows[i].type, rows[i].rot);
    }
    /* Every mask is defined. */
    int bad = 0;
    for (unsigned m = 0; m < 256; m++) {
        rs_tile_type t = (rs_tile_type)-1;
        int r = -1;
        rs_mask_classify((uint8_t)m, &t, &r);
        if ((int)t < 0 || t > RS_TILE_TERRAIN || r < 0 || r > 3) bad++;
    }
    CHECK_EQ_INT(bad, 0);
    /* The paper's geometry (hard edge, away from the line): edge through the
     * centre; inner corner cut between the N and E midpoints; outer corner cut
     * between the E and S midpoints. */
    int wrong = 0;
    for (int i = 0; i < 40; i++)
        for (int j = 0; j < 40; j++) {
            double u = (j + 0.5) / 40, v = (i + 0.5) / 40;
            double e = rs_tile_alpha(0x7C, u, v, 0), in = rs_tile_alpha(0xFD, u, v, 0), out = rs_tile_alpha(0x1C, u, v, 0);
            if (fabs(v - 0.5) > 1e-9 && e != (v < 0.5 ? 1.0 : 0.0)) wrong++;
            if (fabs(u - v - 0.5) > 1e-9 && in != (u - v > 0.5 ? 1.0 : 0.0)) wrong++;
            if (fabs(u + v - 1.5) > 1e-9 && out != (u + v > 1.5 ? 0.0 : 1.0)) wrong++;
        }
    CHECK_EQ_INT(wrong, 0);
    /* Interior is all road; an isolated cell all terrain. */
    CHECK(rs_tile_alpha(0xFF, 0.3, 0.7, 0.1) == 0.0);
    CHECK(rs_tile_alpha(0x00, 0.5, 0.5, 0.1) == 1.0);
}

/* Compare a mask's tile with the transformed tile of its image under D4. */
static void test_d4(void)
{
    maps m[2];
    make_maps(&m[0], 2.0, 0);
    make_maps(&m[1], 3.0, 12345); /* jitter is symmetrised, so D4 holds too */
    int bad_exact = 0, bad_raster = 0;
    for (unsigned mask = 0; mask < 256; mask++) {
        for (int s = 0; s < 8; s++) {
            int r = s & 3, mir = s >> 2;
            unsigned gm = mir ? mirror_mask(mask) : mask;
            gm = rotl8(gm, 2 * r);
            for (int i = 0; i <= RES; i++)
                for (int j = 0; j <= RES; j++) {
                    /* point (j,i) of the original maps to g(point) in the image */
                    int ii = i, jj = mir ? RES - j : j;
                    for (int k = 0; k < r; k++) { int ni = jj, nj = RES - ii; ii = ni; jj = nj; }
                    double a0 = rs_tile_alpha((uint8_t)mask, (double)j / RES, (double)i / RES, 0.07);
                    double a1 = rs_tile_alpha((uint8_t)gm, (double)jj / RES, (double)ii / RES, 0.07);
                    if (fabs(a0 - a1) > 1e-12) bad_exact++;
                    for (int q = 0; q < 2; q++)
                        if (raster_alpha(&m[q], mask, i, j) != raster_alpha(&m[q], gm, ii, jj)) bad_raster++;
                }
        }
    }
    CHECKF(bad_exact == 0, "%d exact samples break D4", bad_exact);
    CHECKF(bad_raster == 0, "%d raster samples break D4", bad_raster);
}

/* Two cells side by side in a 3-row x 4-column window: cells (1,1)=A and
 * (1,2)=B; the other 10 cells take every configuration. */
static unsigned window_mask(int w[3][4], int r, int c)
{
    static const int dr[8] = { -1, -1, 0, 1, 1, 1, 0, -1 }, dc[8] = { 0, 1, 1, 1, 0, -1, -1, -1 };
    unsigned m = 0;
    for (int b = 0; b < 8; b++) {
        int rr = r + dr[b], cc = c + dc[b];
        if (w[rr][cc]) m |= 1u << b;
    }
    return m;
}

static void test_seams(void)
{
    maps mp;
    make_maps(&mp, 2.0, 777);
    double worst_exact = 0;
    int worst_raster = 0, cases = 0;
    for (int ab = 1; ab < 4; ab++) {          /* A,B road/terrain, not both terrain */
        for (unsigned cfg = 0; cfg < 1024; cfg++) {
            int w[3][4], bit = 0;
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 4; c++) {
                    if (r == 1 && c == 1) w[r][c] = ab & 1;
                    else if (r == 1 && c == 2) w[r][c] = (ab >> 1) & 1;
                    else w[r][c] = (cfg >> bit++) & 1;
                }
            unsigned ma = window_mask(w, 1, 1), mb = window_mask(w, 1, 2);
            /* Horizontal pair: A's east edge against B's west edge. The same
             * window read transposed gives the vertical pair (A over B). */
            unsigned ta = 0, tb = 0;
            {
                /* transpose: swap N<->W, NE<->SW(?) -> map (dr,dc) to (dc,dr) */
                static const int to[8] = { 6, 5, 4, 3, 2, 1, 0, 7 };
                for (int b = 0; b < 8; b++) {
                    if (ma & (1u << b)) ta |= 1u << to[b];
                    if (mb & (1u << b)) tb |= 1u << to[b];
                }
            }
            for (int k = 0; k <= 4 * RES; k++) {
                double v = (double)k / (4 * RES);
                double aA = (ab & 1) ? rs_tile_alpha((uint8_t)ma, 1.0, v, 0.0625) : 1.0;
                double aB = (ab & 2) ? rs_tile_alpha((uint8_t)mb, 0.0, v, 0.0625) : 1.0;
                if (fabs(aA - aB) > worst_exact) worst_exact = fabs(aA - aB);
                /* transposed: A above B, A's south edge against B's north edge */
                double tA = (ab & 1) ? rs_tile_alpha((uint8_t)ta, v, 1.0, 0.0625) : 1.0;
                double tB = (ab & 2) ? rs_tile_alpha((uint8_t)tb, v, 0.0, 0.0625) : 1.0;
                if (fabs(tA - tB) > worst_exact) worst_exact = fabs(tA - tB);
            }
            for (int i = 0; i <= RES; i++) {
                int aA = (ab & 1) ? raster_alpha(&mp, ma, i, RES) : 255;
                int aB = (ab & 2) ? raster_alpha(&mp, mb, i, 0) : 255;
                int tA = (ab & 1) ? raster_alpha(&mp, ta, RES, i) : 255;
                int tB = (ab & 2) ? raster_alpha(&mp, tb, 0, i) : 255;
                if (abs(aA - aB) > worst_raster) worst_raster = abs(aA - aB);
                if (abs(tA - tB) > worst_raster) worst_raster = abs(tA - tB);
            }
            cases++;
        }
    }
    CHECK_EQ_INT(cases, 3 * 1024);
    CHECKF(worst_exact <= 1.0 / 255, "exact seam error %g", worst_exact);
    CHECKF(worst_raster <= 1, "raster seam error %d/255", worst_raster);
}

static void test_monotone(void)
{
    maps mp;
    make_maps(&mp, 2.0, 0);
    int bad = 0;
    for (unsigned m = 0; m < 256; m++)
        for (int b = 0; b < 8; b++) {
            if (m & (1u << b)) continue;
            unsigned m2 = m | (1u << b);
            for (int i = 0; i <= RES; i++)
                for (int j = 0; j <= RES; j++) {
                    if (raster_alpha(&mp, m2, i, j) > raster_alpha(&mp, m, i, j)) bad++;
                    double u = (j + 0.37) / (RES + 1), v = (i + 0.61) / (RES + 1);
                    if (rs_tile_alpha((uint8_t)m2, u, v, 0.1) > rs_tile_alpha((uint8_t)m, u, v, 0.1)) bad++;
                }
        }
    CHECKF(bad == 0, "%d samples lose road weight when a neighbour becomes road", bad);
}

static void test_alpha_map_api(void)
{
    uint8_t buf[(RES + 1) * (RES + 1)];
    CHECK(rs_alpha_map(RS_TILE_EDGE, RES, 2, 0, 0, buf, sizeof buf) == RS_OK);
    CHECK_EQ_INT(buf[0], 255);                         /* N side terrain */
    CHECK_EQ_INT(buf[RES * (RES + 1)], 0);             /* S side road */
    CHECK_EQ_INT(buf[(RES / 2) * (RES + 1) + 3], 128); /* the edge line itself: alpha 0.5 */
    CHECK(rs_alpha_map(RS_TILE_EDGE, RES, 2, 0, 0, buf, sizeof buf - 1) == RS_ERR_BUFFER_TOO_SMALL);
    CHECK(rs_alpha_map(RS_TILE_SADDLE, RES, 2, 0, 0, buf, sizeof buf) == RS_ERR_INVALID_ARG);
    CHECK(rs_alpha_map(RS_TILE_EDGE, 1, 2, 0, 0, buf, sizeof buf) == RS_ERR_INVALID_ARG);
    CHECK(rs_alpha_map(RS_TILE_EDGE, RES, RES, 0, 0, buf, sizeof buf) == RS_ERR_INVALID_ARG);
    CHECK(rs_alpha_map(RS_TILE_EDGE, RES, 2, 1, 2.0, buf, sizeof buf) == RS_ERR_INVALID_ARG);
    CHECK(rs_alpha_map(RS_TILE_EDGE, RES, 2, 0, 0, NULL, 0) == RS_ERR_INVALID_ARG);
    /* Jitter changes the band, never the border. */
    uint8_t j1[(RES + 1) * (RES + 1)];
    CHECK(rs_alpha_map(RS_TILE_INNER, RES, 6, 99, 1.0, j1, sizeof j1) == RS_OK);
    CHECK(rs_alpha_map(RS_TILE_INNER, RES, 6, 0, 0, buf, sizeof buf) == RS_OK);
    int border_diff = 0, band_diff = 0;
    for (int i = 0; i <= RES; i++)
        for (int j = 0; j <= RES; j++) {
            int d = buf[i * (RES + 1) + j] != j1[i * (RES + 1) + j];
            if (i == 0 || j == 0 || i == RES || j == RES) border_diff += d;
            else band_diff += d;
        }
    CHECK_EQ_INT(border_diff, 0);
    CHECK(band_diff > 0);
    /* Hard edges: only 0, 128 (on the line) and 255. */
    CHECK(rs_alpha_map(RS_TILE_OUTER, RES, -1, 0, 0, buf, sizeof buf) == RS_OK);
    int other = 0;
    for (size_t i = 0; i < sizeof buf; i++)
        if (buf[i] != 0 && buf[i] != 255 && buf[i] != 128) other++;
    CHECK_EQ_INT(other, 0);
}

int main(void)
{
    test_paper_table();
    test_d4();
    test_seams();
    test_monotone();
    test_alpha_map_api();
    return th_finish("test_mask");
}
