//! The perceptual filter of the evaluation: what the eye does to a sequence of
//! images, a spatial filter and FovVideoVDP's temporal response at the frame
//! rate, each normalised to sum 1, so a constant image passes unchanged. The
//! spatial filter is a Gaussian exp(-r^2 / sigma^2) (sigma in pixels at the
//! viewing distance), or the eye on a display: the mixture of Gaussians the
//! kernels fit to the contrast sensitivity at its pixels per degree
//! (`crate::core::csf`). Every Gaussian is cut at 3 of its widths.

use rayon::prelude::*;

use crate::core::kernel::perceptual_taps;

pub struct Eye {
    /// The spatial filter as a weighted sum of separable parts: (weight, 1-D
    /// Gaussian taps at offsets -r..=r, normalised); each part is the product
    /// of its taps along x and y, applied as two passes.
    spatial: Vec<(f64, Vec<f64>)>,
    temporal: Vec<f64>,
    /// Pixels at the border that the spatial filter would read outside the image.
    pub margin: usize,
}

impl Eye {
    pub fn new(sigma: f64, fps: f64) -> Self {
        Self::with_temporal(sigma, &perceptual_taps(fps))
    }

    /// The spatial Gaussian alone (one temporal tap): a judge blind to how the
    /// error moves over frames.
    pub fn spatial_only(sigma: f64) -> Self {
        Self::with_temporal(sigma, &[1.0])
    }

    /// The spatial Gaussian of `sigma` and temporal taps `taps` (lag 0 first),
    /// each normalised to sum 1.
    pub fn with_temporal(sigma: f64, taps: &[f64]) -> Self {
        let sum: f64 = taps.iter().sum();
        Self::with_raw_temporal(sigma, &taps.iter().map(|t| t / sum).collect::<Vec<_>>())
    }

    /// The spatial Gaussian of `sigma` (normalised) and temporal taps as given
    /// (a transient channel sums to about 0 and is not normalised).
    pub fn with_raw_temporal(sigma: f64, taps: &[f64]) -> Self {
        Self::of_parts(vec![(1.0, gaussian_taps(sigma))], taps.to_vec())
    }

    /// The eye on a display of `ppd` pixels per degree (the contrast
    /// sensitivity's mixture of Gaussians, as the kernels fit it) and
    /// FovVideoVDP's temporal response at `fps`.
    pub fn on_display(ppd: f64, fps: f64) -> Self {
        let parts = crate::core::csf::mixture(ppd).into_iter().map(|(w, s)| (w, gaussian_taps(s))).collect();
        let taps = perceptual_taps(fps);
        let sum: f64 = taps.iter().sum();
        Self::of_parts(parts, taps.iter().map(|t| t / sum).collect())
    }

    fn of_parts(spatial: Vec<(f64, Vec<f64>)>, temporal: Vec<f64>) -> Self {
        let margin = spatial.iter().map(|p| p.1.len() / 2).max().unwrap_or(0);
        Self { spatial, temporal, margin }
    }

    /// FovVideoVDP's two temporal channels at `fps` as two eyes (sustained,
    /// transient), scaled so that their filters add up to `Eye::new`'s.
    pub fn channels(sigma: f64, fps: f64) -> (Self, Self) {
        let (sustained, transient) = crate::core::kernel::perceptual_channels(fps);
        (Self::with_raw_temporal(sigma, &sustained), Self::with_raw_temporal(sigma, &transient))
    }

    /// Frames the temporal filter needs before the first one it can filter.
    pub fn history(&self) -> usize {
        self.temporal.len() - 1
    }

    /// Frame `f` of `frames` (n x n images) as the eye sees it, on the interior
    /// (margin pixels cut from each side), row by row. Needs f >= history().
    pub fn filter(&self, frames: &[Vec<f64>], f: usize, n: usize) -> Vec<f64> {
        self.filter_rect(frames, f, n, n)
    }

    /// As `filter`, for w x h images: the interior is (w - 2 margin) x (h - 2 margin).
    pub fn filter_rect(&self, frames: &[Vec<f64>], f: usize, w: usize, h: usize) -> Vec<f64> {
        let mut temporal = vec![0.0f64; w * h];
        for (k, weight) in self.temporal.iter().enumerate() {
            for (t, e) in temporal.iter_mut().zip(&frames[f - k]) {
                *t += weight * e;
            }
        }
        let m = self.margin;
        let (inner_w, inner_h) = (w.saturating_sub(2 * m), h.saturating_sub(2 * m));
        let mut out = vec![0.0f64; inner_w * inner_h];
        for (weight, taps) in &self.spatial {
            // A part narrower than the margin starts that much further in.
            let skip = m - taps.len() / 2;
            // Along x (every row, interior columns), then along y (interior rows).
            let rows: Vec<f64> = (0..h * inner_w)
                .into_par_iter()
                .map(|i| {
                    let (x, y) = (i % inner_w, i / inner_w);
                    taps.iter().enumerate().map(|(k, wk)| wk * temporal[y * w + x + skip + k]).sum()
                })
                .collect();
            let part: Vec<f64> = (0..inner_w * inner_h)
                .into_par_iter()
                .map(|i| {
                    let (x, y) = (i % inner_w, i / inner_w);
                    taps.iter().enumerate().map(|(k, wk)| wk * rows[(y + skip + k) * inner_w + x]).sum()
                })
                .collect();
            out.iter_mut().zip(part).for_each(|(o, p)| *o += weight * p);
        }
        out
    }
}

/// exp(-d^2 / s^2) at offsets d = -r..=r, r = ceil(3 s), normalised to sum 1.
fn gaussian_taps(s: f64) -> Vec<f64> {
    let r = (s * 3.0).ceil() as i64;
    let raw: Vec<f64> = (-r..=r).map(|d| (-((d * d) as f64) / (s * s)).exp()).collect();
    let total: f64 = raw.iter().sum();
    raw.iter().map(|w| w / total).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_constant_sequence_passes_unchanged_and_a_pixel_spreads_by_the_weights() {
        let eye = Eye::new(2.1, 60.0);
        let n = 40;
        let frames: Vec<Vec<f64>> = (0..20).map(|_| vec![0.7; n * n]).collect();
        let out = eye.filter(&frames, 19, n);
        assert!(out.iter().all(|v| (v - 0.7).abs() < 1e-12));
        // One lit pixel in the current frame only: the centre of the filtered
        // image is that pixel times the centre weights of both filters.
        let mut frames: Vec<Vec<f64>> = (0..20).map(|_| vec![0.0; n * n]).collect();
        frames[19][20 * n + 20] = 1.0;
        let out = eye.filter(&frames, 19, n);
        let inner = n - 2 * eye.margin;
        let centre = out[(20 - eye.margin) * inner + 20 - eye.margin];
        let taps = &eye.spatial[0].1;
        let spatial_centre = taps[eye.margin] * taps[eye.margin];
        assert!((centre - spatial_centre * eye.temporal[0]).abs() < 1e-15);
        // The product of the 1-D taps is the 2-D Gaussian exp(-r^2 / sigma^2).
        let (a, b) = (taps[eye.margin + 2] * taps[eye.margin + 1], spatial_centre);
        assert!((a / b - (-5.0f64 / (2.1 * 2.1)).exp()).abs() < 1e-12);
        assert!((out.iter().sum::<f64>() - eye.temporal[0]).abs() < 1e-12);
    }

    #[test]
    fn a_rectangular_image_is_filtered_as_the_brute_force_gaussian_of_its_interior() {
        let eye = Eye::new(1.3, 60.0);
        let (w, h) = (17, 11);
        let history = eye.history();
        let mut stream = crate::core::rng::Stream::new(5);
        let frames: Vec<Vec<f64>> =
            (0..=history).map(|_| (0..w * h).map(|_| stream.next_f64()).collect()).collect();
        let got = eye.filter_rect(&frames, history, w, h);
        let m = eye.margin as i64;
        let (inner_w, inner_h) = (w - 2 * eye.margin, h - 2 * eye.margin);
        assert_eq!(got.len(), inner_w * inner_h);
        // The 2-D Gaussian exp(-r^2 / sigma^2) over the (2m + 1)^2 window,
        // normalised as a whole, and the temporal taps as the eye holds them.
        let weight = |dx: i64, dy: i64| (-((dx * dx + dy * dy) as f64) / (1.3 * 1.3)).exp();
        let total: f64 = (-m..=m).flat_map(|dy| (-m..=m).map(move |dx| weight(dx, dy))).sum();
        for y in 0..inner_h as i64 {
            for x in 0..inner_w as i64 {
                let mut want = 0.0;
                for (k, wt) in eye.temporal.iter().enumerate() {
                    for dy in -m..=m {
                        for dx in -m..=m {
                            let at = ((y + m + dy) * w as i64 + x + m + dx) as usize;
                            want += wt * weight(dx, dy) / total * frames[history - k][at];
                        }
                    }
                }
                let v = got[y as usize * inner_w + x as usize];
                assert!((v - want).abs() < 1e-12, "({x}, {y}): {v} against {want}");
            }
        }
    }

    #[test]
    fn the_eye_on_a_display_is_the_brute_force_sum_of_its_fitted_gaussians() {
        // 38 pixels per degree (the FHD preset) and 75 (4K): the eye is the
        // kernels' mixture sum_i w_i exp(-r^2 / s_i^2) / Z_i, each Gaussian cut at
        // 3 s_i and normalised over its square window, summed in f64 pixel by pixel.
        for ppd in [37.84, 75.4] {
            let eye = Eye::on_display(ppd, 60.0);
            let mixture = crate::core::csf::mixture(ppd);
            let widest = mixture.iter().map(|p| (3.0 * p.1).ceil() as usize).max().unwrap();
            assert_eq!(eye.margin, widest);
            let (w, h) = (2 * eye.margin + 9, 2 * eye.margin + 6);
            let history = eye.history();
            let mut stream = crate::core::rng::Stream::new(7);
            let frames: Vec<Vec<f64>> =
                (0..=history).map(|_| (0..w * h).map(|_| stream.next_f64()).collect()).collect();
            let got = eye.filter_rect(&frames, history, w, h);
            let m = eye.margin as i64;
            let (inner_w, inner_h) = (w - 2 * eye.margin, h - 2 * eye.margin);
            let weight = |dx: i64, dy: i64| -> f64 {
                mixture
                    .iter()
                    .map(|&(wi, s)| {
                        let r = (3.0 * s).ceil() as i64;
                        if dx.abs() > r || dy.abs() > r {
                            return 0.0;
                        }
                        let g = |dx: i64, dy: i64| (-((dx * dx + dy * dy) as f64) / (s * s)).exp();
                        let z: f64 = (-r..=r).flat_map(|a| (-r..=r).map(move |b| g(a, b))).sum();
                        wi * g(dx, dy) / z
                    })
                    .sum()
            };
            for y in 0..inner_h as i64 {
                for x in 0..inner_w as i64 {
                    let mut want = 0.0;
                    for (k, wt) in eye.temporal.iter().enumerate() {
                        for dy in -m..=m {
                            for dx in -m..=m {
                                let at = ((y + m + dy) * w as i64 + x + m + dx) as usize;
                                want += wt * weight(dx, dy) * frames[history - k][at];
                            }
                        }
                    }
                    let v = got[y as usize * inner_w + x as usize];
                    assert!((v - want).abs() < 1e-12, "{ppd} ppd ({x}, {y}): {v} against {want}");
                }
            }
            // Sharper on the closer-packed display: at 38 pixels per degree the
            // centre keeps more of a pixel than at 75.
            let flat: Vec<Vec<f64>> = (0..=history).map(|_| vec![0.25; w * h]).collect();
            assert!(eye.filter_rect(&flat, history, w, h).iter().all(|v| (v - 0.25).abs() < 1e-12));
        }
        let centre = |ppd: f64| {
            crate::core::csf::mixture(ppd)
                .iter()
                .map(|&(w, s)| {
                    let t = gaussian_taps(s);
                    w * t[t.len() / 2] * t[t.len() / 2]
                })
                .sum::<f64>()
        };
        assert!(centre(37.84) > centre(75.4), "{} against {}", centre(37.84), centre(75.4));
    }

    #[test]
    fn the_two_channels_filter_to_the_evaluation_eye_when_added() {
        let (w, h) = (20, 20);
        let eye = Eye::new(2.1, 60.0);
        let (sustained, transient) = Eye::channels(2.1, 60.0);
        let mut stream = crate::core::rng::Stream::new(11);
        let frames: Vec<Vec<f64>> =
            (0..=eye.history()).map(|_| (0..w * h).map(|_| stream.next_f64()).collect()).collect();
        let f = eye.history();
        let (s, t, both) =
            (sustained.filter(&frames, f, w), transient.filter(&frames, f, w), eye.filter(&frames, f, w));
        for ((a, b), c) in s.iter().zip(&t).zip(&both) {
            assert!((a + b - c).abs() < 1e-12, "{a} + {b} against {c}");
        }
        // The transient channel answers change, not level: a constant sequence
        // passes the sustained channel only (its taps' sum, almost all of it).
        let flat: Vec<Vec<f64>> = (0..=f).map(|_| vec![0.5; w * h]).collect();
        let still = transient.filter(&flat, f, w);
        let total: f64 = transient.temporal.iter().sum();
        assert!(still.iter().all(|v| (v - 0.5 * total).abs() < 1e-12));
        assert!(total.abs() < 0.2 * sustained.temporal.iter().sum::<f64>(), "transient sum {total}");
    }
}
