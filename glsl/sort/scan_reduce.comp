#version 450
// Scan level 1 of 2: each workgroup sums its chunk of the histogram.
#include "scan_common.glsl"


void main() {
    uint tid = gl_LocalInvocationID.x;
    uint n = 256u * radix_blocks();
    uint base = gl_WorkGroupID.x * block_size() + tid * ITEMS;
    uint sum = 0u;
    for (uint it = 0u; it < ITEMS; ++it) {
        uint i = base + it;
        if (i < n) { sum += hist[i]; }
    }
    uint total;
    workgroup_exclusive(sum, total);
    if (tid == 0u) { partials[gl_WorkGroupID.x] = total; }
}
