// Adding a class member's displacement and a class's cost, shared by every
// transport pass. Include after declaring `acc` (int64 fixed point, or float with
// FSOT_FLOAT_ATOMICS) and `costs`.

const float FIXED_SCALE = 1099511627776.0; // 2^40, as src/cpu.rs
const float COST_SCALE = 4294967296.0;     // 2^32

// The member `point` moves by delta along theta (d <= 2, as fsot_project).
void fsot_add_component(uint index, float value) {
#ifdef FSOT_FLOAT_ATOMICS
    atomicAdd(acc[index], value);
#else
    atomicAdd(acc[index], int64_t(round(value * FIXED_SCALE)));
#endif
}

void fsot_add_displacement(uint point, uint dims, float delta, float theta[FSOT_MAX_DIMS]) {
    uint base = point * dims;
    if (theta[0] != 0.0) {
        fsot_add_component(base, delta * theta[0]);
    }
    if (dims > 1u && theta[1] != 0.0) {
        fsot_add_component(base + 1u, delta * theta[1]);
    }
}

// A class of n members whose squared distances to their targets sum to `squared`.
void fsot_add_cost(uint slot, float squared, uint n) {
    atomicAdd(costs[2u * slot], int64_t(round(squared * COST_SCALE)));
    atomicAdd(costs[2u * slot + 1u], int64_t(n));
}
