/* MBTiles 1.3 output of `roadsplat tiles --format mbtiles`: the module
 * roadsplat-mbtiles.so, so that the executable itself needs no SQLite
 * (docs/packaging.md). One transaction for the whole pyramid. */
#include "cli.h"
#include "tiles.h"

#include <sqlite3.h>
#include <stdlib.h>
#include <string.h>

typedef struct mbt {
    sqlite3 *db;
    sqlite3_stmt *put[2], *meta;
    char *shown;
} mbt;

static int fail(mbt *m, const char *what)
{
    cli_error("%s: SQLite: %s: %s", m->shown, what, sqlite3_errmsg(m->db));
    return 1;
}

static int exec(mbt *m, const char *sql) { return sqlite3_exec(m->db, sql, NULL, NULL, NULL) != SQLITE_OK ? fail(m, sql) : 0; }

static int mbt_close(void *h, int commit)
{
    mbt *m = h;
    if (!m) return 1;
    int bad = 0;
    sqlite3_finalize(m->put[0]);
    sqlite3_finalize(m->put[1]);
    sqlite3_finalize(m->meta);
    if (commit) bad = exec(m, "COMMIT");
    else sqlite3_exec(m->db, "ROLLBACK", NULL, NULL, NULL);
    if (sqlite3_close(m->db) != SQLITE_OK && !bad) bad = fail(m, "close");
    free(m->shown);
    free(m);
    return bad;
}

static void *mbt_open(const char *path, const char *shown, int normals)
{
    mbt *m = calloc(1, sizeof *m);
    if (!m || !(m->shown = malloc(strlen(shown) + 1))) {
        free(m);
        cli_error("%s: out of memory", shown);
        return NULL;
    }
    strcpy(m->shown, shown);
    if (sqlite3_open_v2(path, &m->db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, NULL) != SQLITE_OK) {
        fail(m, "open");
        sqlite3_close(m->db);
        free(m->shown);
        free(m);
        return NULL;
    }
    if (exec(m, "PRAGMA journal_mode=OFF") || exec(m, "PRAGMA synchronous=OFF") || exec(m, "BEGIN") ||
        exec(m, "CREATE TABLE metadata (name TEXT, value TEXT)") ||
        exec(m, "CREATE TABLE tiles (zoom_level INTEGER, tile_column INTEGER, tile_row INTEGER, tile_data BLOB)") ||
        exec(m, "CREATE UNIQUE INDEX tile_index ON tiles (zoom_level, tile_column, tile_row)") ||
        exec(m, "CREATE UNIQUE INDEX name ON metadata (name)") ||
        (sqlite3_prepare_v2(m->db, "INSERT INTO tiles VALUES (?, ?, ?, ?)", -1, &m->put[0], NULL) != SQLITE_OK &&
         fail(m, "prepare")) ||
        (normals &&
         (exec(m, "CREATE TABLE normal_tiles (zoom_level INTEGER, tile_column INTEGER, tile_row INTEGER, tile_data BLOB)") ||
          exec(m, "CREATE UNIQUE INDEX normal_tile_index ON normal_tiles (zoom_level, tile_column, tile_row)") ||
          (sqlite3_prepare_v2(m->db, "INSERT INTO normal_tiles VALUES (?, ?, ?, ?)", -1, &m->put[1], NULL) != SQLITE_OK &&
           fail(m, "prepare")))) ||
        (sqlite3_prepare_v2(m->db, "INSERT OR REPLACE INTO metadata VALUES (?, ?)", -1, &m->meta, NULL) != SQLITE_OK &&
         fail(m, "prepare"))) {
        mbt_close(m, 0);
        return NULL;
    }
    return m;
}

static int mbt_meta(void *h, const char *name, const char *value)
{
    mbt *m = h;
    sqlite3_reset(m->meta);
    sqlite3_bind_text(m->meta, 1, name, -1, SQLITE_STATIC);
    sqlite3_bind_text(m->meta, 2, value, -1, SQLITE_STATIC);
    return sqlite3_step(m->meta) != SQLITE_DONE ? fail(m, "metadata") : 0;
}

static int mbt_put(void *h, int layer, uint32_t z, uint32_t x, uint32_t row, const void *png, size_t size)
{
    mbt *m = h;
    sqlite3_stmt *st = m->put[layer ? 1 : 0];
    if (!st) {
        cli_error("%s: no normal_tiles table", m->shown);
        return 1;
    }
    sqlite3_reset(st);
    sqlite3_bind_int64(st, 1, z);
    sqlite3_bind_int64(st, 2, x);
    sqlite3_bind_int64(st, 3, row);
    sqlite3_bind_blob64(st, 4, png, size, SQLITE_STATIC);
    return sqlite3_step(st) != SQLITE_DONE ? fail(m, "tile") : 0;
}

#if defined(__GNUC__)
__attribute__((visibility("default")))
#endif
extern const cli_mbtiles_api cli_mbtiles_api_v2;
const cli_mbtiles_api cli_mbtiles_api_v2 = { mbt_open, mbt_meta, mbt_put, mbt_close };
