#version 450
// Large classes, between the two sorts: after sorting elements by projection,
// key each one by its segment, so a stable sort by segment groups every class
// with its members in projection order.
#include "common.glsl"

layout(local_size_x_id = 0) in;

layout(std430, set = 0, binding = 0) readonly buffer LargeMeta { uint large_count; };
layout(std430, set = 0, binding = 1) writeonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 2) readonly buffer Vals { uint vals[]; };
layout(std430, set = 0, binding = 3) readonly buffer LargeSeg { uint large_seg[]; };

void main() {
    uint j = gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * gl_WorkGroupSize.x) + gl_GlobalInvocationID.x;
    if (j < large_count) {
        keys[j] = large_seg[vals[j]];
    }
}
