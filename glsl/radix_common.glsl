// Shared by the radix sort passes: an LSD sort of 32-bit keys with 32-bit
// payloads, 8 bits per pass, reduce-then-scan (no cross-workgroup waiting, so it
// is correct on drivers without forward progress between workgroups, lavapipe
// included). A block is WG x ITEMS consecutive elements; block b's count of digit
// d lives at hist[d * blocks + b], so one exclusive scan of hist gives every
// (digit, block) its first output position. The element count is read from a
// buffer so a producer on the GPU can set it.
#include "common.glsl"

layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint ITEMS = 8u;

layout(std430, set = 0, binding = 0) readonly buffer Info { uint count; };

struct RadixPush {
    uint shift;   // bit offset of this pass's digit
    uint blocks;  // blocks in the dispatch (hist has 256 x blocks entries); 0: from count
    uint chunks;  // scan chunks (workgroups of scan_reduce / scan_apply); 0: from count
    uint pad;
};
layout(push_constant) uniform Push { RadixPush pc; };

uint block_size() { return gl_WorkGroupSize.x * ITEMS; }

// Blocks and scan chunks: given by the host, or (0) derived from the element
// count the GPU produced, matching the indirect dispatch sizes of sort_args.comp.
uint radix_blocks() { return pc.blocks != 0u ? pc.blocks : max(1u, (count + block_size() - 1u) / block_size()); }
uint radix_chunks() { return pc.chunks != 0u ? pc.chunks : (256u * radix_blocks() + block_size() - 1u) / block_size(); }
