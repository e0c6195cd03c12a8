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
