/* Shader render mode (render_shader.h, docs/render.md "Shader mode"):
 * OSMesa core-profile context, the scene in buffer textures, one draw call
 * for the terrain mesh whose fragment shader (lib/gpu/glsl.c) evaluates
 * roads, styles and markings per pixel. Built only with -DRS_WITH_OSMESA. */
#include "render_shader.h"

#ifdef RS_WITH_OSMESA
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


#define RSH_PI 3.14159265358979323846

/* GL entry points past 1.1, from OSMesaGetProcAddress. */
#define RSH_GL_FUNCS(X)                                                                                             \
    X(PFNGLGENBUFFERSPROC, GenBuffers)                                                                              \
    X(PFNGLBINDBUFFERPROC, BindBuffer)                                                                              \
    X(PFNGLBUFFERDATAPROC, BufferData)                                                                              \
    X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                                                                        \
    X(PFNGLTEXBUFFERPROC, TexBuffer)                                                                                \
    X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays)                                                                    \
    X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)                                                                    \
    X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays)                                                              \
    X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer)                                                            \
    X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray)                                                    \
    X(PFNGLCREATESHADERPROC, CreateShader)                                                                          \
    X(PFNGLSHADERSOURCEPROC, ShaderSource)                                                                          \
    X(PFNGLCOMPILESHADERPROC, CompileShader)                                                                        \
    X(PFNGLGETSHADERIVPROC, GetShaderiv)                                                                            \
    X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)                                                                  \
    X(PFNGLDELETESHADERPROC, DeleteShader)                                                                          \
    X(PFNGLCREATEPROGRAMPROC, CreateProgram)                                                                        \
    X(PFNGLATTACHSHADERPROC, AttachShader)                                                                          \
    X(PFNGLLINKPROGRAMPROC, LinkProgram)                                                                            \
    X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                                                                          \
    X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)                                                                \
    X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                                                                        \
    X(PFNGLUSEPROGRAMPROC, UseProgram)                                                                              \
    X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)                                                              \
    X(PFNGLUNIFORM1IPROC, Uniform1i)                                                                                \
    X(PFNGLUNIFORM2IPROC, Uniform2i)                                                                                \
    X(PFNGLUNIFORM2FPROC, Uniform2f)                                                                                \
    X(PFNGLUNIFORM3FPROC, Uniform3f)                                                                                \
    X(PFNGLUNIFORM4FPROC, Uniform4f)                                                                                \
    X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv)                                                                  \
    X(PFNGLACTIVETEXTUREPROC, ActiveTexture)                                                                        \
    X(PFNGLGENERATEMIPMAPPROC, GenerateMipmap)

typedef struct rsh_gl {
#define RSH_DECL(type, name) type name;
    RSH_GL_FUNCS(RSH_DECL)
#undef RSH_DECL
} rsh_gl;

/* the scene's buffer textures: rs_gpu_array 0 .. RS_GPU_ARRAY_CUT, bound to units 2 .. */
enum { NBUF = RS_GPU_ARRAY_CUT + 1 };

struct rsh_renderer {
    OSMesaContext osm;
    GLubyte *buf;
    uint32_t w, h;
    GLint max_tex;
    rsh_gl gl;
    GLuint prog, sky_prog, vao, vbo, ibo, sky_vao, sky_vbo;
    GLuint tex_terrain, tex_road, tex_normal;
    GLuint bufs[NBUF], btex[NBUF];
    int have_scene;
    double map_w, map_h;
    /* scene grid */
    float grid[4];
    int gdim[2];
    float *vtx;
    size_t cap_v;
};

static void set_err(char *err, size_t n, const char *msg)
{
    if (err && n) snprintf(err, n, "%s", msg);
}

static GLuint compile(rsh_renderer *r, GLenum type, const char *const *src, int count, char *err, size_t n)
{
    GLuint s = r->gl.CreateShader(type);
    r->gl.ShaderSource(s, count, (const GLchar *const *)src, NULL);
    r->gl.CompileShader(s);
    GLint ok = 0;
    r->gl.GetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024];
        r->gl.GetShaderInfoLog(s, sizeof log, NULL, log);
        if (err && n) snprintf(err, n, "shader compile failed: %s", log);
        r->gl.DeleteShader(s);
        return 0;
    }
    return s;
}

static GLuint link(rsh_renderer *r, const char *vs, const char *const *fs, int nfs, char *err, size_t n)
{
    GLuint v = compile(r, GL_VERTEX_SHADER, &vs, 1, err, n);
    if (!v) return 0;
    GLuint f = compile(r, GL_FRAGMENT_SHADER, fs, nfs, err, n);
    if (!f) { r->gl.DeleteShader(v); return 0; }
    GLuint p = r->gl.CreateProgram();
    r->gl.AttachShader(p, v);
    r->gl.AttachShader(p, f);
    r->gl.LinkProgram(p);
    r->gl.DeleteShader(v);
    r->gl.DeleteShader(f);
    GLint ok = 0;
    r->gl.GetProgramiv(p, GL_LINK_STATUS, &ok);
    if (!ok) {
        char log[1024];
        r->gl.GetProgramInfoLog(p, sizeof log, NULL, log);
        if (err && n) snprintf(err, n, "shader link failed: %s", log);
        r->gl.DeleteProgram(p);
        return 0;
    }
    return p;
}

rsh_renderer *rsh_create(uint32_t width, uint32_t height, char *err, size_t err_size)
{
    rsh_renderer *r = calloc(1, sizeof *r);
    if (!r) { set_err(err, err_size, "out of memory"); return NULL; }
    r->w = width;
    r->h = height;
    const int attribs[] = { OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_STENCIL_BITS, 0,
                            OSMESA_ACCUM_BITS, 0, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION, 3, OSMESA_CONTEXT_MINOR_VERSION, 3, 0 };
    r->osm = OSMesaCreateContextAttribs(attribs, NULL);
    if (!r->osm) {
        set_err(err, err_size, "this OSMesa gives no OpenGL 3.3 core context");
        free(r);
        return NULL;
    }
    r->buf = malloc((size_t)width * height * 4);
    if (!r->buf) { set_err(err, err_size, "out of memory for the frame buffer"); rsh_destroy(r); return NULL; }
    if (!OSMesaMakeCurrent(r->osm, r->buf, GL_UNSIGNED_BYTE, (GLsizei)width, (GLsizei)height)) {
        set_err(err, err_size, "OSMesaMakeCurrent failed (size too large for this Mesa?)");
        rsh_destroy(r);
        return NULL;
    }
#define RSH_LOAD(type, name)                                                                                        \
    {                                                                                                               \
        OSMESAproc fp = OSMesaGetProcAddress("gl" #name); /* memcpy: no cast between function types */             \
        memcpy(&r->gl.name, &fp, sizeof r->gl.name);                                                                \
    }                                                                                                               \
    if (!r->gl.name) {                                                                                              \
        set_err(err, err_size, "this OpenGL lacks gl" #name);                                                       \
        rsh_destroy(r);                                                                                             \
        return NULL;                                                                                                \
    }
    RSH_GL_FUNCS(RSH_LOAD)
#undef RSH_LOAD
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &r->max_tex);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    /* the library's GLSL (rs_gpu_glsl): what an embedding host compiles too */
    size_t nvs = 0, nfs = 0, nsv = 0, nsf = 0;
    const char *const *vs = rs_gpu_glsl(330, RS_GPU_SHADER_TERRAIN_VERTEX, &nvs);
    const char *const *fs = rs_gpu_glsl(330, RS_GPU_SHADER_TERRAIN_FRAGMENT, &nfs);
    const char *const *sv = rs_gpu_glsl(330, RS_GPU_SHADER_SKY_VERTEX, &nsv);
    const char *const *sf = rs_gpu_glsl(330, RS_GPU_SHADER_SKY_FRAGMENT, &nsf);
    if (!vs || !fs || !sv || !sf || nvs != 1 || nsv != 1) {
        set_err(err, err_size, "the library has no GLSL 330 sources");
        rsh_destroy(r);
        return NULL;
    }
    if (!(r->prog = link(r, vs[0], fs, (int)nfs, err, err_size)) ||
        !(r->sky_prog = link(r, sv[0], sf, (int)nsf, err, err_size))) {
        rsh_destroy(r);
        return NULL;
    }
    r->gl.GenVertexArrays(1, &r->vao);
    r->gl.GenBuffers(1, &r->vbo);
    r->gl.GenBuffers(1, &r->ibo);
    r->gl.GenVertexArrays(1, &r->sky_vao);
    r->gl.GenBuffers(1, &r->sky_vbo);
    r->gl.BindVertexArray(r->vao);
    r->gl.BindBuffer(GL_ARRAY_BUFFER, r->vbo);
    r->gl.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), (void *)0);
    r->gl.EnableVertexAttribArray(0);
    r->gl.VertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float), (void *)(3 * sizeof(float)));
    r->gl.EnableVertexAttribArray(1);
    r->gl.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, r->ibo);
    r->gl.BindVertexArray(r->sky_vao);
    r->gl.BindBuffer(GL_ARRAY_BUFFER, r->sky_vbo);
    static const float quad[12] = { -1, -1, 1, -1, 1, 1, -1, -1, 1, 1, -1, 1 };
    r->gl.BufferData(GL_ARRAY_BUFFER, sizeof quad, quad, GL_STATIC_DRAW);
    r->gl.VertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), (void *)0);
    r->gl.EnableVertexAttribArray(0);
    r->gl.BindVertexArray(0);
    if (glGetError() != GL_NO_ERROR) {
        set_err(err, err_size, "GL setup failed (GL error)");
        rsh_destroy(r);
        return NULL;
    }
    return r;
}

void rsh_destroy(rsh_renderer *r)
{
    if (!r) return;
    if (r->osm && r->gl.DeleteBuffers) {
        if (r->have_scene) {
            r->gl.DeleteBuffers(NBUF, r->bufs);
            glDeleteTextures(NBUF, r->btex);
        }
        if (r->tex_terrain) glDeleteTextures(1, &r->tex_terrain);
        if (r->tex_road) glDeleteTextures(1, &r->tex_road);
        if (r->tex_normal) glDeleteTextures(1, &r->tex_normal);
        if (r->prog) r->gl.DeleteProgram(r->prog);
        if (r->sky_prog) r->gl.DeleteProgram(r->sky_prog);
        if (r->vao) r->gl.DeleteVertexArrays(1, &r->vao);
        if (r->sky_vao) r->gl.DeleteVertexArrays(1, &r->sky_vao);
        if (r->vbo) r->gl.DeleteBuffers(1, &r->vbo);
        if (r->ibo) r->gl.DeleteBuffers(1, &r->ibo);
        if (r->sky_vbo) r->gl.DeleteBuffers(1, &r->sky_vbo);
    }
    if (r->osm) OSMesaDestroyContext(r->osm);
    free(r->buf);
    free(r->vtx);
    free(r);
}

void rsh_describe(const rsh_renderer *r, char *out, size_t out_size)
{
    const GLubyte *rn = glGetString(GL_RENDERER), *ver = glGetString(GL_VERSION);
    const GLubyte *sl = glGetString(GL_SHADING_LANGUAGE_VERSION);
    (void)r;
    snprintf(out, out_size, "%s, GL %s, GLSL %s", rn ? (const char *)rn : "?", ver ? (const char *)ver : "?",
             sl ? (const char *)sl : "?");
    for (char *c = out; *c; c++)
        if (*c == '"' || *c == '\\' || (unsigned char)*c < 32) *c = ' ';
}

uint32_t rsh_max_texture_size(const rsh_renderer *r) { return (uint32_t)r->max_tex; }

static void tex2d(rsh_renderer *r, GLuint *t, const uint8_t *px, uint32_t w, uint32_t h, GLenum fmt)
{
    glGenTextures(1, t);
    glBindTexture(GL_TEXTURE_2D, *t);
    glTexImage2D(GL_TEXTURE_2D, 0, fmt == GL_RGB ? GL_RGB8 : GL_RGBA8, (GLsizei)w, (GLsizei)h, 0, fmt,
                 GL_UNSIGNED_BYTE, px);
    r->gl.GenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

int rsh_upload(rsh_renderer *r, const rs_gpu_scene *g, const uint8_t *terrain, const uint8_t *road,
               const uint8_t *normals, uint32_t tex_w, uint32_t tex_h, char *err, size_t err_size)
{
    if (tex_w > (uint32_t)r->max_tex || tex_h > (uint32_t)r->max_tex) {
        set_err(err, err_size, "texture larger than GL_MAX_TEXTURE_SIZE");
        return 1;
    }
    tex2d(r, &r->tex_terrain, terrain, tex_w, tex_h, GL_RGBA);
    tex2d(r, &r->tex_road, road ? road : terrain, tex_w, tex_h, GL_RGBA);
    if (normals) tex2d(r, &r->tex_normal, normals, tex_w, tex_h, GL_RGB);
    if (g) {
        /* every array the fragment shader samples, ready to upload (the
         * marking tables included: rs_gpu_scene_array) */
        GLint maxbuf = 0;
        glGetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &maxbuf);
        r->gl.GenBuffers(NBUF, r->bufs);
        glGenTextures(NBUF, r->btex);
        r->have_scene = 1;
        for (int k = 0; k < NBUF; k++) {
            static const GLenum fmt[2][3] = { { GL_R32F, GL_R32UI, GL_R32I }, { GL_RGBA32F, GL_RGBA32UI, GL_RGBA32I } };
            uint32_t ch = 0, kind = 0;
            rs_gpu_array_sampler((rs_gpu_array)k, &ch, &kind);
            size_t n = 0;
            const void *data = rs_gpu_scene_array(g, (rs_gpu_array)k, &n);
            size_t texel = 4 * ch, bytes = n ? n * 4 : texel; /* an empty array: one zero texel */
            if (bytes / texel > (size_t)maxbuf) {
                set_err(err, err_size, "the road scene exceeds GL_MAX_TEXTURE_BUFFER_SIZE");
                return 1;
            }
            r->gl.BindBuffer(GL_TEXTURE_BUFFER, r->bufs[k]);
            r->gl.BufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)bytes, n ? data : NULL, GL_STATIC_DRAW);
            glBindTexture(GL_TEXTURE_BUFFER, r->btex[k]);
            r->gl.TexBuffer(GL_TEXTURE_BUFFER, fmt[ch == 4][kind], r->bufs[k]);
        }
        r->gl.BindBuffer(GL_TEXTURE_BUFFER, 0);
        rs_gpu_scene_info si;
        rs_gpu_scene_get_info(g, &si);
        r->grid[0] = (float)si.x0;
        r->grid[1] = (float)si.y0;
        r->grid[2] = (float)(1.0 / si.cell);
        r->grid[3] = (float)si.reach;
        r->gdim[0] = (int)si.gw;
        r->gdim[1] = (int)si.gh;
        r->map_w = si.map_w;
        r->map_h = si.map_h;
    }
    if (glGetError() != GL_NO_ERROR) { set_err(err, err_size, "upload failed (GL error)"); return 1; }
    return 0;
}

/* ---- matrices (column-major, map frame -> clip) ------------------------ */

static void mat_mul(const double *a, const double *b, double *o)
{
    double t[16];
    for (int c = 0; c < 4; c++)
        for (int rr = 0; rr < 4; rr++) {
            double s = 0;
            for (int k = 0; k < 4; k++) s += a[k * 4 + rr] * b[c * 4 + k];
            t[c * 4 + rr] = s;
        }
    memcpy(o, t, sizeof t);
}

int rsh_draw(rsh_renderer *r, const rg_view *v, const float *vertices, const float *normals, size_t nv,
             const uint32_t *indices, size_t ni, char *err, size_t err_size)
{
    if (nv > r->cap_v) {
        free(r->vtx);
        r->vtx = malloc(nv * 6 * sizeof *r->vtx);
        if (!r->vtx) { r->cap_v = 0; set_err(err, err_size, "out of memory for the vertex array"); return 1; }
        r->cap_v = nv;
    }
    for (size_t k = 0; k < nv; k++) {
        memcpy(r->vtx + 6 * k, vertices + 5 * k, 3 * sizeof(float));
        memcpy(r->vtx + 6 * k + 3, normals + 3 * k, 3 * sizeof(float));
    }
    glViewport(0, 0, (GLsizei)r->w, (GLsizei)r->h);
    glClearColor(0.62f, 0.66f, 0.70f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    double E[3], s[3], u[3], f[3], P[16];
    memset(P, 0, sizeof P);
    if (v->ortho) {
        double eye[3] = { v->map_w / 2, v->map_h / 2, v->zmax + 1.0 }, look[3] = { v->map_w / 2, v->map_h / 2, v->zmin };
        rg_camera_basis(eye, look, E, s, u, f);
        double ppm = fmin((double)r->w / v->map_w, (double)r->h / v->map_h);
        double hw = r->w / (2 * ppm), hh = r->h / (2 * ppm), n = 0.5, fa = v->zmax - v->zmin + 2.0;
        P[0] = 1 / hw;
        P[5] = 1 / hh;
        P[10] = -2 / (fa - n);
        P[14] = -(fa + n) / (fa - n);
        P[15] = 1;
    } else {
        rg_camera_basis(v->eye, v->look, E, s, u, f);
        double ty = tan(v->fov_y * RSH_PI / 360.0), tx = ty * r->w / r->h, n = v->znear, fa = v->zfar;
        P[0] = 1 / tx;
        P[5] = 1 / ty;
        P[10] = -(fa + n) / (fa - n);
        P[11] = -1;
        P[14] = -2 * fa * n / (fa - n);
        /* the sky */
        glDisable(GL_DEPTH_TEST);
        r->gl.UseProgram(r->sky_prog);
        r->gl.Uniform3f(r->gl.GetUniformLocation(r->sky_prog, "u_f"), (float)f[0], (float)f[1], (float)f[2]);
        r->gl.Uniform3f(r->gl.GetUniformLocation(r->sky_prog, "u_s"), (float)s[0], (float)s[1], (float)s[2]);
        r->gl.Uniform3f(r->gl.GetUniformLocation(r->sky_prog, "u_u"), (float)u[0], (float)u[1], (float)u[2]);
        r->gl.Uniform2f(r->gl.GetUniformLocation(r->sky_prog, "u_tan"), (float)tx, (float)ty);
        r->gl.BindVertexArray(r->sky_vao);
        glDrawArrays(GL_TRIANGLES, 0, 6);
    }
    double V[16] = { s[0], u[0], -f[0], 0, s[1], u[1], -f[1], 0, s[2], u[2], -f[2], 0,
                     -(s[0] * E[0] + s[1] * E[1] + s[2] * E[2]), -(u[0] * E[0] + u[1] * E[1] + u[2] * E[2]),
                     f[0] * E[0] + f[1] * E[1] + f[2] * E[2], 1 };
    /* map (x, y, z) -> GL world (x, z, y) */
    double M[16] = { 1, 0, 0, 0, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 1 };
    double MVP[16];
    mat_mul(V, M, MVP);
    mat_mul(P, MVP, MVP);
    float mvp[16];
    for (int k = 0; k < 16; k++) mvp[k] = (float)MVP[k];

    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    GLuint p = r->prog;
    r->gl.UseProgram(p);
    r->gl.UniformMatrix4fv(r->gl.GetUniformLocation(p, "u_mvp"), 1, GL_FALSE, mvp);
    r->gl.Uniform3f(r->gl.GetUniformLocation(p, "u_eye"), (float)v->eye[0], (float)v->eye[1], (float)v->eye[2]);
    r->gl.Uniform2f(r->gl.GetUniformLocation(p, "u_map"), (float)v->map_w, (float)v->map_h);
    r->gl.Uniform1i(r->gl.GetUniformLocation(p, "u_roads"), r->have_scene);
    r->gl.Uniform4f(r->gl.GetUniformLocation(p, "u_grid"), r->grid[0], r->grid[1], r->grid[2], r->grid[3]);
    r->gl.Uniform2i(r->gl.GetUniformLocation(p, "u_gdim"), r->gdim[0], r->gdim[1]);
    r->gl.Uniform1i(r->gl.GetUniformLocation(p, "u_lighting"), v->lighting);
    r->gl.Uniform3f(r->gl.GetUniformLocation(p, "u_sun"), (float)v->sun[0], (float)v->sun[1], (float)v->sun[2]);
    r->gl.Uniform3f(r->gl.GetUniformLocation(p, "u_amb"), 0.42f, 0.42f, 0.45f);
    r->gl.Uniform3f(r->gl.GetUniformLocation(p, "u_dif"), 0.70f, 0.68f, 0.64f);
    r->gl.Uniform1i(r->gl.GetUniformLocation(p, "u_fog"), v->fog && !v->ortho);
    r->gl.Uniform2f(r->gl.GetUniformLocation(p, "u_fogr"), (float)v->fog_start, (float)v->fog_end);
    r->gl.Uniform3f(r->gl.GetUniformLocation(p, "u_fogc"), 0.78f, 0.85f, 0.93f);
    r->gl.ActiveTexture(GL_TEXTURE0);
    glBindTexture(GL_TEXTURE_2D, r->tex_terrain);
    r->gl.Uniform1i(r->gl.GetUniformLocation(p, "u_terrain"), 0);
    r->gl.ActiveTexture(GL_TEXTURE1);
    glBindTexture(GL_TEXTURE_2D, r->tex_road);
    r->gl.Uniform1i(r->gl.GetUniformLocation(p, "u_road"), 1);
    r->gl.ActiveTexture(GL_TEXTURE2 + NBUF);
    glBindTexture(GL_TEXTURE_2D, r->tex_normal);
    r->gl.Uniform1i(r->gl.GetUniformLocation(p, "u_normal"), 2 + NBUF);
    r->gl.Uniform1i(r->gl.GetUniformLocation(p, "u_nmap"), r->tex_normal != 0);
    for (int k = 0; k < NBUF; k++) {
        r->gl.ActiveTexture(GL_TEXTURE2 + k);
        if (r->have_scene) glBindTexture(GL_TEXTURE_BUFFER, r->btex[k]);
        r->gl.Uniform1i(r->gl.GetUniformLocation(p, rs_gpu_array_sampler((rs_gpu_array)k, NULL, NULL)), 2 + k);
    }
    r->gl.ActiveTexture(GL_TEXTURE0);
    r->gl.BindVertexArray(r->vao);
    r->gl.BindBuffer(GL_ARRAY_BUFFER, r->vbo);
    r->gl.BufferData(GL_ARRAY_BUFFER, (GLsizeiptr)(nv * 6 * sizeof(float)), r->vtx, GL_STREAM_DRAW);
    r->gl.BufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(ni * sizeof(uint32_t)), indices, GL_STREAM_DRAW);
    glDrawElements(GL_TRIANGLES, (GLsizei)ni, GL_UNSIGNED_INT, (void *)0);
    r->gl.BindVertexArray(0);
    glFinish();
    if (glGetError() != GL_NO_ERROR) { set_err(err, err_size, "drawing failed (GL error)"); return 1; }
    return 0;
}

void rsh_read_rgba(rsh_renderer *r, uint8_t *out) { rg_read_current(r->w, r->h, out); }

#else
typedef int rsh_no_osmesa_in_this_build;
#endif
