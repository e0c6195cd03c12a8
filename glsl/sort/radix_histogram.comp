#version 450
// Radix pass 1 of 3: per-block digit counts. The loop is unrolled with no early
// exit, so the block's loads are issued together.
#extension GL_EXT_control_flow_attributes : require
#include "radix_common.glsl"


shared uint s_hist[256];

void main() {
    uint tid = gl_LocalInvocationID.x;
    uint block = gl_WorkGroupID.x;
    for (uint d = tid; d < 256u; d += gl_WorkGroupSize.x) { s_hist[d] = 0u; }
    barrier();
    uint base = block * block_size();
    [[unroll]] for (uint it = 0u; it < ITEMS; ++it) {
        uint i = base + it * gl_WorkGroupSize.x + tid;
        if (i < count) {
            atomicAdd(s_hist[(keys_in[i] >> pc.shift) & 255u], 1u);
        }
    }
    barrier();
    for (uint d = tid; d < 256u; d += gl_WorkGroupSize.x) { hist[d * radix_blocks() + block] = s_hist[d]; }
}
