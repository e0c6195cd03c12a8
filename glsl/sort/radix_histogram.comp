#version 450
// Radix pass 1 of 3: per-block digit counts. The loop is unrolled with no early
// exit, so the block's loads are issued together.
//
// TAIL (small sorts): the last workgroup to finish also scans the whole
// histogram, so the two scan dispatches are not needed. No workgroup waits on
// another: each counts itself done, and the one that finds itself last (all
// others' histograms written and made visible before they counted) scans.
// variant TAIL: SORT_SCAN_TAIL
#extension GL_EXT_control_flow_attributes : require
#include "scan_common.glsl"


shared uint s_hist[256];
shared bool s_last;

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
#ifdef SORT_SCAN_TAIL
    memoryBarrierBuffer();
    barrier();
    if (tid == 0u) {
        s_last = atomicAdd(partials[0], 1u) == radix_blocks() - 1u;
    }
    barrier();
    if (!s_last) {
        return; // whole workgroup
    }
    memoryBarrierBuffer();
    // Exclusive scan of every (digit, block) count, chunk by chunk.
    uint n = 256u * radix_blocks();
    uint offset = 0u;
    for (uint chunk = 0u; chunk < n; chunk += block_size()) {
        uint first = chunk + tid * ITEMS;
        uint local[ITEMS];
        uint sum = 0u;
        [[unroll]] for (uint it = 0u; it < ITEMS; ++it) {
            local[it] = first + it < n ? hist[first + it] : 0u;
            sum += local[it];
        }
        uint total;
        uint run = workgroup_exclusive(sum, total) + offset;
        [[unroll]] for (uint it = 0u; it < ITEMS; ++it) {
            if (first + it < n) { hist[first + it] = run; }
            run += local[it];
        }
        offset += total;
    }
    if (tid == 0u) {
        partials[0] = 0u;
    }
#endif
}
