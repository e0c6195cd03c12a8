#version 450
// Large classes, between two stable sorts: key each element (payload: its index)
// by a per-element table. After the sort by point, the table is the projection's
// sortable key; after the sort by projection, the segment, so the last sort groups
// every class with its members in projection order, ties in point order.
#include "common.glsl"

layout(local_size_x_id = 0) in;

layout(std430, set = 0, binding = 0) readonly buffer LargeMeta { uint large_count; };
layout(std430, set = 0, binding = 1) writeonly buffer Keys { uint keys[]; };
layout(std430, set = 0, binding = 2) readonly buffer Vals { uint vals[]; };
layout(std430, set = 0, binding = 3) readonly buffer Table { uint table[]; };

void main() {
    uint j = gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * gl_WorkGroupSize.x) + gl_GlobalInvocationID.x;
    if (j < large_count) {
        keys[j] = table[vals[j]];
    }
}
