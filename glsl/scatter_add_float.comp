#version 450
// Scatter benchmark, float atomic accumulators (VK_EXT_shader_atomic_float).
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_EXT_shader_atomic_float : require
#define FSOT_FLOAT_ATOMICS
#include "scatter_add_body.glsl"
