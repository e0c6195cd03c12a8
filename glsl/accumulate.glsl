// Adding a class member's displacement and a class's cost, shared by every
// transport pass. Include after declaring `acc` (int64 fixed point, or float with
// FSOT_FLOAT_ATOMICS) and `costs`.

const float FIXED_SCALE = 1099511627776.0; // 2^40, as src/cpu.rs
const float COST_SCALE = 4294967296.0;     // 2^32

// The member `point` moves by delta along theta.
void fsot_add_displacement(uint point, uint dims, float delta, float theta[FSOT_MAX_DIMS]) {
    uint base = point * dims;
    for (uint k = 0u; k < dims; ++k) {
        float t = theta[k];
        if (t != 0.0) {
#ifdef FSOT_FLOAT_ATOMICS
            atomicAdd(acc[base + k], delta * t);
#else
            atomicAdd(acc[base + k], int64_t(round(delta * t * FIXED_SCALE)));
#endif
        }
    }
}

// A class of n members whose squared distances to their targets sum to `squared`.
void fsot_add_cost(uint slot, float squared, uint n) {
    atomicAdd(costs[2u * slot], int64_t(round(squared * COST_SCALE)));
    atomicAdd(costs[2u * slot + 1u], int64_t(n));
}
