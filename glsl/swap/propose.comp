#version 450
// Pass 1 of a round, one proposal per invocation. In the batch's first round:
// the pair and the uniform number drawn from the pass's stream as the CPU path
// draws them (proposal g reads counters 4g to 4g + 3); in a later round, only
// the proposals the last round dropped. Each: its energy change on the values
// as they stand at the round's start, the decision (improving, or uphill by
// Metropolis at the pass's temperature), and for a taken swap a claim on both
// its pixels.
#include "bindings.glsl"
#include "energy.glsl"

layout(local_size_x_id = 0) in;
layout(push_constant) uniform Push { SwapPush pc; };

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= pc.count || (pc.retry != 0u && proposals[i].state != SWAP_DROPPED)) {
        return;
    }
    uint n = pc.width * pc.height * pc.frames;
    FsotStream s = FsotStream(pc.pass_key, 4u * (pc.first + i));
    uint p = fsot_below(s, n);
    uint q = (p + 1u + fsot_below(s, n - 1u)) % n;
    float u = fsot_unit(fsot_next(s));
    float delta = swap_delta(p, q, pc);
    bool take = delta < 0.0 || (pc.temperature > 0.0 && u < exp(-delta / pc.temperature));
    proposals[i] = SwapProposal(p, q, delta, take ? SWAP_TAKEN : SWAP_REJECTED);
    if (take) {
        uint64_t tag = (uint64_t(pc.batch) << 32) | uint64_t(~i);
        atomicMax(claims[p], tag);
        atomicMax(claims[q], tag);
    }
}
