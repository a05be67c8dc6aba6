/* OpenDRIVE in the executable (issue 32, docs/opendrive.md): `.xodr` road
 * sources and `roadsplat convert X.xodr OUT.txt`. The reader itself is in
 * the module roadsplat-odr.so (cli/odr.c, expat), loaded on first use. */
#include "cli.h"
#include "odr.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

int cli_roads_are_odr(const char *path)
{
    const char *slash = strrchr(path, '/'), *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    if (!dot || dot == base || strlen(dot) != 5) return 0;
    static const char x[] = ".xodr";
    for (int i = 0; i < 5; i++) {
        char c = dot[i];
        if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
        if (c != x[i]) return 0;
    }
    return 1;
}

int cli_odr_roads_text(const char *path, char **text, size_t *size)
{
    *text = NULL;
    *size = 0;
#ifndef RS_WITH_EXPAT
    cli_error("%s: reading OpenDRIVE needs expat, and this roadsplat was built without it: install libexpat1-dev "
              "(make deps) and rebuild", path);
    return 1;
#else
    void *sym = cli_module_symbol("odr", "cli_odr_text", path);
    if (!sym) return 1;
    cli_odr_text_fn f;
    memcpy(&f, &sym, sizeof f); /* object to function pointer, as POSIX dlsym allows */
    char *data = NULL, err[800];
    size_t n = 0;
    /* 2 GiB: the largest networks published are a few hundred MB */
    if (cli_read_input(path, "ROADS", (size_t)1 << 31, &data, &n)) return 1;
    int r = f(data, n, path, 0, text, size, err, sizeof err);
    free(data);
    if (r) cli_error("%s", err);
    return r;
#endif
}

static const char convert_usage[] =
    "usage: roadsplat convert ROADS.xodr ROADS_OUT.txt\n"
    "  Writes the road text an OpenDRIVE file draws as (docs/opendrive.md):\n"
    "  surfaces of the lanes, every road mark line and dash, crosswalks and\n"
    "  stop lines, in the world frame of the file (frame world [geoReference]).\n";

int cli_odr_convert_wants(int argc, char **argv)
{
    for (int i = 1; i < argc; i++)
        if (argv[i][0] != '-') return cli_roads_are_odr(argv[i]);
    return 0;
}

int cli_odr_convert_main(int argc, char **argv)
{
    const char *pos[2];
    int npos = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
            fputs(convert_usage, stdout);
            return 0;
        }
        if (argv[i][0] == '-' || npos == 2) {
            cli_error("convert: unexpected argument '%s' for an OpenDRIVE input (see roadsplat convert --help)",
                      argv[i]);
            return 1;
        }
        pos[npos++] = argv[i];
    }
    if (npos != 2) {
        cli_error("convert: expected ROADS.xodr ROADS_OUT.txt, got %d argument%s", npos, npos == 1 ? "" : "s");
        return 1;
    }
    const cli_file_role outs[1] = { { pos[1], "ROADS_OUT" } };
    const cli_file_role ins[1] = { { pos[0], "ROADS_IN" } };
    if (cli_check_outputs(outs, 1, ins, 1)) return 1;
    char *text = NULL;
    size_t size = 0;
    if (cli_odr_roads_text(pos[0], &text, &size)) return 1;
    int rc = 1;
    /* what is written reads back, styles and all */
    rs_ctx *ctx = NULL;
    rs_roads *roads = NULL;
    rs_styles *styles = NULL;
    if (rs_ctx_create(NULL, NULL, &ctx) == RS_OK && rs_styles_create(ctx, &styles) == RS_OK) {
        rs_road_parse_options po;
        memset(&po, 0, sizeof po);
        po.styles = styles;
        rs_result r = rs_roads_parse_ex(ctx, text, size, &po, &roads);
        if (r) cli_error("%s: the converted roads do not parse: %s", pos[0], rs_ctx_message(ctx));
        rs_roads_free(ctx, roads);
        rs_styles_free(ctx, styles);
        rs_ctx_free(ctx);
        if (r) goto done;
    } else {
        rs_ctx_free(ctx);
    }
    if (cli_out_write_file(pos[1], text, size)) goto done;
    rc = 0;
done:
    free(text);
    return rc;
}
