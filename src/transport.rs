//! The transport rule of one slice, shared by every backend: gather the class,
//! project it (after the slice's toroidal shift), sort, and send the sample of rank
//! r towards the exact target of rank r (`targets`). Also the objective that the
//! rule descends, which `fsot score` reports.

use crate::kernel::Kernel;
use crate::problem::Tile;
use crate::slice::Slice;
use crate::targets::ProjectedUniform;

/// Scratch buffers for one worker; reused from slice to slice.
#[derive(Default)]
pub struct Scratch {
    points: Vec<u32>,
    order: Vec<(f64, u32)>,
    targets: Vec<f64>,
}

/// Outcome of one slice.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SliceCost {
    /// Sum over the class of the squared distance to the target of its rank.
    pub squared: f64,
    /// Number of samples in the class.
    pub count: usize,
}

/// Point indices of the slice's class, in kernel-tap order (spp samples per pixel).
pub fn gather_class(tile: &Tile, kernel: &Kernel, slice: &Slice, out: &mut Vec<u32>) {
    out.clear();
    let (w, h, t) = (tile.width as u32, tile.height as u32, tile.frames as u32);
    for tap in &kernel.taps[..slice.len as usize] {
        let x = (slice.cx + tap.dx) % w;
        let y = (slice.cy + tap.dy) % h;
        let f = (slice.ct + tap.dt) % t;
        let pixel = (f * h + y) * w + x;
        for s in 0..tile.spp as u32 {
            out.push(pixel * tile.spp as u32 + s);
        }
    }
}

/// Projection of one sample on the slice's direction after the toroidal shift.
#[inline]
pub fn project(sample: &[f32], slice: &Slice) -> f64 {
    let mut p = 0.0;
    for (k, &x) in sample.iter().enumerate() {
        let y = x as f64 - slice.shift[k];
        p += slice.theta[k] * (y - y.floor());
    }
    p
}

/// Runs the rule on one slice. For each class member, calls `emit(point,
/// displacement)` where the sample should move by `displacement * theta`.
/// Classes of fewer than two samples carry no information (their target is the
/// mean of a uniformly shifted point) and are skipped.
pub fn transport_slice(
    samples: &[f32],
    tile: &Tile,
    kernel: &Kernel,
    slice: &Slice,
    scratch: &mut Scratch,
    mut emit: impl FnMut(u32, f64),
) -> SliceCost {
    let d = tile.dims;
    gather_class(tile, kernel, slice, &mut scratch.points);
    let n = scratch.points.len();
    if n < 2 {
        return SliceCost::default();
    }
    scratch.order.clear();
    for &p in &scratch.points {
        let i = p as usize * d;
        scratch.order.push((project(&samples[i..i + d], slice), p));
    }
    // Ties (equal projections) ordered by point index: deterministic.
    scratch.order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    scratch.targets.resize(n, 0.0);
    ProjectedUniform::new(&slice.theta[..d]).rank_targets(n, &mut scratch.targets);
    let mut squared = 0.0;
    for (&(proj, point), &target) in scratch.order.iter().zip(&scratch.targets) {
        let delta = target - proj;
        squared += delta * delta;
        emit(point, delta);
    }
    SliceCost { squared, count: n }
}

/// The objective estimated on given slices: the mean squared distance of a class
/// member to its transport target, classes weighted by their size (the weighting
/// under which the filtered error of a kernel is bounded, and the one the rule's
/// displacements descend). Lower is better.
pub fn objective(samples: &[f32], tile: &Tile, kernel: &Kernel, slices: &[Slice]) -> f64 {
    use rayon::prelude::*;
    let costs: Vec<SliceCost> = slices
        .par_iter()
        .map_init(Scratch::default, |scratch, s| {
            transport_slice(samples, tile, kernel, s, scratch, |_, _| {})
        })
        .collect();
    mean_cost(&costs)
}

/// The objective over slices: squared distances to the targets per class member,
/// classes weighted by size (0 for no members).
pub fn mean_cost(costs: &[SliceCost]) -> f64 {
    let squared: f64 = costs.iter().map(|c| c.squared).sum();
    let count: usize = costs.iter().map(|c| c.count).sum();
    if count == 0 {
        0.0
    } else {
        squared / count as f64
    }
}
