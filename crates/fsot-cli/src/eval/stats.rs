//! Means with 95% confidence intervals over independent seeds: Student's t
//! (two-sided 95% quantiles by degrees of freedom), the interval's half-width
//! t s / sqrt n, and whether two intervals overlap. Two methods judged at
//! placements drawn alike are compared placement by placement: the interval of
//! their differences tests the difference at 95%, where two intervals apart is
//! a stricter test, and it is narrower still wherever a placement moves both
//! alike.

use serde::Serialize;

/// Two-sided 95% quantiles of Student's t for 1 to 30 degrees of freedom.
const T95: [f64; 30] = [
    12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228, 2.201, 2.179, 2.160, 2.145, 2.131,
    2.120, 2.110, 2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042,
];

/// The two-sided 95% quantile of Student's t with `dof` degrees of freedom
/// (beyond 30, the Cornish-Fisher expansion around the normal's quantile).
pub fn t95(dof: usize) -> f64 {
    match dof {
        0 => f64::INFINITY,
        d if d <= 30 => T95[d - 1],
        d => {
            let (z, v) = (1.959_964f64, d as f64);
            z + (z.powi(3) + z) / (4.0 * v) + (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / (96.0 * v * v)
        }
    }
}

/// A mean and the half-width of its 95% interval (infinite from one value).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Interval {
    pub mean: f64,
    pub ci95: f64,
}

impl Interval {
    pub fn of(values: &[f64]) -> Self {
        let n = values.len();
        let mean = values.iter().sum::<f64>() / n.max(1) as f64;
        if n < 2 {
            return Self { mean, ci95: f64::INFINITY };
        }
        let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1) as f64;
        Self { mean, ci95: t95(n - 1) * (var / n as f64).sqrt() }
    }

    /// Whether the two intervals share a point.
    pub fn overlaps(&self, other: &Interval) -> bool {
        (self.mean - other.mean).abs() <= self.ci95 + other.ci95
    }

    /// The interval of `a[k] - b[k]` over pairs k (the same placement judged
    /// for two methods); `None` unless both hold the same number of values,
    /// at least two.
    pub fn difference(a: &[f64], b: &[f64]) -> Option<Self> {
        (a.len() == b.len() && a.len() >= 2)
            .then(|| Self::of(&a.iter().zip(b).map(|(x, y)| x - y).collect::<Vec<_>>()))
    }

    /// Whether the interval holds only values above zero (`Some(true)`), only
    /// values below (`Some(false)`), or both.
    pub fn sign(&self) -> Option<bool> {
        if self.mean - self.ci95 > 0.0 {
            Some(true)
        } else if self.mean + self.ci95 < 0.0 {
            Some(false)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Student's t density with `dof` degrees of freedom, in f64.
    fn t_density(x: f64, dof: f64) -> f64 {
        let ln_gamma = |z: f64| -> f64 {
            // Lanczos (g = 7, n = 9), accurate to ~1e-15 for z > 0.5.
            const C: [f64; 9] = [
                0.999_999_999_999_809_9,
                676.520_368_121_885_1,
                -1_259.139_216_722_402_8,
                771.323_428_777_653_1,
                -176.615_029_162_140_6,
                12.507_343_278_686_905,
                -0.138_571_095_265_720_12,
                9.984_369_578_019_572e-6,
                1.505_632_735_149_311_6e-7,
            ];
            let z = z - 1.0;
            let t = z + 7.5;
            let s: f64 = C[0] + (1..9).map(|i| C[i] / (z + i as f64)).sum::<f64>();
            0.5 * (2.0 * std::f64::consts::PI).ln() + (z + 0.5) * t.ln() - t + s.ln()
        };
        let c =
            (ln_gamma((dof + 1.0) / 2.0) - ln_gamma(dof / 2.0)).exp() / (dof * std::f64::consts::PI).sqrt();
        c * (1.0 + x * x / dof).powf(-(dof + 1.0) / 2.0)
    }

    #[test]
    fn the_t_quantiles_hold_95_percent_of_the_density_by_numerical_integration() {
        for dof in (1..=40).chain([60, 100, 1000]) {
            let q = t95(dof);
            // Simpson's rule over [-q, q].
            let steps = 200_000;
            let h = 2.0 * q / steps as f64;
            let mut sum = t_density(-q, dof as f64) + t_density(q, dof as f64);
            for i in 1..steps {
                let x = -q + i as f64 * h;
                sum += if i % 2 == 1 { 4.0 } else { 2.0 } * t_density(x, dof as f64);
            }
            let mass = sum * h / 3.0;
            // Three-decimal tables, and the expansion beyond 30: within 2e-4 of 0.95.
            assert!((mass - 0.95).abs() < 2e-4, "dof {dof}: {mass}");
        }
    }

    #[test]
    fn an_interval_is_t_times_the_standard_error_and_overlap_is_symmetric() {
        let i = Interval::of(&[1.0, 2.0, 3.0]);
        assert_eq!(i.mean, 2.0);
        // s = 1, n = 3: 4.303 / sqrt 3.
        assert!((i.ci95 - 4.303 / 3f64.sqrt()).abs() < 1e-12);
        let far = Interval { mean: 10.0, ci95: 1.0 };
        assert!(!i.overlaps(&far) && !far.overlaps(&i));
        let near = Interval { mean: 4.0, ci95: 0.0 };
        assert!(i.overlaps(&near) && near.overlaps(&i));
        assert!(Interval::of(&[5.0]).ci95.is_infinite());
    }

    #[test]
    fn a_paired_difference_is_the_interval_of_the_differences() {
        // Differences 1, 0.9, 1.1: mean 1, s = 0.1, n = 3: 4.303 * 0.1 / sqrt 3.
        let a = [10.0, 20.0, 30.0];
        let b = [9.0, 19.1, 28.9];
        let d = Interval::difference(&a, &b).unwrap();
        assert!((d.mean - 1.0).abs() < 1e-12);
        assert!((d.ci95 - 4.303 * 0.1 / 3f64.sqrt()).abs() < 1e-12);
        assert_eq!(d.sign(), Some(true));
        // Side by side the intervals overlap: the placements' spread (10 to
        // 30) hides the difference that every pair shows.
        assert!(Interval::of(&a).overlaps(&Interval::of(&b)));
        assert_eq!(Interval::difference(&b, &a).unwrap().sign(), Some(false));
        assert_eq!(Interval { mean: 0.2, ci95: 0.3 }.sign(), None);
        assert_eq!(Interval::difference(&a, &b[..2]), None);
        assert_eq!(Interval::difference(&a[..1], &b[..1]), None);
    }
}
