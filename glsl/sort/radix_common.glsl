// Shared by the radix sort passes: the bindings, the launch shape and the sizes
// derived from the element count.
#include "bindings.glsl"

layout(local_size_x_id = 0) in;
layout(constant_id = 1) const uint ITEMS = 8u;
layout(push_constant) uniform Push { RadixPush pc; };

uint block_size() { return gl_WorkGroupSize.x * ITEMS; }

// Blocks and scan chunks: given by the host, or (0) derived from the element
// count the GPU produced, matching the indirect dispatch sizes of radix_args.comp.
uint radix_blocks() { return pc.blocks != 0u ? pc.blocks : max(1u, (count + block_size() - 1u) / block_size()); }
uint radix_chunks() { return pc.chunks != 0u ? pc.chunks : (256u * radix_blocks() + block_size() - 1u) / block_size(); }
