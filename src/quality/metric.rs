//! The one pRelMSE (and RelMSE) of a render against its reference. Per pixel p
//! of the image interior and per frame f after the warm-up, the mean over both:
//! - e = I - R: the 1-spp render I minus the reference R, both after the
//!   display's TAA (moving average, alpha 0.1) in the TAA case;
//! - RelMSE = mean e^2 / (R^2 + eps);
//! - pRelMSE = mean (P e)^2 / ((P R)^2 + eps), P the perceptual filter (the eye's
//!   spatial Gaussian exp(-r^2 / sigma^2) times FovVideoVDP's temporal response,
//!   normalised to sum 1; `eye.rs`); eps = [`EPSILON`].

use crate::quality::eye::Eye;

/// The eps of RelMSE and pRelMSE's denominators.
pub const EPSILON: f64 = 0.01;

/// (pRelMSE, RelMSE) of one render against the reference, over the frames from
/// `start` (`seen_reference[f - start]`: what the eye sees of reference frame f)
/// and the image interior the eye's margin leaves; n x n images.
pub fn relative_errors(
    render: &[Vec<f64>],
    reference: &[Vec<f64>],
    seen_reference: &[Vec<f64>],
    eye: &Eye,
    start: usize,
    n: usize,
) -> (f64, f64) {
    relative_errors_rect(render, reference, seen_reference, eye, start, [n, n])
}

/// As `relative_errors`, for w x h images (`Eye::filter_rect`). Panics unless
/// the images are wider and taller than twice the eye's margin and some frame
/// from `start` on (at least the eye's history) is judged.
pub fn relative_errors_rect(
    render: &[Vec<f64>],
    reference: &[Vec<f64>],
    seen_reference: &[Vec<f64>],
    eye: &Eye,
    start: usize,
    [w, h]: [usize; 2],
) -> (f64, f64) {
    let m = eye.margin;
    assert!(
        w > 2 * m && h > 2 * m && start >= eye.history() && start < render.len(),
        "a {w} x {h} image of {} frames from frame {start} leaves the eye (margin {m}, history {}) nothing to judge",
        render.len(),
        eye.history()
    );
    let inner = w - 2 * m;
    let error: Vec<Vec<f64>> =
        render.iter().zip(reference).map(|(a, b)| a.iter().zip(b).map(|(x, y)| x - y).collect()).collect();
    let (mut p_sum, mut r_sum, mut count) = (0.0, 0.0, 0usize);
    for f in start..render.len() {
        let seen = eye.filter_rect(&error, f, w, h);
        for (i, (&e, &r)) in seen.iter().zip(&seen_reference[f - start]).enumerate() {
            p_sum += e * e / (r * r + EPSILON);
            let (x, y) = (i % inner + m, i / inner + m);
            let (e, r) = (error[f][y * w + x], reference[f][y * w + x]);
            r_sum += e * e / (r * r + EPSILON);
            count += 1;
        }
    }
    (p_sum / count as f64, r_sum / count as f64)
}

/// What the two channels of `Eye::channels` see of the reference, per frame
/// from `start`: (S R)^2 + (T R)^2 on the interior (the denominator of
/// `channels_apart`, computed once per reference).
pub fn channels_seen(reference: &[Vec<f64>], eyes: &(Eye, Eye), start: usize, n: usize) -> Vec<Vec<f64>> {
    (start..reference.len())
        .map(|f| {
            let (sr, tr) = (eyes.0.filter(reference, f, n), eyes.1.filter(reference, f, n));
            sr.iter().zip(&tr).map(|(s, t)| s * s + t * t).collect()
        })
        .collect()
}

/// pRelMSE with FovVideoVDP's sustained and transient channels kept apart:
/// mean ((S e)^2 + (T e)^2) / ((S R)^2 + (T R)^2 + eps), S and T the two eyes
/// of `Eye::channels` (their sum is the evaluation's eye), over the same
/// frames and interior as `relative_errors` (`seen_reference` from
/// `channels_seen`); n x n images. Where the combined filter lets the channels'
/// responses to an error cancel, this does not.
pub fn channels_apart(
    render: &[Vec<f64>],
    reference: &[Vec<f64>],
    seen_reference: &[Vec<f64>],
    eyes: &(Eye, Eye),
    start: usize,
    n: usize,
) -> f64 {
    let error: Vec<Vec<f64>> =
        render.iter().zip(reference).map(|(a, b)| a.iter().zip(b).map(|(x, y)| x - y).collect()).collect();
    let (mut sum, mut count) = (0.0, 0usize);
    for f in start..render.len() {
        let (se, te) = (eyes.0.filter(&error, f, n), eyes.1.filter(&error, f, n));
        for ((s, t), r) in se.iter().zip(&te).zip(&seen_reference[f - start]) {
            sum += (s * s + t * t) / (r + EPSILON);
            count += 1;
        }
    }
    sum / count as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    /// exp(-d^2 / s^2) at d = -r..=r, r = ceil(3 s), normalised: the eye's
    /// spatial filter as its documentation defines it.
    fn taps(s: f64) -> Vec<f64> {
        let r = (3.0 * s).ceil() as i64;
        let raw: Vec<f64> = (-r..=r).map(|d| (-(d * d) as f64 / (s * s)).exp()).collect();
        let total: f64 = raw.iter().sum();
        raw.into_iter().map(|v| v / total).collect()
    }

    /// The spatio-temporal filter by brute force: the triple sum over every tap,
    /// at each interior pixel of frame f.
    fn filtered(frames: &[Vec<f64>], f: usize, w: usize, h: usize, s: &[f64], t: &[f64]) -> Vec<f64> {
        let r = s.len() / 2;
        let mut out = Vec::new();
        for y in r..h - r {
            for x in r..w - r {
                let mut sum = 0.0;
                for (k, tk) in t.iter().enumerate() {
                    for (j, sy) in s.iter().enumerate() {
                        for (i, sx) in s.iter().enumerate() {
                            sum += tk * sy * sx * frames[f - k][(y + j - r) * w + (x + i - r)];
                        }
                    }
                }
                out.push(sum);
            }
        }
        out
    }

    fn noise(len: usize, seed: u32) -> Vec<f64> {
        let mut rng = crate::core::rng::Stream::new(seed);
        (0..len).map(|_| rng.next_f64()).collect()
    }

    #[test]
    fn a_constant_error_on_a_constant_reference_scores_its_closed_form() {
        let (w, h, frames, start) = (15, 12, 6, 3);
        let eye = Eye::with_temporal(1.0, &[3.0, 2.0, 1.0]);
        let (r, e) = (0.3, 0.05);
        let reference = vec![vec![r; w * h]; frames];
        let render = vec![vec![r + e; w * h]; frames];
        let inner = (w - 2 * eye.margin) * (h - 2 * eye.margin);
        let seen = vec![vec![r; inner]; frames - start];
        let (p, rel) = relative_errors_rect(&render, &reference, &seen, &eye, start, [w, h]);
        let expected = e * e / (r * r + EPSILON);
        assert!((p - expected).abs() < 1e-12 * expected, "{p} against {expected}");
        assert!((rel - expected).abs() < 1e-12 * expected, "{rel} against {expected}");
    }

    #[test]
    fn prelmse_and_relmse_match_the_brute_force_sums_on_a_non_square_sequence() {
        let (w, h, frames, start) = (13, 11, 7, 4);
        let (sigma, temporal) = (1.2, [0.5, 0.3, 0.2]);
        let eye = Eye::with_temporal(sigma, &temporal);
        let reference: Vec<Vec<f64>> = (0..frames).map(|f| noise(w * h, 100 + f as u32)).collect();
        let render: Vec<Vec<f64>> =
            (0..frames).map(|f| noise(w * h, 200 + f as u32).iter().map(|v| 2.0 * v).collect()).collect();
        let s = taps(sigma);
        assert_eq!(s.len() / 2, eye.margin);
        let error: Vec<Vec<f64>> =
            render.iter().zip(&reference).map(|(a, b)| a.iter().zip(b).map(|(x, y)| x - y).collect()).collect();
        let seen: Vec<Vec<f64>> = (start..frames).map(|f| filtered(&reference, f, w, h, &s, &temporal)).collect();
        let (mut p_sum, mut r_sum, mut count) = (0.0, 0.0, 0.0);
        for f in start..frames {
            let pe = filtered(&error, f, w, h, &s, &temporal);
            let m = eye.margin;
            for (i, (pe, pr)) in pe.iter().zip(&seen[f - start]).enumerate() {
                p_sum += pe * pe / (pr * pr + EPSILON);
                let (x, y) = (i % (w - 2 * m) + m, i / (w - 2 * m) + m);
                let (e, r) = (error[f][y * w + x], reference[f][y * w + x]);
                r_sum += e * e / (r * r + EPSILON);
                count += 1.0;
            }
        }
        let (p, rel) = relative_errors_rect(&render, &reference, &seen, &eye, start, [w, h]);
        assert!((p - p_sum / count).abs() < 1e-12 * p, "{p} against {}", p_sum / count);
        assert!((rel - r_sum / count).abs() < 1e-12 * rel, "{rel} against {}", r_sum / count);
    }

    #[test]
    #[should_panic(expected = "nothing to judge")]
    fn an_image_no_wider_than_the_eye_s_margins_is_refused() {
        let eye = Eye::with_temporal(2.0, &[1.0]);
        let n = 2 * eye.margin;
        let frames = vec![vec![0.5; n * n]; 2];
        relative_errors_rect(&frames, &frames, &[], &eye, 0, [n, n]);
    }
}
