//! One slice of the stochastic step: a direction, a kernel centre, a level and a
//! toroidal shift, all drawn from the counter-based generator, so a slice is a pure
//! function of (seed, iteration, slice index) and both backends draw the same ones.

use crate::core::kernel::Kernel;
use crate::core::rng::{derive, hash2, Stream};
use crate::core::tile::{Tile, MAX_DIMS};

/// The default probability of an axis-aligned direction (one coordinate alone),
/// for d >= 2 (`Settings::axis_share`): about a third of the slices, so that
/// each coordinate read alone (a 1-D decision reading one channel, an integrand
/// aligned with the axes) is well spread too; more comes at the cost of
/// directions across the axes.
pub const DEFAULT_AXIS_SHARE: f64 = 0.35;
/// Probability of a direction inside one pair of coordinates (2k, 2k+1), for
/// d >= 3 (at most what the axis share leaves): renderers consume dimensions in
/// pairs, so these 2-D projections matter.
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

/// Level thresholds of a kernel's taps as 32-bit integers: tap i belongs to the
/// class of level bits L (uniform over u32) when `threshold[i] > L`, i.e. with
/// probability weight_i / max weight. Integer comparison makes the class size the
/// same on every backend.
pub fn level_thresholds(kernel: &Kernel) -> Vec<u32> {
    let max = kernel.max_weight();
    kernel
        .taps
        .iter()
        .enumerate()
        .map(|(i, t)| {
            if i == 0 {
                u32::MAX
            } else {
                ((t.weight / max) * 4_294_967_296.0).floor().min(u32::MAX as f64) as u32
            }
        })
        .collect()
}

/// Integer threshold of `probability` over the u32 range.
pub const fn probability_bits(probability: f64) -> u32 {
    (probability * 4_294_967_296.0) as u32
}

/// The integer thresholds of a slice's first draw for an axis share in [0, 1]:
/// below the first, an axis; below the second (d >= 3), a pair of coordinates.
/// A share of 1 is 1 - 2^-32. The GPU's transport passes get the same two
/// numbers (`TransportPush`).
pub fn share_bits(axis_share: f64) -> (u32, u32) {
    (probability_bits(axis_share), probability_bits((axis_share + PAIR_PROBABILITY).min(1.0)))
}

/// Draws the slices of one run. The order and use of the draws is mirrored by
/// `fsot_draw_slice` in `glsl/fsot/common.glsl`: integer decisions (axis, pair,
/// centre, level) are bit-identical on both backends; angles and Gaussian
/// directions agree to float32 rounding.
#[derive(Clone, Debug)]
pub struct SliceSampler {
    key: u32,
    tile: Tile,
    thresholds: Vec<u32>,
    axis_bits: u32,
    pair_bits: u32,
}

impl SliceSampler {
    /// The slices of a run of seed key `seed_key` on `tile` under `kernel`, an
    /// `axis_share` of them along one coordinate (in [0, 1]; d >= 2).
    pub fn new(seed_key: u32, tile: Tile, kernel: &Kernel, axis_share: f64) -> Self {
        debug_assert!((0.0..=1.0).contains(&axis_share), "axis share {axis_share}");
        let (axis_bits, pair_bits) = share_bits(axis_share);
        Self { key: slice_key(seed_key), tile, thresholds: level_thresholds(kernel), axis_bits, pair_bits }
    }

    pub fn draw(&self, iteration: u32, index: u32) -> Slice {
        let d = self.tile.dims;
        let mut rng = Stream::new(hash2(derive(self.key, iteration), index));
        let mut theta = [0.0; MAX_DIMS];
        let pick = rng.next_u32();
        let angle = |rng: &mut Stream| turn_cos_sin(rng.next_f32() as f64);
        if d == 1 {
            theta[0] = 1.0;
        } else if pick < self.axis_bits {
            theta[rng.below(d as u32) as usize] = 1.0;
        } else if d >= 3 && pick < self.pair_bits {
            let p = 2 * rng.below((d / 2) as u32) as usize;
            (theta[p], theta[p + 1]) = angle(&mut rng);
        } else if d == 2 {
            (theta[0], theta[1]) = angle(&mut rng);
        } else {
            // Gaussian direction; retried (at most 4 times) in the astronomically
            // unlikely case of a near-zero vector.
            for _ in 0..4 {
                let mut norm = 0.0;
                for t in theta.iter_mut().take(d) {
                    let u1 = 1.0 - rng.next_f32() as f64;
                    let u2 = rng.next_f32() as f64;
                    *t = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
                    norm += *t * *t;
                }
                if norm > 1e-12 {
                    let inv = 1.0 / norm.sqrt();
                    theta.iter_mut().take(d).for_each(|t| *t *= inv);
                    break;
                }
                theta = [0.0; MAX_DIMS];
                theta[0] = 1.0;
            }
        }
        let mut shift = [0.0; MAX_DIMS];
        for s in shift.iter_mut().take(d) {
            *s = rng.next_f32() as f64;
        }
        let cx = rng.below(self.tile.width as u32);
        let cy = rng.below(self.tile.height as u32);
        let ct = rng.below(self.tile.frames as u32);
        let level = rng.next_u32();
        let len = self.thresholds.partition_point(|&q| q > level) as u32;
        Slice { theta, shift, cx, cy, ct, len }
    }
}

/// cos and sin of an angle in turns (u in [0, 1)): exact quadrant reduction and
/// Taylor polynomials on |z| <= pi/4, the same formula the GPU evaluates in
/// float32 (`fsot_turn_cos_sin` in common.glsl), so both backends draw the same
/// directions to float32 rounding whatever the device's own sin and cos do.
pub fn turn_cos_sin(u: f64) -> (f64, f64) {
    let x = 4.0 * u;
    let q = x.floor();
    let z = (x - q - 0.5) * std::f64::consts::FRAC_PI_2;
    let z2 = z * z;
    let s = z
        * (1.0
            + z2 * (-1.0 / 6.0
                + z2 * (1.0 / 120.0
                    + z2 * (-1.0 / 5040.0
                        + z2 * (1.0 / 362880.0 + z2 * (-1.0 / 39916800.0 + z2 * (1.0 / 6227020800.0)))))));
    let c = 1.0
        + z2 * (-0.5
            + z2 * (1.0 / 24.0
                + z2 * (-1.0 / 720.0
                    + z2 * (1.0 / 40320.0 + z2 * (-1.0 / 3628800.0 + z2 * (1.0 / 479001600.0))))));
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let (cq, sq) = (h * (c - s), h * (c + s));
    match (q as i64) & 3 {
        0 => (cq, sq),
        1 => (-sq, cq),
        2 => (-cq, -sq),
        _ => (sq, -cq),
    }
}

/// The key of a run's slice stream, from its seed key.
pub fn slice_key(seed_key: u32) -> u32 {
    derive(seed_key, 0x51ce)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turn_cos_sin_matches_the_library_to_1e_12() {
        for i in 0..10_000 {
            let u = i as f64 / 10_000.0;
            let (c, s) = turn_cos_sin(u);
            let a = std::f64::consts::TAU * u;
            assert!((c - a.cos()).abs() < 1e-12 && (s - a.sin()).abs() < 1e-12, "{u}");
        }
    }

    /// The share of each kind of direction a sampler draws, over `n` slices:
    /// (one axis, a pair of coordinates, any other).
    fn kinds(share: f64, dims: usize, n: u32) -> (f64, f64, f64) {
        let tile = Tile::new(8, 8, 4, 1, dims).unwrap();
        let kernel = Kernel::new(crate::core::kernel::KernelSpec::named("taa").unwrap(), &tile);
        let sampler = SliceSampler::new(7, tile, &kernel, share);
        let (mut axis, mut pair) = (0u32, 0u32);
        for i in 0..n {
            let nonzero = sampler.draw(3, i).theta.iter().filter(|t| **t != 0.0).count();
            match nonzero {
                1 => axis += 1,
                2 if dims >= 3 => pair += 1,
                _ => {}
            }
        }
        let n = n as f64;
        (axis as f64 / n, pair as f64 / n, (n - axis as f64 - pair as f64) / n)
    }

    #[test]
    fn the_axis_share_is_the_share_of_slices_along_one_coordinate() {
        let n = 40_000;
        // Five binomial standard deviations at n draws, at worst p = 1/2.
        let tolerance = 5.0 * (0.25 / n as f64).sqrt();
        for share in [0.0, DEFAULT_AXIS_SHARE, 0.85, 1.0] {
            let (axis, _, _) = kinds(share, 2, n);
            assert!((axis - share).abs() < tolerance, "d = 2, share {share}: {axis}");
            // d >= 3: pairs take PAIR_PROBABILITY of what the axes leave, at most.
            let (axis, pair, other) = kinds(share, 5, n);
            let pair_share = PAIR_PROBABILITY.min(1.0 - share);
            assert!((axis - share).abs() < tolerance, "d = 5, share {share}: {axis}");
            assert!((pair - pair_share).abs() < tolerance, "d = 5, share {share}: pairs {pair}");
            assert!((other - (1.0 - share - pair_share)).abs() < tolerance, "d = 5, share {share}: {other}");
        }
        // One coordinate: every slice is along it, whatever the share.
        assert_eq!(kinds(0.0, 1, 1000).0, 1.0);
    }
}
