#version 450
// Scatter benchmark, fixed-point (int64) accumulators: bit-identical run to run.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "scatter_add_body.glsl"
