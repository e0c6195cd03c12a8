#version 450
// Indirect dispatch sizes of the sort for a count only the GPU knows: the
// histogram and scatter's blocks, the scan's chunks. One invocation.
#include "bindings.glsl"

layout(local_size_x = 1) in;
// Pairs per block (the sort's WG x ITEMS).
layout(constant_id = 0) const uint BLOCK = 2048u;
// Blocks a workgroup of the histogram and scatter takes: 1, or on the lanes
// path (a run an invocation) the workgroup's invocations.
layout(constant_id = 1) const uint BLOCKS_PER_GROUP = 1u;

void main() {
    uint blocks = max(1u, (count + BLOCK - 1u) / BLOCK);
    uint chunks = (256u * blocks + BLOCK - 1u) / BLOCK;
    sort_args[0] = uvec4((blocks + BLOCKS_PER_GROUP - 1u) / BLOCKS_PER_GROUP, 1u, 1u, 0u);
    sort_args[1] = uvec4(chunks, 1u, 1u, 0u);
}
