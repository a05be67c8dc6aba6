/* Offscreen OpenGL renderer of `roadsplat render` (cli/render_gl.c), on
 * OSMesa with legacy fixed-function GL. The only file that includes GL
 * headers; the declarations here are GL-free so the rest of the CLI (and the
 * library, which never sees this) builds without OSMesa.
 *
 * Frames: inputs are in the road file's map frame (x east, y down the map,
 * z height up, metres). Internally GL world = (x, z, y): right-handed, y up. */
#ifndef RS_RENDER_GL_H
#define RS_RENDER_GL_H
#include <stddef.h>
#include <stdint.h>

typedef struct rg_renderer rg_renderer;

/* One view. All positions and directions in the map frame. */
typedef struct rg_view {
    int ortho;                  /* top-down orthographic view of the whole map */
    double eye[3], look[3];     /* perspective camera */
    double fov_y;               /* degrees */
    double znear, zfar;         /* clip distances (perspective) */
    double map_w, map_h;        /* map extent, metres: [0,map_w] x [0,map_h] */
    double zmin, zmax;          /* height range, metres */
    int lighting;               /* modulate the texture by sun lighting */
    double sun[3];              /* unit vector towards the sun */
    int fog;                    /* linear fog towards the horizon colour */
    double fog_start, fog_end;  /* metres from the eye */
    double anisotropy;          /* texture mode: at most this many anisotropic taps; 0: the GL's
                                   maximum, 1: off (isotropic mip levels only) */
} rg_view;

typedef struct rg_tex_stats {
    uint32_t max_texture_size;  /* GL_MAX_TEXTURE_SIZE */
    uint32_t tiles_x, tiles_y;  /* texture tiles */
    uint32_t tile_core;         /* texels per tile side, without the border */
    uint32_t finest_level;      /* finest mip level uploaded over all tiles */
    uint32_t coarsest_base;     /* coarsest base level chosen for a tile */
    uint64_t texels_uploaded;   /* all levels, all tiles */
    uint64_t texels_full;       /* what a full mip chain of every tile would hold */
    double anisotropy;          /* anisotropic filtering used (1: none; the GL offers none or --anisotropy 1) */
    double anisotropy_max;      /* what the GL offers (1: no anisotropic filtering) */
} rg_tex_stats;

/* Create an RGBA offscreen context with a 24-bit depth buffer, width x
 * height pixels, and make it current. Writes a message to err and returns
 * NULL on failure. */
rg_renderer *rg_create(uint32_t width, uint32_t height, char *err, size_t err_size);
void rg_destroy(rg_renderer *r);
uint32_t rg_max_texture_size(const rg_renderer *r);
/* "GL_RENDERER, GL_VERSION" of the current context (for the stats). */
void rg_describe(const rg_renderer *r, char *out, size_t out_size);

/* Upload the splat texture (tex_w x tex_h RGBA8, top row = map y 0) with
 * box-filtered mip levels, split into tiles of at most `tile_limit` texels
 * per side (0: GL_MAX_TEXTURE_SIZE). Each tile gets the base mip level that
 * the view needs (seed 002: level from the tile's projected texel size at
 * its nearest point); levels finer than that are never uploaded. Returns 0,
 * or non-zero with a message in err. */
int rg_upload_texture(rg_renderer *r, const uint8_t *rgba, uint32_t tex_w, uint32_t tex_h, uint32_t tile_limit,
                      const rg_view *view, rg_tex_stats *stats, char *err, size_t err_size);

/* Draw one frame: sky, then the mesh. `vertices` are 5 floats per vertex
 * (x, y, z map frame, u, v as from rs_roam_extract), `normals` 3 per vertex
 * (map frame), `indices` 3 per triangle. Ends with glFinish. Returns 0, or
 * non-zero (out of memory) with a message in err. */
int rg_draw(rg_renderer *r, const rg_view *view, const float *vertices, const float *normals, size_t vertex_count,
            const uint32_t *indices, size_t index_count, char *err, size_t err_size);

/* Camera basis in the GL frame (x, z, y) from eye and look-at in the map
 * frame: E the eye, side s, up u, forward f (unit vectors). Straight down,
 * "up" on screen is north (-y map). Shared by the shader mode
 * (cli/render_shader.c). */
void rg_camera_basis(const double *eye_m, const double *look_m, double *E, double *s, double *u, double *f);

/* Read the frame back as width*height RGBA8, top row first. */
void rg_read_rgba(rg_renderer *r, uint8_t *out);
/* The same for the current context's w x h frame (also the shader mode's). */
void rg_read_current(uint32_t w, uint32_t h, uint8_t *out);

/* `render --path` (cli/render_vt.c): the virtual texture's tiles, one GL
 * texture per rs_vt slot (side x side RGBA8, linear filtering, no mip
 * levels: the vt picks the level per tile), drawn each over its own part of
 * the mesh. rg_vt_slots once; rg_vt_upload whenever a tile is made into a
 * slot. */
typedef struct rg_vt_draw_tile {
    uint32_t slot;
    double x0, x1, y0, y1; /* the tile's core in finest-level texels */
    double scale;          /* finest texels per texel of the tile's level (2^level) */
    double ox, oy;         /* the tile's first texel (border included) in its level's texels */
} rg_vt_draw_tile;
int rg_vt_slots(rg_renderer *r, uint32_t slots, uint32_t side, char *err, size_t err_size);
int rg_vt_upload(rg_renderer *r, uint32_t slot, const uint8_t *rgba, char *err, size_t err_size);
/* rg_draw with the tiles instead of the uploaded texture; tex_w x tex_h:
 * the finest level's size (the mesh's u, v times these are its texels). */
int rg_draw_vt(rg_renderer *r, const rg_view *v, const float *vertices, const float *normals, size_t nv,
               const uint32_t *indices, size_t ni, uint32_t tex_w, uint32_t tex_h, const rg_vt_draw_tile *tiles,
               size_t ntiles, char *err, size_t err_size);

/* `roadsplat render --path FILE ...` (cli/render_vt.c), called by
 * cli_render_main when --path is given. */
int cli_render_path_main(int argc, char **argv);

#endif
