/* Splat options: validation and defaults, shared by the road grid and the
 * splatter (one meaning per field; see include/roadsplat.h). */
#include "internal.h"
#include "mask.h"

#include <math.h>
#include <string.h>

rs_result rs__splat_defaults(rs_ctx *ctx, const rs_splat_options *in, rs_splat_options *out)
{
    rs_splat_options o;
    rs_result r = RS__OPTS_IN(ctx, in, &o, rs_splat_options);
    if (r) return r;
    /* the nested structs' own sizes mean nothing here (the outer size
     * covers them): make them this layout's for the calls that take them
     * alone (rs_road_style_ex, rs_normal_window) */
    o.style.size = sizeof o.style;
    o.lighting.normal.size = sizeof o.lighting.normal;
    rs_coverage_options *c = &o.coverage;
    rs_surface_options *f = &o.surface;
    if (o.texels == 0) o.texels = 8;
    if (c->alpha_res == 0) c->alpha_res = 32;
    if (c->transition_px == 0) c->transition_px = 2;
    if (c->jitter_amount == 0) c->jitter_amount = 0.5;
    if (f->texture_scale == 0) f->texture_scale = 10;
    if (o.texels > 1024) return rs__fail(ctx, RS_ERR_INVALID_ARG, "texels %u must be 1..1024", o.texels);
    if (o.grid.buffer != RS_BUFFER_DISTANCE && o.grid.buffer != RS_BUFFER_DILATE)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "unknown buffer mode %d", (int)o.grid.buffer);
    if (!(o.grid.road_cell >= 0 && o.grid.road_cell <= 1e9))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "road cell %g must be in [0, 1e9] metres (0 = automatic)",
                        o.grid.road_cell);
    if (c->edges != RS_EDGES_ALPHAMAP && c->edges != RS_EDGES_ANALYTIC)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "unknown edge mode %d", (int)c->edges);
    if (c->alpha_res < 2 || c->alpha_res > RS__MAX_ALPHA_RES)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "alpha-map resolution %u must be 2..%u", c->alpha_res,
                        RS__MAX_ALPHA_RES);
    if (!(c->transition_px > 0 && c->transition_px <= c->alpha_res / 2.0))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "transition %g px must be > 0 and at most half the alpha-map (%u px)",
                        c->transition_px, c->alpha_res / 2);
    if (!(c->jitter_amount > 0 && c->jitter_amount <= 1))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "jitter amount %g must be in (0,1]", c->jitter_amount);
    if (!(f->texture_scale >= 1e-6 && f->texture_scale <= 1e9))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "texture scale %g must be in [1e-6, 1e9] metres", f->texture_scale);
    if (o.style.profile != RS_PROFILE_RMS && o.style.profile != RS_PROFILE_MUTCD)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "unknown style profile %d", (int)o.style.profile);
    if (o.style.aa != RS_LINE_AA_EXACT && o.style.aa != RS_LINE_AA_HERMITE)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "unknown line anti-aliasing %d", (int)o.style.aa);
    if (f->tint != RS_TINT_ABSOLUTE && f->tint != RS_TINT_RELATIVE)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "unknown tint mode %d", (int)f->tint);
    if (f->ramp || f->ramp_count) {
        if (!f->ramp || f->ramp_count < 2 || f->ramp_count > RS_RAMP_MAX_STOPS)
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "colour ramp of %zu stops%s: it needs 2..%d", f->ramp_count,
                            f->ramp ? "" : " (NULL)", RS_RAMP_MAX_STOPS);
        for (size_t i = 0; i < f->ramp_count; i++) {
            double hgt = f->ramp[i].height;
            if (!(fabs(hgt) <= 1e9))
                return rs__fail(ctx, RS_ERR_INVALID_ARG, "colour ramp stop %zu: height %g must be finite (|h| <= 1e9 m)",
                                i, hgt);
            if (i && !(hgt > f->ramp[i - 1].height))
                return rs__fail(ctx, RS_ERR_INVALID_ARG,
                                "colour ramp stop %zu: height %g must be above the previous stop's %g", i, hgt,
                                f->ramp[i - 1].height);
        }
    }
    if (f->height_min != 0 || f->height_max != 0) {
        if (!(fabs(f->height_min) <= 1e9 && fabs(f->height_max) <= 1e9 && f->height_min < f->height_max))
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "height range %g..%g must be finite with min < max",
                            f->height_min, f->height_max);
    }
    if (f->texel_offset_x > ((int64_t)1 << 52) || f->texel_offset_x < -((int64_t)1 << 52) ||
        f->texel_offset_y > ((int64_t)1 << 52) || f->texel_offset_y < -((int64_t)1 << 52))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "texel offset %lld, %lld must be within 2^52",
                        (long long)f->texel_offset_x, (long long)f->texel_offset_y);
    const rs_image *tex[2] = { f->terrain_texture, f->road_texture };
    for (int i = 0; i < 2; i++)
        if (tex[i]) {
            if (!tex[i]->rgba || tex[i]->width == 0 || tex[i]->height == 0)
                return rs__fail(ctx, RS_ERR_INVALID_ARG, "%s texture is empty", i ? "road" : "terrain");
            if ((uint64_t)tex[i]->width * tex[i]->height > ctx->limits.max_texture_pixels)
                return rs__fail(ctx, RS_ERR_LIMIT, "%s texture of %u x %u pixels exceeds the limit of %llu pixels",
                                i ? "road" : "terrain", tex[i]->width, tex[i]->height,
                                (unsigned long long)ctx->limits.max_texture_pixels);
        }
    /* the surface-image table: a count needs its array, every entry a name
     * and, when it has a size, pixels (checked whether a style uses the
     * entry or not; an empty image is refused when a style uses it) */
    const rs_style_options *so = &o.style;
    if (so->surface_image_count && !so->surface_images)
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "style.surface_images is NULL but surface_image_count is %zu",
                        so->surface_image_count);
    for (size_t k = 0; k < so->surface_image_count; k++) {
        const rs_surface_image *si = &so->surface_images[k];
        if (!si->name)
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "style.surface_images[%zu]: name is NULL", k);
        if (!si->image.rgba && si->image.width && si->image.height)
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "style.surface_images[%zu]: %u x %u pixels at NULL", k,
                            si->image.width, si->image.height);
    }
    *out = o;
    return RS_OK;
}
