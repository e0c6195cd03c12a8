#version 450
// Indirect dispatch sizes of the large-class stage, which only the GPU knows:
// the gather (256 per workgroup) and one workgroup per large class, each spread
// over y past 65535 workgroups. One invocation.
#include "bindings.glsl"

layout(local_size_x = 1) in;

void main() {
    uint gather = max(1u, (large_count + 255u) / 256u);
    uint gx = min(gather, 65535u);
    large_args[0] = uvec4(gx, (gather + gx - 1u) / gx, 1u, 0u);
    uint segments = max(large_segments, 1u);
    uint sx = min(segments, 65535u);
    large_args[1] = uvec4(sx, (segments + sx - 1u) / sx, 1u, 0u);
}
