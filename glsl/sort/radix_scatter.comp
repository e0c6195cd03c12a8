#version 450
// Radix pass 3 of 3: stable scatter, one block per workgroup, placed by
// radix_place.glsl at the positions the scanned histogram gives.
//
// Every key and payload of the block is loaded into registers first, in one
// burst, so their memory latency is paid once per block and overlaps the
// histogram reads (the subgroup barriers of the ranking order memory too, so a
// load left inside that loop waits on each of them in turn).
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_EXT_control_flow_attributes : require
#include "radix_common.glsl"
#include "radix_place.glsl"

void main() {
    uint tid = gl_LocalInvocationID.x;
    uint block = gl_WorkGroupID.x;
    uint base = block * block_size();
    if (base >= count) {
        return; // whole workgroup: nothing to place
    }
    // The block's pairs, loaded first in one burst.
    uint key[ITEMS];
    uint val[ITEMS];
    load_block(base, key, val);
    // The block's count of digit d is the next scanned entry minus this one
    // (entries are digit-major; the one after the last is the total).
    for (uint d = tid; d < 256u; d += gl_WorkGroupSize.x) {
        uint e = d * radix_blocks() + block;
        uint next = e + 1u < 256u * radix_blocks() ? hist[e + 1u] : count;
        s_dest[d] = hist[e];
        s_local[d] = next - hist[e];
    }
    barrier();
    place_block(base, key, val);
}
