/* ASAM OpenDRIVE (.xodr) as a road source (issue 32, docs/opendrive.md).
 *
 * The XML reader lives in the module roadsplat-odr.so (cli/odr.c, linked
 * with expat): it fills the library's plain OpenDRIVE document
 * (lib/input/odr_lanes.h) and has the library turn it into road text. The
 * executable calls it through cli/odr_run.c, so a run on road text never
 * loads expat. */
#ifndef RS_CLI_ODR_H
#define RS_CLI_ODR_H
#include <stddef.h>

/* The road text of the OpenDRIVE document data[0..n) (malloc'd, NUL
 * terminated): 0, or 1 with one line in err ("FILE line N: ...", FILE =
 * `shown`). No global state; the fuzz target calls it directly. */
int cli_odr_text(const char *data, size_t n, const char *shown, size_t max_points, char **text, size_t *size,
                 char *err, size_t nerr);
typedef int (*cli_odr_text_fn)(const char *, size_t, const char *, size_t, char **, size_t *, char *, size_t);

/* ---- cli/odr_run.c (the executable) ----------------------------------------- */

/* 1 when ROADS is an OpenDRIVE file (extension .xodr, any case). */
int cli_roads_are_odr(const char *path);
/* The road text of an OpenDRIVE file: 0, or 1 after a message (also when
 * the module is missing: the one line names libexpat1 / libexpat1-dev). */
int cli_odr_roads_text(const char *path, char **text, size_t *size);
/* 1 when `roadsplat convert`'s first file is an OpenDRIVE file. */
int cli_odr_convert_wants(int argc, char **argv);
/* `roadsplat convert X.xodr OUT.txt`. */
int cli_odr_convert_main(int argc, char **argv);
#endif
