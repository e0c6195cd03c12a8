#version 450
// Scan level 2: one workgroup scans the chunk sums in place (exclusive).
#include "scan_common.glsl"

layout(std430, set = 0, binding = 1) buffer Partials { uint partials[]; };

void main() {
    uint tid = gl_LocalInvocationID.x;
    uint n = radix_chunks();
    uint base = tid * ITEMS;
    uint local[32];
    uint sum = 0u;
    for (uint it = 0u; it < ITEMS; ++it) {
        uint i = base + it;
        local[it] = i < n ? partials[i] : 0u;
        sum += local[it];
    }
    uint total;
    uint run = workgroup_exclusive(sum, total);
    for (uint it = 0u; it < ITEMS; ++it) {
        uint i = base + it;
        if (i < n) { partials[i] = run; }
        run += local[it];
    }
}
