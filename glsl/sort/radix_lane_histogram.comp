#version 450
// Radix pass 1 of 3 on CPU implementations (SortPath::Lanes): each invocation
// counts the digits of one run of block_size() consecutive pairs by itself, in
// private memory, and writes them at hist[d * runs + run], so that the scan
// (scan_reduce, scan_apply) gives every (digit, run) its first output position
// as for the blocks of the other paths. No barrier, no ballot and no shared
// memory: a CPU driver runs a workgroup's invocations as the lanes of one
// vector, where every per-lane access is a loop over the lanes anyway.
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
    uint counts[256];
    for (uint d = 0u; d < 256u; ++d) {
        counts[d] = 0u;
    }
    uint first = run * block_size();
    uint end = min(first + block_size(), count);
    for (uint i = first; i < end; ++i) {
        counts[(key_in(i) >> pc.shift) & 255u] += 1u;
    }
    for (uint d = 0u; d < 256u; ++d) {
        hist[d * runs + run] = counts[d];
    }
}
