//! The transport rule of one slice, shared by every backend: gather the class,
//! project it (after the slice's toroidal shift), sort, and send the sample of rank
//! r towards the exact target of rank r (`targets`). Also the objective that the
//! rule descends, which `fsot score` reports.

use crate::core::kernel::Kernel;
use crate::core::slice::Slice;
use crate::core::targets::ProjectedUniform;
use crate::core::tile::Tile;

/// Scratch buffers for one worker; reused from slice to slice.
#[derive(Default)]
pub struct Scratch {
    points: Vec<u32>,
    projections: Vec<f64>,
    buckets: Vec<u32>,
    /// Projection (order bits) above, point below: one integer per member, so
    /// the sort compares integers, ties by point as `total_cmp` then index would.
    order: Vec<u128>,
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
    // Taps and centres both lie in [0, size): one conditional subtraction wraps
    // (no division per tap).
    let wrap = |v: u32, size: u32| if v >= size { v - size } else { v };
    for tap in &kernel.taps[..slice.len as usize] {
        let x = wrap(slice.cx + tap.dx, w);
        let y = wrap(slice.cy + tap.dy, h);
        let f = wrap(slice.ct + tap.dt, t);
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
        p += slice.theta[k] * wrap_unit(x as f64 - slice.shift[k]);
    }
    p
}

/// y - floor(y) for y in (-1, 1) (a sample in [0, 1) minus a shift in [0, 1)),
/// the same value without a call to floor (not inlined without SSE4.1).
#[inline]
fn wrap_unit(y: f64) -> f64 {
    debug_assert!(y > -1.0 && y < 1.0, "{y}");
    if y < 0.0 {
        y + 1.0
    } else {
        y
    }
}

/// Sorts the class (`points` with their `projections`) into `order` by
/// projection, ties by point index: a bucket sort over the projections' range
/// (n buckets, monotone in the key, so only members of one bucket can be out of
/// order), then insertion within buckets; O(n) for spread keys. Where keys pile
/// into few buckets, a comparison sort instead. The same order as sorting the
/// packed keys outright.
fn sort_class(scratch: &mut Scratch, (low, high): (f64, f64)) {
    let n = scratch.points.len();
    if n <= SMALL_CLASS {
        scratch.order.clear();
        scratch.order.extend(scratch.projections.iter().zip(&scratch.points).map(|(&v, &p)| sort_key(v, p)));
        insertion_sort(&mut scratch.order);
        return;
    }
    let scale = n as f64 / (high - low).max(1e-300);
    let bucket = |v: f64| (((v - low) * scale).max(0.0) as usize).min(n - 1);
    scratch.buckets.clear();
    scratch.buckets.resize(n + 1, 0);
    for &v in &scratch.projections {
        scratch.buckets[bucket(v) + 1] += 1;
    }
    let mut pairs = 0usize;
    for b in 1..=n {
        let c = scratch.buckets[b] as usize;
        pairs += c * c.saturating_sub(1) / 2;
        scratch.buckets[b] += scratch.buckets[b - 1];
    }
    scratch.order.clear();
    scratch.order.resize(n, 0);
    for (&v, &p) in scratch.projections.iter().zip(&scratch.points) {
        let b = bucket(v);
        let at = scratch.buckets[b] as usize;
        scratch.buckets[b] += 1;
        scratch.order[at] = sort_key(v, p);
    }
    if pairs > 4 * n {
        scratch.order.sort_unstable();
    } else {
        insertion_sort(&mut scratch.order);
    }
}

/// Classes of at most this many members are sorted by insertion outright: for
/// so few keys the buckets' passes cost more than they save.
const SMALL_CLASS: usize = 48;

fn insertion_sort(order: &mut [u128]) {
    for i in 1..order.len() {
        let key = order[i];
        let mut j = i;
        while j > 0 && order[j - 1] > key {
            order[j] = order[j - 1];
            j -= 1;
        }
        order[j] = key;
    }
}

/// A member's key in `Scratch::order`: its projection's order bits above, its
/// point below.
#[inline]
fn sort_key(projection: f64, point: u32) -> u128 {
    ((order_bits(projection) as u128) << 32) | point as u128
}

/// Maps an f64 to a u64 in the same total order (`f64::total_cmp`).
#[inline]
fn order_bits(v: f64) -> u64 {
    let b = v.to_bits();
    if b >> 63 == 1 {
        !b
    } else {
        b | (1 << 63)
    }
}

/// The inverse of `order_bits`.
#[inline]
fn from_order_bits(k: u64) -> f64 {
    f64::from_bits(if k >> 63 == 1 { k & !(1 << 63) } else { !k })
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
    let dist = ProjectedUniform::new(&slice.theta[..d]);
    scratch.projections.clear();
    for &p in &scratch.points {
        let i = p as usize * d;
        scratch.projections.push(project(&samples[i..i + d], slice));
    }
    sort_class(scratch, dist.support());
    scratch.targets.resize(n, 0.0);
    dist.rank_targets(n, &mut scratch.targets);
    let mut squared = 0.0;
    for (&packed, &target) in scratch.order.iter().zip(&scratch.targets) {
        let (proj, point) = (from_order_bits((packed >> 32) as u64), packed as u32);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn order_bits_sort_like_total_cmp_and_invert_exactly() {
        let mut values =
            vec![0.0, -0.0, 1.0, -1.0, f64::MIN_POSITIVE, -f64::MIN_POSITIVE, 1e-300, -1e300, 0.5];
        let mut rng = crate::core::rng::Stream::new(3);
        values.extend((0..1000).map(|_| (rng.next_f64() - 0.5) * 3.0));
        for &a in &values {
            assert_eq!(from_order_bits(order_bits(a)).to_bits(), a.to_bits());
            for &b in values.iter().take(40) {
                assert_eq!(order_bits(a).cmp(&order_bits(b)), a.total_cmp(&b), "{a} {b}");
            }
        }
    }

    #[test]
    fn wrapping_is_the_fractional_part() {
        let mut rng = crate::core::rng::Stream::new(5);
        for _ in 0..10_000 {
            let y = rng.next_f64() * 2.0 - 1.0;
            if y > -1.0 {
                assert_eq!(wrap_unit(y).to_bits(), (y - y.floor()).to_bits(), "{y}");
            }
        }
    }
}
