//! The CPU backend: the reference implementation of the optimizer, multi-threaded
//! with rayon (`CpuRun`, one implementation of `backend::Backend`). Deterministic
//! whatever the thread count: slices are pure functions of
//! (seed, iteration, index), displacements are summed in 64-bit fixed point (integer
//! addition is associative, so the order in which threads add does not matter), and
//! the update is element-wise. The same freedom lets a large tile's slices go in the
//! order of their kernel centres (`SliceOrder`), which keeps what they touch in cache.

use std::sync::atomic::{AtomicI64, Ordering};

use rayon::prelude::*;

use crate::core::kernel::Kernel;
use crate::core::mask::Mask;
use crate::core::rng::seed_key;
use crate::core::slice::SliceSampler;
use crate::core::step_rule::{schedule, step_value, OptimizerState};
use crate::core::tile::Tile;
use crate::core::transport::{mean_cost, transport_slice, Scratch, SliceCost};
use crate::error::Result;
use crate::optimize::backend::{Backend, BackendKind, Report};
use crate::optimize::settings::{initial_samples, run_mask, slices_and_hits, RunState, Settings};

/// Fixed-point scale of the displacement accumulators: 2^40 (resolution 1e-12;
/// 2^23 of headroom over the largest sums that occur).
pub const FIXED_SCALE: f64 = (1u64 << 40) as f64;

/// `x.round() as i64` (half away from zero) without a call to round, which is not
/// inlined without SSE4.1: x - trunc(x) is exact for |x| < 2^52.
#[inline]
pub fn round_half_away(x: f64) -> i64 {
    let i = x as i64;
    let frac = x - i as f64;
    // Branch-free: which way a fraction goes is a coin toss.
    i + (frac >= 0.5) as i64 - (frac <= -0.5) as i64
}

/// Per-coordinate sums of displacements in fixed point (2^-40): integer sums, so
/// the result is the same whatever order the contributions arrive in. Each
/// worker thread of the pool adds into its own lane with a plain load and store
/// (one writer per lane: no locked instruction, no cache line passed between
/// cores); a thread outside the pool, or a pool larger than at creation, adds
/// into a shared lane with an atomic add. Reading sums the lanes. Tiles whose
/// lanes would take more than LANES_MAX_BYTES use the shared lane alone.
pub struct Accumulator {
    /// One per pool thread, then the shared lane.
    lanes: Vec<Vec<AtomicI64>>,
    len: usize,
}

/// Where one thread adds: its own lane, or the shared one.
pub struct Lane<'a> {
    values: &'a [AtomicI64],
    own: bool,
}

impl Lane<'_> {
    #[inline]
    pub fn add(&self, index: usize, value: f64) {
        let q = round_half_away(value * FIXED_SCALE);
        let slot = &self.values[index];
        if self.own {
            // This thread is the lane's only writer: a load and a store suffice.
            slot.store(slot.load(Ordering::Relaxed) + q, Ordering::Relaxed);
        } else {
            slot.fetch_add(q, Ordering::Relaxed);
        }
    }
}

/// Memory the per-thread lanes may take.
const LANES_MAX_BYTES: usize = 256 << 20;

impl Accumulator {
    pub fn new(len: usize) -> Self {
        let threads = rayon::current_num_threads();
        let own = if (threads + 1) * len * 8 <= LANES_MAX_BYTES && threads > 1 { threads } else { 0 };
        let lanes = (0..=own).map(|_| (0..len).map(|_| AtomicI64::new(0)).collect()).collect();
        Self { lanes, len }
    }
    /// Adds `value` at `index`, in this thread's lane.
    #[inline]
    pub fn add(&self, index: usize, value: f64) {
        self.lane().add(index, value);
    }

    /// This thread's lane (look it up once, add many times).
    #[inline]
    pub fn lane(&self) -> Lane<'_> {
        let shared = self.lanes.len() - 1;
        match rayon::current_thread_index().filter(|&t| t < shared) {
            Some(t) => Lane { values: &self.lanes[t], own: true },
            None => Lane { values: &self.lanes[shared], own: false },
        }
    }
    /// The sum at `index`, which is reset to zero. Call when no thread adds.
    #[inline]
    pub fn take(&self, index: usize) -> f64 {
        let sum: i64 = self.lanes.iter().map(|lane| lane[index].swap(0, Ordering::Relaxed)).sum();
        sum as f64 / FIXED_SCALE
    }
    pub fn len(&self) -> usize {
        self.len
    }
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }
}

/// The order in which one iteration's slices are transported. The displacements
/// are summed in integers, so the order changes no result, only how well the
/// samples and accumulators the slices touch stay in cache.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SliceOrder {
    /// By slice index, as drawn.
    Index,
    /// By kernel centre (row, column, frame): consecutive slices share most of
    /// the samples and accumulators they touch. Costs a second draw of each
    /// slice and a sort.
    Centre,
}

/// Accumulator lanes of more bytes than this outgrow a core's own cache, and a
/// tile's slices are transported by centre (BENCHMARKS.md: from 1.1 times as
/// fast at 2 MiB a lane to 2 times at 16 MiB); below it the second draw and the
/// sort cost about what the cache saves.
const CENTRE_ORDER_ABOVE_BYTES: usize = 1 << 20;

impl SliceOrder {
    /// The faster order for a tile: by centre once its accumulators outgrow a
    /// core's cache.
    pub fn for_tile(tile: &Tile) -> Self {
        if tile.values() * std::mem::size_of::<i64>() > CENTRE_ORDER_ABOVE_BYTES {
            Self::Centre
        } else {
            Self::Index
        }
    }

    fn indices(self, sampler: &SliceSampler, tile: &Tile, iteration: u32, slices: u32) -> Vec<u32> {
        match self {
            Self::Index => (0..slices).collect(),
            Self::Centre => {
                let (w, t) = (tile.width as u64, tile.frames as u64);
                let mut keys: Vec<u64> = (0..slices)
                    .into_par_iter()
                    .map(|index| {
                        let s = sampler.draw(iteration, index);
                        let centre = (s.cy as u64 * w + s.cx as u64) * t + s.ct as u64;
                        (centre << 32) | index as u64
                    })
                    .collect();
                keys.par_sort_unstable();
                keys.into_iter().map(|k| k as u32).collect()
            }
        }
    }
}

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
    order: SliceOrder,
) -> f64 {
    let d = tile.dims;
    let indices = order.indices(sampler, tile, iteration, slices);
    // Each slice's cost, in the order transported.
    let transported: Vec<SliceCost> = {
        let samples: &[f32] = samples;
        indices
            .par_iter()
            .map_init(Scratch::default, |scratch, &index| {
                let slice = sampler.draw(iteration, index);
                let lane = acc.lane();
                transport_slice(samples, tile, kernel, &slice, scratch, |point, delta| {
                    let base = point as usize * d;
                    for k in 0..d {
                        if slice.theta[k] != 0.0 {
                            lane.add(base + k, delta * slice.theta[k]);
                        }
                    }
                })
            })
            .collect()
    };
    // In index order, so that their sum is the same in either order.
    let costs = match order {
        SliceOrder::Index => transported,
        SliceOrder::Centre => {
            let mut costs = vec![SliceCost::default(); transported.len()];
            for (&index, cost) in indices.iter().zip(transported) {
                costs[index as usize] = cost;
            }
            costs
        }
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

/// The CPU path's summed displacement per coordinate for one iteration's slices,
/// in f64 (the reference the GPU's float32 is held to).
pub fn reference_displacements(mask: &Mask, s: &Settings, slices: u32, iteration: u32) -> Vec<f64> {
    let tile = mask.tile;
    let kernel = Kernel::new(s.kernel, &tile);
    let sampler = SliceSampler::new(seed_key(s.seed), tile, &kernel, s.axis_share);
    let mut out = vec![0.0f64; tile.values()];
    let mut scratch = Scratch::default();
    for i in 0..slices {
        let slice = sampler.draw(iteration, i);
        transport_slice(&mask.samples, &tile, &kernel, &slice, &mut scratch, |p, delta| {
            for k in 0..tile.dims {
                out[p as usize * tile.dims + k] += delta * slice.theta[k];
            }
        });
    }
    out
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
    order: SliceOrder,
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
            sampler: SliceSampler::new(seed_key(settings.seed), tile, &kernel, settings.axis_share),
            kernel,
            state: OptimizerState::new(settings.rule, tile.values()),
            acc: Accumulator::new(tile.values()),
            samples,
            settings,
            iteration: 0,
            slices,
            hits_per_value,
            order: SliceOrder::for_tile(&tile),
            scale: None,
        })
    }

    /// Transports the slices in `order` instead of the tile's faster one.
    pub fn set_slice_order(&mut self, order: SliceOrder) {
        self.order = order;
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
            self.order,
        );
        self.iteration += 1;
        cost
    }
}

impl Backend for CpuRun {
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_without_libm_matches_round_half_away_from_zero() {
        let below_half = 0.5 - f64::EPSILON / 4.0; // 0.49999999999999994
        let mut values = vec![0.0, -0.0, 0.5, -0.5, 1.5, -1.5, 2.5, -2.5, below_half, -below_half, 1e-300];
        values.extend([(1u64 << 51) as f64 + 0.5, -((1u64 << 51) as f64) - 0.5, 4503599627370495.5]);
        let mut rng = crate::core::rng::Stream::new(7);
        values.extend((0..100_000).map(|_| (rng.next_f64() - 0.5) * FIXED_SCALE * 0.02));
        for v in values {
            assert_eq!(round_half_away(v), v.round() as i64, "{v:e}");
        }
    }
}
