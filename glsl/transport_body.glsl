// The transport pass, one workgroup per slice: draw the slice, gather its class,
// project it after the toroidal shift, sort it in shared memory (bitonic, ties by
// point index: the CPU's order), send the sample of rank r towards the exact
// target of rank r, and add the displacements into the per-value accumulators.
// Classes larger than FSOT_LOCAL_MAX are written out for the global radix sort
// (transport_large.comp finishes them). Included by transport.comp (fixed-point
// accumulators, deterministic) and transport_float.comp (float atomics).
#include "common.glsl"
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require

layout(local_size_x_id = 0) in;
// Slices handled one after another by each workgroup (amortises launch costs on
// CPU implementations), and whether the workgroup is exactly one subgroup (then a
// subgroup barrier synchronises it, which CPU implementations make nearly free).
layout(constant_id = 1) const uint SLICES_PER_GROUP = 1u;
layout(constant_id = 2) const bool ONE_SUBGROUP = false;
#define FSOT_LOCAL_MAX 2048u

layout(std430, set = 0, binding = 0) readonly buffer Samples { float samples[]; };
layout(std430, set = 0, binding = 1) readonly buffer Taps { uvec4 taps[]; }; // dx, dy, dt, threshold
#ifdef FSOT_FLOAT_ATOMICS
layout(std430, set = 0, binding = 2) buffer Acc { float acc[]; };
#else
layout(std430, set = 0, binding = 2) buffer Acc { int64_t acc[]; };
#endif
layout(std430, set = 0, binding = 3) buffer Costs { int64_t costs[]; }; // per slot: squared (2^32 fixed), count
layout(std430, set = 0, binding = 4) buffer LargeMeta { uint large_count; uint large_segments; uint large_overflow; uint large_pad; uvec4 segments[]; };
// Large classes, element e: sort key and payload (the radix sort's input), point,
// projection, and the segment (its first element) it belongs to.
layout(std430, set = 0, binding = 5) writeonly buffer LargeKeys { uint large_keys[]; };
layout(std430, set = 0, binding = 6) writeonly buffer LargeVals { uint large_vals[]; };
layout(std430, set = 0, binding = 7) writeonly buffer LargePoints { uint large_points[]; };
layout(std430, set = 0, binding = 8) writeonly buffer LargeProj { float large_proj[]; };
layout(std430, set = 0, binding = 9) writeonly buffer LargeSeg { uint large_seg[]; };

layout(push_constant) uniform Push { TransportPush pc; };

void sync() {
    if (ONE_SUBGROUP) {
        subgroupBarrier();
    } else {
        barrier();
    }
}

shared float s_key[FSOT_LOCAL_MAX];
shared uint s_val[FSOT_LOCAL_MAX];
shared float s_theta[FSOT_MAX_DIMS];
shared float s_shift[FSOT_MAX_DIMS];
shared uint s_cx, s_cy, s_ct, s_n;
shared int s_large;
shared float s_part[gl_WorkGroupSize.x];

const float FIXED_SCALE = 1099511627776.0; // 2^40, as src/cpu.rs
const float COST_SCALE = 4294967296.0;     // 2^32

uint class_point(uint i) {
    uvec4 tap = taps[i / pc.spp];
    uint x = (s_cx + tap.x) % pc.width;
    uint y = (s_cy + tap.y) % pc.height;
    uint f = (s_ct + tap.z) % pc.frames;
    return ((f * pc.height + y) * pc.width + x) * pc.spp + (i % pc.spp);
}

float project(uint point) {
    float p = 0.0;
    for (uint k = 0u; k < pc.dims; ++k) {
        float y = samples[point * pc.dims + k] - s_shift[k];
        p += s_theta[k] * (y - floor(y));
    }
    return p;
}

bool before(float ka, uint va, float kb, uint vb) {
    return ka < kb || (ka == kb && va < vb);
}

void process_slice(uint slice) {
    uint tid = gl_LocalInvocationID.x;
    uint wg = gl_WorkGroupSize.x;
    if (tid == 0u) {
        FsotSlice s = fsot_draw_slice(pc.slice_key, pc.iteration, slice, pc.dims, pc.width, pc.height, pc.frames);
        for (uint k = 0u; k < FSOT_MAX_DIMS; ++k) { s_theta[k] = s.theta[k]; s_shift[k] = s.shift[k]; }
        s_cx = s.cx; s_cy = s.cy; s_ct = s.ct;
        // Class size: taps whose threshold exceeds the level (thresholds decrease).
        uint lo = 0u, hi = pc.taps;
        while (lo < hi) {
            uint mid = (lo + hi) / 2u;
            if (taps[mid].w > s.level) { lo = mid + 1u; } else { hi = mid; }
        }
        uint n = lo * pc.spp;
        s_n = n;
        s_large = -1;
        if (n > FSOT_LOCAL_MAX) {
            uint off = atomicAdd(large_count, n);
            if (off + n <= pc.large_capacity) {
                uint seg = atomicAdd(large_segments, 1u);
                segments[seg] = uvec4(slice, off, n, 0u);
                s_large = int(off);
            } else {
                atomicAdd(large_overflow, 1u);
            }
        }
    }
    sync();
    uint n = s_n;
    if (n < 2u) {
        return;
    }
    if (n > FSOT_LOCAL_MAX) {
        int off = s_large;
        if (off >= 0) {
            for (uint i = tid; i < n; i += wg) {
                uint point = class_point(i);
                uint e = uint(off) + i;
                float proj = project(point);
                large_keys[e] = fsot_float_key(proj);
                large_vals[e] = e;
                large_points[e] = point;
                large_proj[e] = proj;
                large_seg[e] = uint(off);
            }
        }
        return;
    }
    {
        uint p2 = 2u;
        while (p2 < n) { p2 <<= 1; }
        for (uint i = tid; i < p2; i += wg) {
            if (i < n) {
                uint point = class_point(i);
                s_key[i] = project(point);
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
                        if (before(kb, vb, ka, va) == ascending) {
                            s_key[i] = kb; s_key[l] = ka;
                            s_val[i] = vb; s_val[l] = va;
                        }
                    }
                }
                sync();
            }
        }
    }
    // Only d <= 2 reaches the GPU path (the host checks): two components.
    FsotTrapezoid z = fsot_trapezoid(s_theta[0], s_theta[1]);
    float local_cost = 0.0;
    for (uint i = tid; i < n; i += wg) {
        float delta = fsot_rank_target(z, i, n) - s_key[i];
        local_cost += delta * delta;
        uint base = s_val[i] * pc.dims;
        for (uint k = 0u; k < pc.dims; ++k) {
            float t = s_theta[k];
            if (t != 0.0) {
#ifdef FSOT_FLOAT_ATOMICS
                atomicAdd(acc[base + k], delta * t);
#else
                atomicAdd(acc[base + k], int64_t(round(delta * t * FIXED_SCALE)));
#endif
            }
        }
    }
    s_part[tid] = local_cost;
    sync();
    for (uint stride = wg / 2u; stride > 0u; stride >>= 1) {
        if (tid < stride) { s_part[tid] += s_part[tid + stride]; }
        sync();
    }
    if (tid == 0u) {
        atomicAdd(costs[2u * pc.cost_slot], int64_t(round(s_part[0] * COST_SCALE)));
        atomicAdd(costs[2u * pc.cost_slot + 1u], int64_t(n));
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
