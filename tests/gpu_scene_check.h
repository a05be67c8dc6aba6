/* Structural check of an rs_gpu_scene (include/roadsplat.h "GPU export"):
 * every index it holds points inside the array it indexes and every float
 * a shader reads is finite. Shared by tests/test_gpu_export.c and the
 * fuzz target fuzz/gpu_export/fuzz.c. Returns NULL when the scene is sound,
 * else what is wrong. */
#ifndef RS_TESTS_GPU_SCENE_CHECK_H
#define RS_TESTS_GPU_SCENE_CHECK_H
#include "roadsplat.h"
#include "gpu_scene_view.h"

#include <math.h>
#include <stddef.h>


static int gsc_finite(const float *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i])) return 0;
    return 1;
}

/* v is an integer in [lo, hi) */
static int gsc_index(float v, double lo, double hi)
{
    return v >= lo && v < hi && v == floorf(v);
}

/* start: n + 1 ascending offsets from 0 to `entries`; ids below `items`, ascending per range */
static int gsc_lists(const uint32_t *start, const uint32_t *ids, size_t n, size_t entries, size_t items)
{
    if (!start || !ids || start[0] != 0 || start[n] != entries) return 0;
    for (size_t c = 0; c < n; c++) {
        if (start[c] > start[c + 1]) return 0;
        for (uint32_t e = start[c]; e < start[c + 1]; e++)
            if (ids[e] >= items || (e > start[c] && ids[e] <= ids[e - 1])) return 0;
    }
    return 1;
}

static const char *gpu_scene_check(const rs_gpu_scene *scene)
{
    if (!scene) return "no scene";
    const gsv view = gsv_of(scene), *g = &view;
    if (!(g->cell > 0) || !isfinite(g->x0) || !isfinite(g->y0) || g->gw == 0 || g->gh == 0) return "grid";
    const size_t ncell = (size_t)g->gw * g->gh;
    if (!g->seg || !g->road || !g->band || !g->mark || !g->types || !g->levels || !g->atlas_px)
        return "an array is NULL";
    for (size_t k = 0; k < g->nseg; k++) {
        const float *s = g->seg + RS_GPU_SEG_FLOATS * k;
        if (!gsc_finite(s, RS_GPU_SEG_FLOATS)) return "segment float not finite";
        if (!gsc_index(s[6], 0, (double)g->nroads)) return "segment road index";
        if (!gsc_index(s[7], 0, 32)) return "segment flags";
        if (k > 0 && s[6] < s[6 - RS_GPU_SEG_FLOATS]) return "segments not in road order";
        if (!(s[4] >= 0 && s[8] >= 0 && s[9] >= 0)) return "segment width or length negative";
    }
    if (!gsc_lists(g->cell_start, g->cell_seg, ncell, g->nseg_entries, g->nseg)) return "segment index";
    /* each road's first segment (float 39), exact below 2^24 segments */
    for (size_t i = 0, k = 0; i < g->nroads && g->nseg < ((size_t)1 << 24); i++) {
        while (k < g->nseg && g->seg[RS_GPU_SEG_FLOATS * k + 6] < (float)i) k++;
        if (g->road[RS_GPU_ROAD_FLOATS * i + 39] != (float)k) return "road first segment";
    }
    /* joints: both sides flagged, each the other's continuation, meeting at one point */
    for (size_t k = 0; k < g->nseg; k++) {
        const float *s = g->seg + RS_GPU_SEG_FLOATS * k;
        uint32_t f = (uint32_t)s[7];
        if (!(f & (RS_GPU_SEG_JOIN_FIRST | RS_GPU_SEG_JOIN_LAST))) continue;
        size_t i = (size_t)s[6];
        const float *rd = g->road + RS_GPU_ROAD_FLOATS * i;
        for (int e = 0; e < 2; e++) {
            if (!(f & (e ? RS_GPU_SEG_JOIN_LAST : RS_GPU_SEG_JOIN_FIRST))) continue;
            if (!(f & (e ? RS_GPU_SEG_LAST : RS_GPU_SEG_FIRST)) || rd[5 + e] < 0) return "joint without its end";
            size_t b = (size_t)rd[5 + e], kb;
            const float *rb = g->road + RS_GPU_ROAD_FLOATS * b;
            if (rb[6 - e] != (float)i) return "joint partner";
            if (e) kb = (size_t)rb[39];
            else kb = (b + 1 < g->nroads ? (size_t)rb[RS_GPU_ROAD_FLOATS + 39] : g->nseg) - 1;
            if (kb >= g->nseg) return "joint partner segment";
            const float *sb = g->seg + RS_GPU_SEG_FLOATS * kb;
            uint32_t fb = (uint32_t)sb[7];
            if (sb[6] != (float)b || !(fb & (e ? RS_GPU_SEG_JOIN_FIRST : RS_GPU_SEG_JOIN_LAST))) return "joint partner flags";
            if (e ? (s[2] != sb[0] || s[3] != sb[1]) : (s[0] != sb[2] || s[1] != sb[3])) return "joint point";
        }
    }
    for (size_t i = 0; i < g->nroads; i++) {
        const float *rd = g->road + RS_GPU_ROAD_FLOATS * i;
        if (!gsc_finite(rd, RS_GPU_ROAD_FLOATS)) return "road float not finite";
        if (!gsc_index(rd[3], 0, (double)g->nbands + 1) || !gsc_index(rd[4], 0, 33) ||
            (double)rd[3] + rd[4] > (double)g->nbands)
            return "road bands";
        for (int e = 5; e <= 6; e++)
            if (rd[e] != -1 && !gsc_index(rd[e], 0, (double)g->nroads)) return "road continuation";
        for (int e = 24; e <= 26; e++) /* strokes: at most one per road */
            if (rd[e] != -1 && !gsc_index(rd[e], 0, (double)g->nroads)) return "road stroke";
        /* (the depths: negative for an end short of the through road's
         * centre line by more than its kept lines, docs/network.md "Ends
         * inside a surface") */
        if (rd[27] != rd[27] || rd[28] != rd[28] || (rd[29] != 0 && rd[29] != 1)) /* (huge widths: huge depths) */
            return "road T fields";
    }
    for (size_t b = 0; b < g->nbands; b++) {
        const float *bd = g->band + RS_GPU_BAND_FLOATS * b;
        if (!gsc_finite(bd, RS_GPU_BAND_FLOATS)) return "band float not finite";
        if (!gsc_index(bd[8], 0, 9)) return "band dash count";
    }
    for (size_t m = 0; m < g->nmarks; m++) {
        const float *mk = g->mark + RS_GPU_MARK_FLOATS * m;
        if (!gsc_finite(mk, RS_GPU_MARK_FLOATS)) return "marking float not finite";
        if (!gsc_index(mk[0], 0, (double)g->nroads) || !gsc_index(mk[1], 0, (double)g->ntypes))
            return "marking road or type";
    }
    if (!gsc_lists(g->mark_start, g->mark_ids, ncell, g->nmark_entries, g->nmarks)) return "marking index";
    for (size_t t = 0; t < g->ntypes; t++) {
        const uint32_t *ty = g->types + RS_GPU_TYPE_INTS * t;
        if ((size_t)ty[0] + ty[1] > g->nlevels) return "atlas type levels";
    }
    for (size_t l = 0; l < g->nlevels; l++) {
        const uint32_t *L = g->levels + RS_GPU_LEVEL_INTS * l;
        if ((size_t)L[0] + (size_t)L[1] * L[2] > g->atlas_texels) return "atlas level texels";
    }
    return NULL;
}
#endif
