//! The CPU backend: the reference implementation of the optimizer, multi-threaded
//! with rayon (`CpuRun`, one implementation of `backend::Backend`). Deterministic whatever the thread count: slices are pure functions of
//! (seed, iteration, index), displacements are summed in 64-bit fixed point (integer
//! addition is associative, so the order in which threads add does not matter), and
//! the update is element-wise.

use std::sync::atomic::{AtomicI64, Ordering};

use rayon::prelude::*;

use crate::backend::{Backend, BackendKind, Report};
use crate::error::Result;
use crate::kernel::Kernel;
use crate::mask::Mask;
use crate::problem::Tile;
use crate::rng::seed_key;
use crate::settings::{initial_samples, run_mask, slices_and_hits, RunState, Settings};
use crate::slice::SliceSampler;
use crate::step_rule::{schedule, step_value, OptimizerState};
use crate::transport::{mean_cost, transport_slice, Scratch, SliceCost};

/// Fixed-point scale of the displacement accumulators: 2^40 (resolution 1e-12;
/// 2^23 of headroom over the largest sums that occur).
pub const FIXED_SCALE: f64 = (1u64 << 40) as f64;

/// Sparse per-sample accumulation of displacements, in fixed point.
pub struct Accumulator {
    values: Vec<AtomicI64>,
}

impl Accumulator {
    pub fn new(len: usize) -> Self {
        Self { values: (0..len).map(|_| AtomicI64::new(0)).collect() }
    }
    #[inline]
    pub fn add(&self, index: usize, value: f64) {
        let q = (value * FIXED_SCALE).round() as i64;
        self.values[index].fetch_add(q, Ordering::Relaxed);
    }
    /// Reads one sum and resets it to zero.
    #[inline]
    pub fn take(&self, index: usize) -> f64 {
        self.values[index].swap(0, Ordering::Relaxed) as f64 / FIXED_SCALE
    }
    pub fn len(&self) -> usize {
        self.values.len()
    }
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
}

/// Runs one iteration: `slices` slices of iteration number `iteration`, then the
/// update with step scale `scale` (the schedule's). Returns the iteration's
/// objective estimate (before its update).
#[allow(clippy::too_many_arguments)]
pub fn iterate(
    samples: &mut [f32],
    tile: &Tile,
    kernel: &Kernel,
    sampler: &SliceSampler,
    state: &mut OptimizerState,
    acc: &Accumulator,
    iteration: u32,
    scale: f32,
    slices: u32,
    hits_per_value: f64,
) -> f64 {
    let d = tile.dims;
    let costs: Vec<SliceCost> = {
        let samples: &[f32] = samples;
        (0..slices)
            .into_par_iter()
            .map_init(Scratch::default, |scratch, index| {
                let slice = sampler.draw(iteration, index);
                transport_slice(samples, tile, kernel, &slice, scratch, |point, delta| {
                    let base = point as usize * d;
                    for k in 0..d {
                        if slice.theta[k] != 0.0 {
                            acc.add(base + k, delta * slice.theta[k]);
                        }
                    }
                })
            })
            .collect()
    };
    state.steps += 1;
    let t = state.steps;
    let rule = state.rule;
    let inv_hits = 1.0 / hits_per_value;
    const CHUNK: usize = 4096;
    let update = |(c, (xs, ms)): (usize, (&mut [f32], &mut [f32])), vs: Option<&mut [f32]>| {
        let base = c * CHUNK;
        match vs {
            Some(vs) => {
                for (i, ((x, m), v)) in xs.iter_mut().zip(ms.iter_mut()).zip(vs.iter_mut()).enumerate() {
                    let g = (acc.take(base + i) * inv_hits) as f32;
                    *x = step_value(rule, *x, g, scale, t, m, Some(v));
                }
            }
            None => {
                for (i, (x, m)) in xs.iter_mut().zip(ms.iter_mut()).enumerate() {
                    let g = (acc.take(base + i) * inv_hits) as f32;
                    *x = step_value(rule, *x, g, scale, t, m, None);
                }
            }
        }
    };
    if state.second.is_empty() {
        samples
            .par_chunks_mut(CHUNK)
            .zip(state.first.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|item| update(item, None));
    } else {
        samples
            .par_chunks_mut(CHUNK)
            .zip(state.first.par_chunks_mut(CHUNK))
            .zip(state.second.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(c, ((xs, ms), vs))| update((c, (xs, ms)), Some(vs)));
    }
    mean_cost(&costs)
}

/// An optimization in progress on the CPU.
pub struct CpuRun {
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
    /// A step scale set by the caller (an end-agnostic schedule); None: the
    /// cosine schedule over the run's iterations.
    scale: Option<f32>,
}

impl CpuRun {
    /// Starts from `init` or from white noise drawn from the seed.
    pub fn new(tile: Tile, settings: Settings, init: Option<&Mask>) -> Result<Self> {
        if settings.iterations == 0 {
            return Err(crate::error::Error::invalid("iterations must be at least 1"));
        }
        let kernel = Kernel::new(settings.kernel, &tile);
        let (slices, hits_per_value) = slices_and_hits(&tile, &kernel, &settings)?;
        let samples = initial_samples(&tile, &settings, init)?;
        Ok(Self {
            tile,
            sampler: SliceSampler::new(seed_key(settings.seed), tile, &kernel),
            kernel,
            state: OptimizerState::new(settings.rule, tile.values()),
            acc: Accumulator::new(tile.values()),
            samples,
            settings,
            iteration: 0,
            slices,
            hits_per_value,
            scale: None,
        })
    }

    pub fn finished(&self) -> bool {
        self.iteration >= self.settings.iterations
    }

    /// The samples as they are now.
    pub fn current(&self) -> &[f32] {
        &self.samples
    }

    /// One iteration; returns its objective estimate (measured before its update).
    pub fn step(&mut self) -> f64 {
        let cost = iterate(
            &mut self.samples,
            &self.tile,
            &self.kernel,
            &self.sampler,
            &mut self.state,
            &self.acc,
            self.iteration,
            self.scale.unwrap_or_else(|| schedule(self.iteration, self.settings.iterations)),
            self.slices,
            self.hits_per_value,
        );
        self.iteration += 1;
        cost
    }
}

impl Backend for CpuRun {
    fn kind(&self) -> BackendKind {
        BackendKind::Cpu
    }

    fn describe(&self) -> String {
        format!("cpu, {} threads", rayon::current_num_threads())
    }

    fn iteration(&self) -> u32 {
        self.iteration
    }

    fn slices_per_iteration(&self) -> u32 {
        self.slices
    }

    /// One iteration per call (so cancellation is seen between iterations).
    fn step_up_to(&mut self, _max: u32) -> Result<Vec<f64>> {
        Ok(if self.finished() { Vec::new() } else { vec![self.step()] })
    }

    fn state(&self) -> Result<RunState> {
        Ok(RunState {
            iteration: self.iteration,
            samples: self.samples.clone(),
            first: self.state.first.clone(),
            second: self.state.second.clone(),
            plateau: None,
        })
    }

    /// Continues from a saved state: the following iterations are those the
    /// saved run would have taken.
    fn restore(&mut self, saved: &RunState) -> Result<()> {
        saved.check(&self.tile, &self.settings)?;
        self.iteration = saved.iteration;
        self.samples.clone_from(&saved.samples);
        self.state.first.clone_from(&saved.first);
        self.state.second.clone_from(&saved.second);
        self.state.steps = saved.iteration;
        Ok(())
    }

    fn samples(&self) -> Result<Vec<f32>> {
        Ok(self.samples.clone())
    }

    fn mask(&self) -> Result<Mask> {
        let mut mask =
            run_mask(&self.tile, &self.settings, self.iteration, self.slices, self.samples.clone());
        mask.set_meta("backend", "cpu");
        Ok(mask)
    }

    /// The summed displacement of every coordinate from the slices of iteration
    /// `iteration` (no update), in the fixed point the run accumulates in.
    fn displacements(&mut self, iteration: u32) -> Result<Vec<f64>> {
        let d = self.tile.dims;
        (0..self.slices).into_par_iter().for_each_init(Scratch::default, |scratch, index| {
            let slice = self.sampler.draw(iteration, index);
            transport_slice(&self.samples, &self.tile, &self.kernel, &slice, scratch, |point, delta| {
                for k in 0..d {
                    if slice.theta[k] != 0.0 {
                        self.acc.add(point as usize * d + k, delta * slice.theta[k]);
                    }
                }
            });
        });
        Ok((0..self.acc.len()).map(|i| self.acc.take(i)).collect())
    }

    fn set_scale(&mut self, scale: Option<f32>) {
        self.scale = scale;
    }

    fn report(&self) -> Report {
        Report::default()
    }
}
