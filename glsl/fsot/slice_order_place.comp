#version 450
// The slice order's second pass (slice_order.glsl): one workgroup per iteration
// of the batch (row k) turns its bins' counts into first positions and places
// every slice at its bin's next position. Within a bin the order is whatever the
// atomics make it: the transport's sums do not depend on it.
#include "bindings.glsl"
layout(push_constant) uniform Push { TransportPush pc; };
#include "transport_common.glsl"
#include "slice_order.glsl"

layout(local_size_x = 64) in;

shared uint next_rank[FSOT_ORDER_BINS];

void main() {
    uint k = gl_WorkGroupID.y;
    if (gl_LocalInvocationIndex == 0u) {
        uint total = 0u;
        for (uint b = 0u; b < FSOT_ORDER_BINS; ++b) {
            next_rank[b] = total;
            total += slice_order[fsot_order_bin_at(k, b)];
        }
    }
    barrier();
    for (uint slice = gl_LocalInvocationIndex; slice < pc.slices; slice += gl_WorkGroupSize.x) {
        uint rank = atomicAdd(next_rank[slice_order[fsot_order_key_at(k, slice)]], 1u);
        slice_order[fsot_order_rank_at(k, rank)] = slice;
    }
}
