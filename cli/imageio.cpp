// Image files through OpenImageIO, behind the C interface of cli.h: the
// readers cli_image_read_gray_float and cli_image_read_rgba8. This file is
// the image module (roadsplat-image.so, loaded by cli/module.c on first use,
// so runs without PNG/TIFF inputs never load OpenImageIO); the demimage fuzz
// target links it directly. PNG output is cli/png.c.
// Nothing thrown inside escapes an extern "C" function: every failure
// prints one line "roadsplat: FILE: problem" and returns non-zero.
#include "cli.h"

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <memory>
#include <string>
#include <vector>
#include <cerrno>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

using OIIO::ImageInput;
using OIIO::ImageSpec;
using OIIO::TypeDesc;

namespace {

// Largest native scanline or tile buffer an image may make OpenImageIO
// allocate (4096 x 4096 float RGBA is 256 MiB).
const uint64_t MAX_BUFFER_BYTES = (uint64_t)256 << 20;

struct free_deleter {
    void operator()(void *p) const { std::free(p); }
};
template <class T> using malloc_ptr = std::unique_ptr<T, free_deleter>;

// OIIO messages can span lines; keep the first, trimmed.
std::string one_line(std::string s)
{
    size_t nl = s.find_first_of("\r\n");
    if (nl != std::string::npos) s.resize(nl);
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.pop_back();
    return s.empty() ? std::string("unknown OpenImageIO error") : s;
}

// Open for reading with alpha left unassociated: textures and DEMs with an
// alpha channel must keep their stored values, not premultiplied ones.
std::unique_ptr<ImageInput> open_input(const char *path, const char *shown)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        cli_error("%s: %s", shown, std::strerror(errno));
        return nullptr;
    }
    ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = ImageInput::open(path, &config);
    if (!in) {
        cli_error("%s: cannot read image: %s", shown, one_line(OIIO::geterror()).c_str());
        return nullptr;
    }
    return in;
}

// Dimensions a caller can allocate: 2D, positive, w*h*4*4 bytes fit.
bool check_size(const char *path, const ImageSpec &spec, uint32_t *w, uint32_t *h)
{
    if (spec.width <= 0 || spec.height <= 0 || spec.depth > 1 || spec.nchannels <= 0) {
        cli_error("%s: unsupported image layout (%dx%dx%d, %d channels)", path, spec.width, spec.height,
                  spec.depth, spec.nchannels);
        return false;
    }
    uint64_t px = (uint64_t)spec.width * (uint64_t)spec.height;
    if (px > ((uint64_t)1 << 31) || px * 16 > (uint64_t)SIZE_MAX) {
        cli_error("%s: image too large (%dx%d)", path, spec.width, spec.height);
        return false;
    }
    // OpenImageIO buffers whole native scanlines and whole tiles (every
    // channel): bound them, since a tiny header can declare either huge.
    const uint64_t px_bytes = spec.pixel_bytes(true);
    if (px_bytes == 0 || (uint64_t)spec.width * px_bytes > MAX_BUFFER_BYTES) {
        cli_error("%s: unsupported image layout (%d channels of %d pixels per row)", path, spec.nchannels,
                  spec.width);
        return false;
    }
    if (spec.tile_width > 0) {
        uint64_t tile = (uint64_t)spec.tile_width * (uint64_t)(spec.tile_height > 0 ? spec.tile_height : 1) *
                        (uint64_t)(spec.tile_depth > 0 ? spec.tile_depth : 1) * px_bytes;
        if (tile > MAX_BUFFER_BYTES) {
            cli_error("%s: tiles of %dx%d pixels are too large (at most %d MiB each)", path, spec.tile_width,
                      spec.tile_height, (int)(MAX_BUFFER_BYTES >> 20));
            return false;
        }
    }
    *w = (uint32_t)spec.width;
    *h = (uint32_t)spec.height;
    return true;
}

// OIIO converts integer pixels to float normalised to [0,1] (or [-1,1]);
// the DEM wants the stored integer, i.e. "file units".
double integer_scale(TypeDesc t)
{
    switch (t.basetype) {
    case TypeDesc::UINT8: return 255.0;
    case TypeDesc::INT8: return 127.0;
    case TypeDesc::UINT16: return 65535.0;
    case TypeDesc::INT16: return 32767.0;
    case TypeDesc::UINT32: return 4294967295.0;
    case TypeDesc::INT32: return 2147483647.0;
    default: return 0.0; // half, float, double: as stored
    }
}

// Channels [0, nc) of the whole image as `type`, packed. OpenImageIO 2.4
// reads strip TIFFs in chunks of whole strips and sizes its buffer by
// RowsPerStrip even when that exceeds the image: a 161-byte TIFF asked for
// 24.7 GB. Such files are read one scanline at a time instead (every
// channel, then packed); all others in one read_image call.
bool read_pixels(ImageInput *in, const ImageSpec &spec, int nc, TypeDesc type, uint8_t *out)
{
    unsigned rps = (unsigned)spec.get_int_attribute("tiff:RowsPerStrip", 0);
    if (spec.tile_width > 0 || rps <= (unsigned)spec.height)
        return in->read_image(0, 0, 0, nc, type, out);
    const size_t w = (size_t)spec.width, ts = type.size(), all = (size_t)spec.nchannels;
    std::vector<uint8_t> row(w * all * ts);
    for (int y = 0; y < spec.height; y++) {
        if (!in->read_scanline(spec.y + y, spec.z, type, row.data())) return false;
        uint8_t *dst = out + (size_t)y * w * (size_t)nc * ts;
        for (size_t x = 0; x < w; x++)
            std::memcpy(dst + x * (size_t)nc * ts, row.data() + x * all * ts, (size_t)nc * ts);
    }
    return true;
}

// The bit depth of a grey PNG stored with 1, 2 or 4 bits per sample (read
// from its IHDR: OpenImageIO 2.4 expands such samples to 8 bits and does not
// say so), else 0.
int low_bit_depth(const char *path)
{
    unsigned char b[26];
    FILE *f = std::fopen(path, "rb");
    if (!f) return 0;
    size_t got = std::fread(b, 1, sizeof b, f);
    std::fclose(f);
    static const unsigned char sig[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n' };
    if (got < sizeof b || std::memcmp(b, sig, 8) != 0 || std::memcmp(b + 12, "IHDR", 4) != 0) return 0;
    int depth = b[24], colour = b[25];
    return colour == 0 && (depth == 1 || depth == 2 || depth == 4) ? depth : 0;
}

int read_gray_float(const char *path_in, const char *path, uint32_t max_side, uint32_t *w, uint32_t *h, float **data)
{
    auto in = open_input(path_in, path);
    if (!in) return 1;
    const ImageSpec spec = in->spec();
    if (!check_size(path, spec, w, h)) return 1;
    // A height map has one channel (grey + alpha keeps the grey): an RGB
    // image is a picture, not heights.
    if (spec.nchannels > 2) {
        cli_error("%s: a DEM must have one channel (or grey + alpha), this image has %d", path, spec.nchannels);
        return 1;
    }
    // Refuse what rs_dem_create would refuse before allocating w*h floats
    // for it (a PNG header alone can ask for 46000 x 46000).
    if (max_side && (*w > max_side || *h > max_side)) {
        cli_error("%s: %ux%u is too large for a DEM (at most %u samples per side)", path, *w, *h, max_side);
        return 1;
    }
    size_t n = (size_t)*w * *h;
    malloc_ptr<float> buf((float *)std::malloc(n * sizeof(float)));
    if (!buf) {
        cli_error("%s: out of memory for %ux%u samples", path, *w, *h);
        return 1;
    }
    if (!read_pixels(in.get(), spec, 1, TypeDesc::FLOAT, (uint8_t *)buf.get())) {
        cli_error("%s: cannot read pixels: %s", path, one_line(in->geterror()).c_str());
        return 1;
    }
    in->close();
    double s = integer_scale(spec.channelformat(0));
    // 1-, 2- and 4-bit samples come normalised from their own range, not
    // from the 8-bit type they are delivered in: 0..2^bits-1 is the height.
    int bps = low_bit_depth(path_in);
    if (s > 0.0 && bps > 0 && spec.channelformat(0).basetype == TypeDesc::UINT8) s = (double)((1u << bps) - 1u);
    if (s > 0.0) {
        float *z = buf.get();
        for (size_t i = 0; i < n; i++) z[i] = (float)std::nearbyint((double)z[i] * s);
    }
    *data = buf.release();
    return 0;
}

int read_rgba8(const char *path_in, const char *path, uint64_t max_pixels, uint32_t *w, uint32_t *h,
               uint8_t **data)
{
    auto in = open_input(path_in, path);
    if (!in) return 1;
    const ImageSpec spec = in->spec();
    if (!check_size(path, spec, w, h)) return 1;
    // The declared size against the limit, before a pixel is decoded (an
    // 875 KB PNG can declare 30000 x 30000).
    if (max_pixels && (uint64_t)*w * *h > max_pixels) {
        cli_error("%s: %ux%u is too large for a texture (at most %llu pixels)", path, *w, *h,
                  (unsigned long long)max_pixels);
        return 1;
    }
    int nc = spec.nchannels > 4 ? 4 : spec.nchannels;
    size_t n = (size_t)*w * *h;
    malloc_ptr<uint8_t> srcp((uint8_t *)std::malloc(n * (size_t)nc));
    malloc_ptr<uint8_t> outp((uint8_t *)std::malloc(n * 4));
    if (!srcp || !outp) {
        cli_error("%s: out of memory for %ux%u pixels", path, *w, *h);
        return 1;
    }
    if (!read_pixels(in.get(), spec, nc, TypeDesc::UINT8, srcp.get())) {
        cli_error("%s: cannot read pixels: %s", path, one_line(in->geterror()).c_str());
        return 1;
    }
    in->close();
    const uint8_t *src = srcp.get();
    uint8_t *out = outp.get();
    for (size_t i = 0; i < n; i++) {
        const uint8_t *s = src + i * (size_t)nc;
        uint8_t *d = out + 4 * i;
        switch (nc) {
        case 1: d[0] = d[1] = d[2] = s[0]; d[3] = 255; break;
        case 2: d[0] = d[1] = d[2] = s[0]; d[3] = s[1]; break;
        case 3: d[0] = s[0]; d[1] = s[1]; d[2] = s[2]; d[3] = 255; break;
        default: std::memcpy(d, s, 4); break;
        }
    }
    *data = outp.release();
    return 0;
}

} // namespace

namespace {
// Exceptions never cross the C boundary: report them as one line naming the
// file, free any partial result, and fail.
template <typename T, typename Read>
int guarded_read(const char *path, T **data, Read read)
{
    *data = nullptr;
    try {
        return read();
    } catch (const std::exception &e) {
        cli_error("%s: %s", path, e.what());
    } catch (...) {
        cli_error("%s: unknown error while reading", path);
    }
    std::free(*data);
    *data = nullptr;
    return 1;
}
} // namespace

extern "C" int cli_image_read_gray_float(const char *path, const char *shown, uint32_t max_side, uint32_t *w,
                                         uint32_t *h, float **data)
{
    return guarded_read(shown, data, [&] { return read_gray_float(path, shown, max_side, w, h, data); });
}

extern "C" int cli_image_read_rgba8(const char *path, const char *shown, uint64_t max_pixels, uint32_t *w,
                                    uint32_t *h, uint8_t **data)
{
    return guarded_read(shown, data, [&] { return read_rgba8(path, shown, max_pixels, w, h, data); });
}
