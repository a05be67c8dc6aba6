/* The version and error-code functions an embedder checks first (issue 30):
 * the linked library's version equals the header's, every result code has
 * its own description, and unknown codes still get a string. */
#include "roadsplat.h"
#include "harness.h"

#include <stdio.h>
#include <string.h>

int main(void)
{
    char want[32];
    snprintf(want, sizeof want, "%d.%d.%d", RS_VERSION_MAJOR, RS_VERSION_MINOR, RS_VERSION_PATCH);
    CHECK(strcmp(rs_version_string(), want) == 0);
    CHECK_EQ_INT(rs_version_number(), RS_VERSION);
    CHECK_EQ_INT(rs_version_number() >> 16, RS_VERSION_MAJOR);
    CHECK_EQ_INT((rs_version_number() >> 8) & 0xFF, RS_VERSION_MINOR);
    const char *seen[RS_ERR_CANCELLED + 1];
    for (int r = RS_OK; r <= RS_ERR_CANCELLED; r++) {
        seen[r] = rs_strerror((rs_result)r);
        CHECK(seen[r] != NULL && seen[r][0] != '\0');
        for (int k = 0; k < r; k++) CHECKF(strcmp(seen[k], seen[r]) != 0, "codes %d and %d share '%s'", k, r, seen[r]);
    }
    CHECK(rs_strerror((rs_result)99) != NULL);
    return th_finish("test_api");
}
