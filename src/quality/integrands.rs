//! Animated integrands with exact references, computed independently of the
//! optimizer's math: each pixel (x, y) of frame f integrates a function of the 1-D
//! or 2-D sample whose parameters drift smoothly across the image and over time,
//! like a penumbra or a glossy highlight moving across a screen.

use std::f64::consts::{PI, TAU};

/// One animated integrand family.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    /// 2-D: visibility of a half-plane, 1[n . (u - 1/2) < s]; n and s drift.
    Edge,
    /// 2-D: sin^2(pi (a u + b v + phase)), a smooth ripple that travels.
    Ripple,
    /// 1-D: threshold `1[u < s]`; s drifts.
    Threshold,
    /// 1-D: smooth ramp u^p with an exponent that drifts.
    Ramp,
}

pub const FAMILIES_2D: [Family; 2] = [Family::Edge, Family::Ripple];
pub const FAMILIES_1D: [Family; 2] = [Family::Threshold, Family::Ramp];

/// Parameters of one pixel in one frame (a slowly varying field).
#[derive(Clone, Copy, Debug)]
pub struct Params {
    pub angle: f64,
    pub level: f64,
}

impl Family {
    pub fn dims(&self) -> usize {
        match self {
            Family::Edge | Family::Ripple => 2,
            Family::Threshold | Family::Ramp => 1,
        }
    }

    /// The parameter field: features about 40 pixels wide drifting about 0.4
    /// pixel per frame. `variant` picks an independent field.
    pub fn params(&self, x: f64, y: f64, f: f64, variant: u32) -> Params {
        let v = variant as f64;
        let ph = 1.7 * v;
        let (cx, cy) = (x - 0.4 * f, y + 0.25 * f);
        let angle = ph + TAU * (cx / 97.0 + cy / 131.0) + 0.8 * (TAU * (cx + cy) / 61.0 + v).sin();
        let level =
            0.5 * (TAU * (cx / 53.0 - cy / 71.0) + 2.3 * v).sin() * (0.6 + 0.4 * (TAU * f / 90.0).cos());
        Params { angle, level }
    }

    /// The integrand at sample `u` (first one or two coordinates used).
    pub fn eval(&self, p: Params, u: &[f64]) -> f64 {
        match self {
            Family::Edge => {
                let (n0, n1) = (p.angle.cos(), p.angle.sin());
                if n0 * (u[0] - 0.5) + n1 * (u[1] - 0.5) < 0.45 * p.level {
                    1.0
                } else {
                    0.0
                }
            }
            Family::Ripple => {
                let (a, b) = ripple_frequencies(p);
                let s = (PI * (a * u[0] + b * u[1] + p.level)).sin();
                s * s
            }
            Family::Threshold => {
                if u[0] < 0.5 + 0.45 * p.level {
                    1.0
                } else {
                    0.0
                }
            }
            Family::Ramp => u[0].powf(ramp_exponent(p)),
        }
    }

    /// The exact integral over [0,1)^dims.
    pub fn reference(&self, p: Params) -> f64 {
        match self {
            Family::Edge => {
                let (n0, n1) = (p.angle.cos(), p.angle.sin());
                half_plane_area(n0, n1, 0.45 * p.level + 0.5 * (n0 + n1))
            }
            Family::Ripple => {
                // sin^2 = (1 - cos(2 pi (a u + b v + level))) / 2; the mean of the
                // cosine over the square is Re(e^{i psi} E(a) E(b)) with
                // E(k) = (e^{2 pi i k} - 1) / (2 pi i k).
                let (a, b) = ripple_frequencies(p);
                let e = |k: f64| -> (f64, f64) {
                    let w = TAU * k;
                    (w.sin() / w, (1.0 - w.cos()) / w)
                };
                let (ar, ai) = e(a);
                let (br, bi) = e(b);
                let (pr, pi) = (ar * br - ai * bi, ar * bi + ai * br);
                let psi = TAU * p.level;
                let re = psi.cos() * pr - psi.sin() * pi;
                0.5 - 0.5 * re
            }
            Family::Threshold => 0.5 + 0.45 * p.level,
            Family::Ramp => 1.0 / (ramp_exponent(p) + 1.0),
        }
    }
}

fn ripple_frequencies(p: Params) -> (f64, f64) {
    (0.6 + 0.5 * p.angle.cos().abs(), 0.5 + 0.6 * p.angle.sin().abs())
}

fn ramp_exponent(p: Params) -> f64 {
    1.5 + 1.2 * p.angle.sin()
}

/// Area of `{(u, v) in [0,1]^2 : n0 u + n1 v < c}`, by clipping the square's polygon.
pub fn half_plane_area(n0: f64, n1: f64, c: f64) -> f64 {
    let square = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
    let side = |p: (f64, f64)| n0 * p.0 + n1 * p.1 - c;
    let mut poly: Vec<(f64, f64)> = Vec::with_capacity(6);
    for i in 0..4 {
        let (a, b) = (square[i], square[(i + 1) % 4]);
        let (sa, sb) = (side(a), side(b));
        if sa < 0.0 {
            poly.push(a);
        }
        if (sa < 0.0) != (sb < 0.0) {
            let t = sa / (sa - sb);
            poly.push((a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1)));
        }
    }
    let n = poly.len();
    let twice: f64 = (0..n)
        .map(|i| {
            let (p, q) = (poly[i], poly[(i + 1) % n]);
            p.0 * q.1 - q.0 * p.1
        })
        .sum();
    0.5 * twice.abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: midpoint rule on a fine grid.
    fn grid_mean(f: impl Fn(&[f64]) -> f64, dims: usize, k: usize) -> f64 {
        let mut sum = 0.0;
        if dims == 1 {
            for i in 0..k {
                sum += f(&[(i as f64 + 0.5) / k as f64]);
            }
            return sum / k as f64;
        }
        for i in 0..k {
            for j in 0..k {
                sum += f(&[(i as f64 + 0.5) / k as f64, (j as f64 + 0.5) / k as f64]);
            }
        }
        sum / (k * k) as f64
    }

    #[test]
    fn references_match_brute_force_integration() {
        for family in FAMILIES_2D.iter().chain(FAMILIES_1D.iter()) {
            for (x, y, f) in [(0.0, 0.0, 0.0), (13.0, 40.0, 7.0), (55.0, 3.0, 31.0)] {
                let p = family.params(x, y, f, 1);
                let exact = family.reference(p);
                let k = if family.dims() == 1 { 1_000_000 } else { 1000 };
                let brute = grid_mean(|u| family.eval(p, u), family.dims(), k);
                assert!((exact - brute).abs() < 3e-3, "{family:?} {exact} vs {brute}");
            }
        }
    }
}
