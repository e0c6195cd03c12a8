#version 450
// The transport pass for GPUs, one workgroup per slice: draw the slice, gather
// its class, project it after the toroidal shift, sort it in shared memory
// (bitonic, ties by point index: the CPU's order), send the sample of rank r
// towards the exact target of rank r, and add the displacements into the
// per-coordinate accumulators. Classes larger than FSOT_LOCAL_MAX are written out
// for the global radix sort (transport_large.comp finishes them). Included by
// build.rs as TRANSPORT (fixed point, deterministic) and TRANSPORT_FLOAT.
// variant FLOAT: FSOT_FLOAT_ATOMICS
#extension GL_KHR_shader_subgroup_basic : require
#include "bindings.glsl"
layout(push_constant) uniform Push { TransportPush pc; };
#include "transport_common.glsl"

layout(local_size_x_id = 0) in;
// Slices handled one after another by each workgroup (amortises launch costs),
// and whether the workgroup is exactly one subgroup (then a subgroup barrier
// synchronises it).
layout(constant_id = 1) const uint SLICES_PER_GROUP = 1u;
layout(constant_id = 2) const bool ONE_SUBGROUP = false;
// Largest class sorted in shared memory (src/gpu/shape.rs: LOCAL_MAX).
layout(constant_id = 3) const uint FSOT_LOCAL_MAX = 2048u;

void sync() {
    if (ONE_SUBGROUP) {
        subgroupBarrier();
    } else {
        barrier();
    }
}

shared float s_key[FSOT_LOCAL_MAX];
shared uint s_val[FSOT_LOCAL_MAX];
shared FsotSlice s_slice;
shared uint s_n;
shared int s_large;
shared float s_part[gl_WorkGroupSize.x];

void process_slice(uint slice) {
    uint tid = gl_LocalInvocationID.x;
    uint wg = gl_WorkGroupSize.x;
    if (tid == 0u) {
        FsotSlice s = fsot_draw_slice(pc.slice_key, pc.iteration, slice, pc.dims, pc.width, pc.height, pc.frames);
        uint n = fsot_class_size(s);
        s_slice = s;
        s_n = n;
        s_large = n > FSOT_LOCAL_MAX ? fsot_reserve_large(slice, n) : -1;
    }
    sync();
    FsotSlice s = s_slice;
    uint n = s_n;
    if (n < 2u) {
        return;
    }
    if (n > FSOT_LOCAL_MAX) {
        if (s_large >= 0) {
            for (uint i = tid; i < n; i += wg) {
                fsot_write_large(s, uint(s_large), i);
            }
        }
        return;
    }
    uint p2 = 2u;
    while (p2 < n) { p2 <<= 1; }
    for (uint i = tid; i < p2; i += wg) {
        if (i < n) {
            uint point = fsot_class_point(s, i);
            s_key[i] = fsot_project(s, point);
            s_val[i] = point;
        } else {
            s_key[i] = uintBitsToFloat(0x7f800000u); // +inf pads sort last
            s_val[i] = 0xffffffffu;
        }
    }
    sync();
    for (uint k = 2u; k <= p2; k <<= 1) {
        for (uint j = k >> 1; j > 0u; j >>= 1) {
            for (uint i = tid; i < p2; i += wg) {
                uint l = i ^ j;
                if (l > i) {
                    bool ascending = (i & k) == 0u;
                    float ka = s_key[i], kb = s_key[l];
                    uint va = s_val[i], vb = s_val[l];
                    if (fsot_before(kb, vb, ka, va) == ascending) {
                        s_key[i] = kb; s_key[l] = ka;
                        s_val[i] = vb; s_val[l] = va;
                    }
                }
            }
            sync();
        }
    }
    // Only d <= 2 reaches the GPU path (the host checks): two components.
    FsotTrapezoid z = fsot_trapezoid(s.theta[0], s.theta[1]);
    float local_cost = 0.0;
    for (uint i = tid; i < n; i += wg) {
        float delta = fsot_rank_target(z, i, n) - s_key[i];
        local_cost += delta * delta;
        fsot_add_displacement(s_val[i], pc.dims, delta, s.theta);
    }
    s_part[tid] = local_cost;
    sync();
    for (uint stride = wg / 2u; stride > 0u; stride >>= 1) {
        if (tid < stride) { s_part[tid] += s_part[tid + stride]; }
        sync();
    }
    if (tid == 0u) {
        fsot_add_cost(pc.cost_slot, s_part[0], n);
    }
}

void main() {
    uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    for (uint k = 0u; k < SLICES_PER_GROUP; ++k) {
        uint slice = group * SLICES_PER_GROUP + k;
        if (slice >= pc.slices) {
            return;
        }
        process_slice(slice);
        sync(); // shared memory is reused by the next slice
    }
}
