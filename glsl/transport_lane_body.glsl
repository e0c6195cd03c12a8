// The transport pass for CPU implementations of Vulkan (lavapipe): one
// invocation per slice, its class in private memory, sorted by an in-place heap
// sort (O(n log n), ties by point index: the CPU's order), no barriers and no
// traffic between invocations, which such drivers run as SIMD lanes. Classes
// larger than FSOT_LANE_MAX go to the large-class path (global radix sort), as in
// transport_body.glsl; GPUs use that file instead.
#include "transport_bindings.glsl"

layout(local_size_x_id = 0) in;
#define FSOT_LANE_MAX 1024u

float key[FSOT_LANE_MAX];
uint val[FSOT_LANE_MAX];

void sift_down(uint root, uint end) {
    while (2u * root + 1u < end) {
        uint child = 2u * root + 1u;
        if (child + 1u < end && fsot_before(key[child], val[child], key[child + 1u], val[child + 1u])) {
            child += 1u;
        }
        if (!fsot_before(key[root], val[root], key[child], val[child])) {
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
    uint n = fsot_class_size(s);
    if (n < 2u) {
        return;
    }
    if (n > FSOT_LANE_MAX) {
        int off = fsot_reserve_large(slice, n);
        if (off >= 0) {
            for (uint i = 0u; i < n; ++i) {
                fsot_write_large(s, uint(off), i);
            }
        }
        return;
    }
    for (uint i = 0u; i < n; ++i) {
        uint point = fsot_class_point(s, i);
        key[i] = fsot_project(s, point);
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
        fsot_add_displacement(val[i], pc.dims, delta, s.theta);
    }
    fsot_add_cost(pc.cost_slot, cost, n);
}
