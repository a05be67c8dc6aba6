/* Shader render mode of `roadsplat render --roads shader` (cli/render_shader.c,
 * docs/render.md "Shader mode"): an OpenGL >= 3.3 core context on OSMesa;
 * the terrain mesh in one draw call, its fragment shader evaluating the
 * roads, styles and markings of an rs_gpu_scene per screen pixel. GL-free
 * declarations, as cli/render_gl.h. */
#ifndef RS_RENDER_SHADER_H
#define RS_RENDER_SHADER_H
#include "render_gl.h"
#include "roadsplat.h"

typedef struct rsh_renderer rsh_renderer;

/* A core-profile context (3.3 or later, with buffer textures) of width x
 * height RGBA pixels with a 24-bit depth buffer, made current. NULL with a
 * message in err when this OSMesa cannot make one (the caller falls back to
 * the texture mode). */
rsh_renderer *rsh_create(uint32_t width, uint32_t height, char *err, size_t err_size);
void rsh_destroy(rsh_renderer *r);
/* "GL_RENDERER, GL VERSION, GLSL VERSION" (JSON-safe). */
void rsh_describe(const rsh_renderer *r, char *out, size_t out_size);
uint32_t rsh_max_texture_size(const rsh_renderer *r);

/* Upload the scene (buffer textures), the terrain colour T and the road
 * surface S (tex_w x tex_h RGBA8 each, top row = map y 0, mipmapped) and
 * the normal map for lighting (RGB8 as rs_normal_window, or NULL: the mesh
 * normals). g may be NULL (terrain only). Returns 0, or non-zero with a
 * message. */
int rsh_upload(rsh_renderer *r, const rs_gpu_scene *g, const uint8_t *terrain, const uint8_t *road,
               const uint8_t *normals, uint32_t tex_w, uint32_t tex_h, char *err, size_t err_size);

/* One frame: sky, then the mesh (5 floats per vertex as rs_roam_extract,
 * normals 3 per vertex, map frame) in one draw call. Ends with glFinish. */
int rsh_draw(rsh_renderer *r, const rg_view *view, const float *vertices, const float *normals, size_t vertex_count,
             const uint32_t *indices, size_t index_count, char *err, size_t err_size);

/* The frame as width*height RGBA8, top row first. */
void rsh_read_rgba(rsh_renderer *r, uint8_t *out);
#endif
