#version 450
// The slice order's second pass (slice_order.glsl): one workgroup per iteration
// of the batch (row k) turns its bins' counts into first positions and places
// every slice at its bin's next position. Within a bin the order is whatever the
// atomics make it: the transport's sums do not depend on it. Its first
// invocation also writes the slot's chunk plan for the per-lane transport.
#include "bindings.glsl"
layout(push_constant) uniform Push { TransportPush pc; };
#include "transport_common.glsl"
#include "slice_order.glsl"

layout(local_size_x = 64) in;

shared uint next_rank[FSOT_ORDER_BINS];

// Slot k's chunk plan: each tier's slices (its bins' counts, in rank order),
// then its rounds, as many as the lane table allows at its cost and no more
// than a chunk needs to hold the aimed-at share of the whole iteration's cost
// (so that there are about as many chunks as the table aims at, where the
// costs allow: few workgroups, each of which a CPU implementation starts at a
// price, yet enough for its threads to share), and so its chunks of
// lanes x rounds slices; then the transport's dispatch.
void write_plan(uint k) {
    uint lanes = slice_order[FSOT_LANE_TABLE_LANES];
    for (uint b = 0u; b < FSOT_ORDER_BINS; ++b) {
        uint t = slice_order[fsot_lane_table_tier(b)];
        slice_order[fsot_lane_tier_at(k, t) + 2u] += slice_order[fsot_order_bin_at(k, b)];
    }
    float total = 0.0;
    for (uint t = 0u; t < FSOT_LANE_TIERS; ++t) {
        float slices = float(slice_order[fsot_lane_tier_at(k, t) + 2u]);
        total += slices / float(lanes) * float(slice_order[fsot_lane_table_cost(t)]);
    }
    float share = total / float(max(slice_order[FSOT_LANE_TABLE_AIM], 1u));
    uint chunks = 0u;
    uint ranks = 0u;
    for (uint t = 0u; t < FSOT_LANE_TIERS; ++t) {
        uint at = fsot_lane_tier_at(k, t);
        uint slices = slice_order[at + 2u];
        float fit = share / float(slice_order[fsot_lane_table_cost(t)]);
        uint rounds = clamp(uint(min(fit, 4.0e9)), 1u, slice_order[fsot_lane_table_most(t)]);
        slice_order[at] = chunks;
        slice_order[at + 1u] = ranks;
        slice_order[at + 3u] = rounds;
        chunks += (slices + lanes * rounds - 1u) / (lanes * rounds);
        ranks += slices;
    }
    uint plan = fsot_lane_plan_at(k);
    uint x = clamp(chunks, 1u, 65535u);
    slice_order[plan + 1u] = x;
    slice_order[plan + 2u] = (chunks + x - 1u) / x;
    slice_order[plan + 3u] = 1u;
    slice_order[plan + 4u] = chunks;
}

void main() {
    uint k = gl_WorkGroupID.y;
    if (gl_LocalInvocationIndex == 0u) {
        uint total = 0u;
        for (uint b = 0u; b < FSOT_ORDER_BINS; ++b) {
            next_rank[b] = total;
            total += slice_order[fsot_order_bin_at(k, b)];
        }
        write_plan(k);
    }
    barrier();
    for (uint slice = gl_LocalInvocationIndex; slice < pc.slices; slice += gl_WorkGroupSize.x) {
        uint rank = atomicAdd(next_rank[fsot_order_bin(slice_order[fsot_order_key_at(k, slice)])], 1u);
        slice_order[fsot_order_rank_at(k, rank)] = slice;
    }
}
