/* Overlays stage: line symbols and markings drawn onto the road colour S
 * (SPEC: markings are composited onto S). None yet: the stage is the place
 * they plug in, after the surface and before the composite. */
#include "splatter.h"

void rs__overlays(const rs_splatter *s, rs__piece *p)
{
    (void)s;
    (void)p;
}
