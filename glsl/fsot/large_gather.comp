#version 450
// Large classes, between two stable sorts: key each element (payload: its index)
// by a per-element table. After the sort by point, the table is the projection's
// sortable key; after the sort by projection, the segment, so the last sort groups
// every class with its members in projection order, ties in point order.
#include "bindings.glsl"

layout(local_size_x_id = 0) in;

void main() {
    uint j = gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * gl_WorkGroupSize.x) + gl_GlobalInvocationID.x;
    if (j < large_count) {
        large_keys[j] = gather_table[large_vals[j]];
    }
}
