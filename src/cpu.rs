//! The CPU backend: the reference implementation of the optimizer, multi-threaded
//! with rayon. Deterministic whatever the thread count: slices are pure functions of
//! (seed, iteration, index), displacements are summed in 64-bit fixed point (integer
//! addition is associative, so the order in which threads add does not matter), and
//! the update is element-wise.

use std::sync::atomic::{AtomicI64, Ordering};

use rayon::prelude::*;

use crate::kernel::Kernel;
use crate::optimizer::{schedule, step_value, OptimizerState};
use crate::problem::Tile;
use crate::slice::SliceSampler;
use crate::transport::{transport_slice, Scratch, SliceCost};

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
/// update with schedule position `iteration` of `iterations`. Returns the
/// iteration's objective estimate (before its update).
#[allow(clippy::too_many_arguments)]
pub fn iterate(
    samples: &mut [f32],
    tile: &Tile,
    kernel: &Kernel,
    sampler: &SliceSampler,
    state: &mut OptimizerState,
    acc: &Accumulator,
    iteration: u32,
    iterations: u32,
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
    let scale = schedule(iteration, iterations);
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
    let squared: f64 = costs.iter().map(|c| c.squared).sum();
    let count: usize = costs.iter().map(|c| c.count).sum();
    if count == 0 {
        0.0
    } else {
        squared / count as f64
    }
}
