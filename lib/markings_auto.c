/* Automatic marking placement (issue 14, docs/markings.md "Automatic
 * placement"). */
#include "markings.h"

rs_result rs__markings_auto(rs_ctx *ctx, const rs_dem *dem, const rs_roads *roads, const rs_atlas *atlas,
                            rs__placement **pl, size_t *n, size_t *cap)
{
    (void)ctx; (void)dem; (void)roads; (void)atlas; (void)pl; (void)n; (void)cap;
    return RS_OK;
}
