#version 450
// Update pass reading float accumulators.
#define FSOT_FLOAT_ATOMICS
#include "update_body.glsl"
