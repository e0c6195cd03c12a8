// The loop-cap check of the transport passes (transport.comp, transport_lane.comp,
// transport_large.comp). Include after bindings.glsl and the pass's push-constant
// block `pc` (TransportPush).
#ifndef FSOT_LOOP_CAP_GLSL
#define FSOT_LOOP_CAP_GLSL

// Lavapipe runs an invocation's loops for 65535 iterations in
// all and then drops the rest silently, which would leave a class's targets as
// garbage. The passes are budgeted to stay under it (src/optimize/vulkan/shape.rs); this
// last loop, of a run-time count of at least 3, checks it: past the cap a loop
// still runs its first iteration, and no more (on llvmpipe a count of 1 does
// not tell), and the batch's count of cut invocations fails the run on the
// host.
void fsot_check_loop_cap() {
    uint want = pc.spp + 2u;
    uint ran = 0u;
    for (uint i = 0u; i < want; ++i) {
        ran += 1u;
    }
    if (ran != want) {
        atomicAdd(loop_cut, 1u);
    }
}

#endif
