/* An rs_gpu_scene's info and arrays in one struct, through the public
 * accessors (the scene is opaque): tests and the fuzz target read
 * gsv_of(g).seg[...] as they read the fields before. */
#ifndef RS_TESTS_GPU_SCENE_VIEW_H
#define RS_TESTS_GPU_SCENE_VIEW_H
#include "roadsplat.h"

/* The scene's fields as tests read them, through the public accessors
 * (rs_gpu_scene_get_info, rs_gpu_scene_array): gsv_of(g).seg[...]. */
typedef struct gsv {
    double cell, x0, y0, reach;
    uint32_t gw, gh;
    double map_w, map_h;
    size_t nseg, nroads, nbands, nmarks, ntypes, nlevels, ncuts;
    size_t nseg_entries, nmark_entries, atlas_texels, sat_corners, bytes;
    const float *seg, *road, *band, *mark, *atlas_px, *cut;
    const uint32_t *cell_start, *cell_seg, *mark_start, *mark_ids, *types, *levels, *mark_levels;
    const int32_t *mark_sat;
} gsv;

static inline gsv gsv_of(const rs_gpu_scene *s)
{
    gsv v;
    rs_gpu_scene_info in;
    rs_gpu_scene_get_info(s, &in);
    v.cell = in.cell, v.x0 = in.x0, v.y0 = in.y0, v.reach = in.reach, v.gw = in.gw, v.gh = in.gh;
    v.map_w = in.map_w, v.map_h = in.map_h;
    v.nseg = in.nseg, v.nroads = in.nroads, v.nbands = in.nbands, v.nmarks = in.nmarks, v.ntypes = in.ntypes;
    v.nlevels = in.nlevels, v.ncuts = in.ncuts, v.nseg_entries = in.nseg_entries;
    v.nmark_entries = in.nmark_entries, v.atlas_texels = in.atlas_texels, v.sat_corners = in.sat_corners;
    v.bytes = in.bytes;
    v.seg = (const float *)rs_gpu_scene_array(s, RS_GPU_ARRAY_SEG, NULL);
    v.road = (const float *)rs_gpu_scene_array(s, RS_GPU_ARRAY_ROAD, NULL);
    v.band = (const float *)rs_gpu_scene_array(s, RS_GPU_ARRAY_BAND, NULL);
    v.mark = (const float *)rs_gpu_scene_array(s, RS_GPU_ARRAY_MARK, NULL);
    v.atlas_px = (const float *)rs_gpu_scene_array(s, RS_GPU_ARRAY_ATLAS_PX, NULL);
    v.cut = (const float *)rs_gpu_scene_array(s, RS_GPU_ARRAY_CUT, NULL);
    v.cell_start = (const uint32_t *)rs_gpu_scene_array(s, RS_GPU_ARRAY_CELL_START, NULL);
    v.cell_seg = (const uint32_t *)rs_gpu_scene_array(s, RS_GPU_ARRAY_CELL_SEG, NULL);
    v.mark_start = (const uint32_t *)rs_gpu_scene_array(s, RS_GPU_ARRAY_MARK_START, NULL);
    v.mark_ids = (const uint32_t *)rs_gpu_scene_array(s, RS_GPU_ARRAY_MARK_IDS, NULL);
    v.types = (const uint32_t *)rs_gpu_scene_array(s, RS_GPU_ARRAY_TYPES, NULL);
    v.levels = (const uint32_t *)rs_gpu_scene_array(s, RS_GPU_ARRAY_LEVELS, NULL);
    v.mark_levels = (const uint32_t *)rs_gpu_scene_array(s, RS_GPU_ARRAY_MARK_LEVELS, NULL);
    v.mark_sat = (const int32_t *)rs_gpu_scene_array(s, RS_GPU_ARRAY_MARK_SAT, NULL);
    return v;
}
#endif
