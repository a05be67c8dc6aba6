/* libFuzzer target: raw doubles (any bit pattern: NaN, infinities,
 * subnormals, 1e308) into every numeric option of every entry point -
 * the DEM frame, the splat options by stage, road widths and points, the
 * road-field query, the ROAM options, refinement, the view and the mesh
 * options, the alpha-map functions - on a small fixed scene. Issue 19's
 * class 8: options are range-checked up front, so nothing downstream can
 * overflow, divide by zero or convert a NaN to an integer (UBSan with
 * float-cast-overflow and float-divide-by-zero traps here).
 *
 * Input: a sequence of 8-byte little-endian doubles (short input reads as
 * zero bytes) consumed in a fixed order, see next_d() calls below.
 * Findings (abort): an unknown result code, success with a non-finite
 * output value, an object returned on failure, or a sanitizer report. */
#include "roadsplat_experimental.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define REQUIRE(c) do { if (!(c)) abort(); } while (0)

typedef struct reader {
    const uint8_t *p;
    size_t n, i;
} reader;

static double next_d(reader *r)
{
    uint64_t u = 0;
    for (int k = 0; k < 8; k++) u |= (uint64_t)(r->i < r->n ? r->p[r->i++] : 0) << (8 * k);
    double d;
    memcpy(&d, &u, sizeof d);
    return d;
}

/* A double's low bits as a small count, for the few integer options. */
static uint32_t next_u(reader *r, uint32_t mod)
{
    double d = next_d(r);
    uint64_t u;
    memcpy(&u, &d, sizeof u);
    return (uint32_t)(u % mod);
}

static int known(rs_result r) { return r >= RS_OK && r <= RS_ERR_CANCELLED; }

static void fuzz_splat(rs_ctx *ctx, rs_dem *dem, reader *rd)
{
    rs_roads *roads = NULL;
    REQUIRE(rs_roads_create(ctx, &roads) == RS_OK);
    for (int k = 0; k < 2; k++) {
        double w = next_d(rd), xy[6];
        for (int i = 0; i < 6; i++) xy[i] = next_d(rd);
        rs_result r = rs_roads_add(ctx, roads, "r", w, xy, 3);
        REQUIRE(known(r));
        if (!(w > 0) || !isfinite(w)) REQUIRE(r != RS_OK);
    }
    rs_splat_options o;
    memset(&o, 0, sizeof o);
    o.texels = 1 + next_u(rd, 3);
    o.grid.buffer = (rs_buffer_mode)next_u(rd, 2);
    o.grid.road_cell = next_d(rd);
    o.coverage.edges = (rs_edge_mode)next_u(rd, 2);
    o.coverage.alpha_res = next_u(rd, 40);
    o.coverage.hard_edge = (int)next_u(rd, 2);
    o.coverage.transition_px = next_d(rd);
    o.coverage.jitter = (int)next_u(rd, 2);
    o.coverage.jitter_seed = next_u(rd, 0xFFFFFFFFu);
    o.coverage.jitter_amount = next_d(rd);
    uint8_t tex_px[4 * 4 * 4];
    for (size_t i = 0; i < sizeof tex_px; i++) tex_px[i] = (uint8_t)(i * 29);
    rs_image tex = { 4, 4, tex_px };
    if (next_u(rd, 2)) o.surface.terrain_texture = &tex;
    if (next_u(rd, 2)) o.surface.road_texture = &tex;
    o.surface.texture_scale = next_d(rd);
    /* styles last, so older corpus inputs keep their meaning: raw enums,
     * and classes on the roads (lines, kerbs, fills) */
    o.style.profile = (rs_profile)next_u(rd, 3);
    o.style.aa = (rs_line_aa)next_u(rd, 3);
    o.style.disable = (int)next_u(rd, 2);
    static const char *const cls[] = { "motorway", "primary", "residential", "track", "footway" };
    for (size_t k = 0; k < rs_roads_count(roads); k++) {
        uint32_t c = next_u(rd, 6);
        if (c < 5) REQUIRE(rs_roads_set_attr(ctx, roads, k, "class", cls[c]) == RS_OK);
    }
    /* issue 16: lighting and a road-aligned surface image, raw doubles */
    o.lighting.enable = (int)next_u(rd, 2);
    o.lighting.sun_given = (int)next_u(rd, 2);
    o.lighting.sun_azimuth = next_d(rd);
    o.lighting.sun_altitude = next_d(rd);
    o.lighting.ambient = next_d(rd);
    o.lighting.specular = next_d(rd);
    o.lighting.normal.strength = next_d(rd);
    o.lighting.normal.paint_height = next_d(rd);
    rs_styles *sty = NULL;
    rs_surface_image si = { "s", { 4, 4, tex_px } };
    if (next_u(rd, 2) && rs_roads_count(roads)) {
        REQUIRE(rs_styles_create(ctx, &sty) == RS_OK);
        rs_style st;
        memset(&st, 0, sizeof st);
        strcpy(st.name, "img");
        strcpy(st.surface_image, "s");
        st.surface_length = next_d(rd);
        rs_result ar = rs_styles_add(ctx, sty, &st);
        REQUIRE(known(ar));
        if (ar == RS_OK) {
            o.style.styles = sty;
            o.style.surface_images = &si;
            o.style.surface_image_count = 1;
            REQUIRE(rs_roads_set_attr(ctx, roads, 0, "style", "img") == RS_OK);
        }
    }
    /* issue 28: the tint mode, a ramp of raw doubles (0..3 stops), a height
     * range and texel offsets up to and past their 2^52 bound */
    rs_colour_stop ramp[3];
    o.surface.tint = (rs_tint_mode)next_u(rd, 3);
    uint32_t nramp = next_u(rd, 4);
    for (int i = 0; i < 3; i++) {
        ramp[i].height = next_d(rd);
        ramp[i].colour.r = (uint8_t)next_u(rd, 256);
        ramp[i].colour.g = (uint8_t)next_u(rd, 256);
        ramp[i].colour.b = (uint8_t)next_u(rd, 256);
        ramp[i].colour.a = 255;
    }
    if (nramp) {
        o.surface.ramp = ramp;
        o.surface.ramp_count = nramp;
    }
    o.surface.height_min = next_d(rd);
    o.surface.height_max = next_d(rd);
    o.surface.texel_offset_x = ((int64_t)next_u(rd, 0xFFFFFFFFu) - 0x7FFFFFFF) * (int64_t)(1 + next_u(rd, 1u << 21));
    o.surface.texel_offset_y = ((int64_t)next_u(rd, 0xFFFFFFFFu) - 0x7FFFFFFF) * (int64_t)(1 + next_u(rd, 1u << 21));
    /* issue 30: the grid's edit pieces (their budgets: huge widths and coordinates) */
    o.grid.edits = (int)next_u(rd, 2);
    rs_splatter *s = (rs_splatter *)&o;
    rs_result r = rs_splatter_create(ctx, dem, roads, NULL, &o, &s);
    REQUIRE(known(r));
    if (r != RS_OK) {
        REQUIRE(s == NULL);
    } else {
        uint32_t w, h;
        rs_splatter_size(s, &w, &h);
        uint32_t x0 = next_u(rd, w), y0 = next_u(rd, h);
        uint32_t ww = 1 + next_u(rd, w - x0), hh = 1 + next_u(rd, h - y0);
        uint8_t *px = malloc((size_t)ww * hh * 4);
        uint16_t *wt = malloc((size_t)ww * hh * 2);
        if (px && wt) {
            r = rs_splat_window(ctx, s, x0, y0, ww, hh, px, (size_t)ww * 4, wt, ww, NULL);
            REQUIRE(r == RS_OK || r == RS_ERR_NOMEM);
        }
        free(px);
        free(wt);
        REQUIRE(rs_road_grid_rect_has_roads(rs_splatter_grid(s), x0, y0, x0 + ww, y0 + hh) <= 1);
        rs_road_point p;
        double qx = next_d(rd), qy = next_d(rd), reach = next_d(rd);
        if (rs_road_grid_query(rs_splatter_grid(s), qx, qy, reach, &p))
            REQUIRE(p.road < 2 && isfinite(p.s) && isfinite(p.t) && p.distance >= 0);
        rs_splatter_free(ctx, s);
    }
    rs_styles_free(ctx, sty);
    rs_roads_free(ctx, roads);
}

static void fuzz_roam(rs_ctx *ctx, rs_dem *dem, reader *rd)
{
    rs_roam_options o;
    memset(&o, 0, sizeof o);
    o.pool_nodes = next_u(rd, 4096);
    o.patch_size = 1u << next_u(rd, 6);
    rs_roam *L = (rs_roam *)&o;
    rs_result r = rs_roam_create(ctx, dem, &o, &L);
    REQUIRE(known(r));
    if (r != RS_OK) { REQUIRE(L == NULL); return; }
    switch (next_u(rd, 3)) {
    case 0: r = rs_roam_refine_error(ctx, L, next_d(rd)); break;
    case 1: r = rs_roam_refine_count(ctx, L, next_u(rd, 100000)); break;
    default: {
        rs_roam_view v;
        memset(&v, 0, sizeof v);
        for (int i = 0; i < 3; i++) v.eye[i] = next_d(rd);
        for (int i = 0; i < 3; i++) v.dir[i] = next_d(rd);
        v.fov_y = next_d(rd);
        v.width = next_u(rd, 5000);
        v.height = next_u(rd, 5000);
        v.pixel_error = next_d(rd);
        v.target_triangles = next_u(rd, 3) ? 0 : next_u(rd, 10000);
        v.far_dist = next_d(rd);
        r = rs_roam_frame(ctx, L, &v);
    }
    }
    REQUIRE(known(r));
    rs_roam_mesh_options mo;
    memset(&mo, 0, sizeof mo);
    mo.normals = (int)next_u(rd, 2);
    mo.skirt_depth = next_d(rd);
    size_t mv = 0, mi = 0, nv = 0, ni = 0;
    rs_roam_mesh_bound(L, &mo, &mv, &mi);
    float *vtx = malloc((mv + 1) * 5 * sizeof *vtx), *nrm = malloc((mv + 1) * 3 * sizeof *nrm);
    uint32_t *idx = malloc((mi + 1) * sizeof *idx);
    if (vtx && nrm && idx) {
        r = rs_roam_extract(ctx, L, &mo, vtx, nrm, mv, idx, mi, &nv, &ni);
        REQUIRE(known(r));
        if (r == RS_OK) {
            for (size_t k = 0; k < nv * 5; k++) REQUIRE(isfinite(vtx[k]));
            if (mo.normals)
                for (size_t k = 0; k < nv * 3; k++) REQUIRE(isfinite(nrm[k]));
            for (size_t k = 0; k < ni; k++) REQUIRE(idx[k] < nv);
        }
    }
    free(vtx);
    free(nrm);
    free(idx);
    rs_roam_free(ctx, L);
}

static void fuzz_alpha(reader *rd)
{
    double u = next_d(rd), v = next_d(rd), tr = next_d(rd);
    double a = rs_tile_alpha((uint8_t)next_u(rd, 256), u, v, tr);
    (void)a; /* any value; it must only not trap */
    uint8_t out[9 * 9];
    rs_result r = rs_alpha_map((rs_tile_type)next_u(rd, 6), 8, next_d(rd), next_u(rd, 1000), next_d(rd), out,
                               sizeof out);
    REQUIRE(known(r));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    reader rd = { data, size, 0 };
    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_pixels = (uint64_t)1 << 14;
    lim.max_road_cells = (uint64_t)1 << 16;
    lim.max_pool_nodes = 1u << 14;
    rs_ctx *ctx = NULL;
    if (rs_ctx_create(NULL, &lim, &ctx) != RS_OK) return 0;
    float z[9 * 7];
    for (int i = 0; i < 9 * 7; i++) z[i] = (float)((i * 37) % 23);
    z[10] = NAN;
    z[20] = (float)next_d(&rd); /* any float value but inf is a valid sample */
    if (isinf(z[20])) z[20] = NAN;
    rs_dem *dem = NULL;
    REQUIRE(rs_dem_create(ctx, 9, 7, z, &dem) == RS_OK);
    rs_dem_frame fr = { next_d(&rd), next_d(&rd), next_d(&rd), next_d(&rd) };
    rs_result r = rs_dem_set_frame(ctx, dem, &fr);
    REQUIRE(r == RS_OK || r == RS_ERR_INVALID_ARG);
    if (r == RS_OK) {
        rs_dem_frame got;
        rs_dem_get_frame(dem, &got);
        REQUIRE(got.cell_size > 0 && isfinite(got.cell_size) && isfinite(got.z_scale) && got.z_scale != 0);
    }
    switch (next_u(&rd, 3)) {
    case 0: fuzz_splat(ctx, dem, &rd); break;
    case 1: fuzz_roam(ctx, dem, &rd); break;
    default: fuzz_alpha(&rd); break;
    }
    rs_dem_free(ctx, dem);
    rs_ctx_free(ctx);
    return 0;
}
