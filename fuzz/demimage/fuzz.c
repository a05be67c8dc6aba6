/* libFuzzer target: the CLI's DEM loader (cli_load_dem in cli/util.c, which
 * sends non-PGM files through OpenImageIO in cli/imageio.cpp) on arbitrary
 * file contents. cli_load_dem takes a path, so each input is written to a
 * file in one temporary folder per process (under $TMPDIR, /dev/shm when
 * present) and loaded from there: the exact code path of `roadsplat DEM ...`.
 * OpenImageIO itself is not instrumented; our code around it is.
 *
 * Input: byte 0 picks the file name's extension (mod 4: none, .png, .tif,
 * .pgm), the rest is the file. The extension decides which reader
 * OpenImageIO tries first, and .pgm sends any content to our own reader.
 *
 * Findings (abort): a DEM with a side < 2 or a non-finite, non-NaN sample;
 * a failure that does not print exactly one "roadsplat: PATH: ..." line;
 * success that prints a "roadsplat: " line. File descriptor 2 is sent to a
 * temporary file during the load (as cli/util.c itself does around
 * OpenImageIO) for that check; set RS_FUZZ_STDERR=1 to leave stderr alone
 * and skip the message checks, e.g. to see a sanitizer report on replay. */
#define _POSIX_C_SOURCE 200809L
#include "../../cli/cli.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerInitialize(int *argc, char ***argv);

/* OpenImageIO 2.4's PNG reader longjmps out of libpng over a live
 * std::string on some read errors and leaks it: a bug inside OpenImageIO,
 * not ours. Suppress exactly that frame for LeakSanitizer (fuzzer, replay
 * and `make sanitize-test` alike); seeing it needs full unwinding through
 * the uninstrumented libraries. Leaks from our own frames still report. */
#if defined(__GNUC__)
#define SANITIZER_HOOK __attribute__((visibility("default"), used))
#else
#define SANITIZER_HOOK
#endif
SANITIZER_HOOK const char *__lsan_default_suppressions(void);
SANITIZER_HOOK const char *__asan_default_options(void);
const char *__lsan_default_suppressions(void) { return "leak:OpenImageIO_v2_4::PNGInput::PngReadCallback\n"; }
const char *__asan_default_options(void) { return "fast_unwind_on_malloc=0"; }

static char msg[8192]; /* what the load printed */

/* Show what was printed, then abort: the finding is in the message. */
#define REQUIRE(c) do { if (!(c)) { fprintf(stderr, "demimage: %s fails; stderr was:\n%s\n", #c, msg); abort(); } } while (0)

static const char *const exts[4] = { "", ".png", ".tif", ".pgm" };
static char dir[256], err_path[300];
static int err_fd = -1;

static void remove_temp(void)
{
    char p[300];
    for (int i = 0; i < 4; i++) {
        snprintf(p, sizeof p, "%s/dem%s", dir, exts[i]);
        unlink(p);
    }
    if (err_fd >= 0) { close(err_fd); unlink(err_path); }
    rmdir(dir);
}

static int open_temp(void)
{
    const char *tmp = getenv("TMPDIR");
    if (!tmp || !*tmp) tmp = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
    snprintf(dir, sizeof dir, "%s/roadsplat-fuzz-XXXXXX", tmp);
    if (!mkdtemp(dir)) return -1;
    snprintf(err_path, sizeof err_path, "%s/stderr", dir);
    err_fd = open(err_path, O_RDWR | O_CREAT | O_TRUNC, 0600);
    atexit(remove_temp);
    return err_fd < 0 ? -1 : 0;
}

static int write_file(const char *path, const uint8_t *data, size_t size)
{
    int f = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (f < 0) return -1;
    for (size_t off = 0; off < size; ) {
        ssize_t k = write(f, data + off, size - off);
        if (k <= 0) { close(f); return -1; }
        off += (size_t)k;
    }
    return close(f);
}

static size_t count_lines(const char *s, const char *prefix, size_t plen)
{
    size_t n = 0;
    for (const char *p = s; *p; ) {
        if (strncmp(p, prefix, plen) == 0) n++;
        const char *nl = strchr(p, '\n');
        if (!nl) break;
        p = nl + 1;
    }
    return n;
}

/* OpenImageIO keeps per-thread error text and plugin state that it
 * allocates on first use and never frees; libFuzzer would call that a leak
 * of whichever input came first. Load a few failing files here, before any
 * input (libFuzzer only; the replay driver does not call this). */
int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc; (void)argv;
    static const uint8_t warm[][9] = { { 1, 0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n' },
                                       { 2, 'I', 'I', '*', 0 }, { 0, 0 }, { 1, 0 }, { 2, 0 } };
    for (size_t i = 0; i < sizeof warm / sizeof warm[0]; i++) {
        LLVMFuzzerTestOneInput(warm[i], 9);
        LLVMFuzzerTestOneInput(warm[i], 5);
    }
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) return 0;
    if (err_fd < 0 && open_temp() != 0) return 0;
    char path[300];
    snprintf(path, sizeof path, "%s/dem%s", dir, exts[data[0] % 4]);
    if (write_file(path, data + 1, size - 1) != 0) return 0;

    rs_limits lim;
    memset(&lim, 0, sizeof lim);
    lim.max_dem_side = 4096;
    rs_ctx *ctx = NULL;
    if (rs_ctx_create(NULL, &lim, &ctx) != RS_OK) return 0;

    memset(msg, 0, sizeof msg);
    int check = !getenv("RS_FUZZ_STDERR");
    int saved = -1;
    if (check) {
        fflush(stderr);
        /* fd 2 will share err_fd's offset: rewind it, or the text lands after a hole */
        if (ftruncate(err_fd, 0) != 0 || lseek(err_fd, 0, SEEK_SET) != 0 || (saved = dup(2)) < 0 || dup2(err_fd, 2) < 0) {
            if (saved >= 0) close(saved);
            rs_ctx_free(ctx);
            return 0;
        }
    }
    rs_dem *dem = cli_load_dem(ctx, path);
    if (check) {
        fflush(stderr);
        dup2(saved, 2);
        close(saved);
        ssize_t got = pread(err_fd, msg, sizeof msg - 1, 0);
        msg[got > 0 ? got : 0] = 0;
    }

    char prefix[sizeof path + 16];
    int plen = snprintf(prefix, sizeof prefix, "roadsplat: %s: ", path);
    if (dem) {
        uint32_t w = rs_dem_width(dem), h = rs_dem_height(dem);
        REQUIRE(w >= 2 && h >= 2 && w <= lim.max_dem_side && h <= lim.max_dem_side);
        const float *z = rs_dem_samples(dem);
        for (size_t k = 0; k < (size_t)w * h; k++) REQUIRE(!isinf(z[k]));
        if (check) REQUIRE(count_lines(msg, "roadsplat: ", 11) == 0);
        rs_dem_free(ctx, dem);
    } else if (check) {
        REQUIRE(count_lines(msg, "roadsplat: ", 11) == 1);
        REQUIRE(count_lines(msg, prefix, (size_t)plen) == 1);
    }
    rs_ctx_free(ctx);
    return 0;
}
