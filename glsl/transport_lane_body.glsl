// The transport pass for CPU implementations of Vulkan (lavapipe): one
// invocation per slice, its class in private memory, sorted by an in-place heap
// sort (O(n log n), ties by point index: the CPU's order), no barriers and no
// traffic between invocations, which such drivers run as SIMD lanes. Classes
// larger than FSOT_LANE_MAX go to the large-class path (global radix sort), as in
// transport_body.glsl; GPUs use that file instead.
#include "common.glsl"

layout(local_size_x_id = 0) in;
#define FSOT_LANE_MAX 1024u

layout(std430, set = 0, binding = 0) readonly buffer Samples { float samples[]; };
layout(std430, set = 0, binding = 1) readonly buffer Taps { uvec4 taps[]; }; // dx, dy, dt, threshold
#ifdef FSOT_FLOAT_ATOMICS
layout(std430, set = 0, binding = 2) buffer Acc { float acc[]; };
#else
layout(std430, set = 0, binding = 2) buffer Acc { int64_t acc[]; };
#endif
layout(std430, set = 0, binding = 3) buffer Costs { int64_t costs[]; };
layout(std430, set = 0, binding = 4) buffer LargeMeta { uint large_count; uint large_segments; uint large_overflow; uint large_pad; uvec4 segments[]; };
layout(std430, set = 0, binding = 5) writeonly buffer LargeKeys { uint large_keys[]; };
layout(std430, set = 0, binding = 6) writeonly buffer LargeVals { uint large_vals[]; };
layout(std430, set = 0, binding = 7) writeonly buffer LargePoints { uint large_points[]; };
layout(std430, set = 0, binding = 8) writeonly buffer LargeProj { float large_proj[]; };
layout(std430, set = 0, binding = 9) writeonly buffer LargeSeg { uint large_seg[]; };

layout(push_constant) uniform Push { TransportPush pc; };

const float FIXED_SCALE = 1099511627776.0; // 2^40, as src/cpu.rs
const float COST_SCALE = 4294967296.0;     // 2^32

float key[FSOT_LANE_MAX];
uint val[FSOT_LANE_MAX];

uint class_point(FsotSlice s, uint i) {
    uvec4 tap = taps[i / pc.spp];
    uint x = (s.cx + tap.x) % pc.width;
    uint y = (s.cy + tap.y) % pc.height;
    uint f = (s.ct + tap.z) % pc.frames;
    return ((f * pc.height + y) * pc.width + x) * pc.spp + (i % pc.spp);
}

float project(FsotSlice s, uint point) {
    float p = 0.0;
    for (uint k = 0u; k < pc.dims; ++k) {
        float y = samples[point * pc.dims + k] - s.shift[k];
        p += s.theta[k] * (y - floor(y));
    }
    return p;
}

bool before(float ka, uint va, float kb, uint vb) {
    return ka < kb || (ka == kb && va < vb);
}

void sift_down(uint root, uint end) {
    while (2u * root + 1u < end) {
        uint child = 2u * root + 1u;
        if (child + 1u < end && before(key[child], val[child], key[child + 1u], val[child + 1u])) {
            child += 1u;
        }
        if (!before(key[root], val[root], key[child], val[child])) {
            return;
        }
        float tk = key[root]; key[root] = key[child]; key[child] = tk;
        uint tv = val[root]; val[root] = val[child]; val[child] = tv;
        root = child;
    }
}

void main() {
    uint slice = gl_GlobalInvocationID.y * (gl_NumWorkGroups.x * gl_WorkGroupSize.x) + gl_GlobalInvocationID.x;
    if (slice >= pc.slices) {
        return;
    }
    FsotSlice s = fsot_draw_slice(pc.slice_key, pc.iteration, slice, pc.dims, pc.width, pc.height, pc.frames);
    uint lo = 0u, hi = pc.taps;
    while (lo < hi) {
        uint mid = (lo + hi) / 2u;
        if (taps[mid].w > s.level) { lo = mid + 1u; } else { hi = mid; }
    }
    uint n = lo * pc.spp;
    if (n < 2u) {
        return;
    }
    if (n > FSOT_LANE_MAX) {
        uint off = atomicAdd(large_count, n);
        if (off + n > pc.large_capacity) {
            atomicAdd(large_overflow, 1u);
            return;
        }
        uint seg = atomicAdd(large_segments, 1u);
        segments[seg] = uvec4(slice, off, n, 0u);
        for (uint i = 0u; i < n; ++i) {
            uint point = class_point(s, i);
            uint e = off + i;
            float proj = project(s, point);
            large_keys[e] = fsot_float_key(proj);
            large_vals[e] = e;
            large_points[e] = point;
            large_proj[e] = proj;
            large_seg[e] = off;
        }
        return;
    }
    for (uint i = 0u; i < n; ++i) {
        uint point = class_point(s, i);
        key[i] = project(s, point);
        val[i] = point;
    }
    for (uint i = n / 2u; i > 0u; --i) {
        sift_down(i - 1u, n);
    }
    for (uint end = n - 1u; end > 0u; --end) {
        float tk = key[0]; key[0] = key[end]; key[end] = tk;
        uint tv = val[0]; val[0] = val[end]; val[end] = tv;
        sift_down(0u, end);
    }
    // Only d <= 2 reaches the GPU path (the host checks): two components.
    FsotTrapezoid z = fsot_trapezoid(s.theta[0], s.theta[1]);
    float cost = 0.0;
    for (uint i = 0u; i < n; ++i) {
        float delta = fsot_rank_target(z, i, n) - key[i];
        cost += delta * delta;
        uint base = val[i] * pc.dims;
        for (uint k = 0u; k < pc.dims; ++k) {
            float t = s.theta[k];
            if (t != 0.0) {
#ifdef FSOT_FLOAT_ATOMICS
                atomicAdd(acc[base + k], delta * t);
#else
                atomicAdd(acc[base + k], int64_t(round(delta * t * FIXED_SCALE)));
#endif
            }
        }
    }
    atomicAdd(costs[2u * pc.cost_slot], int64_t(round(cost * COST_SCALE)));
    atomicAdd(costs[2u * pc.cost_slot + 1u], int64_t(n));
}
