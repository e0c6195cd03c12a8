// The stable placement of one block (shared by radix_scatter.comp and
// radix_small.comp): the block's elements are ranked and placed in shared memory in
// digit order, then written out in that order, so consecutive invocations write
// consecutive addresses of each digit's run (coalesced), instead of every store
// of a subgroup touching up to 32 runs.
//
// Ranking: a block is walked in rounds of WG x KEYS elements; in a round each
// subgroup owns a contiguous chunk of S x KEYS elements, taken KEYS slots of S at
// a time, so (subgroup, slot, lane) is input order. An element's rank among equal
// digits comes from subgroup ballots (lanes of its slot with the same digit and a
// lower index), the digit's count in the subgroup's earlier slots, in earlier
// subgroups and in earlier rounds: equal keys keep their order.
//
// Include after radix_common.glsl, with the subgroup extensions enabled.
#ifndef SORT_PLACE_GLSL
#define SORT_PLACE_GLSL

// Subgroups per workgroup: WG / the device's subgroup size (the host queries it).
layout(constant_id = 2) const uint SUBGROUPS = 8u;
// Keys per invocation per round (ITEMS must be a multiple).
#define KEYS 8u
// Pairs per block (WG x ITEMS): sizes the staging arrays.
layout(constant_id = 3) const uint BLOCK = 2048u;


shared uint s_dest[256];   // set by the caller: where the block's first digit d goes (then minus its staged start)
shared uint s_local[256];  // set by the caller: the block's count of digit d (then where it starts, staged)
shared uint s_seen[256];   // digit d's count in earlier rounds
shared uint s_round[256];
shared uint s_sub[SUBGROUPS * 256u];
shared uint s_stage_k[BLOCK];
shared uint s_stage_v[BLOCK];

// Lanes of the subgroup whose (valid) digit equals this lane's: eight ballots,
// on one word where the subgroup fits in 32 lanes (portable, where
// subgroupPartitionNV is an NVIDIA extension).
uvec4 same_digit(uint digit, bool valid) {
    if (gl_SubgroupSize <= 32u) {
        uint same = subgroupBallot(valid).x;
        for (uint b = 0u; b < 8u; ++b) {
            bool bit = ((digit >> b) & 1u) == 1u;
            uint ones = subgroupBallot(bit).x;
            same &= bit ? ones : ~ones;
        }
        return uvec4(same, 0u, 0u, 0u);
    }
    uvec4 same = subgroupBallot(valid);
    for (uint b = 0u; b < 8u; ++b) {
        bool bit = ((digit >> b) & 1u) == 1u;
        uvec4 ones = subgroupBallot(bit);
        same &= bit ? ones : ~ones;
    }
    return same;
}


// Exclusive scan of the 256 digit counts in s_local, by the first subgroup; with
// `dest`, each digit's start is also taken off s_dest (so s_dest + staged index
// is the output address). A barrier must follow.
void scan_local(bool dest) {
    if (gl_SubgroupID == 0u) {
        uint per = (256u + gl_SubgroupSize - 1u) / gl_SubgroupSize;
        uint first = gl_SubgroupInvocationID * per;
        uint sum = 0u;
        for (uint j = 0u; j < per; ++j) {
            if (first + j < 256u) { sum += s_local[first + j]; }
        }
        uint run = subgroupExclusiveAdd(sum);
        for (uint j = 0u; j < per; ++j) {
            if (first + j < 256u) {
                uint c = s_local[first + j];
                s_local[first + j] = run;
                if (dest) { s_dest[first + j] -= run; }
                run += c;
            }
        }
    }
}

// Slot j = round x KEYS + k of this invocation: the index of its element.
uint place_index(uint base, uint j) {
    return base + (j / KEYS) * gl_WorkGroupSize.x * KEYS + gl_SubgroupID * gl_SubgroupSize * KEYS
        + (j % KEYS) * gl_SubgroupSize + gl_SubgroupInvocationID;
}

// Loads the block starting at `base` into this invocation's slots, in one
// burst (zeros past the count).
void load_block(uint base, out uint key[ITEMS], out uint val[ITEMS]) {
    [[unroll]] for (uint j = 0u; j < ITEMS; ++j) {
        uint i = place_index(base, j);
        key[j] = i < count ? keys_in[i] : 0u;
        val[j] = i < count ? vals_in[i] : 0u;
    }
}

// Adds the block's digit counts (its keys in this invocation's slots) into
// s_local, which the caller zeroed; a barrier must follow.
void count_block(uint base, uint key[ITEMS]) {
    [[unroll]] for (uint j = 0u; j < ITEMS; ++j) {
        if (place_index(base, j) < count) {
            atomicAdd(s_local[(key[j] >> pc.shift) & 255u], 1u);
        }
    }
}

// Places the block starting at `base` (its pairs in this invocation's slots)
// where s_dest and s_local say. Called by the whole workgroup.
void place_block(uint base, uint key[ITEMS], uint val[ITEMS]) {
    uint tid = gl_LocalInvocationID.x;
    uint wg = gl_WorkGroupSize.x;
    uint sg = gl_SubgroupID;
    uint lane = gl_SubgroupInvocationID;
    uint sgsize = gl_SubgroupSize;
    uint len = min(block_size(), count - base);
    for (uint d = tid; d < 256u; d += wg) {
        s_seen[d] = 0u;
        s_round[d] = 0u;
    }
    barrier();
    scan_local(true);
    barrier();
    [[unroll]] for (uint r = 0u; r < ITEMS / KEYS; ++r) {
        // Phase A: fold the previous round into the counts; clear the counters.
        for (uint d = tid; d < 256u; d += wg) { s_seen[d] += s_round[d]; }
        for (uint j = tid; j < SUBGROUPS * 256u; j += wg) { s_sub[j] = 0u; }
        barrier();
        // Phase B: ranks within the subgroup's chunk, slot by slot.
        uint chunk = base + r * wg * KEYS + sg * sgsize * KEYS;
        uint digit[KEYS];
        uint rank[KEYS];
        bool valid[KEYS];
        [[unroll]] for (uint k = 0u; k < KEYS; ++k) {
            valid[k] = chunk + k * sgsize + lane < count;
            digit[k] = (key[r * KEYS + k] >> pc.shift) & 255u;
            uvec4 same = same_digit(digit[k], valid[k]);
            uint below = subgroupBallotExclusiveBitCount(same);
            uint prior = valid[k] ? s_sub[sg * 256u + digit[k]] : 0u;
            rank[k] = prior + below;
            subgroupBarrier();
            if (valid[k] && below == 0u) {
                s_sub[sg * 256u + digit[k]] = prior + subgroupBallotBitCount(same);
            }
            subgroupBarrier();
        }
        barrier();
        // Phase C: per digit, exclusive prefix over subgroups; the round's total.
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
        // Phase D: stage in digit order.
        [[unroll]] for (uint k = 0u; k < KEYS; ++k) {
            if (valid[k]) {
                uint d = digit[k];
                uint pos = s_local[d] + s_seen[d] + s_sub[sg * 256u + d] + rank[k];
                s_stage_k[pos] = key[r * KEYS + k];
                s_stage_v[pos] = val[r * KEYS + k];
            }
        }
        barrier();
    }
    // Write the staged block out: runs of equal digits go to consecutive addresses.
    for (uint i = tid; i < len; i += wg) {
        uint k = s_stage_k[i];
        uint dst = s_dest[(k >> pc.shift) & 255u] + i;
        keys_out[dst] = k;
        vals_out[dst] = s_stage_v[i];
    }
}

#endif
