/* `roadsplat tiles` (cli/tiles.c) and its MBTiles writer, the optional
 * module roadsplat-mbtiles.so (cli/mbtiles.c, SQLite; docs/tiles.md). */
#ifndef RS_CLI_TILES_H
#define RS_CLI_TILES_H
#include <stddef.h>
#include <stdint.h>

/* The module's one symbol, "cli_mbtiles_api_v2". Every function prints one
 * line naming `shown` on failure and returns 1 (NULL from open). */
typedef struct cli_mbtiles_api {
    /* a new MBTiles 1.3 database at `path` (an empty temporary file); with
     * normals, a second table normal_tiles of the same columns and index */
    void *(*open)(const char *path, const char *shown, int normals);
    int (*meta)(void *db, const char *name, const char *value);
    /* tile_row in TMS order (row 0 at the bottom), as MBTiles 1.3 says;
     * layer 0 into tiles, 1 into normal_tiles */
    int (*put)(void *db, int layer, uint32_t z, uint32_t x, uint32_t tms_row, const void *png, size_t size);
    /* commit (or, commit 0, roll back) and close */
    int (*close)(void *db, int commit);
} cli_mbtiles_api;

int cli_tiles_main(int argc, char **argv);

#endif
