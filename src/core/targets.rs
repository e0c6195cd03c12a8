//! Exact 1-D transport targets: the projection of the uniform hypercube [0,1)^d on a
//! unit direction theta, and the mean of its inverse CDF over each rank's quantile
//! interval.
//!
//! theta . U is a sum of scaled uniforms (a box spline). With a_k = |theta_k| and
//! b_S = sum of a_k over a subset S, its CDF is (inclusion-exclusion)
//!
//!   F(s) = sum_S (-1)^|S| (s - b_S)_+^d / (d! prod a_k),
//!
//! on [0, sum a_k], shifted by sum of the negative theta_k. Its partial first moment
//! is G(s) = s F(s) - I(s) with I(s) = sum_S (-1)^|S| (s - b_S)_+^(d+1) / ((d+1)! prod a),
//! so the target of rank r of n (seed eq. 8) is n (G(q_(r+1)) - G(q_r)) with
//! q_r = F^-1(r / n). Everything is evaluated in f64; the terms cancel badly when a
//! component is tiny, so such components (those that make the formula's condition
//! number exceed 1e8) are replaced by their mean a_k / 2, which moves any quantile by
//! at most a_k / 2.

/// Condition number above which the smallest components are replaced by their mean.
const MAX_CONDITION: f64 = 1e8;

/// The distribution of theta . U for U uniform on [0,1)^d.
#[derive(Clone, Debug)]
pub struct ProjectedUniform {
    /// Subset sums b_S with sign (-1)^|S|, sorted by b_S ascending.
    breaks: Vec<(f64, f64)>,
    /// Exponent d of the kept components.
    degree: i32,
    /// 1 / (d! prod a_k) and 1 / ((d+1)! prod a_k).
    norm_f: f64,
    norm_i: f64,
    /// Support [0, total] before the shift.
    total: f64,
    /// Position of the support's start on the real line.
    offset: f64,
}

impl ProjectedUniform {
    /// `theta` need not be normalised; zero components are fine, not all zero.
    pub fn new(theta: &[f64]) -> Self {
        let mut offset: f64 = theta.iter().filter(|&&t| t < 0.0).sum();
        let mut a: Vec<f64> = theta.iter().map(|t| t.abs()).collect();
        a.sort_by(|x, y| x.total_cmp(y));
        // Drop exact zeros, then the smallest while the formula is ill-conditioned.
        a.retain(|&x| x > 0.0);
        assert!(!a.is_empty(), "projection direction must not be zero");
        while a.len() > 1 && condition(&a) > MAX_CONDITION {
            let small = a.remove(0);
            offset += small / 2.0;
        }
        let d = a.len();
        let mut breaks = Vec::with_capacity(1 << d);
        for mask in 0u32..(1 << d) {
            let b: f64 = (0..d).filter(|k| mask & (1 << k) != 0).map(|k| a[k]).sum();
            let sign = if mask.count_ones() % 2 == 0 { 1.0 } else { -1.0 };
            breaks.push((b, sign));
        }
        breaks.sort_by(|x, y| x.0.total_cmp(&y.0));
        let prod: f64 = a.iter().product();
        let fact = |n: usize| (1..=n).map(|k| k as f64).product::<f64>();
        let total = a.iter().sum();
        Self {
            breaks,
            degree: d as i32,
            norm_f: 1.0 / (fact(d) * prod),
            norm_i: 1.0 / (fact(d + 1) * prod),
            total,
            offset,
        }
    }

    /// Lowest and highest value of the projection.
    pub fn support(&self) -> (f64, f64) {
        (self.offset, self.offset + self.total)
    }

    /// F, its derivative (the density) and its integral I at `s` (local
    /// coordinates, 0 <= s <= total). Only breaks below `s` contribute.
    fn eval(&self, s: f64) -> (f64, f64, f64) {
        let d = self.degree;
        let (mut f, mut dens, mut int) = (0.0, 0.0, 0.0);
        for &(b, sign) in &self.breaks {
            let x = s - b;
            if x <= 0.0 {
                break;
            }
            let xd1 = x.powi(d - 1);
            dens += sign * xd1;
            f += sign * xd1 * x;
            int += sign * xd1 * x * x;
        }
        (f * self.norm_f, dens * self.norm_f * d as f64, int * self.norm_i)
    }

    /// CDF at `x` on the real line.
    pub fn cdf(&self, x: f64) -> f64 {
        let s = x - self.offset;
        if s <= 0.0 {
            0.0
        } else if s >= self.total {
            1.0
        } else if s <= self.total / 2.0 {
            self.eval(s).0.clamp(0.0, 1.0)
        } else {
            // Symmetric about the centre: evaluate the lower half, where fewer
            // terms are active and less cancels.
            (1.0 - self.eval(self.total - s).0).clamp(0.0, 1.0)
        }
    }

    /// Solves F(s) = u in local coordinates, for u <= 1/2, starting at `guess`,
    /// with Newton steps kept inside a shrinking bracket.
    fn local_quantile(&self, u: f64, guess: f64) -> f64 {
        let (mut lo, mut hi) = (0.0, self.total / 2.0);
        let mut s = guess.clamp(lo, hi);
        for _ in 0..200 {
            let (f, dens, _) = self.eval(s);
            let err = f - u;
            if err.abs() <= 1e-15 {
                break;
            }
            if err < 0.0 {
                lo = s;
            } else {
                hi = s;
            }
            let newton = if dens > 0.0 { s - err / dens } else { f64::NAN };
            s = if newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
            if hi - lo <= 1e-15 * self.total {
                break;
            }
        }
        s
    }

    /// Partial first moment G(s) = integral of t f(t) over [0, s], local coordinates.
    fn partial_moment(&self, s: f64) -> f64 {
        let (f, _, int) = self.eval(s);
        s * f - int
    }

    /// Writes the mean of the inverse CDF over [r/n, (r+1)/n] for r = 0..n into
    /// `out` (length n): where the sample of rank r should go. Symmetric about
    /// the centre of the support. Two kept components (a trapezoid) take a
    /// closed form, exact up to f64 rounding; more, the Newton walk below, whose
    /// rank means are n times a difference of partial moments: their error is
    /// about n x the condition number (at most `MAX_CONDITION`; a few thousand
    /// for most directions) x 1e-16 of the support, so 1e-12 for well-spread
    /// directions and classes of thousands, and up to about 1e-4 for a class of
    /// 8192 on a direction with one component near 1e-8 of the others.
    pub fn rank_targets(&self, n: usize, out: &mut [f64]) {
        assert_eq!(out.len(), n);
        if n == 0 {
            return;
        }
        if self.degree == 1 {
            // One kept component: uniform on [0, a], bin centres.
            let nf = n as f64;
            for (r, slot) in out.iter_mut().enumerate() {
                *slot = self.offset + self.total * (r as f64 + 0.5) / nf;
            }
            return;
        }
        if self.degree == 2 {
            return self.trapezoid_targets(n, out);
        }
        self.walk_targets(n, out);
    }

    /// The general form: each quantile solved from the last, by Newton steps.
    pub fn walk_targets(&self, n: usize, out: &mut [f64]) {
        assert_eq!(out.len(), n);
        if n == 0 {
            return;
        }
        let nf = n as f64;
        let half = n / 2;
        let mut q_prev: f64 = 0.0;
        let mut g_prev: f64 = 0.0;
        for (r, slot) in out.iter_mut().enumerate().take(half) {
            // q_(r+1) <= total / 2 because r + 1 <= n / 2.
            let u = (r + 1) as f64 / nf;
            let dens_guess = self.eval(q_prev.max(1e-300)).1;
            let guess = if dens_guess > 0.0 { q_prev + (1.0 / nf) / dens_guess } else { q_prev };
            let q = self.local_quantile(u, guess);
            let g = self.partial_moment(q);
            *slot = self.offset + nf * (g - g_prev);
            q_prev = q;
            g_prev = g;
        }
        if n % 2 == 1 {
            out[half] = self.offset + self.total / 2.0;
        }
        let (low, high) = out.split_at_mut(n - half);
        for (hi, lo) in high.iter_mut().rev().zip(low.iter()) {
            *hi = 2.0 * self.offset + self.total - lo;
        }
    }
}

impl ProjectedUniform {
    /// Rank means of a trapezoid (two kept components a1 <= a2, the breaks 0, a1,
    /// a2, a1 + a2): the quantile is sqrt(2 a1 a2 u) below u1 = a1 / (2 a2) and
    /// a2 u + a1 / 2 from there to 1/2; a bin's mean is each piece's closed-form
    /// mean, weighted by the bin's share of it (as `fsot_quantile_mean` in
    /// glsl/fsot/common.glsl, here in f64). Symmetric beyond 1/2.
    fn trapezoid_targets(&self, n: usize, out: &mut [f64]) {
        let (a1, a2) = (self.breaks[1].0, self.breaks[2].0);
        let nf = n as f64;
        let u1n = 0.5 * a1 / a2 * nf; // u1 in units of a bin
        let root = (2.0 * a1 * a2).sqrt();
        // Mean of the quantile over [y, x] within one piece.
        let low = |y: f64, x: f64| {
            let (sx, sy) = (x.sqrt(), y.sqrt());
            (2.0 / 3.0) * root * (x + sx * sy + y) / (sx + sy)
        };
        let mid = |y: f64, x: f64| 0.5 * a2 * (x + y) + 0.5 * a1;
        let half = n / 2;
        for (q, slot) in out.iter_mut().enumerate().take(half) {
            let (qf, qf1) = (q as f64, (q + 1) as f64);
            let (y, x) = (qf / nf, qf1 / nf);
            let m = if qf1 <= u1n {
                low(y, x)
            } else if qf >= u1n {
                mid(y, x)
            } else {
                let share = u1n - qf; // of the bin below u1
                let u1 = u1n / nf;
                share * low(y, u1) + (1.0 - share) * mid(u1, x)
            };
            *slot = self.offset + m;
        }
        if n % 2 == 1 {
            out[half] = self.offset + self.total / 2.0;
        }
        let (lower, upper) = out.split_at_mut(n - half);
        for (hi, lo) in upper.iter_mut().rev().zip(lower.iter()) {
            *hi = 2.0 * self.offset + self.total - lo;
        }
    }
}

/// Relative error bound of the inclusion-exclusion sum: (sum a)^d / (d! prod a).
fn condition(a: &[f64]) -> f64 {
    let d = a.len();
    let log: f64 = d as f64 * a.iter().sum::<f64>().ln()
        - (1..=d).map(|k| (k as f64).ln()).sum::<f64>()
        - a.iter().map(|x| x.ln()).sum::<f64>();
    log.exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_dimension_gives_bin_centres() {
        let p = ProjectedUniform::new(&[-1.0]);
        let mut out = vec![0.0; 7];
        p.rank_targets(7, &mut out);
        for (r, v) in out.iter().enumerate() {
            assert!((v - (-1.0 + (r as f64 + 0.5) / 7.0)).abs() < 1e-14);
        }
        // The general walk agrees with the closed form it stands in for.
        let mut walked = vec![0.0; 7];
        p.walk_targets(7, &mut walked);
        assert!(out.iter().zip(&walked).all(|(a, b)| (a - b).abs() < 1e-14), "{out:?} {walked:?}");
    }

    #[test]
    fn diagonal_square_matches_the_triangular_closed_form() {
        // theta = (1, 1) / sqrt 2: a triangle on [0, sqrt 2].
        let c = std::f64::consts::FRAC_1_SQRT_2;
        let p = ProjectedUniform::new(&[c, c]);
        let l = 2.0 * c;
        let cdf = |x: f64| {
            if x < l / 2.0 {
                2.0 * x * x / (l * l)
            } else {
                1.0 - 2.0 * (l - x) * (l - x) / (l * l)
            }
        };
        for x in [0.1, 0.3, 0.7, 1.0, 1.3] {
            assert!((p.cdf(x) - cdf(x)).abs() < 1e-13);
        }
        // Rank means for n = 2: the halves' means, (l/2)(2/3) and l - that.
        let mut out = [0.0; 2];
        p.rank_targets(2, &mut out);
        assert!((out[0] - l / 3.0).abs() < 1e-12);
        assert!((out[1] - 2.0 * l / 3.0).abs() < 1e-12);
    }

    #[test]
    fn the_trapezoid_closed_form_matches_the_newton_walk() {
        // Two kept components: diagonal, skewed, nearly an axis (but above the
        // conditioning cut), with negative parts; bins that straddle u1.
        for theta in [[0.6f64, 0.8], [-0.6, 0.8], [0.995, 0.0998], [1e-3, -1.0], [0.7, 0.7001]] {
            let p = ProjectedUniform::new(&theta);
            assert_eq!(p.degree, 2);
            for n in [2usize, 3, 7, 64, 257, 2048] {
                let (mut closed, mut walked) = (vec![0.0; n], vec![0.0; n]);
                p.rank_targets(n, &mut closed);
                p.walk_targets(n, &mut walked);
                let worst = closed.iter().zip(&walked).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                // The walk differences G at neighbouring quantiles and scales
                // by n, through a sum whose condition number reaches about 500
                // here: its own rounding, up to 2.2e-11 at n = 2048 (the closed
                // form is checked against 40-digit arithmetic below). Far below
                // a float32 sample's resolution (6e-8).
                assert!(worst < 1e-10, "{theta:?} n = {n}: {worst:e}");
            }
        }
    }

    #[test]
    fn the_trapezoid_closed_form_matches_40_digit_integration() {
        // Rank means of theta = (0.6, 0.8), n = 2048, from the quantile's exact
        // integral in 40-digit arithmetic (mpmath 1.3.0, outside fsot).
        let reference = [
            (0, 0.014433756729740644),
            (1, 0.02639107231664566),
            (2, 0.0341751709536137),
            (600, 0.5305509954165655),
            (1023, 0.6998046875),
        ];
        let mut out = vec![0.0; 2048];
        ProjectedUniform::new(&[0.6, 0.8]).rank_targets(2048, &mut out);
        for (r, want) in reference {
            assert!((out[r] - want).abs() <= 4.0 * f64::EPSILON * want, "rank {r}: {} vs {want}", out[r]);
        }
        // Nearly an axis, negative: theta = (0.001, -1.0).
        let skewed = [
            (0, -0.9993411921541316),
            (1, -0.9987675786792017),
            (2, -0.998279296875),
            (500, -0.755115234375),
            (1023, -0.499744140625),
        ];
        ProjectedUniform::new(&[0.001, -1.0]).rank_targets(2048, &mut out);
        for (r, want) in skewed {
            assert!((out[r] - want).abs() <= 4.0 * f64::EPSILON, "rank {r}: {} vs {want}", out[r]);
        }
    }

    #[test]
    fn rank_targets_are_sorted() {
        // (Their mean is the distribution's by construction: the upper half
        // mirrors the lower. tests/targets.rs checks the values themselves.)
        for theta in [vec![0.3, -0.9, 0.2], vec![1.0, 1e-9], vec![0.5; 8]] {
            let p = ProjectedUniform::new(&theta);
            for n in [1, 2, 3, 10, 257] {
                let mut out = vec![0.0; n];
                p.rank_targets(n, &mut out);
                assert!(out.windows(2).all(|w| w[0] <= w[1]), "{theta:?} {n}");
            }
        }
    }
}
