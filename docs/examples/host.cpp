// An embedding host in C++11 (docs/embedding.md "An example host"): the
// installed roadsplat only (pkg-config roadsplat), its objects held by
// std::unique_ptr, the roads drawn by the library's shaders on a GL context
// of the host's own.
//
//   c++ -std=c++11 host.cpp $(pkg-config --cflags --libs roadsplat osmesa) -o host_cpp
//   ./host_cpp network_tee.txt 41 21 2 16
//
// A flat map of W x H samples (CELL metres apart) under the roads of a road
// file, splatted at TEXELS pixels a cell: the GPU scene straight from the
// roads (rs_gpu_scene_create; host.c exports it from a prepared grid), an
// OpenGL 3.3 core context from OSMesa, one top-down quad whose fragment
// shader draws the roads, the frame read back and compared with the CPU
// splat. Exit status 1 past the bound (mean 1/255, 99th percentile 8/255),
// 2 when a step fails.
#define GL_GLEXT_PROTOTYPES 1 // libOSMesa exports every GL entry point
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>
#include <roadsplat.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

// One context for the whole run: a context serves one thread at a time.
rs_ctx *g_ctx = nullptr;

// A failed library call as an exception carrying the library's message.
void check(rs_result r, const char *step)
{
    if (r == RS_OK) return;
    const char *msg = rs_ctx_message(g_ctx);
    throw std::runtime_error(std::string(step) + ": " + (msg[0] ? msg : rs_strerror(r)));
}

// Library objects freed with the context they came from.
template <class T, void (*Free)(rs_ctx *, T *)> struct Freer {
    void operator()(T *p) const { Free(g_ctx, p); }
};
template <class T, void (*Free)(rs_ctx *, T *)> using Owned = std::unique_ptr<T, Freer<T, Free>>;
using Dem = Owned<rs_dem, rs_dem_free>;
using Roads = Owned<rs_roads, rs_roads_free>;
using Splatter = Owned<rs_splatter, rs_splatter_free>;
using Scene = Owned<rs_gpu_scene, rs_gpu_scene_free>;

struct Image {
    uint32_t w = 0, h = 0;
    std::vector<uint8_t> rgba;
};

// The whole splat of `roads` (the splatter prepares its own grid) and, from
// one layers pass of the same splatter, the shader's two colour images: the
// terrain colour (no roads) and the unstyled road surface (the material alone).
struct Splats {
    Image colour, terrain, surface;
};
Splats splat(const rs_dem *dem, const rs_roads *roads, const rs_splat_options &o)
{
    rs_splatter *raw = nullptr;
    check(rs_splatter_create(g_ctx, dem, roads, nullptr, &o, &raw), "splatter");
    Splatter sp(raw);
    Splats out;
    for (Image *im : { &out.colour, &out.terrain, &out.surface }) {
        rs_splatter_size(sp.get(), &im->w, &im->h);
        im->rgba.resize(size_t(im->w) * im->h * 4);
    }
    const uint32_t w = out.colour.w, h = out.colour.h;
    check(rs_splat_window(g_ctx, sp.get(), 0, 0, w, h, out.colour.rgba.data(), size_t(w) * 4, nullptr, 0, nullptr),
          "splat");
    rs_splat_layers layers{};
    layers.terrain = out.terrain.rgba.data();
    layers.terrain_stride = size_t(w) * 4;
    layers.surface = out.surface.rgba.data();
    layers.surface_stride = size_t(w) * 4;
    layers.surface_unstyled = 1;
    check(rs_splat_layers_window(g_ctx, sp.get(), nullptr, 0, 0, w, h, &layers, nullptr), "layers");
    return out;
}

GLuint compile(GLenum type, rs_gpu_shader which)
{
    size_t parts = 0;
    const char *const *src = rs_gpu_glsl(330, which, &parts);
    GLuint s = glCreateShader(type);
    glShaderSource(s, GLsizei(parts), src, nullptr);
    glCompileShader(s);
    GLint ok = GL_FALSE;
    glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        std::array<char, 1024> log{};
        glGetShaderInfoLog(s, GLsizei(log.size()), nullptr, log.data());
        throw std::runtime_error(std::string("GLSL: ") + log.data());
    }
    return s;
}

// A 2D image the fragment shader samples (mipmapped, clamped).
void bind_image(GLuint prog, const char *name, GLint unit, const Image &im)
{
    GLuint t = 0;
    glGenTextures(1, &t);
    glActiveTexture(GLenum(GL_TEXTURE0 + unit));
    glBindTexture(GL_TEXTURE_2D, t);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, GLsizei(im.w), GLsizei(im.h), 0, GL_RGBA, GL_UNSIGNED_BYTE,
                 im.rgba.data());
    glGenerateMipmap(GL_TEXTURE_2D);
    for (GLenum wrap : { GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T }) glTexParameteri(GL_TEXTURE_2D, wrap, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
    glUniform1i(glGetUniformLocation(prog, name), unit);
}

// Every array the shader reads, as a buffer texture on the units from 2 up.
void bind_scene(GLuint prog, const rs_gpu_scene *scene)
{
    for (int a = RS_GPU_ARRAY_SEG; a <= RS_GPU_ARRAY_CUT; ++a) {
        const rs_gpu_array which = rs_gpu_array(a);
        uint32_t channels = 0, kind = 0;
        const char *sampler = rs_gpu_array_sampler(which, &channels, &kind);
        size_t values = 0;
        const void *data = rs_gpu_scene_array(scene, which, &values);
        const GLenum formats[3][2] = { { GL_R32F, GL_RGBA32F }, { GL_R32UI, GL_RGBA32UI }, { GL_R32I, GL_RGBA32I } };
        std::vector<uint32_t> zero(channels, 0); // buffer textures cannot be empty
        GLuint buf = 0, tex = 0;
        glGenBuffers(1, &buf);
        glBindBuffer(GL_TEXTURE_BUFFER, buf);
        glBufferData(GL_TEXTURE_BUFFER, GLsizeiptr(4 * (values ? values : channels)), values ? data : zero.data(),
                     GL_STATIC_DRAW);
        glGenTextures(1, &tex);
        glActiveTexture(GLenum(GL_TEXTURE2 + a));
        glBindTexture(GL_TEXTURE_BUFFER, tex);
        glTexBuffer(GL_TEXTURE_BUFFER, formats[kind][channels == 4], buf);
        glUniform1i(glGetUniformLocation(prog, sampler), 2 + a);
    }
}

int run(int argc, char **argv)
{
    const std::string roads_path = argc > 1 ? argv[1] : "network_tee.txt";
    const uint32_t dw = argc > 2 ? uint32_t(std::atoi(argv[2])) : 41, dh = argc > 3 ? uint32_t(std::atoi(argv[3])) : 21;
    const double cell = argc > 4 ? std::atof(argv[4]) : 2;
    rs_splat_options opts{};
    opts.texels = argc > 5 ? uint32_t(std::atoi(argv[5])) : 16;

    // a flat DEM made in memory, and the roads
    std::vector<float> heights(size_t(dw) * dh, 0.0f);
    rs_dem *raw_dem = nullptr;
    check(rs_dem_create(g_ctx, dw, dh, heights.data(), &raw_dem), "DEM");
    Dem dem(raw_dem);
    rs_dem_frame frame{};
    frame.cell_size = cell;
    check(rs_dem_set_frame(g_ctx, dem.get(), &frame), "DEM frame");
    std::ifstream in(roads_path, std::ios::binary);
    if (!in.is_open()) throw std::runtime_error(roads_path + ": cannot open");
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    rs_roads *raw_roads = nullptr;
    check(rs_roads_parse(g_ctx, text.data(), text.size(), &raw_roads), roads_path.c_str());
    Roads roads(raw_roads);

    // the CPU splat, the shader's two colour images, the GPU scene
    const Splats splats = splat(dem.get(), roads.get(), opts);
    const Image &cpu = splats.colour, &terrain = splats.terrain, &surface = splats.surface;
    rs_gpu_scene *raw_scene = nullptr;
    check(rs_gpu_scene_create(g_ctx, dem.get(), roads.get(), &opts, nullptr, &raw_scene), "GPU scene");
    Scene scene(raw_scene);
    rs_gpu_scene_info info;
    rs_gpu_scene_get_info(scene.get(), &info);

    // the host's context: OpenGL 3.3 core into memory
    const int attribs[] = { OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24, OSMESA_PROFILE, OSMESA_CORE_PROFILE,
                            OSMESA_CONTEXT_MAJOR_VERSION, 3, OSMESA_CONTEXT_MINOR_VERSION, 3, 0 };
    std::unique_ptr<osmesa_context, void (*)(OSMesaContext)> gl(OSMesaCreateContextAttribs(attribs, nullptr),
                                                                OSMesaDestroyContext);
    std::vector<uint8_t> target(cpu.rgba.size());
    if (!gl || !OSMesaMakeCurrent(gl.get(), target.data(), GL_UNSIGNED_BYTE, GLsizei(cpu.w), GLsizei(cpu.h)))
        throw std::runtime_error("no OpenGL 3.3 core context from OSMesa");
    const GLuint prog = glCreateProgram();
    glAttachShader(prog, compile(GL_VERTEX_SHADER, RS_GPU_SHADER_TERRAIN_VERTEX));
    glAttachShader(prog, compile(GL_FRAGMENT_SHADER, RS_GPU_SHADER_TERRAIN_FRAGMENT));
    glLinkProgram(prog);
    GLint linked = GL_FALSE;
    glGetProgramiv(prog, GL_LINK_STATUS, &linked);
    if (!linked) throw std::runtime_error("the library's shaders do not link");
    glUseProgram(prog);
    bind_image(prog, "u_terrain", 0, terrain);
    bind_image(prog, "u_road", 1, surface);
    bind_scene(prog, scene.get());
    glUniform4f(glGetUniformLocation(prog, "u_grid"), float(info.x0), float(info.y0), float(1 / info.cell),
                float(info.reach));
    glUniform2i(glGetUniformLocation(prog, "u_gdim"), GLint(info.gw), GLint(info.gh));
    glUniform2f(glGetUniformLocation(prog, "u_map"), float(info.map_w), float(info.map_h));
    glUniform1i(glGetUniformLocation(prog, "u_roads"), 1);
    for (const char *off : { "u_lighting", "u_fog", "u_nmap" }) glUniform1i(glGetUniformLocation(prog, off), 0);

    // the flat map as one quad (map frame, normal up), seen from straight
    // above: x 0..map_w to clip -1..1, y 0..map_h to 1..-1 (first row on top)
    const float W = float(info.map_w), H = float(info.map_h);
    const std::array<float, 24> quad = { 0, 0, 0, 0, 0, 1, W, 0, 0, 0, 0, 1, 0, H, 0, 0, 0, 1, W, H, 0, 0, 0, 1 };
    const std::array<float, 16> mvp = { 2 / W, 0, 0, 0, 0, -2 / H, 0, 0, 0, 0, -1, 0, -1, 1, 0, 1 };
    glUniformMatrix4fv(glGetUniformLocation(prog, "u_mvp"), 1, GL_FALSE, mvp.data());
    glUniform3f(glGetUniformLocation(prog, "u_eye"), W / 2, H / 2, 1);
    GLuint vao = 0, vbo = 0;
    glGenVertexArrays(1, &vao);
    glBindVertexArray(vao);
    glGenBuffers(1, &vbo);
    glBindBuffer(GL_ARRAY_BUFFER, vbo);
    glBufferData(GL_ARRAY_BUFFER, GLsizeiptr(sizeof quad), quad.data(), GL_STATIC_DRAW);
    for (GLuint attr : { 0u, 1u }) {
        glVertexAttribPointer(attr, 3, GL_FLOAT, GL_FALSE, 6 * sizeof(float),
                              reinterpret_cast<const void *>(attr * 3 * sizeof(float)));
        glEnableVertexAttribArray(attr);
    }
    glViewport(0, 0, GLsizei(cpu.w), GLsizei(cpu.h));
    glClear(GL_COLOR_BUFFER_BIT);
    glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
    glFinish();
    if (glGetError() != GL_NO_ERROR) throw std::runtime_error("GL error while drawing");
    std::vector<uint8_t> frame_rgba(cpu.rgba.size());
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glReadPixels(0, 0, GLsizei(cpu.w), GLsizei(cpu.h), GL_RGBA, GL_UNSIGNED_BYTE, frame_rgba.data());

    // against the CPU splat: GL's rows run bottom-up
    std::array<size_t, 256> hist{};
    double sum = 0;
    const size_t row = size_t(cpu.w) * 4;
    for (uint32_t y = 0; y < cpu.h; ++y)
        for (size_t i = 0; i < row; ++i) {
            if (i % 4 == 3) continue; // RGB only
            const int d = std::abs(int(frame_rgba[(cpu.h - 1 - y) * row + i]) - int(cpu.rgba[y * row + i]));
            ++hist[size_t(d)];
            sum += d;
        }
    const size_t values = size_t(cpu.w) * cpu.h * 3;
    size_t seen = 0, p99 = 0;
    while (p99 < 255 && (seen += hist[p99]) < size_t(std::ceil(0.99 * double(values)))) ++p99;
    const double mean = sum / double(values);
    std::printf("host_cpp: %u x %u pixels, %zu segments, %zu bands, %zu markings: GPU - CPU mean %.3f/255, "
                "p99 %zu/255\n", cpu.w, cpu.h, info.nseg, info.nbands, info.nmarks, mean, p99);
    return mean <= 1 && p99 <= 8 ? 0 : 1;
}

} // namespace

int main(int argc, char **argv)
{
    if (rs_ctx_create(nullptr, nullptr, &g_ctx) != RS_OK) return 2;
    int rc = 2;
    try {
        rc = run(argc, argv);
    } catch (const std::exception &e) {
        std::fprintf(stderr, "host_cpp: %s\n", e.what());
    }
    rs_ctx_free(g_ctx);
    return rc;
}
