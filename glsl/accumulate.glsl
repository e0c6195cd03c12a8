// Adding a contribution to a sample's accumulator, shared by every transport pass
// and the scatter benchmark. Include after declaring `acc` (int64 fixed point, or
// float with FSOT_FLOAT_ATOMICS).

const float FIXED_SCALE = 1099511627776.0; // 2^40, as src/cpu.rs

// Adds `value` to accumulator `index`.
void fsot_add_component(uint index, float value) {
#ifdef FSOT_FLOAT_ATOMICS
    atomicAdd(acc[index], value);
#else
    atomicAdd(acc[index], int64_t(round(value * FIXED_SCALE)));
#endif
}

// The member `point` moves by delta along theta (d <= 2, as fsot_project).
void fsot_add_displacement(uint point, uint dims, float delta, float theta[FSOT_MAX_DIMS]) {
    uint base = point * dims;
    if (theta[0] != 0.0) {
        fsot_add_component(base, delta * theta[0]);
    }
    if (dims > 1u && theta[1] != 0.0) {
        fsot_add_component(base + 1u, delta * theta[1]);
    }
}
