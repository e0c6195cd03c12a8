#version 450
// Update pass reading fixed-point (int64) accumulators.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#include "update_body.glsl"
