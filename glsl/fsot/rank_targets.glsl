// The exact targets of a slice's ranks, in whichever form the variant takes
// (the direction's box: fsot_targets; the projections' range):
// FSOT_ANY_DIMS (d = 1 to 8, box spline in f64 or, with FSOT_DF32, float32
// pairs: targets.glsl) or the float32 closed
// form for d <= 2 (common.glsl). Include after the pass's push constants `pc`.
#ifndef FSOT_RANK_TARGETS_GLSL
#define FSOT_RANK_TARGETS_GLSL
#ifdef FSOT_ANY_DIMS
#include "targets.glsl"
#define FsotTargets FsotBox
FsotTargets fsot_targets(FsotSlice s) { return fsot_box(s.theta, pc.dims); }
// (Ranks: a walk over the lower half, fsot_walk; each pass splits it.)
// The projections' range: [low, low + width].
float fsot_targets_low(FsotTargets z) { return r_float(z.offset); }
float fsot_targets_width(FsotTargets z) { return r_float(z.total); }
#else
#define FsotTargets FsotTrapezoid
FsotTargets fsot_targets(FsotSlice s) { return fsot_trapezoid(s.theta[0], s.theta[1]); }
float fsot_target(FsotTargets z, uint r, uint n) { return fsot_rank_target(z, r, n); }
float fsot_targets_low(FsotTargets z) { return z.offset; }
float fsot_targets_width(FsotTargets z) { return z.a1 + z.a2; }
#endif
#endif
