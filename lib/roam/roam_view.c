/* ROAM view-dependent mode: the view frustum, per-patch culling and the
 * tolerance feedback of rs_roam_frame (docs/roam.md, "View-dependent mode"). */
#include "roam.h"

#include <math.h>
#include <string.h>

#define FRAME_MAX_PASSES 12

static rs_result make_view(rs_ctx *ctx, const rs_roam *L, const rs_roam_view *vw, view_params *v)
{
    memset(v, 0, sizeof *v);
    double fov = vw->fov_y == 0.0 ? 60.0 : vw->fov_y;
    double wpx = vw->width ? vw->width : 1280, hpx = vw->height ? vw->height : 720;
    for (int i = 0; i < 3; i++)
        if (!isfinite(vw->eye[i]) || !isfinite(vw->dir[i]))
            return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM view: eye and dir must be finite");
    if (!(fov > 0.0 && fov < 179.0))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM view: fov_y %g must be in (0, 179) degrees", fov);
    if (!(vw->pixel_error >= 0.0) || !isfinite(vw->pixel_error) || !(vw->far_dist >= 0.0))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM view: pixel_error and far_dist must be >= 0");
    if (!(vw->merge_hysteresis == 0.0 || (vw->merge_hysteresis >= 1.0 && isfinite(vw->merge_hysteresis))))
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM view: merge_hysteresis %g must be 0 or >= 1", vw->merge_hysteresis);
    double fl = sqrt(vw->dir[0] * vw->dir[0] + vw->dir[1] * vw->dir[1] + vw->dir[2] * vw->dir[2]);
    if (!(fl > 0.0)) return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM view: dir must not be zero");
    double f[3] = { vw->dir[0] / fl, vw->dir[1] / fl, vw->dir[2] / fl };
    /* right = f x up(z); looking straight down, take the map's x axis */
    double rt[3] = { f[1], -f[0], 0.0 };
    double rl = sqrt(rt[0] * rt[0] + rt[1] * rt[1]);
    if (rl < 1e-9) { rt[0] = 1; rt[1] = 0; rl = 1; }
    rt[0] /= rl; rt[1] /= rl;
    double up[3] = { rt[1] * f[2] - rt[2] * f[1], rt[2] * f[0] - rt[0] * f[2], rt[0] * f[1] - rt[1] * f[0] };
    double ty = tan(fov * 0.5 * 3.14159265358979323846 / 180.0), tx = ty * wpx / hpx;
    if (!(ty >= 1e-9)) /* a subnormal fov_y: no finite projection */
        return rs__fail(ctx, RS_ERR_INVALID_ARG, "ROAM view: fov_y %g degrees is too small", fov);
    memcpy(v->eye, vw->eye, sizeof v->eye);
    memcpy(v->f, f, sizeof f);
    double sx = sqrt(1 + tx * tx), sy = sqrt(1 + ty * ty);
    double nrm[5][3];
    for (int i = 0; i < 3; i++) {
        nrm[0][i] = (f[i] * tx - rt[i]) / sx;
        nrm[1][i] = (f[i] * tx + rt[i]) / sx;
        nrm[2][i] = (f[i] * ty - up[i]) / sy;
        nrm[3][i] = (f[i] * ty + up[i]) / sy;
        nrm[4][i] = f[i];
    }
    for (int p = 0; p < 5; p++) {
        v->planes[p][0] = nrm[p][0]; v->planes[p][1] = nrm[p][1]; v->planes[p][2] = nrm[p][2];
        v->planes[p][3] = -(nrm[p][0] * vw->eye[0] + nrm[p][1] * vw->eye[1] + nrm[p][2] * vw->eye[2]);
    }
    v->nplanes = 5; /* the far limit is applied per patch */
    v->k = hpx / (2.0 * ty);
    (void)L;
    return RS_OK;
}

static int patch_visible(const rs_roam *L, const view_params *v, uint32_t p, double far_dist)
{
    uint32_t px = p % L->npx, py = p / L->npx;
    double P = L->P, cs = L->cs;
    double x0 = px * P, y0 = py * P;
    double x1 = x0 + P < L->cw ? x0 + P : L->cw, y1 = y0 + P < L->ch ? y0 + P : L->ch;
    double zlo = L->pzmin[p] * L->zs, zhi = L->pzmax[p] * L->zs;
    double c[3] = { 0.5 * (x0 + x1) * cs, 0.5 * (y0 + y1) * cs, 0.5 * (zlo + zhi) };
    double hx = 0.5 * (x1 - x0) * cs, hy = 0.5 * (y1 - y0) * cs, hz = 0.5 * (zhi - zlo);
    double r = sqrt(hx * hx + hy * hy + hz * hz);
    if (!sphere_visible(v, c, r)) return 0;
    if (far_dist > 0.0) {
        double dx = c[0] - v->eye[0], dy = c[1] - v->eye[1], dz = c[2] - v->eye[2];
        if (sqrt(dx * dx + dy * dy + dz * dz) - r > far_dist) return 0;
    }
    return 1;
}

/* One tessellation at tolerance tol; patches outside the frustum keep their
 * roots (only forced splits reach them). */
static void frame_pass(rs_roam *L, const view_params *v0, double tol, const unsigned char *vis)
{
    view_params v = *v0;
    v.tol = tol;
    rs__roam_reset_mesh(L);
    refine_params rp = { 0.0, 0, &v, vis, 0 };
    rs__roam_refine(L, &rp);
}

rs_result rs__roam_view_begin(rs_ctx *ctx, rs_roam *L, const rs_roam_view *vw, view_params *v,
                              unsigned char *visbuf, size_t nbuf, unsigned char **vis)
{
    rs_result r = make_view(ctx, L, vw, v);
    if (r != RS_OK) return r;
    rs__roam_patch_ranges(L);
    uint32_t np = L->npx * L->npy;
    *vis = visbuf;
    if (np > nbuf) {
        *vis = rs__malloc(ctx, np);
        if (!*vis) return rs__fail(ctx, RS_ERR_NOMEM, "ROAM: out of memory for %u patch flags", np);
    }
    L->culled = 0;
    for (uint32_t p = 0; p < np; p++) {
        (*vis)[p] = (unsigned char)patch_visible(L, v, p, vw->far_dist);
        if (!(*vis)[p]) L->culled++;
    }
    return RS_OK;
}

static rs_result frame_run(rs_ctx *ctx, rs_roam *L, const rs_roam_view *vw);

/* Progress: pool nodes taken by each pass's splits (at most
 * FRAME_MAX_PASSES + 1 passes with a target). A cancelled frame leaves the
 * mesh of the pass under way: valid and crack-free, coarser; the
 * tolerance feedback is not updated. */
rs_result rs__roam_view_in(rs_ctx *ctx, const rs_roam *L, const rs_roam_view *vw_in, const char *call,
                           rs_roam_view *vw)
{
    if (!L || !vw_in) return rs__fail(ctx, RS_ERR_INVALID_ARG, "%s: roam and view must not be NULL", call);
    return RS__OPTS_IN(ctx, vw_in, vw, rs_roam_view);
}

rs_result rs_roam_frame(rs_ctx *ctx, rs_roam *L, const rs_roam_view *vw_in)
{
    if (!ctx) return RS_ERR_INVALID_ARG;
    rs_roam_view vw;
    rs_result r = rs__roam_view_in(ctx, L, vw_in, "rs_roam_frame", &vw);
    if (r != RS_OK) return r;
    rs__progress pg;
    rs_ctx *saved;
    uint64_t passes = vw.target_triangles ? FRAME_MAX_PASSES + 1 : 1;
    rs__roam_progress_begin(ctx, L, &pg, passes * (L->cap - L->base_count), &saved);
    return rs__roam_progress_end(ctx, L, &pg, frame_run(ctx, L, &vw), saved);
}

static rs_result frame_run(rs_ctx *ctx, rs_roam *L, const rs_roam_view *vw)
{
    rs_result r;
    view_params v;
    unsigned char visbuf[256], *vis;
    r = rs__roam_view_begin(ctx, L, vw, &v, visbuf, sizeof visbuf, &vis);
    if (r != RS_OK) return r;
    int own = vis != visbuf;
    double tol = vw->pixel_error > 0.0 ? vw->pixel_error : 1.0;
    if (vw->target_triangles && L->tol > 0.0 && isfinite(L->tol)) tol = L->tol; /* gFrameVariance */
    uint32_t passes = 0;
    if (!vw->target_triangles) {
        frame_pass(L, &v, tol, vis);
        passes = 1;
    } else {
        double target = vw->target_triangles;
        double lo_t = 0.0, hi_t = INFINITY;   /* tol giving too many / too few */
        double lo_c = 0.0, hi_c = 0.0;
        double best_tol = tol;
        double best_dev = INFINITY;
        for (passes = 1; passes <= FRAME_MAX_PASSES && !L->cancelled; passes++) {
            frame_pass(L, &v, tol, vis);
            if (L->cancelled) break;
            double c = L->tris, dev = fabs(c - target) / target;
            if (dev < best_dev) { best_dev = dev; best_tol = tol; }
            if (dev <= 0.03) break;
            if (c > target) { lo_t = tol; lo_c = c; } else { hi_t = tol; hi_c = c; }
            if (c < target && L->exhausted) break; /* cannot reach: pool too small */
            double nt;
            if (lo_t > 0.0 && isfinite(hi_t)) {
                /* secant in log-log between the bracket ends, kept inside it */
                double a = log(lo_c) - log(hi_c > 0 ? hi_c : 1), b = log(hi_t) - log(lo_t);
                double s = b > 0 && a > 0 ? (log(lo_c) - log(target)) / a : 0.5;
                if (!(s > 0.05 && s < 0.95)) s = 0.5;
                nt = exp(log(lo_t) + s * b);
            } else {
                /* count grows roughly like tol^-1.5 */
                double ratio = c > 0 ? c / target : 0.01;
                nt = tol * pow(ratio, 1.0 / 1.5);
                if (nt > tol * 16) nt = tol * 16;
                if (nt < tol / 16) nt = tol / 16;
            }
            if (!(nt > 0.0) || !isfinite(nt)) break;
            tol = nt;
        }
        if (passes > FRAME_MAX_PASSES && !L->cancelled) {
            passes = FRAME_MAX_PASSES + 1;
            frame_pass(L, &v, best_tol, vis);
            tol = best_tol;
        }
        if (!L->cancelled) L->tol = tol;
    }
    if (own) rs__free(ctx, vis);
    L->frame_passes = passes;
    L->threshold = tol;
    if (L->exhausted)
        return rs__fail(ctx, RS_ERR_POOL_EXHAUSTED, "ROAM: pool of %u nodes ran out in a frame "
                        "(mesh valid but coarser: %u triangles)", L->cap - L->base_count, L->tris);
    rs__ok(ctx);
    return RS_OK;
}

