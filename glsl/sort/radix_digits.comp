#version 450
// The look-back path, before its passes: every pass's digit counts over all
// pairs in one read of the keys (pc.passes digits of 8 bits per key), added into
// lb_digits. One block per workgroup.
#extension GL_EXT_control_flow_attributes : require
#include "radix_common.glsl"

shared uint s_hist[4 * 256];

void main() {
    uint tid = gl_LocalInvocationID.x;
    uint wg = gl_WorkGroupSize.x;
    uint passes = min(pc.passes, 4u);
    for (uint d = tid; d < passes * 256u; d += wg) { s_hist[d] = 0u; }
    barrier();
    uint base = gl_WorkGroupID.x * block_size();
    [[unroll]] for (uint it = 0u; it < ITEMS; ++it) {
        uint i = base + it * wg + tid;
        if (i < count) {
            uint k = keys_in[i];
            for (uint p = 0u; p < passes; ++p) {
                atomicAdd(s_hist[p * 256u + ((k >> (8u * p)) & 255u)], 1u);
            }
        }
    }
    barrier();
    for (uint d = tid; d < passes * 256u; d += wg) {
        uint c = s_hist[d];
        if (c != 0u) { atomicAdd(lb_digits[d], c); }
    }
}
