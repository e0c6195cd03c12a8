#version 450
// The stopping rule on the device, one invocation after each iteration: the
// same f64 operations as the host's (src/core/step_rule.rs: PlateauState::observe,
// and Until::Objective in src/optimize/run.rs). It takes the iteration's objective
// estimate from its cost slot; every `window` iterations it closes a window,
// multiplies the step scale by `factor` when the window gained less than
// `decay_below`, and ends the run when, with the scale at its floor, a window
// gained less than `stop_below`, or when a window's mean reached the target.
// Once ended, every pass does nothing, so a submission may run past the end.
// Needs shaderFloat64.
#include "bindings.glsl"

layout(local_size_x = 1) in;
layout(push_constant) uniform Push { PlateauPush pc; };

void main() {
    if (schedule.stopped != 0u) {
        return;
    }
    int64_t members = costs[2u * pc.slot + 1u];
    precise double objective =
        members > 0 ? double(costs[2u * pc.slot]) / double(FSOT_COST_SCALE) / double(members) : 0.0LF;
    precise double sum = packDouble2x32(schedule.sum) + objective;
    uint count = schedule.count + 1u;
    if (count < max(schedule.window, 1u)) {
        schedule.sum = unpackDouble2x32(sum);
        schedule.count = count;
        return;
    }
    // A window's end.
    precise double mean = sum / double(count);
    precise double previous = packDouble2x32(schedule.previous);
    bool had = schedule.has_previous != 0u;
    schedule.previous = unpackDouble2x32(mean);
    schedule.has_previous = 1u;
    schedule.sum = uvec2(0u);
    schedule.count = 0u;
    bool stop = false;
    // The host's gain is NaN for the first window, and for 0 / 0: it then
    // decides nothing (every comparison with NaN is false).
    if (had && !(previous == 0.0LF && mean == 0.0LF)) {
        precise double gain = (previous - mean) / previous;
        if (schedule.scale <= schedule.floor_scale) {
            stop = gain < packDouble2x32(schedule.stop_below);
        } else if (gain < packDouble2x32(schedule.decay_below)) {
            precise float scaled = schedule.scale * schedule.factor;
            schedule.scale = max(scaled, schedule.floor_scale);
        }
    }
    if (schedule.has_target != 0u && mean <= packDouble2x32(schedule.target)) {
        stop = true;
    }
    if (stop) {
        schedule.stopped = 1u;
        schedule.stop_iteration = pc.iteration + 1u;
    }
}
