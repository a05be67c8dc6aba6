/* Byte identity across threads, for the tests: a prepared splatter rendered
 * by several threads at once, each with its own context, in interleaved row
 * bands, against the single-call image. */
#ifndef RS_TESTS_BAND_THREADS_H
#define RS_TESTS_BAND_THREADS_H
#include "roadsplat.h"

/* Renders the w x h image of s on n threads (at most 8): thread k takes
 * row bands k, k + n, ... of `band` rows; the colour (RGBA) or, when nopt
 * is not NULL, the normal map (RGB, rs_normal_window with *nopt). Returns
 * 1 when every call succeeded and the image equals ref (tightly packed),
 * else 0. */
int bt_threads_equal(const rs_splatter *s, const rs_normal_options *nopt, const uint8_t *ref, uint32_t w, uint32_t h,
                     uint32_t band, uint32_t n);
#endif
