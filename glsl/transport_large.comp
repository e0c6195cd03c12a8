#version 450
// Large-class transport with fixed-point (int64) accumulators.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#include "transport_large_body.glsl"
