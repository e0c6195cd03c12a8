#version 450
// A whole radix pass in one dispatch (decoupled look-back): each workgroup takes
// the next block in start order (a ticket), counts its digits, publishes them,
// then, digit by digit, adds up the counts of the blocks before it, walking back
// until a block that published its inclusive prefix, and publishes its own;
// then it places its block stably (radix_place.glsl) at the digit's start over
// all pairs (lb_digits, scanned here) plus that prefix. A workgroup waits only on
// blocks that started before it, so it needs a device on which a started
// workgroup goes on running while another waits: GPUs, not lavapipe with several
// threads (src/vk/sort.rs: SortPath::LookBack).
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_EXT_control_flow_attributes : require
#include "radix_common.glsl"
#include "radix_place.glsl"

shared uint s_block;

void main() {
    uint tid = gl_LocalInvocationID.x;
    uint wg = gl_WorkGroupSize.x;
    uint pass = pc.shift / 8u;
    if (tid == 0u) {
        s_block = atomicAdd(lb_ticket[pass], 1u);
    }
    // Each digit's start over all pairs: the exclusive scan of this pass's counts.
    for (uint d = tid; d < 256u; d += wg) { s_local[d] = lb_digits[pass * 256u + d]; }
    barrier();
    scan_local(false);
    barrier();
    uint block = s_block;
    uint base = block * block_size();
    if (base >= count) {
        return; // whole workgroup
    }
    for (uint d = tid; d < 256u; d += wg) {
        s_dest[d] = s_local[d];
        s_local[d] = 0u;
    }
    uint key[ITEMS];
    uint val[ITEMS];
    load_block(base, key, val);
    barrier();
    count_block(base, key);
    barrier();
    for (uint d = tid; d < 256u; d += wg) {
        uint own = s_local[d];
        uint status = block * 256u + d;
        if (block == 0u) {
            atomicExchange(lb_status[status], LB_PREFIX | own);
            continue;
        }
        atomicExchange(lb_status[status], LB_AGGREGATE | own);
        uint before = 0u;
        uint q = block - 1u;
        for (;;) {
            uint word = atomicAdd(lb_status[q * 256u + d], 0u);
            if (word == 0u) {
                continue; // block q has not published yet
            }
            before += word & LB_COUNT;
            if ((word & LB_PREFIX) != 0u) {
                break;
            }
            q -= 1u;
        }
        atomicExchange(lb_status[status], LB_PREFIX | (before + own));
        s_dest[d] += before;
    }
    barrier();
    place_block(base, key, val);
}
