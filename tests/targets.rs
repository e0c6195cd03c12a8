//! Exact 1-D targets against brute force: a million projected uniform points.

use fsot::core::rng::{derive, Stream};
use fsot::core::targets::ProjectedUniform;

/// Projects `count` uniform points of [0,1)^d on theta and sorts them.
fn projected_points(theta: &[f64], count: usize, key: u32) -> Vec<f64> {
    let mut rng = Stream::new(key);
    let mut p: Vec<f64> = (0..count).map(|_| theta.iter().map(|t| t * rng.next_f64()).sum()).collect();
    p.sort_by(|a, b| a.total_cmp(b));
    p
}

fn unit(v: &[f64]) -> Vec<f64> {
    let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    v.iter().map(|x| x / n).collect()
}

fn directions() -> Vec<Vec<f64>> {
    let mut rng = Stream::new(derive(42, 1));
    let mut out = Vec::new();
    for d in [2usize, 3, 4, 8] {
        out.push(unit(&(0..d).map(|_| rng.normal()).collect::<Vec<_>>()));
    }
    // Near-degenerate directions: one tiny component, several, and an axis.
    out.push(unit(&[1.0, 1e-4]));
    out.push(unit(&[0.7, -0.7, 1e-4, 2e-9]));
    out.push(unit(&[0.3, 1e-9, -0.5, 1e-12, 0.8, 1e-7, 0.1, 0.2]));
    out.push(vec![0.0, 1.0]);
    out
}

#[test]
fn rank_targets_match_the_mean_of_projected_points_per_quantile_bin() {
    let count = 1_000_000;
    for (i, theta) in directions().into_iter().enumerate() {
        let points = projected_points(&theta, count, derive(7, i as u32));
        let dist = ProjectedUniform::new(&theta);
        for n in [1usize, 2, 8, 50] {
            let mut exact = vec![0.0; n];
            dist.rank_targets(n, &mut exact);
            for (r, &target) in exact.iter().enumerate() {
                let bin = &points[r * count / n..(r + 1) * count / n];
                let brute = bin.iter().sum::<f64>() / bin.len() as f64;
                // Sampling error of a bin mean is far below 1e-3 here.
                assert!(
                    (target - brute).abs() < 2e-3,
                    "theta {theta:?}, n {n}, rank {r}: exact {target}, brute force {brute}"
                );
            }
        }
    }
}

#[test]
fn cdf_matches_the_fraction_of_projected_points() {
    let count = 1_000_000;
    for (i, theta) in directions().into_iter().enumerate() {
        let points = projected_points(&theta, count, derive(9, i as u32));
        let dist = ProjectedUniform::new(&theta);
        let (lo, hi) = dist.support();
        assert!(points[0] >= lo - 1e-9 && points[count - 1] <= hi + 1e-9);
        for q in [0.01, 0.1, 0.25, 0.5, 0.75, 0.9, 0.99] {
            let x = lo + q * (hi - lo);
            let brute = points.partition_point(|&p| p <= x) as f64 / count as f64;
            assert!((dist.cdf(x) - brute).abs() < 3e-3, "theta {theta:?} at {x}: {} vs {brute}", dist.cdf(x));
        }
    }
}

/// The CDF of a1 U1 + a2 U2 (a1 >= a2 > 0) at t: a trapezoid's, integrated piece by piece.
fn trapezoid_cdf(a1: f64, a2: f64, t: f64) -> f64 {
    if t <= 0.0 {
        0.0
    } else if t < a2 {
        t * t / (2.0 * a1 * a2)
    } else if t <= a1 {
        (t - a2 / 2.0) / a1
    } else if t < a1 + a2 {
        1.0 - (a1 + a2 - t).powi(2) / (2.0 * a1 * a2)
    } else {
        1.0
    }
}

/// The rank targets of theta . U for three components, by another route than
/// the crate's inclusion-exclusion: the density of a3 U3 + (a1 U1 + a2 U2) is
/// (F2(x) - F2(x - a3)) / a3, a quadratic between the subset sums, integrated
/// there exactly by 3-point Gauss-Legendre; quantiles by bisection on that CDF;
/// each target the mean of x over its quantile interval.
fn reference_targets_3d(theta: [f64; 3], n: usize) -> Vec<f64> {
    let offset: f64 = theta.iter().filter(|&&t| t < 0.0).sum();
    let mut a = theta.map(f64::abs);
    a.sort_by(|x, y| y.total_cmp(x));
    let (a1, a2, a3) = (a[0], a[1], a[2]);
    let density = |x: f64| (trapezoid_cdf(a1, a2, x) - trapezoid_cdf(a1, a2, x - a3)) / a3;
    let mut breaks: Vec<f64> =
        (0..8u32).map(|m| (0..3).filter(|k| m & (1 << k) != 0).map(|k| a[k]).sum::<f64>()).collect();
    breaks.sort_by(|x, y| x.total_cmp(y));
    // Integral of x^power times the density over [lo, hi].
    let integral = |lo: f64, hi: f64, power: i32| -> f64 {
        let nodes = [(-(0.6f64).sqrt(), 5.0 / 9.0), (0.0, 8.0 / 9.0), ((0.6f64).sqrt(), 5.0 / 9.0)];
        let mut cuts: Vec<f64> = breaks.iter().copied().filter(|&b| b > lo && b < hi).collect();
        cuts.insert(0, lo);
        cuts.push(hi);
        cuts.windows(2)
            .map(|w| {
                let (mid, half) = ((w[0] + w[1]) / 2.0, (w[1] - w[0]) / 2.0);
                nodes
                    .iter()
                    .map(|&(x, wt)| wt * half * (mid + half * x).powi(power) * density(mid + half * x))
                    .sum::<f64>()
            })
            .sum()
    };
    let total = a1 + a2 + a3;
    let quantile = |p: f64| -> f64 {
        let (mut lo, mut hi) = (0.0, total);
        for _ in 0..200 {
            let mid = (lo + hi) / 2.0;
            if integral(0.0, mid, 0) < p {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        (lo + hi) / 2.0
    };
    let q: Vec<f64> = (0..=n).map(|r| if r == n { total } else { quantile(r as f64 / n as f64) }).collect();
    (0..n).map(|r| offset + n as f64 * integral(q[r], q[r + 1], 1)).collect()
}

#[test]
fn three_dimensional_rank_targets_match_an_independent_integration_to_1e_10() {
    for theta in [[0.7, -0.5, 0.3], [0.2, 0.9, -0.4], [0.6, 0.6, 0.05]] {
        let theta = unit(&theta);
        let dist = ProjectedUniform::new(&theta);
        for n in [3usize, 64, 2048] {
            let mut got = vec![0.0; n];
            dist.rank_targets(n, &mut got);
            let want = reference_targets_3d([theta[0], theta[1], theta[2]], n);
            let worst = got.iter().zip(&want).map(|(g, w)| (g - w).abs()).fold(0.0, f64::max);
            assert!(worst < 1e-10, "theta {theta:?}, n {n}: off by {worst:e}");
        }
    }
}
