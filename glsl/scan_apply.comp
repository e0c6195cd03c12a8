#version 450
// Scan level 3: each workgroup scans its chunk (exclusive) and adds the chunk's
// offset from level 2.
#include "scan_common.glsl"

layout(std430, set = 0, binding = 1) buffer Data { uint data[]; };
layout(std430, set = 0, binding = 2) readonly buffer Partials { uint partials[]; };

void main() {
    uint tid = gl_LocalInvocationID.x;
    uint n = 256u * radix_blocks();
    uint base = gl_WorkGroupID.x * block_size() + tid * ITEMS;
    uint local[32];
    uint sum = 0u;
    for (uint it = 0u; it < ITEMS; ++it) {
        uint i = base + it;
        local[it] = i < n ? data[i] : 0u;
        sum += local[it];
    }
    uint total;
    uint run = workgroup_exclusive(sum, total) + partials[gl_WorkGroupID.x];
    for (uint it = 0u; it < ITEMS; ++it) {
        uint i = base + it;
        if (i < n) { data[i] = run; }
        run += local[it];
    }
}
