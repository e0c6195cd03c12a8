#version 450
// A whole radix pass for small counts in one workgroup (one dispatch per pass
// instead of four: histogram, scan and scatter fused): the digit counts of every
// pair, their exclusive scan, then the blocks in order, each placed stably by
// radix_place.glsl after the runs of the blocks before it. Nothing waits on
// another workgroup, so it is correct on lavapipe too.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_EXT_control_flow_attributes : require
#include "radix_common.glsl"
#include "radix_place.glsl"

shared uint s_next[256]; // where the next block's first digit d goes

void main() {
    uint tid = gl_LocalInvocationID.x;
    uint wg = gl_WorkGroupSize.x;
    for (uint d = tid; d < 256u; d += wg) { s_local[d] = 0u; }
    barrier();
    for (uint i = tid; i < count; i += wg) {
        atomicAdd(s_local[(keys_in[i] >> pc.shift) & 255u], 1u);
    }
    barrier();
    scan_local(false);
    barrier();
    for (uint d = tid; d < 256u; d += wg) { s_next[d] = s_local[d]; }
    barrier();
    for (uint base = 0u; base < count; base += block_size()) {
        uint key[ITEMS];
        uint val[ITEMS];
        load_block(base, key, val);
        for (uint d = tid; d < 256u; d += wg) { s_local[d] = 0u; }
        barrier();
        count_block(base, key);
        barrier();
        for (uint d = tid; d < 256u; d += wg) {
            s_dest[d] = s_next[d];
            s_next[d] += s_local[d];
        }
        barrier();
        place_block(base, key, val);
        barrier();
    }
}
