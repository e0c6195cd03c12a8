// Every buffer, push-constant struct and binding index of the swap passes (the
// peers' swap search, src/peers/swap/mod.rs), declared once. Mirrored once in
// Rust (src/peers/swap/vulkan.rs, `layout`); tests/spirv_layout.rs checks the compiled
// SPIR-V against the mirror. Both passes use this one layout.
#ifndef SWAP_BINDINGS_GLSL
#define SWAP_BINDINGS_GLSL
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "../fsot/rng.glsl"

#define SWAP_BINDING_VALUES 0
#define SWAP_BINDING_OFFSETS 1
#define SWAP_BINDING_PROPOSALS 2
#define SWAP_BINDING_CLAIMS 3
#define SWAP_BINDING_STATS 4
#define SWAP_BINDINGS 5

// Largest sample dimension (the value term's loop is unrolled to it).
#define SWAP_MAX_DIMS 8
// The sample dimension, a specialization constant (constant 0 is the
// workgroup size): loops over it unroll to exactly its length.
layout(constant_id = 1) const uint SWAP_DIMS = 1u;
// Fixed-point scale of the energy change summed in SwapStats: 2^32.
#define SWAP_ENERGY_SCALE 4294967296.0
// ValueTerm: exp(-|a - b|^(d/2) / sigma^2), or -|a - b|.
#define SWAP_TERM_GAUSSIAN 0u
#define SWAP_TERM_NEG_DISTANCE 1u

// One batch of proposals.
struct SwapPush {
    uint width;
    uint height;
    uint frames;
    uint offsets;      // entries of Offsets
    uint term;         // SWAP_TERM_*
    float inv_sigma2;  // 1 / sigma^2 of the Gaussian term
    float temperature; // 0: greedy
    uint pass_key;     // rng::derive(search key, pass): the pass's proposal stream
    uint first;        // index in the pass of the batch's first proposal
    uint count;        // proposals in the batch
    uint batch;        // rounds recorded so far in the pass, from 1: tags the claims
    uint retry;        // 0: the batch's first round; else a round over its dropped proposals
    uint last;         // 1: the batch's last round (a proposal dropped now stays rejected)
};

// A weight at an offset of the wrapping tile (each component in [0, size)).
struct SwapOffset {
    uint dx;
    uint dy;
    uint dt;
    float weight;
};

// Where a proposal of the batch stands.
#define SWAP_REJECTED 0u
#define SWAP_TAKEN 1u
#define SWAP_DROPPED 2u
#define SWAP_APPLIED 3u

// One proposal of the batch: the pair, its energy change on the values of its
// round's start, and where it stands (SWAP_*).
struct SwapProposal {
    uint p;
    uint q;
    float delta;
    uint state;
};

// What a pass did (zeroed before it).
struct SwapStats {
    int64_t energy;   // summed change of the taken swaps, SWAP_ENERGY_SCALE fixed point
    uint accepted;
    uint dropped;     // taken, but an earlier swap of the round moved what they read, in the last round
    uint uphill;
    uint retried;     // the same, in an earlier round: evaluated again in the next
};

layout(std430, binding = SWAP_BINDING_VALUES) buffer Values { float values[]; };
layout(std430, binding = SWAP_BINDING_OFFSETS) readonly buffer Offsets { SwapOffset offsets[]; };
layout(std430, binding = SWAP_BINDING_PROPOSALS) buffer Proposals { SwapProposal proposals[]; };
// Per pixel: (batch << 32) | (~index) of the earliest taken proposal of the
// latest batch that swaps it (atomicMax), so older batches' tags lose.
layout(std430, binding = SWAP_BINDING_CLAIMS) buffer Claims { uint64_t claims[]; };
layout(std430, binding = SWAP_BINDING_STATS) buffer Stats { SwapStats stats; };

// (x, y, frame) of pixel p.
uvec3 swap_coords(uint p, SwapPush pc) {
    return uvec3(p % pc.width, (p / pc.width) % pc.height, p / (pc.width * pc.height));
}

// The pixel at offset o from (x, y, frame).
uint swap_neighbour(uvec3 at, SwapOffset o, SwapPush pc) {
    uint x = at.x + o.dx, y = at.y + o.dy, f = at.z + o.dt;
    x = x >= pc.width ? x - pc.width : x;
    y = y >= pc.height ? y - pc.height : y;
    f = f >= pc.frames ? f - pc.frames : f;
    return (f * pc.height + y) * pc.width + x;
}

#endif
