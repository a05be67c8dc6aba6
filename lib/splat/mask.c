/* The 8-neighbour mask table and the alpha-maps.
 *
 * Rule (docs/design.md has the pictures and the proofs):
 *  - A corner of a road cell "touches terrain" when any of the three other
 *    cells around that corner is terrain. That is all a tile depends on: the
 *    4 corner bits, so 256 masks fold onto 16 corner patterns.
 *  - The tile is the signed offset field phi (terrain-ward, in cell units),
 *    piecewise linear on a fan of 8 triangles around the centre: corners are
 *    +1/2 (touch terrain) or -1/2, edge midpoints the mean of their corners,
 *    the centre fixed by the pattern's type. Alpha = clamp(1/2 + phi/w).
 *  - Along a shared edge, phi depends only on the two corner bits of that
 *    edge, which both cells compute from the same 2x2 blocks: seam-free by
 *    construction. Every node value is monotone in terrain-ness: monotone.
 *    Corner bits, the fan and the centre rule commute with D4: equivariant.
 * The paper's 20 masks land on its 3 tiles at the listed rotations.
 */
#include "internal.h"
#include "mask.h"

#include <math.h>
#include <string.h>

/* Corner pattern bits, clockwise from NE so that a 90-degree clockwise turn
 * of the neighbourhood is a 1-bit left rotation of the 4-bit pattern. */
enum { C_NE = 1, C_SE = 2, C_SW = 4, C_NW = 8 };

#define M_N 0x01u
#define M_NE 0x02u
#define M_E 0x04u
#define M_SE 0x08u
#define M_S 0x10u
#define M_SW 0x20u
#define M_W 0x40u
#define M_NW 0x80u

unsigned rs__mask_corners(unsigned m)
{
    unsigned p = 0;
    if ((m & (M_N | M_NE | M_E)) != (M_N | M_NE | M_E)) p |= C_NE;
    if ((m & (M_E | M_SE | M_S)) != (M_E | M_SE | M_S)) p |= C_SE;
    if ((m & (M_S | M_SW | M_W)) != (M_S | M_SW | M_W)) p |= C_SW;
    if ((m & (M_W | M_NW | M_N)) != (M_W | M_NW | M_N)) p |= C_NW;
    return p;
}

static unsigned rotl4(unsigned p, int r)
{
    r &= 3;
    return ((p << r) | (p >> (4 - r))) & 15u;
}

/* Canonical corner patterns (rotation 0) of each type. */
static const unsigned canon_pattern[6] = {
    0,                   /* interior */
    C_NW | C_NE,         /* edge: terrain along N */
    C_NE,                /* inner corner: only the NE corner touches terrain */
    C_NW | C_NE | C_SW,  /* outer corner: road towards SE */
    C_NE | C_SW,         /* saddle: NE and SW inner corners */
    15                   /* all terrain */
};

void rs__pattern_classify(unsigned p, rs_tile_type *type, int *rotation)
{
    for (int t = 0; t < 6; t++)
        for (int r = 0; r < 4; r++)
            if (rotl4(canon_pattern[t], r) == p) {
                *type = (rs_tile_type)t;
                *rotation = r;
                return;
            }
    *type = RS_TILE_INTERIOR; /* unreachable: the 6 orbits cover all 16 */
    *rotation = 0;
}

void rs__mask_table_build(rs__mask_table *t)
{
    for (unsigned m = 0; m < 256; m++) t->corners[m] = (uint8_t)rs__mask_corners(m);
    for (unsigned p = 0; p < 16; p++) {
        rs_tile_type ty;
        int r;
        rs__pattern_classify(p, &ty, &r);
        t->type[p] = (uint8_t)ty;
        t->rot[p] = (uint8_t)r;
    }
}

void rs_mask_classify(uint8_t mask, rs_tile_type *type, int *rotation)
{
    rs_tile_type t;
    int r;
    rs__pattern_classify(rs__mask_corners(mask), &t, &r);
    /* Types whose canonical tile has 4-fold or 2-fold symmetry report the
     * smallest rotation that reproduces them. */
    if (t == RS_TILE_INTERIOR || t == RS_TILE_TERRAIN) r = 0;
    if (type) *type = t;
    if (rotation) *rotation = r;
}

/* Centre value of phi for each type (see the header comment). */
static double centre_phi(rs_tile_type t)
{
    switch (t) {
    case RS_TILE_EDGE: return 0.0;
    case RS_TILE_OUTER:
    case RS_TILE_TERRAIN: return 0.5;
    default: return -0.5; /* interior, inner corner, saddle */
    }
}

double rs__pattern_phi(unsigned p, double u, double v)
{
    rs_tile_type t;
    int r;
    rs__pattern_classify(p, &t, &r);
    double cne = (p & C_NE) ? 0.5 : -0.5, cse = (p & C_SE) ? 0.5 : -0.5;
    double csw = (p & C_SW) ? 0.5 : -0.5, cnw = (p & C_NW) ? 0.5 : -0.5;
    double c = centre_phi(t);
    double dx = u - 0.5, dy = v - 0.5;
    double mid, corner, s, w;
    /* Pick the fan triangle (centre, edge midpoint, corner) holding (u,v). */
    if (fabs(dx) >= fabs(dy)) {
        s = 2.0 * fabs(dx);
        w = 2.0 * fabs(dy);
        if (dx >= 0) { mid = 0.5 * (cne + cse); corner = dy < 0 ? cne : cse; }
        else { mid = 0.5 * (cnw + csw); corner = dy < 0 ? cnw : csw; }
    } else {
        s = 2.0 * fabs(dy);
        w = 2.0 * fabs(dx);
        if (dy < 0) { mid = 0.5 * (cnw + cne); corner = dx < 0 ? cnw : cne; }
        else { mid = 0.5 * (csw + cse); corner = dx < 0 ? csw : cse; }
    }
    return c + s * (mid - c) + w * (corner - mid);
}

double rs__phi_to_alpha(double phi, double w)
{
    if (!(w > 0)) return phi > 0 ? 1.0 : (phi < 0 ? 0.0 : 0.5);
    double a = 0.5 + phi / w;
    return a < 0 ? 0 : (a > 1 ? 1 : a);
}

double rs_tile_alpha(uint8_t mask, double u, double v, double transition)
{
    if (u != u || v != v) return 1.0;
    u = u < 0 ? 0 : (u > 1 ? 1 : u);
    v = v < 0 ? 0 : (v > 1 ? 1 : v);
    return rs__phi_to_alpha(rs__pattern_phi(rs__mask_corners(mask), u, v), transition);
}

/* --- alpha-map rasters ------------------------------------------------------ */

static uint32_t hash32(uint32_t x)
{
    x ^= x >> 16; x *= 0x7feb352dU;
    x ^= x >> 15; x *= 0x846ca68bU;
    x ^= x >> 16;
    return x;
}

/* Smooth seeded noise in [-1,1] on a lattice of `cell` samples. */
static double lattice_noise(uint32_t seed, uint32_t type, double x, double y, double cell)
{
    double gx = x / cell, gy = y / cell;
    double fx0 = floor(gx), fy0 = floor(gy);
    double fx = gx - fx0, fy = gy - fy0;
    uint32_t ix = (uint32_t)fx0, iy = (uint32_t)fy0;
    double v[4];
    for (int k = 0; k < 4; k++) {
        uint32_t h = hash32(seed ^ hash32(type * 0x9E3779B9u ^ hash32((ix + (k & 1)) * 73856093u ^
                                                                  (iy + (k >> 1)) * 19349663u)));
        v[k] = (double)h / 2147483647.5 - 1.0;
    }
    fx = fx * fx * (3 - 2 * fx);
    fy = fy * fy * (3 - 2 * fy);
    return (v[0] * (1 - fx) + v[1] * fx) * (1 - fy) + (v[2] * (1 - fx) + v[3] * fx) * fy;
}

/* Map a sample of a canonical tile to its representative under the tile's
 * own mirror symmetry, so jitter keeps the table D4-equivariant. */
static void mirror_rep(rs_tile_type t, uint32_t res, uint32_t *i, uint32_t *j)
{
    uint32_t a = *i, b = *j;
    if (t == RS_TILE_EDGE) {            /* u <-> 1-u */
        if (b > res - b) b = res - b;
    } else if (t == RS_TILE_INNER) {    /* (u,v) <-> (1-v, 1-u) */
        uint32_t a2 = res - b, b2 = res - a;
        if (a2 < a || (a2 == a && b2 < b)) { a = a2; b = b2; }
    } else if (t == RS_TILE_OUTER) {    /* (u,v) <-> (v,u) */
        if (b < a) { uint32_t x = a; a = b; b = x; }
    }
    *i = a;
    *j = b;
}

/* One alpha-map sample, 0..255: the exact tile, plus symmetrised jitter in
 * the band (never on the border, so seams stay exact). */
static unsigned alpha_sample(rs_tile_type type, uint32_t res, double w, uint32_t seed, double amount,
                             uint32_t i, uint32_t j)
{
    double u = (double)j / res, v = (double)i / res;
    double a = rs__phi_to_alpha(rs__pattern_phi(canon_pattern[type], u, v), w);
    int border = (i == 0 || j == 0 || i == res || j == res);
    if (amount > 0 && !border && a > 0 && a < 1) {
        uint32_t ri = i, rj = j;
        mirror_rep(type, res, &ri, &rj);
        a += amount * lattice_noise(seed, (uint32_t)type, rj, ri, 4.0) * 4.0 * a * (1.0 - a);
        a = a < 0 ? 0 : (a > 1 ? 1 : a);
    }
    return (unsigned)floor(a * 255.0 + 0.5);
}

int rs__alpha_args_ok(rs_tile_type type, uint32_t res, double transition_px, double jitter_amount)
{
    if (res < 2 || res > RS__MAX_ALPHA_RES) return 0;
    if (type != RS_TILE_EDGE && type != RS_TILE_INNER && type != RS_TILE_OUTER) return 0;
    if (transition_px != transition_px || transition_px > (double)res / 2) return 0;
    return jitter_amount == jitter_amount && jitter_amount >= 0 && jitter_amount <= 1;
}

void rs__alpha_map_float(rs_tile_type type, uint32_t res, double transition_px, uint32_t seed,
                         double amount, float *out)
{
    double w = transition_px > 0 ? transition_px / (double)res : 0.0;
    for (uint32_t i = 0; i <= res; i++)
        for (uint32_t j = 0; j <= res; j++)
            out[(size_t)i * (res + 1) + j] = (float)alpha_sample(type, res, w, seed, amount, i, j) / 255.0f;
}

rs_result rs_alpha_map(rs_tile_type type, uint32_t res, double transition_px, uint32_t jitter_seed,
                       double jitter_amount, uint8_t *out, size_t out_size)
{
    if (!out || !rs__alpha_args_ok(type, res, transition_px, jitter_amount)) return RS_ERR_INVALID_ARG;
    if (out_size < (size_t)(res + 1) * (res + 1)) return RS_ERR_BUFFER_TOO_SMALL;
    double w = transition_px > 0 ? transition_px / (double)res : 0.0;
    for (uint32_t i = 0; i <= res; i++)
        for (uint32_t j = 0; j <= res; j++)
            out[(size_t)i * (res + 1) + j] =
                (uint8_t)alpha_sample(type, res, w, jitter_seed, jitter_amount, i, j);
    return RS_OK;
}
