//! The swap search on the CPU cores (rayon): batches of proposals whose deltas
//! are computed in parallel and applied in order, exactly as a sequential
//! search would.

use rayon::prelude::*;

use super::{mean_abs_delta, propose, start, PairEnergy, Schedule, SwapReport};
use crate::core::rng::{derive, Stream};
use crate::error::Result;

/// Improves `values` (pixels x dims) by swapping values between pixels.
/// `on_pass(pass, energy)` is called after each pass.
///
/// The result is the one a plain sequential search over the same proposals
/// gives: a batch's deltas are computed in parallel from the state at its start,
/// and a proposal that reads a value an earlier swap of the batch changed has
/// its delta computed again, at its turn. Batches are sized from the last
/// batch's acceptance rate so that such recomputations stay rare.
pub fn swap_search(
    energy: &PairEnergy,
    values: &mut [f32],
    schedule: Schedule,
    key: u32,
    mut on_pass: impl FnMut(u32, f64),
) -> Result<SwapReport> {
    let (n, d) = (energy.tile.pixels(), energy.tile.dims);
    let (mut report, trivial) = start(energy, values, schedule)?;
    if trivial {
        return Ok(report);
    }
    let mut current = report.start_energy;
    let mut acceptance = 0.5f64;
    let mut size = 8usize;
    let t0 = schedule.start_temperature * mean_abs_delta(energy, values, key);
    // Pixels changed by the swaps taken so far in the batch.
    let mut changed: Vec<(usize, usize, usize)> = Vec::new();
    for pass in 0..schedule.passes {
        let mut rng = Stream::new(derive(key, pass));
        let mut left = n;
        while left > 0 {
            // About one stale proposal in ten: a batch taking k swaps makes
            // about 2 k x footprint of the later ones stale. Grows at most
            // twofold per batch, so one unlucky batch cannot make a huge one.
            size = energy.batch_for(acceptance).clamp(8, 4096).min(2 * size).min(left);
            left -= size;
            let proposals: Vec<(usize, usize, f64)> = (0..size).map(|_| propose(&mut rng, n)).collect();
            let frozen: &[f32] = values;
            let deltas: Vec<f64> =
                proposals.par_iter().map(|&(p, q, _)| energy.swap_delta(frozen, p, q)).collect();
            let temperature = schedule.temperature(t0, pass);
            changed.clear();
            for (&(p, q, u), &delta) in proposals.iter().zip(&deltas) {
                report.proposed += 1;
                let (at_p, at_q) = (energy.coords(p), energy.coords(q));
                let stale = changed.iter().any(|&c| energy.reaches(at_p, c) || energy.reaches(at_q, c));
                let delta = if stale {
                    report.recomputed += 1;
                    energy.swap_delta(values, p, q)
                } else {
                    delta
                };
                let accept = delta < 0.0 || (temperature > 0.0 && u < (-delta / temperature).exp());
                if !accept {
                    continue;
                }
                for k in 0..d {
                    values.swap(p * d + k, q * d + k);
                }
                current += delta;
                report.uphill += u64::from(delta > 0.0);
                changed.push(at_p);
                changed.push(at_q);
            }
            let taken = changed.len() / 2;
            report.accepted += taken as u64;
            // Smoothed, and never zero.
            acceptance = 0.5 * acceptance + 0.5 * (taken as f64 + 0.5) / (size as f64 + 1.0);
        }
        report.trace.push(current);
        on_pass(pass, current);
    }
    Ok(report)
}
