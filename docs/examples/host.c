/* An embedding host in C99 (docs/embedding.md "An example host"): it links
 * the installed roadsplat only (pkg-config roadsplat) and draws the roads
 * with the library's shaders on a GL context of its own.
 *
 *   cc -std=c99 host.c $(pkg-config --cflags --libs roadsplat osmesa) -lm -o host
 *   ./host junction-dem.pgm junction.txt 2 0.01 5
 *
 * Steps: load a DEM and roads; prepare the road grid once; export the GPU
 * scene from that grid; make an OpenGL 3.3 core context (OSMesa here: it
 * draws into memory, no window or GPU needed; a host on a window system
 * makes its context and loads its GL functions its own way); compile the
 * library's GLSL; upload the scene's arrays as buffer textures; draw the
 * terrain mesh top-down, one screen pixel per splat pixel; read the frame
 * back and compare it with the CPU splat of the same grid. Exit status 1
 * when the mean difference passes 1/255 or the 99th percentile 8/255 (the
 * bound of tests/cli_render_test.sh), 2 when a step fails. A sixth
 * argument names a PPM file for the GPU frame. */
#define GL_GLEXT_PROTOTYPES 1 /* libOSMesa exports every GL entry point */
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <roadsplat.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static rs_ctx *ctx; /* one context: this host runs on one thread */

static int fail(const char *step, rs_result r)
{
    fprintf(stderr, "host: %s: %s\n", step, rs_ctx_message(ctx)[0] ? rs_ctx_message(ctx) : rs_strerror(r));
    return 2;
}

static char *read_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    char *buf = NULL;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) == 0 && (n = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (buf = malloc((size_t)n + 1)) != NULL) {
        *size = fread(buf, 1, (size_t)n, f);
        buf[*size] = 0;
    }
    fclose(f);
    return buf;
}

/* The fragment shader's two colour images, from one layers pass of the
 * splatter: the terrain colour T (no roads) and the unstyled road surface
 * S (the road material alone: the shader adds styles and paint). */
static rs_result surfaces(const rs_splatter *sp, uint32_t w, uint32_t h, uint8_t **t, uint8_t **s)
{
    rs_splat_layers L;
    memset(&L, 0, sizeof L);
    *t = malloc((size_t)w * h * 4);
    *s = malloc((size_t)w * h * 4);
    if (!*t || !*s) return RS_ERR_NOMEM;
    L.terrain = *t;
    L.terrain_stride = (size_t)w * 4;
    L.surface = *s;
    L.surface_stride = (size_t)w * 4;
    L.surface_unstyled = 1;
    return rs_splat_layers_window(ctx, sp, NULL, 0, 0, w, h, &L, NULL);
}

static GLuint shader(GLenum type, rs_gpu_shader which)
{
    size_t n = 0;
    const char *const *src = rs_gpu_glsl(330, which, &n);
    GLuint s = glCreateShader(type);
    GLint ok = 0;
    glShaderSource(s, (GLsizei)n, (const GLchar *const *)src, NULL);
    glCompileShader(s);
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024];
        glGetShaderInfoLog(s, sizeof log, NULL, log);
        fprintf(stderr, "host: shader %d: %s\n", (int)which, log);
        return 0;
    }
    return s;
}

static void image_texture(GLuint tex, const uint8_t *rgba, uint32_t w, uint32_t h)
{
    glBindTexture(GL_TEXTURE_2D, tex);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, (GLsizei)w, (GLsizei)h, 0, GL_RGBA, GL_UNSIGNED_BYTE, rgba);
    glGenerateMipmap(GL_TEXTURE_2D);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
}

/* The scene's arrays as buffer textures on units 2, 3, ...: the sampler
 * names and formats come from the library (rs_gpu_array_sampler). */
static void upload_scene(GLuint prog, const rs_gpu_scene *scene, GLuint *bufs, GLuint *texs)
{
    static const GLenum format[2][3] = { { GL_R32F, GL_R32UI, GL_R32I }, { GL_RGBA32F, GL_RGBA32UI, GL_RGBA32I } };
    int k;
    glGenBuffers(RS_GPU_ARRAY_CUT + 1, bufs);
    glGenTextures(RS_GPU_ARRAY_CUT + 1, texs);
    for (k = 0; k <= RS_GPU_ARRAY_CUT; k++) {
        uint32_t channels, kind;
        size_t count;
        const char *name = rs_gpu_array_sampler((rs_gpu_array)k, &channels, &kind);
        const void *data = rs_gpu_scene_array(scene, (rs_gpu_array)k, &count);
        glBindBuffer(GL_TEXTURE_BUFFER, bufs[k]);
        /* an empty array: one zero texel (a buffer texture cannot be empty) */
        glBufferData(GL_TEXTURE_BUFFER, (GLsizeiptr)(count ? 4 * count : 4 * channels), count ? data : NULL,
                     GL_STATIC_DRAW);
        glActiveTexture(GL_TEXTURE2 + k);
        glBindTexture(GL_TEXTURE_BUFFER, texs[k]);
        glTexBuffer(GL_TEXTURE_BUFFER, format[channels == 4][kind], bufs[k]);
        glUniform1i(glGetUniformLocation(prog, name), 2 + k);
    }
}

int main(int argc, char **argv)
{
    const char *dem_path = argc > 1 ? argv[1] : "junction-dem.pgm", *roads_path = argc > 2 ? argv[2] : "junction.txt";
    double cell = argc > 3 ? atof(argv[3]) : 2, zscale = argc > 4 ? atof(argv[4]) : 0.01;
    rs_splat_options o;
    rs_dem *dem = NULL;
    rs_roads *roads = NULL;
    rs_road_grid *grid = NULL;
    rs_splatter *sp = NULL;
    rs_gpu_scene *scene = NULL;
    rs_gpu_scene_info si;
    rs_dem_frame fr;
    rs_result r;
    uint32_t w, h, x, y;
    char *text;
    size_t size = 0;
    uint8_t *cpu, *gpu, *terrain, *road;
    memset(&o, 0, sizeof o);
    o.texels = argc > 5 ? (uint32_t)atoi(argv[5]) : 5;
    if (rs_ctx_create(NULL, NULL, &ctx) != RS_OK) return 2;

    /* the DEM (a PGM: 2 m between samples, heights in centimetres) and the roads */
    if (!(text = read_file(dem_path, &size))) { perror(dem_path); return 2; }
    r = rs_dem_parse_pgm(ctx, text, size, &dem);
    free(text);
    if (r) return fail(dem_path, r);
    rs_dem_get_frame(dem, &fr);
    fr.cell_size = cell;
    fr.z_scale = zscale;
    if ((r = rs_dem_set_frame(ctx, dem, &fr))) return fail("frame", r);
    if (!(text = read_file(roads_path, &size))) { perror(roads_path); return 2; }
    r = rs_roads_parse(ctx, text, size, &roads);
    free(text);
    if (r) return fail(roads_path, r);

    /* prepared once: the grid serves the CPU splat and the GPU scene */
    if ((r = rs_road_grid_build(ctx, dem, roads, &o, &grid))) return fail("road grid", r);
    if ((r = rs_gpu_scene_from_grid(ctx, dem, roads, grid, NULL, &scene))) return fail("GPU scene", r);
    if ((r = rs_splatter_create(ctx, dem, NULL, grid, &o, &sp))) return fail("splatter", r);
    rs_splatter_size(sp, &w, &h);
    cpu = malloc((size_t)w * h * 4);
    gpu = malloc((size_t)w * h * 4);
    if (!cpu || !gpu) return 2;
    if ((r = rs_splat_window(ctx, sp, 0, 0, w, h, cpu, (size_t)w * 4, NULL, 0, NULL))) return fail("CPU splat", r);
    if ((r = surfaces(sp, w, h, &terrain, &road))) return fail("terrain and road layers", r);

    {
        /* the host's own GL context: 3.3 core, drawing into `gpu` */
        const int attribs[] = { OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_PROFILE,
                                OSMESA_CORE_PROFILE, OSMESA_CONTEXT_MAJOR_VERSION, 3,
                                OSMESA_CONTEXT_MINOR_VERSION, 3, 0 };
        OSMesaContext gl = OSMesaCreateContextAttribs(attribs, NULL);
        GLuint vs, fs, prog, tex[2], bufs[RS_GPU_ARRAY_CUT + 1], texs[RS_GPU_ARRAY_CUT + 1], vao, vbo, ibo;
        GLint linked = 0;
        const float *z = rs_dem_samples(dem);
        uint32_t dw = rs_dem_width(dem), dh = rs_dem_height(dem);
        float *vtx = malloc((size_t)dw * dh * 6 * sizeof *vtx), mvp[16];
        GLuint *idx = malloc((size_t)(dw - 1) * (dh - 1) * 6 * sizeof *idx);
        double zmin, zmax, zr;
        size_t ni = 0;
        if (!gl || !OSMesaMakeCurrent(gl, gpu, GL_UNSIGNED_BYTE, (GLsizei)w, (GLsizei)h)) {
            fprintf(stderr, "host: no OpenGL 3.3 core context from OSMesa\n");
            return 2;
        }
        if (!vtx || !idx) return 2;
        if (!(vs = shader(GL_VERTEX_SHADER, RS_GPU_SHADER_TERRAIN_VERTEX)) ||
            !(fs = shader(GL_FRAGMENT_SHADER, RS_GPU_SHADER_TERRAIN_FRAGMENT)))
            return 2;
        prog = glCreateProgram();
        glAttachShader(prog, vs);
        glAttachShader(prog, fs);
        glLinkProgram(prog);
        glGetProgramiv(prog, GL_LINK_STATUS, &linked);
        if (!linked) { fprintf(stderr, "host: the shaders do not link\n"); return 2; }
        glUseProgram(prog);

        /* the terrain colour and road surface images on units 0 and 1, the scene on 2 .. */
        glGenTextures(2, tex);
        glActiveTexture(GL_TEXTURE0);
        image_texture(tex[0], terrain, w, h);
        glUniform1i(glGetUniformLocation(prog, "u_terrain"), 0);
        glActiveTexture(GL_TEXTURE1);
        image_texture(tex[1], road, w, h);
        glUniform1i(glGetUniformLocation(prog, "u_road"), 1);
        upload_scene(prog, scene, bufs, texs);
        rs_gpu_scene_get_info(scene, &si);
        glUniform4f(glGetUniformLocation(prog, "u_grid"), (float)si.x0, (float)si.y0, (float)(1 / si.cell),
                    (float)si.reach);
        glUniform2i(glGetUniformLocation(prog, "u_gdim"), (GLint)si.gw, (GLint)si.gh);
        glUniform2f(glGetUniformLocation(prog, "u_map"), (float)si.map_w, (float)si.map_h);
        glUniform1i(glGetUniformLocation(prog, "u_roads"), 1);
        glUniform1i(glGetUniformLocation(prog, "u_lighting"), 0); /* the splat's own shading */
        glUniform1i(glGetUniformLocation(prog, "u_fog"), 0);
        glUniform1i(glGetUniformLocation(prog, "u_nmap"), 0);

        /* the terrain mesh: a vertex per DEM sample (map frame: x east, y
         * down the map, z up, metres) with its normal, two triangles a cell */
        rs_dem_height_range(dem, &zmin, &zmax, NULL);
        zmin *= zscale, zmax *= zscale;
        if (zmin > zmax) { double t = zmin; zmin = zmax; zmax = t; }
        for (y = 0; y < dh; y++)
            for (x = 0; x < dw; x++) {
                float *v = vtx + 6 * ((size_t)y * dw + x);
                uint32_t xl = x ? x - 1 : x, xr = x + 1 < dw ? x + 1 : x, yu = y ? y - 1 : y, yd = y + 1 < dh ? y + 1 : y;
                double gx = (z[(size_t)y * dw + xr] - z[(size_t)y * dw + xl]) * zscale / ((xr - xl) * cell);
                double gy = (z[(size_t)yd * dw + x] - z[(size_t)yu * dw + x]) * zscale / ((yd - yu) * cell);
                double len = sqrt(gx * gx + gy * gy + 1);
                v[0] = (float)(x * cell), v[1] = (float)(y * cell), v[2] = (float)(z[(size_t)y * dw + x] * zscale);
                v[3] = (float)(-gx / len), v[4] = (float)(-gy / len), v[5] = (float)(1 / len);
                if (x + 1 < dw && y + 1 < dh) {
                    GLuint a = y * dw + x, b = a + 1, c = a + dw, d = c + 1;
                    idx[ni++] = a, idx[ni++] = c, idx[ni++] = b, idx[ni++] = b, idx[ni++] = c, idx[ni++] = d;
                }
            }
        glGenVertexArrays(1, &vao);
        glBindVertexArray(vao);
        glGenBuffers(1, &vbo);
        glBindBuffer(GL_ARRAY_BUFFER, vbo);
        glBufferData(GL_ARRAY_BUFFER, (GLsizeiptr)((size_t)dw * dh * 6 * sizeof *vtx), vtx, GL_STATIC_DRAW);
        glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 6 * sizeof *vtx, (void *)0);
        glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 6 * sizeof *vtx, (void *)(3 * sizeof *vtx));
        glEnableVertexAttribArray(0);
        glEnableVertexAttribArray(1);
        glGenBuffers(1, &ibo);
        glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, ibo);
        glBufferData(GL_ELEMENT_ARRAY_BUFFER, (GLsizeiptr)(ni * sizeof *idx), idx, GL_STATIC_DRAW);

        /* top-down orthographic (column-major): x 0..map_w -> -1..1, y
         * 0..map_h -> 1..-1 (the map's first row at the top), higher nearer */
        zr = zmax - zmin + 2;
        memset(mvp, 0, sizeof mvp);
        mvp[0] = (float)(2 / si.map_w);
        mvp[5] = (float)(-2 / si.map_h);
        mvp[10] = (float)(-2 / zr);
        mvp[12] = -1, mvp[13] = 1, mvp[14] = (float)((zmax + zmin) / zr), mvp[15] = 1;
        glUniformMatrix4fv(glGetUniformLocation(prog, "u_mvp"), 1, GL_FALSE, mvp);
        glUniform3f(glGetUniformLocation(prog, "u_eye"), (float)(si.map_w / 2), (float)(si.map_h / 2), (float)(zmax + 1));

        glViewport(0, 0, (GLsizei)w, (GLsizei)h);
        glClearColor(0, 0, 0, 1);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        glEnable(GL_DEPTH_TEST);
        glDrawElements(GL_TRIANGLES, (GLsizei)ni, GL_UNSIGNED_INT, (void *)0);
        glFinish();
        if (glGetError() != GL_NO_ERROR) { fprintf(stderr, "host: GL error\n"); return 2; }
        /* the frame, top row first (GL rows run bottom-up) */
        glPixelStorei(GL_PACK_ALIGNMENT, 1);
        glReadPixels(0, 0, (GLsizei)w, (GLsizei)h, GL_RGBA, GL_UNSIGNED_BYTE, terrain);
        for (y = 0; y < h; y++) memcpy(gpu + (size_t)y * w * 4, terrain + (size_t)(h - 1 - y) * w * 4, (size_t)w * 4);

        glDeleteBuffers(1, &vbo);
        glDeleteBuffers(1, &ibo);
        glDeleteVertexArrays(1, &vao);
        glDeleteBuffers(RS_GPU_ARRAY_CUT + 1, bufs);
        glDeleteTextures(RS_GPU_ARRAY_CUT + 1, texs);
        glDeleteTextures(2, tex);
        glDeleteProgram(prog);
        glDeleteShader(vs);
        glDeleteShader(fs);
        OSMesaDestroyContext(gl);
        free(vtx);
        free(idx);
    }

    {
        /* the GPU frame against the CPU splat: per-channel RGB differences */
        size_t hist[256] = { 0 }, n = (size_t)w * h * 3, acc = 0, i;
        double sum = 0, mean;
        int p99 = 0, c;
        for (i = 0; i < (size_t)w * h; i++)
            for (c = 0; c < 3; c++) {
                int d = abs((int)gpu[4 * i + c] - (int)cpu[4 * i + c]);
                hist[d]++;
                sum += d;
            }
        for (p99 = 0; p99 < 255 && (acc += hist[p99]) < (size_t)ceil(0.99 * n); p99++) continue;
        mean = sum / n;
        printf("host: %u x %u pixels, %zu segments, %zu markings: GPU - CPU mean %.3f/255, p99 %d/255\n", w, h,
               si.nseg, si.nmarks, mean, p99);
        if (argc > 6) { /* the frame as a binary PPM */
            FILE *f = fopen(argv[6], "wb");
            if (!f) { perror(argv[6]); return 2; }
            fprintf(f, "P6\n%u %u\n255\n", w, h);
            for (i = 0; i < (size_t)w * h; i++) fwrite(gpu + 4 * i, 1, 3, f);
            if (fclose(f)) { perror(argv[6]); return 2; }
        }
        free(cpu);
        free(gpu);
        free(terrain);
        free(road);
        rs_splatter_free(ctx, sp);
        rs_gpu_scene_free(ctx, scene);
        rs_road_grid_free(ctx, grid);
        rs_roads_free(ctx, roads);
        rs_dem_free(ctx, dem);
        rs_ctx_free(ctx);
        return mean <= 1 && p99 <= 8 ? 0 : 1;
    }
}
