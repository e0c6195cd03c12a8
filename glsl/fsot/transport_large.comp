#version 450
// Large classes, after both sorts: one workgroup per class sends its member of
// rank r (already in order) towards the exact target of rank r, as the transport
// pass does for small classes.
// variant FLOAT: FSOT_FLOAT_ATOMICS
#include "bindings.glsl"
#include "accumulate.glsl"

layout(local_size_x_id = 0) in;
layout(push_constant) uniform Push { TransportPush pc; };

shared float s_part[gl_WorkGroupSize.x];

void main() {
    uint g = gl_WorkGroupID.x;
    uint tid = gl_LocalInvocationID.x;
    uint wg = gl_WorkGroupSize.x;
    if (g >= large_segments) {
        return;
    }
    LargeSegment seg = segments[g];
    uint off = seg.first, n = seg.size;
    FsotSlice s = fsot_draw_slice(pc.slice_key, pc.iteration, seg.slice, pc.dims, pc.width, pc.height, pc.frames);
    FsotTrapezoid z = fsot_trapezoid(s.theta[0], s.theta[1]);
    float local_cost = 0.0;
    for (uint r = tid; r < n; r += wg) {
        uint e = large_vals[off + r];
        float delta = fsot_rank_target(z, r, n) - large_proj[e];
        local_cost += delta * delta;
        fsot_add_displacement(large_points[e], pc.dims, delta, s.theta);
    }
    s_part[tid] = local_cost;
    barrier();
    for (uint stride = wg / 2u; stride > 0u; stride >>= 1) {
        if (tid < stride) { s_part[tid] += s_part[tid + stride]; }
        barrier();
    }
    if (tid == 0u) {
        fsot_add_cost(pc.cost_slot, s_part[0], n);
    }
}
