// The CLI's PNG writer (cli/png.c): images written at several levels, sizes
// and layouts are read back through OpenImageIO and through libpng directly
// and compared pixel for pixel; atomic replacement, refused targets, the
// completeness check and the progress callback.
//
// Also the writers' timing tool of tests/bench/write.sh:
//   test_png --time-oiio IN.png OUT.png RUNS     OpenImageIO 2.4 defaults (libpng)
//   test_png --time-level L IN.png OUT.png RUNS  cli/png.c at level L
// read IN (RGB8 or RGBA8), write OUT RUNS times, print "fastest_ms bytes".
#include "../../cli/png.h"

#include <OpenImageIO/imageio.h>
#include <png.h>

#include <algorithm>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <dirent.h>
#include <string>
#include <sys/stat.h>
#include <unistd.h>
#include <vector>

static int passed, failed;
#define CHECK(c, ...)                                                                                                 \
    do {                                                                                                              \
        if (c) passed++;                                                                                              \
        else {                                                                                                        \
            failed++;                                                                                                 \
            std::printf("FAIL %s:%d: %s: ", __FILE__, __LINE__, #c);                                                  \
            std::printf(__VA_ARGS__);                                                                                 \
            std::printf("\n");                                                                                        \
        }                                                                                                             \
    } while (0)

static std::string dir;

struct image {
    uint32_t w, h;
    int channels, bits;
    std::vector<uint8_t> b8;
    std::vector<uint16_t> b16;
    const void *data() const { return bits == 8 ? (const void *)b8.data() : (const void *)b16.data(); }
    size_t samples() const { return (size_t)w * h * (size_t)channels; }
};

// Smooth gradients with some noise (kind 0), pure noise (kind 1) or one flat
// value (kind 2).
static image make_image(uint32_t w, uint32_t h, int channels, int bits, int kind, uint32_t seed)
{
    image im{ w, h, channels, bits, {}, {} };
    uint32_t s = seed * 2654435761u + 1;
    size_t n = im.samples();
    if (bits == 8) im.b8.resize(n);
    else im.b16.resize(n);
    for (uint32_t y = 0; y < h; y++)
        for (uint32_t x = 0; x < w; x++)
            for (int c = 0; c < channels; c++) {
                s = s * 1103515245u + 12345u;
                uint32_t noise = s >> 16; /* the LCG's better bits */
                uint32_t v = kind == 1 ? noise
                             : kind == 2 ? 77u
                                         : (x * 7 + y * 3 + (uint32_t)c * 50) * (bits == 8 ? 1u : 131u) + (noise & 7);
                size_t i = ((size_t)y * w + x) * (size_t)channels + (size_t)c;
                if (bits == 8) im.b8[i] = (uint8_t)v;
                else im.b16[i] = (uint16_t)v;
            }
    return im;
}

// Through OpenImageIO, in the image's own type.
static bool read_oiio(const std::string &path, const image &want, std::string &why)
{
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1); // stored values, not premultiplied
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in) { why = OIIO::geterror(); return false; }
    const OIIO::ImageSpec &sp = in->spec();
    if ((uint32_t)sp.width != want.w || (uint32_t)sp.height != want.h || sp.nchannels != want.channels) {
        why = "size or channels differ";
        return false;
    }
    OIIO::TypeDesc t = want.bits == 8 ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::UINT16;
    if (sp.format != t) { why = "sample type differs"; return false; }
    std::vector<uint8_t> buf(want.samples() * (size_t)(want.bits / 8));
    if (!in->read_image(0, 0, 0, want.channels, t, buf.data())) { why = in->geterror(); return false; }
    in->close();
    if (std::memcmp(buf.data(), want.data(), buf.size()) != 0) { why = "pixels differ"; return false; }
    return true;
}

// Through libpng's own reader, 16-bit samples swapped to native order.
static bool read_libpng(const std::string &path, const image &want, std::string &why)
{
    FILE *f = std::fopen(path.c_str(), "rb");
    if (!f) { why = "cannot open"; return false; }
    png_structp p = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
    png_infop info = p ? png_create_info_struct(p) : nullptr;
    if (!info) { std::fclose(f); why = "libpng init"; return false; }
    std::vector<uint8_t> buf(want.samples() * (size_t)(want.bits / 8));
    std::vector<png_bytep> rows(want.h);
    volatile bool ok = false; // set between setjmp and a possible longjmp
    if (setjmp(png_jmpbuf(p)) == 0) {
        png_init_io(p, f);
        png_read_info(p, info);
        if (png_get_image_width(p, info) == want.w && png_get_image_height(p, info) == want.h &&
            png_get_channels(p, info) == want.channels && png_get_bit_depth(p, info) == want.bits &&
            png_get_interlace_type(p, info) == PNG_INTERLACE_NONE) {
            if (want.bits == 16) {
                uint16_t one = 1;
                uint8_t first;
                std::memcpy(&first, &one, 1);
                if (first) png_set_swap(p);
            }
            png_read_update_info(p, info);
            size_t stride = (size_t)want.w * (size_t)want.channels * (size_t)(want.bits / 8);
            for (uint32_t y = 0; y < want.h; y++) rows[y] = buf.data() + (size_t)y * stride;
            png_read_image(p, rows.data());
            png_read_end(p, nullptr);
            ok = std::memcmp(buf.data(), want.data(), buf.size()) == 0;
            if (!ok) why = "pixels differ";
        } else why = "header differs";
    } else why = "libpng error";
    png_destroy_read_struct(&p, &info, nullptr);
    std::fclose(f);
    return ok;
}

static long file_size(const std::string &path)
{
    struct stat st;
    return stat(path.c_str(), &st) == 0 ? (long)st.st_size : -1;
}

static int entries(const std::string &d)
{
    int n = 0;
    DIR *dp = opendir(d.c_str());
    if (!dp) return -1;
    while (struct dirent *e = readdir(dp))
        if (std::strcmp(e->d_name, ".") && std::strcmp(e->d_name, "..")) n++;
    closedir(dp);
    return n;
}

struct progress_log {
    std::vector<uint64_t> done;
    bool bad_total = false;
};
static int log_progress(void *user, uint64_t done, uint64_t total)
{
    auto *l = (progress_log *)user;
    l->done.push_back(done);
    if (total != 1000) l->bad_total = true;
    return 0;
}

// The file through the band coder with libdeflate at every level (ISA-L's
// level 1 off), as cli_png_encode does.
static bool encode_libdeflate(const std::string &path, const image &im, int level)
{
    cli_png_layout l;
    if (cli_png_layout_init(&l, path.c_str(), im.w, im.h, im.channels, im.bits, level)) return false;
    l.isal = 0;
    cli_png_coder *c = cli_png_coder_new(&l);
    FILE *f = std::fopen(path.c_str(), "wb");
    cli_png_writer w;
    bool ok = c && f && cli_png_writer_begin(&w, f, &l) == 0;
    size_t stride = (size_t)im.w * (size_t)im.channels * (size_t)(im.bits / 8);
    for (uint32_t b = 0; ok && b < l.nbands; b++) {
        cli_png_piece p;
        ok = cli_png_coder_band(c, b, (const uint8_t *)im.data() + (size_t)b * l.band_rows * stride, stride, &p) == 0 &&
             cli_png_writer_band(&w, &p) == 0;
    }
    ok = ok && cli_png_writer_end(&w) == 0;
    if (f && std::fclose(f) != 0) ok = false;
    cli_png_coder_free(c);
    return ok;
}

// isal false: level 1 by libdeflate even where ISA-L is built in.
static void round_trip(uint32_t w, uint32_t h, int channels, int bits, int kind, int level, bool isal = true)
{
    image im = make_image(w, h, channels, bits, kind, w * 31 + h + (uint32_t)level);
    std::string path = dir + "/rt.png", why;
    cli_png_image img = { w, h, channels, bits, im.data() };
    progress_log pl;
    cli_png_options opt = { level, log_progress, &pl, 0 };
    char name[160];
    std::snprintf(name, sizeof name, "%ux%u, %d channels, %d bits, kind %d, level %d%s", w, h, channels, bits, kind,
                  level, isal ? "" : " (libdeflate)");
    if (isal) {
        CHECK(cli_png_write(path.c_str(), nullptr, &img, &opt) == 0, "%s: write", name);
        bool mono = std::is_sorted(pl.done.begin(), pl.done.end());
        CHECK(!pl.done.empty() && pl.done.back() == 1000 && mono && !pl.bad_total, "%s: progress", name);
    } else {
        CHECK(encode_libdeflate(path, im, level), "%s: write", name);
    }
    CHECK(cli_png_file_complete(path.c_str()), "%s: not complete", name);
    CHECK(read_oiio(path, im, why), "%s: OpenImageIO: %s", name, why.c_str());
    why.clear();
    CHECK(read_libpng(path, im, why), "%s: libpng: %s", name, why.c_str());
}

// How the pieces of an image's bands were joined (cli_png_coder_joins).
static void joins_of(const image &im, int level, uint64_t j[4], bool isal = true)
{
    cli_png_layout l;
    j[0] = j[1] = j[2] = j[3] = 0;
    if (cli_png_layout_init(&l, "joins", im.w, im.h, im.channels, im.bits, level)) return;
    if (!isal) l.isal = 0;
    cli_png_coder *c = cli_png_coder_new(&l);
    if (!c) return;
    size_t stride = (size_t)im.w * (size_t)im.channels * (size_t)(im.bits / 8);
    for (uint32_t b = 0; b < l.nbands; b++) {
        cli_png_piece p;
        if (cli_png_coder_band(c, b, (const uint8_t *)im.data() + (size_t)b * l.band_rows * stride, stride, &p)) break;
    }
    cli_png_coder_joins(c, j);
    cli_png_coder_free(c);
}

// An 8-bit RGB or RGBA image (the CLI's output: RGB when opaque, RGBA
// with --rgba or nodata); *ch = its channels.
static bool read_rgb8(const char *path, std::vector<uint8_t> &px, uint32_t &w, uint32_t &h, int &ch)
{
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in) return false;
    w = (uint32_t)in->spec().width;
    h = (uint32_t)in->spec().height;
    ch = in->spec().nchannels;
    if (ch != 3 && ch != 4) return false;
    px.resize((size_t)w * h * (size_t)ch);
    return in->read_image(0, 0, 0, ch, OIIO::TypeDesc::UINT8, px.data());
}

static int time_writer(int argc, char **argv)
{
    bool oiio = !std::strcmp(argv[1], "--time-oiio");
    if (oiio ? argc != 5 : (argc != 6 || std::strcmp(argv[1], "--time-level"))) return 2;
    int level = oiio ? -1 : std::atoi(argv[2]);
    const char *in = argv[oiio ? 2 : 3], *out = argv[oiio ? 3 : 4];
    int runs = std::atoi(argv[oiio ? 4 : 5]);
    std::vector<uint8_t> px;
    uint32_t w, h;
    int ch;
    if (!read_rgb8(in, px, w, h, ch)) { std::fprintf(stderr, "test_png: cannot read %s as RGB8 or RGBA8\n", in); return 1; }
    std::vector<double> ms;
    for (int r = 0; r < (runs > 0 ? runs : 1); r++) {
        double t0 = cli_now_ms();
        if (oiio) { // what cli/imageio.cpp did before cli/png.c (minus the temporary + rename)
            auto o = OIIO::ImageOutput::create("png");
            OIIO::ImageSpec spec((int)w, (int)h, ch, OIIO::TypeDesc::UINT8);
            spec.attribute("oiio:UnassociatedAlpha", 1);
            if (!o || !o->open(out, spec) || !o->write_image(OIIO::TypeDesc::UINT8, px.data()) || !o->close()) {
                std::fprintf(stderr, "test_png: OpenImageIO write failed\n");
                return 1;
            }
        } else {
            cli_png_image img = { w, h, ch, 8, px.data() };
            cli_png_options opt = { level, nullptr, nullptr, 0 };
            if (cli_png_write(out, nullptr, &img, &opt)) return 1;
        }
        ms.push_back(cli_now_ms() - t0);
    }
    std::sort(ms.begin(), ms.end());
    std::printf("%.1f %ld\n", ms[0], file_size(out));
    return 0;
}

int main(int argc, char **argv)
{
    if (argc > 1) {
        int rc = time_writer(argc, argv);
        if (rc == 2) std::fprintf(stderr, "usage: test_png [--time-oiio IN OUT RUNS | --time-level L IN OUT RUNS]\n");
        return rc;
    }
    char tmpl[] = "/tmp/test_png.XXXXXX";
    if (!mkdtemp(tmpl)) return 1;
    dir = tmpl;

    // The layouts the CLI writes: RGBA8 (splat), RGB8 (render), grey16; and the rest.
    const uint32_t sizes[][2] = { { 1, 1 }, { 7, 3 }, { 1, 9 }, { 300, 200 } };
    for (auto &s : sizes)
        for (int level : { 0, 1, 6, 12 }) {
            round_trip(s[0], s[1], 4, 8, 0, level);
            round_trip(s[0], s[1], 1, 16, 0, level);
        }
    for (int ch = 1; ch <= 4; ch++)
        for (int bits : { 8, 16 }) round_trip(33, 17, ch, bits, 0, 3);
    round_trip(640, 480, 3, 8, 0, 1);
    // Noise: several 1 MiB IDAT chunks, and a stream that does not compress.
    round_trip(800, 400, 4, 8, 1, 1);
    round_trip(700, 300, 1, 16, 1, 9);
    round_trip(1024, 300, 4, 8, 1, 0);
    // Several bands (cli/png.h): each compressed alone and joined into one
    // stream, at every kind of level; 16-bit rows across band edges; a flat
    // image; noise that libdeflate stores.
    for (bool isal : { true, false }) { // level 1 by either engine
        for (int level : { 0, 1, 2, 6, 12 }) round_trip(2000, 700, 4, 8, 0, level, isal);
        round_trip(3000, 200, 1, 16, 0, 1, isal);
        round_trip(1500, 500, 4, 16, 0, 4, isal);
        round_trip(1024, 600, 4, 8, 2, 1, isal);
        round_trip(1024, 600, 3, 8, 2, 9, isal);
        round_trip(1500, 400, 4, 8, 1, 1, isal);
        round_trip(4096, 100, 4, 8, 0, 1, isal);
        round_trip(300, 200, 2, 16, 0, 1, isal);
        round_trip(1, 1, 4, 8, 0, 1, isal);
    }
    { // every way of joining pieces is used
        uint64_t j[4];
        auto show = [&j]() {
            static char b[96];
            std::snprintf(b, sizeof b, "%llu %llu %llu %llu", (unsigned long long)j[0], (unsigned long long)j[1],
                          (unsigned long long)j[2], (unsigned long long)j[3]);
            return b;
        };
        joins_of(make_image(2000, 700, 4, 8, 0, 1), 1, j, false);
        CHECK(j[1] > 0 && j[3] == 0, "libdeflate level 1: no piece joined by its end-of-block code (%s)", show());
        joins_of(make_image(2000, 700, 4, 8, 0, 1), 0, j);
        CHECK(j[0] > 0 && j[1] == 0 && j[2] == 0 && j[3] == 0, "level 0: pieces not stored (%s)", show());
        joins_of(make_image(1500, 400, 4, 8, 1, 1), 1, j, false);
        CHECK(j[0] > 0, "noise at libdeflate level 1: no stored piece (%s)", show());
        joins_of(make_image(2000, 700, 4, 8, 0, 1), 6, j);
        CHECK(j[2] > 0, "level 6: no piece joined through inflate (%s)", show());
        joins_of(make_image(2000, 700, 4, 8, 0, 1), 1, j);
#ifdef RS_WITH_ISAL
        CHECK(j[3] >= 2 && j[0] + j[1] + j[2] == 0, "ISA-L level 1: not ISA-L bands (%s)", show());
#else
        CHECK(j[3] == 0 && j[1] > 0, "level 1 without ISA-L: not libdeflate (%s)", show());
#endif
    }
    // Random layouts, sizes and levels.
    uint32_t rs = 12345;
    auto rnd = [&rs](uint32_t n) { rs = rs * 1103515245u + 12345u; return (rs >> 8) % n; };
    for (int i = 0; i < 24; i++) {
        uint32_t w = 1 + rnd(1800), h = 1 + rnd(600);
        int ch = 1 + (int)rnd(4), bits = rnd(3) ? 8 : 16, kind = (int)rnd(3), level = (int)rnd(13);
        if ((uint64_t)w * h * (uint64_t)ch * (uint64_t)(bits / 8) > (6u << 20)) h = 1 + h / 4;
        round_trip(w, h, ch, bits, kind, level);
    }

    // Atomic replacement: an old file is replaced whole, no temporary left.
    std::string sub = dir + "/atomic";
    mkdir(sub.c_str(), 0755);
    std::string target = sub + "/out.png";
    FILE *f = std::fopen(target.c_str(), "wb");
    std::fputs("old", f);
    std::fclose(f);
    image im = make_image(50, 40, 4, 8, 0, 7);
    cli_png_image img = { 50, 40, 4, 8, im.data() };
    std::string why;
    CHECK(cli_png_write(target.c_str(), nullptr, &img, nullptr) == 0 && read_oiio(target, im, why), "replace");
    CHECK(entries(sub) == 1, "temporary left behind (%d entries)", entries(sub));

    // Refused: bad layouts and levels, a folder as target (old file kept).
    std::fprintf(stderr, "(the next lines are expected refusals)\n");
    cli_png_image bad = { 50, 40, 5, 8, im.data() };
    CHECK(cli_png_write(target.c_str(), nullptr, &bad, nullptr) != 0, "5 channels");
    bad = { 50, 40, 4, 12, im.data() };
    CHECK(cli_png_write(target.c_str(), nullptr, &bad, nullptr) != 0, "12 bits");
    cli_png_options lv = { 13, nullptr, nullptr, 0 };
    CHECK(cli_png_write(target.c_str(), nullptr, &img, &lv) != 0, "level 13");
    CHECK(read_oiio(target, im, why) && entries(sub) == 1, "old file kept after refusals");
    CHECK(cli_png_write(sub.c_str(), nullptr, &img, nullptr) != 0, "folder as target");
    CHECK(cli_png_write((sub + "/missing/x.png").c_str(), nullptr, &img, nullptr) != 0, "missing folder");
    int lvl = -5;
    CHECK(cli_parse_png_level("--png-level", "12", &lvl) == 0 && lvl == 12, "parse 12");
    CHECK(cli_parse_png_level("--png-level", "0", &lvl) == 0 && lvl == 0, "parse 0");
    CHECK(cli_parse_png_level("--png-level", "13", &lvl) != 0, "parse 13");
    CHECK(cli_parse_png_level("--png-level", "-1", &lvl) != 0, "parse -1");
    CHECK(cli_parse_png_level("--png-level", "x", &lvl) != 0, "parse x");

    // The completeness check: truncation and a flipped byte are caught.
    std::vector<uint8_t> bytes;
    f = std::fopen(target.c_str(), "rb");
    for (int c; (c = std::fgetc(f)) != EOF;) bytes.push_back((uint8_t)c);
    std::fclose(f);
    std::string cut = dir + "/cut.png";
    for (size_t keep : { bytes.size() - 1, bytes.size() - 12, (size_t)40, (size_t)8 }) {
        f = std::fopen(cut.c_str(), "wb");
        std::fwrite(bytes.data(), 1, keep, f);
        std::fclose(f);
        CHECK(!cli_png_file_complete(cut.c_str()), "truncated to %zu bytes passes", keep);
    }
    bytes[bytes.size() / 2] ^= 1;
    f = std::fopen(cut.c_str(), "wb");
    std::fwrite(bytes.data(), 1, bytes.size(), f);
    std::fclose(f);
    CHECK(!cli_png_file_complete(cut.c_str()), "flipped byte passes");

    std::string cmd = "rm -rf '" + dir + "'";
    if (std::system(cmd.c_str()) != 0) std::printf("note: could not remove %s\n", dir.c_str());
    std::printf("test_png: %d passed, %d failed\n", passed, failed);
    return failed != 0;
}
