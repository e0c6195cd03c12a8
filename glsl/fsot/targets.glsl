// Exact 1-D targets for any d (1 to 8), in f64: the projection of the uniform
// hypercube on theta (a box spline), mirrored from src/targets.rs, which explains
// the inclusion-exclusion form, its conditioning rule and the rank means. Only the
// FSOT_ANY_DIMS variants include it; they need shaderFloat64, which the host
// checks. d <= 2 keeps the float32 closed form of common.glsl.
#ifndef FSOT_TARGETS_GLSL
#define FSOT_TARGETS_GLSL

// Condition number above which the smallest components are replaced by their
// mean (src/targets.rs: MAX_CONDITION).
#define FSOT_MAX_CONDITION 1e8LF
// Newton steps per quantile at most (src/targets.rs allows 200; a bracketed
// Newton from a guess below the root needs far fewer, and lavapipe's loop
// budget is short).
#define FSOT_NEWTON_MAX 60u

struct FsotBox {
    double a[FSOT_MAX_DIMS]; // kept |theta_k|, ascending
    uint degree;             // how many are kept
    double norm_f;           // 1 / (d! prod a)
    double norm_i;           // 1 / ((d+1)! prod a)
    double total;            // support [0, total] before the shift
    double offset;           // where the support starts on the real line
};

double fsot_factorial(uint n) {
    double f = 1.0LF;
    for (uint k = 2u; k <= n; ++k) { f *= double(k); }
    return f;
}

// (sum a)^d / (d! prod a) over a[first..degree): the inclusion-exclusion sum's
// relative error bound.
double fsot_box_condition(double a[FSOT_MAX_DIMS], uint first, uint degree) {
    double sum = 0.0LF, prod = 1.0LF;
    for (uint k = first; k < degree; ++k) { sum += a[k]; prod *= a[k]; }
    double power = 1.0LF;
    for (uint k = first; k < degree; ++k) { power *= sum; }
    return power / (fsot_factorial(degree - first) * prod);
}

FsotBox fsot_box(float theta[FSOT_MAX_DIMS], uint dims) {
    FsotBox z;
    z.offset = 0.0LF;
    uint kept = 0u;
    for (uint k = 0u; k < FSOT_MAX_DIMS; ++k) { z.a[k] = 0.0LF; }
    for (uint k = 0u; k < dims; ++k) {
        double t = double(theta[k]);
        if (t < 0.0LF) { z.offset += t; }
        // Insertion into the ascending list of nonzero components.
        if (t != 0.0LF) {
            double v = abs(t);
            uint j = kept;
            while (j > 0u && z.a[j - 1u] > v) { z.a[j] = z.a[j - 1u]; --j; }
            z.a[j] = v;
            ++kept;
        }
    }
    // Drop the smallest while the formula is ill-conditioned (kept >= 1: the
    // host never draws a zero direction).
    uint first = 0u;
    while (kept - first > 1u && fsot_box_condition(z.a, first, kept) > FSOT_MAX_CONDITION) {
        z.offset += 0.5LF * z.a[first];
        ++first;
    }
    z.degree = kept - first;
    for (uint k = 0u; k < z.degree; ++k) { z.a[k] = z.a[k + first]; }
    for (uint k = z.degree; k < FSOT_MAX_DIMS; ++k) { z.a[k] = 0.0LF; }
    double prod = 1.0LF;
    z.total = 0.0LF;
    for (uint k = 0u; k < z.degree; ++k) { prod *= z.a[k]; z.total += z.a[k]; }
    z.norm_f = 1.0LF / (fsot_factorial(z.degree) * prod);
    z.norm_i = 1.0LF / (fsot_factorial(z.degree + 1u) * prod);
    return z;
}

// The subset sums b_S (S a bitmask of the kept components), with sign
// (-1)^|S|. Shared by a workgroup (FSOT_SHARED_BREAKS) or private to an
// invocation. Filled once per slice: loops count against lavapipe's budget of
// 65535 iterations per invocation, so evaluations must not rebuild them.
#ifdef FSOT_SHARED_BREAKS
shared double fsot_breaks[1u << FSOT_MAX_DIMS];
#else
double fsot_breaks[1u << FSOT_MAX_DIMS];
#endif

// Subset sum of mask m, the components added in ascending order (as the CPU).
double fsot_subset_sum(FsotBox z, uint m) {
    double b = 0.0LF;
    for (uint k = 0u; k < z.degree; ++k) {
        if ((m & (1u << k)) != 0u) { b += z.a[k]; }
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
    fsot_breaks[0] = 0.0LF;
    for (uint m = 1u; m < (1u << z.degree); ++m) {
        uint top = uint(findMSB(m));
        fsot_breaks[m] = fsot_breaks[m ^ (1u << top)] + z.a[top];
    }
}

// x^p for p = 0..7 without a loop.
double fsot_power(double x, uint p) {
    double x2 = x * x;
    double r = (p & 1u) != 0u ? x : 1.0LF;
    if ((p & 2u) != 0u) { r *= x2; }
    if ((p & 4u) != 0u) { r *= x2 * x2; }
    return r;
}

// F, its density and its integral I at s (local coordinates, 0 <= s <= total):
// every subset S adds (-1)^|S| (s - b_S)_+^d. One loop of 2^d.
dvec3 fsot_box_eval(FsotBox z, double s) {
    double f = 0.0LF, dens = 0.0LF, integ = 0.0LF;
    for (uint m = 0u; m < (1u << z.degree); ++m) {
        double x = s - fsot_breaks[m];
        if (x <= 0.0LF) { continue; }
        double xd1 = fsot_power(x, z.degree - 1u);
        double sign = (bitCount(m) & 1) == 0 ? 1.0LF : -1.0LF;
        dens += sign * xd1;
        f += sign * xd1 * x;
        integ += sign * xd1 * x * x;
    }
    return dvec3(f * z.norm_f, dens * z.norm_f * double(z.degree), integ * z.norm_i);
}

// Solves F(s) = u for u <= 1/2 (local coordinates) from `guess`, with Newton
// steps kept inside a shrinking bracket (src/targets.rs: local_quantile); also
// gives the density at the last point evaluated.
double fsot_box_quantile(FsotBox z, double u, double guess, out double dens) {
    double lo = 0.0LF, hi = 0.5LF * z.total;
    double s = clamp(guess, lo, hi);
    dens = 0.0LF;
    for (uint it = 0u; it < FSOT_NEWTON_MAX; ++it) {
        dvec3 e = fsot_box_eval(z, s);
        dens = e.y;
        double err = e.x - u;
        if (abs(err) <= 1e-15LF) { break; }
        if (err < 0.0LF) { lo = s; } else { hi = s; }
        double newton = e.y > 0.0LF ? s - err / e.y : lo - 1.0LF;
        s = (newton > lo && newton < hi) ? newton : 0.5LF * (lo + hi);
        if (hi - lo <= 1e-15LF * z.total) { break; }
    }
    return s;
}

// Partial first moment G(s) = s F(s) - I(s).
double fsot_box_moment(FsotBox z, double s) {
    dvec3 e = fsot_box_eval(z, s);
    return s * e.x - e.z;
}

// A starting point below the quantile of u: below every break but 0, F(s) is
// s^d / (d! prod a), and beyond them F is smaller, so this s never overshoots.
double fsot_box_guess(FsotBox z, double u) {
    float root = pow(float(u / z.norm_f), 1.0 / float(z.degree));
    return min(double(root), 0.5LF * z.total);
}

// A walk over consecutive ranks of the lower half (q < n / 2), each quantile
// solved from the last (src/targets.rs: rank_targets): the quantile, G and the
// density at the lower end of rank `next`.
struct FsotWalk { double q; double g; double dens; uint next; };

FsotWalk fsot_walk(FsotBox z, uint n, uint first) {
    FsotWalk w;
    w.next = first;
    w.q = 0.0LF;
    w.g = 0.0LF;
    w.dens = 0.0LF;
    if (first > 0u) {
        double u = double(first) / double(n);
        w.q = fsot_box_quantile(z, u, fsot_box_guess(z, u), w.dens);
        w.g = fsot_box_moment(z, w.q);
    }
    return w;
}

// The local mean of rank w.next's quantile interval; steps to the next rank.
double fsot_walk_step(FsotBox z, uint n, inout FsotWalk w) {
    double nf = double(n);
    double u = double(w.next + 1u) / nf;
    double guess = w.next == 0u ? fsot_box_guess(z, u)
                 : (w.dens > 0.0LF ? w.q + (1.0LF / nf) / w.dens : w.q);
    double q = fsot_box_quantile(z, u, guess, w.dens);
    double g = fsot_box_moment(z, q);
    double mean = nf * (g - w.g);
    w.q = q;
    w.g = g;
    w.next += 1u;
    return mean;
}

// Targets on the real line of lower-half rank q (local mean m) and of its
// mirror n - 1 - q.
float fsot_box_low_target(FsotBox z, double m) { return float(z.offset + m); }
float fsot_box_high_target(FsotBox z, double m) { return float(z.offset + z.total - m); }
// The middle rank of an odd n.
float fsot_box_centre(FsotBox z) { return float(z.offset + 0.5LF * z.total); }

#endif
