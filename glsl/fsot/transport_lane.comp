#version 450
// The transport pass for CPU implementations of Vulkan (lavapipe): one
// invocation per slice, its class in private memory, sorted by a bucket sort
// (O(n) expected; ties by point index: the CPU's order), no barriers and no
// traffic between invocations, which such drivers run as SIMD lanes. Classes
// larger than FSOT_LANE_MAX go to the large-class path (global radix sort), as in
// transport.comp; GPUs use that pass instead. The invocations take the slices
// in decreasing class size (slice_order.glsl), several each, so
// the lanes that run together have classes of about the same size, and the
// workgroups take chunks of them from a queue, each as many as its lanes can
// take within the loop cap (slice_order.glsl).
// variant FLOAT: FSOT_FLOAT_ATOMICS
// variant DIMS: FSOT_ANY_DIMS
// variant DIMS_FLOAT: FSOT_ANY_DIMS FSOT_FLOAT_ATOMICS
// variant DIMS_DF: FSOT_ANY_DIMS FSOT_DF32
// variant DIMS_DF_FLOAT: FSOT_ANY_DIMS FSOT_DF32 FSOT_FLOAT_ATOMICS
#extension GL_KHR_shader_subgroup_vote : require
#extension GL_KHR_shader_subgroup_ballot : require
#define FSOT_TEXEL_READS // samples and taps through their texel views (bindings.glsl)
#include "bindings.glsl"
layout(push_constant) uniform Push { TransportPush pc; };

#include "transport_common.glsl"
#include "slice_order.glsl"

layout(local_size_x_id = 0) in;
// Largest class sorted in one invocation (set by the host: src/optimize/vulkan/shape.rs
// lane_limit_for, at most 65535 for the 16-bit counters); 36 KiB of private
// memory per invocation at 2048, which llvmpipe zero-fills at each workgroup's start.
layout(constant_id = 3) const uint FSOT_LANE_MAX = 2048u;
#define FSOT_INSERTION_BUDGET 4u

// Private arrays: the members in class order and in sorted order, each as its
// projection's sortable key (fsot_float_key) above its point in 64 bits, so
// that one comparison of two members orders them by projection, ties by point
// (the CPU's order), and one private-memory access moves a member where two
// would (on a SIMD driver each is a loop over the lanes); a 16-bit counter per
// bucket, two a word (the count, then the bucket's next position).
uint64_t member[FSOT_LANE_MAX];
uint bucket_pair[(FSOT_LANE_MAX + 1u) / 2u];
uint64_t sorted[FSOT_LANE_MAX];

uint64_t pack_member(float key, uint point) {
    return (uint64_t(fsot_float_key(key)) << 32) | uint64_t(point);
}
float member_key(uint64_t m) {
    return fsot_key_float(uint(m >> 32));
}
uint member_point(uint64_t m) {
    return uint(m);
}

// Heap sort of `sorted` in place: the fallback when keys pile into few buckets.
void sift_down(uint root, uint end) {
    while (2u * root + 1u < end) {
        uint child = 2u * root + 1u;
        if (child + 1u < end && sorted[child] < sorted[child + 1u]) {
            child += 1u;
        }
        if (!(sorted[root] < sorted[child])) {
            return;
        }
        uint64_t t = sorted[root]; sorted[root] = sorted[child]; sorted[child] = t;
        root = child;
    }
}

void heap_sort(uint n) {
    for (uint i = n / 2u; i > 0u; --i) {
        sift_down(i - 1u, n);
    }
    for (uint end = n - 1u; end > 0u; --end) {
        uint64_t t = sorted[0]; sorted[0] = sorted[end]; sorted[end] = t;
        sift_down(0u, end);
    }
}

// Sends the member of rank i towards `target`; its squared distance.
float send(FsotSlice s, uint i, float target) {
    uint64_t m = sorted[i];
    float delta = target - member_key(m);
    fsot_add_displacement(member_point(m), pc.dims, delta, s.theta);
    return delta * delta;
}

// Transports the slice of rank `rank` in the iteration's order.
void transport_rank(uint rank) {
    uint slice = slice_order[fsot_order_rank_at(pc.order_slot, rank)];
    FsotSlice s = fsot_draw_slice(pc.slice_key, pc.axis_bits, pc.pair_bits, pc.iteration, slice, pc.dims, pc.width, pc.height, pc.frames);
    // The class's size, which the ordering found (no search of the taps).
    uint n = slice_order[fsot_order_key_at(pc.order_slot, slice)] * pc.spp;
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
    // Bucket sort: O(n) expected, few per-lane memory accesses (each one a
    // gather on a SIMD driver), then an insertion sort that only has to order
    // keys within a bucket; ties by point index, the CPU's order.
    FsotTargets z = fsot_targets(s);
    float low = fsot_targets_low(z);
    float scale = float(n) / max(fsot_targets_width(z), 1e-30);
    // Two 16-bit counters a word (classes hold at most 2048 members): half the
    // words to clear and to turn into first positions, where each word is a
    // private-memory access per lane.
    uint words = (n + 1u) / 2u;
    for (uint w = 0u; w < words; ++w) {
        bucket_pair[w] = 0u;
    }
    for (uint i = 0u; i < n; ++i) {
        uint point = fsot_class_point(s, i);
        float p = fsot_project(s, point);
        member[i] = pack_member(p, point);
        uint b = fsot_bucket(p, low, scale, n);
        bucket_pair[b >> 1u] += 1u << ((b & 1u) * 16u);
    }
    uint total = 0u;
    uint pairs = 0u; // pairs sharing a bucket: at most this many insertion moves
    for (uint w = 0u; w < words; ++w) {
        uint c = bucket_pair[w];
        uint c0 = c & 0xffffu;
        uint c1 = c >> 16u;
        bucket_pair[w] = total | ((total + c0) << 16u);
        total += c0 + c1;
        pairs += c0 * (c0 - min(c0, 1u)) / 2u + c1 * (c1 - min(c1, 1u)) / 2u;
    }
    for (uint i = 0u; i < n; ++i) {
        uint64_t m = member[i];
        uint b = fsot_bucket(member_key(m), low, scale, n);
        uint shift = (b & 1u) * 16u;
        uint word = bucket_pair[b >> 1u];
        bucket_pair[b >> 1u] = word + (1u << shift);
        sorted[(word >> shift) & 0xffffu] = m;
    }
    // Insertion sort: each key moves past the larger keys of its own bucket,
    // so at most `pairs` moves in all. Where keys pile into few buckets
    // (degenerate samples), a heap sort instead: O(n log n) whatever the keys,
    // so no class pushes an invocation past the driver's loop budget. Every
    // lane of the subgroup takes the heap sort if one does (the same order
    // either way): a SIMD driver runs both sides of a branch, and a group
    // whose lanes took both would spend the two sorts' loops in one slice,
    // past what the budget allows for it (src/optimize/vulkan/shape.rs: lane_iterations).
    bool piled = pairs > FSOT_INSERTION_BUDGET * n;
    if (!subgroupAny(piled)) {
        // In two loops, because a SIMD driver (llvmpipe) runs both sides of a
        // branch for all its lanes, masked, and a store under a mask is a loop
        // over the lanes: first the keys smaller than the largest before them,
        // found with that largest in registers and listed in `member` (free
        // after the placing pass) without a branch (every lane stores, the slot
        // is kept only where counted); then only those, in order, each moved
        // down past the larger keys (the same moves as one insertion loop: a
        // key's predecessors are in order when its turn comes). About a fifth
        // of the keys are listed, so the loop with the moves runs a fifth as
        // often.
        uint64_t last = sorted[0];
        uint listed = 0u;
        for (uint i = 1u; i < n; ++i) {
            uint64_t m = sorted[i];
            member[listed] = uint64_t(i); // kept only if counted
            listed += m < last ? 1u : 0u;
            last = max(last, m);
        }
        for (uint k = 0u; k < listed; ++k) {
            uint j = uint(member[k]);
            uint64_t m = sorted[j];
            do {
                sorted[j] = sorted[j - 1u];
                --j;
            } while (j > 0u && m < sorted[j - 1u]);
            sorted[j] = m;
        }
    } else {
        heap_sort(n);
    }
    float cost = 0.0;
#ifdef FSOT_ANY_DIMS
    // The lower half's ranks in order, each quantile solved from the last
    // (src/core/targets.rs: rank_targets), each with its mirror n - 1 - q.
    fsot_fill_breaks_alone(z);
    uint half_n = n / 2u;
    FsotWalk w = fsot_walk(z, n, 0u);
    for (uint q = 0u; q < half_n; ++q) {
        FsotReal m = fsot_walk_step(z, n, w);
        cost += send(s, q, fsot_box_low_target(z, m));
        cost += send(s, n - 1u - q, fsot_box_high_target(z, m));
    }
    if ((n & 1u) == 1u) {
        cost += send(s, half_n, fsot_box_centre(z));
    }
#else
    for (uint i = 0u; i < n; ++i) {
        cost += send(s, i, fsot_target(z, i, n));
    }
#endif
    fsot_add_cost(pc.cost_slot, cost, n);
}

void main() {
    if (schedule.stopped != 0u) {
        return; // the stopping rule ended the run
    }
    // The workgroup (one subgroup: src/optimize/vulkan/shape.rs) takes the next chunk of
    // the iteration's plan (slice_order.glsl), the largest classes first, so
    // that the driver's threads, each running its share of the workgroups,
    // take large classes and small. A chunk is `rounds` rounds of neighbouring
    // ranks, one a lane each round, as many as its tier's cost allows within
    // the loop budget (src/optimize/vulkan/shape.rs: lane_table). The dispatch holds a
    // workgroup for every chunk (more past 65535 chunks: those take none).
    uint plan = fsot_lane_plan_at(pc.order_slot);
    uint chunk = 0u;
    if (subgroupElect()) {
        chunk = atomicAdd(slice_order[plan], 1u);
    }
    chunk = subgroupBroadcastFirst(chunk);
    if (chunk < slice_order[plan + 4u]) {
        uint tier = 0u;
        while (tier + 1u < FSOT_LANE_TIERS && slice_order[fsot_lane_tier_at(pc.order_slot, tier + 1u)] <= chunk) {
            ++tier;
        }
        uint at = fsot_lane_tier_at(pc.order_slot, tier);
        uint rounds = slice_order[at + 3u];
        uint lanes = gl_WorkGroupSize.x;
        uint first = slice_order[at + 1u] + (chunk - slice_order[at]) * lanes * rounds;
        uint end = min(first + lanes * rounds, slice_order[at + 1u] + slice_order[at + 2u]);
        for (uint round = 0u; round < rounds; ++round) {
            uint rank = first + round * lanes + gl_LocalInvocationIndex;
            if (rank >= end) {
                break; // the tier's last chunk
            }
            transport_rank(rank);
        }
    }
    fsot_check_loop_cap();
}
