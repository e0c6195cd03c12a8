//! One slice of the stochastic step: a direction, a kernel centre, a level and a
//! toroidal shift, all drawn from the counter-based generator, so a slice is a pure
//! function of (seed, iteration, slice index) and both backends draw the same ones.

use crate::kernel::Kernel;
use crate::problem::{Tile, MAX_DIMS};
use crate::rng::{derive, hash2, Stream};

/// Probability of an axis-aligned direction (one coordinate alone), for d >= 2.
pub const AXIS_PROBABILITY: f64 = 0.2;
/// Probability of a direction inside one pair of coordinates (2k, 2k+1), for
/// d >= 3: renderers consume dimensions in pairs, so these 2-D projections matter.
pub const PAIR_PROBABILITY: f64 = 0.2;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slice {
    /// Unit direction; entries past `dims` are 0.
    pub theta: [f64; MAX_DIMS],
    /// Toroidal shift of the sample domain: samples are projected as
    /// theta . ((x - shift) mod 1).
    pub shift: [f64; MAX_DIMS],
    /// Kernel centre pixel.
    pub cx: u32,
    pub cy: u32,
    pub ct: u32,
    /// Class size in pixels: the first `len` taps of the kernel.
    pub len: u32,
}

/// Draws the slices of one run.
#[derive(Clone, Debug)]
pub struct SliceSampler {
    key: u32,
    tile: Tile,
    max_weight: f64,
    weights: Vec<f64>,
}

impl SliceSampler {
    pub fn new(seed_key: u32, tile: Tile, kernel: &Kernel) -> Self {
        Self {
            key: derive(seed_key, 0x51ce),
            tile,
            max_weight: kernel.max_weight(),
            weights: kernel.taps.iter().map(|t| t.weight).collect(),
        }
    }

    pub fn draw(&self, iteration: u32, index: u32) -> Slice {
        let d = self.tile.dims;
        let mut rng = Stream::new(hash2(derive(self.key, iteration), index));
        let mut theta = [0.0; MAX_DIMS];
        let pick = rng.next_f64();
        if d == 1 {
            theta[0] = 1.0;
        } else if pick < AXIS_PROBABILITY {
            theta[rng.below(d as u32) as usize] = 1.0;
        } else if d >= 3 && pick < AXIS_PROBABILITY + PAIR_PROBABILITY {
            let p = 2 * rng.below((d / 2) as u32) as usize;
            let phi = std::f64::consts::TAU * rng.next_f64();
            theta[p] = phi.cos();
            theta[p + 1] = phi.sin();
        } else if d == 2 {
            let phi = std::f64::consts::TAU * rng.next_f64();
            theta[0] = phi.cos();
            theta[1] = phi.sin();
        } else {
            let mut norm = 0.0;
            while norm < 1e-12 {
                norm = 0.0;
                for t in theta.iter_mut().take(d) {
                    *t = rng.normal();
                    norm += *t * *t;
                }
            }
            let inv = 1.0 / norm.sqrt();
            theta.iter_mut().take(d).for_each(|t| *t *= inv);
        }
        let mut shift = [0.0; MAX_DIMS];
        for s in shift.iter_mut().take(d) {
            *s = rng.next_f64();
        }
        let cx = rng.below(self.tile.width as u32);
        let cy = rng.below(self.tile.height as u32);
        let ct = rng.below(self.tile.frames as u32);
        // Level uniform in (0, max weight]: the class is every tap at least that heavy.
        let z = (1.0 - rng.next_f64()) * self.max_weight;
        let len = self.weights.partition_point(|&w| w >= z) as u32;
        Slice {
            theta,
            shift,
            cx,
            cy,
            ct,
            len,
        }
    }
}
