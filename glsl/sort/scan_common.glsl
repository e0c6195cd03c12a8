// Exclusive scan helpers over chunks of WG x ITEMS uints in shared memory.
#include "radix_common.glsl"

shared uint s_scan[gl_WorkGroupSize.x];

// Exclusive prefix of `value` over the workgroup (Hillis-Steele); returns it and
// leaves the total in `total`.
uint workgroup_exclusive(uint value, out uint total) {
    uint tid = gl_LocalInvocationID.x;
    s_scan[tid] = value;
    barrier();
    for (uint off = 1u; off < gl_WorkGroupSize.x; off <<= 1) {
        uint add = tid >= off ? s_scan[tid - off] : 0u;
        barrier();
        s_scan[tid] += add;
        barrier();
    }
    uint inclusive = s_scan[tid];
    total = s_scan[gl_WorkGroupSize.x - 1u];
    barrier();
    return inclusive - value;
}
