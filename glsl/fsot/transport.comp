#version 450
// The transport pass for GPUs, one workgroup per slice: draw the slice, gather
// its class, project it after the toroidal shift, sort it in shared memory
// (a bucket sort: ties by point index, the CPU's order), send the sample of rank
// r towards the exact target of rank r, and add the displacements into the
// per-coordinate accumulators. Classes larger than FSOT_LOCAL_MAX are written out
// for the global radix sort (transport_large.comp finishes them). Included by
// scripts/spirv.sh as TRANSPORT (fixed point, deterministic) and TRANSPORT_FLOAT, and
// for d >= 3 (f64 targets) as TRANSPORT_DIMS and TRANSPORT_DIMS_FLOAT.
// variant FLOAT: FSOT_FLOAT_ATOMICS
// variant DIMS: FSOT_ANY_DIMS
// variant DIMS_FLOAT: FSOT_ANY_DIMS FSOT_FLOAT_ATOMICS
// variant DIMS_DF: FSOT_ANY_DIMS FSOT_DF32
// variant DIMS_DF_FLOAT: FSOT_ANY_DIMS FSOT_DF32 FSOT_FLOAT_ATOMICS
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
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
// Largest class sorted in shared memory (src/optimize/vulkan/shape.rs: LOCAL_MAX).
layout(constant_id = 3) const uint FSOT_LOCAL_MAX = 2048u;
// Classes larger than FSOT_LOCAL_MAX and at most FSOT_DEFER_MAX are listed for a
// second pass (0: none) instead of the large-class stage's global sorts: the
// same shader made with FSOT_FROM_LIST, a larger FSOT_LOCAL_MAX and more
// invocations, one workgroup per listed slice (src/optimize/vulkan/shape.rs: defer_max).
// The few classes past the first pass's limit then cost neither the global
// sorts nor the first pass's occupancy (its shared memory).
layout(constant_id = 4) const uint FSOT_DEFER_MAX = 0u;
layout(constant_id = 5) const bool FSOT_FROM_LIST = false;
// Workgroups of the second pass at most (65535, the least maxComputeWorkGroupCount
// a device gives; less in tests): past it, each workgroup takes several listed
// slices (src/optimize/vulkan/shape.rs: DEFER_GROUPS).
layout(constant_id = 6) const uint FSOT_DEFER_GROUPS = 65535u;
// Classes that fit one subgroup taken by the first subgroup alone (true where
// the targets are in closed form, d <= 2; src/optimize/vulkan/shape.rs: subgroup_classes).
layout(constant_id = 7) const bool FSOT_SUBGROUP_CLASSES = true;

void sync() {
    if (ONE_SUBGROUP) {
        subgroupBarrier();
    } else {
        barrier();
    }
}

// Pairs sharing a bucket in one invocation's run of buckets, per bucket of the
// run plus sixteen, above which the bucket sort leaves the class to the bitonic
// network (src/optimize/vulkan/shape.rs: GROUP_INSERTION_BUDGET).
#define FSOT_INSERTION_BUDGET 4u
// Members one invocation gathers: at most ceil(FSOT_LOCAL_MAX / workgroup).
const uint FSOT_PER_INVOCATION = (FSOT_LOCAL_MAX + gl_WorkGroupSize.x - 1u) / gl_WorkGroupSize.x;

shared float s_key[FSOT_LOCAL_MAX];
shared uint s_val[FSOT_LOCAL_MAX];
// Per bucket, 16 bits, two a word (bucket b in word b / 2, the odd one above):
// its members, then its first position (both at most FSOT_LOCAL_MAX). Half the
// words of one counter a word: shared memory is what bounds how many
// workgroups a GPU keeps resident.
shared uint s_count[(FSOT_LOCAL_MAX + 1u) / 2u];
shared uint s_sub[gl_WorkGroupSize.x]; // per subgroup: its invocations' members
shared uint s_fallback;
shared int s_large;
shared float s_part[gl_WorkGroupSize.x];

// Sends the member of rank i towards `target`; its squared distance.
float send(FsotSlice s, uint i, float target) {
    float delta = target - s_key[i];
    fsot_add_displacement(s_val[i], pc.dims, delta, s.theta);
    return delta * delta;
}

// Exclusive prefix of `value` over the workgroup: a subgroup scan, then the
// totals of the subgroups before this one.
uint group_exclusive(uint value) {
    uint total = subgroupAdd(value);
    if (subgroupElect()) {
        s_sub[gl_SubgroupID] = total;
    }
    sync();
    uint before = 0u;
    for (uint k = 0u; k < gl_SubgroupID; ++k) {
        before += s_sub[k];
    }
    return before + subgroupExclusiveAdd(value);
}

// Bitonic network over s_key / s_val[0, n), padded with +inf to a power of two:
// the bucket sort's fallback where keys pile into few buckets. Each invocation
// takes pairs, not elements: pair t joins i (bit j clear) and i + j.
void bitonic_sort(uint n, uint tid, uint wg) {
    uint p2 = 2u;
    while (p2 < n) { p2 <<= 1; }
    for (uint i = n + tid; i < p2; i += wg) {
        s_key[i] = uintBitsToFloat(0x7f800000u); // +inf pads sort last
        s_val[i] = 0xffffffffu;
    }
    sync();
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
}

// Sorts the class into s_key / s_val[0, n) by projection, ties by point (the
// CPU's order). A bucket sort: each member's projection and bucket computed
// once (n buckets over the projections' range, which the members fill about
// evenly), its place in the bucket taken by a shared atomic, the buckets' first
// positions by a workgroup scan, the members written there; then each
// invocation sorts its run of buckets by insertion, where only keys within a
// bucket can be out of order. The result is the one total order whatever
// order the atomics took, so the same as a comparison sort's, in a handful of
// barriers where a bitonic network takes log2(n) (log2(n) + 1) / 2. Where keys
// pile into few buckets (degenerate samples), the bitonic network instead.
void sort_class(FsotSlice s, FsotTargets z, uint n, uint tid, uint wg) {
    float low = fsot_targets_low(z);
    float scale = float(n) / max(fsot_targets_width(z), 1e-30);
    uint words = (n + 1u) / 2u;
    for (uint w = tid; w < words; w += wg) {
        s_count[w] = 0u;
    }
    if (tid == 0u) {
        s_fallback = 0u;
    }
    sync();
    float key[FSOT_PER_INVOCATION];
    uint point[FSOT_PER_INVOCATION];
    uint slot[FSOT_PER_INVOCATION]; // bucket, and place within it above bit 16
    // Loops bounded by the constant FSOT_PER_INVOCATION (known when the
    // pipeline is made, so a GPU's compiler can unroll them and keep the
    // arrays in registers) and left at the class's end.
    uint mine = 0u;
    for (uint m = 0u; m < FSOT_PER_INVOCATION; ++m) {
        uint i = tid + m * wg;
        if (i >= n) {
            break;
        }
        uint p = fsot_class_point(s, i);
        float k = fsot_project(s, p);
        uint b = fsot_bucket(k, low, scale, n);
        key[m] = k;
        point[m] = p;
        uint shift = (b & 1u) * 16u;
        uint place = (atomicAdd(s_count[b >> 1], 1u << shift) >> shift) & 0xffffu;
        slot[m] = b | (place << 16);
        mine = m + 1u;
    }
    sync();
    // Invocation tid owns a run of `chunk` buckets, an even number so that it
    // owns whole words [w0, w1): their members, then (from the scan) each
    // one's first position.
    uint chunk = ((n + wg - 1u) / wg + 1u) & ~1u;
    uint w0 = min(tid * chunk / 2u, words), w1 = min(w0 + chunk / 2u, words);
    uint members = 0u;
    uint pairs = 0u; // pairs sharing a bucket: at most this many insertion moves
    for (uint w = w0; w < w1; ++w) {
        uint c0 = s_count[w] & 0xffffu, c1 = s_count[w] >> 16;
        members += c0 + c1;
        pairs += c0 * (c0 - min(c0, 1u)) / 2u + c1 * (c1 - min(c1, 1u)) / 2u;
    }
    uint first = group_exclusive(members);
    uint at = first;
    for (uint w = w0; w < w1; ++w) {
        uint c0 = s_count[w] & 0xffffu, c1 = s_count[w] >> 16;
        s_count[w] = at | ((at + c0) << 16);
        at += c0 + c1;
    }
    if (pairs > FSOT_INSERTION_BUDGET * (chunk + 16u)) {
        atomicOr(s_fallback, 1u);
    }
    sync();
    for (uint m = 0u; m < FSOT_PER_INVOCATION; ++m) {
        if (m >= mine) {
            break;
        }
        uint b = slot[m] & 0xffffu;
        uint at_m = ((s_count[b >> 1] >> ((b & 1u) * 16u)) & 0xffffu) + (slot[m] >> 16);
        s_key[at_m] = key[m];
        s_val[at_m] = point[m];
    }
    sync();
    if (s_fallback != 0u) {
        bitonic_sort(n, tid, wg);
        return;
    }
    for (uint i = first + 1u; i < first + members; ++i) {
        float k = s_key[i];
        uint v = s_val[i];
        uint j = i;
        while (j > first && fsot_before(k, v, s_key[j - 1u], s_val[j - 1u])) {
            s_key[j] = s_key[j - 1u];
            s_val[j] = s_val[j - 1u];
            --j;
        }
        s_key[j] = k;
        s_val[j] = v;
    }
    sync();
}

// Lists `slice` for the second pass, one more workgroup of its dispatch while
// they are fewer than FSOT_DEFER_GROUPS. The list holds every slice of an
// iteration, so it is never full; were it, the class would be counted as
// dropped, as a large class without room.
void defer_slice(uint slice) {
    uint at = atomicAdd(deferred_count, 1u);
    if (at >= pc.deferred_capacity) {
        atomicAdd(large_overflow, 1u);
        return;
    }
    deferred_slices[at] = slice;
    if (at < FSOT_DEFER_GROUPS) {
        atomicAdd(deferred_groups[0], 1u);
    }
}

#ifndef FSOT_ANY_DIMS
// A class that fits one subgroup (d <= 2: its targets in closed form), by the
// first subgroup alone, with no workgroup barrier: each lane takes one member,
// its rank is the count of members before it in the total order (projection,
// ties by point: the CPU's), read from shared memory behind a subgroup
// barrier, and its target that rank's. The other subgroups have nothing to do.
// The same ranks as the sort's, so the same displacements.
void subgroup_class(FsotSlice s, uint n) {
    if (gl_SubgroupID != 0u) {
        return;
    }
    uint lane = gl_SubgroupInvocationID;
    bool mine = lane < n;
    uint point = 0u;
    float key = 0.0;
    if (mine) {
        point = fsot_class_point(s, lane);
        key = fsot_project(s, point);
        s_key[lane] = key;
        s_val[lane] = point;
    }
    subgroupBarrier();
    float cost = 0.0;
    if (mine) {
        uint rank = 0u;
        for (uint j = 0u; j < n; ++j) {
            rank += fsot_before(s_key[j], s_val[j], key, point) ? 1u : 0u;
        }
        float delta = fsot_target(fsot_targets(s), rank, n) - key;
        fsot_add_displacement(point, pc.dims, delta, s.theta);
        cost = delta * delta;
    }
    float total = subgroupAdd(cost);
    if (subgroupElect()) {
        fsot_add_cost(pc.cost_slot, total, n);
    }
}
#endif

// Every invocation draws the slice and finds its class size itself (the same
// arithmetic, so the same values), where one invocation drawing it for the
// others through shared memory would cost a barrier.
void process_slice(uint slice) {
    uint tid = gl_LocalInvocationID.x;
    uint wg = gl_WorkGroupSize.x;
    FsotSlice s = fsot_draw_slice(pc.slice_key, pc.axis_bits, pc.pair_bits, pc.iteration, slice, pc.dims, pc.width, pc.height, pc.frames);
    uint n = fsot_class_size(s);
    if (n < 2u) {
        return;
    }
    if (n > FSOT_LOCAL_MAX) {
        if (tid == 0u) {
            s_large = -1;
            if (n <= FSOT_DEFER_MAX) {
                defer_slice(slice);
                s_large = -2; // listed (or dropped): nothing to write out
            } else {
                s_large = fsot_reserve_large(slice, n);
            }
        }
        sync();
        if (s_large >= 0) {
            for (uint i = tid; i < n; i += wg) {
                fsot_write_large(s, uint(s_large), i);
            }
        }
        return;
    }
#ifndef FSOT_ANY_DIMS
    // (A workgroup smaller than a subgroup has only that many lanes.)
    if (FSOT_SUBGROUP_CLASSES && n <= min(gl_SubgroupSize, gl_WorkGroupSize.x)) {
        subgroup_class(s, n);
        return;
    }
#endif
    FsotTargets z = fsot_targets(s);
#ifdef FSOT_ANY_DIMS
    // The subset sums, before the sort, whose barriers then cover them.
    fsot_fill_breaks(z, tid, wg);
#endif
    sort_class(s, z, n, tid, wg);
    float local_cost = 0.0;
#ifdef FSOT_ANY_DIMS
    // Each invocation walks a run of the lower half's ranks (each quantile from
    // the last), sending rank q and its mirror n - 1 - q.
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
    // The class's cost: a subgroup sum, then one invocation adds the
    // subgroups' in order (one barrier where a tree over the workgroup takes
    // log2 of its size).
    float part = subgroupAdd(local_cost);
    if (subgroupElect()) {
        s_part[gl_SubgroupID] = part;
    }
    sync();
    if (tid == 0u) {
        // The subgroups counted from their size: on lavapipe, gl_NumSubgroups
        // leaves out the partial last subgroup of 100 invocations (the cost
        // would come out 1% low).
        uint subgroups = (wg + gl_SubgroupSize - 1u) / gl_SubgroupSize;
        float cost = 0.0;
        for (uint k = 0u; k < subgroups; ++k) {
            cost += s_part[k];
        }
        fsot_add_cost(pc.cost_slot, cost, n);
    }
}

void main() {
    if (schedule.stopped != 0u) {
        return; // the stopping rule ended the run (the same for every invocation)
    }
    uint group = gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
    if (FSOT_FROM_LIST) {
        // The second pass: workgroup p takes the listed slices p, p + G, ...
        // (G the dispatch's workgroups: as many as listed, at most
        // FSOT_DEFER_GROUPS).
        uint listed = min(deferred_count, pc.deferred_capacity);
        uint groups = gl_NumWorkGroups.x * gl_NumWorkGroups.y;
        for (uint k = group; k < listed; k += groups) {
            if (k != group) {
                sync(); // shared memory is reused by the next slice
            }
            process_slice(deferred_slices[k]);
        }
        fsot_check_loop_cap();
        return;
    }
    for (uint k = 0u; k < SLICES_PER_GROUP; ++k) {
        uint slice = group * SLICES_PER_GROUP + k;
        if (slice >= pc.slices) {
            break;
        }
        process_slice(slice);
        if (k + 1u < SLICES_PER_GROUP) {
            sync(); // shared memory is reused by the next slice
        }
    }
    fsot_check_loop_cap();
}
