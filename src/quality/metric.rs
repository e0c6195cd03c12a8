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

/// As `relative_errors`, for w x h images (`Eye::filter_rect`).
pub fn relative_errors_rect(
    render: &[Vec<f64>],
    reference: &[Vec<f64>],
    seen_reference: &[Vec<f64>],
    eye: &Eye,
    start: usize,
    [w, h]: [usize; 2],
) -> (f64, f64) {
    let m = eye.margin;
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
