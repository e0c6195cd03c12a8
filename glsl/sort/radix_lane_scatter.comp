#version 450
// Radix pass 3 of 3 on CPU implementations (SortPath::Lanes): each invocation
// places its run of block_size() consecutive pairs, in input order, from the
// scanned positions of its digits (radix_lane_histogram.comp): stable, since
// runs are scanned in order within each digit and a run is placed in order.
// variant STORAGE: SORT_STORAGE_READS
// (the input read as storage, where a texel view would pass the device's
// maxTexelBufferElements)
#ifndef SORT_STORAGE_READS
#define SORT_TEXEL_READS
#endif
#include "radix_common.glsl"

void main() {
    uint runs = radix_blocks();
    uint run = gl_GlobalInvocationID.x;
    if (run >= runs) {
        return;
    }
    uint next[256];
    for (uint d = 0u; d < 256u; ++d) {
        next[d] = hist[d * runs + run];
    }
    uint first = run * block_size();
    uint end = min(first + block_size(), count);
    for (uint i = first; i < end; ++i) {
        uint k = key_in(i);
        uint d = (k >> pc.shift) & 255u;
        uint at = next[d];
        next[d] = at + 1u;
        keys_out[at] = k;
        vals_out[at] = val_in(i);
    }
}
