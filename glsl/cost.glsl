// Adding a class's transport cost, shared by every transport pass. Include after
// declaring `costs` (per slot: squared distances in 2^32 fixed point, count).

const float COST_SCALE = 4294967296.0; // 2^32

// A class of n members whose squared distances to their targets sum to `squared`.
void fsot_add_cost(uint slot, float squared, uint n) {
    atomicAdd(costs[2u * slot], int64_t(round(squared * COST_SCALE)));
    atomicAdd(costs[2u * slot + 1u], int64_t(n));
}
