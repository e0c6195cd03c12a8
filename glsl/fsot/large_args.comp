#version 450
// Indirect dispatch sizes of the large-class stage, which only the GPU knows:
// the gather (256 per workgroup, spread over y past 65535 workgroups) and one
// workgroup per large class. One invocation.
#include "bindings.glsl"

layout(local_size_x = 1) in;

void main() {
    uint gather = max(1u, (large_count + 255u) / 256u);
    uint gx = min(gather, 65535u);
    large_args[0] = uvec4(gx, (gather + gx - 1u) / gx, 1u, 0u);
    large_args[1] = uvec4(max(large_segments, 1u), 1u, 1u, 0u);
}
