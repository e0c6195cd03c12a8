// The number type of the exact targets for d >= 3 (targets.glsl): f64 where the
// device has shaderFloat64, or with FSOT_DF32 a pair of float32s (hi + lo,
// |lo| <= ulp(hi) / 2: about 48 significant bits) made only of float32
// arithmetic, for devices without it. The error-free transformations (Knuth's
// two-sum, Dekker's split product) are `precise`, so no compiler may reassociate
// or fuse them. Every operation is a function, so targets.glsl is written
// once for both.
#ifndef FSOT_REAL_GLSL
#define FSOT_REAL_GLSL

#ifdef FSOT_DF32

#define FsotReal vec2

FsotReal r_of(float x) { return vec2(x, 0.0); }
float r_float(FsotReal a) { return a.x + a.y; }

// s + e == a + b exactly (Knuth).
vec2 fsot_two_sum(float a, float b) {
    precise float s = a + b;
    precise float v = s - a;
    precise float e = (a - (s - v)) + (b - v);
    return vec2(s, e);
}
// s + e == a + b exactly when |a| >= |b|.
vec2 fsot_quick_two_sum(float a, float b) {
    precise float s = a + b;
    precise float e = b - (s - a);
    return vec2(s, e);
}
FsotReal r_add(FsotReal a, FsotReal b) {
    vec2 s = fsot_two_sum(a.x, b.x);
    vec2 t = fsot_two_sum(a.y, b.y);
    precise float e = s.y + t.x;
    vec2 u = fsot_quick_two_sum(s.x, e);
    precise float f = t.y + u.y;
    return fsot_quick_two_sum(u.x, f);
}
FsotReal r_neg(FsotReal a) { return -a; }
FsotReal r_sub(FsotReal a, FsotReal b) { return r_add(a, -b); }
// hi + lo == a exactly, each with at most 12 significant bits (Dekker), so
// their products are exact in float32.
vec2 fsot_split(float a) {
    precise float t = 4097.0 * a;
    precise float hi = t - (t - a);
    precise float lo = a - hi;
    return vec2(hi, lo);
}
// p + e == a * b exactly (Dekker's product: no fma, which some drivers
// lower to a rounded multiply and add).
vec2 fsot_two_prod(float a, float b) {
    precise float p = a * b;
    vec2 x = fsot_split(a), y = fsot_split(b);
    precise float e = ((x.x * y.x - p) + x.x * y.y + x.y * y.x) + x.y * y.y;
    return vec2(p, e);
}
FsotReal r_mul(FsotReal a, FsotReal b) {
    vec2 p = fsot_two_prod(a.x, b.x);
    precise float f = p.y + (a.x * b.y + a.y * b.x);
    return fsot_quick_two_sum(p.x, f);
}
FsotReal r_div(FsotReal a, FsotReal b) {
    float q1 = a.x / b.x;
    FsotReal r = r_sub(a, r_mul(b, r_of(q1)));
    float q2 = r.x / b.x;
    r = r_sub(r, r_mul(b, r_of(q2)));
    float q3 = r.x / b.x;
    vec2 q = fsot_quick_two_sum(q1, q2);
    return r_add(q, r_of(q3));
}
bool r_lt(FsotReal a, FsotReal b) { return a.x < b.x || (a.x == b.x && a.y < b.y); }
bool r_le(FsotReal a, FsotReal b) { return !r_lt(b, a); }
FsotReal r_abs(FsotReal a) { return r_lt(a, r_of(0.0)) ? -a : a; }

#else

#define FsotReal double

FsotReal r_of(float x) { return double(x); }
float r_float(FsotReal a) { return float(a); }
FsotReal r_add(FsotReal a, FsotReal b) { return a + b; }
FsotReal r_neg(FsotReal a) { return -a; }
FsotReal r_sub(FsotReal a, FsotReal b) { return a - b; }
FsotReal r_mul(FsotReal a, FsotReal b) { return a * b; }
FsotReal r_div(FsotReal a, FsotReal b) { return a / b; }
bool r_lt(FsotReal a, FsotReal b) { return a < b; }
bool r_le(FsotReal a, FsotReal b) { return a <= b; }
FsotReal r_abs(FsotReal a) { return abs(a); }

#endif

FsotReal r_of_uint(uint n) {
    // Exact for n < 2^24 in both forms (ranks and class sizes are far below).
    return r_of(float(n));
}

#endif
