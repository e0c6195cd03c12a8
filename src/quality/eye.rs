//! The perceptual filter of the evaluation: what the eye does to a sequence of
//! images, a spatial Gaussian exp(-r^2 / sigma^2) (sigma in pixels at the viewing
//! distance) and FovVideoVDP's temporal response at the frame rate, each
//! normalised to sum 1, so a constant image passes unchanged.

use rayon::prelude::*;

use crate::core::kernel::perceptual_taps;

pub struct Eye {
    /// 1-D Gaussian taps at offsets -margin..=margin; the 2-D filter is their
    /// product, applied as two passes.
    spatial: Vec<f64>,
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
        let r = (sigma * 3.0).ceil() as i64;
        let mut spatial: Vec<f64> = (-r..=r).map(|d| (-((d * d) as f64) / (sigma * sigma)).exp()).collect();
        let total: f64 = spatial.iter().sum();
        spatial.iter_mut().for_each(|w| *w /= total);
        Self { spatial, temporal: taps.to_vec(), margin: r as usize }
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
        // Along x (every row, interior columns), then along y (interior rows).
        let rows: Vec<f64> = (0..h * inner_w)
            .into_par_iter()
            .map(|i| {
                let (x, y) = (i % inner_w, i / inner_w);
                self.spatial.iter().enumerate().map(|(k, wk)| wk * temporal[y * w + x + k]).sum()
            })
            .collect();
        (0..inner_w * inner_h)
            .into_par_iter()
            .map(|i| {
                let (x, y) = (i % inner_w, i / inner_w);
                self.spatial.iter().enumerate().map(|(k, wk)| wk * rows[(y + k) * inner_w + x]).sum()
            })
            .collect()
    }
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
        let spatial_centre = eye.spatial[eye.margin] * eye.spatial[eye.margin];
        assert!((centre - spatial_centre * eye.temporal[0]).abs() < 1e-15);
        // The product of the 1-D taps is the 2-D Gaussian exp(-r^2 / sigma^2).
        let (a, b) = (eye.spatial[eye.margin + 2] * eye.spatial[eye.margin + 1], spatial_centre);
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
