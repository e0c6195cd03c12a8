// The energy change of a swap (src/peers/swap/mod.rs: PairEnergy::swap_delta),
// shared by the swap passes. The value term's loop over dimensions unrolls (its
// length is a specialization constant: no loop iterations against lavapipe's
// per-invocation budget); the loop over offsets runs offsets iterations.
#ifndef SWAP_ENERGY_GLSL
#define SWAP_ENERGY_GLSL
#extension GL_EXT_control_flow_attributes : require

// The value term of a (held in registers) against the values of pixel r.
float swap_phi(float a[SWAP_MAX_DIMS], uint r, SwapPush pc) {
    uint base = r * SWAP_DIMS;
    float d2 = 0.0;
    [[unroll]] for (uint k = 0u; k < SWAP_DIMS; k++) {
        float e = a[k] - values[base + k];
        d2 += e * e;
    }
    if (pc.term == SWAP_TERM_NEG_DISTANCE) {
        return -sqrt(d2);
    }
    // |a - b|^(d/2) = (|a - b|^2)^(d/4)
    float r2 = SWAP_DIMS == 1u ? sqrt(sqrt(d2)) : SWAP_DIMS == 2u ? sqrt(d2) : SWAP_DIMS == 4u ? d2 : pow(d2, float(SWAP_DIMS) * 0.25);
    return exp(-r2 * pc.inv_sigma2);
}

// The values of pixel p, in registers.
void swap_load(uint p, out float a[SWAP_MAX_DIMS], SwapPush pc) {
    [[unroll]] for (uint k = 0u; k < SWAP_DIMS; k++) {
        a[k] = values[p * SWAP_DIMS + k];
    }
}

// The change of the energy if the values of p and q (p != q) were swapped.
float swap_delta(uint p, uint q, SwapPush pc) {
    float a[SWAP_MAX_DIMS], b[SWAP_MAX_DIMS];
    swap_load(p, a, pc);
    swap_load(q, b, pc);
    uvec3 at_p = swap_coords(p, pc), at_q = swap_coords(q, pc);
    float delta = 0.0;
    for (uint k = 0u; k < pc.offsets; k++) {
        SwapOffset o = offsets[k];
        uint r = swap_neighbour(at_p, o, pc);
        if (r != q) {
            delta += o.weight * (swap_phi(b, r, pc) - swap_phi(a, r, pc));
        }
        r = swap_neighbour(at_q, o, pc);
        if (r != p) {
            delta += o.weight * (swap_phi(a, r, pc) - swap_phi(b, r, pc));
        }
    }
    return 2.0 * delta;
}

#endif
