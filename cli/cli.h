/* Shared CLI helpers: number parsing, file I/O, atomic output, images
 * through OpenImageIO (cli/imageio.cpp), progress bar, error reporting.
 * Every function that fails prints exactly one line on stderr,
 * "roadsplat: <file>: <problem>", and returns non-zero / NULL. */
#ifndef RS_CLI_H
#define RS_CLI_H
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <sys/stat.h>
#include "roadsplat.h"

#ifdef __cplusplus
extern "C" {
#endif

/* "roadsplat: " + message + newline on stderr. */
void cli_error(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;

/* Strict number parsing of a whole option value: end-pointer checked, no
 * trailing junk, finite, locale-independent. Return 0 on success; on
 * failure print "roadsplat: OPTION: 'VALUE' is not a ..." and return 1. */
int cli_parse_double(const char *option, const char *s, double *out);
int cli_parse_u32(const char *option, const char *s, uint32_t *out);
/* "X,Y" or "X,Y,Z" (n = 2 or 3) and "WxH". */
int cli_parse_vec(const char *option, const char *s, double *out, int n);
int cli_parse_size(const char *option, const char *s, uint32_t *w, uint32_t *h);

/* Read a whole file (max `limit` bytes, 0 = no limit). *data is malloc'd
 * and NUL-terminated (size excludes the NUL). */
int cli_read_file(const char *path, size_t limit, char **data, size_t *size);
/* The same for an input of the run: registered under `role` (below). */
int cli_read_input(const char *path, const char *role, size_t limit, char **data, size_t *size);

/* The run's inputs (docs/ROBUSTNESS.md, "trust model"): every loader
 * registers the file it read, by the descriptor it read it from, so that
 * no output replaces an input (cli_out_commit_all checks every rename) and
 * tiles can hash exactly the bytes that were loaded. A regular file keeps
 * a descriptor of that inode; a pipe's bytes (data, size; NULL when fd is
 * already a copy) go to an unlinked temporary file when
 * cli_inputs_keep_pipes is on. 0, or 1 after a message. */
int cli_inputs_add(const char *path, const char *role, int fd, const void *data, size_t size);
/* (A folder - a GIS source - is registered by inode, not hashed.) */
/* Keep a copy of what is read from pipes (for hashing: tiles); off by
 * default, so a pipe costs no temporary file where nothing hashes it. */
void cli_inputs_keep_pipes(int on);
size_t cli_inputs_count(void);
/* Entry i's names; returns its descriptor (read it with pread from offset
 * 0; -1: a folder, -1 too when i is out of range). */
int cli_inputs_get(size_t i, const char **path, const char **role);
/* 1 after a message when the existing file `path` is one of the inputs. */
int cli_inputs_check_output(const char *path, const char *role);
void cli_inputs_clear(void);

/* The decoded-image budget: the pixels every texture, atlas and surface
 * image of a run may hold together (--max-image-pixels; 0: none). */
#define CLI_IMAGE_BUDGET_DEFAULT ((uint64_t)1 << 27)
void cli_image_budget_set(uint64_t pixels);

/* An input opened once (docs/ROBUSTNESS.md, "trust model"): every reader
 * of a run's input reads this descriptor (or what was read from it), never
 * the name again, so what is loaded, registered and hashed is one inode (or
 * one pipe's bytes). cli_input_open: a regular file or a pipe (a folder
 * when folder_ok: a GIS source), devices refused; the first bytes are read
 * into head (got of them; eof: that is all). 0, or 1 after a message. */
typedef struct cli_input {
    const char *path;
    int fd;
    struct stat st;
    char head[4096];
    size_t got;
    int eof;
    char *all; /* a pipe's bytes handed back by a reader (cli_input_keep) */
    size_t all_size;
} cli_input;
int cli_input_open(cli_input *in, const char *path, int folder_ok);
/* The whole input, head included (malloc'd, NUL-terminated, at most limit
 * bytes): a regular file from its descriptor, a pipe once. 0, or 1 after a
 * message. */
int cli_input_read_all(cli_input *in, size_t limit, char **data, size_t *size);
/* Give a pipe's bytes back for the next reader (the input owns them). */
void cli_input_keep(cli_input *in, char *data, size_t size);
void cli_input_close(cli_input *in);

/* Load a DEM: PGM (P2/P5) through the library, anything else through
 * OpenImageIO (PNG 8/16-bit, TIFF incl. float32; single channel, or the
 * first channel of a grey+alpha image). Prints the error and returns NULL. */
rs_dem *cli_load_dem(rs_ctx *ctx, const char *path);
/* The same from an opened input (closed here, on every path). */
rs_dem *cli_load_dem_input(rs_ctx *ctx, cli_input *in);
/* A texture image as RGBA8 (malloc'd, the caller frees *rgba); OpenImageIO's
 * own stderr output is filtered as for DEMs. Registered as an input under
 * `role` (NULL: not) and charged to the decoded-image budget (a PNG from
 * its header, before decoding). 0 or 1 after a message. */
int cli_load_texture(const char *path, const char *role, uint32_t *w, uint32_t *h, uint8_t **rgba);
/* A context for the next cli_error lines ("FILE line N: surface image"),
 * printed before their message; NULL: none. */
void cli_error_context(const char *context);
/* cli_error on this thread writes its first line (no newline) into buf
 * (CLI_ERROR_CAP bytes, emptied here) instead of stderr, until called with
 * NULL: a worker thread's error is printed by the thread that reports it
 * (cli/tiles.c), so a run still says one line. 0, or 1 when it cannot. */
#define CLI_ERROR_CAP 512
int cli_error_capture(char *buf);

/* Atomic output: write into a temporary file in the same folder, then
 * rename over `path` on commit. Abort (or a failed commit) removes the
 * temporary file and leaves any existing `path` untouched. */
typedef struct cli_out {
    FILE *f;
    char *path;
    char *tmp;
} cli_out;
int cli_out_open(cli_out *o, const char *path);     /* opens o->f for binary writing */
int cli_out_commit(cli_out *o);                       /* fflush+fsync+fclose+rename */
void cli_out_abort(cli_out *o);
int cli_out_write_file(const char *path, const void *data, size_t size); /* open, write, commit: 0 or 1 */
/* fflush+fsync+fclose of o->f (when open), without renaming: 0 or 1 after a
 * "write failed" message. */
int cli_out_finish(cli_out *o);
/* Commit a run's outputs together: finish each (NULL entries and outputs
 * without a temporary are skipped), then rename them all with SIGINT,
 * SIGTERM and SIGHUP held. A failure leaves the temporaries for
 * cli_out_abort. */
int cli_out_commit_all(cli_out *const *outs, size_t n);

/* Temporaries: "DIR/.rs-XXXXXX" next to `path` (a fixed-length name, so any
 * OUT name the file system accepts works), mode 0666 & ~umask, registered
 * so that a signal removes it. Returns the descriptor, or -1 with errno. */
int cli_temp_create(const char *path, char **tmp);
void cli_temp_remove(const char *tmp); /* unlink + forget */
int cli_temp_create_named(const char *tmp); /* a new temporary of a name unique to the run (O_EXCL | O_NOFOLLOW) */
void cli_temp_forget(const char *tmp); /* after a rename */
/* SIGINT, SIGTERM, SIGHUP: remove every registered temporary and exit with
 * status 128 + signal. Call once at start-up. */
void cli_signals_install(void);

/* One file of a run and its role in messages ("OUT", "--stats", "DEM"). */
typedef struct cli_file_role {
    const char *path; /* NULL: not given */
    const char *role;
} cli_file_role;
/* Before any work: every output name is non-empty and not a folder name,
 * names no input (same device and inode) and no other output (same inode,
 * or the same folder and name when not created yet). 0, or 1 after one
 * error line. */
int cli_check_outputs(const cli_file_role *outs, size_t nout, const cli_file_role *ins, size_t nin);

/* 1 when the file at `path` is a whole PNG (signature, chunk lengths that
 * chain to an IEND at the end of the file, every CRC right). */
int cli_png_file_complete(const char *path);

/* Images through OpenImageIO (the image module). Data is malloc'd,
 * row-major, top row first. */
/* A grey image larger than max_side (0: no limit) on either side is refused
 * before its samples are allocated. */
/* `shown` is the name messages give (path may be a /dev/fd/N copy of a pipe).
 * A DEM must have one channel (or grey + alpha); images of fewer than 8 bits
 * per sample give their stored values (a 1-bit PNG: 0 and 1). */
int cli_image_read_gray_float(const char *path, const char *shown, uint32_t max_side, uint32_t *w, uint32_t *h,
                              float **data);
/* A texture of more than max_pixels (0: no limit) is refused from its
 * header, before anything is decoded. */
int cli_image_read_rgba8(const char *path, const char *shown, uint64_t max_pixels, uint32_t *w, uint32_t *h,
                         uint8_t **data);

/* PNG output (cli/png.c: own container, libdeflate for the stream). An
 * image: channels 1..4 (grey, grey+alpha, RGB, RGBA), bits 8 or 16 (16-bit
 * data as native uint16), rows top first, no padding. */
typedef struct cli_png_image {
    uint32_t width, height;
    int channels, bits;
    const void *data;
} cli_png_image;
/* --png-level: libdeflate's 0 (stored) .. 12; the default 1 is the fastest
 * compressing level (docs/packaging.md: why). */
#define CLI_PNG_LEVEL_DEFAULT 1
#define CLI_PNG_LEVEL_MAX 12
typedef struct cli_png_options {
    int level;                 /* -1: CLI_PNG_LEVEL_DEFAULT */
    rs_progress_fn progress;   /* may be NULL; called with total 1000 */
    void *progress_user;
    /* 1: level 1 by libdeflate, never ISA-L: ISA-L's level-1 stream for the
     * same bytes was seen to differ between processes (docs/tiles.md,
     * "Threads"), and tiles are compared byte for byte */
    int no_isal;
} cli_png_options;
/* Encode the PNG into an open file (flushed, not closed). opt may be NULL. */
int cli_png_encode(FILE *f, const char *shown, const cli_png_image *img, const cli_png_options *opt);
/* Write a PNG atomically (temp file in the same folder + rename), only
 * after checking the temporary is a whole PNG; refuses a target that exists
 * and is not a regular file. Messages name `shown` (NULL: path). */
int cli_png_write(const char *path, const char *shown, const cli_png_image *img, const cli_png_options *opt);
/* cli_png_write at the default level. */
int cli_image_write_png(const char *path, uint32_t w, uint32_t h, int channels, int bits,
                        const void *data);
/* The same, naming `shown` in its messages (path is then a temporary). */
int cli_image_write_png_as(const char *path, const char *shown, uint32_t w, uint32_t h, int channels, int bits,
                           const void *data);
/* Parse a --png-level value (0..CLI_PNG_LEVEL_MAX): 0, or 1 after a message. */
int cli_parse_png_level(const char *option, const char *s, int *level);

/* Optional modules (cli/module.c), loaded on first use from the folder of
 * the executable, then $(LIBDIR)/roadsplat: "image" (roadsplat-image.so,
 * OpenImageIO) and "render" (roadsplat-render.so, OSMesa). Returns the
 * symbol, or NULL after printing "roadsplat: WHAT: ..." naming the module
 * and the reason (not found, or the library it could not load). */
void *cli_module_symbol(const char *module, const char *symbol, const char *what);

/* Start-up time in ms at the moment of the call: CPU time the process used
 * before main() (exec, dynamic loading; Linux records the wall-clock start
 * only to 10 ms) plus the wall time since main() was entered. */
double cli_startup_ms(void);
/* Write a PNG straight into `path` (an existing temporary of the caller's,
 * truncated), with no temporary or rename of its own; checks it is whole.
 * Messages name `shown`. */
int cli_image_write_png_file(const char *path, const char *shown, uint32_t w, uint32_t h, int channels, int bits,
                             const void *data);

/* Progress bar on stderr: silent when quiet or stderr is not a TTY, and
 * only drawn once the work has run for more than a second. Use
 * cli_progress_cb as an rs_progress_fn with the cli_progress as user. */
typedef struct cli_progress {
    const char *label;
    int enabled;
    double start;
    int shown;
    int last_permille;
} cli_progress;
void cli_progress_init(cli_progress *p, const char *label, int quiet);
int cli_progress_cb(void *user, uint64_t done, uint64_t total);
void cli_progress_done(cli_progress *p);

/* Monotonic wall clock in milliseconds. */
double cli_now_ms(void);

/* A raster's georeference (cli/gis.h). crs is malloc'd: "EPSG:32632" when
 * GDAL identifies an EPSG code, else the WKT; NULL when the file has none. */
typedef struct cli_geo {
    int georef;   /* 1: the file has a geotransform (or a CRS) */
    double gt[6]; /* GDAL's geotransform: X0, gx, 0, Y0, 0, gy (gy = -gx) */
    char *crs;
} cli_geo;

/* What a GIS road source held (cli_gdal_roads_text; --stats "roads_source"):
 * features read, roads written, features skipped (no highway=* in OSM
 * data, highway values that are not roads, not lines, not reprojectable),
 * crossing nodes (zebras, on roads as points; signals and unmarked ones,
 * not drawn). set: filled. */
typedef struct cli_gdal_road_counts {
    size_t features, roads, no_highway, not_roads, not_lines, not_reprojected;
    size_t zebra_nodes, zebra_points, signal_nodes, unmarked_nodes;
    size_t tunnels; /* highway ways with tunnel=* (but no, building_passage): under the ground, skipped */
    int set;
} cli_gdal_road_counts;

/* Splat options and inputs shared by `roadsplat` and `roadsplat render`
 * (cli/splat_args.c). */
typedef struct cli_splat_args {
    rs_splat_options o;
    rs_dem_frame frame; /* --cell-size, --z-scale, --origin: set on the DEM */
    unsigned threads;   /* --threads; 0 = all cores */
    const char *terrain_tex, *road_tex;
    const char *styles_path;        /* --styles FILE */
    const char *atlas_path, *atlas_index_path; /* --atlas IMG --atlas-index FILE */
    int png_level_given, png_level; /* --png-level (OUT.png), also read here */
    int cell_size_given, origin_given;
    const char *layer, *where; /* --layer NAME, --where SQL: GIS road sources (cli/geo.c) */
    int strict;                /* --strict: no road on the map is an error, not a warning */
    int light_given;           /* --sun or --specular (they need --lighting) */
    double pixel_size;         /* --pixel-size M (0: not given); sets o.texels once the cell size is known */
    const char *color_relief;  /* --color-relief FILE (gdaldem's text format) */
    int auto_pixel;            /* the main command: without --texels/--pixel-size, 1 m pixels on cells over 8 m
                                  (render and tiles keep 8 texels per cell: they hold more per pixel) */
    char pixel_note[240];      /* the pixel size chosen, when worth saying: printed once the run is sure to go on */
    uint64_t max_field_work;   /* --max-field-work N: rs_limits.max_field_work (0 = default) */
    uint64_t max_atlas_bytes;  /* --max-atlas-mb N: rs_limits.max_atlas_bytes (0 = default) */
    uint64_t max_linesym_bytes; /* --max-linesym-mb N: rs_limits.max_linesym_bytes (0 = default) */
} cli_splat_args;
/* Most pixels of one image the CLI writes or renders (the library's default
 * limit); a window of a larger virtual image is fine (docs/gis.md). */
#define CLI_MAX_IMAGE_PIXELS ((uint64_t)1 << 28)
/* The library limits the splat options ask for (defaults elsewhere). */
void cli_splat_limits(const cli_splat_args *s, rs_limits *lim);
/* The context's last message (or the result's text), and when it names a
 * budget (rs_limits field) with an option here, that option: into buf. */
const char *cli_lib_message(const rs_ctx *ctx, rs_result r, char *buf, size_t cap);
/* Splits an argument "--name=value" into name (NUL-terminated, cut to
 * CLI_OPT_NAME - 1 bytes) and the inline value (NULL without '='). */
#define CLI_OPT_NAME 64
const char *cli_option_split(const char *arg, char name[CLI_OPT_NAME]);
/* Value of option `name`: inline ("--x=v", inl) or the next argument. */
int cli_option_value(int argc, char **argv, int *i, const char *name, const char *inl, const char **val);
/* When `name` is a splat option, read and apply its value: 0, or 1 on a bad
 * value (error printed). -1 when `name` is not a splat option. */
int cli_splat_option(int argc, char **argv, int *i, const char *name, const char *inl, cli_splat_args *s);
/* Lit output (docs/surface.md): --lighting, --sun AZ,ALT, --specular K for
 * the main command and tiles (render has its own GL lighting options).
 * Returns as cli_splat_option. */
int cli_lighting_option(int argc, char **argv, int *i, const char *name, const char *inl, cli_splat_args *s);
/* After the options: --sun and --specular without --lighting is an error
 * (printed; 1), else 0. */
int cli_lighting_check(const cli_splat_args *s);
/* The DEM, the parsed roads and the textures named in s; sets s->o's
 * texture pointers into `in`. Errors printed; free with cli_splat_input_free
 * (also after a failed load). */
typedef struct cli_splat_input {
    rs_dem *dem;
    rs_roads *roads;
    rs_image terrain, road;
    uint8_t *terrain_px, *road_px;
    rs_styles *styles; /* style blocks of the road file and of --styles FILE */
    rs_atlas *atlas;   /* --atlas, NULL: the built-in one */
    uint8_t *atlas_px;
    cli_geo geo;       /* the DEM's georeference (geo.georef 0: none) */
    uint8_t *nodata;   /* W x H, 1 where the DEM sample is nodata (NaN); NULL: none */
    rs_surface_image *surf; /* the styles' `surface IMG` images, decoded (docs/surface.md) */
    char **surf_path;       /* each one's file (relative to its style file's folder) */
    uint8_t **surf_px;
    size_t nsurf;
    int world;         /* roads and DEM in a north-up world frame (cli/geo.c) */
    double wx0, wy0;   /* world point of DEM sample (0,0) (x, y north) when world */
    cli_gdal_road_counts source; /* a GIS road source's counts (source.set 0: road text) */
    rs_colour_stop *relief;      /* --color-relief's stops (s->o.surface.ramp points here) */
} cli_splat_input;
int cli_splat_input_load(rs_ctx *ctx, const char *dem_path, const char *roads_path, cli_splat_args *s,
                         cli_splat_input *in);
void cli_splat_input_free(rs_ctx *ctx, cli_splat_input *in);

/* The current ROAM mesh with normals into buffers grown to
 * rs_roam_mesh_bound as needed (cli/mesh.c; render's frame loops). 0, or 1
 * after an error line naming `shown`. Free with cli_mesh_buf_free. */
typedef struct cli_mesh_buf {
    float *vtx, *nrm;   /* 5 and 3 floats a vertex (rs_roam_extract) */
    uint32_t *idx;
    size_t cap_v, cap_i, nv, ni;
} cli_mesh_buf;
int cli_mesh_extract(rs_ctx *ctx, rs_roam *roam, const char *shown, cli_mesh_buf *m);
void cli_mesh_buf_free(cli_mesh_buf *m);

/* The splat of `roadsplat` and `roadsplat render` (cli/splat_run.c).
 * cli_splatter_prepare: the road grid for the loaded input and s->o (with a
 * "roads" progress bar) and the splatter on it; the error is printed naming
 * roads_path. Free the splatter, then the grid (both may be set on failure). */
int cli_splatter_prepare(rs_ctx *ctx, const cli_splat_input *in, const char *roads_path, cli_splat_args *s, int quiet,
                         rs_road_grid **grid, rs_splatter **out);
/* A threaded splat of a window: cli_splat_job_init sets the splatter, the
 * whole image as the window, the texels and the thread count from s
 * (--threads, else all cores); the caller sets the output buffers (w*h,
 * tightly packed; weight may be NULL) and may narrow the window.
 * cli_splat_run draws a "splat" progress bar unless quiet; profile and
 * threads_used come back summed over the threads. It prints the error and
 * returns 1 on failure. */
typedef struct cli_splat_job {
    const rs_splatter *s;
    uint32_t x0, y0, w, h, texels;
    unsigned threads, threads_used;
    int quiet;
    uint8_t *rgba;
    uint16_t *weight;
    rs_splat_profile profile;
    const uint8_t *nodata; /* the input's nodata mask (alpha 0 there), or NULL */
    uint32_t dem_w, dem_h;
    int alpha;             /* cli_splat_png_run: keep the alpha channel although every pixel is opaque */
    const rs_splat_layers *layers; /* cli_splat_run: these planes of the window instead of rgba */
} cli_splat_job;
void cli_splat_job_init(cli_splat_job *job, const rs_splatter *sp, const cli_splat_args *s, int quiet);
int cli_splat_run(cli_splat_job *job);

/* --normal-out (cli/normals.c): 0 when path ends in .png, else 1 after a
 * message; the normal map of the window [x0, x0+w) x [y0, y0+h) on
 * `threads` threads, encoded as an RGB8 PNG into f (flushed, not closed;
 * png_level -1: the default). 0, or 1 after a message naming path. */
int cli_normal_png_check(const char *path);
int cli_normal_png(const rs_splatter *s, const rs_normal_options *o, uint32_t x0, uint32_t y0, uint32_t w,
                   uint32_t h, unsigned threads, int png_level, FILE *f, const char *path);
/* The same window's normal map into rgb (w*h*3 bytes), by bands of `band`
 * rows on up to `threads` threads, each with its own context (the same bytes
 * for any count and band). 0, or 1 with the library's message in msg. Also
 * used by tiles (cli/tiles.c). */
int cli_normal_rgb(const rs_splatter *s, const rs_normal_options *o, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h,
                   unsigned threads, uint32_t band, uint8_t *rgb, char *msg, size_t msg_size);

/* Subcommands, each `int f(int argc, char **argv)` with argv[0] the
 * subcommand name; return the process exit code (0 ok, 1 error). */
int cli_mesh_main(int argc, char **argv);   /* cli/mesh.c   (roadsplat mesh)   */
int cli_render_main(int argc, char **argv); /* cli/render.c (roadsplat render) */

#ifdef __cplusplus
}
#endif
#endif
