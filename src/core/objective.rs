//! `fsot score`: the objective of any mask on a fixed set of slices, so masks from
//! any source (and any run) are compared on the same footing.

use rayon::prelude::*;

use crate::core::kernel::{Kernel, KernelSpec};
use crate::core::mask::Mask;
use crate::core::rng::seed_key;
use crate::core::slice::{Slice, SliceSampler, DEFAULT_AXIS_SHARE};
use crate::core::tile::Tile;
use crate::core::transport::objective;
use crate::error::Result;

/// Slices in the fixed scoring set.
pub const SCORE_SLICES: u32 = 16384;
/// Seed of the fixed scoring set (never a run's own slices: a different stream).
const SCORE_SEED: u64 = 0x5c0e_5c0e;

/// The fixed slices for a tile and kernel, at the default axis share whatever a
/// run's: scores of masks made with any share stay comparable.
pub fn score_slices(kernel: &Kernel, tile: &Tile, count: u32) -> Vec<Slice> {
    let sampler = SliceSampler::new(seed_key(SCORE_SEED), *tile, kernel, DEFAULT_AXIS_SHARE);
    (0..count).into_par_iter().map(|i| sampler.draw(u32::MAX, i)).collect()
}

/// A mask's objective on a fixed set of slices, beside white noise's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Score {
    /// The mask's objective (mean squared transport distance; lower is better).
    pub objective: f64,
    /// The same for white noise of the same shape (mean of 4 seeds).
    pub white: f64,
}

impl Score {
    /// The objective as a fraction of white noise's (lower is better); 1 where
    /// both are 0 (a tile of one pixel and frame, which no order changes).
    pub fn ratio(&self) -> f64 {
        if self.white == 0.0 && self.objective == 0.0 {
            return 1.0;
        }
        self.objective / self.white
    }
}

impl Mask {
    /// The mask's objective under `kernel` on `SCORE_SLICES` fixed slices (the
    /// same for every mask of the tile), beside white noise's: a measure of how
    /// far the optimization got that does not depend on the run. An error,
    /// before any work, for a mask (`Mask::check`) or a kernel
    /// (`KernelSpec::check`) set out of range by hand.
    ///
    /// ```
    /// use fsot::{KernelSpec, Mask, Tile};
    /// let kernel = KernelSpec::named("taa")?;
    /// let tile = Tile::new(8, 8, 4, 1, 1)?;
    /// let white = Mask::white(tile, 3).score(kernel)?;
    /// assert!((0.5..2.0).contains(&white.ratio()));
    /// // Every pixel the same sample: far worse than white noise.
    /// let mut flat = Mask::white(tile, 3);
    /// flat.samples.fill(0.5);
    /// assert!(flat.score(kernel)?.ratio() > 2.0);
    /// # Ok::<(), fsot::Error>(())
    /// ```
    pub fn score(&self, kernel: KernelSpec) -> Result<Score> {
        self.check()?;
        kernel.check()?;
        Ok(score(self, kernel, SCORE_SLICES))
    }
}

/// `Mask::score` on `count` slices.
pub fn score(mask: &Mask, spec: KernelSpec, count: u32) -> Score {
    scores(&mask.tile, &[&mask.samples], spec, count)[0]
}

/// The scores of several sample sets of one tile on `count` slices: the kernel,
/// the slices and white noise's objective are made once for all of them.
pub fn scores(tile: &Tile, samples: &[&[f32]], spec: KernelSpec, count: u32) -> Vec<Score> {
    let kernel = Kernel::new(spec, tile);
    let slices = score_slices(&kernel, tile, count);
    let white = (0..4u64)
        .map(|s| objective(&Mask::white(*tile, 0xa11ce + s).samples, tile, &kernel, &slices))
        .sum::<f64>()
        / 4.0;
    samples.iter().map(|s| Score { objective: objective(s, tile, &kernel, &slices), white }).collect()
}
