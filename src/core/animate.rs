//! A spatial tile set in motion: frame t of the animated mask is the spatial
//! mask's samples rotated (modulo 1) by t steps of the R_d sequence (Roberts'
//! generalised golden ratio), so each pixel's samples over time are a
//! low-discrepancy sequence and each frame keeps the spatial mask's structure.
//! A cheap start for a spatio-temporal optimization.

use crate::core::mask::Mask;
use crate::core::tile::Tile;
use crate::error::{Error, Result};

/// The R_d sequence's step in each of d dimensions: alpha_k = phi_d^-(k + 1),
/// phi_d the positive root of x^(d + 1) = x + 1 (the golden ratio for d = 1).
pub fn rd_step(dims: usize) -> Vec<f64> {
    let mut phi = 2.0f64;
    for _ in 0..64 {
        phi = (1.0 + phi).powf(1.0 / (dims as f64 + 1.0));
    }
    (1..=dims).map(|k| phi.powi(-(k as i32))).collect()
}

/// The mask of `frames` frames whose frame t is `spatial` (one frame) with
/// every coordinate k moved by t alpha_k, modulo 1.
pub fn animate(spatial: &Mask, frames: usize) -> Result<Mask> {
    let s = spatial.tile;
    if s.frames != 1 {
        return Err(Error::invalid(format!("an animated start takes a one-frame mask, not {}", s.describe())));
    }
    let tile = Tile::new(s.width, s.height, frames, s.spp, s.dims)?;
    let step = rd_step(s.dims);
    let below_one = 1.0f32 - f32::EPSILON / 2.0;
    let per_frame = spatial.samples.len();
    let mut samples = Vec::with_capacity(per_frame * frames);
    for t in 0..frames {
        for (i, &v) in spatial.samples.iter().enumerate() {
            let moved = (v as f64 + t as f64 * step[i % s.dims]).fract();
            samples.push((moved as f32).min(below_one));
        }
    }
    let mut mask = Mask { tile, samples, meta: spatial.meta.clone() };
    mask.set_meta("start", "animated by the R_d sequence");
    Ok(mask)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_steps_are_the_golden_ratio_and_the_plastic_number_powers() {
        let golden = (5f64.sqrt() - 1.0) / 2.0;
        assert!((rd_step(1)[0] - golden).abs() < 1e-15);
        // The plastic number, the real root of x^3 = x + 1.
        let p = ((9.0 + 69f64.sqrt()) / 18.0).cbrt() + ((9.0 - 69f64.sqrt()) / 18.0).cbrt();
        let two = rd_step(2);
        assert!((two[0] - 1.0 / p).abs() < 1e-15 && (two[1] - 1.0 / (p * p)).abs() < 1e-15);
    }

    #[test]
    fn each_pixel_over_time_is_its_spatial_value_plus_t_steps_modulo_one() {
        let spatial = Mask::white(Tile::new(4, 3, 1, 2, 2).unwrap(), 9);
        let mask = animate(&spatial, 7).unwrap();
        assert_eq!(mask.tile, Tile::new(4, 3, 7, 2, 2).unwrap());
        let step = rd_step(2);
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
    fn a_mask_of_several_frames_is_refused() {
        assert!(animate(&Mask::white(Tile::new(4, 4, 2, 1, 1).unwrap(), 1), 4).is_err());
    }
}
