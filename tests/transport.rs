//! The transport rule, checked on sets whose answer is known.

use fsot::core::kernel::{Kernel, KernelSpec};
use fsot::core::slice::Slice;
use fsot::core::tile::{Tile, MAX_DIMS};
use fsot::core::transport::{transport_slice, Scratch};

#[test]
fn one_step_moves_a_1d_set_exactly_onto_its_quantiles() {
    // 16 pixels in a row, one frame, d = 1; a kernel wide enough that the whole row
    // is one class; the slice takes every tap.
    let tile = Tile::new(16, 1, 1, 1, 1).unwrap();
    let kernel = Kernel::new(KernelSpec::from_name("spatial", 40.0, None, 0.1, 60.0).unwrap(), &tile);
    assert_eq!(kernel.taps.len(), 16);
    let mut samples: Vec<f32> =
        (0..16).map(|i| ((i * 7919) % 16) as f32 / 16.0 + 0.013 * i as f32 / 16.0).collect();
    let mut theta = [0.0; MAX_DIMS];
    theta[0] = 1.0;
    let mut shift = [0.0; MAX_DIMS];
    shift[0] = 0.3;
    let slice = Slice { theta, shift, cx: 5, cy: 0, ct: 0, len: 16 };
    let mut moves = vec![0.0f64; 16];
    let cost = transport_slice(&samples, &tile, &kernel, &slice, &mut Scratch::default(), |p, delta| {
        moves[p as usize] += delta;
    });
    assert_eq!(cost.count, 16);
    assert!(cost.squared > 0.0);
    for (x, m) in samples.iter_mut().zip(&moves) {
        *x = (*x as f64 + m) as f32;
    }
    // After the move, the shifted coordinates are exactly the bin centres.
    let mut shifted: Vec<f64> = samples.iter().map(|&x| (x as f64 - 0.3).rem_euclid(1.0)).collect();
    shifted.sort_by(|a, b| a.total_cmp(b));
    for (r, v) in shifted.iter().enumerate() {
        assert!((v - (r as f64 + 0.5) / 16.0).abs() < 1e-6, "rank {r}: {v}");
    }
    // A second step has nothing left to do.
    let again = transport_slice(&samples, &tile, &kernel, &slice, &mut Scratch::default(), |_, _| {});
    assert!(again.squared < 1e-10, "{}", again.squared);
}

#[test]
fn every_class_size_ranks_its_members_by_projection_then_by_point() {
    // d = 1, one frame of 32 x 16 pixels, one class the first n taps of a wide
    // kernel: the member of rank r (by shifted value, ties by point index) moves
    // to the bin centre (r + 1/2) / n. Sizes from 2 to 512, each with spread
    // values, with ties, and with most values piled on one.
    let tile = Tile::new(32, 16, 1, 1, 1).unwrap();
    let kernel = Kernel::new(KernelSpec::from_name("spatial", 64.0, None, 0.1, 60.0).unwrap(), &tile);
    assert_eq!(kernel.taps.len(), 512);
    let mut rng = fsot::core::rng::Stream::new(31);
    for n in [2usize, 3, 7, 24, 47, 48, 49, 64, 200, 512] {
        for kind in ["spread", "ties", "piled"] {
            let samples: Vec<f32> = (0..tile.values())
                .map(|i| match kind {
                    "spread" => rng.next_f64() as f32,
                    "ties" => (rng.below(7) as f32) / 7.0,
                    _ if i % 5 == 0 => rng.next_f64() as f32,
                    _ => 0.625,
                })
                .collect();
            let mut theta = [0.0; MAX_DIMS];
            theta[0] = 1.0;
            let mut shift = [0.0; MAX_DIMS];
            shift[0] = 0.25;
            let slice = Slice { theta, shift, cx: 9, cy: 4, ct: 0, len: n as u32 };
            let mut moved: Vec<(u32, f64)> = Vec::new();
            transport_slice(&samples, &tile, &kernel, &slice, &mut Scratch::default(), |p, delta| {
                moved.push((p, delta))
            });
            assert_eq!(moved.len(), n);
            let shifted = |p: u32| (samples[p as usize] as f64 - 0.25).rem_euclid(1.0);
            let mut ranked: Vec<u32> = moved.iter().map(|m| m.0).collect();
            ranked.sort_by(|&a, &b| shifted(a).total_cmp(&shifted(b)).then(a.cmp(&b)));
            for (rank, &p) in ranked.iter().enumerate() {
                let delta = moved.iter().find(|m| m.0 == p).unwrap().1;
                let target = (rank as f64 + 0.5) / n as f64;
                assert!(
                    (shifted(p) + delta - target).abs() < 1e-9,
                    "n = {n}, {kind}: point {p} of rank {rank} goes to {} instead of {target}",
                    shifted(p) + delta
                );
            }
        }
    }
}

#[test]
fn classes_follow_the_kernel_prefix_and_wrap_around_the_tile() {
    let tile = Tile::new(8, 8, 4, 2, 2).unwrap();
    let kernel = Kernel::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), &tile);
    let slice = Slice { theta: [0.0; MAX_DIMS], shift: [0.0; MAX_DIMS], cx: 7, cy: 0, ct: 0, len: 3 };
    let mut points = Vec::new();
    fsot::core::transport::gather_class(&tile, &kernel, &slice, &mut points);
    assert_eq!(points.len(), 3 * 2, "three pixels, two samples each");
    // The heaviest tap is the centre itself: pixel (7, 0, 0), samples 0 and 1.
    assert_eq!(&points[..2], &[7 * 2, 7 * 2 + 1]);
    for p in &points {
        assert!((*p as usize) < tile.points());
    }
}

/// Brute-force targets: the mean of each of `n` equal-count bins of uniform
/// points of [0,1)^d projected on theta and sorted, in f64, estimated over
/// `batches` independent batches of `m` points: the mean of the batches' bin
/// means, with its standard error from their spread (which counts the noise of
/// the bins' edges as well as of their contents).
fn brute_force_targets(theta: &[f64], n: usize, m: usize, batches: usize, key: u32) -> Vec<(f64, f64)> {
    let mut rng = fsot::core::rng::Stream::new(key);
    let per_batch: Vec<Vec<f64>> = (0..batches)
        .map(|_| {
            let mut p: Vec<f64> = (0..m).map(|_| theta.iter().map(|t| t * rng.next_f64()).sum()).collect();
            p.sort_by(|a, b| a.total_cmp(b));
            (0..n).map(|r| p[r * m / n..(r + 1) * m / n].iter().sum::<f64>() / (m / n) as f64).collect()
        })
        .collect();
    (0..n)
        .map(|r| {
            let b = batches as f64;
            let mean = per_batch.iter().map(|t| t[r]).sum::<f64>() / b;
            let var = per_batch.iter().map(|t| (t[r] - mean) * (t[r] - mean)).sum::<f64>() / (b - 1.0);
            (mean, (var / b).sqrt())
        })
        .collect()
}

#[test]
fn displacements_in_two_to_eight_dimensions_are_the_brute_force_targets_minus_the_projections() {
    // One class per d: random samples, a slice in a generic direction with a
    // toroidal shift; each member must move by (its rank's target - its
    // projection) along theta, the targets taken from 3.8 million projected
    // uniform points (not from fsot::core::targets) and the projections recomputed here.
    let mut rng = fsot::core::rng::Stream::new(fsot::core::rng::derive(9, 9));
    for d in [2usize, 3, 4, 8] {
        let tile = Tile::new(8, 8, 4, 1, d).unwrap();
        let kernel = Kernel::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), &tile);
        let samples: Vec<f32> = (0..tile.values()).map(|_| rng.next_f64() as f32).collect();
        let mut theta = [0.0; MAX_DIMS];
        let mut shift = [0.0; MAX_DIMS];
        for k in 0..d {
            theta[k] = rng.normal();
            shift[k] = rng.next_f64();
        }
        let norm = theta.iter().map(|t| t * t).sum::<f64>().sqrt();
        theta.iter_mut().for_each(|t| *t /= norm);
        let len = 24.min(kernel.taps.len() as u32);
        let slice = Slice { theta, shift, cx: 3, cy: 5, ct: 2, len };
        let mut moved: Vec<(u32, f64)> = Vec::new();
        transport_slice(&samples, &tile, &kernel, &slice, &mut Scratch::default(), |p, delta| {
            moved.push((p, delta))
        });
        let n = moved.len();
        assert_eq!(n, len as usize, "d = {d}: every tap of the class moves");
        // Projections of the members, by hand, in f64; ranks by projection.
        let project = |p: u32| -> f64 {
            (0..d)
                .map(|k| {
                    let y = samples[p as usize * d + k] as f64 - shift[k];
                    theta[k] * (y - y.floor())
                })
                .sum()
        };
        let mut ranked: Vec<(f64, u32)> = moved.iter().map(|&(p, _)| (project(p), p)).collect();
        ranked.sort_by(|a, b| a.0.total_cmp(&b.0));
        let targets = brute_force_targets(&theta[..d], n, 240_000, 16, 77 + d as u32);
        // Each difference within 6 standard errors of the brute-force mean
        // (the errors are about 1e-4), far below a rank's spacing (about 0.3 / 24).
        let mut worst = 0.0f64;
        for (rank, &(proj, p)) in ranked.iter().enumerate() {
            let delta = moved.iter().find(|m| m.0 == p).unwrap().1;
            let (target, error) = targets[rank];
            let off = (delta - (target - proj)).abs();
            assert!(
                off < 6.0 * error,
                "d = {d}, rank {rank}: {off:.2e} against a standard error {error:.2e}"
            );
            worst = worst.max(off / error);
        }
        eprintln!("d = {d}: largest difference {worst:.2} standard errors");
    }
}
