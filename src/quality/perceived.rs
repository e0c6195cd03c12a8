//! Perceived error of a mask under TAA on animated integrands: the independent test
//! of mask quality. Each frame is rendered with one sample per pixel taken from the
//! mask (tile repeated over the image, one random Cranley-Patterson shift per
//! render), the error against the exact reference goes through the display's TAA
//! (exponential moving average) when asked, then through the eye: a spatial
//! Gaussian exp(-r^2 / sigma^2) and FovVideoVDP's temporal response at 60 fps (all
//! 15 taps, negative ones included; `eye.rs`). The score is the mean squared filtered error
//! over the image's interior and the frames after a warm-up.

use rayon::prelude::*;

use crate::core::mask::Mask;
use crate::core::rng::{derive, seed_key, Stream};
use crate::core::tile::Tile;
use crate::quality::eye::Eye;
use crate::quality::integrands::{Family, FAMILIES_1D, FAMILIES_2D};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TestSetup {
    pub image: usize,
    pub frames: usize,
    pub warmup: usize,
    /// TAA blend weight, or None for no TAA.
    pub taa_alpha: Option<f64>,
    /// Eye's spatial Gaussian, exp(-r^2 / sigma^2).
    pub eye_sigma: f64,
    pub fps: f64,
    /// Renders per integrand family (each with its own shift and parameter field).
    pub renders: u32,
}

impl Default for TestSetup {
    fn default() -> Self {
        Self {
            image: 96,
            frames: 96,
            warmup: 48,
            taa_alpha: Some(0.1),
            eye_sigma: 2.1,
            fps: 60.0,
            renders: 3,
        }
    }
}

/// Mean squared perceived error of one render.
fn render_error(mask: &Mask, family: Family, variant: u32, shift: [f64; 2], setup: &TestSetup) -> f64 {
    let Tile { width, height, frames: tf, dims, .. } = mask.tile;
    let n = setup.image;
    let frames = setup.frames;
    // Per-frame error images, after TAA.
    let mut history = vec![0.0f64; n * n];
    let mut after_taa: Vec<Vec<f64>> = Vec::with_capacity(frames);
    let used = family.dims().min(dims);
    for f in 0..frames {
        let err: Vec<f64> = (0..n * n)
            .into_par_iter()
            .map(|i| {
                let (x, y) = (i % n, i / n);
                let s = mask.sample(x % width, y % height, f % tf, 0);
                let mut u = [0.0f64; 2];
                for k in 0..used {
                    let v = s[k] as f64 + shift[k];
                    u[k] = v - v.floor();
                }
                let p = family.params(x as f64, y as f64, f as f64, variant);
                family.eval(p, &u) - family.reference(p)
            })
            .collect();
        match setup.taa_alpha {
            Some(a) => {
                for (h, e) in history.iter_mut().zip(&err) {
                    *h = a * e + (1.0 - a) * *h;
                }
                after_taa.push(history.clone());
            }
            None => after_taa.push(err),
        }
    }
    // The eye: temporal response, then spatial Gaussian, on the interior.
    let eye = Eye::new(setup.eye_sigma, setup.fps);
    let start = setup.warmup.max(eye.history());
    let sums: Vec<(f64, usize)> = (start..frames)
        .map(|f| {
            let seen = eye.filter(&after_taa, f, n);
            (seen.iter().map(|v| v * v).sum::<f64>(), seen.len())
        })
        .collect();
    let (sum, count) = sums.iter().fold((0.0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
    sum / count as f64
}

/// Perceived error of `mask` averaged over the integrand families that match its
/// dimension and `setup.renders` renders each; `seed` picks the shifts.
pub fn perceived_error(mask: &Mask, setup: &TestSetup, seed: u64) -> f64 {
    let families: &[Family] = if mask.tile.dims >= 2 { &FAMILIES_2D } else { &FAMILIES_1D };
    let mut rng = Stream::new(derive(seed_key(seed), 0xe7a1));
    let mut total = 0.0;
    let mut count = 0;
    for &family in families {
        for variant in 0..setup.renders {
            let shift = [rng.next_f64(), rng.next_f64()];
            total += render_error(mask, family, variant, shift, setup);
            count += 1;
        }
    }
    total / count as f64
}

/// Ratio of `mask`'s perceived error to that of white noise of the same shape
/// (averaged over `white_masks` white-noise masks). Below 1 is better than white.
pub fn ratio_to_white(mask: &Mask, setup: &TestSetup, white_masks: u32) -> f64 {
    let own = perceived_error(mask, setup, 1);
    let white: f64 = (0..white_masks)
        .map(|i| perceived_error(&Mask::white(mask.tile, 1000 + i as u64), setup, 1))
        .sum::<f64>()
        / white_masks as f64;
    own / white
}
