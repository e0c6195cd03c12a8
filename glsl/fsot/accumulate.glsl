// Adding displacements and costs into the accumulators (bindings.glsl), shared by
// every transport pass and the scatter benchmark.

// Adds `value` to accumulator `index`.
void fsot_add_component(uint index, float value) {
#ifdef FSOT_FLOAT_ATOMICS
    atomicAdd(acc[index], value);
#else
    atomicAdd(acc[index], int64_t(round(value * FSOT_FIXED_SCALE)));
#endif
}

// The member `point` moves by delta along theta (components 0 and 1 written
// out, as fsot_project; the rest in the FSOT_ANY_DIMS variants).
void fsot_add_displacement(uint point, uint dims, float delta, float theta[FSOT_MAX_DIMS]) {
    uint base = point * dims;
    if (theta[0] != 0.0) {
        fsot_add_component(base, delta * theta[0]);
    }
    if (dims > 1u && theta[1] != 0.0) {
        fsot_add_component(base + 1u, delta * theta[1]);
    }
#ifdef FSOT_ANY_DIMS
    for (uint k = 2u; k < dims; ++k) {
        if (theta[k] != 0.0) {
            fsot_add_component(base + k, delta * theta[k]);
        }
    }
#endif
}

// A class of n members whose squared distances to their targets sum to `squared`.
void fsot_add_cost(uint slot, float squared, uint n) {
    atomicAdd(costs[2u * slot], int64_t(round(squared * FSOT_COST_SCALE)));
    atomicAdd(costs[2u * slot + 1u], int64_t(n));
}
