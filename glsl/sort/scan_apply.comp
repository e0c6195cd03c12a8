#version 450
// Scan level 2 of 2: each workgroup sums the chunk totals before its own (a few
// hundred at most, so every workgroup redoing it is cheaper than one more
// dispatch and barrier), then scans its chunk (exclusive) from that offset.
#include "scan_common.glsl"


void main() {
    uint tid = gl_LocalInvocationID.x;
    uint n = 256u * radix_blocks();
    uint base = gl_WorkGroupID.x * block_size() + tid * ITEMS;
    uint local[ITEMS];
    uint sum = 0u;
    for (uint it = 0u; it < ITEMS; ++it) {
        uint i = base + it;
        local[it] = i < n ? hist[i] : 0u;
        sum += local[it];
    }
    uint before = 0u;
    for (uint c = tid; c < gl_WorkGroupID.x; c += gl_WorkGroupSize.x) { before += partials[c]; }
    uint offset;
    workgroup_exclusive(before, offset);
    uint total;
    uint run = workgroup_exclusive(sum, total) + offset;
    for (uint it = 0u; it < ITEMS; ++it) {
        uint i = base + it;
        if (i < n) { hist[i] = run; }
        run += local[it];
    }
}
