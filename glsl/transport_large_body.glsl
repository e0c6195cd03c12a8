// Large classes, after both sorts: one workgroup per class sends its member of
// rank r (already in order) towards the exact target of rank r, as the transport
// pass does for small classes. Included by transport_large.comp (fixed point) and
// transport_large_float.comp.
#include "common.glsl"

layout(local_size_x_id = 0) in;

#ifdef FSOT_FLOAT_ATOMICS
layout(std430, set = 0, binding = 0) buffer Acc { float acc[]; };
#else
layout(std430, set = 0, binding = 0) buffer Acc { int64_t acc[]; };
#endif
layout(std430, set = 0, binding = 1) buffer Costs { int64_t costs[]; };
layout(std430, set = 0, binding = 2) readonly buffer LargeMeta { uint large_count; uint large_segments; uint large_overflow; uint large_pad; uvec4 segments[]; };
layout(std430, set = 0, binding = 3) readonly buffer Vals { uint vals[]; };
layout(std430, set = 0, binding = 4) readonly buffer LargePoints { uint large_points[]; };
layout(std430, set = 0, binding = 5) readonly buffer LargeProj { float large_proj[]; };

layout(push_constant) uniform Push { TransportPush pc; };

#include "accumulate.glsl"
#include "cost.glsl"

shared float s_part[gl_WorkGroupSize.x];

void main() {
    uint g = gl_WorkGroupID.x;
    uint tid = gl_LocalInvocationID.x;
    uint wg = gl_WorkGroupSize.x;
    if (g >= large_segments) {
        return;
    }
    uvec4 seg = segments[g];
    uint off = seg.y, n = seg.z;
    FsotSlice s = fsot_draw_slice(pc.slice_key, pc.iteration, seg.x, pc.dims, pc.width, pc.height, pc.frames);
    FsotTrapezoid z = fsot_trapezoid(s.theta[0], s.theta[1]);
    float local_cost = 0.0;
    for (uint r = tid; r < n; r += wg) {
        uint e = vals[off + r];
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
