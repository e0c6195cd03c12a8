#version 450
// Radix pass 3 of 3: stable scatter. Each block walks its elements in rounds of
// WG (input order); within a round an element's rank among equal digits comes
// from subgroup ballots (lanes with the same digit and a lower index) plus the
// counts of earlier subgroups and earlier rounds, so equal keys keep their order.
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_ballot : require
#include "radix_common.glsl"

// Subgroups per workgroup: WG / the device's subgroup size (the host queries it).
layout(constant_id = 2) const uint SUBGROUPS = 8u;

layout(std430, set = 0, binding = 1) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, set = 0, binding = 2) readonly buffer ValsIn { uint vals_in[]; };
layout(std430, set = 0, binding = 3) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, set = 0, binding = 4) writeonly buffer ValsOut { uint vals_out[]; };
layout(std430, set = 0, binding = 5) readonly buffer Hist { uint hist[]; };

shared uint s_offset[256];
shared uint s_round[256];
shared uint s_sub[SUBGROUPS * 256u];

void main() {
    uint tid = gl_LocalInvocationID.x;
    uint wg = gl_WorkGroupSize.x;
    uint block = gl_WorkGroupID.x;
    uint sg = gl_SubgroupID;
    if (block * block_size() >= count) {
        return; // whole workgroup: nothing to place
    }
    for (uint d = tid; d < 256u; d += wg) { s_offset[d] = hist[d * pc.blocks + block]; }
    uint base = block * block_size();
    for (uint it = 0u; it < ITEMS; ++it) {
        for (uint j = tid; j < SUBGROUPS * 256u; j += wg) { s_sub[j] = 0u; }
        barrier();
        uint i = base + it * wg + tid;
        bool valid = i < count;
        uint key = valid ? keys_in[i] : 0u;
        uint digit = (key >> pc.shift) & 255u;
        uvec4 same = subgroupBallot(valid);
        for (uint b = 0u; b < 8u; ++b) {
            bool bit = ((digit >> b) & 1u) == 1u;
            uvec4 ones = subgroupBallot(bit);
            same &= bit ? ones : ~ones;
        }
        uint below = subgroupBallotExclusiveBitCount(same);
        if (valid && below == 0u) {
            s_sub[sg * 256u + digit] = subgroupBallotBitCount(same);
        }
        barrier();
        for (uint d = tid; d < 256u; d += wg) {
            uint run = 0u;
            for (uint s = 0u; s < SUBGROUPS; ++s) {
                uint c = s_sub[s * 256u + d];
                s_sub[s * 256u + d] = run;
                run += c;
            }
            s_round[d] = run;
        }
        barrier();
        if (valid) {
            uint dst = s_offset[digit] + s_sub[sg * 256u + digit] + below;
            keys_out[dst] = key;
            vals_out[dst] = vals_in[i];
        }
        barrier();
        for (uint d = tid; d < 256u; d += wg) { s_offset[d] += s_round[d]; }
        barrier();
    }
}
