/* SHA-256 (FIPS 180-4) by Nettle (nettle-dev), which uses the CPU's SHA
 * instructions where it has them (5-6x our own portable code here): the
 * tile pyramid's manifest hashes every tile and input with it
 * (docs/tiles.md). */
#ifndef RS_CLI_SHA256_H
#define RS_CLI_SHA256_H
#include <stddef.h>
#include <stdint.h>
#include <nettle/sha2.h>

typedef struct cli_sha256 {
    struct sha256_ctx n;
} cli_sha256_ctx;

void cli_sha256_init(cli_sha256_ctx *s);
void cli_sha256_update(cli_sha256_ctx *s, const void *data, size_t n);
void cli_sha256_final(cli_sha256_ctx *s, uint8_t out[32]);
/* One call; hex: 64 lower-case digits and a NUL. */
void cli_sha256(const void *data, size_t n, uint8_t out[32]);
void cli_sha256_hex(const uint8_t d[32], char hex[65]);
/* The SHA-256 of all of an open file, from offset 0 (pread: its position
 * is untouched): 0, or 1 with errno set. */
int cli_sha256_fd(int fd, uint8_t out[32]);

#endif
