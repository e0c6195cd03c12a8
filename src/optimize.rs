//! The fsot optimizer as a resumable run, independent of the command line: a tile,
//! a kernel, settings, a backend; iterate, observe, stop, take the mask.

use crate::cpu::{self, Accumulator};
use crate::error::{Error, Result};
use crate::kernel::{Kernel, KernelSpec};
use crate::mask::Mask;
use crate::optimizer::{OptimizerState, StepRule};
use crate::problem::Tile;
use crate::rng::seed_key;
use crate::slice::SliceSampler;

/// Default number of times each sample is in a slice's class per iteration; sets
/// the default slices per iteration.
pub const DEFAULT_HITS: f64 = 16.0;
pub const DEFAULT_ITERATIONS: u32 = 1000;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    pub kernel: KernelSpec,
    pub iterations: u32,
    /// Slices per iteration; `None`: enough for DEFAULT_HITS hits per sample.
    pub slices: Option<u32>,
    pub seed: u64,
    pub rule: StepRule,
}

impl Settings {
    pub fn new(kernel: KernelSpec, seed: u64) -> Self {
        Self { kernel, iterations: DEFAULT_ITERATIONS, slices: None, seed, rule: StepRule::DEFAULT }
    }
}

/// Where a run stands after some iterations: enough to continue it exactly
/// (`checkpoint.rs` stores it). `second` is empty unless the rule is Adam.
#[derive(Clone, Debug, PartialEq)]
pub struct RunState {
    pub iteration: u32,
    pub samples: Vec<f32>,
    pub first: Vec<f32>,
    pub second: Vec<f32>,
}

impl RunState {
    /// Checks the state against a run's tile, rule and length.
    pub fn check(&self, tile: &Tile, settings: &Settings) -> Result<()> {
        let n = tile.values();
        let adam = matches!(settings.rule, StepRule::Adam { .. });
        if self.samples.len() != n || self.first.len() != n || self.second.len() != if adam { n } else { 0 } {
            return Err(Error::invalid("the saved state does not match this run's tile or step rule"));
        }
        if self.iteration > settings.iterations {
            return Err(Error::invalid(format!(
                "the saved state is at iteration {} of a run of {}",
                self.iteration, settings.iterations
            )));
        }
        Ok(())
    }
}

/// An optimization in progress on the CPU.
pub struct Run {
    pub tile: Tile,
    pub settings: Settings,
    pub kernel: Kernel,
    sampler: SliceSampler,
    samples: Vec<f32>,
    state: OptimizerState,
    acc: Accumulator,
    iteration: u32,
    slices: u32,
    hits_per_value: f64,
}

impl Run {
    /// Starts from `init` (validated by the caller's reader) or from white noise
    /// drawn from the seed.
    pub fn new(tile: Tile, settings: Settings, init: Option<&Mask>) -> Result<Self> {
        if settings.iterations == 0 {
            return Err(Error::invalid("iterations must be at least 1"));
        }
        let kernel = Kernel::new(settings.kernel, &tile);
        let (slices, hits_per_value) = slices_and_hits(&tile, &kernel, &settings)?;
        let samples = match init {
            Some(mask) => {
                if mask.tile != tile {
                    return Err(Error::invalid(format!(
                        "--init mask is {} but the run asks for {}",
                        mask.tile.describe(),
                        tile.describe()
                    )));
                }
                mask.samples.clone()
            }
            None => Mask::white(tile, settings.seed).samples,
        };
        let key = seed_key(settings.seed);
        Ok(Self {
            tile,
            sampler: SliceSampler::new(key, tile, &kernel),
            kernel,
            state: OptimizerState::new(settings.rule, tile.values()),
            acc: Accumulator::new(tile.values()),
            samples,
            settings,
            iteration: 0,
            slices,
            hits_per_value,
        })
    }

    pub fn slices_per_iteration(&self) -> u32 {
        self.slices
    }
    pub fn iteration(&self) -> u32 {
        self.iteration
    }
    pub fn finished(&self) -> bool {
        self.iteration >= self.settings.iterations
    }
    pub fn samples(&self) -> &[f32] {
        &self.samples
    }

    /// One iteration; returns its objective estimate (measured before its update).
    pub fn step(&mut self) -> f64 {
        let cost = cpu::iterate(
            &mut self.samples,
            &self.tile,
            &self.kernel,
            &self.sampler,
            &mut self.state,
            &self.acc,
            self.iteration,
            self.settings.iterations,
            self.slices,
            self.hits_per_value,
        );
        self.iteration += 1;
        cost
    }

    /// Where the run stands.
    pub fn state(&self) -> RunState {
        RunState {
            iteration: self.iteration,
            samples: self.samples.clone(),
            first: self.state.first.clone(),
            second: self.state.second.clone(),
        }
    }

    /// Continues from a saved state: the following iterations are those the
    /// saved run would have taken.
    pub fn restore(&mut self, saved: &RunState) -> Result<()> {
        saved.check(&self.tile, &self.settings)?;
        self.iteration = saved.iteration;
        self.samples.clone_from(&saved.samples);
        self.state.first.clone_from(&saved.first);
        self.state.second.clone_from(&saved.second);
        self.state.steps = saved.iteration;
        Ok(())
    }

    /// The mask with its provenance.
    pub fn mask(&self) -> Mask {
        let mut mask =
            run_mask(&self.tile, &self.settings, self.iteration, self.slices, self.samples.clone());
        mask.set_meta("backend", "cpu");
        mask
    }
}

/// Slices per iteration (the setting, or enough for DEFAULT_HITS class
/// memberships per sample) and the resulting expected hits per sample.
pub fn slices_and_hits(tile: &Tile, kernel: &Kernel, settings: &Settings) -> Result<(u32, f64)> {
    let mean_points = kernel.mean_class_len() * tile.spp as f64;
    let slices = match settings.slices {
        Some(0) => return Err(Error::invalid("slices per iteration must be at least 1")),
        Some(s) => s,
        None => ((DEFAULT_HITS * tile.points() as f64 / mean_points).ceil() as u32).max(16),
    };
    Ok((slices, slices as f64 * mean_points / tile.points() as f64))
}

/// A mask with the provenance of a run.
pub fn run_mask(tile: &Tile, s: &Settings, iterations: u32, slices: u32, samples: Vec<f32>) -> Mask {
    let mut meta = vec![
        ("method".to_string(), "fsot".to_string()),
        ("kernel".to_string(), s.kernel.describe()),
        ("seed".to_string(), s.seed.to_string()),
        ("iterations".to_string(), iterations.to_string()),
        ("slices".to_string(), slices.to_string()),
        ("step".to_string(), format!("{:?}", s.rule)),
        ("version".to_string(), env!("CARGO_PKG_VERSION").to_string()),
    ];
    meta.sort();
    Mask { tile: *tile, samples, meta }
}

/// Runs to the end with no observer.
pub fn optimize(tile: Tile, settings: Settings, init: Option<&Mask>) -> Result<Mask> {
    let mut run = Run::new(tile, settings, init)?;
    while !run.finished() {
        run.step();
    }
    Ok(run.mask())
}
