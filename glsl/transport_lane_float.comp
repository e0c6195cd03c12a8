#version 450
// Per-invocation transport (CPU Vulkan implementations), float atomic accumulators.
#extension GL_EXT_shader_explicit_arithmetic_types_int64 : require
#extension GL_EXT_shader_atomic_int64 : require
#extension GL_EXT_shader_atomic_float : require
#define FSOT_FLOAT_ATOMICS
#include "transport_lane_body.glsl"
