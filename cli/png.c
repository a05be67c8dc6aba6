/* PNG writer of the CLI: the container (signature, IHDR, IDAT, IEND) is
 * written here, the deflate stream by libdeflate, in bands that can be
 * compressed in parallel (cli/png.h; docs/packaging.md has the
 * measurements behind the choices).
 *
 * - Filter: UP on every row but the first of each band, which takes SUB (a
 *   band is filtered without its neighbours). On the splat textures UP
 *   compresses best of the five PNG filters at every level, and costs one
 *   subtraction per byte; libpng's adaptive choice (Paeth there) and a
 *   per-row minimum-sum choice among None/SUB/UP were both larger.
 * - Bands: rows of about BAND_BYTES, a count fixed by the row size, so the
 *   bytes never depend on the thread count. Each band is cut into pieces
 *   (PIECE_FAST bytes at levels 0 and 1, the whole band above) that
 *   libdeflate compresses independently into raw deflate streams. PNG
 *   allows one zlib stream, so every piece but the very last is turned
 *   into non-final blocks that end on a byte boundary (make_joinable), as
 *   pigz does with zlib's Z_SYNC_FLUSH; libdeflate has no flush, so the
 *   final block's BFINAL bit is cleared and the stream is ended byte-
 *   aligned by an empty stored block where needed. The Adler-32 is
 *   combined from the bands' (zlib's adler32_combine).
 * - Memory: nothing image-sized; a coder holds one band's filtered bytes
 *   and their compressed form.
 *
 * Every failure prints one line "roadsplat: SHOWN: problem" and returns 1. */
#define _GNU_SOURCE 1 /* sync_file_range */
#include "png.h"

#include <errno.h>
#include <fcntl.h>
#include <libdeflate.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <zlib.h>
#ifdef RS_WITH_ISAL
#include <isa-l/igzip_lib.h>
#endif
#ifdef __SSE2__
#include <emmintrin.h>
#endif

/* Unfiltered bytes per band (rows rounded up to a multiple of 8, so whole
 * DEM-cell rows at 1, 2, 4 and 8 texels): big enough that the per-band
 * costs (a SUB row, an IDAT chunk, the splat's re-scan of a cell row) stay
 * small, small enough to stay in cache and to share out among threads. */
#define BAND_BYTES ((size_t)512 << 10)
/* Piece size at levels 0 and 1: libdeflate 1.14's level 1 ends a block only
 * after 65535 bytes or 8192 matches, so a piece this size is almost always
 * one block, which make_joinable handles without decoding. */
#define PIECE_FAST ((size_t)32 << 10)
/* Pieces and ISA-L streams stay far below the 32-bit counts of zlib's and
 * ISA-L's streams (a band is one row when rows are long). */
#define PIECE_MAX ((size_t)64 << 20)
/* Largest IDAT payload written; the progress bar advances per band. */
#define IDAT_CHUNK ((size_t)1 << 20)
/* The writer asks the kernel to start writing the file out every this many
 * bytes, so that the fsync before the rename has little left to wait for
 * (17 MB: 20 ms down to 10 on the benchmark machine). */
#define WRITEBACK_BYTES ((uint64_t)4 << 20)

static void put_be32(uint8_t *p, uint32_t v)
{
    p[0] = (uint8_t)(v >> 24);
    p[1] = (uint8_t)(v >> 16);
    p[2] = (uint8_t)(v >> 8);
    p[3] = (uint8_t)v;
}

static uint32_t get_be32(const uint8_t *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

/* ---- layout ---------------------------------------------------------------- */

int cli_png_layout_init(cli_png_layout *l, const char *shown, uint32_t w, uint32_t h, int channels, int bits,
                        int level)
{
    memset(l, 0, sizeof *l);
    if (level < 0) level = CLI_PNG_LEVEL_DEFAULT;
    if (channels < 1 || channels > 4 || (bits != 8 && bits != 16) || !w || !h || w > 0x7fffffffu ||
        h > 0x7fffffffu || level > CLI_PNG_LEVEL_MAX) {
        cli_error("%s: cannot write a %ux%u PNG with %d channels of %d bits at level %d", shown, w, h, channels, bits,
                  level);
        return 1;
    }
    const size_t bpp = (size_t)channels * (size_t)(bits / 8);
    /* a band's buffers (rows, filtered, compressed bound) must fit size_t */
    if ((size_t)w > (SIZE_MAX / 8 - 4096) / bpp) {
        cli_error("%s: image too large for this machine (%ux%u)", shown, w, h);
        return 1;
    }
    l->width = w;
    l->height = h;
    l->channels = channels;
    l->bits = bits;
    l->level = level;
    l->row_bytes = (size_t)w * bpp;
    size_t rows = (BAND_BYTES + l->row_bytes - 1) / l->row_bytes;
    if (rows > 8) rows = (rows + 7) / 8 * 8;
    l->band_rows = rows < h ? (uint32_t)rows : h;
    l->nbands = (uint32_t)(((uint64_t)h + l->band_rows - 1) / l->band_rows);
#ifdef RS_WITH_ISAL
    l->isal = level == 1 && (l->row_bytes + 1) * l->band_rows <= PIECE_MAX;
#endif
    return 0;
}

/* ---- filtering ------------------------------------------------------------- */

/* o[i] = a[i] - b[i] (a and b may overlap o only as SUB does: b behind a) */
static void sub_bytes(uint8_t *o, const uint8_t *a, const uint8_t *b, size_t n)
{
    size_t i = 0;
#ifdef __SSE2__
    for (; i + 16 <= n; i += 16)
        _mm_storeu_si128((__m128i *)(void *)(o + i), _mm_sub_epi8(_mm_loadu_si128((const __m128i *)(const void *)(a + i)),
                                                                  _mm_loadu_si128((const __m128i *)(const void *)(b + i))));
#endif
    for (; i < n; i++) o[i] = (uint8_t)(a[i] - b[i]);
}

/* ---- joining deflate streams ----------------------------------------------- */

typedef struct bitreader {
    const uint8_t *p;
    size_t n, pos; /* in bits */
} bitreader;

static int get_bits(bitreader *b, unsigned n, unsigned *v)
{
    if (b->n - b->pos < n) return 1;
    unsigned x = 0;
    for (unsigned i = 0; i < n; i++, b->pos++) x |= (unsigned)(b->p[b->pos >> 3] >> (b->pos & 7) & 1) << i;
    *v = x;
    return 0;
}

static int bit_at(const uint8_t *p, size_t pos) { return p[pos >> 3] >> (pos & 7) & 1; }

/* One symbol of the canonical Huffman code with count[len] codes of each
 * length and `sorted` the symbols ordered by (length, value). */
static int decode_symbol(bitreader *b, const uint16_t *count, const uint16_t *sorted, unsigned *sym)
{
    unsigned code = 0, first = 0, index = 0;
    for (unsigned len = 1; len <= 15; len++) {
        unsigned bit;
        if (get_bits(b, 1, &bit)) return 1;
        code |= bit;
        if (code - first < count[len]) { /* unsigned: false when code < first */
            *sym = sorted[index + code - first];
            return 0;
        }
        index += count[len];
        first = (first + count[len]) << 1;
        code <<= 1;
    }
    return 1;
}

/* For a stream of ONE dynamic-Huffman block (its BFINAL bit, bit 0, set):
 * the number of zero padding bits after its end-of-block code, found by
 * reading the block header for that code and matching it against the end
 * of the stream. -1 when the header does not parse or when more than one
 * padding fits (then the caller decodes the stream instead). */
static int single_block_padding(const uint8_t *p, size_t n)
{
    static const uint8_t order[19] = { 16, 17, 18, 0, 8, 7, 9, 6, 10, 5, 11, 4, 12, 3, 13, 2, 14, 1, 15 };
    bitreader b = { p, n * 8, 3 };
    unsigned hlit, hdist, hclen, v;
    if (get_bits(&b, 5, &hlit) || get_bits(&b, 5, &hdist) || get_bits(&b, 4, &hclen)) return -1;
    hlit += 257;
    hdist += 1;
    hclen += 4;
    uint8_t cl[19] = { 0 };
    for (unsigned i = 0; i < hclen; i++) {
        if (get_bits(&b, 3, &v)) return -1;
        cl[order[i]] = (uint8_t)v;
    }
    uint16_t count[16] = { 0 }, sorted[19];
    for (unsigned s = 0; s < 19; s++) count[cl[s]]++;
    count[0] = 0;
    unsigned k = 0;
    for (unsigned len = 1; len <= 7; len++)
        for (unsigned s = 0; s < 19; s++)
            if (cl[s] == len) sorted[k++] = (uint16_t)s;
    uint8_t lens[288 + 32];
    for (unsigned i = 0; i < hlit + hdist;) { /* litlen then distance code lengths */
        unsigned sym, rep, val = 0;
        if (decode_symbol(&b, count, sorted, &sym)) return -1;
        if (sym < 16) { lens[i++] = (uint8_t)sym; continue; }
        if (sym == 16) {
            if (!i || get_bits(&b, 2, &rep)) return -1;
            val = lens[i - 1];
            rep += 3;
        } else if (sym == 17) {
            if (get_bits(&b, 3, &rep)) return -1;
            rep += 3;
        } else {
            if (get_bits(&b, 7, &rep)) return -1;
            rep += 11;
        }
        if (rep > hlit + hdist - i) return -1;
        while (rep--) lens[i++] = (uint8_t)val;
    }
    /* the canonical code of symbol 256 (end of block), RFC 1951 3.2.2 */
    const unsigned eob_len = lens[256];
    if (!eob_len) return -1;
    unsigned lit_count[16] = { 0 }, code = 0;
    for (unsigned s = 0; s < hlit; s++) lit_count[lens[s]]++;
    lit_count[0] = 0;
    for (unsigned len = 1; len <= eob_len; len++) code = (code + lit_count[len - 1]) << 1;
    for (unsigned s = 0; s < 256; s++) code += lens[s] == eob_len;
    /* Huffman codes go most significant bit first; padding bits are zero */
    int found = -1;
    for (unsigned pad = 0; pad < 8; pad++) {
        size_t end = n * 8 - pad;
        if (end < b.pos + eob_len) break;
        if (pad && p[n - 1] >> (8 - pad)) continue;
        unsigned i = 0;
        while (i < eob_len && (unsigned)bit_at(p, end - eob_len + i) == (code >> (eob_len - 1 - i) & 1)) i++;
        if (i < eob_len) continue;
        if (found >= 0) return -1; /* ambiguous */
        found = (int)pad;
    }
    return found;
}

/* For any raw deflate stream: the bit position of its final block's header
 * and the number of bits up to the end of that block, by decoding it with
 * zlib's inflate, which stops at every block boundary under Z_BLOCK and
 * reports the unused bits of the last byte (as zlib's examples/gzjoin.c). */
static int walk_blocks(z_stream *z, uint8_t *scratch, size_t cap, const uint8_t *p, size_t n, size_t *final_hdr,
                       size_t *end)
{
    if (inflateReset(z) != Z_OK) return 1;
    z->next_in = (Bytef *)(uintptr_t)p; /* zlib's API is not const; inflate only reads it */
    z->avail_in = (uInt)n;
    size_t hdr = 0;
    for (int stuck = 0; stuck < 2;) {
        uInt in_before = z->avail_in;
        z->next_out = scratch;
        z->avail_out = (uInt)cap;
        int r = inflate(z, Z_BLOCK);
        if (r != Z_OK && r != Z_BUF_ERROR && r != Z_STREAM_END) return 1;
        if (z->data_type & 128) { /* just after an end-of-block code: < 8 unused bits */
            size_t pos = 8 * (n - z->avail_in) - (size_t)(z->data_type & 7);
            if (z->data_type & 64) { /* that block was the final one */
                *final_hdr = hdr;
                *end = pos;
                return 0;
            }
            hdr = pos;
        } else if (r == Z_STREAM_END) {
            return 1;
        }
        stuck = z->avail_in == in_before && z->avail_out == cap ? stuck + 1 : 0;
    }
    return 1; /* no progress */
}

struct cli_png_coder {
    cli_png_layout l;
    struct libdeflate_compressor *c;
    z_stream z;
    int z_ready;
    size_t piece;        /* bytes per piece */
    uint8_t *filt;       /* one piece, filtered */
    uint8_t *out;        /* the band's compressed form */
    size_t out_cap;
    uint8_t *rows16[2];  /* 16-bit: big-endian copies of rows of either parity */
    uint32_t row16_of[2]; /* which rows they hold */
    uint8_t *walk;       /* inflate's output in walk_blocks */
    uint64_t joins[4];   /* pieces joined as stored, by end-of-block code, by inflate; ISA-L bands */
#ifdef RS_WITH_ISAL
    struct isal_zstream *isal; /* ISA-L's stream: its state, window and hash table */
#endif
};

#define WALK_SCRATCH ((size_t)64 << 10)

/* Turn the raw deflate stream at p (n bytes, room for 5 more) into
 * non-final blocks that end on a byte boundary; returns its new size, 0 on
 * failure. */
static size_t make_joinable(cli_png_coder *c, uint8_t *p, size_t n)
{
    size_t hdr = 0, end = 0;
    unsigned btype = n ? (p[0] >> 1 & 3) : 3;
    int pad = -1;
    if (n >= 5 && (p[0] & 1) && btype == 0 && (size_t)p[1] + ((size_t)p[2] << 8) + 5 == n) {
        pad = 0; /* one stored block: it already ends on a byte boundary */
    } else if (n && (p[0] & 1) && btype == 2) {
        pad = single_block_padding(p, n);
    }
    if (pad >= 0) {
        hdr = 0;
        end = n * 8 - (size_t)pad;
        c->joins[btype == 0 ? 0 : 1]++;
    } else { /* several blocks, a fixed-code block, or an ambiguous end */
        if (!c->z_ready) {
            memset(&c->z, 0, sizeof c->z);
            if (inflateInit2(&c->z, -15) != Z_OK) return 0;
            c->z_ready = 1;
        }
        if (walk_blocks(&c->z, c->walk, WALK_SCRATCH, p, n, &hdr, &end) || end > n * 8 || n * 8 - end > 7 ||
            !bit_at(p, hdr))
            return 0;
        pad = (int)(n * 8 - end);
        c->joins[2]++;
    }
    p[hdr >> 3] &= (uint8_t) ~(1u << (hdr & 7)); /* BFINAL = 0 */
    if (pad == 0) return n; /* the next block starts on the next byte */
    /* An empty stored block: its 3 header bits are zero, after them the
     * stream skips to a byte boundary, then LEN = 0, NLEN = 0xFFFF. The
     * header fits in the padding (zero bits already) when there are >= 3. */
    if (pad < 3) p[n++] = 0;
    p[n++] = 0;
    p[n++] = 0;
    p[n++] = 0xFF;
    p[n++] = 0xFF;
    return n;
}

static size_t pieces_of(size_t filtered, size_t piece) { return (filtered + piece - 1) / piece; }

/* Row r of the band as PNG bytes: 8-bit rows as they are, 16-bit samples
 * big-endian (converted once into the buffer of r's parity). */
static const uint8_t *band_row(cli_png_coder *c, const uint8_t *rows, size_t stride, uint32_t r)
{
    const uint8_t *src = rows + (size_t)r * stride;
    if (c->l.bits == 8) return src;
    uint8_t *t = c->rows16[r & 1];
    if (c->row16_of[r & 1] != r) {
        for (size_t i = 0; i < c->l.row_bytes / 2; i++) {
            uint16_t v;
            memcpy(&v, src + 2 * i, 2);
            t[2 * i] = (uint8_t)(v >> 8);
            t[2 * i + 1] = (uint8_t)(v & 0xFF);
        }
        c->row16_of[r & 1] = r;
    }
    return t;
}

/* Bytes [off, off + m) of the band's filtered rows (each row: its filter
 * type, then the filtered bytes) into dst, so that each piece is filtered
 * just before it is compressed, while both are in cache. The first row of
 * a band has no row above: SUB; the others UP; level 0 stores rows as they
 * are (filtering would not pay). */
static void filter_range(cli_png_coder *c, const uint8_t *rows, size_t stride, size_t off, size_t m, uint8_t *dst)
{
    const size_t rb = c->l.row_bytes, bpp = (size_t)c->l.channels * (size_t)(c->l.bits / 8);
    uint32_t r = (uint32_t)(off / (rb + 1));
    size_t col = off % (rb + 1);
    while (m) {
        const uint8_t *cur = band_row(c, rows, stride, r);
        const int type = c->l.level == 0 ? 0 : r == 0 ? 1 : 2;
        if (col == 0) {
            *dst++ = (uint8_t)type;
            if (!--m) break;
            col = 1;
        }
        const size_t a = col - 1, n = rb - a < m ? rb - a : m; /* bytes [a, a + n) of the row */
        if (type == 0) {
            memcpy(dst, cur + a, n);
        } else if (type == 2) {
            sub_bytes(dst, cur + a, band_row(c, rows, stride, r - 1) + a, n);
        } else {
            size_t i = a;
            for (; i < a + n && i < bpp; i++) dst[i - a] = cur[i];
            if (i < a + n) sub_bytes(dst + (i - a), cur + i, cur + i - bpp, a + n - i);
        }
        dst += n;
        m -= n;
        r++;
        col = 0;
    }
}

cli_png_coder *cli_png_coder_new(const cli_png_layout *l)
{
    cli_png_coder *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    c->l = *l;
    const size_t filtered = (l->row_bytes + 1) * l->band_rows;
    c->piece = (l->level <= 1 || l->isal) && PIECE_FAST < filtered ? PIECE_FAST : filtered;
    if (c->piece > PIECE_MAX) c->piece = PIECE_MAX;
#ifdef RS_WITH_ISAL
    if (l->isal && !(c->isal = malloc(sizeof *c->isal))) {
        cli_png_coder_free(c);
        return NULL;
    }
#else
    c->l.isal = 0;
#endif
    c->filt = malloc(c->piece);
    if (l->bits == 16) {
        c->rows16[0] = malloc(l->row_bytes);
        c->rows16[1] = malloc(l->row_bytes);
    }
    int ok = c->filt && (l->bits == 8 || (c->rows16[0] && c->rows16[1]));
    if (c->l.isal) {
        /* ISA-L's level-0 stream over the whole band: its fixed code has
         * literals of up to 15 bits and matches of up to 48 bits for 3
         * bytes, so at most 2 bytes a byte (noise: about 1.23), and block
         * headers; the zlib header */
        c->out_cap = 2 * filtered + 65536;
    } else if ((c->c = libdeflate_alloc_compressor(l->level)) && (c->walk = malloc(WALK_SCRATCH))) {
        /* every piece of a band at its bound, its ending, the zlib header */
        size_t np = pieces_of(filtered, c->piece), each = (filtered + np - 1) / np;
        c->out_cap = np * (libdeflate_deflate_compress_bound(c->c, each) + 5) + 2;
    } else {
        ok = 0;
    }
    if (!ok || !(c->out = malloc(c->out_cap))) {
        cli_png_coder_free(c);
        return NULL;
    }
    return c;
}

void cli_png_coder_joins(const cli_png_coder *c, uint64_t joins[4])
{
    for (int i = 0; i < 4; i++) joins[i] = c->joins[i];
}

void cli_png_coder_free(cli_png_coder *c)
{
    if (!c) return;
    if (c->c) libdeflate_free_compressor(c->c);
    if (c->z_ready) inflateEnd(&c->z);
    free(c->filt);
    free(c->out);
    free(c->walk);
    free(c->rows16[0]);
    free(c->rows16[1]);
#ifdef RS_WITH_ISAL
    free(c->isal);
#endif
    free(c);
}

int cli_png_coder_band(cli_png_coder *c, uint32_t band, const void *rows_in, size_t stride, cli_png_piece *out)
{
    const cli_png_layout *l = &c->l;
    const uint8_t *rows = rows_in;
    const uint32_t y0 = band * l->band_rows, nrows = l->height - y0 < l->band_rows ? l->height - y0 : l->band_rows;
    const size_t filtered = (l->row_bytes + 1) * nrows;
    const int last_band = band + 1 == l->nbands;
    c->row16_of[0] = c->row16_of[1] = UINT32_MAX;
    size_t n = 0;
    if (band == 0) { /* zlib header: deflate, 32 KiB window, FLEVEL as libdeflate sets it */
        static const uint8_t flg[4] = { 0x01, 0x5E, 0x9C, 0xDA };
        c->out[n++] = 0x78;
        c->out[n++] = flg[l->level < 2 ? 0 : l->level < 6 ? 1 : l->level == 6 ? 2 : 3];
    }
    /* pieces of (nearly) equal size: no tiny last piece */
    const size_t np = pieces_of(filtered, c->piece), each = (filtered + np - 1) / np;
    uint32_t adler = 1;
#ifdef RS_WITH_ISAL
    if (l->isal) { /* one ISA-L stream over the band's pieces, ended by a full flush */
        /* ISA-L's level 0: its level 1 chose between equal matches
         * differently in about one process in a thousand on the same
         * bytes (docs/packaging.md "Deterministic bytes"); level 0 never
         * did. The state is zeroed first so that nothing of an earlier
         * band can reach this one. */
        struct isal_zstream *zs = c->isal;
        memset(zs, 0, sizeof *zs);
        isal_deflate_init(zs);
        zs->level = 0;
        zs->gzip_flag = IGZIP_DEFLATE;
        zs->next_out = c->out + n;
        zs->avail_out = (uint32_t)(c->out_cap - n);
        for (size_t off = 0; off < filtered; off += each) {
            size_t m = filtered - off < each ? filtered - off : each;
            const int last = off + m == filtered;
            filter_range(c, rows, stride, off, m, c->filt);
            adler = libdeflate_adler32(adler, c->filt, m);
            zs->next_in = c->filt;
            zs->avail_in = (uint32_t)m;
            zs->flush = last ? FULL_FLUSH : NO_FLUSH;
            zs->end_of_stream = (uint16_t)(last && last_band);
            if (isal_deflate(zs) != COMP_OK || zs->avail_in || !zs->avail_out) return 1;
        }
        /* every byte out: at a new block (full flush) or at the stream's end */
        if (zs->internal_state.state != (last_band ? ZSTATE_END : ZSTATE_NEW_HDR)) return 1;
        const size_t stored = filtered + 5 * ((filtered + 65534) / 65535);
        if (zs->total_out <= stored) {
            n += zs->total_out;
        } else { /* a band that does not compress (noise): stored blocks, smaller than the fixed code's */
            for (size_t off = 0; off < filtered;) {
                size_t m = filtered - off < 65535 ? filtered - off : 65535;
                uint8_t *h = c->out + n;
                h[0] = (uint8_t)(last_band && off + m == filtered); /* BFINAL, BTYPE 00; the band starts on a byte */
                h[1] = (uint8_t)(m & 0xFF), h[2] = (uint8_t)(m >> 8);
                h[3] = (uint8_t)(~m & 0xFF), h[4] = (uint8_t)((~m >> 8) & 0xFF);
                filter_range(c, rows, stride, off, m, h + 5);
                n += 5 + m;
                off += m;
            }
        }
        c->joins[3]++;
        goto done;
    }
#endif
    for (size_t off = 0; off < filtered; off += each) {
        size_t m = filtered - off < each ? filtered - off : each;
        filter_range(c, rows, stride, off, m, c->filt);
        adler = libdeflate_adler32(adler, c->filt, m);
        size_t k = libdeflate_deflate_compress(c->c, c->filt, m, c->out + n, c->out_cap - n - 5);
        if (k && !(last_band && off + m == filtered)) k = make_joinable(c, c->out + n, k);
        if (!k) return 1;
        n += k;
    }
#ifdef RS_WITH_ISAL
done:
#endif
    out->data = c->out;
    out->size = n;
    out->adler = adler;
    out->raw = filtered;
    return 0;
}

/* ---- the file ------------------------------------------------------------- */

/* One chunk whose data is a then b (either may be empty). */
static int write_chunk2(FILE *f, const char type[4], const uint8_t *a, size_t na, const uint8_t *b, size_t nb)
{
    uint8_t hdr[8], crc[4];
    put_be32(hdr, (uint32_t)(na + nb));
    memcpy(hdr + 4, type, 4);
    uint32_t c = libdeflate_crc32(0, hdr + 4, 4);
    if (na) c = libdeflate_crc32(c, a, na);
    if (nb) c = libdeflate_crc32(c, b, nb);
    put_be32(crc, c);
    return fwrite(hdr, 1, 8, f) == 8 && (na == 0 || fwrite(a, 1, na, f) == na) &&
           (nb == 0 || fwrite(b, 1, nb, f) == nb) && fwrite(crc, 1, 4, f) == 4;
}

int cli_png_writer_begin(cli_png_writer *w, FILE *f, const cli_png_layout *l)
{
    static const uint8_t sig[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n' };
    w->f = f;
    w->l = l;
    w->next = 0;
    w->adler = 1;
    w->bytes = 8 + 12 + 13; /* file offset after the signature and IHDR */
    w->synced = 0;
    uint8_t ihdr[13];
    put_be32(ihdr, l->width);
    put_be32(ihdr + 4, l->height);
    ihdr[8] = (uint8_t)l->bits;
    ihdr[9] = (uint8_t)(l->channels == 1 ? 0 : l->channels == 2 ? 4 : l->channels == 3 ? 2 : 6); /* colour type */
    ihdr[10] = ihdr[11] = ihdr[12] = 0; /* deflate, adaptive filtering, no interlace */
    errno = 0;
    return !(fwrite(sig, 1, 8, f) == 8 && write_chunk2(f, "IHDR", ihdr, sizeof ihdr, NULL, 0));
}

int cli_png_writer_band(cli_png_writer *w, const cli_png_piece *p)
{
    const int last = w->next + 1 == w->l->nbands;
    uint8_t tail[4];
    w->adler = (uint32_t)adler32_combine(w->adler, p->adler, (z_off_t)p->raw);
    put_be32(tail, w->adler);
    const size_t ntail = last ? 4 : 0, total = p->size + ntail;
    errno = 0;
    for (size_t off = 0; off < total; off += IDAT_CHUNK) {
        size_t len = total - off < IDAT_CHUNK ? total - off : IDAT_CHUNK;
        size_t na = off < p->size ? (p->size - off < len ? p->size - off : len) : 0;
        const uint8_t *b = off + na >= p->size ? tail + (off + na - p->size) : NULL;
        if (!write_chunk2(w->f, "IDAT", na ? p->data + off : NULL, na, b, len - na)) return 1;
        w->bytes += 12 + len;
    }
    w->next++;
#if defined(__linux__) && defined(SYNC_FILE_RANGE_WRITE)
    if (w->bytes - w->synced >= WRITEBACK_BYTES) {
        if (fflush(w->f) != 0) return 1;
        /* a hint: unsupported files and errors are left to fsync */
        (void)sync_file_range(fileno(w->f), (off_t)w->synced, (off_t)(w->bytes - w->synced), SYNC_FILE_RANGE_WRITE);
        w->synced = w->bytes;
    }
#endif
    return 0;
}

int cli_png_writer_end(cli_png_writer *w)
{
    errno = 0;
    return w->next != w->l->nbands || !write_chunk2(w->f, "IEND", NULL, 0, NULL, 0);
}

/* ---- whole images in memory ------------------------------------------------ */

int cli_png_encode(FILE *f, const char *shown, const cli_png_image *img, const cli_png_options *opt)
{
    cli_png_layout l;
    if (cli_png_layout_init(&l, shown, img->width, img->height, img->channels, img->bits, opt ? opt->level : -1))
        return 1;
    if (opt && opt->no_isal) l.isal = 0;
    if (!img->data) {
        cli_error("%s: no pixels to write", shown);
        return 1;
    }
    cli_png_coder *c = cli_png_coder_new(&l);
    if (!c) {
        cli_error("%s: out of memory for a %ux%u PNG", shown, l.width, l.height);
        return 1;
    }
    cli_png_writer w;
    int bad = cli_png_writer_begin(&w, f, &l), failed_deflate = 0;
    for (uint32_t b = 0; !bad && b < l.nbands; b++) {
        cli_png_piece p;
        const uint8_t *rows = (const uint8_t *)img->data + (size_t)b * l.band_rows * l.row_bytes;
        if (cli_png_coder_band(c, b, rows, l.row_bytes, &p)) {
            bad = failed_deflate = 1;
            break;
        }
        bad = cli_png_writer_band(&w, &p);
        if (opt && opt->progress) opt->progress(opt->progress_user, (uint64_t)(b + 1) * 1000 / l.nbands, 1000);
    }
    bad = bad || cli_png_writer_end(&w) || fflush(f) != 0 || ferror(f);
    cli_png_coder_free(c);
    if (failed_deflate) cli_error("%s: compression failed", shown);
    else if (bad) cli_error("%s: write failed: %s", shown, strerror(errno ? errno : EIO));
    return bad;
}

int cli_png_write(const char *path, const char *shown, const cli_png_image *img, const cli_png_options *opt)
{
    cli_out o;
    if (!shown) shown = path;
    if (cli_out_open(&o, path)) return 1;
    int bad = cli_png_encode(o.f, shown, img, opt);
    if (!bad) {
        /* Close the temporary (its write errors reported) before checking it. */
        int e = 0;
        if (fflush(o.f) != 0 || ferror(o.f)) { bad = 1; e = errno; }
        if (!bad && fsync(fileno(o.f)) != 0 && errno != EINVAL) { bad = 1; e = errno; }
        if (fclose(o.f) != 0 && !bad) { bad = 1; e = errno; }
        o.f = NULL;
        if (bad) cli_error("%s: write failed: %s", shown, strerror(e ? e : EIO));
        else if (!cli_png_file_complete(o.tmp)) {
            cli_error("%s: write failed: the PNG did not reach the disk whole", shown);
            bad = 1;
        } else if (rename(o.tmp, o.path) != 0) {
            cli_error("%s: write failed: %s", shown, strerror(errno));
            bad = 1;
        }
    }
    if (bad) {
        cli_out_abort(&o);
        return 1;
    }
    cli_temp_forget(o.tmp); /* renamed: no longer ours to remove on a signal */
    free(o.path);
    free(o.tmp);
    return 0;
}

int cli_image_write_png(const char *path, uint32_t w, uint32_t h, int channels, int bits, const void *data)
{
    cli_png_image img = { w, h, channels, bits, data };
    return cli_png_write(path, path, &img, NULL);
}

int cli_image_write_png_as(const char *path, const char *shown, uint32_t w, uint32_t h, int channels, int bits,
                           const void *data)
{
    cli_png_image img = { w, h, channels, bits, data };
    return cli_png_write(path, shown, &img, NULL);
}

/* 1 when the file at `path` is a whole PNG: the signature, then chunks
 * whose lengths chain exactly to an IEND at the end of the file, every CRC
 * right. OUT is only renamed into place after this check (a full disk or a
 * file size limit must never leave a truncated image under the OUT name). */
int cli_png_file_complete(const char *path)
{
    static const unsigned char sig[8] = { 0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n' };
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    unsigned char hdr[8], buf[1 << 15];
    int ok = fread(hdr, 1, 8, f) == 8 && memcmp(hdr, sig, 8) == 0, seen_iend = 0, first = 1;
    while (ok && !seen_iend) {
        if (fread(hdr, 1, 8, f) != 8) { ok = 0; break; }
        uint32_t len = get_be32(hdr);
        if (len > 0x7FFFFFFFu || (first && memcmp(hdr + 4, "IHDR", 4) != 0)) { ok = 0; break; }
        first = 0;
        seen_iend = memcmp(hdr + 4, "IEND", 4) == 0;
        uint32_t c = libdeflate_crc32(0, hdr + 4, 4);
        for (uint32_t left = len; left > 0;) {
            size_t want = left < sizeof buf ? left : sizeof buf;
            if (fread(buf, 1, want, f) != want) { ok = 0; break; }
            c = libdeflate_crc32(c, buf, want);
            left -= (uint32_t)want;
        }
        if (!ok || fread(hdr, 1, 4, f) != 4) { ok = 0; break; }
        ok = get_be32(hdr) == c;
    }
    ok = ok && seen_iend && fgetc(f) == EOF && !ferror(f);
    fclose(f);
    return ok;
}

int cli_parse_png_level(const char *option, const char *s, int *level)
{
    uint32_t u;
    if (cli_parse_u32(option, s, &u)) return 1;
    if (u > CLI_PNG_LEVEL_MAX) {
        cli_error("%s: '%s' must be 0..%d", option, s, CLI_PNG_LEVEL_MAX);
        return 1;
    }
    *level = (int)u;
    return 0;
}

/* Into an existing temporary of the caller's (truncated), no rename. */
int cli_image_write_png_file(const char *path, const char *shown, uint32_t w, uint32_t h, int channels, int bits,
                             const void *data)
{
    cli_png_image img = { w, h, channels, bits, data };
    FILE *f = fopen(path, "wb");
    if (!f) {
        cli_error("%s: write failed: %s", shown, strerror(errno));
        return 1;
    }
    int bad = cli_png_encode(f, shown, &img, NULL), e = 0;
    if (!bad) {
        if (fflush(f) != 0 || ferror(f)) { bad = 1; e = errno; }
        if (!bad && fsync(fileno(f)) != 0 && errno != EINVAL) { bad = 1; e = errno; }
    }
    if (fclose(f) != 0 && !bad) { bad = 1; e = errno; }
    if (bad) {
        if (e) cli_error("%s: write failed: %s", shown, strerror(e));
        return 1;
    }
    if (!cli_png_file_complete(path)) {
        cli_error("%s: write failed: the PNG did not reach the disk whole", shown);
        return 1;
    }
    return 0;
}
