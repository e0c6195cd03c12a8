#version 450
// Pass 2 of a round, one proposal per invocation: a taken swap is applied unless
// an earlier taken swap of the round claims a pixel it reads or moves (its
// change would be stale); that one is dropped, to be evaluated again in the
// next round, or for good in the last. The swaps applied are pairwise apart (the
// offsets are symmetric), so each one's change, made on the round's starting
// values, is exact, and none reads what another writes.
#include "bindings.glsl"
#extension GL_EXT_control_flow_attributes : require

layout(local_size_x_id = 0) in;
layout(push_constant) uniform Push { SwapPush pc; };

// Does an earlier taken swap of this round claim pixel r?
bool claimed_before(uint r, uint64_t mine) {
    return claims[r] > mine;
}

// ... pixel p, or any pixel its energy terms read?
bool reach_claimed(uint p, uint64_t mine) {
    if (claimed_before(p, mine)) {
        return true;
    }
    uvec3 at = swap_coords(p, pc);
    for (uint k = 0u; k < pc.offsets; k++) {
        if (claimed_before(swap_neighbour(at, offsets[k], pc), mine)) {
            return true;
        }
    }
    return false;
}

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count || proposals[i].state != SWAP_TAKEN) {
        return;
    }
    SwapProposal s = proposals[i];
    uint64_t mine = (uint64_t(pc.batch) << 32) | uint64_t(~i);
    if (reach_claimed(s.p, mine) || reach_claimed(s.q, mine)) {
        if (pc.last != 0u) {
            proposals[i].state = SWAP_REJECTED;
            atomicAdd(stats.dropped, 1u);
        } else {
            proposals[i].state = SWAP_DROPPED;
            atomicAdd(stats.retried, 1u);
        }
        return;
    }
    proposals[i].state = SWAP_APPLIED;
    [[unroll]] for (uint k = 0u; k < SWAP_DIMS; k++) {
        float v = values[s.p * SWAP_DIMS + k];
        values[s.p * SWAP_DIMS + k] = values[s.q * SWAP_DIMS + k];
        values[s.q * SWAP_DIMS + k] = v;
    }
    atomicAdd(stats.energy, int64_t(round(s.delta * SWAP_ENERGY_SCALE)));
    atomicAdd(stats.accepted, 1u);
    if (s.delta > 0.0) {
        atomicAdd(stats.uphill, 1u);
    }
}
