//! The transport rule, checked on sets whose answer is known.

use fsot::kernel::{Kernel, KernelSpec};
use fsot::problem::{Tile, MAX_DIMS};
use fsot::slice::Slice;
use fsot::transport::{transport_slice, Scratch};

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
fn classes_follow_the_kernel_prefix_and_wrap_around_the_tile() {
    let tile = Tile::new(8, 8, 4, 2, 2).unwrap();
    let kernel = Kernel::new(KernelSpec::from_name("taa", 2.1, None, 0.1, 60.0).unwrap(), &tile);
    let slice = Slice { theta: [0.0; MAX_DIMS], shift: [0.0; MAX_DIMS], cx: 7, cy: 0, ct: 0, len: 3 };
    let mut points = Vec::new();
    fsot::transport::gather_class(&tile, &kernel, &slice, &mut points);
    assert_eq!(points.len(), 3 * 2, "three pixels, two samples each");
    // The heaviest tap is the centre itself: pixel (7, 0, 0), samples 0 and 1.
    assert_eq!(&points[..2], &[7 * 2, 7 * 2 + 1]);
    for p in &points {
        assert!((*p as usize) < tile.points());
    }
}
