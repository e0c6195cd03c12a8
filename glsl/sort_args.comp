#version 450
// Indirect dispatch sizes for work whose size only the GPU knows: the radix
// sort's blocks and scan chunks for `count` elements, the large-class gather
// (256 per workgroup, spread over y past 65535 workgroups) and one workgroup per
// large class. One invocation.
#include "common.glsl"

layout(local_size_x = 1) in;
layout(constant_id = 0) const uint BLOCK = 2048u;

layout(std430, set = 0, binding = 0) readonly buffer LargeMeta { uint count; uint segments; };
layout(std430, set = 0, binding = 1) writeonly buffer Args { uint args[]; };

void main() {
    uint blocks = max(1u, (count + BLOCK - 1u) / BLOCK);
    uint chunks = (256u * blocks + BLOCK - 1u) / BLOCK;
    uint gather = max(1u, (count + 255u) / 256u);
    uint gx = min(gather, 65535u);
    uvec3 cmds[4] = uvec3[4](
        uvec3(blocks, 1u, 1u),
        uvec3(chunks, 1u, 1u),
        uvec3(gx, (gather + gx - 1u) / gx, 1u),
        uvec3(max(segments, 1u), 1u, 1u));
    for (uint i = 0u; i < 4u; ++i) {
        args[4u * i] = cmds[i].x;
        args[4u * i + 1u] = cmds[i].y;
        args[4u * i + 2u] = cmds[i].z;
        args[4u * i + 3u] = 0u;
    }
}
