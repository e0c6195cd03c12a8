// Exact 1-D targets for any d (1 to 8): the projection of the uniform hypercube
// on theta (a box spline), mirrored from src/core/targets.rs, which explains the
// inclusion-exclusion form, its conditioning rule and the rank means. Only the
// FSOT_ANY_DIMS variants include it. Written once in the number type of
// real.glsl: f64 (shaderFloat64), or with FSOT_DF32 pairs of float32s for
// devices without it (48 bits against 53: Newton stops sooner, below). d <= 2
// keeps the float32 closed form of common.glsl.
#ifndef FSOT_TARGETS_GLSL
#define FSOT_TARGETS_GLSL
#include "real.glsl"

// Condition number above which the smallest components are replaced by their
// mean (src/core/targets.rs: MAX_CONDITION; the same rule in both number types, so
// both keep the CPU's components), and Newton's tolerances on F and on the
// bracket (relative to the support): float32 pairs stop sooner, at what their 48
// bits can resolve.
#define FSOT_MAX_CONDITION 1e8
#ifdef FSOT_DF32
#define FSOT_F_TOL vec2(1e-13, 0.0)
#define FSOT_BRACKET_TOL vec2(1e-13, 0.0)
#else
#define FSOT_F_TOL 1e-15LF
#define FSOT_BRACKET_TOL 1e-15LF
#endif
// Newton steps per quantile at most (src/core/targets.rs allows 200; a bracketed
// Newton from a guess below the root needs far fewer, and lavapipe's loop
// budget is short).
#define FSOT_NEWTON_MAX 60u

struct FsotBox {
    FsotReal a[FSOT_MAX_DIMS]; // kept |theta_k|, ascending
    uint degree;               // how many are kept
    FsotReal norm_f;           // 1 / (d! prod a)
    FsotReal norm_i;           // 1 / ((d+1)! prod a)
    FsotReal total;            // support [0, total] before the shift
    FsotReal offset;           // where the support starts on the real line
};

FsotReal fsot_factorial(uint n) {
    FsotReal f = r_of(1.0);
    for (uint k = 2u; k <= n; ++k) { f = r_mul(f, r_of_uint(k)); }
    return f;
}

// (sum a)^d / (d! prod a) over a[first..degree): the inclusion-exclusion sum's
// relative error bound.
FsotReal fsot_box_condition(FsotReal a[FSOT_MAX_DIMS], uint first, uint degree) {
    FsotReal sum = r_of(0.0), prod = r_of(1.0);
    for (uint k = first; k < degree; ++k) { sum = r_add(sum, a[k]); prod = r_mul(prod, a[k]); }
    FsotReal power = r_of(1.0);
    for (uint k = first; k < degree; ++k) { power = r_mul(power, sum); }
    return r_div(power, r_mul(fsot_factorial(degree - first), prod));
}

FsotBox fsot_box(float theta[FSOT_MAX_DIMS], uint dims) {
    FsotBox z;
    z.offset = r_of(0.0);
    uint kept = 0u;
    for (uint k = 0u; k < FSOT_MAX_DIMS; ++k) { z.a[k] = r_of(0.0); }
    for (uint k = 0u; k < dims; ++k) {
        float t = theta[k];
        if (t < 0.0) { z.offset = r_add(z.offset, r_of(t)); }
        // Insertion into the ascending list of nonzero components.
        if (t != 0.0) {
            FsotReal v = r_of(abs(t));
            uint j = kept;
            while (j > 0u && r_lt(v, z.a[j - 1u])) { z.a[j] = z.a[j - 1u]; --j; }
            z.a[j] = v;
            ++kept;
        }
    }
    // Drop the smallest while the formula is ill-conditioned (kept >= 1: the
    // host never draws a zero direction).
    uint first = 0u;
    while (kept - first > 1u && r_lt(r_of(FSOT_MAX_CONDITION), fsot_box_condition(z.a, first, kept))) {
        z.offset = r_add(z.offset, r_mul(r_of(0.5), z.a[first]));
        ++first;
    }
    z.degree = kept - first;
    for (uint k = 0u; k < z.degree; ++k) { z.a[k] = z.a[k + first]; }
    for (uint k = z.degree; k < FSOT_MAX_DIMS; ++k) { z.a[k] = r_of(0.0); }
    FsotReal prod = r_of(1.0);
    z.total = r_of(0.0);
    for (uint k = 0u; k < z.degree; ++k) { prod = r_mul(prod, z.a[k]); z.total = r_add(z.total, z.a[k]); }
    z.norm_f = r_div(r_of(1.0), r_mul(fsot_factorial(z.degree), prod));
    z.norm_i = r_div(r_of(1.0), r_mul(fsot_factorial(z.degree + 1u), prod));
    return z;
}

// The subset sums b_S (S a bitmask of the kept components), with sign
// (-1)^|S|. Shared by a workgroup (FSOT_SHARED_BREAKS) or private to an
// invocation. Filled once per slice: loops count against lavapipe's budget of
// 65535 iterations per invocation, so evaluations must not rebuild them.
#ifdef FSOT_SHARED_BREAKS
shared FsotReal fsot_breaks[1u << FSOT_MAX_DIMS];
#else
FsotReal fsot_breaks[1u << FSOT_MAX_DIMS];
#endif

// Subset sum of mask m, the components added in ascending order (as the CPU).
FsotReal fsot_subset_sum(FsotBox z, uint m) {
    FsotReal b = r_of(0.0);
    for (uint k = 0u; k < z.degree; ++k) {
        if ((m & (1u << k)) != 0u) { b = r_add(b, z.a[k]); }
    }
    return b;
}

// Fills entries first, first + step, ... (one invocation of `step`; barrier
// after in a workgroup).
void fsot_fill_breaks(FsotBox z, uint first, uint step) {
    for (uint m = first; m < (1u << z.degree); m += step) {
        fsot_breaks[m] = fsot_subset_sum(z, m);
    }
}

// The same sums in one invocation, one addition each: b_m is b of m without its
// highest bit plus that component, the same additions in the same order.
void fsot_fill_breaks_alone(FsotBox z) {
    fsot_breaks[0] = r_of(0.0);
    for (uint m = 1u; m < (1u << z.degree); ++m) {
        uint top = uint(findMSB(m));
        fsot_breaks[m] = r_add(fsot_breaks[m ^ (1u << top)], z.a[top]);
    }
}

// x^p for p = 0..7 without a loop.
FsotReal fsot_power(FsotReal x, uint p) {
    FsotReal x2 = r_mul(x, x);
    FsotReal r = (p & 1u) != 0u ? x : r_of(1.0);
    if ((p & 2u) != 0u) { r = r_mul(r, x2); }
    if ((p & 4u) != 0u) { r = r_mul(r, r_mul(x2, x2)); }
    return r;
}

// F, its density and its integral I at s (local coordinates, 0 <= s <= total):
// every subset S adds (-1)^|S| (s - b_S)_+^d. One loop of 2^d.
void fsot_box_eval(FsotBox z, FsotReal s, out FsotReal f, out FsotReal dens, out FsotReal integ) {
    FsotReal fs = r_of(0.0), ds = r_of(0.0), is = r_of(0.0);
    for (uint m = 0u; m < (1u << z.degree); ++m) {
        FsotReal x = r_sub(s, fsot_breaks[m]);
        if (r_le(x, r_of(0.0))) { continue; }
        FsotReal xd1 = fsot_power(x, z.degree - 1u);
        FsotReal xd = r_mul(xd1, x);
        FsotReal xd2 = r_mul(xd, x);
        if ((bitCount(m) & 1) == 0) {
            ds = r_add(ds, xd1);
            fs = r_add(fs, xd);
            is = r_add(is, xd2);
        } else {
            ds = r_sub(ds, xd1);
            fs = r_sub(fs, xd);
            is = r_sub(is, xd2);
        }
    }
    f = r_mul(fs, z.norm_f);
    dens = r_mul(r_mul(ds, z.norm_f), r_of_uint(z.degree));
    integ = r_mul(is, z.norm_i);
}

// Solves F(s) = u for u <= 1/2 (local coordinates) from `guess`, with Newton
// steps kept inside a shrinking bracket (src/core/targets.rs: local_quantile); also
// gives the density at the last point evaluated.
FsotReal fsot_box_quantile(FsotBox z, FsotReal u, FsotReal guess, out FsotReal dens) {
    FsotReal lo = r_of(0.0), hi = r_mul(r_of(0.5), z.total);
    FsotReal s = r_lt(guess, lo) ? lo : (r_lt(hi, guess) ? hi : guess);
    dens = r_of(0.0);
    for (uint it = 0u; it < FSOT_NEWTON_MAX; ++it) {
        FsotReal f, integ;
        fsot_box_eval(z, s, f, dens, integ);
        FsotReal err = r_sub(f, u);
        if (r_le(r_abs(err), FSOT_F_TOL)) { break; }
        if (r_lt(err, r_of(0.0))) { lo = s; } else { hi = s; }
        bool step = r_lt(r_of(0.0), dens);
        FsotReal newton = step ? r_sub(s, r_div(err, dens)) : lo;
        s = (step && r_lt(lo, newton) && r_lt(newton, hi)) ? newton : r_mul(r_of(0.5), r_add(lo, hi));
        if (r_le(r_sub(hi, lo), r_mul(FSOT_BRACKET_TOL, z.total))) { break; }
    }
    return s;
}

// Partial first moment G(s) = s F(s) - I(s).
FsotReal fsot_box_moment(FsotBox z, FsotReal s) {
    FsotReal f, dens, integ;
    fsot_box_eval(z, s, f, dens, integ);
    return r_sub(r_mul(s, f), integ);
}

// A starting point below the quantile of u: below every break but 0, F(s) is
// s^d / (d! prod a), and beyond them F is smaller, so this s never overshoots.
FsotReal fsot_box_guess(FsotBox z, FsotReal u) {
    float root = pow(r_float(r_div(u, z.norm_f)), 1.0 / float(z.degree));
    FsotReal half_total = r_mul(r_of(0.5), z.total);
    return r_lt(r_of(root), half_total) ? r_of(root) : half_total;
}

// A walk over consecutive ranks of the lower half (q < n / 2), each quantile
// solved from the last (src/core/targets.rs: rank_targets): the quantile, G and the
// density at the lower end of rank `next`.
struct FsotWalk { FsotReal q; FsotReal g; FsotReal dens; uint next; };

FsotWalk fsot_walk(FsotBox z, uint n, uint first) {
    FsotWalk w;
    w.next = first;
    w.q = r_of(0.0);
    w.g = r_of(0.0);
    w.dens = r_of(0.0);
    if (first > 0u) {
        FsotReal u = r_div(r_of_uint(first), r_of_uint(n));
        w.q = fsot_box_quantile(z, u, fsot_box_guess(z, u), w.dens);
        w.g = fsot_box_moment(z, w.q);
    }
    return w;
}

// The local mean of rank w.next's quantile interval; steps to the next rank.
FsotReal fsot_walk_step(FsotBox z, uint n, inout FsotWalk w) {
    FsotReal nf = r_of_uint(n);
    FsotReal u = r_div(r_of_uint(w.next + 1u), nf);
    FsotReal guess = w.next == 0u ? fsot_box_guess(z, u)
        : (r_lt(r_of(0.0), w.dens) ? r_add(w.q, r_div(r_div(r_of(1.0), nf), w.dens)) : w.q);
    FsotReal q = fsot_box_quantile(z, u, guess, w.dens);
    FsotReal g = fsot_box_moment(z, q);
    FsotReal mean = r_mul(nf, r_sub(g, w.g));
    w.q = q;
    w.g = g;
    w.next += 1u;
    return mean;
}

// Targets on the real line of lower-half rank q (local mean m) and of its
// mirror n - 1 - q.
float fsot_box_low_target(FsotBox z, FsotReal m) { return r_float(r_add(z.offset, m)); }
float fsot_box_high_target(FsotBox z, FsotReal m) { return r_float(r_sub(r_add(z.offset, z.total), m)); }
// The middle rank of an odd n.
float fsot_box_centre(FsotBox z) { return r_float(r_add(z.offset, r_mul(r_of(0.5), z.total))); }

#endif
