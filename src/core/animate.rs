//! A spatial tile set in motion: frame t of the animated mask is the spatial
//! mask's samples rotated (modulo 1) by t steps of a Kronecker sequence, so each
//! pixel's samples over time are a low-discrepancy sequence and each frame keeps
//! the spatial mask's structure. A scalar mask's pixels take their step by their
//! place in each 2x2 block, so that two pixels a 2-D decision reads together do
//! not move in lockstep. A cheap start for a spatio-temporal optimization.
//!
//! Also the coarse start's layout (`lay_out`): a mask of a quarter of the tile
//! laid out 2x2, each copy rotated (modulo 1) by its own multiple of the
//! Kronecker steps, so that no copy holds another's values.

use crate::core::mask::Mask;
use crate::core::tile::{Tile, MAX_DIMS};
use crate::error::{Error, Result};

/// The Kronecker sequence's step in each of d dimensions: the golden ratio's
/// conjugate (sqrt 5 - 1) / 2, then the fractional parts of the square roots of
/// 3, 2, 7, 11, 13, 17 and 19. Each step alone has a continued fraction of small
/// bounded partial quotients, so every coordinate over a few frames (what TAA
/// averages) is close to even, as the golden ratio is in one dimension; the
/// square roots lie in distinct quadratic fields, so 1 and the steps are
/// rationally independent and the coordinates together are equidistributed.
/// In every run of up to 32 frames the widest gap between a coordinate's values
/// stays under 3 / n for n frames; the R_2 sequence's steps (0.755 and 0.570)
/// reach 4.1 / n and 3.4 / n.
pub fn kronecker_step(dims: usize) -> Vec<f64> {
    const ROOTS: [f64; MAX_DIMS - 1] = [3.0, 2.0, 7.0, 11.0, 13.0, 17.0, 19.0];
    let golden = (5f64.sqrt() - 1.0) / 2.0;
    std::iter::once(golden).chain(ROOTS.iter().map(|r| r.sqrt().fract())).take(dims).collect()
}

/// The step of pixel (x, y)'s coordinate k: `steps[k]`, or for a scalar mask
/// the first four steps by the pixel's place in its 2x2 block. With one step
/// for all, two pixels of a scalar mask read as one 2-D sample keep the same
/// difference in every frame; with distinct steps the pair is itself a 2-D
/// Kronecker sequence over time.
fn step_of(steps: &[f64], block: &[f64], x: usize, y: usize, k: usize) -> f64 {
    if steps.len() == 1 {
        block[x % 2 + 2 * (y % 2)]
    } else {
        steps[k]
    }
}

/// `v` moved by `by` (at least 0) modulo 1, in f64, and kept below 1 in f32.
fn rotated(v: f32, by: f64) -> f32 {
    ((v as f64 + by).fract() as f32).min(crate::core::mask::BELOW_ONE)
}

/// The mask of `frames` frames whose frame t is `spatial` (one frame) with
/// every coordinate moved by t times its step (`step_of`), modulo 1.
pub fn animate(spatial: &Mask, frames: usize) -> Result<Mask> {
    let s = spatial.tile;
    if s.frames != 1 {
        return Err(Error::invalid(format!("an animated start takes a one-frame mask, not {}", s.describe())));
    }
    let tile = Tile::new(s.width, s.height, frames, s.spp, s.dims)?;
    let steps = kronecker_step(s.dims);
    let block = kronecker_step(4);
    let per_frame = spatial.samples.len();
    let mut samples = Vec::with_capacity(per_frame * frames);
    for t in 0..frames {
        for (i, &v) in spatial.samples.iter().enumerate() {
            let pixel = i / (s.spp * s.dims);
            let alpha = step_of(&steps, &block, pixel % s.width, pixel / s.width, i % s.dims);
            samples.push(rotated(v, t as f64 * alpha));
        }
    }
    let mut mask = Mask { tile, samples, meta: spatial.meta.clone() };
    mask.set_meta("start", "animated by a Kronecker sequence");
    Ok(mask)
}

/// The mask of `tile` whose quarter at copy (i, j) (i across, j down) is
/// `quarter` with every coordinate k moved by the fractional part of c times
/// `kronecker_step`'s k-th step, modulo 1, c = i + 2 j: the first copy as it
/// is, the others rotated apart. `quarter` must be half the tile's width and
/// height, with its frames, samples per pixel and dimensions. A rotation of a
/// whole copy leaves every class inside it as well spread as it was (the
/// transport projects after a random toroidal shift); only classes that
/// straddle two copies see the seam.
pub fn lay_out(quarter: &Mask, tile: Tile) -> Result<Mask> {
    let q = quarter.tile;
    if Tile::new(2 * q.width, 2 * q.height, q.frames, q.spp, q.dims)? != tile {
        return Err(Error::invalid(format!(
            "a coarse start lays out a quarter of the tile, not {} for {}",
            q.describe(),
            tile.describe()
        )));
    }
    let steps = kronecker_step(q.dims);
    // Copy c's rotation of coordinate k.
    let rotation: Vec<Vec<f64>> = (0..4).map(|c| steps.iter().map(|a| (c as f64 * a).fract()).collect()).collect();
    let per = q.spp * q.dims;
    let mut samples = Vec::with_capacity(tile.values());
    for t in 0..tile.frames {
        for y in 0..tile.height {
            for x in 0..tile.width {
                let rotation = &rotation[x / q.width + 2 * (y / q.height)];
                let at = ((t * q.height + y % q.height) * q.width + x % q.width) * per;
                for (i, &v) in quarter.samples[at..at + per].iter().enumerate() {
                    samples.push(rotated(v, rotation[i % q.dims]));
                }
            }
        }
    }
    let mut mask = Mask { tile, samples, meta: quarter.meta.clone() };
    mask.set_meta("start", "a quarter of the tile laid out 2x2");
    Ok(mask)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_steps_are_the_golden_ratio_then_square_roots_of_distinct_primes() {
        let steps = kronecker_step(MAX_DIMS);
        assert_eq!(steps.len(), MAX_DIMS);
        // The golden ratio's conjugate solves x^2 + x = 1.
        assert!((steps[0] * steps[0] + steps[0] - 1.0).abs() < 1e-15);
        // Each later step plus its integer part squares to its prime.
        for (step, (prime, whole)) in steps[1..].iter().zip([(3, 1), (2, 1), (7, 2), (11, 3), (13, 3), (17, 4), (19, 4)]) {
            assert!(((step + whole as f64).powi(2) - prime as f64).abs() < 1e-13, "{step} for {prime}");
        }
        assert_eq!(kronecker_step(2), steps[..2]);
    }

    #[test]
    fn any_run_of_up_to_32_frames_leaves_each_coordinate_no_gap_wider_than_three_over_its_length() {
        for (k, alpha) in kronecker_step(MAX_DIMS).iter().enumerate() {
            for n in 2..=32 {
                let mut v: Vec<f64> = (0..n).map(|t| (t as f64 * alpha).fract()).collect();
                v.sort_by(f64::total_cmp);
                let wrap = 1.0 - v[n - 1] + v[0];
                let widest = v.windows(2).map(|w| w[1] - w[0]).fold(wrap, f64::max);
                assert!(widest * (n as f64) < 3.0, "coordinate {k}, {n} frames: widest gap {widest}");
            }
        }
    }

    #[test]
    fn each_pixel_over_time_is_its_spatial_value_plus_t_steps_modulo_one() {
        let spatial = Mask::white(Tile::new(4, 3, 1, 2, 2).unwrap(), 9);
        let mask = animate(&spatial, 7).unwrap();
        assert_eq!(mask.tile, Tile::new(4, 3, 7, 2, 2).unwrap());
        let step = kronecker_step(2);
        for t in 0..7 {
            for (y, x, s) in [(0, 0, 0), (2, 3, 1), (1, 2, 0)] {
                for (k, alpha) in step.iter().enumerate() {
                    let want = (spatial.sample(x, y, 0, s)[k] as f64 + t as f64 * alpha).rem_euclid(1.0);
                    let got = mask.sample(x, y, t, s)[k] as f64;
                    assert!((got - want).abs() < 1e-6, "t {t} ({x}, {y}) s {s} k {k}: {got} against {want}");
                }
            }
        }
        assert!(mask.samples.iter().all(|v| (0.0..1.0).contains(v)));
        assert_eq!(animate(&spatial, 1).unwrap().samples, spatial.samples);
    }

    #[test]
    fn a_scalar_masks_2x2_block_moves_by_four_distinct_steps() {
        let spatial = Mask::white(Tile::new(4, 4, 1, 1, 1).unwrap(), 3);
        let mask = animate(&spatial, 9).unwrap();
        let steps = kronecker_step(4);
        for (y, x, k) in [(0, 0, 0), (0, 1, 1), (1, 0, 2), (1, 1, 3), (2, 2, 0), (3, 2, 2), (1, 3, 3)] {
            for t in 0..9 {
                let want = (spatial.sample(x, y, 0, 0)[0] as f64 + t as f64 * steps[k]).rem_euclid(1.0);
                let got = mask.sample(x, y, t, 0)[0] as f64;
                assert!((got - want).abs() < 1e-6, "t {t} ({x}, {y}): {got} against {want}");
            }
        }
        // Two neighbours' difference changes from frame to frame.
        let diff = |t| mask.sample(1, 0, t, 0)[0] - mask.sample(0, 0, t, 0)[0];
        assert!(((diff(1) - diff(0)).rem_euclid(1.0) - (steps[1] - steps[0]).rem_euclid(1.0) as f32).abs() < 1e-5);
    }

    #[test]
    fn a_quarter_laid_out_holds_four_copies_each_rotated_by_its_multiple_of_the_steps() {
        let quarter = Mask::white(Tile::new(3, 2, 4, 2, 2).unwrap(), 5);
        let tile = Tile::new(6, 4, 4, 2, 2).unwrap();
        let mask = lay_out(&quarter, tile).unwrap();
        assert_eq!(mask.tile, tile);
        let step = kronecker_step(2);
        for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            let c = (i + 2 * j) as f64;
            for (x, y, t, s) in [(0, 0, 0, 0), (2, 1, 3, 1), (1, 0, 2, 1)] {
                for (k, alpha) in step.iter().enumerate() {
                    let want = (quarter.sample(x, y, t, s)[k] as f64 + c * alpha).rem_euclid(1.0);
                    let got = mask.sample(x + 3 * i, y + 2 * j, t, s)[k] as f64;
                    assert!((got - want).abs() < 1e-6, "copy ({i}, {j}) ({x}, {y}, {t}) s {s} k {k}: {got} against {want}");
                }
            }
        }
        assert!(mask.samples.iter().all(|v| (0.0..1.0).contains(v)));
        // The first copy is the quarter itself.
        assert_eq!(mask.sample(2, 1, 3, 1), quarter.sample(2, 1, 3, 1));
    }

    #[test]
    fn only_a_quarter_of_the_tile_is_laid_out() {
        let quarter = Mask::white(Tile::new(4, 4, 2, 1, 1).unwrap(), 1);
        assert!(lay_out(&quarter, Tile::new(8, 8, 2, 1, 1).unwrap()).is_ok());
        for other in [Tile::new(8, 4, 2, 1, 1), Tile::new(8, 8, 4, 1, 1), Tile::new(8, 8, 2, 1, 2)] {
            assert!(lay_out(&quarter, other.unwrap()).is_err());
        }
    }

    #[test]
    fn a_mask_of_several_frames_is_refused() {
        assert!(animate(&Mask::white(Tile::new(4, 4, 2, 1, 1).unwrap(), 1), 4).is_err());
    }
}
