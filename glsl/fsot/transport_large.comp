#version 450
// Large classes, after both sorts: one workgroup per class sends its member of
// rank r (already in order) towards the exact target of rank r, as the transport
// pass does for small classes.
// variant FLOAT: FSOT_FLOAT_ATOMICS
// variant DIMS: FSOT_ANY_DIMS
// variant DIMS_FLOAT: FSOT_ANY_DIMS FSOT_FLOAT_ATOMICS
// variant DIMS_DF: FSOT_ANY_DIMS FSOT_DF32
// variant DIMS_DF_FLOAT: FSOT_ANY_DIMS FSOT_DF32 FSOT_FLOAT_ATOMICS
#define FSOT_SHARED_BREAKS
#include "bindings.glsl"
#include "accumulate.glsl"

layout(local_size_x_id = 0) in;
layout(push_constant) uniform Push { TransportPush pc; };
#include "rank_targets.glsl"
#include "loop_cap.glsl"

shared float s_part[gl_WorkGroupSize.x];

// Sends the member in sorted place `at` towards `target`; its squared distance.
float send(FsotSlice s, uint at, float target) {
    uint e = large_vals[at];
    float delta = target - large_proj[e];
    fsot_add_displacement(large_points[e], pc.dims, delta, s.theta);
    return delta * delta;
}

void main() {
    uint g = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    uint tid = gl_LocalInvocationID.x;
    uint wg = gl_WorkGroupSize.x;
    if (g >= large_segments) {
        return;
    }
    LargeSegment seg = segments[g];
    uint off = seg.first, n = seg.size;
    FsotSlice s = fsot_draw_slice(pc.slice_key, pc.axis_bits, pc.pair_bits, pc.iteration, seg.slice, pc.dims, pc.width, pc.height, pc.frames);
    FsotTargets z = fsot_targets(s);
    float local_cost = 0.0;
#ifdef FSOT_ANY_DIMS
    // As transport.comp: each invocation walks a run of the lower half.
    fsot_fill_breaks(z, tid, wg);
    barrier();
    uint half_n = n / 2u;
    uint chunk = (half_n + wg - 1u) / wg;
    uint q0 = min(tid * chunk, half_n), q1 = min(q0 + chunk, half_n);
    if (q0 < q1) {
        FsotWalk w = fsot_walk(z, n, q0);
        for (uint q = q0; q < q1; ++q) {
            FsotReal m = fsot_walk_step(z, n, w);
            local_cost += send(s, off + q, fsot_box_low_target(z, m));
            local_cost += send(s, off + n - 1u - q, fsot_box_high_target(z, m));
        }
    }
    if ((n & 1u) == 1u && tid == 0u) {
        local_cost += send(s, off + half_n, fsot_box_centre(z));
    }
#else
    for (uint r = tid; r < n; r += wg) {
        local_cost += send(s, off + r, fsot_target(z, r, n));
    }
#endif
    s_part[tid] = local_cost;
    barrier();
    for (uint stride = wg / 2u; stride > 0u; stride >>= 1) {
        if (tid < stride) { s_part[tid] += s_part[tid + stride]; }
        barrier();
    }
    if (tid == 0u) {
        fsot_add_cost(pc.cost_slot, s_part[0], n);
    }
    fsot_check_loop_cap();
}
