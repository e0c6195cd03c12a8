#version 450
// The transport pass for GPUs, one workgroup per slice: draw the slice, gather
// its class, project it after the toroidal shift, sort it in shared memory
// (bitonic, ties by point index: the CPU's order), send the sample of rank r
// towards the exact target of rank r, and add the displacements into the
// per-coordinate accumulators. Classes larger than FSOT_LOCAL_MAX are written out
// for the global radix sort (transport_large.comp finishes them). Included by
// build.rs as TRANSPORT (fixed point, deterministic) and TRANSPORT_FLOAT, and
// for d >= 3 (f64 targets) as TRANSPORT_DIMS and TRANSPORT_DIMS_FLOAT.
// variant FLOAT: FSOT_FLOAT_ATOMICS
// variant DIMS: FSOT_ANY_DIMS
// variant DIMS_FLOAT: FSOT_ANY_DIMS FSOT_FLOAT_ATOMICS
// variant DIMS_DF: FSOT_ANY_DIMS FSOT_DF32
// variant DIMS_DF_FLOAT: FSOT_ANY_DIMS FSOT_DF32 FSOT_FLOAT_ATOMICS
#extension GL_KHR_shader_subgroup_basic : require
#define FSOT_SHARED_BREAKS
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

// Sends the member of rank i towards `target`; its squared distance.
float send(FsotSlice s, uint i, float target) {
    float delta = target - s_key[i];
    fsot_add_displacement(s_val[i], pc.dims, delta, s.theta);
    return delta * delta;
}

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
    // Each invocation takes pairs, not elements: pair t joins i (bit j clear)
    // and i + j, so no invocation idles on the upper half of a pair.
    for (uint k = 2u; k <= p2; k <<= 1) {
        for (uint j = k >> 1; j > 0u; j >>= 1) {
            for (uint t = tid; t < p2 / 2u; t += wg) {
                uint i = ((t & ~(j - 1u)) << 1) | (t & (j - 1u));
                uint l = i | j;
                bool ascending = (i & k) == 0u;
                float ka = s_key[i], kb = s_key[l];
                uint va = s_val[i], vb = s_val[l];
                if (fsot_before(kb, vb, ka, va) == ascending) {
                    s_key[i] = kb; s_key[l] = ka;
                    s_val[i] = vb; s_val[l] = va;
                }
            }
            sync();
        }
    }
    FsotTargets z = fsot_targets(s);
    float local_cost = 0.0;
#ifdef FSOT_ANY_DIMS
    // Each invocation walks a run of the lower half's ranks (each quantile from
    // the last), sending rank q and its mirror n - 1 - q.
    fsot_fill_breaks(z, tid, wg);
    sync();
    uint half_n = n / 2u;
    uint chunk = (half_n + wg - 1u) / wg;
    uint q0 = min(tid * chunk, half_n), q1 = min(q0 + chunk, half_n);
    if (q0 < q1) {
        FsotWalk w = fsot_walk(z, n, q0);
        for (uint q = q0; q < q1; ++q) {
            FsotReal m = fsot_walk_step(z, n, w);
            local_cost += send(s, q, fsot_box_low_target(z, m));
            local_cost += send(s, n - 1u - q, fsot_box_high_target(z, m));
        }
    }
    if ((n & 1u) == 1u && tid == 0u) {
        local_cost += send(s, half_n, fsot_box_centre(z));
    }
#else
    for (uint i = tid; i < n; i += wg) {
        local_cost += send(s, i, fsot_target(z, i, n));
    }
#endif
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
    if (schedule.stopped != 0u) {
        return; // the stopping rule ended the run (the same for every invocation)
    }
    uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    for (uint k = 0u; k < SLICES_PER_GROUP; ++k) {
        uint slice = group * SLICES_PER_GROUP + k;
        if (slice >= pc.slices) {
            break;
        }
        process_slice(slice);
        sync(); // shared memory is reused by the next slice
    }
    fsot_check_loop_cap();
}
