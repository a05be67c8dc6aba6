/* Private: the road-text lexer shared by road and style blocks
 * (lib/input/roads.c) and the style-block parser (lib/input/style.c). The road file
 * may hold both kinds of block; one text parser (rs__text_parse) reads
 * it for rs_roads_parse* and rs_styles_*, so both report the same error
 * for the same text. */
#ifndef RS_STYLE_H
#define RS_STYLE_H
#include "internal.h"

/* A token of the current line: [s, s+n) of the text, quotes included. */
typedef struct rs__tok {
    const char *s;
    size_t n;
    int quoted; /* holds a "..." part (unescape with rs__tok_text) */
} rs__tok;

/* What the next token may be. PLAIN splits at blanks and ends the line at
 * any '#' (the format before styles, unchanged); NAME also reads "quoted
 * text"; ATTR also reads key="quoted text"; COLOUR also reads #RRGGBB and
 * #RRGGBBAA (a '#' not followed by 6 or 8 hex digits and a blank or the
 * line end starts a comment). */
enum { RS__LEX_PLAIN, RS__LEX_NAME, RS__LEX_ATTR, RS__LEX_COLOUR };

enum { RS__LEX_ERR_UNTERMINATED = 1, RS__LEX_ERR_ESCAPE, RS__LEX_ERR_AFTER_QUOTE };

typedef struct rs__lex {
    const char *s;       /* the line (comment included), checked bytes */
    size_t n, i;         /* length, read position */
    const char *comment; /* where a comment started, once reached */
    int err;             /* RS__LEX_ERR_* after rs__lex_next returned -1 */
    const char *err_at;  /* the offending byte */
    const char *tok_at;  /* start of the token with the error */
} rs__lex;

/* Next token: 1 and *t, 0 at the end of the line (or at a comment), -1 on
 * a quoting error (see rs__lex_fail). */
int rs__lex_next(rs__lex *L, int mode, rs__tok *t);
/* "line N: ..." message for the quoting error in L. */
rs_result rs__lex_fail(rs_ctx *ctx, unsigned long long line, const rs__lex *L);
/* 1 if an unquoted token equals `word`. */
int rs__tok_is(const rs__tok *t, const char *word);
/* The token's text with quotes removed and \" \\ unescaped, into `out`
 * (room for t->n bytes); returns its length. Not NUL-terminated. */
size_t rs__tok_text(const rs__tok *t, char *out);
/* Quote text for a message, shortened to keep messages one line. */
const char *rs__quote(char *buf, size_t cap, const char *s, size_t n);
/* Length of a well-formed UTF-8 sequence at s (lead byte >= 0x80), 0 if
 * malformed (overlong, surrogate, > U+10FFFF, truncated). */
size_t rs__utf8_len(const unsigned char *s, size_t avail);
/* Read a whole token as a number; else a "line N: WHAT 'x' is not a
 * number" / "is out of range" failure. */
rs_result rs__number(rs_ctx *ctx, unsigned long long line, const rs__tok *t, const char *what, double *out);

/* A style block being read: `style NAME` opens it, each line inside goes
 * to rs__style_line, `end` closes it into the set. */
typedef struct rs__style_block {
    rs_style st;
    unsigned long long line; /* of the `style` line */
    int have_casing;
} rs__style_block;

/* L is positioned after the `style` keyword. */
rs_result rs__style_begin(rs_ctx *ctx, rs__style_block *b, unsigned long long line, rs__lex *L);
/* A line inside the block; `first` is its first token (not `end`). */
rs_result rs__style_line(rs_ctx *ctx, rs__style_block *b, unsigned long long line, const rs__tok *first,
                         rs__lex *L);
/* The block's `end` line (L after `end`): check and add to `styles`. */
rs_result rs__style_end(rs_ctx *ctx, rs_styles *styles, rs__style_block *b, unsigned long long line, rs__lex *L);
/* Undo adds: keep the first `count` styles. */
void rs__styles_truncate(rs_styles *styles, size_t count);

/* The text parser. `roads` NULL: road blocks are checked but not kept
 * (their points not stored); `styles` NULL: style blocks are checked
 * into a scratch set. On failure, styles added to `styles` are removed. */
rs_result rs__text_parse(rs_ctx *ctx, const char *text, size_t size, rs_profile profile, rs_roads *roads,
                         rs_styles *styles);
#endif
